//! The Kalman baseline of the tracker: an interacting multiple model (Blom and Bar-Shalom
//! 1988) of two extended Kalman filters on the [`Mover`] state, one still and one nearly
//! constant velocity, each linearising the bearings and RSSI readings at its own estimate.
//!
//! Per update: the two models' estimates are mixed by the switch probabilities of
//! [`super::Motion`]; each predicts (still: the position kept; moving: F x, F P F^T + Q); each
//! folds in the epoch's measurements one at a time (H for a bearing: -(y - sy)/d^2,
//! (x - sx)/d^2 and 1 on its source's offset; for RSSI: -10 eta dx / (ln10 d^2), likewise for
//! y, 1 on the power offset and -10 log10(d / d0) on the exponent correction); the Gaussian
//! likelihoods of their innovations weigh the model probabilities. A measurement whose
//! innovation lies beyond [`ImmEkf::gate`] sigmas is skipped (chosen: 5, so one wild bearing
//! cannot throw the linearisation off). The still model's velocity is kept as the
//! distribution an emitter starting now would have, N(0, start speed^2): what the moving model
//! receives when it mixes the still one in.
//!
//! Cartesian EKFs are known to grow overconfident on bearings-only data (Aidala and Hammel
//! 1983); it is here as the baseline the particle filters are measured against.

use super::epoch::Epoch;
use super::mover::{Mover, bounce};
use super::{MODE, PARAMETERS};
use crate::error::Error;
use crate::filter::{Estimate, Filter, StepStatus, moments};
use crate::model::Model;
use crate::model::bearing::{predicted, wrap};
use crate::model::rssi::MIN_DISTANCE;
use rand_core::Rng;

/// One model's Gaussian.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Gauss<const D: usize> {
    mean: [f32; D],
    cov: [[f32; D]; D],
}

/// Model probabilities below this are held at it: a model never dies out completely, so a
/// start or a stop is seen within a few updates.
const MIN_PROBABILITY: f32 = 1e-6;

/// The IMM of a still and a moving EKF over the [`Mover`] layout.
#[derive(Debug, Clone)]
pub struct ImmEkf<const D: usize, const K: usize> {
    /// The motion and measurement model.
    pub model: Mover<K>,
    /// Innovations beyond this many sigmas are skipped.
    pub gate: f32,
    models: Option<[Gauss<D>; 2]>,
    /// P(still), P(moving).
    mu: [f32; 2],
    prior: Option<Gauss<D>>,
    last: Option<Estimate<D>>,
    evaluations: u64,
}

impl<const D: usize, const K: usize> ImmEkf<D, K> {
    /// A filter awaiting [`Filter::initialise`].
    pub fn new(model: Mover<K>) -> Self {
        Self {
            model,
            gate: 5.0,
            models: None,
            mu: [0.5, 0.5],
            prior: None,
            last: None,
            evaluations: 0,
        }
    }

    /// The components the filters estimate: position, velocity and the parameters' means
    /// (the layout's variance components stay zero: the filters' own covariance holds them).
    fn used(&self, i: usize) -> bool {
        i < 4 || self.model.layout.means().any(|m| m == i)
    }

    /// `g` as the still model holds it: the velocity a start would draw, uncorrelated.
    fn as_still(&self, mut g: Gauss<D>) -> Gauss<D> {
        let v = self.model.motion.start_speed_sd * self.model.motion.start_speed_sd;
        for a in 2..4 {
            g.mean[a] = 0.0;
            for j in 0..D {
                g.cov[a][j] = 0.0;
                g.cov[j][a] = 0.0;
            }
            g.cov[a][a] = v;
        }
        g
    }

    /// Keep only the estimated components (the mode and unused ones at zero variance).
    fn tidy(&self, mut g: Gauss<D>) -> Gauss<D> {
        for i in 0..D {
            if !self.used(i) {
                g.mean[i] = 0.0;
                for j in 0..D {
                    g.cov[i][j] = 0.0;
                    g.cov[j][i] = 0.0;
                }
            }
        }
        g
    }

