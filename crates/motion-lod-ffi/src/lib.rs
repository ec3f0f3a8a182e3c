//! The C ABI of the motion-lod runtime ([`lod_policy`]), for engines written in C, C++ or any
//! language with a C foreign-function interface.
//!
//! This crate is for: loading a model file, asking it for its levels, joints and control ranges,
//! choosing a level of detail from a distance, and evaluating a walker's pose and joint transforms
//! into arrays the caller owns. It is not for: building models (the `motion-lod` command line and
//! library do that offline) or simulating crowds (the engine owns its characters; `crowd-sim` is the
//! Rust one).
//!
//! The header `include/motion_lod.h` is generated from this file by cbindgen (`cargo xtask header`)
//! and checked in; a test fails when it is out of date. `examples/crowd.c` animates a small crowd
//! through it, and a test checks its poses against the Rust API bit for bit.
//!
//! Conventions:
//! - Every function returns an [`MlodStatus`]; `MLOD_STATUS_OK` is 0. On any other status,
//!   [`mlod_last_error`] gives a message naming what was wrong and where (per thread, valid until the
//!   next call on that thread). No call unwinds across the boundary: a Rust panic (a bug) becomes
//!   `MLOD_STATUS_PANIC`.
//! - Objects are opaque pointers created by `*_new`/`*_load*` and released by `*_free` (null is
//!   accepted and ignored). A walker must be used with the model it was created for and must not
//!   outlive it; passing another model is an error (`MLOD_STATUS_INVALID_ARGUMENT`), never undefined
//!   behaviour.
//! - Units: metres, seconds, radians. Controls describe one gait cycle (two steps): `dx` sideways and
//!   `dz` forward displacement (m), `turn` (rad, positive towards +x), `height` of the performer (m).
//! - Poses are the model's pose vectors (`mlod_model_pose_len` floats: root position, root
//!   exponential map, the time row, then three exponential-map rows per joint in the model's joint
//!   order). Joint transforms are in the cycle frame (metres; +y up, the cycle starting at the
//!   origin heading +z), parents before children.
//! - Calls on different walkers may run on different threads at once; a model is read-only after
//!   loading and may be shared by every thread.

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use lod_policy::{
    ClipKernel, Controls, Detail, DistancePolicy, FileError, JointTransform, KernelScratch,
    LevelPolicy, RuntimeModel, ViewParams,
};

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
    /// The walker has no clip yet: call `mlod_walker_prepare` first.
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
}

/// A level of detail: an accuracy level (0 = the most accurate) and the number of animated joints,
/// in the model's evaluation order (legs first); the others keep their mean rotation and the root
/// always moves.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MlodDetail {
    /// Accuracy level, `0..mlod_model_levels()`.
    pub level: u32,
    /// Animated joints, `0..=` the `animated_joints` of `mlod_model_sizes`.
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

/// A loaded model (opaque): the runtime model and its distance policy.
pub struct MlodModel {
    model: RuntimeModel,
    policy: DistancePolicy,
}

/// One walker's buffers (opaque): its clip kernel, scratch and last pose, allocated once.
pub struct MlodWalker {
    /// The model the buffers were sized for (identity only, never dereferenced).
    model: *const MlodModel,
    kernel: ClipKernel,
    scratch: KernelScratch,
    pose: Vec<f32>,
    transforms: Vec<JointTransform>,
    /// The prepared cycle's body scale.
    body_scale: f32,
    prepared: bool,
    posed: bool,
}

// SAFETY: the raw pointer is only compared, never dereferenced; everything else is owned data.
unsafe impl Send for MlodWalker {}

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

/// Runs `f`, catching panics, and turns its outcome into a status (recording the message).
fn guard(what: &str, f: impl FnOnce() -> Result<(), Failure>) -> MlodStatus {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => {
            set_last_error("");
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

fn new_model(model: RuntimeModel) -> Box<MlodModel> {
    let policy = DistancePolicy::for_model(model.lod());
    Box::new(MlodModel { model, policy })
}

/// Loads a model from the bytes of a model file (`len` bytes at `bytes`) into `*out`.
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

/// Loads a model file from `path` (UTF-8, NUL-terminated) into `*out`.
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

/// The model's sizes: accuracy levels, joints of the skeleton (the transforms' count), animated
/// joints (the most a detail's `joints` can ask for) and the pose length in floats. Any output
/// pointer may be null.
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

/// Joint `joint`'s name (NUL-terminated, truncated to `capacity` bytes with the NUL) into `name`,
/// and its parent's index into `*parent` (-1 for the root). Joints are in the model's order
/// (parents first), the order of the transforms. `name` may be null with `capacity` 0 to
/// ask only for `*name_len`, the name's length in bytes without the NUL; any output may be null.
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
        let rig = &m.model.rig();
        if joint >= rig.joint_count() {
            return Err(Failure::invalid(format!(
                "joint {joint} is out of range (the model has {})",
                rig.joint_count()
            )));
        }
        let text = rig.joints()[joint].name.as_bytes();
        // SAFETY: null or writable per the contract.
        if let Some(len) = unsafe { name_len.as_mut() } {
            *len = text.len();
        }
        // SAFETY: null or writable per the contract.
        if let Some(p) = unsafe { parent.as_mut() } {
            *p = rig.joints()[joint]
                .parent
                .and_then(|j| i32::try_from(j).ok())
                .unwrap_or(-1);
        }
        if !name.is_null() && capacity > 0 {
            let n = text.len().min(capacity - 1);
            // SAFETY: `name` holds `capacity` bytes and `n + 1 <= capacity`.
            unsafe {
                std::ptr::copy_nonoverlapping(text.as_ptr(), name.cast::<u8>(), n);
                *name.add(n) = 0;
            }
        }
        Ok(())
    })
}

