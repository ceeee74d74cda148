//! KrakenSDR records: the "Kraken App" CSV line (`DOA_value.html`, `mydata.csv`) and the XML
//! record df-aggregator polls (`doa.xml`, and the KerberosSDR's older multi-line form).
//!
//! Both are decoded as the bytes arrive, one field (CSV) or one tag or text (XML) at a time,
//! each parsed in place in the demultiplexer's buffer and dropped once read: a 2.5 KB CSV line
//! never sits in memory whole. The 360 values of the CSV's DoA spectrum are kept only in a
//! demultiplexer built with room for them ([`crate::stream::Demux`]'s `SPECTRUM` parameter).
//!
//! CSV, as `kraken_sdr_signal_processor.py` (krakenrf/krakensdr_doa) writes it: fields
//! separated by `, `, 377 of them, a line ending ` \n`: 1 epoch ms (end of the DSP frame), 2
//! bearing relative to the array, 3 confidence, 4 power (dB), 5 frequency (Hz), 6 array type,
//! 7 latency (ms), 8 station id, 9-10 latitude and longitude (0, 0 = no fix), 11-12 heading
//! (true: the GPS course, held below 2 m/s), 13 `GPS`, 14-17 `R`, 18-377 the spectrum. The
//! bearing is clockwise (`360 − θ`) except in the builds of 2023-05 to 2024-07, which wrote the
//! raw anticlockwise θ; nothing in a line tells which, so [`CsvConvention`] is a setting.
//!
//! XML: `<DATA>` with STATION_ID, TIME (ms; seconds in the KerberosSDR form), GPS_TIME,
//! FREQUENCY (MHz), LOCATION/{LATITUDE, LONGITUDE, HEADING, SPEED}, DOA (the raw
//! anticlockwise θ: true bearing = HEADING + 360 − DOA), PWR (power + 100 dB, at least 0), CONF
//! (int(confidence × 100)) and more; unknown elements are skipped. The form with an XML
//! declaration, tabs and newlines (rdf-sim's `kerbs_xml_sample.xml`) reads the same.
//!
//! The CSV line and its decoder are in `csv.rs`, the XML record and its decoder in `xml.rs`;
//! the limits, errors and helpers they share are here.

// The decoders index the token they have measured in the demultiplexer's buffer, and a
// station id its own fixed bytes.
#![allow(clippy::indexing_slicing)]

mod csv;
mod xml;

#[cfg(test)]
pub(crate) mod tests;

pub(crate) use csv::CsvDecoder;
pub use csv::{ArrayType, CsvConvention, KrakenCsv};
pub use xml::KrakenXml;
pub(crate) use xml::XmlDecoder;

use crate::nmea::{Decimal, LatLon};
use core::fmt;

/// Fields of a CSV line.
pub const CSV_FIELDS: u16 = 377;
/// Values of the DoA spectrum (fields 18-377).
pub const SPECTRUM_LEN: usize = 360;
/// Longest CSV field or XML text (a station id, a number).
pub const MAX_FIELD: usize = 32;
/// Longest XML tag (the declaration `<?xml version="1.0" encoding="UTF-8" ?>` is 39).
pub const MAX_TAG: usize = 64;
/// Longest station id kept.
pub const STATION_LEN: usize = 16;
/// Times below this are seconds (the KerberosSDR form), above it milliseconds: 1e11 s is the
/// year 5138, 1e11 ms is 1973.
pub const SECONDS_BELOW: u64 = 100_000_000_000;

/// Why a Kraken record was dropped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum KrakenError {
    /// CSV field `n` (1-based) or an XML value did not parse.
    BadField(u16),
    /// A field, text or tag longer than the framing holds.
    TooLong,
    /// Too few or too many CSV fields, or XML tags out of order.
    Structure,
    /// The record has no bearing (XML without DOA).
    NoBearing,
}

impl fmt::Display for KrakenError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadField(n) => write!(f, "Kraken field {n} malformed"),
            Self::TooLong => f.write_str("Kraken field or tag too long"),
            Self::Structure => f.write_str("Kraken record of the wrong shape"),
            Self::NoBearing => f.write_str("Kraken record without a bearing"),
        }
    }
}

/// A station id, as many bytes as fit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Station {
    bytes: [u8; STATION_LEN],
    len: u8,
}

impl Station {
    /// The id (printable ASCII).
    pub fn as_str(&self) -> &str {
        core::str::from_utf8(&self.bytes[..usize::from(self.len)]).unwrap_or("")
    }

    /// An id from text (cut at [`STATION_LEN`] bytes, non-printable bytes left out).
    pub fn new(s: &str) -> Self {
        let mut st = Self::default();
        for &b in s.as_bytes().iter().filter(|b| (0x20..0x7f).contains(*b)) {
            if usize::from(st.len) < STATION_LEN {
                st.bytes[usize::from(st.len)] = b;
                st.len += 1;
            }
        }
        st
    }
}

/// `x` in [0, 360) for x in (-360, 720).
fn wrap(x: f32) -> f32 {
    let a = if x >= 360.0 {
        x - 360.0
    } else if x < 0.0 {
        x + 360.0
    } else {
        x
    };
    if (0.0..360.0).contains(&a) { a } else { 0.0 }
}

fn decimal(s: &[u8]) -> Option<f64> {
    Decimal::parse_bytes(s).map(Decimal::to_f64)
}

fn unsigned(s: &[u8]) -> Option<u64> {
    if s.is_empty() || s.len() > 19 || !s.iter().all(u8::is_ascii_digit) {
        return None;
    }
    s.iter().try_fold(0u64, |a, &b| {
        a.checked_mul(10)?.checked_add(u64::from(b - b'0'))
    })
}

fn position(lat: Option<f64>, lon: Option<f64>) -> Option<LatLon> {
    match (lat, lon) {
        (Some(lat), Some(lon))
            if (lat != 0.0 || lon != 0.0)
                && (-90.0..=90.0).contains(&lat)
                && (-180.0..=180.0).contains(&lon) =>
        {
            Some(LatLon { lat, lon })
        }
        _ => None,
    }
}

/// What a streaming decoder did with the bytes at the start of its input.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Step<R> {
    /// More bytes needed for the current token.
    NeedMore,
    /// A token of this many bytes was read.
    Took(usize),
    /// The record ended after this many bytes.
    Done(usize, R),
    /// The record is dropped; scanning resumes this many bytes on (0: at the token that
    /// failed, which may start a record of its own).
    Reject(KrakenError, usize),
}

impl<R> Step<R> {
    pub(crate) fn map<S>(self, f: impl FnOnce(R) -> S) -> Step<S> {
        match self {
            Self::NeedMore => Step::NeedMore,
            Self::Took(n) => Step::Took(n),
            Self::Done(n, r) => Step::Done(n, f(r)),
            Self::Reject(e, n) => Step::Reject(e, n),
        }
    }
}
