//! What the offline crates share with the runtime so that their results are the runtime's to the
//! bit: the exponential map and frame split of the pose vectors (`motion-io`, `timewarp`'s tests),
//! the foot lock's leg solver and constants (the offline foot lock of `motion-lod`'s `synth`, and
//! `gpu-crowd`'s shaders), and
//! the crowd's cache hints (`crowd-sim`). An engine needs none of it: its jobs are the crate
//! root's re-exports.

pub use crate::footlock::{
    GROUND_MARGIN_M, LOCK_HEIGHT_M, LOCK_SPEED_M_S, MAX_REACH, ONSET_S, POLE_WEIGHT, RELEASE_S,
    SOFT_REACH, TELEPORT_SPEED_M_S, soft_reach, two_bone,
};
pub use crate::math::{clear_avx_upper_state, prefetch, prefetch_bytes};
pub use crate::rig::exp_to_quat;
pub use crate::time_table::split_phase;
