//! Walker paths: seeded closed ellipses over the field, and the controller that turns "the path
//! ahead" into the controls of the next gait cycle.
//!
//! Ground coordinates are `(x, z)` as a `Vec2`; a heading `h` faces `(sin h, cos h)` and its left
//! is `(cos h, -sin h)` (positive heading change = turn left, as in `docs/architecture.md`).

use glam::{DVec2, Vec2};
use lod_policy::SplitMix64;
use lod_policy::{ControlRange, Controls, wrap_angle_f64};
use std::f32::consts::{PI, TAU};

/// Newton steps [`EllipsePath::closest_param_near`] takes at most.
const NEWTON_STEPS: usize = 8;
/// Newton step (rad) below which the closest-point search has converged.
const NEWTON_TOLERANCE: f64 = 1e-9;

/// Heading of a non-zero ground direction `d`: `atan2(d.x, d.z)`.
pub fn heading_of(d: Vec2) -> f32 {
    d.x.atan2(d.y)
}

/// A closed elliptic path `p(s) = c + R(rot) (a cos s, b sin s)`, travelled with increasing `s`
/// when `dir = 1` and decreasing `s` when `dir = -1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EllipsePath {
    /// Centre on the ground (m).
    pub centre: Vec2,
    /// Semi-axes `(a, b)` (m), `a >= b > 0`.
    pub axes: Vec2,
    /// Rotation of the major axis (rad).
    pub rot: f32,
    /// Direction of travel, +1 or -1.
    pub dir: f32,
}

