//! Bad and extreme input to the crowd's public API: clear errors, no panic, no abort, no NaN in an
//! `Ok` (the audit of the crate's API).

use crate::altered::Altered;
use crowd_sim::culling::WalkerAabbTree;
use crowd_sim::render::{Image, render_frame, render_map, write_gif_atomic, write_png_atomic};
use crowd_sim::testing::{ProceduralSource, paper_distance_policy};
use crowd_sim::{
    Bounds, Camera, CameraPath, ClipSource, Crowd, CrowdConfig, CrowdError, CrowdReport, Culling,
    FrameTimes, Frustum, LevelTable, MAX_FIELD_M, MAX_WALKERS, RenderError, StageTimings,
};
use glam::Vec3;
use lod_policy::{Detail, ViewParams};
use std::time::Duration;

const DT: f32 = 1.0 / 30.0;

fn config(walkers: usize) -> CrowdConfig {
    CrowdConfig {
        walkers,
        field_size_m: 60.0,
        ..CrowdConfig::default()
    }
}

/// Defect 16: the walker count is capped, and a crowd within the cap that the machine cannot hold
/// is an error, not an abort (nor a capacity-overflow panic).
#[test]
fn too_many_walkers_or_too_much_memory_are_errors() {
    let source = ProceduralSource::new();
    for walkers in [usize::MAX, 1 << 33, MAX_WALKERS + 1] {
        let e = Crowd::new(&source, config(walkers)).err();
        assert_eq!(e, Some(CrowdError::TooManyWalkers { walkers }), "{walkers}");
        assert!(config(walkers).validate().is_err());
    }
    assert!(config(MAX_WALKERS).validate().is_ok());
    let msg = CrowdError::TooManyWalkers { walkers: 1 << 33 }.to_string();
    assert!(
        msg.contains("8589934592") && msg.contains("2147483647"),
        "{msg}"
    );
    // Pose vectors whose size overflows, or needs more than the address space.
    let levels = source.levels();
    for pose_len in [usize::MAX / 2, 1 << 45] {
        let big = Altered::with_levels(source.clone(), LevelTable { pose_len, ..levels });
        let e = Crowd::new(&big, config(4)).err();
        assert!(
            matches!(
                e,
                Some(CrowdError::OutOfMemory {
                    what: "pose vectors",
                    walkers: 4
                })
            ),
            "{e:?}"
        );
    }
    // A level table too large for its histogram.
    let big = Altered::with_levels(
        source.clone(),
        LevelTable {
            accuracy_levels: usize::MAX,
            ..levels
        },
    );
    assert!(matches!(
        Crowd::new(&big, config(4)),
        Err(CrowdError::OutOfMemory { .. })
    ));
    // An ordinary crowd is unchanged.
    assert_eq!(Crowd::new(&source, config(100)).unwrap().len(), 100);
}

/// Defect 17: a report's room for frames is a hint, capped; a crowd still runs and reports.
#[test]
fn a_report_for_very_many_frames_reserves_a_bounded_room() {
    for frames in [usize::MAX, 1 << 37] {
        let r = CrowdReport::with_frames(frames);
        assert_eq!(r.frames, 0);
        assert!(r.frame_s.capacity() <= CrowdReport::MAX_RESERVED_FRAMES);
        assert!(r.frame_allocations.capacity() <= CrowdReport::MAX_RESERVED_FRAMES);
    }
    assert!(CrowdReport::with_frames(100).frame_s.capacity() >= 100);
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let mut crowd = Crowd::new(&source, config(20)).unwrap();
    let r = crowd
        .run(&source, &policy, &CameraPath::Fixed, &Camera::default(), 3)
        .unwrap();
    assert_eq!((r.frames, r.frame_s.len()), (3, 3));
}

