//! Geometric anisotropy: the variogram's range depends on the direction.

use serde::{Deserialize, Serialize};

use crate::error::KrigingError;

/// Geometric anisotropy of the variogram, applied as a linear map of the coordinates before
/// distances are taken: rotate into the frame of the anisotropy ellipse (ellipsoid), then stretch the
/// minor axes by `1 / ratio`. Ranges of the variogram are then the ranges along the major axis, in
/// the coordinates' units.
///
/// 2-D: `angle` is the direction of the major axis in degrees, counter-clockwise from the x axis;
/// `ratio = minor range / major range` in `(0, 1]`. The map is
/// `u = [cos a, sin a; -sin a / r, cos a / r] (x - centre)`.
///
/// 3-D: `angles = [azimuth, dip, roll]` in degrees: the major axis is the x axis rotated by
/// `azimuth` about z (counter-clockwise seen from +z), then tilted by `dip` about the new y axis
/// (positive dip points the major axis down, towards -z), then the frame is rolled by `roll` about
/// the major axis; `ratios = [r1, r2]` are the second and third axes' ranges over the major range.
/// The frame is `R = Rz(azimuth) Ry(dip) Rx(roll)` and `u = diag(1, 1/r1, 1/r2) R^t (x - centre)`.
///
/// ```
/// use kriging::faer::Mat;
/// use kriging::{Anisotropy, Krige, NestedVariogram, VariogramModel};
///
/// // Major axis along y (90 degrees), minor range half the major one.
/// let aniso = Anisotropy::TwoD { angle: 90.0, ratio: 0.5 };
/// let m = aniso.matrix(2)?; // row-major: u = (y, -2x)
/// let expect = [0.0, 1.0, -2.0, 0.0];
/// assert!(m.iter().zip(expect).all(|(a, b)| (a - b).abs() < 1e-15));
///
/// // Kriging with it is isotropic kriging on coordinates with x stretched by 2.
/// let xy = [[0.0, 0.0], [30.0, 0.0], [0.0, 30.0], [30.0, 30.0], [10.0, 20.0], [25.0, 5.0]];
/// let z = [0.3, 1.2, 0.8, 1.9, 1.0, 1.1];
/// let v = NestedVariogram::single(VariogramModel::Exponential, 0.0, 1.0, 50.0)?;
/// let coords = Mat::from_fn(6, 2, |i, k| xy[i][k]);
/// let stretched = Mat::from_fn(6, 2, |i, k| xy[i][k] * [2.0, 1.0][k]);
/// let a = Krige::new().variogram(v.clone()).anisotropy(aniso).fit(coords.as_ref(), &z)?;
/// let b = Krige::new().variogram(v).fit(stretched.as_ref(), &z)?;
/// let (pa, pb) = (a.predict(&[12.0, 14.0])?, b.predict(&[24.0, 14.0])?);
/// assert!((pa.value - pb.value).abs() < 1e-10 && (pa.variance - pb.variance).abs() < 1e-10);
///
/// // A 2-D anisotropy does not fit 3-D coordinates, and ratios lie in (0, 1].
/// assert!(aniso.matrix(3).is_err());
/// assert!(Anisotropy::TwoD { angle: 0.0, ratio: 2.0 }.matrix(2).is_err());
/// # Ok::<(), kriging::KrigingError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub enum Anisotropy {
    /// The same range in every direction.
    #[default]
    Isotropic,
    /// Two dimensions: major-axis direction (degrees) and minor/major range ratio.
    TwoD {
        /// Direction of the major axis, degrees counter-clockwise from +x.
        angle: f64,
        /// Minor range over major range, in `(0, 1]`.
        ratio: f64,
    },
    /// Three dimensions: azimuth, dip, roll (degrees) and two range ratios.
    ThreeD {
        /// `[azimuth, dip, roll]` in degrees.
        angles: [f64; 3],
        /// `[second, third]` axis range over the major range, each in `(0, 1]`.
        ratios: [f64; 2],
    },
}

