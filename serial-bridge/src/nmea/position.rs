//! Where the receiver is and how it moves: time, date and position, and the sentences that
//! carry them (GGA, RMC, GLL, GNS) with course and speed over ground (RMC, VTG).

use super::fields::{Fields, date, degrees, non_negative, number, position, small_uint, time};
use super::writer::{Opt, PositionField, TimeField};
use super::{NmeaError, talker_str};
use core::fmt::{self, Write};

/// UTC time of day, milliseconds since midnight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UtcTime {
    /// Milliseconds since 00:00:00 UTC (a leap second gives up to 86 400 999).
    pub ms_of_day: u32,
}

/// Calendar date (UTC).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Date {
    /// Year, four digits (RMC's two digits read as 2000-2099 before 80, else 1980-1999).
    pub year: u16,
    /// Month 1-12.
    pub month: u8,
    /// Day 1-31.
    pub day: u8,
}

/// A geodetic position, decimal degrees (north and east positive).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LatLon {
    /// Latitude, degrees.
    pub lat: f64,
    /// Longitude, degrees.
    pub lon: f64,
}

/// GGA: fix time, position, quality.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gga {
    /// Talker (GP, GN, ...).
    pub talker: [u8; 2],
    /// Time of the fix.
    pub time: UtcTime,
    /// Position.
    pub position: LatLon,
    /// Fix quality (1 GPS, 2 DGPS, 4 RTK fixed, ...; `None` when the receiver sent 0 or left
    /// it empty beside three or more satellites in use, which GPSD takes as a fix).
    pub quality: Option<u8>,
    /// Satellites used, if given.
    pub satellites: Option<u8>,
    /// Horizontal dilution of precision, if given.
    pub hdop: Option<f32>,
    /// Altitude above mean sea level, metres, if given.
    pub altitude_m: Option<f32>,
}

/// RMC: time, date, position, speed and course.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rmc {
    /// Talker.
    pub talker: [u8; 2],
    /// Time of the fix.
    pub time: UtcTime,
    /// Date, if given.
    pub date: Option<Date>,
    /// Position.
    pub position: LatLon,
    /// Speed over ground, knots, if given.
    pub speed_kn: Option<f64>,
    /// Course over ground, degrees true, if given.
    pub course_deg: Option<f64>,
}

/// GLL: position and (since NMEA 2.0) its time.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gll {
    /// Talker.
    pub talker: [u8; 2],
    /// Position.
    pub position: LatLon,
    /// Time of the fix; NMEA 1.5 receivers leave it out.
    pub time: Option<UtcTime>,
}

/// GNS: the multi-constellation fix.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gns {
    /// Talker.
    pub talker: [u8; 2],
    /// Time of the fix.
    pub time: UtcTime,
    /// Position.
    pub position: LatLon,
    /// The first constellation's mode letter (A autonomous, D differential, R/F RTK, E
    /// estimated, ...; never N here).
    pub mode: u8,
    /// Satellites used, if given.
    pub satellites: Option<u8>,
    /// Horizontal dilution of precision, if given.
    pub hdop: Option<f32>,
    /// Altitude above mean sea level, metres, if given.
    pub altitude_m: Option<f32>,
}

/// VTG: course and speed over ground.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Vtg {
    /// Talker.
    pub talker: [u8; 2],
    /// Course over ground, degrees true.
    pub course_deg: Option<f64>,
    /// Course over ground, degrees magnetic.
    pub course_magnetic_deg: Option<f64>,
    /// Speed over ground, knots.
    pub speed_kn: Option<f64>,
    /// Speed over ground, km/h.
    pub speed_kmh: Option<f64>,
    /// The old form (NMEA 1.x: `cogT,cogM,kn,kmh` without unit letters).
    pub old_form: bool,
}

impl Vtg {
    /// Speed in m/s: from knots, else from km/h.
    pub fn speed_mps(&self) -> Option<f64> {
        self.speed_kn
            .map(|k| k * KNOT_MPS)
            .or(self.speed_kmh.map(|k| k / 3.6))
    }
}

/// Metres per second in a knot.
pub const KNOT_MPS: f64 = 1852.0 / 3600.0;

impl Gga {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let quality = f.optional(6, small_uint)?;
        let satellites = f.optional(7, small_uint)?;
        // GPSD's rules (see the module doc): quality 0 or empty is a fix when three or more
        // satellites are in use; no satellites in use is no fix whatever the quality says.
        let no_quality = matches!(quality, None | Some(0));
        if no_quality && satellites.is_none_or(|n| n < 3) || satellites == Some(0) {
            return Err(NmeaError::NoFix);
        }
        let position = position(f, 2)?;
        Ok(Self {
            talker,
            time: f.required(1, time)?,
            position,
            quality: quality.filter(|&q| q > 0),
            satellites,
            hdop: f.optional(8, non_negative)?.map(|v| v as f32),
            altitude_m: f.optional(9, number)?.map(|v| v as f32),
        })
    }

    /// Write the body (`GPGGA,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}GGA,{},{},{},{},{},{},M,0.0,M,,",
            talker_str(&self.talker),
            TimeField(self.time),
            PositionField(self.position),
            Opt(self.quality, 1),
            Opt(self.satellites, 2),
            Opt(self.hdop, 1),
            Opt(self.altitude_m, 1),
        )
    }
}

