//! The joint-DOF order by visual importance, measured from the data (paper section 4.3), and which
//! joints are evaluated at all.
//!
//! The paper sorts the rows of `U_P` by hand so that the joint-DOF reduction drops wrists and ankles
//! first. Here the order is measured: the importance of a rotating joint is the mean joint position error
//! (see [`crate::metrics`]) that replacing its rotation by its rest (mean) rotation causes over the data
//! set, which is exactly what a character shows when the runtime drops that joint. Joints are sorted by
//! decreasing importance; the root rows always come first.
//!
//! Two rules come before the measured error:
//!
//! - **Static joints are not counted.** A rotating joint whose rotation stays within
//!   [`STATIC_RMS_DEG`] (RMS angle about its mean) over the training poses ([`static_joints`]), such as
//!   the fingers and eyes of the CMU skeleton, holds its mean rotation always: it has no rows in the
//!   tensor and is not one of the joints `--joints N`, `LodModel::joints()` and the policies count.
//! - **Legs before arms, limbs whole** ([`limb_order`]). The joints of both legs (every joint below
//!   each hip that [`motion_io::find_feet`] finds) come before any arm (a joint outside the legs with a
//!   left/right side in its name), and a joint and its left/right counterpart are adjacent, so that for
//!   every joint count, when an arm moves both legs move, and the legs are never frozen one knee but not
//!   the other. The reason is what each frozen joint does to the walk: a frozen leg skates (the planted
//!   foot is carried along with the body and slides over the floor, and the character limps), a frozen
//!   arm only swings less. The mean position error alone does not see this: on the CMU data a shoulder
//!   moves more joints (the hand and its fingers) than a knee, and it ranked both shoulders above both
//!   legs. Within these constraints the measured order is kept: leg units (a joint with its
//!   counterpart) by decreasing error, then arm units likewise, and the spine, neck and head (joints
//!   without a side) merged in by their own error. When the feet cannot be found, the measured order
//!   is kept and the build report says so.

use glam::{DQuat, DVec3};
use motion_io::expmap::exp_to_quat;
use motion_io::{FootNames, PoseLayout, find_feet, mirrored_names, side_of};
use rayon::prelude::*;

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
    // Each joint is measured on its own (in parallel, each with its own buffer and meter), so the
    // figures are the same on any pool.
    let mut out: Vec<JointImportance> = layout
        .joint_order()
        .par_iter()
        .map(|&j| {
            let rows = layout.joint_rows(j).expect("rotating joint has rows");
            let mut edited = vec![0.0; p];
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

/// A rotating joint whose rotation is constant over the data within [`STATIC_RMS_DEG`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StaticJoint {
    /// Skeleton joint index.
    pub joint: usize,
    /// Joint name.
    pub name: String,
    /// RMS angle (degrees) of its rotation about its mean rotation over the measured poses.
    pub rms_deg: f64,
}

/// The largest RMS angle (degrees) about its mean at which a joint counts as static: half a degree
/// moves a point 1 m away by less than 9 mm, below what a character shows, and far below every joint
/// that moves in a walk (the least moving ones in the shared data turn by 3.97 degrees RMS, Bandai's
/// `Spine`, and 4.27, CMU's `chest`; `tests/joints_and_controls.rs`).
pub const STATIC_RMS_DEG: f64 = 0.5;

/// The rotating joints of `layout` whose rotation stays within `tol_deg` (RMS angle about the mean
/// rotation, a sign-aligned quaternion average) over `poses` (`n x dof`, row-major), in the layout's
/// joint order. Every other rotating joint is listed nowhere. An empty `poses` gives no static joint.
pub fn static_joints(layout: &PoseLayout, poses: &[f64], tol_deg: f64) -> Vec<StaticJoint> {
    let p = layout.dof();
    let n = poses.len() / p;
    if n == 0 {
        return Vec::new();
    }
    let rotation = |pose: &[f64], k: usize| {
        let r = lod_policy::ALWAYS_ROWS + 3 * k;
        exp_to_quat(DVec3::from_slice(&pose[r..r + 3]))
    };
    layout
        .joint_order()
        .iter()
        .enumerate()
        .filter_map(|(k, &j)| {
            let first = rotation(&poses[..p], k);
            let mut sum = glam::DVec4::ZERO;
            for pose in poses.chunks_exact(p) {
                let q = rotation(pose, k);
                sum += glam::DVec4::from(if q.dot(first) < 0.0 { -q } else { q });
            }
            let mean = if sum.length() > 1e-12 {
                DQuat::from_vec4(sum).normalize()
            } else {
                first
            };
            let sq: f64 = poses
                .chunks_exact(p)
                .map(|pose| {
                    let c = rotation(pose, k).dot(mean).abs().min(1.0);
                    (2.0 * c.acos()).powi(2)
                })
                .sum();
            let rms_deg = (sq / n as f64).sqrt().to_degrees();
            (rms_deg < tol_deg).then(|| StaticJoint {
                joint: j,
                name: layout.skeleton().joints[j].name.clone(),
                rms_deg,
            })
        })
        .collect()
}

/// The body part of a joint in the reduction order (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum BodyPart {
    /// Below a hip: thigh, knee, ankle, toes.
    Leg,
    /// Outside the legs with a left/right side in its name: collar, shoulder, elbow, wrist, ...
    Arm,
    /// Neither: pelvis, spine, neck, head.
    Axial,
}

