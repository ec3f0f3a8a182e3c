//! An RGB image with line and dot drawing.

use crate::error::RenderError;

/// An 8-bit RGB colour.
pub type Rgb = [u8; 3];

/// Largest accepted image side (pixels).
const MAX_SIDE: u32 = 16384;

/// An RGB image, rows top to bottom, 3 bytes per pixel.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width * height * 3` bytes.
    pub rgb: Vec<u8>,
}

impl Image {
    /// A `width x height` image filled with `bg`; sides must be in `1..=16384`.
    pub fn new(width: u32, height: u32, bg: Rgb) -> Result<Self, RenderError> {
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            return Err(RenderError::BadSize {
                width,
                height,
                what: "sides must be in 1..=16384",
            });
        }
        let rgb = bg
            .iter()
            .copied()
            .cycle()
            .take(width as usize * height as usize * 3)
            .collect();
        Ok(Self { width, height, rgb })
    }

    /// Colour at `(x, y)`, or `None` outside the image (or beyond the end of `rgb`, for a
    /// hand-built image whose buffer is shorter than `width * height * 3` bytes).
    pub fn pixel(&self, x: u32, y: u32) -> Option<Rgb> {
        if x < self.width && y < self.height {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            if let Some(&[r, g, b]) = self.rgb.get(i..i + 3) {
                return Some([r, g, b]);
            }
        }
        None
    }

    /// Sets `(x, y)` when inside the image (and inside `rgb`, for a hand-built image whose buffer
    /// is shorter than `width * height * 3` bytes: nothing is drawn beyond its end).
    pub fn put(&mut self, x: i64, y: i64, c: Rgb) {
        if (0..i64::from(self.width)).contains(&x) && (0..i64::from(self.height)).contains(&y) {
            let i = 3 * (y as usize * self.width as usize + x as usize);
            if let Some(p) = self.rgb.get_mut(i..i + 3) {
                p.copy_from_slice(&c);
            }
        }
    }

    /// A filled square of side `2 r + 1` centred at `(x, y)`.
    pub fn dot(&mut self, x: f32, y: f32, r: i64, c: Rgb) {
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        let (cx, cy) = (x.round() as i64, y.round() as i64);
        for dy in -r..=r {
            for dx in -r..=r {
                self.put(cx + dx, cy + dy, c);
            }
        }
    }

    /// A line from `a` to `b` (pixel coordinates), clipped to the image (Liang-Barsky), drawn
    /// with a DDA; `thick` draws a second parallel line below.
    pub fn line(&mut self, a: [f32; 2], b: [f32; 2], c: Rgb, thick: bool) {
        let Some((a, b)) = clip_to_rect(a, b, self.width as f32, self.height as f32) else {
            return;
        };
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let steps = dx.abs().max(dy.abs()).ceil().max(1.0) as usize;
        for k in 0..=steps {
            let t = k as f32 / steps as f32;
            let (x, y) = (
                (a[0] + t * dx).round() as i64,
                (a[1] + t * dy).round() as i64,
            );
            self.put(x, y, c);
            if thick {
                if dx.abs() > dy.abs() {
                    self.put(x, y + 1, c)
                } else {
                    self.put(x + 1, y, c)
                }
            }
        }
    }

    /// The image shrunk by an integer `factor` (box filter); `factor <= 1` clones.
    pub fn downscale(&self, factor: u32) -> Image {
        if factor <= 1 {
            return self.clone();
        }
        let (w, h) = ((self.width / factor).max(1), (self.height / factor).max(1));
        let mut rgb = Vec::with_capacity(w as usize * h as usize * 3);
        for y in 0..h {
            for x in 0..w {
                let mut acc = [0u32; 3];
                let mut n = 0;
                for sy in y * factor..((y + 1) * factor).min(self.height) {
                    for sx in x * factor..((x + 1) * factor).min(self.width) {
                        let p = self.pixel(sx, sy).unwrap_or([0; 3]);
                        for k in 0..3 {
                            acc[k] += u32::from(p[k]);
                        }
                        n += 1;
                    }
                }
                for a in acc {
                    rgb.push((a / n.max(1)) as u8);
                }
            }
        }
        Image {
            width: w,
            height: h,
            rgb,
        }
    }
}

/// Liang-Barsky clipping of segment `a b` to `[0, w] x [0, h]`; `None` when outside or not finite.
fn clip_to_rect(a: [f32; 2], b: [f32; 2], w: f32, h: f32) -> Option<([f32; 2], [f32; 2])> {
    if !(a.iter().chain(&b).all(|v| v.is_finite())) {
        return None;
    }
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [(-dx, a[0]), (dx, w - a[0]), (-dy, a[1]), (dy, h - a[1])] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then(|| {
        (
            [a[0] + t0 * dx, a[1] + t0 * dy],
            [a[0] + t1 * dx, a[1] + t1 * dy],
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_clipped_and_drawn() {
        let mut im = Image::new(10, 10, [0; 3]).unwrap();
        im.line([-100.0, 5.0], [100.0, 5.0], [255, 0, 0], false);
        for x in 0..10 {
            assert_eq!(im.pixel(x, 5), Some([255, 0, 0]));
        }
        assert_eq!(im.pixel(3, 4), Some([0, 0, 0]));
        im.line([f32::NAN, 0.0], [3.0, 3.0], [0, 255, 0], true);
        im.line([-5.0, -5.0], [-1.0, 20.0], [0, 255, 0], true);
        assert!(!im.rgb.chunks(3).any(|p| p == [0, 255, 0]));
    }

    #[test]
    fn sizes_are_checked_and_downscale_averages() {
        assert!(Image::new(0, 5, [0; 3]).is_err());
        let mut im = Image::new(4, 2, [0; 3]).unwrap();
        im.put(0, 0, [200, 100, 40]);
        let s = im.downscale(2);
        assert_eq!((s.width, s.height), (2, 1));
        assert_eq!(s.pixel(0, 0), Some([50, 25, 10]));
    }
}