/// `v` rotated by the angle whose `(sin, cos)` is `sc`.
fn rotate_by((s, c): (f32, f32), v: Vec2) -> Vec2 {
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

impl EllipsePath {
    fn rotate(&self, v: Vec2) -> Vec2 {
        rotate_by(self.rot.sin_cos(), v)
    }

    /// Point at parameter `s`.
    pub fn point(&self, s: f32) -> Vec2 {
        self.point_rotated(self.rot.sin_cos(), s)
    }

    /// [`EllipsePath::point`] with `rot_sc = self.rot.sin_cos()` given (the same bits; a search
    /// that evaluates many points computes it once).
    fn point_rotated(&self, rot_sc: (f32, f32), s: f32) -> Vec2 {
        self.centre
            + rotate_by(
                rot_sc,
                Vec2::new(self.axes.x * s.cos(), self.axes.y * s.sin()),
            )
    }

    /// Derivative `dp/ds` times `dir` (the direction of travel, not normalised).
    pub fn velocity(&self, s: f32) -> Vec2 {
        self.dir * self.rotate(Vec2::new(-self.axes.x * s.sin(), self.axes.y * s.cos()))
    }

    /// Smallest radius of curvature, `b^2 / a`.
    pub fn min_radius_of_curvature(&self) -> f32 {
        self.axes.y * self.axes.y / self.axes.x
    }

    /// The rotation's `(sin, cos)` in double precision.
    pub(crate) fn rotation_f64(&self) -> (f64, f64) {
        f64::from(self.rot).sin_cos()
    }

    /// [`EllipsePath::point`] in double precision: `p(s) = c + R(rot) (a cos s, b sin s)` with
    /// the path's single-precision centre, axes and rotation widened. What the path controller
    /// reads ([`path_controls`]), so that its answer is the exact one rounded once (and the same
    /// on the GPU, which evaluates it in double-float arithmetic: `gpu-crowd`).
    pub fn point_f64(&self, s: f64) -> DVec2 {
        self.point_rotated_f64(self.rotation_f64(), s)
    }

    /// [`EllipsePath::point_f64`] with the rotation's `(sin, cos)` given (a search or the
    /// controller, evaluating several points, computes it once).
    fn point_rotated_f64(&self, rot: (f64, f64), s: f64) -> DVec2 {
        self.point_rotated_sc_f64(rot, s.sin_cos())
    }

    /// [`EllipsePath::point_rotated_f64`] with the parameter's `(sin, cos)` given as well (the
    /// controller reads the point and the velocity at one parameter).
    fn point_rotated_sc_f64(&self, (sr, cr): (f64, f64), (ss, cs): (f64, f64)) -> DVec2 {
        let (x, y) = (f64::from(self.axes.x) * cs, f64::from(self.axes.y) * ss);
        DVec2::new(
            f64::from(self.centre.x) + (cr * x - sr * y),
            f64::from(self.centre.y) + (sr * x + cr * y),
        )
    }

    /// [`EllipsePath::velocity`] in double precision: `dir R(rot) (-a sin s, b cos s)`.
    pub fn velocity_f64(&self, s: f64) -> DVec2 {
        self.velocity_rotated_f64(self.rotation_f64(), s)
    }

    /// [`EllipsePath::velocity_f64`] with the rotation's `(sin, cos)` given.
    fn velocity_rotated_f64(&self, rot: (f64, f64), s: f64) -> DVec2 {
        self.velocity_rotated_sc_f64(rot, s.sin_cos())
    }

    /// [`EllipsePath::velocity_rotated_f64`] with the parameter's `(sin, cos)` given as well.
    fn velocity_rotated_sc_f64(&self, (sr, cr): (f64, f64), (ss, cs): (f64, f64)) -> DVec2 {
        let (x, y) = (-f64::from(self.axes.x) * ss, f64::from(self.axes.y) * cs);
        let dir = f64::from(self.dir);
        DVec2::new(dir * (cr * x - sr * y), dir * (sr * x + cr * y))
    }

    /// Parameter of the point closest to `p` near `s_guess` (walkers stay close to their path, so
    /// a local answer suffices), in double precision: `s_guess + wrap(theta - s_guess)` with
    /// `theta` the closest point's angle in `(-pi, pi]`, found by Newton's method in the ellipse's
    /// own frame.
    ///
    /// With `(x, y) = R(-rot) (p - centre)`, the squared distance to `(a cos s, b sin s)` is
    /// stationary where `g(s) = (b^2 - a^2) sin s cos s + a x sin s - b y cos s = 0`, a minimum
    /// where `g'(s) = (b^2 - a^2) cos 2s + a x cos s + b y sin s > 0`. Newton's iteration
    /// `s <- s - g / g'` starts at `atan2(a y, b x)`, exact on a circle and close for points near
    /// the ellipse, and converges in a few steps (a few `sin_cos` where a sampled search takes
    /// fifty), to a step of at most 1e-9 rad. Where it cannot (`g' <= 0` on the way, no convergence
    /// in 8 steps, or an answer more than 0.9 rad from `s_guess`), the sampled search runs instead:
    /// 17 samples within `+-0.8` rad of `s_guess`, then golden-section refinement (to about `1e-4`
    /// rad).
    pub fn closest_param_near(&self, p: DVec2, s_guess: f64) -> f64 {
        self.closest_param_near_rotated(self.rotation_f64(), p, s_guess)
    }

    /// [`EllipsePath::closest_param_near`] with the rotation's `(sin, cos)` given (a walker at a
    /// cycle end computes it once for this and [`path_controls`]).
    pub(crate) fn closest_param_near_rotated(
        &self,
        rot: (f64, f64),
        p: DVec2,
        s_guess: f64,
    ) -> f64 {
        let (a, b) = (f64::from(self.axes.x), f64::from(self.axes.y));
        let (sr, cr) = rot;
        let (vx, vy) = (
            p.x - f64::from(self.centre.x),
            p.y - f64::from(self.centre.y),
        );
        let (x, y) = (cr * vx + sr * vy, -sr * vx + cr * vy);
        let k = b * b - a * a;
        let mut theta = (a * y).atan2(b * x);
        let mut converged = false;
        for _ in 0..NEWTON_STEPS {
            let (s, c) = theta.sin_cos();
            let g = k * s * c + a * x * s - b * y * c;
            let dg = k * (c * c - s * s) + a * x * c + b * y * s;
            if dg.is_nan() || dg <= 0.0 {
                break;
            }
            let step = g / dg;
            theta -= step;
            if step.abs() <= NEWTON_TOLERANCE {
                converged = true;
                break;
            }
        }
        let delta = wrap_angle_f64(theta - s_guess);
        if converged && delta.abs() <= 0.9 {
            s_guess + delta
        } else {
            self.closest_param_sampled(rot, p, s_guess)
        }
    }

    /// The sampled search [`EllipsePath::closest_param_near`] falls back on (`rot`: the
    /// rotation's `(sin, cos)`).
    fn closest_param_sampled(&self, rot: (f64, f64), p: DVec2, s_guess: f64) -> f64 {
        let d2 = |s: f64| self.point_rotated_f64(rot, s).distance_squared(p);
        let step = 0.1;
        let mut best = s_guess;
        let mut best_d = d2(s_guess);
        for k in -8..=8 {
            let s = s_guess + f64::from(k) * step;
            let d = d2(s);
            if d < best_d {
                best_d = d;
                best = s;
            }
        }
        let (mut lo, mut hi) = (best - step, best + step);
        let g = 0.618_034;
        for _ in 0..16 {
            let m1 = hi - g * (hi - lo);
            let m2 = lo + g * (hi - lo);
            if d2(m1) < d2(m2) { hi = m2 } else { lo = m1 }
        }
        0.5 * (lo + hi)
    }

    /// Distance from `p` to the path (global search: 720 samples then local refinement).
    pub fn distance_to(&self, p: Vec2) -> f32 {
        let mut best = 0.0;
        let mut best_d = f32::MAX;
        for k in 0..720 {
            let s = k as f32 * TAU / 720.0;
            let d = self.point(s).distance_squared(p);
            if d < best_d {
                best_d = d;
                best = s;
            }
        }
        let p = p.as_dvec2();
        let s = self.closest_param_near(p, f64::from(best));
        self.point_f64(s).distance(p) as f32
    }

    /// Draws a path that fits in the square field `[-field/2, field/2]^2` with `margin` to spare
    /// and whose radius of curvature is at least `min_radius`. Returns `None` when even the
    /// smallest such ellipse does not fit.
    pub fn random(g: &mut SplitMix64, field: f32, margin: f32, min_radius: f32) -> Option<Self> {
        let half = 0.5 * field - margin;
        let a_min = (1.5 * min_radius).max(3.0);
        if half < a_min {
            return None;
        }
        let a_max = half.min(40.0).max(a_min);
        let a = g.range(a_min, a_max);
        // b^2 / a >= min_radius  <=>  b >= sqrt(min_radius a).
        let b_min = (min_radius * a).sqrt().max(0.5 * a).min(a);
        let b = g.range(b_min, a);
        let lim = half - a;
        let centre = Vec2::new(g.range(-lim, lim), g.range(-lim, lim));
        let rot = g.range(0.0, PI);
        let dir = if g.next_u64() & 1 == 0 { 1.0 } else { -1.0 };
        Some(Self {
            centre,
            axes: Vec2::new(a, b),
            rot,
            dir,
        })
    }
}

/// Controls for the next cycle of a walker at `pos` with heading `heading` (its cycle frame's
/// origin and heading, `lod_policy::CycleFrame`), following `path` from parameter `s` with a
/// preferred stride `stride` (m per cycle), then clamped into `bounds`.
///
/// Pure pursuit one stride ahead: the target `T = p(s + dir L / |p'(s)|)` is expressed in the
/// walker's heading frame, `dx = (T - pos) . left(h)`, `dz = (T - pos) . forward(h)`, and
/// `turn = wrap(heading(p'(s_T)) - h)`. Lateral and heading errors are corrected within a few
/// cycles; the clamp keeps every request inside what the model covers.
///
/// Computed in double precision and rounded once: in single precision, points of a path tens of
/// metres from the origin carry 2e-6 m of rounding (and the platform's single-precision sine
/// misrounds about 1 value in 80), which the controller feeds back into the next cycles, so
/// that two implementations of it (this crate and the GPU crowd's shaders) would drift apart by
/// 1e-4 m within ten seconds.
pub fn path_controls(
    path: &EllipsePath,
    s: f64,
    pos: DVec2,
    heading: f64,
    stride: f32,
    height: f32,
    bounds: &ControlRange,
) -> Controls {
    let heading_sc = heading.sin_cos();
    path_controls_rotated(
        path,
        path.rotation_f64(),
        s,
        pos,
        (heading, heading_sc),
        stride,
        height,
        bounds,
    )
}

/// [`path_controls`] with the path's rotation `(sin, cos)` and the heading's given with the
/// heading (`(h, (sin h, cos h))`): the same bits, each sine computed once at a cycle end.
#[allow(clippy::too_many_arguments)]
pub(crate) fn path_controls_rotated(
    path: &EllipsePath,
    rot: (f64, f64),
    s: f64,
    pos: DVec2,
    (heading, (sh, ch)): (f64, (f64, f64)),
    stride: f32,
    height: f32,
    bounds: &ControlRange,
) -> Controls {
    let speed = path.velocity_rotated_f64(rot, s).length().max(1e-3);
    let s_t = s + f64::from(path.dir) * f64::from(stride) / speed;
    let sc_t = s_t.sin_cos();
    let d = path.point_rotated_sc_f64(rot, sc_t) - pos;
    let vt = path.velocity_rotated_sc_f64(rot, sc_t);
    let turn = wrap_angle_f64(vt.x.atan2(vt.y) - heading);
    // d . left(h) and d . forward(h), with left = (cos h, -sin h) and forward = (sin h, cos h).
    bounds.clamp(&Controls::from_array([
        (d.x * ch - d.y * sh) as f32,
        (d.x * sh + d.y * ch) as f32,
        turn as f32,
        height,
    ]))
}

/// The paths a crowd's walkers can follow with a source's control range (`bounds`): the strides
/// they prefer and the tightest curvature those strides allow with half the turn range, and the
/// field those paths need. One rule for every crowd that draws walkers the same way (the CPU crowd,
/// `gpu-crowd`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPlan {
    /// Preferred strides (m per cycle) are drawn from `[stride_lo, stride_hi)`: 30% to 80% of the
    /// way from the shortest usable step (the data's, at least a fifth of its longest) to the
    /// longest.
    pub stride_lo: f32,
    /// See `stride_lo`.
    pub stride_hi: f32,
    /// Smallest radius of curvature of a path: `2 stride_hi / turn_max`.
    pub min_radius: f32,
    /// Border kept between paths and the field's edge (m).
    pub border_m: f32,
}

