//! Clip kernels: the per-clip part of pose synthesis (kriging weights, blended core, `G(c)`, time
//! table) and the per-frame pose evaluation.
//!
//! For controls `c` at an accuracy level with ranks `(r_P, r_T, r_S)` of key `(Z, U_P, U_T, Q, V)`:
//! 1. `gamma_i(c) = variogram(|scale(c) - c_i|)` and `[U_S^T b ; C b] = Q [gamma(c) ; 1]`
//!    (appendix A, with `b(c)` the kriging weights);
//! 2. `w = U_S^T b + V ([c ; 1] - C b)`, so that eq. 8, `K(c) = F [c;1] + sum_i b_i (K_i - F [c_i;1])`
//!    with `F = K C^+`, becomes `K(c) = Z x_3 w`;
//! 3. `G(c) = U_P[:P', :] K(c)` (`P' x r_T`, eq. 7);
//! 4. per frame `pose(tau) = G w_T`, `w_T = (1 - a) U_T[i, :] + a U_T[i + 1, :]` (eq. 5).
//!
//! A truncated accuracy level uses the leading blocks `Z[:r_P, :r_T, :r_S]`, `U_P[:, :r_P]`,
//! `U_T[:, :r_T]` and the first `r_S` rows of the `U_S^T` part of `Q` and of `V` (all `d + 1` rows
//! of the `C` part are kept). This equals the paper's universal kriging of the truncated sample
//! cores, with the trend refitted to them: `F_trunc = Z_t(12) U_S[:, :r_S]^T C^+`.

use crate::error::KernelError;
use crate::time_table::TimeTable;
use crate::variogram::{SquaredForm, linear_of_squared, spherical_of_squared};

use crate::chain::{RootMotion, exp_map_to_quat};
use crate::controls::Controls;
use crate::detail::Detail;
use crate::model::{ALWAYS_ROWS, CONTROL_VALUES, LodModel, Ranks, TIME_ROW};

/// Index of the control that is a clip's travel turn (radians, + = left): the heading of the
/// direction of travel changes by it over one cycle (the data's definition; the pelvis may turn by more
/// or less on cycles that enter or leave a turn).
pub const TURN_CONTROL: usize = 2;

/// Heading (yaw about +y, radians, 0 = +z, + = towards +x) of a root orientation given as an
/// exponential map.
pub fn yaw_of_exp_map(v: &[f32]) -> f32 {
    let f = exp_map_to_quat(glam::Vec3::new(v[0], v[1], v[2])) * glam::Vec3::Z;
    f.x.atan2(f.z)
}

/// The instruction-set build the kernel and pose loops run: the baseline (x86-64 SSE2, or any other
/// target) or, where the CPU has it, AVX2. Both builds perform the same floating-point operations in
/// the same order (no fused multiply-add is enabled), so they give the same bits; only the width of
/// the vector registers differs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Isa {
    Baseline,
    #[cfg(target_arch = "x86_64")]
    Avx2,
}

impl Isa {
    /// The best build the running CPU can take (detected once by the standard library, then a load).
    #[inline]
    fn current() -> Isa {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Isa::Avx2;
        }
        Isa::Baseline
    }
}

/// Defines the method `$avx2`, the AVX2 build of the `#[inline(always)]` method `$body::<AVX2>`
/// with the same arguments: the body is compiled again with AVX2 enabled and its const parameter
/// `AVX2` true (no FMA: the same operations in the same order, so the same bits; see [`Isa`]; the
/// parameter lets the body hold more sums in the wider registers). Callers check
/// [`Isa::current`] before calling it.
macro_rules! avx2_build {
    (fn $avx2:ident = $body:ident($($arg:ident: $ty:ty),* $(,)?) -> $ret:ty) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        fn $avx2(&self, $($arg: $ty),*) -> $ret {
            self.$body::<true>($($arg),*)
        }
    };
}

/// Most bytes of `G(c)` [`ClipKernel::prefetch`] hints at: a root-only or far clip's whole `G`; the
/// first rows of a full-detail one (its pose streams through the rest).
pub const PREFETCH_G_BYTES: usize = 1024;

/// Caller-owned working memory for [`LodModel::build_kernel`], sized for the largest level.
#[derive(Debug, Clone)]
pub struct KernelScratch {
    /// `[gamma(c) ; 1]`, length `S + 1`.
    x: Vec<f64>,
    /// `Q [gamma ; 1]` restricted to the used rows: `r_S` then `d + 1`.
    y: Vec<f64>,
    /// Scaled controls `[c' ; 1]`, length `d + 1`.
    c: Vec<f64>,
    /// Sample-mode weights `w`, length `max R_S`.
    w: Vec<f32>,
    /// Blended core `K(c)`, `r_P x r_T` column-major.
    k: Vec<f32>,
    /// Time increments of the `T` aligned frames.
    dt: Vec<f64>,
}

impl KernelScratch {
    /// Allocates scratch for every level of `model`.
    pub fn new(model: &LodModel) -> KernelScratch {
        let r = model.max_ranks();
        KernelScratch {
            x: vec![0.0; model.s() + 1],
            y: vec![0.0; r.s + model.d() + 1],
            c: vec![0.0; model.d() + 1],
            w: vec![0.0; r.s],
            k: vec![0.0; r.p * r.t],
            dt: vec![0.0; model.t()],
        }
    }

    /// Whether this scratch can serve [`LodModel::build_kernel`] for `model` (it holds nothing
    /// between builds, so any scratch of the right sizes will do).
    pub fn fits_model(&self, model: &LodModel) -> bool {
        self.fits(model).is_ok()
    }

    fn fits(&self, model: &LodModel) -> Result<(), KernelError> {
        let r = model.max_ranks();
        let ok = self.x.len() == model.s() + 1
            && self.y.len() > r.s + model.d()
            && self.c.len() == model.d() + 1
            && self.w.len() >= r.s
            && self.k.len() >= r.p * r.t
            && self.dt.len() == model.t();
        if ok {
            Ok(())
        } else {
            Err(KernelError::Capacity {
                what: "scratch",
                detail: format!(
                    "model S = {}, d = {}, max ranks {:?}",
                    model.s(),
                    model.d(),
                    r
                ),
            })
        }
    }
}

/// A clip kernel: `G(c)` for the evaluated rows and the clip's playback time table.
///
/// Allocated once per model with [`ClipKernel::new`] (for the largest level) and refilled by
/// [`LodModel::build_kernel`] without allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipKernel {
    /// The model's `P` and `T` (checked against the model that evaluates it; `u32` so that
    /// `frames_per_second` fits in the kernel's 128 bytes).
    p: u32,
    t: u32,
    detail: Detail,
    ranks: Ranks,
    rows: usize,
    clamped: bool,
    /// Sized for the clip's own level ([`ClipKernel::compact`]) rather than the largest.
    compact: bool,
    /// A compact kernel that keeps its buffer: it is never released for a smaller build, only
    /// grown for a larger one ([`ClipKernel::compact_holding`]). A flag rather than a size, so
    /// that it fits beside the other flags: a crowd holds a kernel in every walker, and 8 bytes
    /// more per kernel made its pose stage 10 % slower.
    keeps: bool,
    /// `(T - 1) / duration`, aligned frames per second of playback (0 until built): where
    /// [`ClipKernel::phase_at`] starts its search.
    frames_per_second: f32,
    /// `G(c)`, `rows x r_T` column-major (capacity `P x max R_T`, or exactly `rows x r_T` when
    /// compact).
    g: Vec<f32>,
    /// Playback times of the `T` aligned frames (incremental inverse timewarp).
    times: TimeTable,
    /// Root motion from the first to the last aligned frame ([`crate::chain`]).
    root_motion: RootMotion,
}

/// A model dimension as stored in a kernel (`P`, `T`: far below `u32::MAX`; a larger one, which
/// no model has, saturates and then matches no model's).
fn dim_u32(n: usize) -> u32 {
    u32::try_from(n).unwrap_or(u32::MAX)
}

impl ClipKernel {
    /// Preallocates a kernel for the largest level of `model`. Until it is built it holds the
    /// smallest level with `G = 0` (every row then reads as zero; the time table is flat).
    pub fn new(model: &LodModel) -> ClipKernel {
        let r = model.max_ranks();
        let last = model.levels().len() - 1;
        ClipKernel {
            p: dim_u32(model.p()),
            t: dim_u32(model.t()),
            detail: model.root_only(),
            ranks: model.levels()[last].ranks,
            rows: model.always_rows(),
            clamped: false,
            compact: false,
            keeps: false,
            frames_per_second: 0.0,
            g: vec![0.0; model.p() * r.t],
            times: TimeTable::with_capacity(model.t()),
            root_motion: RootMotion::default(),
        }
    }

