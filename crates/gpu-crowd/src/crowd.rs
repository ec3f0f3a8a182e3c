//! [`GpuCrowd`]: the crowd's walkers on the GPU, stepped by the compute shaders.

use std::time::{Duration, Instant};

use bytemuck::{Pod, Zeroable};
use crowd_sim::path::{PathPlan, WalkerStart};
use crowd_sim::{Camera, CrowdConfig, CrowdStyle, Frustum, MAX_DT, check_control_range};
use glam::Vec3;
use lod_policy::{Detail, LevelPolicy, RuntimeModel, SplitMix64, StyleMix, ViewParams};

use crate::device::Gpu;
use crate::error::GpuError;
use crate::host::HostDispatch;
use crate::policy::PolicyTable;
use crate::tables::{LOCK_FLOATS, POLICY_MAX, SeamParams, Tables, style_row};

const NONE: u32 = u32::MAX;
const MODE_INIT: u32 = 2;
/// Threads per workgroup of the per-walker passes (the shaders' `WG`).
const WG: u32 = 64;
/// Largest workgroup count in one dimension of a dispatch.
const MAX_X: u32 = 65535;
/// The counters' layout (the shaders' `C_*`): the round's builds, the walkers in view, the slot
/// faults, the free-slot stack's top.
pub(crate) const C_BUILDS: usize = 3;
const C_VISIBLE: usize = 4;
const C_SLOT_FAULTS: usize = 5;
const C_FREE_TOP: usize = 6;
/// The shortest clip duration built since the crowd was made, as its f32 bits (the shaders'
/// `C_MIN_DUR`, an `atomicMin` in the build pass; never reset).
const C_MIN_DUR: usize = 7;
/// Walkers whose root or joint positions came out NaN or infinite this frame, and the first of
/// them (the shaders' `C_NONFINITE`, `C_NONFINITE_FIRST`).
pub(crate) const C_NONFINITE: usize = 8;
const C_NONFINITE_FIRST: usize = 9;
/// Walkers inside a running seam transition this frame (the shaders' `C_SEAMS`).
const C_SEAMS: usize = 10;
/// Walkers whose foot lock corrected a leg this frame (the shaders' `C_LOCKS`).
const C_LOCKS: usize = 11;
/// Rounds of cycle ends and builds run this frame (the shaders' `C_ROUND`, which `fix_free`
/// counts).
const C_ROUND: usize = 12;
/// Walkers whose clock is past the end of the clip the last round built (the shaders' `C_BEHIND`).
const C_BEHIND: usize = 13;
/// Clips built this frame, every round's (the shaders' `C_BUILT`).
const C_BUILT: usize = 14;
/// The round's joint-slot grant threshold, a key's high and low words (the shaders'
/// `C_GRANT_HI`, `C_GRANT_LO`, written by `grant` before `build` reads them).
const C_GRANT_HI: usize = 15;
const C_GRANT_LO: usize = 16;
/// The round's builds with joints of walkers without a slot (the shaders' `C_ASKERS`).
const C_ASKERS: usize = 17;
const C_HIST: usize = 18;
// The frame's reset (`counters_reset`, from `C_NONFINITE` on) clears the grant's counters too.
const _: () = assert!(C_NONFINITE < C_GRANT_HI && C_GRANT_LO < C_ASKERS && C_ASKERS < C_HIST);

/// A frame is split into rounds (see [`GpuCrowd::step`]) when its `dt` is at least this fraction
/// of the shortest clip the crowd has built. A walker can end more than one cycle in a frame only
/// when a clip built in that frame is shorter than `dt` (the clock left past a cycle end is below
/// `dt`), so a frame that is not split can leave a walker behind only through a clip shorter than
/// half the shortest of every clip built before it. At 30 or 60 fps (`dt` of 33 or 17 ms against
/// clips of about a second) no frame is split and none pays the round trip.
const SPLIT_MARGIN: f32 = 0.5;
/// Most rounds encoded in one submission of a split frame (the rounds expected, `1 + dt /` the
/// shortest clip, are encoded at once; rounds without a walker behind cost one light `advance`
/// dispatch).
const MAX_ROUNDS_PER_SUBMIT: u32 = 32;
/// Rounds after which a split frame gives up ([`GpuError::Runtime`]): each cycle end takes at
/// least a clip's shortest duration, 1 ms, off a clock at most `MAX_DT` past its clip's end, so
/// more rounds than this mean a fault, not a long frame.
const MAX_ROUNDS: u32 = (MAX_DT * 1000.0) as u32 + 2;

/// One walker as the shaders hold it (`struct Walker` of `crowd.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(crate) struct GpuWalker {
    t: f32,
    cur_dur: f32,
    hold_s: f32,
    pend_u: f32,
    root: [f32; 3],
    height: f32,
    base: [f32; 2],
    heading: f32,
    sin_h: f32,
    cos_h: f32,
    s: f32,
    stride: f32,
    body_scale: f32,
    path_c: [f32; 2],
    path_ab: [f32; 2],
    path_rot: f32,
    path_dir: f32,
    controls: [f32; 4],
    motion: [f32; 3],
    init_phase: f32,
    init_hold: f32,
    /// The cycle frame's origin and heading are double-floats (`df.wgsl`): `base + base_lo`,
    /// `heading + heading_lo`, as the CPU crowd's f64 `lod_policy::CycleFrame`.
    base_lo: [f32; 2],
    heading_lo: f32,
    /// The path parameter is a double-float too: `s + s_lo` (the CPU's f64 `s`).
    s_lo: f32,
    /// Joints drawn at the last frame: the clip's, or more while a seam fades joints out.
    shown: u32,
    cur_acc: u32,
    cur_joints: u32,
    pend_acc: u32,
    pend_joints: u32,
    style: u32,
    slot: u32,
    mode: u32,
    flags: u32,
}

/// The per-frame uniform (`struct Frame` of `crowd.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
pub(crate) struct FrameUniform {
    planes: [[f32; 4]; 6],
    eye: [f32; 4],
    dt: f32,
    margin: f32,
    pub(crate) n: u32,
    pub(crate) n_slots: u32,
    vis_entries: u32,
    hid_entries: u32,
    /// 0: the double-float library's `df_zero()`, bits the shader compiler cannot see through
    /// (`df.wgsl`).
    df_zero: u32,
    pad: u32,
    policy: [[u32; 4]; POLICY_MAX],
}

/// Settings of the GPU crowd beyond the CPU crowd's [`CrowdConfig`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GpuOptions {
    /// Walkers that can hold a clip with joints at the same time (each such clip takes
    /// `4 (P max r_T + 2 T)` bytes, plus `12 J` for its joint positions, with seams on
    /// `4 (3 P + 3)` for its seam transition and with the foot lock on 216 for its lock state:
    /// [`GpuCrowd::bytes_per_joint_slot`]); `None` gives
    /// every walker one; a page's slots are its share of them, in proportion to its walkers.
    ///
    /// A walker competes for a slot at each clip build with joints: one that holds a slot (its
    /// cycle end, or a refinement) and one that asks for one (a walker shown root only whose
    /// policy wants joints asks again every frame). When a round's builds ask for more slots than
    /// are free, the competing walkers of the page get them nearest first: walkers in view before
    /// walkers out of view, then by distance from the eye, then by walker index. A holder that
    /// loses gives its slot back and is shown root only, as a walker the policy wants with
    /// joints and that gets no slot; both are counted in [`GpuFrameStats::slot_faults`]. A far
    /// walker keeps its slot until its next build, so the slots move to the nearest walkers
    /// within a cycle. Which walkers win does not depend on the order of the GPU's threads: runs
    /// are repeatable with any number of slots.
    pub joint_slots: Option<usize>,
    /// Walkers per page (the crowd is split into pages whose buffers each fit the adapter's
    /// largest storage binding); `None` picks the largest that fits. `Some(0)` is an error
    /// ([`GpuError::Config`]); small pages cost a dispatch chain and ten buffers each.
    pub page_walkers: Option<usize>,
}