/// The reduction order of [`limb_order`]: joints with their part, and a note when the rule could not
/// be applied.
#[derive(Debug, Clone, PartialEq)]
pub struct LimbOrder {
    /// The joints in evaluation order (most important first).
    pub joints: Vec<JointImportance>,
    /// The body part of each entry of `joints` (all [`BodyPart::Axial`] when the feet were not found).
    pub parts: Vec<BodyPart>,
    /// Why the measured order was kept as it is, when the legs could not be identified.
    pub note: Option<String>,
}

/// Reorders `measured` (joints of `layout` by decreasing importance, as [`joint_importance`] returns
/// them) so that every leg joint comes before every arm joint and left/right counterparts are adjacent,
/// keeping the measured order otherwise (the rule and its reason are in the module documentation).
///
/// Legs are the rotating joints below each hip of [`motion_io::find_feet`]; counterparts are found by
/// name ([`motion_io::mirrored_names`]). A joint whose counterpart is missing (or static) forms a unit
/// alone. Deterministic: ties keep the measured order.
pub fn limb_order(layout: &PoseLayout, measured: &[JointImportance]) -> LimbOrder {
    let sk = layout.skeleton();
    let feet = match find_feet(sk, &FootNames::default()) {
        Ok(f) => f,
        Err(e) => {
            return LimbOrder {
                joints: measured.to_vec(),
                parts: vec![BodyPart::Axial; measured.len()],
                note: Some(format!(
                    "legs not identified ({e}): joints kept in the measured order, a leg may be \
                     dropped before an arm"
                )),
            };
        }
    };
    let part = |j: usize| {
        if sk.is_ancestor_or_self(feet.left_hip, j) || sk.is_ancestor_or_self(feet.right_hip, j) {
            BodyPart::Leg
        } else if side_of(&sk.joints[j].name).is_some() {
            BodyPart::Arm
        } else {
            BodyPart::Axial
        }
    };
    // Units: a joint with its counterpart (same part, other side), in measured order of their first
    // member.
    let index_of = |j: usize| measured.iter().position(|m| m.joint == j);
    let mut taken = vec![false; measured.len()];
    let mut units: Vec<(BodyPart, Vec<usize>)> = Vec::new();
    for (i, m) in measured.iter().enumerate() {
        if taken[i] {
            continue;
        }
        taken[i] = true;
        let pt = part(m.joint);
        let mut unit = vec![i];
        if pt != BodyPart::Axial {
            let side = side_of(&m.name);
            let mate = mirrored_names(&m.name)
                .iter()
                .filter_map(|n| sk.find(n))
                .filter_map(index_of)
                .find(|&k| {
                    !taken[k]
                        && part(measured[k].joint) == pt
                        && side_of(&measured[k].name).is_some()
                        && side_of(&measured[k].name) != side
                });
            if let Some(k) = mate {
                taken[k] = true;
                unit.push(k);
            }
        }
        units.push((pt, unit));
    }
    // Units are in measured order of their most important member, so a stable partition keeps each
    // part sorted by decreasing importance.
    let of = |want: BodyPart| -> Vec<&Vec<usize>> {
        units
            .iter()
            .filter(|(pt, _)| *pt == want)
            .map(|(_, u)| u)
            .collect()
    };
    let limbs: Vec<&Vec<usize>> = of(BodyPart::Leg)
        .into_iter()
        .chain(of(BodyPart::Arm))
        .collect();
    let axial = of(BodyPart::Axial);
    let key = |u: &Vec<usize>| u.iter().map(|&i| measured[i].error_cm).fold(0.0, f64::max);
    let (mut a, mut b) = (0, 0);
    let mut joints = Vec::with_capacity(measured.len());
    let mut parts = Vec::with_capacity(measured.len());
    while a < limbs.len() || b < axial.len() {
        let take_limb = b >= axial.len() || (a < limbs.len() && key(limbs[a]) >= key(axial[b]));
        let unit = if take_limb {
            a += 1;
            limbs[a - 1]
        } else {
            b += 1;
            axial[b - 1]
        };
        for &i in unit {
            joints.push(measured[i].clone());
            parts.push(part(measured[i].joint));
        }
    }
    LimbOrder {
        joints,
        parts,
        note: None,
    }
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

    /// A BVH joint block with 3 rotation channels and the given children.
    fn joint(name: &str, offset: [f64; 3], children: &[String]) -> String {
        format!(
            "JOINT {name}\n{{\nOFFSET {} {} {}\nCHANNELS 3 Zrotation Xrotation Yrotation\n{}\n}}\n",
            offset[0],
            offset[1],
            offset[2],
            if children.is_empty() {
                "End Site\n{\nOFFSET 0 -0.05 0\n}".to_string()
            } else {
                children.concat()
            }
        )
    }

    /// A biped: Hips -> Spine -> Chest -> {Head, Left/Right Shoulder -> Arm -> ForeArm},
    /// Hips -> Left/Right UpLeg -> Leg -> Foot -> Toe (metres).
    fn biped_layout() -> PoseLayout {
        let arm = |side: &str, x: f64| {
            joint(
                &format!("{side}Shoulder"),
                [x * 0.1, 0.2, 0.0],
                &[joint(
                    &format!("{side}Arm"),
                    [x * 0.1, 0.0, 0.0],
                    &[joint(&format!("{side}ForeArm"), [0.0, -0.3, 0.0], &[])],
                )],
            )
        };
        let leg = |side: &str, x: f64| {
            joint(
                &format!("{side}UpLeg"),
                [x * 0.1, 0.0, 0.0],
                &[joint(
                    &format!("{side}Leg"),
                    [0.0, -0.45, 0.0],
                    &[joint(
                        &format!("{side}Foot"),
                        [0.0, -0.45, 0.0],
                        &[joint(&format!("{side}Toe"), [0.0, -0.05, 0.1], &[])],
                    )],
                )],
            )
        };
        let spine = joint(
            "Spine",
            [0.0, 0.1, 0.0],
            &[joint(
                "Chest",
                [0.0, 0.2, 0.0],
                &[
                    joint("Head", [0.0, 0.3, 0.0], &[]),
                    arm("Left", 1.0),
                    arm("Right", -1.0),
                ],
            )],
        );
        let body = [spine, leg("Left", 1.0), leg("Right", -1.0)].concat();
        let n = 1 + 3 + 2 * 3 + 2 * 4;
        let text = format!(
            "HIERARCHY\nROOT Hips\n{{\nOFFSET 0 1 0\nCHANNELS 6 Xposition Yposition Zposition \
             Zrotation Xrotation Yrotation\n{body}}}\nMOTION\nFrames: 1\nFrame Time: 0.0333333\n{}\n",
            vec!["0"; 3 + 3 * n].join(" ")
        );
        let motion = parse_bvh(&text).expect("biped parses");
        PoseLayout::new(&motion.skeleton, 1.0).expect("layout")
    }

    fn measured(layout: &PoseLayout, by_name: &[(&str, f64)]) -> Vec<JointImportance> {
        let mut v: Vec<JointImportance> = by_name
            .iter()
            .map(|&(n, e)| JointImportance {
                joint: layout.skeleton().find(n).expect(n),
                name: n.to_string(),
                error_cm: e,
            })
            .collect();
        v.sort_by(|a, b| b.error_cm.total_cmp(&a.error_cm));
        v
    }

    #[test]
    fn legs_come_before_arms_and_counterparts_are_adjacent() {
        let layout = biped_layout();
        assert_eq!(layout.joint_count(), 17);
        // Measured: the arms and one knee rank high, the other knee low (the limp the rule prevents).
        let m = measured(
            &layout,
            &[
                ("LeftArm", 10.0),
                ("RightArm", 9.5),
                ("Spine", 9.0),
                ("LeftUpLeg", 8.0),
                ("LeftLeg", 7.0),
                ("RightUpLeg", 6.0),
                ("Head", 5.0),
                ("RightLeg", 4.0),
                ("LeftForeArm", 3.0),
                ("RightForeArm", 2.9),
                ("LeftFoot", 2.0),
                ("RightFoot", 1.9),
                ("LeftShoulder", 1.5),
                ("RightShoulder", 1.4),
                ("LeftToe", 1.0),
                ("RightToe", 0.9),
                ("Chest", 0.5),
            ],
        );
        let order = limb_order(&layout, &m);
        assert_eq!(order.note, None);
        let names: Vec<&str> = order.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "Spine",
                "LeftUpLeg",
                "RightUpLeg",
                "LeftLeg",
                "RightLeg",
                "Head",
                "LeftFoot",
                "RightFoot",
                "LeftToe",
                "RightToe",
                "LeftArm",
                "RightArm",
                "LeftForeArm",
                "RightForeArm",
                "LeftShoulder",
                "RightShoulder",
                "Chest",
            ]
        );
        use BodyPart::*;
        let first_arm = order.parts.iter().position(|p| *p == Arm).unwrap();
        let last_leg = order.parts.iter().rposition(|p| *p == Leg).unwrap();
        assert!(last_leg < first_arm, "{:?}", order.parts);
        assert_eq!(order.parts[0], Axial);
    }

    #[test]
    fn without_feet_the_measured_order_stays_with_a_note() {
        // The leg layout has no side markers: no feet can be found.
        let layout = leg_layout();
        let m = measured(&layout, &[("Foot", 2.0), ("Leg", 1.0)]);
        let order = limb_order(&layout, &m);
        assert_eq!(order.joints, m);
        assert!(
            order
                .note
                .as_deref()
                .unwrap()
                .contains("legs not identified")
        );
    }

    #[test]
    fn joints_within_half_a_degree_of_their_mean_are_static() {
        let layout = leg_layout();
        let p = layout.dof();
        let leg = layout.joint_rows(1).unwrap();
        let foot = layout.joint_rows(2).unwrap();
        // The leg swings by +-20 degrees; the foot jitters by +-0.3 degree (RMS 0.3) about a fixed
        // 30-degree rotation, the second case by +-0.7 degree (RMS 0.7).
        let poses = |jitter_deg: f64| {
            let mut v = Vec::new();
            for f in 0..40 {
                let mut pose = vec![0.0; p];
                let sign = if f % 2 == 0 { 1.0 } else { -1.0 };
                pose[leg.start] = (20.0 * (f as f64 * 0.3).sin()).to_radians();
                pose[foot.start] = 30f64.to_radians();
                pose[foot.start + 1] = (sign * jitter_deg).to_radians();
                v.extend(pose);
            }
            v
        };
        let found = static_joints(&layout, &poses(0.3), STATIC_RMS_DEG);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].name, "Foot");
        assert!((found[0].rms_deg - 0.3).abs() < 0.02, "{found:?}");
        assert!(static_joints(&layout, &poses(0.7), STATIC_RMS_DEG).is_empty());
        assert!(static_joints(&layout, &[], STATIC_RMS_DEG).is_empty());
    }
}