/// The range of every control over the model's training data (`*min`, `*max`). Controls outside
/// it are extrapolated, and clamped to the model's margin when a clip is prepared.
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
        };
        *lo = pick(&c.min);
        *hi = pick(&c.max);
        Ok(())
    })
}

/// The level of detail the model's distance policy gives a character `distance_m` metres from
/// the camera (1920 x 1080, 60 degrees vertical field of view; at most about a pixel of error).
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
        let lod = m.model.lod();
        let detail = m
            .policy
            .detail(distance_m, true, &ViewParams::default())
            .resolve(lod.levels().len(), lod.joints())
            .ok_or_else(|| Failure::invalid("the policy chose a level the model lacks"))?;
        *out = MlodDetail {
            level: detail.accuracy as u32,
            joints: detail.active_joints as u32,
        };
        Ok(())
    })
}

/// Creates a walker for `model` into `*out`: its buffers, allocated once (no call on it
/// allocates afterwards).
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
        let lod = &m.model.lod();
        let walker = MlodWalker {
            model,
            kernel: ClipKernel::new(lod),
            scratch: KernelScratch::new(lod),
            pose: vec![0.0; lod.p()],
            transforms: vec![JointTransform::default(); m.model.rig().joint_count()],
            body_scale: 1.0,
            prepared: false,
            posed: false,
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

/// Prepares the walker's next cycle: the clip for `controls` at `detail` (the kriging weights and
/// blended core of the paper's eq. 8). Controls beyond the model's margin are clamped (see
/// `mlod_model_control_range`); `*cycle`, when not null, receives the cycle's duration and root
/// motion.
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
        let values = [c.dx, c.dz, c.turn, c.height];
        if let Some(k) = values.iter().position(|v| !v.is_finite()) {
            return Err(Failure::invalid(format!(
                "control {} is {} (must be finite)",
                ["dx", "dz", "turn", "height"][k],
                values[k]
            )));
        }
        let lod = &m.model.lod();
        if detail.level as usize >= lod.levels().len() {
            return Err(Failure::invalid(format!(
                "level {} is out of range (the model has {})",
                detail.level,
                lod.levels().len()
            )));
        }
        w.prepared = false;
        w.posed = false;
        let d = Detail::new(detail.level as usize, detail.joints as usize);
        lod.build_kernel(&values, d, &mut w.scratch, &mut w.kernel)
            .map_err(|e| Failure::invalid(e.to_string()))?;
        w.body_scale = m.model.body_scale(&Controls::from_array(values));
        w.prepared = true;
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

/// Evaluates the prepared cycle `seconds` into it (clamped to the cycle) into `pose`
/// (`len >= mlod_model_pose_len` floats), and keeps it for `mlod_walker_joint_transforms`.
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
                "no clip: call mlod_walker_prepare first".into(),
            ));
        }
        if !seconds.is_finite() {
            return Err(Failure::invalid(format!("time {seconds} s is not finite")));
        }
        let lod = &m.model.lod();
        let phase = w.kernel.phase_at(seconds);
        lod.pose(&w.kernel, phase, &mut w.pose)
            .map_err(|e| Failure::invalid(e.to_string()))?;
        w.posed = true;
        if !pose.is_null() {
            // SAFETY: per this function's contract.
            let out = unsafe { out_slice(pose, len, lod.p(), "pose") }?;
            out[..lod.p()].copy_from_slice(&w.pose);
        }
        Ok(())
    })
}

/// The world transforms (cycle frame) of every joint for the pose last evaluated by
/// `mlod_walker_pose`, into `out` (`len >=` the `joints` of `mlod_model_sizes`, in joint order), for a
/// body of the prepared cycle's `body_scale`. Joints beyond the prepared detail's count keep the mean
/// pose's rotations.
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
                "no pose: call mlod_walker_pose first".into(),
            ));
        }
        let rig = &m.model.rig();
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

/// The message of the last failed call on this thread (empty after a success). The pointer stays
/// valid until the next call on this thread.
#[unsafe(no_mangle)]
pub extern "C" fn mlod_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}
