//! How the emitter moves: still, or nearly constant velocity, with switches between the two.
//!
//! Moving: white-noise acceleration with spectral density q = `accel_sd`^2 (m^2/s^3) on each
//! axis, so over dt the position and velocity of one axis gain noise of covariance
//! q [[dt^3/3, dt^2/2], [dt^2/2, dt]] (the continuous-time nearly-constant-velocity model).
//! Still: the position does not change and the velocity is zero. A still emitter starts to
//! move with probability 1 - exp(-`start_rate` dt) per step, its velocity then drawn from
//! N(0, `start_speed_sd`^2) on each axis; a moving one stops with 1 - exp(-`stop_rate` dt)
//! (a jump-Markov pair, as an IMM mixes them: Blom and Bar-Shalom 1988).

use crate::error::{Error, check_finite};

/// The motion model's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// Acceleration sd of the moving model, m/s^2 (q = accel_sd^2, m^2/s^3, per axis).
    pub accel_sd: f32,
    /// Still to moving, per second.
    pub start_rate: f32,
    /// Moving to still, per second.
    pub stop_rate: f32,
    /// Velocity sd of an emitter that starts to move, m/s per axis.
    pub start_speed_sd: f32,
}

impl Motion {
    /// Outdoors (a drone, a vehicle, an animal): 1 m/s^2 of acceleration (a 90 degree turn at
    /// 12 m/s takes about 20 s), a switch once in ten minutes each way, 10 m/s at a start
    /// (chosen).
    pub const OUTDOOR: Motion = Motion {
        accel_sd: 1.0,
        start_rate: 1.0 / 600.0,
        stop_rate: 1.0 / 600.0,
        start_speed_sd: 10.0,
    };

    /// Indoors (a walking person with a tag): 0.5 m/s^2, a switch once in a minute each way,
    /// 1 m/s at a start (chosen).
    pub const INDOOR: Motion = Motion {
        accel_sd: 0.5,
        start_rate: 1.0 / 60.0,
        stop_rate: 1.0 / 60.0,
        start_speed_sd: 1.0,
    };

    /// `Ok` when every setting is a finite number >= 0 and the acceleration and start speed
    /// are positive.
    pub fn check(&self) -> Result<(), Error> {
        check_finite(&[
            self.accel_sd,
            self.start_rate,
            self.stop_rate,
            self.start_speed_sd,
        ])?;
        if self.accel_sd > 0.0
            && self.start_speed_sd > 0.0
            && self.start_rate >= 0.0
            && self.stop_rate >= 0.0
        {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }

    /// Spectral density q of the acceleration, m^2/s^3.
    pub fn q(&self) -> f32 {
        self.accel_sd * self.accel_sd
    }

    /// Probabilities over `dt` seconds that a still emitter starts and a moving one stops.
    pub fn switches(&self, dt: f32) -> (f32, f32) {
        let p = |rate: f32| 1.0 - libm::expf(-rate * dt);
        (p(self.start_rate), p(self.stop_rate))
    }

    /// The per-axis noise of a moving step over `dt`, q [[dt^3/3, dt^2/2], [dt^2/2, dt]]: its
    /// covariance entries (position, cross, velocity).
    pub fn axis_noise(&self, dt: f32) -> [f32; 3] {
        let q = self.q();
        [q * dt * dt * dt / 3.0, q * dt * dt / 2.0, q * dt]
    }

    /// The lower Cholesky factor [l11, l21, l22] of [`Motion::axis_noise`]: position noise
    /// l11 n1, velocity noise l21 n1 + l22 n2. In closed form, l11 = sqrt(q dt^3 / 3),
    /// l21 = sqrt(3 q dt) / 2, l22 = sqrt(q dt) / 2.
    pub fn axis_factor(&self, dt: f32) -> [f32; 3] {
        let qdt = self.q() * dt.max(0.0);
        let s = libm::sqrtf(qdt);
        [
            s * dt.max(0.0) / libm::sqrtf(3.0),
            0.5 * libm::sqrtf(3.0) * s,
            0.5 * s,
        ]
    }

    /// The moving model's transition over `dt` and its noise, on a `D`-component state of
    /// this module's layout (static parameters and the mode carried unchanged): (F, Q).
    pub fn moving<const D: usize>(&self, dt: f32) -> ([[f32; D]; D], [[f32; D]; D]) {
        let mut f = identity::<D>();
        f[0][2] = dt;
        f[1][3] = dt;
        let [pp, pv, vv] = self.axis_noise(dt);
        let mut q = [[0.0f32; D]; D];
        for a in 0..2 {
            q[a][a] = pp;
            q[a][a + 2] = pv;
            q[a + 2][a] = pv;
            q[a + 2][a + 2] = vv;
        }
        (f, q)
    }

    /// The still model's transition: the position kept, the velocity zeroed (F, with no
    /// noise).
    pub fn still<const D: usize>(&self) -> [[f32; D]; D] {
        let mut f = identity::<D>();
        f[2][2] = 0.0;
        f[3][3] = 0.0;
        f
    }
}

/// The D x D identity.
pub(crate) fn identity<const D: usize>() -> [[f32; D]; D] {
    core::array::from_fn(|i| core::array::from_fn(|j| if i == j { 1.0 } else { 0.0 }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_factor_reproduces_the_noise() {
        let m = Motion::OUTDOOR;
        for dt in [0.01f32, 0.1, 1.0, 7.0] {
            let [l11, l21, l22] = m.axis_factor(dt);
            let [pp, pv, vv] = m.axis_noise(dt);
            assert!((l11 * l11 - pp).abs() <= 1e-5 * pp.max(1e-6), "{dt}");
            assert!((l11 * l21 - pv).abs() <= 1e-5 * pv.max(1e-6), "{dt}");
            assert!(
                (l21 * l21 + l22 * l22 - vv).abs() <= 1e-5 * vv.max(1e-6),
                "{dt}"
            );
        }
    }

    #[test]
    fn switches_grow_with_time_and_settings_are_checked() {
        let m = Motion::INDOOR;
        let (a, b) = m.switches(1.0);
        let (c, d) = m.switches(10.0);
        assert!(a > 0.0 && c > a && d > b);
        assert_eq!(m.switches(0.0), (0.0, 0.0));
        assert!(m.check().is_ok());
        let bad = Motion {
            accel_sd: f32::NAN,
            ..m
        };
        assert_eq!(bad.check(), Err(Error::NonFinite));
        let bad = Motion {
            start_rate: -1.0,
            ..m
        };
        assert_eq!(bad.check(), Err(Error::OutOfRange));
    }
}
