//! The "Kraken App" CSV line: its fields, and its decoder, a field at a time.

use super::{
    CSV_FIELDS, KrakenError, MAX_FIELD, SPECTRUM_LEN, STATION_LEN, Station, Step, decimal,
    position, unsigned, wrap,
};
use crate::nmea::LatLon;
use core::fmt::{self, Write};

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
