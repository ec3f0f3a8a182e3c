//! The camera (a pinhole with an image size), its paths over time, and its view frustum.

use crate::error::CrowdError;
use glam::{Mat4, Vec3, Vec4};

/// A perspective camera: placement, lens and image size.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position (m).
    pub position: Vec3,
    /// Point looked at (m).
    pub target: Vec3,
    /// Up direction (need not be unit or orthogonal to the view direction, but not parallel).
    pub up: Vec3,
    /// Vertical field of view (rad), in `(0, pi)`.
    pub fov_y: f32,
    /// Width / height of the image.
    pub aspect: f32,
    /// Near clipping distance (m), `> 0`.
    pub near: f32,
    /// Far clipping distance (m), `> near`.
    pub far: f32,
    /// Image width in pixels (used by rendering and screen-space policies).
    pub image_width: u32,
    /// Image height in pixels.
    pub image_height: u32,
}

impl Default for Camera {
    /// A 60-degree camera 1.7 m above the origin looking along +z, 640x360 pixels.
    fn default() -> Self {
        Self {
            position: Vec3::new(0.0, 1.7, 0.0),
            target: Vec3::new(0.0, 1.2, 10.0),
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            aspect: 640.0 / 360.0,
            near: 0.1,
            far: 500.0,
            image_width: 640,
            image_height: 360,
        }
    }
}

/// Orthonormal camera basis: forward, right and true up.
#[derive(Debug, Clone, Copy)]
pub struct CameraBasis {
    /// Unit view direction.
    pub forward: Vec3,
    /// Unit right direction (`forward x up`).
    pub right: Vec3,
    /// Unit up direction orthogonal to both.
    pub up: Vec3,
}

impl Camera {
    /// What a level-of-detail policy sees of the camera: its vertical field of view and image
    /// height.
    pub fn view(&self) -> lod_policy::ViewParams {
        lod_policy::ViewParams {
            fov_y_radians: self.fov_y,
            image_height_px: self.image_height as f32,
        }
    }

    /// Checks every field: finite, `0 < fov_y < pi`, `aspect > 0`, `0 < near < far`, a non-zero
    /// view direction (`target - position`, finite and of a length single precision can
    /// normalise) not parallel to `up`, `tan(fov_y / 2) * aspect` finite, a non-zero image, and a
    /// frustum whose six planes ([`Frustum::from_camera`]) are finite with unit normals.
    pub fn validate(&self) -> Result<(), CrowdError> {
        let bad = |what| Err(CrowdError::BadCamera { what });
        let vs = [self.position, self.target, self.up];
        if vs.iter().any(|v| !v.is_finite()) {
            return bad("position, target or up is NaN or infinite");
        }
        if ![self.fov_y, self.aspect, self.near, self.far]
            .iter()
            .all(|v| v.is_finite())
        {
            return bad("fov_y, aspect, near or far is NaN or infinite");
        }
        if !(self.fov_y > 0.0 && self.fov_y < std::f32::consts::PI) {
            return bad("fov_y outside (0, pi)");
        }
        if self.aspect <= 0.0 {
            return bad("aspect <= 0");
        }
        if !(self.near > 0.0 && self.far > self.near) {
            return bad("need 0 < near < far");
        }
        let f = self.target - self.position;
        if f.length_squared() < 1e-12 {
            return bad("target equals position");
        }
        let forward = f.normalize();
        if !(f.is_finite() && forward.is_finite() && (forward.length_squared() - 1.0).abs() < 1e-3)
        {
            return bad("target - position overflows or cannot be normalised (too far apart)");
        }
        if forward.cross(self.up).length_squared() < 1e-10 {
            return bad("up is zero or parallel to the view direction");
        }
        if !((0.5 * self.fov_y).tan() * self.aspect).is_finite() {
            return bad("tan(fov_y / 2) * aspect overflows (aspect too large)");
        }
        if self.image_width == 0 || self.image_height == 0 {
            return bad("image size is zero");
        }
        let unit_and_finite =
            |p: &Vec4| p.is_finite() && (p.truncate().length_squared() - 1.0).abs() < 1e-3;
        if !self.frustum_planes().iter().all(unit_and_finite) {
            return bad("frustum planes overflow (position, far or aspect too large)");
        }
        Ok(())
    }

