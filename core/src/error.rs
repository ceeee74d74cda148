//! Typed errors of the core: small, `Copy`, and printable on the MCU.

use core::fmt;

/// Why the core refused an input or could not give an estimate.
///
/// Every public entry point reports bad input through this enum instead of returning NaN or a
/// confident wrong answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Error {
    /// A value was NaN or infinite.
    NonFinite,
    /// A value was finite but outside its allowed range (a negative sigma, a zero capacity...).
    OutOfRange,
    /// Fewer usable measurements than the method needs (two bearings for a fix).
    TooFewMeasurements,
    /// Every bearing is (nearly) parallel: the lines do not cross, the range is unobservable.
    ParallelBearings,
    /// The vehicle never moved far enough for its bearings to cross.
    StationaryVehicle,
    /// Two bearings cross at less than the minimum angle.
    ShallowCrossing,
    /// The crossing point lies behind one of the vehicles.
    BehindVehicle,
    /// The geometry gives a singular or near-singular information matrix.
    DegenerateGeometry,
    /// An iterative solver did not converge.
    NotConverged,
    /// Every particle weight was zero or non-finite; the filter re-initialised from its prior.
    WeightCollapse,
    /// The filter was stepped before it was initialised.
    NotInitialised,
    /// The DF unit rated the bearing at or below the quality gate.
    LowQuality,
    /// The method does not apply here (a Kalman filter asked for particles, a particle count
    /// that is not compiled in, a batch fix asked to step).
    Unsupported,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let text = match self {
            Error::NonFinite => "a value is NaN or infinite",
            Error::OutOfRange => "a value is outside its allowed range",
            Error::TooFewMeasurements => "too few usable measurements",
            Error::ParallelBearings => "all bearings are parallel: the range is unobservable",
            Error::StationaryVehicle => "the vehicle never moved: bearings cannot cross",
            Error::ShallowCrossing => "the bearings cross at too shallow an angle",
            Error::BehindVehicle => "the bearings cross behind a vehicle position",
            Error::DegenerateGeometry => "the geometry is degenerate (singular information)",
            Error::NotConverged => "the solver did not converge",
            Error::WeightCollapse => "every particle weight vanished; re-initialised",
            Error::NotInitialised => "the filter was not initialised",
            Error::LowQuality => "the bearing's DF quality is below the gate",
            Error::Unsupported => "the method does not apply here",
        };
        f.write_str(text)
    }
}

impl core::error::Error for Error {}

#[cfg(feature = "defmt")]
impl defmt::Format for Error {
    fn format(&self, f: defmt::Formatter) {
        defmt::write!(f, "{}", defmt::Debug2Format(self))
    }
}

/// `Ok(())` when every value is finite.
pub(crate) fn check_finite(values: &[f32]) -> Result<(), Error> {
    if values.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite)
    }
}
