//! The model as the shaders read it: one f32 array (controls, kriging projections, cores,
//! factors, rig), one table of integers (levels, keys, rig structure) and the WGSL constants that
//! size the shaders' arrays.

use lod_policy::{
    ControlRange, Controls, JointRole, RuntimeModel, StyleMix, VariogramModel, offline,
};

use crate::error::GpuError;

/// The compute shaders, before the model's constants are prepended.
const SHADER: &str = include_str!("shaders/crowd.wgsl");

/// Largest number of entries of a tabulated policy (visible and hidden together).
pub(crate) const POLICY_MAX: usize = 256;

/// Largest rig the shaders take (joints held in registers per walker).
const MAX_RIG_JOINTS: usize = 256;

/// What the shaders' seam inertialization takes from the crowd's config.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SeamParams {
    /// Accuracy levels whose clip changes are inertialized (`CrowdConfig::seam_levels`, at most
    /// `u32::MAX`); 0: none, and the seam passes are not run.
    pub levels: u32,
    /// The spring's decay rate `2 ln 2 / halflife` (1/s), as `lod_policy::SeamTransition::new`.
    pub decay: f32,
}

impl SeamParams {
    pub fn new(seam_levels: usize, halflife_s: f32) -> SeamParams {
        SeamParams {
            levels: u32::try_from(seam_levels).unwrap_or(u32::MAX),
            decay: 2.0 * std::f32::consts::LN_2 / halflife_s.max(1e-3),
        }
    }
}

/// Floats of foot lock state in a joint slot (`crowd.wgsl`'s `2 FOOT_FLOATS`): per foot the previous
/// ground points (8, double-floats), flags, the contact's clock and lowest height, the correction
/// and its rate, both at lift-off (12), the clock since lift-off, the lift, the lift at touchdown and
/// the clock since touchdown.
pub(crate) const LOCK_FLOATS: usize = 2 * 27;

/// The packed model and the shader source for it.
#[derive(Debug, Clone)]
pub(crate) struct Tables {
    pub md: Vec<f32>,
    pub mtab: Vec<u32>,
    pub source: String,
    /// Pose rows `P`, aligned frames `T`, largest `r_T`, `r_T` of the last level.
    pub p: usize,
    pub t: usize,
    pub rt_max: usize,
    pub rt_last: usize,
    /// Rotating joints.
    pub joints: usize,
    pub levels: usize,
    /// Accuracy levels whose visible walkers lock their feet (`CrowdConfig::foot_lock_levels`,
    /// at most `u32::MAX`): 0 when the config asks for none or the model has no feet (as the CPU
    /// source, which locks nothing then); with 0 the shaders hold no lock state.
    pub lock_levels: u32,
    /// Bytes of workgroup memory the build pass declares.
    pub workgroup_bytes: u64,
}

/// A finite `v` as a WGSL `f32` literal that every WGSL compiler takes: the shortest decimal that
/// reads back as `v` (Rust's `{:?}`), except for the largest finite values, whose shortest decimal
/// (`3.4028235e38`) lies beyond them; Tint, Chromium's compiler, refuses a literal beyond the
/// largest f32 (naga rounds it), so those are written exactly, in hexadecimal.
pub(crate) fn wgsl_f32(v: f32) -> String {
    if v.abs() == f32::MAX {
        let sign = if v < 0.0 { "-" } else { "" };
        format!("{sign}0x1.fffffep+127f")
    } else {
        format!("{v:?}")
    }
}

fn push(md: &mut Vec<f32>, v: &[f32]) -> usize {
    let off = md.len();
    md.extend_from_slice(v);
    off
}

