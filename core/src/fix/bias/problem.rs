//! The problem the solver works on: the cost over the position and the stations' offsets with
//! any loss, and its normal equations (IRLS weights, the priors included) accumulated into the
//! station table, centred on the drive.

use super::super::{Geometry, geometry_of};
use super::direction::{HARMONICS, harmonics};
use super::stations::HarmonicStart;
use super::stations::StationSlot;
use super::summary::Summary;
use super::{BiasedOptions, Sighting, Start, StartOffsets};
use crate::error::{Error, check_finite};
use crate::likelihood::Likelihood;
use crate::linalg::dot;
use crate::model::bearing::{Bearing, predicted, wrap};

/// Residual z - h(p) - b of one sighting at centred position `p` with correction `bias` (the
/// offset and the direction-dependent error).
#[inline]
pub(super) fn residual(b: &Bearing, origin: [f32; 2], p: [f32; 2], bias: f32) -> f32 {
    let s = [b.vehicle[0] - origin[0], b.vehicle[1] - origin[1]];
    wrap(b.theta - predicted(&p, &s) - bias)
}

/// The usable sightings of a station the table holds, with that station and the harmonic
/// regressors of its relative bearing.
pub(super) fn usable<T: Sighting>(
    items: &[T],
    stations: usize,
) -> impl Iterator<Item = (&Bearing, usize, [f32; HARMONICS])> {
    usable_as(items, stations, Known::default())
}

/// What set-up learnt of a problem's sightings, so the solver's passes (a hundred or more per
/// fix, two dozen fixes per offset profile) skip the work whose answer cannot change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Known {
    /// Every sighting's bearing passed [`Bearing::check`]: no need to check it again.
    checked: bool,
    /// Some station's direction-dependent error is estimated or non-zero: the regressors are
    /// needed (otherwise they only multiply zeros, so zeros stand in for them and their sine
    /// and cosine are never taken).
    harmonics: bool,
    /// The loss is quadratic and no station has a direction-dependent error: a station's
    /// bearings from one place stand summed ([`super::summary`]).
    summed: bool,
}

impl Default for Known {
    /// Nothing known: check every bearing, compute every regressor.
    fn default() -> Self {
        Self {
            checked: false,
            harmonics: true,
            summed: false,
        }
    }
}

/// [`usable`], skipping what `known` says is settled.
fn usable_as<T: Sighting>(
    items: &[T],
    stations: usize,
    known: Known,
) -> impl Iterator<Item = (&Bearing, usize, [f32; HARMONICS])> {
    items
        .iter()
        .filter(move |t| t.station() < stations && (known.checked || t.bearing().check().is_ok()))
        .map(move |t| {
            let u = if known.harmonics {
                harmonics(t.relative())
            } else {
                [0.0; HARMONICS]
            };
            (t.bearing(), t.station(), u)
        })
}

/// Which of a row's offsets a cost is taken at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum At {
    /// The solver's current offsets.
    Current,
    /// The trial step's.
    Trial,
}

/// Working problem: the sightings, the loss and the centred origin.
pub(super) struct Problem<'a, T, L> {
    pub(super) items: &'a [T],
    loss: &'a L,
    pub(super) origin: [f32; 2],
    pub(super) scale: f32,
    position_sd: f32,
    known: Known,
}

