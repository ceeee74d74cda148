//! The XML record df-aggregator polls (and the KerberosSDR's older form), and its decoder, a
//! tag or a text at a time.

use super::{
    KrakenError, MAX_FIELD, MAX_TAG, SECONDS_BELOW, STATION_LEN, Station, Step, decimal, position,
    unsigned, wrap,
};
use crate::nmea::LatLon;
use core::fmt::{self, Write};

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
    /// The elements read so far (bit `Tag as u16`): one given twice refuses the record, as
    /// neither value can be told to be the right one.
    seen: u16,
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
            seen: 0,
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
        if tag != Tag::Other {
            let bit = 1u16 << (tag as u16);
            if self.seen & bit != 0 {
                return Err(KrakenError::Structure);
            }
            self.seen |= bit;
        }
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
            Tag::Frequency => {
                // A negative or zero frequency is no channel (the CSV refuses it too).
                let f = num()?;
                if !(f > 0.0) {
                    return Err(bad);
                }
                r.freq_mhz = Some(f);
            }
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
