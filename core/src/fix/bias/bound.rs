//! The bias-aware bound: the Fisher information about [x, y, b] and the position block of its
//! inverse.

use super::super::{geometry, usable};
use super::BiasPrior;
use crate::error::{Error, check_finite};
use crate::linalg::inverse_scaled;
use crate::model::bearing::Bearing;

/// Fisher information about [x, y, b] of one unit's bearings at emitter `p`, the prior's
/// information on b included (infinite for a calibrated unit: then b is dropped and the
/// position block is the plain 2 x 2 information with a 1 in the corner).
pub fn information(p: &[f32; 2], bearings: &[Bearing], prior: BiasPrior) -> Option<[[f32; 3]; 3]> {
    let mut j = [[0.0f32; 3]; 3];
    let mut any = false;
    for b in usable(bearings) {
        let dx = p[0] - b.vehicle[0];
        let dy = p[1] - b.vehicle[1];
        let d2 = dx * dx + dy * dy;
        if !(d2 > 0.0) {
            return None;
        }
        let k = 1.0 / (b.sigma * b.sigma);
        let jac = [-dy / d2, dx / d2, 1.0];
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += k * jac[r] * jac[c];
            }
        }
        any = true;
    }
    if !prior.is_free() {
        j[0][2] = 0.0;
        j[1][2] = 0.0;
        j[2][0] = 0.0;
        j[2][1] = 0.0;
        j[2][2] = 1.0;
    } else {
        j[2][2] += prior.information();
    }
    (any && j.iter().flatten().all(|v| v.is_finite())).then_some(j)
}

/// The bias-aware bound for an emitter at `p`: the marginal position block of the inverse
/// 3 x 3 information (with the prior), and the bound on the offset's sd.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasedCrlb {
    /// Position covariance bound, m^2.
    pub covariance: [[f32; 2]; 2],
    /// sqrt(trace) of it, metres: the smallest position rmse once the offset is unknown.
    pub rmse: f32,
    /// Bound on the offset's sd, radians (0 for a calibrated unit).
    pub bias_sd: f32,
}

/// The bias-aware CRLB (Bayesian where the prior is proper). With a calibrated unit it is the
/// plain CRLB; on a drive that surrounds the emitter it is close to it; on a straight road
/// the prior's sd times the range dominates it.
pub fn crlb(p: &[f32; 2], bearings: &[Bearing], prior: BiasPrior) -> Result<BiasedCrlb, Error> {
    check_finite(p)?;
    prior.check()?;
    // Centred: the information is translation-invariant, the f32 sums are not.
    let geo = geometry(bearings)?;
    let o = geo.origin;
    let centred = [p[0] - o[0], p[1] - o[1]];
    let mut j = [[0.0f32; 3]; 3];
    for b in usable(bearings) {
        let (dx, dy) = (
            centred[0] - (b.vehicle[0] - o[0]),
            centred[1] - (b.vehicle[1] - o[1]),
        );
        let d2 = dx * dx + dy * dy;
        if !(d2 > 0.0) {
            return Err(Error::DegenerateGeometry);
        }
        let k = 1.0 / (b.sigma * b.sigma);
        let jac = [-dy / d2, dx / d2, 1.0];
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += k * jac[r] * jac[c];
            }
        }
    }
    let (covariance, bias_sd) = if prior.is_free() {
        j[2][2] += prior.information();
        let c = inverse_scaled(&j).ok_or(Error::DegenerateGeometry)?;
        (
            [[c[0][0], c[0][1]], [c[1][0], c[1][1]]],
            libm::sqrtf(c[2][2].max(0.0)),
        )
    } else {
        let m = [[j[0][0], j[0][1]], [j[1][0], j[1][1]]];
        (inverse_scaled(&m).ok_or(Error::DegenerateGeometry)?, 0.0)
    };
    let trace = covariance[0][0] + covariance[1][1];
    if !(trace > 0.0) || !trace.is_finite() {
        return Err(Error::DegenerateGeometry);
    }
    Ok(BiasedCrlb {
        covariance,
        rmse: libm::sqrtf(trace),
        bias_sd,
    })
}
