//! The refinement of a consensus: Tukey's biweight, then trimmed Gaussian ML with the noise
//! scale re-estimated, until the kept set settles.

use super::super::bias::{
    self, BiasedFix, BiasedOptions, Sighting, Start, StartOffsets, StationSlot,
};
use super::super::noise::median_sigma;
use super::{Consensus, MAX_TRIM_ROUNDS, TRIM_ALPHA, TRIM_CUT};
use crate::error::{Error, check_finite};
use crate::likelihood::Tukey;
use crate::model::bearing::{predicted, wrap};
use crate::stats;
use core::f32::consts::PI;

/// The cut in scaled sigmas for `n` bearings with `dof` residual degrees of freedom.
pub fn trim_cut(n: u32, dof: f32) -> f32 {
    if !(dof > 0.0) || n == 0 {
        return f32::INFINITY;
    }
    let p = 1.0 - TRIM_ALPHA / n as f32;
    stats::t_quantile(p, dof)
        .map(|t| t.max(TRIM_CUT))
        .unwrap_or(TRIM_CUT)
}

/// Share of a Gaussian's variance inside +-c: 1 - 2 c phi(c) / (2 Phi(c) - 1). Corrects the
/// scale estimated from bearings trimmed at c.
fn kept_variance(c: f32) -> f32 {
    if !c.is_finite() {
        return 1.0;
    }
    let inside = libm::erff(c / core::f32::consts::SQRT_2);
    let density = libm::expf(-0.5 * c * c) / libm::sqrtf(2.0 * PI);
    if inside > 0.0 {
        (1.0 - 2.0 * c * density / inside).clamp(0.05, 1.0)
    } else {
        1.0
    }
}

/// A refined robust fix and the bearings it rests on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobustFix {
    /// Gaussian ML on the kept bearings, covariance at `scale`.
    pub fix: BiasedFix,
    /// The noise scale: every bearing's sigma times this is the residuals' sd (1 when the
    /// scale was not estimated).
    pub scale: f32,
    /// Bearings kept (the first `kept` of the scratch buffer, in input order).
    pub kept: u32,
    /// Trimming rounds run.
    pub rounds: u32,
}

/// Settings of the refinement.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefineOptions {
    /// Estimate the noise scale from the residuals (otherwise the bearings' sigmas hold).
    pub estimate_scale: bool,
    /// Solver settings of each ML fit.
    pub solver: BiasedOptions,
}

impl Default for RefineOptions {
    fn default() -> Self {
        Self {
            estimate_scale: true,
            solver: BiasedOptions::default(),
        }
    }
}

/// The residual of a sighting at a fix, its station's offset and direction-dependent error
/// (the table's) removed.
fn residual_at<T: Sighting>(t: &T, fix: &BiasedFix, stations: &[StationSlot]) -> Option<f32> {
    let b = t.bearing();
    let bias = stations.get(t.station())?.correction(t.relative());
    b.check().ok()?;
    Some(wrap(b.theta - predicted(&fix.position, &b.vehicle) - bias))
}

/// Refine a consensus on `items`: Tukey from the hypothesis, then trimmed Gaussian ML. The kept
/// bearings are copied, in order, to the front of `scratch` (at least `items.len()` long); the
/// stations' offsets are the table's (`stations`, one row per station index, with its prior).
pub fn refine<T: Sighting + Copy>(
    items: &[T],
    scratch: &mut [T],
    stations: &mut [StationSlot],
    consensus: &Consensus,
    options: RefineOptions,
) -> Result<RobustFix, Error> {
    if scratch.len() < items.len() {
        return Err(Error::OutOfRange);
    }
    let median = median_sigma(items);
    if !(median > 0.0) {
        return Err(Error::TooFewMeasurements);
    }
    // The hypothesis' threshold in sigmas sets the first scale: a floor-dominated threshold
    // (precise bearings) starts Tukey wider than the sigmas say.
    let mut scale = if options.estimate_scale {
        (consensus.threshold / (TRIM_CUT * median)).max(1.0)
    } else {
        1.0
    };
    let start = Start {
        position: consensus.position,
        offsets: StartOffsets::Common(consensus.bias),
    };
    let tukey = bias::ml_sources(
        items,
        stations,
        start,
        &Tukey::default(),
        BiasedOptions {
            scale,
            ..options.solver
        },
    )?;
    let mut fix = tukey;
    let mut kept_before = u32::MAX;
    let mut rounds = 0;
    // The first round keeps what Tukey gave weight to (|u| < c); later ones cut at the
    // Student-t quantile of the last round's degrees of freedom.
    let mut cut = Tukey::default().c;
    while rounds < MAX_TRIM_ROUNDS {
        rounds += 1;
        let mut kept = 0usize;
        for t in items {
            if let Some(r) = residual_at(t, &fix, stations)
                && libm::fabsf(r) <= cut * scale * t.bearing().sigma
                && let Some(slot) = scratch.get_mut(kept)
            {
                *slot = *t;
                kept += 1;
            }
        }
        if kept < 3 {
            return Err(Error::TooFewMeasurements);
        }
        let set = scratch.get(..kept).ok_or(Error::OutOfRange)?;
        let next = bias::refit(set, stations, &fix, scale, options.solver)?;
        let mut settled = kept as u32 == kept_before;
        let dof = kept as f32 - next.parameters;
        if options.estimate_scale && dof > 0.0 {
            // chi2 is at the current scale: sum (r / sigma)^2 = chi2 scale^2, from bearings
            // cut at `cut` scale sigmas.
            let s2 = next.chi2 * scale * scale / dof / kept_variance(cut);
            let s = libm::sqrtf(s2);
            if s.is_finite() && s > 0.0 {
                settled &= libm::fabsf(s / scale - 1.0) < 0.01;
                scale = s;
            }
        }
        cut = trim_cut(kept as u32, dof);
        fix = next;
        kept_before = kept as u32;
        if settled {
            break;
        }
    }
    // The covariance and chi-square at the final scale.
    let set = scratch
        .get(..kept_before as usize)
        .ok_or(Error::OutOfRange)?;
    let fix = bias::refit(set, stations, &fix, scale, options.solver)?;
    check_finite(&[scale])?;
    Ok(RobustFix {
        fix,
        scale,
        kept: kept_before,
        rounds,
    })
}
