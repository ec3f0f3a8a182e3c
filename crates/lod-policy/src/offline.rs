//! What the offline crates share with the runtime so that their results are the runtime's to the
//! bit: the exponential map and frame split of the pose vectors (`motion-io`, `timewarp`'s tests),
//! the foot lock's leg solver and constants (the offline foot lock of `motion-lod`'s `synth`), and
//! the crowd's cache hints (`crowd-sim`). An engine needs none of it: its jobs are the crate
//! root's re-exports.

pub use crate::chain::{exp_map_to_quat, nearest_branch, quat_to_exp_map};
pub use crate::footlock::{
    GROUND_MARGIN_M, LOCK_HEIGHT_M, LOCK_SPEED_M_S, MAX_REACH, ONSET_S, POLE_WEIGHT, RELEASE_S,
    SOFT_REACH, TELEPORT_SPEED_M_S, soft_reach, two_bone,
};
pub use crate::kernel::{PREFETCH_G_BYTES, yaw_of_exp_map};
pub use crate::math::{clear_avx_upper_state, prefetch, prefetch_bytes, prefetch_slice};
pub use crate::rig::{STACK_JOINTS, exp_to_quat};
pub use crate::time_table::split_phase;
