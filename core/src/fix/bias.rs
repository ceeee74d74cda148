//! A constant bearing offset per DF source, estimated with the position.
//!
//! Every real DF unit has one: an antenna mounted a few degrees off the vehicle's axis, an
//! array whose reference element is not where the software thinks (1-5 degrees for
//! pseudo-Doppler units, 9-12 for some KrakenSDR set-ups, FIELD.md). Ignored, an offset b
//! moves the fix by about r b (5 degrees at 2 km: 175 m) while the ellipse stays small. Here
//! the model is z_k = atan2(emitter - s_k) + b_{source(k)} + noise and the unknowns are
//! [x, y, b_0 .. b_{S-1}]: the ML Jacobian gains one column of ones per source.
//!
//! Each offset has a Gaussian prior: by default mean 0 and sd [`DEFAULT_BIAS_SD`] (6 degrees,
//! so the 1-12 degrees real units show lie within two sd); sd 0 is a calibrated unit (the
//! offset is fixed at the prior's mean); an infinite sd is no prior at all. On a drive that
//! cannot tell an offset from a cross-range shift (a straight road, a short arc: FIELD.md's
//! inscribed-angle argument) the prior governs and the position covariance, the marginal of the
//! (2 + S)-dimensional one, grows to show it; where the drive surrounds the emitter the offset
//! is measured to sigma / sqrt(N) and costs the position nothing.
//!
//! Levenberg-Marquardt on sum rho(r_k / sigma_k) + sum (b - mu)^2 / (2 tau^2) with any
//! [`Likelihood`]'s IRLS weights; the normal matrix is scaled to unit diagonal before it is
//! factored, since in f32 the position terms (1 / (sigma r)^2) and the offset terms
//! (1 / sigma^2) differ by the square of the range.

use super::{Geometry, geometry};
use crate::error::{Error, check_finite};
use crate::likelihood::Likelihood;
use crate::linalg;
use crate::model::bearing::{Bearing, predicted, wrap};

/// DF sources (units, or antenna set-ups) whose offsets are estimated separately.
pub const MAX_SOURCES: usize = 4;
/// Unknowns of the fix: position and one offset per source.
pub const STATE: usize = 2 + MAX_SOURCES;
/// Default prior sd of an uncalibrated unit's offset: 6 degrees, radians.
pub const DEFAULT_BIAS_SD: f32 = 6.0 * core::f32::consts::PI / 180.0;

/// What is known of one source's offset before the drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasPrior {
    /// Expected offset, radians (added to the true bearing by the unit).
    pub mean: f32,
    /// Its standard deviation, radians: 0 for a calibrated unit (fixed at `mean`), infinite
    /// for no prior.
    pub sd: f32,
}

impl Default for BiasPrior {
    fn default() -> Self {
        Self {
            mean: 0.0,
            sd: DEFAULT_BIAS_SD,
        }
    }
}

impl BiasPrior {
    /// A unit calibrated to `offset` (its offset is not estimated).
    pub const fn calibrated(offset: f32) -> Self {
        Self {
            mean: offset,
            sd: 0.0,
        }
    }

    /// `Ok` when the mean is finite and the sd is >= 0 (infinity allowed).
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&[self.mean])?;
        if self.sd >= 0.0 {
            Ok(())
        } else if self.sd.is_nan() {
            Err(Error::NonFinite)
        } else {
            Err(Error::OutOfRange)
        }
    }

    /// Whether the offset is a free unknown (sd > 0).
    pub fn is_free(&self) -> bool {
        self.sd > 0.0
    }

    /// 1 / sd^2: the prior's information (0 for no prior).
    fn information(&self) -> f32 {
        if self.sd.is_finite() && self.sd > 0.0 {
            1.0 / (self.sd * self.sd)
        } else {
            0.0
        }
    }
}

/// A bearing together with the DF source that took it.
pub trait Sighting {
    /// The bearing.
    fn bearing(&self) -> &Bearing;
    /// Index of its DF source (< [`MAX_SOURCES`] to be used).
    fn source(&self) -> usize {
        0
    }
}

