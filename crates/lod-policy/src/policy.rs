//! Level-of-detail policies: which [`Detail`] a character gets from its distance to the camera
//! (section 5.1's schedule) or from its projected error on screen.

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::detail::Detail;
use crate::model::LodModel;

/// Camera parameters a policy may use.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ViewParams {
    /// Vertical field of view in radians.
    pub fov_y_radians: f32,
    /// Image height in pixels.
    pub image_height_px: f32,
}

impl Default for ViewParams {
    /// 60 degrees vertical field of view, 1080 pixels.
    fn default() -> Self {
        ViewParams {
            fov_y_radians: std::f32::consts::FRAC_PI_3,
            image_height_px: 1080.0,
        }
    }
}

impl ViewParams {
    /// Metres per pixel at `distance_m` on the view axis: `2 d tan(fov_y / 2) / H`, so that an
    /// error of `e` metres covers `e / metres_per_pixel` pixels.
    pub fn metres_per_pixel(&self, distance_m: f32) -> f32 {
        2.0 * distance_m * (0.5 * self.fov_y_radians).tan() / self.image_height_px
    }
}

/// Factor on the measured errors in both policies' screen checks. The error tables hold maxima over
/// the controls the build measured (48 training samples and the quality grid); controls between
/// them can do worse, the foot slide most (a threshold measure: up to 1.23x the stored maximum at
/// midpoints between training samples in `motion-lod`'s `tests/quality.rs` on Bandai, 1.04x on the
/// embedded data), so a detail must fit the budget with this much to spare.
pub const ERROR_MARGIN: f32 = 1.5;

/// A rule that maps a character's distance and visibility to a level of detail: the one policy
/// trait of the runtime, used by engines and by the crowd (`crowd-sim`). Any
/// `Fn(f32, bool, &ViewParams) -> Detail` closure is a policy.
pub trait LevelPolicy {
    /// Detail for a character `distance_m` metres from the camera; `visible` is false outside
    /// the view frustum (then only the root is evaluated).
    fn detail(&self, distance_m: f32, visible: bool, view: &ViewParams) -> Detail;
}

impl<F> LevelPolicy for F
where
    F: Fn(f32, bool, &ViewParams) -> Detail,
{
    fn detail(&self, distance_m: f32, visible: bool, view: &ViewParams) -> Detail {
        self(distance_m, visible, view)
    }
}

/// Full detail for every character, visible or not: the baseline without level of detail.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct FullDetail {
    detail: Detail,
}

impl FullDetail {
    /// Full detail of `model` ([`LodModel::full_detail`]) for every character.
    pub fn for_model(model: &LodModel) -> FullDetail {
        FullDetail {
            detail: model.full_detail(),
        }
    }
}

impl LevelPolicy for FullDetail {
    fn detail(&self, _distance_m: f32, _visible: bool, _view: &ViewParams) -> Detail {
        self.detail
    }
}

/// Why a policy could not be built.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PolicyError {
    /// A configuration value is out of its domain.
    #[error("policy configuration: {name} = {value} must be {rule}")]
    Config {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: f32,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// A level table without levels or with decreasing keys.
    #[error("a level table needs at least one level and non-decreasing keys")]
    LevelKeys,
    /// The model has no measured error table for its accuracy levels.
    #[error("the model has no per-level error table (the screen-space policy needs one)")]
    NoErrorTable,
    /// A deserialised policy is inconsistent (its tables disagree in length, hold NaN or negative
    /// errors, or its costs overflow): deserialising re-runs the checks of the constructors.
    #[error("policy data: {0}")]
    Data(String),
}

/// Distances of the [`DistancePolicy`] (paper defaults, section 5.1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DistanceConfig {
    /// Full detail below this distance (30 m).
    pub near_m: f32,
    /// One key level more every this many metres beyond `near_m` (50 m).
    pub key_step_m: f32,
    /// `joints_per_step` joints fewer every this many metres beyond `near_m` (10 m).
    pub joint_step_m: f32,
    /// Joints dropped per joint step (1 joint = 3 DOF).
    pub joints_per_step: usize,
    /// The screen check (beyond the paper; default 1 px): where the schedule's level and joint
    /// count would show more than this many pixels of pose error or foot slide (the model's
    /// measured [`LevelError`](crate::model::LevelError)s, shell metric, projected at the
    /// character's distance with the frame's [`ViewParams`]), the policy takes the finest detail
    /// below it that stays within budget instead. `None`: the paper's schedule as published. A
    /// model without error tables is not checked.
    pub screen_budget_px: Option<f32>,
}

