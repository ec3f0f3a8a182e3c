//! [`crowd_sim::ClipSource`] for the multilinear model ([`LodSource`]).
//!
//! Joint positions handed to the crowd are the root followed by the rotating joints in the model's
//! importance order, so that a walker with `k` active joints draws the root and its `k` most important
//! joints (the paper's joint-DOF reduction, section 4.3). Bones connect each of those joints to its
//! nearest ancestor in that list.

use crowd_sim::{ClipError, ClipSource, LevelTable};
use glam::Vec3;
use lod_policy::{
    ClipKernel, ControlRange, Controls, CycleFrame, Detail, FootLock, KernelScratch, RootMotion,
};
use motion_io::PoseLayout;

use crate::model::MotionModel;

/// Largest skeleton handled without allocation in [`ClipSource::joints`].
const MAX_JOINTS: usize = 128;

/// Bones between the root and the rotating joints of `layout`, as indices into the crowd's joint list
/// (0 = root, `1 + k` = k-th rotating joint in row order).
pub fn bones_of(layout: &PoseLayout) -> Vec<(usize, usize)> {
    let sk = layout.skeleton();
    let mut slot = vec![usize::MAX; sk.joints.len()];
    slot[layout.root()] = 0;
    for (k, &j) in layout.joint_order().iter().enumerate() {
        slot[j] = 1 + k;
    }
    let mut bones = Vec::new();
    for &j in layout.joint_order() {
        let mut a = sk.joints[j].parent;
        while let Some(p) = a {
            if slot[p] != usize::MAX {
                bones.push((slot[p].min(slot[j]), slot[p].max(slot[j])));
                break;
            }
            a = sk.joints[p].parent;
        }
    }
    bones.sort_unstable();
    bones
}

/// One walker's clip: the kernel and what the crowd asks of it without recomputing.
#[derive(Debug, Clone)]
pub struct LodClip {
    kernel: ClipKernel,
    duration: f32,
    root_motion: RootMotion,
    /// The body scale of the clip's controls ([`MotionModel::body_scale`]).
    body_scale: f32,
}

/// The multilinear model as a crowd clip source.
///
/// [`LodSource::new`] is the crowd's fast path: every clip's `G(c)` is sized for its own level
/// ([`ClipKernel::compact`]), so a root-only clip holds `7 r_T` floats, and `pose` writes only the
/// rows the clip evaluates (a root-only walker: the 7 root rows, `7 r_T` multiply-adds, and no
/// forward kinematics beyond copying the root). `LodSource::reference` (feature `reference`, for
/// tests) keeps the straightforward path to check against: kernels sized for the largest level and
/// built with the kriging projections summed column by column
/// (`lod_policy::LodModel::build_kernel_reference`), poses completed with the mean pose. The two
/// differ by rounding in the kriging sums only.
#[derive(Debug)]
pub struct LodSource<'m> {
    model: &'m MotionModel,
    bones: Vec<(usize, usize)>,
    /// [`rest_rows_of`] the model.
    rest: Vec<f32>,
    /// Kernels sized per level and poses limited to the evaluated rows.
    compact: bool,
}

/// Size classes of [`LodSource::new`]'s clips with joints ([`ClipSource::clip_classes`]).
const JOINT_CLASSES: usize = 3;

/// `G(c)` entries a clip of class `class` (`1..=JOINT_CLASSES`) holds: `P x max R_T` halved for
/// each class below the last.
fn class_entries(lod: &lod_policy::LodModel, class: usize) -> usize {
    (lod.p() * lod.max_ranks().t) >> (JOINT_CLASSES - class.min(JOINT_CLASSES))
}

thread_local! {
    /// Kernel-build scratch of this thread (kernels are built inside the crowd's parallel pass).
    static SCRATCH: std::cell::RefCell<Option<KernelScratch>> = const { std::cell::RefCell::new(None) };
}

