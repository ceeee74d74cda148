//! Tracking one emitter for ever in fixed memory: a window of recent bearings and a robust fix
//! updated after every bearing, started from the previous fix.
//!
//! The DF unit's MCU cannot re-solve a whole drive per bearing, and must never stall on what
//! arrives, so every step here has a hard bound:
//!
//! - **Window**: at most [`WINDOW`] bearings (fewer by [`TrackConfig::window`]), and none older
//!   than [`TrackConfig::max_age_ms`] behind the newest. A ring: no allocation, no shifting.
//! - **Start**: the previous fix. Without one (at the start, after a lost lock or a
//!   reconfiguration) a pair search: at most [`PAIR_ATTEMPTS`] bearing pairs drawn, at most
//!   [`HYPOTHESES`] crossings scored, each by how many window bearings pass within three sigmas
//!   of it (O(window) each).
//! - **Refinement**: Levenberg-Marquardt on Tukey's biweight (wild bearings get no say), at most
//!   [`MAX_PASSES`] passes over the window per update; what is left unconverged continues at
//!   the next bearing. With the noise estimated, its scale is re-estimated from the inliers'
//!   residuals once per update.
//! - **Answer**: the Gaussian information of the inliers gives the covariance; the ellipse is
//!   scaled by chi-square(2) when the stated sigma holds, by 2 F(2, n - 2) when the noise was
//!   estimated (the quantiles cached per degree of freedom, so each is computed once).
//!   Degenerate geometry (parallel bearings, a vehicle that has not moved, a range without
//!   bound) is a status, never a position.
//!
//! Only `f32` arithmetic, with the core's branch-free `atan2` and `sincos` (libm's `sinf`,
//! `cosf` and `hypotf` compute in `f64`, which the Cortex-M4F emulates in software), so the
//! host and the MCU compute the same bits.

use foxhunt_core::Bearing;
use foxhunt_core::fastmath::{atan2, sincos};

/// (sin, cos) of an angle the tracker holds in (-pi, pi] (anything else, NaN included, reads
/// as 0): within the core's fast range, so its libm fallback (computed in `f64`) is never taken
/// and the compiler drops it.
#[inline(always)]
fn sin_cos(a: f32) -> (f32, f32) {
    let a = if libm::fabsf(a) <= 4.0 { a } else { 0.0 };
    sincos(a)
}
use foxhunt_core::fix::consistency::ellipse_scale;
use foxhunt_core::linalg::{inverse2, solve2};
use foxhunt_core::model::bearing::wrap;

use core::f32::consts::PI;

/// Bearings the window holds at most.
pub const WINDOW: usize = 128;
/// Crossings scored at most per pair search.
pub const HYPOTHESES: u32 = 32;
/// Pairs drawn at most per pair search (pairs that do not cross in front are drawn and dropped).
pub const PAIR_ATTEMPTS: u32 = 128;
/// Passes over the window at most per update (each a normal-equation or a cost pass).
pub const MAX_PASSES: u32 = 12;
/// Tukey's biweight constant, in sigmas.
pub const TUKEY_C: f32 = 4.685;
/// A crossing farther than this from the window's centroid is no hypothesis, metres.
pub const MAX_RANGE_M: f32 = 50_000.0;
/// An ellipse longer than this (semi-major axis, metres) is no fix: the range is unbounded.
pub const MAX_AXIS_M: f32 = 20_000.0;
/// Smallest noise scale the estimate may reach, radians (exact bearings must not collapse it).
pub const MIN_SIGMA: f32 = 0.05 * PI / 180.0;
/// Confidence of the reported ellipse.
pub const CONFIDENCE: f32 = 0.95;

const DEG: f32 = PI / 180.0;
/// Vehicle positions within this of each other count as one position, metres.
const STATIONARY_M: f32 = 1.0;
/// Bearings within this of each other (radians) count as parallel.
const PARALLEL_RAD: f32 = 0.1 * DEG;
/// The sine of the shallowest crossing a pair may make.
const MIN_CROSSING_SIN: f32 = 0.017_452_4;