impl Default for DistanceConfig {
    fn default() -> Self {
        DistanceConfig {
            near_m: 30.0,
            key_step_m: 50.0,
            joint_step_m: 10.0,
            joints_per_step: 1,
            screen_budget_px: Some(1.0),
        }
    }
}

/// The paper's distance schedule.
///
/// With `x = (distance - near) / key_step`: below `near` the most accurate level and every joint;
/// key group `g` (the `g`-th run of consecutive accuracy levels sharing one key) occupies
/// `x in [g, g + 1)`, its `n_g` levels spread evenly over it (level `i` of the group from
/// `x = g + i / n_g`), so one more key level is reached every `key_step` metres. Past the last
/// group (`x >= number of groups`) or outside the view: root only. Joints: all below `near`, then
/// `joints_per_step` fewer every `joint_step` metres (never below zero).
///
/// With the screen check ([`DistanceConfig::screen_budget_px`]), the scheduled `(level, joints)` must
/// satisfy `m (e_l + e_J(joints)) / metres_per_pixel(distance) <= budget`, where `m` is
/// [`ERROR_MARGIN`] and `e_l` and `e_J` are the measured
/// [visible errors](crate::model::LevelError::visible_m) of the level and the joint count
/// (`e_J` made non-increasing in the joint count, as in [`ScreenSpacePolicy`]). Otherwise the
/// policy takes the cheapest detail that fits and is nowhere coarser than the schedule's: among the
/// levels `l <= level` and joint counts `j >= joints`, the one with the smallest cost (as in
/// [`ScreenSpacePolicy`]: a cycle's kernel and poses); if none fits, level 0 with every joint. An
/// accuracy level whose measured motion quality fails ([`LevelError::passes_quality`]: it pops or
/// skates beyond the near-character thresholds on the quality grid) never fits; it serves only
/// root-only walkers.
///
/// [`LevelError::passes_quality`]: crate::model::LevelError::passes_quality
///
/// Serialises as its fields; deserialising re-runs the constructors' checks
/// ([`PolicyError::Config`], [`PolicyError::Data`]). In a human-readable format (JSON) an infinite
/// error is written as the string `"inf"` (JSON has no infinity; `null` also reads as infinity);
/// binary formats keep the plain floats.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawDistancePolicy")]
pub struct DistancePolicy {
    config: DistanceConfig,
    /// Fractional key-group position of each accuracy level (non-decreasing).
    positions: Vec<f32>,
    groups: usize,
    joints: usize,
    /// Visible error (m) per accuracy level (infinite for a level whose motion quality fails);
    /// empty without an error table or a screen check.
    #[serde(with = "float_text")]
    level_err_m: Vec<f32>,
    /// Non-increasing visible error (m) per active joint count `0..=J` (empty likewise).
    #[serde(with = "float_text")]
    joint_err_m: Vec<f32>,
    /// Cost of each detail (empty likewise).
    costs: DetailCosts,
}

/// [`DistancePolicy`]'s fields as stored (the same names and order, so the same bytes), checked
/// by `TryFrom` before they become a policy.
#[derive(Deserialize)]
struct RawDistancePolicy {
    config: DistanceConfig,
    positions: Vec<f32>,
    groups: usize,
    joints: usize,
    #[serde(with = "float_text")]
    level_err_m: Vec<f32>,
    #[serde(with = "float_text")]
    joint_err_m: Vec<f32>,
    costs: DetailCosts,
}

