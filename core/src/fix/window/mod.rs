//! The windowed fix: one still emitter followed for ever in fixed memory, a window of recent
//! bearings and a robust fix updated after every bearing, started from the previous fix. The
//! DF unit's firmware runs it, and the host runs the same code (`foxhunt locate --method
//! unit`), so both give the same bits.
//!
//! It is not the field pipeline ([`super::locate`]): that one re-solves the whole capture, finds
//! several emitters per channel, estimates each DF unit's mounting offset and checks the noise
//! it was told; the unit cannot afford any of that per bearing within its budgets (a fix within
//! 20 ms of its bearing at 168 MHz, 32 KiB of RAM with the stack). What the window leaves out:
//! no offset (a mounting error moves the fix), one emitter per channel, no evidence step, and the
//! past beyond the window forgotten.
//!
//! The MCU cannot re-solve a whole drive per bearing, and must never stall on what
//! arrives, so every step here has a hard bound:
//!
//! - **Window**: at most [`WINDOW`] bearings (fewer by [`WindowConfig::window`]), and none older
//!   than [`WindowConfig::max_age_ms`] behind the newest. A ring: no allocation, no shifting.
//! - **Start**: the previous fix. Without one (at the start, after a lost lock or a
//!   reconfiguration) a pair search: at most [`PAIR_ATTEMPTS`] bearing pairs drawn, at most
//!   [`HYPOTHESES`] crossings scored, each by how many window bearings pass within three sigmas
//!   of it (O(window) each).
//! - **Refinement**: Levenberg-Marquardt on Tukey's biweight ([`Tukey`]) (wild bearings get no say), at most
//!   [`MAX_PASSES`] passes over the window per update; what is left unconverged continues at
//!   the next bearing. With the noise estimated, its scale is re-estimated from the inliers'
//!   residuals once per update.
//! - **Answer**: the Gaussian information of the inliers gives the covariance; the ellipse is
//!   scaled by chi-square(2) when the stated sigma holds, by 2 F(2, n - 2) when the noise was
//!   estimated (the quantiles cached per degree of freedom, so each is computed once).
//!   Degenerate geometry (parallel bearings, a vehicle that has not moved, a range without
//!   bound) is a status, never a position.
//!
//! - **Randomness**: the pair search draws from the caller's generator, as every estimator
//!   of the core does.
//!
//! Only `f32` arithmetic, with the core's branch-free `atan2` and `sincos` (libm's `sinf`,
//! `cosf` and `hypotf` compute in `f64`, which the Cortex-M4F emulates in software), so the
//! host and the MCU compute the same bits.

// The MCU image runs this module on every bearing: no unwrap, expect, panic, unreachable or
// unchecked indexing (tests/tests/firmware_image.rs checks the linked image for panic calls
// here as in the bridge).
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::unreachable,
    clippy::todo,
    clippy::unimplemented
)]

mod answer;
mod pass;
use pass::Pass;
mod settings;
mod start;
#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests;

pub use answer::{Status, Update, WindowCounters};
pub use settings::{Noise, WindowConfig, WindowError};

use crate::Bearing;
use crate::fastmath::sincos;
use crate::fix::consistency::ellipse_scale;
use crate::fix::init::CLOUD_MAX_RANGE_M;
use crate::fix::noise::chance_cut;
use crate::likelihood::Tukey;
use crate::linalg::{eigen2, inverse2, solve2};
use crate::model::bearing::wrap;
use core::f32::consts::PI;
use rand_core::Rng;

/// (sin, cos) of an angle the tracker holds in (-pi, pi] (anything else, NaN included, reads
/// as 0): within the core's fast range, so its libm fallback (computed in `f64`) is never taken
/// and the compiler drops it.
#[inline(always)]
fn sin_cos(a: f32) -> (f32, f32) {
    let a = if libm::fabsf(a) <= 4.0 { a } else { 0.0 };
    sincos(a)
}