impl Sighting for Bearing {
    fn bearing(&self) -> &Bearing {
        self
    }
}

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

/// Residual z - h(p) - b of one sighting at centred position `p` with offsets `b`.
#[inline]
fn residual(b: &Bearing, origin: [f32; 2], p: [f32; 2], bias: f32) -> f32 {
    let s = [b.vehicle[0] - origin[0], b.vehicle[1] - origin[1]];
    wrap(b.theta - predicted(&p, &s) - bias)
}

/// The usable sightings with a known source.
fn usable<T: Sighting>(items: &[T]) -> impl Iterator<Item = (&Bearing, usize)> {
    items
        .iter()
        .map(|t| (t.bearing(), t.source()))
        .filter(|(b, s)| *s < MAX_SOURCES && b.check().is_ok())
}

/// Working problem: centred origin, priors, which offsets are free.
struct Problem<'a, T, L> {
    items: &'a [T],
    priors: &'a [BiasPrior; MAX_SOURCES],
    loss: &'a L,
    origin: [f32; 2],
    scale: f32,
    position_sd: f32,
    free: [bool; MAX_SOURCES],
}

impl<T: Sighting, L: Likelihood> Problem<'_, T, L> {
    /// The bearing's sd at centred position `p` (the position error's share included).
    fn sigma(&self, b: &Bearing, p: [f32; 2]) -> f32 {
        let plain = self.scale * b.sigma;
        if self.position_sd > 0.0 {
            let (dx, dy) = (
                p[0] - (b.vehicle[0] - self.origin[0]),
                p[1] - (b.vehicle[1] - self.origin[1]),
            );
            let d2 = (dx * dx + dy * dy).max(1e-6);
            libm::sqrtf(plain * plain + self.position_sd * self.position_sd / d2)
        } else {
            plain
        }
    }

    fn cost(&self, x: &[f32; STATE]) -> f32 {
        let p = [x[0], x[1]];
        let mut c = 0.0f32;
        for (b, s) in usable(self.items) {
            let r = residual(b, self.origin, p, x[2 + s]);
            let sigma = self.sigma(b, p);
            c -= self.loss.ln(r, sigma);
            if self.position_sd > 0.0 {
                // The normalising constant, now that the sd depends on the position.
                c += libm::logf(sigma / (self.scale * b.sigma));
            }
        }
        for s in 0..MAX_SOURCES {
            if self.free[s] {
                let d = x[2 + s] - self.priors[s].mean;
                c += 0.5 * d * d * self.priors[s].information();
            }
        }
        c
    }

    /// Normal matrix and gradient (IRLS weights), priors included; fixed offsets get an
    /// identity row so the step leaves them alone.
    fn normal(&self, x: &[f32; STATE]) -> ([[f32; STATE]; STATE], [f32; STATE]) {
        let mut h = [[0.0f32; STATE]; STATE];
        let mut g = [0.0f32; STATE];
        let p = [x[0], x[1]];
        for (b, s) in usable(self.items) {
            let v = [b.vehicle[0] - self.origin[0], b.vehicle[1] - self.origin[1]];
            let (dx, dy) = (p[0] - v[0], p[1] - v[1]);
            let d2 = (dx * dx + dy * dy).max(1e-6);
            let r = wrap(b.theta - predicted(&p, &v) - x[2 + s]);
            let sigma = self.sigma(b, p);
            let w = self.loss.irls_weight(r, sigma) / (sigma * sigma);
            // d h / d [x, y, b_s] for h = atan2(dy, dx) + b_s.
            let jac = [-dy / d2, dx / d2, 1.0];
            let idx = [0, 1, 2 + s];
            for i in 0..3 {
                for j in 0..3 {
                    h[idx[i]][idx[j]] += w * jac[i] * jac[j];
                }
                g[idx[i]] += w * jac[i] * r;
            }
        }
        for s in 0..MAX_SOURCES {
            let k = 2 + s;
            if self.free[s] {
                let info = self.priors[s].information();
                h[k][k] += info;
                g[k] += info * (self.priors[s].mean - x[k]);
            } else {
                for j in 0..STATE {
                    h[k][j] = 0.0;
                    h[j][k] = 0.0;
                }
                h[k][k] = 1.0;
                g[k] = 0.0;
            }
        }
        (h, g)
    }
}

