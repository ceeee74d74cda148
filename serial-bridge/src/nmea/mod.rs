//! NMEA 0183 sentences as GPSD takes them: positions (GGA, RMC, GLL, GNS), course and speed
//! (VTG), headings (HDT, THS, HDG, HDM) from any two-letter talker, and this project's `$PFOXB`.
//!
//! Decoding works on the checked text between `$` and `*` that [`crate::stream`] delivers.
//! Numbers are parsed as exact decimals (integer mantissa and power of ten) and converted once
//! to `f64`, so a latitude agrees with GPSD's to 1e-9 degrees; no float parser is linked.
//! Every sentence type is a plain `Copy` struct with `parse` and `emit` (smoltcp's `Repr`
//! pattern): `emit` writes the body that `parse` reads back, and is what `foxhunt simulate`
//! uses. [`write_sentence`] adds the `$`, the checksum and the line end.
//!
//! Where GPSD still takes a fix, so do we: a GGA whose fix quality is empty or 0 but which
//! names three or more satellites in use is a (2D) fix, as GPSD decides over its regression
//! suite (mtk-3301, myguide-3100); with fewer it is no fix, and so is any GGA naming zero
//! satellites in use (garmin25lp, haicom-305N).
//!
//! The files, by concept: `position` (time, date, position and the fix sentences GGA, RMC,
//! GLL, GNS with VTG), `heading` (HDT, THS, HDG, HDM), `pfoxb`, `fields` (reading fields:
//! exact decimals, times, angles), `writer` (the checksum and the fields `emit` writes) and
//! `legacy` (the free encoders of older callers). Every public item is re-exported here.

use core::fmt::{self, Write};

mod fields;
mod heading;
mod legacy;
mod pfoxb;
mod position;
mod writer;

#[cfg(test)]
mod tests;

use fields::Fields;
pub(crate) use fields::{Decimal, angle, number, time};
pub use heading::{Hdg, Hdm, Hdt, Ths};
pub use legacy::{gga_body, pfoxb_body, rmc_body};
pub use pfoxb::{Pfoxb, Reference};
pub use position::{Date, Gga, Gll, Gns, KNOT_MPS, LatLon, Rmc, UtcTime, Vtg};
pub use writer::{AngleField, Line, PositionField, TimeField, checksum, write_sentence, xor};

/// Why a sentence gave nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NmeaError {
    /// A sentence type this crate does not decode (GSV, GSA, ...); not an error on the link.
    Unsupported,
    /// The receiver says it has no fix (GGA quality 0, RMC/GLL status V, mode N, empty
    /// position, THS mode V).
    NoFix,
    /// Field `n` (1 = the first after the address) is missing or malformed.
    BadField(u8),
}

impl fmt::Display for NmeaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unsupported => f.write_str("sentence type not decoded"),
            Self::NoFix => f.write_str("receiver reports no fix"),
            Self::BadField(n) => write!(f, "field {n} missing or malformed"),
        }
    }
}

/// A decoded sentence.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sentence {
    /// GGA.
    Gga(Gga),
    /// RMC.
    Rmc(Rmc),
    /// GLL.
    Gll(Gll),
    /// GNS.
    Gns(Gns),
    /// VTG.
    Vtg(Vtg),
    /// HDT.
    Hdt(Hdt),
    /// THS.
    Ths(Ths),
    /// HDG.
    Hdg(Hdg),
    /// HDM.
    Hdm(Hdm),
    /// PFOXB.
    Pfoxb(Pfoxb),
}

/// The common GNSS talkers (any two capital letters are accepted).
pub const TALKERS: [&[u8; 2]; 6] = [b"GP", b"GN", b"GL", b"GA", b"GB", b"BD"];

/// A sentence's talker and type, if its address is two capital letters and three more.
fn address(body: &str) -> Option<([u8; 2], &[u8])> {
    let a = body.split(',').next()?.as_bytes();
    match a {
        [t0, t1, kind @ ..] if t0.is_ascii_uppercase() && t1.is_ascii_uppercase() => {
            Some(([*t0, *t1], kind))
        }
        _ => None,
    }
}

pub(super) fn talker_str(t: &[u8; 2]) -> &str {
    core::str::from_utf8(t).unwrap_or("GP")
}

impl Sentence {
    /// Decode the text between `$` and `*` of a checked sentence.
    pub fn parse(body: &str) -> Result<Self, NmeaError> {
        let f = Fields::split(body);
        if f.get(0) == "PFOXB" {
            return Pfoxb::from_fields(&f).map(Self::Pfoxb);
        }
        let Some((talker, kind)) = address(body) else {
            return Err(NmeaError::Unsupported);
        };
        match kind {
            b"GGA" => Gga::from_fields(&f, talker).map(Self::Gga),
            b"RMC" => Rmc::from_fields(&f, talker).map(Self::Rmc),
            b"GLL" => Gll::from_fields(&f, talker).map(Self::Gll),
            b"GNS" => Gns::from_fields(&f, talker).map(Self::Gns),
            b"VTG" => Vtg::from_fields(&f, talker).map(Self::Vtg),
            b"HDT" => Hdt::from_fields(&f, talker).map(Self::Hdt),
            b"THS" => Ths::from_fields(&f, talker).map(Self::Ths),
            b"HDG" => Hdg::from_fields(&f, talker).map(Self::Hdg),
            b"HDM" => Hdm::from_fields(&f, talker).map(Self::Hdm),
            _ => Err(NmeaError::Unsupported),
        }
    }

    /// Write the body that [`Sentence::parse`] reads back.
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        match self {
            Self::Gga(s) => s.emit(out),
            Self::Rmc(s) => s.emit(out),
            Self::Gll(s) => s.emit(out),
            Self::Gns(s) => s.emit(out),
            Self::Vtg(s) => s.emit(out),
            Self::Hdt(s) => s.emit(out),
            Self::Ths(s) => s.emit(out),
            Self::Hdg(s) => s.emit(out),
            Self::Hdm(s) => s.emit(out),
            Self::Pfoxb(s) => s.emit(out),
        }
    }

    /// The time of day a sentence carries, even one that gives no fix: the bridge's clock
    /// keeps running while the receiver has no fix.
    pub fn time_of(body: &str) -> Option<UtcTime> {
        let (_, kind) = address(body)?;
        let n = match kind {
            b"GGA" | b"RMC" | b"GNS" => 1,
            b"GLL" => 5,
            _ => return None,
        };
        time(body.split(',').nth(n)?)
    }
}

/// Parse one sentence type from its body alone (the address must name it).
macro_rules! parse_one {
    ($t:ident, $variant:ident) => {
        impl $t {
            /// Decode a checked sentence body of this type.
            pub fn parse(body: &str) -> Result<Self, NmeaError> {
                match Sentence::parse(body)? {
                    Sentence::$variant(s) => Ok(s),
                    _ => Err(NmeaError::Unsupported),
                }
            }
        }
    };
}

parse_one!(Gga, Gga);
parse_one!(Rmc, Rmc);
parse_one!(Gll, Gll);
parse_one!(Gns, Gns);
parse_one!(Vtg, Vtg);
parse_one!(Hdt, Hdt);
parse_one!(Ths, Ths);
parse_one!(Hdg, Hdg);
parse_one!(Hdm, Hdm);
parse_one!(Pfoxb, Pfoxb);
