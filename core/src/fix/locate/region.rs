//! A source's confidence region: the covariance at the noise used, widened by N / N_eff for
//! correlated residuals, stretched to the far end of the range interval, then held to the
//! likelihood's reach ([`super::super::reach`]); its ellipses and CEP50. A likelihood region
//! that runs out to the search's range is no ellipse but a wedge: a line of bearing from the
//! observers, its half-width, and the range interval the region allows ([`Wedge`]).

use super::super::bias::{BiasedFix, StationSlot};
use super::super::consistency;
use super::super::ellipse::{Ellipse, cep50_of};
use super::super::reach;
use super::{Item, LocateConfig, NoEmitter};
use crate::error::Error;
use crate::fix::bias::Sighting;
use crate::fix::device::WIDEST_CEILING;
use crate::model::bearing::wrap;
use crate::stats;

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

/// What the likelihood region came to: an ellipse, or a wedge where the range is open.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Held {
    /// Bounded on every side: a fix's confidence region.
    Bounded(Confidence),
    /// Open in range: the line of bearing and the range interval.
    Open(Wedge),
}

/// Bearings spread by less than this, radians (0.1 degree), are parallel: lines that cross,
/// if at all, hundreds of baselines away.
pub const PARALLEL_SPREAD: f32 = 0.1 * core::f32::consts::PI / 180.0;

/// A region open in range, seen from the observers ([`super::Region`] has the fields' words).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Wedge {
    pub apex: [f32; 2],
    pub theta: f32,
    pub half_width: f32,
    pub min_range: f32,
    pub max_range: Option<f32>,
    pub parallel: bool,
}

/// A source's confidence region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Confidence {
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
/// is no fix but a [`Wedge`].
pub(super) fn confidence_region(
    members: &[Item],
    stations: &mut [StationSlot],
    at_scale: &BiasedFix,
    position: &[f32; 2],
    noise: Noise,
    config: &LocateConfig,
) -> Result<Held, NoEmitter> {
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
        scale: noise.scale,
        inflation: tau,
    };
    let held = reach::reach(
        members,
        stations,
        fit,
        &stretched,
        k,
        config.ransac.max_range,
    )
    .map_err(NoEmitter::Geometry)?;
    if !held.bounded {
        let wedge = wedge(members, stations, fit, &held, k, noise, config.confidence)
            .map_err(NoEmitter::Geometry)?;
        return Ok(Held::Open(wedge));
    }
    let covariance = held.covariance;
    let k50 = consistency::ellipse_scale(0.5, noise.dof).map_err(NoEmitter::Geometry)?;
    let ellipse =
        Ellipse::with_scale(&covariance, k, config.confidence).map_err(NoEmitter::Geometry)?;
    let half = Ellipse::with_scale(&covariance, k50, 0.5).map_err(NoEmitter::Geometry)?;
    Ok(Held::Bounded(Confidence {
        covariance,
        ellipse,
        scale: k,
        cep50: cep50_of(&half),
        stretch: held.stretch,
        crlb,
    }))
}

/// The wedge of a region open in range.
///
/// The apex is the observers' centroid, each bearing weighted by its information (1 /
/// sigma^2): seen from there, the best-fitting direction is the same at every range to first
/// order in the drive's spread over the range (an observer `d` to the side of the centroid sees
/// a point at range r along phi at phi + d / r, and the weighted d sum to zero), so the line of
/// bearing is a straight ray from it. Its direction is the one the region's far slices take.
///
/// The half-width is the direction's at long range, where every station's offset is
/// confounded with the direction ([`direction_half_width`]). It is widened to hold the fix and the
/// region's near end when they lie off the ray
/// beyond the drive's own extent (a drive not small against the range).
///
/// The range interval runs from the likelihood-ratio region's nearest point along the ray
/// ([`reach::nearest`]; the drive's extent when it reaches that close) to its far end, `None`
/// where it ran out.
fn wedge(
    members: &[Item],
    stations: &mut [StationSlot],
    fit: reach::Fit<'_>,
    held: &reach::Reach,
    k: f32,
    noise: Noise,
    confidence: f32,
) -> Result<Wedge, Error> {
    let (apex, spread) = apex_of(members)?;
    let fix = fit.fix.position;
    let at = |q: [f32; 2]| [fix[0] + q[0] - apex[0], fix[1] + q[1] - apex[1]];
    // The far side: the one that ran out (the one farther from the apex if both did).
    let open = |e: Option<reach::End>| e.is_none_or(|e| e.sideways);
    let far_side = match held.ends.map(open) {
        [true, false] => 0,
        [false, true] => 1,
        _ => {
            let r = |q| {
                let p = at(q);
                libm::hypotf(p[0], p[1])
            };
            usize::from(r(held.farthest[1]) > r(held.farthest[0]))
        }
    };
    let heading = at(held.farthest[far_side]);
    let theta = if libm::hypotf(heading[0], heading[1]) > 0.0 {
        libm::atan2f(heading[1], heading[0])
    } else {
        let p = at([0.0; 2]);
        libm::atan2f(p[1], p[0])
    };
    let u = [libm::cosf(theta), libm::sinf(theta)];
    let mut half_width = direction_half_width(
        members,
        stations,
        noise.scale,
        noise.inflation,
        confidence,
        noise.dof,
    )?;
    // The nearest range: searched along the ray inward from the fix's range (the fix when it
    // lies within the drive's extent, or behind the apex: the drive's extent), the half-width
    // widened to hold the fix when it lies off the ray beyond the drive's extent.
    let p = at([0.0; 2]);
    let along = p[0] * u[0] + p[1] * u[1];
    let from = along.max(spread);
    let min_range = reach::nearest(members, stations, fit, held, apex, u, from, spread, k);
    if along > spread {
        half_width = half_width.max(wrap(libm::atan2f(p[1], p[0]) - theta).abs());
    }
    let max_range = held.ends[far_side].filter(|e| !e.sideways).map(|e| {
        let p = at(e.outside);
        libm::hypotf(p[0], p[1]).max(min_range)
    });
    let offset = |it: &Item| {
        stations
            .get(it.station())
            .map_or(0.0, |s| s.correction(it.relative))
    };
    let parallel = is_parallel(members, theta, offset);
    crate::error::check_finite(&[apex[0], apex[1], theta, half_width, min_range])?;
    Ok(Wedge {
        apex,
        theta,
        half_width,
        min_range,
        max_range,
        parallel,
    })
}

