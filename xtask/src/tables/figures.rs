//! SVG plots of Figures 4 and 5 (plotters, SVG backend).

use std::path::Path;

use anyhow::{Result, anyhow};
use plotters::prelude::*;

use super::timing::{DistancePoint, Figure4, LevelPoint};

/// One named series of `(x, y)` points.
struct Series<'a> {
    name: &'a str,
    color: RGBColor,
    points: Vec<(f64, f64)>,
}

/// Colours of the three schemes (truncation, ALS, hybrid) and of single series.
const COLORS: [RGBColor; 3] = [
    RGBColor(214, 39, 40),
    RGBColor(31, 119, 180),
    RGBColor(44, 160, 44),
];

/// An axis tick label: the value rounded to 3 decimals, without trailing zeros (`0.3`, `2`, `0.125`).
fn tick(v: f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    format!("{}", r + 0.0)
}

fn err(e: impl std::fmt::Debug) -> anyhow::Error {
    anyhow!("plotting: {e:?}")
}

/// Range `[lo, hi]` of the y values with a 5 % margin (`log`: a factor instead, lo > 0).
fn y_range(series: &[Series<'_>], log: bool) -> (f64, f64) {
    let ys = series.iter().flat_map(|s| s.points.iter().map(|p| p.1));
    let (mut lo, mut hi) = ys
        .filter(|y| y.is_finite() && (!log || *y > 0.0))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
            (a.min(y), b.max(y))
        });
    if !lo.is_finite() {
        return if log { (0.1, 1.0) } else { (0.0, 1.0) };
    }
    if log {
        lo /= 1.3;
        hi *= 1.3;
    } else {
        let m = 0.05 * (hi - lo).max(1e-9);
        lo = (lo - m).min(0.0);
        hi += m;
    }
    (lo, hi)
}

/// Draws `series` into `area` with a caption and axis labels; `log` makes the y axis logarithmic.
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series<'_>],
    log: bool,
) -> Result<()> {
    let xs = series.iter().flat_map(|s| s.points.iter().map(|p| p.0));
    let (x0, x1) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let (x0, x1) = if x0.is_finite() && x1 > x0 {
        (x0, x1)
    } else {
        (0.0, 1.0)
    };
    let (y0, y1) = y_range(series, log);
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(caption, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60);
    macro_rules! draw {
        ($chart:expr) => {{
            let mut chart = $chart;
            chart
                .configure_mesh()
                .x_desc(x_label)
                .y_desc(y_label)
                .x_label_formatter(&|v: &f64| tick(*v))
                .y_label_formatter(&|v: &f64| tick(*v))
                .light_line_style(WHITE.mix(0.0))
                .draw()
                .map_err(err)?;
            for s in series {
                let style = ShapeStyle::from(&s.color).stroke_width(2);
                let pts: Vec<(f64, f64)> = s
                    .points
                    .iter()
                    .copied()
                    .filter(|p| p.1.is_finite() && (!log || p.1 > 0.0))
                    .collect();
                chart
                    .draw_series(LineSeries::new(pts.clone(), style))
                    .map_err(err)?
                    .label(s.name)
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
                chart
                    .draw_series(pts.iter().map(|&p| Circle::new(p, 3, s.color.filled())))
                    .map_err(err)?;
            }
            if series.len() > 1 {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()
                    .map_err(err)?;
            }
        }};
    }
    if log {
        draw!(
            builder
                .build_cartesian_2d(x0..x1, (y0..y1).log_scale())
                .map_err(err)?
        );
    } else {
        draw!(builder.build_cartesian_2d(x0..x1, y0..y1).map_err(err)?);
    }
    Ok(())
}

fn level_series<'a>(
    name: &'a str,
    color: RGBColor,
    pts: &[LevelPoint],
    y: impl Fn(&LevelPoint) -> f64,
) -> Series<'a> {
    Series {
        name,
        color,
        points: pts.iter().map(|p| (p.level as f64, y(p))).collect(),
    }
}

