//! The station table: one row per DF station, its offset's prior in, its estimate out, and the
//! blocks of the normal equations the solver eliminates it with.
//!
//! Each bearing depends on the position and on its own station's offset only, so the normal
//! matrix over [x, y, b_0 .. b_{S-1}] is an arrow: a 2 x 2 position block, a 2 x 1 column and a
//! 1 x 1 diagonal entry per station, nothing between stations. Each offset is eliminated on its
//! own (the Schur complement of its diagonal entry), leaving a 2 x 2 system for the position:
//! O(N + S) work and O(S) memory for any number of stations, where the dense (2 + S)-square
//! matrix cost O(S^3). Per station the bearings are summed as a weighted mean and scatter of
//! their Jacobians (Welford's update, so a fixed station whose bearings all share one Jacobian
//! leaves an exact zero scatter instead of the difference of two large sums):
//!
//! - the position block of station s is C_s + W_s m_s m_s^T (C_s the scatter, m_s the mean
//!   Jacobian, W_s the summed weight), its column W_s m_s, its diagonal W_s + I_s (I_s the
//!   prior's information);
//! - eliminating b_s leaves C_s + a_s m_s m_s^T with a_s = W_s I_s / (W_s + I_s): a station
//!   that measures its offset well (W_s >> I_s) keeps only the spread of its geometry, one that
//!   relies on its prior (a fixed station: C_s = 0) keeps I_s, and the position covariance
//!   shows the prior's share.

use super::BiasPrior;
use super::direction::{DirectionPrior, HARMONICS};
use super::summary::{Summary, Summed};
use crate::error::{Error, check_finite};
use crate::linalg::dot;
use crate::linalg::inverse_scaled;

/// How far (metres) a station must move before its course gives the antenna's front: GPS
/// jitter of a parked vehicle stays under it, a vehicle at 20 m/s covers it in a quarter
/// second.
pub const FRONT_STEP_M: f32 = 5.0;

/// One station's row of the table a fix works in (see the module doc). The caller gives each
/// row its prior ([`StationSlot::new`]) and reads the fit's offset back
/// ([`StationSlot::offset`]); the rest is the solver's room.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StationSlot {
    /// The prior the caller gave.
    given: BiasPrior,
    /// The prior in force (a channel's later sources see the emitter's estimate).
    pub(super) in_force: BiasPrior,
    /// Sd of the station's unmodelled systematic error, radians (0: none; already in the
    /// priors' sds).
    unmodelled: f32,
    /// The last fit's offset, radians.
    pub(super) bias: f32,
    /// Its standard deviation, radians.
    pub(super) sd: f32,
    /// Bearings of this station in the last fit.
    pub(super) used: u32,
    /// Share of the offset's information the last fit's bearings gave (0: the prior alone).
    pub(super) measured: f32,
    /// Whether the offset is an unknown of the current problem (seen, prior sd > 0).
    pub(super) free: bool,
    /// Bearings of this station in the current problem.
    pub(super) n: u32,
    /// The solver's offset, its trial step's, and one kept aside (a profile's start).
    pub(super) x: f32,
    pub(super) trial: f32,
    pub(super) saved: f32,
    /// The last fit as it was before a profile round the circle ([`super::offset_circle`]):
    /// offset, sd, share measured, and the bearings it used.
    held: ([f32; 3], u32),
    /// Summed weight, mean Jacobian and mean residual of the current accumulation.
    w: f32,
    mean_j: [f32; 2],
    mean_r: f32,
    /// Weighted scatter of the Jacobians (xx, xy, yy) and their cross-scatter with the
    /// residuals.
    scatter: [f32; 3],
    cross: [f32; 2],
    /// The direction-dependent error's prior and the antenna's front where the station does
    /// not move (theta, radians; north by default).
    direction: DirectionPrior,
    front: f32,
    /// Whether the harmonics are unknowns of the current problem (seen, prior sd > 0).
    pub(super) hfree: bool,
    /// The solver's harmonic coefficients, the trial step's, one set kept aside, the last
    /// fit's and their sds, and the fit held aside.
    pub(super) hx: [f32; HARMONICS],
    pub(super) htrial: [f32; HARMONICS],
    hsaved: [f32; HARMONICS],
    pub(super) hfit: [f32; HARMONICS],
    pub(super) hsd: [f32; HARMONICS],
    hheld: [[f32; HARMONICS]; 2],
    /// Mean harmonic regressors, their weighted scatter with the Jacobians, with each other
    /// (upper triangle, row by row) and with the residuals.
    mean_u: [f32; HARMONICS],
    scatter_ju: [[f32; HARMONICS]; 2],
    scatter_uu: [f32; 10],
    cross_u: [f32; HARMONICS],
    /// The antenna's course while the observations are read: where the station last moved
    /// from, its course since (theta), the first course it showed.
    track: Option<[f32; 2]>,
    course: Option<f32>,
    first_course: Option<f32>,
    /// The current problem's bearings of this station as set-up counted them, and where they
    /// stand summed for the solver's passes ([`super::summary`]).
    pub(super) summary: Summary,
    pub(super) summed: Option<Summed>,
    /// Where all its bearings in the current problem were taken (two or more), and the
    /// direction from there to the position the solver last evaluated: one `atan2` a pass.
    pub(super) place: Option<[f32; 2]>,
    pub(super) toward: f32,
}

