//! Clip transitions (paper section 5.2): ease-in/out blending of pose vectors for walkers at the
//! first levels, a plain switch beyond.

/// Ease-in/out weight `e(u) = u^2 (3 - 2 u)` for `u` clamped to `[0, 1]` (zero slope at both ends).
pub fn ease_in_out(u: f32) -> f32 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

/// A blend window in clip phase (`u = t / duration`): the pose goes from the previous clip at
/// `start` to the current clip at `end`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlendWindow {
    /// Phase where the blend starts (weight 0 for the current clip).
    pub start: f32,
    /// Phase where the blend ends (weight 1), `> start`.
    pub end: f32,
}

impl BlendWindow {
    /// Weight of the current clip at phase `u`: `e((u - start) / (end - start))`.
    pub fn weight(&self, u: f32) -> f32 {
        ease_in_out((u - self.start) / (self.end - self.start).max(1e-6))
    }
}

/// Blends in place: `cur[i] = prev[i] + w (cur[i] - prev[i])` for the rows both vectors hold
/// (`i < min(prev.len(), cur.len())`); rows only `cur` holds are kept.
pub fn blend_into(prev: &[f32], cur: &mut [f32], w: f32) {
    for (c, p) in cur.iter_mut().zip(prev) {
        *c = *p + w * (*c - *p);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ease_is_monotone_with_flat_ends() {
        assert_eq!(ease_in_out(-1.0), 0.0);
        assert_eq!(ease_in_out(0.0), 0.0);
        assert_eq!(ease_in_out(1.0), 1.0);
        assert_eq!(ease_in_out(0.5), 0.5);
        let mut prev = 0.0;
        for k in 1..=100 {
            let e = ease_in_out(k as f32 / 100.0);
            assert!(e >= prev);
            prev = e;
        }
        // Zero slope at the ends: a small step moves the weight much less than linearly.
        assert!(ease_in_out(0.01) < 0.001);
    }

    #[test]
    fn blend_mixes_common_rows_only() {
        let prev = [0.0, 10.0];
        let mut cur = [1.0, 20.0, 5.0];
        blend_into(&prev, &mut cur, 0.25);
        assert_eq!(cur, [0.25, 12.5, 5.0]);
        let w = BlendWindow {
            start: 0.2,
            end: 0.6,
        };
        assert_eq!(w.weight(0.1), 0.0);
        assert!((w.weight(0.4) - 0.5).abs() < 1e-6);
        assert_eq!(w.weight(0.9), 1.0);
    }
}
