//! The motion-quality meter, defined once beside the joint error ([`crate::metrics`]) and used by every
//! test, table and the `quality` command. It sees what a viewer sees and a per-pose error cannot: a pop
//! at a cycle seam, a sliding planted foot, feet that float or sink, a pelvis that crabs against its path,
//! a cadence that does not fit the speed.
//!
//! It works on any motion given as world-frame pose vectors of a [`PoseLayout`] (`frames x dof`, metres,
//! y up), synthesized or captured, after forward kinematics; `x_j(f)` is joint `j`'s world position at
//! frame `f` of `n`, `y` its height and `|v|_xz` the length of a vector's ground (x, z) part. With
//! `k` = the frame step nearest 1/30 s (`k = max(1, round(1 / (30 dt)))` frames, so 30 fps data use
//! neighbouring frames and 120 Hz data every fourth):
//!
//! - **pop** (cm per frame² at 30 fps): the largest joint acceleration,
//!   `max_{f, j} |x_j(f + k) - 2 x_j(f) + x_j(f - k)| (1 / (30 k dt))^2`, over the measured joints
//!   ([`measured_joints`]); **seam pop**: the same maximum over frames within `k` of a seam.
//! - **Feet.** Each foot `F` has one or two points (ankle, and toe when the skeleton has one); its
//!   **lowest point** `l_F(f)` is the one lowest at frame `f`, at height `h_F(f)`, moving at the
//!   horizontal speed `v_F(f) = |x_l(f + k) - x_l(f - k)|_xz / (2 k dt)` (m/s, `l = l_F(f)`, for
//!   `k <= f < n - k`).
//! - **Stance floor** `s_F(f)` (m): the [`STANCE_QUANTILE`] quantile (10th percentile) of `h_F` over
//!   the one-cycle window of frames around `f` (`2 round(cycle_s / (2 dt)) + 1` frames, shifted to lie
//!   inside the motion; the whole motion when that is shorter; quantile `q` of `m` sorted values is the
//!   value at position `round(q (m - 1))`). Every window one gait cycle long holds one stance of each
//!   foot, so `s_F` is the height that foot stands at, wherever the motion holds it: a walk lifted by
//!   3 cm has its stance floor 3 cm higher, and a walk whose stance height changes along the way (a
//!   crowd walker changing level) is followed cycle by cycle.
//! - **Contact**: foot `F` is in contact at frame `f` (`k <= f < n - k`) when its lowest point is within
//!   [`CONTACT_HEIGHT_M`] (2 cm) of its stance floor, `h_F(f) - s_F(f) < 0.02`, and slower than
//!   [`CONTACT_SPEED_M_S`] (1 m/s), `v_F(f) < 1`. No absolute floor enters: raising or lowering a
//!   motion changes none of its contacts. **Contact share**: contacts over the `2 (n - 2 k)`
//!   (foot, frame) pairs.
//! - **Foot skate** (cm/s): `100 mean v_F(f)` over the (foot, frame) pairs in contact, 0 without
//!   contacts: how fast a planted foot slides. (The speed limit sits in the gap the data leave between
//!   stance and swing: of the Bandai frames where a foot is within 2 cm of its stance floor, 92% move
//!   slower than 1 m/s, 6.5% faster than 2 m/s (swing feet passing low) and 1.2% in between. A foot
//!   that slides faster than 1 m/s at stance height is taken for a swing foot: it shows as a contact
//!   share below the data's.)
//! - **Floating** (cm): `100 (mean_{F, f} s_F(f) - g)` over both feet and every frame, `g` the ground
//!   (below): how far the feet stand above the floor (negative: below it).
//! - **Floor offset**, **float** and **sink** (cm), the window rule: the lowest point of both feet is
//!   at the floor at least once in every step. Over windows of [`STEP_WINDOW_S`], the window's lowest
//!   height minus `g`: the median is the floor offset (positive floats, negative sinks), the largest is
//!   the float (both feet off the floor for a whole step); the sink is the deepest any foot point goes
//!   below `g` (0 when none does).
//! - **facing against travel** (degrees): the pelvis heading (perpendicular to the line from the right
//!   hip to the left hip on the ground) minus the travel heading (the root's ground displacement over one
//!   cycle centred on the frame), averaged over frames; the smallest and largest one-cycle means are
//!   reported too.
//! - **cycle duration** (s) against the data's cycles of similar step length (see
//!   [`QualityReference::duration_for_step`]).
//!
//! Only the floating and the window-rule figures depend on the ground `g`. A synthesized walk or a crowd
//! track is measured against the data's floor, [`QualityReference::floor_m`]; a data take against its
//! own floor (the window rule's median, [`floor_of`]), and the data's floor is the median of those over
//! the takes. Every figure is also reported as a ratio to the data ([`QualityReference`]), measured on
//! the data's own takes (the steady stretch of every take that gave cycles) by the same function,
//! [`measure`], as every walk: the data's skate and a walk's are one definition. A walk of known
//! controls has its pop and skate compared with the data's at its step length
//! ([`QualityReference::at_step`]: the robust trend of the takes' figures over their mean step),
//! because the data's own pop and skate can grow with the step (the embedded data: pop 5.4 cm per
//! frame² in the 1.03 m takes, 17.5 in the 1.64 m one); a crowd, whose walkers walk every step, is
//! compared with the median of all takes ([`QualityReference::median`]).
//!
//! (Until issue 34 a foot counted as planted while within 2 cm of the data's floor: a walk whose
//! feet floated lost its contacts and read as not skating, and swing feet passing low counted as
//! sliding, so that Bandai's own takes read 22.3 cm/s of skate, 3.2x what the rule above reads,
//! 7.0 cm/s.)

