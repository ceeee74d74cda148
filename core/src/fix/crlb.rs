//! The Cramér-Rao lower bound of a bearing geometry:
//! J = sum_k [s^2, -s c; -s c, c^2] / (sigma_k^2 d_k^2), rmse >= sqrt(trace J^-1).

use crate::error::Error;
use crate::linalg;
use crate::model::bearing::Bearing;

/// Fisher information of the usable bearings about an emitter at `p`; `None` if none is usable
/// or the emitter sits on a vehicle position.
pub fn information(p: &[f32; 2], bearings: &[Bearing]) -> Option<[[f32; 2]; 2]> {
    let mut j = [[0.0f32; 2]; 2];
    let mut any = false;
    for b in bearings.iter().filter(|b| b.check().is_ok()) {
        let dx = p[0] - b.vehicle[0];
        let dy = p[1] - b.vehicle[1];
        let d2 = dx * dx + dy * dy;
        if !(d2 > 0.0) {
            return None;
        }
        // s = dy/d, c = dx/d: the entries are s^2 / (sigma^2 d^2) = dy^2 / (sigma^2 d^4), etc.
        let k = 1.0 / (b.sigma * b.sigma * d2 * d2);
        j[0][0] += k * dy * dy;
        j[0][1] -= k * dx * dy;
        j[1][1] += k * dx * dx;
        any = true;
    }
    j[1][0] = j[0][1];
    (any && j.iter().flatten().all(|v| v.is_finite())).then_some(j)
}

/// The bound for an emitter at `p` seen by `bearings`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crlb {
    /// The bound on the covariance, J^-1 (m^2).
    pub covariance: [[f32; 2]; 2],
    /// sqrt(trace J^-1): the smallest rmse an unbiased estimator can reach (m).
    pub rmse: f32,
}

/// The CRLB of a geometry. A geometry with no range information (parallel bearings, a
/// stationary vehicle) has no finite bound and is reported as [`Error::DegenerateGeometry`].
pub fn crlb(p: &[f32; 2], bearings: &[Bearing]) -> Result<Crlb, Error> {
    crate::error::check_finite(p)?;
    let j = information(p, bearings).ok_or(Error::DegenerateGeometry)?;
    let covariance = linalg::inverse2(&j).ok_or(Error::DegenerateGeometry)?;
    let trace = covariance[0][0] + covariance[1][1];
    if !(trace > 0.0) || !trace.is_finite() {
        return Err(Error::DegenerateGeometry);
    }
    Ok(Crlb {
        covariance,
        rmse: libm::sqrtf(trace),
    })
}
