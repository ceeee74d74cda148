//! One bearing as a DF station delivered it: the angle with its time, station and frequency.
//!
//! The pipeline's input ([`super::locate`]) and what the evidence checks judge
//! ([`super::evidence`]): both read it from here, so neither depends on the other for it.

use super::bias::Sighting;
use crate::model::bearing::Bearing;

/// One bearing as a DF station delivered it (32 bytes: a long capture keeps millions).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// The bearing in the local frame (the station's position, angle, its sigma).
    pub bearing: Bearing,
    /// When it was taken, seconds (any origin; only the order and equality matter).
    pub time_s: f32,
    /// The channel's frequency, MHz, if the station reports one.
    pub freq_mhz: Option<f32>,
    /// Which station took it: its row in the caller's station table (each station has its
    /// own offset; a station beyond the table is rejected as unknown).
    pub station: u16,
    /// Whether `time_s` is the station's own stamp of the bearing (a KrakenSDR's epoch, a
    /// `$PFOXB` time), so the station, the time and the channel identify it: the same bearing
    /// arriving twice (a unit's CSV and XML logs) counts once. False where the time is when
    /// it arrived (an Agrelo unit's bearings take the GPS clock's, several to a second).
    pub stamped: bool,
}

const _: () = assert!(core::mem::size_of::<Observation>() == 32);

impl Sighting for Observation {
    fn bearing(&self) -> &Bearing {
        &self.bearing
    }
    fn station(&self) -> usize {
        usize::from(self.station)
    }
}

impl Observation {
    /// A stamped bearing from station 0 without a frequency.
    pub const fn new(bearing: Bearing, time_s: f32) -> Self {
        Self {
            bearing,
            time_s,
            freq_mhz: None,
            station: 0,
            stamped: true,
        }
    }
}
