//! The crowd: configuration, construction and the per-frame step (cull, kernels, poses, FK).

use crate::camera::{Bounds, Camera, CameraPath, Frustum};
use crate::culling::WalkerAabbTree;
use crate::error::CrowdError;
use crate::levels::{LevelTable, check_control_range};
use crate::path::{EllipsePath, PathPlan, WalkerStart};
use crate::source::ClipSource;
use crate::stats::{ClipFaults, CrowdReport, FrameStats, StageTimings};
use crate::stock::{Lender, Lent, Stock};
use crate::walker::{StageParams, Walker, WalkerFault, heading_sin_cos, valid_duration};
use glam::Vec3;
use lod_policy::SeamScratch;
use lod_policy::SplitMix64;
use lod_policy::{Controls, CycleFrame, Detail, LevelPolicy, StyleMix};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Walkers per rayon task: large enough to amortise scheduling, small enough to balance.
const CHUNK: usize = 64;
/// Walkers ahead whose clips are prefetched ([`ClipSource::prefetch`]) in the pose stage. About
/// eight cache lines each (clip, pose and joint slots): six walkers keep a core's line fill buffers
/// busy without queueing prefetches behind them (twelve: 58 against 63 fps at 100,000 Bandai
/// walkers on the ground, the same at 10,000).
const PREFETCH: usize = 6;

/// Walkers ahead whose own memory the kernel stage hints the CPU to fetch.
const PREFETCH_WALKERS: usize = 4;
/// Largest time step (s) [`Crowd::step`] accepts: a crowd's frame rate is at least its inverse.
pub const MAX_DT: f32 = 10.0;
/// Most walkers a crowd holds ([`CrowdConfig::walkers`]), `2^31 - 1`: the walker indices and the
/// per-frame counts (`FrameStats::level_histogram` is `u32`) fit in 32 bits, as the GPU crowd
/// (`gpu-crowd`) needs. A crowd within the cap that does not fit in memory is an error too
/// ([`CrowdError::OutOfMemory`]).
pub const MAX_WALKERS: usize = (u32::MAX / 2) as usize;
/// Largest field side (m) a crowd places walkers on ([`CrowdConfig::field_size_m`], also after
/// it is enlarged for the source's turn range), 100,000 km: walkers' world positions are single
/// precision outside their cycle frames, and within 50,000 km of the origin they resolve 4 m at
/// worst (1/16 m within 1,000 km, the command line's largest field is about 1,000 km). A field
/// that large is only reached by enlarging: a model of straight walks, whose paths can barely
/// turn, needs about 39,000 km (tests/skeleton_variants.rs in motion-lod) and still runs. Beyond
/// the cap a field is a mistake (1e20 m, where a stride is lost in rounding).
pub const MAX_FIELD_M: f32 = 1.0e8;

/// How a crowd finds the walkers in view each frame. Both give the same flags (a walker is visible
/// when its culling box, from the previous frame's placement, intersects the frustum:
/// [`Frustum::intersects`]), so the same frames; they differ in cost.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Culling {
    /// Every walker's box is tested against the frustum inside the frame's parallel pass, just
    /// before its kernel stage, while the chunk's boxes are in cache: `n` box tests on every
    /// thread, nothing to maintain. The default: the pass visits every walker anyway.
    #[default]
    Scan,
    /// An AABB tree over the boxes ([`WalkerAabbTree`]), refitted every frame, rebuilt every
    /// [`CrowdConfig::tree_rebuild_interval`] frames and queried with the frustum before the pass:
    /// queries cost in proportion to the walkers in view, but the refit visits every box.
    Tree,
}

/// What one chunk of walkers reports from the fused cull, kernel, pose and FK pass.
#[derive(Debug, Default)]
struct ChunkOutcome {
    /// Walkers in view ([`Culling::Scan`]; 0 under the tree, which counts them itself).
    visible: usize,
    built: usize,
    in_transition: usize,
    /// Clips the source could not build (the walkers kept their previous clips).
    clip_faults: ClipFaults,
    /// The first failing walker (lowest index) and its fault.
    fault: Option<(usize, WalkerFault)>,
    /// Time spent in the cull (scan), kernel, pose and FK stages, summed over chunks.
    cpu: [Duration; 4],
}

impl ChunkOutcome {
    fn merge(a: ChunkOutcome, b: ChunkOutcome) -> ChunkOutcome {
        let fault = match (a.fault, b.fault) {
            (Some(x), Some(y)) => Some(if x.0 <= y.0 { x } else { y }),
            (x, y) => x.or(y),
        };
        ChunkOutcome {
            visible: a.visible + b.visible,
            built: a.built + b.built,
            in_transition: a.in_transition + b.in_transition,
            clip_faults: ClipFaults::merge(a.clip_faults, b.clip_faults),
            fault,
            cpu: std::array::from_fn(|i| a.cpu[i] + b.cpu[i]),
        }
    }
}

