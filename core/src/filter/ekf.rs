//! Extended Kalman filter for the static emitter (seed 004's baseline): the bearing model
//! linearised at the current estimate, H = [-(yT - y)/d^2, (xT - x)/d^2], with the innovation
//! wrapped to (-pi, pi]. O(1) per step; biased when the prior is far from the truth, which is
//! the point seed 004 makes.

use super::{Estimate, Filter, StepStatus, moments};
use crate::error::Error;
use crate::model::bearing::{Bearing, predicted, wrap};
use rand_core::Rng;

/// EKF over the emitter position with optional random-walk process noise.
#[derive(Debug, Clone)]
pub struct BearingEkf {
    /// Random-walk variance per step, m^2 (0 for a static emitter).
    pub process_var: f32,
    state: Option<([f32; 2], [[f32; 2]; 2])>,
}

impl BearingEkf {
    /// A filter awaiting [`Filter::initialise`].
    pub fn new(process_var: f32) -> Self {
        Self {
            process_var,
            state: None,
        }
    }
}

impl Filter<2> for BearingEkf {
    type Measurement = Bearing;

    fn initialise<R: Rng + ?Sized>(
        &mut self,
        cloud: &[[f32; 2]],
        _rng: &mut R,
    ) -> Result<(), Error> {
        let m = moments(cloud)?;
        self.state = Some(m);
        Ok(())
    }

    fn step<R: Rng + ?Sized>(&mut self, z: &Bearing, _rng: &mut R) -> Result<Estimate<2>, Error> {
        let (mut x, mut p) = self.state.ok_or(Error::NotInitialised)?;
        z.check()?;
        p[0][0] += self.process_var;
        p[1][1] += self.process_var;
        let dx = x[0] - z.vehicle[0];
        let dy = x[1] - z.vehicle[1];
        let d2 = dx * dx + dy * dy;
        if !(d2 > 0.0) {
            return Err(Error::DegenerateGeometry);
        }
        let h = [-dy / d2, dx / d2];
        let ph = [
            p[0][0] * h[0] + p[0][1] * h[1],
            p[1][0] * h[0] + p[1][1] * h[1],
        ];
        let s = h[0] * ph[0] + h[1] * ph[1] + z.sigma * z.sigma;
        let k = [ph[0] / s, ph[1] / s];
        let innovation = wrap(z.theta - predicted(&x, &z.vehicle));
        x[0] += k[0] * innovation;
        x[1] += k[1] * innovation;
        // Joseph form: stays symmetric positive definite in f32.
        let a = [
            [1.0 - k[0] * h[0], -k[0] * h[1]],
            [-k[1] * h[0], 1.0 - k[1] * h[1]],
        ];
        let mut ap = [[0.0f32; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                ap[i][j] = a[i][0] * p[0][j] + a[i][1] * p[1][j];
            }
        }
        let r = z.sigma * z.sigma;
        let mut next = [[0.0f32; 2]; 2];
        for i in 0..2 {
            for j in 0..2 {
                next[i][j] = ap[i][0] * a[j][0] + ap[i][1] * a[j][1] + k[i] * r * k[j];
            }
        }
        if x.iter()
            .chain(next.iter().flatten())
            .any(|v| !v.is_finite())
        {
            return Err(Error::NonFinite);
        }
        p = next;
        self.state = Some((x, p));
        self.estimate()
    }

    fn estimate(&self) -> Result<Estimate<2>, Error> {
        let (mean, covariance) = self.state.ok_or(Error::NotInitialised)?;
        Ok(Estimate {
            mean,
            covariance,
            ess: 0.0,
            status: StepStatus::Updated,
        })
    }
}
