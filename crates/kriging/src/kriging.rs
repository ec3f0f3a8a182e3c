//! The fitted kriging model: ordinary kriging (appendix A) and the paper's regression kriging (eq. 8,
//! which the paper calls universal kriging).

use faer::{Mat, MatRef};

use crate::config::{CandidateReport, KrigingConfig, LooReport, Method, ModelChoice, Selection};
use crate::empirical::{EmpiricalVariogram, PairDistances};
use crate::error::KrigingError;
use crate::fit::{FitOptions, fit_variogram};
use crate::linalg::{
    CheckedLu, checked_inverse_of, from_fn_par, matmul, matmul_par_cols, select_rows, sym_pinv,
};
use crate::scaling::ParamScaling;
use crate::variogram::{Variogram, VariogramModel};
use std::sync::OnceLock;

/// A fitted ordinary or regression kriging model over S samples with d parameters and D values.
///
/// The kriging matrix `A = [Gamma 1; 1^t 0]` ((S+1) x (S+1), `Gamma_ij = gamma(|c_i - c_j|)` for
/// `i != j`, 0 on the diagonal) is factorised once at fit time and kept as its inverse `A^-1`, so
/// that the weights of appendix A, `[b(c); lambda] = A^-1 [gamma(c); 1]`, cost `S (S+1)`
/// multiply-adds plus S variogram evaluations. For regression kriging ([`Method::Regression`]) the
/// values are first reduced
/// by the trend hyperplane `F [c; 1]` (eq. 8) and `b(c)` are the ordinary-kriging weights of the
/// residuals.
#[derive(Debug, Clone)]
pub struct Kriging {
    method: Method,
    variogram: Variogram,
    scaling: ParamScaling,
    dropped: Vec<usize>,
    /// S x d scaled parameters.
    scaled: Mat<f64>,
    /// Row-major copy of `scaled` (S * d).
    scaled_rows: Vec<f64>,
    /// S x D residuals (values for ordinary kriging).
    residuals: Mat<f64>,
    /// D x (d+1) trend F (regression kriging only).
    trend: Option<Mat<f64>>,
    /// Numerical rank of `C C^t` (regression kriging only).
    trend_rank: Option<usize>,
    /// (d+1) x (d+1) Gram matrix C C^t and (d+1) x D product C X (regression only, for the LOO).
    gram: Option<Mat<f64>>,
    cx: Option<Mat<f64>>,
    /// The factorised kriging matrix and its symmetric inverse ((S+1) x (S+1)).
    system: System,
    /// Row-major (S+1) x D dual coefficients `A^-1[:, :S] R`.
    dual: Vec<f64>,
    empirical: Option<EmpiricalVariogram>,
    candidates: Vec<CandidateReport>,
}

/// Checks shapes and finiteness of `params` (S x d) and `values` (S x D).
/// Shapes (one row per sample, at least one parameter and one value dimension) and finiteness.
pub(crate) fn check_inputs(
    params: MatRef<'_, f64>,
    values: MatRef<'_, f64>,
) -> Result<(), KrigingError> {
    if params.nrows() != values.nrows() {
        return Err(KrigingError::ShapeMismatch {
            what: "values rows vs parameter rows",
            expected: params.nrows(),
            got: values.nrows(),
        });
    }
    if params.ncols() == 0 {
        return Err(KrigingError::ShapeMismatch {
            what: "parameter dimensions (need at least one)",
            expected: 1,
            got: 0,
        });
    }
    if values.ncols() == 0 {
        return Err(KrigingError::ShapeMismatch {
            what: "value dimensions (need at least one)",
            expected: 1,
            got: 0,
        });
    }
    crate::check_finite("params", params)?;
    crate::check_finite("values", values)
}

/// The augmented parameter matrix `C` ((d+1) x S): column i is `[c_i; 1]` (scaled).
///
/// ```
/// use kriging::faer::Mat;
/// let p = Mat::from_fn(3, 2, |i, k| (10 * i + k) as f64); // rows (0, 1), (10, 11), (20, 21)
/// let c = kriging::augmented_params(p.as_ref());
/// assert_eq!(c.shape(), (3, 3));
/// assert_eq!([c[(0, 2)], c[(1, 2)], c[(2, 2)]], [20.0, 21.0, 1.0]);
/// ```
pub fn augmented_params(scaled: MatRef<'_, f64>) -> Mat<f64> {
    let (s, d) = scaled.shape();
    Mat::from_fn(d + 1, s, |k, i| if k < d { scaled[(i, k)] } else { 1.0 })
}

/// Centres the scaled parameters for the trend when they are far from the origin: for every kept
/// dimension whose scaled mean `m_k` exceeds ten times its scaled standard deviation in magnitude
/// (raw map coordinates such as 1.8e5 with a spread of 1e3), the offset moves by `m_k / scale_k` so that the
/// scaled dimension has mean about 0. A translation leaves every distance, hence the variogram and
/// the kriging weights, unchanged; it keeps the Gram matrix `C C^t` of the trend well conditioned
/// (otherwise its pseudo-inverse, with relative tolerance [`PINV_RTOL`](crate::PINV_RTOL), silently
/// drops a direction). Standardised parameters have mean 0 and are left exactly as they are.
fn centre_for_trend(scaling: &mut ParamScaling, params: MatRef<'_, f64>) {
    let s = params.nrows();
    for k in 0..params.ncols() {
        let sc = scaling.scale[k];
        if sc == 0.0 || s == 0 {
            continue;
        }
        let col = |i: usize| (params[(i, k)] - scaling.offset[k]) * sc;
        let mean = (0..s).map(col).sum::<f64>() / s as f64;
        let sd = ((0..s).map(|i| (col(i) - mean).powi(2)).sum::<f64>() / s as f64).sqrt();
        if mean.abs() > 10.0 * sd {
            scaling.offset[k] += mean / sc;
        }
    }
}

