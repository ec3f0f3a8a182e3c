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
}
