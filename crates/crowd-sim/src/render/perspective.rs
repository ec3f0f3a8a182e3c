//! Perspective view: ground grid and stick figures coloured by level.

use super::RenderStyle;
use super::image::{Image, Rgb};
use crate::camera::Camera;
use crate::crowd::Crowd;
use crate::error::RenderError;
use glam::{Mat4, Vec3, Vec4};

/// Projects world segments to pixels with near-plane clipping.
struct Projector {
    vp: Mat4,
    w: f32,
    h: f32,
}

impl Projector {
    fn new(camera: &Camera) -> Self {
        Self {
            vp: camera.view_projection(),
            w: camera.image_width as f32,
            h: camera.image_height as f32,
        }
    }

    fn to_pixel(&self, c: Vec4) -> [f32; 2] {
        let (x, y) = (c.x / c.w, c.y / c.w);
        [(x + 1.0) * 0.5 * self.w, (1.0 - y) * 0.5 * self.h]
    }

    /// Segment `a b` in pixels, clipped against the near plane (clip-space `z >= 0`).
    fn segment(&self, a: Vec3, b: Vec3) -> Option<([f32; 2], [f32; 2])> {
        let mut ca = self.vp * a.extend(1.0);
        let mut cb = self.vp * b.extend(1.0);
        if ca.z < 0.0 && cb.z < 0.0 {
            return None;
        }
        if ca.z < 0.0 {
            ca = ca + (cb - ca) * (-ca.z / (cb.z - ca.z));
        } else if cb.z < 0.0 {
            cb = cb + (ca - cb) * (-cb.z / (ca.z - cb.z));
        }
        if ca.w <= 0.0 || cb.w <= 0.0 {
            return None;
        }
        Some((self.to_pixel(ca), self.to_pixel(cb)))
    }

    fn point(&self, p: Vec3) -> Option<[f32; 2]> {
        let c = self.vp * p.extend(1.0);
        (c.z >= 0.0 && c.w > 0.0).then(|| self.to_pixel(c))
    }
}

fn draw(img: &mut Image, pr: &Projector, a: Vec3, b: Vec3, c: Rgb, thick: bool) {
    if let Some((p, q)) = pr.segment(a, b) {
        img.line(p, q, c, thick);
    }
}

/// Renders the crowd as seen by `camera` (image size from the camera): the ground grid over the
/// field, then visible walkers from far to near, bones coloured by level bin, root-only walkers
/// as a dot at hip height.
pub fn render_frame<C>(
    crowd: &Crowd<C>,
    camera: &Camera,
    style: &RenderStyle,
) -> Result<Image, RenderError> {
    camera.validate()?;
    let mut img = Image::new(camera.image_width, camera.image_height, style.background)?;
    let pr = Projector::new(camera);
    let half = 0.5 * crowd.config().field_size_m;
    if style.grid_step_m > 0.0 && style.grid_step_m.is_finite() {
        let n = (2.0 * half / style.grid_step_m).floor() as i64;
        for k in 0..=n.min(10_000) {
            let v = -half + k as f32 * style.grid_step_m;
            draw(
                &mut img,
                &pr,
                Vec3::new(v, 0.0, -half),
                Vec3::new(v, 0.0, half),
                style.grid,
                false,
            );
            draw(
                &mut img,
                &pr,
                Vec3::new(-half, 0.0, v),
                Vec3::new(half, 0.0, v),
                style.grid,
                false,
            );
        }
    }
    let eye = camera.position;
    let mut order: Vec<(f32, usize)> = (0..crowd.len())
        .filter(|&i| crowd.is_visible(i))
        .map(|i| (crowd.root_position(i).distance(eye), i))
        .collect();
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let levels = crowd.levels().accuracy_levels;
    for (dist, i) in order {
        let joints = crowd.joint_positions(i);
        let color = style.color_of_bin(crowd.level_bin(i), levels);
        if joints.len() <= 1 {
            let r = crowd.root_position(i);
            if let Some(p) = pr.point(Vec3::new(r.x, 0.5 * crowd.height(i), r.z)) {
                img.dot(p[0], p[1], 1, color);
            }
            continue;
        }
        let thick = dist < style.thick_within_m;
        for &(a, b) in crowd.bones() {
            if a < joints.len() && b < joints.len() {
                draw(&mut img, &pr, joints[a], joints[b], color, thick);
            }
        }
    }
    Ok(img)
}