/// Where the solver's harmonic coefficients start (as [`super::StartOffsets`] for offsets).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum HarmonicStart {
    /// The prior's mean.
    Prior,
    /// The last fit's.
    Fitted,
    /// Where a profile kept them aside.
    Saved,
    /// Where the solver left them.
    Current,
}

/// Index of (k, l), k <= l, in a packed upper triangle of 4 x 4.
const fn packed(k: usize, l: usize) -> usize {
    let (k, l) = if k <= l { (k, l) } else { (l, k) };
    k * HARMONICS - k * (k + 1) / 2 + l
}

impl Default for StationSlot {
    fn default() -> Self {
        Self::new(BiasPrior::default())
    }
}

impl StationSlot {
    /// A row for a station whose offset has `prior`.
    pub const fn new(prior: BiasPrior) -> Self {
        Self {
            given: prior,
            in_force: prior,
            unmodelled: 0.0,
            bias: prior.mean,
            sd: prior.sd,
            used: 0,
            measured: 0.0,
            free: false,
            n: 0,
            x: prior.mean,
            trial: prior.mean,
            saved: prior.mean,
            held: ([prior.mean, prior.sd, 0.0], 0),
            w: 0.0,
            mean_j: [0.0; 2],
            mean_r: 0.0,
            scatter: [0.0; 3],
            cross: [0.0; 2],
            direction: DirectionPrior::NONE,
            front: core::f32::consts::FRAC_PI_2,
            hfree: false,
            hx: [0.0; HARMONICS],
            htrial: [0.0; HARMONICS],
            hsaved: [0.0; HARMONICS],
            hfit: [0.0; HARMONICS],
            hsd: [0.0; HARMONICS],
            hheld: [[0.0; HARMONICS]; 2],
            mean_u: [0.0; HARMONICS],
            scatter_ju: [[0.0; HARMONICS]; 2],
            scatter_uu: [0.0; 10],
            cross_u: [0.0; HARMONICS],
            track: None,
            course: None,
            first_course: None,
            summary: Summary::EMPTY,
            summed: None,
            place: None,
            toward: 0.0,
        }
    }

    /// The same row with a direction-dependent error of `prior` (its coefficients estimated
    /// with the position where the prior's sd is > 0, applied as known where it is 0) and,
    /// for a station that does not move, its antenna's front `front` (theta, radians: the
    /// direction its relative bearings are measured from; a moving station's is its course).
    pub const fn with_direction(mut self, prior: DirectionPrior, front: f32) -> Self {
        self.direction = prior;
        self.front = front;
        self.hx = prior.mean;
        self.htrial = prior.mean;
        self.hsaved = prior.mean;
        self.hfit = prior.mean;
        self.hsd = [prior.sd; HARMONICS];
        self.hheld = [prior.mean, [prior.sd; HARMONICS]];
        self
    }

    /// The direction-dependent error's prior.
    pub fn direction(&self) -> DirectionPrior {
        self.direction
    }

    /// The last fit's harmonic coefficients a_1, b_1, a_2, b_2 and their sds, radians (the
    /// prior's where they were not estimated).
    pub fn harmonics(&self) -> ([f32; HARMONICS], [f32; HARMONICS]) {
        (self.hfit, self.hsd)
    }

    /// What the last fit says the station adds to a bearing whose relative bearing is `phi`:
    /// its offset and its direction-dependent error, radians.
    pub fn correction(&self, phi: f32) -> f32 {
        self.bias + self.direction_error(phi)
    }

    /// The last fit's direction-dependent error at relative bearing `phi`, radians.
    pub fn direction_error(&self, phi: f32) -> f32 {
        super::direction::error(&self.hfit, phi)
    }

    /// Forget the course of an earlier reading of the observations.
    pub(crate) fn start_track(&mut self) {
        self.track = None;
        self.course = None;
        self.first_course = None;
    }

