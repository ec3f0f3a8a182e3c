//! The C ABI of the motion-lod runtime ([`lod_policy`]), for engines written in C, C++ or any
//! language with a C foreign-function interface.
//!
//! This crate is for: loading a model file, asking it for its levels, joints and control ranges,
//! choosing each character's level of detail from the camera, and walking characters: the library
//! chains gait cycles by their root motion, evaluates poses, plants the feet (the runtime foot
//! lock) and writes local joint rotations (for skinning), joint transforms and the root's world
//! placement into memory the caller owns. It is not for: building models (the `motion-lod` command
//! line and library do that offline) or simulating crowds (the engine owns its characters, their
//! paths and their culling; `crowd-sim` is the Rust one).
//!
//! The header `include/motion_lod.h` is generated from this file by cbindgen (regenerate it with
//! `MOTION_LOD_BLESS_HEADER=1 cargo test -p motion-lod-ffi --test integration header::`) and
//! checked in; a test fails when it is out of date, and another when it names a function or type
//! that does not exist.
//! `examples/crowd.c` walks a crowd of 1,000 characters through it, and a test checks every value it
//! prints against the Rust API bit for bit.
//!
//! The jobs, in call order:
//! 1. **Check the library** the program linked: [`mlod_abi_version`] equals the header's
//!    [`MLOD_ABI_VERSION`]; [`mlod_version`] names the release.
//! 2. **Load a model** once: [`mlod_model_load`] (a file) or [`mlod_model_from_bytes`]; then
//!    [`mlod_model_sizes`] (levels, joints, animated joints, pose length), [`mlod_model_joint`]
//!    and [`mlod_model_joint_rest`] (each joint's name, parent, offset and rest rotation, to bind
//!    a skeleton), [`mlod_model_root_joint`], [`mlod_model_control_range`] and
//!    [`mlod_model_ignored_controls`] (controls the build left out); for a model built
//!    with style labels, [`mlod_model_style_count`], [`mlod_model_style_name`] and
//!    [`mlod_model_style_share`] (the styles a walk's `style` weights, in order).
//! 3. **Create a walker** per character: [`mlod_walker_new`] allocates its buffers, once.
//! 4. **Start its walk**: its first level of detail from the camera at its start position
//!    ([`mlod_model_detail_from_camera`]), then [`mlod_walker_start`] with its first cycle's
//!    controls, its position and heading on the ground; it shows the walk's first frame.
//! 5. **Every frame**: the detail the camera gives the walker now
//!    ([`mlod_walker_detail_from_camera`]), then [`mlod_walker_advance`] by the frame's step with
//!    the controls and detail of its next cycle (used when the current cycle ends); it writes the
//!    root's world position and rotation ([`MlodWalkerState`]). For skinning,
//!    [`mlod_walker_local_rotations`]; for joints in the cycle frame,
//!    [`mlod_walker_joint_transforms`]. [`mlod_walker_set_foot_lock`] turns the foot lock off or
//!    on, [`mlod_walker_set_seam_blend`] the inertialized seams between cycles (on: a change of
//!    controls or detail does not pop); [`mlod_walker_shown_pose`] gives the pose shown, to record
//!    a walk. [`mlod_walkers_step`] does this step (detail from the camera, then advance) for a
//!    whole crowd in one call.
//! 6. **Release**: [`mlod_walker_free`] for each walker, then [`mlod_model_free`].
//!
//! A host without an allocator of its own in the library's memory (a WebAssembly page, which
//! sees the module's linear memory as an array) gets the buffers it passes from
//! [`mlod_buffer_new`] and returns them with [`mlod_buffer_free`]; `viewer/mlod.js` drives this
//! ABI from JavaScript that way.
//!
//! Engines that chain cycles themselves use the lower-level pair instead of steps 4-5:
//! [`mlod_walker_prepare`] (one cycle's clip, with its duration and root motion) and
//! [`mlod_walker_pose`] (the pose at a time in it), with [`mlod_model_detail_at`] for a detail
//! from a distance alone.
//!
//! Conventions:
//! - Every function returns an [`MlodStatus`] (except those that only report a value, the `_free`
//!   functions and [`mlod_last_error`]); `MLOD_STATUS_OK` is 0. On any other status,
//!   [`mlod_last_error`] gives a message naming what was wrong and where (per thread, valid until
//!   the next call on that thread). No call unwinds across the boundary: a Rust panic (a bug)
//!   becomes `MLOD_STATUS_PANIC`. A failed call changes none of its outputs except where its
//!   documentation says so.
//! - Objects are opaque pointers created by `mlod_model_load`, `mlod_model_from_bytes` and
//!   `mlod_walker_new` and released by `mlod_model_free` and `mlod_walker_free` (null is accepted and
//!   ignored). A walker must be used with the model it was created for and must not outlive it;
//!   passing another model is an error (`MLOD_STATUS_INVALID_ARGUMENT`), never undefined behaviour.
//! - Units: metres, seconds, radians. Controls describe one gait cycle (two steps): `dx` sideways and
//!   `dz` forward displacement (m), `turn` (rad, positive towards +x), `height` of the performer (m),
//!   and the performer's `style`: a weight per style of the model (all 0, as a zero-initialised
//!   struct has them, is the data's own mix of styles; a model without styles ignores them).
//!   The world is +y up; a heading is a rotation about +y, 0 facing +z. World positions (a
//!   walker's cycle frame and root, the camera's eye) are doubles, as large worlds keep them: a
//!   walker an hour's walk or kilometres from the origin chains its cycles to the same
//!   micrometres as one near it. Poses, rotations and transforms in the cycle frame are floats.
//! - Poses are the model's pose vectors (the `pose_len` of [`mlod_model_sizes`] floats: root
//!   position, root exponential map, the time row, then three exponential-map rows per animated
//!   joint in the model's evaluation order, legs first, the order a detail's `joints` counts in).
//!   Joint transforms and local rotations are in the model's joint order (parents before
//!   children); transforms are in the cycle frame (metres; +y up, the cycle starting at the origin
//!   heading +z).
//! - Walkers allocate nothing after [`mlod_walker_new`] (for skeletons of up to 128 joints).
//! - Calls on different walkers may run on different threads at once; a model is read-only after
//!   loading and may be shared by every thread.

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use lod_policy::glam::{DVec3, Quat, Vec3};
use lod_policy::{
    ClipKernel, Controls, CycleFrame, DEFAULT_HALFLIFE_S, Detail, DistancePolicy, FileError,
    FootLock, JointTransform, KernelScratch, LevelPolicy, RootMotion, RuntimeModel, SeamScratch,
    SeamTransition, StyleMix, ViewParams, wrap_angle_f64,
};

/// The version of this C ABI: the functions, their arguments and the layouts of the structs in
/// `motion_lod.h`. It changes whenever any of them changes; a program compiled against a header
/// whose `MLOD_ABI_VERSION` differs from what `mlod_abi_version` returns must not use the library.
pub const MLOD_ABI_VERSION: u32 = 5;

/// The most styles a model holds: the length of [`MlodControls`]'s `style` weights.
pub const MLOD_MAX_STYLES: usize = 8;

/// The half-life of the seam transitions between a walker's cycles, seconds
/// ([`mlod_walker_set_seam_blend`]).
pub const MLOD_SEAM_HALFLIFE_S: f32 = 0.15;

// The runtime's own seams (synth, the crowd) use the same half-life.
const _: () = assert!(MLOD_SEAM_HALFLIFE_S == DEFAULT_HALFLIFE_S);

/// The longest step [`mlod_walker_advance`] takes, seconds.
pub const MLOD_MAX_STEP_S: f64 = 10.0;

/// The library's version (`CARGO_PKG_VERSION`), NUL-terminated.
const VERSION: &CStr =
    match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
        Ok(v) => v,
        Err(_) => panic!("the package version holds a NUL byte"),
    };

/// The step the foot lock is given for a walk's first frame ([`mlod_walker_start`]). A fresh lock
/// holds no correction yet and needs two frames to measure a foot's speed, so the step changes
/// nothing it shows or keeps (the crate's C example test checks that against a walk whose first
/// frame uses the frame step, as `examples/engine` does); it only has to be positive.
const FIRST_FRAME_STEP_S: f32 = 1.0 / 60.0;

/// Outcome of every call.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MlodStatus {
    /// Success.
    Ok = 0,
    /// A required pointer argument was null.
    NullPointer = 1,
    /// An argument is out of range or inconsistent (the message says which).
    InvalidArgument = 2,
    /// The model bytes are not a valid model file (truncated, corrupted, wrong version).
    InvalidModel = 3,
    /// A file could not be read.
    Io = 4,
    /// An output array is shorter than needed (the message gives the length needed).
    BufferTooSmall = 5,
    /// The walker has nothing to evaluate yet: call `mlod_walker_start` (or `mlod_walker_prepare`)
    /// first, and `mlod_walker_pose` before asking for the joints of a prepared clip.
    NotPrepared = 6,
    /// A bug in the library (a Rust panic, caught at the boundary).
    Panic = 7,
}