/// Least-squares trend of eq. 8: returns `(F, R, G, C X)` with `F = X^t C^+` (D x (d+1)) computed
/// as `(C X)^t (C C^t)^+`, residuals `R = X - C^t F^t` (S x D), `G = C C^t`.
fn fit_trend(
    scaled: MatRef<'_, f64>,
    values: MatRef<'_, f64>,
) -> (Mat<f64>, Mat<f64>, Mat<f64>, Mat<f64>) {
    let c = augmented_params(scaled);
    let g = matmul(c.as_ref(), c.transpose());
    let cx = matmul(c.as_ref(), values);
    let (gp, _) = sym_pinv(g.as_ref());
    let t = matmul(gp.as_ref(), cx.as_ref()); // (d+1) x D = F^t
    let fitted = matmul(c.transpose(), t.as_ref()); // S x D
    let residuals = Mat::from_fn(values.nrows(), values.ncols(), |i, j| {
        values[(i, j)] - fitted[(i, j)]
    });
    (t.transpose().to_owned(), residuals, g, cx)
}

/// Fails when the residuals (values for ordinary kriging) vanish relative to the spread of the
/// values around their mean (`|R|_F <= 1e-10 |X - mean X|_F`, or both zero): there is nothing to fit
/// a variogram to (constant values, or values exactly linear in the parameters under regression
/// kriging). [`ModelChoice::Given`] skips this check.
fn check_residuals_vary(
    values: MatRef<'_, f64>,
    residuals: MatRef<'_, f64>,
) -> Result<(), KrigingError> {
    let (s, dv) = values.shape();
    let mut spread = 0.0;
    for j in 0..dv {
        let mean = (0..s).map(|i| values[(i, j)]).sum::<f64>() / s as f64;
        let col = (0..s).map(|i| (values[(i, j)] - mean).powi(2)).sum::<f64>();
        // Finite values whose squared deviations overflow would otherwise read as "do not vary".
        if !col.is_finite() {
            return Err(KrigingError::Overflow {
                what: format!("values column {j}"),
                reason: format!("the sum of squared deviations from the mean is {col}"),
            });
        }
        spread += col;
    }
    let rnorm: f64 = (0..dv)
        .flat_map(|j| (0..s).map(move |i| (i, j)))
        .map(|(i, j)| residuals[(i, j)].powi(2))
        .sum();
    if !(spread.is_finite() && rnorm.is_finite()) {
        return Err(KrigingError::Overflow {
            what: "values".into(),
            reason: format!(
                "the sums of squares over the samples are {spread} (values) and {rnorm} \
                 (residuals of the trend)"
            ),
        });
    }
    if rnorm.sqrt() <= 1e-10 * spread.sqrt() {
        return Err(KrigingError::VariogramFit {
            model: None,
            reason:
                "the kriged quantities do not vary over the samples (constant values, or values \
                     exactly linear in the parameters under regression kriging); give a variogram \
                     with ModelChoice::Given to get blending weights anyway"
                    .into(),
        });
    }
    Ok(())
}

/// The entries of the kriging matrix `A = [Gamma 1; 1^t 0]` for variogram `v`, after refusing
/// coinciding samples without a nugget ([`KrigingError::DuplicateParams`]).
fn kriging_entries<'a>(
    dist: &'a PairDistances,
    s: usize,
    v: &'a Variogram,
) -> Result<impl Fn(usize, usize) -> f64 + Sync + 'a, KrigingError> {
    if v.nugget == 0.0 {
        if let Some((first, second)) = dist.first_duplicate(dist.duplicate_tol()) {
            return Err(KrigingError::DuplicateParams {
                what: "kriging",
                first,
                second,
            });
        }
    }
    Ok(move |i: usize, j: usize| {
        if i == s || j == s {
            if i == j { 0.0 } else { 1.0 }
        } else if i == j {
            0.0
        } else {
            v.between_samples(dist.get(i, j))
        }
    })
}

/// Builds and inverts the kriging matrix `A = [Gamma 1; 1^t 0]`.
fn kriging_inverse(
    dist: &PairDistances,
    s: usize,
    v: &Variogram,
) -> Result<Mat<f64>, KrigingError> {
    let entry = kriging_entries(dist, s, v)?;
    checked_inverse_of(from_fn_par(s + 1, s + 1, &entry), &entry, true, "kriging")
}

/// The kriging matrix's factorisation for a system above [`EAGER_INVERSE_MAX_SAMPLES`] samples
/// (same checks as [`kriging_inverse`]).
fn kriging_factor(
    dist: &PairDistances,
    s: usize,
    v: &Variogram,
) -> Result<CheckedLu, KrigingError> {
    let entry = kriging_entries(dist, s, v)?;
    CheckedLu::factor(from_fn_par(s + 1, s + 1, &entry), &entry, "kriging")
}