    /// The antenna's front as the station stands at `position` (read in time order): its
    /// course once it has moved [`FRONT_STEP_M`] (`None` before).
    pub fn course_at(&mut self, position: [f32; 2]) -> Option<f32> {
        let Some(from) = self.track else {
            self.track = Some(position);
            return None;
        };
        let (dx, dy) = (position[0] - from[0], position[1] - from[1]);
        if dx * dx + dy * dy >= FRONT_STEP_M * FRONT_STEP_M {
            let course = libm::atan2f(dy, dx);
            self.course = Some(course);
            self.first_course = self.first_course.or(Some(course));
            self.track = Some(position);
        }
        self.course
    }

    /// The front of a bearing read before the station moved: its first course, or the fixed
    /// front of a station that never moved.
    pub(crate) fn still_front(&self) -> f32 {
        self.first_course.unwrap_or(self.front)
    }

    /// The antenna's front for a bearing read at `position`, from what came before alone (read
    /// in time order): the station's course once it has moved [`FRONT_STEP_M`], its stated
    /// front before. A live line's bearing gets the same front as the recording's.
    pub fn front_so_far(&mut self, position: [f32; 2]) -> f32 {
        self.course_at(position).unwrap_or(self.front)
    }

    /// The same row with an unmodelled systematic error of sd `sd` (radians) on its bearings:
    /// an error common to the station's bearings (geodesy, mounting, a calibration's residue)
    /// that no number of them averages away. Its variance is added to the offset prior's (the
    /// prior given and in force): indistinguishable from the offset, it is the offset's
    /// uncertainty, so the position covariance carries its share as it carries the prior's
    /// (exactly, for a station whose bearings cannot show its offset: a fixed station, a
    /// calibrated unit on a straight road; a vehicle whose drive measures its offset takes a
    /// common error up there, where it costs the position nothing). A calibrated prior
    /// becomes a free offset with this sd; no prior stays no prior.
    pub fn with_unmodelled(self, sd: f32) -> Self {
        let widen = |p: BiasPrior| BiasPrior {
            mean: p.mean,
            sd: libm::hypotf(p.sd, sd),
        };
        let mut row = Self::new(widen(self.given)).with_direction(self.direction, self.front);
        row.in_force = widen(self.in_force);
        row.unmodelled = sd;
        row
    }

    /// Sd of the station's unmodelled systematic error, radians.
    pub fn unmodelled(&self) -> f32 {
        self.unmodelled
    }

