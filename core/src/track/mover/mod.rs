//! The moving emitter as a particle filter's model: [`Mover`].

use super::epoch::{Epoch, Level};
use super::motion::Motion;
use super::{MODE, PARAMETERS};
use crate::error::{Error, check_finite};
use crate::fastmath;
use crate::fix::observation::Observation;
use crate::likelihood::Likelihood;
use crate::model::Model;
use crate::model::bearing::wrap;
use crate::model::rssi::{MIN_DISTANCE, reflect};
use crate::random;
use rand_core::Rng;

/// Where the static parameters' statistics sit in the state (the module's table): for each of
/// `sources` DF sources the mean and variance of its offset from [`PARAMETERS`]; then, with
/// `rssi`, the means of the power offset and exponent correction and their covariance
/// (pp, pe, ee). A state longer than [`Layout::dims`] carries the rest unused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Layout {
    /// DF sources with an offset each: source s's mean is component [`PARAMETERS`] + 2 s, its
    /// variance the next. A bearing from a source at or beyond this count is refused.
    pub sources: u8,
    /// Whether RSSI readings are modelled (five components after the offsets).
    pub rssi: bool,
}

impl Layout {
    /// Components used.
    pub const fn dims(&self) -> usize {
        PARAMETERS + 2 * self.sources as usize + if self.rssi { 5 } else { 0 }
    }

    /// The components of source `s`'s offset: its mean and variance.
    pub fn offset(&self, s: usize) -> Option<(usize, usize)> {
        (s < self.sources as usize).then_some((PARAMETERS + 2 * s, PARAMETERS + 2 * s + 1))
    }

    /// The first of the RSSI components: the power offset's mean (dB), the exponent
    /// correction's mean, then their covariance pp, pe, ee.
    pub fn rssi(&self) -> Option<usize> {
        self.rssi.then_some(PARAMETERS + 2 * self.sources as usize)
    }

    /// The components whose values are estimates (the offsets' and RSSI terms' means), in
    /// layout order: what a bound and a Kalman filter treat as the parameters.
    pub fn means(&self) -> impl Iterator<Item = usize> + '_ {
        let offsets = (0..self.sources as usize).map(|s| PARAMETERS + 2 * s);
        let rssi = self.rssi().into_iter().flat_map(|r| [r, r + 1]);
        offsets.chain(rssi)
    }
}

/// How the parameters' statistics forget: each variance grows by its prior variance every
/// `memory_s` seconds (a random walk), up to that prior variance; a variance of zero (a
/// calibrated source, a known law) stays zero. The offset of a real DF unit varies with the
/// direction it looks in, and a particle filter's particles soon share their ancestors, so
/// statistics that never forget grow surer than the data allow (module [`Mover`]'s measure).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Forgetting {
    /// Seconds in which a variance regains its prior (infinite: never forget).
    pub memory_s: f32,
    /// The offsets' prior variance, rad^2.
    pub offset_var: f32,
    /// The RSSI power offset's prior variance, dB^2.
    pub power_var: f32,
    /// The exponent correction's prior variance.
    pub exponent_var: f32,
}

impl Forgetting {
    /// Never forget.
    pub const NEVER: Forgetting = Forgetting {
        memory_s: f32::INFINITY,
        offset_var: 0.0,
        power_var: 0.0,
        exponent_var: 0.0,
    };

    /// What each variance gains over `dt` seconds: (offset, power, exponent).
    fn growth(&self, dt: f32) -> [f32; 3] {
        let k = if self.memory_s > 0.0 {
            dt / self.memory_s
        } else {
            0.0
        };
        [
            self.offset_var * k,
            self.power_var * k,
            self.exponent_var * k,
        ]
    }
}

