//! Coordinates on the sphere: latitude/longitude in degrees, chordal and great-circle distances.
//!
//! Kriging on the sphere follows GSTools' `latlon=True`: the points are placed on a sphere of
//! radius `R` ([`latlon_to_xyz`]) and the variogram is a function of the *chordal* (straight-line)
//! distance `c = 2 R sin(alpha / 2)` (`alpha` the central angle), so that every model valid in 3-D
//! stays positive definite on the sphere (Yadrenko's construction). Ranges are then in the units of
//! `R` (kilometres with `R = 6371`). Empirical variograms bin the great-circle distance `R alpha`
//! instead (GSTools' `vario_estimate(latlon=True, geo_scale=R)`, [`crate::EstimateOptions::great_circle`]);
//! the two agree to 1 % up to `alpha` = 0.5 rad (3,200 km on the Earth), since `c / (R alpha) =
//! sin(alpha/2) / (alpha/2)`.

use faer::{Mat, MatRef};

use crate::error::KrigingError;

/// Checks one latitude/longitude pair (degrees): finite, `|lat| <= 90`.
fn check_latlon(row: usize, lat: f64, lon: f64) -> Result<(), KrigingError> {
    if !lat.is_finite() {
        return Err(KrigingError::NonFinite {
            what: "latitude",
            row,
            col: 0,
        });
    }
    if !lon.is_finite() {
        return Err(KrigingError::NonFinite {
            what: "longitude",
            row,
            col: 1,
        });
    }
    if lat.abs() > 90.0 {
        return Err(KrigingError::InvalidConfig(format!(
            "latitude {lat} at row {row} is outside [-90, 90] degrees (are latitude and longitude \
             swapped? the columns are latitude, then longitude)"
        )));
    }
    Ok(())
}

fn check_radius(radius: f64) -> Result<(), KrigingError> {
    if !(radius.is_finite() && radius > 0.0) {
        return Err(KrigingError::InvalidConfig(format!(
            "sphere radius {radius} must be finite and > 0"
        )));
    }
    Ok(())
}

/// Cartesian coordinates (n x 3) of points given by latitude and longitude in degrees (n x 2:
/// column 0 latitude, column 1 longitude) on a sphere of radius `radius`:
/// `(R cos(lat) cos(lon), R cos(lat) sin(lon), R sin(lat))`, as GSTools' `latlon2pos`. Euclidean
/// distances between the rows are chordal distances `2 R sin(alpha / 2)`: kriging, leave-one-out,
/// the fitted variogram and simulation on these coordinates are GSTools' `latlon=True` with
/// `geo_scale = radius` (ranges in the units of `radius`).
///
/// Errors: not two columns, NaN or infinite entries, a latitude outside `[-90, 90]`, a radius that is
/// not finite and positive.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{chord_distance, great_circle_distance, latlon_to_xyz, Krige, NestedVariogram, VariogramModel};
///
/// // Four stations (latitude, longitude) and values; kriging on the Earth (R = 6371 km).
/// let ll = [[48.1, 11.6], [52.5, 13.4], [50.1, 8.7], [53.6, 10.0]];
/// let z = [1.0, 2.0, 1.5, 2.5];
/// let xyz = latlon_to_xyz(Mat::from_fn(4, 2, |i, k| ll[i][k]).as_ref(), 6371.0)?;
/// let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 900.0)?; // range in km
/// let model = Krige::new().variogram(v).fit(xyz.as_ref(), &z)?;
/// let q = latlon_to_xyz(Mat::from_fn(1, 2, |_, k| [51.0, 10.0][k]).as_ref(), 6371.0)?;
/// let p = model.predict(&[q[(0, 0)], q[(0, 1)], q[(0, 2)]])?;
/// assert!(p.value > 1.0 && p.value < 2.5);
/// // Munich - Berlin: 505.6 km along the great circle, 0.13 km less along the chord.
/// let (arc, chord) = (great_circle_distance(ll[0], ll[1], 6371.0), chord_distance(ll[0], ll[1], 6371.0));
/// assert!((arc - 505.64).abs() < 0.01 && chord < arc && arc - chord < 0.2);
/// let (dx, dy, dz) = (xyz[(0, 0)] - xyz[(1, 0)], xyz[(0, 1)] - xyz[(1, 1)], xyz[(0, 2)] - xyz[(1, 2)]);
/// assert!(((dx * dx + dy * dy + dz * dz).sqrt() - chord).abs() < 1e-9);
/// # Ok::<(), kriging::KrigingError>(())
/// ```
pub fn latlon_to_xyz(latlon: MatRef<'_, f64>, radius: f64) -> Result<Mat<f64>, KrigingError> {
    if latlon.ncols() != 2 {
        return Err(KrigingError::ShapeMismatch {
            what: "latitude/longitude columns",
            expected: 2,
            got: latlon.ncols(),
        });
    }
    check_radius(radius)?;
    for i in 0..latlon.nrows() {
        check_latlon(i, latlon[(i, 0)], latlon[(i, 1)])?;
    }
    Ok(Mat::from_fn(latlon.nrows(), 3, |i, k| {
        let (lat, lon) = (latlon[(i, 0)].to_radians(), latlon[(i, 1)].to_radians());
        match k {
            0 => radius * lat.cos() * lon.cos(),
            1 => radius * lat.cos() * lon.sin(),
            _ => radius * lat.sin(),
        }
    }))
}

/// The central angle `alpha` (radians) between two `[latitude, longitude]` points in degrees, by
/// the haversine formula as GSTools computes it: `a = sin^2(dlat/2) + cos(lat1) cos(lat2)
/// sin^2(dlon/2)`, `alpha = 2 atan2(sqrt(a), sqrt(1 - a))`.
pub(crate) fn central_angle(p: [f64; 2], q: [f64; 2]) -> f64 {
    let d = std::f64::consts::PI / 180.0;
    let dlat = (q[0] - p[0]) * d;
    let dlon = (q[1] - p[1]) * d;
    let a = (dlat / 2.0).sin().powi(2)
        + (p[0] * d).cos() * (q[0] * d).cos() * (dlon / 2.0).sin().powi(2);
    2.0 * a.sqrt().atan2((1.0 - a).sqrt())
}

/// Great-circle distance `R alpha` between two `[latitude, longitude]` points in degrees on a
/// sphere of radius `radius` (haversine formula, see the [module docs](self)); NaN for non-finite
/// input.
pub fn great_circle_distance(p: [f64; 2], q: [f64; 2], radius: f64) -> f64 {
    radius * central_angle(p, q)
}

/// Chordal distance `2 R sin(alpha / 2)` between two `[latitude, longitude]` points in degrees on
/// a sphere of radius `radius`: the distance kriging on [`latlon_to_xyz`] coordinates uses.
pub fn chord_distance(p: [f64; 2], q: [f64; 2], radius: f64) -> f64 {
    2.0 * radius * (0.5 * central_angle(p, q)).sin()
}

/// Validates latitude/longitude coordinates for [`crate::EmpiricalVariogram::estimate`].
pub(crate) fn check_latlon_coords(
    coords: MatRef<'_, f64>,
    radius: f64,
) -> Result<(), KrigingError> {
    if coords.ncols() != 2 {
        return Err(KrigingError::ShapeMismatch {
            what: "latitude/longitude columns",
            expected: 2,
            got: coords.ncols(),
        });
    }
    check_radius(radius)?;
    for i in 0..coords.nrows() {
        check_latlon(i, coords[(i, 0)], coords[(i, 1)])?;
    }
    Ok(())
}