/// How to populate and run a crowd.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrowdConfig {
    /// Number of walkers (at least 1, at most [`MAX_WALKERS`]).
    pub walkers: usize,
    /// Side of the square field `[-size/2, size/2]^2` (m), at most [`MAX_FIELD_M`].
    pub field_size_m: f32,
    /// Seed of every walker's generator (walker `i` uses `seed` and `i`).
    pub seed: u64,
    /// Frames per second of `Crowd::run` (`dt = 1 / fps`; at least `1 /` [`MAX_DT`]).
    pub fps: f32,
    /// At accuracy levels `0..seam_levels` a change of clip (a cycle seam, or a finer detail
    /// mid-cycle) is inertialized ([`lod_policy::SeamTransition`]): every row stays continuous in position
    /// and velocity. Coarser levels and root-only walkers switch clips as they are. Default
    /// `usize::MAX`: every walker with joints.
    pub seam_levels: usize,
    /// Half-life of a seam's offset (s).
    pub seam_halflife_s: f32,
    /// Visible walkers at accuracy levels `0..foot_lock_levels` (with joints) keep planted feet planted: the
    /// source's foot lock ([`ClipSource::plant_feet`], `lod_policy::FootLock`) runs on their pose
    /// every frame (the lock runs where the walker's legs are evaluated). Walkers at coarser
    /// levels skate as much as their level's measured slide, which the policies keep under a
    /// pixel. Default `usize::MAX`: every level, so that a coarse level's remaining error is its
    /// pose, not a slide (the model's level errors are measured with the lock on); 0 turns the
    /// lock off.
    pub foot_lock_levels: usize,
    /// Distance kept between paths and the field border (m).
    pub border_m: f32,
    /// Growth of each walker's culling box beyond its body, covering one frame of motion (m).
    pub cull_margin_m: f32,
    /// How the walkers in view are found ([`Culling`]; default [`Culling::Scan`]).
    pub culling: Culling,
    /// Under [`Culling::Tree`], rebuild the culling tree ([`WalkerAabbTree`]) every this many
    /// frames; refit it in between (1 = rebuild every frame). Default 240: a rebuild costs ~20
    /// refits at 10k walkers, and walkers move little per frame.
    pub tree_rebuild_interval: u32,
    /// Spread the clip builds of the first frames over the first cycle: a new walker that the
    /// policy wants finer than its starting root-only clip waits a seeded fraction of that clip
    /// (uniform in `[0, duration)`) before it rebuilds mid-cycle, instead of every such walker
    /// building in the first frame. Later refinements are immediate (there is no per-frame build
    /// budget). Default on. It trades a first-frame spike of clip builds for walkers that start
    /// root-only and snap into walking over their first cycle, which suits a timed run; a crowd
    /// that is watched or recorded from frame 0 calls [`Crowd::prime`] instead, which builds every
    /// walker's clip at its detail before the first frame and cancels the spread.
    pub spread_first_builds: bool,
    /// The walkers' styles ([`CrowdStyle`]; default [`CrowdStyle::DataMix`]: each walker walks one
    /// style, drawn with the data's shares). Ignored by a source without styles.
    pub style: CrowdStyle,
}

/// How a crowd's walkers get their style ([`lod_policy::StyleMix`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum CrowdStyle {
    /// Each walker walks one of the source's styles ([`ClipSource::style_mix`]), drawn from its
    /// generator with the data's shares: a crowd of the data's mix.
    #[default]
    DataMix,
    /// Every walker walks this style or blend of styles.
    Each(StyleMix),
}

impl CrowdStyle {
    /// The style of a walker for a source whose data mix is `mix` (style `j` has share `mix[j]`),
    /// with `u` uniform in `[0, 1)` from the walker's generator.
    pub fn for_walker(&self, mix: &[f32], u: f32) -> StyleMix {
        match self {
            CrowdStyle::Each(style) => *style,
            CrowdStyle::DataMix => {
                let total: f32 = mix.iter().sum();
                let mut acc = 0.0;
                for (j, &share) in mix.iter().enumerate() {
                    acc += share;
                    if u * total < acc {
                        return StyleMix::one(j);
                    }
                }
                mix.len()
                    .checked_sub(1)
                    .map_or(StyleMix::DATA_MIX, StyleMix::one)
            }
        }
    }
}

impl Default for CrowdConfig {
    fn default() -> Self {
        Self {
            walkers: 100,
            field_size_m: 100.0,
            seed: 1,
            fps: 30.0,
            seam_levels: usize::MAX,
            seam_halflife_s: lod_policy::DEFAULT_HALFLIFE_S,
            foot_lock_levels: usize::MAX,
            border_m: 2.0,
            cull_margin_m: 0.25,
            culling: Culling::Scan,
            tree_rebuild_interval: 240,
            spread_first_builds: true,
            style: CrowdStyle::DataMix,
        }
    }
}

impl CrowdConfig {
    /// A config with `walkers` walkers at `density` walkers per square metre (field side
    /// `sqrt(walkers / density)`), other fields default.
    pub fn with_density(walkers: usize, density: f32) -> Self {
        Self {
            walkers,
            field_size_m: (walkers as f32 / density).sqrt(),
            ..Self::default()
        }
    }

