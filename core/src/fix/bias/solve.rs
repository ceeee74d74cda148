//! The Levenberg-Marquardt fix of position and offsets, and what it reports.

use super::super::{Geometry, geometry};
use super::problem::{Problem, on_line, residual, set_up, usable};
use super::{BiasPrior, MAX_SOURCES, STATE, Sighting, same_priors};
use crate::error::{Error, check_finite};
use crate::likelihood::{Gaussian, Likelihood};
use crate::linalg::{inverse_scaled, mat_vec};
use crate::model::bearing::{Bearing, wrap};

/// Solver settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasedOptions {
    /// Outer iterations at most.
    pub max_iterations: u32,
    /// Stop when a step moves the fix less than this, metres (and the offsets less than this
    /// over 1 km, radians).
    pub tolerance_m: f32,
    /// Every bearing's sigma is multiplied by this (an estimated noise scale; 1 = as given).
    pub scale: f32,
    /// Vehicle position error, metres: a bearing at range r then has sd sqrt((scale
    /// sigma)^2 + (position_sd_m / r)^2), so a point a metre from the vehicle is not pinned by
    /// its bearing (0: positions exact, the plain model).
    pub position_sd_m: f32,
}

impl Default for BiasedOptions {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            tolerance_m: 1e-3,
            scale: 1.0,
            position_sd_m: 0.0,
        }
    }
}

/// A position fix with the offsets of its sources.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasedFix {
    /// Emitter position (east, north), metres.
    pub position: [f32; 2],
    /// Covariance of the position with the offsets integrated out (the top-left block of the
    /// inverse information), m^2, at the options' noise scale.
    pub covariance: [[f32; 2]; 2],
    /// Offset of each source, radians (the prior's mean where the source was not seen or is
    /// calibrated).
    pub bias: [f32; MAX_SOURCES],
    /// Standard deviation of each offset, radians (0 where calibrated, the prior's sd where
    /// the source was not seen).
    pub bias_sd: [f32; MAX_SOURCES],
    /// Bit s set when source s contributed bearings.
    pub sources: u8,
    /// Bearings that entered the fix.
    pub used: u32,
    /// Bearings skipped as unusable (non-finite, bad sigma, unknown source).
    pub skipped: u32,
    /// Bearings whose final residual exceeds 3 sigma (at the options' scale).
    pub outliers: u32,
    /// Solver iterations.
    pub iterations: u32,
    /// sum (r_k / (scale sigma_k))^2 over the used bearings, offsets removed.
    pub chi2: f32,
    /// Effective number of unknowns: 2 plus, per free offset, the share of its information
    /// that came from the data (the trace of the hat matrix: near 0 when the prior governs,
    /// 1 when the drive measures it).
    pub parameters: f32,
}

impl BiasedFix {
    /// Offset of `source` (radians) and its sd.
    pub fn offset(&self, source: usize) -> Option<(f32, f32)> {
        Some((*self.bias.get(source)?, *self.bias_sd.get(source)?))
    }
}

/// Where the solver starts: a position and each source's offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Start {
    /// Emitter position, metres.
    pub position: [f32; 2],
    /// Offsets, radians (the prior's mean is a fine default).
    pub bias: [f32; MAX_SOURCES],
}

/// ML fix of position and offsets over sightings from up to [`MAX_SOURCES`] sources, started
/// at `start` (a robust search's answer: the loss may be redescending).
pub fn ml_sources<T: Sighting, L: Likelihood>(
    items: &[T],
    priors: &[BiasPrior; MAX_SOURCES],
    start: Start,
    loss: &L,
    options: BiasedOptions,
) -> Result<BiasedFix, Error> {
    let (problem, mut x, geo) = set_up(items, priors, start, loss, options)?;
    let iterations = descend(&problem, &mut x, options, None);
    finish(&problem, &x, &geo, iterations)
}

/// Gaussian ML on `items` started from the fix `from` (converged, or nearly: the same source's
/// fix on a set of bearings that changed a little, or at another noise `scale`): how a robust
/// fit is refitted on the bearings it kept and at the noise it estimated.
pub fn refit<T: Sighting>(
    items: &[T],
    priors: &[BiasPrior; MAX_SOURCES],
    from: &BiasedFix,
    scale: f32,
    solver: BiasedOptions,
) -> Result<BiasedFix, Error> {
    ml_sources(
        items,
        priors,
        Start {
            position: from.position,
            bias: from.bias,
        },
        &Gaussian,
        BiasedOptions { scale, ..solver },
    )
}

