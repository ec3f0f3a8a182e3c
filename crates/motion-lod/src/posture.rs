//! The posture meter, defined once: how straight the knees get and how far forward the head leans,
//! on any motion (the data's gait cycles or a synthesized walk), so that a walk can be compared with
//! each style's takes ("a slow normal walk that looks elderly").
//!
//! It works on pose vectors of a [`PoseLayout`] (`frames x dof`, metres, y up), after forward
//! kinematics ([`PoseLayout::joint_positions_f64`]); the joints are [`PostureJoints`]. Per frame, with
//! `x_j` the world position of joint `j`:
//!
//! - **knee flexion** of a leg (degrees; 0 = straight leg): `180 - angle(x_hip - x_knee,
//!   x_ankle - x_knee)`, the angle at the knee between the thigh and the shin. It is unsigned: a
//!   hyperextended knee also reads above 0. The hip point is the thigh joint (the knee's parent).
//! - **head pitch** (degrees; 0 = upright, positive = leaning forward): with `v = x_head - x_neck` and
//!   the pelvis's forward direction `f` (the horizontal unit vector perpendicular to the line from the
//!   right hip to the left hip, `f = normalize((x_lhip - x_rhip)_xz x y)`: `+z` when the left hip is
//!   at `+x`, the data's convention of y up, +z forward, +x left, as in [`crate::quality`]'s facing
//!   figure), `atan2(v . f, v . y)`: the angle of the neck-to-head vector from the vertical in the
//!   pelvis's sagittal plane (a sideways lean does not count).
//!
//! Over a motion's frames:
//!
//! - **knee extension** ([`Posture::knee_extension_deg`]): for each leg its smallest flexion over
//!   the frames (how straight that knee gets), averaged over the two legs. A walker whose knees are
//!   "never straighter than 37 degrees" reads 37.
//! - **head pitch** ([`Posture::head_pitch_deg`]): the mean over the frames.
//!
//! Over a style's cycles ([`style_postures`]): each figure's 10th percentile, median and 90th
//! percentile over the style's cycles ([`Spread`], linear interpolation between order statistics).
//! [`nearest_style`] finds the style whose medians are nearest to a motion's figures.

use glam::DVec3;
use motion_io::{Feet, FootNames, PoseLayout, Skeleton, find_feet};
use serde::{Deserialize, Serialize};

/// A bone counts as a bone when it is at least this share of the leg length (pelvis to ankle).
const MIN_BONE_SHARE: f64 = 0.1;

/// The joints the posture meter reads (skeleton joint indices).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct PostureJoints {
    /// Left leg: hip (the thigh joint, the knee's parent), knee (the ankle's parent), ankle.
    pub left: [usize; 3],
    /// Right leg: hip, knee, ankle.
    pub right: [usize; 3],
    /// The neck: the head's parent.
    pub neck: usize,
    /// The head.
    pub head: usize,
}

impl PostureJoints {
    /// The joints of `layout`'s skeleton from the feet and head that [`motion_io::find_feet`] finds
    /// by name (no joint map); `None` without a clear knee on both legs or without a head.
    pub fn find(layout: &PoseLayout) -> Option<PostureJoints> {
        let feet = find_feet(layout.skeleton(), &FootNames::default()).ok()?;
        PostureJoints::from_feet(layout.skeleton(), &feet)
    }

    /// The joints from feet already found (with a joint map, say). Each leg's knee is its ankle's
    /// parent and its hip the knee's parent; the knee must lie strictly below the leg's first
    /// joint under the pelvis ([`Feet::left_hip`]), so that the hip point is on the leg, and the
    /// thigh and shin bones must each be at least a tenth of the leg length. The neck is the head's
    /// parent, with a bone of non-zero length between them. `None` when any of this fails.
    pub fn from_feet(sk: &Skeleton, feet: &Feet) -> Option<PostureJoints> {
        let leg_length = feet.leg_length;
        let min_bone = MIN_BONE_SHARE * leg_length;
        let leg = |ankle: usize, top: usize| -> Option<[usize; 3]> {
            let knee = sk.joints.get(ankle)?.parent?;
            if knee == top || !sk.is_ancestor_or_self(top, knee) {
                return None;
            }
            let hip = sk.joints[knee].parent?;
            let bones_ok =
                sk.chain_length(hip, knee) >= min_bone && sk.chain_length(knee, ankle) >= min_bone;
            bones_ok.then_some([hip, knee, ankle])
        };
        let left = leg(feet.left_foot, feet.left_hip)?;
        let right = leg(feet.right_foot, feet.right_hip)?;
        let head = feet.head?;
        let neck = sk.joints.get(head)?.parent?;
        let neck_bone = sk.joints[head].offset.length();
        if neck_bone.is_nan() || neck_bone <= 0.0 {
            return None;
        }
        Some(PostureJoints {
            left,
            right,
            neck,
            head,
        })
    }

