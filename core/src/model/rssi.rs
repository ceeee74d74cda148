//! Indoor tracking from RSSI (seed 003): a node moving with constant velocity, received by
//! fixed anchors through log-distance path loss.
//!
//! State [x, vx, y, vy]; x_k = A x_{k-1} + w_k, A = blockdiag([[1, T], [0, 1]] x 2),
//! w ~ N(0, diag(q)). Anchor m hears z_m = P0 - 10 eta log10(d_m / d0) + v_m, v_m ~ N(0, s_m^2).

use super::Model;
use crate::error::{Error, check_finite};
use crate::likelihood::Likelihood;
use crate::random;
use rand_core::Rng;

/// Log-distance path loss: received power P0 at distance d0, falling 10 eta dB per decade.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathLoss {
    /// Received power at the reference distance, dBm.
    pub p0: f32,
    /// Reference distance, metres.
    pub d0: f32,
    /// Path-loss exponent.
    pub eta: f32,
}

/// Distances below this (metres) are clamped: the log-distance law has no meaning at zero.
pub const MIN_DISTANCE: f32 = 0.05;

impl PathLoss {
    /// Expected RSSI (dBm) at distance `d`.
    #[inline]
    pub fn rssi(&self, d: f32) -> f32 {
        self.p0 - 10.0 * self.eta * libm::log10f(d.max(MIN_DISTANCE) / self.d0)
    }

    /// The distance that inverts `rssi` exactly, d0 10^((P0 - z) / (10 eta)). It is biased: its
    /// mean exceeds the true distance by exp((sigma ln10 / (10 eta))^2 / 2) for noise sigma dB.
    pub fn distance(&self, rssi: f32) -> f32 {
        self.d0 * libm::powf(10.0, (self.p0 - rssi) / (10.0 * self.eta))
    }

    /// [`PathLoss::distance`] with the log-normal bias divided out.
    pub fn unbiased_distance(&self, rssi: f32, sigma: f32) -> f32 {
        let k = sigma * core::f32::consts::LN_10 / (10.0 * self.eta);
        self.distance(rssi) / libm::expf(0.5 * k * k)
    }
}

/// One RSSI reading per anchor; anchors not heard this step are marked absent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RssiMeasurement<const A: usize> {
    /// Received power per anchor, dBm.
    pub dbm: [f32; A],
    /// Whether each anchor was heard.
    pub present: [bool; A],
}

impl<const A: usize> RssiMeasurement<A> {
    /// Every anchor heard.
    pub fn all(dbm: [f32; A]) -> Self {
        Self {
            dbm,
            present: [true; A],
        }
    }
}

/// Mirror one coordinate `p` back into the wall-to-wall span [0, `size`], reversing its
/// velocity `v` after an odd number of wall crossings: a node that walks into a wall bounces
/// off it. A coordinate already inside, a non-finite one or a non-positive span is left alone.
pub fn reflect(size: f32, p: &mut f32, v: &mut f32) {
    if !(size > 0.0) || !p.is_finite() || (0.0..=size).contains(p) {
        return;
    }
    // Fold into [0, 2 size), then mirror the upper half.
    let period = 2.0 * size;
    let folded = *p - period * libm::floorf(*p / period);
    let crossings = libm::floorf(*p / size) as i64;
    *p = if folded > size {
        period - folded
    } else {
        folded
    };
    if crossings % 2 != 0 {
        *v = -*v;
    }
}

/// The constant-velocity RSSI tracker with `A` anchors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RssiTracker<const A: usize> {
    /// Anchor positions (x, y), metres.
    pub anchors: [[f32; 2]; A],
    /// RSSI noise standard deviation per anchor, dB.
    pub sigma: [f32; A],
    /// Propagation law.
    pub path_loss: PathLoss,
    /// Time step T, seconds.
    pub dt: f32,
    /// Process noise variances of [x, vx, y, vy].
    pub q: [f32; 4],
    /// The room [0, w] x [0, h] the node cannot leave, if known: a state that would cross a
    /// wall is mirrored back and that velocity component reversed. `None`: open space.
    pub room: Option<[f32; 2]>,
}

impl<const A: usize> RssiTracker<A> {
    /// The transition matrix A.
    pub fn transition(&self) -> [[f32; 4]; 4] {
        let t = self.dt;
        [
            [1.0, t, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, t],
            [0.0, 0.0, 0.0, 1.0],
        ]
    }

    /// Noise-free move of a state by one step.
    pub fn advance(&self, x: &[f32; 4]) -> [f32; 4] {
        [x[0] + self.dt * x[1], x[1], x[2] + self.dt * x[3], x[3]]
    }

