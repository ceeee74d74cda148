//! A source's confidence region: the covariance at the noise used, widened by N / N_eff for
//! correlated residuals, stretched to the far end of the range interval, then held to the
//! likelihood's reach ([`super::super::reach`]); its ellipses and CEP50.

use super::super::bias::{BiasPrior, BiasedFix, MAX_SOURCES};
use super::super::consistency;
use super::super::ellipse::{Ellipse, cep50_of};
use super::super::reach;
use super::{Item, LocateConfig, NoEmitter};
use crate::error::Error;

/// The noise a region is drawn at.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Noise {
    /// The noise scale the fit used (every bearing's sigma times this).
    pub scale: f32,
    /// N / N_eff: the covariance is multiplied by it (correlated residuals).
    pub inflation: f32,
    /// The residual degrees of freedom when the noise was estimated (the ellipse then scales
    /// by 2 F(2, dof)); `None` when the bearings' sigmas hold (chi-square).
    pub dof: Option<f32>,
}

/// A source's confidence region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Region {
    /// The honest position covariance, m^2.
    pub covariance: [[f32; 2]; 2],
    /// The `confidence` ellipse.
    pub ellipse: Ellipse,
    /// The ellipse's scale k: x^T C^-1 x <= k.
    pub scale: f32,
    /// Circular error probable, metres.
    pub cep50: f32,
    /// The ellipse's major axis over the Fisher ellipse's.
    pub stretch: f32,
    /// The bias-aware bound at the fix: sqrt(trace) of the fit's marginal position covariance.
    pub crlb: f32,
}

/// The region of the fit `at_scale` (made at `noise.scale`) of `members`, the stretch measured
/// from `position` (the refined fix). A likelihood region that runs out to the search's range
/// is no fix: [`Error::ParallelBearings`].
pub(super) fn confidence_region(
    members: &[Item],
    priors: &[BiasPrior; MAX_SOURCES],
    at_scale: &BiasedFix,
    position: &[f32; 2],
    noise: Noise,
    config: &LocateConfig,
) -> Result<Region, NoEmitter> {
    let info = at_scale.covariance;
    let crlb = libm::sqrtf(info[0][0] + info[1][1]);
    let tau = noise.inflation;
    let widened = [
        [tau * info[0][0], tau * info[0][1]],
        [tau * info[1][0], tau * info[1][1]],
    ];
    let k =
        consistency::ellipse_scale(config.confidence, noise.dof).map_err(NoEmitter::Geometry)?;
    let stretched = far_side(&widened, position, members, k, config.ransac.max_range);
    // The Fisher ellipse is the likelihood's curvature at the fix; where the range is barely
    // observed the likelihood-ratio region reaches much farther: the ellipse is made to hold
    // it, and a region that runs out to the search's range is no fix.
    let fit = reach::Fit {
        fix: at_scale,
        priors,
        scale: noise.scale,
        inflation: tau,
    };
    let held = reach::reach(members, fit, &stretched, k, config.ransac.max_range)
        .map_err(NoEmitter::Geometry)?;
    if !held.bounded {
        return Err(NoEmitter::Geometry(Error::ParallelBearings));
    }
    let covariance = held.covariance;
    let k50 = consistency::ellipse_scale(0.5, noise.dof).map_err(NoEmitter::Geometry)?;
    let ellipse =
        Ellipse::with_scale(&covariance, k, config.confidence).map_err(NoEmitter::Geometry)?;
    let half = Ellipse::with_scale(&covariance, k50, 0.5).map_err(NoEmitter::Geometry)?;
    Ok(Region {
        covariance,
        ellipse,
        scale: k,
        cep50: cep50_of(&half),
        stretch: held.stretch,
        crlb,
    })
}

/// The covariance stretched along the line of sight so its ellipse reaches the far end of the
/// range interval. Bearings measure inverse range (the angle a baseline subtends) nearly
/// linearly, so the range interval of a distant emitter is [r / (1 + k s), r / (1 - k s)]
/// (s the relative range sd, k the ellipse's sqrt scale), not r (1 +- k s): a fix that fell
/// short of a distant emitter, with its ellipse computed at the short range, would exclude it.
/// The far end is capped at `max_range`. Near emitters (k s small) are barely touched, and an
/// emitter within twice the drive's own spread of its centre (a drive around it) is left alone:
/// its range is no line-of-sight quantity.
fn far_side(
    cov: &[[f32; 2]; 2],
    position: &[f32; 2],
    members: &[Item],
    scale: f32,
    max_range: f32,
) -> [[f32; 2]; 2] {
    let n = members.len().max(1) as f32;
    let mut c = [0.0f32; 2];
    for it in members {
        c[0] += it.obs.bearing.vehicle[0] / n;
        c[1] += it.obs.bearing.vehicle[1] / n;
    }
    let mut spread = 0.0f32;
    for it in members {
        let v = it.obs.bearing.vehicle;
        spread += ((v[0] - c[0]) * (v[0] - c[0]) + (v[1] - c[1]) * (v[1] - c[1])) / n;
    }
    let spread = libm::sqrtf(spread);
    let (dx, dy) = (position[0] - c[0], position[1] - c[1]);
    let r = libm::hypotf(dx, dy);
    if !(r > 2.0 * spread) || !(r > 0.0) {
        return *cov;
    }
    let u = [dx / r, dy / r];
    let var =
        u[0] * (cov[0][0] * u[0] + cov[0][1] * u[1]) + u[1] * (cov[1][0] * u[0] + cov[1][1] * u[1]);
    if !(var > 0.0) {
        return *cov;
    }
    let k = libm::sqrtf(scale);
    let ks = k * libm::sqrtf(var) / r;
    let far = if ks < 1.0 {
        (r * ks / (1.0 - ks)).min(max_range)
    } else {
        max_range
    };
    let wanted = (far / k) * (far / k);
    let extra = (wanted - var).max(0.0);
    let out = [
        [
            cov[0][0] + extra * u[0] * u[0],
            cov[0][1] + extra * u[0] * u[1],
        ],
        [
            cov[1][0] + extra * u[1] * u[0],
            cov[1][1] + extra * u[1] * u[1],
        ],
    ];
    if out.iter().flatten().all(|v| v.is_finite()) {
        out
    } else {
        *cov
    }
}