/// The moving emitter: the [`Motion`] between updates, bearings and RSSI readings at each
/// ([`Epoch`] of up to `K` of each), the state laid out by `layout` in `D` components.
///
/// The sensors' parameters enter the measurements linearly (a bearing is the true one plus
/// its source's offset; an RSSI reading is P0 + power offset - 10 (eta + correction)
/// log10(d / d0)), so each particle carries their Gaussian posterior given its own trajectory
/// instead of sampling them (a Rao-Blackwellised filter: Doucet, de Freitas, Murphy and
/// Russell 2000): a measurement weighs a particle by its predictive density, the
/// parameters' doubt added to the noise, then conditions the particle's statistics by a Kalman
/// step. A heavy-tailed likelihood's step is scaled by its IRLS weight (the mixture's inlier
/// probability: a wild bearing barely moves them). Sampled static parameters would collapse
/// onto a few values and grow confidently wrong (measured: 2 degree offsets estimated to
/// 0.1-0.2 degrees, 1-2 degrees off, the track's ellipses missing the truth all along).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mover<const K: usize> {
    /// How it moves.
    pub motion: Motion,
    /// Where the parameters sit.
    pub layout: Layout,
    /// The room [0, w] x [0, h] it cannot leave, if known: a position that would cross a wall
    /// is mirrored back and that velocity reversed (as [`crate::RssiTracker`] does).
    pub room: Option<[f32; 2]>,
    /// How the parameters' statistics forget.
    pub forgetting: Forgetting,
}

/// What one step's propagation needs, computed once for every particle.
#[derive(Debug, Clone, Copy)]
struct Advance {
    dt: f32,
    start: f32,
    stop: f32,
    factor: [f32; 3],
    start_speed: f32,
    growth: [f32; 3],
}

/// Mirror the position of state `x` (a tracker layout: position, then velocity) back into
/// `room`, reversing the velocity of each wall crossed.
pub(crate) fn bounce(room: [f32; 2], x: &mut [f32]) {
    if let [px, py, vx, vy, ..] = x {
        reflect(room[0], px, vx);
        reflect(room[1], py, vy);
    }
}

/// 5 log10(r) = 10 log10(sqrt(r)): the decibels of a squared-distance ratio.
const DB_OF_SQUARED: f32 = 5.0 * core::f32::consts::LOG10_E;

impl<const K: usize> Mover<K> {
    /// A mover in open space whose parameters never forget.
    pub const fn new(motion: Motion, layout: Layout) -> Self {
        Self {
            motion,
            layout,
            room: None,
            forgetting: Forgetting::NEVER,
        }
    }

    fn advance(&self, dt: f32) -> Advance {
        let (start, stop) = self.motion.switches(dt);
        Advance {
            dt,
            start,
            stop,
            factor: self.motion.axis_factor(dt),
            start_speed: self.motion.start_speed_sd,
            growth: self.forgetting.growth(dt),
        }
    }

    /// One particle over one step, given a uniform `u` (the switch) and four normals; its
    /// statistics kept valid (a variance below zero, as a Gaussian redraw can give, is zero).
    #[inline(always)]
    fn step<const D: usize>(&self, x: &mut [f32; D], a: &Advance, u: f32, n: [f32; 4]) {
        let [l11, l21, l22] = a.factor;
        if x[MODE] > 0.5 {
            if u < a.stop {
                x[2] = 0.0;
                x[3] = 0.0;
                x[MODE] = 0.0;
            } else {
                x[0] += a.dt * x[2] + l11 * n[0];
                x[2] += l21 * n[0] + l22 * n[1];
                x[1] += a.dt * x[3] + l11 * n[2];
                x[3] += l21 * n[2] + l22 * n[3];
                x[MODE] = 1.0;
            }
        } else if u < a.start {
            x[2] = a.start_speed * n[0];
            x[3] = a.start_speed * n[1];
            x[MODE] = 1.0;
        } else {
            x[2] = 0.0;
            x[3] = 0.0;
            x[MODE] = 0.0;
        }
        if let Some(room) = self.room {
            bounce(room, x);
        }
        let f = &self.forgetting;
        // Selects, not f32::min/max: on the MCU those are calls to fminf/fmaxf per particle.
        let grow = |v: f32, by: f32, cap: f32| {
            let cap = if cap > v { cap } else { v };
            let grown = v + by;
            if !(v > 0.0) {
                0.0
            } else if grown < cap {
                grown
            } else {
                cap
            }
        };
        for s in 0..self.layout.sources as usize {
            let v = PARAMETERS + 2 * s + 1;
            if v < D {
                x[v] = grow(x[v], a.growth[0], f.offset_var);
            }
        }
        if let Some(r) = self.layout.rssi().filter(|r| r + 4 < D) {
            let pp = grow(x[r + 2], a.growth[1], f.power_var);
            let ee = grow(x[r + 4], a.growth[2], f.exponent_var);
            let bound = libm::sqrtf(pp * ee);
            x[r + 2] = pp;
            x[r + 3] = x[r + 3].clamp(-bound, bound);
            x[r + 4] = ee;
        }
    }