use glam::DVec3;
use motion_io::{Feet, PoseLayout};
use serde::{Deserialize, Serialize};

use crate::metrics::measured_joints;

/// A foot is in contact only while its lowest point is within this height of its own stance floor
/// (2 cm; module documentation).
pub const CONTACT_HEIGHT_M: f64 = 0.02;
/// A foot is in contact only while its lowest point moves slower than this horizontally (1 m/s).
pub const CONTACT_SPEED_M_S: f64 = 1.0;
/// The quantile of a foot's heights over one cycle that is its stance floor (the 10th percentile).
pub const STANCE_QUANTILE: f64 = 0.1;
/// Window of the floor rule: at walking pace one foot is flat on the floor at least once in 0.5 s.
pub const STEP_WINDOW_S: f64 = 0.5;
/// The rate accelerations and speeds are taken at (frames per second).
pub const REFERENCE_FPS: f64 = 30.0;

/// The joints the meter reads: the two feet (ankle and optional toe) and the two hips.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FootJoints {
    /// Points of the left foot (ankle, then toe when present).
    pub left: Vec<usize>,
    /// Points of the right foot.
    pub right: Vec<usize>,
    /// Left hip joint.
    pub left_hip: usize,
    /// Right hip joint.
    pub right_hip: usize,
}

impl FootJoints {
    /// The meter's joints from the feet found by [`motion_io::find_feet`].
    pub fn from_feet(feet: &Feet) -> FootJoints {
        FootJoints {
            left: std::iter::once(feet.left_foot)
                .chain(feet.left_toe)
                .collect(),
            right: std::iter::once(feet.right_foot)
                .chain(feet.right_toe)
                .collect(),
            left_hip: feet.left_hip,
            right_hip: feet.right_hip,
        }
    }

    /// Every joint index is below `joints`.
    pub fn fits(&self, joints: usize) -> bool {
        self.left
            .iter()
            .chain(&self.right)
            .chain([&self.left_hip, &self.right_hip])
            .all(|&j| j < joints)
            && !self.left.is_empty()
            && !self.right.is_empty()
    }
}

/// What the meter measured on one motion.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct MotionQuality {
    /// Frames measured.
    pub frames: usize,
    /// Largest joint acceleration, cm per frame² at 30 fps.
    pub pop_cm: f64,
    /// Largest joint acceleration within one 30 fps frame of a seam (0 without seams).
    pub seam_pop_cm: f64,
    /// Mean horizontal speed of a foot's lowest point while the foot is in contact (within 2 cm of
    /// its own stance floor and slower than 1 m/s), cm/s.
    pub skate_cm_s: f64,
    /// Share of (foot, frame) pairs in contact.
    pub contact_share: f64,
    /// Median over step windows of the lowest foot point above the floor, cm (negative: sinks).
    pub floor_offset_cm: f64,
    /// Largest step-window lowest point above the floor, cm (both feet in the air for a step).
    pub float_cm: f64,
    /// Deepest foot point below the floor, cm (0 when none sinks).
    pub sink_cm: f64,
    /// Mean over both feet and every frame of the foot's stance floor above the floor, cm (how far
    /// the feet stand above it; negative: below it).
    pub floating_cm: f64,
    /// Mean pelvis heading minus travel heading, degrees (+ = facing left of the path).
    pub facing_deg: f64,
    /// Smallest mean facing against travel over one-cycle windows, degrees.
    pub facing_min_deg: f64,
    /// Largest mean facing against travel over one-cycle windows, degrees.
    pub facing_max_deg: f64,
}

/// The data's own figures: the median over the training takes of each take's [`MotionQuality`], the
/// floor, the range of facing against travel, and cycle durations by step length.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct QualityReference {
    /// The feet and hips of the data's skeleton the meter reads.
    pub feet: FootJoints,
    /// Standing height (m) of the layout's skeleton (the first take's), measured as the height
    /// control is; each take is measured with its bones scaled by its own height over this (the
    /// body scale the model draws a character of that height with). `None` without feet.
    pub stature_m: Option<f64>,
    /// Takes measured.
    pub takes: usize,
    /// The floor height (m) in the data's frame: median over takes of each take's floor (the
    /// window rule, [`floor_of`]). The ground of every walk's floating and window-rule figures, and
    /// the floor of the foot lock.
    pub floor_m: f64,
    /// Median over takes of the per-take figures, each take measured by [`measure`] as a walk is
    /// (the floating and window-rule figures against the take's own floor; the pop, skate and
    /// contacts do not depend on it).
    pub median: MotionQuality,
    /// The data's range of facing against travel, degrees: the 2nd percentile of the takes' smallest
    /// one-cycle means and the 98th percentile of their largest.
    pub facing_range_deg: (f64, f64),
    /// `(step length m, duration s)` of every training cycle, sorted by step length.
    pub cycle_steps: Vec<(f64, f64)>,
    /// The takes' pop and skate against their mean step length (the step of a take is the mean
    /// `sqrt(dx^2 + dz^2)` of its cycles), fitted once when the reference is made: what
    /// [`QualityReference::at_step`] reads. `None` with fewer than two takes.
    pub step_trends: Option<StepTrends>,
}

