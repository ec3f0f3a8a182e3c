//! The naive-kriging crowd (the baseline of every crowd table) is deterministic whatever the thread
//! count: the same poses, bit for bit, for 1, 2 and 8 threads, at the level its policy gives.

use crate::common;

use crowd_sim::{Camera, CrowdConfig};
use lod_policy::FullDetail;
use motion_lod::NaiveSource;

use common::built;

#[test]
fn naive_crowd_poses_are_bit_identical_for_1_2_and_8_threads() {
    let (model, analysis) = built();
    let source = NaiveSource::new(model, analysis).unwrap();
    let policy = FullDetail::for_model(model.lod());
    let config = CrowdConfig {
        seed: 17,
        ..CrowdConfig::with_density(120, 0.05)
    };
    let lens = Camera::default();
    let path = crowd_sim::CameraPath::inside_crowd(config.field_size_m);
    let simulate = |threads: usize| -> Vec<u32> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut crowd = crowd_sim::Crowd::new(&source, config).unwrap();
            // 2.5 s: every walker finishes a cycle and chains the next (about 1.1 s each).
            for f in 0..75 {
                let cam = path.camera_at(f as f32 / 30.0, &lens);
                crowd.step(&source, &policy, &cam, 1.0 / 30.0).unwrap();
            }
            (0..crowd.len())
                .flat_map(|i| crowd.joint_positions(i).to_vec())
                .flat_map(|p| p.to_array())
                .map(f32::to_bits)
                .collect()
        })
    };
    let one = simulate(1);
    assert_eq!(one.len(), 120 * (model.lod().joints() + 1) * 3);
    assert!(one.iter().all(|&b| f32::from_bits(b).is_finite()));
    assert!(one == simulate(2), "2 threads differ from 1");
    assert!(one == simulate(8), "8 threads differ from 1");
}