/// Up to this many samples a fit forms the inverse of its kriging system at once (leave-one-out,
/// the weights and the search use it); above, it keeps the LU factorisation, solves for the dual
/// coefficients and forms the inverse only when asked ([`Kriging::system_inverse`],
/// [`Kriging::loo_errors`], [`Kriging::weights`]): the inverse of a system over ten thousand samples
/// takes about twice the factorisation's flops (`4 n^3 / 3` against `2 n^3 / 3`) and another 800 MB.
pub const EAGER_INVERSE_MAX_SAMPLES: usize = 1000;

/// The factorised kriging system (see [`EAGER_INVERSE_MAX_SAMPLES`]).
#[derive(Debug, Clone, Default)]
struct System {
    /// The LU factors (large systems only).
    lu: Option<CheckedLu>,
    /// The symmetric inverse: set by the fit for small systems, on first use for large ones.
    inverse: OnceLock<Mat<f64>>,
}

impl System {
    fn inverse(&self) -> &Mat<f64> {
        self.inverse.get_or_init(|| {
            self.lu
                .as_ref()
                .map_or_else(|| Mat::zeros(0, 0), |lu| lu.inverse(true))
        })
    }
}

/// `[m; 0]`: `m` (S x k) with a row of zeros below, the right-hand side of `A X = [m; 0]`.
fn with_zero_row(m: MatRef<'_, f64>) -> Mat<f64> {
    let s = m.nrows();
    Mat::from_fn(s + 1, m.ncols(), |i, j| if i < s { m[(i, j)] } else { 0.0 })
}

/// A matrix's entries row by row.
fn row_major(m: MatRef<'_, f64>) -> Vec<f64> {
    let (r, c) = m.shape();
    let mut out = Vec::with_capacity(r * c);
    for i in 0..r {
        for j in 0..c {
            out.push(m[(i, j)]);
        }
    }
    out
}

/// Row-major `A^-1[:, :S] R` (`n x D` for an `n x n` inverse of a system over `S` samples): the dual
/// coefficients of kriging (`n = S + 1`) and of the RBF baseline (`n = S + q`).
pub(crate) fn dual_coefficients(ainv: MatRef<'_, f64>, residuals: MatRef<'_, f64>) -> Vec<f64> {
    let s = residuals.nrows();
    row_major(matmul_par_cols(ainv.subcols(0, s), residuals).as_ref())
}

impl Kriging {
    /// Fits a kriging model to `params` (S x d, one sample per row) and `values` (S x D).
    ///
    /// Steps: scale the parameters (for [`Method::Regression`], parameters far from the origin
    /// relative to their spread are also centred, which changes no distance: see
    /// [`Kriging::scaling`]); for [`Method::Regression`] fit the trend `F = K C^+` (pseudo-
    /// inverse with a relative eigenvalue tolerance of 1e-12 on `C C^t`, so constant or collinear
    /// dimensions are handled) and take residuals; bin the empirical variogram of the residuals;
    /// fit or take the variogram; factorise the kriging system.
    ///
    /// Errors: shape mismatch, NaN/inf, too few samples (ordinary: 2; regression: d' + 2 with d'
    /// the non-dropped dimensions), coinciding parameters without nugget
    /// ([`KrigingError::DuplicateParams`], both indices), no usable variogram, singular system.
    /// With a positive nugget duplicates are allowed: the nugget then acts as independent noise
    /// between distinct samples ([`Variogram::between_samples`]), which keeps the system regular.
    pub fn fit(
        params: MatRef<'_, f64>,
        values: MatRef<'_, f64>,
        config: &KrigingConfig,
    ) -> Result<Kriging, KrigingError> {
        check_inputs(params, values)?;
        let s = params.nrows();
        let mut scaling = ParamScaling::from_choice(&config.scaling, params)?;
        if config.method == Method::Regression {
            centre_for_trend(&mut scaling, params);
        }
        let dropped = scaling.dropped();
        let d_eff = params.ncols() - dropped.len();
        let needed = match config.method {
            Method::Ordinary => 2,
            Method::Regression => d_eff + 2,
        };
        if s < needed {
            return Err(KrigingError::TooFewSamples {
                what: match config.method {
                    Method::Ordinary => "ordinary kriging",
                    Method::Regression => "regression kriging (trend over [c; 1] plus residuals)",
                },
                needed,
                got: s,
            });
        }
        let scaled = scaling.apply_rows(params);
        let (trend, residuals, gram, cx) = match config.method {
            Method::Ordinary => (None, values.to_owned(), None, None),
            Method::Regression => {
                let (f, r, g, cx) = fit_trend(scaled.as_ref(), values);
                (Some(f), r, Some(g), Some(cx))
            }
        };
        let trend_rank = gram.as_ref().map(|g| sym_pinv(g.as_ref()).1);
        let dist = PairDistances::new(scaled.as_ref());
        if dist.max().is_nan() || dist.max() <= 0.0 {
            return Err(KrigingError::NoSpread { samples: s });
        }
        if dist.max().is_infinite() {
            return Err(KrigingError::Overflow {
                what: "parameters".into(),
                reason: "the distance between two (scaled) samples is inf".into(),
            });
        }
        let mut scaled_rows = Vec::with_capacity(s * scaled.ncols());
        for i in 0..s {
            for k in 0..scaled.ncols() {
                scaled_rows.push(scaled[(i, k)]);
            }
        }
        let mut model = Kriging {
            method: config.method,
            variogram: Variogram {
                model: VariogramModel::Linear,
                nugget: 0.0,
                sill: 1.0,
                range: 0.0,
                exponent: 1.0,
            },
            scaling,
            dropped,
            scaled,
            scaled_rows,
            residuals,
            trend,
            trend_rank,
            gram,
            cx,
            system: System::default(),
            dual: Vec::new(),
            empirical: None,
            candidates: Vec::new(),
        };
        if !matches!(config.model, ModelChoice::Given(_)) {
            check_residuals_vary(values, model.residuals.as_ref())?;
        }
        let opts = FitOptions {
            nugget: config.nugget,
            weights: config.fit_weights,
        };
        match config.model {
            ModelChoice::Given(v) => {
                v.validate()?;
                model.install(&dist, v)?;
            }
            ModelChoice::Fixed(m) => {
                let emp = model.empirical_variogram(&dist, config.bins)?;
                let fitted = fit_variogram(&emp, m, &opts)?;
                model.candidates.push(CandidateReport {
                    model: m,
                    variogram: Some(fitted.variogram),
                    wsse: Some(fitted.wsse),
                    loo_rmse: None,
                    error: None,
                    bounds: Some(fitted.bounds),
                });
                model.empirical = Some(emp);
                model.install(&dist, fitted.variogram)?;
            }
            ModelChoice::Auto(Selection::LooSearch) => {
                let emp = model.empirical_variogram(&dist, config.bins)?;
                let mut reports = crate::search::candidates(&emp, &dist, s, &opts);
                // Ranked on at most SEARCH_SAMPLES of the samples (a copy only when fewer).
                let rows = crate::search::search_rows(s);
                let picked = (rows.len() < s)
                    .then(|| (select_rows(params, &rows), select_rows(values, &rows)));
                let (p_rank, v_rank) = picked
                    .as_ref()
                    .map_or((params, values), |(p, v)| (p.as_ref(), v.as_ref()));
                let probe = crate::search::compress(v_rank, crate::search::SEARCH_COLUMNS);
                let order = crate::search::rank(p_rank, probe.as_ref(), config, &mut reports);
                model.empirical = Some(emp);
                model.install_first(&dist, reports, &order)?;
            }
            ModelChoice::Auto(sel) => {
                let emp = model.empirical_variogram(&dist, config.bins)?;
                model.auto_select(&dist, &emp, sel, &opts)?;
                model.empirical = Some(emp);
            }
        }
        Ok(model)
    }

