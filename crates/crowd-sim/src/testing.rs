//! A procedural [`ClipSource`] (an analytic stick walker), a source that fails on purpose, and the
//! paper's distance policy for a level table, for tests, benches, demos and the facade's tests. No
//! data, no model: clips are sums of two harmonics of the gait phase per pose row.

use crate::error::ClipError;
use crate::levels::LevelTable;
use crate::source::ClipSource;
use glam::{Quat, Vec3};
use lod_policy::{ControlRange, Controls, Detail, DistanceConfig, DistancePolicy, RootMotion};
use std::f32::consts::TAU;

/// Non-root joints of the stick walker.
const JOINTS: usize = 14;
/// Rows of a full pose vector: root position (3), root exp-map (3), time increment (1), joints.
const POSE_LEN: usize = 7 + 3 * JOINTS;
/// Accuracy levels the procedural source offers.
const LEVELS: usize = 10;

/// Parent of each position (index 0 = root, listed in decreasing visual importance with parents
/// before children): chest, head, hips, knees, shoulders, elbows, ankles, wrists.
const PARENT: [usize; JOINTS + 1] = [0, 0, 1, 0, 0, 3, 4, 1, 1, 7, 8, 5, 6, 9, 10];
/// Bone offset from the parent, in units of the character height.
const OFFSET: [[f32; 3]; JOINTS + 1] = [
    [0.0, 0.0, 0.0],
    [0.0, 0.28, 0.0],
    [0.0, 0.13, 0.0],
    [0.09, 0.0, 0.0],
    [-0.09, 0.0, 0.0],
    [0.0, -0.245, 0.0],
    [0.0, -0.245, 0.0],
    [0.12, 0.0, 0.0],
    [-0.12, 0.0, 0.0],
    [0.0, -0.17, 0.0],
    [0.0, -0.17, 0.0],
    [0.0, -0.25, 0.0],
    [0.0, -0.25, 0.0],
    [0.0, -0.16, 0.0],
    [0.0, -0.16, 0.0],
];
const BONES: [(usize, usize); JOINTS] = [
    (0, 1),
    (1, 2),
    (0, 3),
    (0, 4),
    (3, 5),
    (4, 6),
    (1, 7),
    (1, 8),
    (7, 9),
    (8, 10),
    (5, 11),
    (6, 12),
    (9, 13),
    (10, 14),
];

/// Coefficients of one pose row: `v(u) = c0 + lin u + a1 cos(phi) + b1 sin(phi) + a2 cos(2 phi)
/// + b2 sin(2 phi)`, `phi = 2 pi u`, `u = t / duration`.
type RowCoeffs = [f32; 6];

/// A clip of the procedural walker: row coefficients for its detail.
#[derive(Debug, Clone)]
pub struct ProceduralClip {
    coeffs: Vec<RowCoeffs>,
    detail: Detail,
    duration: f32,
    motion: RootMotion,
    height: f32,
}

impl ProceduralClip {
    /// Detail the clip was built at.
    pub fn detail(&self) -> Detail {
        self.detail
    }
}

/// An analytic walker with 14 joints and 10 accuracy levels. Coarser levels perturb joint
/// amplitudes by up to 3 % per level and drop the second harmonic from level 5, so levels
/// differ visibly; the root trajectory is exact at every level.
#[derive(Debug, Clone, Default)]
pub struct ProceduralSource;

impl ProceduralSource {
    /// The source.
    pub fn new() -> Self {
        Self
    }