    /// A kernel whose `G(c)` buffer is sized for the level it is built at, not the largest: it
    /// starts at the root-only size (`7 x r_T` of the smallest level) and
    /// [`LodModel::build_kernel`] resizes it to `P' x r_T` of each build (allocating when a build
    /// needs more than the buffer holds, releasing memory when it needs less than half). A crowd
    /// of mostly far or culled walkers then holds a few hundred bytes per walker instead of
    /// `4 P max R_T`. Until it is built it reads as [`ClipKernel::new`]'s does.
    pub fn compact(model: &LodModel) -> ClipKernel {
        let last = model.levels().len() - 1;
        let ranks = model.levels()[last].ranks;
        let rows = model.always_rows();
        ClipKernel {
            compact: true,
            keeps: false,
            frames_per_second: 0.0,
            g: vec![0.0; rows * ranks.t],
            times: TimeTable::with_capacity(model.t()),
            p: dim_u32(model.p()),
            t: dim_u32(model.t()),
            detail: model.root_only(),
            ranks,
            rows,
            clamped: false,
            root_motion: RootMotion::default(),
        }
    }

    /// A compact kernel ([`ClipKernel::compact`]) whose buffer holds `entries` floats from the
    /// start and keeps them: a build that needs at most `entries` ([`LodModel::kernel_entries`])
    /// never allocates or frees (a larger one grows the buffer, which is then kept). A crowd keeps
    /// such kernels in a few sizes and lends each walker one of the size its detail needs, so that
    /// a walker that comes near or goes far exchanges kernels instead of resizing one. Until it is
    /// built it reads as [`ClipKernel::new`]'s does.
    ///
    /// `entries` is capped at the most any build of `model` needs (`P x max R_T`), so that a
    /// huge request neither overflows nor allocates more than the model can use.
    pub fn compact_holding(model: &LodModel, entries: usize) -> ClipKernel {
        let mut kernel = ClipKernel::compact(model);
        let most = model.p().saturating_mul(model.max_ranks().t);
        kernel
            .g
            .reserve_exact(entries.min(most).saturating_sub(kernel.g.len()));
        kernel.keeps = true;
        kernel
    }

    /// Puts a kernel whose build failed part-way back to the unbuilt state of
    /// [`ClipKernel::new`] (the smallest level, `G = 0`, no time table), keeping its buffer.
    fn reset_unbuilt(&mut self, model: &LodModel) {
        let last = model.levels().len() - 1;
        self.detail = model.root_only();
        self.ranks = model.levels()[last].ranks;
        self.rows = model.always_rows();
        self.clamped = false;
        self.frames_per_second = 0.0;
        let need = self.rows * self.ranks.t;
        if self.g.len() < need {
            self.g.resize(need, 0.0);
        }
        self.g.fill(0.0);
        self.times.clear();
        self.root_motion = RootMotion::default();
    }

    /// Whether the kernel is sized per level ([`ClipKernel::compact`]).
    pub fn is_compact(&self) -> bool {
        self.compact
    }

    /// Bytes held on the heap by this kernel (its `G(c)` buffer and the entries of its time table).
    pub fn heap_bytes(&self) -> usize {
        self.g.capacity() * std::mem::size_of::<f32>()
            + self.times.len() * std::mem::size_of::<f64>()
    }

    /// The detail this kernel was built with.
    pub fn detail(&self) -> Detail {
        self.detail
    }
    /// The accuracy level index of its detail.
    pub fn level(&self) -> usize {
        self.detail.accuracy
    }
    /// Ranks of its accuracy level.
    pub fn ranks(&self) -> Ranks {
        self.ranks
    }
    /// Number of evaluated rows `P'`.
    pub fn rows(&self) -> usize {
        self.rows
    }
    /// True when some control was outside the data range and was clamped.
    pub fn clamped(&self) -> bool {
        self.clamped
    }
    /// `G(c)` as a `rows x r_T` column-major matrix.
    pub fn g(&self) -> &[f32] {
        &self.g[..self.rows * self.ranks.t]
    }
    /// The clip's root motion: the root's ground displacement `(dx, dz)` from the first to the last
    /// aligned frame in the cycle frame, and the travel turn (the clamped turn control,
    /// [`TURN_CONTROL`]; when the model ignores turn, the turn the data imply for the other controls,
    /// [`crate::ControlSpace::implied`]; the pelvis's yaw change for a model without a turn
    /// dimension). The next cycle frame
    /// follows from it ([`crate::CycleFrame::next`]).
    pub fn root_motion(&self) -> RootMotion {
        self.root_motion
    }
    /// The clip's time table: playback time (seconds) of each aligned frame, built from the
    /// time-increment row (row 6) of `G(c)` at every aligned frame ([`TimeTable`]: the
    /// increment of the last frame is unused, increments below [`crate::MIN_INCREMENT`] are
    /// raised to it). Empty until the kernel is built.
    pub fn time_table(&self) -> &TimeTable {
        &self.times
    }
    /// Playback duration of the clip in seconds: the time of aligned frame `T - 1`.
    pub fn duration(&self) -> f64 {
        self.times.duration()
    }
    /// Hints the CPU to fetch the memory [`ClipKernel::phase_at`] and [`LodModel::pose_rows`] read
    /// (the time table and the evaluated `G(c)`, at most `PREFETCH_G_BYTES` (1 KiB) of it) without waiting
    /// for it ([`crate::math::prefetch_bytes`]), so that a caller can start those cache misses a few
    /// walkers ahead. No effect on any result.
    #[inline]
    pub fn prefetch(&self) {
        crate::math::prefetch_slice(self.times.times());
        let g = &self.g[..(self.rows * self.ranks.t).min(self.g.len())];
        let bytes = std::mem::size_of_val(g).min(PREFETCH_G_BYTES);
        crate::math::prefetch_bytes(g.as_ptr().cast::<u8>(), bytes);
    }

    /// Phase (fractional aligned frame in `[0, T - 1]`) at playback time `seconds` (clamped to
    /// `[0, duration]`, NaN gives 0), by inverting the piecewise linear time table: with
    /// `t_j <= seconds < t_{j+1}`, `phase = j + (seconds - t_j) / (t_{j+1} - t_j)`.
    #[inline]
    pub fn phase_at(&self, seconds: f64) -> f32 {
        // `TimeTable::phase_at`'s result (the same interval and arithmetic), with the interval
        // found from a guess by uniform spacing and a short walk instead of a binary search: one
        // or two cache lines of the table instead of four to six dependent reads.
        let times = self.times.times();
        let n = times.len();
        if n < 2 {
            return 0.0;
        }
        let duration = times[n - 1];
        let t = seconds.max(0.0).min(duration);
        // A table's length is a frame count, far below 2^32: conversions through `u32` are exact
        // (single instructions, where `usize` needs an unsigned fix-up). The guess needs no
        // precision (the walk corrects it) and no division.
        let guess = (t as f32 * self.frames_per_second) as u32 as usize;
        // The last k <= n - 2 with times[k] <= t (or 0), as the binary search finds it. The guess
        // is most often right or one off: one step down or up without a branch (both tests read
        // within the table), then the walk for what is left (rarely a step).
        let mut k = guess.min(n - 2);
        k -= usize::from((k > 0) & (times[k] > t));
        k += usize::from((k + 2 < n) & (times[k + 1] <= t));
        while k > 0 && times[k] > t {
            k -= 1;
        }
        while k + 2 < n && times[k + 1] <= t {
            k += 1;
        }
        let (t0, t1) = (times[k], times[k + 1]);
        let f = crate::time_table::interval_fraction(t, t0, t1);
        (k as u32 as f64 + f) as f32
    }
}

/// `h2_i += (c - samples_i)^2` over contiguous samples.
fn add_squared_differences(h2: &mut [f64], c: f64, samples: &[f32]) {
    for (h, &si) in h2.iter_mut().zip(samples) {
        let diff = c - f64::from(si);
        *h += diff * diff;
    }
}