/// Defect 18: cameras whose view vector, side planes or frustum overflow are refused by
/// `validate`, `Frustum::from_camera`, the step and rendering.
#[test]
fn degenerate_frustums_are_errors() {
    let source = ProceduralSource::new();
    let policy = paper_distance_policy(source.levels());
    let base = Camera::default();
    let cams = [
        Camera {
            position: Vec3::new(-3e38, 1.7, 0.0),
            target: Vec3::new(3e38, 1.7, 0.0),
            ..base
        },
        Camera {
            aspect: 3e38,
            ..base
        },
        Camera {
            position: Vec3::new(3e38, 3e38, 3e38),
            target: Vec3::new(3e38, 3e38, 2e38),
            ..base
        },
    ];
    for cam in cams {
        let e = cam.validate().unwrap_err();
        assert!(matches!(e, CrowdError::BadCamera { .. }), "{e}");
        assert!(Frustum::from_camera(&cam).is_err());
        let mut crowd = Crowd::new(&source, config(10)).unwrap();
        assert!(matches!(
            crowd.step(&source, &policy, &cam, DT),
            Err(CrowdError::BadCamera { .. })
        ));
        assert!(matches!(
            render_frame(&crowd, &cam, &Default::default()),
            Err(RenderError::Camera(_))
        ));
        assert!(render_map(&crowd, &cam, &Default::default(), 64).is_err());
    }
    let e = cams[0].validate().unwrap_err().to_string();
    assert!(e.contains("target - position"), "{e}");
    let e = cams[1].validate().unwrap_err().to_string();
    assert!(e.contains("aspect"), "{e}");
    // Every plane of an accepted camera is finite with a unit normal.
    for cam in [
        base,
        Camera {
            fov_y: 3.1415925,
            ..base
        },
        Camera { far: 3e38, ..base },
    ] {
        if let Ok(f) = Frustum::from_camera(&cam) {
            for p in f.planes() {
                assert!(p.is_finite() && (p.truncate().length() - 1.0).abs() < 1e-3);
            }
        }
    }
}

/// Defect 19: a detail with too many joints says so, naming the joints, not a level.
#[test]
fn a_policy_asking_for_too_many_joints_names_them() {
    let source = ProceduralSource::new();
    let levels = source.levels();
    let many = |_: f32, _: bool, _: &ViewParams| Detail::new(0, usize::MAX);
    let want = CrowdError::BadJoints {
        walker: 0,
        level: 0,
        active_joints: usize::MAX,
        joints: levels.joints,
    };
    let mut crowd = Crowd::new(&source, config(10)).unwrap();
    let e = crowd
        .step(&source, &many, &Camera::default(), DT)
        .unwrap_err();
    assert_eq!(e, want);
    assert!(e.to_string().contains("joints"), "{e}");
    let mut crowd = Crowd::new(&source, config(10)).unwrap();
    assert_eq!(
        crowd.prime(&source, &many, &Camera::default()).unwrap_err(),
        want
    );
    // A level the source does not have is still a level error (before the joints).
    let both = |_: f32, _: bool, _: &ViewParams| Detail::new(usize::MAX, usize::MAX);
    assert!(matches!(
        crowd.step(&source, &both, &Camera::default(), DT),
        Err(CrowdError::BadLevel {
            level: usize::MAX,
            ..
        })
    ));
}