impl<T: Sighting, L: Likelihood> Problem<'_, T, L> {
    /// The usable sightings ([`usable`]) of a table of `stations` rows, as set-up found them.
    pub(super) fn sightings(
        &self,
        stations: usize,
    ) -> impl Iterator<Item = (&Bearing, usize, [f32; HARMONICS])> {
        usable_as(self.items, stations, self.known)
    }

    /// The bearing's sd at centred position `p` (the position error's share included).
    fn sigma(&self, b: &Bearing, p: [f32; 2]) -> f32 {
        self.sigma_of(b.vehicle, b.sigma, p)
    }

    /// The sd at centred position `p` of a bearing of sd `sigma` taken at `place`.
    fn sigma_of(&self, place: [f32; 2], sigma: f32, p: [f32; 2]) -> f32 {
        let plain = self.scale * sigma;
        if self.position_sd > 0.0 {
            let (dx, dy) = (
                p[0] - (place[0] - self.origin[0]),
                p[1] - (place[1] - self.origin[1]),
            );
            let d2 = (dx * dx + dy * dy).max(1e-6);
            libm::sqrtf(plain * plain + self.position_sd * self.position_sd / d2)
        } else {
            plain
        }
    }

    /// Each row's direction from its one place to centred position `p` (rows whose bearings
    /// were taken at one place; but for the summed rows when `summed`, whose bearings do not
    /// count one by one): the same `atan2` every one of those bearings would take.
    fn aim(&self, stations: &mut [StationSlot], p: [f32; 2], summed: bool) {
        for row in stations.iter_mut() {
            if summed && row.summed.is_some() {
                continue;
            }
            if let Some(place) = row.place {
                let s = [place[0] - self.origin[0], place[1] - self.origin[1]];
                row.toward = predicted(&p, &s);
            }
        }
    }

    /// Bearing `b`'s predicted direction from centred position `p`, from its row's `aim`ed
    /// direction where the row has one place.
    #[inline]
    fn toward(&self, b: &Bearing, row: &StationSlot, p: [f32; 2]) -> f32 {
        if row.place.is_some() {
            row.toward
        } else {
            let s = [b.vehicle[0] - self.origin[0], b.vehicle[1] - self.origin[1]];
            predicted(&p, &s)
        }
    }

    /// The cost at centred position `p` with the rows' offsets `at`.
    pub(super) fn cost(&self, stations: &mut [StationSlot], p: [f32; 2], at: At) -> f32 {
        let offset = |s: &StationSlot| match at {
            At::Current => s.x,
            At::Trial => s.trial,
        };
        let trial = at == At::Trial;
        let summed = self.summed_cost(stations, p, offset);
        let mut c = summed.unwrap_or(0.0);
        self.aim(stations, p, summed.is_some());
        for (b, s, u) in self.sightings(stations.len()) {
            let Some(row) = stations.get(s) else { continue };
            if summed.is_some() && row.summed.is_some() {
                continue;
            }
            let bias = offset(row) + dot(row.harmonics_at(trial), &u);
            let r = wrap(b.theta - self.toward(b, row, p) - bias);
            let sigma = self.sigma(b, p);
            c -= self.loss.ln(r, sigma);
            if self.position_sd > 0.0 {
                // The normalising constant, now that the sd depends on the position.
                c += libm::logf(sigma / (self.scale * b.sigma));
            }
        }
        for s in stations.iter().filter(|s| s.free) {
            let d = offset(s) - s.in_force.mean;
            c += 0.5 * d * d * s.in_force.information();
        }
        for s in stations.iter() {
            c += s.harmonic_cost(trial);
        }
        c
    }

    /// The summed stations' share of the cost at centred position `p` with the rows' offsets
    /// `offset`; `None` where none is summed or some residual might wrap (every bearing then
    /// counts alone).
    fn summed_cost(
        &self,
        stations: &[StationSlot],
        p: [f32; 2],
        offset: impl Fn(&StationSlot) -> f32,
    ) -> Option<f32> {
        if !self.known.summed {
            return None;
        }
        let mut c = 0.0f32;
        for row in stations {
            let Some(g) = row.summed else { continue };
            let r = g.residual(self.origin, p, offset(row))?;
            let sigma = self.sigma_of(g.place, g.sigma, p);
            c -= self.loss.ln_sum(g.n, r, g.scatter, sigma)?;
            if self.position_sd > 0.0 {
                c += g.n * libm::logf(sigma / (self.scale * g.sigma));
            }
        }
        Some(c)
    }

    /// Accumulate the normal equations at centred position `p` and the rows' current offsets
    /// (IRLS weights) into the rows; with `along`, the position's Jacobian is taken along that
    /// unit vector only (its first component; the second is zero).
    pub(super) fn accumulate(
        &self,
        stations: &mut [StationSlot],
        p: [f32; 2],
        along: Option<[f32; 2]>,
    ) {
        for s in stations.iter_mut() {
            s.clear_blocks();
        }
        // The summed stations first, each as one bearing of weight n; where one might wrap,
        // they are cleared again and every bearing counts alone (as in `cost`).
        let mut summed = self.known.summed;
        if summed {
            for row in stations.iter_mut() {
                let Some(g) = row.summed else { continue };
                let Some(r) = g.residual(self.origin, p, row.x) else {
                    summed = false;
                    break;
                };
                let sigma = self.sigma_of(g.place, g.sigma, p);
                let w = g.n * self.loss.irls_weight(r, sigma) / (sigma * sigma);
                let jac = self.jacobian(g.place, p, along);
                row.add(jac, [0.0; HARMONICS], w, r);
            }
            if !summed {
                for s in stations.iter_mut() {
                    s.clear_blocks();
                }
            }
        }
        self.aim(stations, p, summed);
        let n = stations.len();
        for (b, s, u) in self.sightings(n) {
            let Some(row) = stations.get_mut(s) else {
                continue;
            };
            if summed && row.summed.is_some() {
                continue;
            }
            let r = wrap(b.theta - self.toward(b, row, p) - row.x - dot(&row.hx, &u));
            let sigma = self.sigma(b, p);
            let w = self.loss.irls_weight(r, sigma) / (sigma * sigma);
            let jac = self.jacobian(b.vehicle, p, along);
            row.add(jac, u, w, r);
        }
    }

    /// d h / d [x, y] at centred position `p` of h = atan2 from `place` (+ the offset); with
    /// `along`, along that unit vector only (first component; the second is zero).
    fn jacobian(&self, place: [f32; 2], p: [f32; 2], along: Option<[f32; 2]>) -> [f32; 2] {
        let (dx, dy) = (
            p[0] - (place[0] - self.origin[0]),
            p[1] - (place[1] - self.origin[1]),
        );
        let d2 = (dx * dx + dy * dy).max(1e-6);
        let jac = [-dy / d2, dx / d2];
        match along {
            Some([a, c]) => [jac[0] * a + jac[1] * c, 0.0],
            None => jac,
        }
    }
}