/// Bearings the window holds at most.
pub const WINDOW: usize = 128;
/// Crossings scored at most per pair search.
pub const HYPOTHESES: u32 = 32;
/// Pairs drawn at most per pair search (pairs that do not cross in front are drawn and dropped).
pub const PAIR_ATTEMPTS: u32 = 128;
/// Passes over the window at most per update (each a normal-equation or a cost pass).
pub const MAX_PASSES: u32 = 12;
/// A crossing farther than this from the window's centroid is no hypothesis, metres (the
/// search range of the pipeline's start cloud).
pub const MAX_RANGE_M: f32 = CLOUD_MAX_RANGE_M;
/// An ellipse longer than this (semi-major axis, metres) is no fix: the range is unbounded.
pub const MAX_AXIS_M: f32 = 20_000.0;
/// Smallest noise scale the estimate may reach, radians (exact bearings must not collapse it).
pub const MIN_SIGMA: f32 = 0.05 * PI / 180.0;
/// Confidence of the reported ellipse.
pub const CONFIDENCE: f32 = 0.95;

/// Scale changes at most per judgement ([`WindowFix::admit`]).
const ADMIT_ROUNDS: u32 = 3;
/// Degrees of freedom from which the admission is not tried: the chance cut (Bonferroni over
/// 128 bearings) is then below Tukey's 4.685.
const ADMIT_DOF: u32 = 20;
/// A changed scale puts the bearing judged this far inside (or outside) Tukey's cut.
const ADMIT_MARGIN: f32 = 1.05;

/// One degree, radians.
const DEG: f32 = PI / 180.0;
/// A bearing in the window.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    vehicle: [f32; 2],
    theta: f32,
    /// Relative weight: the bearing's sigma over the unit's (1 unless quality widens it).
    rel: f32,
    time_ms: i64,
}

const EMPTY: Entry = Entry {
    vehicle: [0.0; 2],
    theta: 0.0,
    rel: 1.0,
    time_ms: 0,
};

/// The robust loss: Tukey's biweight at its 95 %-efficiency constant, as the pipeline's.
const TUKEY: Tukey = Tukey { c: 4.685 };

/// The previous update's solution.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lock {
    position: [f32; 2],
    /// Noise scale, radians per unit relative weight.
    sigma: f32,
    lambda: f32,
}

/// The windowed fix: the window, the lock and the quantile caches.
#[derive(Debug, Clone)]
pub struct WindowFix {
    config: WindowConfig,
    ring: [Entry; WINDOW],
    /// Index of the oldest entry.
    head: usize,
    len: usize,
    lock: Option<Lock>,
    /// 2 F(2, dof; 0.95) and (0.5) by dof (0: not computed yet).
    k95: [f32; WINDOW + 1],
    k50: [f32; WINDOW + 1],
    counters: WindowCounters,
}

impl Default for WindowFix {
    fn default() -> Self {
        Self::new(WindowConfig::default())
    }
}

/// (-pi, pi] for a difference of two angles each in [-pi, pi].
fn fold(a: f32) -> f32 {
    if a > PI {
        a - 2.0 * PI
    } else if a <= -PI {
        a + 2.0 * PI
    } else {
        a
    }
}

