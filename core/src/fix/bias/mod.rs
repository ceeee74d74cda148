//! A constant bearing offset per DF station, estimated with the position.
//!
//! Every real DF antenna has one: an antenna mounted a few degrees off the vehicle's axis, an
//! array whose reference element is not where the software thinks, a fixed station's array
//! not quite aligned to north (1-5 degrees for pseudo-Doppler units, 9-12 for some KrakenSDR
//! set-ups: docs/src/field.md, "Mounting offset"). Ignored, an offset b moves the fix by about
//! r b (5 degrees at 2 km: 175 m) while the ellipse stays small. Here the model is z_k =
//! atan2(emitter - s_k) + b_{station(k)} + noise and the unknowns are [x, y, b_0 .. b_{S-1}]:
//! one offset per station, for any number of stations (the caller's [`StationSlot`] table,
//! one row per station index; the normal equations are an arrow, each offset eliminated on
//! its own: [`stations`](StationSlot)).
//!
//! Each offset has a Gaussian prior: by default mean 0 and sd [`DEFAULT_BIAS_SD`] (6 degrees,
//! so the 1-12 degrees real units show lie within two sd); sd 0 is a calibrated station (the
//! offset is fixed at the prior's mean); an infinite sd is no prior at all. A station's
//! unmodelled systematic error (its device class's, [`crate::fix::device`]) adds its variance
//! to the prior's ([`StationSlot::with_unmodelled`]): an error common to its bearings is its
//! offset's uncertainty, which no number of bearings averages away. A station that
//! cannot tell its offset from a cross-range shift (a straight road, a short arc:
//! docs/src/field.md's inscribed-angle argument; a fixed station, which sees the emitter from
//! one direction only: docs/src/networks.md) leans on its prior, and the position covariance,
//! the marginal with every offset integrated out, grows to show the prior's share; where a
//! drive surrounds the emitter the offset is measured to sigma / sqrt(N) and costs the
//! position nothing.
//!
//! Levenberg-Marquardt on sum rho(r_k / sigma_k) + sum (b - mu)^2 / (2 tau^2) with any
//! [`Likelihood`](crate::likelihood::Likelihood)'s IRLS weights; the reduced 2 x 2 position
//! system is scaled to unit diagonal before it is inverted, since in f32 the position terms
//! (1 / (sigma r)^2) and the offset terms (1 / sigma^2) differ by the square of the range.

mod bound;
mod calibration;
mod direction;
mod prior;
mod problem;
mod profile_likelihood;
mod rival;
mod solve;
mod stations;
mod summary;
#[cfg(test)]
mod tests;

pub use bound::{BiasedCrlb, crlb, crlb_stations, information};
pub use calibration::{
    Calibration, DirectionCalibration, MIN_SPAN, calibrate, calibrate_direction,
};
pub use direction::{DirectionPrior, HARMONICS, harmonics, relative_to_course};
pub use prior::{BiasPrior, CONTRADICTED_Z, KNOWN_SD};
pub use profile_likelihood::{CIRCLE_STEPS, OffsetCircle, ProfilePoint, offset_circle, profile};
pub use rival::no_rival;
pub use solve::{BiasedFix, BiasedOptions, Start, StartOffsets, ml, ml_sources, refit};
pub use stations::{FRONT_STEP_M, StationSlot};

use crate::model::bearing::Bearing;

/// Default prior sd of an uncalibrated unit's offset: 6 degrees, radians.
pub const DEFAULT_BIAS_SD: f32 = 6.0 * core::f32::consts::PI / 180.0;

/// A bearing together with the DF station that took it.
pub trait Sighting {
    /// The bearing.
    fn bearing(&self) -> &Bearing;
    /// Index of its DF station in the caller's station table (a sighting of a station beyond
    /// the table is not used).
    fn station(&self) -> usize {
        0
    }
    /// The bearing relative to its antenna's front (counter-clockwise, radians), the regressor
    /// of the station's direction-dependent error ([`DirectionPrior`]): by default an antenna
    /// facing north (a fixed array's usual reference).
    fn relative(&self) -> f32 {
        crate::model::bearing::wrap(self.bearing().theta - core::f32::consts::FRAC_PI_2)
    }
}

impl Sighting for Bearing {
    fn bearing(&self) -> &Bearing {
        self
    }
}