    /// A bearing's residual under state `x` with its source's offset mean taken off, and the
    /// variance of that mean (0 for a source without one).
    #[inline]
    fn bearing_terms<const D: usize>(&self, x: &[f32; D], o: &Observation) -> (f32, f32) {
        let b = &o.bearing;
        let h = fastmath::atan2(x[1] - b.vehicle[1], x[0] - b.vehicle[0]);
        match self
            .layout
            .offset(usize::from(o.station))
            .filter(|(_, v)| *v < D)
        {
            Some((m, v)) => (wrap(b.theta - h - x[m]), x[v]),
            None => (wrap(b.theta - h), 0.0),
        }
    }

    /// An RSSI reading's residual under state `x` at the RSSI terms' means, its regressor on
    /// (power, exponent) and the variance the terms' doubt adds.
    #[inline]
    fn level_terms<const D: usize>(&self, x: &[f32; D], l: &Level) -> (f32, f32, f32) {
        let (dx, dy) = (x[0] - l.anchor[0], x[1] - l.anchor[1]);
        let d2 = (dx * dx + dy * dy).max(MIN_DISTANCE * MIN_DISTANCE);
        // The exponent's regressor: -10 log10(d / d0).
        let g = -DB_OF_SQUARED * libm::logf(d2 / (l.law.d0 * l.law.d0));
        let base = l.law.p0 + l.law.eta * g;
        match self.layout.rssi().filter(|r| r + 4 < D) {
            Some(r) => {
                let pred = base + x[r] + g * x[r + 1];
                let var = x[r + 2] + 2.0 * g * x[r + 3] + g * g * x[r + 4];
                (l.dbm - pred, g, var.max(0.0))
            }
            None => (l.dbm - base, g, 0.0),
        }
    }

    /// Expected RSSI of reading `l` from the state `x` (the RSSI terms at their means).
    pub fn expected_dbm<const D: usize>(&self, x: &[f32; D], l: &Level) -> f32 {
        l.dbm - self.level_terms(x, l).0
    }
}

/// log L of residual `r` whose predictive sd is `s`: the likelihood's shape plus its
/// normaliser -ln s, which differs between particles whose parameters are surer or less sure.
#[inline(always)]
fn ln_density<L: Likelihood>(lik: &L, r: f32, s: f32) -> f32 {
    lik.ln(r, s) - libm::logf(s)
}

impl<const D: usize, const K: usize> Model<D> for Mover<K> {
    type Measurement = Epoch<K>;

    fn check(&self, z: &Epoch<K>) -> Result<(), Error> {
        self.motion.check()?;
        check_finite(&[z.dt])?;
        if self.layout.dims() > D || z.dt < 0.0 {
            return Err(Error::OutOfRange);
        }
        if let Some([w, h]) = self.room
            && !(w > 0.0 && h > 0.0 && w.is_finite() && h.is_finite())
        {
            return Err(Error::OutOfRange);
        }
        for o in z.bearings() {
            o.bearing.check()?;
            if o.station >= u16::from(self.layout.sources) {
                return Err(Error::OutOfRange);
            }
        }
        if !z.levels().is_empty() && !self.layout.rssi {
            return Err(Error::Unsupported);
        }
        for l in z.levels() {
            l.check()?;
        }
        Ok(())
    }

    fn propagate<R: Rng + ?Sized>(&self, x: &mut [f32; D], z: &Epoch<K>, rng: &mut R) {
        let a = self.advance(z.dt);
        let u = random::uniform(rng);
        let n = core::array::from_fn(|_| random::normal(rng));
        self.step(x, &a, u, n);
    }

    /// Four particles per draw of the four-lane generator for the switches, one for each
    /// particle's four normals.
    fn propagate_all<R: Rng + ?Sized>(&self, states: &mut [[f32; D]], z: &Epoch<K>, rng: &mut R) {
        let a = self.advance(z.dt);
        let mut lanes = random::Lanes::seed_from(rng);
        let mut fours = states.chunks_exact_mut(4);
        for four in &mut fours {
            let u = lanes.next_u32x4();
            for (x, u) in four.iter_mut().zip(u) {
                let n = lanes.normals(rng);
                self.step(x, &a, (u >> 8) as f32 * (1.0 / 16_777_216.0), n);
            }
        }
        for x in fours.into_remainder() {
            self.propagate(x, z, rng);
        }
    }

