//! Top-down map: every walker (culled ones in grey) and the camera frustum on the ground.

use super::RenderStyle;
use super::image::Image;
use crate::camera::Camera;
use crate::crowd::Crowd;
use crate::error::RenderError;
use glam::Vec3;

/// Renders a `size_px` square map of the field seen from above (+x to the right, +z up):
/// grid, walkers as dots coloured by level when visible and grey when culled, and the frustum's
/// ground footprint (edges from near to far corners, far edge) with the camera as a dark dot.
pub fn render_map<C>(
    crowd: &Crowd<C>,
    camera: &Camera,
    style: &RenderStyle,
    size_px: u32,
) -> Result<Image, RenderError> {
    camera.validate()?;
    let mut img = Image::new(size_px, size_px, style.background)?;
    let field = crowd.config().field_size_m;
    // Show a little beyond the field so the camera stays in view when it is near the border.
    let extent = 0.55 * field;
    let s = size_px as f32 / (2.0 * extent);
    let to_px = |p: Vec3| [(p.x + extent) * s, (extent - p.z) * s];
    let half = 0.5 * field;
    if style.grid_step_m > 0.0 && style.grid_step_m.is_finite() {
        let n = (field / style.grid_step_m).floor() as i64;
        for k in 0..=n.min(10_000) {
            let v = -half + k as f32 * style.grid_step_m;
            img.line(
                to_px(Vec3::new(v, 0.0, -half)),
                to_px(Vec3::new(v, 0.0, half)),
                style.grid,
                false,
            );
            img.line(
                to_px(Vec3::new(-half, 0.0, v)),
                to_px(Vec3::new(half, 0.0, v)),
                style.grid,
                false,
            );
        }
    }
    let levels = crowd.levels().accuracy_levels;
    // Culled first so visible walkers are drawn on top.
    for pass_visible in [false, true] {
        for i in (0..crowd.len()).filter(|&i| crowd.is_visible(i) == pass_visible) {
            let c = if pass_visible {
                style.color_of_bin(crowd.level_bin(i), levels)
            } else {
                style.root_only
            };
            let p = to_px(crowd.root_position(i));
            img.dot(p[0], p[1], 1, c);
        }
    }
    let k = camera.frustum_corners();
    let ink = [30, 30, 30];
    for j in 0..4 {
        img.line(to_px(k[j]), to_px(k[4 + j]), ink, false);
        img.line(to_px(k[4 + j]), to_px(k[4 + (j + 1) % 4]), ink, false);
        img.line(to_px(k[j]), to_px(k[(j + 1) % 4]), ink, false);
    }
    let e = to_px(camera.position);
    img.dot(e[0], e[1], 2, ink);
    Ok(img)
}