    /// `Ok` when the prior is usable ([`BiasPrior::check`]) and the unmodelled error's sd is
    /// finite and >= 0.
    pub fn check(&self) -> Result<(), Error> {
        self.given.check()?;
        self.direction.check()?;
        check_finite(&[self.unmodelled, self.front])?;
        if self.unmodelled >= 0.0 {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }

    /// The prior the caller gave (its unmodelled error's variance added,
    /// [`StationSlot::with_unmodelled`]).
    pub fn prior(&self) -> BiasPrior {
        self.given
    }

    /// The prior in force for the next fit.
    pub fn prior_in_force(&self) -> BiasPrior {
        self.in_force
    }

    /// Narrow the prior in force to `prior` (the caller's stays as given).
    pub fn set_prior_in_force(&mut self, prior: BiasPrior) {
        self.in_force = prior;
    }

    /// Back to the caller's prior, the last fit forgotten.
    pub fn reset(&mut self) {
        let unmodelled = self.unmodelled;
        *self = Self::new(self.given).with_direction(self.direction, self.front);
        self.unmodelled = unmodelled;
    }

    /// The last fit's offset and its sd, radians (the prior's where the station took no part).
    pub fn offset(&self) -> (f32, f32) {
        (self.bias, self.sd)
    }

    /// Bearings of this station the last fit used.
    pub fn used(&self) -> u32 {
        self.used
    }

    /// Share of the offset's information that came from the last fit's bearings: near 0 when
    /// the prior governs (a fixed station), near 1 when the bearings measured it.
    pub fn measured(&self) -> f32 {
        self.measured
    }

    /// Keep the solver's current offset aside ([`super::StartOffsets::Saved`] starts from it).
    pub(crate) fn keep_current(&mut self) {
        self.saved = self.x;
        self.hsaved = self.hx;
    }

    /// Where the solver's harmonics start (`saved`: where they were kept aside, else the
    /// last fit's when `fitted`, else the prior's mean; a fixed table stays at its mean).
    pub(super) fn start_harmonics(&mut self, from: HarmonicStart) {
        self.hfree = self.n > 0 && self.direction.is_free();
        self.hx = if !self.hfree {
            self.direction.mean
        } else {
            match from {
                HarmonicStart::Prior => self.direction.mean,
                HarmonicStart::Fitted => self.hfit,
                HarmonicStart::Saved => self.hsaved,
                HarmonicStart::Current => self.hx,
            }
        };
    }

    /// Hold the last fit aside, exactly, while other fits use the row.
    pub(super) fn hold(&mut self) {
        self.held = ([self.bias, self.sd, self.measured], self.used);
        self.hheld = [self.hfit, self.hsd];
    }

    /// The fit held aside back, exactly.
    pub(super) fn unhold(&mut self) {
        let ([bias, sd, measured], used) = self.held;
        (self.bias, self.sd, self.measured, self.used) = (bias, sd, measured, used);
        self.x = bias;
        [self.hfit, self.hsd] = self.hheld;
        self.hx = self.hfit;
    }

    /// Forget the last accumulation.
    pub(super) fn clear_blocks(&mut self) {
        self.w = 0.0;
        self.mean_j = [0.0; 2];
        self.mean_r = 0.0;
        self.scatter = [0.0; 3];
        self.cross = [0.0; 2];
        self.mean_u = [0.0; HARMONICS];
        self.scatter_ju = [[0.0; HARMONICS]; 2];
        self.scatter_uu = [0.0; 10];
        self.cross_u = [0.0; HARMONICS];
    }

    /// The harmonic coefficients the cost is taken at.
    pub(super) fn harmonics_at(&self, trial: bool) -> &[f32; HARMONICS] {
        if trial { &self.htrial } else { &self.hx }
    }

    /// The harmonics' prior term of the cost at the current or trial coefficients.
    pub(super) fn harmonic_cost(&self, trial: bool) -> f32 {
        if !self.hfree {
            return 0.0;
        }
        let c = self.harmonics_at(trial);
        let d: [f32; HARMONICS] = core::array::from_fn(|k| c[k] - self.direction.mean[k]);
        0.5 * dot(&d, &d) * self.direction.information()
    }

    /// Add one bearing: Jacobian `j` of its prediction with respect to the position, its
    /// harmonic regressors `u`, weight `w` (information), residual `r` (weighted Welford
    /// update; the harmonics' sums only where they are unknowns).
    pub(super) fn add(&mut self, j: [f32; 2], u: [f32; HARMONICS], w: f32, r: f32) {
        if !(w > 0.0) {
            return;
        }
        let total = self.w + w;
        let f = w / total;
        let dj = [j[0] - self.mean_j[0], j[1] - self.mean_j[1]];
        let dr = r - self.mean_r;
        if self.hfree {
            let du: [f32; HARMONICS] = core::array::from_fn(|k| u[k] - self.mean_u[k]);
            let mut after_u = [0.0f32; HARMONICS];
            for k in 0..HARMONICS {
                self.mean_u[k] += f * du[k];
                after_u[k] = u[k] - self.mean_u[k];
            }
            let after_r = r - (self.mean_r + f * dr);
            for k in 0..HARMONICS {
                for a in 0..2 {
                    self.scatter_ju[a][k] += w * dj[a] * after_u[k];
                }
                for l in k..HARMONICS {
                    self.scatter_uu[packed(k, l)] += w * du[k] * after_u[l];
                }
                self.cross_u[k] += w * du[k] * after_r;
            }
        }
        self.mean_j[0] += f * dj[0];
        self.mean_j[1] += f * dj[1];
        self.mean_r += f * dr;
        let after = [j[0] - self.mean_j[0], j[1] - self.mean_j[1]];
        self.scatter[0] += w * dj[0] * after[0];
        self.scatter[1] += w * dj[0] * after[1];
        self.scatter[2] += w * dj[1] * after[1];
        self.cross[0] += w * dj[0] * (r - self.mean_r);
        self.cross[1] += w * dj[1] * (r - self.mean_r);
        self.w = total;
    }

    /// The offset's diagonal entry damped by `lambda`, (W + I)(1 + lambda).
    fn diagonal(&self, lambda: f32) -> f32 {
        (self.w + self.in_force.information()) * (1.0 + lambda)
    }
}

/// The position's normal equations with every offset eliminated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Reduced {
    /// The reduced 2 x 2 matrix (the inverse of the position's marginal covariance when
    /// undamped).
    pub(super) matrix: [[f32; 2]; 2],
    /// The reduced gradient.
    pub(super) gradient: [f32; 2],
    /// The full matrix's position diagonal (what the damping scales).
    pub(super) diagonal: [f32; 2],
}

