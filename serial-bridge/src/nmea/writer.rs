//! Writing sentences: the checksum, `$body*hh` with its line end, and the fields the `emit`
//! methods share (time, angles, positions, optional numbers).

use super::{LatLon, UtcTime};
use core::fmt::{self, Write};

/// XOR of the bytes of a sentence body: the one checksum of NMEA 0183 (the framing in
/// [`crate::stream`] checks it with this function too).
pub fn checksum(body: &str) -> u8 {
    xor(body.as_bytes())
}

/// XOR of some bytes: NMEA's checksum and the MT frame check sequence, the one place either
/// is computed.
pub fn xor(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |x, b| x ^ b)
}

/// Write `$body*hh\r\n`.
pub fn write_sentence(out: &mut impl Write, body: &str) -> fmt::Result {
    write!(out, "${body}*{:02X}\r\n", checksum(body))
}

/// Formats a time of day as `hhmmss.sss`.
pub struct TimeField(pub UtcTime);

impl fmt::Display for TimeField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ms = self.0.ms_of_day;
        let s = ms / 1000;
        write!(
            f,
            "{:02}{:02}{:02}.{:03}",
            s / 3600,
            s / 60 % 60,
            s % 60,
            ms % 1000
        )
    }
}

/// Formats a latitude or longitude as `ddmm.mmmmmm,H` (`dddmm...` for longitude).
pub struct AngleField {
    /// Degrees, signed.
    pub degrees: f64,
    /// Longitude (three degree digits, E/W) or latitude.
    pub longitude: bool,
}

impl fmt::Display for AngleField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = if self.degrees < 0.0 {
            -self.degrees
        } else {
            self.degrees
        };
        // Six decimals of minutes: 1.9 mm, far below any GPS error.
        let micro_minutes = libm::round(a * 60.0e6) as u64;
        let (deg, rest) = (micro_minutes / 60_000_000, micro_minutes % 60_000_000);
        let hemisphere = match (self.longitude, self.degrees < 0.0) {
            (false, false) => 'N',
            (false, true) => 'S',
            (true, false) => 'E',
            (true, true) => 'W',
        };
        let width = if self.longitude { 3 } else { 2 };
        write!(
            f,
            "{deg:0width$}{:02}.{:06},{hemisphere}",
            rest / 1_000_000,
            rest % 1_000_000
        )
    }
}

/// Formats a position as the four NMEA fields `lat,N|S,lon,E|W`.
pub struct PositionField(pub LatLon);

impl fmt::Display for PositionField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lat = AngleField {
            degrees: self.0.lat,
            longitude: false,
        };
        let lon = AngleField {
            degrees: self.0.lon,
            longitude: true,
        };
        write!(f, "{lat},{lon}")
    }
}

/// A fixed-capacity line buffer that implements `fmt::Write` (no allocator).
pub type Line = heapless::String<128>;

pub(super) struct Opt<T>(pub(super) Option<T>, pub(super) usize);

impl fmt::Display for Opt<f64> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(v) => write!(f, "{v:.prec$}", prec = self.1),
            None => Ok(()),
        }
    }
}

impl fmt::Display for Opt<f32> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        Opt(self.0.map(f64::from), self.1).fmt(f)
    }
}

impl fmt::Display for Opt<u8> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(v) => write!(f, "{v:0width$}", width = self.1),
            None => Ok(()),
        }
    }
}

/// A signed east/west angle as `magnitude,E|W` (both empty when unknown).
pub(super) struct EastWest(pub(super) Option<f64>);

impl fmt::Display for EastWest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(v) if v < 0.0 => write!(f, "{:.1},W", -v),
            Some(v) => write!(f, "{v:.1},E"),
            None => f.write_str(","),
        }
    }
}
