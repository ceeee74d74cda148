//! Batch fixes: every bearing at once. The ML fix is the physical limit the sequential filters
//! are measured against; the CRLB says what no unbiased estimator can beat.

pub mod bias;
pub mod channel;
pub mod consistency;
pub mod crlb;
pub mod device;
pub mod ellipse;
pub mod evidence;
pub mod init;
pub mod intersection;
pub mod locate;
pub mod ml;
pub mod noise;
pub mod observation;
pub mod order;
pub mod pcrb;
pub mod ple;
pub mod reach;
pub mod robust;
pub mod window;

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
    let mut g = geometry_of(usable(bearings))?;
    g.skipped = bearings.len() as u32 - g.used;
    Ok(g)
}

/// [`geometry`] of bearings already filtered for use (`skipped` is left 0 for the caller).
pub(crate) fn geometry_of<'a>(
    bearings: impl Iterator<Item = &'a Bearing>,
) -> Result<Geometry, Error> {
    let mut used = 0u32;
    let mut sum = [0.0f64; 2];
    let mut first: Option<Bearing> = None;
    let mut moved = false;
    let mut turned = false;
    for b in bearings {
        used += 1;
        sum[0] += b.vehicle[0] as f64;
        sum[1] += b.vehicle[1] as f64;
        match first {
            None => first = Some(*b),
            // Each test once it is passed is not made again: every solve's set-up (hundreds a
            // network's fix) walks its bearings through here.
            Some(f) => {
                if !moved {
                    let dx = b.vehicle[0] - f.vehicle[0];
                    let dy = b.vehicle[1] - f.vehicle[1];
                    moved = libm::hypotf(dx, dy) > STATIONARY_M;
                }
                if !turned {
                    turned = libm::fabsf(libm::sinf(b.theta - f.theta)) > PARALLEL_SIN;
                }
            }
        }
    }
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
        skipped: 0,
        origin,
    })
}

/// Usable bearings only.
pub(crate) fn usable(bearings: &[Bearing]) -> impl Iterator<Item = &Bearing> {
    bearings.iter().filter(|b| b.check().is_ok())
}

#[cfg(test)]
mod tests {
    use super::crlb::crlb;
    use super::ml::{MlOptions, ml};
    use super::ple::{ple, wiv};
    use crate::error::Error;
    use crate::likelihood::{Gaussian, Huber};
    use crate::model::bearing::{Bearing, predicted};

    fn exact(vehicles: &[[f32; 2]], e: [f32; 2]) -> [Bearing; 8] {
        core::array::from_fn(|i| {
            let v = vehicles[i % vehicles.len()];
            Bearing {
                vehicle: v,
                theta: predicted(&e, &v),
                sigma: 0.02,
            }
        })
    }

    const ROUTE: [[f32; 2]; 8] = [
        [0.0, 0.0],
        [50.0, 0.0],
        [100.0, 0.0],
        [150.0, 0.0],
        [200.0, 0.0],
        [200.0, 50.0],
        [200.0, 100.0],
        [200.0, 150.0],
    ];

    #[test]
    fn noise_free_fixes_land_on_the_emitter() {
        let e = [1200.0, 800.0];
        let bs = exact(&ROUTE, e);
        for (name, f) in [
            ("ple", ple(&bs)),
            ("wiv", wiv(&bs, 3)),
            ("ml", ml(&bs, None, &Gaussian, MlOptions::default())),
            (
                "huber",
                ml(&bs, None, &Huber::default(), MlOptions::default()),
            ),
        ] {
            let p = f.unwrap().position;
            let err = libm::hypotf(p[0] - e[0], p[1] - e[1]);
            // Within 2 m of the emitter 1.4 km away: a loose bound, f32 round-off leaves
            // millimetres here. (The bias-compensated PLE is left out: on noise-free bearings
            // it still subtracts the bias that noise would cause.)
            assert!(err < 2.0, "{name}: {p:?}");
        }
    }

    #[test]
    fn degenerate_geometries_are_named() {
        let e = [1200.0, 800.0];
        let one = &exact(&ROUTE, e)[..1];
        assert_eq!(
            ml(one, None, &Gaussian, MlOptions::default()),
            Err(Error::TooFewMeasurements)
        );
        let parked = exact(&[[5.0, 5.0]], e);
        assert_eq!(ple(&parked), Err(Error::StationaryVehicle));
        assert_eq!(
            ml(&parked, None, &Gaussian, MlOptions::default()),
            Err(Error::StationaryVehicle)
        );
        // Driving straight at the emitter: every bearing is the same line.
        let toward: [[f32; 2]; 4] = [[0.0, 0.0], [120.0, 80.0], [240.0, 160.0], [360.0, 240.0]];
        let parallel = exact(&toward, e);
        assert_eq!(ple(&parallel), Err(Error::ParallelBearings));
        assert_eq!(wiv(&parallel, 3), Err(Error::ParallelBearings));
        let no_range = crlb(&e, &parallel);
        assert_eq!(no_range, Err(Error::DegenerateGeometry));
    }

    #[test]
    fn bad_bearings_are_skipped_not_fatal() {
        let e = [1200.0, 800.0];
        let mut bs = exact(&ROUTE, e);
        bs[2].theta = f32::NAN;
        bs[5].sigma = -1.0;
        let f = ml(&bs, None, &Gaussian, MlOptions::default()).unwrap();
        assert_eq!((f.used, f.skipped), (6, 2));
        assert!(libm::hypotf(f.position[0] - e[0], f.position[1] - e[1]) < 1.0);
    }
}