    /// The six planes of [`Frustum::from_camera`] (near, far, left, right, bottom, top), unchecked.
    fn frustum_planes(&self) -> [Vec4; 6] {
        let b = self.basis();
        let tv = (0.5 * self.fov_y).tan();
        let th = tv * self.aspect;
        let eye = self.position;
        let plane = |n: Vec3, through: Vec3| {
            let n = n.normalize();
            n.extend(-n.dot(through))
        };
        [
            plane(b.forward, eye + b.forward * self.near),
            plane(-b.forward, eye + b.forward * self.far),
            plane(b.right + b.forward * th, eye),
            plane(-b.right + b.forward * th, eye),
            plane(b.up + b.forward * tv, eye),
            plane(-b.up + b.forward * tv, eye),
        ]
    }

    /// The orthonormal basis; call on a validated camera.
    pub fn basis(&self) -> CameraBasis {
        let forward = (self.target - self.position).normalize();
        let right = forward.cross(self.up).normalize();
        let up = right.cross(forward);
        CameraBasis { forward, right, up }
    }

    /// View-projection matrix `P V` (right-handed, depth in `[0, 1]`).
    pub fn view_projection(&self) -> Mat4 {
        Mat4::perspective_rh(self.fov_y, self.aspect, self.near, self.far)
            * Mat4::look_at_rh(self.position, self.target, self.up)
    }

    /// Corners of the view frustum: near plane (4) then far plane (4), each in the order
    /// bottom-left, bottom-right, top-right, top-left.
    pub fn frustum_corners(&self) -> [Vec3; 8] {
        let b = self.basis();
        let tv = (0.5 * self.fov_y).tan();
        let th = tv * self.aspect;
        let mut out = [Vec3::ZERO; 8];
        for (k, dist) in [self.near, self.far].into_iter().enumerate() {
            let c = self.position + b.forward * dist;
            let (h, v) = (b.right * th * dist, b.up * tv * dist);
            out[4 * k] = c - h - v;
            out[4 * k + 1] = c + h - v;
            out[4 * k + 2] = c + h + v;
            out[4 * k + 3] = c - h + v;
        }
        out
    }
}

/// A camera that moves over time.
#[derive(Debug, Clone, PartialEq)]
pub enum CameraPath {
    /// Always the same camera.
    Fixed,
    /// Circles `centre` at `radius` and `height` above it, looking at `centre`, one turn per
    /// `period_s` seconds.
    Orbit {
        /// Point looked at (m).
        centre: Vec3,
        /// Horizontal distance to the centre (m).
        radius: f32,
        /// Height above the centre (m).
        height: f32,
        /// Seconds per revolution.
        period_s: f32,
    },
    /// Flies along a closed polyline of `waypoints` at `speed_mps`, looking `look_ahead_m`
    /// further along the path and slightly down.
    FlyThrough {
        /// Closed loop of positions (at least two).
        waypoints: Vec<Vec3>,
        /// Speed along the loop (m/s).
        speed_mps: f32,
        /// Distance along the loop to the point looked at (m).
        look_ahead_m: f32,
    },
}

impl CameraPath {
    /// A walk at eye height (1.7 m) around a square loop of half-size `0.3 * field_size_m`, inside
    /// a crowd spread over a field of that size centred at the origin.
    pub fn inside_crowd(field_size_m: f32) -> Self {
        let h = 0.3 * field_size_m;
        let y = 1.7;
        CameraPath::FlyThrough {
            waypoints: vec![
                Vec3::new(-h, y, -h),
                Vec3::new(-h, y, h),
                Vec3::new(h, y, h),
                Vec3::new(h, y, -h),
            ],
            speed_mps: 1.5,
            look_ahead_m: 10.0,
        }
    }

    /// A slow orbit 40 m up and 80 m outside the field's edge, looking at its centre (radius
    /// `0.5 field_size_m + 80`), one turn per 600 s. With the default 60-degree lens (16:9) it sees
    /// most of a crowd spread over the field (about four fifths of a large one), from the near
    /// edge, at the first levels of detail, to the far corner, beyond the last; use
    /// [`Scene::lens`] for a far plane that reaches it.
    pub fn overview(field_size_m: f32) -> Self {
        CameraPath::Orbit {
            centre: Vec3::ZERO,
            radius: 0.5 * field_size_m + 80.0,
            height: 40.0,
            period_s: 600.0,
        }
    }