impl Anisotropy {
    /// The most coordinate dimensions [`Anisotropy::matrix`] accepts (4096: a 128 MiB matrix).
    pub const MAX_DIMS: usize = 1 << 12;

    /// The `d x d` matrix (row-major) that maps centred coordinates to isotropic ones; fails when the
    /// anisotropy does not fit `d` dimensions or a parameter is out of its domain, when `d` is
    /// above [`Anisotropy::MAX_DIMS`] (the identity of [`Anisotropy::Isotropic`] would take `d^2`
    /// entries), and with [`KrigingError::Overflow`] when a ratio is so small (below about
    /// `5.6e-309`) that its reciprocal overflows.
    pub fn matrix(&self, d: usize) -> Result<Vec<f64>, KrigingError> {
        let bad = |m: String| Err(KrigingError::InvalidConfig(format!("anisotropy: {m}")));
        let ok_ratio = |r: f64| r.is_finite() && r > 0.0 && r <= 1.0;
        let m = match *self {
            Anisotropy::Isotropic => {
                if d > Self::MAX_DIMS {
                    return bad(format!(
                        "{d}-D coordinates: at most {} dimensions",
                        Self::MAX_DIMS
                    ));
                }
                let mut m = vec![0.0; d * d];
                for k in 0..d {
                    m[k * d + k] = 1.0;
                }
                m
            }
            Anisotropy::TwoD { angle, ratio } => {
                if d != 2 {
                    return bad(format!("a 2-D anisotropy for {d}-D coordinates"));
                }
                if !angle.is_finite() || !ok_ratio(ratio) {
                    return bad(format!(
                        "angle {angle} must be finite and ratio {ratio} in (0, 1]"
                    ));
                }
                let (s, c) = angle.to_radians().sin_cos();
                vec![c, s, -s / ratio, c / ratio]
            }
            Anisotropy::ThreeD { angles, ratios } => {
                if d != 3 {
                    return bad(format!("a 3-D anisotropy for {d}-D coordinates"));
                }
                if angles.iter().any(|a| !a.is_finite()) || !ratios.iter().all(|&r| ok_ratio(r)) {
                    return bad(format!(
                        "angles {angles:?} must be finite and ratios {ratios:?} in (0, 1]"
                    ));
                }
                let (sa, ca) = angles[0].to_radians().sin_cos();
                let (sd, cd) = angles[1].to_radians().sin_cos();
                let (sr, cr) = angles[2].to_radians().sin_cos();
                let rz = [[ca, -sa, 0.0], [sa, ca, 0.0], [0.0, 0.0, 1.0]];
                let ry = [[cd, 0.0, sd], [0.0, 1.0, 0.0], [-sd, 0.0, cd]];
                let rx = [[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]];
                let mul = |a: [[f64; 3]; 3], b: [[f64; 3]; 3]| {
                    let mut o = [[0.0; 3]; 3];
                    for i in 0..3 {
                        for j in 0..3 {
                            o[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
                        }
                    }
                    o
                };
                let r = mul(mul(rz, ry), rx);
                let stretch = [1.0, 1.0 / ratios[0], 1.0 / ratios[1]];
                // u_i = stretch_i * sum_j R_ji x_j (R^t).
                let mut m = vec![0.0; 9];
                for i in 0..3 {
                    for j in 0..3 {
                        m[i * 3 + j] = stretch[i] * r[j][i];
                    }
                }
                m
            }
        };
        // A subnormal ratio: 1 / ratio is inf (an inf entry, or inf * 0 = NaN).
        if m.iter().any(|v| !v.is_finite()) {
            return Err(KrigingError::Overflow {
                what: format!("anisotropy {self:?}"),
                reason: "the reciprocal of a ratio overflows".into(),
            });
        }
        Ok(m)
    }
}
