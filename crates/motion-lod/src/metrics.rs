//! The project's error metrics, defined once and used by every test, table and the build's level table.
//!
//! Both compare two pose vectors of one [`PoseLayout`] after forward kinematics, in the canonical frame
//! (root motion included):
//!
//! - **Mean joint position error** (paper section 5): the mean over joints of `|x_j(a) - x_j(b)|`, in cm.
//! - **Shell error** (as ACL measures it): for every joint, six virtual vertices 3 cm from the joint along
//!   its local axes (`x_j + R_j (+-3 cm e_k)`); the error is the largest displacement of any vertex, in cm.
//!   It sees rotation errors of end joints that the position error misses.
//!
//! A clip's error is the mean of the per-frame joint errors and the maximum of the per-frame shell errors;
//! a set of clips averages the joint errors (every frame weighs the same) and takes the maximum shell error.

use glam::DVec3;
use motion_io::{PoseLayout, Transform};

/// Distance of the shell's virtual vertices from their joint, in metres (3 cm).
pub const SHELL_RADIUS_M: f64 = 0.03;

/// Errors of one comparison, in centimetres.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PoseErrorCm {
    /// Mean joint position error (cm).
    pub mean_joint_cm: f64,
    /// Largest virtual-vertex displacement (cm).
    pub shell_cm: f64,
}

/// The joints the metrics measure: the motion root and every joint below it (static joints above the
/// root, such as Bandai's `joint_Root`, are left out).
pub fn measured_joints(layout: &PoseLayout) -> Vec<usize> {
    let sk = layout.skeleton();
    let root = layout.root();
    (0..sk.joints.len())
        .filter(|&j| sk.is_ancestor_or_self(root, j))
        .collect()
}

/// Reusable buffers for [`ErrorMeter::compare`]: one comparison allocates nothing.
#[derive(Debug, Clone)]
pub struct ErrorMeter<'a> {
    layout: &'a PoseLayout,
    a: Vec<Transform>,
    b: Vec<Transform>,
    /// Joints that are measured (below the motion root, or the root itself).
    measured: Vec<usize>,
    sum_joint_cm: f64,
    frames: usize,
    max_shell_cm: f64,
}

impl<'a> ErrorMeter<'a> {
    /// A meter for poses of `layout`. Joints that are not the motion root or below it (static joints
    /// above the root, such as Bandai's `joint_Root`) are not measured.
    pub fn new(layout: &'a PoseLayout) -> ErrorMeter<'a> {
        let measured = measured_joints(layout);
        let n = layout.skeleton().joints.len();
        ErrorMeter {
            layout,
            a: vec![Transform::default(); n],
            b: vec![Transform::default(); n],
            measured,
            sum_joint_cm: 0.0,
            frames: 0,
            max_shell_cm: 0.0,
        }
    }

    /// Compares two full pose vectors (length `layout.dof()`), adds the frame to the running totals and
    /// returns this frame's errors.
    ///
    /// # Panics
    /// If either pose does not have `layout.dof()` rows (a programming error, not user input).
    pub fn compare(&mut self, a: &[f64], b: &[f64]) -> PoseErrorCm {
        self.layout.joint_transforms_f64(a, &mut self.a);
        self.layout.joint_transforms_f64(b, &mut self.b);
        let mut sum = 0.0;
        let mut shell: f64 = 0.0;
        for &j in &self.measured {
            let (ta, tb) = (&self.a[j], &self.b[j]);
            sum += (ta.position - tb.position).length();
            for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                for s in [SHELL_RADIUS_M, -SHELL_RADIUS_M] {
                    let va = ta.position + ta.rotation * (axis * s);
                    let vb = tb.position + tb.rotation * (axis * s);
                    shell = shell.max((va - vb).length());
                }
            }
        }
        let frame = PoseErrorCm {
            mean_joint_cm: 100.0 * sum / self.measured.len().max(1) as f64,
            shell_cm: 100.0 * shell,
        };
        self.sum_joint_cm += frame.mean_joint_cm;
        self.frames += 1;
        self.max_shell_cm = self.max_shell_cm.max(frame.shell_cm);
        frame
    }

    /// Compares two sequences of pose vectors (`frames x dof`, row-major) frame by frame.
    pub fn compare_sequences(&mut self, a: &[f64], b: &[f64]) -> PoseErrorCm {
        let p = self.layout.dof();
        debug_assert_eq!(a.len(), b.len());
        let mut sum = 0.0;
        let mut shell: f64 = 0.0;
        let mut n = 0usize;
        for (fa, fb) in a.chunks_exact(p).zip(b.chunks_exact(p)) {
            let e = self.compare(fa, fb);
            sum += e.mean_joint_cm;
            shell = shell.max(e.shell_cm);
            n += 1;
        }
        PoseErrorCm {
            mean_joint_cm: sum / n.max(1) as f64,
            shell_cm: shell,
        }
    }

    /// Totals over every frame compared so far: mean joint error and largest shell error.
    pub fn total(&self) -> PoseErrorCm {
        PoseErrorCm {
            mean_joint_cm: self.sum_joint_cm / self.frames.max(1) as f64,
            shell_cm: self.max_shell_cm,
        }
    }

    /// Number of frames compared so far.
    pub fn frames(&self) -> usize {
        self.frames
    }
}
