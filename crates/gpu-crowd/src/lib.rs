//! The motion-lod crowd on the GPU: the runtime's clip build, poses and forward kinematics as
//! wgpu compute shaders (WGSL), for crowds of hundreds of thousands to millions of walkers.
//!
//! This crate is for: running `crowd-sim`'s crowd (the same walkers, paths, frustum culling and
//! level-of-detail policy) with every per-walker job on the GPU: per clip the kriging weights, the
//! blended core, `G(c)`, the time table and the root motion (`lod-policy`'s
//! `LodModel::build_kernel`), per frame the pose at the clip's phase (`LodModel::pose_rows`), the
//! seam inertialization between clips (`SeamTransition`, with `seam_levels > 0`), the foot lock of
//! near walkers (`FootLock` on the model's `FootRig`, with `foot_lock_levels > 0`) and the forward
//! kinematics of the active joints (`Rig::joint_positions_scaled`), from the same model file.
//! Walker state lives on the GPU; per frame the host uploads the camera, the time step and
//! the policy (tabulated over distance, [`PolicyTable`]) and reads back a few counters. What the
//! CPU runtime computes in f64 (the kriging weights, the time table, the walkers' cycle frames and
//! their steering along their paths) the shaders compute in double-float arithmetic (two f32 a
//! value, `shaders/df.wgsl`), so that both crowds walk the same walks. It runs on
//! Vulkan (default feature `vulkan`), Metal (`metal`) and DirectX 12 (`dx12`) through wgpu, and on
//! Mesa's software Vulkan (lavapipe) where there is no GPU, which is how CI checks it against the
//! CPU crowd. An engine draws the crowd where it lives: [`GpuCrowd::draw_pages`] gives the buffers
//! its shaders read the walkers' roots and joints from after each step, [`DRAW_WGSL`] the
//! declarations they include, [`Gpu::from_wgpu`] runs the crowd on the engine's own device, and
//! [`Preview`] is such a reader: a render pass that draws the stick figures from the buffers into
//! an image (`motion-lod crowd --gpu --render`). [`GpuCrowd::submit`] leaves a frame in flight
//! (its statistics come with the next call), so that the engine's draw follows it on the queue
//! and the host prepares the next frame meanwhile; [`GpuCrowd::step`] waits for it.
//! [`crowd_wgsl`] and [`Preview::wgsl`] give the shaders' source without a device (CI compiles
//! them with Chromium's WebGPU too). It is not for: an engine's rendering (meshes,
//! skinning, materials are the engine's; `Preview` draws lines for checks and previews), or
//! building models (see `motion-lod`). Seam state costs each joint slot `4 (3 P + 3)` bytes,
//! and nothing with `seam_levels = 0`; foot lock state 216 bytes, and nothing with
//! `foot_lock_levels = 0` or a model without feet ([`GpuCrowd::bytes_per_joint_slot`]).
//!
//! ```no_run
//! use crowd_sim::{Camera, CrowdConfig};
//! use gpu_crowd::{Gpu, GpuCrowd, GpuOptions};
//! use lod_policy::{DistancePolicy, RuntimeModel};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let model = RuntimeModel::load(std::path::Path::new("walk.mlod"))?;
//! let gpu = Gpu::new()?; // GpuError::NoAdapter names what is missing
//! // The CPU crowd's defaults: seams and the foot lock at every level.
//! let config = CrowdConfig::with_density(100_000, 0.01);
//! let mut crowd = GpuCrowd::new(&gpu, &model, config, GpuOptions::default())?;
//! let policy = DistancePolicy::for_model(model.lod());
//! let stats = crowd.step(&policy, &Camera::default(), 1.0 / 30.0)?;
//! println!("{} visible, {} clips built, {:?}", stats.visible, stats.kernels_built, stats.gpu);
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

mod crowd;
mod device;
mod df;
mod draw;
mod error;
mod host;
mod policy;
mod preview;
mod tables;

pub use crowd::{GpuCrowd, GpuFrameStats, GpuOptions, WalkerJoints, crowd_wgsl};
pub use device::{Gpu, ICD_ENV};
pub use draw::{DRAW_WGSL, DrawPage};
pub use error::GpuError;
pub use host::{HostBinding, HostBuffer, HostDispatch, HostPage, HostState};
pub use policy::PolicyTable;
pub use preview::Preview;

/// The environment variable that makes a missing GPU adapter an error in the tests (CI sets it:
/// lavapipe is installed there) instead of a skip.
pub const REQUIRE_GPU_ENV: &str = "MOTION_LOD_REQUIRE_GPU";