    /// Every joint index is below `joints`.
    pub fn fits(&self, joints: usize) -> bool {
        self.left
            .iter()
            .chain(&self.right)
            .chain([&self.neck, &self.head])
            .all(|&j| j < joints)
    }
}

/// What the posture meter measured on one motion (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Posture {
    /// Mean over the two legs of the leg's smallest knee flexion over the frames, degrees (0 = the
    /// knee straightens fully at least once; larger = the knees never get that straight).
    pub knee_extension_deg: f64,
    /// Mean over the frames of the neck-to-head vector's angle from the vertical in the pelvis's
    /// sagittal plane, degrees (positive = the head leans forward).
    pub head_pitch_deg: f64,
}

/// Angle in degrees between `a` and `b`; `None` when either is (nearly) zero.
fn angle_deg(a: DVec3, b: DVec3) -> Option<f64> {
    let (la, lb) = (a.length(), b.length());
    if !(la > 1e-9 && lb > 1e-9) {
        return None;
    }
    Some((a.dot(b) / (la * lb)).clamp(-1.0, 1.0).acos().to_degrees())
}

/// Knee flexion in degrees of the leg `[hip, knee, ankle]` at joint positions `x`.
fn knee_flexion_deg(x: &[DVec3], [hip, knee, ankle]: [usize; 3]) -> Option<f64> {
    angle_deg(x[hip] - x[knee], x[ankle] - x[knee]).map(|a| 180.0 - a)
}

/// Head pitch in degrees at joint positions `x`; `None` when the hips or the neck bone degenerate.
fn head_pitch_deg(x: &[DVec3], joints: &PostureJoints) -> Option<f64> {
    let across = x[joints.left[0]] - x[joints.right[0]];
    let forward = DVec3::new(across.x, 0.0, across.z).cross(DVec3::Y);
    let v = x[joints.head] - x[joints.neck];
    if !(forward.length() > 1e-9 && v.length() > 1e-9) {
        return None;
    }
    let forward = forward.normalize();
    Some(v.dot(forward).atan2(v.y).to_degrees())
}

/// Measures one motion (module documentation): `poses` holds `poses.len() / layout.dof()` pose
/// vectors of `layout`. `None` when there is no frame, the poses do not make whole frames, a value
/// is not finite, the joints are not in the skeleton, or a bone the meter reads has no length.
pub fn measure_posture(
    layout: &PoseLayout,
    poses: &[f64],
    joints: &PostureJoints,
) -> Option<Posture> {
    let dof = layout.dof();
    let nj = layout.skeleton().joints.len();
    if dof == 0 || poses.is_empty() || poses.len() % dof != 0 || !joints.fits(nj) {
        return None;
    }
    if poses.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut x = vec![DVec3::ZERO; nj];
    let (mut left, mut right) = (f64::INFINITY, f64::INFINITY);
    let (mut pitch_sum, mut frames) = (0.0, 0usize);
    for pose in poses.chunks_exact(dof) {
        layout.joint_positions_f64(pose, &mut x);
        left = left.min(knee_flexion_deg(&x, joints.left)?);
        right = right.min(knee_flexion_deg(&x, joints.right)?);
        pitch_sum += head_pitch_deg(&x, joints)?;
        frames += 1;
    }
    Some(Posture {
        knee_extension_deg: 0.5 * (left + right),
        head_pitch_deg: pitch_sum / frames as f64,
    })
}

/// A figure's spread over a style's cycles: its 10th percentile, median and 90th percentile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// 10th percentile.
    pub p10: f64,
    /// Median.
    pub median: f64,
    /// 90th percentile.
    pub p90: f64,
}

