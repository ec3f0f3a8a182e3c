//! Kriging weights from the command line, for use from other tools.
//!
//! ```text
//! cargo run --release -p kriging --example krige -- PARAMS.csv VALUES.npy \
//!     [--method regression|ordinary|rbf] \
//!     [--model auto|linear|power|spherical|exponential|gaussian|matern|cardinal-sine] \
//!     [--query QUERY.csv]
//! ```
//! PARAMS.csv: one row of comma-separated numbers per sample (an optional non-numeric header line
//! and `#` comments are skipped). VALUES.npy: an NPY array whose first axis is the sample (the other
//! axes are flattened). Prints one JSON line
//! `{"method":..,"model":..,"loo_rmse":X,"weights":[[..],..]}` with the leave-one-out RMSE over the
//! samples and, for each query row, the weights b(c). `auto` chooses the variogram model with the
//! smallest leave-one-out error; the others fix it ([`kriging::VariogramModel::from_name`]: `matern`
//! and `cardinal-sine` are shapes `auto` does not try; `hole-effect` and `wave`, older names of
//! `cardinal-sine`, are read as it). For `rbf` the model is the radial function (cubic).
//!
//! `regression` (the default) is the regression kriging of Mukai and Kuriyama's motion model
//! ([`kriging::Method::Regression`]: an ordinary least-squares trend over the parameters, then
//! ordinary kriging of its residuals), which the paper calls universal kriging; it is not textbook
//! universal kriging (the drift inside the kriging system: [`kriging::Krige`] with a
//! [`kriging::Drift`]). The old option value `universal` is still read as `regression` (with a note
//! on stderr), and the JSON line then says `"method":"regression"`.

use std::path::Path;
use std::process::ExitCode;

use faer::Mat;
use kriging::{
    Kriging, KrigingConfig, Method, ModelChoice, Rbf, RbfConfig, Selection, VariogramModel,
};

type Error = Box<dyn std::error::Error>;

const USAGE: &str = "usage: krige PARAMS.csv VALUES.npy [--method regression|ordinary|rbf] \
[--model auto|linear|power|spherical|exponential|gaussian|matern|cardinal-sine] [--query QUERY.csv]";

/// Reads rows of numbers; the first line may be a header.
fn read_csv(path: &Path) -> Result<Vec<Vec<f64>>, Error> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let parsed: Result<Vec<f64>, _> =
            line.split(',').map(|f| f.trim().parse::<f64>()).collect();
        match parsed {
            Ok(r) => {
                if let Some(first) = rows.first() {
                    if first.len() != r.len() {
                        return Err(format!(
                            "{}:{}: {} columns, the first row has {}",
                            path.display(),
                            n + 1,
                            r.len(),
                            first.len()
                        )
                        .into());
                    }
                }
                rows.push(r);
            }
            Err(_) if rows.is_empty() && n == 0 => continue, // header
            Err(e) => return Err(format!("{}:{}: {e}", path.display(), n + 1).into()),
        }
    }
    if rows.is_empty() {
        return Err(format!("{}: no rows of numbers", path.display()).into());
    }
    Ok(rows)
}

/// Reads an NPY array as S x D (first axis = samples, the rest flattened in C order).
fn read_values(path: &Path) -> Result<Mat<f64>, Error> {
    let arr = tensor_ops::npy::read_npy(path)?;
    let Some(&s) = arr.shape.first() else {
        return Err(format!("{}: a 0-d array has no sample axis", path.display()).into());
    };
    let d: usize = arr.shape[1..].iter().product();
    let c = arr.to_order(false);
    Ok(Mat::from_fn(s, d, |i, j| c.data[i * d + j]))
}

struct Args {
    params: String,
    values: String,
    method: String,
    model: String,
    query: Option<String>,
}

fn parse_args() -> Result<Args, Error> {
    let mut it = std::env::args().skip(1);
    let mut pos = Vec::new();
    let (mut method, mut model, mut query) = ("regression".to_string(), "auto".to_string(), None);
    while let Some(a) = it.next() {
        let mut value = || {
            it.next()
                .ok_or_else(|| format!("{a} needs a value\n{USAGE}"))
        };
        match a.as_str() {
            "--method" => {
                method = value()?;
                if method == "universal" {
                    eprintln!(
                        "krige: --method universal is the old name of --method regression \
                         (regression kriging: OLS trend plus ordinary kriging of the residuals)"
                    );
                    method = "regression".to_string();
                }
            }
            "--model" => model = value()?,
            "--query" => query = Some(value()?),
            "-h" | "--help" => return Err(USAGE.into()),
            s if s.starts_with("--") => return Err(format!("unknown option {s}\n{USAGE}").into()),
            _ => pos.push(a),
        }
    }
    if pos.len() != 2 {
        return Err(USAGE.into());
    }
    Ok(Args {
        values: pos.pop().unwrap_or_default(),
        params: pos.pop().unwrap_or_default(),
        method,
        model,
        query,
    })
}

fn run() -> Result<String, Error> {
    let args = parse_args()?;
    let rows = read_csv(Path::new(&args.params))?;
    let params = Mat::from_fn(rows.len(), rows[0].len(), |i, k| rows[i][k]);
    let values = read_values(Path::new(&args.values))?;
    let queries = match &args.query {
        Some(q) => read_csv(Path::new(q))?,
        None => Vec::new(),
    };
    let s = params.nrows();
    let mut weights = Vec::with_capacity(queries.len());
    let (model_name, loo) = if args.method == "rbf" {
        let r = Rbf::fit(params.as_ref(), values.as_ref(), &RbfConfig::default())?;
        for q in &queries {
            let mut b = vec![0.0; s];
            r.weights(q, &mut b)?;
            weights.push(b);
        }
        (r.kernel().name().to_string(), r.leave_one_out()?.rmse)
    } else {
        let method = match args.method.as_str() {
            "regression" => Method::Regression,
            "ordinary" => Method::Ordinary,
            m => return Err(format!("unknown method {m}\n{USAGE}").into()),
        };
        let model = if args.model == "auto" {
            ModelChoice::Auto(Selection::BestLoo)
        } else {
            ModelChoice::Fixed(
                VariogramModel::from_name(&args.model)
                    .ok_or_else(|| format!("unknown model {}\n{USAGE}", args.model))?,
            )
        };
        let config = KrigingConfig {
            method,
            model,
            ..KrigingConfig::default()
        };
        let k = Kriging::fit(params.as_ref(), values.as_ref(), &config)?;
        for q in &queries {
            let mut b = vec![0.0; s];
            k.weights(q, &mut b)?;
            weights.push(b);
        }
        (
            k.variogram().model.name().to_string(),
            k.leave_one_out()?.rmse,
        )
    };
    // Keys in the documented order (serde_json's map would sort them).
    Ok(format!(
        "{{\"method\":{},\"model\":{},\"loo_rmse\":{},\"weights\":{}}}",
        serde_json::to_string(&args.method)?,
        serde_json::to_string(&model_name)?,
        serde_json::to_string(&loo)?,
        serde_json::to_string(&weights)?
    ))
}

fn main() -> ExitCode {
    match run() {
        Ok(line) => {
            println!("{line}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("krige: {e}");
            ExitCode::FAILURE
        }
    }
}
