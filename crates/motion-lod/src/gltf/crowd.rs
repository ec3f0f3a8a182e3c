//! A crowd clip as a `.glb`: the crowd runs as `motion-lod crowd` runs it, seen from the camera
//! asked for (`--camera ground|overview`), its walkers starting mid-stride at their detail
//! ([`crowd_sim::Crowd::prime`]), and a subset of its walkers, spread over their distance from the
//! camera, is recorded frame by frame as skinned characters coloured by their level of detail.

use std::sync::Arc;

use crowd_sim::{Camera, Crowd, CrowdConfig, Scene as CameraScene};
use glam::Vec3;
use lod_policy::LevelPolicy;
use motion_io::PoseLayout;
use motion_io::expmap::quat_to_exp;
use serde_json::json;

use super::character::{Character, Rest};
use super::glb::Scene;
use super::{GltfError, level_color, level_label};
use crate::model::MotionModel;
use crate::synth::WalkRequest;

/// What to record.
#[derive(Debug, Clone)]
pub struct CrowdClip {
    /// The crowd (walkers, field, seed, frame rate).
    pub config: CrowdConfig,
    /// The camera's lens (its far plane as the scene sets it, [`CameraScene::lens`]).
    pub lens: Camera,
    /// The scene whose camera path the clip is seen from ([`CameraScene::path`]: inside the crowd on
    /// the ground, or circling above it), as in `motion-lod crowd --camera`.
    pub scene: CameraScene,
    /// Seconds recorded from the start.
    pub seconds: f32,
    /// Walkers written to the file (at most the crowd's), chosen evenly over their distance from
    /// the camera among the walkers in view at the start (then among the others), so that the
    /// levels the camera's view shows appear.
    pub exported: usize,
}

/// What was recorded.
#[derive(Debug, Clone, PartialEq)]
pub struct CrowdClipSummary {
    /// Walkers written.
    pub walkers: usize,
    /// Frames per walker.
    pub frames: usize,
    /// Walkers per colour (level histogram bin: accuracy levels, then root only), by the level
    /// each walker showed most often.
    pub level_counts: Vec<usize>,
}

/// The walkers to export: `n` of them, evenly spaced in the order of their distance from `eye`,
/// taken from the walkers in view first (those the camera sees, whose levels the policy chose by
/// distance), then from the others.
fn pick_walkers<C>(crowd: &Crowd<C>, eye: Vec3, n: usize) -> Vec<usize> {
    let n = n.clamp(1, crowd.len());
    let mut by_distance: Vec<(bool, f32, usize)> = (0..crowd.len())
        .map(|i| {
            (
                !crowd.is_visible(i),
                crowd.root_position(i).distance(eye),
                i,
            )
        })
        .collect();
    by_distance.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
    let visible = by_distance.iter().filter(|w| !w.0).count();
    let mut picked: Vec<usize> = if visible >= n {
        (0..n).map(|k| by_distance[(k * visible) / n].2).collect()
    } else {
        let rest = crowd.len() - visible;
        let more = n - visible;
        (0..visible)
            .map(|k| by_distance[k].2)
            .chain((0..more).map(|k| by_distance[visible + (k * rest) / more].2))
            .collect()
    };
    picked.sort_unstable();
    picked.dedup();
    picked
}

/// A full pose vector (f64, `layout.dof()` rows) in the world frame from a crowd pose in the
/// walker's cycle frame (`rows` rows written; the joints beyond them are at the rest rotation, as
/// the crowd's forward kinematics places them) and the cycle frame (`CycleFrame::to_world` for the
/// root, its rotation for the root's orientation).
fn world_pose(
    layout: &PoseLayout,
    rest_rows: &[f64],
    pose: &[f32],
    frame: &lod_policy::CycleFrame,
) -> Vec<f64> {
    let mut out = rest_rows.to_vec();
    for (o, &v) in out.iter_mut().zip(pose) {
        *o = f64::from(v);
    }
    let root = frame.to_world(Vec3::new(pose[0], pose[1], pose[2]));
    out[0] = root.x;
    out[2] = root.z;
    let q = lod_policy::offline::exp_to_quat(Vec3::new(pose[3], pose[4], pose[5]));
    let world = (frame.rotation() * q).normalize();
    let e = quat_to_exp(world.as_dquat());
    out[3..6].copy_from_slice(&e.to_array());
    debug_assert_eq!(out.len(), layout.dof());
    out
}

