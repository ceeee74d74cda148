//! Agrelo `%BBB/Q`: the serial output of amateur Doppler DF units (Agrelo DFjr, AHHA
//! MicroFinder, PicoDopp, KN2C DF 2020T, PA3BNX SoundDoppler), 4800 baud, 15-20 a second.
//!
//! `%`, the bearing, `/`, one quality digit, a line end. APRS 1.2 pads the bearing to three
//! digits; real units send it unpadded (`%0/7`, `%90/3`: the KN2C unit's test script), with a
//! decimal (`%136.0/9`), with `\` for `/`, and with a trailing magnetic bearing
//! (`%136.0/8/158.0`), all of which Xastir's reader notes. The bearing is relative to the
//! vehicle, clockwise; `0` means "no bearing" and 360 dead ahead. Quality 0 is unusable, 1-8
//! increasing, 9 entered by hand. There is no timestamp: a record takes its arrival time in
//! the stream (the bridge's clock when it arrives, which the latest GPS sentence set).
//!
//! A record ends at CR or LF, or where the next record (`%`) or sentence (`$`) starts, since
//! units that share a line with their own GPS may not end it.

// The record scanner slices the bytes it has just measured.
#![allow(clippy::indexing_slicing)]

use core::fmt::{self, Write};

/// Longest record the framing looks at, `%` to the line end.
pub const MAX_RECORD: usize = 24;

/// Why an Agrelo record gave nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AgreloError {
    /// Not `%bearing/quality[/magnetic]`.
    Malformed,
    /// A bearing outside [0, 360].
    BadBearing,
}

impl fmt::Display for AgreloError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Malformed => "not an Agrelo %bearing/quality record",
            Self::BadBearing => "Agrelo bearing outside 0-360",
        })
    }
}

/// One Agrelo record.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Agrelo {
    /// Bearing as sent, degrees clockwise from the vehicle's front (0 = no bearing).
    pub bearing_deg: f32,
    /// Quality digit 0-9.
    pub quality: u8,
    /// The trailing magnetic bearing some units add.
    pub magnetic_deg: Option<f32>,
}

impl Agrelo {
    /// The relative bearing in [0, 360), or `None` for "no bearing" (`0`).
    pub fn bearing(&self) -> Option<f32> {
        if self.bearing_deg == 0.0 {
            None
        } else if self.bearing_deg >= 360.0 {
            Some(0.0)
        } else {
            Some(self.bearing_deg)
        }
    }

    /// Quality on the 0-100 scale of the bridge's gate (9 = 100).
    pub fn quality_percent(&self) -> f32 {
        f32::from(self.quality) * (100.0 / 9.0)
    }

    /// Decode a record: its text from `%` up to (not including) the line end.
    pub fn parse(text: &str) -> Result<Self, AgreloError> {
        let rest = text.strip_prefix('%').ok_or(AgreloError::Malformed)?;
        let mut parts = rest.split(['/', '\\']);
        let bearing = parts.next().ok_or(AgreloError::Malformed)?;
        let quality = parts.next().ok_or(AgreloError::Malformed)?;
        let magnetic = parts.next();
        if parts.next().is_some() {
            return Err(AgreloError::Malformed);
        }
        let quality = match quality.as_bytes() {
            [q @ b'0'..=b'9'] => q - b'0',
            _ => return Err(AgreloError::Malformed),
        };
        Ok(Self {
            bearing_deg: angle(bearing)?,
            quality,
            magnetic_deg: magnetic.map(angle).transpose()?,
        })
    }

    /// Write the record (`%` to the quality digit or the magnetic bearing), without a line
    /// end: whole bearings unpadded (`%90/3`), others with one decimal (`%136.5/9`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        out.write_char('%')?;
        write_angle(out, self.bearing_deg)?;
        write!(out, "/{}", self.quality.min(9))?;
        if let Some(m) = self.magnetic_deg {
            out.write_char('/')?;
            write_angle(out, m)?;
        }
        Ok(())
    }
}

fn write_angle(out: &mut impl Write, a: f32) -> fmt::Result {
    let tenths = libm::roundf(a * 10.0) as u32;
    if tenths.is_multiple_of(10) {
        write!(out, "{}", tenths / 10)
    } else {
        write!(out, "{}.{}", tenths / 10, tenths % 10)
    }
}

/// `ddd[.d...]`, 0 to 360.
fn angle(s: &str) -> Result<f32, AgreloError> {
    let b = s.as_bytes();
    let int = b.iter().take_while(|c| c.is_ascii_digit()).count();
    if int == 0 || int > 3 {
        return Err(AgreloError::Malformed);
    }
    let d = crate::nmea::Decimal::parse_bytes(b).ok_or(AgreloError::Malformed)?;
    let v = d.to_f64() as f32;
    if (0.0..=360.0).contains(&v) {
        Ok(v)
    } else {
        Err(AgreloError::BadBearing)
    }
}