    /// Checks every value (walkers in `1..=`[`MAX_WALKERS`]; sizes, rates and margins finite and
    /// in their domains, the field side at most [`MAX_FIELD_M`]; style weights finite and
    /// non-negative): what [`Crowd::new`] asks of a config, for any crowd that runs one
    /// (`gpu-crowd` too).
    pub fn validate(&self) -> Result<(), CrowdError> {
        let bad = |field, value: f32| {
            Err(CrowdError::BadConfig {
                field,
                value: f64::from(value),
            })
        };
        if self.walkers == 0 {
            return Err(CrowdError::NoWalkers);
        }
        if self.walkers > MAX_WALKERS {
            return Err(CrowdError::TooManyWalkers {
                walkers: self.walkers,
            });
        }
        if !(self.field_size_m.is_finite() && self.field_size_m > 0.0) {
            return bad("field_size_m", self.field_size_m);
        }
        if self.field_size_m > MAX_FIELD_M {
            return Err(CrowdError::AboveLimit {
                field: "field_size_m",
                value: f64::from(self.field_size_m),
                max: f64::from(MAX_FIELD_M),
            });
        }
        // The crowd steps by `1 / fps`, at most `MAX_DT`.
        if !(self.fps.is_finite() && self.fps >= 1.0 / MAX_DT) {
            return bad("fps", self.fps);
        }
        if !(self.seam_halflife_s.is_finite() && self.seam_halflife_s > 0.0) {
            return bad("seam_halflife_s", self.seam_halflife_s);
        }
        if !(self.border_m.is_finite() && self.border_m >= 0.0) {
            return bad("border_m", self.border_m);
        }
        if !(self.cull_margin_m.is_finite() && self.cull_margin_m >= 0.0) {
            return bad("cull_margin_m", self.cull_margin_m);
        }
        if self.tree_rebuild_interval == 0 {
            return bad("tree_rebuild_interval", 0.0);
        }
        if let CrowdStyle::Each(style) = &self.style
            && let Some(j) = style
                .weights
                .iter()
                .position(|w| !(w.is_finite() && *w >= 0.0))
        {
            return bad("style", style.weights[j]);
        }
        Ok(())
    }
}

/// Asks the system for every per-walker buffer of a crowd of `n` walkers at once (reserved
/// together, then given back; [`Crowd::new`] then allocates them as before, zeroed pages left to
/// the system until written): [`CrowdError::OutOfMemory`] for a size beyond the address space or
/// an allocation refused, instead of an abort partway through `new`.
fn check_memory<C>(n: usize, levels: &LevelTable) -> Result<(), CrowdError> {
    fn reserve<T>(len: Option<usize>, what: &'static str, n: usize) -> Result<Vec<T>, CrowdError> {
        let mut v = Vec::new();
        len.and_then(|len| v.try_reserve_exact(len).ok())
            .ok_or(CrowdError::OutOfMemory { what, walkers: n })?;
        Ok(v)
    }
    let npos = levels.joints.checked_add(1);
    let _held = (
        reserve::<f32>(n.checked_mul(levels.pose_len), "pose vectors", n)?,
        reserve::<Vec3>(npos.and_then(|p| n.checked_mul(p)), "joint positions", n)?,
        reserve::<Bounds>(n.checked_mul(2), "culling boxes", n)?,
        reserve::<u32>(Some(n), "level bins", n)?,
        reserve::<bool>(Some(n), "visibility flags", n)?,
        reserve::<Walker<C>>(Some(n), "walker states", n)?,
        // Each frame's level histogram (`FrameStats`, `CrowdReport`): one bin per level.
        reserve::<u64>(levels.accuracy_levels.checked_add(1), "level histogram", n)?,
    );
    Ok(())
}

/// Culling box of a walker: root ground position +-(0.4 height + margin) horizontally,
/// `[-margin, 1.1 height + margin]` vertically.
fn walker_bounds<C>(w: &Walker<C>, m: f32) -> Bounds {
    let r = 0.4 * w.height + m;
    Bounds {
        min: Vec3::new(w.root.x - r, -m, w.root.z - r),
        max: Vec3::new(w.root.x + r, 1.1 * w.height + m, w.root.z + r),
    }
}

/// A crowd of walkers driven by clips of a [`ClipSource`] whose clip type is `C`.
///
/// All per-frame buffers are allocated by `new`. What a walker needs only for some details or
/// some time is lent to it by the crowd's stock and given back when it no longer needs it: a clip
/// of the size class its detail needs (when the source has several:
/// [`ClipSource::clip_classes`]; a walker whose detail changes class exchanges its clip), a foot
/// lock while near, a seam transition (`3 P` floats) while a seam runs. The stock grows only when
/// more walkers need a buffer of a kind at once than ever before, so `step_into` allocates only
/// then (counted in [`FrameStats::allocations`]: while the crowd warms up, and at a new peak;
/// [`Crowd::reserve`] stocks it beforehand) and when the culling tree ([`Culling::Tree`]) is
/// rebuilt (every `tree_rebuild_interval` frames).
pub struct Crowd<C> {
    config: CrowdConfig,
    params: StageParams,
    walkers: Vec<Walker<C>>,
    poses: Vec<f32>,
    /// Level histogram bin of every walker's clip after the last step.
    bins: Vec<u32>,
    /// Scratch of the seam transitions started in the kernel stage, one per `CHUNK` walkers.
    seam_scratch: Vec<SeamScratch>,
    /// The buffers lent to near walkers and seams ([`Stock`]).
    stock: Stock<C>,
    joints: Vec<Vec3>,
    bounds: Vec<Bounds>,
    /// The boxes the FK stage writes as it places each walker: the next step's `bounds` (swapped in).
    placed_bounds: Vec<Bounds>,
    visible: Vec<bool>,
    tree: WalkerAabbTree,
    bones: Vec<(usize, usize)>,
    frame: u64,
    time_s: f64,
    field_enlarged_from: Option<f32>,
}

