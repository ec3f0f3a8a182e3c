//! The documented range of every number the command line takes, as clap value parsers: a value
//! outside its range is refused before any work starts, with a message that names the option,
//! the value and the range (README.md lists them).

use clap::builder::{RangedU64ValueParser, TypedValueParser};

/// `--cycles` of `synth`: cycles in the written walk.
pub const CYCLES: (u64, u64) = (1, 10_000);
/// `--walkers` of `crowd` and `demo`.
pub const WALKERS: (u64, u64) = (1, 1_000_000);
/// `--seconds` of `crowd`, `demo` and `quality --crowd`: simulated seconds, from a millisecond to an
/// hour.
pub const SECONDS: (f64, f64) = (0.001, 3600.0);
/// `--fps` of `synth` and `crowd`: frames per second. Below one frame a second a walk's steps
/// are not seen (a cycle lasts about a second), and far below it the frame time leaves the
/// numbers a crowd steps by.
pub const FPS: (f64, f64) = (1.0, 1000.0);
/// `--density` of `crowd` and `quality --crowd`: walkers per square metre, from one per square
/// kilometre (a million walkers on a field of 1,000 km) to ten.
pub const DENSITY: (f64, f64) = (1e-6, 10.0);
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

/// `--control-margin` of `build`: a fraction of the error (1 = 100%).
pub const CONTROL_MARGIN: (f64, f64) = (0.0, 1.0);
/// `--control-min-t` of `build`: a t statistic (0 tests the margin alone).
pub const CONTROL_MIN_T: (f64, f64) = (0.0, 100.0);
/// `--export-seconds` of `crowd`: seconds of the crowd recorded as glTF.
pub const EXPORT_SECONDS: (f64, f64) = (0.001, 60.0);

/// A number in `[range.0, range.1]`, or a message naming the value and the range. A closed lower
/// bound, not `(0, max]`: `1e-300` is positive but is 0 as an `f32`, and a frame rate of `1e-9`
/// gave a walk of one frame.
fn within(s: &str, range: (f64, f64)) -> Result<f64, String> {
    debug_assert!(0.0 <= range.0 && range.0 <= range.1);
    let v = number(s)?;
    if (range.0..=range.1).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{s} is not in [{}, {}]", range.0, range.1))
    }
}

/// `s` as a number, or a message naming it.
fn number(s: &str) -> Result<f64, String> {
    s.trim()
        .parse()
        .map_err(|e| format!("`{s}` is not a number ({e})"))
}

/// `--seconds`: in [`SECONDS`].
pub fn seconds(s: &str) -> Result<f32, String> {
    within(s, SECONDS).map(|v| v as f32)
}

/// `--fps` of `crowd`: in [`FPS`].
pub fn fps_f32(s: &str) -> Result<f32, String> {
    within(s, FPS).map(|v| v as f32)
}

/// `--fps` of `synth`: in [`FPS`].
pub fn fps(s: &str) -> Result<f64, String> {
    within(s, FPS)
}

/// `--band` of the DTW alignment: a fraction of the cycle length in `[0, 1]`.
pub fn band(s: &str) -> Result<f64, String> {
    within(s, (0.0, 1.0))
}

/// A control of `synth`: a finite number that single precision holds (`--dx 1e39` was read as
/// infinity and refused as "dx inf is not a finite number").
pub fn finite_f32(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v.is_finite() && v.abs() <= f64::from(f32::MAX) {
        Ok(v as f32)
    } else {
        Err(format!(
            "{s} is not a finite number (at most 3.4e38 in magnitude)"
        ))
    }
}

/// `--control-margin`: in [`CONTROL_MARGIN`].
pub fn control_margin(s: &str) -> Result<f64, String> {
    within(s, CONTROL_MARGIN)
}

/// `--control-min-t`: in [`CONTROL_MIN_T`].
pub fn control_min_t(s: &str) -> Result<f64, String> {
    within(s, CONTROL_MIN_T)
}

/// `--export-seconds`: in [`EXPORT_SECONDS`].
pub fn export_seconds(s: &str) -> Result<f32, String> {
    within(s, EXPORT_SECONDS).map(|v| v as f32)
}

/// `--density`: in [`DENSITY`].
pub fn density(s: &str) -> Result<f32, String> {
    within(s, DENSITY).map(|v| v as f32)
}

/// `--joint-slots` of `crowd --gpu`: how many walkers can hold joints at once, as a count or as a
/// share of the walkers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum JointSlots {
    /// This many slots (at most [`WALKERS`]'s largest).
    Count(usize),
    /// This percentage of the walkers, in [0, 100], rounded up to whole slots.
    Percent(f64),
}

