//! The joint-DOF order by visual importance, measured from the data (paper section 4.3).
//!
//! The paper sorts the rows of `U_P` by hand so that the joint-DOF reduction drops wrists and ankles
//! first. Here the order is measured: the importance of a rotating joint is the mean joint position error
//! (see [`crate::metrics`]) that replacing its rotation by its rest (mean) rotation causes over the data
//! set, which is exactly what a character shows when the runtime drops that joint. Joints are sorted by
//! decreasing importance; the root rows always come first.

use motion_io::PoseLayout;

use crate::metrics::ErrorMeter;

/// The importance of one rotating joint.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct JointImportance {
    /// Skeleton joint index.
    pub joint: usize,
    /// Joint name.
    pub name: String,
    /// Mean joint position error (cm) over the measured poses when this joint holds its rest rotation.
    pub error_cm: f64,
}

/// Measures every rotating joint of `layout` over `poses` (`n x dof`, row-major) and returns them sorted by
/// decreasing importance (ties keep the layout's order, so the result is deterministic).
///
/// At most `max_poses` poses are used, taken at an even stride.
pub fn joint_importance(
    layout: &PoseLayout,
    poses: &[f64],
    max_poses: usize,
) -> Vec<JointImportance> {
    let p = layout.dof();
    let n = poses.len() / p;
    let stride = n.div_ceil(max_poses.max(1)).max(1);
    let rest = layout.rest_pose();
    let mut edited = vec![0.0; p];
    let mut out: Vec<JointImportance> = layout
        .joint_order()
        .iter()
        .map(|&j| {
            let rows = layout.joint_rows(j).expect("rotating joint has rows");
            let mut meter = ErrorMeter::new(layout);
            for pose in poses.chunks_exact(p).step_by(stride) {
                edited.copy_from_slice(pose);
                edited[rows.clone()].copy_from_slice(&rest[rows.clone()]);
                meter.compare(pose, &edited);
            }
            JointImportance {
                joint: j,
                name: layout.skeleton().joints[j].name.clone(),
                error_cm: meter.total().mean_joint_cm,
            }
        })
        .collect();
    out.sort_by(|a, b| b.error_cm.total_cmp(&a.error_cm));
    out
}
