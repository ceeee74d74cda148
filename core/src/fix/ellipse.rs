//! Confidence ellipse and CEP50 from a 2x2 position covariance.

use crate::error::Error;
use crate::linalg;

/// An error ellipse: semi-axes and orientation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ellipse {
    /// Semi-major axis, metres.
    pub major: f32,
    /// Semi-minor axis, metres.
    pub minor: f32,
    /// Orientation of the major axis, radians counter-clockwise from east.
    pub orientation: f32,
    /// Probability mass inside, e.g. 0.95.
    pub confidence: f32,
}

impl Ellipse {
    /// The ellipse holding `confidence` of a Gaussian with covariance `cov`: semi-axes
    /// sqrt(-2 ln(1 - p) lambda_i) (sqrt(5.991 lambda) at 95 %).
    pub fn from_covariance(cov: &[[f32; 2]; 2], confidence: f32) -> Result<Self, Error> {
        crate::error::check_finite(&[cov[0][0], cov[0][1], cov[1][0], cov[1][1], confidence])?;
        if !(confidence > 0.0 && confidence < 1.0) {
            return Err(Error::OutOfRange);
        }
        let (l1, l2, orientation) = linalg::eigen2(cov).ok_or(Error::NonFinite)?;
        if l2 < -1e-6 * l1.abs().max(1e-12) {
            return Err(Error::OutOfRange);
        }
        // sqrt(k) sqrt(lambda), not sqrt(k lambda): the product overflows f32 near its range.
        let k = libm::sqrtf(-2.0 * libm::logf(1.0 - confidence));
        let e = Self {
            major: k * libm::sqrtf(l1.max(0.0)),
            minor: k * libm::sqrtf(l2.max(0.0)),
            orientation,
            confidence,
        };
        crate::error::check_finite(&[e.major, e.minor, e.orientation])?;
        Ok(e)
    }

    /// The ellipse x^T C^-1 x <= `scale` of covariance `cov`, labelled with the `confidence`
    /// the caller's distribution gives that scale (2 F(2, dof) when the noise was estimated,
    /// see [`crate::fix::consistency::ellipse_scale`]).
    pub fn with_scale(cov: &[[f32; 2]; 2], scale: f32, confidence: f32) -> Result<Self, Error> {
        crate::error::check_finite(&[scale])?;
        if !(scale > 0.0) {
            return Err(Error::OutOfRange);
        }
        // The 1 - e^{-1/2} ellipse has k = 1: rescale its axes.
        let unit = Self::from_covariance(cov, 1.0 - libm::expf(-0.5))?;
        let k = libm::sqrtf(scale);
        let e = Self {
            major: k * unit.major,
            minor: k * unit.minor,
            orientation: unit.orientation,
            confidence,
        };
        crate::error::check_finite(&[e.major, e.minor])?;
        if !(confidence > 0.0 && confidence < 1.0) {
            return Err(Error::OutOfRange);
        }
        Ok(e)
    }

    /// Whether `point` lies inside the ellipse centred on `centre`.
    pub fn contains(&self, centre: &[f32; 2], point: &[f32; 2]) -> bool {
        let (dx, dy) = (point[0] - centre[0], point[1] - centre[1]);
        let (s, c) = (libm::sinf(self.orientation), libm::cosf(self.orientation));
        let along = c * dx + s * dy;
        let across = -s * dx + c * dy;
        if !(self.major > 0.0 && self.minor > 0.0) {
            return false;
        }
        let a = along / self.major;
        let b = across / self.minor;
        a * a + b * b <= 1.0
    }
}

/// Mahalanobis distance sqrt(d^T C^-1 d) of `point` from `centre` under covariance `cov`;
/// `None` when `cov` is singular.
pub fn mahalanobis(cov: &[[f32; 2]; 2], centre: &[f32; 2], point: &[f32; 2]) -> Option<f32> {
    let inv = linalg::inverse2(cov)?;
    let d = [point[0] - centre[0], point[1] - centre[1]];
    let q =
        d[0] * (inv[0][0] * d[0] + inv[0][1] * d[1]) + d[1] * (inv[1][0] * d[0] + inv[1][1] * d[1]);
    (q >= 0.0 && q.is_finite()).then(|| libm::sqrtf(q))
}

/// CEP50 per unit of s1 + s2, the standard deviations along a Gaussian's two axes: the usual
/// approximation CEP50 ~ 0.59 (s1 + s2), accurate to a few percent while s2 / s1 > 0.2.
pub const CEP50_PER_SD_SUM: f32 = 0.59;

/// Circular error probable (50 %): 0.59 (s1 + s2) of the standard deviations along the axes
/// ([`CEP50_PER_SD_SUM`]).
pub fn cep50(cov: &[[f32; 2]; 2]) -> Result<f32, Error> {
    let e = Ellipse::from_covariance(cov, 0.5)?;
    let k = libm::sqrtf(-2.0 * libm::logf(0.5));
    Ok(CEP50_PER_SD_SUM * (e.major + e.minor) / k)
}

/// CEP50 from a 50 % ellipse whatever scale made it (chi-square, or 2 F(2, dof) when the noise
/// was estimated): the 0.59 (s1 + s2) rule on its axes, each an sd times sqrt(chi2(2; 0.5)),
/// so an F-scaled ellipse gives the F-scaled CEP50.
pub fn cep50_of(half: &Ellipse) -> f32 {
    // chi2(2; 0.5) = 2 ln 2; the fallback is never taken (0.5 is a valid probability).
    let median = crate::stats::chi2_2_quantile(0.5).unwrap_or(core::f32::consts::LN_2 * 2.0);
    CEP50_PER_SD_SUM * (half.major + half.minor) / libm::sqrtf(median)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circular_95() {
        let e = Ellipse::from_covariance(&[[4.0, 0.0], [0.0, 4.0]], 0.95).unwrap();
        assert!((e.major - 2.0 * libm::sqrtf(5.991)).abs() < 1e-2);
        assert!((e.minor - e.major).abs() < 1e-4);
        // CEP50 of a circular Gaussian is 1.1774 sigma; the 0.59 (s1 + s2) rule gives 1.18 sigma.
        let c = cep50(&[[4.0, 0.0], [0.0, 4.0]]).unwrap();
        assert!((c - 2.0 * 1.1774).abs() < 0.01, "{c}");
    }

    #[test]
    fn scaled_ellipses_and_membership() {
        let cov = [[9.0, 0.0], [0.0, 1.0]];
        let e = Ellipse::with_scale(&cov, 5.991, 0.95).unwrap();
        let g = Ellipse::from_covariance(&cov, 0.95).unwrap();
        assert!((e.major - g.major).abs() < 1e-3 && (e.minor - g.minor).abs() < 1e-3);
        assert!(e.contains(&[0.0, 0.0], &[7.0, 0.0]) && !e.contains(&[0.0, 0.0], &[0.0, 2.6]));
        let m = mahalanobis(&cov, &[0.0, 0.0], &[3.0, 1.0]).unwrap();
        assert!((m - libm::sqrtf(2.0)).abs() < 1e-5);
    }

    #[test]
    fn rejects_bad_covariances() {
        assert!(Ellipse::from_covariance(&[[f32::NAN, 0.0], [0.0, 1.0]], 0.95).is_err());
        assert!(Ellipse::from_covariance(&[[1.0, 0.0], [0.0, -1.0]], 0.95).is_err());
        assert!(Ellipse::from_covariance(&[[1.0, 0.0], [0.0, 1.0]], 1.0).is_err());
    }
}
