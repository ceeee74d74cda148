//! Headings: true (HDT, THS) and magnetic (HDG, HDM) from any two-letter talker.

use super::fields::{Fields, east_west, heading};
use super::writer::EastWest;
use super::{NmeaError, talker_str};
use core::fmt::{self, Write};

/// HDT: true heading (gyro, dual-antenna GNSS).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hdt {
    /// Talker (HE, GP, ...).
    pub talker: [u8; 2],
    /// Heading, degrees true.
    pub heading_deg: f64,
}

/// THS: true heading and its mode.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ths {
    /// Talker.
    pub talker: [u8; 2],
    /// Heading, degrees true.
    pub heading_deg: f64,
    /// Mode: A autonomous, E estimated, M manual, S simulator (V, not valid, is
    /// [`NmeaError::NoFix`]).
    pub mode: u8,
}

/// HDG: a magnetic sensor's heading with its deviation and the local variation.
///
/// Magnetic heading = sensor + deviation; true heading = magnetic + variation (east positive).
/// The fields are read here as NMEA 0183 defines them (GPSD's decoder indexes them one off).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hdg {
    /// Talker (HC, SD, II, ...).
    pub talker: [u8; 2],
    /// Sensor heading, degrees.
    pub sensor_deg: f64,
    /// Deviation, degrees, east positive; `None` when not given.
    pub deviation_deg: Option<f64>,
    /// Magnetic variation, degrees, east positive; `None` when not given.
    pub variation_deg: Option<f64>,
}

impl Hdg {
    /// Magnetic heading, degrees in [0, 360) (deviation taken as 0 when not given).
    pub fn magnetic_deg(&self) -> f64 {
        wrap_deg(self.sensor_deg + self.deviation_deg.unwrap_or(0.0))
    }

    /// True heading with this sentence's own variation, if it carries one.
    pub fn true_deg(&self) -> Option<f64> {
        self.variation_deg
            .map(|v| wrap_deg(self.magnetic_deg() + v))
    }
}

/// HDM: magnetic heading (deprecated in NMEA 4, still sent by autopilots).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hdm {
    /// Talker.
    pub talker: [u8; 2],
    /// Heading, degrees magnetic.
    pub heading_deg: f64,
}

/// `x` in [0, 360), for sums of angles each already in (-360, 720).
fn wrap_deg(x: f64) -> f64 {
    let mut a = x;
    // At most two steps for the sums built here; no fmod linked.
    for _ in 0..3 {
        if a >= 360.0 {
            a -= 360.0;
        } else if a < 0.0 {
            a += 360.0;
        }
    }
    if (0.0..360.0).contains(&a) { a } else { 0.0 }
}

impl Hdt {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        if f.get(1).is_empty() {
            return Err(NmeaError::NoFix);
        }
        if !matches!(f.get(2), "T" | "") {
            return Err(NmeaError::BadField(2));
        }
        Ok(Self {
            talker,
            heading_deg: f.required(1, heading)?,
        })
    }

    /// Write the body (`HEHDT,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}HDT,{:.2},T",
            talker_str(&self.talker),
            self.heading_deg
        )
    }
}

impl Ths {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let mode = match f.get(2).as_bytes() {
            [b'V'] => return Err(NmeaError::NoFix),
            [m @ (b'A' | b'E' | b'M' | b'S')] => *m,
            _ => return Err(NmeaError::BadField(2)),
        };
        if f.get(1).is_empty() {
            return Err(NmeaError::NoFix);
        }
        Ok(Self {
            talker,
            heading_deg: f.required(1, heading)?,
            mode,
        })
    }

    /// Write the body (`GNTHS,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}THS,{:.2},{}",
            talker_str(&self.talker),
            self.heading_deg,
            self.mode as char
        )
    }
}

impl Hdg {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        if f.get(1).is_empty() {
            return Err(NmeaError::NoFix);
        }
        Ok(Self {
            talker,
            sensor_deg: f.required(1, heading)?,
            deviation_deg: east_west(f, 2)?,
            variation_deg: east_west(f, 4)?,
        })
    }

    /// Write the body (`HCHDG,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}HDG,{:.1},{},{}",
            talker_str(&self.talker),
            self.sensor_deg,
            EastWest(self.deviation_deg),
            EastWest(self.variation_deg)
        )
    }
}

impl Hdm {
    pub(super) fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        if f.get(1).is_empty() {
            return Err(NmeaError::NoFix);
        }
        if !matches!(f.get(2), "M" | "") {
            return Err(NmeaError::BadField(2));
        }
        Ok(Self {
            talker,
            heading_deg: f.required(1, heading)?,
        })
    }

    /// Write the body (`HCHDM,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}HDM,{:.3},M",
            talker_str(&self.talker),
            self.heading_deg
        )
    }
}