/// What one GPU frame did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct GpuFrameStats {
    /// Walkers whose box intersected the view frustum.
    pub visible: u64,
    /// Clips built this frame.
    pub kernels_built: u64,
    /// Walkers shown root only because no joint slot was free ([`GpuOptions::joint_slots`]).
    pub slot_faults: u64,
    /// Walkers inside a seam transition after the frame (as `crowd_sim::FrameStats`; 0 with
    /// `seam_levels = 0`).
    pub in_transition: u64,
    /// Walkers whose foot lock moved a leg this frame by at least 1e-6 m (a planted foot held,
    /// lowered or lifted, a swing foot lifted, or a correction easing out; 0 with
    /// `foot_lock_levels = 0` or a model without feet).
    pub feet_locked: u64,
    /// Walkers per accuracy level, then root-only walkers last (as `crowd_sim::FrameStats`).
    pub level_histogram: Vec<u32>,
    /// Rounds of cycle ends and clip builds run this frame, the most of any page: 1, or more when
    /// the frame was split because its `dt` may hold several cycle ends of a walker (see
    /// [`GpuCrowd::step`]).
    pub rounds: u32,
    /// Walkers whose clock is still past the end of their clip after the frame: cycle ends the
    /// CPU crowd would have made in this frame and the GPU crowd makes later (0 unless a clip
    /// built in a frame that was not split is shorter than the time left past the previous
    /// clip's end; see [`GpuCrowd::step`]).
    pub behind: u64,
    /// Wall time from the frame's first submission to its completion on the device, including
    /// the read-back of these statistics (and, in a split frame, the waits between its rounds).
    pub gpu: Duration,
    /// Wall time of the whole step on the host (upload, encode, submit, wait, read back).
    pub wall: Duration,
}

/// One walker's joints after a frame, read back from the GPU ([`GpuCrowd::read_walkers`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WalkerJoints {
    /// The detail of the walker's clip (the policy's, as the CPU crowd's `Crowd::detail`).
    pub detail: Detail,
    /// World joint positions (m): the root, then the clip's active joints in row order (as the
    /// CPU crowd's `Crowd::joint_positions`).
    pub positions: Vec<Vec3>,
}

/// One page of walkers: its buffers and bind group.
#[derive(Debug)]
pub(crate) struct Page {
    pub(crate) n: usize,
    pub(crate) slots: usize,
    frame: wgpu::Buffer,
    pub(crate) walkers: wgpu::Buffer,
    pub(crate) counters: wgpu::Buffer,
    pub(crate) joints: wgpu::Buffer,
    /// The bind group's other storage buffers, in binding order: the build list (4), the free
    /// slots (5), the root-only clips (7) and the clips with joints (8).
    pub(crate) lists: [wgpu::Buffer; 4],
    /// The arguments of the round's indirect dispatches (`dispatch_args`, binding 10), and the
    /// bind group of `build_args`, which writes them (the counters and them).
    pub(crate) args: wgpu::Buffer,
    args_bind: wgpu::BindGroup,
    bind: wgpu::BindGroup,
    bytes: u64,
}

/// The crowd of [`crowd_sim`] on the GPU: the same walkers, paths, culling and level-of-detail
/// policy, with clips built, posed and skinned by compute shaders.
///
/// What it does as the CPU crowd does (`crowd_sim::Crowd` with the same [`CrowdConfig`] and a
/// `LodSource` over the same model): the walkers' seeded paths, strides, heights, styles and
/// starting phases; per frame the frustum test of each walker's box from its last root, the
/// policy's detail from its distance ([`PolicyTable`]), the clock, cycle ends (the cycle frame
/// moved by the clip's root motion, the next controls from the path ahead), mid-cycle refinement
/// when the policy wants a finer detail (after the spread of first builds), the clip build at the
/// detail the model evaluates (kriging weights, core, `G(c)`, time table, root motion, body
/// scale), the pose at the clip's phase and forward kinematics of the active joints; and with
/// `seam_levels > 0` the inertialized seams (`lod_policy::SeamTransition`, as the CPU walker
/// starts, applies and ends them): at a clip change between two clips with joints, the new one at
/// one of the first `seam_levels` levels, the displayed pose of the outgoing clip and its velocity
/// (by a finite difference over `lod_policy::SEAM_STEP_S`, in the next cycle frame at a cycle
/// end) start offsets that decay with a critically damped spring of half-life
/// `seam_halflife_s`, the root orientation's composed as a rotation, joints only one side shows
/// fading from or to their rest rotations (drawn beyond the clip's while they fade out); and with
/// `foot_lock_levels > 0` and a model with feet, the foot lock (`lod_policy::FootLock`, as the
/// CPU walker's pose stage runs it through the model source): each visible walker at one of the
/// first `foot_lock_levels` levels with joints plants its feet (per foot the pivot placed in the
/// world by its double-float cycle frame, contact, the horizontal correction and the lowering
/// with the onset's easing, release, clearance and the ground's margin, then two-bone IK that
/// writes the thigh, knee and ankle rows before forward kinematics); any other walker lets go at
/// once (out of view, at a coarser level, root only).
///
/// Seam state lives in the walker's joint slot, after its clip: offset, velocity and base rows and
/// three scalars, `4 (3 P + 3)` bytes a slot (with seams on only; walkers without joints hold no
/// slot and pay nothing). Per frame two passes around the clip build run when seams are on:
/// `seam_capture` (the outgoing clip's displayed state, before the build overwrites the clip) and
/// `seam_start` (the transition to the incoming clip); the pose pass applies the running
/// transition and ends it once decayed. Foot lock state lives in the joint slot too, after the
/// seam state: 27 floats a foot (the previous frame's ground points as double-floats, flags,
/// clocks, the correction, its rate and both at lift-off, the lifts), 216 bytes a slot, with the
/// lock on only (nothing with `foot_lock_levels = 0` or a model without feet). It needs no pass of
/// its own: the pose pass runs it between the seam and forward kinematics, and `advance` clears
/// it when it gives a slot back.
///
/// A frame step `dt` longer than a clip holds several cycle ends of a walker, which the CPU walker
/// makes in one loop; on the GPU each cycle end needs the clip the previous one built (its
/// duration and root motion), so they run in rounds of `advance` and the build passes, all before
/// the pose pass: [`GpuCrowd::step`] splits such a frame (when `dt` is at least half the shortest
/// clip the crowd has built) and runs catch-up rounds until no walker's clock is past its clip's
/// end. Frames that are not split (at 30 or 60 fps, every frame: clips last about a second) run
/// as one submission, as before. What remains ([`GpuFrameStats::behind`]): a walker whose clip,
/// built in a frame that was not split, is shorter than the clock left past the previous clip's
/// end — possible only for a clip shorter than half the shortest of all clips built before that
/// frame — shows that clip's last pose in that frame and makes the cycle ends it owes in the next
/// frames, at their detail (all of them in the next split frame; one a frame otherwise), so that
/// it may walk on apart from the CPU's walker.
///
/// Walker state lives on the GPU; per frame the host uploads the frame's uniform (camera planes,
/// time step, the policy table) and resets a few counters, and reads back the counters (a split
/// frame reads them back after its rounds too).
#[derive(Debug)]
pub struct GpuCrowd {
    gpu_name: String,
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    pipelines: Pipelines,
    pub(crate) pages: Vec<Page>,
    /// Read-back buffers of the counters: `step` uses the first; frames of `submit` alternate,
    /// so that one can be in flight while the next is recorded.
    staging: [wgpu::Buffer; 2],
    /// Set by `map_async` when `staging[k]` is mapped for `submit` (made once).
    mapped: [MapSignal; 2],
    /// The compute shaders' source (for [`GpuCrowd::host_state`]).
    pub(crate) wgsl: String,
    /// The model's packed numbers (binding 6) and table (binding 1), shared by the pages.
    pub(crate) model_buffers: [wgpu::Buffer; 2],
    pub(crate) counters_len: usize,
    /// The frame `submit` left in flight, or a frame it ran to the end whose statistics the next
    /// call returns.
    pending: Option<Pending>,
    /// What `step` writes over the counters from [`C_NONFINITE`] to the end before each frame:
    /// no walker not finite (the first at `u32::MAX`, the shaders' `atomicMin`), no seam, no
    /// lock, an empty histogram. Made once (no allocation per frame).
    pub(crate) counters_reset: Vec<u32>,
    levels: usize,
    joints: usize,
    walkers: usize,
    config: CrowdConfig,
    field_enlarged_from: Option<f32>,
    policy_cache: Option<PolicyCache>,
    frame: u64,
    bytes_per_slot: u64,
    /// The shortest clip duration (s) built so far, from the counters read back after the
    /// crowd's first builds and after each frame (`C_MIN_DUR`).
    min_dur: f32,
}