/// Figure 4: time per pose (µs, log scale) and mean joint error (cm) per accuracy level for online
/// truncation, ALS at every level and the hybrid scheme.
pub fn figure4(path: &Path, fig: &Figure4, data: &str) -> Result<()> {
    let root = SVGBackend::new(path, (1200, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (left, right) = root.split_horizontally(600);
    let schemes = [
        ("online truncation", &fig.truncation),
        ("ALS at every level", &fig.als),
        ("hybrid (key levels)", &fig.hybrid),
    ];
    let time: Vec<Series<'_>> = schemes
        .iter()
        .zip(COLORS)
        .map(|((n, p), c)| level_series(n, c, p, |q| q.timed.per_pose_ns() / 1e3))
        .collect();
    let error: Vec<Series<'_>> = schemes
        .iter()
        .zip(COLORS)
        .map(|((n, p), c)| level_series(n, c, p, |q| q.error_cm))
        .collect();
    panel(
        &left,
        &format!("Time per pose ({data})"),
        "accuracy level",
        "µs per pose (kernel / T + pose)",
        &time,
        true,
    )?;
    panel(
        &right,
        "Mean joint position error vs data",
        "accuracy level",
        "cm",
        &error,
        false,
    )?;
    root.present().map_err(err)?;
    Ok(())
}

/// Figure 5: key tensor size ratio, time per pose (µs) and mean joint error (cm) against the distance
/// from the camera under the distance policy.
pub fn figure5(path: &Path, pts: &[DistancePoint], data: &str) -> Result<()> {
    let root = SVGBackend::new(path, (1500, 450)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let areas = root.split_evenly((1, 3));
    let one = |name, color, y: &dyn Fn(&DistancePoint) -> f64| {
        vec![Series {
            name,
            color,
            points: pts
                .iter()
                .map(|p| (f64::from(p.distance_m), y(p)))
                .collect(),
        }]
    };
    panel(
        &areas[0],
        &format!("(a) Key tensor size / maximum ({data})"),
        "distance from camera (m)",
        "r_P r_T r_S / (R_P R_T R_S)",
        &one("size ratio", COLORS[1], &|p| p.size_ratio),
        false,
    )?;
    panel(
        &areas[1],
        "(b) Time per pose",
        "distance from camera (m)",
        "µs per pose (kernel / T + pose)",
        &one("time", COLORS[2], &|p| p.timed.per_pose_ns() / 1e3),
        true,
    )?;
    panel(
        &areas[2],
        "(c) Mean joint position error",
        "distance from camera (m)",
        "cm",
        &one("error", COLORS[0], &|p| p.error_cm),
        false,
    )?;
    root.present().map_err(err)?;
    Ok(())
}

/// Section 7's figure: pop and skate as ratios to the data's takes of similar step length, worst and median over the grid
/// walks per accuracy level (left), and at level 0 per walk against its step length (right).
pub fn quality_figure(
    path: &Path,
    rows: &[super::quality::LevelRow],
    level0: &[(f64, f64, f64)],
    data: &str,
) -> Result<()> {
    let root = SVGBackend::new(path, (1200, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (left, right) = root.split_horizontally(600);
    let by_level = |name, color, y: &dyn Fn(&super::quality::LevelRow) -> f64| Series {
        name,
        color,
        points: rows.iter().map(|r| (r.0 as f64, y(r))).collect(),
    };
    panel(
        &left,
        &format!("Pop and skate per level ({data})"),
        "accuracy level",
        "ratio to the data at that step",
        &[
            by_level("pop, worst walk", COLORS[0], &|r| r.1),
            by_level("skate, worst walk", COLORS[1], &|r| r.3),
            by_level("pop, median walk", COLORS[2], &|r| r.2),
        ],
        false,
    )?;
    let mut sorted = level0.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    panel(
        &right,
        "Level 0: pop and skate against the walk's step",
        "step per cycle, |(dx, dz)| (m)",
        "ratio to the data at that step",
        &[
            Series {
                name: "pop",
                color: COLORS[0],
                points: sorted.iter().map(|p| (p.0, p.1)).collect(),
            },
            Series {
                name: "skate",
                color: COLORS[1],
                points: sorted.iter().map(|p| (p.0, p.2)).collect(),
            },
        ],
        false,
    )?;
    root.present().map_err(err)?;
    Ok(())
}

/// `cargo xtask scaling`'s curve: the build's wall time (s, log scale) and peak memory (GB) against
/// the cycles, one line per thread count. `points` are `(cycles, threads, build s, peak GB)` of the
/// builds that finished.
pub fn scaling_figure(path: &Path, points: &[(usize, usize, f64, f64)], data: &str) -> Result<()> {
    let root = SVGBackend::new(path, (1200, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (left, right) = root.split_horizontally(600);
    let mut threads: Vec<usize> = points.iter().map(|p| p.1).collect();
    threads.sort_unstable();
    threads.dedup();
    let names: Vec<String> = threads
        .iter()
        .map(|t| format!("{t} thread{}", if *t == 1 { "" } else { "s" }))
        .collect();
    let series = |y: fn(&(usize, usize, f64, f64)) -> f64| -> Vec<Series<'_>> {
        threads
            .iter()
            .zip(&names)
            .enumerate()
            .map(|(k, (&t, name))| Series {
                name,
                color: COLORS[k % COLORS.len()],
                points: points
                    .iter()
                    .filter(|p| p.1 == t)
                    .map(|p| (p.0 as f64, y(p)))
                    .collect(),
            })
            .collect()
    };
    panel(
        &left,
        &format!("Build time ({data})"),
        "cycles",
        "s (log scale)",
        &series(|p| p.2),
        true,
    )?;
    panel(
        &right,
        "Peak resident memory",
        "cycles",
        "GB",
        &series(|p| p.3),
        false,
    )?;
    root.present().map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_short() {
        assert_eq!(tick(0.30000000000000004), "0.3");
        assert_eq!(tick(2.0), "2");
        assert_eq!(tick(-0.0), "0");
        assert_eq!(tick(0.1254), "0.125");
    }
}
