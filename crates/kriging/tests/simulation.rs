//! Sequential Gaussian simulation ([`kriging::Sgs`]): the data are honoured exactly, the ensemble
//! of many realisations has the simple-kriging mean, variance and covariance (exact law with a
//! full neighbourhood), unconditional realisations reproduce the variogram, the same seed gives the
//! same bits on 1 and 4 threads, and bad input gives clear errors.
//!
//! Tolerances of the statistical checks are stated in standard errors of the estimate at hand,
//! `R` realisations being independent draws (each from its own random stream):
//! - ensemble mean: `sigma / sqrt(R)`;
//! - ensemble variance: `sigma^2 sqrt(2 / (R - 1))` (Gaussian);
//! - ensemble covariance of two targets: `sqrt((s11 s22 + s12^2) / (R - 1))`;
//! - a variogram averaged over realisations: the standard deviation of the per-realisation
//!   values over `sqrt(R)` (measured).
//!
//! Each check allows 4.5 standard errors (a false alarm has probability 7e-6 per check, below 1e-3
//! for the at most 110 checks of a test); the seeds are fixed, so the outcome is reproducible.

use kriging::faer::Mat;
use kriging::{
    Anisotropy, Krige, KrigingError, Neighbourhood, NestedVariogram, Realisations, Sgs, SgsMean,
    SgsPath, VariogramModel,
};

fn expo(nugget: f64, sill: f64, range: f64) -> NestedVariogram {
    NestedVariogram::single(VariogramModel::Exponential, nugget, sill, range).unwrap()
}

/// Low-discrepancy points (Halton bases 2 and 3) on `[0, side]^2`.
fn halton(n: usize, side: f64) -> Mat<f64> {
    let radical = |mut i: usize, b: usize| {
        let (mut f, mut r) = (1.0, 0.0);
        while i > 0 {
            f /= b as f64;
            r += f * (i % b) as f64;
            i /= b;
        }
        r
    };
    Mat::from_fn(n, 2, |i, c| side * radical(i + 1, [2, 3][c]))
}

/// `nx x ny` grid with spacing `step`, x fastest.
fn grid(nx: usize, ny: usize, step: f64) -> Mat<f64> {
    Mat::from_fn(nx * ny, 2, |t, c| {
        step * if c == 0 {
            (t % nx) as f64
        } else {
            (t / nx) as f64
        }
    })
}

fn bits(r: &Realisations) -> Vec<u64> {
    r.as_slice().iter().map(|v| v.to_bits()).collect()
}