/// The control parameters of one gait cycle (two steps).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MlodControls {
    /// Sideways displacement over the cycle, metres (+x).
    pub dx: f32,
    /// Forward displacement over the cycle, metres (+z).
    pub dz: f32,
    /// Change of heading over the cycle, radians (positive towards +x).
    pub turn: f32,
    /// Standing height of the performer, metres.
    pub height: f32,
    /// The performer's style: a weight per style of the model, in the order of
    /// `mlod_model_style_name` (finite and `>= 0`, every one of the `MLOD_MAX_STYLES`, or the
    /// controls are refused). The weights are normalised to sum 1, a blend of styles; all 0 (a
    /// zero-initialised struct) is the data's own mix, each style weighted by its share of the
    /// training cycles (`mlod_model_style_share`). Weights beyond the model's
    /// `mlod_model_style_count` are ignored, and so is the whole array by a model without styles.
    pub style: [f32; MLOD_MAX_STYLES],
}

/// A level of detail: an accuracy level (0 = the most accurate) and the number of animated joints,
/// in the model's evaluation order (legs first); the others keep their mean rotation and the root
/// always moves.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MlodDetail {
    /// Accuracy level, below the `levels` of `mlod_model_sizes`.
    pub level: u32,
    /// Animated joints, at most the `animated_joints` of `mlod_model_sizes` (more means all of
    /// them); 0 is root only.
    pub joints: u32,
}

/// What one prepared cycle does: how long it lasts and how the root travels over it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MlodCycle {
    /// Playback duration of the cycle, seconds.
    pub duration_s: f64,
    /// Root displacement over the cycle, metres, in the cycle frame (+x).
    pub dx: f32,
    /// Root displacement over the cycle, metres, in the cycle frame (+z).
    pub dz: f32,
    /// Change of heading over the cycle, radians.
    pub turn: f32,
    /// The character's body scale: its height over the skeleton's stature (1 when the data hold
    /// one height). `mlod_walker_joint_transforms` draws the bones below the root this many times
    /// as long; an engine skinning from local rotations scales the bone translations likewise.
    pub body_scale: f32,
}

/// One joint's transform in the cycle frame.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MlodJointTransform {
    /// Rotation as a unit quaternion `(x, y, z, w)`.
    pub rotation: [f32; 4],
    /// Position, metres.
    pub translation: [f32; 3],
}

/// A rotation as a unit quaternion.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MlodQuat {
    /// Vector part, x.
    pub x: f32,
    /// Vector part, y.
    pub y: f32,
    /// Vector part, z.
    pub z: f32,
    /// Scalar part.
    pub w: f32,
}

impl From<Quat> for MlodQuat {
    fn from(q: Quat) -> MlodQuat {
        let [x, y, z, w] = q.to_array();
        MlodQuat { x, y, z, w }
    }
}

/// Where a walker is after `mlod_walker_start` or `mlod_walker_advance`: its root in the world, the
/// cycle it is in and what that cycle was built with.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MlodWalkerState {
    /// Time into the current cycle, seconds.
    pub time_in_cycle_s: f64,
    /// Playback duration of the current cycle, seconds.
    pub cycle_duration_s: f64,
    /// Index of the current cycle: 0 for the cycle `mlod_walker_start` built, one more for each
    /// cycle chained after it.
    pub cycle: u64,
    /// The root joint's position in the world, metres (double precision, as the cycle frame).
    pub root_position: [f64; 3],
    /// Origin of the current cycle frame on the ground, metres (world x). The cycle frame is kept in
    /// double precision: a walker far from the origin chains its cycles as exactly as one near it.
    pub cycle_x: f64,
    /// Origin of the current cycle frame on the ground, metres (world z).
    pub cycle_z: f64,
    /// Heading of the current cycle frame, radians about +y (0 = facing +z), in `(-pi, pi]`: the
    /// start heading plus every chained cycle's turn.
    pub heading: f64,
    /// The root joint's rotation in the world: the cycle frame's heading times the root's rotation
    /// in the cycle frame (which is the root's entry of `mlod_walker_local_rotations`).
    pub root_rotation: MlodQuat,
    /// The current cycle's body scale (see `MlodCycle`).
    pub body_scale: f32,
    /// The detail the current cycle was built with (joints clamped to the model's).
    pub detail: MlodDetail,
    /// Cycles this call began: 0 while the walker stays in its cycle, 1 when it crossed into the
    /// next one (more for a step longer than a cycle).
    pub cycles_begun: u32,
    /// Whether the foot lock ran on this frame: the model knows its feet and the walker's lock is
    /// on (`mlod_walker_set_foot_lock`). It plants a foot in contact with the floor; a leg whose
    /// joints the detail does not animate is never locked.
    pub foot_locked: bool,
}

/// A camera, as a level-of-detail choice sees it: where it is, where it looks and its lens.
///
/// A point is in view when a sphere around it meets the cone of the view direction whose half-angle
/// reaches the image's corners (`atan(tan(fov_y / 2) sqrt(1 + aspect^2))`), between the near and far
/// distances along the view direction.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MlodCamera {
    /// Eye position in the world, metres (double precision, as walkers' positions).
    pub position: [f64; 3],
    /// View direction, a unit vector (length within 1e-3 of 1).
    pub direction: [f32; 3],
    /// Vertical field of view, radians, in `(0, pi)`.
    pub fov_y: f32,
    /// Image width over height, `> 0`.
    pub aspect: f32,
    /// Image height, pixels, `> 0`: with `fov_y`, how large an error looks at a distance.
    pub image_height_px: f32,
    /// Near clipping distance along the view direction, metres; 0 for none.
    pub near_m: f32,
    /// Far clipping distance along the view direction, metres, beyond `near_m`; 0 or infinity for
    /// none.
    pub far_m: f32,
}

/// A loaded model (opaque): the runtime model and its distance policy.
pub struct MlodModel {
    model: RuntimeModel,
    policy: DistancePolicy,
}

/// A walker's walk: where its cycle frame is, how far into the cycle, and what the next cycle will
/// be built with.
#[derive(Debug, Clone, Copy)]
struct Walk {
    frame: CycleFrame,
    lock: FootLock,
    /// Time into the current cycle (s).
    t: f64,
    cycle: u64,
    /// Controls and detail of the next cycle.
    next_controls: Controls,
    next_detail: Detail,
    /// The current cycle's detail (resolved).
    detail: Detail,
    /// The root in the world at the last frame shown.
    root: DVec3,
    root_rotation: Quat,
    locked: bool,
}

/// One walker (opaque): its clip kernel, scratch, last pose, walk state and output buffers, all
/// allocated by `mlod_walker_new`.
pub struct MlodWalker {
    /// The model the buffers were sized for (identity only, never dereferenced).
    model: *const MlodModel,
    kernel: ClipKernel,
    scratch: KernelScratch,
    pose: Vec<f32>,
    /// `pose[mean_from..]` holds the model's mean pose (the rows no clip since evaluated): a
    /// frame whose clip evaluates `rows >= mean_from` writes only those rows, the rest being what
    /// a whole pose would write there. A root-only walker so writes 7 floats a frame, not `P`.
    mean_from: usize,
    transforms: Vec<JointTransform>,
    locals: Vec<Quat>,
    /// The prepared cycle's body scale.
    body_scale: f32,
    prepared: bool,
    posed: bool,
    /// A walk was started (and not ended by `mlod_walker_prepare` or a failed clip).
    walking: bool,
    walk: Walk,
    /// The foot lock is on.
    foot_lock: bool,
    /// Seams between cycles are inertialized (`mlod_walker_set_seam_blend`).
    seam_blend: bool,
    /// The running seam transition into the current clip (inactive when none runs).
    seam: SeamTransition,
    /// The current clip's time at its seam, seconds.
    seam_start: f32,
    /// What starting a seam needs (allocated once).
    seam_scratch: SeamScratch,
}

// SAFETY: the raw pointer is only compared, never dereferenced; everything else is owned data.
unsafe impl Send for MlodWalker {}

// The header's thread rules rest on this: a model shared by threads is read through `&` only.
const _: () = {
    const fn shared_by_threads<T: Send + Sync>() {}
    shared_by_threads::<MlodModel>();
};

/// A failed call: its status and message.
struct Failure(MlodStatus, String);

impl Failure {
    fn invalid(message: impl Into<String>) -> Failure {
        Failure(MlodStatus::InvalidArgument, message.into())
    }
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(message: &str) {
    let text = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = text);
}

/// Empties the last error; allocates only when it held a message, so that a successful call
/// allocates nothing.
fn clear_last_error() {
    LAST_ERROR.with(|e| {
        let mut e = e.borrow_mut();
        if !e.as_bytes().is_empty() {
            *e = CString::default();
        }
    });
}

/// Runs `f`, catching panics, and turns its outcome into a status (recording the message).
fn guard(what: &str, f: impl FnOnce() -> Result<(), Failure>) -> MlodStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => {
            clear_last_error();
            MlodStatus::Ok
        }
        Ok(Err(Failure(status, message))) => {
            set_last_error(&format!("{what}: {message}"));
            status
        }
        Err(panic) => {
            let detail = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            set_last_error(&format!("{what}: internal error (please report): {detail}"));
            MlodStatus::Panic
        }
    }
}

/// `&*ptr`, or a null-pointer failure naming the argument.
///
/// # Safety
/// `ptr` is null or points to a valid `T` for the duration of the call.
unsafe fn reference<'a, T>(ptr: *const T, name: &str) -> Result<&'a T, Failure> {
    // SAFETY: the caller guarantees validity when non-null.
    unsafe { ptr.as_ref() }
        .ok_or_else(|| Failure(MlodStatus::NullPointer, format!("{name} is null")))
}