/// The geometry check of the usable sightings.
fn sighting_geometry<T: Sighting>(items: &[T], stations: usize) -> Result<Geometry, Error> {
    // The plain geometry check on the bearings of known stations; the others count as
    // skipped.
    let mut g = geometry_of(usable(items, stations).map(|(b, _, _)| b))?;
    g.skipped = items.len() as u32 - g.used;
    Ok(g)
}

/// A checked problem, the solver's starting position (centred on the drive) and the geometry.
pub(super) type SetUp<'a, T, L> = (Problem<'a, T, L>, [f32; 2], Geometry);

/// The checked problem and the solver's starting state (centred on the drive): each row's
/// bearings counted, its offset free or held, its offset started as `start` says.
pub(super) fn set_up<'a, T: Sighting, L: Likelihood>(
    items: &'a [T],
    stations: &mut [StationSlot],
    start: Start,
    loss: &'a L,
    options: BiasedOptions,
) -> Result<SetUp<'a, T, L>, Error> {
    for s in stations.iter() {
        s.in_force.check()?;
    }
    check_finite(&[options.scale, options.tolerance_m, options.position_sd_m])?;
    check_finite(&start.position)?;
    if let StartOffsets::Common(b) = start.offsets {
        check_finite(&[b])?;
    }
    if !(options.scale > 0.0 && options.position_sd_m >= 0.0) {
        return Err(Error::OutOfRange);
    }
    let geo = sighting_geometry(items, stations.len())?;
    for s in stations.iter_mut() {
        s.n = 0;
        s.summary = Summary::EMPTY;
    }
    let mut counted = 0usize;
    for (b, s, _) in usable_as(
        items,
        stations.len(),
        Known {
            checked: false,
            harmonics: false,
            summed: false,
        },
    ) {
        if let Some(row) = stations.get_mut(s) {
            row.n += 1;
            row.summary.add(b);
            counted += 1;
        }
    }
    for s in stations.iter_mut() {
        s.free = s.n > 0 && s.in_force.is_free();
        s.x = if !s.free {
            s.in_force.mean
        } else {
            match start.offsets {
                StartOffsets::Prior => s.in_force.mean,
                StartOffsets::Common(b) => b,
                StartOffsets::Fitted => s.bias,
                StartOffsets::Saved => s.saved,
                StartOffsets::Current => s.x,
            }
        };
        check_finite(&[s.x])?;
        s.start_harmonics(match start.offsets {
            StartOffsets::Prior | StartOffsets::Common(_) => HarmonicStart::Prior,
            StartOffsets::Fitted => HarmonicStart::Fitted,
            StartOffsets::Saved => HarmonicStart::Saved,
            StartOffsets::Current => HarmonicStart::Current,
        });
        check_finite(&s.hx)?;
    }
    let harmonics = stations
        .iter()
        .any(|s| s.hfree || s.hx.iter().chain(&s.htrial).any(|&h| h != 0.0));
    let summed = !harmonics && loss.ln_sum(1.0, 0.0, 0.0, 1.0).is_some();
    for s in stations.iter_mut() {
        s.summed = if summed { s.summary.summed() } else { None };
        s.place = s.summary.one_place();
    }
    let problem = Problem {
        items,
        loss,
        origin: geo.origin,
        scale: options.scale,
        position_sd: options.position_sd_m,
        known: Known {
            checked: counted == items.len(),
            harmonics,
            summed,
        },
    };
    let p = [
        start.position[0] - geo.origin[0],
        start.position[1] - geo.origin[1],
    ];
    Ok((problem, p, geo))
}