    /// The two models mixed by the switch probabilities over `dt`: each model's start.
    fn mix(&self, m: &[Gauss<D>; 2], dt: f32) -> ([Gauss<D>; 2], [f32; 2]) {
        let (start, stop) = self.model.motion.switches(dt);
        // pi[i][j]: from model i to model j (0 still, 1 moving).
        let pi = [[1.0 - start, start], [stop, 1.0 - stop]];
        let mut out = *m;
        let mut c = [0.0f32; 2];
        for j in 0..2 {
            c[j] = pi[0][j] * self.mu[0] + pi[1][j] * self.mu[1];
            let w = [
                pi[0][j] * self.mu[0] / c[j].max(f32::MIN_POSITIVE),
                pi[1][j] * self.mu[1] / c[j].max(f32::MIN_POSITIVE),
            ];
            let from = if j == 0 {
                [m[0], self.as_still(m[1])]
            } else {
                [m[0], m[1]]
            };
            let mut mean = [0.0f32; D];
            for (g, wi) in from.iter().zip(w) {
                for k in 0..D {
                    mean[k] += wi * g.mean[k];
                }
            }
            let mut cov = [[0.0f32; D]; D];
            for (g, wi) in from.iter().zip(w) {
                for a in 0..D {
                    for b in 0..D {
                        let da = g.mean[a] - mean[a];
                        let db = g.mean[b] - mean[b];
                        cov[a][b] += wi * (g.cov[a][b] + da * db);
                    }
                }
            }
            out[j] = Gauss { mean, cov };
        }
        (out, c)
    }

    /// The parameters' variances grown as the model's [`super::mover::Forgetting`] says (up to
    /// their prior variance; a known parameter stays known).
    fn forget(&self, g: &mut Gauss<D>, dt: f32) {
        let f = self.model.forgetting;
        if !(f.memory_s > 0.0) || !f.memory_s.is_finite() {
            return;
        }
        let k = dt / f.memory_s;
        let layout = self.model.layout;
        let mut grow = |i: usize, var: f32| {
            if i < D && g.cov[i][i] > 0.0 {
                g.cov[i][i] = (g.cov[i][i] + var * k).min(var.max(g.cov[i][i]));
            }
        };
        for s in 0..layout.sources as usize {
            grow(PARAMETERS + 2 * s, f.offset_var);
        }
        if let Some(r) = layout.rssi() {
            grow(r, f.power_var);
            grow(r + 1, f.exponent_var);
        }
    }

    /// Fold one scalar measurement (innovation `nu`, Jacobian `h`, noise variance `r`) into
    /// `g`; the log-likelihood of the innovation, or `None` when it was gated out.
    fn update(&self, g: &mut Gauss<D>, nu: f32, h: &[f32; D], r: f32) -> Option<f32> {
        let mut ph = [0.0f32; D];
        for i in 0..D {
            for j in 0..D {
                ph[i] += g.cov[i][j] * h[j];
            }
        }
        let s = h.iter().zip(ph.iter()).map(|(a, b)| a * b).sum::<f32>() + r;
        if !(s > 0.0) || nu * nu > self.gate * self.gate * s {
            return None;
        }
        let k: [f32; D] = core::array::from_fn(|i| ph[i] / s);
        for i in 0..D {
            g.mean[i] += k[i] * nu;
        }
        // P - K S K^T, kept symmetric.
        for i in 0..D {
            for j in 0..=i {
                let v = g.cov[i][j] - k[i] * s * k[j];
                g.cov[i][j] = v;
                g.cov[j][i] = v;
            }
        }
        Some(-0.5 * (nu * nu / s + libm::logf(core::f32::consts::TAU * s)))
    }

    /// Fold in every measurement of `z`: the summed log-likelihood of the innovations.
    fn measure(&mut self, g: &mut Gauss<D>, z: &Epoch<K>) -> f32 {
        let mut ll = 0.0;
        let layout = self.model.layout;
        for o in z.bearings() {
            let b = &o.bearing;
            let (dx, dy) = (g.mean[0] - b.vehicle[0], g.mean[1] - b.vehicle[1]);
            let d2 = dx * dx + dy * dy;
            if !(d2 > 0.0) {
                continue;
            }
            let mut h = [0.0f32; D];
            h[0] = -dy / d2;
            h[1] = dx / d2;
            let mut offset = 0.0;
            if let Some((i, _)) = layout
                .offset(usize::from(o.station))
                .filter(|(_, v)| *v < D)
            {
                h[i] = 1.0;
                offset = g.mean[i];
            }
            let p = [g.mean[0], g.mean[1]];
            let nu = wrap(b.theta - predicted(&p, &b.vehicle) - offset);
            self.evaluations += 1;
            ll += self.update(g, nu, &h, b.sigma * b.sigma).unwrap_or(0.0);
        }
        for l in z.levels() {
            let (dx, dy) = (g.mean[0] - l.anchor[0], g.mean[1] - l.anchor[1]);
            let d2 = (dx * dx + dy * dy).max(MIN_DISTANCE * MIN_DISTANCE);
            let mut h = [0.0f32; D];
            let mut eta = l.law.eta;
            if let Some(r) = layout.rssi().filter(|r| r + 4 < D) {
                eta += g.mean[r + 1];
                h[r] = 1.0;
                h[r + 1] =
                    -5.0 * core::f32::consts::LOG10_E * libm::logf(d2 / (l.law.d0 * l.law.d0));
            }
            let k = -10.0 * eta * core::f32::consts::LOG10_E / d2;
            h[0] = k * dx;
            h[1] = k * dy;
            let nu = l.dbm - self.model.expected_dbm(&g.mean, l);
            self.evaluations += 1;
            ll += self
                .update(g, nu, &h, l.sigma_db * l.sigma_db)
                .unwrap_or(0.0);
        }
        ll
    }