impl<C: Send> Crowd<C> {
    /// Places `config.walkers` walkers on seeded paths with root-only clips at random phases
    /// ([`Crowd::prime`] gives them their clips at the policy's detail before a first frame).
    ///
    /// A field too small for the paths the source's turn range can follow (a model of straight
    /// walks turns little per cycle, so its paths need large radii) is enlarged to fit them:
    /// [`Crowd::field_enlarged_from`] tells, and [`Crowd::config`] holds the size used.
    ///
    /// Errors: zero walkers or more than [`MAX_WALKERS`], a source without levels or with unusable
    /// control bounds, a bad config value, a field that the paths need enlarged beyond
    /// [`MAX_FIELD_M`], an invalid clip, or buffers the system cannot allocate
    /// ([`CrowdError::OutOfMemory`]: asked for before any is made, so that a crowd too large for
    /// the machine is an error, not an abort).
    pub fn new<S: ClipSource<Clip = C>>(
        source: &S,
        mut config: CrowdConfig,
    ) -> Result<Self, CrowdError> {
        config.validate()?;
        let levels = source.levels();
        if levels.accuracy_levels == 0 || levels.pose_len == 0 {
            return Err(CrowdError::NoLevels {
                accuracy_levels: levels.accuracy_levels,
                pose_len: levels.pose_len,
            });
        }
        let bounds = source.control_range();
        check_control_range(&bounds)?;
        let classes = source.clip_classes();
        if !(1..=crate::source::MAX_CLIP_CLASSES).contains(&classes) {
            return Err(CrowdError::ClipClasses { classes });
        }
        let params = StageParams {
            levels,
            bounds,
            seam_levels: config.seam_levels,
            seam_halflife_s: config.seam_halflife_s,
            foot_lock_levels: config.foot_lock_levels,
        };
        // Preferred strides, the tightest curvature they can follow, and the field that needs.
        let plan = PathPlan::new(&bounds, config.border_m);
        let field_enlarged_from = plan.fit_field(&mut config.field_size_m);
        if config.field_size_m > MAX_FIELD_M {
            return Err(CrowdError::FieldTooLarge {
                needed_m: config.field_size_m,
            });
        }
        let n = config.walkers;
        check_memory::<C>(n, &levels)?;
        let npos = levels.joints + 1;
        let root_only = levels.root_only().ok_or(CrowdError::NoLevels {
            accuracy_levels: levels.accuracy_levels,
            pose_len: levels.pose_len,
        })?;
        let make = |i: usize| -> Result<Walker<C>, CrowdError> {
            let mut g = SplitMix64::for_walker(config.seed, i);
            let start @ WalkerStart {
                path,
                s,
                base,
                heading,
                stride,
                height,
                phase,
            } = plan.draw(&mut g, config.field_size_m, &bounds).ok_or(
                CrowdError::FieldTooSmall {
                    field_m: config.field_size_m,
                    needed_m: plan.needed_field_m(),
                },
            )?;
            // Drawn after the path, phase and stride, and only for a source with styles, so that
            // a crowd without styles is the same walk for walk.
            let mix = source.style_mix();
            let style = if mix.is_empty() {
                StyleMix::DATA_MIX
            } else {
                config.style.for_walker(mix, g.next_f32())
            };
            let controls = start.first_controls(&bounds).with_style(style);
            let mut cur = source.new_clip();
            source
                .build_clip(&controls, root_only, &mut cur)
                .map_err(|error| CrowdError::FirstClip { walker: i, error })?;
            let dur = source.clip_duration(&cur);
            if !valid_duration(dur) {
                return Err(CrowdError::BadClipDuration {
                    walker: i,
                    duration: dur,
                });
            }
            let cur_motion = source.clip_root_motion(&cur);
            let frame = CycleFrame {
                x: f64::from(base.x),
                z: f64::from(base.y),
                heading: f64::from(heading),
            };
            // Drawn last, so that the paths, phases and strides do not depend on the option.
            let hold_s = if config.spread_first_builds {
                g.next_f32() * dur
            } else {
                0.0
            };
            Ok(Walker {
                path,
                s: f64::from(s),
                stride,
                height,
                frame,
                heading_sc: heading_sin_cos(&frame),
                t: phase * dur,
                controls,
                cur,
                cur_detail: root_only,
                cur_dur: dur,
                cur_motion,
                seam: None,
                hold_s,
                seam_start: 0.0,
                lock: None,
                rows: 0,
                n_joints: 0,
                root: Vec3::new(base.x, 0.0, base.y),
            })
        };
        // Into a vector reserved up front (a refused allocation is an error), stopping at a
        // failing walker as `collect::<Result<Vec<_>, _>>` does.
        let mut walkers = Vec::new();
        walkers
            .try_reserve_exact(n)
            .map_err(|_| CrowdError::OutOfMemory {
                what: "walker states",
                walkers: n,
            })?;
        let first_error = std::sync::Mutex::new(None);
        walkers.par_extend(
            (0..n)
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(make)
                .map(|w| match w {
                    Ok(w) => Some(w),
                    Err(e) => {
                        if let Ok(mut first) = first_error.lock() {
                            first.get_or_insert(e);
                        }
                        None
                    }
                })
                .while_some(),
        );
        if let Some(e) = first_error.into_inner().unwrap_or_else(|p| p.into_inner()) {
            return Err(e);
        }
        debug_assert_eq!(walkers.len(), n);
        let mut crowd = Self {
            config,
            params,
            field_enlarged_from,
            walkers,
            poses: vec![0.0; n * levels.pose_len],
            bins: vec![0; n],
            seam_scratch: (0..n.div_ceil(CHUNK))
                .map(|_| SeamScratch::new(levels.pose_len))
                .collect(),
            stock: Stock::new(n, classes),
            joints: vec![Vec3::ZERO; n * npos],
            bounds: Vec::new(),
            placed_bounds: vec![
                Bounds {
                    min: Vec3::ZERO,
                    max: Vec3::ZERO
                };
                n
            ],
            visible: vec![false; n],
            tree: WalkerAabbTree::new(&[]),
            bones: source.bones().to_vec(),
            frame: 0,
            time_s: 0.0,
        };
        crowd.update_bounds();
        crowd.bounds.clone_from(&crowd.placed_bounds);
        if config.culling == Culling::Tree {
            crowd.tree.rebuild(&crowd.bounds);
        }
        Ok(crowd)
    }

