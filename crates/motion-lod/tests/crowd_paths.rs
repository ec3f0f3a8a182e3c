//! The crowd's fast paths against the reference path, in both scenes, and the same bytes for any
//! thread count (embedded data set).

use crowd_sim::{ClipSource, CrowdConfig, Scene};
use lod_policy::DistancePolicy;
use motion_lod::LodSource;

use crate::common;

use common::{Frame, built, crowd_frames};

fn simulate<S: ClipSource>(source: &S, scene: Scene, frames: usize) -> Vec<Frame> {
    let (model, _) = built();
    // The paper's schedule as published (no screen check): this test is about the arithmetic of the
    // fast path at every kind of detail, and the published schedule uses root-only walkers in view
    // and several levels in the 300-walker overview.
    let published = lod_policy::DistanceConfig {
        screen_budget_px: None,
        ..lod_policy::DistanceConfig::default()
    };
    let policy = DistancePolicy::new(model.lod(), published).unwrap();
    let config = CrowdConfig {
        seed: 11,
        ..CrowdConfig::with_density(300, 0.01)
    };
    crowd_frames(source, &policy, config, scene, frames)
}

#[test]
fn fast_path_poses_match_the_reference_path() {
    let (model, _) = built();
    let levels = model.lod().levels().len();
    for scene in Scene::ALL {
        let fast = simulate(&LodSource::new(model), scene, 75);
        let reference = simulate(&LodSource::reference(model), scene, 75);
        let mut worst = 0.0f32;
        for (f, (a, b)) in fast.iter().zip(&reference).enumerate() {
            assert_eq!(a.bins, b.bins, "{scene:?} frame {f}: levels differ");
            for (i, (pa, pb)) in a.poses.iter().zip(&b.poses).enumerate() {
                assert_eq!(pa.len(), pb.len(), "{scene:?} frame {f} walker {i}: rows");
                for (x, y) in pa.iter().zip(pb) {
                    assert!(
                        (x - y).abs() <= 1e-5,
                        "{scene:?} frame {f} walker {i}: {x} vs {y}"
                    );
                }
            }
            for (ja, jb) in a.joints.iter().zip(&b.joints) {
                assert_eq!(ja.len(), jb.len());
                for (p, q) in ja.iter().zip(jb) {
                    for k in 0..3 {
                        worst = worst.max((p[k] - q[k]).abs());
                    }
                }
            }
        }
        assert!(worst <= 1e-5, "{scene:?}: joints differ by {worst} m");
        // Root-only walkers write the 7 root rows and place the root alone.
        let last = fast.last().unwrap();
        let root_only = last.bins.iter().filter(|&&b| b == levels).count();
        assert!(root_only > 0, "{scene:?}: no root-only walker");
        for (i, &b) in last.bins.iter().enumerate() {
            if b == levels {
                assert_eq!(last.poses[i].len(), model.lod().always_rows());
                assert_eq!(last.joints[i].len(), 1);
            }
        }
        if scene == Scene::Overview {
            // The overview sees at least half the crowd, at levels between full detail and root only.
            assert!(
                2 * last.visible >= last.bins.len(),
                "visible {}",
                last.visible
            );
            let mut used: Vec<usize> = last.bins.iter().copied().filter(|&b| b < levels).collect();
            used.sort_unstable();
            used.dedup();
            assert!(used.len() >= 3, "overview levels in use: {used:?}");
        }
    }
}

#[test]
fn crowd_poses_are_bit_identical_for_1_2_and_8_threads_in_both_scenes() {
    let (model, _) = built();
    let source = LodSource::new(model);
    for scene in Scene::ALL {
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| simulate(&source, scene, 50))
        };
        let bits = |frames: &[Frame]| -> Vec<u32> {
            frames
                .iter()
                .flat_map(|f| {
                    f.poses
                        .iter()
                        .flatten()
                        .copied()
                        .chain(f.joints.iter().flatten().flatten().copied())
                })
                .map(f32::to_bits)
                .collect()
        };
        let one = run(1);
        let b1 = bits(&one);
        assert!(!b1.is_empty());
        let two = run(2);
        assert!(b1 == bits(&two), "{scene:?}: 2 threads differ from 1");
        assert_eq!(one.last().map(|f| &f.bins), two.last().map(|f| &f.bins));
        assert!(b1 == bits(&run(8)), "{scene:?}: 8 threads differ from 1");
    }
}
