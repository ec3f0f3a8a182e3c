//! Choosing a detail per walker per frame.

use crate::camera::Camera;
use crate::controls::Detail;

/// Maps a walker's distance to the camera and visibility to a [`Detail`].
///
/// The facade plugs in lod-policy's distance policy (paper section 5.1: full accuracy below
/// 30 m, one key level more every 50 m, three joint DOF fewer every 10 m, root only when culled)
/// and its screen-space policy. Any `Fn(f32, bool, &Camera) -> Detail + Sync` closure is a policy.
pub trait DetailPolicy: Sync {
    /// Detail for a walker at `distance_m` from the camera, `visible` when its bounds intersect the
    /// view frustum.
    fn detail(&self, distance_m: f32, visible: bool, camera: &Camera) -> Detail;
}

impl<F> DetailPolicy for F
where
    F: Fn(f32, bool, &Camera) -> Detail + Sync,
{
    fn detail(&self, distance_m: f32, visible: bool, camera: &Camera) -> Detail {
        self(distance_m, visible, camera)
    }
}