/// Inverse of a symmetric positive definite matrix scaled to unit diagonal first, so entries
/// of very different sizes (metres and radians) keep their digits. `None` if not SPD.
pub(crate) fn inverse_scaled<const D: usize>(m: &[[f32; D]; D]) -> Option<[[f32; D]; D]> {
    let mut d = [0.0f32; D];
    for i in 0..D {
        if !(m[i][i] > 0.0) || !m[i][i].is_finite() {
            return None;
        }
        d[i] = 1.0 / libm::sqrtf(m[i][i]);
    }
    let mut s = [[0.0f32; D]; D];
    for i in 0..D {
        for j in 0..D {
            s[i][j] = 0.5 * (m[i][j] + m[j][i]) * d[i] * d[j];
        }
    }
    let mut inv = linalg::inverse_spd(&s)?;
    for i in 0..D {
        for j in 0..D {
            inv[i][j] *= d[i] * d[j];
        }
    }
    inv.iter().flatten().all(|v| v.is_finite()).then_some(inv)
}

fn mat_vec<const D: usize>(m: &[[f32; D]; D], v: &[f32; D]) -> [f32; D] {
    core::array::from_fn(|i| (0..D).map(|j| m[i][j] * v[j]).sum())
}

/// The geometry check of the usable sightings.
fn sighting_geometry<T: Sighting>(items: &[T]) -> Result<Geometry, Error> {
    // The plain geometry check on the bearings of known sources; unknown sources count as
    // skipped.
    let mut g = super::geometry_of(usable(items).map(|(b, _)| b))?;
    g.skipped = items.len() as u32 - g.used;
    Ok(g)
}

/// Where the solver starts: a position and each source's offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Start {
    /// Emitter position, metres.
    pub position: [f32; 2],
    /// Offsets, radians (the prior's mean is a fine default).
    pub bias: [f32; MAX_SOURCES],
}

/// Priors of every source, the same for each.
pub fn same_priors(prior: BiasPrior) -> [BiasPrior; MAX_SOURCES] {
    [prior; MAX_SOURCES]
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

/// One point of the profile likelihood: the best fit with the position held on a line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfilePoint {
    /// The best position on the line, metres.
    pub position: [f32; 2],
    /// The offsets there, radians.
    pub bias: [f32; MAX_SOURCES],
    /// -2 ln L there (the offsets' prior included), up to a constant shared by every point
    /// of the same sightings, loss and scale: differences are likelihood-ratio statistics.
    pub deviance: f32,
    /// Standard deviation of the position along the line, offsets integrated out, metres.
    pub along_sd: f32,
}

/// The profile likelihood at one slice: the position free only along the unit vector
/// `along` through `start.position` (its component across the line held), the offsets free.
/// Where the Fisher ellipse is a poor picture of the likelihood (a range the bearings barely
/// observe), walking such slices outward shows how far the data really allow the fix to go.
pub fn profile<T: Sighting, L: Likelihood>(
    items: &[T],
    priors: &[BiasPrior; MAX_SOURCES],
    start: Start,
    along: [f32; 2],
    loss: &L,
    options: BiasedOptions,
) -> Result<ProfilePoint, Error> {
    check_finite(&along)?;
    let norm = libm::hypotf(along[0], along[1]);
    if !(norm > 0.0) {
        return Err(Error::OutOfRange);
    }
    let along = [along[0] / norm, along[1] / norm];
    let (problem, mut x, geo) = set_up(items, priors, start, loss, options)?;
    descend(&problem, &mut x, options, Some(along));
    let (h, g) = problem.normal(&x);
    let (h, _) = on_line(&h, &g, along);
    let c = inverse_scaled(&h).ok_or(Error::DegenerateGeometry)?;
    let point = ProfilePoint {
        position: [x[0] + geo.origin[0], x[1] + geo.origin[1]],
        bias: core::array::from_fn(|s| x[2 + s]),
        deviance: 2.0 * problem.cost(&x),
        along_sd: libm::sqrtf(c[0][0].max(0.0)),
    };
    check_finite(&point.position)?;
    check_finite(&point.bias)?;
    check_finite(&[point.deviance, point.along_sd])?;
    Ok(point)
}

