//! Joint slots scarcer than the walkers wanting joints (`GpuOptions::joint_slots`): the slots go to
//! the walkers in view nearest the eye, move to the nearest within a cycle when the camera moves,
//! and the same walkers get them in every run. On any adapter (lavapipe in CI).

use crowd_sim::{Camera, CrowdConfig, Frustum, Scene};
use glam::Vec3;
use gpu_crowd::{Gpu, GpuCrowd, GpuOptions, WalkerJoints};
use lod_policy::FullDetail;

mod common;
use common::{gpu, model};

const DT: f32 = 1.0 / 30.0;

/// `walkers` walkers at 0.2 a square metre, seams and the foot lock on (a holder that loses its
/// slot releases both), every walker asking for its detail from the first frame.
fn config(walkers: usize) -> CrowdConfig {
    CrowdConfig {
        spread_first_builds: false,
        ..CrowdConfig::with_density(walkers, 0.2)
    }
}

fn crowd(gpu: &Gpu, walkers: usize, slots: usize) -> GpuCrowd {
    let options = GpuOptions {
        joint_slots: Some(slots),
        ..GpuOptions::default()
    };
    GpuCrowd::new(gpu, model(), config(walkers), options).expect("the GPU crowd")
}

fn roots(walkers: &[WalkerJoints]) -> Vec<Vec3> {
    walkers.iter().map(|w| w.positions[0]).collect()
}

fn holders(walkers: &[WalkerJoints]) -> Vec<usize> {
    (0..walkers.len())
        .filter(|&i| walkers[i].detail.active_joints > 0)
        .collect()
}

/// A camera 0.9 field sizes above the point (0.7 f x, 0, 0.7 f z) of the field (centred on the
/// origin), looking at its centre: every walker in view.
fn above_corner(field: f32, x: f32, z: f32) -> Camera {
    Camera {
        position: Vec3::new(0.7 * field * x, 0.9 * field, 0.7 * field * z),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y: 90f32.to_radians(),
        aspect: 1.0,
        near: 0.1,
        far: 4.0 * field,
        image_width: 640,
        image_height: 640,
    }
}

/// With more walkers in view than slots, the first frame's slots go to the walkers in view
/// nearest the eye: no walker surely out of view gets one, though some are nearer than the
/// farthest that does, and no walker surely in view without one is nearer than one with one.
#[test]
fn scarce_joint_slots_go_to_the_nearest_walkers_in_view() {
    let Some(gpu) = gpu() else {
        return;
    };
    let (n, slots) = (400, 20);
    let mut crowd = crowd(gpu, n, slots);
    let field = crowd.config().field_size_m;
    let margin = crowd.config().cull_margin_m;
    let cam = Scene::Ground
        .path(field)
        .camera_at(0.0, &Scene::Ground.lens(Camera::default(), field));
    // The frame culls and measures each walker from its root before the frame.
    let before = roots(&crowd.read_walkers().expect("walkers"));
    let frustum = Frustum::from_camera(&cam).expect("frustum");
    // A walker's box reaches at most 0.4 h + margin across and 1.1 h + margin up from its root
    // (h below 2.5 m): a root at least 4 m + margin inside every plane is surely in view, one
    // further than that outside a plane surely not.
    let reach = 4.0 + margin;
    let inside = |p: Vec3| {
        frustum
            .planes()
            .iter()
            .map(|pl| pl.truncate().dot(p) + pl.w)
            .fold(f32::INFINITY, f32::min)
    };
    let dist: Vec<f32> = before
        .iter()
        .map(|p| (*p - cam.position).length())
        .collect();
    let stats = crowd
        .step(&FullDetail::for_model(model().lod()), &cam, DT)
        .unwrap();
    let after = crowd.read_walkers().expect("walkers");
    let won = holders(&after);
    assert_eq!(won.len(), slots, "every slot given");
    assert_eq!(stats.slot_faults, (n - slots) as u64, "{stats:?}");
    assert!(stats.visible as usize > slots, "{stats:?}");
    let far_winner = won.iter().map(|&i| dist[i]).fold(0.0, f32::max);
    let hidden_nearer = (0..n)
        .filter(|&i| inside(before[i]) < -reach && dist[i] < far_winner)
        .count();
    assert!(
        hidden_nearer > 0,
        "the camera must have walkers out of view nearer than its slots reach"
    );
    for &i in &won {
        assert!(
            inside(before[i]) >= -reach,
            "walker {i}, surely out of view, got a slot"
        );
    }
    for i in (0..n).filter(|i| !won.contains(i) && inside(before[*i]) >= reach) {
        assert!(
            dist[i] >= far_winner * (1.0 - 1e-6),
            "walker {i} in view at {} m got no slot; one at {far_winner} m did",
            dist[i]
        );
    }
}