/// `&mut *ptr`, or a null-pointer failure naming the argument.
///
/// # Safety
/// `ptr` is null or points to a valid, unaliased `T` for the duration of the call.
unsafe fn mutable<'a, T>(ptr: *mut T, name: &str) -> Result<&'a mut T, Failure> {
    // SAFETY: the caller guarantees validity and exclusivity when non-null.
    unsafe { ptr.as_mut() }
        .ok_or_else(|| Failure(MlodStatus::NullPointer, format!("{name} is null")))
}

/// The slice `ptr[..len]`, checked for null and for holding at least `needed` elements.
///
/// # Safety
/// `ptr` is null or points to `len` writable elements for the duration of the call.
unsafe fn out_slice<'a, T>(
    ptr: *mut T,
    len: usize,
    needed: usize,
    name: &str,
) -> Result<&'a mut [T], Failure> {
    if ptr.is_null() {
        return Err(Failure(MlodStatus::NullPointer, format!("{name} is null")));
    }
    if len < needed {
        return Err(Failure(
            MlodStatus::BufferTooSmall,
            format!("{name} holds {len} elements, {needed} are needed"),
        ));
    }
    // SAFETY: non-null and the caller guarantees `len` valid elements.
    Ok(unsafe { std::slice::from_raw_parts_mut(ptr, len) })
}

/// The controls as the kernel takes them, checked: every control finite, every style weight
/// finite and `>= 0` (all of them, also those the model ignores).
fn control_values(c: &MlodControls, name: &str) -> Result<Controls, Failure> {
    let values = [c.dx, c.dz, c.turn, c.height];
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(Failure::invalid(format!(
            "{name}: control {} is {} (must be finite)",
            Controls::NAMES[k],
            values[k]
        )));
    }
    // The two arrays have the same length (this does not compile otherwise).
    let style = StyleMix { weights: c.style };
    if let Some(problem) = style.problem() {
        return Err(Failure::invalid(format!("{name}: {problem}")));
    }
    Ok(controls_of(c))
}

/// The controls as the kernel takes them, for controls [`control_values`] accepted.
fn controls_of(c: &MlodControls) -> Controls {
    Controls::from_array([c.dx, c.dz, c.turn, c.height]).with_style(StyleMix { weights: c.style })
}

/// `detail` for `m`, checked: a level the model has; more joints than it animates mean all of
/// them (`MlodDetail::joints`).
fn checked_detail(m: &MlodModel, detail: MlodDetail, name: &str) -> Result<Detail, Failure> {
    let lod = m.model.lod();
    let joints = (detail.joints as usize).min(lod.joints());
    lod.check_detail(Detail::new(detail.level as usize, joints))
        .map_err(|e| Failure::invalid(format!("{name}: {e}")))
}

/// A policy's detail as the C ABI gives it: a root-only detail at the smallest level (the cheapest
/// clip, as the crowd evaluates it, `LodModel::evaluated`), checked for the model.
fn policy_detail(m: &MlodModel, detail: Detail) -> Result<MlodDetail, Failure> {
    let lod = m.model.lod();
    let d = lod
        .check_detail(lod.evaluated(detail))
        .map_err(|e| Failure::invalid(format!("the policy chose a detail the model lacks: {e}")))?;
    Ok(MlodDetail {
        level: d.accuracy as u32,
        joints: d.active_joints as u32,
    })
}

fn new_model(model: RuntimeModel) -> Box<MlodModel> {
    let policy = DistancePolicy::for_model(model.lod());
    Box::new(MlodModel { model, policy })
}

/// The library's version, NUL-terminated (for example `"0.1.0"`); the pointer is static.
#[unsafe(no_mangle)]
pub extern "C" fn mlod_version() -> *const c_char {
    VERSION.as_ptr()
}

/// The ABI version of the library linked: compare it with the header's `MLOD_ABI_VERSION`.
#[unsafe(no_mangle)]
pub extern "C" fn mlod_abi_version() -> u32 {
    MLOD_ABI_VERSION
}

/// Loads a model from the bytes of a model file (`len` bytes at `bytes`) into `*out` (null on
/// failure).
///
/// # Safety
/// `bytes` points to `len` readable bytes; `out` is a valid pointer to write the model pointer to.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_from_bytes(
    bytes: *const u8,
    len: usize,
    out: *mut *mut MlodModel,
) -> MlodStatus {
    guard("mlod_model_from_bytes", || {
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        *out = std::ptr::null_mut();
        if bytes.is_null() {
            return Err(Failure(MlodStatus::NullPointer, "bytes is null".into()));
        }
        // SAFETY: non-null, `len` readable bytes per the contract.
        let data = unsafe { std::slice::from_raw_parts(bytes, len) };
        let model = RuntimeModel::from_bytes(data)
            .map_err(|e| Failure(MlodStatus::InvalidModel, e.to_string()))?;
        *out = Box::into_raw(new_model(model));
        Ok(())
    })
}

/// Loads a model file from `path` (UTF-8, NUL-terminated) into `*out` (null on failure).
///
/// # Safety
/// `path` is a NUL-terminated string; `out` is a valid pointer to write the model pointer to.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_load(
    path: *const c_char,
    out: *mut *mut MlodModel,
) -> MlodStatus {
    guard("mlod_model_load", || {
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        *out = std::ptr::null_mut();
        if path.is_null() {
            return Err(Failure(MlodStatus::NullPointer, "path is null".into()));
        }
        // SAFETY: non-null and NUL-terminated per the contract.
        let path = unsafe { CStr::from_ptr(path) }
            .to_str()
            .map_err(|_| Failure::invalid("path is not UTF-8"))?;
        let model = RuntimeModel::load(Path::new(path)).map_err(|e| {
            let status = match e {
                FileError::Io { .. } => MlodStatus::Io,
                _ => MlodStatus::InvalidModel,
            };
            Failure(status, e.to_string())
        })?;
        *out = Box::into_raw(new_model(model));
        Ok(())
    })
}

/// Releases a model (null is ignored). Its walkers must be freed first.
///
/// # Safety
/// `model` is null or was returned by `mlod_model_load`/`mlod_model_from_bytes` and not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_free(model: *mut MlodModel) {
    if !model.is_null() {
        // SAFETY: created by Box::into_raw in this crate, freed once per the contract.
        drop(unsafe { Box::from_raw(model) });
    }
}

/// The model's sizes: accuracy levels, joints of the skeleton (the count of joint transforms and
/// local rotations), animated joints (the most a detail's `joints` can ask for) and the pose length
/// in floats. Any output pointer may be null.
///
/// # Safety
/// `model` is a live model; each non-null output points to a writable `size_t`.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_sizes(
    model: *const MlodModel,
    levels: *mut usize,
    joints: *mut usize,
    animated_joints: *mut usize,
    pose_len: *mut usize,
) -> MlodStatus {
    guard("mlod_model_sizes", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        let (rig, lod) = (m.model.rig(), m.model.lod());
        for (ptr, value) in [
            (levels, lod.levels().len()),
            (joints, rig.joint_count()),
            (animated_joints, rig.rotating_joints().len()),
            (pose_len, lod.p()),
        ] {
            // SAFETY: null or writable per the contract.
            if let Some(slot) = unsafe { ptr.as_mut() } {
                *slot = value;
            }
        }
        Ok(())
    })
}

/// A name's length (without the NUL) into `*name_len` and the name, NUL-terminated and truncated to
/// `capacity` bytes with the NUL, into `name`: the one convention of the ABI's name getters.
///
/// # Safety
/// `name` is null or holds `capacity` bytes; `name_len` is null or writable.
unsafe fn write_name(text: &[u8], name: *mut c_char, capacity: usize, name_len: *mut usize) {
    // SAFETY: null or writable per the contract.
    if let Some(len) = unsafe { name_len.as_mut() } {
        *len = text.len();
    }
    if !name.is_null() && capacity > 0 {
        let n = text.len().min(capacity - 1);
        // SAFETY: `name` holds `capacity` bytes and `n + 1 <= capacity`.
        unsafe {
            std::ptr::copy_nonoverlapping(text.as_ptr(), name.cast::<u8>(), n);
            *name.add(n) = 0;
        }
    }
}

/// Joint `joint`'s name (NUL-terminated, truncated to `capacity` bytes with the NUL) into `name`,
/// and its parent's index into `*parent` (-1 for the skeleton's top joint). Joints are in the
/// model's order (parents first), the order of the transforms and local rotations. `name` may be
/// null with `capacity` 0 to ask only for `*name_len`, the name's length in bytes without the NUL;
/// any output may be null.
///
/// # Safety
/// `model` is a live model; `name` is null or holds `capacity` bytes; `name_len` and `parent` are
/// null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_joint(
    model: *const MlodModel,
    joint: usize,
    name: *mut c_char,
    capacity: usize,
    name_len: *mut usize,
    parent: *mut i32,
) -> MlodStatus {
    guard("mlod_model_joint", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        let rig = m.model.rig();
        if joint >= rig.joint_count() {
            return Err(Failure::invalid(format!(
                "joint {joint} is out of range (the model has {})",
                rig.joint_count()
            )));
        }
        // SAFETY: null or writable per the contract.
        if let Some(p) = unsafe { parent.as_mut() } {
            *p = rig.joints()[joint]
                .parent
                .and_then(|j| i32::try_from(j).ok())
                .unwrap_or(-1);
        }
        // SAFETY: per this function's contract.
        unsafe {
            write_name(
                rig.joints()[joint].name.as_bytes(),
                name,
                capacity,
                name_len,
            )
        };
        Ok(())
    })
}

