//! [`GpuError`]: why the GPU crowd could not start or step.

/// Why the GPU crowd could not start or step.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// No GPU adapter was found for the enabled backends (`what` names the backends tried and
    /// how to provide one).
    #[error("no GPU adapter: {what}")]
    NoAdapter {
        /// What was tried and what is missing.
        what: String,
    },
    /// The adapter refused to create a device with the limits the crowd needs.
    #[error("the GPU adapter {adapter} refused a device: {reason}")]
    Device {
        /// The adapter's name and backend.
        adapter: String,
        /// The driver's reason.
        reason: String,
    },
    /// The crowd needs more of a resource than the adapter offers.
    #[error("the crowd needs {what} = {needed}, the adapter {adapter} offers {limit}")]
    Limit {
        /// The resource (a buffer's size, workgroup memory).
        what: &'static str,
        /// How much the crowd needs.
        needed: u64,
        /// How much the adapter offers.
        limit: u64,
        /// The adapter's name.
        adapter: String,
    },
    /// The model cannot run on the GPU crowd (e.g. a skeleton with more joints than it supports).
    #[error("the model does not fit the GPU crowd: {0}")]
    Model(String),
    /// A setting of the crowd that the GPU crowd does not implement, or an invalid one.
    #[error("GPU crowd setting: {0}")]
    Config(String),
    /// The CPU crowd's own checks refused the configuration or the camera.
    #[error(transparent)]
    Crowd(#[from] crowd_sim::CrowdError),
    /// The level-of-detail policy gave a detail the model does not have.
    #[error(
        "the level-of-detail policy gave accuracy level {accuracy} with {joints} joints at {distance_m} m; the model has {levels} levels and {max_joints} joints"
    )]
    Policy {
        /// The accuracy level given.
        accuracy: usize,
        /// The joints given.
        joints: usize,
        /// The distance asked.
        distance_m: f32,
        /// The model's levels.
        levels: usize,
        /// The model's joints.
        max_joints: usize,
    },
    /// The device failed while running or reading back a frame (lost device, mapping error,
    /// shader validation).
    #[error("GPU device error: {0}")]
    Runtime(String),
    /// The device could not allocate buffers the crowd needs (out of memory, or a size it
    /// refuses): `what` says which, `bytes` how much.
    #[error(
        "allocating {what} ({bytes} bytes of GPU memory, {walkers} walkers) failed on {adapter}: \
         {reason}; use fewer walkers, or fewer joint slots (GpuOptions::joint_slots)"
    )]
    Memory {
        /// What was being allocated (the crowd's buffers, the model's, a read-back buffer).
        what: &'static str,
        /// The bytes asked for.
        bytes: u64,
        /// The crowd's walkers.
        walkers: usize,
        /// The adapter's name.
        adapter: String,
        /// The device's error.
        reason: String,
    },
    /// Joint positions came out of a frame NaN or infinite: the model's values overflow single
    /// precision for these walkers (as the CPU runtime's `lod_policy::KernelError::Overflow`,
    /// which refuses to build such a clip). The walkers keep their state, so later frames give
    /// this error too.
    #[error(
        "after frame {frame}, {walkers} walker(s) have joint positions that are NaN or infinite \
         (the first: walker {first}); the model's values overflow single precision"
    )]
    NonFinite {
        /// Frames stepped, this one included.
        frame: u64,
        /// Walkers with a root or a joint position that is not finite.
        walkers: u64,
        /// The first such walker (index in the crowd).
        first: usize,
    },
}