/// The trends of [`QualityReference::step_trends`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StepTrends {
    /// Pop (cm per frame²) against the step (m).
    pub pop_cm: StepTrend,
    /// Skate (cm/s) against the step (m).
    pub skate_cm_s: StepTrend,
}

impl QualityReference {
    /// The runtime foot lock's feet and floor ([`lod_policy::FootRig`]) for `rig`: the ankle and
    /// toe of each foot and the data's floor; `None` when they do not fit the rig (a foot without
    /// a rotating knee and thigh above it).
    pub fn foot_rig(&self, rig: &lod_policy::Rig) -> Option<lod_policy::FootRig> {
        let foot = |points: &[usize]| lod_policy::Foot {
            ankle: points[0],
            toe: points.get(1).copied(),
        };
        if self.feet.left.is_empty() || self.feet.right.is_empty() {
            return None;
        }
        let feet = lod_policy::FootRig {
            left: foot(&self.feet.left),
            right: foot(&self.feet.right),
            floor_m: self.floor_m as f32,
        };
        feet.check(rig).is_ok().then_some(feet)
    }

    /// Median duration of the data's cycles whose step length is near `step_m` ([`near_step`]);
    /// `None` without cycles.
    pub fn duration_for_step(&self, step_m: f64) -> Option<f64> {
        let mut near: Vec<f64> = near_step(&self.cycle_steps, step_m)
            .into_iter()
            .copied()
            .collect();
        (!near.is_empty()).then(|| median(&mut near))
    }

    /// The data's figures for a walk of step length `step_m` (m, `sqrt(dx^2 + dz^2)` of its
    /// controls): [`QualityReference::median`] with the pop and the skate taken from their trend
    /// over the takes' steps ([`StepTrend`], the Theil-Sen line through every take's `(mean step,
    /// figure)`, kept within the takes' own range). The data's pop and skate grow with the step (the
    /// embedded data: pop 5.4 cm per frame² in its 1.03 m takes, 17.5 in its 1.64 m one), so a fast
    /// walk is held to what the data do at that pace. The pooled median without trends (fewer
    /// than two takes).
    pub fn at_step(&self, step_m: f64) -> MotionQuality {
        match &self.step_trends {
            Some(t) => MotionQuality {
                pop_cm: t.pop_cm.at(step_m),
                skate_cm_s: t.skate_cm_s.at(step_m),
                ..self.median
            },
            None => self.median,
        }
    }

    /// [`QualityReference::at_step`] for a walk of `controls` (its step from `dx` and `dz`).
    pub fn at_controls(&self, controls: &lod_policy::Controls) -> MotionQuality {
        self.at_step(f64::from(controls.dx).hypot(f64::from(controls.dz)))
    }
}

/// The take or cycle count [`near_step`] pools at least, when fewer lie within 10% of the step.
pub const NEAR_STEP_COUNT: usize = 9;

/// The values of `by_step` (`(step length m, value)`, any order) whose step is within 10% of
/// `step_m`, or the [`NEAR_STEP_COUNT`] nearest (ties in order) when fewer are that close; empty
/// only when `by_step` is.
pub fn near_step<T>(by_step: &[(f64, T)], step_m: f64) -> Vec<&T> {
    let near: Vec<&T> = by_step
        .iter()
        .filter(|(s, _)| (s - step_m).abs() <= 0.1 * step_m.abs())
        .map(|(_, v)| v)
        .collect();
    if near.len() >= NEAR_STEP_COUNT {
        return near;
    }
    let mut by_dist: Vec<(f64, &T)> = by_step
        .iter()
        .map(|(s, v)| ((s - step_m).abs(), v))
        .collect();
    by_dist.sort_by(|a, b| a.0.total_cmp(&b.0));
    by_dist
        .into_iter()
        .take(NEAR_STEP_COUNT)
        .map(|(_, v)| v)
        .collect()
}

/// Field by field median of `qs` (the seam pop too; the frames rounded down).
fn median_quality(qs: &[MotionQuality]) -> MotionQuality {
    let pick = |f: &dyn Fn(&MotionQuality) -> f64| {
        let mut v: Vec<f64> = qs.iter().map(f).collect();
        median(&mut v)
    };
    MotionQuality {
        frames: pick(&|q| q.frames as f64) as usize,
        pop_cm: pick(&|q| q.pop_cm),
        seam_pop_cm: pick(&|q| q.seam_pop_cm),
        skate_cm_s: pick(&|q| q.skate_cm_s),
        contact_share: pick(&|q| q.contact_share),
        floor_offset_cm: pick(&|q| q.floor_offset_cm),
        float_cm: pick(&|q| q.float_cm),
        sink_cm: pick(&|q| q.sink_cm),
        floating_cm: pick(&|q| q.floating_cm),
        facing_deg: pick(&|q| q.facing_deg),
        facing_min_deg: pick(&|q| q.facing_min_deg),
        facing_max_deg: pick(&|q| q.facing_max_deg),
    }
}