    /// Culling box of every walker ([`walker_bounds`]) into `placed_bounds`, the boxes the next step
    /// culls with. The frame's FK stage writes each walker's box there as it places it (while the
    /// walker is in cache), so this full pass runs only for a new crowd or after a failed step.
    fn update_bounds(&mut self) {
        let m = self.config.cull_margin_m;
        // Walkers are borrowed mutably (clips need only be `Send`, not `Sync`).
        self.placed_bounds
            .par_iter_mut()
            .zip(self.walkers.par_iter_mut())
            .with_min_len(4 * CHUNK)
            .for_each(|(b, w)| *b = walker_bounds(w, m));
    }

    /// Stocks the crowd while loading so that its frame loop allocates nothing while at most
    /// `near` walkers at once hold a clip of any one size class other than root-only clips'
    /// ([`ClipSource::clip_classes`]), plant their feet or run a seam: makes the spare clips of
    /// each such class, foot locks and seam transitions that the walkers holding them now leave
    /// missing. The stock otherwise grows at each new peak of near walkers
    /// ([`FrameStats::allocations`]); it holds at most one spare of a kind per walker up to 4,096
    /// walkers, one per eight beyond. Call it after [`Crowd::prime`] (which gives the walkers in
    /// view their clips) and before the first step. Returns the buffers made.
    pub fn reserve<S: ClipSource<Clip = C>>(&mut self, source: &S, near: usize) -> usize {
        let mut lent = Lent::default();
        for w in &self.walkers {
            let class = source.clip_class(&w.cur_detail);
            lent.clips[class.min(crate::source::MAX_CLIP_CLASSES - 1)] += 1;
            lent.locks += usize::from(w.lock.is_some());
            lent.seams += usize::from(w.seam.is_some());
        }
        let levels = self.params.levels;
        let root = levels.root_only().map(|d| source.clip_class(&d));
        let classes = (0..source.clip_classes()).filter(|&c| Some(c) != root);
        let seam = (levels.pose_len, self.params.seam_halflife_s);
        self.stock.reserve(source, near, classes, &lent, seam)
    }