/// Defect 20: the culling tree takes NaN, infinite, huge and inverted boxes without panicking,
/// never shows a NaN box, answers as the frustum test for the rest, and says what it asks of the
/// flag slice.
#[test]
fn the_culling_tree_takes_any_boxes() {
    let f = Frustum::from_camera(&Camera::default()).unwrap();
    let boxes: Vec<Bounds> = (0..400)
        .map(|i| {
            let c = Vec3::new(
                (i * 37 % 101) as f32 - 50.0,
                0.0,
                (i * 53 % 97) as f32 - 20.0,
            );
            Bounds {
                min: c - 0.5,
                max: c + 0.5,
            }
        })
        .collect();
    let mut odd = boxes.clone();
    for i in (0..400).step_by(7) {
        odd[i] = Bounds {
            min: Vec3::NAN,
            max: Vec3::NAN,
        };
    }
    odd[3].min.x = f32::NAN;
    odd[5] = Bounds {
        min: Vec3::splat(-3e38),
        max: Vec3::splat(3e38),
    };
    odd[9] = Bounds {
        min: Vec3::new(5.0, 1.0, 30.0),
        max: Vec3::new(-5.0, 0.0, 10.0),
    };
    odd[11] = Bounds {
        min: Vec3::splat(f32::NEG_INFINITY),
        max: Vec3::new(f32::INFINITY, 2.0, f32::INFINITY),
    };
    let all_nan = vec![
        Bounds {
            min: Vec3::NAN,
            max: Vec3::NAN,
        };
        100
    ];
    let mut nan_tree = WalkerAabbTree::new(&all_nan);
    let mut vis = vec![true; 100];
    assert_eq!(nan_tree.query(&f, &mut vis), 0);
    assert!(vis.iter().all(|v| !v));

    let mut tree = WalkerAabbTree::new(&odd);
    let mut vis = vec![false; 400];
    for round in 0..3 {
        match round {
            0 => {}
            1 => tree.refit(&odd),
            _ => tree.rebuild(&odd),
        }
        let n = tree.query(&f, &mut vis);
        assert_eq!(n, vis.iter().filter(|v| **v).count());
        for (i, b) in odd.iter().enumerate() {
            if b.min.is_nan() || b.max.is_nan() {
                assert!(!vis[i], "NaN box {i} visible");
            } else if b.min.is_finite() && b.max.is_finite() {
                assert_eq!(vis[i], f.intersects(b), "box {i} {b:?} (round {round})");
            }
        }
        assert!(vis[5], "the huge box spans the frustum");
    }
    // The normal boxes among them are answered as by a tree of the normal boxes alone.
    let mut clean = WalkerAabbTree::new(&boxes);
    let mut clean_vis = vec![false; 400];
    clean.query(&f, &mut clean_vis);
    for i in (0..400).filter(|i| i % 7 != 0 && ![3, 5, 9, 11].contains(i)) {
        assert_eq!(vis[i], clean_vis[i], "box {i}");
    }
    // A flag slice of the wrong length is a documented panic with a message, in every profile.
    let short = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        clean.query(&f, &mut [false; 3])
    }));
    let msg = short.unwrap_err();
    let msg = msg
        .downcast_ref::<String>()
        .map(String::as_str)
        .unwrap_or_default();
    assert!(msg.contains("one visibility flag per box"), "{msg}");
}

/// Defect 20 in the crowd: walkers whose boxes are NaN (a source gone wrong) under the tree are
/// culled as the scan culls them.
#[test]
fn a_crowd_culled_by_the_tree_survives_nan_roots() {
    let source = Altered {
        pose: |out| out[0] = f32::NAN,
        ..Altered::new(ProceduralSource::new())
    };
    let policy = paper_distance_policy(source.levels());
    let mut flags = Vec::new();
    for culling in [Culling::Scan, Culling::Tree] {
        let cfg = CrowdConfig {
            culling,
            tree_rebuild_interval: 2,
            ..config(200)
        };
        let mut crowd = Crowd::new(&source, cfg).unwrap();
        for _ in 0..4 {
            crowd
                .step(&source, &policy, &Camera::default(), DT)
                .unwrap();
        }
        flags.push(crowd.visible_flags().to_vec());
    }
    assert_eq!(flags[0], flags[1]);
}

