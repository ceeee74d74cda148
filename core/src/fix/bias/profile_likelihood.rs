//! The profile likelihood: the best fit with the position held on a line.

use super::problem::{At, set_up};
use super::solve::{descend, marginal};
use super::stations::StationSlot;
use super::{BiasPrior, BiasedOptions, Sighting, Start, StartOffsets, ml_sources};
use crate::error::{Error, check_finite};
use crate::likelihood::{Gaussian, Likelihood};
use crate::model::bearing::wrap;

/// One point of the profile likelihood: the best fit with the position held on a line (the
/// offsets there are the table's current ones: [`super::StartOffsets::Current`] starts the
/// next slice from them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProfilePoint {
    /// The best position on the line, metres.
    pub position: [f32; 2],
    /// -2 ln L there (the offsets' prior included), up to a constant shared by every point
    /// of the same sightings, loss and scale: differences are likelihood-ratio statistics.
    pub deviance: f32,
    /// Standard deviation of the position along the line, offsets integrated out, metres.
    pub along_sd: f32,
}

/// The profile likelihood at one slice: the position free only along the unit vector
/// `along` through `start.position` (its component across the line held), the offsets free.
/// Where the Fisher ellipse is a poor picture of the likelihood (a range the bearings barely
/// observe), walking such slices outward shows how far the data really allow the fix to go.
/// The table's fitted offsets and sds are left as they were.
pub fn profile<T: Sighting, L: Likelihood>(
    items: &[T],
    stations: &mut [StationSlot],
    start: Start,
    along: [f32; 2],
    loss: &L,
    options: BiasedOptions,
) -> Result<ProfilePoint, Error> {
    check_finite(&along)?;
    let norm = libm::hypotf(along[0], along[1]);
    if !(norm > 0.0) {
        return Err(Error::OutOfRange);
    }
    let along = [along[0] / norm, along[1] / norm];
    let (problem, mut p, geo) = set_up(items, stations, start, loss, options)?;
    descend(&problem, stations, &mut p, options, Some(along));
    let (c, _) = marginal(&problem, stations, p, Some(along))?;
    let point = ProfilePoint {
        position: [p[0] + geo.origin[0], p[1] + geo.origin[1]],
        deviance: 2.0 * problem.cost(stations, p, At::Current),
        along_sd: libm::sqrtf(c[0][0].max(0.0)),
    };
    check_finite(&point.position)?;
    check_finite(&[point.deviance, point.along_sd])?;
    for s in stations.iter() {
        check_finite(&[s.x])?;
    }
    Ok(point)
}

/// Steps of the offset's circle an [`offset_circle`] profile takes (15 degrees apart): fine
/// enough that no basin of the likelihood falls between two steps at the noise of a DF unit
/// (a basin is tens of degrees wide where the drive turns), coarse enough for a live update.
pub const CIRCLE_STEPS: usize = 24;

/// The profile likelihood of one station's offset around its whole circle: at each step the
/// best fit with that offset held and everything else free. Where the data contradict the
/// offset's prior, this is where the offset lies without it: one clear minimum (the drive
/// turned enough to show it), or several (0 against 180 degrees on a drive that barely turns),
/// which no single fix should pick from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OffsetCircle {
    /// -2 ln L (Gaussian, at the options' noise scale; the other stations' priors included)
    /// with the offset held at [`OffsetCircle::offset`] of each step, up to a shared constant;
    /// infinite where that offset gives no fix (the bearings would meet behind the vehicle).
    pub deviance: [f32; CIRCLE_STEPS],
    /// The best position at each step, metres.
    pub position: [[f32; 2]; CIRCLE_STEPS],
    /// The step of the lowest deviance.
    pub best: usize,
    /// The step of the next-lowest local minimum, if the profile has another.
    pub second: Option<usize>,
}

impl OffsetCircle {
    /// The offset of step `k`, radians: -180 degrees + k 15 degrees.
    pub fn offset(k: usize) -> f32 {
        let step = 2.0 * core::f32::consts::PI / CIRCLE_STEPS as f32;
        wrap(-core::f32::consts::PI + step * k as f32)
    }

