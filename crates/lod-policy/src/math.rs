//! The runtime's two scalar helpers on angles and blends, defined once for every crate that
//! depends on the runtime (`motion-io` keeps its own `f64` angle wrap for the offline cycle
//! analysis, since it does not depend on this crate).

use std::f32::consts::{PI, TAU};

/// Clears the upper halves of this thread's AVX registers (`vzeroupper`) when the CPU has AVX;
/// nothing on other CPUs.
///
/// This crate is compiled for baseline x86-64 (SSE). Vector code that leaves the AVX upper state
/// dirty (a linear-algebra kernel that did not clear it) makes every later SSE instruction on that
/// thread, and on threads spawned from it, pay for merging that state: measured here, a crowd frame
/// ran 2.5 times slower after a model build in the same process. The crowd calls this at the start
/// of each frame and of each chunk of walkers ([`crate::FootLock`] and the kernels need nothing
/// else); an engine that runs its own vector code before the runtime's may call it too. It changes
/// no value the program holds.
#[inline]
pub fn clear_avx_upper_state() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX (checked just above); `vzeroupper` zeroes only the upper halves
        // of the vector registers, which code compiled for SSE never holds values in.
        unsafe { std::arch::x86_64::_mm256_zeroupper() }
    }
}

/// Asks the CPU to bring the `bytes` bytes from `start` into cache (one prefetch hint per 64-byte
/// line) without waiting for them: the crowd calls it for the walkers and clips a few steps ahead of
/// the one it works on, so that their memory arrives while it computes. A hint only: it reads
/// nothing, changes no value and never faults, whatever the address; a no-op off x86-64.
#[inline]
pub fn prefetch_bytes(start: *const u8, bytes: usize) {
    #[cfg(target_arch = "x86_64")]
    {
        let mut off = 0;
        while off < bytes {
            // SAFETY: `prefetcht0` is a hint: it does not dereference in the language's sense,
            // cannot fault on any address and has no observable effect besides timing.
            unsafe {
                std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(
                    start.wrapping_add(off).cast::<i8>(),
                )
            };
            off += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (start, bytes);
}

/// [`prefetch_bytes`] over the memory of `value` itself (not what it points to).
#[inline]
pub fn prefetch<T>(value: &T) {
    prefetch_bytes((value as *const T).cast::<u8>(), std::mem::size_of::<T>());
}

/// [`prefetch_bytes`] over the elements of `slice`.
#[inline]
pub fn prefetch_slice<T>(slice: &[T]) {
    prefetch_bytes(slice.as_ptr().cast::<u8>(), std::mem::size_of_val(slice));
}

/// Wraps an angle (radians) into `(-pi, pi]`.
pub fn wrap_angle(a: f32) -> f32 {
    let w = a - TAU * (a / TAU).round();
    let w = if w <= -PI { w + TAU } else { w };
    if -PI < w && w <= PI {
        w
    } else {
        // `a` so large (beyond about 2^24 turns) that `TAU * round(a / TAU)` is rounded by more
        // than a turn (`wrap_angle(1e30)` gave about 7e22): the exact remainder.
        let r = a.rem_euclid(TAU);
        if r > PI { r - TAU } else { r }
    }
}

/// [`wrap_angle`] in double precision: the heading of a cycle frame, summed over hours of turns.
pub fn wrap_angle_f64(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let w = a - TAU * (a / TAU).round();
    let w = if w <= -PI { w + TAU } else { w };
    if -PI < w && w <= PI {
        w
    } else {
        // As in `wrap_angle`: beyond about 2^53 turns (`wrap_angle_f64(1e18)` gave 128).
        let r = a.rem_euclid(TAU);
        if r > PI { r - TAU } else { r }
    }
}

/// Ease-in/out weight `3u^2 - 2u^3` (smoothstep) for `u` clamped to `[0, 1]`: 0 at 0, 1 at 1,
/// zero slope at both ends.
pub fn ease_in_out(u: f32) -> f32 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Angles too large for `a - TAU * round(a / TAU)` (a C caller's heading of 1e18 came back as
    /// 128) still land in `(-pi, pi]`; ordinary ones keep that formula's bits.
    #[test]
    fn huge_angles_wrap_into_the_half_open_interval() {
        use std::f64::consts::PI as PI64;
        for a in [
            1e18,
            -1e18,
            3e300,
            -f64::MAX,
            f64::MAX,
            1e16 + 0.5,
            9.007e15,
        ] {
            let w = wrap_angle_f64(a);
            assert!(-PI64 < w && w <= PI64, "{a} -> {w}");
        }
        for a in [1e30f32, -1e30, f32::MAX, -f32::MAX, 1e8, -3e7] {
            let w = wrap_angle(a);
            assert!(-PI < w && w <= PI, "{a} -> {w}");
        }
        for k in -1000..1000 {
            let a = f64::from(k) * 12.345;
            let w = a - std::f64::consts::TAU * (a / std::f64::consts::TAU).round();
            let w = if w <= -PI64 {
                w + std::f64::consts::TAU
            } else {
                w
            };
            assert_eq!(wrap_angle_f64(a).to_bits(), w.to_bits(), "{a}");
        }
    }

    #[test]
    fn wrap_angle_f64_lands_in_half_open_interval() {
        use std::f64::consts::PI;
        assert!((wrap_angle_f64(3.0 * PI) - PI).abs() < 1e-12);
        assert_eq!(wrap_angle_f64(-PI), PI);
        for k in -50..50 {
            let a = f64::from(k) * 0.37;
            let w = wrap_angle_f64(a);
            assert!(-PI < w && w <= PI, "{a} -> {w}");
            // The same angle: a whole number of turns apart.
            let turns = (a - w) / std::f64::consts::TAU;
            assert!((turns - turns.round()).abs() < 1e-12, "{a} -> {w}");
        }
    }

    #[test]
    fn wrap_angle_lands_in_half_open_interval() {
        assert!((wrap_angle(3.0 * PI) - PI).abs() < 1e-5);
        assert!((wrap_angle(-0.5) + 0.5).abs() < 1e-6);
        assert_eq!(wrap_angle(-PI), PI);
        for k in -20..20 {
            let a = 0.37 * k as f32;
            let w = wrap_angle(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            assert!(((a - w) / TAU - ((a - w) / TAU).round()).abs() < 1e-4);
        }
    }

    #[test]
    fn ease_in_out_is_monotone_with_flat_ends() {
        assert_eq!(ease_in_out(-1.0), 0.0);
        assert_eq!(ease_in_out(0.5), 0.5);
        assert_eq!(ease_in_out(2.0), 1.0);
        assert!(ease_in_out(0.01) < 0.001);
        let mut prev = 0.0;
        for i in 1..=100 {
            let v = ease_in_out(i as f32 / 100.0);
            assert!(v >= prev);
            prev = v;
        }
    }
}