/// The observers' centroid, each bearing weighted by its information (1 / sigma^2), and their
/// rms distance from it, metres.
fn apex_of(members: &[Item]) -> Result<([f32; 2], f32), Error> {
    let mut apex = [0.0f32; 2];
    let mut total = 0.0f32;
    for it in members {
        let w = 1.0 / (it.obs.bearing.sigma * it.obs.bearing.sigma);
        apex[0] += w * it.obs.bearing.vehicle[0];
        apex[1] += w * it.obs.bearing.vehicle[1];
        total += w;
    }
    if !(total > 0.0) {
        return Err(Error::TooFewMeasurements);
    }
    apex = [apex[0] / total, apex[1] / total];
    let spread = members
        .iter()
        .map(|it| {
            let v = it.obs.bearing.vehicle;
            let w = 1.0 / (it.obs.bearing.sigma * it.obs.bearing.sigma);
            w * ((v[0] - apex[0]) * (v[0] - apex[0]) + (v[1] - apex[1]) * (v[1] - apex[1]))
        })
        .sum::<f32>()
        / total;
    Ok((apex, libm::sqrtf(spread)))
}

/// The half-width at `confidence` of the direction of a distant emitter, radians (pi: any
/// direction, without information). Each station's bearings give their mean at W = sum 1 /
/// (scale sigma)^2 / inflation, its offset prior (P = 1 / sd^2) in series, 1 / (1 / W + 1 /
/// P) (a calibrated station gives W, one without a prior nothing), the stations summed. The
/// variance splits into the noise's share (1 / sum W, scaled by Student's t with `dof` when
/// the noise was estimated) and the offsets' (known priors: the normal quantile); a t on the
/// whole would count the prior's sd as estimated too.
fn direction_half_width(
    members: &[Item],
    stations: &[StationSlot],
    scale: f32,
    inflation: f32,
    confidence: f32,
    dof: Option<f32>,
) -> Result<f32, Error> {
    let inflation = inflation.max(1.0);
    let (mut precision, mut noise) = (0.0f32, 0.0f32);
    for (s, slot) in stations.iter().enumerate() {
        let w: f32 = members
            .iter()
            .filter(|it| it.station() == s)
            .map(|it| {
                let sd = scale * it.obs.bearing.sigma;
                1.0 / (sd * sd)
            })
            .sum::<f32>()
            / inflation;
        if !(w > 0.0) {
            continue;
        }
        noise += w;
        let sd = slot.prior_in_force().sd;
        precision += if sd == 0.0 {
            w
        } else if sd.is_finite() {
            let p = 1.0 / (sd * sd);
            w * p / (w + p)
        } else {
            0.0
        };
    }
    if !(precision > 0.0 && noise > 0.0) {
        return Ok(core::f32::consts::PI);
    }
    let (total, of_noise) = (1.0 / precision, 1.0 / noise);
    let z = libm::sqrtf(stats::chi2_quantile(confidence, 1.0)?);
    let t = match dof {
        Some(dof) => stats::t_quantile(confidence, dof)?,
        None => z,
    };
    let hw = libm::sqrtf(t * t * of_noise + z * z * (total - of_noise).max(0.0));
    Ok(hw.min(core::f32::consts::PI))
}

/// Whether the bearings, less their stations' offsets (`offset`), spread by no more than
/// [`PARALLEL_SPREAD`] about `theta`.
fn is_parallel(members: &[Item], theta: f32, offset: impl Fn(&Item) -> f32) -> bool {
    let (lo, hi) = members
        .iter()
        .map(|it| wrap(it.obs.bearing.theta - offset(it) - theta))
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    hi - lo <= PARALLEL_SPREAD
}

