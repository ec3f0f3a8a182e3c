//! A worked example on the Meuse data (155 topsoil samples, log zinc): fit a variogram in metres,
//! compare ordinary and universal kriging by leave-one-out, predict a grid with variances.
//!
//! Run: `cargo run --release -p kriging --example meuse` (the data are the test fixture
//! `tests/data/meuse.csv`, GPL-3: see `tests/data/MEUSE_SOURCE.md`).

use kriging::faer::Mat;
use kriging::{Binning, Drift, Krige, MaxLag, VariogramModel};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/meuse.csv");
    let text = std::fs::read_to_string(path)?;
    let rows: Vec<[f64; 3]> = text
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<f64> = l.split(',').map(|v| v.parse().unwrap()).collect();
            [f[0], f[1], f[2]]
        })
        .collect();
    // Raw Dutch RD coordinates (~1.8e5, 3.3e5 m): no centring needed, the crate does it inside.
    let coords = Mat::from_fn(rows.len(), 2, |i, k| rows[i][k]);
    let log_zinc: Vec<f64> = rows.iter().map(|r| r[2].ln()).collect();

    for (name, drift) in [
        ("ordinary", Drift::Constant),
        ("universal, linear drift", Drift::Linear),
    ] {
        // Map defaults: 15 bins up to a third of the bounding-box diagonal, Cressie's weights,
        // best of spherical / exponential / gaussian. Here: spherical only, lags up to 1500 m.
        let model = Krige::new()
            .drift(drift)
            .fit_model(VariogramModel::Spherical)
            .binning(Binning {
                bins: 15,
                max_lag: MaxLag::Distance(1500.0),
            })
            .fit(coords.as_ref(), &log_zinc)?;
        let v = model.variogram();
        let s = &v.structures[0];
        println!(
            "{name}: spherical variogram, nugget {:.4}, partial sill {:.4}, range {:.0} m",
            v.nugget, s.sill, s.range
        );
        let loo = model.leave_one_out()?;
        println!(
            "  leave-one-out: RMSE {:.4}, mean error {:+.4}, mean squared standardised error {:.3}",
            loo.rmse, loo.mean_error, loo.msse
        );
        let xs: Vec<f64> = (0..5).map(|i| 178_600.0 + 650.0 * i as f64).collect();
        let ys: Vec<f64> = (0..3).map(|j| 330_500.0 + 1000.0 * j as f64).collect();
        let p = model.predict_grid(&xs, &ys)?;
        for (j, y) in ys.iter().enumerate() {
            let line: Vec<String> = (0..xs.len())
                .map(|i| {
                    let q = j * xs.len() + i;
                    format!("{:.2}±{:.2}", p.values[q], p.variances[q].sqrt())
                })
                .collect();
            println!("  y = {y:.0}: {}", line.join("  "));
        }
    }
    Ok(())
}