impl Spread {
    /// The spread of `values` (percentiles by linear interpolation between order statistics:
    /// quantile `q` of `n` sorted values is at position `q (n - 1)`); `None` when empty.
    pub fn of(values: &[f64]) -> Option<Spread> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let at = |q: f64| {
            let pos = q * (v.len() - 1) as f64;
            let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
            v[lo] + (pos - lo as f64) * (v[hi] - v[lo])
        };
        Some(Spread {
            p10: at(0.1),
            median: at(0.5),
            p90: at(0.9),
        })
    }

    /// `p90 - p10`.
    pub fn width(&self) -> f64 {
        self.p90 - self.p10
    }
}

/// The posture of one style's cycles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StylePosture {
    /// The style's name ([`crate::style::StyleLabels::names`]).
    pub style: String,
    /// Cycles measured.
    pub cycles: usize,
    /// Knee extension ([`Posture::knee_extension_deg`]) over the style's cycles.
    pub knee_extension_deg: Spread,
    /// Head pitch ([`Posture::head_pitch_deg`]) over the style's cycles.
    pub head_pitch_deg: Spread,
}

/// Measures every sample (gait cycle) of `tensor` (`P x T x S` pose vectors of `layout`, each
/// sample's style `of_sample[i]`, an index into `names`) and gives each style's spread, in the
/// order of `names` (a training set's: [`crate::TrainingSet::style_postures`]). `None` when the
/// skeleton has no clear knees or head ([`PostureJoints::find`]). A style none of whose cycles could
/// be measured is left out.
pub fn style_postures(
    layout: &PoseLayout,
    tensor: &tensor_ops::Tensor3,
    names: &[String],
    of_sample: &[usize],
) -> Option<Vec<StylePosture>> {
    let joints = PostureJoints::find(layout)?;
    let samples = tensor.dims()[2];
    let mut by_style: Vec<Vec<Posture>> = vec![Vec::new(); names.len()];
    for (i, &style) in of_sample.iter().enumerate().take(samples) {
        if let (Some(p), Some(list)) = (
            measure_posture(layout, tensor.sample(i), &joints),
            by_style.get_mut(style),
        ) {
            list.push(p);
        }
    }
    Some(
        names
            .iter()
            .zip(&by_style)
            .filter_map(|(name, list)| {
                let knee: Vec<f64> = list.iter().map(|p| p.knee_extension_deg).collect();
                let head: Vec<f64> = list.iter().map(|p| p.head_pitch_deg).collect();
                Some(StylePosture {
                    style: name.clone(),
                    cycles: list.len(),
                    knee_extension_deg: Spread::of(&knee)?,
                    head_pitch_deg: Spread::of(&head)?,
                })
            })
            .collect(),
    )
}

