//! The Levenberg-Marquardt fix of position and offsets, and what it reports.

use super::super::{Geometry, geometry};
use super::problem::{At, Problem, residual, set_up};
use super::stations::{StationSlot, back_substitute, offset_variances, reduce};
use super::{BiasPrior, Sighting};
use crate::error::{Error, check_finite};
use crate::likelihood::{Gaussian, Likelihood};
use crate::linalg::dot;
use crate::linalg::inverse_scaled;
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

/// A position fix; each station's offset is in the station table it was solved in
/// ([`StationSlot::offset`]), the main station's also here.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasedFix {
    /// Emitter position (east, north), metres.
    pub position: [f32; 2],
    /// Covariance of the position with the offsets integrated out (the inverse of the reduced
    /// information), m^2, at the options' noise scale.
    pub covariance: [[f32; 2]; 2],
    /// The station with most bearings in the fix.
    pub main: u16,
    /// Its offset, radians (the prior's mean when calibrated).
    pub bias: f32,
    /// Its standard deviation, radians (0 when calibrated).
    pub bias_sd: f32,
    /// Stations that contributed bearings.
    pub stations: u32,
    /// Bearings that entered the fix.
    pub used: u32,
    /// Bearings skipped as unusable (non-finite, bad sigma, a station beyond the table).
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

/// Where each free offset starts (a calibrated one is held at its prior's mean).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StartOffsets {
    /// At its prior's mean.
    Prior,
    /// At one value for every station (a consensus' common offset), radians.
    Common(f32),
    /// At the last fit's estimate ([`StationSlot::offset`]).
    Fitted,
    /// Where a profile kept it aside.
    Saved,
    /// Where the solver left it.
    Current,
}

/// Where the solver starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Start {
    /// Emitter position, metres.
    pub position: [f32; 2],
    /// The offsets.
    pub offsets: StartOffsets,
}

/// ML fix of the position and every station's offset over sightings of the stations of
/// `stations` (one row per station index; sightings of a station beyond it are skipped),
/// started at `start` (a robust search's answer: the loss may be redescending). Each row's
/// offset, sd and share measured are written to it.
pub fn ml_sources<T: Sighting, L: Likelihood>(
    items: &[T],
    stations: &mut [StationSlot],
    start: Start,
    loss: &L,
    options: BiasedOptions,
) -> Result<BiasedFix, Error> {
    let (problem, mut p, geo) = set_up(items, stations, start, loss, options)?;
    let iterations = descend(&problem, stations, &mut p, options, None);
    finish(&problem, stations, p, &geo, iterations)
}

/// Gaussian ML on `items` started from the fix `from` and the table's offsets (converged, or
/// nearly: the same source's fix on a set of bearings that changed a little, or at another
/// noise `scale`): how a robust fit is refitted on the bearings it kept and at the noise it
/// estimated.
pub fn refit<T: Sighting>(
    items: &[T],
    stations: &mut [StationSlot],
    from: &BiasedFix,
    scale: f32,
    solver: BiasedOptions,
) -> Result<BiasedFix, Error> {
    ml_sources(
        items,
        stations,
        Start {
            position: from.position,
            offsets: StartOffsets::Fitted,
        },
        &Gaussian,
        BiasedOptions { scale, ..solver },
    )
}

/// One damped step from `p` and the rows' offsets: the position's (along `line` only, if
/// given) and each offset's, written to the rows' trial; `None` when the damped system is
/// singular. Also the largest offset step.
fn step(
    stations: &mut [StationSlot],
    lambda: f32,
    line: Option<[f32; 2]>,
) -> Option<([f32; 2], f32)> {
    let r = reduce(stations, lambda)?;
    let dp = match line {
        Some([a, b]) => {
            let h = r.matrix[0][0];
            if !(h > 0.0) {
                return None;
            }
            let t = r.gradient[0] / h;
            [t * a, t * b]
        }
        None => {
            let inv = inverse_scaled(&r.matrix)?;
            [
                inv[0][0] * r.gradient[0] + inv[0][1] * r.gradient[1],
                inv[1][0] * r.gradient[0] + inv[1][1] * r.gradient[1],
            ]
        }
    };
    // The offsets' back-substitution sees the step in the coordinates it was accumulated in.
    let along = match line {
        Some([a, b]) => [dp[0] * a + dp[1] * b, 0.0],
        None => dp,
    };
    if !(dp[0].is_finite() && dp[1].is_finite()) {
        return None;
    }
    let turn = back_substitute(stations, lambda, along);
    turn.is_finite().then_some((dp, turn))
}

