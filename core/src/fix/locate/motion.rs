//! Does the emitter stand still? A fix assumes it does; bearings of an emitter that moves
//! (a drone crossing a city) can still meet near one point, the middle of its path, with a
//! small ellipse: a confident wrong answer. The check (docs/src/field.md, "An emitter that
//! moves"):
//!
//! 1. The bearings are split by time into [`SEGMENTS`] equal spans (early, middle, late).
//! 2. Two models are fitted to the same bearings by Gauss-Newton: the still one (one position)
//!    and the moving one (one position per span). Both share **one offset per station** with
//!    its prior: a station's mounting offset is the same all drive long, so an offset that
//!    shifts the span fixes differently as a vehicle turns, or a network's per-station
//!    offsets, are explained by the still model and do not read as motion.
//! 3. The drop in deviance, divided by the residuals' correlation time (N / N_eff), is
//!    chi-square with 2 (SEGMENTS - 1) degrees of freedom if the emitter stands still (an F
//!    test when the noise was estimated). Below [`MOTION_ALPHA`] the emitter moves.
//!
//! A likelihood-ratio test, not a comparison of separate span fixes: a span of a drive past an
//! emitter gives a fix with an ellipse that is long and curved (the range barely observed),
//! which a Gaussian comparison of span ellipses would misjudge; the deviance does not care.
//!
//! Fixed capacity: up to [`MOTION_STATIONS`] stations (a channel seen by more is not checked),
//! a 2 SEGMENTS-square system, [`MAX_ITERATIONS`] steps.

use super::super::bias::{Sighting, StationSlot};
use crate::linalg::{cholesky, inverse_spd};
use crate::model::bearing::{predicted, wrap};
use crate::stats;

/// Time spans the bearings are split into.
pub const SEGMENTS: usize = 3;
/// The check's false-alarm level: P(an emitter that stands still reads as moving), if the
/// noise model holds. At 1e-3 the network bench (2000 still runs) saw two, at p = 0.0007 and
/// 0.0009 (spans 74-90 m, 3 sds apart), as that level expects; a drone's spans lie 28-98 sds
/// apart (p below 1e-30), so the stricter level costs them nothing.
pub const MOTION_ALPHA: f32 = 1e-5;
/// Bearings a span needs at least for the check to run.
pub const MIN_SPAN_BEARINGS: usize = 8;
/// Stations the check holds offsets for at most.
pub const MOTION_STATIONS: usize = 32;
/// Gauss-Newton steps at most per model.
pub const MAX_ITERATIONS: u32 = 40;

/// Unknowns of the moving model's positions.
const D: usize = 2 * SEGMENTS;

/// One span's position in the moving model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpanFix {
    /// Position (east, north), metres.
    pub position: [f32; 2],
    /// Its covariance, m^2 (offsets integrated out, at the noise used, widened by N / N_eff).
    pub covariance: [[f32; 2]; 2],
    /// First and last time of its bearings, seconds.
    pub time_span: [f32; 2],
    /// Its bearings.
    pub used: u32,
}

/// What the check found: the early and late spans' positions and the test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// The first span.
    pub early: SpanFix,
    /// The last span.
    pub late: SpanFix,
    /// How far apart they lie, metres.
    pub apart_m: f32,
    /// The same in standard deviations of their difference (the joint covariance: the shared
    /// offsets counted once).
    pub apart_sd: f32,
    /// The deviance drop of the moving model over the still one, per degree of freedom and
    /// over N / N_eff.
    pub statistic: f32,
    /// P(a still emitter gives a statistic this large): below [`MOTION_ALPHA`] it moves.
    pub p_value: f32,
}

impl Motion {
    /// Whether the check says the emitter moves.
    pub fn moving(&self) -> bool {
        self.p_value < MOTION_ALPHA
    }
}

/// The noise the check works at: the source's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionNoise {
    /// Every bearing's sigma times this.
    pub scale: f32,
    /// N / N_eff of the residuals.
    pub tau: f32,
    /// Residual degrees of freedom when the scale was estimated (an F test), `None` when the
    /// sigmas are the unit's (chi-square).
    pub dof: Option<f32>,
}

/// The working state: each station's offset, its prior, and the spans' positions.
struct State {
    /// Positions, centred on the bearings' vehicles.
    p: [[f32; 2]; SEGMENTS],
    /// Offsets, radians.
    b: [f32; MOTION_STATIONS],
}

/// The problem: the sightings, how they are split, the priors.
struct Problem<'a, T> {
    /// The bearings, in up to [`SEGMENTS`] slices (any split: each bearing's span is its
    /// time's).
    parts: [&'a [T]; SEGMENTS],
    origin: [f32; 2],
    /// How the bearings are split into spans.
    split: Split,
    /// Spans in use: 1 for the still model, [`SEGMENTS`] for the moving one.
    spans: usize,
    scale: f32,
    /// Each station's prior mean and information (0: no prior; infinite: held).
    mean: [f32; MOTION_STATIONS],
    info: [f32; MOTION_STATIONS],
    /// The station table: each station's direction-dependent error as the fix found it, held
    /// (a property of the antenna, the same whether the emitter moves or not).
    table: &'a [StationSlot],
}

