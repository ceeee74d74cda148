//! What the bridge hands on (fixes, bearings, RSSI readings) and what it refused, by reason.

use crate::nmea::LatLon;
use foxhunt_core::Bearing;

/// What turned a bearing to true.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum HeadingSource {
    /// The bearing came true: nothing turned it.
    TrueBearing,
    /// A fresh true heading sentence (HDT, THS).
    TrueHeading,
    /// The record's own heading (KrakenSDR).
    Record,
    /// A fresh magnetic heading (HDG, HDM) corrected to true.
    Magnetic,
    /// Course over ground above the speed gate.
    Course,
}

/// Which kind of record a bearing came in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BearingKind {
    /// `$PFOXB`.
    Pfoxb,
    /// Agrelo `%BBB/Q`.
    Agrelo,
    /// KrakenSDR CSV.
    KrakenCsv,
    /// KrakenSDR / KerberosSDR XML.
    KrakenXml,
}

/// A vehicle fix in the local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VehicleFix {
    /// Milliseconds on the bridge's continuous UTC clock (days counted from the first time).
    pub time_ms: i64,
    /// Position as received.
    pub position: LatLon,
    /// Position in the local frame (east, north), metres.
    pub local: [f32; 2],
    /// Speed over ground, m/s (RMC only).
    pub speed_mps: Option<f32>,
    /// Course over ground, degrees true (RMC only).
    pub course_deg: Option<f32>,
}

/// A bearing ready for the core.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BearingMeasurement {
    /// Time of the bearing on the bridge's clock, ms.
    pub time_ms: i64,
    /// The bearing in the local frame.
    pub bearing: Bearing,
    /// DF quality, 0-100.
    pub quality: f32,
    /// Frequency, MHz (0 when the format has none: Agrelo).
    pub freq_mhz: f64,
    /// The record kind.
    pub kind: BearingKind,
    /// What turned it to true.
    pub heading: HeadingSource,
    /// Its station: its place in [`Bridge::stations`](super::Bridge::stations).
    pub station: u16,
}

/// An RSSI reading from a known anchor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RssiReading {
    /// Index of the anchor in the bridge's table.
    pub anchor: usize,
    /// The anchor's short address.
    pub src_addr: u16,
    /// Link quality as received.
    pub link_quality: u8,
    /// RSSI, dBm.
    pub dbm: f32,
    /// The receiver's timestamp.
    pub timestamp: u32,
}

/// What the bridge hands on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// A new vehicle fix (one per GPS epoch: GGA and RMC of the same second merge).
    Fix(VehicleFix),
    /// A bearing placed in the local frame.
    Bearing(BearingMeasurement),
    /// An RSSI reading.
    Rssi(RssiReading),
}

/// Frames and measurements the bridge rejected, by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BridgeCounters {
    /// Vehicle fixes accepted (epochs).
    pub fixes: u32,
    /// Bearings handed on.
    pub bearings: u32,
    /// RSSI readings handed on.
    pub rssi: u32,
    /// Sentences of types the bridge does not read (GSV, VTG, ...).
    pub unsupported_sentences: u32,
    /// GGA/RMC saying the receiver has no fix.
    pub no_fix_sentences: u32,
    /// Sentences or records with a missing or malformed field.
    pub bad_field: u32,
    /// Heading sentences taken (HDT, THS, HDG, HDM).
    pub headings: u32,
    /// Positions outside the valid range.
    pub bad_position: u32,
    /// Bearings at or below the quality gate (PFOXB quality, Agrelo digit, Kraken CONF).
    pub low_quality: u32,
    /// Agrelo records saying "no bearing" (`0`).
    pub no_bearing: u32,
    /// Relative bearings with no fresh heading, magnetic heading or gated course.
    pub no_heading: u32,
    /// Bearings with no fix at all.
    pub no_fix: u32,
    /// Bearings whose nearest fix is further than the allowed gap.
    pub stale_fix: u32,
    /// Bearings older than the fixes kept (further behind the newest fix than
    /// [`BridgeConfig::fix_span_ms`](super::BridgeConfig::fix_span_ms), or than the history holds).
    pub late: u32,
    /// Bearings turned by a heading while the vehicle (or the station whose record carried
    /// the heading) turned faster than the yaw gate.
    pub turning: u32,
    /// Bearings of a station beyond the station table's capacity.
    pub stations_full: u32,
    /// Bearing records whose time jumped away from their source's clock on their own (a
    /// corrupt digit): the records around them said so (the bridge's `clock`).
    pub time_jump: u32,
    /// Valid MT frames of other commands.
    pub other_mt: u32,
    /// AF_INCOMING_MSG frames too short for their fields.
    pub short_mt: u32,
    /// RSSI frames from addresses not in the anchor table.
    pub unknown_anchor: u32,
}
