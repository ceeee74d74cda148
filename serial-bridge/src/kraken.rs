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

use crate::nmea::{Decimal, LatLon};
use core::fmt::{self, Write};

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

/// Which way the CSV's bearing turns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum CsvConvention {
    /// Clockwise from the array's front, `360 − θ` (builds before 2023-05 and after 2024-07).
    #[default]
    Clockwise,
    /// The raw anticlockwise θ (builds of 2023-05 to 2024-07).
    Anticlockwise,
}

/// The array geometry named in field 6.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ArrayType {
    /// Uniform circular array.
    Uca,
    /// Uniform linear array.
    Ula,
    /// Anything else (`Custom`, ...).
    Other,
}

/// One "Kraken App" CSV line (one channel).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KrakenCsv {
    /// End of the DSP frame, ms since 1970 (the unit's clock, not GPS time).
    pub epoch_ms: u64,
    /// Field 2 as written, degrees (may read 360).
    pub bearing_deg: f32,
    /// Confidence (the DSP's raw figure).
    pub confidence: f32,
    /// Power, dB.
    pub power_db: f32,
    /// Frequency, Hz.
    pub freq_hz: u64,
    /// Array geometry.
    pub array: ArrayType,
    /// Acquisition latency, ms.
    pub latency_ms: u32,
    /// Station id.
    pub station: Station,
    /// The unit's position; `None` for its "no fix" (0, 0).
    pub position: Option<LatLon>,
    /// Heading (true, clockwise), degrees.
    pub heading_deg: f32,
}

impl KrakenCsv {
    /// The bearing relative to the array, clockwise, in [0, 360), under a convention.
    pub fn relative_deg(&self, c: CsvConvention) -> f32 {
        let b = wrap(self.bearing_deg);
        match c {
            CsvConvention::Clockwise => b,
            CsvConvention::Anticlockwise => wrap(360.0 - b),
        }
    }

    /// Write the line (with its ` \n`), the spectrum from `spectrum` (zeros past its end).
    pub fn emit(&self, spectrum: &[f32], out: &mut impl Write) -> fmt::Result {
        let array = match self.array {
            ArrayType::Uca => "UCA",
            ArrayType::Ula => "ULA",
            ArrayType::Other => "Custom",
        };
        let (lat, lon) = self.position.map_or((0.0, 0.0), |p| (p.lat, p.lon));
        write!(
            out,
            "{}, {}, {:.2}, {:.1}, {}, {array}, {}, {}, {lat:.7}, {lon:.7}, {:.1}, {:.1}, GPS, R, R, R, R",
            self.epoch_ms,
            self.bearing_deg,
            self.confidence,
            self.power_db,
            self.freq_hz,
            self.latency_ms,
            self.station.as_str(),
            self.heading_deg,
            self.heading_deg,
        )?;
        for i in 0..SPECTRUM_LEN {
            write!(out, ", {:.2}", spectrum.get(i).copied().unwrap_or(0.0))?;
        }
        out.write_str(" \n")
    }
}

/// One XML record.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KrakenXml {
    /// Station id.
    pub station: Station,
    /// TIME in ms since 1970 (seconds in the KerberosSDR form, converted).
    pub time_ms: Option<u64>,
    /// GPS_TIME, ms since 1970 (0 = none).
    pub gps_time_ms: Option<u64>,
    /// Frequency, MHz.
    pub freq_mhz: Option<f64>,
    /// The unit's position; `None` when absent or (0, 0).
    pub position: Option<LatLon>,
    /// Heading (true, clockwise), degrees.
    pub heading_deg: Option<f32>,
    /// Speed, m/s.
    pub speed_mps: Option<f32>,
    /// DOA as written: the raw anticlockwise θ, degrees.
    pub doa_deg: f32,
    /// PWR: power + 100 dB.
    pub pwr: Option<f32>,
    /// CONF: int(confidence × 100).
    pub conf: Option<f32>,
}

impl KrakenXml {
    /// The bearing relative to the array, clockwise: 360 − DOA, in [0, 360).
    pub fn relative_deg(&self) -> f32 {
        wrap(360.0 - wrap(self.doa_deg))
    }