fn dist(m: &Mat<f64>, i: usize, p: &Mat<f64>, j: usize) -> f64 {
    (0..m.ncols())
        .map(|c| (m[(i, c)] - p[(j, c)]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Solves the small symmetric positive definite system `a x = b` (Gaussian elimination).
#[allow(clippy::needless_range_loop)]
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for k in 0..n {
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    x
}

/// (a) Every realisation takes the datum at every target placed on a data site, bit for bit, with
/// and without a nugget, for both paths and ordinary kriging; the targets next to the data vary
/// little.
#[test]
fn honours_the_data_exactly() {
    let n = 40;
    let data = halton(n, 100.0);
    let z: Vec<f64> = (0..n)
        .map(|i| (data[(i, 0)] / 17.0).sin() + 0.01 * data[(i, 1)])
        .collect();
    // A 15 x 15 grid, then every data site (targets 225..265).
    let g = grid(15, 15, 100.0 / 14.0);
    let m = 225 + n;
    let targets = Mat::from_fn(m, 2, |t, c| {
        if t < 225 {
            g[(t, c)]
        } else {
            data[(t - 225, c)]
        }
    });
    for (v, mean, path) in [
        (
            expo(0.0, 1.0, 40.0),
            SgsMean::DataMean,
            SgsPath::PerRealisation,
        ),
        (expo(0.0, 1.0, 40.0), SgsMean::Known(0.5), SgsPath::Shared),
        (
            expo(0.3, 0.7, 40.0),
            SgsMean::Known(0.5),
            SgsPath::PerRealisation,
        ),
        (
            expo(0.0, 1.0, 40.0),
            SgsMean::Ordinary,
            SgsPath::PerRealisation,
        ),
    ] {
        let sims = Sgs::new(v.clone())
            .mean(mean)
            .path(path)
            .seed(11)
            .realisations(20)
            .simulate(data.as_ref(), &z, targets.as_ref())
            .unwrap();
        assert_eq!((sims.n_realisations(), sims.n_targets()), (20, m));
        for r in sims.iter() {
            for i in 0..n {
                assert_eq!(
                    r[225 + i].to_bits(),
                    z[i].to_bits(),
                    "{v:?} {mean:?} datum {i}"
                );
            }
        }
        // The grid targets (none on a data site) vary.
        assert!(sims.variance()[..225].iter().all(|&s| s > 0.0));
    }
}

/// Targets at one place share a value; a target a hair away from a datum (within 1e-12 of the
/// extent) takes the datum.
#[test]
fn coinciding_targets_share_a_value() {
    let data = Mat::from_fn(3, 1, |i, _| [0.0, 5.0, 10.0][i]);
    let z = [1.0, -1.0, 2.0];
    let tx = [2.0, 7.5, 2.0, 5.0 + 1e-15, 7.5, 12.0];
    let targets = Mat::from_fn(6, 1, |i, _| tx[i]);
    let sims = Sgs::new(expo(0.1, 1.0, 6.0))
        .simple(0.0)
        .seed(3)
        .realisations(50)
        .simulate(data.as_ref(), &z, targets.as_ref())
        .unwrap();
    for r in sims.iter() {
        assert_eq!(r[0], r[2]);
        assert_eq!(r[1], r[4]);
        assert_eq!(r[3], -1.0);
        assert_ne!(r[0], r[5]);
    }
}

/// The exact conditional law of simple kriging: a global system by hand (data `D`, targets `T`,
/// `C(h) = sill exp(-3 h / range)`), the mean `m + C_TD C_DD^-1 (z - m)` and the covariance
/// `C_TT - C_TD C_DD^-1 C_DT`.
fn conditional_law(
    data: &Mat<f64>,
    z: &[f64],
    targets: &Mat<f64>,
    mean: f64,
    sill: f64,
    range: f64,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let cov = |h: f64| sill * (-3.0 * h / range).exp();
    let (n, m) = (data.nrows(), targets.nrows());
    let cdd: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| cov(dist(data, i, data, j))).collect())
        .collect();
    // W = C_DD^-1 C_DT, column by column.
    let w: Vec<Vec<f64>> = (0..m)
        .map(|t| {
            solve(
                cdd.clone(),
                (0..n).map(|i| cov(dist(data, i, targets, t))).collect(),
            )
        })
        .collect();
    let mu = (0..m)
        .map(|t| mean + (0..n).map(|i| w[t][i] * (z[i] - mean)).sum::<f64>())
        .collect();
    let sigma = (0..m)
        .map(|s| {
            (0..m)
                .map(|t| {
                    let ctd: f64 = (0..n)
                        .map(|i| cov(dist(data, i, targets, s)) * w[t][i])
                        .sum();
                    cov(dist(targets, s, targets, t)) - ctd
                })
                .collect()
        })
        .collect();
    (mu, sigma)
}

/// (b) With every datum and every earlier node in the neighbourhood, SGS draws from the exact
/// conditional law: over 20,000 realisations the ensemble mean is the simple-kriging estimate
/// (also that of `Krige::simple`), the ensemble variance the simple-kriging variance and the
/// ensemble covariance the conditional covariance, for both paths (4.5 standard errors each, see
/// the file's docs).
#[test]
fn ensemble_has_the_simple_kriging_law_with_a_full_neighbourhood() {
    let xy = [
        [1.0, 1.0],
        [9.0, 2.0],
        [4.0, 8.0],
        [8.0, 9.0],
        [5.0, 4.5],
        [0.5, 6.0],
        [10.0, 5.5],
        [3.0, 3.0],
    ];
    let data = Mat::from_fn(8, 2, |i, c| xy[i][c]);
    let z = [0.3, 1.6, -0.4, 0.9, 1.2, -1.0, 0.2, 0.7];
    // 12 targets: between the data, next to one, and far outside.
    let txy = [
        [2.0, 2.0],
        [5.0, 5.0],
        [7.0, 3.0],
        [6.0, 8.0],
        [1.0, 4.0],
        [9.5, 8.0],
        [4.0, 8.5],
        [3.0, 6.0],
        [8.0, 6.0],
        [5.2, 4.5],
        [12.0, 12.0],
        [-6.0, 3.0],
    ];
    let targets = Mat::from_fn(12, 2, |i, c| txy[i][c]);
    let (mean, sill, range) = (0.4, 1.5, 9.0);
    let (mu, sigma) = conditional_law(&data, &z, &targets, mean, sill, range);
    // The same estimate and variance from the crate's simple kriging.
    let sk = Krige::new()
        .simple(mean)
        .variogram(expo(0.0, sill, range))
        .fit(data.as_ref(), &z)
        .unwrap()
        .predict_many(targets.as_ref())
        .unwrap();
    for t in 0..12 {
        assert!((sk.values[t] - mu[t]).abs() < 1e-10);
        assert!((sk.variances[t] - sigma[t][t]).abs() < 1e-10);
    }
    let r = 20_000;
    for path in [SgsPath::PerRealisation, SgsPath::Shared] {
        let sims = Sgs::new(expo(0.0, sill, range))
            .simple(mean)
            .neighbours(20) // 8 data + 12 targets: everything
            .path(path)
            .seed(2024)
            .realisations(r)
            .simulate(data.as_ref(), &z, targets.as_ref())
            .unwrap();
        let em = sims.mean();
        let rf = r as f64;
        let mut worst = 0.0f64; // largest deviation in standard errors
        for t in 0..12 {
            let se = (sigma[t][t] / rf).sqrt();
            worst = worst.max((em[t] - mu[t]).abs() / se);
        }
        for s in 0..12 {
            for t in s..12 {
                let c: f64 = sims
                    .iter()
                    .map(|x| (x[s] - em[s]) * (x[t] - em[t]))
                    .sum::<f64>()
                    / (rf - 1.0);
                let se = ((sigma[s][s] * sigma[t][t] + sigma[s][t].powi(2)) / (rf - 1.0)).sqrt();
                worst = worst.max((c - sigma[s][t]).abs() / se);
            }
        }
        // The variances are the diagonal of the covariance check; check the helper too.
        let ev = sims.variance();
        for t in 0..12 {
            let se = sigma[t][t] * (2.0 / (rf - 1.0)).sqrt();
            worst = worst.max((ev[t] - sigma[t][t]).abs() / se);
        }
        println!("{path:?}: largest deviation {worst:.2} standard errors");
        assert!(worst < 4.5, "{path:?}: {worst} standard errors");
    }
}

/// Per realisation: the semivariogram at each lag, the mean and the variance about the mean.
type PerRealisation = (Vec<f64>, f64, f64);

/// (b) Unconditional realisations on a 50 x 50 grid (spacing 1) with the 16 nearest earlier nodes
/// (the default): averaged over 200 realisations, the empirical semivariogram along x and y at
/// lags 1 to 16 is the model's (exponential, practical range 12, sill 1, and with a nugget 0.2),
/// within 4.5 standard errors plus 3 % of the model for the neighbourhood's approximation (16
/// neighbours screen the rest almost entirely for an exponential model; measured: at most 1.6 %
/// low without nugget, 2.3 % with the nugget); the ensemble mean is the mean and the ensemble variance the sill (4.5 standard
/// errors of their averages over the grid, with the grid's correlation counted by measuring the
/// spread over realisations; the variance also 0.03 for the approximation).
#[test]
fn unconditional_realisations_reproduce_the_variogram() {
    let (nx, ny, r) = (50, 50, 200);
    let targets = grid(nx, ny, 1.0);
    let lags = [1, 2, 3, 4, 6, 8, 12, 16];
    for (nugget, path) in [(0.0, SgsPath::PerRealisation), (0.2, SgsPath::Shared)] {
        let v = expo(nugget, 1.0 - nugget, 12.0);
        let sims = Sgs::new(v.clone())
            .simple(3.0)
            .path(path)
            .seed(99)
            .realisations(r)
            .simulate_unconditional(targets.as_ref())
            .unwrap();
        // Per realisation: the semivariogram at each lag (x and y pairs pooled), its mean and
        // its variance over the grid.
        let per: Vec<PerRealisation> = sims
            .iter()
            .map(|x| {
                let g = lags
                    .iter()
                    .map(|&h| {
                        let (mut s, mut c) = (0.0, 0usize);
                        for j in 0..ny {
                            for i in 0..nx {
                                let a = x[j * nx + i];
                                if i + h < nx {
                                    s += (x[j * nx + i + h] - a).powi(2);
                                    c += 1;
                                }
                                if j + h < ny {
                                    s += (x[(j + h) * nx + i] - a).powi(2);
                                    c += 1;
                                }
                            }
                        }
                        s / (2 * c) as f64
                    })
                    .collect();
                let m = x.iter().sum::<f64>() / x.len() as f64;
                let v = x.iter().map(|a| (a - 3.0).powi(2)).sum::<f64>() / x.len() as f64;
                (g, m, v)
            })
            .collect();
        let rf = r as f64;
        let avg_se = |f: &dyn Fn(&PerRealisation) -> f64| {
            let vals: Vec<f64> = per.iter().map(f).collect();
            let a = vals.iter().sum::<f64>() / rf;
            let sd = (vals.iter().map(|x| (x - a).powi(2)).sum::<f64>() / (rf - 1.0)).sqrt();
            (a, sd / rf.sqrt())
        };
        for (li, &h) in lags.iter().enumerate() {
            let (a, se) = avg_se(&|p| p.0[li]);
            let model = v.eval(h as f64);
            println!(
                "nugget {nugget}, lag {h}: {a:.4} vs {model:.4} (se {se:.4}, {:+.1} %)",
                100.0 * (a / model - 1.0)
            );
            assert!(
                (a - model).abs() <= 4.5 * se + 0.03 * model,
                "lag {h}: {a} vs {model} (se {se})"
            );
        }
        let (m, se) = avg_se(&|p| p.1);
        assert!((m - 3.0).abs() <= 4.5 * se, "mean {m} (se {se})");
        let (s2, se) = avg_se(&|p| p.2);
        println!("nugget {nugget}: variance about the mean {s2:.4} (se {se:.4})");
        assert!(
            (s2 - 1.0).abs() <= 4.5 * se + 0.03,
            "variance {s2} (se {se})"
        );
    }
}

/// Geometric anisotropy: unconditional realisations with the major axis along x and a ratio of
/// 1/2 have, along y at lag h, the variogram the model has at 2h (same tolerance as above).
#[test]
fn anisotropy_shapes_the_realisations() {
    let (nx, ny, r) = (40, 40, 150);
    let targets = grid(nx, ny, 1.0);
    let v = expo(0.0, 1.0, 16.0);
    let sims = Sgs::new(v.clone())
        .simple(0.0)
        .anisotropy(Anisotropy::TwoD {
            angle: 0.0,
            ratio: 0.5,
        })
        .path(SgsPath::Shared)
        .seed(5)
        .realisations(r)
        .simulate_unconditional(targets.as_ref())
        .unwrap();
    for h in [1usize, 2, 4, 6] {
        let per: Vec<(f64, f64)> = sims
            .iter()
            .map(|x| {
                let (mut gx, mut gy, mut c) = (0.0, 0.0, 0usize);
                for j in 0..ny - h {
                    for i in 0..nx - h {
                        let a = x[j * nx + i];
                        gx += (x[j * nx + i + h] - a).powi(2);
                        gy += (x[(j + h) * nx + i] - a).powi(2);
                        c += 1;
                    }
                }
                (gx / (2 * c) as f64, gy / (2 * c) as f64)
            })
            .collect();
        let rf = r as f64;
        for (axis, stretch) in [(0, 1.0), (1, 2.0)] {
            let vals: Vec<f64> = per
                .iter()
                .map(|p| if axis == 0 { p.0 } else { p.1 })
                .collect();
            let a = vals.iter().sum::<f64>() / rf;
            let se =
                (vals.iter().map(|x| (x - a).powi(2)).sum::<f64>() / (rf - 1.0)).sqrt() / rf.sqrt();
            let model = v.eval(stretch * h as f64);
            assert!(
                (a - model).abs() <= 4.5 * se + 0.03 * model,
                "axis {axis}, lag {h}: {a} vs {model} (se {se})"
            );
        }
    }
}

/// A limited neighbourhood (the usual use): on 400 targets conditioned on 60 data with the 16
/// nearest, over 4,000 realisations, the ensemble mean and variance at each target are the global
/// simple-kriging estimate and variance within 4.5 standard errors plus 0.03 (3 % of the sill) for
/// the neighbourhood's approximation (measured: at most 4.9 standard errors, 0.004 beyond 4.5 of
/// them; with every node in the neighbourhood the law is exact, see the test above).
#[test]
fn ensemble_is_close_to_kriging_with_a_moving_neighbourhood() {
    let data = halton(60, 100.0);
    let z: Vec<f64> = (0..60)
        .map(|i| (data[(i, 0)] / 25.0).sin() + (data[(i, 1)] / 30.0).cos())
        .collect();
    let targets = grid(20, 20, 100.0 / 19.0);
    let v = expo(0.0, 1.0, 50.0);
    let sk = Krige::new()
        .simple(0.0)
        .variogram(v.clone())
        .fit(data.as_ref(), &z)
        .unwrap()
        .predict_many(targets.as_ref())
        .unwrap();
    let r = 4000;
    let sims = Sgs::new(v)
        .simple(0.0)
        .seed(17)
        .realisations(r)
        .simulate(data.as_ref(), &z, targets.as_ref())
        .unwrap();
    let (em, ev) = (sims.mean(), sims.variance());
    let rf = r as f64;
    let mut worst = 0.0f64; // largest deviation in standard errors
    let mut excess = f64::NEG_INFINITY; // largest deviation beyond 4.5 standard errors
    for t in 0..400 {
        let (est, var) = (sk.values[t], sk.variances[t]);
        let (se_m, se_v) = ((var / rf).sqrt(), var * (2.0 / (rf - 1.0)).sqrt());
        assert!(
            (em[t] - est).abs() <= 4.5 * se_m + 0.03,
            "target {t}: mean {} vs {est}",
            em[t]
        );
        assert!(
            (ev[t] - var).abs() <= 4.5 * se_v + 0.03,
            "target {t}: variance {} vs {var}",
            ev[t]
        );
        worst = worst
            .max((em[t] - est).abs() / se_m)
            .max((ev[t] - var).abs() / se_v);
        excess = excess
            .max((em[t] - est).abs() - 4.5 * se_m)
            .max((ev[t] - var).abs() - 4.5 * se_v);
    }
    println!("largest deviation {worst:.2} standard errors, beyond 4.5 of them by {excess:.4}");
}

/// (c) The same seed gives the same bits on 1 and 4 threads (both paths, nearest and radius
/// neighbourhoods, simple and ordinary kriging, conditional and not); another seed differs.
#[test]
fn same_bits_on_one_and_four_threads() {
    let data = halton(80, 50.0);
    let z: Vec<f64> = (0..80).map(|i| (data[(i, 0)] / 9.0).sin()).collect();
    let targets = grid(25, 25, 50.0 / 24.0);
    let v = NestedVariogram::single(VariogramModel::Spherical, 0.05, 1.0, 20.0)
        .unwrap()
        .with(VariogramModel::Exponential, 0.5, 60.0, 1.0);
    let pool = |t| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build()
            .unwrap()
    };
    let (one, four) = (pool(1), pool(4));
    for (path, nbh, mean) in [
        (
            SgsPath::PerRealisation,
            Neighbourhood::Nearest { k: 16 },
            SgsMean::DataMean,
        ),
        (
            SgsPath::Shared,
            Neighbourhood::Nearest { k: 24 },
            SgsMean::Known(0.0),
        ),
        (
            SgsPath::PerRealisation,
            Neighbourhood::Radius {
                radius: 8.0,
                max: 12,
            },
            SgsMean::Known(0.1),
        ),
        (
            SgsPath::Shared,
            Neighbourhood::Nearest { k: 10 },
            SgsMean::Ordinary,
        ),
    ] {
        let sgs = Sgs::new(v.clone())
            .path(path)
            .neighbourhood(nbh)
            .mean(mean)
            .seed(123)
            .realisations(9);
        let run = |s: &Sgs| s.simulate(data.as_ref(), &z, targets.as_ref()).unwrap();
        let a = one.install(|| run(&sgs));
        let b = four.install(|| run(&sgs));
        assert_eq!(bits(&a), bits(&b), "{path:?} {nbh:?} {mean:?}");
        let c = four.install(|| run(&sgs.clone().seed(124)));
        assert_ne!(bits(&a), bits(&c));
        // Realisations are distinct draws.
        assert_ne!(a.realisation(0), a.realisation(1));
    }
    let uncond = Sgs::new(v).simple(1.0).seed(7).realisations(5);
    let a = one.install(|| uncond.simulate_unconditional(targets.as_ref()).unwrap());
    let b = four.install(|| uncond.simulate_unconditional(targets.as_ref()).unwrap());
    assert_eq!(bits(&a), bits(&b));
}

