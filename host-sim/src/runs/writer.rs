//! A capture written record by record as the radios send them: NMEA sentences framed with
//! their checksum and CR LF, Agrelo bearings, KrakenSDR CSV lines and XML records, each with the
//! line end its device uses, and ZigBee coordinators' MT frames. `foxhunt simulate` (drives and
//! indoor captures), the field conditions' captures and the firmware's QEMU tests all write
//! through this one writer, so a framing rule lives here only.

use foxhunt_bridge::agrelo::Agrelo;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::kraken::{KrakenCsv, KrakenXml, Station};
use foxhunt_bridge::mt::AfIncomingMsg;
use foxhunt_bridge::nmea::{
    Date, Hdt, LatLon, Line, Pfoxb, UtcTime, gga_body, pfoxb_body, rmc_body, write_sentence,
};

/// Why a record could not be written: a field that does not fit its record's buffer.
pub const TOO_LONG: &str = "record longer than its buffer";

/// One station's bearing as its KrakenSDR logs it ([`CaptureWriter::station_bearing`]).
#[derive(Debug, Clone, Copy)]
pub struct StationBearing<'a> {
    /// The station's id (its STATION_ID).
    pub id: &'a str,
    /// Whether it stands still (speed 0 in the record).
    pub fixed: bool,
    /// Where it stood, local metres.
    pub at: [f32; 2],
    /// The true azimuth of the bearing, degrees clockwise from north.
    pub azimuth_deg: f32,
    /// The array's heading: 0 for a fixed array facing north, a vehicle's course.
    pub heading_deg: f32,
    /// The channel, MHz.
    pub freq_mhz: Option<f32>,
    /// The record's epoch, ms since 1970.
    pub epoch_ms: u64,
}

/// The course from `a` to `b` (local metres), degrees clockwise from north, to the 0.1 degree
/// a unit's GPS heading carries.
pub fn course_deg(a: [f32; 2], b: [f32; 2]) -> f32 {
    let c = (b[0] - a[0])
        .atan2(b[1] - a[1])
        .to_degrees()
        .rem_euclid(360.0);
    (c * 10.0).round() / 10.0 % 360.0
}

/// The bytes of a capture, written in order.
#[derive(Debug, Default, Clone)]
pub struct CaptureWriter {
    out: Vec<u8>,
    line: Line,
    text: String,
}

impl CaptureWriter {
    /// An empty capture.
    pub fn new() -> Self {
        Self::default()
    }

    /// Frame the sentence body in `self.line` (`$`, checksum, CR LF).
    fn frame(&mut self) -> Result<(), String> {
        self.text.clear();
        write_sentence(&mut self.text, &self.line).map_err(|_| TOO_LONG.to_string())?;
        self.out.extend_from_slice(self.text.as_bytes());
        Ok(())
    }

    /// Append a text record `write` makes, then `end`.
    fn text_record(
        &mut self,
        write: impl FnOnce(&mut String) -> core::fmt::Result,
        end: &str,
    ) -> Result<(), String> {
        self.text.clear();
        write(&mut self.text).map_err(|_| TOO_LONG.to_string())?;
        self.text.push_str(end);
        self.out.extend_from_slice(self.text.as_bytes());
        Ok(())
    }

    /// A GPS fix as a receiver reports it: GGA (9 satellites, HDOP 0.9).
    pub fn gga(&mut self, time: UtcTime, at: LatLon) -> Result<(), String> {
        self.line.clear();
        gga_body(&mut self.line, time, at, 9, 0.9).map_err(|_| TOO_LONG.to_string())?;
        self.frame()
    }

    /// The RMC of a GPS fix: date, speed over ground (knots) and course (degrees true).
    pub fn rmc(
        &mut self,
        time: UtcTime,
        date: Date,
        at: LatLon,
        speed_kn: f64,
        course_deg: f64,
    ) -> Result<(), String> {
        self.line.clear();
        rmc_body(&mut self.line, time, date, at, speed_kn, course_deg)
            .map_err(|_| TOO_LONG.to_string())?;
        self.frame()
    }

    /// A heading sensor's HDT.
    pub fn hdt(&mut self, h: &Hdt) -> Result<(), String> {
        self.line.clear();
        h.emit(&mut self.line).map_err(|_| TOO_LONG.to_string())?;
        self.frame()
    }

    /// A `$PFOXB` bearing.
    pub fn pfoxb(&mut self, b: &Pfoxb) -> Result<(), String> {
        self.line.clear();
        pfoxb_body(&mut self.line, b).map_err(|_| TOO_LONG.to_string())?;
        self.frame()
    }

    /// An Agrelo bearing (`%BBB/Q`, CR LF).
    pub fn agrelo(&mut self, a: &Agrelo) -> Result<(), String> {
        self.text_record(|t| a.emit(t), "\r\n")
    }

    /// A KrakenSDR CSV line with its DoA spectrum (the line writes its own end).
    pub fn kraken_csv(&mut self, c: &KrakenCsv, spectrum: &[f32]) -> Result<(), String> {
        self.text_record(|t| c.emit(spectrum, t), "")
    }

    /// A KrakenSDR XML record on one line.
    pub fn kraken_xml(&mut self, x: &KrakenXml) -> Result<(), String> {
        self.text_record(|t| x.emit(t), "\n")
    }

    /// A station's bearing as a KrakenSDR XML record: its position in `frame`, its heading,
    /// and the bearing relative to the heading as the unit's DOA (counter-clockwise).
    pub fn station_bearing(
        &mut self,
        frame: &LocalFrame,
        b: &StationBearing<'_>,
    ) -> Result<(), String> {
        let position = frame
            .to_geodetic([f64::from(b.at[0]), f64::from(b.at[1])])
            .map_err(|_| format!("station {} is out of range", b.id))?;
        let relative = (b.azimuth_deg - b.heading_deg).rem_euclid(360.0);
        self.kraken_xml(&KrakenXml {
            station: Station::new(b.id),
            time_ms: Some(b.epoch_ms),
            gps_time_ms: Some(b.epoch_ms),
            freq_mhz: b.freq_mhz.map(f64::from),
            position: Some(position),
            heading_deg: Some(b.heading_deg),
            speed_mps: Some(if b.fixed { 0.0 } else { 10.0 }),
            doa_deg: (360.0 - relative).rem_euclid(360.0),
            pwr: Some(60.0),
            conf: Some(80.0),
        })
    }

    /// A ZigBee coordinator's AF_INCOMING_MSG frame (UNPI: start byte, length, command, data,
    /// check byte).
    pub fn af_incoming_msg(&mut self, m: &AfIncomingMsg<'_>) -> Result<(), String> {
        let mut buf = [0u8; 300];
        let n = m
            .encode(&mut buf)
            .map_err(|_| "an AF_INCOMING_MSG frame did not fit its buffer".to_string())?;
        self.out.extend_from_slice(buf.get(..n).unwrap_or(&[]));
        Ok(())
    }

    /// Bytes written so far.
    pub fn len(&self) -> usize {
        self.out.len()
    }

    /// Nothing written yet.
    pub fn is_empty(&self) -> bool {
        self.out.is_empty()
    }

    /// The capture's bytes.
    pub fn into_bytes(self) -> Vec<u8> {
        self.out
    }
}