impl PathPlan {
    /// The plan for a source whose controls span `bounds`, with `border_m` to spare at the field's
    /// edge.
    pub fn new(bounds: &ControlRange, border_m: f32) -> PathPlan {
        let dz_lo = bounds.min.dz.max(0.2 * bounds.max.dz);
        let (stride_lo, stride_hi) = (
            dz_lo + 0.3 * (bounds.max.dz - dz_lo),
            dz_lo + 0.8 * (bounds.max.dz - dz_lo),
        );
        let turn_max = bounds.max.turn.min(-bounds.min.turn);
        PathPlan {
            stride_lo,
            stride_hi,
            min_radius: 2.0 * stride_hi / turn_max,
            border_m,
        }
    }

    /// The smallest field side (m) that fits one path ([`EllipsePath::random`]: half-width at least
    /// `1.5 r + border`).
    pub fn needed_field_m(&self) -> f32 {
        2.0 * ((1.5 * self.min_radius).max(3.0) + self.border_m)
    }

    /// Enlarges `field_m` to fit the paths when it is too small (with a margin of 0.1% for
    /// rounding); returns the size it had, or `None` when it fitted and is unchanged.
    pub fn fit_field(&self, field_m: &mut f32) -> Option<f32> {
        let needed = self.needed_field_m() * 1.001;
        if *field_m < needed && needed.is_finite() {
            Some(std::mem::replace(field_m, needed))
        } else {
            None
        }
    }

