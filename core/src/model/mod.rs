//! State-space models: how a state moves and what a measurement says about it.

pub mod bearing;
pub mod biased;
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
    /// Move every state forward to the time of `z`: the filters' other hot loop. Models
    /// override it to draw their noise in bulk ([`crate::random::Lanes`]).
    fn propagate_all<R: Rng + ?Sized>(
        &self,
        states: &mut [[f32; D]],
        z: &Self::Measurement,
        rng: &mut R,
    ) {
        for x in states.iter_mut() {
            self.propagate(x, z, rng);
        }
    }
    /// Log-likelihood of `z` given the state, under `lik`.
    fn ln_likelihood<L: Likelihood>(&self, x: &[f32; D], z: &Self::Measurement, lik: &L) -> f32;
    /// The log-likelihood of `z` as a function of the state alone: what the swarms evaluate,
    /// thousands of times per step. Models override it to do the per-measurement work once (a
    /// bearing's sine and cosine); it must agree with [`Model::ln_likelihood`] to a few ulp.
    fn fitness<'a, L: Likelihood>(
        &'a self,
        z: &'a Self::Measurement,
        lik: &'a L,
    ) -> impl Fn(&[f32; D]) -> f32 + 'a {
        move |x| self.ln_likelihood(x, z, lik)
    }
    /// Add the log-likelihood of `z` to each particle's log-weight: the filters' hot loop.
    /// Models override it to hoist per-measurement work (a bearing's sine and cosine) out of
    /// the loop; the result must agree with [`Model::ln_likelihood`] to a few ulp.
    fn add_ln_likelihoods<L: Likelihood>(
        &self,
        states: &[[f32; D]],
        z: &Self::Measurement,
        lik: &L,
        log_weights: &mut [f32],
    ) {
        for (x, lw) in states.iter().zip(log_weights.iter_mut()) {
            *lw += self.ln_likelihood(x, z, lik);
        }
    }
    /// Weigh every particle by `z` ([`Model::add_ln_likelihoods`]) and, for a model whose
    /// particles carry the sufficient statistics of a sub-state that enters the measurement
    /// linearly (a Rao-Blackwellised filter: a DF unit's offset, an RSSI power), condition
    /// those statistics on `z` in the same pass. The filters call this once per step, after
    /// any swarm move; the default only weighs.
    fn update_all<L: Likelihood>(
        &self,
        states: &mut [[f32; D]],
        z: &Self::Measurement,
        lik: &L,
        log_weights: &mut [f32],
    ) {
        self.add_ln_likelihoods(states, z, lik, log_weights);
    }
    /// Seconds of time from the previous measurement to `z`, for a model whose steps are time
    /// (a tracker's epochs): the roughening kernel is then owed per second of time
    /// ([`crate::roughen::KERNEL_PERIOD_S`]), not per resampling. `None` (the default): a step
    /// is not time, and every resampling is jittered by a full kernel.
    fn elapsed_s(&self, _z: &Self::Measurement) -> Option<f32> {
        None
    }

    /// Which state components the roughening kernel may jitter after resampling
    /// ([`crate::Roughening::apply_to`]): those the motion does not diversify itself (a still
    /// emitter's position, a constant parameter). A component the model keeps discrete (a
    /// motion mode) or drives with its own noise (a velocity) is left out. `covariance` is the
    /// weighted cloud's before the resampling. Default: every one.
    fn regularised(&self, _covariance: &[[f32; D]; D]) -> [bool; D] {
        [true; D]
    }
}
