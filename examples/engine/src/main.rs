//! An engine's walk loop on the motion-lod runtime, written as an external crate that depends on
//! the runtime crate `lod-policy` alone (no linear algebra, threads or command line: what an engine
//! links). Run it on a model file:
//!
//! ```sh
//! motion-lod build -o walk.mlod        # or any folder of BVH takes
//! cargo run --release -p engine-example -- walk.mlod
//! ```
//!
//! It walks one character for ten seconds at 60 frames per second, turning 20 degrees per gait
//! cycle, 12 metres from the camera: the level of detail comes from the model's distance policy,
//! each gait cycle is a clip built once, cycles are chained by their root motion into one
//! continuous walk, planted feet stay where they land (the runtime foot lock), and every frame
//! gives the root's world transform and every joint's local rotation, which is what a skinned mesh
//! takes. Units: metres, seconds, radians (the command line
//! takes turns in degrees; the library never does).

use std::error::Error;

use lod_policy::glam::{DVec3, Quat, Vec3};
use lod_policy::{
    ClipKernel, Controls, CycleFrame, DistancePolicy, FootLock, KernelScratch, LevelPolicy,
    RuntimeModel, ViewParams,
};

/// What one frame hands to the renderer.
#[derive(Debug, Clone)]
pub struct Frame {
    /// Seconds since the walk began.
    pub time_s: f64,
    /// The root joint's position in the world (metres), in double precision as the cycle frame
    /// (`CycleFrame::to_world`): an engine with a large world keeps it so, or subtracts its
    /// camera's position before rounding to single precision.
    pub root_position: DVec3,
    /// The root joint's orientation in the world.
    pub root_rotation: Quat,
    /// Every joint's rotation relative to its parent, in the rig's joint order (parents first);
    /// the root's is relative to the cycle frame.
    pub local_rotations: Vec<Quat>,
    /// Index of the gait cycle the frame belongs to.
    pub cycle: usize,
    /// Heading of that cycle's frame (radians about +y, 0 = +z): the cycles' root motion summed.
    pub cycle_heading: f64,
    /// The character's body scale (`RuntimeModel::body_scale` of its height): the skeleton's bone
    /// translations below the root are drawn this many times as long.
    pub body_scale: f32,
}

