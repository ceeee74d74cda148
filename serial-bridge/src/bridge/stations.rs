//! The stations the bridge tells apart: who took each bearing, by what its record says.
//!
//! A DF source is a station, not a record kind: a KrakenSDR names itself (its STATION_ID, in
//! the CSV and the XML alike, so one unit's two logs are one station); a unit whose records
//! carry no id (`$PFOXB`, Agrelo, a KrakenSDR with an empty id) is its record kind on the
//! input it came in on (a capture file, a serial port: [`super::Bridge::set_input`]). Each
//! station keeps what is its own: the headings its records carry (so four fixed arrays with
//! boresights 0, 90, 180 and 270 degrees interleaved in one stream are four steady headings,
//! not one vehicle spinning), where it stands (a surveyed position replaces its records'), and
//! whether it ever moved (a station whose positions all lie within [`FIXED_WITHIN_M`] of its
//! first is fixed: its offset cannot be measured from its own bearings, docs/src/networks.md).
//! The table has a fixed capacity `S`: the MCU's bridge holds [`MCU_STATIONS`], a host's as
//! many as it asks for; the bearings of a station beyond it are counted `stations_full`.

use super::heading::{Stamped, TURN_SPACING_MS, yaw_rate};
use super::{BearingKind, Bridge};
use crate::kraken::Station;
use crate::nmea::LatLon;

/// Stations the MCU's bridge tells apart (about 340 bytes each): its DF port carries one unit,
/// in any of the formats the bridge decodes (a record kind without an id is a station of its
/// own, so a port switched from `$PFOXB` to Agrelo to a named KrakenSDR needs three rows), and a
/// fourth keeps a second named unit apart.
pub const MCU_STATIONS: usize = 4;
/// Heading samples kept per station for its yaw rate (16 bytes each), at most one per
/// [`TURN_SPACING_MS`]: 1.5 s or more, past the default yaw window of 1 s.
pub const STATION_TURNS: usize = 16;
/// A station whose positions all lie within this many metres of its first is fixed (a GPS
/// on a mast wanders a few metres).
pub const FIXED_WITHIN_M: f32 = 25.0;

/// Who took a bearing, as its record says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StationKey {
    /// A station that names itself (a KrakenSDR's STATION_ID).
    Named(Station),
    /// A unit whose records carry no id: its record kind on an input (a capture file or a
    /// port, numbered by whoever feeds the bridge).
    Unnamed {
        /// The record kind.
        kind: BearingKind,
        /// The input it came in on.
        input: u8,
    },
}

impl StationKey {
    /// The key of a record of `kind` from `id` (`None` or empty: unnamed) on `input`.
    pub fn of(kind: BearingKind, id: Option<&Station>, input: u8) -> Self {
        match id {
            Some(s) if !s.as_str().is_empty() => Self::Named(*s),
            _ => Self::Unnamed { kind, input },
        }
    }
}

/// What the bridge knows of one station.
#[derive(Debug, Clone)]
pub struct StationState {
    key: StationKey,
    /// Samples of the headings its own records carry, oldest first.
    turns: heapless::Vec<Stamped, STATION_TURNS>,
    /// Where its first placed bearing was, local metres, and where geodetically.
    first: Option<([f32; 2], LatLon)>,
    /// The farthest any of its bearings was from the first, metres.
    span_m: f32,
    /// Bearings it handed on.
    bearings: u32,
    /// A surveyed position: its records' own (or the vehicle's) are replaced by it.
    surveyed: Option<LatLon>,
}

impl StationState {
    fn new(key: StationKey) -> Self {
        Self {
            key,
            turns: heapless::Vec::new(),
            first: None,
            span_m: 0.0,
            bearings: 0,
            surveyed: None,
        }
    }

    /// Who it is.
    pub fn key(&self) -> StationKey {
        self.key
    }

    /// Where its first bearing was taken, if it handed one on.
    pub fn first_position(&self) -> Option<LatLon> {
        self.first.map(|f| f.1)
    }

    /// The farthest its bearings were from its first, metres.
    pub fn span_m(&self) -> f32 {
        self.span_m
    }

    /// Bearings it handed on.
    pub fn bearings(&self) -> u32 {
        self.bearings
    }

    /// Whether it never moved: every bearing within [`FIXED_WITHIN_M`] of its first (or it
    /// stands at a surveyed position).
    pub fn fixed(&self) -> bool {
        self.surveyed.is_some() || self.span_m <= FIXED_WITHIN_M
    }

    /// Its surveyed position, if it was given one.
    pub fn surveyed(&self) -> Option<LatLon> {
        self.surveyed
    }