impl Rmc {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        match f.get(2) {
            "A" => {}
            "V" => return Err(NmeaError::NoFix),
            _ => return Err(NmeaError::BadField(2)),
        }
        // NMEA 2.3 mode indicator: N = data not valid.
        if f.get(12) == "N" {
            return Err(NmeaError::NoFix);
        }
        let position = position(f, 3)?;
        Ok(Self {
            talker,
            time: f.required(1, time)?,
            date: f.optional(9, date)?,
            position,
            speed_kn: f.optional(7, non_negative)?,
            course_deg: f.optional(8, degrees)?,
        })
    }

    /// Write the body (`GPRMC,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}RMC,{},A,{},{},{},",
            talker_str(&self.talker),
            TimeField(self.time),
            PositionField(self.position),
            Opt(self.speed_kn, 2),
            Opt(self.course_deg, 2),
        )?;
        if let Some(d) = self.date {
            write!(out, "{:02}{:02}{:02}", d.day, d.month, d.year % 100)?;
        }
        out.write_str(",,,A")
    }
}

impl Gll {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        // Status (NMEA 2.0) and mode (2.3): V / N are no fix.
        match f.get(6) {
            "" | "A" => {}
            "V" => return Err(NmeaError::NoFix),
            _ => return Err(NmeaError::BadField(6)),
        }
        if f.get(7) == "N" {
            return Err(NmeaError::NoFix);
        }
        let position = position(f, 1)?;
        Ok(Self {
            talker,
            position,
            time: f.optional(5, time)?,
        })
    }

    /// Write the body (`GPGLL,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}GLL,{},",
            talker_str(&self.talker),
            PositionField(self.position)
        )?;
        if let Some(t) = self.time {
            write!(out, "{}", TimeField(t))?;
        }
        out.write_str(",A,A")
    }
}

impl Gns {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let mode = f.get(6).as_bytes();
        // One letter per constellation; the fix is valid when any has one.
        if !mode.iter().all(u8::is_ascii_uppercase) {
            return Err(NmeaError::BadField(6));
        }
        let Some(&first) = mode.iter().find(|&&m| m != b'N') else {
            return Err(NmeaError::NoFix);
        };
        let position = position(f, 2)?;
        Ok(Self {
            talker,
            time: f.required(1, time)?,
            position,
            mode: first,
            satellites: f.optional(7, small_uint)?,
            hdop: f.optional(8, non_negative)?.map(|v| v as f32),
            altitude_m: f.optional(9, number)?.map(|v| v as f32),
        })
    }

    /// Write the body (`GNGNS,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        let mode = if self.mode.is_ascii_uppercase() && self.mode != b'N' {
            self.mode as char
        } else {
            'A'
        };
        write!(
            out,
            "{}GNS,{},{},{mode},{},{},{},0.0,,",
            talker_str(&self.talker),
            TimeField(self.time),
            PositionField(self.position),
            Opt(self.satellites, 2),
            Opt(self.hdop, 1),
            Opt(self.altitude_m, 1),
        )
    }
}

impl Vtg {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let old_form = f.get(2) != "T";
        let (cog, cog_m, kn, kmh, mode) = if old_form {
            (1, 2, 3, 4, 5)
        } else {
            (1, 3, 5, 7, 9)
        };
        if f.get(mode) == "N" {
            return Err(NmeaError::NoFix);
        }
        Ok(Self {
            talker,
            course_deg: f.optional(cog, degrees)?,
            course_magnetic_deg: f.optional(cog_m, degrees)?,
            speed_kn: f.optional(kn, non_negative)?,
            speed_kmh: f.optional(kmh, non_negative)?,
            old_form,
        })
    }

    /// Write the body (`GPVTG,...`), in the form it was read in.
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        let t = talker_str(&self.talker);
        let (c, m) = (Opt(self.course_deg, 2), Opt(self.course_magnetic_deg, 2));
        let (k, h) = (Opt(self.speed_kn, 2), Opt(self.speed_kmh, 2));
        if self.old_form {
            write!(out, "{t}VTG,{c},{m},{k},{h}")
        } else {
            write!(out, "{t}VTG,{c},T,{m},M,{k},N,{h},K,A")
        }
    }
}
