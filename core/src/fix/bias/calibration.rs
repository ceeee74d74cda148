//! A unit's offset, and where the drive turns its direction-dependent error, measured on a
//! drive past a transmitter at a known position.

use super::BiasPrior;
use super::direction::{DirectionPrior, HARMONICS, harmonics};
use crate::error::{Error, check_finite};
use crate::model::bearing::{Bearing, wrap};

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
    let centre = super::super::order::median(&mut sample[..k]);
    for v in sample[..k].iter_mut() {
        *v = libm::fabsf(wrap(*v - centre));
    }
    let spread = (1.4826 * super::super::order::median(&mut sample[..k])).max(1e-5);
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
    let effective = super::super::consistency::effective_count(
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

/// Per bearing, the least information the drive gives any combination of the four harmonic
/// coefficients, relative to a full turn's best: the smallest eigenvalue of the harmonics'
/// information per bearing (offset eliminated, unit noise) must reach this before they are
/// said to be measured. Relative bearings spread evenly round the circle give 0.5 (each
/// regressor's mean square), so 0.1 lets the worst-determined combination have five times the
/// variance it would have on a full turn; a drive past the transmitter on a straight road,
/// where the relative bearing sweeps half the circle once, stays far below it.
pub const MIN_SPAN: f32 = 0.1;

/// A unit's offset and direction-dependent error measured together on a drive past a
/// transmitter at a known position (docs/src/field.md, "Calibration"): the residuals
/// z_k - atan2(emitter - s_k) regressed on 1, cos phi_k, sin phi_k, cos 2 phi_k, sin 2 phi_k.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DirectionCalibration {
    /// The offset with its sd (the harmonics integrated out), the noise, the counts.
    pub offset: Calibration,
    /// The harmonic coefficients a_1, b_1, a_2, b_2, radians.
    pub coefficients: [f32; HARMONICS],
    /// Their covariance, radians^2 (sigma^2 / N_eff times the inverse information).
    pub covariance: [[f32; HARMONICS]; HARMONICS],
    /// How well the relative bearings span the circle: the smallest eigenvalue of the
    /// harmonics' information per bearing, offset eliminated ([`MIN_SPAN`]).
    pub span: f32,
}

impl DirectionCalibration {
    /// Whether the drive turned enough for the harmonics to count as measured ([`MIN_SPAN`]).
    pub fn measured(&self) -> bool {
        self.span >= MIN_SPAN
    }

    /// One sd for the four coefficients, radians: the largest along any combination of them
    /// (the covariance's largest eigenvalue, square-rooted), so the isotropic prior a fix
    /// takes ([`DirectionPrior`]) is never narrower than the measurement.
    pub fn sd(&self) -> f32 {
        libm::sqrtf(crate::linalg::largest_eigenvalue(&self.covariance).max(0.0))
    }

    /// The measured table as a prior for later drives: the coefficients with their sd.
    pub fn prior(&self) -> DirectionPrior {
        DirectionPrior {
            mean: self.coefficients,
            sd: self.sd(),
        }
    }
}

/// Coefficients of the third and fourth harmonics, fitted beside the table as nuisance and
/// dropped: the table of two harmonics is what the fixes model, but a real antenna's error
/// (and the model's own second-order terms: the error is a function of the true relative
/// bearing, the table of the measured one) has more. A lap turns through every direction and
/// leaves them orthogonal to the table; a part of a lap does not, and there they bend the
/// table by more than its sd (measured: a three-quarter lap's coefficients 1.45-1.63 of their
/// sd off, rms, and 89.3 % of its fixes' ellipses holding the truth; with them fitted
/// 1.09-1.39 and 94.4 %, over 2 000 runs: docs/src/field.md, "Calibration").
const HIGHER: usize = 4;

/// The table's unknowns: the offset and the four coefficients.
const TABLE: usize = 1 + HARMONICS;

/// Unknowns of the direction calibration: the table's and the higher harmonics'.
const UNKNOWNS: usize = TABLE + HIGHER;