/// Joint `joint`'s rest transform relative to its parent into `*out`: `translation` is the
/// joint's offset from its parent (metres, in the parent's frame, for a body scale of 1; a
/// character of another `body_scale` has every offset that many times as long) and `rotation`
/// its rest rotation (what `mlod_walker_local_rotations` gives a joint the pose does not move).
/// The root and any joint not below it are placed by the pose, not by their offsets.
///
/// # Safety
/// `model` is a live model; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_joint_rest(
    model: *const MlodModel,
    joint: usize,
    out: *mut MlodJointTransform,
) -> MlodStatus {
    guard("mlod_model_joint_rest", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        let rig = m.model.rig();
        let j = rig.joints().get(joint).ok_or_else(|| {
            Failure::invalid(format!(
                "joint {joint} is out of range (the model has {})",
                rig.joint_count()
            ))
        })?;
        *out = MlodJointTransform {
            rotation: j.rest.to_array(),
            translation: j.offset.to_array(),
        };
        Ok(())
    })
}

/// The index of the root joint into `*out`: the joint the pose's root rows drive, whose local
/// rotation (`mlod_walker_local_rotations`) is relative to the cycle frame and whose world position
/// and rotation are the walker state's `root_position` and `root_rotation`. Joints not below it,
/// if any, are placed on the ground under it.
///
/// # Safety
/// `model` is a live model; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_root_joint(
    model: *const MlodModel,
    out: *mut usize,
) -> MlodStatus {
    guard("mlod_model_root_joint", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        *out = m.model.rig().root();
        Ok(())
    })
}

/// Which of the four walk controls the model ignores, into `*out` as bits: `1 << k` for `dx`,
/// `dz`, `turn`, `height` (k = 0..3) when the build left that control out of the kriging (it
/// carried no signal in the data, or was constant; `motion-lod info MODEL` says which and why).
/// A clip then follows what the data imply for it from the other controls, so a host should not
/// offer it as a control (a value given is not refused, only unused).
///
/// # Safety
/// `model` is a live model; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_ignored_controls(
    model: *const MlodModel,
    out: *mut u32,
) -> MlodStatus {
    guard("mlod_model_ignored_controls", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        let scale = &m.model.lod().controls().scale;
        *out = (0..Controls::COUNT)
            .filter(|&k| scale.get(k).is_none_or(|&v| v == 0.0))
            .fold(0, |bits, k| bits | (1 << k));
        Ok(())
    })
}

/// The range of every control over the model's training data (`*min`, `*max`). Controls outside
/// it are extrapolated, and clamped to the model's margin when a clip is built. The style weights
/// of both are 0 (the data's mix; see `mlod_model_style_share` for the styles).
///
/// # Safety
/// `model` is a live model; `min` and `max` are writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_control_range(
    model: *const MlodModel,
    min: *mut MlodControls,
    max: *mut MlodControls,
) -> MlodStatus {
    guard("mlod_model_control_range", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let (lo, hi) = unsafe { (mutable(min, "min")?, mutable(max, "max")?) };
        let c = m.model.lod().controls();
        let pick = |v: &[f32]| MlodControls {
            dx: v[0],
            dz: v[1],
            turn: v[2],
            height: v[3],
            style: [0.0; MLOD_MAX_STYLES],
        };
        *lo = pick(&c.min);
        *hi = pick(&c.max);
        Ok(())
    })
}

/// The number of styles the model conditions on into `*out`: the leading weights of an
/// `MlodControls`'s `style` it reads (at most `MLOD_MAX_STYLES`); 0 for a model built without
/// style labels, which ignores the weights.
///
/// # Safety
/// `model` is a live model; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_style_count(
    model: *const MlodModel,
    out: *mut usize,
) -> MlodStatus {
    guard("mlod_model_style_count", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        *out = m.model.styles().len();
        Ok(())
    })
}

/// The style index `index` weighs (`index <` the count of `mlod_model_style_count`): its name
/// (NUL-terminated, truncated to `capacity` bytes with the NUL) into `name`, as the model's labels
/// gave it (for example a performer's name). `name` may be null with `capacity` 0 to ask only for
/// `*name_len`, the name's length in bytes without the NUL; any output may be null.
///
/// # Safety
/// `model` is a live model; `name` is null or holds `capacity` bytes; `name_len` is null or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_style_name(
    model: *const MlodModel,
    index: usize,
    name: *mut c_char,
    capacity: usize,
    name_len: *mut usize,
) -> MlodStatus {
    guard("mlod_model_style_name", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        let text = style(m, index)?.as_bytes();
        // SAFETY: per this function's contract.
        unsafe { write_name(text, name, capacity, name_len) };
        Ok(())
    })
}

/// The share of the model's training cycles that have style `index` (`index <` the count of
/// `mlod_model_style_count`) into `*out`: its weight in the data's mix, what a `style` of all 0
/// asks for. The shares of a model's styles sum to 1.
///
/// # Safety
/// `model` is a live model; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_style_share(
    model: *const MlodModel,
    index: usize,
    out: *mut f32,
) -> MlodStatus {
    guard("mlod_model_style_share", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        style(m, index)?;
        *out = *m.model.data_style_mix().get(index).ok_or_else(|| {
            Failure::invalid(format!("the model holds no share of style {index}"))
        })?;
        Ok(())
    })
}

/// The name of the model's style `index`, or an out-of-range failure.
fn style(m: &MlodModel, index: usize) -> Result<&str, Failure> {
    let styles = m.model.styles();
    styles.get(index).map(String::as_str).ok_or_else(|| {
        Failure::invalid(format!(
            "style {index} is out of range (the model has {} styles)",
            styles.len()
        ))
    })
}

/// The level of detail the model's distance policy gives a visible character `distance_m` metres
/// from the camera (1920 x 1080, 60 degrees vertical field of view; at most about a pixel of
/// error). A detail without joints comes at the smallest level (root only, the cheapest clip).
///
/// # Safety
/// `model` is a live model; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_model_detail_at(
    model: *const MlodModel,
    distance_m: f32,
    out: *mut MlodDetail,
) -> MlodStatus {
    guard("mlod_model_detail_at", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        if !(distance_m.is_finite() && distance_m >= 0.0) {
            return Err(Failure::invalid(format!(
                "distance {distance_m} m must be finite and >= 0"
            )));
        }
        let detail = m.policy.detail(distance_m, true, &ViewParams::default());
        *out = policy_detail(m, detail)?;
        Ok(())
    })
}

/// Checks every field of a camera (see [`MlodCamera`]).
fn check_camera(c: &MlodCamera) -> Result<(), Failure> {
    let bad = |what: String| Err(Failure::invalid(format!("camera: {what}")));
    if !(c.position.iter().all(|v| v.is_finite()) && c.direction.iter().all(|v| v.is_finite())) {
        return bad("position or direction is not finite".into());
    }
    let length = Vec3::from_array(c.direction).length();
    if (length - 1.0).abs() > 1e-3 {
        return bad(format!(
            "direction has length {length} (must be a unit vector)"
        ));
    }
    if !(c.fov_y > 0.0 && c.fov_y < std::f32::consts::PI) {
        return bad(format!("fov_y {} rad is outside (0, pi)", c.fov_y));
    }
    if !(c.aspect.is_finite() && c.aspect > 0.0) {
        return bad(format!("aspect {} must be finite and > 0", c.aspect));
    }
    if !(c.image_height_px.is_finite() && c.image_height_px > 0.0) {
        return bad(format!(
            "image_height_px {} must be finite and > 0",
            c.image_height_px
        ));
    }
    if !(c.near_m.is_finite() && c.near_m >= 0.0) {
        return bad(format!("near_m {} m must be finite and >= 0", c.near_m));
    }
    if !(c.far_m == 0.0 || c.far_m > c.near_m) {
        return bad(format!(
            "far_m {} m must be 0 (none) or beyond near_m {} m",
            c.far_m, c.near_m
        ));
    }
    Ok(())
}

/// Whether a sphere of `radius` around the point `offset` from the eye (`distance` its length) is in
/// the camera's view cone, between its near and far distances (see [`MlodCamera`]).
/// The half-angle of the cone that reaches the image's corners (see `MlodCamera`), radians.
fn view_half_angle(c: &MlodCamera) -> f32 {
    ((0.5 * c.fov_y).tan() * (1.0 + c.aspect * c.aspect).sqrt()).atan()
}

fn in_view(c: &MlodCamera, half: f32, offset: Vec3, distance: f32, radius: f32) -> bool {
    let along = offset.dot(Vec3::from_array(c.direction));
    if c.near_m > 0.0 && along + radius < c.near_m {
        return false;
    }
    if c.far_m > 0.0 && along - radius > c.far_m {
        return false;
    }
    if distance <= radius {
        return true;
    }
    let reach = half + (radius / distance).asin();
    reach >= std::f32::consts::PI || (along / distance).clamp(-1.0, 1.0).acos() <= reach
}