    /// Whether the profile has a minimum at least `apart` radians from `offset` whose deviance
    /// lies within `gap` of the lowest: a fit at `offset` is then one of several the data allow.
    pub fn rival(&self, offset: f32, apart: f32, gap: f32) -> bool {
        let lowest = self.deviance[self.best];
        [Some(self.best), self.second]
            .into_iter()
            .flatten()
            .any(|k| {
                self.deviance[k] - lowest < gap
                    && libm::fabsf(wrap(Self::offset(k) - offset)) >= apart
            })
    }

    /// The deviance of the second minimum above the best (infinite with one minimum): below
    /// about 9 (a likelihood ratio of 1 in 90) the data do not tell the two offsets apart.
    pub fn second_gap(&self) -> f32 {
        self.second.map_or(f32::INFINITY, |k| {
            self.deviance[k] - self.deviance[self.best]
        })
    }
}

/// The profile over the whole circle of the offset of station `station` (its row in
/// `stations`), started at `from` (a fix of the same sightings): each step's fit starts from
/// its neighbour's position, walking both ways round from the step nearest the row's fitted
/// offset, so the position follows the offset continuously. Fixed work: [`CIRCLE_STEPS`]
/// solves of at most `options.max_iterations` iterations each. The table is left exactly as
/// it came: every row's fit held aside and put back, the row's prior in force restored.
pub fn offset_circle<T: Sighting>(
    items: &[T],
    stations: &mut [StationSlot],
    station: usize,
    from: [f32; 2],
    options: BiasedOptions,
) -> Result<OffsetCircle, Error> {
    check_finite(&from)?;
    let row = stations.get(station).ok_or(Error::OutOfRange)?;
    let (kept, fitted) = (row.in_force, row.bias);
    for s in stations.iter_mut() {
        s.hold();
    }
    let step = 2.0 * core::f32::consts::PI / CIRCLE_STEPS as f32;
    let here = wrap(fitted) + core::f32::consts::PI;
    let k0 = (libm::roundf(here / step) as usize) % CIRCLE_STEPS;
    let mut circle = OffsetCircle {
        deviance: [f32::INFINITY; CIRCLE_STEPS],
        position: [from; CIRCLE_STEPS],
        best: k0,
        second: None,
    };
    let half = CIRCLE_STEPS / 2;
    for (dir, count) in [
        (1usize, half + 1),
        (CIRCLE_STEPS - 1, CIRCLE_STEPS - half - 1),
    ] {
        let mut at = from;
        let mut k = k0;
        for i in 0..count {
            if i > 0 || dir != 1 {
                k = (k + dir) % CIRCLE_STEPS;
            }
            if let Some(s) = stations.get_mut(station) {
                s.in_force = BiasPrior::calibrated(OffsetCircle::offset(k));
            }
            let start = Start {
                position: at,
                offsets: StartOffsets::Prior,
            };
            if let Ok(fix) = ml_sources(items, stations, start, &Gaussian, options) {
                let priors: f32 = stations
                    .iter()
                    .filter(|s| s.free)
                    .map(|s| {
                        let d = wrap(s.bias - s.in_force.mean);
                        d * d * s.in_force.information()
                    })
                    .sum();
                circle.deviance[k] = fix.chi2 + priors;
                circle.position[k] = fix.position;
                at = fix.position;
            }
        }
    }
    if let Some(s) = stations.get_mut(station) {
        s.in_force = kept;
    }
    for s in stations.iter_mut() {
        s.unhold();
    }
    let d = circle.deviance;
    let best = (0..CIRCLE_STEPS)
        .min_by(|&a, &b| d[a].total_cmp(&d[b]))
        .unwrap_or(k0);
    if !d[best].is_finite() {
        return Err(Error::DegenerateGeometry);
    }
    circle.best = best;
    let minimum = |k: usize| {
        let (l, r) = (
            d[(k + CIRCLE_STEPS - 1) % CIRCLE_STEPS],
            d[(k + 1) % CIRCLE_STEPS],
        );
        d[k].is_finite() && d[k] <= l && d[k] < r
    };
    circle.second = (0..CIRCLE_STEPS)
        .filter(|&k| k != best && minimum(k))
        .min_by(|&a, &b| d[a].total_cmp(&d[b]));
    Ok(circle)
}