    /// The true bearing df-aggregator computes, HEADING + 360 − DOA, if there is a heading.
    pub fn true_deg(&self) -> Option<f32> {
        self.heading_deg.map(|h| wrap(h + self.relative_deg()))
    }

    /// Write the current one-line form (no declaration, no line end).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "<DATA><STATION_ID>{}</STATION_ID>",
            self.station.as_str()
        )?;
        leaf(out, "TIME", self.time_ms.map(|v| v as f64), 0)?;
        leaf(out, "GPS_TIME", self.gps_time_ms.map(|v| v as f64), 0)?;
        leaf(out, "FREQUENCY", self.freq_mhz, 6)?;
        out.write_str("<LOCATION>")?;
        leaf(out, "LATITUDE", self.position.map(|p| p.lat), 7)?;
        leaf(out, "LONGITUDE", self.position.map(|p| p.lon), 7)?;
        leaf(out, "HEADING", self.heading_deg.map(f64::from), 1)?;
        leaf(out, "SPEED", self.speed_mps.map(f64::from), 2)?;
        out.write_str("</LOCATION>")?;
        leaf(out, "DOA", Some(f64::from(self.doa_deg)), 2)?;
        leaf(out, "PWR", self.pwr.map(f64::from), 1)?;
        leaf(out, "CONF", self.conf.map(f64::from), 0)?;
        out.write_str("</DATA>")
    }

    /// Write the KerberosSDR form: declaration, tabs and newlines, TIME in seconds.
    pub fn emit_legacy(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<DATA>\n\t<STATION_ID>{}</STATION_ID>\n",
            self.station.as_str()
        )?;
        let t = |out: &mut _, name, v, p| -> fmt::Result {
            Write::write_char(out, '\t')?;
            leaf(out, name, v, p)?;
            Write::write_char(out, '\n')
        };
        t(out, "TIME", self.time_ms.map(|v| (v / 1000) as f64), 0)?;
        t(out, "FREQUENCY", self.freq_mhz, 6)?;
        out.write_str("\t<LOCATION>\n\t")?;
        t(out, "LATITUDE", self.position.map(|p| p.lat), 7)?;
        out.write_char('\t')?;
        t(out, "LONGITUDE", self.position.map(|p| p.lon), 7)?;
        out.write_char('\t')?;
        t(out, "HEADING", self.heading_deg.map(f64::from), 1)?;
        out.write_str("\t</LOCATION>\n")?;
        t(out, "DOA", Some(f64::from(self.doa_deg)), 2)?;
        t(out, "PWR", self.pwr.map(f64::from), 1)?;
        t(out, "CONF", self.conf.map(f64::from), 0)?;
        out.write_str("</DATA>\n")
    }
}