/// The detail and visibility the camera gives a sphere of `radius_m` around `p`.
fn seen(
    m: &MlodModel,
    camera: &MlodCamera,
    p: DVec3,
    radius_m: f32,
) -> Result<(MlodDetail, bool), Failure> {
    check_camera(camera)?;
    seen_checked(m, camera, view_half_angle(camera), p, radius_m)
}

/// [`seen`] for a checked camera whose [`view_half_angle`] is `half`.
fn seen_checked(
    m: &MlodModel,
    camera: &MlodCamera,
    half: f32,
    p: DVec3,
    radius_m: f32,
) -> Result<(MlodDetail, bool), Failure> {
    if !p.is_finite() {
        return Err(Failure::invalid(format!("position {p} is not finite")));
    }
    if !(radius_m.is_finite() && radius_m >= 0.0) {
        return Err(Failure::invalid(format!(
            "radius {radius_m} m must be finite and >= 0"
        )));
    }
    // The offset from the eye in double precision: metres, however far both are from the origin.
    let offset = (p - DVec3::from_array(camera.position)).as_vec3();
    let distance = offset.length();
    let visible = in_view(camera, half, offset, distance, radius_m);
    let view = ViewParams {
        fov_y_radians: camera.fov_y,
        image_height_px: camera.image_height_px,
    };
    let detail = m.policy.detail(distance, visible, &view);
    Ok((policy_detail(m, detail)?, visible))
}

/// The level of detail the model's distance policy gives a character at the world position
/// `(x, y, z)` (metres) seen by `camera`, and whether it is in view: a sphere of `radius_m` metres
/// around the position (one that holds the character's body) meets the camera's view (see
/// `MlodCamera`). The distance is the position's from the eye; out of view the detail is root only
/// (no joints, the smallest level). `visible` may be null.
///
/// # Safety
/// `model` is a live model; `camera` is readable; `out` is writable; `visible` is null or writable.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlod_model_detail_from_camera(
    model: *const MlodModel,
    camera: *const MlodCamera,
    x: f64,
    y: f64,
    z: f64,
    radius_m: f32,
    out: *mut MlodDetail,
    visible: *mut bool,
) -> MlodStatus {
    guard("mlod_model_detail_from_camera", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let camera = unsafe { reference(camera, "camera") }?;
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        let (detail, seen_now) = seen(m, camera, DVec3::new(x, y, z), radius_m)?;
        *out = detail;
        // SAFETY: null or writable per the contract.
        if let Some(v) = unsafe { visible.as_mut() } {
            *v = seen_now;
        }
        Ok(())
    })
}

/// Creates a walker for `model` into `*out` (null on failure): its buffers, allocated once (no
/// call on it allocates afterwards). Its foot lock is on.
///
/// # Safety
/// `model` is a live model; `out` is writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_new(
    model: *const MlodModel,
    out: *mut *mut MlodWalker,
) -> MlodStatus {
    guard("mlod_walker_new", || {
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        *out = std::ptr::null_mut();
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        let lod = m.model.lod();
        let joints = m.model.rig().joint_count();
        let walker = MlodWalker {
            model,
            kernel: ClipKernel::new(lod),
            scratch: KernelScratch::new(lod),
            pose: vec![0.0; lod.p()],
            mean_from: lod.p(),
            transforms: vec![JointTransform::default(); joints],
            locals: vec![Quat::IDENTITY; joints],
            body_scale: 1.0,
            prepared: false,
            posed: false,
            walking: false,
            walk: Walk {
                frame: CycleFrame::default(),
                lock: FootLock::new(),
                t: 0.0,
                cycle: 0,
                next_controls: Controls::default(),
                next_detail: lod.root_only(),
                detail: lod.root_only(),
                root: DVec3::ZERO,
                root_rotation: Quat::IDENTITY,
                locked: false,
            },
            foot_lock: true,
            seam_blend: true,
            seam: SeamTransition::new(lod.p(), MLOD_SEAM_HALFLIFE_S),
            seam_start: 0.0,
            seam_scratch: SeamScratch::new(lod.p()),
        };
        *out = Box::into_raw(Box::new(walker));
        Ok(())
    })
}

/// Releases a walker (null is ignored).
///
/// # Safety
/// `walker` is null or was returned by `mlod_walker_new` and not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_free(walker: *mut MlodWalker) {
    if !walker.is_null() {
        // SAFETY: created by Box::into_raw in this crate, freed once per the contract.
        drop(unsafe { Box::from_raw(walker) });
    }
}

/// The walker and its model, checked to belong together.
///
/// # Safety
/// Both are null or live objects of this library.
unsafe fn walker_and_model<'a>(
    walker: *mut MlodWalker,
    model: *const MlodModel,
) -> Result<(&'a mut MlodWalker, &'a MlodModel), Failure> {
    // SAFETY: per the caller's contract.
    let w = unsafe { mutable(walker, "walker") }?;
    // SAFETY: per the caller's contract.
    let m = unsafe { reference(model, "model") }?;
    if !std::ptr::eq(w.model, model) {
        return Err(Failure::invalid("the walker was created for another model"));
    }
    Ok((w, m))
}

/// Builds the walker's clip for `controls` (checked, [`control_values`]) at `detail` (checked),
/// with its body scale. On failure the walker has no clip (and no walk).
fn build_clip(
    w: &mut MlodWalker,
    m: &MlodModel,
    controls: &Controls,
    detail: Detail,
) -> Result<(), Failure> {
    // SAFETY: the walker's own scratch.
    unsafe { build_clip_with(w, m, controls, detail, None) }
}

/// [`build_clip`] with the kernel scratch `shared` (another walker's of the same model, which
/// holds nothing between builds) when not null, else the walker's own: a crowd step builds every
/// clip in one scratch that stays in the cache.
///
/// # Safety
/// `shared` is null or another live walker's scratch for the same model, used by nothing else
/// during the call.
unsafe fn build_clip_with(
    w: &mut MlodWalker,
    m: &MlodModel,
    controls: &Controls,
    detail: Detail,
    shared: Option<*mut KernelScratch>,
) -> Result<(), Failure> {
    w.prepared = false;
    w.posed = false;
    w.walking = false;
    w.seam.clear();
    let scratch = match shared {
        // SAFETY: per this function's contract.
        Some(s) => unsafe { &mut *s },
        None => &mut w.scratch,
    };
    m.model
        .lod()
        .build_kernel(controls, detail, scratch, &mut w.kernel)
        .map_err(|e| Failure::invalid(e.to_string()))?;
    w.body_scale = m.model.body_scale(controls);
    w.prepared = true;
    Ok(())
}

/// Prepares the walker's next cycle: the clip for `controls` at `detail` (the kriging weights and
/// blended core of the paper's eq. 8). Controls beyond the model's margin are clamped (see
/// `mlod_model_control_range`); `*cycle`, when not null, receives the cycle's duration and root
/// motion. This is the lower-level path, for engines that chain cycles themselves; it ends a walk
/// started by `mlod_walker_start`.
///
/// # Safety
/// `walker` and `model` are live and belong together; `controls` is readable; `cycle` is null or
/// writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_prepare(
    walker: *mut MlodWalker,
    model: *const MlodModel,
    controls: *const MlodControls,
    detail: MlodDetail,
    cycle: *mut MlodCycle,
) -> MlodStatus {
    guard("mlod_walker_prepare", || {
        // SAFETY: per this function's contract.
        let (w, m) = unsafe { walker_and_model(walker, model) }?;
        // SAFETY: per this function's contract.
        let c = unsafe { reference(controls, "controls") }?;
        let values = control_values(c, "controls")?;
        let detail = checked_detail(m, detail, "detail")?;
        build_clip(w, m, &values, detail)?;
        // SAFETY: null or writable per the contract.
        if let Some(out) = unsafe { cycle.as_mut() } {
            let motion = w.kernel.root_motion();
            *out = MlodCycle {
                duration_s: w.kernel.duration(),
                dx: motion.dx,
                dz: motion.dz,
                turn: motion.turn,
                body_scale: w.body_scale,
            };
        }
        Ok(())
    })
}

/// Evaluates the prepared cycle `seconds` into it (clamped to the cycle) into `pose` (`len >=` the
/// `pose_len` of `mlod_model_sizes` floats), and keeps it for `mlod_walker_joint_transforms` and
/// `mlod_walker_local_rotations`. No foot lock: the lower-level path (`mlod_walker_prepare`). On a
/// walking walker it replaces what those two read until the next `mlod_walker_advance`.
///
/// # Safety
/// `walker` and `model` are live and belong together; `pose` is null or holds `len` floats
/// (null: only kept for the transforms).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_pose(
    walker: *mut MlodWalker,
    model: *const MlodModel,
    seconds: f64,
    pose: *mut f32,
    len: usize,
) -> MlodStatus {
    guard("mlod_walker_pose", || {
        // SAFETY: per this function's contract.
        let (w, m) = unsafe { walker_and_model(walker, model) }?;
        if !w.prepared {
            return Err(Failure(
                MlodStatus::NotPrepared,
                "no clip: call mlod_walker_prepare or mlod_walker_start first".into(),
            ));
        }
        if !seconds.is_finite() {
            return Err(Failure::invalid(format!("time {seconds} s is not finite")));
        }
        let lod = m.model.lod();
        let out = if pose.is_null() {
            None
        } else {
            // SAFETY: per this function's contract.
            Some(unsafe { out_slice(pose, len, lod.p(), "pose") }?)
        };
        let phase = w.kernel.phase_at(seconds);
        w.mean_from = w.pose.len();
        lod.pose(&w.kernel, phase, &mut w.pose)
            .map_err(|e| Failure::invalid(e.to_string()))?;
        w.mean_from = w.kernel.rows();
        w.posed = true;
        if let Some(out) = out {
            out[..lod.p()].copy_from_slice(&w.pose);
        }
        Ok(())
    })
}

