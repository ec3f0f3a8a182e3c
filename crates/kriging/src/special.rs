//! Special functions for the Matérn model: `ln Gamma` and the modified Bessel function `K_nu`.

/// `ln Gamma(x)` for `x > 0` (Lanczos approximation, g = 7, nine terms; relative error ~1e-15).
pub(crate) fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Reflection: Gamma(x) Gamma(1 - x) = pi / sin(pi x).
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, &c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// `K_nu(x)` for `x > 0`, `nu >= 0`, from `K_nu(x) = int_0^inf exp(-x cosh t) cosh(nu t) dt` by the
/// trapezoidal rule. The integrand is analytic in the strip `|Im t| < pi/2` and decays doubly
/// exponentially, so the rule converges geometrically; the step shrinks like `1/sqrt(x)` so that the
/// peak at `t = 0` (width ~`1/sqrt(x)`) is resolved. The integrand is scaled by `exp(x)` internally;
/// returns `exp(x) K_nu(x)`.
fn bessel_k_scaled(nu: f64, x: f64) -> f64 {
    let h = (0.5 / x.sqrt()).min(0.125);
    let mut sum = 0.5; // t = 0: exp(-x (cosh 0 - 1)) cosh 0 / 2
    let mut k = 1usize;
    loop {
        let t = k as f64 * h;
        let term = (-x * (t.cosh() - 1.0) + nu * t).exp() * 0.5 * (1.0 + (-2.0 * nu * t).exp());
        sum += term;
        // Past the maximum of the integrand (x sinh t > nu) the terms only decrease.
        if (x * t.sinh() > nu && term < 1e-18 * sum) || k > 200_000 {
            break;
        }
        k += 1;
    }
    sum * h
}