impl JointSlots {
    /// The slots for `walkers` walkers (never more than one a walker).
    pub fn of(self, walkers: usize) -> usize {
        match self {
            JointSlots::Count(n) => n.min(walkers),
            JointSlots::Percent(p) => ((walkers as f64 * p / 100.0).ceil() as usize).min(walkers),
        }
    }
}

/// `--joint-slots`: a count in `0..=` [`WALKERS`]'s largest, or a percentage `P%` with `P` in
/// [0, 100].
pub fn joint_slots(s: &str) -> Result<JointSlots, String> {
    match s.trim().strip_suffix('%') {
        Some(p) => within(p, (0.0, 100.0))
            .map(JointSlots::Percent)
            .map_err(|e| format!("{e} (a percentage of the walkers)")),
        None => match s.trim().parse::<u64>() {
            Ok(n) if n <= WALKERS.1 => Ok(JointSlots::Count(n as usize)),
            _ => Err(format!(
                "`{s}` is not a count in 0..={} nor a percentage such as `2%`",
                WALKERS.1
            )),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_slots_are_a_count_or_a_percentage_of_the_walkers() {
        assert_eq!(joint_slots("2000"), Ok(JointSlots::Count(2000)));
        assert_eq!(joint_slots("0"), Ok(JointSlots::Count(0)));
        assert_eq!(joint_slots("2.5%"), Ok(JointSlots::Percent(2.5)));
        assert_eq!(JointSlots::Percent(2.5).of(1000), 25);
        assert_eq!(JointSlots::Percent(0.01).of(1000), 1, "rounded up");
        assert_eq!(JointSlots::Percent(100.0).of(7), 7);
        assert_eq!(JointSlots::Count(50).of(10), 10, "one a walker at most");
        for bad in ["150%", "-1%", "NaN%", "%", "-3", "2.5", "1000001", "x"] {
            let e = joint_slots(bad).unwrap_err();
            assert!(e.contains(bad.trim_end_matches('%')), "{bad}: {e}");
        }
    }

    #[test]
    fn floats_outside_their_range_are_refused_with_the_range() {
        assert_eq!(seconds("2.5"), Ok(2.5));
        assert_eq!(seconds("3600"), Ok(3600.0));
        assert_eq!(seconds("0.001"), Ok(0.001));
        // Positive but 0 as an f32 (or a millisecond's fraction): refused, not passed on as 0.
        for bad in [
            "0", "-1", "1e30", "NaN", "inf", "3600.5", "1e-300", "0.0009",
        ] {
            let e = seconds(bad).unwrap_err();
            assert!(e.contains("[0.001, 3600]"), "{bad}: {e}");
        }
        assert!(seconds("ten").unwrap_err().contains("not a number"));
        assert_eq!(fps("1"), Ok(1.0));
        for bad in ["0", "1e-300", "0.5", "1001"] {
            assert!(fps(bad).unwrap_err().contains("[1, 1000]"), "{bad}");
            assert!(fps_f32(bad).unwrap_err().contains("[1, 1000]"), "{bad}");
        }
        assert!(fps("30").is_ok() && fps_f32("1000").is_ok());
        assert!(density("0.05").is_ok() && density("11").is_err());
        assert_eq!(density("1e-6"), Ok(1e-6));
        for bad in ["1e-300", "1e-7", "0"] {
            assert!(
                density(bad).unwrap_err().contains("[0.000001, 10]"),
                "{bad}"
            );
        }
        // Refused when the command line is read, not after the data are loaded.
        assert_eq!(control_margin("0"), Ok(0.0));
        assert_eq!(control_min_t("2"), Ok(2.0));
        for bad in ["-1", "NaN", "inf", "1e308", "1.5"] {
            assert!(control_margin(bad).unwrap_err().contains("[0, 1]"), "{bad}");
        }
        for bad in ["-0.5", "NaN", "inf", "101"] {
            assert!(
                control_min_t(bad).unwrap_err().contains("[0, 100]"),
                "{bad}"
            );
        }
        for bad in ["0", "1e-300", "1e-45", "61"] {
            assert!(
                export_seconds(bad).unwrap_err().contains("[0.001, 60]"),
                "{bad}"
            );
        }
        assert_eq!(finite_f32("-0.25"), Ok(-0.25));
        for bad in ["1e39", "-1e300", "NaN", "inf"] {
            assert!(
                finite_f32(bad).unwrap_err().contains("not a finite number"),
                "{bad}"
            );
        }
        assert_eq!(band("0"), Ok(0.0));
        assert_eq!(band("1"), Ok(1.0));
        for bad in ["-0.1", "1.5", "NaN", "inf"] {
            assert!(band(bad).unwrap_err().contains("[0, 1]"), "{bad}");
        }
    }
}