    /// A heading its own record carried at `time_ms`, for its yaw rate (samples closer than
    /// [`TURN_SPACING_MS`] are skipped; time going backwards starts afresh).
    fn turn_sample(&mut self, deg: f32, time_ms: i64) {
        if let Some(last) = self.turns.last() {
            if time_ms < last.time_ms {
                self.turns.clear();
            } else if time_ms - last.time_ms < TURN_SPACING_MS {
                return;
            }
        }
        if self.turns.is_full() && !self.turns.is_empty() {
            self.turns.remove(0);
        }
        let _ = self.turns.push(Stamped { deg, time_ms });
    }

    /// A bearing of it handed on at local `at`, geodetic `geo`.
    fn placed(&mut self, at: [f32; 2], geo: LatLon) {
        self.bearings = self.bearings.saturating_add(1);
        match self.first {
            None => self.first = Some((at, geo)),
            Some((f, _)) => {
                let d = libm::hypotf(at[0] - f[0], at[1] - f[1]);
                if d > self.span_m {
                    self.span_m = d;
                }
            }
        }
    }
}

/// The stations seen so far, in order of first appearance (a bearing's station index is its
/// place here).
#[derive(Debug, Clone)]
pub(super) struct Stations<const S: usize> {
    table: heapless::Vec<StationState, S>,
}

impl<const S: usize> Stations<S> {
    pub(super) const fn new() -> Self {
        Self {
            table: heapless::Vec::new(),
        }
    }

    /// The index of `key`, added if new and there is room.
    pub(super) fn index_of(&mut self, key: StationKey) -> Option<u16> {
        if let Some(i) = self.table.iter().position(|s| s.key == key) {
            return u16::try_from(i).ok();
        }
        let i = u16::try_from(self.table.len()).ok()?;
        self.table.push(StationState::new(key)).ok()?;
        Some(i)
    }

    pub(super) fn get_mut(&mut self, i: u16) -> Option<&mut StationState> {
        self.table.get_mut(usize::from(i))
    }

    pub(super) fn all(&self) -> &[StationState] {
        &self.table
    }
}

impl<const A: usize, const S: usize> Bridge<A, S> {
    /// The stations seen so far; a bearing's [`station`](super::BearingMeasurement::station)
    /// indexes this.
    pub fn stations(&self) -> &[StationState] {
        self.stations.all()
    }

    /// Records without a station id that arrive from now on came in on input `input` (a
    /// capture file's or a port's number): a unit on another input is another station.
    pub fn set_input(&mut self, input: u8) {
        self.input = input;
    }

    /// The input unnamed records are taken to come in on.
    pub fn input(&self) -> u8 {
        self.input
    }

    /// Station `key` stands at `at`: its bearings are placed there, whatever its records say.
    /// False when the table is full.
    pub fn survey(&mut self, key: StationKey, at: LatLon) -> bool {
        let Some(i) = self.stations.index_of(key) else {
            return false;
        };
        match self.stations.get_mut(i) {
            Some(s) => {
                s.surveyed = Some(at);
                true
            }
            None => false,
        }
    }

    /// The station of a record, added if new: `None` (counted) when the table is full.
    pub(super) fn station_of(&mut self, key: StationKey) -> Option<u16> {
        let i = self.stations.index_of(key);
        if i.is_none() {
            self.counters.stations_full += 1;
        }
        i
    }

    /// Station `i`'s surveyed position, if any.
    pub(super) fn surveyed_at(&mut self, i: u16) -> Option<LatLon> {
        self.stations.get_mut(i).and_then(|s| s.surveyed)
    }

    /// A heading station `i`'s own record carried.
    pub(super) fn station_turn(&mut self, i: u16, deg: f32, time_ms: i64) {
        if let Some(s) = self.stations.get_mut(i) {
            s.turn_sample(deg, time_ms);
        }
    }

    /// Station `i`'s yaw rate at `time_ms` from its own headings (see
    /// [`Bridge::yaw_rate_at`]).
    pub(super) fn station_yaw_rate(&mut self, i: u16, time_ms: i64) -> Option<f32> {
        let age = i64::from(self.config.heading_max_age_ms);
        let window = i64::from(self.config.yaw_window_ms);
        let s = self.stations.get_mut(i)?;
        yaw_rate(&s.turns, time_ms, age, window)
    }

    /// Station `i` handed a bearing on at local `at`, geodetic `geo`.
    pub(super) fn station_placed(&mut self, i: u16, at: [f32; 2], geo: LatLon) {
        if let Some(s) = self.stations.get_mut(i) {
            s.placed(at, geo);
        }
    }
}