/// Eliminate every free offset from the accumulated blocks (damping the full matrix's diagonal
/// by 1 + `lambda`). A free station whose damped diagonal is not positive leaves the offsets
/// undetermined: `None`.
pub(super) fn reduce(stations: &[StationSlot], lambda: f32) -> Option<Reduced> {
    let mut m = [[0.0f32; 2]; 2];
    let mut g = [0.0f32; 2];
    let mut diagonal = [0.0f32; 2];
    for s in stations.iter().filter(|s| s.n > 0) {
        let [jx, jy] = s.mean_j;
        let full = [
            s.scatter[0] + s.w * jx * jx,
            s.scatter[1] + s.w * jx * jy,
            s.scatter[2] + s.w * jy * jy,
        ];
        diagonal[0] += full[0];
        diagonal[1] += full[2];
        let (a, rhs) = s.offset_eliminated(lambda)?;
        m[0][0] += s.scatter[0] + a * jx * jx;
        m[0][1] += s.scatter[1] + a * jx * jy;
        m[1][1] += s.scatter[2] + a * jy * jy;
        g[0] += s.cross[0] + rhs * jx;
        g[1] += s.cross[1] + rhs * jy;
        if s.hfree {
            // The harmonics eliminated next: less M_pc M_cc^-1 [M_cp, g_c].
            let hb = s.harmonic_block(a, rhs, lambda)?;
            let t = hb.times_inverse();
            for i in 0..2 {
                for k in 0..2 {
                    m[i][k] -= dot(&t[i], &hb.m_pc[k]);
                }
                g[i] -= dot(&t[i], &hb.g_c);
            }
        }
    }
    m[1][0] = m[0][1];
    m[0][0] += lambda * diagonal[0];
    m[1][1] += lambda * diagonal[1];
    Some(Reduced {
        matrix: m,
        gradient: g,
        diagonal,
    })
}

/// The harmonics' block of one station once its offset is eliminated: M_cc (damped) inverted,
/// M_pc (row per position coordinate) and the right-hand side g_c.
struct HarmonicBlock {
    inv: [[f32; HARMONICS]; HARMONICS],
    m_pc: [[f32; HARMONICS]; 2],
    g_c: [f32; HARMONICS],
}

impl HarmonicBlock {
    /// M_pc M_cc^-1, a row per position coordinate.
    fn times_inverse(&self) -> [[f32; HARMONICS]; 2] {
        core::array::from_fn(|i| {
            core::array::from_fn(|l| {
                (0..HARMONICS)
                    .map(|k| self.m_pc[i][k] * self.inv[k][l])
                    .sum()
            })
        })
    }
}

impl StationSlot {
    /// Left of the offset's diagonal: a, the weight its mean Jacobian keeps, and rhs, the
    /// residual's (a free offset eliminated at damping `lambda`; a held one keeps W and W r).
    fn offset_eliminated(&self, lambda: f32) -> Option<(f32, f32)> {
        if self.free {
            let h = self.diagonal(lambda);
            if !(h > 0.0) {
                return None;
            }
            let info = self.in_force.information();
            // h - W = I + lambda (W + I): what is left of the mean Jacobian's weight once the
            // offset has taken its share.
            let left = info + lambda * (self.w + info);
            let a = self.w * left / h;
            let rhs = self.w * (self.mean_r * left - info * (self.in_force.mean - self.x)) / h;
            Some((a, rhs))
        } else {
            Some((self.w, self.w * self.mean_r))
        }
    }

    /// The harmonics' block after the offset's elimination (`a`, `rhs` from
    /// [`StationSlot::offset_eliminated`]), damped by `lambda`.
    fn harmonic_block(&self, a: f32, rhs: f32, lambda: f32) -> Option<HarmonicBlock> {
        let info = self.direction.information();
        let mut m = [[0.0f32; HARMONICS]; HARMONICS];
        for k in 0..HARMONICS {
            for l in 0..HARMONICS {
                m[k][l] = self.scatter_uu[packed(k, l)] + a * self.mean_u[k] * self.mean_u[l];
            }
            let full = self.scatter_uu[packed(k, k)] + self.w * self.mean_u[k] * self.mean_u[k];
            m[k][k] += info + lambda * (full + info);
        }
        let inv = inverse_scaled(&m)?;
        let m_pc = core::array::from_fn(|i| {
            core::array::from_fn(|k| self.scatter_ju[i][k] + a * self.mean_j[i] * self.mean_u[k])
        });
        let g_c = core::array::from_fn(|k| {
            self.cross_u[k] + rhs * self.mean_u[k] + info * (self.direction.mean[k] - self.hx[k])
        });
        Some(HarmonicBlock { inv, m_pc, g_c })
    }
}