impl TryFrom<RawDistancePolicy> for DistancePolicy {
    type Error = PolicyError;
    fn try_from(raw: RawDistancePolicy) -> Result<Self, PolicyError> {
        DistancePolicy::check(&raw.config)?;
        let data = |m: String| PolicyError::Data(m);
        let p = &raw.positions;
        if p.is_empty()
            || p.iter().any(|x| !(x.is_finite() && *x >= 0.0))
            || p.windows(2).any(|w| w[1] < w[0])
        {
            return Err(data(
                "positions must be a non-empty, non-decreasing list of finite values >= 0".into(),
            ));
        }
        if raw.groups == 0 || p[p.len() - 1] >= raw.groups as f32 {
            return Err(data(format!(
                "groups = {} must exceed every position (the last is {})",
                raw.groups,
                p[p.len() - 1]
            )));
        }
        if raw.level_err_m.is_empty() {
            if !raw.joint_err_m.is_empty() {
                return Err(data(
                    "joint_err_m must be empty when level_err_m is (no screen check)".into(),
                ));
            }
        } else {
            if raw.level_err_m.len() != p.len() {
                return Err(data(format!(
                    "level_err_m holds {} levels, positions {}",
                    raw.level_err_m.len(),
                    p.len()
                )));
            }
            check_tables(&raw.level_err_m, &raw.joint_err_m, raw.joints, &raw.costs)
                .map_err(data)?;
        }
        Ok(DistancePolicy {
            config: raw.config,
            positions: raw.positions,
            groups: raw.groups,
            joints: raw.joints,
            level_err_m: raw.level_err_m,
            joint_err_m: raw.joint_err_m,
            costs: raw.costs,
        })
    }
}

/// The error and cost tables of a deserialised policy: `level_err` and the costs one entry per
/// level, `joint_err` one per joint count `0..=joints`, non-increasing, errors not NaN and `>= 0`
/// (infinity allowed), and every cost computable without overflow.
fn check_tables(
    level_err: &[f32],
    joint_err: &[f32],
    joints: usize,
    costs: &DetailCosts,
) -> Result<(), String> {
    let levels = level_err.len();
    if levels == 0 {
        return Err("level_err_m is empty".into());
    }
    if Some(joint_err.len()) != joints.checked_add(1) {
        return Err(format!(
            "joint_err_m holds {} entries for {joints} joints (one per joint count 0..=joints)",
            joint_err.len()
        ));
    }
    if let Some(e) = level_err
        .iter()
        .chain(joint_err)
        .find(|e| e.is_nan() || **e < 0.0)
    {
        return Err(format!("an error is {e} (errors are >= 0, not NaN)"));
    }
    if joint_err.windows(2).any(|w| w[1] > w[0]) {
        return Err("joint_err_m must not increase with the joint count".into());
    }
    if costs.level_base_cost.len() != levels || costs.level_row_cost.len() != levels {
        return Err(format!(
            "costs hold {} and {} levels, the error table {levels}",
            costs.level_base_cost.len(),
            costs.level_row_cost.len()
        ));
    }
    // The largest cost of each level (every joint) fits, so every smaller one does.
    for l in 0..levels {
        if costs.checked_cost(l, joints).is_none() {
            return Err(format!(
                "the cost of level {l} with {joints} joints overflows"
            ));
        }
    }
    Ok(())
}

/// Serde helper for the policies' error tables: in a human-readable format each entry is a
/// number, or the string `"inf"`, `"-inf"` or `"NaN"` for a value JSON cannot hold (reading
/// also takes `null` as infinity, what `serde_json` wrote before); in a binary format a plain
/// sequence of `f32` (the same bytes as without this helper).
mod float_text {
    use serde::de::{self, Deserializer, SeqAccess, Visitor};
    use serde::ser::Serializer;
    use serde::{Deserialize, Serialize};

    struct Text(f32);

