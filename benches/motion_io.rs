//! motion-io: runtime pose FK (f32, per walker per frame), pose extraction and BVH parsing.
//! Uses a Bandai take from ../shared/mocap when present, else a generated skeleton.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use motion_io::{Motion, PoseLayout, parse_bvh, to_bvh_string};

fn sample_motion() -> Motion {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/mocap/bandai-namco-2-walk/dataset-2_walk_normal_001.bvh"
    );
    if let Ok(m) = motion_io::read_bvh(p) {
        return m;
    }
    // Fallback: a 22-joint chain-tree with 3 rotation channels per joint.
    use motion_io::{Channel::*, Joint, Skeleton};
    let mut joints = vec![Joint {
        name: "root".into(),
        parent: None,
        offset: glam::DVec3::ZERO,
        channels: vec![
            Xposition, Yposition, Zposition, Zrotation, Xrotation, Yrotation,
        ],
        end_site: None,
    }];
    for i in 1..22 {
        joints.push(Joint {
            name: format!("j{i}"),
            parent: Some(if i % 5 == 1 { 0 } else { i - 1 }),
            offset: glam::DVec3::new(0.0, 10.0, 1.0),
            channels: vec![Zrotation, Xrotation, Yrotation],
            end_site: None,
        });
    }
    let sk = Skeleton { joints };
    let n = sk.channel_count();
    let frames = (0..200 * n)
        .map(|k| ((k * 37) % 90) as f64 - 45.0)
        .collect();
    Motion {
        skeleton: sk,
        frame_time: 1.0 / 30.0,
        frames,
    }
}

fn bench(c: &mut Criterion) {
    let m = sample_motion();
    let layout = PoseLayout::from_motions(&[&m], 100.0).unwrap();
    let poses = layout.poses_from_motion(&m).unwrap();
    let p = layout.dof();
    let pose32: Vec<f32> = poses[10 * p..11 * p].iter().map(|&x| x as f32).collect();
    let mut out = vec![Vec3::ZERO; m.skeleton.joints.len()];
    c.bench_function("motion_io/joint_positions_f32_all_joints", |b| {
        b.iter(|| layout.joint_positions(black_box(&pose32), layout.joint_count(), &mut out))
    });
    c.bench_function("motion_io/joint_positions_f32_5_active", |b| {
        b.iter(|| layout.joint_positions(black_box(&pose32), 5, &mut out))
    });
    let mut row = vec![0.0; p];
    c.bench_function("motion_io/pose_from_frame", |b| {
        b.iter(|| layout.pose_from_frame(&m, black_box(10), &mut row).unwrap())
    });
    let text = to_bvh_string(&m);
    c.bench_function(
        &format!("motion_io/parse_bvh_{}KB", text.len() / 1024),
        |b| b.iter(|| parse_bvh(black_box(&text)).unwrap()),
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
