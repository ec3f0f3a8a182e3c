//! `cargo xtask scaling`'s grown sets: copies of the data's takes by performers of other heights.

use motion_lod::dataset::DataSpec;
use motion_lod::folds::take_of;
use xtask::scaling::{copy_scale, grown};

#[test]
fn a_grown_set_is_the_data_then_taller_and_shorter_performers() {
    assert_eq!(
        (0..5).map(copy_scale).collect::<Vec<_>>(),
        vec![1.0, 1.02, 0.98, 1.04, 0.96]
    );
    let data = DataSpec {
        samples: Some(10),
        ..DataSpec::default()
    }
    .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
    .expect("fixtures load")
    .training;
    let [p, t, s] = data.tensor.dims();
    let n = 2 * s + 3;
    let set = grown(&data, n).expect("grows");
    assert_eq!(set.tensor.dims(), [p, t, n]);
    assert_eq!((set.controls.len(), set.sources.len()), (n, n));
    for i in 0..n {
        let (j, scale) = (i % s, copy_scale(i / s));
        let (a, b) = (data.tensor.sample(j), set.tensor.sample(i));
        for (e, (&x, &y)) in a.iter().zip(b).enumerate() {
            let want = match e % p {
                0..=2 => x * scale,
                6 => x * scale.sqrt(),
                _ => x,
            };
            assert!(
                (y - want).abs() <= 1e-12 * want.abs().max(1.0),
                "sample {i} value {e}"
            );
        }
        let ([dx, dz, turn, h], [gx, gz, gt, gh]) = (data.controls[j], set.controls[i]);
        assert_eq!([gx, gz, gt, gh], [dx * scale, dz * scale, turn, h * scale]);
        if i >= s {
            // A copy is a take of its own.
            assert_ne!(take_of(&set.sources[i]), take_of(&data.sources[j]));
            assert!(set.sources[i].contains(&format!("(x{scale:.2})")));
        }
    }
    assert!(set.styles.is_none());
    assert!(
        grown(&data, s).is_err(),
        "growing to the data's own size is refused"
    );
}

/// A set past every large-set threshold of the build (compressed values, the control selection on
/// whole takes, the kriging system kept as LU factors and factorised by panels on every thread)
/// builds the same model file, byte for byte, on pools of one and two threads, and its level 0
/// reproduces the training cycles about as well as the set it was grown from.
#[test]
fn a_large_grown_set_builds_the_same_model_on_any_pool() {
    use motion_lod::build::{BuildConfig, COMPRESS_VALUES_ABOVE, SELECT_MAX_SAMPLES};
    use motion_lod::model::MotionModel;
    use motion_lod::progress::NoProgress;
    let data = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .expect("fixtures load")
        .training;
    // Past the kriging crate's EAGER_INVERSE_MAX_SAMPLES (1,000) too.
    let n = SELECT_MAX_SAMPLES.max(COMPRESS_VALUES_ABOVE).max(1000) + 60;
    let set = grown(&data, n).expect("grows");
    let build = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool");
        let model = pool
            .install(|| MotionModel::build(&set, &BuildConfig::default(), &NoProgress))
            .expect("the large set builds");
        let bytes = motion_lod::model_file::encode(&model, std::path::Path::new("large.mlod"))
            .expect("encodes");
        (model, bytes)
    };
    let (model, one) = build(1);
    let (_, two) = build(2);
    assert!(
        one == two,
        "one and two threads built different model files"
    );
    let small = MotionModel::build(&data, &BuildConfig::default(), &NoProgress).expect("builds");
    let fit = |m: &MotionModel| m.report.keys[0].rel_error;
    let (large, base) = (fit(&model), fit(&small));
    assert!(
        large.is_finite() && large < 2.0 * base + 0.01,
        "key 0 of the grown set leaves {large} of the data, of the original {base}"
    );
    let kept = model
        .report
        .control_decisions
        .iter()
        .filter(|d| !d.dropped())
        .count();
    assert!(kept >= 1, "the selection on whole takes kept a control");
}

/// The peak resident memory a build row reports comes from `VmHWM`, and where `/proc/self/status`
/// lacks it (gVisor) from `getrusage`: the two agree on this process.
#[test]
fn peak_memory_has_a_fallback_that_agrees() {
    // Touch 64 MB so that the peak is well above the binary's own.
    let big = vec![1u8; 64 << 20];
    std::hint::black_box(&big);
    // Peaks only grow, and other tests of this binary may raise this process's meanwhile: read
    // ru_maxrss before and after VmHWM.
    let before = xtask::scaling::max_rss_bytes().expect("getrusage's ru_maxrss");
    let hwm = xtask::scaling::peak_resident_bytes().expect("a peak");
    let after = xtask::scaling::max_rss_bytes().expect("getrusage's ru_maxrss");
    assert!(before >= 64 << 20, "ru_maxrss {before}");
    assert!(
        before as f64 <= 1.1 * hwm as f64 && hwm as f64 <= 1.1 * after as f64,
        "VmHWM {hwm} against ru_maxrss {before} before and {after} after"
    );
    assert_eq!(
        xtask::scaling::parse_kb("VmHWM:\t  2048 kB", "VmHWM:").unwrap(),
        2 << 20
    );
    assert!(xtask::scaling::parse_kb("VmHWM: lots", "VmHWM:").is_err());
}