    /// Walker `i`'s start in a field of side `field_m` from its generator `g` (seeded by the
    /// crowd's seed and `i`; it continues for whatever the caller draws next): its path, the path
    /// parameter and place, the heading along the path, its preferred stride, its height (uniform
    /// over the data's) and the phase of its first clip. `None` when no path fits the field.
    pub fn draw(
        &self,
        g: &mut SplitMix64,
        field_m: f32,
        bounds: &ControlRange,
    ) -> Option<WalkerStart> {
        let path = EllipsePath::random(g, field_m, self.border_m, self.min_radius)?;
        let s = g.range(0.0, TAU);
        let stride = g.range(self.stride_lo, self.stride_hi);
        let height = g.range(bounds.min.height, bounds.max.height);
        let phase = g.next_f32();
        let base = path.point(s);
        let heading = heading_of(path.velocity(s));
        Some(WalkerStart {
            path,
            s,
            base,
            heading,
            stride,
            height,
            phase,
        })
    }
}

/// Where and how a walker starts ([`PathPlan::draw`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkerStart {
    /// The path it follows.
    pub path: EllipsePath,
    /// Its parameter on the path.
    pub s: f32,
    /// Its place on the field (x, z).
    pub base: Vec2,
    /// Its heading, along the path.
    pub heading: f32,
    /// Its preferred stride (m per cycle).
    pub stride: f32,
    /// Its standing height (m).
    pub height: f32,
    /// The phase of its first clip, in `[0, 1)`.
    pub phase: f32,
}