/// A frame of [`GpuCrowd::submit`] not yet returned.
#[derive(Debug)]
enum Pending {
    /// Submitted; its counters are copied into `staging[buffer]`, mapped once `mapped[buffer]`
    /// is set.
    InFlight {
        buffer: usize,
        submission: wgpu::SubmissionIndex,
        submitted: Instant,
        wall: Duration,
        frame: u64,
    },
    /// Run to the end (a split frame), its statistics or error kept for the next call.
    Done(Result<GpuFrameStats, GpuError>),
}

/// Set by a read-back buffer's `map_async` callback (shared with it; `Sync`, unlike a channel's
/// receiver, so that the crowd stays `Sync`).
type MapSignal = std::sync::Arc<std::sync::Mutex<Option<Result<(), wgpu::BufferAsyncError>>>>;

/// A frame's work recorded by [`GpuCrowd::encode_frame`], and, for a frame split into rounds, the
/// catch-up pipeline and the rounds a submission.
struct Encoded {
    encoder: wgpu::CommandEncoder,
    split: Option<(wgpu::ComputePipeline, u32)>,
    dt: f32,
}

/// The policy table of the last frames, and what it was made for.
#[derive(Debug)]
struct PolicyCache {
    view: ViewParams,
    /// The policy's address and type (a policy passed by another reference is tabulated anew).
    policy: (usize, &'static str),
    table: PolicyTable,
    entries: Vec<[u32; 4]>,
}

#[derive(Debug)]
struct Pipelines {
    advance: wgpu::ComputePipeline,
    /// `advance` with `CATCH_UP` set: the rounds of a split frame after its first (see
    /// [`GpuCrowd::step`]), made from `module` and `layout` at the first split frame (a crowd
    /// never split does not compile it).
    catch_up: Option<wgpu::ComputePipeline>,
    module: wgpu::ShaderModule,
    layout: wgpu::PipelineLayout,
    build_args: wgpu::ComputePipeline,
    build: wgpu::ComputePipeline,
    /// Which of the walkers competing for too few joint slots get them (nearest first).
    grant: wgpu::ComputePipeline,
    fix_free: wgpu::ComputePipeline,
    pose_fk: wgpu::ComputePipeline,
    /// The seam passes `seam_capture` and `seam_start`, made and run when `seam_levels > 0`.
    seam: Option<(wgpu::ComputePipeline, wgpu::ComputePipeline)>,
}

/// Workgroups for `n` walkers: `(x, y)` with `x y WG >= n`.
pub(crate) fn groups(n: usize) -> (u32, u32) {
    let g = n.div_ceil(WG as usize).max(1) as u32;
    let x = g.min(MAX_X);
    (x, g.div_ceil(x))
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The compute pipeline of `entry` in `module`, with its pipeline-overridable `constants`.
fn compute_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entry: &str,
    constants: &[(&str, f64)],
) -> wgpu::ComputePipeline {
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants,
            ..Default::default()
        },
        cache: None,
    })
}

/// Runs `f` inside a validation and an out-of-memory error scope; their errors become
/// [`GpuError::Runtime`].
pub(crate) fn scoped<R>(
    device: &wgpu::Device,
    what: &str,
    f: impl FnOnce() -> R,
) -> Result<R, GpuError> {
    scoped_raw(device, f).map_err(|e| GpuError::Runtime(format!("{what}: {e}")))
}

/// [`scoped`] giving the device's error (the out-of-memory error first).
fn scoped_raw<R>(device: &wgpu::Device, f: impl FnOnce() -> R) -> Result<R, wgpu::Error> {
    device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    device.push_error_scope(wgpu::ErrorFilter::Validation);
    let r = f();
    let validation = pollster::block_on(device.pop_error_scope());
    let memory = pollster::block_on(device.pop_error_scope());
    match memory.or(validation) {
        Some(e) => Err(e),
        None => Ok(r),
    }
}

/// The model packed for the shaders and the shader source for a crowd of `config` over `model`,
/// and the model's control range: what [`GpuCrowd::new`] checks and makes before it needs a device.
fn tables_for(
    model: &RuntimeModel,
    config: &CrowdConfig,
) -> Result<(Tables, lod_policy::ControlRange), GpuError> {
    check_config(config)?;
    let range = model
        .lod()
        .controls()
        .range()
        .ok_or_else(|| GpuError::Model("the control space is not a walk's".into()))?;
    check_control_range(&range)?;
    // Style rows: one per style alone, then the config's blend (or the data's mix).
    let mut styles = Vec::new();
    for j in 0..model.styles().len() {
        styles.push(style_row(model, StyleMix::one(j))?);
    }
    styles.push(style_row(
        model,
        match config.style {
            CrowdStyle::Each(s) => s,
            CrowdStyle::DataMix => StyleMix::DATA_MIX,
        },
    )?);
    let seam = SeamParams::new(config.seam_levels, config.seam_halflife_s);
    Ok((
        Tables::new(model, &styles, seam, config.foot_lock_levels)?,
        range,
    ))
}

/// The compute shaders of a GPU crowd of `config` over `model`, as [`GpuCrowd::new`] compiles them
/// (WGSL: the model's sizes and numbers as constants, then the double-float library, the
/// [`crate::DRAW_WGSL`] declarations and the passes; entry points `advance`, `build_args`,
/// `grant`, `seam_capture`, `build`, `seam_start`, `fix_free` and `pose_fk`). No device needed:
/// for checking the shaders with another WGSL compiler (CI compiles them with Chromium's WebGPU)
/// or running them on another host.
///
/// Errors: those of [`GpuCrowd::new`] that come before a device is needed (the config, a model
/// the shaders cannot take).
pub fn crowd_wgsl(model: &RuntimeModel, config: &CrowdConfig) -> Result<String, GpuError> {
    Ok(tables_for(model, config)?.0.source)
}