/// The regressors of bearing at relative bearing `phi`: 1, the table's harmonics, the third
/// and fourth.
fn regressors(phi: f32) -> [f32; UNKNOWNS] {
    let h = harmonics(phi);
    let (s3, c3) = (libm::sinf(3.0 * phi), libm::cosf(3.0 * phi));
    let (s4, c4) = (2.0 * h[3] * h[2], h[2] * h[2] - h[3] * h[3]);
    [1.0, h[0], h[1], h[2], h[3], c3, s3, c4, s4]
}

/// The least-squares fit of residuals about `centre` on the regressors, over the bearings
/// `keep` accepts: the solution ([`solve_wide`]) and the count (`None`: too few or
/// degenerate).
fn fit_direction(
    bearings: &[Bearing],
    relative: &[f32],
    emitter: &[f32; 2],
    centre: f32,
    keep: impl Fn(f32, f32) -> bool,
) -> Option<(Wide, u32)> {
    let mut a = [[0.0f32; UNKNOWNS]; UNKNOWNS];
    let mut rhs = [0.0f32; UNKNOWNS];
    let mut n = 0u32;
    for (b, &phi) in bearings.iter().zip(relative) {
        if b.check().is_err() || !phi.is_finite() {
            continue;
        }
        let r = wrap(b.residual(emitter) - centre);
        if !keep(r, phi) {
            continue;
        }
        let x = regressors(phi);
        for i in 0..UNKNOWNS {
            rhs[i] += x[i] * r;
            for j in 0..UNKNOWNS {
                a[i][j] += x[i] * x[j];
            }
        }
        n += 1;
    }
    if (n as usize) <= TABLE {
        return None;
    }
    Some((solve_wide(&a, &rhs, n)?, n))
}

/// The calibration's normal matrix.
type Normal = [[f32; UNKNOWNS]; UNKNOWNS];

/// A solved calibration: the solution, the inverse of the normal matrix and the unknowns
/// fitted (the higher harmonics' rows and columns zero where they were not), and the inverse
/// of the offset's and table's own block (what the directions driven give the table alone:
/// the span).
struct Wide {
    x: [f32; UNKNOWNS],
    inv: Normal,
    unknowns: usize,
    table_inv: [[f32; TABLE]; TABLE],
}

/// The normal equations `a x = rhs` of `n` bearings solved with the higher harmonics, or,
/// where the directions driven cannot hold them apart from the table (a short arc; too few
/// bearings), with the table alone: such a drive's span is far below [`MIN_SPAN`] and it
/// gives the offset only.
fn solve_wide(a: &Normal, rhs: &[f32; UNKNOWNS], n: u32) -> Option<Wide> {
    let table: [[f32; TABLE]; TABLE] = core::array::from_fn(|i| core::array::from_fn(|j| a[i][j]));
    let table_inv = crate::linalg::inverse_scaled(&table)?;
    if n as usize > UNKNOWNS
        && let Some(inv) = crate::linalg::inverse_scaled(a)
    {
        return Some(Wide {
            x: crate::linalg::mat_vec(&inv, rhs),
            inv,
            unknowns: UNKNOWNS,
            table_inv,
        });
    }
    // The table alone, embedded in the wide unknowns.
    let mut x = [0.0f32; UNKNOWNS];
    let mut inv = [[0.0f32; UNKNOWNS]; UNKNOWNS];
    for i in 0..TABLE {
        inv[i][..TABLE].copy_from_slice(&table_inv[i]);
        x[i] = (0..TABLE).map(|j| table_inv[i][j] * rhs[j]).sum();
    }
    Some(Wide {
        x,
        inv,
        unknowns: TABLE,
        table_inv,
    })
}