    /// The empirical variogram of the residuals ([`EmpiricalVariogram`]): over every pair of
    /// samples up to [`crate::search::SEARCH_SAMPLES`], else over the pairs of that many evenly
    /// strided samples ([`crate::search::search_rows`]; the bins then span their largest
    /// distance). Its cost grows as the pairs times the value columns; a variogram's shape is
    /// estimated as well from a thousand samples' half a million pairs.
    fn empirical_variogram(
        &self,
        dist: &PairDistances,
        bins: usize,
    ) -> Result<EmpiricalVariogram, KrigingError> {
        let s = self.n_samples();
        let rows = crate::search::search_rows(s);
        if rows.len() == s {
            return EmpiricalVariogram::from_distances(dist, self.residuals.as_ref(), bins);
        }
        let scaled = select_rows(self.scaled.as_ref(), &rows);
        EmpiricalVariogram::from_distances(
            &PairDistances::new(scaled.as_ref()),
            select_rows(self.residuals.as_ref(), &rows).as_ref(),
            bins,
        )
    }

    /// Factorises the system for `v` and stores everything that depends on it.
    fn install(&mut self, dist: &PairDistances, v: Variogram) -> Result<(), KrigingError> {
        let s = self.n_samples();
        if s <= EAGER_INVERSE_MAX_SAMPLES {
            let ainv = kriging_inverse(dist, s, &v)?;
            self.dual = dual_coefficients(ainv.as_ref(), self.residuals.as_ref());
            self.system = System {
                lu: None,
                inverse: OnceLock::from(ainv),
            };
        } else {
            let lu = kriging_factor(dist, s, &v)?;
            // A^-1[:, :S] R = A^-1 [R; 0].
            let rhs = with_zero_row(self.residuals.as_ref());
            self.dual = row_major(lu.solve(rhs.as_ref()).as_ref());
            self.system = System {
                lu: Some(lu),
                inverse: OnceLock::new(),
            };
        }
        self.variogram = v;
        Ok(())
    }

