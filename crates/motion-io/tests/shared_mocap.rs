//! Acceptance on the shared BVH folders (skipped when ../shared/mocap is absent; a failure then when
//! `MOTION_LOD_REQUIRE_DATA` is set, as in CI).

use std::path::PathBuf;

use motion_io::{
    CycleConfig, Motion, PoseLayout, Transform, detect_units_per_metre, parse_bvh, read_folder,
    segment_cycles, to_bvh_string,
};

fn folder(name: &str) -> Option<PathBuf> {
    motion_io::test_data::shared_mocap(env!("CARGO_MANIFEST_DIR"), name)
}

fn load(name: &str, expected: usize) -> Option<Vec<(PathBuf, Motion)>> {
    let r = read_folder(folder(name)?).unwrap();
    assert!(r.failed.is_empty(), "{:?}", r.failed);
    assert_eq!(r.motions.len(), expected);
    Some(r.motions)
}

/// BVH -> pose vectors -> BVH text -> parse: FK of the written file equals FK of the source.
fn check_round_trip(m: &Motion, layout: &PoseLayout) {
    let poses = layout.poses_from_motion(m).unwrap();
    let written = layout.motion_from_poses(&poses, m.frame_time).unwrap();
    let back = parse_bvh(&to_bvh_string(&written)).unwrap();
    assert_eq!(back.frame_count(), m.frame_count());
    let nj = m.skeleton.joints.len();
    let (mut a, mut b) = (vec![Transform::IDENTITY; nj], vec![Transform::IDENTITY; nj]);
    let mut worst = 0.0f64;
    for f in 0..m.frame_count() {
        m.skeleton.forward_kinematics(m.frame(f), &mut a);
        back.skeleton.forward_kinematics(back.frame(f), &mut b);
        for j in 0..nj {
            worst = worst.max((a[j].position - b[j].position).length());
        }
    }
    // 6 written decimals of degrees over chains of ~100 units.
    assert!(worst < 1e-3, "FK differs by {worst} units");
    // With the source frame as Euler reference the channels themselves come back within 1e-4.
    let p = layout.dof();
    let mut ch = vec![0.0; m.skeleton.channel_count()];
    let varying: Vec<bool> = (0..ch.len())
        .map(|k| {
            m.frames
                .iter()
                .skip(k)
                .step_by(ch.len())
                .any(|v| (v - m.frames[k]).abs() > 1e-9)
        })
        .collect();
    for f in (0..m.frame_count()).step_by(7) {
        layout
            .frame_from_pose_near(&poses[f * p..(f + 1) * p], m.frame(f), &mut ch)
            .unwrap();
        for (k, (x, y)) in ch.iter().zip(m.frame(f)).enumerate() {
            // Static channels come from the layout's template (its first take); they only agree
            // when the template is this take or the channel is the same everywhere.
            if varying[k] {
                assert!((x - y).abs() < 1e-4, "frame {f} channel {k}: {x} vs {y}");
            }
        }
    }
}