/// A radius neighbourhood with no datum or earlier node inside: simple kriging draws from the
/// marginal law N(m, sill); ordinary kriging cannot, and says so, naming the target.
#[test]
fn radius_without_neighbours() {
    let data = Mat::from_fn(2, 1, |i, _| [0.0, 1.0][i]);
    let z = [5.0, 5.5];
    let targets = Mat::from_fn(1, 1, |_, _| 1000.0);
    let radius = Neighbourhood::Radius {
        radius: 10.0,
        max: 8,
    };
    let sims = Sgs::new(expo(0.0, 4.0, 5.0))
        .simple(2.0)
        .neighbourhood(radius)
        .seed(1)
        .realisations(4000)
        .simulate(data.as_ref(), &z, targets.as_ref())
        .unwrap();
    let (m, v) = (sims.mean()[0], sims.variance()[0]);
    // Standard errors: mean 2 / sqrt(4000) = 0.032, variance 4 sqrt(2 / 3999) = 0.089.
    assert!((m - 2.0).abs() < 4.5 * 0.032, "mean {m}");
    assert!((v - 4.0).abs() < 4.5 * 0.09, "variance {v}");
    let err = Sgs::new(expo(0.0, 4.0, 5.0))
        .ordinary()
        .neighbourhood(radius)
        .simulate(data.as_ref(), &z, targets.as_ref())
        .unwrap_err();
    match err {
        KrigingError::SimulationNode {
            target: 0,
            realisation: Some(0),
            ref source,
        } => assert!(matches!(
            **source,
            KrigingError::QueryNeighbourhood { got: 0, .. }
        )),
        e => panic!("unexpected {e:?}"),
    }
    assert!(err.to_string().contains("target 0"));
}