    impl Serialize for Text {
        fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
            let v = self.0;
            if v.is_finite() {
                s.serialize_f32(v)
            } else if v.is_nan() {
                s.serialize_str("NaN")
            } else if v > 0.0 {
                s.serialize_str("inf")
            } else {
                s.serialize_str("-inf")
            }
        }
    }

    struct Entry(f32);

    impl<'de> Deserialize<'de> for Entry {
        fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Entry, D::Error> {
            struct V;
            impl Visitor<'_> for V {
                type Value = Entry;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("a number, \"inf\", \"-inf\", \"NaN\" or null")
                }
                fn visit_f64<E: de::Error>(self, v: f64) -> Result<Entry, E> {
                    Ok(Entry(v as f32))
                }
                fn visit_f32<E: de::Error>(self, v: f32) -> Result<Entry, E> {
                    Ok(Entry(v))
                }
                fn visit_i64<E: de::Error>(self, v: i64) -> Result<Entry, E> {
                    Ok(Entry(v as f32))
                }
                fn visit_u64<E: de::Error>(self, v: u64) -> Result<Entry, E> {
                    Ok(Entry(v as f32))
                }
                fn visit_str<E: de::Error>(self, v: &str) -> Result<Entry, E> {
                    match v {
                        "inf" | "+inf" | "Infinity" => Ok(Entry(f32::INFINITY)),
                        "-inf" | "-Infinity" => Ok(Entry(f32::NEG_INFINITY)),
                        "NaN" | "nan" => Ok(Entry(f32::NAN)),
                        _ => Err(E::invalid_value(de::Unexpected::Str(v), &self)),
                    }
                }
                fn visit_unit<E: de::Error>(self) -> Result<Entry, E> {
                    Ok(Entry(f32::INFINITY))
                }
                fn visit_none<E: de::Error>(self) -> Result<Entry, E> {
                    Ok(Entry(f32::INFINITY))
                }
            }
            d.deserialize_any(V)
        }
    }

    pub fn serialize<S: Serializer>(v: &[f32], s: S) -> Result<S::Ok, S::Error> {
        if s.is_human_readable() {
            s.collect_seq(v.iter().map(|&x| Text(x)))
        } else {
            v.serialize(s)
        }
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f32>, D::Error> {
        if d.is_human_readable() {
            struct S;
            impl<'de> Visitor<'de> for S {
                type Value = Vec<f32>;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("a sequence of errors")
                }
                fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> Result<Vec<f32>, A::Error> {
                    let mut out = Vec::with_capacity(a.size_hint().unwrap_or(0).min(4096));
                    while let Some(Entry(v)) = a.next_element()? {
                        out.push(v);
                    }
                    Ok(out)
                }
            }
            d.deserialize_seq(S)
        } else {
            Vec::<f32>::deserialize(d)
        }
    }
}

impl DistancePolicy {
    /// The paper's defaults for `model`'s level table.
    pub fn for_model(model: &LodModel) -> DistancePolicy {
        Self::build(model, DistanceConfig::default())
    }

    /// A policy with `config` for `model`'s level table; distances must be finite and positive
    /// (`near_m` may be zero).
    pub fn new(model: &LodModel, config: DistanceConfig) -> Result<DistancePolicy, PolicyError> {
        Self::check(&config)?;
        Ok(Self::build(model, config))
    }

    /// The schedule with `config` for a level table given without a model: the key of each
    /// accuracy level (non-decreasing; consecutive levels sharing a key form a group) and the
    /// joint count. There are no error tables, so no screen check. Errors: a bad `config`, no
    /// levels, or decreasing keys.
    pub fn for_level_keys(
        keys: &[usize],
        joints: usize,
        config: DistanceConfig,
    ) -> Result<DistancePolicy, PolicyError> {
        Self::check(&config)?;
        if keys.is_empty() || keys.windows(2).any(|w| w[1] < w[0]) {
            return Err(PolicyError::LevelKeys);
        }
        Ok(Self::schedule(keys, joints, config, Vec::new(), Vec::new()))
    }

    fn check(config: &DistanceConfig) -> Result<(), PolicyError> {
        let check = |name, value: f32, zero_ok: bool| {
            let ok = value.is_finite() && (value > 0.0 || (zero_ok && value == 0.0));
            if ok {
                Ok(())
            } else {
                Err(PolicyError::Config {
                    name,
                    value,
                    rule: if zero_ok {
                        "finite and >= 0"
                    } else {
                        "finite and > 0"
                    },
                })
            }
        };
        check("near_m", config.near_m, true)?;
        check("key_step_m", config.key_step_m, false)?;
        check("joint_step_m", config.joint_step_m, false)?;
        if let Some(b) = config.screen_budget_px {
            check("screen_budget_px", b, false)?;
        }
        Ok(())
    }

    fn build(model: &LodModel, config: DistanceConfig) -> DistancePolicy {
        let levels = model.levels();
        let keys: Vec<usize> = levels.iter().map(|l| l.key).collect();
        let joints = model.joints();
        let checked = config.screen_budget_px.is_some()
            && model.level_errors().len() == levels.len()
            && model.joint_errors().len() == joints + 1;
        if !checked {
            return Self::schedule(&keys, joints, config, Vec::new(), Vec::new());
        }
        let level_err_m = usable_level_errors(model, true);
        let joint_err_m = non_increasing(
            model
                .joint_errors()
                .iter()
                .map(|e| ERROR_MARGIN * e.visible_m(true)),
        );
        let mut policy = Self::schedule(&keys, joints, config, level_err_m, joint_err_m);
        policy.costs = DetailCosts::of(model);
        policy
    }

