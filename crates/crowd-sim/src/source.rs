//! The contract between the crowd and whatever synthesises motion.

use crate::error::ClipError;
use crate::levels::LevelTable;
use glam::Vec3;
use lod_policy::{ControlRange, Controls, CycleFrame, Detail, FootLock, RootMotion};

/// Most size classes of clips a source may have ([`ClipSource::clip_classes`]).
pub const MAX_CLIP_CLASSES: usize = 8;

/// A provider of gait clips at (controls, detail), implemented by the facade for the multilinear
/// model and for a naive baseline, and by [`testing::ProceduralSource`](crate::testing::ProceduralSource).
///
/// The crowd calls the methods in three separate stages so that each is timed on its own:
/// `build_clip` once per cycle (the *kernel*, e.g. `G(c) = U_P K(c)`), then per frame `pose`
/// (e.g. `G(c) w_T`, eq. 5) and `joints` (forward kinematics of the active joints).
///
/// Frames: a clip is one gait cycle starting at the origin of its *cycle frame* (root on the
/// ground origin at `t = 0`, facing +z, +x left, y up). `pose` and `joints` describe the whole
/// body in that frame, root translation and orientation included. The root motion returned by
/// `clip_root_motion` must match where `joints` puts the root at `t = clip_duration` (else
/// walkers jump at cycle boundaries); the next cycle starts there.
///
/// Pose vectors follow the runtime's row layout (`lod_policy`): rows 0-2 the root position in the
/// cycle frame, rows 3-5 the root orientation as an exponential map, row 6 the time increment
/// (left alone by transitions), then three rows per joint (exponential maps on one branch). Seam
/// transitions ([`lod_policy::SeamTransition`]) offset the rows by decaying differences, so every joint row
/// must be a quantity that can be interpolated.
pub trait ClipSource: Sync {
    /// A per-walker clip buffer, allocated once by `new_clip` and refilled by `build_clip`.
    type Clip: Send;

    /// Accuracy levels, joints and pose vector length.
    fn levels(&self) -> LevelTable;

    /// The range of controls the source covers; the crowd clamps every request into it.
    fn control_range(&self) -> ControlRange;

    /// The data's mix of styles, each style's share (summing to 1), in the order of
    /// [`lod_policy::StyleMix`]'s weights; empty (the default) for a source without styles. A
    /// crowd of [`crate::CrowdStyle::DataMix`] draws each walker's style from it.
    fn style_mix(&self) -> &[f32] {
        &[]
    }

    /// A fresh clip buffer (its content is unspecified until `build_clip`).
    fn new_clip(&self) -> Self::Clip;

    /// Size classes of the source's clips (at least 1; 1 by default: every clip holds every
    /// detail). With more, a clip of class `k` ([`ClipSource::new_clip_of_class`]) holds a build
    /// at any detail of that class ([`ClipSource::clip_class`]) without allocating, and the crowd
    /// keeps the classes apart: a walker whose detail changes class exchanges its clip for one of
    /// the new class from the crowd's stock and gives its own back, so that the frame loop
    /// allocates nothing once the stock holds as many of each class as walkers need at once, and
    /// memory follows what each walker's detail needs. At most [`MAX_CLIP_CLASSES`].
    fn clip_classes(&self) -> usize {
        1
    }

    /// The class of clip a build at `detail` needs (`< clip_classes()`; root-only details take
    /// the class of `new_clip`'s clips). 0 by default.
    fn clip_class(&self, detail: &Detail) -> usize {
        let _ = detail;
        0
    }

    /// A fresh clip of `class` (`< clip_classes()`; its content is unspecified until
    /// `build_clip`). `new_clip` by default.
    fn new_clip_of_class(&self, class: usize) -> Self::Clip {
        let _ = class;
        self.new_clip()
    }

    /// Synthesises the clip for `controls` at `detail` into `clip` (the per-cycle kernel).
    /// `detail` is checked ([`LevelTable::check`]): `detail.accuracy < levels().accuracy_levels`
    /// and `detail.active_joints <= levels().joints`.
    ///
    /// Errors: the clip cannot be built. An implementation must then leave `clip` as it was (check
    /// before writing), so that the crowd keeps showing it; the crowd counts the fault in its frame
    /// statistics ([`FrameStats::clip_faults`](crate::FrameStats)).
    fn build_clip(
        &self,
        controls: &Controls,
        detail: Detail,
        clip: &mut Self::Clip,
    ) -> Result<(), ClipError>;

    /// Duration of the clip in seconds (must be finite and at least 1 ms).
    fn clip_duration(&self, clip: &Self::Clip) -> f32;

    /// Root displacement and heading change over the whole clip, in its start heading frame.
    fn clip_root_motion(&self, clip: &Self::Clip) -> RootMotion;

    /// Writes the pose vector at `t_seconds` (in `[0, clip_duration]`) into `out`
    /// (`out.len() >= levels().pose_len`) and returns the number of rows written (rows beyond the
    /// clip's detail are not written).
    fn pose(&self, clip: &Self::Clip, t_seconds: f32, out: &mut [f32]) -> usize;

    /// A hint that `pose(clip, t_seconds, ..)` follows soon: an implementation may read the
    /// parts of the clip that call will read, so that they are in cache by then (the crowd calls
    /// it a few walkers ahead). Must not change anything observable. Does nothing by default.
    fn prefetch(&self, clip: &Self::Clip, t_seconds: f32) {
        let _ = (clip, t_seconds);
    }

    /// Plants the feet of `pose` (the `rows` rows written by `pose` for this clip, seam applied),
    /// shown in cycle frame `frame` `dt` seconds after the walker's previous frame: a source with a
    /// rig runs its foot lock (`lock`, the walker's; [`lod_policy::FootLock`]) and writes the
    /// corrected leg rows into `pose`. The crowd calls it for near walkers only
    /// ([`CrowdConfig::foot_lock_levels`](crate::CrowdConfig)). Does nothing by default (a source
    /// without feet).
    fn plant_feet(
        &self,
        clip: &Self::Clip,
        frame: &CycleFrame,
        dt: f32,
        lock: &mut FootLock,
        pose: &mut [f32],
    ) {
        let _ = (clip, frame, dt, lock, pose);
    }

    /// The pose rows the source's forward kinematics takes for joints a clip does not evaluate (each
    /// joint's rest rotation; the root rows are not read), `levels().pose_len` of them. With them, a
    /// seam that changes the evaluated joints fades the joints dropped out to their rest rotation and
    /// the joints added in from it ([`lod_policy::SeamScratch::start_from_rest`]); for a while the
    /// walker then shows more rows than its clip writes, and `joints` draws them. Empty by default:
    /// such joints switch at once.
    fn rest_rows(&self) -> &[f32] {
        &[]
    }

    /// Forward kinematics of `pose` into cycle-frame joint positions in metres, root first;
    /// `out.len() >= 1 + levels().joints`. `pose` holds the rows written by `pose` for this clip, or
    /// more while a seam fades dropped joints out (their rows follow the clip's: draw the joints of
    /// every row given). Returns how many positions were written (1 for a root-only clip).
    fn joints(&self, clip: &Self::Clip, pose: &[f32], out: &mut [Vec3]) -> usize;

    /// Bones as pairs of indices into the joint positions, for drawing; a bone is drawn only when
    /// both ends were written by `joints`.
    fn bones(&self) -> &[(usize, usize)];
}
