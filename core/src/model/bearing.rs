//! The static emitter seen from a moving vehicle: one bearing per vehicle position.
//!
//! Conventions (docs/src/conventions.md): local East-North metres; the model bearing is the mathematical
//! angle theta = atan2(yT - y, xT - x) from +x, counter-clockwise; a DF unit reports the azimuth
//! gamma clockwise from true north, theta = pi/2 - gamma. Every residual is wrapped to
//! (-pi, pi] before it reaches a likelihood, so a bearing near +-180 degrees is never an outlier.

use super::Model;
use crate::error::{Error, check_finite};
use crate::fastmath;
use crate::likelihood::Likelihood;
use crate::random;
use core::f32::consts::{FRAC_PI_2, PI, TAU};
use rand_core::Rng;

/// One bearing measurement in the local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bearing {
    /// Vehicle position (east, north), metres.
    pub vehicle: [f32; 2],
    /// Measured mathematical angle theta (radians from east, counter-clockwise).
    pub theta: f32,
    /// Standard deviation of the bearing noise, radians (> 0).
    pub sigma: f32,
}

impl Bearing {
    /// A bearing from a DF azimuth (radians clockwise from north).
    pub fn from_azimuth(vehicle: [f32; 2], azimuth: f32, sigma: f32) -> Self {
        Self {
            vehicle,
            theta: azimuth_to_theta(azimuth),
            sigma,
        }
    }

    /// `Ok` when every field is finite and sigma is positive.
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&[self.vehicle[0], self.vehicle[1], self.theta, self.sigma])?;
        if self.sigma > 0.0 && libm::fabsf(self.theta) <= 4.0 * PI {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }

    /// Unit direction (cos theta, sin theta) of the bearing line.
    pub fn direction(&self) -> [f32; 2] {
        [libm::cosf(self.theta), libm::sinf(self.theta)]
    }

    /// Wrapped residual z - h(p) of an emitter hypothesis `p`.
    #[inline]
    pub fn residual(&self, p: &[f32; 2]) -> f32 {
        wrap(self.theta - predicted(p, &self.vehicle))
    }
}

/// Wrap an angle to (-pi, pi]. Non-finite input stays non-finite (callers check first).
///
/// The IEEE remainder is exact for any finite input, so even 1e30 wraps into range. One turn
/// out (a residual of a checked bearing almost always is) one turn taken or added gives the
/// same exact answer far cheaper: the difference of two floats within a factor of two of each
/// other is exact (Sterbenz), and the answer in range is unique (a whole turn's zero may differ
/// in sign, which nothing downstream reads).
#[inline]
pub fn wrap(a: f32) -> f32 {
    if (-PI..=PI).contains(&a) && a != -PI {
        return a;
    }
    let w = if a > PI { a - TAU } else { a + TAU };
    if w > -PI && w <= PI {
        return w;
    }
    let w = libm::remainderf(a, TAU);
    if w <= -PI { w + TAU } else { w }
}

/// The model bearing of an emitter at `p` from a vehicle at `v`: atan2, never the quadrant-losing
/// arctan of the seeds.
#[inline]
pub fn predicted(p: &[f32; 2], v: &[f32; 2]) -> f32 {
    libm::atan2f(p[1] - v[1], p[0] - v[0])
}

/// DF azimuth (clockwise from north) to model angle (counter-clockwise from east), wrapped.
#[inline]
pub fn azimuth_to_theta(azimuth: f32) -> f32 {
    wrap(FRAC_PI_2 - azimuth)
}

/// Model angle back to a DF azimuth in [0, 2 pi).
#[inline]
pub fn theta_to_azimuth(theta: f32) -> f32 {
    let a = wrap(FRAC_PI_2 - theta);
    if a < 0.0 { a + TAU } else { a }
}

/// The static emitter: state [x, y], bearing measurements, an optional random-walk jitter
/// (the seeds' "process noise", variance in m^2 per step; 0 for a truly static model).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticEmitter {
    /// Random-walk variance added per step, m^2.
    pub process_var: f32,
}

impl Model<2> for StaticEmitter {
    type Measurement = Bearing;

    fn check(&self, z: &Bearing) -> Result<(), Error> {
        if !(self.process_var >= 0.0 && self.process_var.is_finite()) {
            return Err(Error::OutOfRange);
        }
        z.check()
    }

    #[inline]
    fn propagate<R: Rng + ?Sized>(&self, x: &mut [f32; 2], _z: &Bearing, rng: &mut R) {
        if self.process_var > 0.0 {
            let s = libm::sqrtf(self.process_var);
            x[0] += s * random::normal(rng);
            x[1] += s * random::normal(rng);
        }
    }