/// Measure the offset and the direction-dependent error of one unit from `bearings` (time
/// order) of a transmitter at `emitter`, `relative[k]` the bearing k relative to the antenna
/// (the vehicle's course: [`relative_to_course`](super::relative_to_course)). Robustly as
/// [`calibrate`]: a first fit about the residuals' median, then the fit of the bearings within
/// 3.5 robust sigmas of it; the covariance sigma^2 / N_eff times the inverse information, N_eff
/// from the residuals' autocorrelation, the third and fourth harmonics integrated out
/// (`HIGHER` terms). A drive that does not turn still gives its offset and
/// a `span` below [`MIN_SPAN`]; then the offset-only [`calibrate`] is the one to use.
pub fn calibrate_direction(
    bearings: &[Bearing],
    relative: &[f32],
    emitter: [f32; 2],
) -> Result<DirectionCalibration, Error> {
    check_finite(&emitter)?;
    if relative.len() != bearings.len() {
        return Err(Error::OutOfRange);
    }
    // The median residual: a centre that keeps every residual away from the wrap.
    let centre = calibrate(bearings, emitter)?.bias;
    let all = |_: f32, _: f32| true;
    let (Wide { x: first, .. }, _) = fit_direction(bearings, relative, &emitter, centre, all)
        .ok_or(Error::TooFewMeasurements)?;
    let misfit = |r: f32, phi: f32| wrap(r - crate::linalg::dot(&first, &regressors(phi)));
    // The robust spread of the first fit's misfits, from a strided sample (no allocator).
    const CAP: usize = 512;
    let stride = bearings.len().div_ceil(CAP).max(1);
    let mut sample = [0.0f32; CAP];
    let mut k = 0;
    for (b, &phi) in bearings.iter().zip(relative).step_by(stride) {
        if b.check().is_ok()
            && phi.is_finite()
            && let Some(slot) = sample.get_mut(k)
        {
            *slot = libm::fabsf(misfit(wrap(b.residual(&emitter) - centre), phi));
            k += 1;
        }
    }
    let spread = (1.4826 * super::super::order::median(&mut sample[..k])).max(1e-5);
    let inside = |r: f32, phi: f32| libm::fabsf(misfit(r, phi)) <= CALIBRATION_CUT * spread;
    let (
        Wide {
            x,
            inv,
            unknowns,
            table_inv,
        },
        n,
    ) = fit_direction(bearings, relative, &emitter, centre, inside)
        .ok_or(Error::TooFewMeasurements)?;
    // The fit's residuals, time order, for the noise and its correlation.
    let kept = || {
        bearings
            .iter()
            .zip(relative)
            .filter(|(b, phi)| b.check().is_ok() && phi.is_finite())
            .map(move |(b, &phi)| (wrap(b.residual(&emitter) - centre), phi))
            .filter(move |&(r, phi)| inside(r, phi))
            .map(move |(r, phi)| r - crate::linalg::dot(&x, &regressors(phi)))
    };
    let ss: f32 = kept().map(|r| r * r).sum();
    let sigma = libm::sqrtf(ss / (n as usize - unknowns) as f32 / 0.9953);
    let effective =
        super::super::consistency::effective_count(kept().map(|r| r / sigma.max(1e-9)), n);
    let scale = sigma * sigma * n as f32 / effective.max(1.0);
    let covariance: [[f32; HARMONICS]; HARMONICS] =
        core::array::from_fn(|i| core::array::from_fn(|j| scale * inv[i + 1][j + 1]));
    // The span is the table's own: the harmonics' block of the inverse per bearing of the
    // offset and table alone (what the directions driven give the table; its largest
    // eigenvalue is 1 / span).
    let block: [[f32; HARMONICS]; HARMONICS] =
        core::array::from_fn(|i| core::array::from_fn(|j| n as f32 * table_inv[i + 1][j + 1]));
    let span = 1.0 / crate::linalg::largest_eigenvalue(&block);
    let bias = wrap(centre + x[0]);
    let sd = libm::sqrtf(scale * inv[0][0]);
    let coefficients = [x[1], x[2], x[3], x[4]];
    check_finite(&[bias, sd, sigma, span])?;
    check_finite(&coefficients)?;
    Ok(DirectionCalibration {
        offset: Calibration {
            bias,
            sd,
            sigma,
            used: n,
            rejected: bearings.len() as u32 - n,
            effective,
        },
        coefficients,
        covariance,
        span,
    })
}