    /// Starts every walker mid-stride at the detail `policy` gives it seen from `camera`, before
    /// the first frame (call it once, between [`Crowd::new`] and the first step, with the first
    /// step's camera). Each walker's root is first placed where its clip puts it at its starting
    /// phase (`new` leaves it at its cycle frame's origin, up to a stride away), its culling box
    /// follows, and the policy is asked from there (distance and visibility, as the first step
    /// asks); a walker the policy wants finer than its starting root-only clip then gets that clip
    /// at once, at the same phase of its first cycle and without a seam (nothing was shown yet),
    /// instead of snapping into walking over its first cycle. The spread of first builds
    /// ([`CrowdConfig::spread_first_builds`]) is cancelled for every walker, primed or not: it
    /// exists only to spread the builds `prime` has just done; later refinements are immediate
    /// either way. For recordings, exports and renders that start at frame 0; a game calls it while
    /// loading (it builds the clips of every walker in view in one go). The same bytes for any
    /// thread count. Returns the kernels built; a clip the source cannot build leaves the walker
    /// with its root-only clip (counted in the returned faults).
    pub fn prime<S, P>(
        &mut self,
        source: &S,
        policy: &P,
        camera: &Camera,
    ) -> Result<(usize, ClipFaults), CrowdError>
    where
        S: ClipSource<Clip = C>,
        P: LevelPolicy + Sync + ?Sized,
    {
        let frustum = Frustum::from_camera(camera)?;
        lod_policy::offline::clear_avx_upper_state();
        let params = self.params;
        let margin = self.config.cull_margin_m;
        let pl = params.levels.pose_len;
        let (eye, view) = (camera.position, camera.view());
        let stock = &self.stock;
        let (built, faults, fault) = self
            .walkers
            .par_chunks_mut(CHUNK)
            .zip(self.placed_bounds.par_chunks_mut(CHUNK))
            .zip(self.poses.par_chunks_mut(CHUNK * pl))
            .zip(self.seam_scratch.par_iter_mut())
            .enumerate()
            .map(|(c, (((walkers, boxes), poses), seams))| {
                let mut out = (0usize, ClipFaults::default(), None);
                // The first step writes every walker's pose slot before reading it: a scratch here.
                let scratch = &mut poses[..pl];
                for (k, (w, b)) in walkers.iter_mut().zip(boxes.iter_mut()).enumerate() {
                    w.place_root(source, scratch);
                    *b = walker_bounds(w, margin);
                    let d = policy.detail(w.root.distance(eye), frustum.intersects(b), &view);
                    let mut lend = Lender {
                        scratch: &mut *seams,
                        stock,
                    };
                    match w.prime(source, &params, d, &mut lend) {
                        Ok(a) => {
                            out.0 += a.built;
                            if let Some(e) = a.fault {
                                out.1.record(c * CHUNK + k, a.faults, e);
                            }
                        }
                        Err(e) => {
                            out.2.get_or_insert((c * CHUNK + k, e));
                        }
                    }
                    // Where the primed clip puts the root (its box is the first step's).
                    w.place_root(source, scratch);
                }
                out
            })
            .reduce(
                || (0, ClipFaults::default(), None),
                |a, b| (a.0 + b.0, ClipFaults::merge(a.1, b.1), a.2.or(b.2)),
            );
        // What priming stocked is loading's, not the first frame's.
        self.stock.take_allocations();
        self.update_bounds();
        if let Some((walker, e)) = fault {
            return Err(walker_error(walker, e, &params));
        }
        Ok((built, faults))
    }

    /// Advances the crowd by `dt` seconds seen from `camera` and returns the frame's statistics.
    pub fn step<S, P>(
        &mut self,
        source: &S,
        policy: &P,
        camera: &Camera,
        dt: f32,
    ) -> Result<FrameStats, CrowdError>
    where
        S: ClipSource<Clip = C>,
        P: LevelPolicy + Sync + ?Sized,
    {
        let mut stats = FrameStats::default();
        self.step_into(source, policy, camera, dt, &mut stats)?;
        Ok(stats)
    }