impl Tables {
    /// Packs `model` with the style rows `styles` (each `d - 4` values: the normalised style part of
    /// the control vector of a walker of that style id).
    /// `seam` sets the seam constants of the shaders, `foot_lock_levels` the foot lock's
    /// (`CrowdConfig::foot_lock_levels`; no lock when the model has no feet).
    pub fn new(
        model: &RuntimeModel,
        styles: &[Vec<f32>],
        seam: SeamParams,
        foot_lock_levels: usize,
    ) -> Result<Tables, GpuError> {
        let lod = model.lod();
        let rig = model.rig();
        let parts = lod.parts();
        let (p, t, s, d) = (lod.p(), lod.t(), lod.s(), lod.d());
        if d < Controls::COUNT {
            return Err(GpuError::Model(format!(
                "{d} controls; a walk model has at least 4"
            )));
        }
        if rig.joint_count() > MAX_RIG_JOINTS {
            return Err(GpuError::Model(format!(
                "{} rig joints; the GPU crowd takes at most {MAX_RIG_JOINTS}",
                rig.joint_count()
            )));
        }
        if t < 2 {
            return Err(GpuError::Model(format!(
                "T = {t} aligned frames; at least 2 are needed"
            )));
        }
        let cs = lod.controls();
        let range: ControlRange = cs
            .range()
            .ok_or_else(|| GpuError::Model("the control space is not a walk's".into()))?;
        let mut md = Vec::new();
        let (lo, hi) = (range.min.to_array(), range.max.to_array());
        let range_off = push(&mut md, &lo);
        push(&mut md, &hi);
        let cs_min = push(&mut md, &cs.min);
        let cs_max = push(&mut md, &cs.max);
        let cs_scale = push(&mut md, &cs.scale);
        let cs_offset = push(&mut md, &cs.offset);
        let cs_samples = push(&mut md, &cs.samples);
        let has_implied = cs.implied.len() == d * (d + 1);
        let cs_implied = push(&mut md, if has_implied { &cs.implied } else { &[] });
        let style_off = md.len();
        for row in styles {
            debug_assert_eq!(row.len(), d - Controls::COUNT);
            md.extend_from_slice(row);
        }
        md.push(0.0);
        let rig_f = md.len();
        for j in rig.joints() {
            md.extend_from_slice(&j.offset.to_array());
            md.extend_from_slice(&j.rest.to_array());
        }
        // The rest rows joints fade to and from at seams (what `motion_lod`'s sources give as
        // `ClipSource::rest_rows`: each rotating joint's rest rotation as an exponential map,
        // computed in f64, here from the rig's f32 rest rotation).
        let rest_rows = md.len();
        md.resize(rest_rows + p, 0.0);
        for j in rig.joints() {
            if let JointRole::Rotating(k) = j.role {
                let r = lod_policy::ALWAYS_ROWS + 3 * k;
                if r + 3 <= p {
                    let e = quat_to_exp(j.rest.as_dquat());
                    md[rest_rows + r..rest_rows + r + 3].copy_from_slice(&e.as_vec3().to_array());
                }
            }
        }
        let mut mtab: Vec<u32> = Vec::new();
        let levels_off = 0usize;
        for lv in lod.levels() {
            mtab.extend([lv.key, lv.ranks.p, lv.ranks.t, lv.ranks.s].map(|v| v as u32));
        }
        let keys_off = mtab.len();
        for key in lod.keys() {
            let r = key.ranks;
            let off_core = push(&mut md, &key.core);
            let off_up = push(&mut md, &key.u_p);
            let off_ut = md.len();
            for j in 0..t {
                for b in 0..r.t {
                    md.push(key.u_t[j + t * b]);
                }
            }
            // A = Q_top - V P_C (the runtime's folded projection), in f64, stored transposed.
            let off_a = md.len();
            let n = s + 1;
            md.resize(off_a + 2 * n * r.s, 0.0);
            for l in 0..r.s {
                for jj in 0..n {
                    let mut acc = f64::from(key.projection[l + r.s * jj]);
                    for m in 0..=d {
                        acc -= f64::from(key.trend[l + r.s * m])
                            * f64::from(cs.projection[m + (d + 1) * jj]);
                    }
                    let hi = acc as f32;
                    md[off_a + jj * r.s + l] = hi;
                    md[off_a + n * r.s + jj * r.s + l] = (acc - f64::from(hi)) as f32;
                }
            }
            let off_v = push(&mut md, &key.trend);
            mtab.extend([r.p, r.t, r.s, off_core, off_up, off_ut, off_a, off_v].map(|v| v as u32));
        }
        if md.len() >= 1 << 31 {
            return Err(GpuError::Model(
                "the model holds more than 2^31 values".into(),
            ));
        }
        let rig_off = mtab.len();
        for j in rig.joints() {
            let (role, k) = match j.role {
                JointRole::Outside => (0, 0),
                JointRole::Root => (1, 0),
                JointRole::Rotating(k) => (2, k),
                JointRole::Static => (3, 0),
            };
            mtab.extend([role, k as u32, j.parent.unwrap_or(0) as u32, 0]);
        }
        let rotating_off = mtab.len();
        mtab.extend(rig.rotating_joints().iter().map(|&j| j as u32));
        mtab.push(0);
        while mtab.len() % 4 != 0 {
            mtab.push(0);
        }
        let levels = lod.levels();
        let rt_max = lod.max_ranks().t;
        let rs_max = lod.max_ranks().s;
        let last = levels.len() - 1;
        let rt_last = levels[last].ranks.t;
        let k_max = levels
            .iter()
            .map(|l| l.ranks.p * l.ranks.t)
            .max()
            .unwrap_or(1);
        let v = cs.variogram;
        let model_id = match v.model {
            VariogramModel::Linear => 0,
            VariogramModel::Power => 1,
            VariogramModel::Spherical => 2,
            VariogramModel::Exponential => 3,
            VariogramModel::Gaussian => 4,
        };
        // The model's numbers that become the shaders' f32 constants must be finite as f32 (an
        // overflowing one would read `inf` in the source, which does not compile).
        // (The range and the exponent only where the variogram's model reads them; elsewhere
        // an unused value is written as 1.)
        let inv_time_scale = 1.0 / parts.time_scale;
        let stature = f64::from(model.stature_m().unwrap_or(0.0));
        let range_used = model_id >= 2;
        let exponent_used = model_id == 1;
        let fits = |x: f64| (x as f32).is_finite();
        for (what, x, used) in [
            ("the variogram's nugget", v.nugget, true),
            ("the variogram's sill", v.sill, true),
            ("the variogram's range", v.range, range_used),
            ("the variogram's exponent", v.exponent, exponent_used),
            ("1 / the time scale", inv_time_scale, true),
            ("the stature (m)", stature, true),
        ] {
            if used && !fits(x) {
                return Err(GpuError::Model(format!(
                    "{what} is {x:e}, beyond single precision (the shaders compute in f32 and \
                     pairs of f32)"
                )));
            }
        }
        let lit = |x: f64| wgsl_f32(x as f32);
        // A double-float constant: the f64 value as a high and a low f32.
        let df = |x: f64| {
            let hi = x as f32;
            format!(
                "vec2<f32>({}, {})",
                wgsl_f32(hi),
                wgsl_f32((x - f64::from(hi)) as f32)
            )
        };
        let consts = [
            ("POLICY_MAX", format!("{POLICY_MAX}u")),
            ("META_VEC4", format!("{}u", mtab.len() / 4)),
            ("RANGE_OFF", format!("{range_off}u")),
            ("D_MAX1", format!("{}u", d + 1)),
            ("D_MAX", format!("{d}u")),
            ("D", format!("{d}u")),
            ("S1", format!("{}u", s + 1)),
            ("S", format!("{s}u")),
            ("RS_MAX", format!("{rs_max}u")),
            ("K_MAX", format!("{k_max}u")),
            ("GROOT_MAX", format!("{}u", 7 * rt_max)),
            ("T", format!("{t}u")),
            ("P", format!("{p}u")),
            ("RT_MAX", format!("{rt_max}u")),
            ("RT_LAST", format!("{rt_last}u")),
            ("VG_MODEL", format!("{model_id}u")),
            ("VG_NUGGET", df(v.nugget)),
            ("VG_SILL", df(v.sill)),
            (
                "VG_RANGE",
                df(if v.range > 0.0 && fits(v.range) {
                    v.range
                } else {
                    1.0
                }),
            ),
            (
                "VG_EXPONENT",
                df(if fits(v.exponent) { v.exponent } else { 1.0 }),
            ),
            ("CS_MIN", format!("{cs_min}u")),
            ("CS_MAX", format!("{cs_max}u")),
            ("CS_SCALE", format!("{cs_scale}u")),
            ("CS_OFFSET", format!("{cs_offset}u")),
            ("CS_SAMPLES", format!("{cs_samples}u")),
            ("CS_IMPLIED", format!("{cs_implied}u")),
            ("HAS_IMPLIED", format!("{}u", u32::from(has_implied))),
            ("STYLE_OFF", format!("{style_off}u")),
            ("LEVELS", format!("{levels_off}u")),
            ("KEYS", format!("{keys_off}u")),
            ("INV_TIME_SCALE", df(inv_time_scale)),
            ("MIN_INCREMENT", df(lod_policy::MIN_INCREMENT)),
            ("STATURE", lit(stature)),
            ("LAST_LEVEL", format!("{last}u")),
            ("LEVEL_COUNT", format!("{}u", levels.len())),
            ("HIST_BINS", format!("{}u", levels.len() + 1)),
            ("NJ", format!("{}u", rig.joint_count())),
            ("RIG_F", format!("{rig_f}u")),
            ("RIG", format!("{rig_off}u")),
            ("ROOT_JOINT", format!("{}u", rig.root())),
            ("ROTATING", format!("{rotating_off}u")),
            ("REST_ROWS", format!("{rest_rows}u")),
            ("SEAM_LEVELS", format!("{}u", seam.levels)),
            ("SEAM_DECAY", format!("{:?}", seam.decay)),
            ("SEAM_STEP", format!("{:?}", lod_policy::SEAM_STEP_S)),
        ];
        // The foot lock: the legs of the model's feet (thigh, knee, ankle, toe or the ankle; the
        // thigh, knee and ankle's rotating indices and the thigh's parent), the joints up to the
        // last one its forward kinematics needs, and its state after the clip and the seam state.
        let lock = if foot_lock_levels > 0 {
            model.feet().map(|feet| lock_legs(rig, feet)).transpose()?
        } else {
            None
        };
        let lock_levels = if lock.is_some() {
            u32::try_from(foot_lock_levels).unwrap_or(u32::MAX)
        } else {
            0
        };
        let (legs, leg_rows, lock_nj) =
            lock.map_or(([[0; 4]; 2], [[0; 4]; 2], 0), |l| (l.legs, l.rows, l.nj));
        let seam_floats = if seam.levels > 0 { 3 * p + 3 } else { 0 };
        let lock_off = p * rt_max + 2 * t + seam_floats;
        let floor = model.feet().map_or(0.0, |f| f.floor_m);
        let release_g = 2.0 * std::f32::consts::LN_2 / (0.25 * offline::RELEASE_S);
        let consts_lock = [
            ("LOCK_LEVELS", format!("{lock_levels}u")),
            ("LOCK_OFF", format!("{lock_off}u")),
            ("LOCK_NJ", format!("{lock_nj}u")),
            ("LOCK_FLOOR", format!("{floor:?}")),
            ("LOCK_HEIGHT", format!("{:?}", offline::LOCK_HEIGHT_M)),
            ("LOCK_SPEED", format!("{:?}", offline::LOCK_SPEED_M_S)),
            ("LOCK_RELEASE", format!("{:?}", offline::RELEASE_S)),
            ("LOCK_RELEASE_G", format!("{release_g:?}")),
            ("LOCK_ONSET", format!("{:?}", offline::ONSET_S)),
            (
                "LOCK_TELEPORT",
                format!("{:?}", offline::TELEPORT_SPEED_M_S),
            ),
            ("LOCK_SOFT_REACH", format!("{:?}", offline::SOFT_REACH)),
            ("LOCK_MAX_REACH", format!("{:?}", offline::MAX_REACH)),
            ("LOCK_POLE_WEIGHT", format!("{:?}", offline::POLE_WEIGHT)),
            (
                "LOCK_GROUND_MARGIN",
                format!("{:?}", offline::GROUND_MARGIN_M),
            ),
        ];
        let vec4s = |rows: [[u32; 4]; 2]| {
            let v = rows.map(|r| format!("vec4<u32>({}u, {}u, {}u, {}u)", r[0], r[1], r[2], r[3]));
            format!("array<vec4<u32>, 2>({}, {})", v[0], v[1])
        };
        let mut source = String::from("// Model constants (gpu-crowd tables.rs).\n");
        source.push_str(&format!(
            "const LOCK_LEGS: array<vec4<u32>, 2> = {};\n",
            vec4s(legs)
        ));
        source.push_str(&format!(
            "const LOCK_LEG_ROWS: array<vec4<u32>, 2> = {};\n",
            vec4s(leg_rows)
        ));
        let consts = consts.into_iter().chain(consts_lock);
        for (name, value) in consts {
            let ty = if value.ends_with('u') {
                "u32"
            } else if value.starts_with("vec2") {
                "vec2<f32>"
            } else {
                "f32"
            };
            source.push_str(&format!("const {name}: {ty} = {value};\n"));
        }
        source.push_str(crate::df::DF_WGSL);
        // The walker struct is the one engines' shaders read (`CrowdWalker`, `Walker` here).
        source.push_str(crate::DRAW_WGSL);
        source.push_str(SHADER);
        let workgroup_bytes = 4
            * (12 + 1 + d + 2 * (d + 1) + 2 * (s + 1) + rs_max + k_max + 7 * rt_max + 2 * t) as u64;
        Ok(Tables {
            md,
            mtab,
            source,
            p,
            t,
            rt_max,
            rt_last,
            joints: lod.joints(),
            levels: levels.len(),
            lock_levels,
            workgroup_bytes,
        })
    }
}