#[test]
fn bandai_loads_segments_and_round_trips() {
    let Some(takes) = load("bandai-namco-2-walk", 168) else {
        return;
    };
    let ms: Vec<&Motion> = takes.iter().map(|t| &t.1).collect();
    let upm = detect_units_per_metre(ms[0]);
    assert_eq!(upm, 100.0);
    let layout = PoseLayout::from_motions(&ms, upm).unwrap();
    assert_eq!(layout.skeleton().joints[layout.root()].name, "Hips");
    assert_eq!(layout.dof(), 7 + 3 * 20);
    let cfg = CycleConfig::default();
    let mut cycles = Vec::new();
    for (p, m) in &takes {
        cycles.extend(segment_cycles(m, &layout, &cfg, p).unwrap().cycles);
    }
    let n = cycles.len();
    assert!((600..=1000).contains(&n), "{n} cycles");
    let mut lens: Vec<usize> = cycles.iter().map(|c| c.frame_count()).collect();
    lens.sort_unstable();
    assert!(
        lens[0] >= 20 && lens[n - 1] <= 45 && (30..=38).contains(&lens[n / 2]),
        "{lens:?}"
    );
    let deg: Vec<f64> = cycles
        .iter()
        .map(|c| c.controls.turn.to_degrees())
        .collect();
    assert!(
        deg.iter().filter(|t| **t > 20.0).count() >= 20,
        "left turns"
    );
    assert!(
        deg.iter().filter(|t| **t < -20.0).count() >= 20,
        "right turns"
    );
    assert!(
        deg.iter().filter(|t| t.abs() < 5.0).count() >= 200,
        "straight walks"
    );
    // Straight walks are straight: the heading is the direction of travel, not the hip line
    // (which is yawed 2.4 degrees off it on average, a sideways drift of 5.5 cm per cycle).
    let straight: Vec<f64> = cycles
        .iter()
        .filter(|c| !c.source.to_string_lossy().contains("turn"))
        .map(|c| c.controls.dx)
        .collect();
    let ns = straight.len() as f64;
    let mean_abs = straight.iter().map(|d| d.abs()).sum::<f64>() / ns;
    let mean = straight.iter().sum::<f64>() / ns;
    assert!(
        ns >= 300.0 && mean_abs < 0.025 && mean.abs() < 0.005,
        "{ns} straight-walk cycles: mean |dx| {mean_abs} m, mean dx {mean} m"
    );
    let p = layout.dof();
    for c in &cycles {
        // Canonical start: root over the origin; forward walking in metres.
        assert!(c.poses[0].abs() < 1e-9 && c.poses[2].abs() < 1e-9);
        assert!(
            (0.8..1.2).contains(&c.poses[1]),
            "root height {} m",
            c.poses[1]
        );
        assert!(
            (0.2..2.5).contains(&c.controls.dz) && c.controls.dx.abs() < 1.5,
            "{:?}",
            c.controls
        );
        assert!((c.controls.height - cycles[0].controls.height).abs() < 1e-12);
        assert_eq!(c.poses.len(), c.frame_count() * p);
        assert!(c.left_contact[0] && c.right_contact[c.right_contact_start]);
        // Continuity over time of every exp-map row.
        for f in 1..c.frame_count() {
            for r in 3..p {
                assert!(
                    r == 6 || (c.poses[f * p + r] - c.poses[(f - 1) * p + r]).abs() < 1.5,
                    "{c:?} row {r}"
                );
            }
        }
    }
    let feat = cycles[0].features(&layout);
    assert_eq!(
        feat.len(),
        cycles[0].frame_count() * 3 * layout.joint_count()
    );
    // Round trips on a few takes (a walk and both turns).
    for k in [0, 60, 120] {
        check_round_trip(&takes[k].1, &layout);
    }
}

#[test]
fn cmu_loads_segments_and_round_trips() {
    let Some(takes) = load("cmu-daz-walk-s07-s08", 22) else {
        return;
    };
    let ms: Vec<&Motion> = takes.iter().map(|t| &t.1).collect();
    let layout = PoseLayout::from_motions(&ms, detect_units_per_metre(ms[0])).unwrap();
    assert_eq!(layout.root(), 0);
    // 43 joints; fingers, eyes, collars and buttocks never move: 16 rotating joints below the root.
    let names: Vec<&str> = layout
        .joint_order()
        .iter()
        .map(|&j| layout.skeleton().joints[j].name.as_str())
        .collect();
    assert_eq!(layout.joint_count(), 16, "{names:?}");
    assert!(
        !names
            .iter()
            .any(|n| n.contains("Index") || n.contains("Eye"))
    );
    let mut n = 0;
    for (p, m) in &takes {
        let r = segment_cycles(m, &layout, &CycleConfig::cmu(), p).unwrap();
        for c in &r.cycles {
            assert!(c.first_frame >= 12);
            assert!(c.controls.turn.abs() < 0.35 && c.controls.dz > 0.8);
        }
        n += r.cycles.len();
    }
    assert!((15..=60).contains(&n), "{n} CMU cycles");
    check_round_trip(&takes[3].1, &layout);
}