/// When the camera moves to the other side of the field, the slots the walkers near its old
/// place hold go, at their next cycle end, to walkers nearer the new place: after two seconds
/// every holder is among the nearest walkers there (and among the farthest from the old place).
#[test]
fn joint_slots_move_to_the_nearest_walkers_within_a_cycle() {
    let Some(gpu) = gpu() else {
        return;
    };
    let (n, slots) = (300, 30);
    let mut crowd = crowd(gpu, n, slots);
    let field = crowd.config().field_size_m;
    let full = FullDetail::for_model(model().lod());
    let (a, b) = (
        above_corner(field, 1.0, 1.0),
        above_corner(field, -1.0, -1.0),
    );
    let by_distance = |walkers: &[WalkerJoints], eye: Vec3| {
        let r = roots(walkers);
        let mut order: Vec<usize> = (0..r.len()).collect();
        order.sort_by(|&i, &j| (r[i] - eye).length().total_cmp(&(r[j] - eye).length()));
        let mut rank = vec![0; r.len()];
        for (k, &i) in order.iter().enumerate() {
            rank[i] = k;
        }
        rank
    };
    // The first frame measures each walker from its root before the frame.
    let rank_a = by_distance(&crowd.read_walkers().expect("walkers"), a.position);
    let stats = crowd.step(&full, &a, DT).unwrap();
    assert_eq!(stats.visible as usize, n, "every walker in view of {a:?}");
    let near_a = holders(&crowd.read_walkers().expect("walkers"));
    assert_eq!(near_a.len(), slots);
    assert!(
        near_a.iter().all(|&i| rank_a[i] < slots),
        "{:?}",
        near_a.iter().map(|&i| rank_a[i]).collect::<Vec<_>>()
    );
    let mut faults = 0;
    for _ in 0..60 {
        let stats = crowd.step(&full, &b, DT).unwrap();
        assert_eq!(stats.visible as usize, n, "every walker in view of {b:?}");
        faults += stats.slot_faults;
    }
    let last = crowd.read_walkers().expect("walkers");
    let rank_b = by_distance(&last, b.position);
    let near_b = holders(&last);
    assert_eq!(near_b.len(), slots, "every slot held");
    assert!(faults > 0);
    // A holder won its slot at its last build against every walker then without one: at most
    // `slots - 1` of those were nearer, and at most `slots` other holders. Walkers move about
    // 1.3 m/s, which reorders the distances a little since.
    for &i in &near_b {
        assert!(
            rank_b[i] < 2 * slots + 10,
            "walker {i} holds a slot at rank {} from the eye (ranks: {:?})",
            rank_b[i],
            near_b.iter().map(|&k| rank_b[k]).collect::<Vec<_>>()
        );
    }
    assert!(
        near_b.iter().all(|i| !near_a.contains(i)),
        "a walker near the old place kept its slot"
    );
}

/// Two crowds with the same settings and scarce slots walk the same: the same walkers hold
/// slots and every position is the same, bit for bit, whatever order the GPU's threads ran in.
/// A walker shown root only for want of a slot asks again each frame without rebuilding the
/// root-only clip it has: the frames build about the cycle ends' clips, not one a waiting walker.
#[test]
fn scarce_joint_slots_are_repeatable_and_waiting_costs_no_build() {
    let Some(gpu) = gpu() else {
        return;
    };
    let (n, slots) = (500, 40);
    let mut one = crowd(gpu, n, slots);
    let mut two = crowd(gpu, n, slots);
    let field = one.config().field_size_m;
    let (path, lens) = (
        Scene::Ground.path(field),
        Scene::Ground.lens(Camera::default(), field),
    );
    let full = FullDetail::for_model(model().lod());
    let (mut faults, mut built, mut waiting) = (0, 0, 0);
    for f in 0..90 {
        let cam = path.camera_at(f as f32 * DT, &lens);
        let s1 = one.step(&full, &cam, DT).unwrap();
        let s2 = two.step(&full, &cam, DT).unwrap();
        assert_eq!(s1.slot_faults, s2.slot_faults, "frame {f}");
        assert_eq!(s1.level_histogram, s2.level_histogram, "frame {f}");
        assert_eq!(s1.kernels_built, s2.kernels_built, "frame {f}");
        faults += s1.slot_faults;
        if f >= 30 {
            built += s1.kernels_built;
            waiting += s1.slot_faults;
        }
        if f % 15 == 14 {
            let (w1, w2) = (one.read_walkers().unwrap(), two.read_walkers().unwrap());
            assert_eq!(holders(&w1).len(), slots, "frame {f}");
            for (i, (a, b)) in w1.iter().zip(&w2).enumerate() {
                assert_eq!(a.detail, b.detail, "walker {i}, frame {f}");
                let bits = |w: &WalkerJoints| -> Vec<[u32; 3]> {
                    w.positions
                        .iter()
                        .map(|p| p.to_array().map(f32::to_bits))
                        .collect()
                };
                assert_eq!(bits(a), bits(b), "walker {i}, frame {f}");
            }
        }
    }
    assert!(faults > 0, "the slots must be scarce");
    // 60 frames of 500 walkers whose cycles last about a second: about 1,000 cycle ends.
    assert!(
        built < waiting / 4,
        "{built} clips built in 60 frames while walkers waited {waiting} walker-frames"
    );
}