    /// The two models combined: the mixture's moments, the mode component P(moving), the
    /// still model counted with zero velocity.
    fn combine(&self, m: &[Gauss<D>; 2]) -> Estimate<D> {
        let mut still = m[0];
        for a in 2..4 {
            for j in 0..D {
                still.cov[a][j] = 0.0;
                still.cov[j][a] = 0.0;
            }
        }
        let parts = [still, m[1]];
        let mut mean = [0.0f32; D];
        for (g, w) in parts.iter().zip(self.mu) {
            for k in 0..D {
                mean[k] += w * g.mean[k];
            }
        }
        let mut cov = [[0.0f32; D]; D];
        for (g, w) in parts.iter().zip(self.mu) {
            for a in 0..D {
                for b in 0..D {
                    cov[a][b] += w * (g.cov[a][b] + (g.mean[a] - mean[a]) * (g.mean[b] - mean[b]));
                }
            }
        }
        mean[MODE] = self.mu[1];
        for j in 0..D {
            cov[MODE][j] = 0.0;
            cov[j][MODE] = 0.0;
        }
        cov[MODE][MODE] = self.mu[0] * self.mu[1];
        Estimate {
            mean,
            covariance: cov,
            ess: 0.0,
            status: StepStatus::Updated,
        }
    }

    fn restart(&mut self) -> Result<Estimate<D>, Error> {
        let mut p = self.prior.ok_or(Error::NotInitialised)?;
        for v in p.cov.iter_mut().flatten() {
            *v *= 4.0;
        }
        self.models = Some([self.as_still(p), p]);
        self.mu = [0.5, 0.5];
        let mut e = self.combine(&[self.as_still(p), p]);
        e.status = StepStatus::Reinitialised;
        self.last = Some(e);
        Ok(e)
    }
}

impl<const D: usize, const K: usize> Filter<D> for ImmEkf<D, K> {
    type Measurement = Epoch<K>;

    fn initialise<R: Rng + ?Sized>(
        &mut self,
        cloud: &[[f32; D]],
        _rng: &mut R,
    ) -> Result<(), Error> {
        if self.model.layout.dims() > D || PARAMETERS > D {
            return Err(Error::OutOfRange);
        }
        let (mean, mut cov) = moments(cloud)?;
        // The particles' parameter statistics: each variance component is the prior's.
        let layout = self.model.layout;
        for s in 0..layout.sources as usize {
            if let Some((m, v)) = layout.offset(s).filter(|(_, v)| *v < D) {
                cov[m][m] += mean[v];
            }
        }
        if let Some(r) = layout.rssi().filter(|r| r + 4 < D) {
            cov[r][r] += mean[r + 2];
            cov[r][r + 1] += mean[r + 3];
            cov[r + 1][r] += mean[r + 3];
            cov[r + 1][r + 1] += mean[r + 4];
        }
        let moving = mean[MODE].clamp(0.01, 0.99);
        let g = self.tidy(Gauss { mean, cov });
        self.prior = Some(g);
        self.models = Some([self.as_still(g), g]);
        self.mu = [1.0 - moving, moving];
        self.last = Some(self.combine(&[self.as_still(g), g]));
        Ok(())
    }

