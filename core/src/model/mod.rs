//! State-space models: how a state moves and what a measurement says about it.

pub mod bearing;
pub mod rssi;
pub mod ungm;

use crate::error::Error;
use crate::likelihood::Likelihood;
use rand_core::Rng;

/// A state-space model over a `D`-dimensional state, as the particle filters need it.
pub trait Model<const D: usize> {
    /// One measurement.
    type Measurement;
    /// `Ok` when the measurement is usable (finite, in range).
    fn check(&self, z: &Self::Measurement) -> Result<(), Error>;
    /// Move one state forward to the time of measurement `z`, process noise included (the
    /// measurement carries its time: the UNGM's step index, say).
    fn propagate<R: Rng + ?Sized>(&self, x: &mut [f32; D], z: &Self::Measurement, rng: &mut R);
    /// Log-likelihood of `z` given the state, under `lik`.
    fn ln_likelihood<L: Likelihood>(&self, x: &[f32; D], z: &Self::Measurement, lik: &L) -> f32;
}
