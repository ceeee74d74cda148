//! A fixed-lag smoother for recorded tracks: each update is reported once `L - 1` later ones
//! have been filtered, sharpened by a Rauch-Tung-Striebel backward pass over the filter's
//! moments (chosen: a Gaussian pass over the particle filter's means and covariances, not a
//! particle smoother; O(L D^3) per update, fixed memory).
//!
//! The pass smooths the kinematic state (position and velocity); the parameters are constants
//! whose filtered estimate at the end of the lag is already their best, and P(moving) stays the
//! filter's. Between updates k and k + 1 the transition is the constant-velocity one with its
//! noise scaled by the filter's P(moving) at k + 1, so a still stretch is smoothed as one
//! position and a moving one along its velocity.

use super::MODE;
use super::motion::Motion;
use crate::filter::Estimate;
use crate::linalg;

/// One filtered update held for smoothing.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Held<const D: usize> {
    estimate: Estimate<D>,
    /// Seconds from the previous held update.
    dt: f32,
}

/// The last `L` filtered updates of a `D`-component track ([`super::Layout`]).
#[derive(Debug, Clone)]
pub struct FixedLag<const D: usize, const L: usize> {
    motion: Motion,
    held: [Option<Held<D>>; L],
    /// Index of the oldest held update.
    head: usize,
    count: usize,
}

impl<const D: usize, const L: usize> FixedLag<D, L> {
    /// A smoother for a track moving by `motion`.
    pub fn new(motion: Motion) -> Self {
        const {
            assert!(
                L > 0 && D >= 4,
                "a lag of updates of a position and a velocity"
            )
        };
        Self {
            motion,
            held: [None; L],
            head: 0,
            count: 0,
        }
    }

    /// Take the filter's estimate of the newest update, `dt` seconds after the previous one;
    /// once `L` are held, the oldest comes back smoothed by all of them.
    pub fn push(&mut self, estimate: Estimate<D>, dt: f32) -> Option<Estimate<D>> {
        // After every push at most L - 1 are held, so there is room for this one.
        self.held[(self.head + self.count) % L] = Some(Held { estimate, dt });
        self.count += 1;
        if self.count < L {
            return None;
        }
        let oldest = self.smoothed(0);
        self.head = (self.head + 1) % L;
        self.count -= 1;
        oldest
    }

    /// The end of the recording: every update still held, oldest first, each smoothed by the
    /// ones after it.
    pub fn drain(&mut self, mut each: impl FnMut(Estimate<D>)) {
        while self.count > 0 {
            if let Some(e) = self.smoothed(0) {
                each(e);
            }
            self.head = (self.head + 1) % L;
            self.count -= 1;
        }
    }

    fn at(&self, k: usize) -> Option<Held<D>> {
        self.held[(self.head + k) % L]
    }

    /// Held update `k` (0: the oldest) smoothed by the later ones: the backward pass from the
    /// newest down to it, over the position and velocity.
    fn smoothed(&self, k: usize) -> Option<Estimate<D>> {
        let newest = self.at(self.count.checked_sub(1)?)?;
        let (mut mean, mut cov) = kinematic(&newest.estimate);
        for i in (k..self.count - 1).rev() {
            let here = self.at(i)?;
            let next = self.at(i + 1)?;
            let (f, mut q) = self.motion.moving::<KIN>(next.dt);
            let moving = next.estimate.mean[MODE].clamp(0.0, 1.0);
            for v in q.iter_mut().flatten() {
                *v *= moving;
            }
            let (mf, pf) = kinematic(&here.estimate);
            // Predicted covariance F P F^T + Q, and the gain C = P F^T (F P F^T + Q)^-1.
            let mut pp = mul_t(&mul(&f, &pf), &f);
            for a in 0..KIN {
                for b in 0..KIN {
                    pp[a][b] += q[a][b];
                }
            }
            let c = mul(&mul_t(&pf, &f), &invert(&pp)?);
            let predicted = linalg::mat_vec(&f, &mf);
            let mut m = mf;
            for a in 0..KIN {
                for b in 0..KIN {
                    m[a] += c[a][b] * (mean[b] - predicted[b]);
                }
            }
            let mut diff = [[0.0f32; KIN]; KIN];
            for a in 0..KIN {
                for b in 0..KIN {
                    diff[a][b] = cov[a][b] - pp[a][b];
                }
            }
            let cdc = mul_t(&mul(&c, &diff), &c);
            let mut p = pf;
            for a in 0..KIN {
                for b in 0..KIN {
                    p[a][b] += cdc[a][b];
                }
            }
            mean = m;
            cov = p;
        }
        let mut e = self.at(k)?.estimate;
        for a in 0..KIN {
            e.mean[a] = mean[a];
            for b in 0..KIN {
                e.covariance[a][b] = cov[a][b];
            }
        }
        let finite = e
            .mean
            .iter()
            .chain(e.covariance.iter().flatten())
            .all(|v| v.is_finite());
        finite.then_some(e)
    }
}