    fn step<R: Rng + ?Sized>(&mut self, z: &Epoch<K>, _rng: &mut R) -> Result<Estimate<D>, Error> {
        let m = self.models.ok_or(Error::NotInitialised)?;
        <Mover<K> as Model<D>>::check(&self.model, z)?;
        let (mixed, c) = self.mix(&m, z.dt);
        // Predict.
        let mut still = self.as_still(mixed[0]);
        let (f, q) = self.model.motion.moving::<D>(z.dt);
        let mut moving = mixed[1];
        let mut fp = [[0.0f32; D]; D];
        for i in 0..D {
            for j in 0..D {
                fp[i][j] = (0..D).map(|k| f[i][k] * moving.cov[k][j]).sum();
            }
        }
        for i in 0..D {
            for j in 0..D {
                moving.cov[i][j] = (0..D).map(|k| fp[i][k] * f[j][k]).sum::<f32>() + q[i][j];
            }
        }
        moving.mean = crate::linalg::mat_vec(&f, &moving.mean);
        self.forget(&mut still, z.dt);
        self.forget(&mut moving, z.dt);
        if let Some(room) = self.model.room {
            bounce(room, &mut moving.mean);
            bounce(room, &mut still.mean);
            still.mean[2] = 0.0;
            still.mean[3] = 0.0;
        }
        // Update.
        let ll = [self.measure(&mut still, z), self.measure(&mut moving, z)];
        let models = [self.tidy(still), self.tidy(moving)];
        let finite = models.iter().all(|g| {
            g.mean
                .iter()
                .chain(g.cov.iter().flatten())
                .all(|v| v.is_finite())
        });
        if !finite {
            return self.restart();
        }
        let top = ll[0].max(ll[1]);
        let w = [
            c[0] * libm::expf(ll[0] - top),
            c[1] * libm::expf(ll[1] - top),
        ];
        let total = w[0] + w[1];
        if !(total > 0.0) || !total.is_finite() {
            return self.restart();
        }
        let moving_p = (w[1] / total).clamp(MIN_PROBABILITY, 1.0 - MIN_PROBABILITY);
        self.mu = [1.0 - moving_p, moving_p];
        self.models = Some(models);
        let e = self.combine(&models);
        self.last = Some(e);
        Ok(e)
    }

    fn estimate(&self) -> Result<Estimate<D>, Error> {
        self.last.ok_or(Error::NotInitialised)
    }

    fn evaluations(&self) -> u64 {
        self.evaluations
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fix::observation::Observation;
    use crate::model::bearing::Bearing;
    use crate::random;
    use crate::track::{Layout, Motion};
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    /// Four fixed stations watch an emitter cross at 12 m/s; the IMM follows it and says it
    /// moves, then sees it stop and says so.
    #[test]
    fn it_follows_a_crossing_and_sees_the_stop() {
        let stations = [
            [0.0f32, 0.0],
            [4000.0, 0.0],
            [4000.0, 4000.0],
            [0.0, 4000.0],
        ];
        let model = Mover::<4>::new(
            Motion::OUTDOOR,
            Layout {
                sources: 4,
                rssi: false,
            },
        );
        let mut f = ImmEkf::<13, 4>::new(model);
        let mut rng = XorShiftRng::seed_from_u64(5);
        let start = [500.0f32, 1500.0];
        let cloud: [[f32; 13]; 64] = core::array::from_fn(|_| {
            let mut x = [0.0f32; 13];
            x[0] = start[0] + 100.0 * random::normal(&mut rng);
            x[1] = start[1] + 100.0 * random::normal(&mut rng);
            x[MODE] = 0.5;
            for s in 0..4 {
                x[PARAMETERS + 2 * s + 1] = 0.02 * 0.02;
            }
            x
        });
        f.initialise(&cloud, &mut rng).unwrap();
        let sigma = 2.0f32.to_radians();
        let mut truth = start;
        let mut last = None;
        for k in 0..400 {
            if k < 200 {
                truth[0] += 12.0;
            }
            let mut z = Epoch::<4>::new(if k == 0 { 0.0 } else { 1.0 });
            for (s, v) in stations.iter().enumerate() {
                let mut o = Observation::new(
                    Bearing {
                        vehicle: *v,
                        theta: predicted(&truth, v) + sigma * random::normal(&mut rng),
                        sigma,
                    },
                    k as f32,
                );
                o.station = s as u16;
                z.push_bearing(o).unwrap();
            }
            let e = f.step(&z, &mut rng).unwrap();
            let err = (e.mean[0] - truth[0]).hypot(e.mean[1] - truth[1]);
            if k == 190 {
                // Moving at 12 m/s, 2 degrees at 2-4 km: tens of metres, and the model says so.
                assert!(err < 150.0 && e.mean[MODE] > 0.9, "{err} {:?}", e.mean);
                assert!((e.mean[2] - 12.0).abs() < 3.0, "{:?}", e.mean);
            }
            last = Some((e, err));
        }
        let (e, err) = last.unwrap();
        assert!(err < 80.0 && e.mean[MODE] < 0.1, "{err} {:?}", e.mean);
    }
}