/// A robust line `value = intercept + slope x step` through `(step, value)` points, the Theil-Sen
/// estimator: the slope is the median of the slopes between every pair of points with different
/// steps, the intercept the median of `value - slope x step`. One take far off the line moves it
/// little (unlike least squares). [`StepTrend::at`] keeps the line within the points' own values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StepTrend {
    /// Change of the value per metre of step.
    pub slope: f64,
    /// The value at step 0.
    pub intercept: f64,
    /// Smallest and largest value of the points.
    pub range: (f64, f64),
}

impl StepTrend {
    /// The line through `points` (flat at their median when no two steps differ; empty: zero).
    pub fn fit(points: &[(f64, f64)]) -> StepTrend {
        let mut slopes = Vec::with_capacity(points.len() * points.len().saturating_sub(1) / 2);
        for (i, a) in points.iter().enumerate() {
            for b in &points[i + 1..] {
                if (b.0 - a.0).abs() > 1e-9 {
                    slopes.push((b.1 - a.1) / (b.0 - a.0));
                }
            }
        }
        let slope = median(&mut slopes);
        let mut rest: Vec<f64> = points.iter().map(|(x, y)| y - slope * x).collect();
        let range = points
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |r, p| {
                (r.0.min(p.1), r.1.max(p.1))
            });
        StepTrend {
            slope,
            intercept: median(&mut rest),
            range: if points.is_empty() { (0.0, 0.0) } else { range },
        }
    }

    /// The line's value at `step`, clamped to the points' range.
    pub fn at(&self, step: f64) -> f64 {
        (self.intercept + self.slope * step).clamp(self.range.0, self.range.1)
    }
}