/// How the bearings' noise is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Noise {
    /// Every bearing's sigma is this (radians) times its relative weight; the residuals only
    /// check it (a unit clearly noisier than it claims gets the estimated scale).
    Known(f32),
    /// Estimated from the residuals; this (radians) is where the estimate starts.
    Estimated(f32),
}

impl Noise {
    fn start(self) -> f32 {
        match self {
            Self::Known(s) | Self::Estimated(s) => s,
        }
    }
}

/// Tracker settings (the unit's configuration commands change them at run time).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TrackConfig {
    /// Bearings kept at most (1 to [`WINDOW`]).
    pub window: u16,
    /// Bearings older than the newest by more than this are dropped, ms.
    pub max_age_ms: u32,
    /// The noise model.
    pub noise: Noise,
    /// An estimated noise above this (radians) makes the fix "noisy", not valid.
    pub max_sigma: f32,
}

impl Default for TrackConfig {
    fn default() -> Self {
        Self {
            window: 120,
            max_age_ms: 300_000,
            noise: Noise::Estimated(2.0 * DEG),
            max_sigma: 10.0 * DEG,
        }
    }
}

impl TrackConfig {
    /// `Ok` when every setting is usable.
    pub fn check(&self) -> Result<(), TrackError> {
        let sigma = self.noise.start();
        let ok = (1..=WINDOW as u16).contains(&self.window)
            && self.max_age_ms > 0
            && sigma.is_finite()
            && (MIN_SIGMA..=45.0 * DEG).contains(&sigma)
            && self.max_sigma.is_finite()
            && self.max_sigma > 0.0;
        if ok { Ok(()) } else { Err(TrackError::Setting) }
    }
}

/// Why a bearing or a setting was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TrackError {
    /// A non-finite value or a non-positive sigma.
    BadBearing,
    /// A setting out of range.
    Setting,
}

impl core::fmt::Display for TrackError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::BadBearing => "bearing not finite or without a positive sigma",
            Self::Setting => "tracker setting out of range",
        })
    }
}

/// What a fix is worth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Status {
    /// A fix whose residuals agree with its noise.
    Valid,
    /// A fix, but the bearings scatter more than [`TrackConfig::max_sigma`]: not to be trusted.
    Noisy,
    /// The geometry gives no fix: parallel bearings, a vehicle that has not moved, a range
    /// without bound.
    Degenerate,
    /// Fewer than three bearings.
    TooFew,
    /// No pair of bearings crosses in front of the vehicle within range yet.
    Searching,
}

impl Status {
    /// The sentence letter: A, E, D, N, S.
    pub fn letter(self) -> u8 {
        match self {
            Self::Valid => b'A',
            Self::Noisy => b'E',
            Self::Degenerate => b'D',
            Self::TooFew => b'N',
            Self::Searching => b'S',
        }
    }

    /// The status a letter names.
    pub fn from_letter(c: u8) -> Option<Self> {
        Some(match c {
            b'A' => Self::Valid,
            b'E' => Self::Noisy,
            b'D' => Self::Degenerate,
            b'N' => Self::TooFew,
            b'S' => Self::Searching,
            _ => return None,
        })
    }

    /// Whether the fix carries a position.
    pub fn has_position(self) -> bool {
        matches!(self, Self::Valid | Self::Noisy)
    }
}