/// The end of `mlod_walker_start` and `mlod_walker_advance`: shows the walk's current frame
/// ([`show_frame`], `dt` seconds after the previous one); when that succeeds the walker walks on,
/// and `*state` (when not null) receives where it is, with `begun` cycles begun by the call. When
/// it fails the walk ends.
///
/// # Safety
/// `state` is null or writable.
unsafe fn finish_step(
    w: &mut MlodWalker,
    m: &MlodModel,
    dt: f32,
    begun: u32,
    state: *mut MlodWalkerState,
) -> Result<(), Failure> {
    w.walking = false;
    show_frame(w, m, dt)?;
    w.walking = true;
    // SAFETY: null or writable per the caller's contract.
    if let Some(out) = unsafe { state.as_mut() } {
        *out = state_of(w, begun);
    }
    Ok(())
}

/// The walker's pose for the current time of its walk, with the foot lock, and its root in the
/// world (step 4 of `examples/engine`'s loop). `dt` is the time since the previous frame (s).
fn show_frame(w: &mut MlodWalker, m: &MlodModel, dt: f32) -> Result<(), Failure> {
    let (lod, rig) = (m.model.lod(), m.model.rig());
    let walk = &mut w.walk;
    w.posed = false;
    let phase = w.kernel.phase_at(walk.t);
    let rows = w.kernel.rows();
    // Unknown until the pose is written (a failure leaves it so).
    let mean_from = std::mem::replace(&mut w.mean_from, w.pose.len());
    if mean_from <= rows && rows <= w.pose.len() {
        // The rows after the clip's already hold the mean pose, which `pose` would write there.
        lod.pose_rows(&w.kernel, phase, &mut w.pose[..rows])
    } else {
        lod.pose(&w.kernel, phase, &mut w.pose)
    }
    .map_err(|e| Failure::invalid(e.to_string()))?;
    w.mean_from = rows;
    if w.seam.is_active() {
        let since = walk.t as f32 - w.seam_start;
        let rows = w.kernel.rows().min(w.pose.len());
        w.seam.apply(since, &mut w.pose[..rows]);
        w.seam.finish_after(since);
    }
    let active = walk.detail.active_joints;
    walk.locked = false;
    if let (true, Some(feet)) = (w.foot_lock, m.model.feet()) {
        if active > 0 {
            // The lock may bend legs' rows: the pose's mean rows are not known from here on.
            w.mean_from = w.pose.len();
        }
        walk.lock
            .apply(
                rig,
                feet,
                &walk.frame,
                active,
                w.body_scale,
                dt,
                &mut w.pose,
            )
            .map_err(|e| Failure::invalid(e.to_string()))?;
        walk.locked = true;
    }
    w.posed = true;
    let root = Vec3::new(w.pose[0], w.pose[1], w.pose[2]);
    let orientation = Vec3::new(w.pose[3], w.pose[4], w.pose[5]);
    walk.root = walk.frame.to_world(root);
    // The root's local rotation, as `Rig::local_rotations` gives it.
    walk.root_rotation = walk.frame.rotation() * lod_policy::offline::exp_to_quat(orientation);
    Ok(())
}

/// The pose a walker shows `t` seconds into its current clip (the running seam applied) into
/// `out`; returns the rows written.
fn displayed(
    w_kernel: &ClipKernel,
    seam: &SeamTransition,
    seam_start: f32,
    m: &MlodModel,
    t: f32,
    out: &mut [f32],
) -> Result<usize, Failure> {
    m.model
        .lod()
        .pose(w_kernel, w_kernel.phase_at(f64::from(t)), out)
        .map_err(|e| Failure::invalid(e.to_string()))?;
    let rows = w_kernel.rows().min(out.len());
    seam.apply(t - seam_start, &mut out[..rows]);
    Ok(rows)
}

/// Captures the pose the walker shows at the end of its current clip (`t_out` seconds into it),
/// moved into the next cycle frame by the clip's `motion`: the outgoing side of a seam.
fn capture_seam(
    w: &mut MlodWalker,
    m: &MlodModel,
    t_out: f32,
    motion: &RootMotion,
) -> Result<(), Failure> {
    let duration = w.kernel.duration() as f32;
    let (kernel, seam, start) = (&w.kernel, &w.seam, w.seam_start);
    w.seam_scratch
        .capture(t_out, duration, Some(motion), |t, out| {
            displayed(kernel, seam, start, m, t, out)
        })
}

/// Starts the seam into the walker's new clip at its time `t_in` (seconds).
fn start_seam(w: &mut MlodWalker, m: &MlodModel, t_in: f32) -> Result<(), Failure> {
    let duration = w.kernel.duration() as f32;
    let kernel = &w.kernel;
    let lod = m.model.lod();
    w.seam_scratch.start(
        t_in,
        duration,
        |t, out| {
            lod.pose(kernel, kernel.phase_at(f64::from(t)), out)
                .map_err(|e| Failure::invalid(e.to_string()))?;
            Ok(kernel.rows().min(out.len()))
        },
        &mut w.seam,
    )?;
    w.seam_start = t_in;
    Ok(())
}

/// The walker's state after a frame; `begun` cycles were begun by the call.
fn state_of(w: &MlodWalker, begun: u32) -> MlodWalkerState {
    let walk = &w.walk;
    MlodWalkerState {
        time_in_cycle_s: walk.t,
        cycle_duration_s: w.kernel.duration(),
        cycle: walk.cycle,
        root_position: walk.root.to_array(),
        root_rotation: walk.root_rotation.into(),
        cycle_x: walk.frame.x,
        cycle_z: walk.frame.z,
        heading: walk.frame.heading,
        body_scale: w.body_scale,
        detail: MlodDetail {
            level: walk.detail.accuracy as u32,
            joints: walk.detail.active_joints as u32,
        },
        cycles_begun: begun,
        foot_locked: walk.locked,
    }
}

/// Starts a walk: the walker's first cycle, built for `controls` at `detail`, begins in the cycle
/// frame at `(x, z)` on the ground (metres) facing `heading` (radians about +y, 0 = +z; kept
/// wrapped to `(-pi, pi]`), and the walk's first frame (time 0 of that cycle) is evaluated, with
/// the foot lock starting afresh (a foot is planted from the second frame on, once its speed is
/// known). `*state`, when not null, receives where the walker is. The controls and detail are also
/// those of the following cycles until `mlod_walker_advance` is given others. Starting again moves
/// the walker (the lock forgets its feet).
///
/// # Safety
/// `walker` and `model` are live and belong together; `controls` is readable; `state` is null or
/// writable.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlod_walker_start(
    walker: *mut MlodWalker,
    model: *const MlodModel,
    controls: *const MlodControls,
    detail: MlodDetail,
    x: f64,
    z: f64,
    heading: f64,
    state: *mut MlodWalkerState,
) -> MlodStatus {
    guard("mlod_walker_start", || {
        // SAFETY: per this function's contract.
        let (w, m) = unsafe { walker_and_model(walker, model) }?;
        // SAFETY: per this function's contract.
        let c = unsafe { reference(controls, "controls") }?;
        let values = control_values(c, "controls")?;
        let detail = checked_detail(m, detail, "detail")?;
        if let Some((name, v)) = [("x", x), ("z", z), ("heading", heading)]
            .into_iter()
            .find(|(_, v)| !v.is_finite())
        {
            return Err(Failure::invalid(format!("{name} is {v} (must be finite)")));
        }
        build_clip(w, m, &values, detail)?;
        w.walk = Walk {
            frame: CycleFrame {
                x,
                z,
                heading: wrap_angle_f64(heading),
            },
            lock: FootLock::new(),
            t: 0.0,
            cycle: 0,
            next_controls: values,
            next_detail: detail,
            detail,
            root: DVec3::ZERO,
            root_rotation: Quat::IDENTITY,
            locked: false,
        };
        // SAFETY: `state` is null or writable per the contract.
        unsafe { finish_step(w, m, FIRST_FRAME_STEP_S, 0, state) }
    })
}