    /// The policy for levels with these keys (see [`DistancePolicy::for_level_keys`]) and the
    /// given error tables (empty: no screen check).
    fn schedule(
        keys: &[usize],
        joints: usize,
        config: DistanceConfig,
        level_err_m: Vec<f32>,
        joint_err_m: Vec<f32>,
    ) -> DistancePolicy {
        let mut positions = Vec::with_capacity(keys.len());
        let mut group = 0usize;
        let mut start = 0usize;
        while start < keys.len() {
            let key = keys[start];
            let end = start + keys[start..].iter().take_while(|&&k| k == key).count();
            let n = end - start;
            for i in 0..n {
                positions.push(group as f32 + i as f32 / n as f32);
            }
            group += 1;
            start = end;
        }
        DistancePolicy {
            config,
            positions,
            groups: group,
            joints,
            level_err_m,
            joint_err_m,
            costs: DetailCosts::default(),
        }
    }

    /// The scheduled `detail` made to fit the screen budget at `distance_m` (see the type's docs).
    fn fit_screen(&self, detail: Detail, distance_m: f32, view: &ViewParams) -> Detail {
        let (Some(budget_px), false) = (self.config.screen_budget_px, self.level_err_m.is_empty())
        else {
            return detail;
        };
        let Some(budget_m) = budget_m(budget_px, view, distance_m, false) else {
            return Detail::new(0, self.joints);
        };
        let joints = detail.active_joints.min(self.joints);
        let level = detail.accuracy.min(self.level_err_m.len() - 1);
        if self.level_err_m[level] + self.joint_err_m[joints] <= budget_m {
            return Detail::new(level, joints);
        }
        // The cheapest detail no coarser than the schedule's that fits: for each finer level, the
        // fewest joints (at least the schedule's) whose error fits beside the level's.
        let mut best: Option<(u64, Detail)> = None;
        for l in 0..=level {
            let rest = budget_m - self.level_err_m[l];
            if rest < 0.0 {
                continue;
            }
            let j = self.joint_err_m.partition_point(|&e| e > rest).max(joints);
            if j > self.joints {
                continue;
            }
            let cost = self.costs.cost(l, j);
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, Detail::new(l, j)));
            }
        }
        best.map_or(Detail::new(0, self.joints), |(_, d)| d)
    }

    /// The configuration in use.
    pub fn config(&self) -> DistanceConfig {
        self.config
    }
}

impl LevelPolicy for DistancePolicy {
    fn detail(&self, distance_m: f32, visible: bool, view: &ViewParams) -> Detail {
        // Root only at the smallest level (the schedule has one position per accuracy level).
        let root_only = Detail::new(self.positions.len().saturating_sub(1), 0);
        if !visible || distance_m.is_nan() {
            return root_only;
        }
        let c = &self.config;
        let beyond = distance_m - c.near_m;
        if beyond < 0.0 {
            return Detail::new(0, self.joints);
        }
        let x = beyond / c.key_step_m;
        if x >= self.groups as f32 {
            return root_only;
        }
        // Last level whose position is <= x (position 0 always qualifies).
        let level = self.positions.partition_point(|&p| p <= x).max(1) - 1;
        let steps = (beyond / c.joint_step_m).floor();
        let dropped = if steps >= self.joints as f32 {
            self.joints
        } else {
            (steps as usize)
                .saturating_mul(c.joints_per_step)
                .min(self.joints)
        };
        self.fit_screen(Detail::new(level, self.joints - dropped), distance_m, view)
    }
}

