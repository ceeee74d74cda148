//! Batch fixes: every bearing at once. The ML fix is the physical limit the sequential filters
//! are measured against; the CRLB says what no unbiased estimator can beat.

pub mod crlb;
pub mod ellipse;
pub mod init;
pub mod intersection;
pub mod ml;
pub mod ple;

use crate::error::Error;
use crate::model::bearing::Bearing;

/// A position fix with its covariance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fix {
    /// Emitter position (east, north), metres.
    pub position: [f32; 2],
    /// Covariance of the position, m^2 (the inverse Fisher information at the fix).
    pub covariance: [[f32; 2]; 2],
    /// Bearings that entered the fix.
    pub used: u32,
    /// Bearings skipped as unusable (non-finite, bad sigma).
    pub skipped: u32,
    /// Bearings whose final residual exceeds 3 sigma (outliers, down-weighted by a robust loss).
    pub outliers: u32,
    /// Solver iterations (0 for closed-form fixes).
    pub iterations: u32,
}

/// The usable bearings of a slice, their count and their centroid.
///
/// Every batch fix starts here: it checks the geometry once and reports the degenerate cases
/// (too few bearings, a vehicle that never moved, all bearings parallel) as typed errors. The
/// centroid of the vehicle positions becomes the working origin, which keeps f32 sums well
/// conditioned kilometres away from the local origin.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Geometry {
    pub used: u32,
    pub skipped: u32,
    pub origin: [f32; 2],
}

/// Vehicle positions closer together than this (metres) count as one position.
const STATIONARY_M: f32 = 0.01;
/// Bearings whose directions differ by less than this (sine of the angle) count as parallel.
const PARALLEL_SIN: f32 = 1e-4;

pub(crate) fn geometry(bearings: &[Bearing]) -> Result<Geometry, Error> {
    let mut used = 0u32;
    let mut sum = [0.0f64; 2];
    let mut first: Option<Bearing> = None;
    let mut moved = false;
    let mut turned = false;
    for b in bearings.iter().filter(|b| b.check().is_ok()) {
        used += 1;
        sum[0] += b.vehicle[0] as f64;
        sum[1] += b.vehicle[1] as f64;
        match first {
            None => first = Some(*b),
            Some(f) => {
                let dx = b.vehicle[0] - f.vehicle[0];
                let dy = b.vehicle[1] - f.vehicle[1];
                moved |= libm::hypotf(dx, dy) > STATIONARY_M;
                turned |= libm::fabsf(libm::sinf(b.theta - f.theta)) > PARALLEL_SIN;
            }
        }
    }
    let skipped = bearings.len() as u32 - used;
    if used < 2 {
        return Err(Error::TooFewMeasurements);
    }
    if !moved {
        return Err(Error::StationaryVehicle);
    }
    if !turned {
        return Err(Error::ParallelBearings);
    }
    let origin = [(sum[0] / used as f64) as f32, (sum[1] / used as f64) as f32];
    Ok(Geometry {
        used,
        skipped,
        origin,
    })
}

/// Usable bearings only.
pub(crate) fn usable(bearings: &[Bearing]) -> impl Iterator<Item = &Bearing> {
    bearings.iter().filter(|b| b.check().is_ok())
}