/// Each free offset's (and harmonics') step given the position's step `dp`
/// (back-substitution), written to the rows' `trial` from their `x`; the largest magnitude of
/// the steps.
pub(super) fn back_substitute(stations: &mut [StationSlot], lambda: f32, dp: [f32; 2]) -> f32 {
    let mut largest = 0.0f32;
    for s in stations.iter_mut() {
        s.trial = s.x;
        s.htrial = s.hx;
        if s.n == 0 {
            continue;
        }
        let mut dc = [0.0f32; HARMONICS];
        if s.hfree {
            let Some(hb) = s
                .offset_eliminated(lambda)
                .and_then(|(a, rhs)| s.harmonic_block(a, rhs, lambda))
            else {
                return f32::NAN;
            };
            let rhs: [f32; HARMONICS] =
                core::array::from_fn(|k| hb.g_c[k] - hb.m_pc[0][k] * dp[0] - hb.m_pc[1][k] * dp[1]);
            for k in 0..HARMONICS {
                dc[k] = dot(&hb.inv[k], &rhs);
                s.htrial[k] = s.hx[k] + dc[k];
                largest = largest.max(libm::fabsf(dc[k]));
            }
        }
        if !s.free {
            continue;
        }
        let h = s.diagonal(lambda);
        let info = s.in_force.information();
        let g = s.w * s.mean_r + info * (s.in_force.mean - s.x);
        let along = s.w * (s.mean_j[0] * dp[0] + s.mean_j[1] * dp[1] + dot(&s.mean_u, &dc));
        let d = (g - along) / h;
        s.trial = s.x + d;
        largest = largest.max(libm::fabsf(d));
    }
    largest
}