impl<'m> LodSource<'m> {
    /// The crowd's fast source over `model` (kernels sized per level, poses of the evaluated rows).
    pub fn new(model: &'m MotionModel) -> LodSource<'m> {
        LodSource {
            model,
            bones: bones_of(&model.layout),
            rest: rest_rows_of(model),
            compact: true,
        }
    }

    /// The reference source over `model`: every kernel preallocated for the largest level, built with
    /// the straightforward column-order kriging sums, and every pose completed with the mean pose
    /// beyond the evaluated rows. The same rows as [`LodSource::new`] up to rounding; slower and
    /// about `4 P max R_T` bytes per walker. For tests (feature `reference`).
    #[cfg(feature = "reference")]
    pub fn reference(model: &'m MotionModel) -> LodSource<'m> {
        LodSource {
            compact: false,
            ..LodSource::new(model)
        }
    }

    fn with_scratch<R>(&self, f: impl FnOnce(&mut KernelScratch) -> R) -> R {
        let lod = self.model.lod();
        SCRATCH.with(|cell| {
            let mut slot = cell.borrow_mut();
            let scratch = match slot.take() {
                Some(s) if s.fits_model(lod) => s,
                _ => KernelScratch::new(lod),
            };
            let s = slot.insert(scratch);
            f(s)
        })
    }
}

/// The rows the runtime's forward kinematics takes for joints a clip does not evaluate: the layout's
/// rest pose ([`PoseLayout::rest_pose`]) in f32, what every source of the model's data fades joints
/// to and from at seams ([`ClipSource::rest_rows`]).
pub(crate) fn rest_rows_of(model: &MotionModel) -> Vec<f32> {
    model.layout.rest_pose().iter().map(|&v| v as f32).collect()
}

/// Forward kinematics of `pose` into the crowd's joint list: the root, then the first `active` rotating
/// joints in row order (more when `pose` holds more joint rows: joints a seam fades out) (cycle-frame positions in metres) of a body `scale` times the skeleton's size
/// ([`lod_policy::Rig::joint_positions_scaled`]); returns how many were written (the root alone when
/// the rig refuses the pose; none, a clip fault, when `pose` lacks the root position or `out` is
/// empty; at most `out.len() - 1` joints). Allocation-free for skeletons up to 128 joints.
#[inline]
pub(crate) fn write_joints(
    layout: &PoseLayout,
    pose: &[f32],
    active: usize,
    scale: f32,
    out: &mut [Vec3],
) -> usize {
    if pose.len() < 3 || out.is_empty() {
        return 0;
    }
    let shown = pose.len().saturating_sub(lod_policy::ALWAYS_ROWS) / lod_policy::ROWS_PER_JOINT;
    let active = active
        .max(shown)
        .min(layout.joint_count())
        .min(out.len() - 1);
    if active == 0 {
        // Root only (most of a crowd): no call, no joint buffer.
        out[0] = Vec3::new(pose[0], pose[1], pose[2]);
        return 1;
    }
    joints_by_fk(layout, pose, active, scale, out)
}

/// [`write_joints`] for `active > 0` joints.
fn joints_by_fk(
    layout: &PoseLayout,
    pose: &[f32],
    active: usize,
    scale: f32,
    out: &mut [Vec3],
) -> usize {
    let nj = layout.skeleton().joints.len();
    let mut stack = [Vec3::ZERO; MAX_JOINTS];
    let mut heap = Vec::new();
    let world: &mut [Vec3] = if nj <= MAX_JOINTS {
        &mut stack[..nj]
    } else {
        heap.resize(nj, Vec3::ZERO);
        &mut heap
    };
    if layout
        .rig()
        .joint_positions_scaled(pose, active, scale, world)
        .is_err()
    {
        out[0] = Vec3::new(pose[0], pose[1], pose[2]);
        return 1;
    }
    out[0] = world[layout.root()];
    for (k, &j) in layout.joint_order().iter().take(active).enumerate() {
        out[1 + k] = world[j];
    }
    1 + active
}

/// The runtime foot lock ([`lod_policy::FootLock::apply`]) on the model's feet for a pose of
/// `active` joints of a body `scale` times the skeleton's size, what every source of the model's
/// data runs for near walkers (the model's, the naive and the PCA baselines: the same work, for a
/// fair comparison); nothing when the model has no feet. The lock validates before it writes, so a
/// refused pose is shown as it is.
#[allow(clippy::too_many_arguments)]
pub(crate) fn plant_feet(
    model: &MotionModel,
    active: usize,
    scale: f32,
    frame: &CycleFrame,
    dt: f32,
    lock: &mut FootLock,
    pose: &mut [f32],
) {
    if let Some(feet) = model.feet() {
        let _ = lock.apply(model.layout.rig(), feet, frame, active, scale, dt, pose);
    }
}

/// The model's accuracy levels, joints and pose length, as a crowd sees them (also reported by the
/// baselines, so that the crowd's policy applies to them unchanged).
pub fn level_table(model: &MotionModel) -> LevelTable {
    LevelTable {
        accuracy_levels: model.lod().levels().len(),
        joints: model.lod().joints(),
        pose_len: model.lod().p(),
    }
}

/// The range of the model's training controls, which the crowd clamps every request into.
pub fn control_range(model: &MotionModel) -> ControlRange {
    let r = model.control_range();
    ControlRange {
        min: Controls::from_array(r.map(|(lo, _)| lo)),
        max: Controls::from_array(r.map(|(_, hi)| hi)),
    }
}

impl ClipSource for LodSource<'_> {
    type Clip = LodClip;

    fn levels(&self) -> LevelTable {
        level_table(self.model)
    }

    fn control_range(&self) -> ControlRange {
        control_range(self.model)
    }

    fn style_mix(&self) -> &[f32] {
        self.model.runtime().data_style_mix()
    }

    fn new_clip(&self) -> LodClip {
        LodClip {
            kernel: if self.compact {
                ClipKernel::compact(self.model.lod())
            } else {
                ClipKernel::new(self.model.lod())
            },
            duration: 1.0,
            root_motion: RootMotion::default(),
            body_scale: 1.0,
        }
    }

    /// Compact clips (the crowd's, [`LodSource::new`]) come in four size classes: class 0 the
    /// root-only clips of [`ClipKernel::compact`], then kernels holding a quarter, a half and all
    /// of `P x max R_T` ([`ClipKernel::compact_holding`]), so that a walker with joints holds at
    /// most twice what its detail needs (or a quarter of the largest kernel) and none reallocates.
    fn clip_classes(&self) -> usize {
        if self.compact { 1 + JOINT_CLASSES } else { 1 }
    }

    fn clip_class(&self, detail: &Detail) -> usize {
        if !self.compact || detail.is_root_only() {
            return 0;
        }
        let lod = self.model.lod();
        let need = lod.kernel_entries(*detail);
        (1..JOINT_CLASSES)
            .find(|&k| need <= class_entries(lod, k))
            .unwrap_or(JOINT_CLASSES)
    }

    fn new_clip_of_class(&self, class: usize) -> LodClip {
        let mut clip = self.new_clip();
        if self.compact && class > 0 {
            let lod = self.model.lod();
            clip.kernel = ClipKernel::compact_holding(lod, class_entries(lod, class));
        }
        clip
    }

    /// Builds the kernel at `detail` evaluated as [`lod_policy::LodModel::evaluated`] (a root-only clip at the
    /// smallest level). The kernel checks controls, level and buffers before it writes, so a
    /// refused build leaves the clip as it was.
    fn build_clip(
        &self,
        controls: &Controls,
        detail: Detail,
        clip: &mut LodClip,
    ) -> Result<(), ClipError> {
        let lod = self.model.lod();
        let detail = lod.evaluated(detail);
        self.with_scratch(|s| {
            #[cfg(feature = "reference")]
            if !self.compact {
                let c = controls.to_array();
                return lod.build_kernel_reference(&c, detail, s, &mut clip.kernel);
            }
            lod.build_kernel(controls, detail, s, &mut clip.kernel)
        })
        .map_err(|e| ClipError(format!("model kernel: {e}")))?;
        clip.duration = (clip.kernel.duration() as f32).max(1e-3);
        // Root motion of the clip: ground displacement and travel turn, the runtime's one chaining
        // rule (lod_policy::chain), as `synth` uses it.
        clip.root_motion = clip.kernel.root_motion();
        clip.body_scale = self.model.body_scale(controls);
        Ok(())
    }

    fn clip_duration(&self, clip: &LodClip) -> f32 {
        clip.duration
    }

    fn clip_root_motion(&self, clip: &LodClip) -> RootMotion {
        clip.root_motion
    }

    fn pose(&self, clip: &LodClip, t_seconds: f32, out: &mut [f32]) -> usize {
        let lod = self.model.lod();
        let phase = clip.kernel.phase_at(f64::from(t_seconds));
        let rows = clip.kernel.rows();
        // A buffer shorter than the rows written is a clip fault (0 rows), not a panic.
        let written = if self.compact {
            match out.get_mut(..rows) {
                Some(out) => lod.pose_rows(&clip.kernel, phase, out),
                None => return 0,
            }
        } else {
            match out.get_mut(..lod.p()) {
                Some(out) => lod.pose(&clip.kernel, phase, out),
                None => return 0,
            }
        };
        match written {
            Ok(()) => rows,
            Err(_) => 0,
        }
    }

    fn prefetch(&self, clip: &LodClip, _t_seconds: f32) {
        clip.kernel.prefetch();
    }

    fn plant_feet(
        &self,
        clip: &LodClip,
        frame: &CycleFrame,
        dt: f32,
        lock: &mut FootLock,
        pose: &mut [f32],
    ) {
        let active = clip.kernel.detail().active_joints;
        plant_feet(self.model, active, clip.body_scale, frame, dt, lock, pose);
    }

    fn joints(&self, clip: &LodClip, pose: &[f32], out: &mut [Vec3]) -> usize {
        write_joints(
            &self.model.layout,
            pose,
            clip.kernel.detail().active_joints,
            clip.body_scale,
            out,
        )
    }

    fn rest_rows(&self) -> &[f32] {
        &self.rest
    }

    fn bones(&self) -> &[(usize, usize)] {
        &self.bones
    }
}