/// The checked step of `mlod_walker_advance` and `mlod_walkers_step`: keeps the next cycle's
/// controls and detail (when given), moves the walk `dt_s` seconds on (chaining cycles, each seam
/// inertialized when both cycles animate joints) and shows the frame there. Clips are built in the
/// scratch `shared` when given ([`build_clip_with`]), else in the walker's own.
///
/// # Safety
/// `state` is null or writable; `shared` as [`build_clip_with`] asks.
unsafe fn step_walker(
    w: &mut MlodWalker,
    m: &MlodModel,
    dt_s: f64,
    controls: Option<Controls>,
    detail: Option<Detail>,
    state: *mut MlodWalkerState,
    shared: Option<*mut KernelScratch>,
) -> Result<(), Failure> {
    if let Some(c) = controls {
        w.walk.next_controls = c;
    }
    if let Some(d) = detail {
        w.walk.next_detail = d;
    }
    w.walk.t += dt_s;
    let mut begun = 0u32;
    while w.walk.t >= w.kernel.duration() {
        let ending = w.kernel.duration();
        w.walk.t -= ending;
        let motion = w.kernel.root_motion();
        let (values, detail) = (w.walk.next_controls, w.walk.next_detail);
        // Inertialized when both cycles animate joints (as the crowd's near walkers are).
        let blend = w.seam_blend
            && w.kernel.detail().active_joints > 0
            && m.model.lod().evaluated(detail).active_joints > 0;
        if blend {
            capture_seam(w, m, ending as f32, &motion)?;
        }
        w.walk.frame = w.walk.frame.next(&motion);
        // SAFETY: per this function's contract.
        unsafe { build_clip_with(w, m, &values, detail, shared) }?;
        if blend && w.kernel.detail().active_joints > 0 {
            start_seam(w, m, w.walk.t as f32)?;
        }
        w.walk.detail = detail;
        w.walk.cycle += 1;
        begun += 1;
    }
    // The foot lock steps in single precision, where a step below about 7e-46 s (accepted:
    // `0 < dt_s`) is 0, which it refuses: such a step failed after the walk had moved, and ended
    // it. The smallest normal `f32` is the same as no time for the lock.
    let lock_dt = (dt_s as f32).max(f32::MIN_POSITIVE);
    // SAFETY: `state` is null or writable per the caller's contract.
    unsafe { finish_step(w, m, lock_dt, begun, state) }
}

/// Moves the walk `dt_s` seconds forward (`0 < dt_s <=` `MLOD_MAX_STEP_S`) and evaluates the frame
/// there: the pose, the foot lock (when on and the model knows its feet), the root in the world.
/// When the current cycle ends on the way, the walker's cycle frame moves by that cycle's root
/// motion and heading change, and the next cycle is built with `next_controls` at `next_detail`
/// (the time past the end carries into it; a long step may chain several). Until a cycle ends they
/// are only kept: the current cycle goes on as it was built, as the runtime chains cycles; the
/// change is inertialized (`mlod_walker_set_seam_blend`). Either
/// may be null to keep those given before (at the start or by an earlier call). `*state`, when not
/// null, receives where the walker is.
///
/// Arguments are checked before anything changes. Should a clip fail to build (it does not with
/// checked arguments), the walk ends: start it again.
///
/// # Safety
/// `walker` and `model` are live and belong together; `next_controls` and `next_detail` are null
/// or readable; `state` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_advance(
    walker: *mut MlodWalker,
    model: *const MlodModel,
    dt_s: f64,
    next_controls: *const MlodControls,
    next_detail: *const MlodDetail,
    state: *mut MlodWalkerState,
) -> MlodStatus {
    guard("mlod_walker_advance", || {
        // SAFETY: per this function's contract.
        let (w, m) = unsafe { walker_and_model(walker, model) }?;
        if !w.walking {
            return Err(Failure(
                MlodStatus::NotPrepared,
                "no walk: call mlod_walker_start first".into(),
            ));
        }
        if !(dt_s.is_finite() && dt_s > 0.0 && dt_s <= MLOD_MAX_STEP_S) {
            return Err(Failure::invalid(format!(
                "step {dt_s} s must be finite, > 0 and <= {MLOD_MAX_STEP_S} s"
            )));
        }
        // SAFETY: null or readable per the contract.
        let controls = match unsafe { next_controls.as_ref() } {
            Some(c) => Some(control_values(c, "next_controls")?),
            None => None,
        };
        // SAFETY: null or readable per the contract.
        let detail = match unsafe { next_detail.as_ref() } {
            Some(d) => Some(checked_detail(m, *d, "next_detail")?),
            None => None,
        };
        // SAFETY: `state` is null or writable per the contract.
        unsafe { step_walker(w, m, dt_s, controls, detail, state, None) }
    })
}

/// Moves `count` walkers one frame, the crowd's loop in one call: for each walker `i`, the level
/// of detail `camera` gives it where its root is (as `mlod_walker_detail_from_camera`, with a
/// sphere of `radius_m` metres) and whether it is in view (into `visible[i]`, when `visible` is
/// not null), then the step of `mlod_walker_advance` by `dt_s` seconds with `next_controls[i]` and
/// that detail for its next cycle, into `states[i]`. `next_controls[i]` is read at every call, so
/// a host keeps each walker's next controls there and changes them when its cycle changes.
///
/// Every argument is checked before any walker moves: each walker live, of `model` and walking,
/// each controls valid; the message names the first index that is not. Walkers must be distinct.
///
/// # Safety
/// `walkers` holds `count` walker pointers, `next_controls` `count` readable controls and `states`
/// `count` writable states; `visible` is null or holds `count` writable flags; `model` and
/// `camera` are live and readable.
#[unsafe(no_mangle)]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn mlod_walkers_step(
    walkers: *const *mut MlodWalker,
    count: usize,
    model: *const MlodModel,
    camera: *const MlodCamera,
    radius_m: f32,
    dt_s: f64,
    next_controls: *const MlodControls,
    states: *mut MlodWalkerState,
    visible: *mut bool,
) -> MlodStatus {
    guard("mlod_walkers_step", || {
        // SAFETY: per this function's contract.
        let m = unsafe { reference(model, "model") }?;
        // SAFETY: per this function's contract.
        let camera = unsafe { reference(camera, "camera") }?;
        check_camera(camera)?;
        if !(radius_m.is_finite() && radius_m >= 0.0) {
            return Err(Failure::invalid(format!(
                "radius {radius_m} m must be finite and >= 0"
            )));
        }
        if !(dt_s.is_finite() && dt_s > 0.0 && dt_s <= MLOD_MAX_STEP_S) {
            return Err(Failure::invalid(format!(
                "step {dt_s} s must be finite, > 0 and <= {MLOD_MAX_STEP_S} s"
            )));
        }
        if count == 0 {
            return Ok(());
        }
        if walkers.is_null() || next_controls.is_null() || states.is_null() {
            return Err(Failure(
                MlodStatus::NullPointer,
                "walkers, next_controls and states must not be null".into(),
            ));
        }
        // SAFETY: non-null and holding `count` elements per the contract.
        let (list, controls, states) = unsafe {
            (
                std::slice::from_raw_parts(walkers, count),
                std::slice::from_raw_parts(next_controls, count),
                std::slice::from_raw_parts_mut(states, count),
            )
        };
        // SAFETY: null or holding `count` flags per the contract.
        let mut visible =
            (!visible.is_null()).then(|| unsafe { std::slice::from_raw_parts_mut(visible, count) });
        for (i, (&w, c)) in list.iter().zip(controls).enumerate() {
            // SAFETY: each pointer is null or a live walker per the contract.
            let w = unsafe { w.as_ref() }
                .ok_or_else(|| Failure(MlodStatus::NullPointer, format!("walker {i} is null")))?;
            if !std::ptr::eq(w.model, model) {
                return Err(Failure::invalid(format!(
                    "walker {i} was created for another model"
                )));
            }
            if !w.walking {
                return Err(Failure(
                    MlodStatus::NotPrepared,
                    format!("walker {i}: no walk: call mlod_walker_start first"),
                ));
            }
            // The message names the index; formatted only for a failure (a step allocates nothing).
            if control_values(c, "").is_err() {
                control_values(c, &format!("next_controls[{i}]"))?;
            }
        }
        let half = view_half_angle(camera);
        // Clips are built in the first walker's kernel scratch (the same sizes for every walker of
        // the model; it holds nothing between builds): one scratch that stays in the cache instead
        // of each walker's own, cold, at every cycle's end.
        // SAFETY: checked above: live, distinct walkers; taken as a raw place, no reference.
        let shared = unsafe { std::ptr::addr_of_mut!((*list[0]).scratch) };
        for (i, (&w, c)) in list.iter().zip(controls).enumerate() {
            // SAFETY: checked above: live, distinct walkers of this model.
            let w = unsafe { &mut *w };
            let (seen_detail, in_view) = seen_checked(m, camera, half, w.walk.root, radius_m)?;
            let detail = checked_detail(m, seen_detail, "detail")?;
            // Checked by the first loop.
            let values = controls_of(c);
            // Walker 0 builds in its own scratch (the shared one).
            let scratch = (i > 0).then_some(shared);
            // SAFETY: `states[i]` is writable; `shared` is walker 0's scratch, not walker i's, and
            // used by nothing else meanwhile.
            unsafe {
                step_walker(
                    w,
                    m,
                    dt_s,
                    Some(values),
                    Some(detail),
                    &mut states[i],
                    scratch,
                )
            }?;
            if let Some(v) = visible.as_deref_mut() {
                v[i] = in_view;
            }
        }
        Ok(())
    })
}