/// Each free offset's variance given the position's marginal covariance `c` (the block
/// inverse: 1 / h + W^2 m^T C m / h^2) and the share of its information the bearings gave,
/// written to the rows when `write`; the sum of those shares (the offsets' effective number of
/// unknowns).
pub(super) fn offset_variances(
    stations: &mut [StationSlot],
    c: &[[f32; 2]; 2],
    write: bool,
) -> Option<f32> {
    let mut shares = 0.0f32;
    for s in stations.iter_mut() {
        if s.n == 0 || !(s.free || s.hfree) {
            continue;
        }
        let [jx, jy] = s.mean_j;
        let mut quad = jx * (c[0][0] * jx + c[0][1] * jy) + jy * (c[1][0] * jx + c[1][1] * jy);
        if s.hfree {
            // The harmonics' covariance: Cov_cc = M^-1 + T^T C T, Cov_pc = -C T (T = M^-1 M_cp).
            let (a, rhs) = s.offset_eliminated(0.0)?;
            let hb = s.harmonic_block(a, rhs, 0.0)?;
            let t = hb.times_inverse();
            let ct: [[f32; HARMONICS]; 2] = core::array::from_fn(|i| {
                core::array::from_fn(|k| c[i][0] * t[0][k] + c[i][1] * t[1][k])
            });
            let cov_cc: [[f32; HARMONICS]; HARMONICS] = core::array::from_fn(|k| {
                core::array::from_fn(|l| hb.inv[k][l] + t[0][k] * ct[0][l] + t[1][k] * ct[1][l])
            });
            let info = s.direction.information();
            for k in 0..HARMONICS {
                let share = (1.0 - cov_cc[k][k] * info).clamp(0.0, 1.0);
                if write {
                    s.hsd[k] = libm::sqrtf(cov_cc[k][k].max(0.0));
                }
                shares += share;
            }
            // The offset's quadratic form over (p, c): m_p C m_p + 2 m_p Cov_pc m_u + m_u Cov_cc m_u.
            let u = s.mean_u;
            let cross = -(jx * dot(&ct[0], &u) + jy * dot(&ct[1], &u));
            let uu: f32 = (0..HARMONICS).map(|k| u[k] * dot(&cov_cc[k], &u)).sum();
            quad += 2.0 * cross + uu;
        }
        if !s.free {
            continue;
        }
        let h = s.diagonal(0.0);
        if !(h > 0.0) {
            return None;
        }
        let var = 1.0 / h + s.w * s.w * quad / (h * h);
        let share = (1.0 - var * s.in_force.information()).clamp(0.0, 1.0);
        if write {
            s.sd = libm::sqrtf(var.max(0.0));
            s.measured = share;
        }
        shares += share;
    }
    Some(shares)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::inverse_scaled;

    /// The arrow's elimination against the dense (2 + S)-square inverse it replaces.
    #[test]
    fn the_reduced_system_is_the_dense_one_with_the_offsets_eliminated() {
        // Three stations: one with a prior, one without, one calibrated; a handful of
        // bearings each with varied Jacobians, weights and residuals.
        let priors = [
            BiasPrior {
                mean: 0.01,
                sd: 0.05,
            },
            BiasPrior {
                mean: 0.0,
                sd: f32::INFINITY,
            },
            BiasPrior::calibrated(0.02),
        ];
        let mut stations = priors.map(StationSlot::new);
        let rows: [(usize, [f32; 2], f32, f32); 9] = [
            (0, [1e-3, 2e-4], 400.0, 0.01),
            (0, [8e-4, 3e-4], 300.0, -0.02),
            (0, [9e-4, -1e-4], 500.0, 0.005),
            (1, [-2e-4, 7e-4], 200.0, 0.03),
            (1, [-3e-4, 6e-4], 250.0, -0.01),
            (1, [-1e-4, 9e-4], 150.0, 0.0),
            (2, [5e-4, 5e-4], 100.0, 0.02),
            (2, [4e-4, 6e-4], 120.0, -0.03),
            (2, [6e-4, 4e-4], 80.0, 0.01),
        ];
        let x = [0.012f32, -0.004, 0.02];
        for (s, slot) in stations.iter_mut().enumerate() {
            slot.x = x[s];
            slot.free = slot.in_force.is_free();
            slot.n = 3;
        }
        for &(s, j, w, r) in &rows {
            stations[s].add(j, [0.0; HARMONICS], w, r);
        }
        // The dense matrix over [x, y, b0, b1] (b2 is calibrated: not an unknown).
        let mut h = [[0.0f64; 4]; 4];
        let mut g = [0.0f64; 4];
        for &(s, j, w, r) in &rows {
            let mut jac = [j[0] as f64, j[1] as f64, 0.0, 0.0];
            if s < 2 {
                jac[2 + s] = 1.0;
            }
            for a in 0..4 {
                for b in 0..4 {
                    h[a][b] += w as f64 * jac[a] * jac[b];
                }
                g[a] += w as f64 * jac[a] * r as f64;
            }
        }
        let info = 1.0 / (0.05f64 * 0.05);
        h[2][2] += info;
        g[2] += info * (0.01 - 0.012);
        let lambda = 0.3f32;
        for i in 0..4 {
            h[i][i] *= 1.0 + lambda as f64;
        }
        let h32: [[f32; 4]; 4] = core::array::from_fn(|a| core::array::from_fn(|b| h[a][b] as f32));
        let inv = inverse_scaled(&h32).expect("dense inverse");
        let step: [f64; 4] =
            core::array::from_fn(|a| (0..4).map(|b| inv[a][b] as f64 * g[b]).sum());
        let r = reduce(&stations, lambda).expect("reduced");
        let c = inverse_scaled(&r.matrix).expect("2 x 2 inverse");
        let dp = [
            c[0][0] * r.gradient[0] + c[0][1] * r.gradient[1],
            c[1][0] * r.gradient[0] + c[1][1] * r.gradient[1],
        ];
        back_substitute(&mut stations, lambda, dp);
        let near = |a: f64, b: f64| (a - b).abs() <= 2e-3 * b.abs().max(1e-6);
        assert!(
            near(dp[0] as f64, step[0]) && near(dp[1] as f64, step[1]),
            "{dp:?} {step:?}"
        );
        for s in 0..2 {
            let d = (stations[s].trial - stations[s].x) as f64;
            assert!(near(d, step[2 + s]), "{s}: {d} {}", step[2 + s]);
        }
        assert_eq!(stations[2].trial, stations[2].x);
    }

    /// With harmonics: the arrow's two-stage elimination (offset, then the four coefficients)
    /// against the dense inverse over [x, y, b0, c0 (4), c1 (4)], the step and the variances.
    #[test]
    fn the_harmonics_are_eliminated_as_the_dense_system_says() {
        let direction = |sd: f32| DirectionPrior {
            mean: [0.01, 0.0, -0.01, 0.005],
            sd,
        };
        let mut stations = [
            StationSlot::new(BiasPrior {
                mean: 0.01,
                sd: 0.05,
            })
            .with_direction(direction(0.04), 0.0),
            StationSlot::new(BiasPrior::calibrated(0.02)).with_direction(direction(0.03), 0.0),
        ];
        // Bearings at relative angles round the circle, varied Jacobians, weights, residuals.
        let rows: [(usize, [f32; 2], f32, f32, f32); 12] = [
            (0, [1e-3, 2e-4], 400.0, 0.01, 0.3),
            (0, [8e-4, 3e-4], 300.0, -0.02, 1.2),
            (0, [9e-4, -1e-4], 500.0, 0.005, 2.0),
            (0, [7e-4, 1e-4], 350.0, 0.0, 2.9),
            (0, [6e-4, -2e-4], 450.0, 0.015, -2.2),
            (0, [5e-4, 4e-4], 250.0, -0.01, -1.0),
            (1, [-2e-4, 7e-4], 200.0, 0.03, -0.5),
            (1, [-3e-4, 6e-4], 250.0, -0.01, 0.7),
            (1, [-1e-4, 9e-4], 150.0, 0.0, 1.6),
            (1, [-4e-4, 5e-4], 220.0, 0.01, 2.6),
            (1, [-2e-4, 8e-4], 180.0, -0.02, -2.7),
            (1, [-3e-4, 7e-4], 210.0, 0.005, -1.6),
        ];
        let x = [0.012f32, 0.02];
        let hx = [[0.012f32, 0.001, -0.008, 0.004], [0.0, 0.01, 0.0, -0.01]];
        for (s, slot) in stations.iter_mut().enumerate() {
            slot.x = x[s];
            slot.free = slot.in_force.is_free();
            slot.n = 6;
            slot.hfree = true;
            slot.hx = hx[s];
        }
        for &(s, j, w, r, phi) in &rows {
            stations[s].add(j, super::super::harmonics(phi), w, r);
        }
        const D: usize = 11;
        // Unknowns [x, y, b0, c0 (3..7), c1 (7..11)]; station 1's offset is calibrated.
        let mut h = [[0.0f64; D]; D];
        let mut g = [0.0f64; D];
        for &(s, j, w, r, phi) in &rows {
            let mut jac = [0.0f64; D];
            jac[0] = j[0] as f64;
            jac[1] = j[1] as f64;
            if s == 0 {
                jac[2] = 1.0;
            }
            for (k, u) in super::super::harmonics(phi).iter().enumerate() {
                jac[3 + 4 * s + k] = *u as f64;
            }
            for a in 0..D {
                for b in 0..D {
                    h[a][b] += w as f64 * jac[a] * jac[b];
                }
                g[a] += w as f64 * jac[a] * r as f64;
            }
        }
        let info = 1.0 / (0.05f64 * 0.05);
        h[2][2] += info;
        g[2] += info * (0.01 - 0.012);
        for s in 0..2 {
            let sd = [0.04f64, 0.03][s];
            for k in 0..4 {
                let i = 3 + 4 * s + k;
                h[i][i] += 1.0 / (sd * sd);
                g[i] += (direction(0.0).mean[k] as f64 - hx[s][k] as f64) / (sd * sd);
            }
        }
        let check = |lambda: f32, stations: &mut [StationSlot; 2]| {
            let mut hd = h;
            for i in 0..D {
                hd[i][i] *= 1.0 + lambda as f64;
            }
            let h32: [[f32; D]; D] =
                core::array::from_fn(|a| core::array::from_fn(|b| hd[a][b] as f32));
            let inv = inverse_scaled(&h32).expect("dense inverse");
            let step: [f64; D] =
                core::array::from_fn(|a| (0..D).map(|b| inv[a][b] as f64 * g[b]).sum());
            let r = reduce(stations, lambda).expect("reduced");
            let c = inverse_scaled(&r.matrix).expect("2 x 2 inverse");
            let dp = [
                c[0][0] * r.gradient[0] + c[0][1] * r.gradient[1],
                c[1][0] * r.gradient[0] + c[1][1] * r.gradient[1],
            ];
            back_substitute(stations, lambda, dp);
            let near = |a: f64, b: f64, scale: f64| (a - b).abs() <= 3e-3 * scale;
            let pscale = step[0].abs().max(step[1].abs());
            assert!(
                near(dp[0] as f64, step[0], pscale) && near(dp[1] as f64, step[1], pscale),
                "{dp:?} {step:?}"
            );
            let nscale = step[2..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let d0 = (stations[0].trial - stations[0].x) as f64;
            assert!(near(d0, step[2], nscale), "b0: {d0} {}", step[2]);
            assert_eq!(stations[1].trial, stations[1].x);
            for s in 0..2 {
                for k in 0..4 {
                    let d = (stations[s].htrial[k] - stations[s].hx[k]) as f64;
                    let want = step[3 + 4 * s + k];
                    assert!(near(d, want, nscale), "c{s}{k}: {d} {want}");
                }
            }
            (inv, c)
        };
        check(0.3, &mut stations);
        let (inv, c) = check(0.0, &mut stations);
        // The variances: the dense inverse's diagonal.
        offset_variances(&mut stations, &c, true).expect("variances");
        let close = |a: f32, b: f32| (a - b).abs() <= 3e-3 * b.abs();
        assert!(
            close(stations[0].sd * stations[0].sd, inv[2][2]),
            "{} {}",
            stations[0].sd,
            inv[2][2].sqrt()
        );
        for s in 0..2 {
            for k in 0..4 {
                let want = inv[3 + 4 * s + k][3 + 4 * s + k];
                let got = stations[s].hsd[k] * stations[s].hsd[k];
                assert!(close(got, want), "var c{s}{k}: {got} {want}");
            }
        }
    }
}