/// Levenberg-Marquardt from `p` and the rows' offsets to the minimum (along `line` only, if
/// given); returns the iterations.
pub(super) fn descend<T: Sighting, L: Likelihood>(
    problem: &Problem<'_, T, L>,
    stations: &mut [StationSlot],
    p: &mut [f32; 2],
    options: BiasedOptions,
    line: Option<[f32; 2]>,
) -> u32 {
    let mut current = problem.cost(stations, *p, At::Current);
    let mut lambda = 1e-3f32;
    let mut iterations = 0;
    let mut converged = false;
    while iterations < options.max_iterations && !converged {
        iterations += 1;
        problem.accumulate(stations, *p, line);
        let mut accepted = false;
        for _ in 0..12 {
            let Some((dp, turn)) = step(stations, lambda, line) else {
                lambda *= 10.0;
                continue;
            };
            let next = [p[0] + dp[0], p[1] + dp[1]];
            let c = problem.cost(stations, next, At::Trial);
            if c.is_finite() && c <= current {
                let moved = libm::hypotf(dp[0], dp[1]);
                converged = (moved < options.tolerance_m && turn * 1000.0 < options.tolerance_m)
                    || current - c <= 1e-7 * current.abs();
                *p = next;
                for s in stations.iter_mut() {
                    s.x = s.trial;
                    s.hx = s.htrial;
                }
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

/// The position's marginal covariance at centred `p` and the rows' offsets (along `line` only,
/// if given: then its [0][0] is the variance along it); without a line each free offset's sd
/// and share are written to the rows. Also the offsets' effective number of unknowns.
pub(super) fn marginal<T: Sighting, L: Likelihood>(
    problem: &Problem<'_, T, L>,
    stations: &mut [StationSlot],
    p: [f32; 2],
    line: Option<[f32; 2]>,
) -> Result<([[f32; 2]; 2], f32), Error> {
    problem.accumulate(stations, p, line);
    let mut r = reduce(stations, 0.0).ok_or(Error::DegenerateGeometry)?;
    if line.is_some() {
        // Across the line the position is held: an identity that leaves the rest alone.
        r.matrix[0][1] = 0.0;
        r.matrix[1][0] = 0.0;
        r.matrix[1][1] = 1.0;
    }
    let c = inverse_scaled(&r.matrix).ok_or(Error::DegenerateGeometry)?;
    let c_along = match line {
        // The offsets' variances in the coordinates the blocks were accumulated in.
        Some(_) => [[c[0][0], 0.0], [0.0, 0.0]],
        None => c,
    };
    let shares =
        offset_variances(stations, &c_along, line.is_none()).ok_or(Error::DegenerateGeometry)?;
    Ok((c, shares))
}

/// Covariance, offsets and counts at the solution.
fn finish<T: Sighting, L: Likelihood>(
    problem: &Problem<'_, T, L>,
    stations: &mut [StationSlot],
    p: [f32; 2],
    geo: &Geometry,
    iterations: u32,
) -> Result<BiasedFix, Error> {
    let position = [p[0] + geo.origin[0], p[1] + geo.origin[1]];
    check_finite(&position)?;
    let (covariance, shares) = marginal(problem, stations, p, None)?;
    if !(covariance[0][0] > 0.0 && covariance[1][1] > 0.0) {
        return Err(Error::DegenerateGeometry);
    }
    let mut count = 0u32;
    for s in stations.iter_mut() {
        s.used = s.n;
        if s.n > 0 {
            count += 1;
        }
        if s.free {
            s.bias = wrap(s.x);
        } else {
            s.bias = s.in_force.mean;
            s.sd = s.in_force.sd;
            s.measured = 0.0;
        }
        s.hfit = s.hx;
        if !s.hfree {
            s.hsd = [s.direction().sd; super::HARMONICS];
        }
    }
    let main = (0..stations.len())
        .max_by_key(|&i| (stations[i].n, core::cmp::Reverse(i)))
        .unwrap_or(0);
    let mut outliers = 0;
    let mut front = 0.0f32;
    let mut chi2 = 0.0f32;
    for (b, s, u) in problem.sightings(stations.len()) {
        let Some(row) = stations.get(s) else { continue };
        let r = residual(b, geo.origin, p, row.bias + dot(&row.hfit, &u));
        let u = r / (problem.scale * b.sigma);
        chi2 += u * u;
        // The bearing line points at the emitter, not away: the residual says which side.
        front += libm::cosf(r);
        if libm::fabsf(u) > 3.0 {
            outliers += 1;
        }
    }
    if front <= 0.0 {
        // The solver settled on the mirror image, behind the vehicle: no fix, not a wrong one.
        return Err(Error::BehindVehicle);
    }
    let parameters = 2.0 + shares;
    check_finite(&[chi2, parameters])?;
    let (bias, bias_sd) = stations.get(main).map_or((0.0, 0.0), StationSlot::offset);
    Ok(BiasedFix {
        position,
        covariance,
        main: main as u16,
        bias,
        bias_sd,
        stations: count,
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
    let mut unit = [StationSlot::new(prior)];
    ml_sources(
        bearings,
        &mut unit,
        Start {
            position,
            offsets: StartOffsets::Prior,
        },
        loss,
        options,
    )
}