    /// Two particles (four coordinates) per draw of the four-lane generator.
    fn propagate_all<R: Rng + ?Sized>(&self, states: &mut [[f32; 2]], z: &Bearing, rng: &mut R) {
        if !(self.process_var > 0.0) {
            return;
        }
        let s = libm::sqrtf(self.process_var);
        let mut lanes = random::Lanes::seed_from(rng);
        let mut pairs = states.chunks_exact_mut(2);
        for pair in &mut pairs {
            let n = lanes.normals(rng);
            pair[0][0] += s * n[0];
            pair[0][1] += s * n[1];
            pair[1][0] += s * n[2];
            pair[1][1] += s * n[3];
        }
        for x in pairs.into_remainder() {
            self.propagate(x, z, rng);
        }
    }
    /// One particle at a time (the swarm moves): the branch-free atan2 here too, so a swarm's
    /// thousands of evaluations per step avoid libm's branchy one.
    #[inline]
    fn ln_likelihood<L: Likelihood>(&self, x: &[f32; 2], z: &Bearing, lik: &L) -> f32 {
        let h = fastmath::atan2(x[1] - z.vehicle[1], x[0] - z.vehicle[0]);
        lik.ln(wrap(z.theta - h), z.sigma)
    }

    /// The residual z - h(p) as one angle: rotate the vehicle-to-particle vector by -theta and
    /// take its angle, already in [-pi, pi] (no wrap), with the branch-free atan2. One sine and
    /// cosine per measurement.
    fn fitness<'a, L: Likelihood>(
        &'a self,
        z: &'a Bearing,
        lik: &'a L,
    ) -> impl Fn(&[f32; 2]) -> f32 + 'a {
        let (s, c) = fastmath::sincos(z.theta);
        // A copy, not a reference into `z`: the loops that call this can then keep it in
        // registers instead of reloading it after every store.
        let [vx, vy] = z.vehicle;
        let ln = lik.ln_at(z.sigma);
        move |p| {
            let (dx, dy) = (p[0] - vx, p[1] - vy);
            ln(fastmath::atan2(s * dx - c * dy, c * dx + s * dy))
        }
    }

    fn add_ln_likelihoods<L: Likelihood>(
        &self,
        states: &[[f32; 2]],
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

    #[test]
    fn wrap_range() {
        for a in [-10.0f32, -PI, -3.0, 0.0, 3.0, PI, 3.2, 7.0, 100.0] {
            let w = wrap(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            assert!(libm::fabsf(libm::sinf(w) - libm::sinf(a)) < 1e-4);
        }
        assert_eq!(wrap(-PI), PI);
    }

    #[test]
    fn one_turn_out_wraps_as_the_remainder_does() {
        let remainder = |a: f32| {
            let w = libm::remainderf(a, TAU);
            if w <= -PI { w + TAU } else { w }
        };
        let mut a = -5.0 * PI;
        while a < 5.0 * PI {
            for x in [a, a.next_up(), a.next_down()] {
                assert_eq!(wrap(x), remainder(x), "{x}");
            }
            a += PI / 7.0;
        }
        for a in [
            3.0 * PI,
            -3.0 * PI,
            4.0 * PI,
            -4.0 * PI,
            TAU,
            -TAU,
            PI.next_up(),
        ] {
            for x in [a, a.next_up(), a.next_down()] {
                // The same value; a whole turn gives +0 where the remainder gives -0.
                assert_eq!(wrap(x), remainder(x), "{x}");
            }
        }
    }

    #[test]
    fn azimuth_conventions() {
        // North is +y, east is +x.
        assert!((azimuth_to_theta(0.0) - FRAC_PI_2).abs() < 1e-6);
        assert!(azimuth_to_theta(FRAC_PI_2).abs() < 1e-6);
        assert!((theta_to_azimuth(PI) - 3.0 * FRAC_PI_2).abs() < 1e-5);
        // Quadrant kept: an emitter south-west of the vehicle.
        let t = predicted(&[-1.0, -1.0], &[0.0, 0.0]);
        assert!((t + 3.0 * PI / 4.0).abs() < 1e-6);
    }

    #[test]
    fn residual_wraps_across_the_cut() {
        let b = Bearing {
            vehicle: [0.0, 0.0],
            theta: PI - 0.01,
            sigma: 0.02,
        };
        let r = b.residual(&[-100.0, -1.0]);
        assert!(libm::fabsf(r) < 0.03, "{r}");
    }
}