/// The budget in metres, `budget_px metres_per_pixel(distance)`, at most `f32::MAX`: `None` for a
/// view whose metres per pixel are NaN, negative (or zero, unless `zero_ok`) at this distance. A
/// valid view (finite positive metres per pixel at 1 m) at a distance so large that its metres
/// per pixel overflow has the largest budget (it is that far away), not none.
fn budget_m(budget_px: f32, view: &ViewParams, distance_m: f32, zero_ok: bool) -> Option<f32> {
    let mut mpp = view.metres_per_pixel(distance_m.max(0.0));
    if mpp == f32::INFINITY {
        let unit = view.metres_per_pixel(1.0);
        if unit.is_finite() && unit > 0.0 {
            mpp = f32::MAX;
        }
    }
    if !(mpp.is_finite() && (mpp > 0.0 || (zero_ok && mpp >= 0.0))) {
        return None;
    }
    // (`min` is the identity for every finite product: the same bits.)
    Some((budget_px * mpp).min(f32::MAX))
}

/// `v` made non-increasing by a running maximum from the end (an error that never decreases as
/// joints are dropped).
fn non_increasing(v: impl Iterator<Item = f32>) -> Vec<f32> {
    let mut v: Vec<f32> = v.collect();
    for j in (0..v.len().saturating_sub(1)).rev() {
        v[j] = v[j].max(v[j + 1]);
    }
    v
}

/// Each accuracy level's visible error with the margin, `ERROR_MARGIN e_l` metres (shell or mean
/// joint error against the foot slide), infinite for a level past 0 whose measured motion quality
/// fails (`LevelError::passes_quality`): no budget admits it.
fn usable_level_errors(model: &LodModel, shell: bool) -> Vec<f32> {
    model
        .level_errors()
        .iter()
        .enumerate()
        .map(|(l, e)| {
            if !model.level_serves_joints(l) {
                f32::INFINITY
            } else {
                ERROR_MARGIN * e.visible_m(shell)
            }
        })
        .collect()
}

/// The cost model of both policies: multiply-adds of one clip kernel and `T` poses of a detail,
/// `base(l) + rows(j) row(l)` with `rows(j) = always + per_joint j` ([`LodModel::kernel_cost`] and
/// the pose cost are affine in the evaluated rows).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
struct DetailCosts {
    /// Per level: the cost's constant part.
    level_base_cost: Vec<u64>,
    /// Per level: the cost per evaluated row (a kernel row and `T` pose rows).
    level_row_cost: Vec<u64>,
    always_rows: usize,
    rows_per_joint: usize,
}

impl DetailCosts {
    fn of(model: &LodModel) -> DetailCosts {
        let t = model.t() as u64;
        let mut level_base_cost = Vec::new();
        let mut level_row_cost = Vec::new();
        for l in 0..model.levels().len() {
            let c0 = model.kernel_cost_rows(l, 0).unwrap_or(0) as u64;
            let c1 = model.kernel_cost_rows(l, 1).unwrap_or(0) as u64;
            let p1 = model.pose_cost_rows(l, 1).unwrap_or(0) as u64;
            level_base_cost.push(c0);
            level_row_cost.push(c1 - c0 + t * p1);
        }
        DetailCosts {
            level_base_cost,
            level_row_cost,
            always_rows: model.always_rows(),
            rows_per_joint: model.rows_per_joint(),
        }
    }

    /// [`DetailCosts::cost`] with every step checked (`None` for a level it lacks or an
    /// overflow): what deserialising checks once, so that `cost` never overflows.
    fn checked_cost(&self, level: usize, joints: usize) -> Option<u64> {
        let rows = self
            .rows_per_joint
            .checked_mul(joints)?
            .checked_add(self.always_rows)?;
        let rows = u64::try_from(rows).ok()?;
        rows.checked_mul(*self.level_row_cost.get(level)?)?
            .checked_add(*self.level_base_cost.get(level)?)
    }

    /// Cost of level `level` (which must exist) with `joints` joints.
    fn cost(&self, level: usize, joints: usize) -> u64 {
        let rows = (self.always_rows + self.rows_per_joint * joints) as u64;
        self.level_base_cost[level] + rows * self.level_row_cost[level]
    }
}

/// Which measured error the [`ScreenSpacePolicy`] projects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ErrorMetric {
    /// Mean joint position error.
    MeanJoint,
    /// Shell error (largest vertex displacement): the conservative choice.
    Shell,
}

/// Settings of the [`ScreenSpacePolicy`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ScreenConfig {
    /// Largest allowed projected error in pixels (default 1).
    pub budget_px: f32,
    /// Error measure used (default [`ErrorMetric::Shell`]).
    pub metric: ErrorMetric,
}

