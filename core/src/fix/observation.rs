//! One bearing as a DF unit delivered it: the angle with its time, DF source and frequency.
//!
//! The pipeline's input ([`super::locate`]) and what the evidence checks judge
//! ([`super::evidence`]): both read it from here, so neither depends on the other for it.

use super::bias::Sighting;
use crate::model::bearing::Bearing;

/// One bearing as a DF unit delivered it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// The bearing in the local frame (vehicle position, angle, the unit's sigma).
    pub bearing: Bearing,
    /// When it was taken, seconds (any origin; only the order and equality matter).
    pub time_s: f32,
    /// The channel's frequency, MHz, if the unit reports one.
    pub freq_mhz: Option<f32>,
    /// Which DF source took it (< [`MAX_SOURCES`](super::bias::MAX_SOURCES)): each has its own
    /// offset.
    pub source: u8,
}

impl Sighting for Observation {
    fn bearing(&self) -> &Bearing {
        &self.bearing
    }
    fn source(&self) -> usize {
        self.source as usize
    }
}

impl Observation {
    /// A bearing from source 0 without a frequency.
    pub const fn new(bearing: Bearing, time_s: f32) -> Self {
        Self {
            bearing,
            time_s,
            freq_mhz: None,
            source: 0,
        }
    }
}