fn leaf(out: &mut impl Write, name: &str, v: Option<f64>, prec: usize) -> fmt::Result {
    match v {
        Some(v) => write!(out, "<{name}>{v:.prec$}</{name}>"),
        None => Ok(()),
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

/// The class of bytes a CSV field may hold.
fn csv_byte_ok(field: u16, b: u8) -> bool {
    match field {
        1 | 5 | 7 => b.is_ascii_digit(),
        2..=4 | 9..=12 | 18.. => b.is_ascii_digit() || b == b'.' || b == b'-',
        _ => (0x20..0x7f).contains(&b) && b != b',',
    }
}

/// The CSV line decoder: its state between fields.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CsvDecoder {
    /// Next field, 1-based.
    field: u16,
    rec: KrakenCsv,
    lat: Option<f64>,
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

impl CsvDecoder {
    pub(crate) const fn new() -> Self {
        Self {
            field: 1,
            rec: KrakenCsv {
                epoch_ms: 0,
                bearing_deg: 0.0,
                confidence: 0.0,
                power_db: 0.0,
                freq_hz: 0,
                array: ArrayType::Other,
                latency_ms: 0,
                station: Station {
                    bytes: [0; STATION_LEN],
                    len: 0,
                },
                position: None,
                heading_deg: 0.0,
            },
            lat: None,
        }
    }

    /// Whether the first field is still to come (a failure there is no record, just noise).
    pub(crate) fn at_start(&self) -> bool {
        self.field == 1
    }

    /// Read the next field at the start of `data`; spectrum values go to `spectrum` if it has
    /// room. At the end of the stream (`ended`) the last field needs no line end.
    pub(crate) fn step(
        &mut self,
        data: &[u8],
        ended: bool,
        spectrum: &mut [f32],
    ) -> Step<KrakenCsv> {
        let lead = data.iter().take_while(|&&b| b == b' ').count();
        let mut i = lead;
        while i < data.len() {
            let b = data[i];
            if b == b',' || b == b'\n' || b == b'\r' || b == b' ' {
                break;
            }
            if !csv_byte_ok(self.field, b) {
                return Step::Reject(KrakenError::BadField(self.field), 0);
            }
            if i - lead >= MAX_FIELD {
                return Step::Reject(KrakenError::TooLong, 0);
            }
            i += 1;
        }
        if lead > MAX_FIELD {
            return Step::Reject(KrakenError::TooLong, 0);
        }
        let value = &data[lead..i];
        // The terminator: ',' or, after optional spaces and a CR, LF.
        let mut j = i;
        while j < data.len() && data[j] == b' ' && j - i <= 2 {
            j += 1;
        }
        if j < data.len() && data[j] == b'\r' {
            j += 1;
        }
        let term = data.get(j).copied();
        let last = match term {
            Some(b',') => false,
            Some(b'\n') => true,
            None if ended && self.field == CSV_FIELDS && !value.is_empty() => {
                if let Err(e) = self.take(value, spectrum) {
                    return Step::Reject(e, 0);
                }
                return Step::Done(data.len(), self.rec);
            }
            None if j - lead <= MAX_FIELD + 3 => return Step::NeedMore,
            _ => return Step::Reject(KrakenError::BadField(self.field), 0),
        };
        if value.is_empty() {
            return Step::Reject(KrakenError::BadField(self.field), 0);
        }
        if let Err(e) = self.take(value, spectrum) {
            return Step::Reject(e, 0);
        }
        match (last, self.field == CSV_FIELDS) {
            (true, true) => Step::Done(j + 1, self.rec),
            (false, false) => {
                self.field += 1;
                Step::Took(j + 1)
            }
            // Too few fields: the next line starts after this LF. Too many: at this ','.
            (true, false) => Step::Reject(KrakenError::Structure, j + 1),
            (false, true) => Step::Reject(KrakenError::Structure, j),
        }
    }

    fn take(&mut self, v: &[u8], spectrum: &mut [f32]) -> Result<(), KrakenError> {
        let n = self.field;
        let bad = KrakenError::BadField(n);
        let r = &mut self.rec;
        match n {
            1 if v.len() == 13 => r.epoch_ms = unsigned(v).ok_or(bad)?,
            1 => return Err(bad),
            2 => {
                r.bearing_deg = decimal(v)
                    .filter(|b| (0.0..=360.0).contains(b))
                    .ok_or(bad)? as f32
            }
            3 => r.confidence = decimal(v).ok_or(bad)? as f32,
            4 => r.power_db = decimal(v).ok_or(bad)? as f32,
            5 => r.freq_hz = unsigned(v).filter(|&f| f > 0).ok_or(bad)?,
            6 => {
                r.array = match v {
                    b"UCA" => ArrayType::Uca,
                    b"ULA" => ArrayType::Ula,
                    _ => ArrayType::Other,
                }
            }
            7 => r.latency_ms = unsigned(v).and_then(|l| u32::try_from(l).ok()).ok_or(bad)?,
            8 => r.station = Station::new(core::str::from_utf8(v).map_err(|_| bad)?),
            9 => self.lat = Some(decimal(v).ok_or(bad)?),
            10 => r.position = position(self.lat, Some(decimal(v).ok_or(bad)?)),
            11 => {
                r.heading_deg = decimal(v)
                    .filter(|h| (0.0..=360.0).contains(h))
                    .ok_or(bad)? as f32
            }
            12 => {
                decimal(v).ok_or(bad)?;
            }
            13..=17 => {}
            _ => {
                let x = decimal(v).ok_or(bad)? as f32;
                if let Some(slot) = spectrum.get_mut(usize::from(n - 18)) {
                    *slot = x;
                }
            }
        }
        Ok(())
    }
}

/// XML elements the decoder reads (others are skipped).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Tag {
    StationId,
    Time,
    GpsTime,
    Frequency,
    Latitude,
    Longitude,
    Heading,
    Speed,
    Doa,
    Pwr,
    Conf,
    Other,
}

fn tag_of(name: &[u8]) -> Tag {
    match name {
        b"STATION_ID" => Tag::StationId,
        b"TIME" => Tag::Time,
        b"GPS_TIME" => Tag::GpsTime,
        b"FREQUENCY" => Tag::Frequency,
        b"LATITUDE" => Tag::Latitude,
        b"LONGITUDE" => Tag::Longitude,
        b"HEADING" => Tag::Heading,
        b"SPEED" => Tag::Speed,
        b"DOA" => Tag::Doa,
        b"PWR" => Tag::Pwr,
        b"CONF" => Tag::Conf,
        _ => Tag::Other,
    }
}

/// Where the XML decoder is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum XmlAt {
    /// Expecting the declaration or `<DATA>`.
    Start,
    /// After the declaration: expecting `<DATA>`.
    Declared,
    /// Inside `<DATA>` (`true`: inside `<LOCATION>`), between elements.
    Between(bool),
    /// Inside a leaf element (its name's hash, for the close tag), text read or not.
    Leaf(bool, Tag, u32, bool),
}