/// The Matérn correlation `rho(t) = 2^(1-nu)/Gamma(nu) t^nu K_nu(t)` (1 at `t = 0`), `t >= 0`.
/// Closed forms for `nu` = 1/2, 3/2, 5/2; the integral of `K_nu` otherwise.
///
/// Finite and in `[0, 1]` for every `t >= 0` (infinity included) and every `nu` in `[0.05, 50]`:
/// where a closed form's polynomial overflows (`t` beyond about `1e154`) the correlation is 0,
/// its limit; below `t = 1e-300` it is 1 (to double precision); where the prefactor `t^nu e^-t 2^(1-nu) / Gamma(nu)` underflows at a small lag with
/// a large `nu` (and `K_nu` is huge or overflows), the product is taken in logarithms (1 when
/// `K_nu` overflows, its limit at the origin). A NaN `t` gives NaN.
pub(crate) fn matern_correlation(t: f64, nu: f64) -> f64 {
    // Without this, NaN would run the integral's loop to its cap.
    if t.is_nan() {
        return f64::NAN;
    }
    if t <= 0.0 {
        return 1.0;
    }
    // `poly(t) exp(-t)` is inf * 0 = NaN once the polynomial overflows; the limit is 0. Only such
    // a NaN is replaced (the check changes no finite value).
    let closed = |r: f64| if r.is_nan() { 0.0 } else { r };
    if nu == 0.5 {
        return (-t).exp();
    }
    if nu == 1.5 {
        return closed((1.0 + t) * (-t).exp());
    }
    if nu == 2.5 {
        return closed((1.0 + t + t * t / 3.0) * (-t).exp());
    }
    if t > 700.0 + nu * 10.0 {
        return 0.0;
    }
    if t < 1e-300 {
        // 1 - rho(t) = O(t^min(2 nu, 2)) < 1e-29 for nu >= 0.05: 1 in double precision. The
        // integral would lose its tail here (cosh overflows before x cosh(t) is large).
        return 1.0;
    }
    let log_pref = (1.0 - nu) * std::f64::consts::LN_2 - ln_gamma(nu) + nu * t.ln() - t;
    let pref = log_pref.exp();
    let k = bessel_k_scaled(nu, t);
    if pref < f64::MIN_POSITIVE && k > 1.0 {
        // A small lag with a large nu: the prefactor underflowed (subnormal or 0, which would
        // give 0 * inf = NaN or lose its bits) while `exp(t) K_nu(t)` is large or infinite. In
        // logarithms; an infinite `k` gives exp(inf), clamped to 1 (the limit at the origin).
        // A subnormal prefactor only arises at such lags (at large `t`, `k < 1`), so no other
        // value changes.
        return (log_pref + k.ln()).exp().clamp(0.0, 1.0);
    }
    let r = pref * k;
    r.clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_matches_factorials_and_half_integers() {
        for (n, f) in [(1.0, 1.0f64), (2.0, 1.0), (5.0, 24.0), (10.0, 362_880.0)] {
            assert!((ln_gamma(n) - f.ln()).abs() < 1e-13, "{n}");
        }
        let sqrt_pi = std::f64::consts::PI.sqrt();
        assert!((ln_gamma(0.5) - sqrt_pi.ln()).abs() < 1e-13);
        assert!((ln_gamma(1.5) - (0.5 * sqrt_pi).ln()).abs() < 1e-13);
        assert!((ln_gamma(0.25) - 3.625_609_908_221_908_f64.ln()).abs() < 1e-13);
    }

    #[test]
    fn general_nu_agrees_with_the_closed_forms() {
        // Perturb nu off the closed-form values by less than the tolerance matters.
        for &(nu, closed) in &[(0.5, 0), (1.5, 1), (2.5, 2)] {
            for &t in &[1e-6f64, 1e-3, 0.1, 0.5, 1.0, 2.0, 5.0, 20.0, 100.0] {
                let exact = match closed {
                    0 => (-t).exp(),
                    1 => (1.0 + t) * (-t).exp(),
                    _ => (1.0 + t + t * t / 3.0) * (-t).exp(),
                };
                let log_pref =
                    (1.0 - nu) * std::f64::consts::LN_2 - ln_gamma(nu) + nu * f64::ln(t) - t;
                let general = log_pref.exp() * bessel_k_scaled(nu, t);
                assert!(
                    (general - exact).abs() < 1e-12 * exact.max(1e-300) + 1e-14,
                    "nu {nu} t {t}: {general} vs {exact}"
                );
            }
        }
    }

    /// The correlation before the overflow guards, kept verbatim to check that the guards change
    /// no ordinary value.
    fn unguarded(t: f64, nu: f64) -> f64 {
        if t <= 0.0 {
            return 1.0;
        }
        if nu == 0.5 {
            return (-t).exp();
        }
        if nu == 1.5 {
            return (1.0 + t) * (-t).exp();
        }
        if nu == 2.5 {
            return (1.0 + t + t * t / 3.0) * (-t).exp();
        }
        if t > 700.0 + nu * 10.0 {
            return 0.0;
        }
        let log_pref = (1.0 - nu) * std::f64::consts::LN_2 - ln_gamma(nu) + nu * t.ln() - t;
        let r = log_pref.exp() * bessel_k_scaled(nu, t);
        r.clamp(0.0, 1.0)
    }

    #[test]
    fn guards_change_no_ordinary_value() {
        let mut nus = vec![0.05, 0.5, 1.5, 2.5, 3.7, 30.0];
        nus.extend((0..40).map(|i| 0.2 * 150f64.powf(i as f64 / 39.0)));
        for nu in nus {
            for i in 0..400 {
                let t = 1e-6 * 1e9f64.powf(i as f64 / 399.0);
                assert_eq!(
                    matern_correlation(t, nu).to_bits(),
                    unguarded(t, nu).to_bits(),
                    "nu {nu} t {t}"
                );
            }
        }
    }

    #[test]
    fn correlation_is_finite_at_extreme_lags() {
        let nus = [0.05, 0.2, 0.5, 1.0, 1.5, 2.5, 5.0, 20.0, 30.0, 49.9, 50.0];
        let tiny = [
            5e-324, 1e-320, 1e-300, 1e-100, 1e-20, 1e-12, 1e-10, 1e-8, 1e-5,
        ];
        let huge = [1e154, 1.4e154, 1e200, 1e300, f64::MAX, f64::INFINITY];
        for nu in nus {
            for t in tiny {
                let r = matern_correlation(t, nu);
                assert!((0.0..=1.0).contains(&r), "nu {nu} t {t}: {r}");
                // Next to the origin the correlation is about 1 (1 - O(t^min(2 nu, 2))).
                if t <= 1e-10 && nu >= 1.0 {
                    assert!(r > 1.0 - 1e-6, "nu {nu} t {t}: {r}");
                }
                if t < 1e-300 {
                    assert_eq!(r, 1.0, "nu {nu} t {t}");
                }
            }
            for t in huge {
                assert_eq!(matern_correlation(t, nu), 0.0, "nu {nu} t {t}");
            }
        }
        // Before the guards these were NaN (0 * inf, inf * 0).
        assert!(unguarded(1e-10, 30.0).is_nan() && unguarded(1e300, 2.5).is_nan());
        assert_eq!(matern_correlation(1e-10, 30.0), 1.0);
        // Where the prefactor is subnormal the logarithmic product is close to 1, as it should be.
        let r = matern_correlation(2e-5, 50.0);
        assert!(r > 1.0 - 1e-9 && r <= 1.0, "{r}");
        assert!(matern_correlation(f64::NAN, 3.0).is_nan());
    }

    #[test]
    fn correlation_is_monotone_and_bounded() {
        for nu in [0.3, 1.0, 3.7, 10.0] {
            let mut prev = 1.0;
            for i in 1..200 {
                let r = matern_correlation(i as f64 * 0.05, nu);
                assert!(
                    r <= prev + 1e-15 && r >= 0.0,
                    "nu {nu} at {i}: {r} after {prev}"
                );
                prev = r;
            }
        }
    }
}
