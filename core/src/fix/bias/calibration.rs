//! A unit's offset measured on a drive past a transmitter at a known position.

use super::BiasPrior;
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