/// `x_i = gamma(h2_i)` with `h2_i = sum_k (c_k - samples_k,i)^2` over the three or four controls
/// `used` (in that order, from the first square: `0 + a^2` is `a^2`, so the sums are those of
/// [`add_squared_differences`] from zero), in one pass over the samples; returns false without
/// writing when `used` holds another number of controls.
#[inline(always)]
fn squared_distances<'a>(
    x: &mut [f64],
    used: &[usize],
    col: impl Fn(usize) -> &'a [f32],
    cv: impl Fn(usize) -> f64,
    gamma: impl Fn(f64) -> f64,
) -> bool {
    match *used {
        [a, b, e, f] => {
            let (ca, cb, ce, cf) = (cv(a), cv(b), cv(e), cv(f));
            let it = col(a).iter().zip(col(b)).zip(col(e)).zip(col(f));
            for (g, (((&sa, &sb), &se), &sf)) in x.iter_mut().zip(it) {
                let (da, db) = (ca - f64::from(sa), cb - f64::from(sb));
                let (de, df) = (ce - f64::from(se), cf - f64::from(sf));
                *g = gamma(((da * da + db * db) + de * de) + df * df);
            }
            true
        }
        [a, b, e] => {
            let (ca, cb, ce) = (cv(a), cv(b), cv(e));
            let it = col(a).iter().zip(col(b)).zip(col(e));
            for (g, ((&sa, &sb), &se)) in x.iter_mut().zip(it) {
                let (da, db) = (ca - f64::from(sa), cb - f64::from(sb));
                let de = ce - f64::from(se);
                *g = gamma((da * da + db * db) + de * de);
            }
            true
        }
        _ => false,
    }
}

/// Partial sums per row of [`dot_rows`]: element `i` goes to sum `i % LANES`.
const LANES: usize = 4;

/// `a . x` in f64 with [`LANES`] partial sums, combined as `(s0 + s2) + (s1 + s3)` after the
/// elements beyond the last full group of `LANES` were added to their sums (a fixed order, so
/// deterministic): the sum of each row of [`dot_rows`], which is tested against it.
#[cfg(test)]
fn dot_row(a: &[f64], x: &[f64]) -> f64 {
    debug_assert_eq!(a.len(), x.len());
    let mut acc = [0.0f64; LANES];
    let (ca, cx) = (a.chunks_exact(LANES), x.chunks_exact(LANES));
    let (ra, rx) = (ca.remainder(), cx.remainder());
    for (p, q) in ca.zip(cx) {
        for i in 0..LANES {
            acc[i] += p[i] * q[i];
        }
    }
    for i in 0..ra.len() {
        acc[i] += ra[i] * rx[i];
    }
    (acc[0] + acc[2]) + (acc[1] + acc[3])
}

/// Most rows [`dot_rows`] sums in one pass in the baseline build: their `LANES`-wide sums take
/// two SSE registers each, eight rows all sixteen.
const MAX_ROW_GROUP: usize = 8;

/// Most rows [`dot_rows`] sums in one pass in the AVX2 build: a 256-bit register per row's sums,
/// twelve of the sixteen, so that a root-only clip's nine rows are one pass over `x` (nine
/// chains of additions in flight, where two passes of five and four each waited on theirs).
const MAX_ROW_GROUP_AVX2: usize = 12;

/// `out[r] = a_r . x` for `R` consecutive rows `a_r = a[(l + r) n..(l + r + 1) n]` in one pass
/// over `x` (each element of `x` loaded once for `R` rows), each row summed exactly as [`dot_row`]
/// sums it.
#[inline(always)]
fn dot_row_group<const R: usize>(a: &[f64], x: &[f64], l: usize, out: &mut [f64]) {
    let n = x.len();
    assert!(
        out.len() == R && a.len() >= (l + R) * n,
        "R rows of x.len() from row l"
    );
    let rows = a[l * n..(l + R) * n].as_ptr();
    let mut acc = [[0.0f64; LANES]; R];
    let full = n - n % LANES;
    let mut j = 0;
    while j < full {
        // SAFETY: `j + LANES <= full <= n`, so `x[j..j + LANES]` and, for `r < R`, row `r`'s
        // entries `rows[r n + j..r n + j + LANES]` lie within `x` and the `R n` entries of `rows`
        // (asserted above). Unchecked reads: a bounds check per row and step cost as much as the
        // multiply-adds and held the row slices in memory instead of registers.
        let q = unsafe { x.as_ptr().add(j).cast::<[f64; LANES]>().read_unaligned() };
        for (r, acc) in acc.iter_mut().enumerate() {
            let p = unsafe { rows.add(r * n + j).cast::<[f64; LANES]>().read_unaligned() };
            for i in 0..LANES {
                acc[i] += p[i] * q[i];
            }
        }
        j += LANES;
    }
    for (r, (acc, o)) in acc.iter_mut().zip(out.iter_mut()).enumerate() {
        let row = &a[(l + r) * n..(l + r + 1) * n];
        for i in 0..n - full {
            acc[i] += row[full + i] * x[full + i];
        }
        *o = (acc[0] + acc[2]) + (acc[1] + acc[3]);
    }
}

/// `out[l] = a_l . x` for the rows `a_l = a[l n..(l + 1) n]`, `n = x.len()`, each row summed
/// exactly as [`dot_row`] sums it, so a row's result does not depend on the rows beside it.
/// The rows are taken in balanced passes of at most `MAX` rows ([`MAX_ROW_GROUP`] in the
/// baseline build, [`MAX_ROW_GROUP_AVX2`] in the AVX2 build): one pass loads `x` once for all its
/// rows, and keeps as many independent sums in flight as the registers hold, so that no pass waits
/// on a single chain of additions (with eight: nine rows are five and four, not eight and one).
#[inline(always)]
fn dot_rows<const MAX: usize>(a: &[f64], x: &[f64], out: &mut [f64]) {
    let rows = out.len();
    debug_assert!(a.len() >= x.len() * rows && (1..=12).contains(&MAX));
    let passes = rows.div_ceil(MAX);
    let mut l = 0;
    for pass in 0..passes {
        // Balanced sizes: the first `rows % passes` passes take one row more.
        let size = rows / passes + usize::from(pass < rows % passes);
        let o = &mut out[l..l + size];
        match size {
            1 => dot_row_group::<1>(a, x, l, o),
            2 => dot_row_group::<2>(a, x, l, o),
            3 => dot_row_group::<3>(a, x, l, o),
            4 => dot_row_group::<4>(a, x, l, o),
            5 => dot_row_group::<5>(a, x, l, o),
            6 => dot_row_group::<6>(a, x, l, o),
            7 => dot_row_group::<7>(a, x, l, o),
            8 => dot_row_group::<8>(a, x, l, o),
            // (Guarded by `MAX`, so that a build with fewer rows a pass keeps no code for more.)
            9 if MAX >= 9 => dot_row_group::<9>(a, x, l, o),
            10 if MAX >= 10 => dot_row_group::<10>(a, x, l, o),
            11 if MAX >= 11 => dot_row_group::<11>(a, x, l, o),
            12 if MAX >= 12 => dot_row_group::<12>(a, x, l, o),
            _ => unreachable!("a pass holds at most MAX <= 12 rows"),
        }
        l += size;
    }
}

/// Largest `r_T` whose time weights a pose holds on the stack (larger ones take the column loop).
const POSE_COLUMNS: usize = 128;

/// Outputs per wide block of [`combine_columns`]: eight 256-bit registers of sums, enough
/// independent additions to keep both of a core's vector adders busy while each waits on its own
/// previous sum.
const COMBINE_BLOCK: usize = 64;

/// `sum_j coef[j] col_j[start..start + B]` over the columns `col_j = cols[stride j..]` in order
/// from `0.0`, the `B` sums held in registers over all columns.
#[inline(always)]
fn block_sums<const B: usize>(start: usize, coef: &[f32], cols: &[f32], stride: usize) -> [f32; B] {
    let mut acc = [0.0f32; B];
    let cols = &cols[start..];
    for (j, &c) in coef.iter().enumerate() {
        let v: &[f32; B] = cols[stride * j..stride * j + B]
            .try_into()
            .expect("a block of B entries");
        for i in 0..B {
            acc[i] += c * v[i];
        }
    }
    acc
}

/// `out[start..start + B] = `[`block_sums`]`::<B>(start, ..)`.
#[inline(always)]
fn combine_block<const B: usize>(
    out: &mut [f32],
    start: usize,
    coef: &[f32],
    cols: &[f32],
    stride: usize,
) {
    out[start..start + B].copy_from_slice(&block_sums::<B>(start, coef, cols, stride));
}