impl GpuCrowd {
    /// Places `config.walkers` walkers as `crowd_sim::Crowd::new` does for a source over `model`
    /// (the same paths, phases, strides, heights and styles; the field enlarged likewise), uploads
    /// them and builds every walker's first, root-only clip on the GPU.
    ///
    /// Seams are inertialized as the CPU crowd's at the first `config.seam_levels` levels (any
    /// value; `usize::MAX`, the CPU crowd's default, is every level), which costs each joint slot
    /// `4 (3 P + 3)` more bytes ([`GpuCrowd::bytes_per_joint_slot`]); `seam_levels = 0` runs no
    /// seam pass and allocates nothing for them. Feet are locked as the CPU crowd's at the first
    /// `config.foot_lock_levels` levels (any value; `usize::MAX`, the CPU crowd's default, is
    /// every level), which costs each joint slot 216 more bytes; `foot_lock_levels = 0` allocates
    /// nothing for it. A model without feet (`RuntimeModel::feet` is `None`) is locked by neither
    /// crowd: the config is taken, nothing is locked and nothing allocated, as the CPU source.
    ///
    /// Errors: a config the CPU crowd would refuse; a model the shaders cannot take (feet that do
    /// not fit its rig among them), or one with a number single precision cannot
    /// hold ([`GpuError::Model`]); [`GpuOptions::page_walkers`] of `Some(0)`
    /// ([`GpuError::Config`]); buffers or workgroup memory beyond the adapter's limits
    /// ([`GpuError::Limit`]), or buffers the device cannot allocate ([`GpuError::Memory`], with
    /// the bytes asked for).
    pub fn new(
        gpu: &Gpu,
        model: &RuntimeModel,
        config: CrowdConfig,
        options: GpuOptions,
    ) -> Result<GpuCrowd, GpuError> {
        let mut config = config;
        let (tables, range) = tables_for(model, &config)?;
        let seam = SeamParams::new(config.seam_levels, config.seam_halflife_s);
        let n_styles = model.styles().len();
        let limits = &gpu.limits;
        if tables.workgroup_bytes > u64::from(limits.max_compute_workgroup_storage_size) {
            return Err(GpuError::Limit {
                what: "workgroup memory of the clip build (bytes)",
                needed: tables.workgroup_bytes,
                limit: u64::from(limits.max_compute_workgroup_storage_size),
                adapter: gpu.adapter_name(),
            });
        }

        // The walkers, as crowd_sim::Crowd::new draws them (the same plan and draws).
        let bounds = range;
        let plan = PathPlan::new(&bounds, config.border_m);
        let field_enlarged_from = fit_field(&plan, &mut config)?;
        let mix = model.data_style_mix();
        let last = tables.levels - 1;
        let mut walkers = Vec::new();
        walkers.try_reserve_exact(config.walkers).map_err(|_| {
            crowd_sim::CrowdError::OutOfMemory {
                what: "walker states",
                walkers: config.walkers,
            }
        })?;
        for i in 0..config.walkers {
            let mut g = SplitMix64::for_walker(config.seed, i);
            let start @ WalkerStart {
                path,
                s,
                base,
                heading,
                stride,
                height,
                phase,
            } = plan.draw(&mut g, config.field_size_m, &bounds).ok_or(
                crowd_sim::CrowdError::FieldTooSmall {
                    field_m: config.field_size_m,
                    needed_m: plan.needed_field_m(),
                },
            )?;
            let (style, style_id) = if mix.is_empty() {
                (StyleMix::DATA_MIX, n_styles as u32)
            } else {
                let st = config.style.for_walker(mix, g.next_f32());
                let id = match config.style {
                    CrowdStyle::Each(_) => n_styles,
                    CrowdStyle::DataMix => (0..n_styles)
                        .find(|&j| st == StyleMix::one(j))
                        .unwrap_or(n_styles),
                };
                (st, id as u32)
            };
            let c = start.first_controls(&bounds).with_style(style);
            let hold = if config.spread_first_builds {
                g.next_f32()
            } else {
                0.0
            };
            // As the CPU crowd's walker: the f64 frame's sine and cosine, rounded.
            let (sh, ch) = f64::from(heading).sin_cos();
            let (sh, ch) = (sh as f32, ch as f32);
            walkers.push(GpuWalker {
                t: 0.0,
                cur_dur: 1.0,
                hold_s: 0.0,
                pend_u: 0.0,
                root: [base.x, 0.0, base.y],
                height,
                base: [base.x, base.y],
                heading,
                sin_h: sh,
                cos_h: ch,
                s,
                stride,
                body_scale: 1.0,
                path_c: [path.centre.x, path.centre.y],
                path_ab: [path.axes.x, path.axes.y],
                path_rot: path.rot,
                path_dir: path.dir,
                controls: c.to_array(),
                motion: [0.0; 3],
                init_phase: phase,
                init_hold: hold,
                base_lo: [0.0; 2],
                heading_lo: 0.0,
                s_lo: 0.0,
                shown: 0,
                cur_acc: last as u32,
                cur_joints: 0,
                pend_acc: last as u32,
                pend_joints: 0,
                style: style_id,
                slot: NONE,
                mode: MODE_INIT,
                flags: 0,
            });
        }

        let device = gpu.device.clone();
        let queue = gpu.queue.clone();
        let module = scoped(&device, "compiling the crowd shaders", || {
            device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("gpu-crowd"),
                source: wgpu::ShaderSource::Wgsl(tables.source.as_str().into()),
            })
        })?;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gpu-crowd"),
            entries: &[
                uniform_entry(0),
                uniform_entry(1),
                storage_entry(2, false),
                storage_entry(3, false),
                storage_entry(4, false),
                storage_entry(5, false),
                storage_entry(6, true),
                storage_entry(7, false),
                storage_entry(8, false),
                storage_entry(9, false),
            ],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gpu-crowd"),
            bind_group_layouts: &[&layout],
            push_constant_ranges: &[],
        });
        // `build_args` binds the counters and the indirect dispatch's arguments, which no other
        // pass binds (the indirect dispatches read them).
        let args_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gpu-crowd dispatch arguments"),
            entries: &[storage_entry(3, false), storage_entry(10, false)],
        });
        let args_pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gpu-crowd dispatch arguments"),
            bind_group_layouts: &[&args_layout],
            push_constant_ranges: &[],
        });
        let pipeline = |entry: &str| compute_pipeline(&device, &module, &pl, entry, &[]);
        let pipelines = scoped(&device, "creating the crowd pipelines", || Pipelines {
            advance: pipeline("advance"),
            catch_up: None,
            build_args: compute_pipeline(&device, &module, &args_pl, "build_args", &[]),
            build: pipeline("build"),
            grant: pipeline("grant"),
            fix_free: pipeline("fix_free"),
            pose_fk: pipeline("pose_fk"),
            seam: (seam.levels > 0).then(|| (pipeline("seam_capture"), pipeline("seam_start"))),
            module: module.clone(),
            layout: pl.clone(),
        })?;

        // Pages: each buffer of a page within the adapter's largest storage binding.
        let n = config.walkers;
        let slots_total = options.joint_slots.unwrap_or(n).min(n);
        let (p, t, rt_max, rt_last, j) = (
            tables.p,
            tables.t,
            tables.rt_max,
            tables.rt_last,
            tables.joints,
        );
        let small_per_walker = 4 * (7 * rt_last + 2 * t) as u64;
        // A joint slot's clip, then its seam state when seams are on (`crowd.wgsl`'s `SB_*`:
        // offset, velocity and base rows, the rows, start and captured rows of the transition),
        // then its foot lock state when the lock is on (`LOCK_OFF`, two feet of `FOOT_FLOATS`).
        let seam_floats = if seam.levels > 0 { 3 * p + 3 } else { 0 };
        let lock_floats = if tables.lock_levels > 0 {
            LOCK_FLOATS
        } else {
            0
        };
        let big_floats = p * rt_max + 2 * t + seam_floats + lock_floats;
        let big_per_slot = 4 * big_floats as u64;
        let joints_per_slot = 12 * j.max(1) as u64;
        let walker_bytes = std::mem::size_of::<GpuWalker>() as u64;
        let max_binding =
            u64::from(limits.max_storage_buffer_binding_size).min(limits.max_buffer_size);
        let largest = walker_bytes
            .max(small_per_walker)
            .max(big_per_slot)
            .max(joints_per_slot);
        let fit = (max_binding / largest).min(u64::from(u32::MAX) / (big_floats as u64).max(1));
        if options.page_walkers == Some(0) {
            return Err(GpuError::Config(
                "GpuOptions::page_walkers = Some(0): a page holds at least one walker (None picks \
                 the largest page that fits)"
                    .into(),
            ));
        }
        let page_walkers = options
            .page_walkers
            .unwrap_or(usize::MAX)
            .min(fit as usize)
            .max(1);
        if fit == 0 {
            return Err(GpuError::Limit {
                what: "bytes of one walker's clip in one storage binding",
                needed: largest,
                limit: max_binding,
                adapter: gpu.adapter_name(),
            });
        }
        let counters_len = C_HIST + tables.levels + 1;
        let page_count = n.div_ceil(page_walkers);
        // Each page's walkers and joint slots: slots shared in proportion (the last page takes
        // what is left).
        let page_slots = |k: usize, pn: usize, slots_left: usize| {
            if k + 1 == page_count {
                slots_left
            } else {
                ((slots_total as u128 * pn as u128) / n as u128) as usize
            }
        };
        // The bytes of every buffer, before any is allocated (for the error when the device
        // cannot hold them).
        let frame_bytes = std::mem::size_of::<FrameUniform>() as u64;
        let mut crowd_bytes = 4 * (counters_len * page_count) as u64;
        {
            let (mut start, mut slots_left) = (0, slots_total);
            for k in 0..page_count {
                let pn = page_walkers.min(n - start);
                let slots = page_slots(k, pn, slots_left);
                slots_left -= slots;
                let (pn, sa) = (pn as u64, slots.max(1) as u64);
                crowd_bytes += pn * (walker_bytes + 8)
                    + 4 * sa
                    + (small_per_walker * pn).max(4)
                    + (big_per_slot * sa).max(4)
                    + (joints_per_slot * sa).max(4)
                    + frame_bytes
                    + 4 * counters_len as u64
                    + 12;
                start += pn as usize;
            }
        }
        // Buffers made and filled inside the error scopes (a buffer the device cannot allocate
        // is an error there, where a buffer mapped at creation would panic).
        let init = |label: &str, contents: &[u8], usage: wgpu::BufferUsages| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: contents.len() as u64,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            queue.write_buffer(&buffer, 0, contents);
            buffer
        };
        let memory = |what: &'static str, bytes: u64, e: wgpu::Error| GpuError::Memory {
            what,
            bytes,
            walkers: n,
            adapter: gpu.adapter_name(),
            reason: e.to_string(),
        };
        let model_bytes = 4 * (tables.md.len() + tables.mtab.len()) as u64;
        let (md, mtab) = scoped_raw(&device, || {
            (
                init(
                    "model",
                    bytemuck::cast_slice(&tables.md),
                    wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
                ),
                init(
                    "model table",
                    bytemuck::cast_slice(&tables.mtab),
                    wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_SRC,
                ),
            )
        })
        .map_err(|e| memory("the model's buffers", model_bytes, e))?;
        let mut pages = Vec::new();
        let mut start = 0;
        let mut slots_left = slots_total;
        let mut encoder = device.create_command_encoder(&Default::default());
        let result = scoped_raw(&device, || {
            for k in 0..page_count {
                let pn = page_walkers.min(n - start);
                let slots = page_slots(k, pn, slots_left);
                slots_left -= slots;
                let slots_alloc = slots.max(1);
                let ws = &walkers[start..start + pn];
                let storage = wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_SRC
                    | wgpu::BufferUsages::COPY_DST;
                let walkers_buf = init("walkers", bytemuck::cast_slice(ws), storage);
                let mut counters = vec![0u32; counters_len];
                let (gx, gy) = (pn.min(MAX_X as usize) as u32, (pn as u32).div_ceil(MAX_X));
                let args = init(
                    "dispatch arguments",
                    bytemuck::cast_slice(&[gx, gy, 1u32]),
                    storage | wgpu::BufferUsages::INDIRECT,
                );
                counters[C_BUILDS] = pn as u32;
                counters[C_FREE_TOP] = slots as u32;
                counters[C_MIN_DUR] = f32::INFINITY.to_bits();
                counters[C_GRANT_HI] = NONE;
                counters[C_GRANT_LO] = NONE;
                let counters_buf = init("counters", bytemuck::cast_slice(&counters), storage);
                // The first builds' walker indices, then room for the grant keys.
                let list: Vec<u32> = (0..pn as u32).chain(std::iter::repeat_n(0, pn)).collect();
                let build_list = init("build list", bytemuck::cast_slice(&list), storage);
                let stack: Vec<u32> = (0..slots_alloc as u32).rev().collect();
                let free_stack = init("free joint slots", bytemuck::cast_slice(&stack), storage);
                let make = |label: &str, size: u64| {
                    device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(label),
                        size: size.max(4),
                        usage: storage,
                        mapped_at_creation: false,
                    })
                };
                let small = make("root-only clips", small_per_walker * pn as u64);
                let big = make("clips with joints", big_per_slot * slots_alloc as u64);
                let joints = make("joint positions", joints_per_slot * slots_alloc as u64);
                let frame = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("frame"),
                    size: frame_bytes,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                let mut uniform = FrameUniform::zeroed();
                uniform.n = pn as u32;
                uniform.n_slots = slots_alloc as u32;
                queue.write_buffer(&frame, 0, bytemuck::bytes_of(&uniform));
                let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("gpu-crowd page"),
                    layout: &layout,
                    entries: &[
                        (0, &frame),
                        (1, &mtab),
                        (2, &walkers_buf),
                        (3, &counters_buf),
                        (4, &build_list),
                        (5, &free_stack),
                        (6, &md),
                        (7, &small),
                        (8, &big),
                        (9, &joints),
                    ]
                    .map(|(binding, b)| wgpu::BindGroupEntry {
                        binding,
                        resource: b.as_entire_binding(),
                    }),
                });
                let bytes = [
                    &walkers_buf,
                    &counters_buf,
                    &args,
                    &build_list,
                    &free_stack,
                    &small,
                    &big,
                    &joints,
                    &frame,
                ]
                .iter()
                .map(|b| b.size())
                .sum();
                let args_bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("gpu-crowd dispatch arguments"),
                    layout: &args_layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 3,
                            resource: counters_buf.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 10,
                            resource: args.as_entire_binding(),
                        },
                    ],
                });
                // The first clips: every walker root only, built on the GPU.
                {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_bind_group(0, &bind, &[]);
                    pass.set_pipeline(&pipelines.build);
                    pass.dispatch_workgroups_indirect(&args, 0);
                    pass.set_pipeline(&pipelines.fix_free);
                    pass.dispatch_workgroups(1, 1, 1);
                }
                pages.push(Page {
                    n: pn,
                    slots: slots_alloc,
                    frame,
                    walkers: walkers_buf,
                    counters: counters_buf,
                    joints,
                    lists: [build_list, free_stack, small, big],
                    args_bind,
                    args,
                    bind,
                    bytes,
                });
                start += pn;
            }
            [0, 1].map(|_| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("counters read-back"),
                    size: (4 * counters_len * page_count) as u64,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
        });
        let staging = result.map_err(|e| memory("the crowd's buffers", crowd_bytes, e))?;
        let mut crowd = GpuCrowd {
            gpu_name: gpu.adapter_name(),
            device,
            queue,
            pipelines,
            pages,
            staging,
            mapped: Default::default(),
            pending: None,
            wgsl: tables.source.clone(),
            model_buffers: [md, mtab],
            counters_len,
            counters_reset: {
                let mut reset = vec![0u32; counters_len - C_NONFINITE];
                reset[C_NONFINITE_FIRST - C_NONFINITE] = u32::MAX;
                reset
            },
            levels: tables.levels,
            joints: j,
            walkers: n,
            config,
            field_enlarged_from,
            policy_cache: None,
            frame: 0,
            bytes_per_slot: big_per_slot + joints_per_slot,
            min_dur: f32::INFINITY,
        };
        // The first clips' shortest duration, which the first frame's split needs.
        let counters = scoped(&crowd.device, "building the first clips", || {
            crowd.submit_and_read(encoder)
        })??;
        crowd.min_dur = crowd.shortest_clip(&counters);
        Ok(crowd)
    }

    /// Appends the copy of every page's counters to the read-back buffer to `encoder`, submits
    /// it, waits and returns the counters (a row of `counters_len` per page).
    fn submit_and_read(&self, mut encoder: wgpu::CommandEncoder) -> Result<Vec<u32>, GpuError> {
        self.copy_counters(&mut encoder, 0);
        self.submit_and_wait(encoder)?;
        self.read_mapped(&self.staging[0])
    }

    /// Appends the copy of every page's counters into `staging[buffer]` to `encoder`.
    fn copy_counters(&self, encoder: &mut wgpu::CommandEncoder, buffer: usize) {
        let row = (4 * self.counters_len) as u64;
        for (k, page) in self.pages.iter().enumerate() {
            encoder.copy_buffer_to_buffer(
                &page.counters,
                0,
                &self.staging[buffer],
                k as u64 * row,
                row,
            );
        }
    }

    /// The shortest clip duration any page has built, from counters read back.
    fn shortest_clip(&self, counters: &[u32]) -> f32 {
        counters
            .chunks_exact(self.counters_len)
            .map(|c| f32::from_bits(c[C_MIN_DUR]))
            .fold(f32::INFINITY, f32::min)
    }

    /// The `advance` pipeline of catch-up rounds, made at the first call.
    fn catch_up_pipeline(&mut self) -> Result<wgpu::ComputePipeline, GpuError> {
        if let Some(made) = &self.pipelines.catch_up {
            return Ok(made.clone());
        }
        let p = &self.pipelines;
        let made = scoped(&self.device, "creating the catch-up pipeline", || {
            compute_pipeline(
                &self.device,
                &p.module,
                &p.layout,
                "advance",
                &[("CATCH_UP", 1.0)],
            )
        })?;
        self.pipelines.catch_up = Some(made.clone());
        Ok(made)
    }

    /// Records one round of cycle ends and clip builds of `page` into `pass`: `advance` (the
    /// frame's first round, or with the catch-up pipeline a catch-up round), `build_args`, with
    /// `grant`, with seams on `seam_capture`, `build`, with seams on `seam_start`, and `fix_free`,
    /// which ends the round.
    fn record_round(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        page: &Page,
        advance: &wgpu::ComputePipeline,
    ) {
        let (gx, gy) = groups(page.n);
        pass.set_bind_group(0, &page.bind, &[]);
        for (_, pipeline, dispatch) in self.round_passes(Some(advance)).into_iter().flatten() {
            pass.set_pipeline(pipeline);
            match dispatch {
                HostDispatch::Walkers => pass.dispatch_workgroups(gx, gy, 1),
                HostDispatch::One => pass.dispatch_workgroups(1, 1, 1),
                HostDispatch::Arguments => {
                    pass.set_bind_group(0, &page.args_bind, &[]);
                    pass.dispatch_workgroups(1, 1, 1);
                    pass.set_bind_group(0, &page.bind, &[]);
                }
                HostDispatch::Indirect => pass.dispatch_workgroups_indirect(&page.args, 0),
            }
        }
    }

    /// The passes of a round in order (`advance` the frame's first round's, `None`, or a catch-up
    /// round's), each with its entry point and how it is dispatched: what `record_round` records
    /// and [`GpuCrowd::host_state`] tells another host. `grant` decides which walkers competing
    /// for joint slots get them before a losing holder's outgoing clip would be captured for a
    /// seam, and `seam_capture` (with seams on) keeps the outgoing clips' displayed states before
    /// `build` overwrites them.
    pub(crate) fn round_passes<'a>(
        &'a self,
        advance: Option<&'a wgpu::ComputePipeline>,
    ) -> [Option<(&'static str, &'a wgpu::ComputePipeline, HostDispatch)>; 7] {
        let p = &self.pipelines;
        let advance = advance.unwrap_or(&p.advance);
        let seam = p.seam.as_ref();
        [
            Some(("advance", advance, HostDispatch::Walkers)),
            Some(("build_args", &p.build_args, HostDispatch::Arguments)),
            Some(("grant", &p.grant, HostDispatch::One)),
            seam.map(|(capture, _)| ("seam_capture", capture, HostDispatch::Indirect)),
            Some(("build", &p.build, HostDispatch::Indirect)),
            seam.map(|(_, start)| ("seam_start", start, HostDispatch::Indirect)),
            Some(("fix_free", &p.fix_free, HostDispatch::One)),
        ]
    }

    /// Records the pose pass of `page` into `pass`.
    fn record_pose(&self, pass: &mut wgpu::ComputePass<'_>, page: &Page) {
        let (gx, gy) = groups(page.n);
        pass.set_bind_group(0, &page.bind, &[]);
        pass.set_pipeline(&self.pipelines.pose_fk);
        pass.dispatch_workgroups(gx, gy, 1);
    }

    fn submit_and_wait(&self, encoder: wgpu::CommandEncoder) -> Result<(), GpuError> {
        let index = self.queue.submit([encoder.finish()]);
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| GpuError::Runtime(e.to_string()))?;
        Ok(())
    }

    /// Advances the crowd by `dt` seconds seen from `camera` under `policy` (the stages of
    /// `crowd_sim::Crowd::step`, on the GPU) and waits for the frame to finish.
    ///
    /// A walker makes every cycle end the CPU crowd's makes in the frame, however long `dt`: the
    /// passes up to the clip build make one cycle end per walker and round, and a frame whose
    /// `dt` is at least half the shortest clip the crowd has built so far (read back with each
    /// frame's counters; the builds of `new` included) is split: its rounds are submitted first
    /// (as many as `dt` over that clip suggests, at most 32 a submission) and, while a walker's
    /// clock is still past its new clip's end, more catch-up rounds (no time added, the spread of
    /// first builds not counted down, no mid-cycle refinement, nothing counted twice), then the
    /// pose pass. Such a frame pays a host round trip or two; any other frame is one submission.
    /// [`GpuFrameStats::rounds`] says how many rounds ran, [`GpuFrameStats::behind`] the walkers
    /// left behind by a frame that was not split (see [`GpuCrowd`]).
    ///
    /// The policy is tabulated over distance ([`PolicyTable`]) when the view, the policy or its
    /// answers change, and the table kept otherwise.
    ///
    /// A frame [`GpuCrowd::submit`] left in flight is finished first; its statistics are dropped
    /// (call [`GpuCrowd::finish`] before to have them), and an error it shows is this call's.
    ///
    /// Errors: a `dt` outside `[0, crowd_sim::MAX_DT]` or a camera the CPU crowd refuses
    /// ([`GpuError::Crowd`]); a policy giving a detail the model does not have
    /// ([`GpuError::Policy`]) or changing detail more often than tabulated
    /// ([`GpuError::Config`]); joint positions that came out NaN or infinite
    /// ([`GpuError::NonFinite`]: a model whose values overflow single precision, which the CPU
    /// runtime refuses with `lod_policy::KernelError::Overflow`); the device's
    /// ([`GpuError::Runtime`]), also for walkers still behind after more rounds than 1 ms clips
    /// could need (a fault).
    pub fn step<P: LevelPolicy + ?Sized>(
        &mut self,
        policy: &P,
        camera: &Camera,
        dt: f32,
    ) -> Result<GpuFrameStats, GpuError> {
        // A frame `submit` left in flight ends first (its statistics are not returned).
        self.finish()?;
        let started = Instant::now();
        let encoded = self.encode_frame(policy, camera, dt)?;
        let submitted = Instant::now();
        let counters = self.run_frame(encoded)?;
        let mut stats = self.frame_stats(&counters, submitted.elapsed(), self.frame)?;
        stats.wall = started.elapsed();
        Ok(stats)
    }

    /// Advances the crowd as [`GpuCrowd::step`] does but does not wait for the frame: it is
    /// submitted to the crowd's queue and left in flight, and the statistics of the frame
    /// submitted before it are returned (`None` at the first call, or after [`GpuCrowd::finish`]
    /// or `step`). An engine calls it, then records the passes that draw the crowd from
    /// [`GpuCrowd::draw_pages`] on the same queue (they run after the frame), and prepares its
    /// next frame on the host while the GPU computes this one; a call waits only for the frame
    /// before, so at most one frame is in flight. The walkers walk exactly as under `step` (the
    /// same passes in the same order; tested bit for bit).
    ///
    /// A frame whose `dt` is long enough to be split into rounds (see `step`) needs the counters
    /// between its rounds: it waits for the frame in flight, runs as `step` does, and its
    /// statistics come with the next call. The shortest clip that decides it is known up to the
    /// frame before the one in flight.
    ///
    /// The returned frame's [`GpuFrameStats::wall`] is the host time of the call that submitted
    /// it (recording and submitting), and [`GpuFrameStats::gpu`] the time from its submission to
    /// its completion as this call saw it (at most that; the host's own work between the calls
    /// included).
    ///
    /// Errors: those of `step`. A frame refused before it is submitted (a bad `dt`, camera or
    /// policy) is the error of this call, the frame in flight left as it was; so is any error of
    /// a split frame, whose statistics the frame before's then wait for the next call. An error
    /// the GPU's counters show (`GpuError::NonFinite`) is that of the call that returns the
    /// frame's statistics, the next frame being already submitted.
    pub fn submit<P: LevelPolicy + ?Sized>(
        &mut self,
        policy: &P,
        camera: &Camera,
        dt: f32,
    ) -> Result<Option<GpuFrameStats>, GpuError> {
        if dt.is_finite() && dt >= SPLIT_MARGIN * self.min_dur {
            let before = self.finish()?;
            match self.step(policy, camera, dt) {
                Ok(stats) => {
                    self.pending = Some(Pending::Done(Ok(stats)));
                    return Ok(before);
                }
                Err(e) => {
                    // The frame before comes with the next call.
                    self.pending = before.map(|s| Pending::Done(Ok(s)));
                    return Err(e);
                }
            }
        }
        let started = Instant::now();
        let Encoded { mut encoder, .. } = self.encode_frame(policy, camera, dt)?;
        let buffer = (self.frame % 2) as usize;
        self.copy_counters(&mut encoder, buffer);
        let submission = self.queue.submit([encoder.finish()]);
        let submitted = Instant::now();
        let signal = self.mapped[buffer].clone();
        self.staging[buffer]
            .slice(..)
            .map_async(wgpu::MapMode::Read, move |r| {
                if let Ok(mut slot) = signal.lock() {
                    *slot = Some(r);
                }
            });
        let before = self.pending.replace(Pending::InFlight {
            buffer,
            submission,
            submitted,
            wall: started.elapsed(),
            frame: self.frame,
        });
        self.resolve(before)
    }

    /// Waits for the frame [`GpuCrowd::submit`] left in flight and returns its statistics (`None`
    /// when there is none). Call it before reading results that must include that frame's
    /// counters on the host; [`GpuCrowd::step`] and [`GpuCrowd::read_walkers`] need no call
    /// (the device runs the queue in order).
    ///
    /// Errors: the frame's, as `step` reports them.
    pub fn finish(&mut self) -> Result<Option<GpuFrameStats>, GpuError> {
        let pending = self.pending.take();
        self.resolve(pending)
    }

    /// The statistics of `pending`, waiting for it when in flight.
    fn resolve(&mut self, pending: Option<Pending>) -> Result<Option<GpuFrameStats>, GpuError> {
        let (buffer, submission, submitted, wall, frame) = match pending {
            None => return Ok(None),
            Some(Pending::Done(stats)) => return stats.map(Some),
            Some(Pending::InFlight {
                buffer,
                submission,
                submitted,
                wall,
                frame,
            }) => (buffer, submission, submitted, wall, frame),
        };
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(submission),
                timeout: None,
            })
            .map_err(|e| GpuError::Runtime(e.to_string()))?;
        let gpu = submitted.elapsed();
        let state = self.mapped[buffer]
            .lock()
            .map_err(|_| GpuError::Runtime("reading back the counters: a poisoned lock".into()))?
            .take();
        match state {
            Some(Ok(())) => {}
            Some(Err(e)) => return Err(GpuError::Runtime(format!("reading back: {e}"))),
            None => {
                return Err(GpuError::Runtime(
                    "reading back the counters: not mapped after the frame finished".into(),
                ));
            }
        }
        let staging = &self.staging[buffer];
        let counters: Vec<u32> =
            bytemuck::cast_slice(&staging.slice(..).get_mapped_range()).to_vec();
        staging.unmap();
        let mut stats = self.frame_stats(&counters, gpu, frame)?;
        stats.wall = wall;
        Ok(Some(stats))
    }

    /// Checks `dt` and `camera`, tabulates `policy` when needed (the table kept while the view,
    /// the policy and its answers stay the same) and returns the frame's uniform (its `n` and
    /// `n_slots` left for each page).
    pub(crate) fn frame_uniform<P: LevelPolicy + ?Sized>(
        &mut self,
        policy: &P,
        camera: &Camera,
        dt: f32,
    ) -> Result<FrameUniform, GpuError> {
        if !(dt.is_finite() && (0.0..=MAX_DT).contains(&dt)) {
            return Err(crowd_sim::CrowdError::BadTimeStep { dt }.into());
        }
        let frustum = Frustum::from_camera(camera)?;
        let view = camera.view();
        // The table is kept while the view, the policy and its answers stay the same: another
        // policy, or the same one changed (other thresholds, at the same address), is tabulated
        // anew (`PolicyTable::matches` asks it at the table's boundaries and along the sweep).
        let id = (
            policy as *const P as *const () as usize,
            std::any::type_name::<P>(),
        );
        let stale = self
            .policy_cache
            .as_ref()
            .is_none_or(|c| c.view != view || c.policy != id || !c.table.matches(policy, &view));
        if stale {
            self.policy_cache = None;
            let table = PolicyTable::new(policy, &view, self.levels, self.joints)?;
            self.policy_cache = Some(PolicyCache {
                view,
                policy: id,
                entries: table.entries(),
                table,
            });
        }
        let cache = self.policy_cache.as_ref().expect("tabulated");
        let (entries, vis, hid) = (
            &cache.entries,
            cache.table.visible().len() as u32,
            cache.table.hidden().len() as u32,
        );
        let mut uniform = FrameUniform::zeroed();
        for (dst, src) in uniform.planes.iter_mut().zip(frustum.planes()) {
            *dst = src.to_array();
        }
        uniform.eye = camera.position.extend(0.0).to_array();
        uniform.dt = dt;
        uniform.margin = self.config.cull_margin_m;
        uniform.vis_entries = vis;
        uniform.hid_entries = hid;
        uniform.policy[..entries.len()].copy_from_slice(entries);
        Ok(uniform)
    }

    /// Checks `dt` and `camera`, tabulates `policy` when needed, writes every page's frame
    /// uniform and counter resets, and records the frame's first round (a split frame: as many
    /// rounds as expected in one submission) and, when not split, the pose pass. Counts the
    /// frame.
    fn encode_frame<P: LevelPolicy + ?Sized>(
        &mut self,
        policy: &P,
        camera: &Camera,
        dt: f32,
    ) -> Result<Encoded, GpuError> {
        let mut uniform = self.frame_uniform(policy, camera, dt)?;
        // A frame whose `dt` may hold more than one cycle end of a walker is split (see
        // `SPLIT_MARGIN`): its rounds first, as many as expected in one submission, then, once
        // every walker is caught up, the pose pass. Any other frame is one submission, as always.
        let split = dt >= SPLIT_MARGIN * self.min_dur;
        let per_submit = if split {
            let expected = (dt / self.min_dur.max(1e-3)).ceil() as u32;
            expected.saturating_add(1).min(MAX_ROUNDS_PER_SUBMIT)
        } else {
            1
        };
        let catch_up = if split {
            Some(self.catch_up_pipeline()?)
        } else {
            None
        };
        let mut encoder = self.device.create_command_encoder(&Default::default());
        for page in &self.pages {
            uniform.n = page.n as u32;
            uniform.n_slots = page.slots as u32;
            self.queue
                .write_buffer(&page.frame, 0, bytemuck::bytes_of(&uniform));
            // Reset the frame's counters (builds, visible, slot faults; then those from the walkers
            // not finite to the histogram's end, the round counter among them); the free-slot
            // stack's top and the shortest clip between them stay.
            self.queue.write_buffer(
                &page.counters,
                4 * C_BUILDS as u64,
                bytemuck::cast_slice(&[0u32; 3]),
            );
            self.queue.write_buffer(
                &page.counters,
                4 * C_NONFINITE as u64,
                bytemuck::cast_slice(&self.counters_reset),
            );
            let mut pass = encoder.begin_compute_pass(&Default::default());
            self.record_round(&mut pass, page, &self.pipelines.advance);
            match &catch_up {
                Some(advance) => {
                    for _ in 1..per_submit {
                        self.record_round(&mut pass, page, advance);
                    }
                }
                None => self.record_pose(&mut pass, page),
            }
        }
        self.frame += 1;
        Ok(Encoded {
            encoder,
            split: catch_up.map(|advance| (advance, per_submit)),
            dt,
        })
    }

    /// Submits a frame `encode_frame` recorded and waits for it; a split frame's catch-up rounds
    /// and pose pass follow until no walker is behind. Returns the counters after the frame.
    fn run_frame(&self, encoded: Encoded) -> Result<Vec<u32>, GpuError> {
        let Encoded { encoder, split, dt } = encoded;
        let mut counters = self.submit_and_read(encoder)?;
        if let Some((advance, per_submit)) = &split {
            let (advance, per_submit) = (advance, *per_submit);
            let mut rounds = per_submit;
            loop {
                let behind: Vec<&Page> = counters
                    .chunks_exact(self.counters_len)
                    .zip(&self.pages)
                    .filter(|(c, _)| c[C_BEHIND] > 0)
                    .map(|(_, page)| page)
                    .collect();
                if behind.is_empty() {
                    break;
                }
                if rounds >= MAX_ROUNDS {
                    return Err(GpuError::Runtime(format!(
                        "frame {}: walkers still behind their clips after {rounds} rounds of \
                         cycle ends (dt = {dt} s)",
                        self.frame
                    )));
                }
                let mut encoder = self.device.create_command_encoder(&Default::default());
                for page in behind {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    for _ in 0..per_submit {
                        self.record_round(&mut pass, page, advance);
                    }
                }
                rounds += per_submit;
                counters = self.submit_and_read(encoder)?;
            }
            let mut encoder = self.device.create_command_encoder(&Default::default());
            for page in &self.pages {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                self.record_pose(&mut pass, page);
            }
            counters = self.submit_and_read(encoder)?;
        }
        Ok(counters)
    }

    /// The statistics of frame number `frame` from its counters (`gpu` its device time; `wall`
    /// left for the caller), the shortest clip updated; `GpuError::NonFinite` when a walker's
    /// positions came out NaN or infinite.
    fn frame_stats(
        &mut self,
        counters: &[u32],
        gpu: Duration,
        frame: u64,
    ) -> Result<GpuFrameStats, GpuError> {
        let mut stats = GpuFrameStats {
            level_histogram: vec![0; self.levels + 1],
            gpu,
            ..GpuFrameStats::default()
        };
        let (mut nonfinite, mut first, mut start) = (0u64, None, 0usize);
        for (c, page) in counters.chunks_exact(self.counters_len).zip(&self.pages) {
            if c[C_NONFINITE] > 0 {
                nonfinite += u64::from(c[C_NONFINITE]);
                first.get_or_insert(start + c[C_NONFINITE_FIRST] as usize);
            }
            start += page.n;
            stats.kernels_built += u64::from(c[C_BUILT]);
            stats.visible += u64::from(c[C_VISIBLE]);
            stats.slot_faults += u64::from(c[C_SLOT_FAULTS]);
            stats.in_transition += u64::from(c[C_SEAMS]);
            stats.feet_locked += u64::from(c[C_LOCKS]);
            stats.rounds = stats.rounds.max(c[C_ROUND]);
            stats.behind += u64::from(c[C_BEHIND]);
            for (h, v) in stats.level_histogram.iter_mut().zip(&c[C_HIST..]) {
                *h += v;
            }
        }
        self.min_dur = self.min_dur.min(self.shortest_clip(counters));
        if let Some(first) = first {
            return Err(GpuError::NonFinite {
                frame,
                walkers: nonfinite,
                first,
            });
        }
        Ok(stats)
    }

    /// Maps `buffer` (MAP_READ), copies it out as `T`s and unmaps it.
    fn read_mapped<T: Pod>(&self, buffer: &wgpu::Buffer) -> Result<Vec<T>, GpuError> {
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GpuError::Runtime(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::Runtime(e.to_string()))?
            .map_err(|e| GpuError::Runtime(format!("reading back: {e}")))?;
        let out = bytemuck::cast_slice(&slice.get_mapped_range()).to_vec();
        buffer.unmap();
        Ok(out)
    }

    /// Copies `buffer` into a new read-back buffer and returns its contents.
    pub(crate) fn read_buffer<T: Pod>(&self, buffer: &wgpu::Buffer) -> Result<Vec<T>, GpuError> {
        let staging = scoped_raw(&self.device, || {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("read-back"),
                size: buffer.size(),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        })
        .map_err(|e| GpuError::Memory {
            what: "a read-back buffer",
            bytes: buffer.size(),
            walkers: self.walkers,
            adapter: self.gpu_name.clone(),
            reason: e.to_string(),
        })?;
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, buffer.size());
        self.submit_and_wait(encoder)?;
        self.read_mapped(&staging)
    }

    /// Every walker's detail and world joint positions after the last step, read back from the
    /// GPU (slow: for tests, exports and inspection, not per frame).
    ///
    /// Errors: [`GpuError::NonFinite`] when a position is NaN or infinite (a model whose values
    /// overflow, as [`GpuCrowd::step`] says); [`GpuError::Memory`] and [`GpuError::Runtime`]
    /// from the device.
    pub fn read_walkers(&self) -> Result<Vec<WalkerJoints>, GpuError> {
        let mut out = Vec::with_capacity(self.walkers);
        for page in &self.pages {
            let walkers: Vec<GpuWalker> = self.read_buffer(&page.walkers)?;
            let joints: Vec<f32> = self.read_buffer(&page.joints)?;
            let ns = page.slots;
            for w in &walkers[..page.n] {
                let mut positions = vec![Vec3::from_array(w.root)];
                if w.cur_joints > 0 && w.slot != NONE {
                    let s = w.slot as usize;
                    if s >= ns || w.shown as usize > self.joints {
                        return Err(GpuError::Runtime(format!(
                            "walker {}: joint slot {s} of {ns} with {} joints of {}: the \
                             walkers read back are corrupt",
                            out.len(),
                            w.shown,
                            self.joints
                        )));
                    }
                    for k in 0..w.shown as usize {
                        let at = |c: usize| joints[(3 * k + c) * ns + s];
                        positions.push(Vec3::new(at(0), at(1), at(2)));
                    }
                }
                out.push(WalkerJoints {
                    detail: Detail::new(w.cur_acc as usize, w.cur_joints as usize),
                    positions,
                });
            }
        }
        let bad = |w: &WalkerJoints| !w.positions.iter().all(|p| p.is_finite());
        if let Some(first) = out.iter().position(bad) {
            return Err(GpuError::NonFinite {
                frame: self.frame,
                walkers: out.iter().filter(|w| bad(w)).count() as u64,
                first,
            });
        }
        Ok(out)
    }

    /// Number of walkers.
    pub fn len(&self) -> usize {
        self.walkers
    }

    /// Always false: a crowd has at least one walker.
    pub fn is_empty(&self) -> bool {
        self.walkers == 0
    }

    /// The configuration in use (the field enlarged when the model's turn range needed it).
    pub fn config(&self) -> &CrowdConfig {
        &self.config
    }

    /// The field size asked for, when the crowd enlarged it (as `crowd_sim::Crowd`).
    pub fn field_enlarged_from(&self) -> Option<f32> {
        self.field_enlarged_from
    }

    /// The adapter the crowd runs on.
    pub fn adapter_name(&self) -> &str {
        &self.gpu_name
    }

    /// Bytes of GPU memory the crowd's buffers take (the model's own buffers excluded).
    pub fn gpu_bytes(&self) -> u64 {
        self.pages.iter().map(|p| p.bytes).sum()
    }

    /// Bytes of one joint slot: a clip with joints (`4 (P max r_T + 2 T)`), its joint positions
    /// (`12 J`), with seams on (`seam_levels > 0`) its seam transition (`4 (3 P + 3)`) and with
    /// the foot lock on (`foot_lock_levels > 0` and a model with feet) its lock state (216).
    pub fn bytes_per_joint_slot(&self) -> u64 {
        self.bytes_per_slot
    }

    /// Pages the walkers are split into (see [`GpuOptions::page_walkers`]).
    pub fn pages(&self) -> usize {
        self.pages.len()
    }

    /// Frames stepped so far.
    pub fn frame(&self) -> u64 {
        self.frame
    }
}

