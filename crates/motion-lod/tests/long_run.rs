//! Issue 8's long run: a crowd animated by the model for one hour of animated time (fast forward) keeps
//! every walker finite, near its path, inside the field and inside the level table, and its memory does
//! not grow after the first minutes.

use crowd_sim::{Camera, CameraPath, Crowd, CrowdConfig, FrameStats};
use glam::Vec2;
use lod_policy::DistancePolicy;
use motion_lod::dataset::DataSpec;
use motion_lod::progress::NoProgress;
use motion_lod::{BuildConfig, LodSource, MotionModel};

/// Resident set size of this process in bytes (Linux), if it can be read.
fn rss_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

#[test]
fn one_hour_of_animated_time_stays_finite_on_path_and_bounded() {
    let loaded = DataSpec::default()
        .load_with_default(motion_io::test_data::fixture_takes(), &|_, _| {})
        .unwrap();
    let model = MotionModel::build(&loaded.training, &BuildConfig::default(), &NoProgress).unwrap();
    let lod = model.lod();
    let source = LodSource::new(&model);
    let policy = DistancePolicy::for_model(lod);
    let config = CrowdConfig {
        seed: 11,
        ..CrowdConfig::with_density(60, 0.05)
    };
    let mut crowd = Crowd::new(&source, config).unwrap();
    let path = CameraPath::inside_crowd(config.field_size_m);
    let lens = Camera::default();
    // Fast forward: 0.5 s steps (about half a cycle) for 3600 s of animated time.
    let dt = 0.5f32;
    let steps = (3600.0 / dt) as usize;
    let mut stats = FrameStats::default();
    let half = config.field_size_m / 2.0;
    let bins = crowd.levels().histogram_bins();
    let mut rss_after_warmup = None;
    for step in 0..steps {
        let cam = path.camera_at(step as f32 * dt, &lens);
        crowd
            .step_into(&source, &policy, &cam, dt, &mut stats)
            .unwrap();
        assert_eq!(stats.level_histogram.len(), bins);
        assert_eq!(
            stats.level_histogram.iter().sum::<u32>() as usize,
            crowd.len()
        );
        if step % 100 == 0 || step + 1 == steps {
            for i in 0..crowd.len() {
                let p = crowd.root_position(i);
                assert!(p.is_finite(), "walker {i} at step {step}: {p}");
                assert!(
                    p.x.abs() <= half && p.z.abs() <= half,
                    "walker {i} left the field: {p}"
                );
                let off = crowd.path(i).distance_to(Vec2::new(p.x, p.z));
                assert!(
                    off < 1.0,
                    "walker {i} is {off:.2} m off its path at step {step}"
                );
                assert!(crowd.level_bin(i) < bins);
                assert!(crowd.joint_positions(i).iter().all(|j| j.is_finite()));
            }
        }
        if step == steps / 6 {
            rss_after_warmup = rss_bytes();
        }
    }
    assert!((crowd.time_s() - 3600.0).abs() < 1.0, "{}", crowd.time_s());
    if let (Some(a), Some(b)) = (rss_after_warmup, rss_bytes()) {
        assert!(
            b <= a + 8 * 1024 * 1024,
            "resident memory grew from {a} to {b} bytes"
        );
    }
}