impl Default for ScreenConfig {
    fn default() -> Self {
        ScreenConfig {
            budget_px: 1.0,
            metric: ErrorMetric::Shell,
        }
    }
}

/// Picks the cheapest detail whose measured error, projected to the screen, stays under a pixel
/// budget (beyond the paper).
///
/// The error of level `l` with `j` active joints is estimated as `e_l + e_J(j)` metres, where `e_l`
/// is the level's measured [visible error](crate::model::LevelError::visible_m) (the larger of its
/// pose error and its foot slide, all joints) and `e_J(j)` the same for evaluating only `j` joints (made non-increasing in `j` by a running maximum, so it is never underestimated
/// against a larger joint count); its projection is
/// `err_px = m err_m * image_height / (2 distance tan(fov_y / 2))` with the margin `m` =
/// [`ERROR_MARGIN`]. Among all `(l, j)` with
/// `err_px <= budget_px` it returns the one with the smallest cost
/// `kernel_cost(l, P') + T pose_cost(l, P')` (a cycle's kernel and poses, [`LodModel::kernel_cost`] of the detail);
/// if none qualifies, full detail. When the model has no joint error table, every joint is kept.
/// An accuracy level whose measured motion quality fails ([`LevelError::passes_quality`]) is not
/// admissible. Since the admissible set only grows with distance, the chosen cost never increases
/// with it.
///
/// [`LevelError::passes_quality`]: crate::model::LevelError::passes_quality
///
/// Serialises as its fields; deserialising re-runs the constructor's checks, and infinite
/// errors are written as in [`DistancePolicy`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawScreenSpacePolicy")]
pub struct ScreenSpacePolicy {
    config: ScreenConfig,
    /// Per level: error in metres (infinite where the level's motion quality fails).
    #[serde(with = "float_text")]
    level_err_m: Vec<f32>,
    /// Non-increasing error in metres per active joint count `0..=J`.
    #[serde(with = "float_text")]
    joint_err_m: Vec<f32>,
    costs: DetailCosts,
    joints: usize,
}

/// [`ScreenSpacePolicy`]'s fields as stored (the same names and order), checked by `TryFrom`.
#[derive(Deserialize)]
struct RawScreenSpacePolicy {
    config: ScreenConfig,
    #[serde(with = "float_text")]
    level_err_m: Vec<f32>,
    #[serde(with = "float_text")]
    joint_err_m: Vec<f32>,
    costs: DetailCosts,
    joints: usize,
}

impl TryFrom<RawScreenSpacePolicy> for ScreenSpacePolicy {
    type Error = PolicyError;
    fn try_from(raw: RawScreenSpacePolicy) -> Result<Self, PolicyError> {
        ScreenSpacePolicy::check_config(&raw.config)?;
        check_tables(&raw.level_err_m, &raw.joint_err_m, raw.joints, &raw.costs)
            .map_err(PolicyError::Data)?;
        Ok(ScreenSpacePolicy {
            config: raw.config,
            level_err_m: raw.level_err_m,
            joint_err_m: raw.joint_err_m,
            costs: raw.costs,
            joints: raw.joints,
        })
    }
}

impl ScreenSpacePolicy {
    fn check_config(config: &ScreenConfig) -> Result<(), PolicyError> {
        if config.budget_px.is_finite() && config.budget_px > 0.0 {
            Ok(())
        } else {
            Err(PolicyError::Config {
                name: "budget_px",
                value: config.budget_px,
                rule: "finite and > 0",
            })
        }
    }

    /// Default budget (1 px, shell error) for `model`; needs its per-level error table.
    pub fn for_model(model: &LodModel) -> Result<ScreenSpacePolicy, PolicyError> {
        Self::new(model, ScreenConfig::default())
    }

    /// A policy with `config` for `model`; `budget_px` must be finite and positive.
    pub fn new(model: &LodModel, config: ScreenConfig) -> Result<ScreenSpacePolicy, PolicyError> {
        Self::check_config(&config)?;
        if model.level_errors().len() != model.levels().len() {
            return Err(PolicyError::NoErrorTable);
        }
        let shell = config.metric == ErrorMetric::Shell;
        let pick = |e: &crate::model::LevelError| ERROR_MARGIN * e.visible_m(shell);
        let level_err_m = usable_level_errors(model, shell);
        let joints = model.joints();
        let joint_err_m = if model.joint_errors().is_empty() {
            // Unknown: only the full joint count is admissible.
            let mut v = vec![f32::INFINITY; joints + 1];
            v[joints] = 0.0;
            v
        } else {
            non_increasing(model.joint_errors().iter().map(pick))
        };
        Ok(ScreenSpacePolicy {
            config,
            level_err_m,
            joint_err_m,
            costs: DetailCosts::of(model),
            joints,
        })
    }