/// The field enlarged for the paths as `crowd_sim::Crowd::new` enlarges it (returns the size asked
/// for when it was), and refused likewise beyond `crowd_sim::MAX_FIELD_M`.
fn fit_field(plan: &PathPlan, config: &mut CrowdConfig) -> Result<Option<f32>, GpuError> {
    let enlarged_from = plan.fit_field(&mut config.field_size_m);
    if config.field_size_m > crowd_sim::MAX_FIELD_M {
        return Err(crowd_sim::CrowdError::FieldTooLarge {
            needed_m: config.field_size_m,
        }
        .into());
    }
    Ok(enlarged_from)
}

/// The CPU crowd's checks of the settings the GPU crowd uses, and the settings it does not
/// implement.
fn check_config(c: &CrowdConfig) -> Result<(), GpuError> {
    // Also the walker cap, `crowd_sim::MAX_WALKERS` (2^31 - 1: walker indices and counts in 32
    // bits, as the shaders keep them).
    c.validate()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crowd_sim::ClipSource;
    use crowd_sim::testing::ProceduralSource;

    fn config(walkers: usize, field_size_m: f32, border_m: f32) -> CrowdConfig {
        CrowdConfig {
            walkers,
            field_size_m,
            border_m,
            seam_levels: 0,
            foot_lock_levels: 0,
            ..CrowdConfig::default()
        }
    }

    /// The walker and field caps of the CPU crowd, before anything reaches the GPU.
    #[test]
    fn walker_and_field_caps_are_the_cpu_crowds() {
        assert!(check_config(&config(crowd_sim::MAX_WALKERS, 100.0, 2.0)).is_ok());
        for walkers in [crowd_sim::MAX_WALKERS + 1, usize::MAX] {
            assert!(matches!(
                check_config(&config(walkers, 100.0, 2.0)),
                Err(GpuError::Crowd(
                    crowd_sim::CrowdError::TooManyWalkers { .. }
                ))
            ));
        }
        assert!(matches!(
            check_config(&config(10, 1e20, 2.0)),
            Err(GpuError::Crowd(crowd_sim::CrowdError::AboveLimit { .. }))
        ));
        let range = ProceduralSource::new().control_range();
        let mut small = config(10, 4.0, 2.0);
        let plan = PathPlan::new(&range, small.border_m);
        assert_eq!(fit_field(&plan, &mut small).unwrap(), Some(4.0));
        let mut huge_border = config(10, 100.0, 1e30);
        let plan = PathPlan::new(&range, huge_border.border_m);
        assert!(matches!(
            fit_field(&plan, &mut huge_border),
            Err(GpuError::Crowd(crowd_sim::CrowdError::FieldTooLarge { .. }))
        ));
    }
}