impl WindowFix {
    /// An empty tracker. A setting out of range is replaced by the default.
    pub fn new(config: WindowConfig) -> Self {
        Self {
            config: if config.check().is_ok() {
                config
            } else {
                WindowConfig::default()
            },
            ring: [EMPTY; WINDOW],
            head: 0,
            len: 0,
            lock: None,
            k95: [0.0; WINDOW + 1],
            k50: [0.0; WINDOW + 1],
            counters: WindowCounters::default(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &WindowConfig {
        &self.config
    }

    /// Counters so far.
    pub fn counters(&self) -> &WindowCounters {
        &self.counters
    }

    /// Bearings in the window.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the window is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// New settings, from the next update on: the window is cut to the new length now, and a
    /// new noise model restarts the scale from its value.
    pub fn set_config(&mut self, config: WindowConfig) -> Result<(), WindowError> {
        config.check()?;
        let noise_changed = config.noise != self.config.noise;
        self.config = config;
        while self.len > usize::from(config.window) {
            self.pop_oldest();
        }
        if noise_changed && let Some(l) = self.lock.as_mut() {
            l.sigma = config.noise.start();
        }
        Ok(())
    }

    /// Forget every bearing and the lock (the frame or the mounting changed).
    pub fn clear(&mut self) {
        self.head = 0;
        self.len = 0;
        self.lock = None;
    }

    fn entry(&self, i: usize) -> Option<&Entry> {
        self.ring.get((self.head + i) % WINDOW)
    }

    fn entries(&self) -> impl Iterator<Item = &Entry> + Clone + '_ {
        (0..self.len).filter_map(|i| self.entry(i))
    }

    fn pop_oldest(&mut self) {
        if self.len > 0 {
            self.head = (self.head + 1) % WINDOW;
            self.len -= 1;
        }
    }

    /// Take a bearing (its sigma is its relative weight, see [`Noise`]) taken at `time_ms`,
    /// and update the fix; a pair search (when there is no lock) draws from `rng`.
    pub fn push<R: Rng + ?Sized>(
        &mut self,
        bearing: &Bearing,
        time_ms: i64,
        rng: &mut R,
    ) -> Result<Update, WindowError> {
        if bearing.check().is_err() {
            self.counters.refused += 1;
            return Err(WindowError::BadBearing);
        }
        self.counters.bearings += 1;
        if self.len >= usize::from(self.config.window) {
            self.pop_oldest();
        }
        let slot = (self.head + self.len) % WINDOW;
        if let Some(e) = self.ring.get_mut(slot) {
            *e = Entry {
                vehicle: bearing.vehicle,
                theta: wrap(bearing.theta),
                rel: bearing.sigma,
                time_ms,
            };
            self.len += 1;
        }
        let newest = self.entries().map(|e| e.time_ms).max().unwrap_or(time_ms);
        let age = i64::from(self.config.max_age_ms);
        while self.entry(0).is_some_and(|e| newest - e.time_ms > age) {
            self.pop_oldest();
        }
        Ok(self.update(newest, rng))
    }

    fn centroid(&self) -> [f32; 2] {
        let n = self.len.max(1) as f32;
        let mut c = [0.0f32; 2];
        for e in self.entries() {
            c[0] += e.vehicle[0] / n;
            c[1] += e.vehicle[1] / n;
        }
        c
    }

    /// The ellipse factors 2 F(2, dof) at 0.95 and 0.5, cached.
    fn scales(&mut self, dof: u32) -> Option<(f32, f32)> {
        let i = dof as usize;
        let (k95, k50) = (*self.k95.get(i)?, *self.k50.get(i)?);
        if k95 > 0.0 && k50 > 0.0 {
            return Some((k95, k50));
        }
        let d = Some(dof as f32);
        let k95 = ellipse_scale(CONFIDENCE, d).ok()?;
        let k50 = ellipse_scale(0.5, d).ok()?;
        *self.k95.get_mut(i)? = k95;
        *self.k50.get_mut(i)? = k50;
        Some((k95, k50))
    }

    fn empty_fix(&self, time_ms: i64, status: Status, sigma: f32, passes: u32) -> Update {
        Update {
            time_ms,
            status,
            position: [0.0; 2],
            covariance: [[0.0; 2]; 2],
            major: 0.0,
            minor: 0.0,
            orientation_deg: 0.0,
            cep50: 0.0,
            used: 0,
            window: self.len as u32,
            sigma,
            passes,
        }
    }

    /// With the noise estimated, Tukey's cut (4.685 of the scale) is only as good as the scale,
    /// and a handful of bearings often make that too small (three fit almost exactly): the
    /// next good bearing is dropped and the scale falls further. So the scale is judged by
    /// chance ([`chance_cut`] over the window, at the inliers' own noise): a bearing beyond the
    /// cut that chance allows is noise, and the scale is raised until the nearest such is an
    /// inlier; an inlier beyond what chance allows the others is wild, and the scale is lowered
    /// until the farthest such is out. Each change takes the pass `at` (at `lock`'s position
    /// and scale) again, at most [`ADMIT_ROUNDS`] times within the pass budget. Only small
    /// samples are judged so: from [`ADMIT_DOF`] degrees of freedom on the chance cut lies
    /// within Tukey's at a settled scale, and the window is fitted as before.
    fn admit(&self, origin: [f32; 2], lock: &mut Lock, mut at: Pass, passes: &mut u32) -> Pass {
        for _ in 0..ADMIT_ROUNDS {
            let dof = at.inliers.saturating_sub(2);
            if dof >= ADMIT_DOF || *passes + 1 >= MAX_PASSES {
                break;
            }
            // How far chance lets the largest of the window's residuals lie, in units of the
            // pass's scale, at a noise of `chi2` over `dof` (none: any residual is chance).
            let allowed = |chi2: f32, dof: u32| {
                if dof == 0 {
                    Some(f32::INFINITY)
                } else {
                    chance_cut(self.len, dof as f32).map(|c| c * libm::sqrtf(chi2 / dof as f32))
                }
            };
            let out = at.nearest_out;
            let far = at.farthest_in;
            let factor = if out.is_finite() && allowed(at.chi2, dof).is_some_and(|a| out <= a) {
                out / TUKEY.c * ADMIT_MARGIN
            } else if dof >= 2 && allowed(at.chi2 - far * far, dof - 1).is_some_and(|a| far > a) {
                far / TUKEY.c / ADMIT_MARGIN
            } else {
                break;
            };
            lock.sigma *= factor;
            at = self.pass(origin, lock.position, lock.sigma);
            *passes += 1;
        }
        at
    }

    fn lose(&mut self) {
        if self.lock.take().is_some() {
            self.counters.lost += 1;
        }
    }

    fn update<R: Rng + ?Sized>(&mut self, time_ms: i64, rng: &mut R) -> Update {
        let noise = self.config.noise;
        let start_sigma = self.lock.map(|l| l.sigma).unwrap_or(noise.start());
        if self.len < 3 {
            return self.empty_fix(time_ms, Status::TooFew, start_sigma, 0);
        }
        if self.degenerate() {
            self.lose();
            return self.empty_fix(time_ms, Status::Degenerate, start_sigma, 0);
        }
        let origin = self.centroid();
        let mut passes = 0;
        let mut lock = match self.lock {
            Some(l) => Lock {
                position: [l.position[0] - origin[0], l.position[1] - origin[1]],
                ..l
            },
            None => {
                passes += 1;
                match self.search(origin, start_sigma, rng) {
                    Some(p) => Lock {
                        position: p,
                        sigma: start_sigma,
                        lambda: 1e-3,
                    },
                    None => return self.empty_fix(time_ms, Status::Searching, start_sigma, 1),
                }
            }
        };
        let mut at = self.pass(origin, lock.position, lock.sigma);
        passes += 1;
        if let Noise::Estimated(_) = noise {
            at = self.admit(origin, &mut lock, at, &mut passes);
        }
        // Levenberg-Marquardt on the Tukey cost, within the pass budget: a step under a
        // millimetre is convergence, and three refused steps in a row end the update (at the
        // minimum, f32 round-off refuses every step).
        let mut refused = 0;
        while passes + 1 < MAX_PASSES {
            let damped = [
                [at.h[0][0] * (1.0 + lock.lambda), at.h[0][1]],
                [at.h[1][0], at.h[1][1] * (1.0 + lock.lambda)],
            ];
            let Some(delta) = solve2(&damped, &at.g) else {
                lock.lambda = (lock.lambda * 10.0).min(1e6);
                break;
            };
            let moved = delta[0] * delta[0] + delta[1] * delta[1];
            if moved < 1e-6 {
                break;
            }
            let next = [lock.position[0] + delta[0], lock.position[1] + delta[1]];
            let trial = self.pass(origin, next, lock.sigma);
            passes += 1;
            if trial.cost.is_finite() && trial.cost <= at.cost {
                lock.position = next;
                lock.lambda = (lock.lambda * 0.1).max(1e-7);
                let settled = at.cost - trial.cost <= 1e-6 * at.cost;
                at = trial;
                refused = 0;
                if settled {
                    break;
                }
            } else {
                lock.lambda = (lock.lambda * 10.0).min(1e6);
                refused += 1;
                if refused >= 3 {
                    break;
                }
            }
        }
        if let Noise::Estimated(_) = noise {
            at = self.admit(origin, &mut lock, at, &mut passes);
        }
        // The noise scale from the inliers (sum u^2 is at the current scale).
        let dof = at.inliers.saturating_sub(2);
        let estimate = if dof > 0 {
            lock.sigma * libm::sqrtf(at.chi2 / dof as f32)
        } else {
            lock.sigma
        };
        let (scale, estimated) = match noise {
            Noise::Estimated(_) => (estimate.max(MIN_SIGMA), true),
            // The stated sigma, unless the residuals clearly say the unit is noisier.
            Noise::Known(s) if dof >= 5 && estimate > 1.5 * s => (estimate, true),
            Noise::Known(s) => (s, false),
        };
        let position = [lock.position[0] + origin[0], lock.position[1] + origin[1]];
        if at.inliers < 3 || 2 * at.inliers < self.len as u32 || !(at.front > 0.0) {
            // Most bearings disagree with the lock, or it is the mirror image behind the
            // vehicle: search again at the next bearing.
            self.lose();
            return self.empty_fix(time_ms, Status::Searching, scale, passes);
        }
        // Covariance at the scale used: the information was summed at lock.sigma.
        let ratio = scale / lock.sigma;
        let cov = inverse2(&at.info).map(|c| c.map(|row| row.map(|v| v * ratio * ratio)));
        lock.sigma = scale;
        lock.position = position;
        let ks = if estimated {
            self.scales(dof.max(1))
        } else {
            // chi-square(2): -2 ln(1 - p).
            Some((-2.0 * libm::logf(1.0 - CONFIDENCE), -2.0 * libm::logf(0.5)))
        };
        let (Some(cov), Some((k95, k50))) = (cov, ks) else {
            self.lose();
            return self.empty_fix(time_ms, Status::Degenerate, scale, passes);
        };
        let Some((l1, l2, angle)) = eigen2(&cov) else {
            self.lose();
            return self.empty_fix(time_ms, Status::Degenerate, scale, passes);
        };
        let (l1, l2) = (l1.max(0.0), l2.max(0.0));
        let major = libm::sqrtf(k95 * l1);
        let minor = libm::sqrtf(k95 * l2);
        let finite = [position[0], position[1], major, minor, angle]
            .iter()
            .all(|v| v.is_finite());
        if !finite || major > MAX_AXIS_M {
            self.lose();
            return self.empty_fix(time_ms, Status::Degenerate, scale, passes);
        }
        self.lock = Some(lock);
        // CEP50 from the 50 % ellipse's axes, as the core's locate reports it.
        let (a50, b50) = (libm::sqrtf(k50 * l1), libm::sqrtf(k50 * l2));
        let cep50 = 0.59 * (a50 + b50) / libm::sqrtf(-2.0 * libm::logf(0.5));
        let mut orientation = 90.0 - angle / DEG;
        while orientation >= 180.0 {
            orientation -= 180.0;
        }
        while orientation < 0.0 {
            orientation += 180.0;
        }
        let status = if estimated && scale > self.config.max_sigma {
            Status::Noisy
        } else {
            Status::Valid
        };
        Update {
            time_ms,
            status,
            position,
            covariance: cov,
            major,
            minor,
            orientation_deg: orientation,
            cep50,
            used: at.inliers,
            window: self.len as u32,
            sigma: scale,
            passes,
        }
    }
}

/// The windowed fix over a whole capture's bearings in order (each with its time, ms), as the
/// unit runs it one bearing at a time with `config`: the last update, `None` when no bearing
/// was taken. Bearings the fix refuses (non-finite) are skipped, as the unit skips them.
pub fn over<R: Rng + ?Sized>(
    config: WindowConfig,
    bearings: impl IntoIterator<Item = (Bearing, i64)>,
    rng: &mut R,
) -> Option<Update> {
    let mut window = WindowFix::new(config);
    let mut last = None;
    for (b, time_ms) in bearings {
        if let Ok(u) = window.push(&b, time_ms, rng) {
            last = Some(u);
        }
    }
    last
}