/// Runs the crowd of `clip` with the model's clip source under `policy`, seen from the camera of
/// `clip.scene` (its path, on the crowd's own field, decides every walker's detail and
/// visibility, which walkers are picked, and the camera written to the scene's extras), and returns
/// the scene of the exported walkers. The crowd is primed with the first frame's camera
/// ([`Crowd::prime`]): every walker starts at its own phase of its first cycle with a clip at its
/// detail, so the first frames pop no more than later ones. The result: one character per walker
/// (`walker NNN`), its body coloured by the level it showed most often (the crowd renderer's
/// colours), its node's extras holding the level bin of every frame (`motion_lod.levels`), and the
/// scene's extras the legend, the first camera and the field used (enlarged when the model's turn
/// range needs larger paths).
pub fn export_crowd<P: LevelPolicy + Sync>(
    model: &MotionModel,
    policy: &P,
    clip: &CrowdClip,
) -> Result<(Scene, CrowdClipSummary), GltfError> {
    if !(clip.seconds.is_finite() && clip.seconds > 0.0) {
        return Err(GltfError::Poses(format!(
            "clip length {} s is not a positive number",
            clip.seconds
        )));
    }
    let source = crate::LodSource::new(model);
    let walkers = clip.config.walkers;
    // Built on one thread (the crowd's poses are the same for any thread count; this keeps the
    // export cheap to reason about).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| GltfError::Recording(format!("thread pool: {e}")))?;
    let mut crowd = pool.install(|| Crowd::new(&source, clip.config))?;
    // The field the crowd uses (enlarged when the model's turn range needs larger paths).
    let field = crowd.config().field_size_m;
    let path = clip.scene.path(field);
    let lens = clip.scene.lens(clip.lens, field);
    let fps = clip.config.fps;
    let frames = ((clip.seconds * fps).round() as usize).max(2);
    let dt = 1.0 / fps;
    let start_camera = path.camera_at(0.0, &lens);
    // Every walker starts mid-stride at its detail, so that frame 0 looks like frame 100 (a new
    // crowd's walkers otherwise start root-only and take their joints over the first cycle).
    pool.install(|| crowd.prime(&source, policy, &start_camera))?;
    let mut picked = Vec::new();
    let mut scales: Vec<f64> = Vec::new();
    let layout = &model.layout;
    let rest_rows = layout.rest_pose();
    let exported = clip.exported.clamp(1, walkers);
    let mut poses: Vec<Vec<f64>> = vec![Vec::with_capacity(frames * layout.dof()); exported];
    let mut bins: Vec<Vec<usize>> = vec![Vec::with_capacity(frames); exported];
    let mut stats = crowd_sim::FrameStats::default();
    for f in 0..frames {
        let camera = path.camera_at(f as f32 * dt, &lens);
        pool.install(|| crowd.step_into(&source, policy, &camera, dt, &mut stats))?;
        if f == 0 {
            picked = pick_walkers(&crowd, start_camera.position, clip.exported);
            scales = picked
                .iter()
                .map(|&i| f64::from(model.body_scale(&crowd.controls(i))))
                .collect();
        }
        for (k, &i) in picked.iter().enumerate() {
            let pose = crowd.pose(i);
            if pose.len() < 6 {
                return Err(GltfError::Recording(format!(
                    "walker {i}: a pose of {} rows at frame {f}",
                    pose.len()
                )));
            }
            let world = world_pose(layout, &rest_rows, pose, &crowd.cycle_frame(i));
            let root = crowd.root_position(i);
            let drift = Vec3::new(world[0] as f32, world[1] as f32, world[2] as f32).distance(root);
            if drift > 1e-3 {
                return Err(GltfError::Recording(format!(
                    "walker {i} at frame {f}: the recorded root is {drift:.4} m from the crowd's"
                )));
            }
            poses[k].extend_from_slice(&world);
            bins[k].push(crowd.level_bin(i));
        }
    }
    // The rest pose: the model's straight walk at the middle of its controls, its first frame,
    // facing +Z, drawn at each walker's body scale; walkers of one scale share it and so the body
    // mesh (every walker, when the data hold one height).
    let reference = reference_walk(model)?;
    let mut rests: Vec<(u64, PoseLayout, Arc<Rest>)> = Vec::new();
    let levels = model.lod().levels().len();
    let mut scene = Scene::new();
    let mut material_of_bin: Vec<Option<usize>> = vec![None; levels + 1];
    let mut level_counts = vec![0usize; levels + 1];
    for (k, &i) in picked.iter().enumerate() {
        let name = format!("walker {i:03}");
        let scale = scales.get(k).copied().unwrap_or(1.0);
        let at = match rests
            .iter()
            .position(|(bits, _, _)| *bits == scale.to_bits())
        {
            Some(at) => at,
            None => {
                let scaled = layout
                    .scaled(scale)
                    .map_err(|e| GltfError::Poses(format!("walker {i}: {e}")))?;
                let rest = Arc::new(super::walk_rest(&scaled, &reference)?);
                rests.push((scale.to_bits(), scaled, rest));
                rests.len() - 1
            }
        };
        let (_, scaled, rest) = &rests[at];
        let character = Character::from_poses(scaled, rest, &poses[k], f64::from(dt), &name)?;
        let bin = most_frequent(&bins[k], levels + 1);
        level_counts[bin] += 1;
        let material = match material_of_bin[bin] {
            Some(m) => m,
            None => {
                let m = scene.add_material(&level_label(bin, levels), level_color(bin, levels));
                material_of_bin[bin] = Some(m);
                m
            }
        };
        scene.add_character(
            character,
            material,
            json!({ "motion_lod": { "walker": i, "levels": bins[k] } }),
        );
    }
    let legend: Vec<_> = (0..=levels)
        .map(|b| json!({ "label": level_label(b, levels), "color": level_color(b, levels) }))
        .collect();
    scene.set_extras(json!({
        "motion_lod": {
            "kind": "crowd",
            "legend": legend,
            "frame_time": dt,
            "walkers": clip.config.walkers,
            "field_size_m": field,
            "camera": {
                "position": start_camera.position.to_array(),
                "target": start_camera.target.to_array(),
                "fov_y_deg": start_camera.fov_y.to_degrees(),
            },
        }
    }));
    Ok((
        scene,
        CrowdClipSummary {
            walkers: picked.len(),
            frames,
            level_counts,
        },
    ))
}

/// The most frequent value of `bins` (each below `n`; ties go to the finer level).
fn most_frequent(bins: &[usize], n: usize) -> usize {
    let mut count = vec![0usize; n];
    for &b in bins {
        count[b.min(n - 1)] += 1;
    }
    let best = count.iter().copied().max().unwrap_or(0);
    count.iter().position(|&c| c == best).unwrap_or(0)
}

/// The walk whose first frame, facing its direction of travel, is every crowd character's rest pose: a
/// one-cycle straight walk at the middle of the model's controls.
fn reference_walk(model: &MotionModel) -> Result<crate::synth::Walk, GltfError> {
    let range = model.control_range();
    let mid = |k: usize| 0.5 * (range[k].0 + range[k].1);
    let req = WalkRequest {
        controls: lod_policy::Controls::from_array([
            mid(0),
            mid(1),
            0.0f32.clamp(range[2].0, range[2].1),
            mid(3),
        ]),
        detail: model.lod().full_detail(),
        cycles: 1,
        fps: 30.0,
        blend: false,
        plant_feet: false,
    };
    model
        .synthesize_walk(&req)
        .map_err(|e| GltfError::Poses(format!("reference walk: {e}")))
}