/// FNV-1a of a tag name: the close tag must match the open one.
fn name_hash(name: &[u8]) -> u32 {
    name.iter().fold(0x811c_9dc5u32, |h, &b| {
        (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
    })
}

/// The XML record decoder: its state between tokens.
#[derive(Debug, Clone, Copy)]
pub(crate) struct XmlDecoder {
    at: XmlAt,
    rec: KrakenXml,
    lat: Option<f64>,
    lon: Option<f64>,
    doa: bool,
}

impl XmlDecoder {
    pub(crate) const fn new() -> Self {
        Self {
            at: XmlAt::Start,
            rec: KrakenXml {
                station: Station {
                    bytes: [0; STATION_LEN],
                    len: 0,
                },
                time_ms: None,
                gps_time_ms: None,
                freq_mhz: None,
                position: None,
                heading_deg: None,
                speed_mps: None,
                doa_deg: 0.0,
                pwr: None,
                conf: None,
            },
            lat: None,
            lon: None,
            doa: false,
        }
    }

    /// Whether the first tag is still to come.
    pub(crate) fn at_start(&self) -> bool {
        self.at == XmlAt::Start
    }

    /// Read the next tag or text at the start of `data`.
    pub(crate) fn step(&mut self, data: &[u8]) -> Step<KrakenXml> {
        let Some(&first) = data.first() else {
            return Step::NeedMore;
        };
        if first != b'<' {
            // Text: a leaf's value, or whitespace between tags.
            let n = data.iter().position(|&b| b == b'<');
            let text = &data[..n.unwrap_or(data.len())];
            if text.iter().any(|&b| {
                b < 0x09 || b == 0x0b || b == 0x0c || (0x0e..0x20).contains(&b) || b >= 0x7f
            }) {
                return Step::Reject(KrakenError::Structure, 0);
            }
            if text.len() > MAX_FIELD {
                return Step::Reject(KrakenError::TooLong, 0);
            }
            let Some(n) = n else {
                return Step::NeedMore;
            };
            let blank = text.iter().all(|b| b.is_ascii_whitespace());
            return match self.at {
                XmlAt::Leaf(loc, tag, h, false) => match self.value(tag, text) {
                    Ok(()) => {
                        self.at = XmlAt::Leaf(loc, tag, h, true);
                        Step::Took(n)
                    }
                    Err(e) => Step::Reject(e, 0),
                },
                XmlAt::Declared | XmlAt::Between(_) if blank => Step::Took(n),
                _ => Step::Reject(KrakenError::Structure, 0),
            };
        }
        let Some(close) = data.iter().position(|&b| b == b'>') else {
            if data.len() > MAX_TAG {
                return Step::Reject(KrakenError::TooLong, 0);
            }
            if data
                .iter()
                .skip(1)
                .any(|&b| b == b'<' || !(0x20..0x7f).contains(&b))
            {
                return Step::Reject(KrakenError::Structure, 0);
            }
            return Step::NeedMore;
        };
        if close > MAX_TAG {
            return Step::Reject(KrakenError::TooLong, 0);
        }
        let inner = &data[1..close];
        if inner
            .iter()
            .any(|&b| b == b'<' || !(0x20..0x7f).contains(&b))
        {
            return Step::Reject(KrakenError::Structure, 0);
        }
        let len = close + 1;
        let bad = Step::Reject(KrakenError::Structure, 0);
        match (self.at, inner) {
            (XmlAt::Start, [b'?', b'x', b'm', b'l', .., b'?']) => {
                self.at = XmlAt::Declared;
                Step::Took(len)
            }
            (XmlAt::Start | XmlAt::Declared, b"DATA") => {
                self.at = XmlAt::Between(false);
                Step::Took(len)
            }
            (XmlAt::Between(false), b"/DATA") => {
                if !self.doa {
                    return Step::Reject(KrakenError::NoBearing, len);
                }
                self.rec.position = position(self.lat, self.lon);
                Step::Done(len, self.rec)
            }
            (XmlAt::Between(false), b"LOCATION") => {
                self.at = XmlAt::Between(true);
                Step::Took(len)
            }
            (XmlAt::Between(true), b"/LOCATION") => {
                self.at = XmlAt::Between(false);
                Step::Took(len)
            }
            (XmlAt::Between(loc), [b'/', ..]) => {
                let _ = loc;
                bad
            }
            (XmlAt::Between(loc), [name @ .., b'/']) => {
                // An empty element, `<NAME/>` or `<NAME />`: nothing to read.
                let name = name.strip_suffix(b" ").unwrap_or(name);
                if name.is_empty() || !name.iter().all(|b| b.is_ascii_uppercase() || *b == b'_') {
                    return bad;
                }
                self.at = XmlAt::Between(loc);
                Step::Took(len)
            }
            (XmlAt::Between(loc), name) => {
                if name.is_empty() || !name.iter().all(|b| b.is_ascii_uppercase() || *b == b'_') {
                    return bad;
                }
                self.at = XmlAt::Leaf(loc, tag_of(name), name_hash(name), false);
                Step::Took(len)
            }
            (XmlAt::Leaf(loc, _, h, _), [b'/', name @ ..]) if name_hash(name) == h => {
                self.at = XmlAt::Between(loc);
                Step::Took(len)
            }
            _ => bad,
        }
    }

    fn value(&mut self, tag: Tag, text: &[u8]) -> Result<(), KrakenError> {
        let t = text.trim_ascii();
        let bad = KrakenError::BadField(0);
        let num = || decimal(t).ok_or(bad);
        let r = &mut self.rec;
        match tag {
            Tag::StationId => r.station = Station::new(core::str::from_utf8(t).map_err(|_| bad)?),
            Tag::Time => {
                let v = unsigned(t).ok_or(bad)?;
                r.time_ms = Some(if v < SECONDS_BELOW {
                    v.saturating_mul(1000)
                } else {
                    v
                });
            }
            Tag::GpsTime => r.gps_time_ms = unsigned(t).ok_or(bad).map(|v| (v > 0).then_some(v))?,
            Tag::Frequency => r.freq_mhz = Some(num()?).filter(|f| *f > 0.0),
            Tag::Latitude => self.lat = Some(num()?),
            Tag::Longitude => self.lon = Some(num()?),
            Tag::Heading => {
                r.heading_deg = Some(num()? as f32)
                    .filter(|h| (0.0..=360.0).contains(h))
                    .or(None);
                if r.heading_deg.is_none() {
                    return Err(bad);
                }
            }
            Tag::Speed => r.speed_mps = Some(num()? as f32),
            Tag::Doa => {
                let d = num()? as f32;
                if !(0.0..=360.0).contains(&d) {
                    return Err(bad);
                }
                r.doa_deg = d;
                self.doa = true;
            }
            Tag::Pwr => r.pwr = Some(num()? as f32),
            Tag::Conf => r.conf = Some(num()? as f32),
            Tag::Other => {}
        }
        Ok(())
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use std::string::String;

    /// Feed one record through a decoder in reads of `chunk` bytes, as the demultiplexer
    /// does (tokens are cut from the front; incomplete ones wait for more).
    fn csv(line: &str, spectrum: &mut [f32]) -> Result<KrakenCsv, KrakenError> {
        let mut d = CsvDecoder::new();
        let b = line.as_bytes();
        let mut at = 0;
        loop {
            match d.step(&b[at..], true, spectrum) {
                Step::Took(n) => at += n,
                Step::Done(_, r) => return Ok(r),
                Step::Reject(e, _) => return Err(e),
                Step::NeedMore => return Err(KrakenError::Structure),
            }
        }
    }

    fn xml(text: &str) -> Result<KrakenXml, KrakenError> {
        let mut d = XmlDecoder::new();
        let b = text.as_bytes();
        let mut at = 0;
        loop {
            match d.step(&b[at..]) {
                Step::Took(n) => at += n,
                Step::Done(_, r) => return Ok(r),
                Step::Reject(e, _) => return Err(e),
                Step::NeedMore => return Err(KrakenError::Structure),
            }
        }
    }

    /// The line a user posted in ckoval7/df-aggregator issue 11 (2023, integer bearing), its
    /// spectrum completed to 360 values.
    pub(crate) fn issue_11_line() -> String {
        let mut s = String::from(
            "1679512414650, 134, 0.41, -48.5, 151880000, UCA, 100, dingus, 66.961348, -66.4438057, 0, 0, GPS, R, R, R, R, 0.07, 0.08",
        );
        for i in 2..SPECTRUM_LEN {
            s.push_str(&std::format!(", {}.{:02}", i / 100, i % 100));
        }
        s.push_str(" \n");
        s
    }

    #[test]
    fn the_line_from_df_aggregator_issue_11() {
        let mut spectrum = [0f32; SPECTRUM_LEN];
        let r = csv(&issue_11_line(), &mut spectrum).expect("line");
        assert_eq!(r.epoch_ms, 1_679_512_414_650);
        assert_eq!(
            (r.bearing_deg, r.confidence, r.power_db),
            (134.0, 0.41, -48.5)
        );
        assert_eq!(
            (r.freq_hz, r.array, r.latency_ms),
            (151_880_000, ArrayType::Uca, 100)
        );
        assert_eq!(r.station.as_str(), "dingus");
        let p = r.position.expect("fix");
        assert_eq!((p.lat, p.lon), (66.961348, -66.4438057));
        assert_eq!(
            (spectrum[0], spectrum[1], spectrum[359]),
            (0.07, 0.08, 3.59)
        );
        assert_eq!(r.relative_deg(CsvConvention::Clockwise), 134.0);
        assert_eq!(r.relative_deg(CsvConvention::Anticlockwise), 226.0);
    }

    #[test]
    fn csv_round_trip_and_rejects() {
        let mut spectrum = [0f32; SPECTRUM_LEN];
        let r = csv(&issue_11_line(), &mut spectrum).expect("line");
        let mut out = String::new();
        r.emit(&spectrum, &mut out).expect("string");
        let mut back = [0f32; SPECTRUM_LEN];
        assert_eq!(csv(&out, &mut back), Ok(r));
        assert_eq!(back, spectrum);
        assert!(out.len() > 2000, "a line is ~2.5 KB: {}", out.len());
        // No fix is (0, 0); 360 reads as 0; a line without its end at the end of a file.
        let zero = out.replacen("66.9613480, -66.4438057", "0.0, 0.0", 1);
        assert_eq!(csv(&zero, &mut back).map(|r| r.position), Ok(None));
        assert_eq!(
            csv(out.trim_end(), &mut back).map(|r| r.epoch_ms),
            Ok(1_679_512_414_650)
        );
        let short = out.replacen(", 0.07", "", 1);
        assert_eq!(csv(&short, &mut back), Err(KrakenError::Structure));
        let bad = out.replacen("134", "1x4", 1);
        assert_eq!(csv(&bad, &mut back), Err(KrakenError::BadField(2)));
        let epoch = out.replacen("1679512414650", "167951241465", 1);
        assert_eq!(csv(&epoch, &mut back), Err(KrakenError::BadField(1)));
    }

    #[test]
    fn kerberos_sample_and_current_form() {
        // ckoval7/rdf-sim kerbs_xml_sample.xml, byte for byte.
        let sample = "<?xml version=\"1.0\" encoding=\"UTF-8\" ?>\n<DATA>\n\t<STATION_ID>K3CPK-1</STATION_ID>\n\t<TIME>1568052311</TIME>\n\t<FREQUENCY>162.4</FREQUENCY>\n\t<LOCATION>\n\t\t<LATITUDE>39.124526</LATITUDE>\n\t\t<LONGITUDE>-76.519717</LONGITUDE>\n\t\t<HEADING>0</HEADING>\n\t</LOCATION>\n\t<DOA>120</DOA>\n\t<PWR>19.265165</PWR>\n\t<CONF>15</CONF>\n</DATA>\n";
        let r = xml(sample).expect("sample");
        assert_eq!(r.station.as_str(), "K3CPK-1");
        assert_eq!(r.time_ms, Some(1_568_052_311_000), "seconds there");
        assert_eq!(
            (r.freq_mhz, r.doa_deg, r.conf),
            (Some(162.4), 120.0, Some(15.0))
        );
        let p = r.position.expect("position");
        assert_eq!((p.lat, p.lon), (39.124526, -76.519717));
        // df-aggregator's true bearing: heading + 360 - DOA.
        assert_eq!(r.true_deg(), Some(240.0));
        // The current one-line form round-trips; its TIME is in ms.
        let mut out = String::new();
        r.emit(&mut out).expect("string");
        assert!(!out.contains('\n') && out.starts_with("<DATA><STATION_ID>K3CPK-1"));
        let back = xml(&out).expect("one line");
        assert_eq!(
            (back.time_ms, back.doa_deg, back.position),
            (r.time_ms, 120.0, r.position)
        );
        let mut legacy = String::new();
        r.emit_legacy(&mut legacy).expect("string");
        assert_eq!(xml(&legacy).map(|b| b.time_ms), Ok(r.time_ms));
        // KrakenSDR's wr_xml element order with the fields the old form lacks.
        let kraken = "<DATA><STATION_ID>NOCALL</STATION_ID><TIME>1700000000123</TIME><GPS_TIME>0</GPS_TIME><FREQUENCY>433.92</FREQUENCY><LOCATION><LATITUDE>0.0</LATITUDE><LONGITUDE>0.0</LONGITUDE><HEADING>0.0</HEADING><SPEED>0.0</SPEED></LOCATION><DOA>270</DOA><PWR>52.5</PWR><CONF>1234</CONF><LATENCY>100</LATENCY><PROCESSING_TIME>42</PROCESSING_TIME><ADC_OVERDRIVE>False</ADC_OVERDRIVE><NUM_CORRELATED_SOURCES>0</NUM_CORRELATED_SOURCES><SNR_DB>12.5</SNR_DB></DATA>";
        let k = xml(kraken).expect("kraken");
        assert_eq!(
            (k.time_ms, k.gps_time_ms, k.position),
            (Some(1_700_000_000_123), None, None)
        );
        assert_eq!(k.relative_deg(), 90.0);
        assert_eq!(
            xml("<DATA><CONF>1</CONF></DATA>"),
            Err(KrakenError::NoBearing)
        );
        assert_eq!(
            xml("<DATA><DOA>1</CONF></DATA>"),
            Err(KrakenError::Structure)
        );
    }
}