    /// Mirror a state back into the room (if any), reversing the velocity of each wall it
    /// crossed; a state already inside, or a non-finite one, is left as it is.
    pub fn confine(&self, mut x: [f32; 4]) -> [f32; 4] {
        let Some(room) = self.room else {
            return x;
        };
        let [px, vx, py, vy] = &mut x;
        reflect(room[0], px, vx);
        reflect(room[1], py, vy);
        x
    }

    /// Expected RSSI at every anchor from position (x, y).
    pub fn expected(&self, x: &[f32; 4]) -> [f32; A] {
        core::array::from_fn(|m| {
            let a = self.anchors[m];
            self.path_loss.rssi(libm::hypotf(x[0] - a[0], x[2] - a[1]))
        })
    }

    /// Fisher information of one step's readings about the state at `x` (position block only):
    /// sum_m b_m (p - a_m)(p - a_m)^T / d_m^4, b_m = (10 eta / (s_m ln 10))^2.
    pub fn information(&self, x: &[f32; 4]) -> [[f32; 4]; 4] {
        let mut j = [[0.0f32; 4]; 4];
        for (a, s) in self.anchors.iter().zip(self.sigma.iter()) {
            let dx = x[0] - a[0];
            let dy = x[2] - a[1];
            let d2 = (dx * dx + dy * dy).max(MIN_DISTANCE * MIN_DISTANCE);
            let g = 10.0 * self.path_loss.eta / (s * core::f32::consts::LN_10);
            let b = g * g / (d2 * d2);
            j[0][0] += b * dx * dx;
            j[0][2] += b * dx * dy;
            j[2][2] += b * dy * dy;
        }
        j[2][0] = j[0][2];
        j
    }
}

impl<const A: usize> Model<4> for RssiTracker<A> {
    type Measurement = RssiMeasurement<A>;

    fn check(&self, z: &RssiMeasurement<A>) -> Result<(), Error> {
        check_finite(&self.q)?;
        check_finite(&[
            self.dt,
            self.path_loss.p0,
            self.path_loss.d0,
            self.path_loss.eta,
        ])?;
        let heard = z.present.iter().filter(|p| **p).count();
        if heard == 0 {
            return Err(Error::TooFewMeasurements);
        }
        for m in 0..A {
            if z.present[m] {
                check_finite(&[z.dbm[m], self.sigma[m]])?;
                if !(self.sigma[m] > 0.0) {
                    return Err(Error::OutOfRange);
                }
            }
        }
        if self.q.iter().any(|v| *v < 0.0) || !(self.path_loss.d0 > 0.0) {
            return Err(Error::OutOfRange);
        }
        Ok(())
    }

    fn propagate<R: Rng + ?Sized>(&self, x: &mut [f32; 4], _z: &RssiMeasurement<A>, rng: &mut R) {
        *x = self.advance(x);
        for (xi, q) in x.iter_mut().zip(self.q.iter()) {
            *xi += libm::sqrtf(*q) * random::normal(rng);
        }
        *x = self.confine(*x);
    }

    fn ln_likelihood<L: Likelihood>(&self, x: &[f32; 4], z: &RssiMeasurement<A>, lik: &L) -> f32 {
        let h = self.expected(x);
        let mut l = 0.0;
        for m in 0..A {
            if z.present[m] {
                l += lik.ln(z.dbm[m] - h[m], self.sigma[m]);
            }
        }
        l
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walls_reflect() {
        let t = RssiTracker {
            anchors: [[0.0, 0.0]],
            sigma: [1.0],
            path_loss: PathLoss {
                p0: -40.0,
                d0: 1.0,
                eta: 2.0,
            },
            dt: 1.0,
            q: [0.0; 4],
            room: Some([10.0, 6.0]),
        };
        assert_eq!(t.confine([-1.0, -2.0, 7.0, 1.0]), [1.0, 2.0, 5.0, -1.0]);
        assert_eq!(t.confine([3.0, 1.0, 4.0, 1.0]), [3.0, 1.0, 4.0, 1.0]);
        // Two crossings (past both walls) keep the velocity's sign.
        let x = t.confine([23.0, 1.0, 1.0, 0.0]);
        assert!((x[0] - 3.0).abs() < 1e-5 && x[1] == 1.0, "{x:?}");
    }

    #[test]
    fn path_loss_round_trip_and_bias() {
        let p = PathLoss {
            p0: -37.8,
            d0: 1.0,
            eta: 2.3,
        };
        let z = p.rssi(4.0);
        assert!((p.distance(z) - 4.0).abs() < 1e-4);
        // sigma 4 dB, eta 2.3: k = 4 ln10 / 23 = 0.4005, bias factor exp(k^2 / 2) = 1.0835.
        assert!((p.distance(z) / p.unbiased_distance(z, 4.0) - 1.0835).abs() < 1e-3);
    }
}