    /// The camera at time `t` seconds: `lens` supplies everything but position and target.
    pub fn camera_at(&self, t: f32, lens: &Camera) -> Camera {
        let mut cam = *lens;
        match self {
            CameraPath::Fixed => {}
            CameraPath::Orbit {
                centre,
                radius,
                height,
                period_s,
            } => {
                let a = std::f32::consts::TAU * t / *period_s;
                cam.position = *centre + Vec3::new(radius * a.cos(), *height, radius * a.sin());
                cam.target = *centre;
            }
            CameraPath::FlyThrough {
                waypoints,
                speed_mps,
                look_ahead_m,
            } => {
                let s = t * speed_mps;
                cam.position = point_on_loop(waypoints, s);
                let ahead = point_on_loop(waypoints, s + look_ahead_m);
                cam.target = ahead - Vec3::new(0.0, 0.15 * look_ahead_m, 0.0);
            }
        }
        cam
    }
}

/// The scenes a crowd is measured in: where the camera is, hence how many walkers it sees and at
/// which levels of detail.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Scene {
    /// The camera walks at eye height inside the crowd ([`CameraPath::inside_crowd`]): most walkers
    /// are culled or beyond the last level, so they need only root motion.
    #[default]
    Ground,
    /// The camera circles above the field's edge looking at its centre ([`CameraPath::overview`]):
    /// most of the crowd is in view, from near to far, so the levels between full detail and root
    /// only are all in use.
    Overview,
}

impl Scene {
    /// Both scenes, ground first.
    pub const ALL: [Scene; 2] = [Scene::Ground, Scene::Overview];

    /// The scene's camera path over a field of side `field_size_m`.
    pub fn path(self, field_size_m: f32) -> CameraPath {
        match self {
            Scene::Ground => CameraPath::inside_crowd(field_size_m),
            Scene::Overview => CameraPath::overview(field_size_m),
        }
    }

    /// `lens` adapted to the scene: the overview's far plane is pushed to `2 field_size_m + 200`
    /// (at least the lens's own) so that the whole field can be seen.
    pub fn lens(self, lens: Camera, field_size_m: f32) -> Camera {
        match self {
            Scene::Ground => lens,
            Scene::Overview => Camera {
                far: lens.far.max(2.0 * field_size_m + 200.0),
                ..lens
            },
        }
    }

    /// Lower-case name (`ground`, `overview`), as the command line spells it.
    pub fn name(self) -> &'static str {
        match self {
            Scene::Ground => "ground",
            Scene::Overview => "overview",
        }
    }
}

/// Point at arc length `s` along the closed polyline `pts` (wrapping around).
fn point_on_loop(pts: &[Vec3], s: f32) -> Vec3 {
    match pts.len() {
        0 => return Vec3::ZERO,
        1 => return pts[0],
        _ => {}
    }
    let seg = |i: usize| (pts[i], pts[(i + 1) % pts.len()]);
    let total: f32 = (0..pts.len()).map(|i| seg(i).0.distance(seg(i).1)).sum();
    if total.is_nan() || total <= 0.0 || !s.is_finite() {
        return pts[0];
    }
    let mut rem = s.rem_euclid(total);
    for i in 0..pts.len() {
        let (a, b) = seg(i);
        let l = a.distance(b);
        if rem <= l && l > 0.0 {
            return a + (b - a) * (rem / l);
        }
        rem -= l;
    }
    pts[0]
}

/// An axis-aligned box, `min <= max` componentwise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

/// The six planes of a view frustum, normals pointing inwards: a point `p` is inside plane
/// `(n, d)` when `n . p + d >= 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frustum {
    /// Near, far, left, right, bottom, top, as `(n.x, n.y, n.z, d)` with unit `n`.
    planes: [Vec4; 6],
    /// The planes by component (`n.x`, `n.y`, `n.z`, `d`), eight lanes of them for the box test
    /// (lanes 6 and 7 repeat the near plane, which changes no answer).
    lanes: [[f32; 8]; 4],
    /// Per lane and axis, all ones where `n >= 0` (the box test takes the box's maximum there).
    takes_max: [[u32; 8]; 3],
}