    /// Tries every model and installs the best by `sel`; fills `self.candidates`.
    fn auto_select(
        &mut self,
        dist: &PairDistances,
        emp: &EmpiricalVariogram,
        sel: Selection,
        opts: &FitOptions,
    ) -> Result<(), KrigingError> {
        let mut reports = crate::search::fitted_candidates(emp, opts);
        for rep in &mut reports {
            let (Some(v), Some(wsse)) = (rep.variogram, rep.wsse) else {
                continue;
            };
            let score = match sel {
                Selection::BestFit => Ok(wsse),
                Selection::BestLoo | Selection::LooSearch => self
                    .install(dist, v)
                    .and_then(|_| self.leave_one_out())
                    .map(|l| {
                        rep.loo_rmse = Some(l.rmse);
                        l.rmse
                    }),
            };
            match score {
                Err(e) => rep.error = Some(e.to_string()),
                Ok(sc) if sc.is_finite() => {}
                Ok(sc) => rep.error = Some(format!("non-finite score {sc}")),
            }
        }
        // For BestFit a model with the best fit may still give a singular system: fall back
        // through the candidates in order of fit error.
        let mut order: Vec<usize> = (0..reports.len())
            .filter(|&i| reports[i].error.is_none())
            .collect();
        let score = |r: &CandidateReport| match sel {
            Selection::BestFit => r.wsse.unwrap_or(f64::INFINITY),
            Selection::BestLoo | Selection::LooSearch => r.loo_rmse.unwrap_or(f64::INFINITY),
        };
        order.sort_by(|&a, &b| {
            score(&reports[a])
                .total_cmp(&score(&reports[b]))
                .then(a.cmp(&b))
        });
        self.install_first(dist, reports, &order)
    }

    /// Installs the first candidate in `order` whose system is regular (recording why earlier ones
    /// failed) and keeps `reports` as [`Kriging::candidates`]; [`KrigingError::NoModel`] if none is.
    fn install_first(
        &mut self,
        dist: &PairDistances,
        mut reports: Vec<CandidateReport>,
        order: &[usize],
    ) -> Result<(), KrigingError> {
        let mut installed = false;
        for &i in order {
            let v = reports[i]
                .variogram
                .expect("ranked candidates have a variogram");
            match self.install(dist, v) {
                Ok(()) => {
                    installed = true;
                    break;
                }
                Err(e) => reports[i].error = Some(e.to_string()),
            }
        }
        self.candidates = reports;
        if !installed {
            return Err(KrigingError::NoModel(self.candidate_errors()));
        }
        Ok(())
    }

    /// Why every candidate failed, one `model: error` per candidate.
    fn candidate_errors(&self) -> String {
        self.candidates
            .iter()
            .map(|r| format!("{}: {}", r.model.name(), r.error.as_deref().unwrap_or("?")))
            .collect::<Vec<_>>()
            .join("; ")
    }

    /// Number of samples S.
    pub fn n_samples(&self) -> usize {
        self.scaled.nrows()
    }

    /// Number of parameter dimensions d.
    pub fn n_params(&self) -> usize {
        self.scaled.ncols()
    }

    /// Number of value dimensions D.
    pub fn n_values(&self) -> usize {
        self.residuals.ncols()
    }

    /// The estimator.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The variogram of the kriging system (of the residuals for regression kriging).
    pub fn variogram(&self) -> &Variogram {
        &self.variogram
    }

    /// The parameter scaling applied before any distance (as chosen, except that regression kriging
    /// centres dimensions whose mean exceeds their spread, so that the trend is well conditioned).
    pub fn scaling(&self) -> &ParamScaling {
        &self.scaling
    }

    /// Parameter dimensions dropped because they are constant over the samples (scale 0).
    pub fn dropped_dims(&self) -> &[usize] {
        &self.dropped
    }