/// Levenberg-Marquardt from `x` to the minimum (along `line` only, if given); returns the
/// iterations.
pub(super) fn descend<T: Sighting, L: Likelihood>(
    problem: &Problem<'_, T, L>,
    x: &mut [f32; STATE],
    options: BiasedOptions,
    line: Option<[f32; 2]>,
) -> u32 {
    let mut current = problem.cost(x);
    let mut lambda = 1e-3f32;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < options.max_iterations && !converged {
        iterations += 1;
        let (h, g) = problem.normal(x);
        let (h, g) = match line {
            Some(along) => on_line(&h, &g, along),
            None => (h, g),
        };
        let mut accepted = false;
        for _ in 0..12 {
            let mut damped = h;
            for (i, row) in damped.iter_mut().enumerate() {
                row[i] *= 1.0 + lambda;
            }
            let Some(inv) = inverse_scaled(&damped) else {
                lambda *= 10.0;
                continue;
            };
            let mut delta = mat_vec(&inv, &g);
            if let Some([a, b]) = line {
                let t = delta[0];
                delta[0] = t * a;
                delta[1] = t * b;
            }
            let mut next = *x;
            for (n, d) in next.iter_mut().zip(delta.iter()) {
                *n += d;
            }
            let c = problem.cost(&next);
            if c.is_finite() && c <= current {
                let step = libm::hypotf(delta[0], delta[1]);
                let turn = delta[2..]
                    .iter()
                    .fold(0.0f32, |m, d| m.max(libm::fabsf(*d)));
                converged = (step < options.tolerance_m && turn * 1000.0 < options.tolerance_m)
                    || current - c <= 1e-7 * current.abs();
                *x = next;
                current = c;
                lambda = (lambda * 0.1).max(1e-7);
                accepted = true;
                break;
            }
            lambda *= 10.0;
        }
        if !accepted {
            // No downhill step at any damping: the minimum to f32 precision.
            converged = true;
        }
    }
    iterations
}

/// Covariance, offsets and counts at the solution.
fn finish<T: Sighting, L: Likelihood>(
    problem: &Problem<'_, T, L>,
    x: &[f32; STATE],
    geo: &Geometry,
    iterations: u32,
) -> Result<BiasedFix, Error> {
    let position = [x[0] + geo.origin[0], x[1] + geo.origin[1]];
    check_finite(&position)?;
    let (h, _) = problem.normal(x);
    let c = inverse_scaled(&h).ok_or(Error::DegenerateGeometry)?;
    let covariance = [[c[0][0], c[0][1]], [c[1][0], c[1][1]]];
    if !(covariance[0][0] > 0.0 && covariance[1][1] > 0.0) {
        return Err(Error::DegenerateGeometry);
    }
    let mut bias = [0.0f32; MAX_SOURCES];
    let mut bias_sd = [0.0f32; MAX_SOURCES];
    let mut parameters = 2.0f32;
    let mut sources = 0u8;
    for s in 0..MAX_SOURCES {
        let prior = problem.priors[s];
        if problem.free[s] {
            bias[s] = wrap(x[2 + s]);
            bias_sd[s] = libm::sqrtf(c[2 + s][2 + s].max(0.0));
            parameters += (1.0 - c[2 + s][2 + s] * prior.information()).clamp(0.0, 1.0);
        } else {
            bias[s] = prior.mean;
            bias_sd[s] = prior.sd;
        }
    }
    let mut outliers = 0;
    let mut front = 0.0f32;
    let mut chi2 = 0.0f32;
    for (b, s) in usable(problem.items) {
        sources |= 1 << s;
        let r = residual(b, geo.origin, [x[0], x[1]], bias[s]);
        let u = r / (problem.scale * b.sigma);
        chi2 += u * u;
        // The bearing line points at the emitter, not away: residual without the offset's
        // share is what says which side.
        front += libm::cosf(r);
        if libm::fabsf(u) > 3.0 {
            outliers += 1;
        }
    }
    if front <= 0.0 {
        // The solver settled on the mirror image, behind the vehicle: no fix, not a wrong one.
        return Err(Error::BehindVehicle);
    }
    check_finite(&[chi2, parameters])?;
    Ok(BiasedFix {
        position,
        covariance,
        bias,
        bias_sd,
        sources,
        used: geo.used,
        skipped: geo.skipped,
        outliers,
        iterations,
        chi2,
        parameters,
    })
}

/// ML fix of the position and one unit's offset, started from `start` (the bias-compensated
/// PLE when `None`, with the prior's mean as the offset: fine for a Gaussian or Huber loss;
/// start a redescending one from a robust search).
pub fn ml<L: Likelihood>(
    bearings: &[Bearing],
    prior: BiasPrior,
    start: Option<[f32; 2]>,
    loss: &L,
    options: BiasedOptions,
) -> Result<BiasedFix, Error> {
    prior.check()?;
    let position = match start {
        Some(p) => p,
        None => {
            // The PLE sees offset-corrected bearings.
            let _ = geometry(bearings)?;
            super::super::ple::bias_compensated_ple(bearings)?.position
        }
    };
    ml_sources(
        bearings,
        &same_priors(prior),
        Start {
            position,
            bias: [prior.mean; MAX_SOURCES],
        },
        loss,
        options,
    )
}