/// The kinematic components: position and velocity.
const KIN: usize = 4;

/// The kinematic block of an estimate.
fn kinematic<const D: usize>(e: &Estimate<D>) -> ([f32; KIN], [[f32; KIN]; KIN]) {
    (
        core::array::from_fn(|a| e.mean[a]),
        core::array::from_fn(|a| core::array::from_fn(|b| e.covariance[a][b])),
    )
}

/// The inverse, a direction without variance (a still emitter's velocity) given no gain.
fn invert(m: &[[f32; KIN]; KIN]) -> Option<[[f32; KIN]; KIN]> {
    let mut a = *m;
    let zero: [bool; KIN] = core::array::from_fn(|i| !(m[i][i] > 0.0));
    for i in 0..KIN {
        if zero[i] {
            for j in 0..KIN {
                a[i][j] = 0.0;
                a[j][i] = 0.0;
            }
            a[i][i] = 1.0;
        }
    }
    let mut inv = linalg::inverse_scaled(&a)?;
    for i in 0..KIN {
        if zero[i] {
            for j in 0..KIN {
                inv[i][j] = 0.0;
                inv[j][i] = 0.0;
            }
        }
    }
    Some(inv)
}

/// A B.
fn mul<const D: usize>(a: &[[f32; D]; D], b: &[[f32; D]; D]) -> [[f32; D]; D] {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..D).map(|k| a[i][k] * b[k][j]).sum()))
}

/// A B^T.
fn mul_t<const D: usize>(a: &[[f32; D]; D], b: &[[f32; D]; D]) -> [[f32; D]; D] {
    core::array::from_fn(|i| core::array::from_fn(|j| (0..D).map(|k| a[i][k] * b[j][k]).sum()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::filter::StepStatus;

    fn estimate(x: f32, v: f32, var: f32, moving: f32) -> Estimate<5> {
        let mut cov = [[0.0f32; 5]; 5];
        cov[0][0] = var;
        cov[1][1] = var;
        cov[2][2] = 0.25;
        cov[3][3] = 0.25;
        Estimate {
            mean: [x, 0.0, v, 0.0, moving],
            covariance: cov,
            ess: 0.0,
            status: StepStatus::Updated,
        }
    }

    #[test]
    fn a_still_stretch_is_smoothed_to_one_position() {
        // A still emitter's filter: the running mean of noisy positions, its variance 100 / k,
        // no velocity. Smoothed over the lag, every earlier update takes the newest's
        // estimate: all of them saw the same still emitter.
        let mut s = FixedLag::<5, 4>::new(Motion::OUTDOOR);
        let ys = [10.0f32, -10.0, 10.0, -10.0, 10.0, 4.0, -2.0];
        let (mut sum, mut n, mut filtered) = (0.0, 0.0, [0.0f32; 7]);
        let mut out = [None; 7];
        let mut emitted = 0;
        for (k, y) in ys.iter().enumerate() {
            sum += y;
            n += 1.0;
            filtered[k] = sum / n;
            let mut e = estimate(sum / n, 0.0, 100.0 / n, 0.0);
            e.covariance[2][2] = 0.0;
            e.covariance[3][3] = 0.0;
            if let Some(e) = s.push(e, 1.0) {
                out[emitted] = Some((k, e));
                emitted += 1;
            }
        }
        // Updates 0..3 come out as updates 3..6 go in, each smoothed by the three after it.
        assert_eq!(emitted, 4);
        for (k, e) in out.iter().flatten() {
            let newest = filtered[*k];
            assert!(
                (e.mean[0] - newest).abs() < 1e-3,
                "{k}: {:?} {newest}",
                e.mean
            );
            assert!((e.covariance[0][0] - 100.0 / (*k as f32 + 1.0)).abs() < 1e-2);
        }
        let mut rest = 0;
        s.drain(|e| {
            assert!((e.mean[0] - filtered[6]).abs() < 1e-3, "{:?}", e.mean);
            rest += 1;
        });
        assert_eq!(rest, 3);
    }

    #[test]
    fn a_moving_track_keeps_its_velocity() {
        let mut s = FixedLag::<5, 3>::new(Motion::OUTDOOR);
        for k in 0..6 {
            let x = 12.0 * k as f32;
            let Some(e) = s.push(estimate(x, 12.0, 25.0, 1.0), 1.0) else {
                continue;
            };
            let x = x - 24.0;
            assert!(
                (e.mean[0] - x).abs() < 1.0 && (e.mean[2] - 12.0).abs() < 0.5,
                "{e:?}"
            );
            assert!(e.covariance[0][0] < 25.0);
        }
    }
}