    /// The scaled sample parameters (S x d).
    pub fn scaled_params(&self) -> MatRef<'_, f64> {
        self.scaled.as_ref()
    }

    /// `C` of eq. 8 ((d+1) x S): column i is `[scaled c_i; 1]`.
    pub fn augmented_params(&self) -> Mat<f64> {
        augmented_params(self.scaled.as_ref())
    }

    /// `C^+ = C^t (C C^t)^+` (S x (d+1)), the pseudo-inverse of [`Kriging::augmented_params`] with
    /// the same tolerance as the trend ([`PINV_RTOL`](crate::PINV_RTOL)): the trend of eq. 8 is
    /// `F = X^t C^+`, and the sample weights equivalent to a regression kriging prediction at `c` are
    /// `C^+ [c; 1] + (I - C^+ C) b(c)`.
    pub fn augmented_pinv(&self) -> Mat<f64> {
        let c = self.augmented_params();
        let g = matmul(c.as_ref(), c.transpose());
        let (gp, _) = sym_pinv(g.as_ref());
        matmul(c.transpose(), gp.as_ref())
    }

    /// The numerical rank of the trend's Gram matrix `C C^t` (regression kriging; `None` for ordinary
    /// kriging). Full rank is `d' + 1` with `d'` the non-dropped dimensions; less means collinear
    /// parameter dimensions, which the pseudo-inverse handles by fitting the trend in their span.
    pub fn trend_rank(&self) -> Option<usize> {
        self.trend_rank
    }

    /// The trend `F` (D x (d+1)) of eq. 8, acting on `[scaled c; 1]`; `None` for ordinary kriging.
    pub fn trend(&self) -> Option<MatRef<'_, f64>> {
        self.trend.as_ref().map(|t| t.as_ref())
    }

    /// The kriged quantities (S x D): residuals `x_i - F [c_i; 1]` for regression kriging, the values
    /// for ordinary kriging.
    pub fn residuals(&self) -> MatRef<'_, f64> {
        self.residuals.as_ref()
    }

    /// The symmetric inverse of the kriging matrix `A^-1` ((S+1) x (S+1)). Above
    /// [`EAGER_INVERSE_MAX_SAMPLES`] samples it is formed from the factorisation on the first call
    /// (and kept); [`Kriging::project_rows`] needs only the factorisation.
    pub fn system_inverse(&self) -> MatRef<'_, f64> {
        self.system.inverse().as_ref()
    }

    /// `U^t A^-1[:S, :]` (m x (S+1)) for `u` (S x m): the rows of the kriging's linear map from
    /// `[gamma(c); 1]` to the weights' projection `U^t b(c)` (appendix A), what a runtime keeps
    /// per key (`u = U_S`) and for the trend (`u = C^t`). With the inverse at hand (up to
    /// [`EAGER_INVERSE_MAX_SAMPLES`] samples) each entry is the dot product of a column of `u`
    /// with a column of `A^-1`, summed in sample order; above, the factorisation solves
    /// `A X = [u; 0]` (`X^t` is the result, `A` being symmetric). Deterministic for any thread
    /// count.
    ///
    /// Errors: `u` with other than S rows, or a non-finite entry.
    pub fn project_rows(&self, u: MatRef<'_, f64>) -> Result<Mat<f64>, KrigingError> {
        use rayon::prelude::*;
        let s = self.n_samples();
        if u.nrows() != s {
            return Err(KrigingError::ShapeMismatch {
                what: "rows of the projected matrix vs samples",
                expected: s,
                got: u.nrows(),
            });
        }
        crate::check_finite("projected matrix", u)?;
        let m = u.ncols();
        if let Some(lu) = &self.system.lu {
            return Ok(lu.solve(with_zero_row(u).as_ref()).transpose().to_owned());
        }
        let a = self.system.inverse();
        let cols: Vec<Vec<f64>> = (0..m).map(|l| u.col(l).iter().copied().collect()).collect();
        let per_col: Vec<Vec<f64>> = (0..=s)
            .into_par_iter()
            .map(|j| {
                let acol = &a.col_as_slice(j)[..s];
                cols.iter()
                    .map(|ucol| ucol.iter().zip(acol).map(|(u, a)| u * a).sum())
                    .collect()
            })
            .collect();
        Ok(Mat::from_fn(m, s + 1, |l, j| per_col[j][l]))
    }

    /// The empirical variogram the model was fitted to (`None` for [`ModelChoice::Given`]): over
    /// every pair of samples, or above [`crate::search::SEARCH_SAMPLES`] samples over the pairs
    /// of that many evenly strided ones.
    pub fn empirical(&self) -> Option<&EmpiricalVariogram> {
        self.empirical.as_ref()
    }

    /// What each candidate model gave during the fit (empty for [`ModelChoice::Given`]).
    pub fn candidates(&self) -> &[CandidateReport] {
        &self.candidates
    }

    /// Checks a query point and an output length.
    fn check_query(
        &self,
        c: &[f64],
        out_len: usize,
        expected_out: usize,
    ) -> Result<(), KrigingError> {
        check_query(c, self.n_params(), out_len, expected_out)
    }

    /// Distance between the scaled query `c` (unscaled input) and sample `j`.
    #[inline]
    fn dist_to(&self, c: &[f64], j: usize) -> f64 {
        scaled_dist(&self.scaling, &self.scaled_rows, c, j)
    }

    /// The kriging weights `b(c)` (length S) of appendix A: `b = A^-1[:S, :] [gamma(c); 1]`.
    /// They sum to one; at a sample `c_i` they are the unit vector `e_i` (exact interpolation).
    /// No allocation.
    pub fn weights(&self, c: &[f64], out: &mut [f64]) -> Result<(), KrigingError> {
        let s = self.n_samples();
        self.check_query(c, out.len(), s)?;
        let ainv = self.system.inverse();
        out.copy_from_slice(&ainv.col_as_slice(s)[..s]);
        for j in 0..s {
            let g = self.variogram.eval(self.dist_to(c, j));
            let col = &ainv.col_as_slice(j)[..s];
            for (o, a) in out.iter_mut().zip(col) {
                *o += g * a;
            }
        }
        check_result("the kriging weights", out)
    }

    /// The prediction at `c` (length D): `F [c; 1] + sum_i b_i(c) r_i` (eq. 8; ordinary kriging:
    /// `sum_i b_i(c) x_i`), evaluated in the dual form `[gamma(c); 1]^t A^-1[:, :S] R`.
    /// No allocation.
    pub fn predict(&self, c: &[f64], out: &mut [f64]) -> Result<(), KrigingError> {
        let s = self.n_samples();
        let dv = self.n_values();
        self.check_query(c, out.len(), dv)?;
        out.copy_from_slice(&self.dual[s * dv..(s + 1) * dv]);
        for j in 0..s {
            let g = self.variogram.eval(self.dist_to(c, j));
            for (o, a) in out.iter_mut().zip(&self.dual[j * dv..(j + 1) * dv]) {
                *o += g * a;
            }
        }
        if let Some(f) = &self.trend {
            let d = self.n_params();
            for k in 0..=d {
                let z = c.get(k).map_or(1.0, |&ck| {
                    (ck - self.scaling.offset[k]) * self.scaling.scale[k]
                });
                for (o, fk) in out.iter_mut().zip(f.col_as_slice(k)) {
                    *o += z * fk;
                }
            }
        }
        check_result("the prediction", out)
    }

    /// The predictions at every row of `queries` (n x d, unscaled like [`Kriging::predict`]'s
    /// `c`), as an n x D matrix: the same dual form as matrix products,
    /// `[Gamma_q 1] (A^-1[:, :S] R) + Z F^t`, with `Gamma_q` the n x S variogram values between
    /// queries and samples and `Z` the scaled queries `[c; 1]`. Agrees with [`Kriging::predict`]
    /// row by row up to the order of the sums (rounding); the products stream the dual
    /// coefficients once per block of queries instead of once per query, which is what
    /// cross-validating many held-out samples needs. Deterministic for any thread count (column
    /// blocks of fixed width).
    ///
    /// Errors: a query of the wrong length or with a non-finite entry (its row in the message).
    pub fn predict_rows(&self, queries: MatRef<'_, f64>) -> Result<Mat<f64>, KrigingError> {
        let s = self.n_samples();
        let d = self.n_params();
        let dv = self.n_values();
        let n = queries.nrows();
        if queries.ncols() != d {
            return Err(KrigingError::ShapeMismatch {
                what: "query parameter length",
                expected: d,
                got: queries.ncols(),
            });
        }
        crate::check_finite("queries", queries)?;
        let mut c = vec![0.0; d];
        let mut gamma = Mat::zeros(n, s + 1);
        for i in 0..n {
            for (k, v) in c.iter_mut().enumerate() {
                *v = queries[(i, k)];
            }
            for j in 0..s {
                gamma[(i, j)] = self.variogram.eval(self.dist_to(&c, j));
            }
            gamma[(i, s)] = 1.0;
        }
        let dual = MatRef::from_row_major_slice(&self.dual, s + 1, dv);
        let mut out = crate::linalg::matmul_par_cols(gamma.as_ref(), dual);
        if let Some(f) = &self.trend {
            let z = Mat::from_fn(n, d + 1, |i, k| {
                if k == d {
                    1.0
                } else {
                    (queries[(i, k)] - self.scaling.offset[k]) * self.scaling.scale[k]
                }
            });
            out += crate::linalg::matmul_par_cols(z.as_ref(), f.transpose());
        }
        for i in 0..n {
            for j in 0..dv {
                if !out[(i, j)].is_finite() {
                    return Err(KrigingError::Overflow {
                        what: format!("the prediction at query row {i}, value column {j}"),
                        reason: format!(
                            "it is {} (the query is too far from the samples)",
                            out[(i, j)]
                        ),
                    });
                }
            }
        }
        Ok(out)
    }

    /// Leave-one-out errors `e_k = x_k - x_hat_{-k}(c_k)` (S x D) without refactorising.
    ///
    /// Ordinary kriging (Dubrule 1983): with `B = A^-1` and `alpha = B[:S, :S] R`,
    /// `e_k = alpha_k / B_kk`; the weights of the system without sample k at `c_k` are
    /// `-B_ki / B_kk`. Regression kriging adds the refit of the trend without sample k:
    /// `e_k = alpha_k / B_kk + (F - F_{-k}) v_k` with `v_k = [c_k; 1] - sum_{i != k} b_i [c_i; 1]`
    /// and `F_{-k} = (X^t C^t - x_k z_k^t) (C C^t - z_k z_k^t)^+`, a (d+1) x (d+1) pseudo-inverse
    /// per sample. The variogram and the scaling stay fixed. Agrees with refitting S times except
    /// at duplicated parameter points (which the refit would treat with `gamma(0) = 0`).
    pub fn loo_errors(&self) -> Result<Mat<f64>, KrigingError> {
        let s = self.n_samples();
        let dv = self.n_values();
        let d = self.n_params();
        let b = self.system.inverse();
        let mut err = Mat::zeros(s, dv);
        for k in 0..s {
            let bkk = b[(k, k)];
            if bkk == 0.0 || !bkk.is_finite() {
                return Err(KrigingError::Singular {
                    what: "leave-one-out",
                    size: s,
                    pivot_ratio: 0.0,
                    residual: f64::NAN,
                });
            }
            let row = &self.dual[k * dv..(k + 1) * dv];
            for j in 0..dv {
                err[(k, j)] = row[j] / bkk;
            }
        }
        if let (Some(f), Some(g), Some(cx)) = (&self.trend, &self.gram, &self.cx) {
            let cm = self.augmented_params(); // (d+1) x S
            let bc = matmul(b.as_ref().submatrix(0, 0, s, s), cm.transpose()); // S x (d+1)
            let mut gk = Mat::zeros(d + 1, d + 1);
            let mut v = vec![0.0; d + 1];
            let mut xk = vec![0.0; dv];
            for k in 0..s {
                let bkk = b[(k, k)];
                // w = sum_{i != k} b_i z_i with b_i = -B_ki / B_kk; v = z_k - w.
                for l in 0..=d {
                    let zk = cm[(l, k)];
                    let w = -(bc[(k, l)] - bkk * zk) / bkk;
                    v[l] = zk - w;
                }
                for q in 0..=d {
                    for p in 0..=d {
                        gk[(p, q)] = g[(p, q)] - cm[(p, k)] * cm[(q, k)];
                    }
                }
                let (gp, _) = sym_pinv(gk.as_ref());
                // gv = (G_{-k})^+ v
                let mut gv = vec![0.0; d + 1];
                for (p, gvp) in gv.iter_mut().enumerate() {
                    *gvp = (0..=d).map(|q| gp[(p, q)] * v[q]).sum();
                }
                let zg: f64 = (0..=d).map(|l| cm[(l, k)] * gv[l]).sum();
                // x_k = r_k + F z_k
                for (j, x) in xk.iter_mut().enumerate() {
                    *x = self.residuals[(k, j)]
                        + (0..=d).map(|l| f[(j, l)] * cm[(l, k)]).sum::<f64>();
                }
                for j in 0..dv {
                    let fv: f64 = (0..=d).map(|l| f[(j, l)] * v[l]).sum();
                    let fkv: f64 = (0..=d).map(|l| cx[(l, j)] * gv[l]).sum::<f64>() - xk[j] * zg;
                    err[(k, j)] += fv - fkv;
                }
            }
        }
        Ok(err)
    }

    /// Leave-one-out cross validation ([`Kriging::loo_errors`] summarised): RMSE over samples of
    /// the Euclidean norm of the error vector, and that norm per sample.
    pub fn leave_one_out(&self) -> Result<LooReport, KrigingError> {
        let e = self.loo_errors()?;
        let per = (0..e.nrows())
            .map(|k| {
                (0..e.ncols())
                    .map(|j| e[(k, j)] * e[(k, j)])
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        Ok(LooReport::from_norms(per))
    }
}

/// Checks the query length, its finiteness and the output length.
pub(crate) fn check_query(
    c: &[f64],
    d: usize,
    out_len: usize,
    expected_out: usize,
) -> Result<(), KrigingError> {
    if c.len() != d {
        return Err(KrigingError::ShapeMismatch {
            what: "query parameter length",
            expected: d,
            got: c.len(),
        });
    }
    if out_len != expected_out {
        return Err(KrigingError::ShapeMismatch {
            what: "output buffer length",
            expected: expected_out,
            got: out_len,
        });
    }
    if let Some(k) = c.iter().position(|x| !x.is_finite()) {
        return Err(KrigingError::NonFinite {
            what: "query parameter",
            row: 0,
            col: k,
        });
    }
    Ok(())
}

/// `Ok` when every entry of a query's result is finite, else [`KrigingError::Overflow`] naming
/// `what` and the first non-finite column (a query so far from the samples that the variogram
/// or the trend overflows).
pub(crate) fn check_result(what: &str, out: &[f64]) -> Result<(), KrigingError> {
    match out.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(j) => Err(KrigingError::Overflow {
            what: format!("{what} at the query (column {j})"),
            reason: format!("it is {} (the query is too far from the samples)", out[j]),
        }),
    }
}