impl WalkerStart {
    /// The controls of the walker's first clip: [`path_controls`] from its start, the parameter,
    /// place and heading widened to double precision as its cycle frame holds them.
    pub fn first_controls(&self, bounds: &ControlRange) -> Controls {
        path_controls(
            &self.path,
            f64::from(self.s),
            self.base.as_dvec2(),
            f64::from(self.heading),
            self.stride,
            self.height,
            bounds,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI as PI_F64;

    #[test]
    fn headings_and_controls_follow_the_conventions() {
        // Heading 0 faces +z; a positive heading faces towards +x, the left of heading 0.
        assert_eq!(heading_of(Vec2::new(0.0, 1.0)), 0.0);
        let h = 1.2f32;
        assert!((heading_of(Vec2::new(h.sin(), h.cos())) - h).abs() < 1e-5);
        // A walker at (10, 0) facing +z on a circle of radius 10: around the origin it bends to
        // the right (the target at -x: dx < 0, a negative turn), around (20, 0) to the left.
        let bounds = ControlRange {
            min: Controls::from_array([-5.0, -5.0, -PI, 0.0]),
            max: Controls::from_array([5.0, 5.0, PI, 3.0]),
        };
        let circle = |cx: f32, dir: f32| EllipsePath {
            centre: Vec2::new(cx, 0.0),
            axes: Vec2::new(10.0, 10.0),
            rot: 0.0,
            dir,
        };
        let pos = DVec2::new(10.0, 0.0);
        let right = path_controls(&circle(0.0, 1.0), 0.0, pos, 0.0, 1.0, 1.7, &bounds);
        let left = path_controls(&circle(20.0, -1.0), PI_F64, pos, 0.0, 1.0, 1.7, &bounds);
        for (c, side) in [(right, -1.0f32), (left, 1.0)] {
            // One stride (1 m) along the arc: 10 sin 0.1 ahead, 10 (1 - cos 0.1) aside, 0.1 rad.
            assert!((c.dz - 10.0 * 0.1f32.sin()).abs() < 1e-5, "{c:?}");
            assert!(
                (c.dx - side * 10.0 * (1.0 - 0.1f32.cos())).abs() < 1e-5,
                "{c:?}"
            );
            assert!((c.turn - side * 0.1).abs() < 1e-5, "{c:?}");
            assert_eq!(c.height, 1.7);
        }
    }

    #[test]
    fn random_paths_fit_the_field_and_curvature() {
        let mut g = SplitMix64::new(3);
        for _ in 0..200 {
            let p = EllipsePath::random(&mut g, 60.0, 2.0, 4.0).unwrap();
            assert!(p.min_radius_of_curvature() >= 4.0 - 1e-3);
            for k in 0..64 {
                let q = p.point(k as f32 * TAU / 64.0);
                assert!(q.x.abs() <= 28.0 + 1e-3 && q.y.abs() <= 28.0 + 1e-3);
            }
        }
        assert!(EllipsePath::random(&mut g, 10.0, 2.0, 4.0).is_none());
    }

    #[test]
    fn newton_closest_point_is_at_least_as_close_as_the_sampled_search() {
        let mut g = SplitMix64::new(11);
        let mut newton_used = 0;
        for _ in 0..300 {
            let min_radius = g.range(2.0, 12.0);
            let path = EllipsePath::random(&mut g, 200.0, 2.0, min_radius).unwrap();
            for _ in 0..20 {
                // A walker up to 1.5 m off its path, its last parameter up to 0.4 rad behind and
                // possibly several turns along.
                let s = g.range(-40.0, 40.0);
                let off = Vec2::new(g.range(-1.5, 1.5), g.range(-1.5, 1.5));
                let q = path.point(s) + off;
                let guess = s - g.range(0.0, 0.4);
                let (q, guess) = (q.as_dvec2(), f64::from(guess));
                let sampled = path.closest_param_sampled(path.rotation_f64(), q, guess);
                let newton = path.closest_param_near(q, guess);
                let (dn, ds) = (
                    path.point_f64(newton).distance(q),
                    path.point_f64(sampled).distance(q),
                );
                assert!(dn <= ds + 1e-4, "newton {dn} sampled {ds}");
                assert!((newton - sampled).abs() < 0.01, "{newton} vs {sampled}");
                newton_used += usize::from(newton != sampled);
            }
        }
        assert!(newton_used > 5000, "Newton answered {newton_used} of 6000");
    }

    #[test]
    fn double_precision_points_and_velocities_are_the_single_precision_ones_unrounded() {
        let mut g = SplitMix64::new(17);
        for _ in 0..200 {
            let min_radius = g.range(2.0, 12.0);
            let path = EllipsePath::random(&mut g, 200.0, 2.0, min_radius).unwrap();
            let s = g.range(-40.0, 40.0);
            // Points up to 100 m from the origin: f32 rounding of a few 1e-6 m, and its sine
            // within an ulp.
            assert!(
                path.point_f64(f64::from(s))
                    .distance(path.point(s).as_dvec2())
                    < 2e-5
            );
            let (v, v32) = (path.velocity_f64(f64::from(s)), path.velocity(s).as_dvec2());
            assert!(v.distance(v32) < 2e-5 * v.length().max(1.0));
        }
    }

    #[test]
    fn closest_param_recovers_the_parameter() {
        let p = EllipsePath {
            centre: Vec2::new(1.0, 2.0),
            axes: Vec2::new(10.0, 6.0),
            rot: 0.4,
            dir: 1.0,
        };
        for k in 0..20 {
            let s = k as f32 * 0.3;
            let got = p.closest_param_near(p.point(s).as_dvec2(), f64::from(s) + 0.3);
            assert!(p.point_f64(got).distance(p.point(s).as_dvec2()) < 1e-3);
            assert!(p.distance_to(p.point(s)) < 1e-3);
        }
    }
}