impl Frustum {
    /// The frustum of a camera (validated first, [`Camera::validate`]: a camera whose planes would
    /// not be finite with unit normals is an error).
    ///
    /// With forward `f`, right `r`, up `u`, `tv = tan(fov_y / 2)` and `th = aspect * tv`, the
    /// inward normals are `f` (near), `-f` (far), `r + th f` (left), `-r + th f` (right),
    /// `u + tv f` (bottom) and `-u + tv f` (top), normalised; side planes pass through the eye.
    pub fn from_camera(camera: &Camera) -> Result<Self, CrowdError> {
        camera.validate()?;
        Ok(Self::from_planes(camera.frustum_planes()))
    }

    /// The frustum bounded by six planes `(n.x, n.y, n.z, d)` (inward unit normals `n`; a point
    /// `p` is inside plane `(n, d)` when `n . p + d >= 0`), in the order near, far, left, right,
    /// bottom, top. The planes are taken as given: a plane with a NaN makes every test false.
    pub fn from_planes(planes: [Vec4; 6]) -> Self {
        let lane = |i: usize| planes[if i < 6 { i } else { 0 }];
        let lanes: [[f32; 8]; 4] = [0, 1, 2, 3].map(|c| std::array::from_fn(|i| lane(i)[c]));
        Self {
            planes,
            lanes,
            takes_max: [0, 1, 2].map(|c| lanes[c].map(|n| if n >= 0.0 { u32::MAX } else { 0 })),
        }
    }

    /// The six planes, near, far, left, right, bottom, top, as `(n.x, n.y, n.z, d)` with unit
    /// inward `n`.
    pub fn planes(&self) -> &[Vec4; 6] {
        &self.planes
    }

    /// True when `p` is inside or on every plane.
    pub fn contains_point(&self, p: Vec3) -> bool {
        self.planes
            .iter()
            .all(|pl| pl.truncate().dot(p) + pl.w >= 0.0)
    }

    /// Conservative box test: false only when the box lies entirely outside one plane (tested
    /// with the box corner furthest along the plane normal). Monotone: a box containing a box
    /// that passes also passes, which makes BVH traversal exact with respect to this test.
    ///
    /// All six planes are tested without branching (most boxes of a crowd fail one plane or
    /// another, unpredictably, and a mispredicted early exit costs more than the remaining tests).
    ///
    /// Per plane: `p = select(n >= 0, max, min)` by component, inside when
    /// `((n.x p.x + n.y p.y) + n.z p.z) + d >= 0` (`Vec3::dot`'s order), the planes in eight lanes
    /// (vectorised).
    #[inline]
    pub fn intersects_box(&self, min: Vec3, max: Vec3) -> bool {
        let [nx, ny, nz, d] = &self.lanes;
        let [mx, my, mz] = &self.takes_max;
        // `n >= 0 ? hi : lo` as a bitwise blend (vectorised where a branch or a conditional move
        // would not be).
        let pick =
            |m: u32, lo: f32, hi: f32| f32::from_bits((hi.to_bits() & m) | (lo.to_bits() & !m));
        let mut inside = 1u32;
        for i in 0..8 {
            let (px, py, pz) = (
                pick(mx[i], min.x, max.x),
                pick(my[i], min.y, max.y),
                pick(mz[i], min.z, max.z),
            );
            let dot = (nx[i] * px + ny[i] * py) + nz[i] * pz;
            // False for NaN, as the per-plane test.
            inside &= u32::from(dot + d[i] >= 0.0);
        }
        inside == 1
    }

