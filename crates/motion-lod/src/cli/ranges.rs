//! The documented range of every number the command line takes, as clap value parsers: a value
//! outside its range is refused before any work starts, with a message that names the option,
//! the value and the range (README.md lists them).

use clap::builder::{RangedU64ValueParser, TypedValueParser};

/// `--cycles` of `synth`: cycles in the written walk.
pub const CYCLES: (u64, u64) = (1, 10_000);
/// `--walkers` of `crowd` and `demo`.
pub const WALKERS: (u64, u64) = (1, 1_000_000);
/// `--seconds` of `crowd` and `demo`: simulated seconds, in `(0, max]` (one hour).
pub const SECONDS_MAX: f64 = 3600.0;
/// `--fps` of `synth` and `crowd`: frames per second, in `(0, max]`.
pub const FPS_MAX: f64 = 1000.0;
/// `--density` of `crowd`: walkers per square metre, in `(0, max]`.
pub const DENSITY_MAX: f64 = 10.0;
/// `--frames` (aligned frames per cycle T).
pub const FRAMES: (u64, u64) = (2, 2_000);
/// `--levels` (key levels N).
pub const KEY_LEVELS: (u64, u64) = (1, 100);
/// `--accuracy-levels` (N_A).
pub const ACCURACY_LEVELS: (u64, u64) = (1, 1_000);
/// Each rank of `--max-ranks` and `--min-ranks`.
pub const RANK: (u64, u64) = (1, 10_000);
/// `--dof-rank-reference` (0 = the ranks as given).
pub const DOF_REFERENCE: (u64, u64) = (0, 10_000);
/// `--samples` (random subset of cycles) and `eval --max-samples`.
pub const SAMPLES: (u64, u64) = (1, 10_000_000);
/// `--pca-rank` of `eval` and `crowd`.
pub const PCA_RANK: (u64, u64) = (1, 10_000);
/// `--render-every` of `crowd`.
pub const RENDER_EVERY: (u64, u64) = (1, 1_000_000);
/// `--level` of `synth` (checked against the model's levels after loading).
pub const LEVEL: (u64, u64) = (0, 10_000);
/// `--joints` of `synth` (more than the model has means all).
pub const JOINTS: (u64, u64) = (0, 10_000);
/// `--folds` of `eval`.
pub const FOLDS: (u64, u64) = (2, 1_000);
/// `--max-slope` of the DTW alignment (its memory grows with `2 max_slope + 2` per cell).
pub const MAX_SLOPE: (u64, u64) = (0, 100);

/// A `usize` option within `range` (inclusive).
pub fn count(range: (u64, u64)) -> impl TypedValueParser<Value = usize> {
    RangedU64ValueParser::<usize>::new().range(range.0..=range.1)
}

/// A finite number in `(0, max]`, or a message naming the value and the range.
fn positive_up_to(s: &str, max: f64) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|e| format!("`{s}` is not a number ({e})"))?;
    if v.is_finite() && v > 0.0 && v <= max {
        Ok(v)
    } else {
        Err(format!("{s} is not in (0, {max}]"))
    }
}

/// `--seconds`: in `(0, SECONDS_MAX]`.
pub fn seconds(s: &str) -> Result<f32, String> {
    positive_up_to(s, SECONDS_MAX).map(|v| v as f32)
}

/// `--fps` of `crowd`: in `(0, FPS_MAX]`.
pub fn fps_f32(s: &str) -> Result<f32, String> {
    positive_up_to(s, FPS_MAX).map(|v| v as f32)
}

/// `--fps` of `synth`: in `(0, FPS_MAX]`.
pub fn fps(s: &str) -> Result<f64, String> {
    positive_up_to(s, FPS_MAX)
}

/// `--band` of the DTW alignment: a fraction of the cycle length in `[0, 1]`.
pub fn band(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|e| format!("`{s}` is not a number ({e})"))?;
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{s} is not in [0, 1]"))
    }
}

/// `--density`: in `(0, DENSITY_MAX]`.
pub fn density(s: &str) -> Result<f32, String> {
    positive_up_to(s, DENSITY_MAX).map(|v| v as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_outside_their_range_are_refused_with_the_range() {
        assert_eq!(seconds("2.5"), Ok(2.5));
        assert_eq!(seconds("3600"), Ok(3600.0));
        for bad in ["0", "-1", "1e30", "NaN", "inf", "3600.5"] {
            let e = seconds(bad).unwrap_err();
            assert!(e.contains("(0, 3600]"), "{bad}: {e}");
        }
        assert!(seconds("ten").unwrap_err().contains("not a number"));
        assert!(fps("0").is_err() && fps("1001").is_err() && fps("30").is_ok());
        assert!(density("0.05").is_ok() && density("11").is_err());
        assert_eq!(band("0"), Ok(0.0));
        assert_eq!(band("1"), Ok(1.0));
        for bad in ["-0.1", "1.5", "NaN", "inf"] {
            assert!(band(bad).unwrap_err().contains("[0, 1]"), "{bad}");
        }
    }
}