impl<T: Sighting> Problem<'_, T> {
    /// Every bearing.
    fn items(&self) -> impl Iterator<Item = &T> {
        self.parts.iter().flat_map(|p| p.iter())
    }

    /// A sighting's direction-dependent error, the fix's.
    fn direction_error(&self, t: &T) -> f32 {
        self.table
            .get(t.station())
            .map_or(0.0, |row| row.direction_error(t.relative()))
    }

    /// The span of a bearing at `t` (the last span holds the end).
    fn span_of(&self, t: f32) -> usize {
        if self.spans == 1 {
            0
        } else {
            self.split.span(t)
        }
    }

    fn held(&self, s: usize) -> bool {
        !self.info[s].is_finite()
    }

    /// The deviance: the bearings' squared normalised residuals plus the priors'.
    fn cost(&self, x: &State, time: impl Fn(&T) -> f32) -> f32 {
        // Summed in f64: the drop that matters is a few units on thousands.
        let mut c = 0.0f64;
        for it in self.items() {
            let (bg, s) = (it.bearing(), it.station());
            let p = x.p[self.span_of(time(it))];
            let v = [
                bg.vehicle[0] - self.origin[0],
                bg.vehicle[1] - self.origin[1],
            ];
            let r = bg.theta - predicted(&p, &v) - x.b[s] - self.direction_error(it);
            let u = wrap(r) / (self.scale * bg.sigma);
            c += f64::from(u * u);
        }
        for s in 0..MOTION_STATIONS {
            if !self.held(s) {
                let d = x.b[s] - self.mean[s];
                c += f64::from(d * d * self.info[s]);
            }
        }
        c as f32
    }

    /// The normal equations with the free offsets eliminated (each station's Schur
    /// complement): the reduced matrix over the positions, its right-hand side, and per
    /// station what the back-substitution needs (the position column, the diagonal, the
    /// offset's right-hand side).
    #[allow(clippy::type_complexity)]
    fn reduced(
        &self,
        x: &State,
        time: impl Fn(&T) -> f32,
    ) -> (
        [[f32; D]; D],
        [f32; D],
        [[[f32; 2]; SEGMENTS]; MOTION_STATIONS],
        [f32; MOTION_STATIONS],
        [f32; MOTION_STATIONS],
    ) {
        let mut h = [[0.0f32; D]; D];
        let mut g = [0.0f32; D];
        let mut col = [[[0.0f32; 2]; SEGMENTS]; MOTION_STATIONS];
        let mut diag = [0.0f32; MOTION_STATIONS];
        let mut gb = [0.0f32; MOTION_STATIONS];
        for it in self.items() {
            let (bg, s) = (it.bearing(), it.station());
            let k = self.span_of(time(it));
            let p = x.p[k];
            let v = [
                bg.vehicle[0] - self.origin[0],
                bg.vehicle[1] - self.origin[1],
            ];
            let (dx, dy) = (p[0] - v[0], p[1] - v[1]);
            let d2 = (dx * dx + dy * dy).max(1e-6);
            let r = wrap(bg.theta - predicted(&p, &v) - x.b[s] - self.direction_error(it));
            let sd = self.scale * bg.sigma;
            let w = 1.0 / (sd * sd);
            let j = [-dy / d2, dx / d2];
            for a in 0..2 {
                g[2 * k + a] += w * j[a] * r;
                for c in 0..2 {
                    h[2 * k + a][2 * k + c] += w * j[a] * j[c];
                }
                col[s][k][a] += w * j[a];
            }
            diag[s] += w;
            gb[s] += w * r;
        }
        for s in 0..MOTION_STATIONS {
            if self.held(s) || !(diag[s] > 0.0) {
                col[s] = [[0.0; 2]; SEGMENTS];
                diag[s] = 0.0;
                gb[s] = 0.0;
                continue;
            }
            diag[s] += self.info[s];
            gb[s] -= self.info[s] * (x.b[s] - self.mean[s]);
            let flat: [f32; D] = core::array::from_fn(|i| col[s][i / 2][i % 2]);
            for i in 0..D {
                g[i] -= flat[i] * gb[s] / diag[s];
                for j in 0..D {
                    h[i][j] -= flat[i] * flat[j] / diag[s];
                }
            }
        }
        // Spans out of use: an identity that leaves them where they are.
        for k in self.spans..SEGMENTS {
            for a in 0..2 {
                h[2 * k + a][2 * k + a] = 1.0;
                g[2 * k + a] = 0.0;
            }
        }
        (h, g, col, diag, gb)
    }

    /// Gauss-Newton (Levenberg-Marquardt damped) from `x`; the deviance reached.
    fn descend(&self, x: &mut State, time: impl Fn(&T) -> f32 + Copy) -> f32 {
        let mut current = self.cost(x, time);
        let mut lambda = 1e-4f32;
        for _ in 0..MAX_ITERATIONS {
            let (h, g, col, diag, gb) = self.reduced(x, time);
            let mut accepted = false;
            for _ in 0..8 {
                let mut damped = h;
                for (i, row) in damped.iter_mut().enumerate() {
                    row[i] += lambda * h[i][i].max(1e-12);
                }
                let Some(step) = solve(&damped, &g) else {
                    lambda *= 10.0;
                    continue;
                };
                let mut next = State { p: x.p, b: x.b };
                for k in 0..self.spans {
                    next.p[k][0] += step[2 * k];
                    next.p[k][1] += step[2 * k + 1];
                }
                for s in 0..MOTION_STATIONS {
                    if diag[s] > 0.0 {
                        let mut dot = 0.0;
                        for k in 0..SEGMENTS {
                            dot += col[s][k][0] * step[2 * k] + col[s][k][1] * step[2 * k + 1];
                        }
                        next.b[s] += (gb[s] - dot) / diag[s];
                    }
                }
                let c = self.cost(&next, time);
                if c.is_finite() && c <= current {
                    let done = current - c <= 1e-6 * current.abs().max(1.0);
                    *x = next;
                    current = c;
                    lambda = (lambda * 0.1).max(1e-7);
                    accepted = true;
                    if done {
                        return current;
                    }
                    break;
                }
                lambda *= 10.0;
            }
            if !accepted {
                break;
            }
        }
        current
    }
}

