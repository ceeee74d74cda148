//! The working storage [`super::locate`] borrows: no allocation, a capacity the caller picks.

use super::super::bias::{BiasPrior, Sighting, StationSlot};
use super::{Observation, StationOffset};
use crate::model::bearing::Bearing;

/// An observation in the working storage, with where it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Item {
    pub(super) obs: Observation,
    /// Its index in the caller's input.
    pub(super) index: u32,
    /// The bearing relative to its antenna's front (counter-clockwise, radians): the
    /// regressor of its station's direction-dependent error ([`super::super::bias::DirectionPrior`]).
    pub(super) relative: f32,
}

impl Item {
    /// An observation as the pipeline holds it (`index`: its place in the caller's input),
    /// its relative bearing not yet known ([`relative_bearings`]).
    pub const fn new(obs: Observation, index: u32) -> Self {
        Self {
            obs,
            index,
            relative: 0.0,
        }
    }

    /// An empty slot, to fill working storage with.
    pub const EMPTY: Self = Self {
        obs: Observation::new(
            Bearing {
                vehicle: [0.0; 2],
                theta: 0.0,
                sigma: 0.0,
            },
            0.0,
        ),
        index: 0,
        relative: 0.0,
    };
}

impl Sighting for Item {
    fn bearing(&self) -> &Bearing {
        &self.obs.bearing
    }
    fn station(&self) -> usize {
        usize::from(self.obs.station)
    }
    fn relative(&self) -> f32 {
        self.relative
    }
}

/// Each item's bearing relative to its antenna (the items in input order, time order within
/// a station): a moving station's front is its course (from where it last moved
/// [`FRONT_STEP_M`](super::super::bias::FRONT_STEP_M) to where it is; before it first moves,
/// its first course), a fixed station's the front its row states. A station whose
/// direction-dependent error is not modelled is left alone.
pub fn relative_bearings(items: &mut [Item], stations: &mut [StationSlot]) {
    use crate::model::bearing::wrap;
    let modelled = |s: &StationSlot| s.direction() != super::super::bias::DirectionPrior::NONE;
    if !stations.iter().any(modelled) {
        return;
    }
    for s in stations.iter_mut() {
        s.start_track();
    }
    // NaN marks a bearing read before its station moved: it takes the station's first course
    // (or fixed front) in a second pass.
    for it in items.iter_mut() {
        let Some(row) = stations.get_mut(it.station()) else {
            continue;
        };
        it.relative = row
            .course_at(it.obs.bearing.vehicle)
            .map_or(f32::NAN, |front| wrap(it.obs.bearing.theta - front));
    }
    for it in items.iter_mut() {
        if it.relative.is_nan()
            && let Some(row) = stations.get(it.station())
        {
            it.relative = wrap(it.obs.bearing.theta - row.still_front());
        }
    }
}

/// Working storage lent by the caller (a host can lend `Vec`s): the capacity is the shortest
/// of the four observation slices; `stations` holds one row per station index (its prior set
/// by the caller, [`StationSlot::new`]; observations of a station beyond it are rejected as
/// unknown), and `offsets` receives each emitter's per-station offsets
/// ([`Source::offsets`](super::Source::offsets)), as many as fit.
pub struct Buffers<'a> {
    pub(super) items: &'a mut [Item],
    pub(super) scratch: &'a mut [Item],
    pub(super) order: &'a mut [u32],
    pub(super) tags: &'a mut [u8],
    pub(super) stations: &'a mut [StationSlot],
    pub(super) offsets: &'a mut [StationOffset],
}

impl<'a> Buffers<'a> {
    /// Borrow the work areas.
    pub fn new(
        items: &'a mut [Item],
        scratch: &'a mut [Item],
        order: &'a mut [u32],
        tags: &'a mut [u8],
        stations: &'a mut [StationSlot],
        offsets: &'a mut [StationOffset],
    ) -> Self {
        Self {
            items,
            scratch,
            order,
            tags,
            stations,
            offsets,
        }
    }

    /// Observations that fit.
    pub fn capacity(&self) -> usize {
        self.items
            .len()
            .min(self.scratch.len())
            .min(self.order.len())
            .min(self.tags.len())
    }
}

/// Working storage for `B` observations (about 80 bytes each) from `S` stations (about 70
/// bytes each, with room for one emitter's offsets of every station), e.g. in a `static` on
/// the MCU.
pub struct Workspace<const B: usize, const S: usize = 4> {
    items: [Item; B],
    scratch: [Item; B],
    order: [u32; B],
    tags: [u8; B],
    stations: [StationSlot; S],
    offsets: [StationOffset; S],
}

impl<const B: usize, const S: usize> Default for Workspace<B, S> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const B: usize, const S: usize> Workspace<B, S> {
    /// Empty storage, every station with the default prior.
    pub const fn new() -> Self {
        Self::with_prior(BiasPrior {
            mean: 0.0,
            sd: super::super::bias::DEFAULT_BIAS_SD,
        })
    }

    /// Empty storage, every station's offset with `prior`.
    pub const fn with_prior(prior: BiasPrior) -> Self {
        Self {
            items: [Item::EMPTY; B],
            scratch: [Item::EMPTY; B],
            order: [0; B],
            tags: [0; B],
            stations: [StationSlot::new(prior); S],
            offsets: [StationOffset::EMPTY; S],
        }
    }

    /// The station table: set a station's prior with `stations()[i] = StationSlot::new(p)`.
    pub fn stations(&mut self) -> &mut [StationSlot; S] {
        &mut self.stations
    }

    /// The emitters' offsets the last [`super::locate`] wrote (each emitter's
    /// [`Source::offsets`](super::Source::offsets) range).
    pub fn offsets(&self) -> &[StationOffset; S] {
        &self.offsets
    }

    /// The storage as [`Buffers`].
    pub fn buffers(&mut self) -> Buffers<'_> {
        Buffers::new(
            &mut self.items,
            &mut self.scratch,
            &mut self.order,
            &mut self.tags,
            &mut self.stations,
            &mut self.offsets,
        )
    }
}