/// Defect 21: hand-built images whose buffer is short are refused by the GIF writer as by the
/// PNG writer, and read or drawn without a panic.
#[test]
fn short_image_buffers_are_errors_or_ignored() {
    let dir = std::env::temp_dir().join(format!("crowd-sim-robustness-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = Image::new(10, 10, [1, 2, 3]).unwrap();
    let short = Image {
        width: 10,
        height: 10,
        rgb: vec![0; 10],
    };
    for frames in [vec![short.clone()], vec![good.clone(), short.clone()]] {
        let e = write_gif_atomic(&dir.join("bad.gif"), &frames, 3).unwrap_err();
        assert!(matches!(e, RenderError::BadSize { .. }), "{e}");
    }
    assert!(matches!(
        write_png_atomic(&dir.join("bad.png"), &short),
        Err(RenderError::BadSize { .. })
    ));
    assert!(!dir.join("bad.gif").exists());
    write_gif_atomic(&dir.join("good.gif"), &[good.clone(), good.clone()], 3).unwrap();
    let mut img = short;
    img.put(5, 5, [9, 9, 9]);
    img.put(1 << 32, 0, [9, 9, 9]);
    assert_eq!(img.pixel(5, 5), None);
    assert_eq!(img.pixel(2, 0), Some([0, 0, 0]));
    assert_eq!(img.pixel(3, 0), None);
    img.line([0.0, 0.0], [9.0, 9.0], [7, 7, 7], true);
    img.dot(8.0, 8.0, 2, [7, 7, 7]);
    assert_eq!(img.downscale(2).rgb.len(), 5 * 5 * 3);
    assert_eq!(good.pixel(9, 9), Some([1, 2, 3]));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Defect 22: mean timings over 2^32 frames or more divide instead of panicking.
#[test]
fn mean_timings_of_very_many_frames() {
    let r = CrowdReport {
        frames: 1 << 32,
        total: StageTimings {
            kernels: Duration::from_secs(1 << 32),
            ..StageTimings::default()
        },
        ..CrowdReport::default()
    };
    let m = r.mean_timings();
    assert_eq!(m.kernels, Duration::from_secs(1));
    assert_eq!(m.cull, Duration::ZERO);
    let r = CrowdReport {
        frames: usize::MAX,
        ..r
    };
    assert!(r.mean_timings().kernels < Duration::from_nanos(1));
    assert!(r.to_string().contains("frames"));
}

/// Defect 23: a table without levels has one histogram bin, and every detail falls in it.
#[test]
fn a_level_table_without_levels_bins_into_its_one_bin() {
    let t = LevelTable {
        accuracy_levels: 0,
        joints: 3,
        pose_len: 10,
    };
    assert_eq!(t.histogram_bins(), 1);
    assert_eq!(t.bin(&Detail::new(0, 1)), 0);
    assert_eq!(t.bin(&Detail::new(5, 0)), 0);
    let t = LevelTable {
        accuracy_levels: usize::MAX,
        ..t
    };
    assert_eq!(t.histogram_bins(), usize::MAX);
}

/// Defect 25: frame times that are not times are refused, not turned into NaN percentiles.
#[test]
fn frame_times_refuse_values_that_are_not_times() {
    for bad in [
        &[f64::NAN, 1.0, f64::INFINITY, -1.0][..],
        &[0.01, f64::NAN],
        &[0.01, f64::INFINITY],
        &[0.01, -0.5],
        &[],
    ] {
        assert_eq!(FrameTimes::of_seconds(bad), None, "{bad:?}");
    }
    let t = FrameTimes::of_seconds(&[0.0, 0.02, 0.01]).unwrap();
    assert_eq!(t.frames, 3);
    assert!((t.worst_ms - 20.0).abs() < 1e-9 && (t.p50_ms - 10.0).abs() < 1e-9);
}

/// Defect 26: the field side is capped (as given, and as enlarged for the paths), with a clear
/// error; the largest field accepted still runs.
#[test]
fn fields_beyond_the_cap_are_errors() {
    let source = ProceduralSource::new();
    for field in [1e20f32, 3e38, MAX_FIELD_M * 1.001] {
        let cfg = CrowdConfig {
            field_size_m: field,
            ..config(8)
        };
        let e = Crowd::new(&source, cfg).err().unwrap();
        assert_eq!(
            e,
            CrowdError::AboveLimit {
                field: "field_size_m",
                value: f64::from(field),
                max: f64::from(MAX_FIELD_M),
            }
        );
        assert!(e.to_string().contains("field_size_m"), "{e}");
    }
    // A border that needs the field enlarged beyond the cap.
    let cfg = CrowdConfig {
        border_m: 1e30,
        ..config(4)
    };
    let e = Crowd::new(&source, cfg).err().unwrap();
    assert!(matches!(e, CrowdError::FieldTooLarge { .. }), "{e}");
    // The command line's largest field (a million walkers at one per square kilometre) and the
    // cap itself are fields a crowd walks on.
    let policy = paper_distance_policy(source.levels());
    for field in [(1e6f32 / 1e-6).sqrt(), MAX_FIELD_M] {
        let cfg = CrowdConfig {
            field_size_m: field,
            ..config(8)
        };
        let mut crowd = Crowd::new(&source, cfg).unwrap();
        for _ in 0..5 {
            crowd
                .step(&source, &policy, &Camera::default(), DT)
                .unwrap();
        }
        for i in 0..crowd.len() {
            assert!(crowd.root_position(i).is_finite());
            assert!(crowd.joint_positions(i).iter().all(|p| p.is_finite()));
        }
    }
}
