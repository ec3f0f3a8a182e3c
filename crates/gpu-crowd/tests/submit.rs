//! `GpuCrowd::submit`: frames left in flight walk exactly as `step`'s, their statistics come one
//! call later, and a split frame or a refused one keeps that order. On any adapter (lavapipe in
//! CI).

use crowd_sim::{Camera, CrowdConfig, Scene};
use gpu_crowd::{Gpu, GpuCrowd, GpuFrameStats, GpuOptions, WalkerJoints};
use lod_policy::DistancePolicy;

mod common;
use common::{gpu, model};

const DT: f32 = 1.0 / 30.0;

/// A crowd of 600 walkers at 0.2 a square metre with the CPU crowd's defaults (seams and the
/// foot lock at every level) and 60 joint slots, so that every pass runs.
fn crowd(gpu: &Gpu) -> GpuCrowd {
    let options = GpuOptions {
        joint_slots: Some(60),
        ..GpuOptions::default()
    };
    GpuCrowd::new(gpu, model(), CrowdConfig::with_density(600, 0.2), options)
        .expect("the GPU crowd")
}

/// A frame's statistics without its timings.
fn counts(s: &GpuFrameStats) -> GpuFrameStats {
    GpuFrameStats {
        gpu: Default::default(),
        wall: Default::default(),
        ..s.clone()
    }
}

fn bits(walkers: &[WalkerJoints]) -> Vec<(usize, usize, Vec<[u32; 3]>)> {
    walkers
        .iter()
        .map(|w| {
            (
                w.detail.accuracy,
                w.detail.active_joints,
                w.positions
                    .iter()
                    .map(|p| p.to_array().map(f32::to_bits))
                    .collect(),
            )
        })
        .collect()
}

/// 90 frames, the 46th 2.5 s long (split into rounds), stepped by one crowd and submitted by
/// another: the same walkers bit for bit whenever read, and each frame's statistics from
/// `submit` one call later (the split frame's too), the last from `finish`.
#[test]
fn submitted_frames_walk_as_stepped_frames() {
    let Some(gpu) = gpu() else {
        return;
    };
    let (mut stepped, mut submitted) = (crowd(gpu), crowd(gpu));
    let field = stepped.config().field_size_m;
    let (path, lens) = (
        Scene::Ground.path(field),
        Scene::Ground.lens(Camera::default(), field),
    );
    let policy = DistancePolicy::for_model(model().lod());
    let mut expected: Vec<GpuFrameStats> = Vec::new();
    let mut got: Vec<GpuFrameStats> = Vec::new();
    for f in 0..90 {
        let dt = if f == 45 { 2.5 } else { DT };
        let cam = path.camera_at(f as f32 * DT, &lens);
        expected.push(counts(&stepped.step(&policy, &cam, dt).unwrap()));
        let before = submitted.submit(&policy, &cam, dt).unwrap();
        assert_eq!(before.is_none(), f == 0, "frame {f}");
        got.extend(before.as_ref().map(counts));
        if f % 30 == 29 {
            // The frame in flight is part of what is read (the queue runs in order).
            assert_eq!(
                bits(&stepped.read_walkers().unwrap()),
                bits(&submitted.read_walkers().unwrap()),
                "frame {f}"
            );
        }
    }
    got.extend(submitted.finish().unwrap().as_ref().map(counts));
    assert_eq!(submitted.finish().unwrap(), None, "nothing left in flight");
    assert_eq!(got.len(), expected.len());
    for (f, (a, b)) in expected.iter().zip(&got).enumerate() {
        assert_eq!(a, b, "frame {f}");
    }
    assert!(expected[45].rounds > 1, "{:?}", expected[45]);
    assert!(expected.iter().any(|s| s.slot_faults > 0));
    assert!(expected.iter().any(|s| s.in_transition > 0));
}

/// A frame refused before it is submitted (a NaN step, a step beyond `MAX_DT`) is the error of
/// its call; the frame in flight is untouched and its statistics come with the next call.
#[test]
fn a_refused_frame_leaves_the_frame_in_flight() {
    let Some(gpu) = gpu() else {
        return;
    };
    let mut crowd = crowd(gpu);
    let field = crowd.config().field_size_m;
    let cam = Scene::Ground
        .path(field)
        .camera_at(0.0, &Scene::Ground.lens(Camera::default(), field));
    let policy = DistancePolicy::for_model(model().lod());
    assert_eq!(crowd.submit(&policy, &cam, DT).unwrap(), None);
    for bad in [f32::NAN, 11.0] {
        assert!(crowd.submit(&policy, &cam, bad).is_err(), "dt {bad}");
    }
    let first = crowd.submit(&policy, &cam, DT).unwrap().expect("frame 1");
    let second = crowd.finish().unwrap().expect("frame 2");
    let mut fresh = self::crowd(gpu);
    assert_eq!(
        counts(&first),
        counts(&fresh.step(&policy, &cam, DT).unwrap())
    );
    assert_eq!(
        counts(&second),
        counts(&fresh.step(&policy, &cam, DT).unwrap())
    );
}