/// Walks `seconds` at `fps` frames per second with `controls` for every cycle, `distance_m` from
/// the camera; `on_frame` receives each frame. Allocates its buffers once, before the loop.
pub fn walk(
    model: &RuntimeModel,
    controls: Controls,
    distance_m: f32,
    seconds: f64,
    fps: f64,
    mut on_frame: impl FnMut(&Frame),
) -> Result<(), Box<dyn Error>> {
    let (lod, rig) = (model.lod(), model.rig());
    // Once per character: buffers sized for the model's largest level.
    let mut kernel = ClipKernel::new(lod);
    let mut scratch = KernelScratch::new(lod);
    let mut pose = vec![0.0f32; lod.p()];
    let mut lock = FootLock::new();
    let mut frame = Frame {
        time_s: 0.0,
        root_position: DVec3::ZERO,
        root_rotation: Quat::IDENTITY,
        local_rotations: vec![Quat::IDENTITY; rig.joint_count()],
        cycle: 0,
        cycle_heading: 0.0,
        body_scale: model.body_scale(&controls),
    };
    // The level of detail for this distance (in a crowd: per character, re-asked per cycle).
    // The policy answers with a detail of its model: a level it has, at most its joints.
    let detail = DistancePolicy::for_model(lod).detail(distance_m, true, &ViewParams::default());
    // The first cycle starts at the world origin facing +z.
    let mut cycle_frame = CycleFrame::default();
    lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)?;
    let mut t_in_cycle = 0.0f64;
    let frames = (seconds * fps).round() as usize;
    for f in 0..frames {
        // A cycle lasts what the model says for these controls (not a fixed frame count): when it
        // ends, move the cycle frame by where its root went and build the next clip.
        while t_in_cycle >= kernel.duration() {
            t_in_cycle -= kernel.duration();
            cycle_frame = cycle_frame.next(&kernel.root_motion());
            lod.build_kernel(&controls, detail, &mut scratch, &mut kernel)?;
            frame.cycle += 1;
        }
        // Per frame: the pose vector, then the root in the world and the joints' local rotations.
        lod.pose(&kernel, kernel.phase_at(t_in_cycle), &mut pose)?;
        // Planted feet: the lock corrects the leg rows of the pose (when the model knows its feet).
        if let Some(feet) = model.feet() {
            let dt = (1.0 / fps) as f32;
            let (active, scale) = (detail.active_joints, frame.body_scale);
            lock.apply(rig, feet, &cycle_frame, active, scale, dt, &mut pose)?;
        }
        rig.local_rotations(&pose, detail.active_joints, &mut frame.local_rotations)?;
        let root_in_cycle = Vec3::new(pose[0], pose[1], pose[2]);
        frame.root_position = cycle_frame.to_world(root_in_cycle);
        frame.root_rotation = cycle_frame.rotation() * frame.local_rotations[rig.root()];
        frame.time_s = f as f64 / fps;
        frame.cycle_heading = cycle_frame.heading;
        on_frame(&frame);
        t_in_cycle += 1.0 / fps;
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn Error>> {
    let path = std::env::args().nth(1).ok_or(
        "usage: engine-example MODEL.mlod (write one with `motion-lod build -o walk.mlod`)",
    )?;
    let model = RuntimeModel::load(path.as_ref())?;
    let range = model
        .lod()
        .controls()
        .range()
        .ok_or("not a walk model (it lacks the four controls dx, dz, turn, height)")?;
    let controls = range.clamp(&Controls::from_array([0.0, 1.3, 20f32.to_radians(), 1.75]));
    println!(
        "{path}: {} joints, {} accuracy levels; walking dx {:.2} m, dz {:.2} m, turn {:.1} deg per cycle, {:.2} m tall (body scale {:.3})",
        model.rig().joint_count(),
        model.lod().levels().len(),
        controls.dx,
        controls.dz,
        controls.turn.to_degrees(),
        controls.height,
        model.body_scale(&controls)
    );
    // A control the data did not vary (or that carried no signal) is ignored by the model.
    let scale = &model.lod().controls().scale;
    for (k, name) in Controls::NAMES.iter().enumerate() {
        if scale.get(k).is_none_or(|&v| v == 0.0) {
            println!("note: this model ignores {name} (its data gave it no signal)");
        }
    }
    walk(&model, controls, 12.0, 10.0, 60.0, |frame| {
        if frame.time_s.fract() < 1e-9 {
            let p = frame.root_position;
            println!(
                "t = {:4.1} s, cycle {:2}: root at ({:6.2}, {:4.2}, {:6.2}) m",
                frame.time_s, frame.cycle, p.x, p.y, p.z
            );
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use motion_lod::dataset::DataSpec;
    use motion_lod::{BuildConfig, MotionModel};

    /// A model built from the checkout's fixtures, through the same crate.
    fn model() -> RuntimeModel {
        let spec = DataSpec {
            dirs: vec![std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures")],
            ..DataSpec::default()
        };
        let data = spec.load(&|_, _| {}).expect("fixtures load");
        let model = MotionModel::build(
            &data.training,
            &BuildConfig::default(),
            &motion_lod::progress::NoProgress,
        )
        .expect("builds");
        let bytes = motion_lod::model_file::encode(&model, "m".as_ref()).expect("encodes");
        RuntimeModel::from_bytes(&bytes).expect("the runtime reads it")
    }

    #[test]
    fn the_walk_is_continuous_turns_as_asked_and_gives_unit_local_rotations() {
        let model = model();
        let range = model.lod().controls().range().expect("walk controls");
        let controls = range.clamp(&Controls::from_array([0.0, 1.3, 20f32.to_radians(), 1.75]));
        let mut frames = Vec::new();
        walk(&model, controls, 3.0, 6.0, 60.0, |f| frames.push(f.clone())).expect("walks");
        assert_eq!(frames.len(), 360);
        let cycles = frames.last().unwrap().cycle;
        assert!(cycles >= 4, "six seconds hold several cycles: {cycles}");
        // Continuous: no frame moves the root much more than a typical frame does, seams included.
        let steps: Vec<f32> = frames
            .windows(2)
            .map(|w| (w[1].root_position - w[0].root_position).length() as f32)
            .collect();
        let mut sorted = steps.clone();
        sorted.sort_by(f32::total_cmp);
        let median = sorted[sorted.len() / 2];
        let worst = sorted[sorted.len() - 1];
        assert!(
            worst < 3.0 * median,
            "a jump: {worst} m against a median {median} m per frame"
        );
        // Turning: the direction of travel turns with the cycle frames, by the model's turn per
        // cycle (the embedded model ignores the turn control: its walker's turns carry no signal).
        let heading = |a: DVec3, b: DVec3| (b.x - a.x).atan2(b.z - a.z);
        let first = heading(frames[0].root_position, frames[60].root_position);
        let last = heading(frames[299].root_position, frames[359].root_position);
        let turned = lod_policy::wrap_angle_f64(last - first);
        let expected =
            lod_policy::wrap_angle_f64(frames[329].cycle_heading - frames[30].cycle_heading);
        assert!(
            (turned - expected).abs() < 0.1,
            "travel turned {turned} rad, the cycle frames {expected}"
        );
        for f in &frames {
            for q in &f.local_rotations {
                assert!((q.length() - 1.0).abs() < 1e-4, "{q:?}");
            }
            assert!(f.root_position.is_finite());
        }
    }
}