    /// [`Crowd::step`] writing into a caller-owned `stats` (no allocation once its histogram has
    /// the right length).
    ///
    /// Stages: (1) cull: the boxes left by the last frame's placement against the frustum, scanned
    /// chunk by chunk inside the parallel pass ([`Culling::Scan`]) or through the culling tree,
    /// refitted (or rebuilt) and queried before it ([`Culling::Tree`]);
    /// (2) kernels: per walker, detail from `policy` (distance from the camera to the root,
    /// visibility), cycle scheduling and clip builds; (3) poses with the running seam transitions;
    /// (4) forward kinematics into world positions. Stages 2-4 run as one parallel pass over chunks
    /// of walkers (each chunk runs the three in turn while its walkers are in cache; the pass's wall
    /// time is split between them in proportion to their summed times) and give the same bytes for
    /// any thread count. The policy's detail is checked against the source's [`LevelTable`]
    /// ([`LevelTable::check`]); a clip the source cannot build is counted in
    /// `stats.clip_faults` and the walker keeps its previous clip (a level the source does not
    /// have, [`CrowdError::BadLevel`], more joints than it has, [`CrowdError::BadJoints`], or a
    /// clip of unusable duration is an error).
    pub fn step_into<S, P>(
        &mut self,
        source: &S,
        policy: &P,
        camera: &Camera,
        dt: f32,
        stats: &mut FrameStats,
    ) -> Result<(), CrowdError>
    where
        S: ClipSource<Clip = C>,
        P: LevelPolicy + Sync + ?Sized,
    {
        if !(dt.is_finite() && (0.0..=MAX_DT).contains(&dt)) {
            return Err(CrowdError::BadTimeStep { dt });
        }
        let frustum = Frustum::from_camera(camera)?;
        // Vector code run before on this thread (a model build) may have left the AVX upper state
        // dirty, which slows every SSE instruction after it.
        lod_policy::offline::clear_avx_upper_state();

        // (1) Culling, over the boxes the last frame's FK stage left (or `new`'s): by the tree here,
        // or by a scan of each chunk's boxes in the pass below.
        let t0 = Instant::now();
        std::mem::swap(&mut self.bounds, &mut self.placed_bounds);
        let scan = self.config.culling == Culling::Scan;
        let tree_visible = if scan {
            0
        } else {
            if self.frame % u64::from(self.config.tree_rebuild_interval) == 0 {
                self.tree.rebuild(&self.bounds);
            } else {
                self.tree.refit(&self.bounds);
            }
            self.tree.query(&frustum, &mut self.visible)
        };

        // (1 scan)-(4) Culling scan, kernels, poses, forward kinematics: one parallel pass over chunks
        // of walkers, each chunk running the stages in turn while its walkers are in cache. Every
        // chunk's stage times are summed over threads and the pass's wall time is split in
        // proportion.
        let t1 = Instant::now();
        let params = self.params;
        let margin = self.config.cull_margin_m;
        let eye = camera.position;
        let view = camera.view();
        let pl = params.levels.pose_len;
        let npos = params.levels.joints + 1;
        // One seam scratch per chunk of walkers, made by `new`; the shared stock allocates only
        // at a new peak of near walkers (counted).
        let stock = &self.stock;
        let pass = self
            .walkers
            .par_chunks_mut(CHUNK)
            .zip(self.visible.par_chunks_mut(CHUNK))
            .zip(self.bounds.par_chunks(CHUNK))
            .zip(self.seam_scratch.par_iter_mut())
            .zip(self.poses.par_chunks_mut(CHUNK * pl))
            .zip(self.joints.par_chunks_mut(CHUNK * npos))
            .zip(self.bins.par_chunks_mut(CHUNK))
            .zip(self.placed_bounds.par_chunks_mut(CHUNK))
            .enumerate()
            .map(
                |(
                    c,
                    (((((((walkers, visible), boxes), scratch), poses), joints), bins), bounds),
                )| {
                    lod_policy::offline::clear_avx_upper_state();
                    let mut out = ChunkOutcome::default();
                    let mut lend = Lender { scratch, stock };
                    let t_scan = Instant::now();
                    if scan {
                        for (v, b) in visible.iter_mut().zip(boxes) {
                            *v = frustum.intersects(b);
                            out.visible += usize::from(*v);
                        }
                    }
                    let ta = Instant::now();
                    for k in 0..walkers.len() {
                        if let Some(ahead) = walkers.get(k + PREFETCH_WALKERS) {
                            lod_policy::offline::prefetch(ahead);
                        }
                        let (w, vis) = (&mut walkers[k], visible[k]);
                        let d = policy.detail(w.root.distance(eye), vis, &view);
                        let i = c * CHUNK + k;
                        match w.advance(source, &params, d, dt, &mut lend) {
                            Ok(a) => {
                                out.built += a.built;
                                if let Some(e) = a.fault {
                                    out.clip_faults.record(i, a.faults, e);
                                }
                            }
                            Err(e) => {
                                out.fault.get_or_insert((i, e));
                            }
                        }
                    }
                    let tb = Instant::now();
                    if out.fault.is_none() {
                        // Touch the clip `PREFETCH` walkers ahead so that its memory is on the
                        // way while this walker's pose is computed.
                        for k in 0..walkers.len() {
                            if let Some(ahead) = walkers.get(k + PREFETCH) {
                                source.prefetch(&ahead.cur, ahead.t);
                                // The first line of its pose and joint slots, which this pass
                                // and the next write (a root-only walker writes nothing more).
                                let j = k + PREFETCH;
                                lod_policy::offline::prefetch_bytes(
                                    poses[j * pl..].as_ptr().cast(),
                                    1,
                                );
                                lod_policy::offline::prefetch_bytes(
                                    joints[j * npos..].as_ptr().cast(),
                                    1,
                                );
                            }
                            let pose = &mut poses[k * pl..(k + 1) * pl];
                            walkers[k].pose(source, &params, dt, visible[k], pose, &mut lend);
                        }
                    }
                    let tc = Instant::now();
                    if out.fault.is_none() {
                        for ((((w, pose), joints), bin), bounds) in walkers
                            .iter_mut()
                            .zip(poses.chunks(pl))
                            .zip(joints.chunks_mut(npos))
                            .zip(bins.iter_mut())
                            .zip(bounds.iter_mut())
                        {
                            w.place(source, pose, joints);
                            *bounds = walker_bounds(w, margin);
                            *bin = params.levels.bin(&w.cur_detail) as u32;
                            out.in_transition += usize::from(w.in_transition());
                        }
                    }
                    let td = Instant::now();
                    out.cpu = [ta - t_scan, tb - ta, tc - tb, td - tc];
                    out
                },
            )
            .reduce(ChunkOutcome::default, ChunkOutcome::merge);
        if let Some((walker, e)) = pass.fault {
            // Chunks after the fault placed nobody: recompute every box from the roots.
            self.update_bounds();
            return Err(walker_error(walker, e, &params));
        }
        let t4 = Instant::now();
        let wall = t4 - t1;
        let cpu: Duration = pass.cpu.iter().sum();
        let share = |d: Duration| {
            if cpu.is_zero() {
                wall / 4
            } else {
                wall.mul_f64(d.as_secs_f64() / cpu.as_secs_f64())
            }
        };
        let [scanned, kernels, poses] = [0, 1, 2].map(|i| share(pass.cpu[i]));

        stats.timings = StageTimings {
            cull: (t1 - t0) + scanned,
            kernels,
            poses,
            fk: wall.saturating_sub(scanned + kernels + poses),
        };
        stats.level_histogram.clear();
        stats
            .level_histogram
            .resize(params.levels.histogram_bins(), 0);
        for &b in &self.bins {
            stats.level_histogram[b as usize] += 1;
        }
        stats.in_transition = pass.in_transition;
        stats.visible = if scan { pass.visible } else { tree_visible };
        stats.kernels_built = pass.built;
        stats.allocations = self.stock.take_allocations();
        stats.clip_faults = pass.clip_faults;
        self.frame += 1;
        self.time_s += f64::from(dt);
        Ok(())
    }