/// Median of `v` (the mean of the two middle values for an even count; 0 when empty). Reorders `v`.
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Why a motion could not be measured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum QualityError {
    /// The poses do not fit the layout.
    #[error("{len} pose values do not make frames of {dof} DOF")]
    Shape {
        /// Values given.
        len: usize,
        /// The layout's DOF.
        dof: usize,
    },
    /// Too few frames for a second difference at the 30 fps step.
    #[error("{frames} frames are too few to measure (at least {needed})")]
    TooShort {
        /// Frames given.
        frames: usize,
        /// Frames needed.
        needed: usize,
    },
    /// A bad frame time or window.
    #[error("invalid {what}: {value}")]
    Bad {
        /// What is invalid.
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A foot or hip joint is not in the skeleton.
    #[error("foot joints {0:?} are not all in the skeleton")]
    Joints(Box<FootJoints>),
    /// A pose holds NaN or infinity.
    #[error("frame {0} holds a non-finite value")]
    NonFinite(usize),
    /// The model carries no reference (built before format 4, or the feet were not found).
    #[error("the model has no motion-quality reference (its feet were not found in the data)")]
    NoReference,
    /// A figure came out NaN or infinite: finite poses too large to measure (joint positions or
    /// their differences past the range of `f64`).
    #[error("the {figure} figure is not finite ({value}): the poses are too large to measure")]
    NonFiniteFigure {
        /// The figure (its field name in [`MotionQuality`]).
        figure: &'static str,
        /// Its value.
        value: f64,
    },
}

/// The frame step nearest 1/30 s for frames `dt` seconds apart.
pub fn step_frames(dt: f64) -> usize {
    ((1.0 / (REFERENCE_FPS * dt)).round() as usize).max(1)
}

/// Ground heading (radians, 0 = +z, + = towards +x) of a horizontal vector.
fn heading(v: DVec3) -> f64 {
    v.x.atan2(v.z)
}

/// The stance floor of one foot at every frame (module documentation): the [`STANCE_QUANTILE`]
/// quantile of `heights` (the foot's lowest point, frame by frame) over the window of `2 half + 1`
/// frames around the frame, shifted to lie inside the motion (all frames when there are fewer).
fn stance_floors(heights: &[f64], half: usize) -> Vec<f64> {
    let n = heights.len();
    let len = (2 * half + 1).min(n);
    let rank = (STANCE_QUANTILE * (len.saturating_sub(1)) as f64).round() as usize;
    let mut window = vec![0.0; len];
    let mut out = Vec::with_capacity(n);
    let mut placed = None;
    for f in 0..n {
        let start = f.saturating_sub(half).min(n - len);
        // Frames near the ends share one window: it is ranked again only where it moved.
        if placed != Some(start) {
            window.copy_from_slice(&heights[start..start + len]);
            window.select_nth_unstable_by(rank, f64::total_cmp);
            placed = Some(start);
        }
        out.push(window[rank]);
    }
    out
}

/// Measures one motion (module documentation).
///
/// `poses`: `frames x dof` world-frame pose vectors of `layout`; `dt`: seconds between frames;
/// `floor_m`: the ground `g` of the floating and window-rule figures (the data's floor,
/// [`QualityReference::floor_m`], for a walk; `None` measures against the motion's own floor by the
/// window rule, as the data's takes are measured); `cycle_s`: the gait cycle duration, the window of
/// the stance floor and of the travel heading; `seams`: frames where one cycle hands over to the
/// next. The pop, skate and contacts do not depend on `floor_m`.
///
/// # Errors
/// [`QualityError::Shape`], [`QualityError::Bad`] (frame time or cycle duration not finite and
/// positive), [`QualityError::Joints`], [`QualityError::TooShort`], [`QualityError::NonFinite`]
/// (a pose value), and [`QualityError::NonFiniteFigure`] when finite poses are too large to give
/// finite figures.
pub fn measure(
    layout: &PoseLayout,
    feet: &FootJoints,
    poses: &[f64],
    dt: f64,
    floor_m: Option<f64>,
    cycle_s: f64,
    seams: &[usize],
) -> Result<MotionQuality, QualityError> {
    let dof = layout.dof();
    if dof == 0 || poses.len() % dof != 0 {
        return Err(QualityError::Shape {
            len: poses.len(),
            dof,
        });
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(QualityError::Bad {
            what: "frame time",
            value: dt,
        });
    }
    if !(cycle_s.is_finite() && cycle_s > 0.0) {
        return Err(QualityError::Bad {
            what: "cycle duration",
            value: cycle_s,
        });
    }
    let nj = layout.skeleton().joints.len();
    if !feet.fits(nj) {
        return Err(QualityError::Joints(Box::new(feet.clone())));
    }
    let n = poses.len() / dof;
    let k = step_frames(dt);
    if n < 2 * k + 1 {
        return Err(QualityError::TooShort {
            frames: n,
            needed: 2 * k + 1,
        });
    }
    if let Some(f) = poses
        .chunks_exact(dof)
        .position(|p| p.iter().any(|v| !v.is_finite()))
    {
        return Err(QualityError::NonFinite(f));
    }
    // World positions of every joint, frame by frame.
    let mut x = vec![DVec3::ZERO; n * nj];
    for (pose, out) in poses.chunks_exact(dof).zip(x.chunks_exact_mut(nj)) {
        layout.joint_positions_f64(pose, out);
    }
    let at = |f: usize, j: usize| x[f * nj + j];

    // Pop.
    let measured = measured_joints(layout);
    let scale = 100.0 / (REFERENCE_FPS * k as f64 * dt).powi(2);
    let mut pop: f64 = 0.0;
    let mut seam_pop: f64 = 0.0;
    for f in k..n - k {
        let a = measured
            .iter()
            .map(|&j| (at(f + k, j) - 2.0 * at(f, j) + at(f - k, j)).length())
            .fold(0.0, f64::max)
            * scale;
        pop = pop.max(a);
        if seams.iter().any(|&s| f + k >= s && f <= s + k) {
            seam_pop = seam_pop.max(a);
        }
    }

    // Lowest point of each foot, per frame.
    let lowest = |f: usize, pts: &[usize]| -> usize {
        *pts.iter()
            .min_by(|&&a, &&b| at(f, a).y.total_cmp(&at(f, b).y))
            .expect("a foot has a point")
    };
    let both_low: Vec<f64> = (0..n)
        .map(|f| {
            at(f, lowest(f, &feet.left))
                .y
                .min(at(f, lowest(f, &feet.right)).y)
        })
        .collect();
    let window = ((STEP_WINDOW_S / dt).round() as usize).clamp(1, n);
    let mut window_mins: Vec<f64> = both_low
        .chunks(window)
        .filter(|c| c.len() * 2 >= window)
        .map(|c| c.iter().copied().fold(f64::INFINITY, f64::min))
        .collect();
    if window_mins.is_empty() {
        window_mins.push(both_low.iter().copied().fold(f64::INFINITY, f64::min));
    }
    let float_m = window_mins
        .iter()
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let offset_m = median(&mut window_mins.clone());
    let floor = floor_m.unwrap_or(offset_m);
    let sink_m = both_low.iter().map(|&y| floor - y).fold(0.0, f64::max);

    // Skate and floating: contacts from each foot's own motion, against its own stance floor.
    let cycle_half = ((0.5 * cycle_s / dt).round() as usize).max(1);
    let (mut skate_sum, mut contacts) = (0.0, 0usize);
    let mut stance_sum = 0.0;
    for pts in [&feet.left, &feet.right] {
        let low: Vec<usize> = (0..n).map(|f| lowest(f, pts)).collect();
        let heights: Vec<f64> = (0..n).map(|f| at(f, low[f]).y).collect();
        let stance = stance_floors(&heights, cycle_half);
        stance_sum += stance.iter().sum::<f64>();
        for f in k..n - k {
            let j = low[f];
            let d = at(f + k, j) - at(f - k, j);
            let speed = DVec3::new(d.x, 0.0, d.z).length() / (2.0 * k as f64 * dt);
            if heights[f] - stance[f] < CONTACT_HEIGHT_M && speed < CONTACT_SPEED_M_S {
                skate_sum += speed;
                contacts += 1;
            }
        }
    }
    let floating_m = stance_sum / (2 * n) as f64 - floor;

    // Facing against travel.
    let root = layout.root();
    let half = ((0.5 * cycle_s / dt).round() as usize).max(1);
    let mut facing = Vec::new();
    for f in 0..n {
        let (a, b) = (f.saturating_sub(half), (f + half).min(n - 1));
        let travel = at(b, root) - at(a, root);
        let travel = DVec3::new(travel.x, 0.0, travel.z);
        if b - a < half || travel.length() < 1e-3 {
            continue;
        }
        let across = at(f, feet.left_hip) - at(f, feet.right_hip);
        let forward = DVec3::new(across.x, 0.0, across.z).cross(DVec3::Y);
        if forward.length() < 1e-6 {
            continue;
        }
        facing.push(motion_io::expmap::wrap_angle(
            heading(forward) - heading(travel),
        ));
    }
    let mean_facing = if facing.is_empty() {
        0.0
    } else {
        facing.iter().sum::<f64>() / facing.len() as f64
    };
    let cycle_frames = (2 * half).max(1);
    let window_means: Vec<f64> = facing
        .chunks(cycle_frames)
        .filter(|c| 2 * c.len() >= cycle_frames)
        .map(|c| c.iter().sum::<f64>() / c.len() as f64)
        .collect();
    let facing_min = window_means.iter().copied().fold(mean_facing, f64::min);
    let facing_max = window_means.iter().copied().fold(mean_facing, f64::max);

    let quality = MotionQuality {
        frames: n,
        pop_cm: pop,
        seam_pop_cm: seam_pop,
        skate_cm_s: if contacts > 0 {
            100.0 * skate_sum / contacts as f64
        } else {
            0.0
        },
        contact_share: contacts as f64 / (2 * (n - 2 * k)) as f64,
        floor_offset_cm: 100.0 * (offset_m - floor),
        float_cm: 100.0 * (float_m - floor),
        sink_cm: 100.0 * sink_m,
        floating_cm: 100.0 * floating_m,
        facing_deg: mean_facing.to_degrees(),
        facing_min_deg: facing_min.to_degrees(),
        facing_max_deg: facing_max.to_degrees(),
    };
    quality.check_finite()?;
    Ok(quality)
}

impl MotionQuality {
    /// Every figure with its field name, in declaration order (`frames` left out).
    fn figures(&self) -> [(&'static str, f64); 11] {
        [
            ("pop_cm", self.pop_cm),
            ("seam_pop_cm", self.seam_pop_cm),
            ("skate_cm_s", self.skate_cm_s),
            ("contact_share", self.contact_share),
            ("floor_offset_cm", self.floor_offset_cm),
            ("float_cm", self.float_cm),
            ("sink_cm", self.sink_cm),
            ("floating_cm", self.floating_cm),
            ("facing_deg", self.facing_deg),
            ("facing_min_deg", self.facing_min_deg),
            ("facing_max_deg", self.facing_max_deg),
        ]
    }

    /// [`QualityError::NonFiniteFigure`] naming the first figure that is NaN or infinite.
    fn check_finite(&self) -> Result<(), QualityError> {
        match self.figures().into_iter().find(|(_, v)| !v.is_finite()) {
            Some((figure, value)) => Err(QualityError::NonFiniteFigure { figure, value }),
            None => Ok(()),
        }
    }
}

/// The data's reference from per-take measurements (each `(figures, floor m, mean step length m)`,
/// measured against its own floor) and every cycle's `(step length, duration)`.
pub fn reference_from_takes(
    feet: &FootJoints,
    stature_m: Option<f64>,
    takes: &[(MotionQuality, f64, f64)],
    mut cycle_steps: Vec<(f64, f64)>,
) -> Option<QualityReference> {
    if takes.is_empty() {
        return None;
    }
    let figures: Vec<MotionQuality> = takes.iter().map(|&(q, _, _)| q).collect();
    let mut floors: Vec<f64> = takes.iter().map(|&(_, fl, _)| fl).collect();
    let percentile = |f: &dyn Fn(&MotionQuality) -> f64, q: f64| {
        let mut v: Vec<f64> = figures.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)]
    };
    let facing_range = (
        percentile(&|m| m.facing_min_deg, 0.02),
        percentile(&|m| m.facing_max_deg, 0.98),
    );
    cycle_steps.sort_by(|a, b| a.0.total_cmp(&b.0));
    let trend = |f: &dyn Fn(&MotionQuality) -> f64| {
        let points: Vec<(f64, f64)> = takes.iter().map(|&(q, _, step)| (step, f(&q))).collect();
        StepTrend::fit(&points)
    };
    let step_trends = (takes.len() >= 2).then(|| StepTrends {
        pop_cm: trend(&|q| q.pop_cm),
        skate_cm_s: trend(&|q| q.skate_cm_s),
    });
    Some(QualityReference {
        feet: feet.clone(),
        stature_m,
        takes: takes.len(),
        floor_m: median(&mut floors),
        median: MotionQuality {
            seam_pop_cm: 0.0,
            ..median_quality(&figures)
        },
        facing_range_deg: facing_range,
        cycle_steps,
        step_trends,
    })
}