/// Turns the walker's foot lock on or off (it is on from `mlod_walker_new`). Turning it off
/// forgets the planted feet, so that turning it on again starts afresh; it takes effect at the
/// next `mlod_walker_advance`. Without feet in the model (the state's `foot_locked` stays false)
/// it changes nothing.
///
/// # Safety
/// `walker` is a live walker.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_set_foot_lock(
    walker: *mut MlodWalker,
    enabled: bool,
) -> MlodStatus {
    guard("mlod_walker_set_foot_lock", || {
        // SAFETY: per this function's contract.
        let w = unsafe { mutable(walker, "walker") }?;
        if !enabled {
            w.walk.lock.release();
        }
        w.foot_lock = enabled;
        Ok(())
    })
}

/// Turns the inertialized seams between the walker's cycles on or off (on from `mlod_walker_new`).
/// On, when a cycle ends and both it and the next one animate joints, the next clip starts from the
/// pose and velocity the walker showed (a seam transition: offsets that decay with a half-life of
/// `MLOD_SEAM_HALFLIFE_S`), so a change of controls or detail does not pop; off, the next clip
/// starts as it is. Takes effect at the next cycle.
///
/// # Safety
/// `walker` is a live walker.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_set_seam_blend(
    walker: *mut MlodWalker,
    enabled: bool,
) -> MlodStatus {
    guard("mlod_walker_set_seam_blend", || {
        // SAFETY: per this function's contract.
        let w = unsafe { mutable(walker, "walker") }?;
        w.seam_blend = enabled;
        Ok(())
    })
}

/// The level of detail `camera` gives the walker, and whether it is in view, from where its root
/// was at the last frame `mlod_walker_start` or `mlod_walker_advance` evaluated, with a sphere of
/// `radius_m` metres around the root holding its body (two thirds of its height holds a walking
/// character's limbs); otherwise as `mlod_model_detail_from_camera`. Pass the result as the
/// `next_detail` of `mlod_walker_advance`. `visible` may be null.
///
/// # Safety
/// `walker` and `model` are live and belong together; `camera` is readable; `out` is writable;
/// `visible` is null or writable.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_detail_from_camera(
    walker: *mut MlodWalker,
    model: *const MlodModel,
    camera: *const MlodCamera,
    radius_m: f32,
    out: *mut MlodDetail,
    visible: *mut bool,
) -> MlodStatus {
    guard("mlod_walker_detail_from_camera", || {
        // SAFETY: per this function's contract.
        let (w, m) = unsafe { walker_and_model(walker, model) }?;
        // SAFETY: per this function's contract.
        let camera = unsafe { reference(camera, "camera") }?;
        // SAFETY: per this function's contract.
        let out = unsafe { mutable(out, "out") }?;
        if !w.walking {
            return Err(Failure(
                MlodStatus::NotPrepared,
                "no walk: call mlod_walker_start first".into(),
            ));
        }
        let (detail, seen_now) = seen(m, camera, w.walk.root, radius_m)?;
        *out = detail;
        // SAFETY: null or writable per the contract.
        if let Some(v) = unsafe { visible.as_mut() } {
            *v = seen_now;
        }
        Ok(())
    })
}

/// The pose vector of the walker's last frame as shown (the frame `mlod_walker_start` or
/// `mlod_walker_advance` evaluated, with its planted feet; or the pose of `mlod_walker_pose`) into
/// `out` (`len >=` the `pose_len` of `mlod_model_sizes` floats), in the cycle frame: what
/// `mlod_walker_joint_transforms` and `mlod_walker_local_rotations` turn into joints, for recording
/// a walk (the quality meter of `motion-lod quality --recorded` reads such poses).
///
/// # Safety
/// `walker` and `model` are live and belong together; `out` holds `len` floats.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_shown_pose(
    walker: *mut MlodWalker,
    model: *const MlodModel,
    out: *mut f32,
    len: usize,
) -> MlodStatus {
    guard("mlod_walker_shown_pose", || {
        // SAFETY: per this function's contract.
        let (w, m) = unsafe { walker_and_model(walker, model) }?;
        if !w.posed {
            return Err(Failure(
                MlodStatus::NotPrepared,
                "no pose: call mlod_walker_start or mlod_walker_pose first".into(),
            ));
        }
        let p = m.model.lod().p();
        // SAFETY: per this function's contract.
        let out = unsafe { out_slice(out, len, p, "out") }?;
        out[..p].copy_from_slice(&w.pose[..p]);
        Ok(())
    })
}

/// The transforms (cycle frame) of every joint for the walker's last pose (the frame
/// `mlod_walker_start` or `mlod_walker_advance` evaluated, with its planted feet, or the pose of
/// `mlod_walker_pose`), into `out` (`len >=` the `joints` of `mlod_model_sizes`, in joint order),
/// for a body of the cycle's `body_scale`. Joints beyond the cycle's detail keep the mean pose's
/// rotations. To place them in the world, rotate them by the state's heading about +y and move
/// them by `(cycle_x, 0, cycle_z)`.
///
/// # Safety
/// `walker` and `model` are live and belong together; `out` holds `len` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_joint_transforms(
    walker: *mut MlodWalker,
    model: *const MlodModel,
    out: *mut MlodJointTransform,
    len: usize,
) -> MlodStatus {
    guard("mlod_walker_joint_transforms", || {
        // SAFETY: per this function's contract.
        let (w, m) = unsafe { walker_and_model(walker, model) }?;
        if !w.posed {
            return Err(Failure(
                MlodStatus::NotPrepared,
                "no pose: call mlod_walker_start or mlod_walker_pose first".into(),
            ));
        }
        let rig = m.model.rig();
        // SAFETY: per this function's contract.
        let out = unsafe { out_slice(out, len, rig.joint_count(), "out") }?;
        let active = w.kernel.detail().active_joints;
        rig.joint_transforms_scaled(&w.pose, active, w.body_scale, &mut w.transforms)
            .map_err(|e| Failure::invalid(e.to_string()))?;
        for (o, t) in out.iter_mut().zip(&w.transforms) {
            *o = MlodJointTransform {
                rotation: t.rotation.to_array(),
                translation: t.position.to_array(),
            };
        }
        Ok(())
    })
}

/// Every joint's rotation relative to its parent for the walker's last pose (as
/// `mlod_walker_joint_transforms`), into `out` (`len >=` the `joints` of `mlod_model_sizes`, in
/// joint order): what a skinned mesh's bones take, with the skeleton's joint offsets
/// (`mlod_model_joint_rest`, times the state's `body_scale`) as local translations. The root's
/// rotation is relative to the cycle frame; in the world the root is at the state's
/// `root_position` with its `root_rotation`. A joint beyond the cycle's detail, or one that never
/// moves, has its rest rotation; a joint not below the root has none (identity).
///
/// # Safety
/// `walker` and `model` are live and belong together; `out` holds `len` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_walker_local_rotations(
    walker: *mut MlodWalker,
    model: *const MlodModel,
    out: *mut MlodQuat,
    len: usize,
) -> MlodStatus {
    guard("mlod_walker_local_rotations", || {
        // SAFETY: per this function's contract.
        let (w, m) = unsafe { walker_and_model(walker, model) }?;
        if !w.posed {
            return Err(Failure(
                MlodStatus::NotPrepared,
                "no pose: call mlod_walker_start or mlod_walker_pose first".into(),
            ));
        }
        let rig = m.model.rig();
        // SAFETY: per this function's contract.
        let out = unsafe { out_slice(out, len, rig.joint_count(), "out") }?;
        let active = w.kernel.detail().active_joints;
        rig.local_rotations(&w.pose, active, &mut w.locals)
            .map_err(|e| Failure::invalid(e.to_string()))?;
        for (o, q) in out.iter_mut().zip(&w.locals) {
            *o = (*q).into();
        }
        Ok(())
    })
}

/// The alignment of every buffer of [`mlod_buffer_new`], bytes: enough for each struct of this ABI.
pub const MLOD_BUFFER_ALIGN: usize = 16;

/// A zero-filled buffer of `len` bytes (`len > 0`), aligned to `MLOD_BUFFER_ALIGN`, for a host
/// that has no allocator of its own in the library's memory (a WebAssembly host passes the
/// library's structs and arrays through it); release it with `mlod_buffer_free` and the same
/// `len`. Returns null when `len` is 0 or too large, or memory runs out.
#[unsafe(no_mangle)]
pub extern "C" fn mlod_buffer_new(len: usize) -> *mut u8 {
    match std::alloc::Layout::from_size_align(len, MLOD_BUFFER_ALIGN) {
        // SAFETY: the layout has a non-zero size.
        Ok(layout) if len > 0 => unsafe { std::alloc::alloc_zeroed(layout) },
        _ => std::ptr::null_mut(),
    }
}

/// Releases a buffer of `mlod_buffer_new` (null is ignored).
///
/// # Safety
/// `buffer` is null or was returned by `mlod_buffer_new(len)` with this `len` and not yet freed.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mlod_buffer_free(buffer: *mut u8, len: usize) {
    if buffer.is_null() {
        return;
    }
    if let Ok(layout) = std::alloc::Layout::from_size_align(len, MLOD_BUFFER_ALIGN) {
        // SAFETY: allocated by `mlod_buffer_new` with this layout, per the contract.
        unsafe { std::alloc::dealloc(buffer, layout) };
    }
}

/// The message of the last failed call on this thread (empty after a success). The pointer stays
/// valid until the next call on this thread.
#[unsafe(no_mangle)]
pub extern "C" fn mlod_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}