/// `out[i] = sum_j coef[j] cols[stride j + i]` for `j = 0..coef.len()` in order, starting from
/// `0.0` (so each entry is bitwise the plain loop `out.fill(0.0); for j { out[i] += coef[j] *
/// col_j[i] }`, `col_j = cols[stride j..]`). Blocks of [`COMBINE_BLOCK`] outputs (then 32, then 8)
/// stay in registers over all columns instead of being loaded and stored once per column. The last
/// few outputs are the last eight recomputed as one block: the outputs it shares with the blocks
/// before get the same sums, so the same bits. An output shorter than eight is one block of eight
/// when every column has eight entries to read, else summed one entry at a time. Every column has
/// at least `out.len()` entries.
#[inline(always)]
fn combine_columns(out: &mut [f32], coef: &[f32], cols: &[f32], stride: usize) {
    let len = out.len();
    debug_assert!(coef.is_empty() || cols.len() >= stride * (coef.len() - 1) + len);
    let mut start = 0;
    while start + COMBINE_BLOCK <= len {
        combine_block::<COMBINE_BLOCK>(out, start, coef, cols, stride);
        start += COMBINE_BLOCK;
    }
    if start + 32 <= len {
        combine_block::<32>(out, start, coef, cols, stride);
        start += 32;
    }
    while start + 8 <= len {
        combine_block::<8>(out, start, coef, cols, stride);
        start += 8;
    }
    if start == len {
        return;
    }
    if len >= 8 {
        combine_block::<8>(out, len - 8, coef, cols, stride);
    } else if coef
        .len()
        .checked_sub(1)
        .is_none_or(|last| stride * last + 8 <= cols.len())
    {
        // An output shorter than eight whose columns have eight entries to read (the rows of
        // `U_P` a root-only clip combines): one block of eight sums, of which the first `len`
        // are kept (each the same sum in the same order; the others read whatever follows).
        out.copy_from_slice(&block_sums::<8>(0, coef, cols, stride)[..len]);
    } else {
        // One entry at a time (a partial vector held across columns would be spilled with masked
        // stores, which stall the loads after them), each stored as it is summed.
        for (i, o) in out.iter_mut().enumerate() {
            let mut sum = 0.0f32;
            for (j, &c) in coef.iter().enumerate() {
                sum += c * cols[stride * j + i];
            }
            *o = sum;
        }
    }
}

/// `y += M[:y.len(), :] x` for `M` column-major with column stride `stride` (f32, one column per
/// entry of `x`), accumulating in f64. Four columns per pass (fewer loop trips, loads in flight);
/// each `y_l` still adds its terms one column at a time in column order, so the result is bitwise
/// that of the plain column loop.
fn accumulate_columns(y: &mut [f64], m: &[f32], stride: usize, x: &[f64]) {
    let n = y.len();
    debug_assert!(n <= stride && m.len() >= stride * x.len());
    let mut blocks = m.chunks_exact(4 * stride);
    let mut xs = x.chunks_exact(4);
    for (block, xb) in blocks.by_ref().zip(xs.by_ref()) {
        let (c0, rest) = block.split_at(stride);
        let (c1, rest) = rest.split_at(stride);
        let (c2, c3) = rest.split_at(stride);
        let (c0, c1, c2, c3) = (&c0[..n], &c1[..n], &c2[..n], &c3[..n]);
        for l in 0..n {
            let mut a = y[l];
            a += f64::from(c0[l]) * xb[0];
            a += f64::from(c1[l]) * xb[1];
            a += f64::from(c2[l]) * xb[2];
            a += f64::from(c3[l]) * xb[3];
            y[l] = a;
        }
    }
    let done = x.len() - xs.remainder().len();
    for (j, &xj) in x.iter().enumerate().skip(done) {
        let col = &m[stride * j..][..n];
        for (yl, &q) in y.iter_mut().zip(col) {
            *yl += f64::from(q) * xj;
        }
    }
}

/// The seven root rows of a pose, `sum_b w_b G[r, b]` for `r < 7` over the `r_T` columns of `G`
/// (column stride `rows`), each summed in column order from `0.0` with `w_b = wb(b)`: entries
/// `0..7` of the result (the eighth is scratch). The seven sums run as eight lanes (a column read
/// eight entries wide, the eighth summed and dropped; the last column from a copy when `G` ends
/// with it): the same operations per lane, so the same bits as the plain loop used elsewhere. The
/// AVX2 build runs [`root_sums_avx2`] instead.
#[inline(always)]
fn root_sums(g: &[f32], rows: usize, rt: usize, wb: impl Fn(usize) -> f32) -> [f32; 8] {
    let (wide, last) = root_columns(g, rows, rt);
    let mut acc = [0.0f32; 8];
    for b in 0..wide {
        // SAFETY: `b < wide` ([`root_columns`]). Unchecked: the check per column cost as much as
        // its sums.
        let col = unsafe { g.as_ptr().add(rows * b).cast::<[f32; 8]>().read_unaligned() };
        let w = wb(b);
        for (a, &v) in acc.iter_mut().zip(&col) {
            *a += w * v;
        }
    }
    if wide < rt {
        let w = wb(wide);
        for (a, &v) in acc.iter_mut().zip(&last) {
            *a += w * v;
        }
    }
    acc
}

/// The columns [`root_sums`] reads eight entries wide from `G` itself, `0..wide`, and a copy of
/// the last column padded to eight when `G` ends with it (`wide = r_T - 1`). Column `b < wide`
/// starts at `rows b` with `rows b + 8 <= g.len()`: when `wide = r_T` by its test; else
/// `b <= r_T - 2` and `rows (r_T - 2) + 8 <= rows r_T` as `rows >= 7`, asserted here.
#[inline(always)]
fn root_columns(g: &[f32], rows: usize, rt: usize) -> (usize, [f32; 8]) {
    // What the unchecked loads rely on (`check_kernel` has made sure of it).
    assert!(
        rows >= ALWAYS_ROWS && g.len() >= rows * rt,
        "G holds rows x r_T"
    );
    let wide = if rt > 0 && rows * (rt - 1) + 8 <= g.len() {
        rt
    } else {
        rt.saturating_sub(1)
    };
    let mut last = [0.0f32; 8];
    if wide < rt {
        last[..ALWAYS_ROWS].copy_from_slice(&g[rows * wide..][..ALWAYS_ROWS]);
    }
    (wide, last)
}

/// [`root_sums`] for `r_T <= 8` columns in one 256-bit register, with the time weights `w` (lane
/// `b` for column `b`) in another: each column read eight entries wide (the eighth summed and
/// dropped; the last column from a copy when `G` ends with it), its weight broadcast from its
/// lane, the same multiply and add per lane in the same order, so the same bits. Kept apart from
/// `root_sums` because the compiler narrows a portable eight-lane loop whose eighth lane is
/// dropped to four, two and one lanes.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn root_sums_avx2(g: &[f32], rows: usize, rt: usize, w: &[f32; 8]) -> [f32; 8] {
    use std::arch::x86_64::{
        _mm256_add_ps, _mm256_loadu_ps, _mm256_mul_ps, _mm256_permutevar8x32_ps, _mm256_set1_epi32,
        _mm256_setzero_ps, _mm256_storeu_ps,
    };
    assert!(rt <= 8, "at most eight columns");
    let (wide, last) = root_columns(g, rows, rt);
    let mut acc = [0.0f32; 8];
    // SAFETY: column `b < wide` has eight floats in `g` ([`root_columns`]); the last column's
    // eight are `last`; the loads of `w` and the store read and write arrays of eight.
    unsafe {
        let lanes = _mm256_loadu_ps(w.as_ptr());
        // The weight of column `b` in every lane (`b < 8`: a lane index).
        let weight = |b: usize| _mm256_permutevar8x32_ps(lanes, _mm256_set1_epi32(b as i32));
        let mut sum = _mm256_setzero_ps();
        for b in 0..wide {
            let col = _mm256_loadu_ps(g.as_ptr().add(rows * b));
            sum = _mm256_add_ps(sum, _mm256_mul_ps(weight(b), col));
        }
        if wide < rt {
            let col = _mm256_loadu_ps(last.as_ptr());
            sum = _mm256_add_ps(sum, _mm256_mul_ps(weight(wide), col));
        }
        _mm256_storeu_ps(acc.as_mut_ptr(), sum);
    }
    acc
}

/// The two aligned frames `i`, `i1` a pose at finite `phase` blends and the blend `a`:
/// `phase` clamped to `[0, T - 1]`, `i = floor(phase)` (at most `T - 2`), `i1 = min(i + 1, T - 1)`,
/// `a = phase - i` (eq. 4).
#[inline(always)]
fn blend_at(phase: f32, t: usize) -> (usize, usize, f32) {
    // `T` is a frame count, far below 2^24: its conversions through `u32` are exact (single
    // instructions, where `usize` to `f32` needs an unsigned fix-up), and for `ph >= 0`
    // truncation is `floor`.
    let ph = phase.clamp(0.0, (t - 1) as u32 as f32);
    let i = (ph as u32 as usize).min(t.saturating_sub(2));
    let i1 = (i + 1).min(t - 1);
    (i, i1, ph - i as u32 as f32)
}

