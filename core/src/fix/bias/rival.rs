//! Whether a station's offset can have a rival, read from the fit instead of walked.
//!
//! The ambiguity check walks one station's offset round its whole circle
//! ([`super::offset_circle`]: 24 solves) to find a second minimum the data do not tell from the
//! fit. In a network the other stations' bearings pin the position, and a rival offset far from
//! the fitted one is then out of reach: near the fix the station's own bearings miss by about
//! the offsets' difference, and far from it the other stations' deviance alone is beyond the
//! gap. Both are bounded here from one accumulation of the normal equations at the fix, so a
//! live network's solve skips the walk where it could not find a rival (docs/src/speed.md).

use super::direction::DirectionPrior;
use super::problem::{residual, set_up, usable};
use super::stations::{StationSlot, reduce};
use super::summary::OnePlace;
use super::{BiasedOptions, OffsetCircle, Sighting, Start, StartOffsets};
use crate::likelihood::Gaussian;
use crate::linalg::{dot, eigen2};
use crate::model::bearing::wrap;

/// How many times the far region's bound must exceed what a rival needs: the other stations'
/// deviance is the normal equations' quadratic at the fix, its curvature cut to the nearest
/// other bearing's worst case, and the offsets' elimination is linear too.
const FAR_MARGIN: f32 = 2.0;

/// Whether the profile round station `station`'s offset circle (as [`super::offset_circle`]
/// walks it on `items` from the fit at `at` the table holds) can have no minimum `apart` or
/// more from the fitted offset within `gap` of its lowest. `false` when it cannot say (the
/// station alone, harmonics free, the others not pinning the position): walk the circle.
///
/// With the rival's offset `apart` from the fit, a position within `d = r sin(apart / 2)` of
/// the fix (`r` the station's nearest range to it) turns none of the station's bearings by
/// more than `apart / 2`, so each misses by at least `apart / 2 - |its residual|`. Farther,
/// the other stations' deviance (their offsets eliminated, the priors kept) rises by at
/// least `k^2 lambda d^2 - 2 |g| d` (`lambda` the smallest curvature of its quadratic at the
/// fix, `g` its slope, and `k = R / (R + d)` for `R` the nearest other bearing's range: a
/// bearing turns by at least `k` of its linear turn that far out). Both must exceed the gap
/// plus the deviance the circle's nearest step already costs at the fix (the lowest is no
/// higher; for a fixed station, the less of that and its cost at the fix turned about the
/// station by the step's difference); far out, a fixed station's own bearings pay part of it:
/// their scatter about their mean, which no position or offset takes away.
pub fn no_rival<T: Sighting>(
    items: &[T],
    stations: &mut [StationSlot],
    station: usize,
    at: [f32; 2],
    options: BiasedOptions,
    apart: f32,
    gap: f32,
) -> bool {
    let Some(row) = stations.get(station) else {
        return false;
    };
    let fitted = row.bias;
    let step = 2.0 * core::f32::consts::PI / super::CIRCLE_STEPS as f32;
    let k0 = (libm::roundf((wrap(fitted) + core::f32::consts::PI) / step) as usize)
        % super::CIRCLE_STEPS;
    let nearest_step = OffsetCircle::offset(k0);
    let turn = apart / 2.0;
    let (mut nearest, mut near, mut at_step, mut own) = (f32::INFINITY, 0.0f32, 0.0f32, 0u32);
    let mut scatter = Scatter::new(row.direction() == DirectionPrior::NONE);
    for (b, _, u) in usable(items, stations.len()).filter(|&(_, s, _)| s == station) {
        let e = residual(b, [0.0, 0.0], at, fitted + dot(&row.hfit, &u));
        let w = 1.0 / (options.scale * b.sigma * options.scale * b.sigma);
        nearest = nearest.min(libm::hypotf(at[0] - b.vehicle[0], at[1] - b.vehicle[1]));
        let miss = (apart - turn - libm::fabsf(e)).max(0.0);
        near += w * miss * miss;
        let off = wrap(e + fitted - nearest_step);
        at_step += w * off * off;
        own += 1;
        scatter.add(b.vehicle, e, w);
    }
    let others = usable(items, stations.len())
        .filter(|&(_, s, _)| s != station)
        .map(|(b, _, _)| libm::hypotf(at[0] - b.vehicle[0], at[1] - b.vehicle[1]))
        .fold(f32::INFINITY, f32::min);
    if own == 0 || !(nearest.is_finite() && nearest > 0.0 && others.is_finite()) {
        return false;
    }
    let Some(q) = others_quadratic(items, stations, station, at, options) else {
        return false;
    };
    // The circle's nearest step, at the fix, costs `at_step`. A fixed station's step can cost
    // less: with the fix turned about the station by the step's difference its own residuals
    // are the fit's, and only the others' rise is added (from their quadratic, with the far
    // bound's margin). The walk's step descends from the fix, not from there: in a network
    // that pins the position both lie in the one basin, whose floor is lower than either (the
    // property tests check the two never disagree).
    let turned = scatter.place().map(|s0| {
        let (sin, cos) = libm::sincosf(-wrap(nearest_step - fitted));
        let r = [at[0] - s0[0], at[1] - s0[1]];
        let delta = [
            s0[0] + cos * r[0] - sin * r[1] - at[0],
            s0[1] + sin * r[0] + cos * r[1] - at[1],
        ];
        scatter.at_fit() + FAR_MARGIN * q.rise(delta)
    });
    let need = turned.map_or(at_step, |t| t.min(at_step)) + gap;
    let d = nearest * libm::sinf(turn);
    let k = others / (others + d);
    let far = k * k * q.lambda * d * d - 2.0 * q.pull * d;
    // A fixed station's own bearings keep their scatter about their mean wherever the
    // position and offset go; only the rest of what a rival needs is asked of the others.
    let beyond = need - scatter.least();
    near - 2.0 * q.decrease >= need && far > 0.0 && far >= FAR_MARGIN * beyond
}