/// The framing's verdict on bytes starting with `%`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scan {
    /// A record of `text` bytes, then `end` bytes of line end (0 when the next record starts
    /// right after it).
    Valid { text: usize, end: usize },
    /// Not a record; `started` when it began like one (`%` and a digit).
    Invalid { started: bool },
    /// More bytes needed.
    Incomplete,
}

/// Check a candidate at the start of `bytes` (which starts with `%`). At the end of the stream
/// (`ended`) a record needs no line end.
pub(crate) fn scan(bytes: &[u8], ended: bool) -> Scan {
    let Some(&first) = bytes.get(1) else {
        return Scan::Incomplete;
    };
    if !first.is_ascii_digit() {
        return Scan::Invalid { started: false };
    }
    for (i, &b) in bytes.iter().enumerate().take(MAX_RECORD).skip(2) {
        let end = match b {
            b'\r' | b'\n' => 1,
            b'$' | b'%' => 0,
            b'0'..=b'9' | b'.' | b'/' | b'\\' => continue,
            _ => return Scan::Invalid { started: true },
        };
        let ok = core::str::from_utf8(&bytes[..i])
            .ok()
            .is_some_and(|t| Agrelo::parse(t).is_ok());
        return if ok {
            Scan::Valid { text: i, end }
        } else {
            Scan::Invalid { started: true }
        };
    }
    if bytes.len() >= MAX_RECORD {
        return Scan::Invalid { started: true };
    }
    if ended {
        let ok = core::str::from_utf8(bytes)
            .ok()
            .is_some_and(|t| Agrelo::parse(t).is_ok());
        if ok {
            return Scan::Valid {
                text: bytes.len(),
                end: 0,
            };
        }
        return Scan::Invalid { started: true };
    }
    Scan::Incomplete
}

#[cfg(test)]
mod tests {
    use super::*;

    fn text(a: &Agrelo) -> heapless::String<24> {
        let mut s = heapless::String::new();
        a.emit(&mut s).expect("fits");
        s
    }

    #[test]
    fn the_units_own_examples() {
        // menloparkinnovation/FoxHunt device_agent/simulate_test.sh (a KN2C DF 2020T agent).
        for (t, b, q) in [
            ("%0/7", 0.0, 7),
            ("%90/3", 90.0, 3),
            ("%270/5", 270.0, 5),
            ("%359/2", 359.0, 2),
            ("%240/1", 240.0, 1),
        ] {
            let a = Agrelo::parse(t).expect(t);
            assert_eq!(
                (a.bearing_deg, a.quality, a.magnetic_deg),
                (b, q, None),
                "{t}"
            );
            assert_eq!(text(&a).as_str(), t);
        }
        assert_eq!(
            Agrelo::parse("%0/7").expect("0").bearing(),
            None,
            "0 is no bearing"
        );
        // APRS 1.2's padded form and the decimal, backslash and magnetic forms (docs/src/formats/
        // bearings.md, "Agrelo", after Xastir's notes).
        assert_eq!(Agrelo::parse("%045/7").map(|a| a.bearing()), Ok(Some(45.0)));
        let a = Agrelo::parse("%136.0/9").expect("decimal");
        assert_eq!((a.bearing_deg, a.quality), (136.0, 9));
        assert_eq!(Agrelo::parse("%136.0\\9").map(|a| a.quality), Ok(9));
        let a = Agrelo::parse("%136.0/8/158.0").expect("magnetic");
        assert_eq!(a.magnetic_deg, Some(158.0));
        assert_eq!(text(&a).as_str(), "%136/8/158");
        assert_eq!(Agrelo::parse("%360/7").map(|a| a.bearing()), Ok(Some(0.0)));
    }

    #[test]
    fn rejects() {
        for t in [
            "%", "%/7", "%90", "%90/", "%90/12", "%1234/5", "%90/7/", "%9.9.9/1", "%90/a",
        ] {
            assert_eq!(Agrelo::parse(t), Err(AgreloError::Malformed), "{t}");
        }
        assert_eq!(Agrelo::parse("%361/5"), Err(AgreloError::BadBearing));
    }

    #[test]
    fn framing() {
        assert_eq!(scan(b"%90/3\r\n", false), Scan::Valid { text: 5, end: 1 });
        assert_eq!(scan(b"%90/3$GP", false), Scan::Valid { text: 5, end: 0 });
        assert_eq!(scan(b"%90/3", false), Scan::Incomplete);
        assert_eq!(scan(b"%90/3", true), Scan::Valid { text: 5, end: 0 });
        assert_eq!(scan(b"%x", false), Scan::Invalid { started: false });
        assert_eq!(scan(b"%9x", false), Scan::Invalid { started: true });
        assert_eq!(scan(b"%90/33\r", false), Scan::Invalid { started: true });
    }
}