/// (d) Errors, each naming what is wrong.
#[test]
fn errors() {
    let v = expo(0.0, 1.0, 5.0);
    let data = Mat::from_fn(3, 2, |i, c| (i * 2 + c) as f64);
    let z = [1.0, 2.0, 3.0];
    let targets = grid(4, 4, 1.0);
    let sgs = Sgs::new(v.clone()).seed(1).realisations(2);
    let sim =
        |s: &Sgs, d: &Mat<f64>, z: &[f64], t: &Mat<f64>| s.simulate(d.as_ref(), z, t.as_ref());

    // No data.
    let none = Mat::<f64>::zeros(0, 2);
    assert!(matches!(
        sim(&sgs, &none, &[], &targets),
        Err(KrigingError::TooFewSamples {
            needed: 1,
            got: 0,
            ..
        })
    ));
    // Unconditional needs a known mean.
    for s in [sgs.clone(), sgs.clone().ordinary()] {
        assert!(matches!(
            s.simulate_unconditional(targets.as_ref()),
            Err(KrigingError::InvalidConfig(_))
        ));
    }
    // Shapes.
    assert!(matches!(
        sim(&sgs, &data, &z[..2], &targets),
        Err(KrigingError::ShapeMismatch {
            expected: 3,
            got: 2,
            ..
        })
    ));
    let t3 = Mat::<f64>::zeros(4, 3);
    assert!(matches!(
        sim(&sgs, &data, &z, &t3),
        Err(KrigingError::ShapeMismatch {
            expected: 2,
            got: 3,
            ..
        })
    ));
    let d0 = Mat::<f64>::zeros(3, 0);
    assert!(matches!(
        sim(&sgs, &d0, &z, &Mat::<f64>::zeros(2, 0)),
        Err(KrigingError::ShapeMismatch { .. })
    ));
    let d1 = Mat::from_fn(3, 1, |i, _| i as f64);
    assert!(matches!(
        sgs.simulate_grid(d1.as_ref(), &z, &[0.0], &[0.0]),
        Err(KrigingError::ShapeMismatch {
            expected: 2,
            got: 1,
            ..
        })
    ));
    // NaN and infinity, with row and column.
    let mut bad = data.clone();
    bad[(1, 1)] = f64::NAN;
    assert!(matches!(
        sim(&sgs, &bad, &z, &targets),
        Err(KrigingError::NonFinite {
            what: "coordinates",
            row: 1,
            col: 1
        })
    ));
    assert!(matches!(
        sim(&sgs, &data, &[1.0, f64::INFINITY, 3.0], &targets),
        Err(KrigingError::NonFinite {
            what: "values",
            row: 1,
            col: 0
        })
    ));
    let mut bt = targets.clone();
    bt[(5, 0)] = f64::NEG_INFINITY;
    assert!(matches!(
        sim(&sgs, &data, &z, &bt),
        Err(KrigingError::NonFinite {
            what: "targets",
            row: 5,
            col: 0
        })
    ));
    // Zero realisations.
    let e = sim(&sgs.clone().realisations(0), &data, &z, &targets).unwrap_err();
    assert!(matches!(e, KrigingError::InvalidConfig(_)) && e.to_string().contains("realisation"));
    // More values than memory can index.
    assert!(matches!(
        sim(&sgs.clone().realisations(usize::MAX), &data, &z, &targets),
        Err(KrigingError::InvalidConfig(_))
    ));
    // Neighbourhoods: global, empty, bad radius.
    for nbh in [
        Neighbourhood::Global,
        Neighbourhood::Nearest { k: 0 },
        Neighbourhood::Radius {
            radius: f64::NAN,
            max: 4,
        },
        Neighbourhood::Radius {
            radius: -1.0,
            max: 4,
        },
        Neighbourhood::Radius {
            radius: 1.0,
            max: 0,
        },
    ] {
        assert!(
            matches!(
                sim(&sgs.clone().neighbourhood(nbh), &data, &z, &targets),
                Err(KrigingError::InvalidConfig(_))
            ),
            "{nbh:?}"
        );
    }
    // A non-finite mean.
    assert!(matches!(
        sim(&sgs.clone().simple(f64::NAN), &data, &z, &targets),
        Err(KrigingError::InvalidConfig(_))
    ));
    // Unbounded variograms have no covariance; invalid parameters; a structureless zero nugget.
    let power = NestedVariogram::single(VariogramModel::Power, 0.0, 1.0, 1.5).unwrap();
    assert!(matches!(
        sim(&Sgs::new(power), &data, &z, &targets),
        Err(KrigingError::InvalidVariogram {
            model: VariogramModel::Power,
            ..
        })
    ));
    let mut negative = v.clone();
    negative.structures[0].sill = -1.0;
    assert!(sim(&Sgs::new(negative), &data, &z, &targets).is_err());
    let empty = NestedVariogram {
        nugget: 0.0,
        structures: vec![],
    };
    assert!(matches!(
        sim(&Sgs::new(empty), &data, &z, &targets),
        Err(KrigingError::InvalidConfig(_))
    ));
    // Anisotropy that does not fit the dimension.
    let aniso = Anisotropy::ThreeD {
        angles: [0.0; 3],
        ratios: [1.0, 1.0],
    };
    assert!(matches!(
        sim(&sgs.clone().anisotropy(aniso), &data, &z, &targets),
        Err(KrigingError::InvalidConfig(_))
    ));
    // Two data at one site (with or without a nugget): one value per site.
    let dup = Mat::from_fn(
        3,
        2,
        |i, c| if i == 2 { c as f64 } else { (i * 2 + c) as f64 },
    );
    for s in [sgs.clone(), Sgs::new(expo(0.5, 1.0, 5.0))] {
        assert!(matches!(
            sim(&s, &dup, &z, &targets),
            Err(KrigingError::CoincidentData {
                first: 0,
                second: 2
            })
        ));
    }
    // A singular node system: a gaussian variogram without nugget and targets 1e-6 apart.
    let gauss = NestedVariogram::single(VariogramModel::Gaussian, 0.0, 1.0, 50.0).unwrap();
    let close = Mat::from_fn(6, 1, |i, _| 10.0 + 1e-6 * i as f64);
    let e = Sgs::new(gauss)
        .simple(0.0)
        .simulate(d1.as_ref(), &z, close.as_ref())
        .unwrap_err();
    assert!(
        matches!(&e, KrigingError::SimulationNode { source, .. }
            if matches!(**source, KrigingError::Singular { .. })),
        "{e:?}"
    );
}