/// The floor of a motion by the meter's window rule: the median over [`STEP_WINDOW_S`] windows of the
/// lowest foot point (m).
pub fn floor_of(
    layout: &PoseLayout,
    feet: &FootJoints,
    poses: &[f64],
    dt: f64,
    cycle_s: f64,
) -> Result<f64, QualityError> {
    let q = measure(layout, feet, poses, dt, Some(0.0), cycle_s, &[])?;
    Ok(q.floor_offset_cm / 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use motion_io::bvh::parse_bvh;

    /// Takes whose pop and skate grow with their step: a walk's pop and skate are the data's at its
    /// step (the Theil-Sen line, unmoved by one take far off it, clamped to the takes' range), every
    /// other figure the median of all takes; the crowd's pooled median is the median of all.
    #[test]
    fn a_walk_is_compared_with_the_data_at_its_step() {
        let take = |step: f64, pop: f64| {
            let q = MotionQuality {
                pop_cm: pop,
                skate_cm_s: step,
                contact_share: 0.5,
                ..MotionQuality::default()
            };
            (q, 0.0, step)
        };
        // 20 takes from 0.5 m to 2.4 m a cycle, every 0.1 m, pop 10 x step; one far off the line.
        let mut takes: Vec<(MotionQuality, f64, f64)> = (0..20)
            .rev()
            .map(|i| {
                let step = 0.5 + 0.1 * i as f64;
                take(step, 10.0 * step)
            })
            .collect();
        takes.push(take(1.0, 40.0));
        let steps = takes.iter().map(|&(_, _, s)| (s, 2.0 * s)).collect();
        let feet = FootJoints {
            left: vec![1],
            right: vec![2],
            left_hip: 3,
            right_hip: 4,
        };
        let r = reference_from_takes(&feet, None, &takes, steps).unwrap();
        assert!((r.median.pop_cm - 15.0).abs() < 1e-9, "{}", r.median.pop_cm);
        assert!((r.at_step(2.0).pop_cm - 20.0).abs() < 1e-9);
        assert!((r.at_step(0.5).pop_cm - 5.0).abs() < 1e-9);
        assert!((r.at_step(1.55).skate_cm_s - 1.55).abs() < 1e-9);
        // Beyond the takes: the largest and the smallest values.
        assert!((r.at_step(3.0).skate_cm_s - 2.4).abs() < 1e-9);
        assert!((r.at_step(0.1).pop_cm - 5.0).abs() < 1e-9);
        assert_eq!(r.at_step(2.0).contact_share, 0.5);
        let c = lod_policy::Controls::from_array([0.3, 0.4, 0.0, 1.7]);
        let step = f64::from(0.3f32).hypot(f64::from(0.4f32));
        assert_eq!(r.at_controls(&c), r.at_step(step));
        // Cycle durations: the median of the cycles within 10% of the step, or the 9 nearest.
        assert!((r.duration_for_step(0.5).unwrap() - 1.8).abs() < 1e-9);
        // Without trends (fewer than two takes): the pooled median.
        let pooled = QualityReference {
            step_trends: None,
            ..r.clone()
        };
        assert_eq!(pooled.at_step(2.4), pooled.median);
    }

    /// Hips -> thigh -> shin -> foot -> toe on each side, metres, feet 0.05 m above y = 0 in the rest pose.
    fn legs() -> (PoseLayout, FootJoints) {
        let leg = |side: &str, x: f64| {
            format!(
                "JOINT {side}Thigh\n{{\nOFFSET {x} 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                 JOINT {side}Shin\n{{\nOFFSET 0 -0.45 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                 JOINT {side}Foot\n{{\nOFFSET 0 -0.4 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                 JOINT {side}Toe\n{{\nOFFSET 0 0 0.1\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
                 End Site\n{{\nOFFSET 0 0 0.05\n}}\n}}\n}}\n}}\n}}\n"
            )
        };
        let text = format!(
            "HIERARCHY\nROOT Hips\n{{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n{}{}}}\nMOTION\nFrames: 1\nFrame Time: 0.0333333\n{}\n",
            leg("Left", 0.1),
            leg("Right", -0.1),
            "0 0.9 0 0 0 0 ".to_string() + &"0 ".repeat(24)
        );
        let motion = parse_bvh(&text).expect("parses");
        let layout = PoseLayout::new(&motion.skeleton, 1.0).expect("layout");
        let feet = motion_io::find_feet(&motion.skeleton, &Default::default()).expect("feet");
        (layout, FootJoints::from_feet(&feet))
    }

    /// `n` frames of the rest pose with the root at `root(f)`.
    fn track(layout: &PoseLayout, n: usize, root: impl Fn(usize) -> [f64; 3]) -> Vec<f64> {
        let rest = layout.rest_pose();
        (0..n)
            .flat_map(|f| {
                let mut p = rest.clone();
                p[0..3].copy_from_slice(&root(f));
                p
            })
            .collect()
    }

    #[test]
    fn a_gliding_body_skates_at_its_speed_and_does_not_pop() {
        let (layout, feet) = legs();
        let dt = 1.0 / 30.0;
        // Gliding forward at 0.6 m/s with both feet 5 cm above y = 0: on the floor, skating.
        let poses = track(&layout, 60, |f| [0.0, 0.9, 0.6 * f as f64 * dt]);
        let q = measure(&layout, &feet, &poses, dt, Some(0.05), 1.0, &[]).unwrap();
        assert!(q.pop_cm < 1e-9, "{q:?}");
        assert!((q.skate_cm_s - 60.0).abs() < 1e-6, "{q:?}");
        assert!(q.floor_offset_cm.abs() < 1e-9 && q.sink_cm < 1e-9, "{q:?}");
        assert!(q.facing_deg.abs() < 1e-6, "{q:?}");
        assert!(
            (q.contact_share - 1.0).abs() < 1e-12 && q.floating_cm.abs() < 1e-9,
            "{q:?}"
        );
        // Against a floor 3 cm lower the feet float 3 cm, and skate as before: contacts are found
        // from the feet's own motion, not from the floor.
        let low = measure(&layout, &feet, &poses, dt, Some(0.02), 1.0, &[]).unwrap();
        assert_eq!(low.skate_cm_s, q.skate_cm_s);
        assert_eq!(low.contact_share, q.contact_share);
        assert!((low.floating_cm - 3.0).abs() < 1e-9, "{low:?}");
        assert!((low.floor_offset_cm - 3.0).abs() < 1e-9 && (low.float_cm - 3.0).abs() < 1e-9);
        // The same body lifted by 3 cm, against the first floor: the same.
        let lifted = track(&layout, 60, |f| [0.0, 0.93, 0.6 * f as f64 * dt]);
        let up = measure(&layout, &feet, &lifted, dt, Some(0.05), 1.0, &[]).unwrap();
        assert_eq!(up.skate_cm_s, q.skate_cm_s);
        assert!((up.floating_cm - 3.0).abs() < 1e-9, "{up:?}");
    }

    #[test]
    fn a_foot_faster_than_the_contact_speed_is_not_in_contact() {
        let (layout, feet) = legs();
        let dt = 1.0 / 30.0;
        for (speed, contact) in [(0.95, true), (1.05, false)] {
            let poses = track(&layout, 60, |f| [speed * f as f64 * dt, 0.9, 0.0]);
            let q = measure(&layout, &feet, &poses, dt, Some(0.05), 1.0, &[]).unwrap();
            if contact {
                assert!((q.skate_cm_s - 100.0 * speed).abs() < 1e-6, "{q:?}");
                assert!((q.contact_share - 1.0).abs() < 1e-12, "{q:?}");
            } else {
                assert_eq!((q.skate_cm_s, q.contact_share), (0.0, 0.0), "{q:?}");
            }
        }
    }

    #[test]
    fn the_stance_floor_follows_a_motion_that_changes_height() {
        let (layout, feet) = legs();
        let dt = 1.0 / 30.0;
        // Gliding at 0.3 m/s, 3 cm higher from frame 60 of 120: with one floor for the whole motion
        // the raised half would lose its contacts; the one-cycle stance floor follows it.
        let poses = track(&layout, 120, |f| {
            let lift = if f >= 60 { 0.03 } else { 0.0 };
            [0.0, 0.9 + lift, 0.3 * f as f64 * dt]
        });
        let q = measure(&layout, &feet, &poses, dt, Some(0.05), 1.0, &[]).unwrap();
        assert!((q.skate_cm_s - 30.0).abs() < 1e-6, "{q:?}");
        // Only the frames whose window still holds more than its 10% of low frames lose contact.
        assert!(q.contact_share > 0.85, "{q:?}");
        assert!(q.floating_cm > 1.0 && q.floating_cm < 2.0, "{q:?}");
    }

    #[test]
    fn stance_floors_are_the_windowed_quantile() {
        // 21 heights 0..=20 cm: a window of 11 frames, rank round(0.1 * 10) = 1: its second lowest.
        let h: Vec<f64> = (0..21).map(|i| f64::from(i) * 0.01).collect();
        let s = stance_floors(&h, 5);
        assert_eq!(s.len(), 21);
        for (f, &v) in s.iter().enumerate() {
            let start = f.saturating_sub(5).min(21 - 11);
            assert!((v - (start + 1) as f64 * 0.01).abs() < 1e-12, "{f}: {v}");
        }
        // Fewer frames than the window: one window, the whole motion.
        assert_eq!(stance_floors(&[0.3, 0.1, 0.2], 5), vec![0.1; 3]);
        assert_eq!(stance_floors(&[], 5), Vec::<f64>::new());
    }

    #[test]
    fn a_jump_at_a_seam_is_a_seam_pop_at_any_frame_rate() {
        let (layout, feet) = legs();
        for fps in [30.0, 120.0] {
            let dt = 1.0 / fps;
            let seam = (1.0 / dt) as usize;
            // The body jumps 6 cm sideways at the seam.
            let poses = track(&layout, 2 * seam, |f| {
                [if f >= seam { 0.06 } else { 0.0 }, 0.9, 0.0]
            });
            let q = measure(&layout, &feet, &poses, dt, Some(0.05), 1.0, &[seam]).unwrap();
            // Second difference over the 30 fps step: 6 cm.
            assert!((q.pop_cm - 6.0).abs() < 1e-6, "{fps}: {q:?}");
            assert_eq!(q.seam_pop_cm, q.pop_cm);
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let (layout, feet) = legs();
        let poses = track(&layout, 10, |_| [0.0, 0.9, 0.0]);
        assert!(matches!(
            measure(&layout, &feet, &poses[1..], 0.1, None, 1.0, &[]),
            Err(QualityError::Shape { .. })
        ));
        assert!(measure(&layout, &feet, &poses, 0.0, None, 1.0, &[]).is_err());
        assert!(matches!(
            measure(
                &layout,
                &feet,
                &poses[..2 * layout.dof()],
                1.0 / 120.0,
                None,
                1.0,
                &[]
            ),
            Err(QualityError::TooShort { .. })
        ));
        let mut nan = poses.clone();
        nan[3 * layout.dof() + 8] = f64::NAN;
        assert_eq!(
            measure(&layout, &feet, &nan, 0.1, None, 1.0, &[]),
            Err(QualityError::NonFinite(3))
        );
    }
}