/// The seven root rows of `G w_T` for the blend `(i, i1, a)` of rows of `U_T` (`u` row-major
/// with `big_t` columns and at least eight entries from each row's start, as
/// [`LodModel::time_rows`] pads it): [`root_sums`] with the time weights
/// `w_b = (1 - a) U_T[i, b] + a U_T[i1, b]`. Up to eight columns (a root-only clip's `r_T`) the
/// weights are computed eight lanes at once (the same operations per lane) and the AVX2 build
/// sums in [`root_sums_avx2`].
#[inline(always)]
fn root_rows<const AVX2: bool>(
    kernel: &ClipKernel,
    u: &[f32],
    big_t: usize,
    (i, i1, a): (usize, usize, f32),
) -> [f32; 8] {
    let (g, rows, rt) = (&kernel.g[..], kernel.rows, kernel.ranks.t);
    if rt <= 8 {
        let (u0, u1): (&[f32; 8], &[f32; 8]) = (
            u[i * big_t..][..8].try_into().expect("eight entries"),
            u[i1 * big_t..][..8].try_into().expect("eight entries"),
        );
        let mut w = [0.0f32; 8];
        for (l, w) in w.iter_mut().enumerate() {
            *w = (1.0 - a) * u0[l] + a * u1[l];
        }
        #[cfg(target_arch = "x86_64")]
        if AVX2 {
            // SAFETY: `AVX2` is true only in the AVX2 build, which runs where the CPU has it.
            return unsafe { root_sums_avx2(g, rows, rt, &w) };
        }
        root_sums(g, rows, rt, |b| w[b])
    } else {
        let (u0, u1) = (&u[i * big_t..][..rt], &u[i1 * big_t..][..rt]);
        root_sums(g, rows, rt, |b| (1.0 - a) * u0[b] + a * u1[b])
    }
}

impl LodModel {
    fn check_kernel(&self, kernel: &ClipKernel) -> Result<(), KernelError> {
        if kernel.p != dim_u32(self.p())
            || kernel.t != dim_u32(self.t())
            || (!kernel.compact && kernel.g.len() < self.p() * self.max_ranks().t)
            || kernel.g.len() < kernel.rows * kernel.ranks.t
            || kernel.detail.accuracy >= self.levels().len()
        {
            return Err(KernelError::Capacity {
                what: "kernel",
                detail: format!(
                    "kernel P = {}, T = {}; model P = {}, T = {}",
                    kernel.p,
                    kernel.t,
                    self.p(),
                    self.t()
                ),
            });
        }
        Ok(())
    }

    /// Builds the clip kernel for `controls` at `detail`, into `out`, without allocating: the job
    /// an engine runs once per gait cycle.
    ///
    /// Controls outside the data's `[min, max]` are clamped (reported by
    /// [`ClipKernel::clamped`]); NaN or infinite controls, a model whose control space is not the
    /// walk's ([`Controls::COUNT`] dimensions) or an unknown accuracy level are errors. Active
    /// joints above the model's count are an error ([`KernelError::Joints`], as
    /// [`LodModel::check_detail`] says). A model whose values are so large that the clip
    /// overflows (a kriging weight, `G(c)`, the duration or the root motion would not be finite,
    /// or a pose could be) is an error too ([`KernelError::Overflow`]; the kernel is then left
    /// unbuilt). Cost
    /// `O((R_S + d) S + r_P r_T r_S + P' r_P r_T + T r_T)`, see [`LodModel::kernel_cost`].
    pub fn build_kernel(
        &self,
        controls: &Controls,
        detail: Detail,
        scratch: &mut KernelScratch,
        out: &mut ClipKernel,
    ) -> Result<(), KernelError> {
        let mut values = [0.0f32; CONTROL_VALUES];
        let d = self.control_values(controls, &mut values)?;
        self.build_kernel_isa(Isa::current(), &values[..d], detail, scratch, out, false)
    }

    /// [`LodModel::build_kernel`] for a raw control vector of the model's `d` dimensions (any
    /// `d`): for tests of control spaces other than the walk's (feature `reference`).
    #[cfg(feature = "reference")]
    pub fn build_kernel_values(
        &self,
        controls: &[f32],
        detail: Detail,
        scratch: &mut KernelScratch,
        out: &mut ClipKernel,
    ) -> Result<(), KernelError> {
        self.build_kernel_isa(Isa::current(), controls, detail, scratch, out, false)
    }

    /// [`LodModel::build_kernel_values`] run by the baseline build of its loops (x86-64 SSE2)
    /// whatever the CPU (feature `reference`). `build_kernel` runs an AVX2 build where the CPU has it; both perform the same
    /// floating-point operations in the same order (no fused multiply-add), so they give the same
    /// bits. This one exists to check that.
    #[cfg(feature = "reference")]
    pub fn build_kernel_baseline(
        &self,
        controls: &[f32],
        detail: Detail,
        scratch: &mut KernelScratch,
        out: &mut ClipKernel,
    ) -> Result<(), KernelError> {
        self.build_kernel_isa(Isa::Baseline, controls, detail, scratch, out, false)
    }

    /// [`LodModel::build_kernel`] with the kriging projections accumulated column by column, in
    /// the order they are stored (one multiply-add per sample and row, summed in sample order),
    /// instead of as row-major dot products with several partial sums. The two differ by rounding
    /// only (relative `1e-15` in the weights); this straightforward form is the reference the
    /// fast path is tested against (feature `reference`; raw control vector of length `d`).
    #[cfg(feature = "reference")]
    pub fn build_kernel_reference(
        &self,
        controls: &[f32],
        detail: Detail,
        scratch: &mut KernelScratch,
        out: &mut ClipKernel,
    ) -> Result<(), KernelError> {
        self.build_kernel_isa(Isa::current(), controls, detail, scratch, out, true)
    }