/// One update's answer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackFix {
    /// Time of the newest bearing on the bridge's clock, ms.
    pub time_ms: i64,
    /// What the fix is worth; position and ellipse mean something only when
    /// [`Status::has_position`].
    pub status: Status,
    /// Emitter position (east, north) in the bridge's local frame, metres.
    pub position: [f32; 2],
    /// Position covariance, m^2 (at the noise used).
    pub covariance: [[f32; 2]; 2],
    /// Semi-major axis of the [`CONFIDENCE`] ellipse, metres.
    pub major: f32,
    /// Semi-minor axis, metres.
    pub minor: f32,
    /// Direction of the major axis, degrees clockwise from true north, in [0, 180).
    pub orientation_deg: f32,
    /// Circular error probable, metres.
    pub cep50: f32,
    /// Bearings with weight in the fix.
    pub used: u32,
    /// Bearings in the window.
    pub window: u32,
    /// Bearing noise used, radians (the stated sigma, or the estimate).
    pub sigma: f32,
    /// Passes over the window this update took.
    pub passes: u32,
}

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

/// The previous update's solution.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lock {
    position: [f32; 2],
    /// Noise scale, radians per unit relative weight.
    sigma: f32,
    lambda: f32,
}

/// Counters of the tracker's work.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TrackCounters {
    /// Bearings taken into the window.
    pub bearings: u32,
    /// Bearings refused (non-finite, bad sigma).
    pub refused: u32,
    /// Pair searches run.
    pub searches: u32,
    /// Locks dropped (too few inliers, behind the vehicle, no bound).
    pub lost: u32,
}

/// The tracker: the window, the lock and the quantile caches.
#[derive(Debug, Clone)]
pub struct Tracker {
    config: TrackConfig,
    ring: [Entry; WINDOW],
    /// Index of the oldest entry.
    head: usize,
    len: usize,
    lock: Option<Lock>,
    /// 2 F(2, dof; 0.95) and (0.5) by dof (0: not computed yet).
    k95: [f32; WINDOW + 1],
    k50: [f32; WINDOW + 1],
    rng: u32,
    counters: TrackCounters,
}

impl Default for Tracker {
    fn default() -> Self {
        Self::new(TrackConfig::default())
    }
}

/// Sums of one pass over the window at a position.
#[derive(Debug, Clone, Copy, Default)]
struct Pass {
    /// IRLS normal matrix and right-hand side.
    h: [[f32; 2]; 2],
    g: [f32; 2],
    /// Tukey cost.
    cost: f32,
    /// Gaussian information of the inliers.
    info: [[f32; 2]; 2],
    /// Inliers (|u| < c), their sum of squared normalised residuals, their sum of cos(r).
    inliers: u32,
    chi2: f32,
    front: f32,
}

fn tukey_rho(u: f32) -> f32 {
    let c2 = TUKEY_C * TUKEY_C;
    if u * u >= c2 {
        return c2 / 6.0;
    }
    let t = 1.0 - u * u / c2;
    c2 / 6.0 * (1.0 - t * t * t)
}

fn tukey_weight(u: f32) -> f32 {
    let c2 = TUKEY_C * TUKEY_C;
    if u * u >= c2 {
        return 0.0;
    }
    let t = 1.0 - u * u / c2;
    t * t
}