    fn joint_rows(c: &Controls, k: f32, j: usize) -> [RowCoeffs; 3] {
        // (c0, lin, a1, b1, a2, b2) for rx, ry, rz of joint j; `side` flips the phase by pi.
        let z = [0.0; 6];
        let side = if j % 2 == 1 { 1.0 } else { -1.0 };
        match j {
            1 => [
                [0.05 + 0.04 * k, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0, 0.1 * k, 0.0, 0.0],
                [-0.3 * c.turn, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
            2 => [[-0.05 - 0.04 * k, 0.0, 0.0, 0.0, 0.0, 0.0], z, z],
            3 | 4 => [z, [0.0, 0.0, 0.0, 0.05 * side, 0.0, 0.0], z],
            // Thigh swing: left leg forward at phi = pi/2.
            5 | 6 => [[0.0, 0.0, 0.0, -0.4 * k * side, 0.05 * k, 0.0], z, z],
            // Upper arm swings against the leg of the same side.
            7 | 8 => [
                [0.0, 0.0, 0.0, 0.3 * k * side, 0.0, 0.0],
                z,
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            ],
            9 | 10 => [[-0.15, 0.0, 0.0, -0.1 * k * side, 0.0, 0.0], z, z],
            // Knee flexion 0.3 k (1 - cos(phi - 0.5)).
            11 | 12 => [
                [
                    0.3 * k,
                    0.0,
                    -0.3 * k * 0.5f32.cos() * side,
                    -0.3 * k * 0.5f32.sin() * side,
                    0.04 * k,
                    0.0,
                ],
                z,
                z,
            ],
            _ => [[-0.25, 0.0, 0.0, -0.1 * k * side, 0.0, 0.0], z, z],
        }
    }
}

impl ClipSource for ProceduralSource {
    type Clip = ProceduralClip;

    fn levels(&self) -> LevelTable {
        LevelTable {
            accuracy_levels: LEVELS,
            joints: JOINTS,
            pose_len: POSE_LEN,
        }
    }

    fn control_range(&self) -> ControlRange {
        ControlRange {
            min: Controls::from_array([-0.4, 0.6, -0.9, 1.5]),
            max: Controls::from_array([0.4, 1.8, 0.9, 1.95]),
        }
    }

    fn new_clip(&self) -> ProceduralClip {
        ProceduralClip {
            coeffs: Vec::with_capacity(POSE_LEN),
            detail: Detail::default(),
            duration: 1.0,
            motion: RootMotion::default(),
            height: 1.7,
        }
    }

    /// Duration `(0.85 + 0.18 |(dx, dz)|) sqrt(height / 1.75)`; root rows: `x = dx u + 0.02 sin
    /// phi`, `y = 0.53 h + 0.01 h cos 2phi`, `z = dz u - 0.03 dz sin 2phi / (2 pi)`, yaw `turn u`.
    fn build_clip(
        &self,
        c: &Controls,
        detail: Detail,
        clip: &mut ProceduralClip,
    ) -> Result<(), ClipError> {
        let h = c.height;
        let dist = (c.dx * c.dx + c.dz * c.dz).sqrt();
        let duration = (0.85 + 0.18 * dist) * (h / 1.75).sqrt();
        let active = detail.active_joints.min(JOINTS);
        clip.coeffs.clear();
        clip.coeffs.extend_from_slice(&[
            [0.0, c.dx, 0.0, 0.02, 0.0, 0.0],
            [0.53 * h, 0.0, 0.0, 0.0, 0.01 * h, 0.0],
            [0.0, c.dz, 0.0, 0.0, 0.0, -0.03 * c.dz / TAU],
            [0.0; 6],
            [0.0, c.turn, 0.0, 0.0, 0.0, 0.0],
            [0.0; 6],
            [duration / 32.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        ]);
        let k = c.dz / 1.3;
        let a = detail.accuracy as f32;
        for j in 1..=active {
            for (axis, mut row) in Self::joint_rows(c, k, j).into_iter().enumerate() {
                let r = (3 * j + axis) as f32;
                let f = 1.0 + 0.03 * a * (1.7 * r + 0.3).sin();
                for v in &mut row[2..] {
                    *v *= f;
                }
                if detail.accuracy >= LEVELS / 2 {
                    row[4] = 0.0;
                    row[5] = 0.0;
                }
                clip.coeffs.push(row);
            }
        }
        clip.detail = Detail {
            accuracy: detail.accuracy,
            active_joints: active,
        };
        clip.duration = duration;
        clip.motion = RootMotion {
            dx: c.dx,
            dz: c.dz,
            turn: c.turn,
        };
        clip.height = h;
        Ok(())
    }

    fn clip_duration(&self, clip: &ProceduralClip) -> f32 {
        clip.duration
    }

    fn clip_root_motion(&self, clip: &ProceduralClip) -> RootMotion {
        clip.motion
    }

    fn pose(&self, clip: &ProceduralClip, t: f32, out: &mut [f32]) -> usize {
        let u = (t / clip.duration).clamp(0.0, 1.0);
        let (s1, c1) = (TAU * u).sin_cos();
        let (s2, c2) = (2.0 * TAU * u).sin_cos();
        let n = clip.coeffs.len().min(out.len());
        for (o, k) in out[..n].iter_mut().zip(&clip.coeffs) {
            *o = k[0] + k[1] * u + k[2] * c1 + k[3] * s1 + k[4] * c2 + k[5] * s2;
        }
        n
    }

    fn joints(&self, clip: &ProceduralClip, pose: &[f32], out: &mut [Vec3]) -> usize {
        if pose.len() < 7 || out.is_empty() {
            return 0;
        }
        let active = ((pose.len() - 7) / 3)
            .min(clip.detail.active_joints)
            .min(out.len() - 1);
        let mut rot = [Quat::IDENTITY; JOINTS + 1];
        out[0] = Vec3::new(pose[0], pose[1], pose[2]);
        rot[0] = Quat::from_scaled_axis(Vec3::new(pose[3], pose[4], pose[5]));
        for j in 1..=active {
            let p = PARENT[j];
            let r = &pose[7 + 3 * (j - 1)..10 + 3 * (j - 1)];
            rot[j] = rot[p] * Quat::from_scaled_axis(Vec3::new(r[0], r[1], r[2]));
            out[j] = out[p] + rot[j] * (Vec3::from_array(OFFSET[j]) * clip.height);
        }
        1 + active
    }

    fn bones(&self) -> &[(usize, usize)] {
        &BONES
    }
}

/// The paper's distance policy (section 5.1, [`DistancePolicy`] with its defaults and without the
/// screen check, which needs measured errors) for a source with `levels`, one key per accuracy
/// level: every joint below 30 m, one accuracy level more every 50 m beyond, one joint (three DOF)
/// fewer every 10 m beyond 30 m, root only beyond the last level or when not visible.
pub fn paper_distance_policy(levels: LevelTable) -> DistancePolicy {
    let keys: Vec<usize> = (0..levels.accuracy_levels.max(1)).collect();
    let config = DistanceConfig {
        screen_budget_px: None,
        ..DistanceConfig::default()
    };
    DistancePolicy::for_level_keys(&keys, levels.joints, config)
        .expect("the default distances are valid and the keys increase")
}

/// A source that fails some of its clip builds on purpose, for testing that faults are counted:
/// a build with joints fails when a hash of the controls' bits is a multiple of `every` (so the
/// same clips fail for any thread count), leaving the clip as it was; root-only builds (a new
/// crowd's first clips among them) never fail.
#[derive(Debug, Clone)]
pub struct FailingSource<S> {
    /// The source that builds the clips that do not fail.
    pub inner: S,
    /// One build with joints in about `every` fails (at least 1: then every one).
    pub every: u32,
}

impl<S> FailingSource<S> {
    /// Whether the build of `c` at `detail` fails.
    pub fn fails(&self, c: &Controls, detail: &Detail) -> bool {
        let h = c.dx.to_bits() ^ c.dz.to_bits().rotate_left(7) ^ c.turn.to_bits().rotate_left(13);
        detail.active_joints > 0 && (h.wrapping_mul(0x9E37_79B1) >> 8) % self.every.max(1) == 0
    }
}

impl<S: ClipSource> ClipSource for FailingSource<S> {
    type Clip = S::Clip;

    fn levels(&self) -> LevelTable {
        self.inner.levels()
    }

    fn control_range(&self) -> ControlRange {
        self.inner.control_range()
    }

    fn style_mix(&self) -> &[f32] {
        self.inner.style_mix()
    }

    fn new_clip(&self) -> S::Clip {
        self.inner.new_clip()
    }

    fn clip_classes(&self) -> usize {
        self.inner.clip_classes()
    }

    fn clip_class(&self, detail: &Detail) -> usize {
        self.inner.clip_class(detail)
    }

    fn new_clip_of_class(&self, class: usize) -> S::Clip {
        self.inner.new_clip_of_class(class)
    }

    fn build_clip(
        &self,
        c: &Controls,
        detail: Detail,
        clip: &mut S::Clip,
    ) -> Result<(), ClipError> {
        if self.fails(c, &detail) {
            return Err(ClipError(format!(
                "test failure for controls {:?} at {detail:?}",
                c.to_array()
            )));
        }
        self.inner.build_clip(c, detail, clip)
    }

    fn clip_duration(&self, clip: &S::Clip) -> f32 {
        self.inner.clip_duration(clip)
    }

    fn clip_root_motion(&self, clip: &S::Clip) -> RootMotion {
        self.inner.clip_root_motion(clip)
    }

    fn pose(&self, clip: &S::Clip, t_seconds: f32, out: &mut [f32]) -> usize {
        self.inner.pose(clip, t_seconds, out)
    }

    fn joints(&self, clip: &S::Clip, pose: &[f32], out: &mut [Vec3]) -> usize {
        self.inner.joints(clip, pose, out)
    }

    fn bones(&self) -> &[(usize, usize)] {
        self.inner.bones()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn controls() -> Controls {
        Controls::from_array([0.1, 1.3, 0.3, 1.75])
    }

    #[test]
    fn root_motion_matches_the_root_at_the_end_of_the_clip() {
        let s = ProceduralSource::new();
        let mut clip = s.new_clip();
        let mut pose = vec![0.0; POSE_LEN];
        let mut pos = vec![Vec3::ZERO; JOINTS + 1];
        for det in [
            Detail {
                accuracy: 0,
                active_joints: JOINTS,
            },
            Detail {
                accuracy: 9,
                active_joints: 0,
            },
        ] {
            s.build_clip(&controls(), det, &mut clip).unwrap();
            let d = s.clip_duration(&clip);
            let n = s.pose(&clip, d, &mut pose);
            assert_eq!(n, 7 + 3 * det.active_joints);
            let m = s.joints(&clip, &pose[..n], &mut pos);
            assert_eq!(m, 1 + det.active_joints);
            let rm = s.clip_root_motion(&clip);
            assert!((pos[0].x - rm.dx).abs() < 1e-5 && (pos[0].z - rm.dz).abs() < 1e-5);
            assert!((pose[4] - rm.turn).abs() < 1e-6);
            // At t = 0 the root is at the origin of the cycle frame.
            s.pose(&clip, 0.0, &mut pose);
            assert!(pose[0].abs() < 1e-6 && pose[2].abs() < 1e-6);
        }
    }

    #[test]
    fn skeleton_stands_on_the_ground_and_reaches_the_height() {
        let s = ProceduralSource::new();
        let mut clip = s.new_clip();
        s.build_clip(
            &controls(),
            Detail {
                accuracy: 0,
                active_joints: JOINTS,
            },
            &mut clip,
        )
        .unwrap();
        let mut pose = vec![0.0; POSE_LEN];
        let mut pos = vec![Vec3::ZERO; JOINTS + 1];
        for k in 0..20 {
            let n = s.pose(&clip, k as f32 * 0.05, &mut pose);
            s.joints(&clip, &pose[..n], &mut pos);
            let lo = pos.iter().map(|p| p.y).fold(f32::MAX, f32::min);
            let hi = pos.iter().map(|p| p.y).fold(f32::MIN, f32::max);
            assert!(lo > -0.05 && lo < 0.2, "lowest joint at {lo}");
            assert!(hi > 1.5 && hi < 1.8, "highest joint at {hi}");
        }
    }

    #[test]
    fn coarser_levels_change_the_pose_but_not_the_root() {
        let s = ProceduralSource::new();
        let (mut a, mut b) = (s.new_clip(), s.new_clip());
        s.build_clip(
            &controls(),
            Detail {
                accuracy: 0,
                active_joints: JOINTS,
            },
            &mut a,
        )
        .unwrap();
        s.build_clip(
            &controls(),
            Detail {
                accuracy: 8,
                active_joints: JOINTS,
            },
            &mut b,
        )
        .unwrap();
        let (mut pa, mut pb) = (vec![0.0; POSE_LEN], vec![0.0; POSE_LEN]);
        s.pose(&a, 0.3, &mut pa);
        s.pose(&b, 0.3, &mut pb);
        assert_eq!(pa[..7], pb[..7]);
        assert!(
            pa[7..]
                .iter()
                .zip(&pb[7..])
                .any(|(x, y)| (x - y).abs() > 1e-3)
        );
    }

    #[test]
    fn paper_policy_follows_the_distance_bands() {
        use lod_policy::{LevelPolicy, ViewParams};
        let lv = ProceduralSource.levels();
        let p = paper_distance_policy(lv);
        let v = ViewParams::default();
        assert_eq!(p.detail(10.0, true, &v), Detail::new(0, JOINTS));
        assert_eq!(p.detail(45.0, true, &v), Detail::new(0, JOINTS - 1));
        assert_eq!(p.detail(85.0, true, &v), Detail::new(1, JOINTS - 5));
        assert_eq!(p.detail(10.0, false, &v).active_joints, 0);
        assert_eq!(p.detail(1000.0, true, &v).active_joints, 0);
    }
}