    /// The configuration in use.
    pub fn config(&self) -> ScreenConfig {
        self.config
    }

    /// Estimated error in metres of `detail` (see the type's docs; infinite for a level whose
    /// motion quality fails); `None` for a level the model lacks.
    pub fn estimated_error_m(&self, detail: Detail) -> Option<f32> {
        let e = self.level_err_m.get(detail.accuracy)?;
        Some(e + self.joint_err_m[detail.active_joints.min(self.joints)])
    }

    /// Estimated cost (multiply-adds of one kernel and `T` poses) of `detail`; `None` for a level
    /// the model lacks.
    pub fn cost(&self, detail: Detail) -> Option<u64> {
        let level = detail.accuracy;
        if level >= self.costs.level_base_cost.len() {
            return None;
        }
        Some(
            self.costs
                .cost(level, detail.active_joints.min(self.joints)),
        )
    }
}

impl LevelPolicy for ScreenSpacePolicy {
    fn detail(&self, distance_m: f32, visible: bool, view: &ViewParams) -> Detail {
        if !visible || distance_m.is_nan() {
            // Root only at the smallest level.
            return Detail::new(self.level_err_m.len().saturating_sub(1), 0);
        }
        let full = Detail::new(0, self.joints);
        let Some(budget_m) = budget_m(self.config.budget_px, view, distance_m, true) else {
            return full;
        };
        let mut best: Option<(u64, Detail)> = None;
        for (l, &e) in self.level_err_m.iter().enumerate() {
            if e > budget_m {
                continue;
            }
            let rest = budget_m - e;
            // Fewest joints whose error fits (joint_err_m is non-increasing in j).
            let j = self.joint_err_m.partition_point(|&ej| ej > rest);
            if j > self.joints {
                continue;
            }
            let cost = self.costs.cost(l, j);
            if best.is_none_or(|(c, _)| cost < c) {
                best = Some((cost, Detail::new(l, j)));
            }
        }
        best.map_or(full, |(_, d)| d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_keys_give_the_schedule_without_a_model() {
        let config = DistanceConfig {
            screen_budget_px: None,
            ..DistanceConfig::default()
        };
        // Two keys: levels 0-1 share key 0 (50 m between them is split in two), level 2 has key 1.
        let p = DistancePolicy::for_level_keys(&[0, 0, 1], 5, config).unwrap();
        let v = ViewParams::default();
        assert_eq!(p.detail(10.0, true, &v), Detail::new(0, 5));
        assert_eq!(p.detail(60.0, true, &v), Detail::new(1, 2));
        assert_eq!(p.detail(85.0, true, &v), Detail::new(2, 0));
        // Beyond the last level and out of view: root only at the smallest level.
        assert_eq!(p.detail(131.0, true, &v), Detail::new(2, 0));
        assert_eq!(p.detail(10.0, false, &v), Detail::new(2, 0));
        assert_eq!(
            DistancePolicy::for_level_keys(&[1, 0], 5, config),
            Err(PolicyError::LevelKeys)
        );
        assert_eq!(
            DistancePolicy::for_level_keys(&[], 5, config),
            Err(PolicyError::LevelKeys)
        );
        let bad = DistanceConfig {
            key_step_m: 0.0,
            ..config
        };
        assert!(matches!(
            DistancePolicy::for_level_keys(&[0], 5, bad),
            Err(PolicyError::Config { .. })
        ));
    }

    #[test]
    fn closures_and_full_detail_are_policies() {
        let v = ViewParams::default();
        let near = |d: f32, _: bool, _: &ViewParams| Detail::new(usize::from(d > 10.0), 3);
        assert_eq!(near.detail(20.0, true, &v), Detail::new(1, 3));
        let full = FullDetail {
            detail: Detail::new(0, 7),
        };
        assert_eq!(full.detail(1e6, false, &v), Detail::new(0, 7));
    }
}