/// `out[j] = gamma(|scale(c) - p_j|)` for `j < out.len()`: the variogram column of a query `c`
/// (unscaled, length `d`) against scaled sample parameters `scaled_params` (row-major, `d` per
/// sample), the right-hand side of the kriging system without its trailing 1. The one evaluation
/// of it offline, shared by [`crate::ProjectedQuery::query`] and the motion baselines' dual form.
/// No allocation.
///
/// # Panics
///
/// When `scaled_params` holds fewer than `out.len()` samples of `c.len()` entries, or `scaling`
/// has fewer than `c.len()` dimensions (a model's own [`Kriging::scaling`] and scaled rows with
/// a query of [`Kriging::n_params`] entries always fit).
///
/// ```
/// use kriging::{ParamScaling, Variogram, VariogramModel, variogram_column};
///
/// let v = Variogram::new(VariogramModel::Linear, 0.0, 2.0, 0.0, 1.0)?; // gamma(h) = 2 h
/// // Parameters scaled by (0.5, 1): the samples (0, 0) and (2, 4) are stored as (0, 0), (1, 4).
/// let scaling = ParamScaling::given(vec![0.0, 0.0], vec![0.5, 1.0])?;
/// let scaled = [0.0, 0.0, 1.0, 4.0];
/// let mut out = [0.0; 2];
/// variogram_column(&v, &scaling, &scaled, &[8.0, 4.0], &mut out); // scaled query (4, 4)
/// assert_eq!(out, [2.0 * 32f64.sqrt(), 6.0]);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
pub fn variogram_column(
    variogram: &Variogram,
    scaling: &ParamScaling,
    scaled_params: &[f64],
    c: &[f64],
    out: &mut [f64],
) {
    assert!(
        out.len()
            .checked_mul(c.len())
            .is_some_and(|n| n <= scaled_params.len())
            && c.len() <= scaling.offset.len().min(scaling.scale.len()),
        "variogram_column: {} outputs of {}-D queries need {} scaled entries and a scaling of {} \
         dimensions, got {} and {}",
        out.len(),
        c.len(),
        out.len().saturating_mul(c.len()),
        c.len(),
        scaled_params.len(),
        scaling.dims()
    );
    for (j, g) in out.iter_mut().enumerate() {
        *g = variogram.eval(scaled_dist(scaling, scaled_params, c, j));
    }
}

/// `|scale(c) - p_j|` with `p` row-major S x d.
#[inline]
pub(crate) fn scaled_dist(scaling: &ParamScaling, rows: &[f64], c: &[f64], j: usize) -> f64 {
    let d = c.len();
    let p = &rows[j * d..(j + 1) * d];
    let mut s = 0.0;
    for k in 0..d {
        let t = (c[k] - scaling.offset[k]) * scaling.scale[k] - p[k];
        s += t * t;
    }
    s.sqrt()
}
