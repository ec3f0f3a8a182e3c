//! The joint-DOF order by visual importance, measured from the data (paper section 4.3).
//!
//! The paper sorts the rows of `U_P` by hand so that the joint-DOF reduction drops wrists and ankles
//! first. Here the order is measured: the importance of a rotating joint is the mean joint position error
//! (see [`crate::metrics`]) that replacing its rotation by its rest (mean) rotation causes over the data
//! set, which is exactly what a character shows when the runtime drops that joint. Joints are sorted by
//! decreasing importance; the root rows always come first.

use motion_io::PoseLayout;

use crate::metrics::{ErrorMeter, SHELL_RADIUS_M, measured_joints};

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

/// Weights of the DOF rows that make the tensor's squared (Frobenius) error approximate the squared
/// joint position error (metres) of [`crate::metrics`], to first order.
///
/// For every row `d` other than the time increment, `w_d^2` is the mean over the measured poses of
/// `(1/J) sum_j |x_j(pose + eps e_d) - x_j(pose)|^2 / eps^2`: the squared displacement of the `J` measured
/// joints per unit change of that row (1 for the root position rows, the squared lever arm of the
/// descendants for a rotation). The time row (in units of the mean increment) gets `v dt_mean`, the distance
/// the root travels in one mean increment: a timing error of one increment shows as that displacement
/// (the smallest other weight when that is zero). A rotation row also counts the joint's own shell
/// vertices ([`SHELL_RADIUS_M`] away), so no row weighs nothing.
///
/// At most `max_poses` poses are used, taken at an even stride.
pub fn dof_weights(
    layout: &PoseLayout,
    poses: &[f64],
    time_row: usize,
    time_weight: f64,
    max_poses: usize,
) -> Vec<f64> {
    let p = layout.dof();
    let n = poses.len() / p;
    let stride = n.div_ceil(max_poses.max(1)).max(1);
    let measured = measured_joints(layout);
    let nj = layout.skeleton().joints.len();
    let mut base = vec![glam::DVec3::ZERO; nj];
    let mut moved = vec![glam::DVec3::ZERO; nj];
    let mut edited = vec![0.0; p];
    let mut sums = vec![0.0; p];
    let mut count = 0usize;
    const EPS: f64 = 1e-4;
    for pose in poses.chunks_exact(p).step_by(stride) {
        layout.joint_positions_f64(pose, &mut base);
        for d in 0..p {
            if d == time_row {
                continue;
            }
            edited.copy_from_slice(pose);
            edited[d] += EPS;
            layout.joint_positions_f64(&edited, &mut moved);
            let sq: f64 = measured
                .iter()
                .map(|&j| (moved[j] - base[j]).length_squared())
                .sum();
            sums[d] += sq / (measured.len().max(1) as f64 * EPS * EPS);
            if d >= 3 {
                // A rotation also turns its own joint's shell vertices, 3 cm away (leaf joints move
                // nothing else).
                sums[d] += SHELL_RADIUS_M * SHELL_RADIUS_M / measured.len().max(1) as f64;
            }
        }
        count += 1;
    }
    let mut w: Vec<f64> = sums
        .iter()
        .map(|&s| (s / count.max(1) as f64).sqrt())
        .collect();
    // A character walking in place moves its root by nothing: the time row then weighs as the
    // least weighted other row.
    let floor = w
        .iter()
        .enumerate()
        .filter(|&(d, &v)| d != time_row && v > 0.0)
        .map(|(_, &v)| v)
        .fold(f64::INFINITY, f64::min);
    w[time_row] = if time_weight > 0.0 || !floor.is_finite() {
        time_weight
    } else {
        floor
    };
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use motion_io::bvh::parse_bvh;

    /// Hips (6 channels) -> Leg (0.5 m below) -> Foot (0.4 m below the leg), in metres.
    fn leg_layout() -> PoseLayout {
        let text = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 1 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n \
                    JOINT Leg\n {\n  OFFSET 0 -0.5 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  \
                    JOINT Foot\n  {\n   OFFSET 0 -0.4 0\n   CHANNELS 3 Zrotation Xrotation Yrotation\n   \
                    End Site\n   {\n    OFFSET 0 0 0.1\n   }\n  }\n }\n}\n\
                    MOTION\nFrames: 1\nFrame Time: 0.0333333\n0 1 0 0 0 0 0 0 0 0 0 0\n";
        let motion = parse_bvh(text).expect("test skeleton parses");
        PoseLayout::new(&motion.skeleton, 1.0).expect("layout")
    }

    #[test]
    fn weights_are_joint_displacements_per_unit_of_each_row() {
        let layout = leg_layout();
        assert_eq!(layout.dof(), 7 + 6);
        let pose = layout.rest_pose();
        let w = dof_weights(&layout, &pose, 6, 0.05, 10);
        let shell = SHELL_RADIUS_M * SHELL_RADIUS_M / 3.0;
        // Root translation moves the three joints by as much.
        for &v in &w[..3] {
            assert!((v - 1.0).abs() < 1e-9, "{w:?}");
        }
        assert_eq!(w[6], 0.05, "the time row takes the given weight");
        // Leg rows follow the layout's joint order; find which rows are the leg's and the foot's.
        let leg = layout.joint_rows(1).unwrap();
        let foot = layout.joint_rows(2).unwrap();
        // The foot is a leaf: only its own shell moves.
        for d in foot {
            assert!((w[d] * w[d] - shell).abs() < 1e-9, "row {d}: {w:?}");
        }
        // Turning the leg about x or z swings the foot 0.4 m away by 0.4 m per radian; about y (along
        // the bone) it moves nothing but the leg's shell.
        let mut leg_w: Vec<f64> = leg.map(|d| w[d] * w[d]).collect();
        leg_w.sort_by(f64::total_cmp);
        assert!((leg_w[0] - shell).abs() < 1e-6, "{leg_w:?}");
        for &v in &leg_w[1..] {
            assert!((v - (0.16 / 3.0 + shell)).abs() < 1e-6, "{leg_w:?}");
        }
        // Root rotation about x swings leg and foot (0.5 and 0.9 m below the hips).
        let root_x = w[3] * w[3];
        assert!(
            (root_x - ((0.25 + 0.81) / 3.0 + shell)).abs() < 1e-6,
            "{w:?}"
        );
    }

    #[test]
    fn a_still_root_gives_the_time_row_the_smallest_other_weight() {
        let layout = leg_layout();
        let pose = layout.rest_pose();
        let w = dof_weights(&layout, &pose, 6, 0.0, 10);
        let smallest = w
            .iter()
            .enumerate()
            .filter(|&(d, _)| d != 6)
            .map(|(_, &v)| v)
            .fold(f64::INFINITY, f64::min);
        assert!(smallest > 0.0);
        assert_eq!(w[6], smallest);
    }
}