/// A checked problem, the solver's starting state (centred on the drive) and the geometry.
type SetUp<'a, T, L> = (Problem<'a, T, L>, [f32; STATE], Geometry);

/// The checked problem and the solver's starting state (centred on the drive).
fn set_up<'a, T: Sighting, L: Likelihood>(
    items: &'a [T],
    priors: &'a [BiasPrior; MAX_SOURCES],
    start: Start,
    loss: &'a L,
    options: BiasedOptions,
) -> Result<SetUp<'a, T, L>, Error> {
    for p in priors {
        p.check()?;
    }
    check_finite(&[options.scale, options.tolerance_m, options.position_sd_m])?;
    check_finite(&start.position)?;
    check_finite(&start.bias)?;
    if !(options.scale > 0.0 && options.position_sd_m >= 0.0) {
        return Err(Error::OutOfRange);
    }
    let geo = sighting_geometry(items)?;
    let mut seen = [false; MAX_SOURCES];
    for (_, s) in usable(items) {
        seen[s] = true;
    }
    let free: [bool; MAX_SOURCES] = core::array::from_fn(|s| seen[s] && priors[s].is_free());
    let problem = Problem {
        items,
        priors,
        loss,
        origin: geo.origin,
        scale: options.scale,
        position_sd: options.position_sd_m,
        free,
    };
    let mut x = [0.0f32; STATE];
    x[0] = start.position[0] - geo.origin[0];
    x[1] = start.position[1] - geo.origin[1];
    for s in 0..MAX_SOURCES {
        x[2 + s] = if free[s] {
            start.bias[s]
        } else {
            priors[s].mean
        };
    }
    Ok((problem, x, geo))
}

/// The normal equations with the position reduced to one unknown t along `along` (x = x0 +
/// t along): row and column 0 become t's, row 1 an identity that leaves the rest alone.
fn on_line(
    h: &[[f32; STATE]; STATE],
    g: &[f32; STATE],
    along: [f32; 2],
) -> ([[f32; STATE]; STATE], [f32; STATE]) {
    let [a, b] = along;
    let mut r = *h;
    let mut q = *g;
    r[0][0] = a * a * h[0][0] + a * b * (h[0][1] + h[1][0]) + b * b * h[1][1];
    for k in 2..STATE {
        let v = a * h[0][k] + b * h[1][k];
        r[0][k] = v;
        r[k][0] = v;
        r[1][k] = 0.0;
        r[k][1] = 0.0;
    }
    r[0][1] = 0.0;
    r[1][0] = 0.0;
    r[1][1] = 1.0;
    q[0] = a * g[0] + b * g[1];
    q[1] = 0.0;
    (r, q)
}