/// The exponential map of a unit quaternion, `theta` in `[0, pi]` (`motion_io`'s `quat_to_exp`,
/// which gives the CPU sources' rest rows).
fn quat_to_exp(q: glam::DQuat) -> glam::DVec3 {
    let q = if q.w < 0.0 { -q } else { q };
    let v = glam::DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s < 1e-12 {
        return 2.0 * v;
    }
    v * (2.0 * s.atan2(q.w) / s)
}

/// The style part (`d - 4` values, normalised) of the control vector of a walker of `style`.
pub(crate) fn style_row(model: &RuntimeModel, style: StyleMix) -> Result<Vec<f32>, GpuError> {
    let mut values = [0.0f32; lod_policy::CONTROL_VALUES];
    let c = Controls::from_array([0.0, 1.0, 0.0, 1.7]).with_style(style);
    let d = model
        .lod()
        .control_vector(&c, &mut values)
        .map_err(|e| GpuError::Config(format!("style: {e}")))?;
    Ok(values[Controls::COUNT..d].to_vec())
}

/// The legs of a foot rig as the shaders' foot lock takes them (`LOCK_LEGS`, `LOCK_LEG_ROWS`,
/// `LOCK_NJ`).
struct LockLegs {
    /// Per leg (left, right) the joints: thigh, knee, ankle, toe (the ankle again without one).
    legs: [[u32; 4]; 2],
    /// Per leg the rotating indices of thigh, knee and ankle, and the thigh's parent joint
    /// (`u32::MAX`: none).
    rows: [[u32; 4]; 2],
    /// The joints up to the last one the lock's forward kinematics needs (the feet's points and
    /// their ancestors, the root).
    nj: usize,
}

