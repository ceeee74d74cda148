//! The static emitter seen by a DF unit with a constant mounting offset: state [x, y, b].
//!
//! The unit reports z = atan2(emitter - vehicle) + b + noise; b is a random constant (it does
//! not move between steps), estimated with the position exactly as the batch fix does
//! ([`crate::fix::bias`]). A particle filter over this state needs a cloud that spans the
//! offset's prior ([`crate::fix::init::initial_biased_particles`]); where the drive cannot
//! observe b, the cloud keeps the prior's spread in b and, through it, the cross-range spread
//! an unknown offset implies.

use super::Model;
use super::bearing::{Bearing, wrap};
use crate::error::Error;
use crate::fastmath;
use crate::likelihood::Likelihood;
use crate::random;
use rand_core::Rng;

/// A static emitter and one unit's constant offset: state [x, y, b] (metres, metres, radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasedEmitter {
    /// Random-walk variance of the position per step, m^2 (0 for a truly static emitter).
    pub process_var: f32,
}

impl Model<3> for BiasedEmitter {
    type Measurement = Bearing;

    fn check(&self, z: &Bearing) -> Result<(), Error> {
        if !(self.process_var >= 0.0 && self.process_var.is_finite()) {
            return Err(Error::OutOfRange);
        }
        z.check()
    }

    #[inline]
    fn propagate<R: Rng + ?Sized>(&self, x: &mut [f32; 3], _z: &Bearing, rng: &mut R) {
        if self.process_var > 0.0 {
            let s = libm::sqrtf(self.process_var);
            x[0] += s * random::normal(rng);
            x[1] += s * random::normal(rng);
        }
    }

    #[inline]
    fn ln_likelihood<L: Likelihood>(&self, x: &[f32; 3], z: &Bearing, lik: &L) -> f32 {
        let h = fastmath::atan2(x[1] - z.vehicle[1], x[0] - z.vehicle[0]);
        lik.ln(wrap(z.theta - h - x[2]), z.sigma)
    }

    /// The residual z - h(p) as one angle from the vehicle-to-particle vector rotated by -z
    /// (one sine and cosine per measurement, as [`super::bearing::StaticEmitter`] does), then
    /// the particle's offset taken off and wrapped.
    fn fitness<'a, L: Likelihood>(
        &'a self,
        z: &'a Bearing,
        lik: &'a L,
    ) -> impl Fn(&[f32; 3]) -> f32 + 'a {
        let (s, c) = fastmath::sincos(z.theta);
        let [vx, vy] = z.vehicle;
        let ln = lik.ln_at(z.sigma);
        move |p| {
            let (dx, dy) = (p[0] - vx, p[1] - vy);
            ln(wrap(
                fastmath::atan2(s * dx - c * dy, c * dx + s * dy) - p[2],
            ))
        }
    }

    fn add_ln_likelihoods<L: Likelihood>(
        &self,
        states: &[[f32; 3]],
        z: &Bearing,
        lik: &L,
        log_weights: &mut [f32],
    ) {
        let fitness = self.fitness(z, lik);
        for (p, lw) in states.iter().zip(log_weights.iter_mut()) {
            *lw += fitness(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Gaussian;
    use crate::likelihood::GaussianUniform;
    use crate::model::bearing::predicted;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    #[test]
    fn fast_paths_agree_with_the_likelihood() {
        let m = BiasedEmitter { process_var: 0.0 };
        let mut rng = XorShiftRng::seed_from_u64(1);
        let states: [[f32; 3]; 64] = core::array::from_fn(|_| {
            [
                random::uniform_in(&mut rng, -3000.0, 3000.0),
                random::uniform_in(&mut rng, -3000.0, 3000.0),
                random::uniform_in(&mut rng, -0.3, 0.3),
            ]
        });
        for theta in [-3.1f32, -1.0, 0.0, 2.0, 3.1] {
            let z = Bearing {
                vehicle: [100.0, -50.0],
                theta,
                sigma: 0.03,
            };
            let lik = GaussianUniform { eps: 0.05 };
            let f = m.fitness(&z, &lik);
            let mut lw = [0.0f32; 64];
            m.add_ln_likelihoods(&states, &z, &lik, &mut lw);
            for (x, w) in states.iter().zip(lw) {
                let slow = m.ln_likelihood(x, &z, &lik);
                assert!((f(x) - slow).abs() < 1e-3 * slow.abs().max(1.0), "{x:?}");
                assert_eq!(w.to_bits(), f(x).to_bits());
            }
        }
    }

    #[test]
    fn the_offset_is_what_the_likelihood_sees() {
        let m = BiasedEmitter { process_var: 0.0 };
        let v = [0.0, 0.0];
        let p = [1000.0, 500.0];
        let z = Bearing {
            vehicle: v,
            theta: predicted(&p, &v) + 0.07,
            sigma: 0.01,
        };
        let right = m.ln_likelihood(&[p[0], p[1], 0.07], &z, &Gaussian);
        let wrong = m.ln_likelihood(&[p[0], p[1], 0.0], &z, &Gaussian);
        assert!(right > -1e-3 && wrong < -20.0, "{right} {wrong}");
        // The offset is a constant: propagation leaves it alone.
        let mut x = [p[0], p[1], 0.07];
        let mut rng = XorShiftRng::seed_from_u64(2);
        BiasedEmitter { process_var: 4.0 }.propagate(&mut x, &z, &mut rng);
        assert_eq!(x[2], 0.07);
        assert!(BiasedEmitter { process_var: -1.0 }.check(&z).is_err());
    }
}