/// A direction-only region wider than this either side (radians, 30 degrees) tells nothing to
/// drive on: the channel stays "no consistent emitter".
pub const MAX_DIRECTION_HALF_WIDTH: f32 = core::f32::consts::PI / 6.0;

/// A channel whose bearings agree on no point, are too noisy for a fix, or cross too shallowly
/// to fit one, may still agree on a direction: the region of their weighted mean direction
/// (each less its station's prior offset) from their centroid, at any range (`min_range` 0:
/// with no fit there is no likelihood to bound it). Only when the directions are concentrated
/// beyond what luck gives (the Rayleigh test at [`LocateConfig::significance`], the same bar
/// as a fix's), with enough effective bearings to estimate their scatter, a half-width
/// within [`MAX_DIRECTION_HALF_WIDTH`] and a scatter not beyond doubt wider than any device
/// class shows ([`WIDEST_CEILING`], the chi-square test at the same 1 %); `None` otherwise.
/// [`LocateConfig::max_sigma`] is a fix's bar, not a direction's (a crossing counts as noise
/// here), but the half-width shrinks with the count: thousands of bearings from arrays round
/// a room, each looking in, scatter by 97 degrees about their mean direction and still passed
/// Rayleigh's test with a half-width of 6.
///
/// The noise is estimated from that scatter (at least the stated sigmas' under
/// [`super::NoiseModel::Known`]); bearings that do cross count their crossing as noise, which
/// only widens the wedge.
pub(super) fn direction_only(
    set: &[Item],
    stations: &[StationSlot],
    config: &LocateConfig,
) -> Option<(Wedge, DirectionNoise)> {
    let n = set.len();
    if (n as u32) < config.min_bearings.max(2) {
        return None;
    }
    let prior = |it: &Item| {
        stations
            .get(it.station())
            .map_or(0.0, |s| s.prior_in_force().mean)
    };
    let (mut c, mut sn, mut total) = (0.0f32, 0.0f32, 0.0f32);
    let (mut uc, mut us) = (0.0f32, 0.0f32);
    for it in set {
        let d = it.obs.bearing.theta - prior(it);
        let w = 1.0 / (it.obs.bearing.sigma * it.obs.bearing.sigma);
        c += w * libm::cosf(d);
        sn += w * libm::sinf(d);
        total += w;
        uc += libm::cosf(d);
        us += libm::sinf(d);
    }
    if !(total > 0.0) {
        return None;
    }
    // Rayleigh's test, Zar's approximation of its p-value.
    let nf = n as f32;
    let r2 = uc * uc + us * us;
    let p = libm::expf(libm::sqrtf(1.0 + 4.0 * nf + 4.0 * (nf * nf - r2)) - (1.0 + 2.0 * nf));
    if !(p <= config.significance) {
        return None;
    }
    let theta = libm::atan2f(sn, c);
    let residual =
        |it: &Item| wrap(it.obs.bearing.theta - prior(it) - theta) / it.obs.bearing.sigma;
    let tau = consistency::correlation_time(set.iter().map(residual), n as u32);
    let effective = nf / tau;
    let dof = effective - 1.0;
    if !(dof >= 1.0) {
        return None;
    }
    let chi2: f32 = set.iter().map(|it| residual(it) * residual(it)).sum();
    let estimated = libm::sqrtf(chi2 / (nf - 1.0));
    let scale = match config.noise {
        super::NoiseModel::Estimated => estimated,
        super::NoiseModel::Known => estimated.max(1.0),
    };
    let median = super::super::noise::median_sigma(set);
    let sigma = scale * median;
    // The scatter beyond the widest any class shows, beyond doubt (a few bearings' estimate
    // may pass it by luck): no direction is shared.
    let ceiling = config.max_sigma.max(WIDEST_CEILING);
    let at_ceiling = chi2 / tau * (median / ceiling) * (median / ceiling);
    if !stats::chi2_sf(at_ceiling, dof).is_ok_and(|p| p >= config.significance) {
        return None;
    }
    let (apex, _) = apex_of(set).ok()?;
    let half_width =
        direction_half_width(set, stations, scale, tau, config.confidence, Some(dof)).ok()?;
    if !(half_width <= MAX_DIRECTION_HALF_WIDTH) {
        return None;
    }
    let parallel = is_parallel(set, theta, prior);
    crate::error::check_finite(&[apex[0], apex[1], theta, half_width, sigma]).ok()?;
    Some((
        Wedge {
            apex,
            theta,
            half_width,
            min_range: 0.0,
            max_range: None,
            parallel,
        },
        DirectionNoise { sigma, effective },
    ))
}

/// The noise of a [`direction_only`] region.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct DirectionNoise {
    /// The bearing noise used, radians.
    pub sigma: f32,
    /// The bearings' effective number.
    pub effective: f32,
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