/// The legs of `feet` on `rig` for the shaders' foot lock. Feet that do not fit the rig are refused
/// ([`lod_policy::FootRig::check`]; a loaded model's always fit).
fn lock_legs(rig: &lod_policy::Rig, feet: &lod_policy::FootRig) -> Result<LockLegs, GpuError> {
    feet.check(rig).map_err(GpuError::Model)?;
    let joints = rig.joints();
    let mut legs = [[0u32; 4]; 2];
    let mut rows = [[0u32; 4]; 2];
    let mut last = rig.root();
    for (f, foot) in [feet.left, feet.right].iter().enumerate() {
        let ankle = foot.ankle;
        // `check` found both parents and the three rotating.
        let knee = joints[ankle].parent.unwrap_or(0);
        let thigh = joints[knee].parent.unwrap_or(0);
        let toe = foot.toe.unwrap_or(ankle);
        legs[f] = [thigh, knee, ankle, toe].map(|j| j as u32);
        let k = |j: usize| match joints[j].role {
            JointRole::Rotating(k) => k as u32,
            _ => u32::MAX,
        };
        rows[f] = [
            k(thigh),
            k(knee),
            k(ankle),
            joints[thigh].parent.map_or(u32::MAX, |p| p as u32),
        ];
        last = last.max(ankle).max(toe);
    }
    Ok(LockLegs {
        legs,
        rows,
        nj: last + 1,
    })
}

#[cfg(test)]
mod tests {
    use super::wgsl_f32;

    #[test]
    fn the_largest_floats_are_written_exactly_and_others_shortest() {
        assert_eq!(wgsl_f32(f32::MAX), "0x1.fffffep+127f");
        assert_eq!(wgsl_f32(-f32::MAX), "-0x1.fffffep+127f");
        // The shortest decimal of f32::MAX is beyond it (why it is not used).
        assert!("3.4028235e38".parse::<f64>().unwrap() > f64::from(f32::MAX));
        for v in [
            0.0f32,
            1.5,
            -2.25e-7,
            6.2831855,
            f32::MIN_POSITIVE,
            3.4028233e38,
        ] {
            let s = wgsl_f32(v);
            assert_eq!(s.parse::<f32>().unwrap().to_bits(), v.to_bits(), "{s}");
            assert!(
                s.parse::<f64>().unwrap().abs() <= f64::from(f32::MAX),
                "{s}"
            );
        }
    }
}