/// Levenberg-Marquardt from `x` to the minimum (along `line` only, if given); returns the
/// iterations.
fn descend<T: Sighting, L: Likelihood>(
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
            super::ple::bias_compensated_ple(bearings)?.position
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

/// Fisher information about [x, y, b] of one unit's bearings at emitter `p`, the prior's
/// information on b included (infinite for a calibrated unit: then b is dropped and the
/// position block is the plain 2 x 2 information with a 1 in the corner).
pub fn information(p: &[f32; 2], bearings: &[Bearing], prior: BiasPrior) -> Option<[[f32; 3]; 3]> {
    let mut j = [[0.0f32; 3]; 3];
    let mut any = false;
    for b in super::usable(bearings) {
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
    for b in super::usable(bearings) {
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

/// A unit's offset measured on a drive past a transmitter at a known position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// The offset, radians (add it to a model bearing to get what the unit reports; subtract
    /// it from the unit's bearings to correct them).
    pub bias: f32,
    /// Its standard deviation, radians: sigma / sqrt(N_eff).
    pub sd: f32,
    /// The bearings' noise estimated from the residuals, radians.
    pub sigma: f32,
    /// Bearings used.
    pub used: u32,
    /// Bearings left out as wild (beyond 3.5 robust sigmas of the offset) or unusable.
    pub rejected: u32,
    /// Effective number of independent bearings (correlated reports count less).
    pub effective: f32,
}

impl Calibration {
    /// The calibration as a prior for later drives (calibrated to its sd, not to zero: a
    /// calibration is a measurement with an error).
    pub fn prior(&self) -> BiasPrior {
        BiasPrior {
            mean: self.bias,
            sd: self.sd,
        }
    }
}

/// Bearings whose residual lies beyond this many robust sigmas are not used to calibrate.
const CALIBRATION_CUT: f32 = 3.5;

/// Measure the offset of one unit from `bearings` taken of a transmitter at `emitter`: the
/// mean residual (robustly: the median first, then the mean of those within 3.5 robust
/// sigmas), with variance sigma^2 / N_eff, N_eff from the residuals' autocorrelation in the
/// order given (time order).
pub fn calibrate(bearings: &[Bearing], emitter: [f32; 2]) -> Result<Calibration, Error> {
    check_finite(&emitter)?;
    const CAP: usize = 512;
    // The median from an evenly strided sample of at most CAP residuals (no allocator).
    let n_all = bearings.len();
    let stride = n_all.div_ceil(CAP).max(1);
    let mut sample = [0.0f32; CAP];
    let mut k = 0;
    for b in bearings.iter().step_by(stride) {
        if b.check().is_ok()
            && let Some(slot) = sample.get_mut(k)
        {
            *slot = b.residual(&emitter);
            k += 1;
        }
    }
    if k < 2 {
        return Err(Error::TooFewMeasurements);
    }
    let centre = super::order::median(&mut sample[..k]);
    for v in sample[..k].iter_mut() {
        *v = libm::fabsf(wrap(*v - centre));
    }
    let spread = (1.4826 * super::order::median(&mut sample[..k])).max(1e-5);
    let inside = |b: &Bearing| {
        b.check().is_ok()
            && libm::fabsf(wrap(b.residual(&emitter) - centre)) <= CALIBRATION_CUT * spread
    };
    let mut n = 0u32;
    let mut sum = 0.0f32;
    for b in bearings.iter().filter(|b| inside(b)) {
        sum += wrap(b.residual(&emitter) - centre);
        n += 1;
    }
    if n < 2 {
        return Err(Error::TooFewMeasurements);
    }
    let bias = wrap(centre + sum / n as f32);
    let mut ss = 0.0f32;
    for b in bearings.iter().filter(|b| inside(b)) {
        let r = wrap(b.residual(&emitter) - bias);
        ss += r * r;
    }
    // A cut at 3.5 sigma keeps 0.9953 of a Gaussian's variance.
    let sigma = libm::sqrtf(ss / (n - 1) as f32 / 0.9953);
    let effective = super::consistency::effective_count(
        bearings
            .iter()
            .filter(|b| inside(b))
            .map(|b| wrap(b.residual(&emitter) - bias) / sigma.max(1e-9)),
        n,
    );
    let sd = sigma / libm::sqrtf(effective.max(1.0));
    check_finite(&[bias, sd, sigma])?;
    Ok(Calibration {
        bias,
        sd,
        sigma,
        used: n,
        rejected: n_all as u32 - n,
        effective,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    const DEG: f32 = core::f32::consts::PI / 180.0;

    /// 120 bearings on a circle of `radius` about `centre`, over `arc` radians, offset `b`.
    fn arc_drive(
        e: [f32; 2],
        centre: [f32; 2],
        radius: f32,
        arc: f32,
        b: f32,
        sigma: f32,
        rng: &mut XorShiftRng,
    ) -> [Bearing; 120] {
        core::array::from_fn(|k| {
            let a = arc * k as f32 / 119.0;
            let v = [
                centre[0] + radius * libm::cosf(a),
                centre[1] + radius * libm::sinf(a),
            ];
            Bearing {
                vehicle: v,
                theta: wrap(predicted(&e, &v) + b + sigma * random::normal(rng)),
                sigma,
            }
        })
    }

    #[test]
    fn a_surrounded_emitter_gives_its_offset_and_an_unchanged_position_bound() {
        let mut rng = XorShiftRng::seed_from_u64(1);
        let e = [1200.0, 800.0];
        let bs = arc_drive(
            e,
            e,
            300.0,
            2.0 * core::f32::consts::PI,
            4.0 * DEG,
            0.02,
            &mut rng,
        );
        let f = ml(
            &bs,
            BiasPrior::default(),
            None,
            &crate::Gaussian,
            Default::default(),
        )
        .unwrap();
        // sigma / sqrt(N) = 1.15 deg / 11 = 0.1 deg: 4 degrees found to a few tenths.
        assert!(
            (f.bias[0] - 4.0 * DEG).abs() < 0.4 * DEG,
            "{}",
            f.bias[0] / DEG
        );
        assert!((f.bias_sd[0] - 0.02 / libm::sqrtf(120.0)).abs() < 0.2 * f.bias_sd[0]);
        assert!(libm::hypotf(f.position[0] - e[0], f.position[1] - e[1]) < 5.0);
        // Around the emitter the offset costs the position nothing.
        let plain = crate::fix::crlb::crlb(&e, &bs).unwrap().rmse;
        let aware = crlb(&e, &bs, BiasPrior::default()).unwrap().rmse;
        assert!(aware < 1.01 * plain, "{aware} {plain}");
        assert!(f.parameters > 2.99, "{}", f.parameters);
    }

    #[test]
    fn on_a_short_arc_the_prior_governs_and_the_covariance_shows_it() {
        let mut rng = XorShiftRng::seed_from_u64(2);
        let e = [0.0, 2000.0];
        // A straight road, 400 m long, the emitter broadside 2 km away: an 11 degree spread of
        // bearings, which cannot tell an offset from a sideways shift.
        let bs: [Bearing; 120] = core::array::from_fn(|k| {
            let v = [-200.0 + 400.0 * k as f32 / 119.0, 0.0];
            Bearing {
                vehicle: v,
                theta: wrap(predicted(&e, &v) + 0.02 * random::normal(&mut rng)),
                sigma: 0.02,
            }
        });
        let prior = BiasPrior::default();
        let f = ml(&bs, prior, None, &crate::Gaussian, Default::default()).unwrap();
        let calibrated = ml(
            &bs,
            BiasPrior::calibrated(0.0),
            None,
            &crate::Gaussian,
            Default::default(),
        )
        .unwrap();
        // The offset is barely measured: its sd stays near the prior's.
        assert!(f.bias_sd[0] > 0.9 * prior.sd, "{}", f.bias_sd[0] / DEG);
        assert!(f.parameters < 2.2, "{}", f.parameters);
        // And the position's cross-range sd grows toward range x prior sd (2 km x 6 deg).
        let cross = libm::sqrtf(f.covariance[0][0]);
        let plain = libm::sqrtf(calibrated.covariance[0][0]);
        assert!(cross > 100.0 && cross > 5.0 * plain, "{cross} vs {plain}");
        let bound = crlb(&e, &bs, prior).unwrap();
        assert!(
            (bound.rmse - libm::sqrtf(f.covariance[0][0] + f.covariance[1][1])).abs()
                < 0.1 * bound.rmse
        );
    }

    #[test]
    fn three_by_three_information_matches_the_bound() {
        let mut rng = XorShiftRng::seed_from_u64(3);
        let e = [500.0, 900.0];
        let bs = arc_drive(e, [0.0, 0.0], 400.0, 1.5, 0.0, 0.03, &mut rng);
        let prior = BiasPrior {
            mean: 0.0,
            sd: 0.05,
        };
        let j = information(&e, &bs, prior).unwrap();
        let c = inverse_scaled(&j).unwrap();
        let b = crlb(&e, &bs, prior).unwrap();
        assert!((libm::sqrtf(c[0][0] + c[1][1]) - b.rmse).abs() < 1e-3 * b.rmse);
        assert!((libm::sqrtf(c[2][2]) - b.bias_sd).abs() < 1e-3 * b.bias_sd);
        assert!((j[2][2] - (120.0 / (0.03 * 0.03) + 400.0)).abs() < 1.0);
        // A calibrated unit: the plain 2 x 2 bound.
        let cal = crlb(&e, &bs, BiasPrior::calibrated(0.0)).unwrap();
        let plain = crate::fix::crlb::crlb(&e, &bs).unwrap();
        assert!((cal.rmse - plain.rmse).abs() < 1e-3 * plain.rmse);
    }

    #[test]
    fn calibration_measures_the_offset_with_sigma_over_root_n() {
        let mut rng = XorShiftRng::seed_from_u64(4);
        let e = [300.0, 700.0];
        let mut bs = arc_drive(e, [0.0, 0.0], 200.0, 1.0, -3.0 * DEG, 0.03, &mut rng);
        bs[7].theta += 1.0; // a wild bearing
        bs[9].sigma = -1.0; // an unusable one
        let c = calibrate(&bs, e).unwrap();
        assert_eq!((c.used, c.rejected), (118, 2));
        assert!(
            (c.bias + 3.0 * DEG).abs() < 4.0 * c.sd,
            "{} +- {}",
            c.bias / DEG,
            c.sd / DEG
        );
        assert!((c.sigma - 0.03).abs() < 0.005, "{}", c.sigma);
        // White noise: N_eff near N, the sd near sigma / sqrt(N).
        assert!(c.effective > 80.0, "{}", c.effective);
        assert!((c.sd - 0.03 / libm::sqrtf(118.0)).abs() < 0.3 * c.sd);
        assert_eq!(calibrate(&bs[..1], e), Err(Error::TooFewMeasurements));
    }

    #[test]
    fn several_sources_get_their_own_offsets() {
        struct S(Bearing, usize);
        impl Sighting for S {
            fn bearing(&self) -> &Bearing {
                &self.0
            }
            fn source(&self) -> usize {
                self.1
            }
        }
        let mut rng = XorShiftRng::seed_from_u64(5);
        let e = [1000.0, 1000.0];
        let bs = arc_drive(e, e, 500.0, 6.0, 0.0, 0.01, &mut rng);
        let items: [S; 120] = core::array::from_fn(|k| {
            let src = k % 2;
            let mut b = bs[k];
            b.theta = wrap(b.theta + if src == 0 { 2.0 * DEG } else { -5.0 * DEG });
            S(b, src)
        });
        let f = ml_sources(
            &items,
            &same_priors(BiasPrior::default()),
            Start {
                position: [900.0, 1100.0],
                bias: [0.0; MAX_SOURCES],
            },
            &crate::Gaussian,
            Default::default(),
        )
        .unwrap();
        assert!(
            (f.bias[0] - 2.0 * DEG).abs() < 0.3 * DEG,
            "{}",
            f.bias[0] / DEG
        );
        assert!(
            (f.bias[1] + 5.0 * DEG).abs() < 0.3 * DEG,
            "{}",
            f.bias[1] / DEG
        );
        assert_eq!(f.sources, 0b11);
        // Unseen sources keep their prior.
        assert_eq!((f.bias[2], f.bias_sd[2]), (0.0, DEFAULT_BIAS_SD));
        assert!(libm::hypotf(f.position[0] - e[0], f.position[1] - e[1]) < 3.0);
    }

    #[test]
    fn bad_priors_are_refused() {
        let bs = [Bearing {
            vehicle: [0.0, 0.0],
            theta: 0.0,
            sigma: 0.01,
        }; 3];
        let nan = BiasPrior {
            mean: 0.0,
            sd: f32::NAN,
        };
        assert_eq!(
            ml(
                &bs,
                nan,
                Some([1.0, 1.0]),
                &crate::Gaussian,
                Default::default()
            ),
            Err(Error::NonFinite)
        );
        let neg = BiasPrior {
            mean: 0.0,
            sd: -1.0,
        };
        assert_eq!(crlb(&[1.0, 1.0], &bs, neg), Err(Error::OutOfRange));
    }
}