    /// [`Frustum::intersects_box`] for a [`Bounds`].
    #[inline]
    pub fn intersects(&self, b: &Bounds) -> bool {
        self.intersects_box(b.min, b.max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_camera_is_valid_and_sees_ahead_not_behind() {
        let cam = Camera::default();
        let f = Frustum::from_camera(&cam).unwrap();
        assert!(f.contains_point(Vec3::new(0.0, 1.0, 20.0)));
        assert!(!f.contains_point(Vec3::new(0.0, 1.0, -5.0)));
        assert!(!f.contains_point(Vec3::new(0.0, 1.0, 600.0)));
        assert!(!f.contains_point(Vec3::new(100.0, 1.0, 20.0)));
        // A box straddling the left plane intersects; one behind does not.
        assert!(f.intersects_box(Vec3::new(10.0, 0.0, 10.0), Vec3::new(30.0, 2.0, 12.0)));
        assert!(!f.intersects_box(Vec3::new(-1.0, 0.0, -3.0), Vec3::new(1.0, 2.0, -1.0)));
    }

    #[test]
    fn box_test_equals_the_per_plane_test() {
        // The eight-lane test against the per-plane form it replaces (`select` of the corner, glam's
        // `dot`), on boxes around and across every plane of two cameras, flat and infinite boxes
        // and NaN.
        let per_plane = |f: &Frustum, min: Vec3, max: Vec3| {
            f.planes().iter().all(|pl| {
                let n = pl.truncate();
                n.dot(Vec3::select(n.cmpge(Vec3::ZERO), max, min)) + pl.w >= 0.0
            })
        };
        let cams = [
            Camera::default(),
            Camera {
                target: Vec3::new(3.0, 0.5, 9.0),
                ..Camera::default()
            },
        ];
        let mut seen = [0usize; 2];
        for cam in cams {
            let f = Frustum::from_camera(&cam).unwrap();
            let mut u = 0.5f32;
            for i in 0..4000 {
                let mut next = || {
                    u = (u * 3.7 + 0.123 * (i % 7) as f32).fract();
                    u
                };
                let c = Vec3::new(
                    next() * 200.0 - 100.0,
                    next() * 6.0 - 3.0,
                    next() * 700.0 - 100.0,
                );
                let h = Vec3::new(next() * 20.0, next() * 2.0, next() * 20.0);
                let (min, max) = (c - h, c + h);
                let want = per_plane(&f, min, max);
                assert_eq!(f.intersects_box(min, max), want, "{min} {max}");
                seen[usize::from(want)] += 1;
            }
            for (min, max) in [
                (Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY)),
                (
                    Vec3::new(-1.0, 0.0, 10.0),
                    Vec3::new(f32::INFINITY, 2.0, 12.0),
                ),
                (Vec3::splat(f32::NAN), Vec3::splat(1.0)),
                (Vec3::new(0.0, 1.0, 20.0), Vec3::new(0.0, 1.0, 20.0)),
            ] {
                assert_eq!(
                    f.intersects_box(min, max),
                    per_plane(&f, min, max),
                    "{min} {max}"
                );
            }
        }
        assert!(
            seen[0] > 1000 && seen[1] > 1000,
            "both answers tested: {seen:?}"
        );
    }

    #[test]
    fn frustum_corners_lie_on_the_frustum_boundary() {
        let cam = Camera {
            target: Vec3::new(3.0, 0.5, 9.0),
            ..Camera::default()
        };
        let f = Frustum::from_camera(&cam).unwrap();
        for c in cam.frustum_corners() {
            let min_dist = f
                .planes
                .iter()
                .map(|p| p.truncate().dot(c) + p.w)
                .fold(f32::MAX, f32::min);
            assert!(
                min_dist.abs() < 1e-2 * c.distance(cam.position).max(1.0),
                "{min_dist}"
            );
        }
    }

    #[test]
    fn nan_or_degenerate_camera_is_an_error() {
        let mut cam = Camera::default();
        cam.position.x = f32::NAN;
        assert!(matches!(
            Frustum::from_camera(&cam),
            Err(CrowdError::BadCamera { .. })
        ));
        let cam = Camera {
            target: Camera::default().position,
            ..Camera::default()
        };
        assert!(cam.validate().is_err());
        let cam = Camera {
            up: Vec3::new(0.0, 0.0, 1.0),
            target: Vec3::new(0.0, 1.7, 5.0),
            ..Camera::default()
        };
        assert!(cam.validate().is_err());
        let cam = Camera {
            near: 0.0,
            ..Camera::default()
        };
        assert!(cam.validate().is_err());
    }

    #[test]
    fn camera_paths_are_continuous() {
        let lens = Camera::default();
        for path in [
            CameraPath::inside_crowd(100.0),
            CameraPath::Orbit {
                centre: Vec3::ZERO,
                radius: 30.0,
                height: 10.0,
                period_s: 20.0,
            },
        ] {
            let mut prev = path.camera_at(0.0, &lens);
            for i in 1..2000 {
                let c = path.camera_at(i as f32 / 30.0, &lens);
                assert!(c.validate().is_ok());
                assert!(c.position.distance(prev.position) < 0.5);
                prev = c;
            }
        }
    }
}