/// `m + k n` for 2 x 2 matrices.
fn add(m: [[f32; 2]; 2], n: [[f32; 2]; 2], k: f32) -> [[f32; 2]; 2] {
    [
        [m[0][0] + k * n[0][0], m[0][1] + k * n[0][1]],
        [m[1][0] + k * n[1][0], m[1][1] + k * n[1][1]],
    ]
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

/// Eigenvalues (descending) and the major axis' angle (radians from east, counter-clockwise)
/// of a symmetric 2 x 2 matrix, in f32 alone.
fn eigen(m: &[[f32; 2]; 2]) -> (f32, f32, f32) {
    let (a, b, c) = (m[0][0], 0.5 * (m[0][1] + m[1][0]), m[1][1]);
    let h = 0.5 * (a - c);
    let r = libm::sqrtf(h * h + b * b);
    let mid = 0.5 * (a + c);
    (mid + r, mid - r, 0.5 * atan2(2.0 * b, a - c))
}

impl Tracker {
    /// An empty tracker. A setting out of range is replaced by the default.
    pub fn new(config: TrackConfig) -> Self {
        Self {
            config: if config.check().is_ok() {
                config
            } else {
                TrackConfig::default()
            },
            ring: [EMPTY; WINDOW],
            head: 0,
            len: 0,
            lock: None,
            k95: [0.0; WINDOW + 1],
            k50: [0.0; WINDOW + 1],
            rng: 0x9E37_79B9,
            counters: TrackCounters::default(),
        }
    }

    /// The settings.
    pub fn config(&self) -> &TrackConfig {
        &self.config
    }

    /// Counters so far.
    pub fn counters(&self) -> &TrackCounters {
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
    pub fn set_config(&mut self, config: TrackConfig) -> Result<(), TrackError> {
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

    fn random(&mut self) -> u32 {
        // xorshift32: a fixed sequence, the same on the host and the MCU.
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.rng = x;
        x
    }

    /// Take a bearing (its sigma is its relative weight, see [`Noise`]) taken at `time_ms`,
    /// and update the fix.
    pub fn push(&mut self, bearing: &Bearing, time_ms: i64) -> Result<TrackFix, TrackError> {
        if bearing.check().is_err() {
            self.counters.refused += 1;
            return Err(TrackError::BadBearing);
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
        Ok(self.update(newest))
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

    /// No position can come of the window: every vehicle position in one place, or every
    /// bearing parallel.
    fn degenerate(&self) -> bool {
        let Some(first) = self.entry(0).copied() else {
            return true;
        };
        let mut moved = false;
        let mut turned = false;
        for e in self.entries() {
            let (dx, dy) = (
                e.vehicle[0] - first.vehicle[0],
                e.vehicle[1] - first.vehicle[1],
            );
            moved |= dx * dx + dy * dy > STATIONARY_M * STATIONARY_M;
            turned |= libm::fabsf(fold(e.theta - first.theta)) > PARALLEL_RAD;
        }
        !(moved && turned)
    }

    /// One pass over the window at `p` (centred coordinates) with noise scale `sigma`.
    fn pass(&self, origin: [f32; 2], p: [f32; 2], sigma: f32) -> Pass {
        let mut s = Pass::default();
        for e in self.entries() {
            let dx = p[0] - (e.vehicle[0] - origin[0]);
            let dy = p[1] - (e.vehicle[1] - origin[1]);
            let d2 = dx * dx + dy * dy;
            // A branch, not `max`: the Cortex-M4F build calls `fmaxf` for that.
            let d2 = if d2 < 1e-6 { 1e-6 } else { d2 };
            let r = fold(e.theta - atan2(dy, dx));
            let sd = sigma * e.rel;
            let u = r / sd;
            s.cost += tukey_rho(u);
            let inv_var = 1.0 / (sd * sd);
            let w = inv_var * tukey_weight(u);
            let inlier = u * u < TUKEY_C * TUKEY_C;
            let (jx, jy) = (-dy / d2, dx / d2);
            let outer = [[jx * jx, jx * jy], [jx * jy, jy * jy]];
            s.h = add(s.h, outer, w);
            if inlier {
                s.info = add(s.info, outer, inv_var);
            }
            s.g[0] += w * jx * r;
            s.g[1] += w * jy * r;
            if inlier {
                s.inliers += 1;
                s.chi2 += u * u;
                s.front += sin_cos(r).1;
            }
        }
        s
    }

    /// Bearings that pass within three sigmas (or half a degree) of `p`, and their summed
    /// absolute residuals.
    fn support(&self, origin: [f32; 2], p: [f32; 2], sigma: f32) -> (u32, f32) {
        let mut n = 0;
        let mut spread = 0.0;
        for e in self.entries() {
            let dx = p[0] - (e.vehicle[0] - origin[0]);
            let dy = p[1] - (e.vehicle[1] - origin[1]);
            let r = libm::fabsf(fold(e.theta - atan2(dy, dx)));
            if r <= (3.0 * sigma * e.rel).max(0.5 * DEG) {
                n += 1;
                spread += r;
            }
        }
        (n, spread)
    }

    /// Where the bearings of entries `i` and `j` cross (centred), if in front of both within
    /// range.
    fn crossing(&self, origin: [f32; 2], i: usize, j: usize) -> Option<[f32; 2]> {
        let (a, b) = (self.entry(i)?, self.entry(j)?);
        let (sa, ca) = sin_cos(a.theta);
        let (sb, cb) = sin_cos(b.theta);
        let cross = ca * sb - sa * cb;
        if libm::fabsf(cross) < MIN_CROSSING_SIN {
            return None;
        }
        let dp = [b.vehicle[0] - a.vehicle[0], b.vehicle[1] - a.vehicle[1]];
        let s = (dp[0] * sb - dp[1] * cb) / cross;
        let t = (dp[0] * sa - dp[1] * ca) / cross;
        if !(s > 0.0 && t > 0.0) {
            return None;
        }
        let p = [
            a.vehicle[0] - origin[0] + s * ca,
            a.vehicle[1] - origin[1] + s * sa,
        ];
        let far = p[0] * p[0] + p[1] * p[1] > MAX_RANGE_M * MAX_RANGE_M;
        (p[0].is_finite() && p[1].is_finite() && !far).then_some(p)
    }

    /// The pair search: the crossing most window bearings agree with.
    fn search(&mut self, origin: [f32; 2], sigma: f32) -> Option<[f32; 2]> {
        self.counters.searches += 1;
        let n = self.len as u32;
        let mut best: Option<(u32, f32, [f32; 2])> = None;
        let mut scored = 0;
        for _ in 0..PAIR_ATTEMPTS {
            if scored >= HYPOTHESES {
                break;
            }
            let i = (self.random() % n) as usize;
            let j = (self.random() % n) as usize;
            if i == j {
                continue;
            }
            let Some(p) = self.crossing(origin, i, j) else {
                continue;
            };
            scored += 1;
            let (count, spread) = self.support(origin, p, sigma);
            let better = match best {
                None => true,
                Some((c, s, _)) => count > c || (count == c && spread < s),
            };
            if better {
                best = Some((count, spread, p));
            }
        }
        best.filter(|b| b.0 >= 3).map(|b| b.2)
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

    fn empty_fix(&self, time_ms: i64, status: Status, sigma: f32, passes: u32) -> TrackFix {
        TrackFix {
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

    fn lose(&mut self) {
        if self.lock.take().is_some() {
            self.counters.lost += 1;
        }
    }

    fn update(&mut self, time_ms: i64) -> TrackFix {
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
                match self.search(origin, start_sigma) {
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
        let (l1, l2, angle) = eigen(&cov);
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
        TrackFix {
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

#[cfg(test)]
mod tests {
    use super::*;
    use foxhunt_core::model::bearing::predicted;
    use foxhunt_core::random;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    const EMITTER: [f32; 2] = [1200.0, 800.0];

    fn drive(k: usize) -> [f32; 2] {
        // An L: east for 60 s at 10 m/s, then north.
        let s = 10.0 * k as f32;
        if s < 600.0 {
            [s, 0.0]
        } else {
            [600.0, s - 600.0]
        }
    }

    fn bearing(k: usize, sd: f32, rng: &mut XorShiftRng) -> Bearing {
        let v = drive(k % 200);
        Bearing {
            vehicle: v,
            theta: predicted(&EMITTER, &v) + sd * random::normal(rng),
            sigma: 1.0,
        }
    }

    #[test]
    fn a_drive_converges_and_the_ellipse_holds_the_emitter() {
        let mut rng = XorShiftRng::seed_from_u64(7);
        let mut t = Tracker::default();
        let mut last = None;
        for k in 0..150 {
            let f = t
                .push(&bearing(k, 1.5 * DEG, &mut rng), k as i64 * 1000)
                .unwrap();
            assert!(f.passes <= MAX_PASSES, "{f:?}");
            last = Some(f);
        }
        let f = last.unwrap();
        assert_eq!(f.status, Status::Valid, "{f:?}");
        let err = libm::hypotf(f.position[0] - EMITTER[0], f.position[1] - EMITTER[1]);
        // 120 bearings of 1.5 degrees at about 1 km: tens of metres; the 95 % ellipse's
        // semi-major axis bounds the error here (one seed, a loose check of the scale).
        assert!(err < f.major, "{err} m against {f:?}");
        assert!(
            (1.0 * DEG..2.2 * DEG).contains(&f.sigma),
            "{}",
            f.sigma / DEG
        );
        assert_eq!(f.window, 120);
    }

    #[test]
    fn wild_bearings_get_no_say() {
        let mut rng = XorShiftRng::seed_from_u64(8);
        let mut t = Tracker::default();
        let mut f = None;
        for k in 0..150 {
            let mut b = bearing(k, 1.0 * DEG, &mut rng);
            if k % 5 == 0 {
                b.theta = random::uniform_in(&mut rng, -PI, PI);
            }
            f = Some(t.push(&b, k as i64 * 1000).unwrap());
        }
        let f = f.unwrap();
        let err = libm::hypotf(f.position[0] - EMITTER[0], f.position[1] - EMITTER[1]);
        assert!(err < 60.0 && f.status == Status::Valid, "{err} m: {f:?}");
        assert!(f.used < 110, "{f:?}");
    }

    #[test]
    fn parallel_bearings_and_a_parked_vehicle_are_degenerate() {
        let mut t = Tracker::default();
        for k in 0..20 {
            // Driving straight at the emitter: one line.
            let v = [60.0 * k as f32, 40.0 * k as f32];
            let b = Bearing {
                vehicle: v,
                theta: predicted(&[6000.0, 4000.0], &v),
                sigma: 1.0,
            };
            let f = t.push(&b, k * 1000).unwrap();
            assert!(
                matches!(f.status, Status::TooFew | Status::Degenerate),
                "{f:?}"
            );
        }
        let mut t = Tracker::default();
        let mut rng = XorShiftRng::seed_from_u64(9);
        for k in 0..20 {
            let b = Bearing {
                vehicle: [5.0, 5.0],
                theta: random::uniform_in(&mut rng, -PI, PI),
                sigma: 1.0,
            };
            let f = t.push(&b, k * 1000).unwrap();
            assert!(!f.status.has_position(), "{f:?}");
        }
    }

    #[test]
    fn the_window_is_bounded_by_count_and_age() {
        let mut rng = XorShiftRng::seed_from_u64(10);
        let mut t = Tracker::new(TrackConfig {
            window: 50,
            max_age_ms: 30_000,
            ..TrackConfig::default()
        });
        for k in 0..100 {
            let f = t.push(&bearing(k, DEG, &mut rng), k as i64 * 500).unwrap();
            assert!(f.window <= 50);
        }
        // 30 s at two a second: 61 would fit the age; the count cuts first.
        assert_eq!(t.len(), 50);
        for k in 100..110 {
            t.push(&bearing(k, DEG, &mut rng), k as i64 * 5000).unwrap();
        }
        assert_eq!(t.len(), 7, "30 s of bearings 5 s apart, both ends in");
        assert!(
            t.set_config(TrackConfig {
                window: 0,
                ..TrackConfig::default()
            })
            .is_err()
        );
    }

    #[test]
    fn bad_bearings_are_refused_and_counted() {
        let mut t = Tracker::default();
        let b = Bearing {
            vehicle: [f32::NAN, 0.0],
            theta: 0.0,
            sigma: 1.0,
        };
        assert_eq!(t.push(&b, 0), Err(TrackError::BadBearing));
        assert_eq!(t.counters().refused, 1);
        assert!(t.is_empty());
    }
}