    /// Runs `frames` frames at `dt = 1 / config.fps` with the camera of `path` (lens and image
    /// from `lens`) and aggregates their statistics.
    pub fn run<S, P>(
        &mut self,
        source: &S,
        policy: &P,
        path: &CameraPath,
        lens: &Camera,
        frames: usize,
    ) -> Result<CrowdReport, CrowdError>
    where
        S: ClipSource<Clip = C>,
        P: LevelPolicy + Sync + ?Sized,
    {
        let dt = 1.0 / self.config.fps;
        let mut report = CrowdReport::with_frames(frames);
        let mut stats = FrameStats::default();
        for _ in 0..frames {
            let cam = path.camera_at(self.time_s as f32, lens);
            self.step_into(source, policy, &cam, dt, &mut stats)?;
            report.add(&stats);
        }
        Ok(report)
    }
}

impl<C> Crowd<C> {
    /// Number of walkers.
    pub fn len(&self) -> usize {
        self.walkers.len()
    }

    /// Always false: a crowd has at least one walker.
    pub fn is_empty(&self) -> bool {
        self.walkers.is_empty()
    }

    /// The field size asked for, when it was too small for the source's turn range and the crowd
    /// enlarged it (see [`Crowd::new`]); `None` when the field was used as given.
    pub fn field_enlarged_from(&self) -> Option<f32> {
        self.field_enlarged_from
    }

    /// The configuration in use (with the field size enlarged when the source's turn range needed
    /// it, see [`Crowd::new`]).
    pub fn config(&self) -> &CrowdConfig {
        &self.config
    }

    /// The source's level table.
    pub fn levels(&self) -> LevelTable {
        self.params.levels
    }

    /// Bones for drawing (copied from the source).
    pub fn bones(&self) -> &[(usize, usize)] {
        &self.bones
    }

    /// Frames stepped so far.
    pub fn frame(&self) -> u64 {
        self.frame
    }

    /// Simulated seconds so far.
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// World joint positions of walker `i` after the last step (root first; empty before the
    /// first step).
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn joint_positions(&self, i: usize) -> &[Vec3] {
        let npos = self.params.levels.joints + 1;
        &self.joints[i * npos..i * npos + self.walkers[i].n_joints]
    }

    /// World root position of walker `i` after the last step (its path start before).
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn root_position(&self, i: usize) -> Vec3 {
        self.walkers[i].root
    }

    /// Whether walker `i`'s box intersected the frustum in the last step.
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn is_visible(&self, i: usize) -> bool {
        self.visible[i]
    }

    /// Visibility flags of all walkers from the last step.
    pub fn visible_flags(&self) -> &[bool] {
        &self.visible
    }

    /// Culling boxes used in the last step.
    pub fn bounds(&self) -> &[Bounds] {
        &self.bounds
    }

    /// Detail of walker `i`'s current clip.
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn detail(&self, i: usize) -> Detail {
        self.walkers[i].cur_detail
    }

    /// Level histogram bin of walker `i` (see `FrameStats::level_histogram`).
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn level_bin(&self, i: usize) -> usize {
        self.params.levels.bin(&self.walkers[i].cur_detail)
    }

    /// The path of walker `i`.
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn path(&self, i: usize) -> &EllipsePath {
        &self.walkers[i].path
    }

    /// Standing height of walker `i` (m).
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn height(&self, i: usize) -> f32 {
        self.walkers[i].height
    }

    /// Controls of walker `i`'s current cycle (after clamping).
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn controls(&self, i: usize) -> Controls {
        self.walkers[i].controls
    }

    /// Walker `i`'s current cycle frame: origin `(x, z)` and heading, in double precision.
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn cycle_frame(&self, i: usize) -> CycleFrame {
        self.walkers[i].frame
    }

    /// Pose vector of walker `i` from the last step, in its cycle frame ([`Crowd::cycle_frame`]):
    /// the rows its clip wrote (the runtime's row layout, `ClipSource`), seam transition applied.
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn pose(&self, i: usize) -> &[f32] {
        let pl = self.params.levels.pose_len;
        &self.poses[i * pl..i * pl + self.walkers[i].rows.min(pl)]
    }

    /// Whether walker `i` is inside a seam transition.
    ///
    /// # Panics
    ///
    /// If `i >= len()`.
    pub fn in_transition(&self, i: usize) -> bool {
        self.walkers[i].in_transition()
    }
}
/// The crowd error for walker `walker`'s fault.
fn walker_error(walker: usize, e: WalkerFault, params: &StageParams) -> CrowdError {
    match e {
        WalkerFault::Duration(duration) => CrowdError::BadClipDuration { walker, duration },
        WalkerFault::Level(d) if d.accuracy >= params.levels.accuracy_levels => {
            CrowdError::BadLevel {
                walker,
                level: d.accuracy,
                levels: params.levels.accuracy_levels,
            }
        }
        WalkerFault::Level(d) => CrowdError::BadJoints {
            walker,
            level: d.accuracy,
            active_joints: d.active_joints,
            joints: params.levels.joints,
        },
    }
}