    /// The predictive density of the epoch's measurements given the state's position, the
    /// parameters integrated out over their Gaussians (as [`Model::update_all`] weighs).
    fn ln_likelihood<L: Likelihood>(&self, x: &[f32; D], z: &Epoch<K>, lik: &L) -> f32 {
        let mut l = 0.0;
        for o in z.bearings() {
            let (r, var) = self.bearing_terms(x, o);
            let s = o.bearing.sigma;
            l += ln_density(lik, r, fastmath::sqrt(s * s + var));
        }
        for lv in z.levels() {
            let (r, _, var) = self.level_terms(x, lv);
            let s = lv.sigma_db;
            l += ln_density(lik, r, fastmath::sqrt(s * s + var));
        }
        l
    }

    /// Weigh, then condition each particle's parameters on each measurement in turn (a
    /// scalar Kalman step on the offset; a two-term one on the RSSI terms).
    fn update_all<L: Likelihood>(
        &self,
        states: &mut [[f32; D]],
        z: &Epoch<K>,
        lik: &L,
        log_weights: &mut [f32],
    ) {
        for o in z.bearings() {
            let s2 = o.bearing.sigma * o.bearing.sigma;
            let slot = self
                .layout
                .offset(usize::from(o.station))
                .filter(|(_, v)| *v < D);
            for (x, lw) in states.iter_mut().zip(log_weights.iter_mut()) {
                let (r, var) = self.bearing_terms(x, o);
                let total = s2 + var;
                let s = fastmath::sqrt(total);
                *lw += ln_density(lik, r, s);
                if let Some((m, v)) = slot
                    && var > 0.0
                {
                    let w = lik.irls_weight(r, s);
                    let gain = w * var / total;
                    x[m] += gain * r;
                    x[v] = var - gain * var;
                }
            }
        }
        for l in z.levels() {
            let s2 = l.sigma_db * l.sigma_db;
            let slot = self.layout.rssi().filter(|r| r + 4 < D);
            for (x, lw) in states.iter_mut().zip(log_weights.iter_mut()) {
                let (r, g, var) = self.level_terms(x, l);
                let total = s2 + var;
                let s = fastmath::sqrt(total);
                *lw += ln_density(lik, r, s);
                if let Some(i) = slot
                    && var > 0.0
                {
                    // P h with h = [1, g]; P <- P - w (P h)(P h)^T / S.
                    let ph = [x[i + 2] + g * x[i + 3], x[i + 3] + g * x[i + 4]];
                    let w = lik.irls_weight(r, s) / total;
                    x[i] += w * ph[0] * r;
                    x[i + 1] += w * ph[1] * r;
                    x[i + 2] -= w * ph[0] * ph[0];
                    x[i + 3] -= w * ph[0] * ph[1];
                    x[i + 4] -= w * ph[1] * ph[1];
                }
            }
        }
    }

    /// The epoch's `dt`: the position's kernel is a rate per second of the track.
    fn elapsed_s(&self, z: &Epoch<K>) -> Option<f32> {
        Some(z.dt)
    }

    /// The position and the offsets' means, jointly: the velocity and the mode are the
    /// motion's, the variances and the RSSI terms follow from the measurements. A particle's
    /// offset means are what its position has learned (the bearings it saw, less their true
    /// directions from there), so the kernel moves them together along the cloud's covariance:
    /// a position jittered alone no longer agrees with its offsets, the next bearings weigh it
    /// out, and only the kernel's shrinkage toward the mean stays, narrowing the cloud at each
    /// resampling (measured: 10 Hz ellipses holding the drone 55 % of the time at N = 1000).
    /// An offset mean the cloud does not spread (variance exactly 0: a calibrated source, or
    /// one no bearing has reached yet) is left out: there is nothing to smooth, and counted it
    /// would change the kernel's width and draws, so a state with room for stations not heard
    /// yet (a live channel's) tracks the heard ones to the bit as a state of those alone does.
    fn regularised(&self, covariance: &[[f32; D]; D]) -> [bool; D] {
        let offsets = PARAMETERS..PARAMETERS + 2 * self.layout.sources as usize;
        core::array::from_fn(|j| {
            let spread = covariance.get(j).and_then(|row| row.get(j)).copied() != Some(0.0);
            j < 2 || (offsets.contains(&j) && (j - PARAMETERS).is_multiple_of(2) && spread)
        })
    }
}

#[cfg(test)]
mod tests;