/// The style (index into `styles`) whose median knee extension and head pitch are nearest to `p`'s,
/// each difference divided by that figure's pooled spread: the mean over the styles, weighted by
/// their cycles, of `p90 - p10` (1 degree when that is not positive). The distance is
/// `sqrt((dk / s_k)^2 + (dh / s_h)^2)`; ties go to the first style. `None` when `styles` is empty or
/// `p` is not finite.
pub fn nearest_style(p: &Posture, styles: &[StylePosture]) -> Option<usize> {
    if styles.is_empty() || !(p.knee_extension_deg.is_finite() && p.head_pitch_deg.is_finite()) {
        return None;
    }
    let pooled = |f: &dyn Fn(&StylePosture) -> f64| {
        let weight: f64 = styles.iter().map(|s| s.cycles.max(1) as f64).sum();
        let s = styles
            .iter()
            .map(|s| s.cycles.max(1) as f64 * f(s))
            .sum::<f64>()
            / weight;
        if s.is_finite() && s > 0.0 { s } else { 1.0 }
    };
    let sk = pooled(&|s| s.knee_extension_deg.width());
    let sh = pooled(&|s| s.head_pitch_deg.width());
    let distance = |s: &StylePosture| {
        let dk = (p.knee_extension_deg - s.knee_extension_deg.median) / sk;
        let dh = (p.head_pitch_deg - s.head_pitch_deg.median) / sh;
        dk.hypot(dh)
    };
    styles
        .iter()
        .enumerate()
        .map(|(i, s)| (i, distance(s)))
        .filter(|(_, d)| d.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use motion_io::bvh::parse_bvh;
    use motion_io::expmap::quat_to_exp;

    /// Hips with two legs (thigh 0.45 m, shin 0.4 m, a toe) and a spine, neck and head, metres,
    /// facing +z with the left hip at +x.
    fn body() -> (PoseLayout, PostureJoints) {
        let leg = |side: &str, x: f64| {
            format!(
                "JOINT {side}Thigh\n{{\nOFFSET {x} 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                 JOINT {side}Shin\n{{\nOFFSET 0 -0.45 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                 JOINT {side}Foot\n{{\nOFFSET 0 -0.4 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                 JOINT {side}Toe\n{{\nOFFSET 0 0 0.1\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                 End Site\n{{\nOFFSET 0 0 0.05\n}}\n}}\n}}\n}}\n}}\n"
            )
        };
        let spine = "JOINT Spine\n{\nOFFSET 0 0.1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                     JOINT Neck\n{\nOFFSET 0 0.5 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                     JOINT Head\n{\nOFFSET 0 0.1 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                     End Site\n{\nOFFSET 0 0.15 0\n}\n}\n}\n}\n";
        let text = format!(
            "HIERARCHY\nROOT Hips\n{{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n{}{}{}}}\nMOTION\nFrames: 1\nFrame Time: 0.0333333\n{}\n",
            leg("Left", 0.1),
            leg("Right", -0.1),
            spine,
            "0 0.9 0 0 0 0 ".to_string() + &"0 ".repeat(33)
        );
        let motion = parse_bvh(&text).expect("parses");
        let layout = PoseLayout::new(&motion.skeleton, 1.0).expect("layout");
        let joints = PostureJoints::find(&layout).expect("knees and head");
        (layout, joints)
    }

    /// The rest pose with joint `name` rotated by `rotation` (its local rotation) for each pair.
    fn pose(layout: &PoseLayout, rotations: &[(&str, DQuat)]) -> Vec<f64> {
        let mut p = layout.rest_pose();
        p[1] = 0.9;
        for (name, q) in rotations {
            let j = layout.skeleton().find(name).expect("joint");
            let rows = layout.joint_rows(j).expect("rotating");
            p[rows].copy_from_slice(&quat_to_exp(*q).to_array());
        }
        p
    }

    #[test]
    fn joints_are_the_legs_neck_and_head() {
        let (layout, j) = body();
        let name = |i: usize| layout.skeleton().joints[i].name.as_str();
        assert_eq!(j.left.map(name), ["LeftThigh", "LeftShin", "LeftFoot"]);
        assert_eq!(j.right.map(name), ["RightThigh", "RightShin", "RightFoot"]);
        assert_eq!((name(j.neck), name(j.head)), ("Neck", "Head"));
    }

    #[test]
    fn straight_legs_and_an_upright_head_read_zero() {
        let (layout, j) = body();
        let p = measure_posture(&layout, &pose(&layout, &[]), &j).unwrap();
        assert!(p.knee_extension_deg.abs() < 1e-6, "{p:?}");
        assert!(p.head_pitch_deg.abs() < 1e-9, "{p:?}");
    }

    #[test]
    fn a_bent_knee_reads_its_angle_and_the_straightest_frame_counts() {
        let (layout, j) = body();
        let bend = |deg: f64| DQuat::from_rotation_x(-f64::to_radians(deg));
        // Left knee bent 40 degrees, right 20: the mean is 30.
        let frame = pose(
            &layout,
            &[("LeftShin", bend(40.0)), ("RightShin", bend(20.0))],
        );
        let p = measure_posture(&layout, &frame, &j).unwrap();
        assert!((p.knee_extension_deg - 30.0).abs() < 1e-9, "{p:?}");
        // Over two frames each leg's smallest flexion counts: left 10, right 20.
        let other = pose(
            &layout,
            &[("LeftShin", bend(10.0)), ("RightShin", bend(60.0))],
        );
        let both: Vec<f64> = frame.iter().chain(&other).copied().collect();
        let p = measure_posture(&layout, &both, &j).unwrap();
        assert!((p.knee_extension_deg - 15.0).abs() < 1e-9, "{p:?}");
    }

    #[test]
    fn a_head_leaning_forward_reads_positive_pitch_whatever_the_heading() {
        let (layout, j) = body();
        // The neck tilted 25 degrees towards +z (forward): a rotation about +x.
        let lean = ("Neck", DQuat::from_rotation_x(25f64.to_radians()));
        let p = measure_posture(&layout, &pose(&layout, &[lean]), &j).unwrap();
        assert!((p.head_pitch_deg - 25.0).abs() < 1e-9, "{p:?}");
        // Leaning back reads negative; a sideways lean does not count.
        let back = ("Neck", DQuat::from_rotation_x(-10f64.to_radians()));
        let p = measure_posture(&layout, &pose(&layout, &[back]), &j).unwrap();
        assert!((p.head_pitch_deg + 10.0).abs() < 1e-9, "{p:?}");
        let side = ("Neck", DQuat::from_rotation_z(30f64.to_radians()));
        let p = measure_posture(&layout, &pose(&layout, &[side]), &j).unwrap();
        assert!(p.head_pitch_deg.abs() < 1e-9, "{p:?}");
        // The body turned to face +x: forward follows the pelvis.
        let mut turned = pose(&layout, &[lean]);
        let yaw = quat_to_exp(DQuat::from_rotation_y(90f64.to_radians()));
        turned[3..6].copy_from_slice(&yaw.to_array());
        let p = measure_posture(&layout, &turned, &j).unwrap();
        assert!((p.head_pitch_deg - 25.0).abs() < 1e-9, "{p:?}");
        // Over frames the pitch is the mean.
        let two: Vec<f64> = pose(&layout, &[lean])
            .into_iter()
            .chain(pose(&layout, &[]))
            .collect();
        let p = measure_posture(&layout, &two, &j).unwrap();
        assert!((p.head_pitch_deg - 12.5).abs() < 1e-9, "{p:?}");
    }

    #[test]
    fn bad_poses_are_not_measured() {
        let (layout, j) = body();
        let frame = pose(&layout, &[]);
        assert_eq!(measure_posture(&layout, &[], &j), None);
        assert_eq!(measure_posture(&layout, &frame[1..], &j), None);
        let mut nan = frame.clone();
        nan[8] = f64::NAN;
        assert_eq!(measure_posture(&layout, &nan, &j), None);
        let far = PostureJoints { head: 999, ..j };
        assert_eq!(measure_posture(&layout, &frame, &far), None);
    }

    #[test]
    fn spreads_interpolate_and_the_nearest_style_is_standardised() {
        let s = Spread::of(&[4.0, 0.0, 1.0, 2.0, 3.0]).unwrap();
        assert!((s.p10 - 0.4).abs() < 1e-12 && s.median == 2.0 && (s.p90 - 3.6).abs() < 1e-12);
        assert_eq!(Spread::of(&[]), None);
        let style = |name: &str, knee: f64, head: f64| StylePosture {
            style: name.into(),
            cycles: 10,
            // Knees spread 20 degrees, heads 2: a head degree weighs ten knee degrees.
            knee_extension_deg: Spread {
                p10: knee - 10.0,
                median: knee,
                p90: knee + 10.0,
            },
            head_pitch_deg: Spread {
                p10: head - 1.0,
                median: head,
                p90: head + 1.0,
            },
        };
        let styles = [style("normal", 10.0, 5.0), style("elderly", 30.0, 9.0)];
        let p = |knee, head| Posture {
            knee_extension_deg: knee,
            head_pitch_deg: head,
        };
        assert_eq!(nearest_style(&p(10.0, 5.0), &styles), Some(0));
        assert_eq!(nearest_style(&p(30.0, 9.0), &styles), Some(1));
        // Knees like normal's, the head like elderly's: the head's 4 degrees outweigh 20 knee degrees.
        assert_eq!(nearest_style(&p(12.0, 8.5), &styles), Some(1));
        assert_eq!(nearest_style(&p(12.0, 5.5), &styles), Some(0));
        assert_eq!(nearest_style(&p(f64::NAN, 5.0), &styles), None);
        assert_eq!(nearest_style(&p(10.0, 5.0), &[]), None);
    }
}