    /// The sample-mode kriging weights `w` of key `key` for `controls`, truncated to its first
    /// `r_s` sample components: steps 1-4 of the module documentation,
    /// `w = U_S^T b(c) + V ([c' ; 1] - C b(c))` with `b(c)` the kriging weights of the scaled,
    /// clamped controls `c'`. The same numbers [`LodModel::build_kernel`] blends the core with; the
    /// returned slice (length `r_s`) lives in `scratch`. No allocation.
    ///
    /// Errors: a model whose control space is not the walk's or a non-finite control, a key out of
    /// range or `r_s` not in `1..=R_S` of that key ([`KernelError::Key`]), scratch sized for
    /// another model.
    pub fn kriging_weights<'s>(
        &self,
        controls: &Controls,
        key: usize,
        r_s: usize,
        scratch: &'s mut KernelScratch,
    ) -> Result<&'s [f32], KernelError> {
        let mut values = [0.0f32; CONTROL_VALUES];
        let d = self.control_values(controls, &mut values)?;
        self.kriging_weights_checked(&values[..d], key, r_s, scratch, false)
    }

    /// [`LodModel::kriging_weights`] for a raw control vector of length `d` (any `d`; feature
    /// `reference`).
    #[cfg(feature = "reference")]
    pub fn kriging_weights_values<'s>(
        &self,
        controls: &[f32],
        key: usize,
        r_s: usize,
        scratch: &'s mut KernelScratch,
    ) -> Result<&'s [f32], KernelError> {
        self.kriging_weights_checked(controls, key, r_s, scratch, false)
    }

    /// [`LodModel::kriging_weights`] for a raw control vector of length `d`, with the projections
    /// accumulated in stored column order as [`LodModel::build_kernel_reference`] does (the two
    /// differ by rounding only; feature `reference`).
    #[cfg(feature = "reference")]
    pub fn kriging_weights_reference<'s>(
        &self,
        controls: &[f32],
        key: usize,
        r_s: usize,
        scratch: &'s mut KernelScratch,
    ) -> Result<&'s [f32], KernelError> {
        self.kriging_weights_checked(controls, key, r_s, scratch, true)
    }

    fn kriging_weights_checked<'s>(
        &self,
        controls: &[f32],
        key: usize,
        r_s: usize,
        scratch: &'s mut KernelScratch,
        column_order: bool,
    ) -> Result<&'s [f32], KernelError> {
        self.check_query_controls(controls)?;
        let keys = self.keys().len();
        let max = self.keys().get(key).map_or(0, |k| k.ranks.s);
        if key >= keys || r_s == 0 || r_s > max {
            return Err(KernelError::Key {
                key,
                r_s,
                keys,
                max,
            });
        }
        scratch.fits(self)?;
        self.weights_in(controls, key, r_s, scratch, column_order);
        Ok(&scratch.w[..r_s])
    }

    /// A control vector of length `d` with finite entries.
    fn check_query_controls(&self, controls: &[f32]) -> Result<(), KernelError> {
        let d = self.d();
        if controls.len() != d {
            return Err(KernelError::ControlLength {
                expected: d,
                found: controls.len(),
            });
        }
        if let Some(index) = controls.iter().position(|v| !v.is_finite()) {
            return Err(KernelError::NonFiniteControl {
                index,
                value: controls[index],
            });
        }
        Ok(())
    }

    /// Steps 1-4 for checked `controls`, key `key_index` and `r_s <= R_S` of that key into
    /// `scratch.w[..r_s]` (and `scratch.c` the scaled controls); returns whether a control was
    /// clamped. Runs the AVX2 build of [`LodModel::weights_body`] where the CPU has it.
    fn weights_in(
        &self,
        controls: &[f32],
        key_index: usize,
        r_s: usize,
        scratch: &mut KernelScratch,
        column_order: bool,
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if Isa::current() == Isa::Avx2 {
            // SAFETY: the CPU has AVX2 (`Isa::current`).
            return unsafe { self.weights_avx2(controls, key_index, r_s, scratch, column_order) };
        }
        self.weights_body::<false>(controls, key_index, r_s, scratch, column_order)
    }

    avx2_build!(fn weights_avx2 = weights_body(
        controls: &[f32],
        key_index: usize,
        r_s: usize,
        scratch: &mut KernelScratch,
        column_order: bool
    ) -> bool);

    /// Steps 1-4 (see [`LodModel::weights_in`]), inlined into each instruction-set build (`AVX2`
    /// true only in the AVX2 build, which runs only where the CPU has AVX2).
    #[inline(always)]
    fn weights_body<const AVX2: bool>(
        &self,
        controls: &[f32],
        key_index: usize,
        r_s: usize,
        scratch: &mut KernelScratch,
        column_order: bool,
    ) -> bool {
        let (s, d) = (self.s(), self.d());
        let key = &self.keys()[key_index];
        let big = key.ranks;
        debug_assert!(r_s <= big.s && controls.len() == d);
        // 1. Clamp and scale the controls: c'_k = (clamp(c_k) - offset_k) * scale_k.
        let cs = self.controls();
        let mut clamped = false;
        for (k, &raw) in controls.iter().enumerate() {
            let v = raw.clamp(cs.min[k], cs.max[k]);
            clamped |= v != raw;
            scratch.c[k] = (f64::from(v) - f64::from(cs.offset[k])) * f64::from(cs.scale[k]);
        }
        scratch.c[d] = 1.0;

        // 2. x = [gamma(c) ; 1], gamma_i = variogram(|c' - c_i|). The squared distances are summed
        //    one control at a time over contiguous samples (vectorised; the same additions in the
        //    same order as summing per sample), and the variogram is applied to each (in the same
        //    pass where it has a branch-free form and three or four controls are used).
        //    A control with scale 0 (constant over the data) adds exactly +0 and is skipped.
        let x = &mut scratch.x[..s];
        let mut used = [0usize; 4];
        let mut n_used = 0;
        for k in (0..d).filter(|&k| cs.scale[k] != 0.0) {
            if n_used < used.len() {
                used[n_used] = k;
            }
            n_used += 1;
        }
        // Three or four used controls in one pass (in control order, so the sums are the same),
        // with the variogram applied to each squared distance as it is summed where the variogram
        // has a branch-free form (the same operations as applying it after, one pass less).
        let col = |k: usize| &cs.samples[s * k..s * (k + 1)];
        let cv = |k: usize| scratch.c[k];
        // (More than four: none here, the general path below.)
        let few = used.get(..n_used).unwrap_or(&[]);
        let fused = match cs.variogram.squared_form() {
            Some(SquaredForm::Spherical {
                nugget,
                sill,
                inv_range,
            }) => squared_distances(x, few, col, cv, |h2| {
                spherical_of_squared(h2, nugget, sill, inv_range)
            }),
            Some(SquaredForm::Linear { nugget, sill }) => {
                squared_distances(x, few, col, cv, |h2| linear_of_squared(h2, nugget, sill))
            }
            None => false,
        };
        if !fused {
            // The distances first (three or four controls in one pass, else one control at a
            // time), then the variogram.
            if !squared_distances(x, few, col, cv, |h2| h2) {
                x.fill(0.0);
                for k in (0..d).filter(|&k| cs.scale[k] != 0.0) {
                    add_squared_differences(x, cv(k), col(k));
                }
            }
            cs.variogram.eval_squared(x);
        }
        scratch.x[s] = 1.0;

        if column_order {
            // 3. y = [U_S^T b (first r_S rows) ; C b] = [Q x ; P_C x], Q column-major R_S x (S + 1)
            //    (the key's), P_C column-major (d + 1) x (S + 1) (the control space's, every key's).
            let y = &mut scratch.y[..r_s + d + 1];
            y.fill(0.0);
            let (y_top, y_c) = y.split_at_mut(r_s);
            accumulate_columns(y_top, &key.projection, big.s, &scratch.x);
            accumulate_columns(y_c, &cs.projection, d + 1, &scratch.x);
            // 4. w = U_S^T b + V ([c' ; 1] - C b), V column-major R_S x (d + 1).
            for l in 0..r_s {
                let mut acc = y[l];
                for m in 0..=d {
                    acc += f64::from(key.trend[l + big.s * m]) * (scratch.c[m] - y[r_s + m]);
                }
                scratch.w[l] = acc as f32;
            }
        } else {
            // 3-4 folded: w = A x + V [c' ; 1], A = Q_top - V P_C row-major f64
            //    ([`crate::model::FoldedProjections`]).
            let a = &self.folded().a[key_index];
            let y = &mut scratch.y[..r_s];
            if AVX2 {
                dot_rows::<MAX_ROW_GROUP_AVX2>(a, &scratch.x[..=s], y);
            } else {
                dot_rows::<MAX_ROW_GROUP>(a, &scratch.x[..=s], y);
            }
            for (l, (&yl, wl)) in y.iter().zip(&mut scratch.w[..r_s]).enumerate() {
                let mut acc = yl;
                for m in 0..=d {
                    acc += f64::from(key.trend[l + big.s * m]) * scratch.c[m];
                }
                *wl = acc as f32;
            }
        }

        clamped
    }

    /// Steps 1-8 with the instruction-set build chosen by the caller ([`Isa::Avx2`] falls back to
    /// the baseline where the CPU lacks AVX2) and the kriging sums in stored column order or folded.
    fn build_kernel_isa(
        &self,
        isa: Isa,
        controls: &[f32],
        detail: Detail,
        scratch: &mut KernelScratch,
        out: &mut ClipKernel,
        column_order: bool,
    ) -> Result<(), KernelError> {
        #[cfg(target_arch = "x86_64")]
        if isa == Isa::Avx2 && Isa::current() == Isa::Avx2 {
            // SAFETY: the CPU has AVX2 (`Isa::current`).
            return unsafe { self.build_kernel_avx2(controls, detail, scratch, out, column_order) };
        }
        let _ = isa;
        self.build_kernel_body::<false>(controls, detail, scratch, out, column_order)
    }

    avx2_build!(fn build_kernel_avx2 = build_kernel_body(
        controls: &[f32],
        detail: Detail,
        scratch: &mut KernelScratch,
        out: &mut ClipKernel,
        column_order: bool
    ) -> Result<(), KernelError>);

    /// Steps 1-8 of the module documentation, inlined into each instruction-set build (`AVX2` as
    /// in [`LodModel::weights_body`]).
    #[inline(always)]
    fn build_kernel_body<const AVX2: bool>(
        &self,
        controls: &[f32],
        detail: Detail,
        scratch: &mut KernelScratch,
        out: &mut ClipKernel,
        column_order: bool,
    ) -> Result<(), KernelError> {
        let (p, t) = (self.p(), self.t());
        self.check_query_controls(controls)?;
        let level = self.check_detail(detail)?.accuracy;
        scratch.fits(self)?;
        self.check_kernel(out)?;

        let lv = self.levels()[level];
        let key = &self.keys()[lv.key];
        let big = key.ranks;
        let r = lv.ranks;
        let rows = self.active_rows(detail.active_joints);
        debug_assert!(rows <= p && r.fits_in(&big));

        // 1-4. The sample-mode kriging weights w (first r_S) into scratch.w.
        let clamped = self.weights_body::<AVX2>(controls, lv.key, r.s, scratch, column_order);
        // (A weight that is not finite: the model's projections or variogram overflow for these
        // controls. `O(r_S)`, before anything is written to `out`.)
        if let Some(index) = scratch.w[..r.s].iter().position(|w| !w.is_finite()) {
            return Err(KernelError::Overflow {
                what: "kriging weights",
                index,
                value: f64::from(scratch.w[index]),
            });
        }

        // 5. K(c) = Z[:r_P, :r_T, :r_S] x_3 w, stored r_P x r_T column-major: each entry sums its
        //    `r_S` terms in order from 0. When the level keeps the key's whole `r_P x r_T` slab (a
        //    contiguous run of `Z` per sample component), the slab is one long combination.
        let kmat = &mut scratch.k[..r.p * r.t];
        let w = &scratch.w[..r.s];
        if r.p == big.p && r.t == big.t {
            let slab = big.p * big.t;
            combine_columns(kmat, w, &key.core, slab);
        } else {
            for (b, kcol) in kmat.chunks_exact_mut(r.p).enumerate() {
                combine_columns(kcol, w, &key.core[big.p * b..], big.p * big.t);
            }
        }
        let kmat = &*kmat;

        // 6. G(c) = U_P[:rows, :r_P] K(c), rows x r_T column-major (each entry sums its `r_P` terms
        //    in order from 0).
        if out.compact {
            let need = rows * r.t;
            // A kernel that keeps its buffer is reallocated only to grow.
            let cap = out.g.capacity();
            if cap < need || (!out.keeps && cap > 2 * need) {
                out.g = Vec::with_capacity(need);
            }
            out.g.resize(need, 0.0);
        }
        let g = &mut out.g[..rows * r.t];
        for (b, gcol) in g.chunks_exact_mut(rows).enumerate() {
            let kcol = &kmat[r.p * b..][..r.p];
            combine_columns(gcol, kcol, &key.u_p, p);
        }
        // A pose sums `r_T` products of an entry of `G` with a time weight of at most the key's
        // largest `|U_T|`: entries within `limit` keep every pose (and the difference of two, the
        // root motion) finite. One pass over what was just written (building it took `r_P` times
        // as long); NaN and infinity fail the test too.
        let limit = 0.25 * f64::from(f32::MAX)
            / (r.t.max(1) as f64 * f64::from(self.u_t_max(lv.key)).max(1.0));
        let limit = limit as f32;
        // (A branch-free fold, which the compiler vectorises; the position only on failure.)
        let within = g.iter().fold(true, |ok, v| ok & (v.abs() <= limit));
        if !within {
            let index = g
                .iter()
                .position(|v| v.is_nan() || v.abs() > limit)
                .unwrap_or(0);
            let value = f64::from(g[index]);
            out.reset_unbuilt(self);
            return Err(KernelError::Overflow {
                what: "G(c)",
                index,
                value,
            });
        }

        // 7. Time table from the time-increment row at every aligned frame:
        //    dt_j = G[6, :] . U_T[j, :r_T] / time_scale.
        //    Summed one column of U_T at a time over all frames (contiguous, vectorised), each dt_j
        //    adding its r_T terms in order from -0.0 as `Iterator::sum` does: the same bits.
        let g = &*g;
        let inv_scale = 1.0 / self.parts().time_scale;
        let dt = &mut scratch.dt[..t];
        dt.fill(-0.0);
        for b in 0..r.t {
            let gb = f64::from(g[TIME_ROW + rows * b]);
            for (d, &u) in dt.iter_mut().zip(&key.u_t[t * b..t * (b + 1)]) {
                *d += gb * f64::from(u);
            }
        }
        out.times.fill_scaled(dt, inv_scale);
        let duration = out.times.duration();
        if !duration.is_finite() {
            out.reset_unbuilt(self);
            return Err(KernelError::Overflow {
                what: "duration",
                index: t - 1,
                value: duration,
            });
        }
        out.frames_per_second = ((t - 1) as f64 / duration) as f32;

        out.detail = detail;
        out.ranks = r;
        out.rows = rows;
        out.clamped = clamped;

        // 8. Root motion: the root's ground displacement from the first to the last aligned frame, and
        //    the travel turn (the clamped turn control; when the model ignores turn, the turn the data
        //    imply for the other controls, `ControlSpace::implied`; the pelvis's yaw change for a model
        //    without a turn dimension).
        // The seven root rows (the root pose of `pose_rows`; root motion reads the first six).
        // (`::<false>`, inlined: the portable sums, the same bits, so that `root_sums_avx2` keeps
        // one call site, the root pose every frame, where it stays inlined.)
        let mut ends = [[0.0f32; ALWAYS_ROWS]; 2];
        for (e, phase) in ends.iter_mut().zip([0.0, (t - 1) as f32]) {
            self.root_pose_body::<false>(out, phase, e)?;
        }
        let [start, end] = ends;
        let motion = self.controls().root_motion_of(controls, &start, &end);
        let parts = [motion.dx, motion.dz, motion.turn];
        if let Some(index) = parts.iter().position(|v| !v.is_finite()) {
            out.reset_unbuilt(self);
            return Err(KernelError::Overflow {
                what: "root motion",
                index,
                value: f64::from(parts[index]),
            });
        }
        out.root_motion = motion;
        Ok(())
    }

    /// Writes the pose at `phase` (fractional aligned frame, clamped to `[0, T - 1]`) into `out`
    /// (length `P`): rows `0..P'` from the kernel, `G w_T` with
    /// `w_T = (1 - a) U_T[i, :r_T] + a U_T[i + 1, :r_T]`, `i = floor(phase)`, `a = phase - i`
    /// (eq. 4-5), and rows `P'..P` from the mean pose. `O(P' r_T)`, no allocation.
    pub fn pose(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        if out.len() != self.p() {
            return Err(KernelError::OutputLength {
                expected: self.p(),
                found: out.len(),
            });
        }
        self.pose_rows(kernel, phase, out)
    }

    /// Writes the first `out.len()` rows (at most `P`) of the pose at `phase`, as [`LodModel::pose`]
    /// does for all of them: rows the kernel evaluated from `G w_T`, later rows from the mean pose.
    /// With `out.len() = 7` it evaluates only the root and the time increment, `O(7 r_T)`.
    ///
    /// Runs an AVX2 build of the same operations where the CPU has AVX2 (the same bits).
    #[inline]
    pub fn pose_rows(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        self.pose_rows_isa(Isa::current(), kernel, phase, out)
    }

    /// [`LodModel::pose_rows`] run by the baseline build (x86-64 SSE2) whatever the CPU: the same
    /// bits as `pose_rows` (see [`LodModel::build_kernel_baseline`]; feature `reference`).
    #[cfg(feature = "reference")]
    pub fn pose_rows_baseline(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        self.pose_rows_isa(Isa::Baseline, kernel, phase, out)
    }

    /// [`LodModel::pose_rows`] with the instruction-set build chosen by the caller.
    #[inline]
    fn pose_rows_isa(
        &self,
        isa: Isa,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        // Root only (the crowd's far walkers, every frame): a small function of its own, without
        // the frame and spills of the general one.
        let root = out.len() == ALWAYS_ROWS;
        #[cfg(target_arch = "x86_64")]
        if isa == Isa::Avx2 && Isa::current() == Isa::Avx2 {
            // SAFETY: the CPU has AVX2 (`Isa::current`).
            return unsafe {
                if root {
                    self.root_pose_avx2(kernel, phase, out)
                } else {
                    self.pose_rows_avx2(kernel, phase, out)
                }
            };
        }
        let _ = isa;
        if root {
            self.root_pose_baseline(kernel, phase, out)
        } else {
            self.pose_rows_body(kernel, phase, out)
        }
    }

    avx2_build!(fn root_pose_avx2 = root_pose_body(
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32]
    ) -> Result<(), KernelError>);

    /// The baseline build of [`LodModel::root_pose_body`].
    fn root_pose_baseline(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        self.root_pose_body::<false>(kernel, phase, out)
    }

    /// [`LodModel::pose_rows_body`] for `out.len() = 7` (the root and the time increment): the
    /// same checks and the same sums, in a function of its own.
    #[inline(always)]
    fn root_pose_body<const AVX2: bool>(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        debug_assert_eq!(out.len(), ALWAYS_ROWS);
        self.check_kernel(kernel)?;
        // (`P >= 7`: a model has its root rows, so `out.len() <= P`.)
        let (key_index, blend) = self.pose_blend(kernel, phase)?;
        let big_t = self.keys()[key_index].ranks.t;
        let acc = root_rows::<AVX2>(kernel, self.time_rows(key_index), big_t, blend);
        out.copy_from_slice(&acc[..ALWAYS_ROWS]);
        Ok(())
    }

    /// The key of a checked kernel's level and the blend of rows of its `U_T` a pose at `phase`
    /// reads ([`blend_at`]); a phase that is not finite is an error.
    #[inline(always)]
    fn pose_blend(
        &self,
        kernel: &ClipKernel,
        phase: f32,
    ) -> Result<(usize, (usize, usize, f32)), KernelError> {
        if !phase.is_finite() {
            return Err(KernelError::NonFinitePhase { phase });
        }
        let level = &self.levels()[kernel.detail.accuracy];
        // A kernel another model built (the same `P` and `T`) may hold more ranks or rows than
        // this model's level: its `G` would be read against rows of `U_T` that do not exist.
        if !kernel.ranks.fits_in(&level.ranks) || kernel.rows > self.p() {
            return Err(KernelError::Capacity {
                what: "kernel",
                detail: format!(
                    "kernel built with ranks {:?} and {} rows; this model's level {} has ranks {:?}, P = {}",
                    kernel.ranks,
                    kernel.rows,
                    kernel.detail.accuracy,
                    level.ranks,
                    self.p()
                ),
            });
        }
        Ok((level.key, blend_at(phase, self.t())))
    }

    /// The AVX2 build of [`LodModel::pose_rows_body`] (see [`Isa`]).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn pose_rows_avx2(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        self.pose_rows_body(kernel, phase, out)
    }

    /// The pose rows, inlined into each instruction-set build.
    #[inline(always)]
    fn pose_rows_body(
        &self,
        kernel: &ClipKernel,
        phase: f32,
        out: &mut [f32],
    ) -> Result<(), KernelError> {
        let p = self.p();
        self.check_kernel(kernel)?;
        if out.len() > p {
            return Err(KernelError::OutputLength {
                expected: p,
                found: out.len(),
            });
        }
        let (key_index, (i, i1, a)) = self.pose_blend(kernel, phase)?;
        let key = &self.keys()[key_index];
        let rows = kernel.rows;
        let used = rows.min(out.len());
        let rt = kernel.ranks.t;
        let (head, tail) = out.split_at_mut(used);
        // Rows i and i1 of U_T, contiguous (row-major copy).
        let big_t = key.ranks.t;
        let u = self.time_rows(key_index);
        let (u0, u1) = (&u[i * big_t..][..rt], &u[i1 * big_t..][..rt]);
        let wb = |b: usize| (1.0 - a) * u0[b] + a * u1[b];
        if used >= 8 && rt <= POSE_COLUMNS {
            // Many rows: blocks of rows held in registers over the `r_T` columns.
            let mut w = [0.0f32; POSE_COLUMNS];
            for (b, v) in w[..rt].iter_mut().enumerate() {
                *v = wb(b);
            }
            combine_columns(head, &w[..rt], &kernel.g, rows);
        } else if used == ALWAYS_ROWS {
            // Root only (`out` longer than the seven rows: the root pose itself goes to
            // `root_pose_body`): the seven sums held in registers over the columns (the same sums
            // in the same order as the column loop below; the portable sums, so that
            // `root_sums_avx2` keeps its one call site).
            let acc = root_rows::<false>(kernel, u, big_t, (i, i1, a));
            head.copy_from_slice(&acc[..ALWAYS_ROWS]);
        } else {
            // A few rows: one pass per column (the same sums in the same order).
            head.fill(0.0);
            for b in 0..rt {
                let w = wb(b);
                let gcol = &kernel.g[rows * b..][..used];
                for (o, &gv) in head.iter_mut().zip(gcol) {
                    *o += w * gv;
                }
            }
        }
        let n = tail.len();
        if n > 0 {
            tail.copy_from_slice(&self.mean_pose()[used..used + n]);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocked_columns_equal_the_plain_column_loop_bitwise() {
        let (stride, n, cols) = (11, 9, 803);
        let m: Vec<f32> = (0..stride * cols)
            .map(|i| ((i * 7919) % 1000) as f32 / 300.0 - 1.6)
            .collect();
        let x: Vec<f64> = (0..cols)
            .map(|j| ((j * 31) % 97) as f64 / 13.0 - 3.0)
            .collect();
        let mut blocked = vec![0.5f64; n];
        accumulate_columns(&mut blocked, &m, stride, &x);
        let mut plain = vec![0.5f64; n];
        for (j, &xj) in x.iter().enumerate() {
            for (l, y) in plain.iter_mut().enumerate() {
                *y += f64::from(m[stride * j + l]) * xj;
            }
        }
        assert_eq!(blocked, plain);
    }

    #[test]
    fn combined_columns_equal_the_plain_column_loop_bitwise() {
        // Every length up to 140 (wide blocks, a 32-block, 8-blocks, the overlapping last eight
        // and lengths under eight) and the model's shapes.
        let cases = (0..=140usize)
            .flat_map(|len| [(len, 1usize), (len, 9)])
            .chain([(986, 60), (67, 29), (7, 5), (29, 34)]);
        for (len, n) in cases {
            // Columns of `len + 3` entries one after the other (stride `len + 3`).
            let cols: Vec<Vec<f32>> = (0..n)
                .map(|j| {
                    (0..len + 3)
                        .map(|i| (((i + 1) * (j + 7) * 7919) % 1000) as f32 / 300.0 - 1.6)
                        .collect()
                })
                .collect();
            let flat: Vec<f32> = cols.concat();
            let coefs: Vec<f32> = (0..n)
                .map(|j| ((j * 31) % 97) as f32 / 13.0 - 3.0)
                .collect();
            let mut got = vec![f32::NAN; len];
            combine_columns(&mut got, &coefs, &flat, len + 3);
            let mut want = vec![0.0f32; len];
            for j in 0..n {
                for i in 0..len {
                    want[i] += coefs[j] * cols[j][i];
                }
            }
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&want), "len {len}, {n} columns");
        }
    }

    #[test]
    fn root_sums_equal_the_plain_column_loop_bitwise() {
        // Root-only clips (stride 7, `G` exactly `7 r_T` long: the last column from a copy) and
        // clips with joints asked for the root rows (stride above 7, or `G` longer than needed).
        for (rows, rt, extra) in [
            (7, 1, 0),
            (7, 7, 0),
            (7, 7, 1),
            (7, 8, 0),
            (8, 8, 0),
            (7, 34, 0),
            (8, 5, 0),
            (67, 29, 0),
        ] {
            let g: Vec<f32> = (0..rows * rt + extra)
                .map(|i| ((i * 7919) % 1000) as f32 / 300.0 - 1.6)
                .collect();
            let wb = |b: usize| ((b * 31) % 97) as f32 / 13.0 - 3.0;
            let mut want = [0.0f32; ALWAYS_ROWS];
            for b in 0..rt {
                for r in 0..ALWAYS_ROWS {
                    want[r] += wb(b) * g[rows * b + r];
                }
            }
            let mut builds = vec![("portable", root_sums(&g, rows, rt, wb))];
            #[cfg(target_arch = "x86_64")]
            if Isa::current() == Isa::Avx2 && rt <= 8 {
                let w: [f32; 8] = std::array::from_fn(wb);
                // SAFETY: the CPU has AVX2.
                builds.push(("avx2", unsafe { root_sums_avx2(&g, rows, rt, &w) }));
            }
            for (build, got) in builds {
                for r in 0..ALWAYS_ROWS {
                    assert_eq!(
                        got[r].to_bits(),
                        want[r].to_bits(),
                        "{build}: rows {rows} r_T {rt} row {r}"
                    );
                }
            }
        }
    }

    /// A crowd holds a kernel in every walker: it stays within two cache lines (8 bytes more made
    /// the crowd's pose stage 10 % slower once).
    #[test]
    fn a_kernel_fits_in_two_cache_lines() {
        assert!(std::mem::size_of::<ClipKernel>() <= 128);
    }

    #[test]
    fn rows_dotted_in_groups_equal_single_row_dots_bitwise() {
        // Every row count from 1 to 20 (passes of one to eight rows, or to twelve in the AVX2
        // build's grouping), lengths with and without a tail.
        for (n, rows) in [801usize, 800, 3, 4]
            .into_iter()
            .flat_map(|n| (1..=20).map(move |r| (n, r)))
        {
            let a: Vec<f64> = (0..rows * n)
                .map(|i| ((i * 7919) % 1000) as f64 / 300.0 - 1.6)
                .collect();
            let x: Vec<f64> = (0..n)
                .map(|j| ((j * 31) % 97) as f64 / 13.0 - 3.0)
                .collect();
            let mut grouped = vec![0.0; rows];
            let mut grouped_avx2 = vec![0.0; rows];
            dot_rows::<MAX_ROW_GROUP>(&a, &x, &mut grouped);
            dot_rows::<MAX_ROW_GROUP_AVX2>(&a, &x, &mut grouped_avx2);
            for l in 0..rows {
                assert_eq!(
                    grouped[l].to_bits(),
                    grouped_avx2[l].to_bits(),
                    "n {n} row {l}"
                );
                let row = &a[l * n..(l + 1) * n];
                assert_eq!(
                    grouped[l].to_bits(),
                    dot_row(row, &x).to_bits(),
                    "n {n} row {l}"
                );
                let plain: f64 = row.iter().zip(&x).map(|(p, q)| p * q).sum();
                assert!(
                    (grouped[l] - plain).abs() <= 1e-12 * (1.0 + plain.abs()),
                    "n {n} row {l}: {} vs {plain}",
                    grouped[l]
                );
            }
        }
    }
}