/// Edge cases that are not errors: no targets, a pure-nugget variogram (independent draws around
/// the mean except at the data), one datum.
#[test]
fn edge_cases() {
    let data = Mat::from_fn(1, 2, |_, c| [3.0, 4.0][c]);
    let z = [7.0];
    let sgs = Sgs::new(expo(0.0, 1.0, 5.0)).realisations(3);
    let empty = sgs
        .simulate(data.as_ref(), &z, Mat::<f64>::zeros(0, 2).as_ref())
        .unwrap();
    assert_eq!((empty.n_realisations(), empty.n_targets()), (3, 0));
    assert_eq!(empty.realisation(2), Some(&[][..]));
    assert_eq!(empty.realisation(3), None);
    // One datum, data mean = the datum: the target on it is the datum, others vary around 7.
    let targets = Mat::from_fn(3, 2, |t, c| [[3.0, 4.0], [3.5, 4.0], [30.0, 4.0]][t][c]);
    let s = sgs.simulate(data.as_ref(), &z, targets.as_ref()).unwrap();
    assert!(s.iter().all(|r| r[0] == 7.0 && r[1] != 7.0));
    // Pure nugget: independent N(m, nugget) off the data.
    let noise = NestedVariogram {
        nugget: 0.25,
        structures: vec![],
    };
    let s = Sgs::new(noise)
        .simple(1.0)
        .seed(4)
        .realisations(4000)
        .simulate(data.as_ref(), &z, targets.as_ref())
        .unwrap();
    let (m, v) = (s.mean(), s.variance());
    assert_eq!((m[0], v[0]), (7.0, 0.0));
    // Standard errors: mean 0.5 / sqrt(4000) = 0.0079, variance 0.25 sqrt(2 / 3999) = 0.0056.
    for t in 1..3 {
        assert!((m[t] - 1.0).abs() < 4.5 * 0.0079, "mean {}", m[t]);
        assert!((v[t] - 0.25).abs() < 4.5 * 0.0056, "variance {}", v[t]);
    }
    // Any number of neighbours: beyond the data and targets it is all of them.
    let all = |k| {
        sgs.clone()
            .neighbours(k)
            .simulate(data.as_ref(), &z, targets.as_ref())
            .unwrap()
    };
    assert_eq!(all(usize::MAX), all(4));
    // The grid helper: target j * nx + i at (xs[i], ys[j]).
    let xs = [0.0, 1.0, 2.0];
    let ys = [3.0, 4.0];
    let g = sgs.simulate_grid(data.as_ref(), &z, &xs, &ys).unwrap();
    assert_eq!(g.n_targets(), 6);
    assert!(g.iter().all(|r| r.len() == 6));
    let one = sgs
        .clone()
        .realisations(1)
        .simulate(data.as_ref(), &z, targets.as_ref())
        .unwrap();
    assert_eq!(one.variance(), vec![0.0; 3]);
}