/// `m x = g` for a symmetric positive definite `m`.
fn solve(m: &[[f32; D]; D], g: &[f32; D]) -> Option<[f32; D]> {
    let l = cholesky(m)?;
    let mut y = [0.0f32; D];
    for i in 0..D {
        let mut s = g[i];
        for j in 0..i {
            s -= l[i][j] * y[j];
        }
        y[i] = s / l[i][i];
    }
    let mut x = [0.0f32; D];
    for i in (0..D).rev() {
        let mut s = y[i];
        for j in i + 1..D {
            s -= l[j][i] * x[j];
        }
        x[i] = s / l[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// How bearings are split into spans by time: [`SEGMENTS`] spans of `length` seconds from
/// `start` (the last one holds the end).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Split {
    /// Time of the first bearing, seconds.
    pub start: f32,
    /// Each span's length, seconds.
    pub length: f32,
}

impl Split {
    /// The split of `items` (`time` each one's time); `None` without a spread in time.
    pub fn of<T>(items: &[T], time: impl Fn(&T) -> f32) -> Option<Self> {
        let (mut t0, mut t1) = (f32::INFINITY, f32::NEG_INFINITY);
        for it in items {
            let t = time(it);
            t0 = t0.min(t);
            t1 = t1.max(t);
        }
        (t1 > t0 && t0.is_finite() && t1.is_finite()).then_some(Self {
            start: t0,
            length: (t1 - t0) / SEGMENTS as f32,
        })
    }

    /// The span of a bearing at `t`.
    pub fn span(&self, t: f32) -> usize {
        let k = libm::floorf((t - self.start) / self.length);
        if k >= 0.0 {
            (k as usize).min(SEGMENTS - 1)
        } else {
            0
        }
    }
}

/// The check on the bearings of `parts` (a source's, all of one emitter if it stands still),
/// split by time as `split` says (`time` each one's time): the moving model started from
/// `starts` (each span's), the still one from each distinct start (the lowest kept), each
/// station's offset from its row of `stations` (the fit's, [`StationSlot::offset`]) with the
/// prior in force. `None` when the check cannot run: a span with fewer than
/// [`MIN_SPAN_BEARINGS`] bearings, a station beyond [`MOTION_STATIONS`], or a singular system
/// (a span whose bearings do not cross).
pub fn check<T: Sighting>(
    parts: [&[T]; SEGMENTS],
    stations: &[StationSlot],
    starts: [[f32; 2]; SEGMENTS],
    noise: MotionNoise,
    split: Split,
    time: impl Fn(&T) -> f32 + Copy,
) -> Option<Motion> {
    if !(noise.scale > 0.0 && noise.tau >= 1.0 && split.length > 0.0) {
        return None;
    }
    let mut sum = [0.0f64; 2];
    let mut counts = [0usize; SEGMENTS];
    let mut spans = [[f32::INFINITY, f32::NEG_INFINITY]; SEGMENTS];
    for it in parts.iter().flat_map(|p| p.iter()) {
        if it.station() >= MOTION_STATIONS.min(stations.len()) || it.bearing().check().is_err() {
            return None;
        }
        sum[0] += f64::from(it.bearing().vehicle[0]);
        sum[1] += f64::from(it.bearing().vehicle[1]);
        let t = time(it);
        let k = split.span(t);
        counts[k] += 1;
        spans[k] = [spans[k][0].min(t), spans[k][1].max(t)];
    }
    if counts.iter().any(|c| *c < MIN_SPAN_BEARINGS) {
        return None;
    }
    let n: usize = counts.iter().sum();
    let origin = [(sum[0] / n as f64) as f32, (sum[1] / n as f64) as f32];
    let mut problem = Problem {
        parts,
        origin,
        split,
        spans: 1,
        scale: noise.scale,
        mean: [0.0; MOTION_STATIONS],
        info: [0.0; MOTION_STATIONS],
        table: stations,
    };
    let start_b: [f32; MOTION_STATIONS] = core::array::from_fn(|s| {
        let Some(row) = stations.get(s) else {
            return 0.0;
        };
        let prior = row.prior_in_force();
        problem.mean[s] = prior.mean;
        problem.info[s] = if prior.is_free() {
            1.0 / (prior.sd * prior.sd)
        } else {
            f32::INFINITY
        };
        if prior.is_free() {
            row.offset().0
        } else {
            prior.mean
        }
    });
    let centred = starts.map(|p| [p[0] - origin[0], p[1] - origin[1]]);
    // The still model from each distinct start: a start far off could leave it in a local
    // minimum, and a still model fitted short reads as motion.
    let mut still: Option<(f32, State)> = None;
    for (k, p) in centred.iter().enumerate() {
        if centred[..k].contains(p) {
            continue;
        }
        let mut x = State {
            p: [*p; SEGMENTS],
            b: start_b,
        };
        let d = problem.descend(&mut x, time);
        if still.as_ref().is_none_or(|(best, _)| d < *best) {
            still = Some((d, x));
        }
    }
    let (d0, _) = still?;
    problem.spans = SEGMENTS;
    let mut moving = State {
        p: centred,
        b: start_b,
    };
    let d1 = problem.descend(&mut moving, time);
    // The moving model's covariance (offsets integrated out), at the noise used and widened
    // by N / N_eff.
    let (h, ..) = problem.reduced(&moving, time);
    let c = inverse_spd(&h)?;
    let block = |i: usize, j: usize| -> [[f32; 2]; 2] {
        [
            [noise.tau * c[2 * i][2 * j], noise.tau * c[2 * i][2 * j + 1]],
            [
                noise.tau * c[2 * i + 1][2 * j],
                noise.tau * c[2 * i + 1][2 * j + 1],
            ],
        ]
    };
    let last = SEGMENTS - 1;
    let span_fix = |k: usize| SpanFix {
        position: [moving.p[k][0] + origin[0], moving.p[k][1] + origin[1]],
        covariance: block(k, k),
        time_span: spans[k],
        used: counts[k] as u32,
    };
    let (early, late) = (span_fix(0), span_fix(last));
    let d = [
        late.position[0] - early.position[0],
        late.position[1] - early.position[1],
    ];
    let (ee, ll, el) = (block(0, 0), block(last, last), block(0, last));
    let cd = [
        [
            ee[0][0] + ll[0][0] - 2.0 * el[0][0],
            ee[0][1] + ll[0][1] - el[0][1] - el[1][0],
        ],
        [
            ee[1][0] + ll[1][0] - el[0][1] - el[1][0],
            ee[1][1] + ll[1][1] - 2.0 * el[1][1],
        ],
    ];
    let apart_sd = crate::linalg::inverse2(&cd).map_or(0.0, |inv| {
        let m = d[0] * (inv[0][0] * d[0] + inv[0][1] * d[1])
            + d[1] * (inv[1][0] * d[0] + inv[1][1] * d[1]);
        libm::sqrtf(m.max(0.0))
    });
    let q = (2 * (SEGMENTS - 1)) as f32;
    let drop = (d0 - d1).max(0.0) / noise.tau;
    let statistic = drop / q;
    let p_value = match noise.dof {
        // P(F(q, dof) > f) = I_{dof / (dof + q f)}(dof / 2, q / 2).
        Some(dof) if dof > 0.0 => {
            stats::beta_inc(dof / 2.0, q / 2.0, dof / (dof + q * statistic)).ok()?
        }
        Some(_) => return None,
        None => stats::chi2_sf(drop, q).ok()?,
    };
    let apart_m = libm::hypotf(d[0], d[1]);
    [apart_m, apart_sd, statistic, p_value]
        .iter()
        .all(|v| v.is_finite())
        .then_some(Motion {
            early,
            late,
            apart_m,
            apart_sd,
            statistic,
            p_value,
        })
}