/// The other stations' deviance about the fix as the normal equations' quadratic:
/// `-2 g . delta + delta' M delta` for a move `delta`.
struct Quadratic {
    /// M's smallest eigenvalue.
    lambda: f32,
    /// The most the deviance can fall, g' M^-1 g.
    decrease: f32,
    /// |g|.
    pull: f32,
    m: [[f32; 2]; 2],
    g: [f32; 2],
}

impl Quadratic {
    /// The most the deviance rises by for a move `delta`, as the quadratic has it.
    fn rise(&self, delta: [f32; 2]) -> f32 {
        let m = self.m;
        let curve = m[0][0] * delta[0] * delta[0]
            + 2.0 * m[0][1] * delta[0] * delta[1]
            + m[1][1] * delta[1] * delta[1];
        curve + 2.0 * libm::fabsf(self.g[0] * delta[0] + self.g[1] * delta[1])
    }
}

/// The least a station's own deviance can be at any position and offset, when its bearings
/// all come from one place and no direction-dependent error turns them: the predicted
/// bearing and the offset then shift them all alike, and no shift takes away their scatter
/// about their weighted mean. Wrapping cannot either while they lie within 45 degrees of it:
/// a shift that wraps one leaves every one at least 90 degrees off. Zero otherwise.
struct Scatter {
    /// Whether the bound can hold at all (no direction-dependent error).
    alike: bool,
    /// The residuals at the fit, weighted, and where they were taken.
    e: OnePlace,
}

impl Scatter {
    fn new(alike: bool) -> Self {
        Self {
            alike,
            e: OnePlace::EMPTY,
        }
    }

    /// A bearing from `vehicle` missing by `e` at the fit, of weight `w`.
    fn add(&mut self, vehicle: [f32; 2], e: f32, w: f32) {
        self.e.add(vehicle, e, w);
    }

    /// The one place of bearings that no direction-dependent error turns.
    fn place(&self) -> Option<[f32; 2]> {
        self.e.place().filter(|_| self.alike && self.e.w > 0.0)
    }

    /// The bearings' deviance at the fit, sum w e^2.
    fn at_fit(&self) -> f32 {
        self.e.scatter.max(0.0) + self.e.w * self.e.mean * self.e.mean
    }

    fn least(&self) -> f32 {
        if self.place().is_none() {
            return 0.0;
        }
        let (e, quarter) = (&self.e, core::f32::consts::FRAC_PI_4);
        let within = e.low >= e.mean - quarter && e.high <= e.mean + quarter;
        if within { e.scatter.max(0.0) } else { 0.0 }
    }
}

/// The other stations' deviance about `at` as the normal equations' quadratic (every station
/// but `station`, offsets eliminated, priors in force). `None` when harmonics are free or the
/// matrix is not positive definite. The table's fit is left as it came.
fn others_quadratic<T: Sighting>(
    items: &[T],
    stations: &mut [StationSlot],
    station: usize,
    at: [f32; 2],
    options: BiasedOptions,
) -> Option<Quadratic> {
    for s in stations.iter_mut() {
        s.hold();
    }
    let start = Start {
        position: at,
        offsets: StartOffsets::Fitted,
    };
    let reduced = set_up(items, stations, start, &Gaussian, options)
        .ok()
        .filter(|_| !stations.iter().any(|s| s.hfree))
        .and_then(|(problem, p, _)| {
            problem.accumulate(stations, p, None);
            let row = stations.get_mut(station)?;
            let own = row.n;
            row.n = 0;
            let reduced = reduce(stations, 0.0);
            if let Some(row) = stations.get_mut(station) {
                row.n = own;
            }
            reduced
        });
    for s in stations.iter_mut() {
        s.unhold();
    }
    let r = reduced?;
    let m = r.matrix;
    let (a, b, _) = eigen2(&m)?;
    let lambda = a.min(b);
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    if !(lambda > 0.0 && det > 0.0) {
        return None;
    }
    let g = r.gradient;
    // g' M^-1 g with the 2 x 2 inverse written out.
    let decrease =
        (m[1][1] * g[0] * g[0] - 2.0 * m[0][1] * g[0] * g[1] + m[0][0] * g[1] * g[1]) / det;
    Some(Quadratic {
        lambda,
        decrease,
        pull: libm::hypotf(g[0], g[1]),
        m,
        g,
    })
}
