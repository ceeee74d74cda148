//! The bridge's bearings as the network's messages ([`BearingMessage`], docs/src/networks.md):
//! true bearings at the station's position, on UTC. What `foxhunt publish` sends and what
//! `foxhunt locate --db` keeps, from any source the decoder reads.
//!
//! The bridge's clock counts milliseconds from midnight of a day 0 it does not know (NMEA
//! carries a time of day); the day comes from the capture (a KrakenSDR record's epoch, an RMC
//! date), the command line, or for a live line the day that puts its first bearing nearest
//! now.

use crate::inputs::capture::{Decoder, kind_name};
use crate::inputs::files::{Source, stream};
use crate::inputs::mqtt::BearingMessage;
use foxhunt_bridge::BridgeConfig;
use foxhunt_bridge::bridge::BearingMeasurement;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use std::time::{SystemTime, UNIX_EPOCH};

/// A day, ms.
pub const DAY_MS: i64 = 86_400_000;

/// Now, ms since 1970.
pub fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as i64)
}

/// Midnight UTC of today, ms since 1970.
pub fn today_ms() -> i64 {
    now_ms() - now_ms().rem_euclid(DAY_MS)
}

/// Midnight UTC of `YYYY-MM-DD`, ms since 1970.
pub fn parse_date(text: &str) -> Result<i64, String> {
    let bad = || format!("--date wants YYYY-MM-DD, not `{text}`");
    let mut parts = text.split('-');
    let (Some(y), Some(m), Some(d), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(bad());
    };
    let year: i32 = y.parse().map_err(|_| bad())?;
    let month: u8 = m.parse().map_err(|_| bad())?;
    let day: u8 = d.parse().map_err(|_| bad())?;
    let month = time::Month::try_from(month).map_err(|_| bad())?;
    time::Date::from_calendar_date(year, month, day)
        .map(|d| d.midnight().assume_utc().unix_timestamp() * 1000)
        .map_err(|_| bad())
}

/// Finds the day of a capture in its first megabyte: a KrakenSDR record's epoch, else an RMC
/// sentence's date (`ddmmyy`).
struct DayFinder {
    rx: Box<foxhunt_bridge::bridge::Receiver<0, 1>>,
    day: Option<i64>,
    read: usize,
}

impl DayFinder {
    fn new() -> Self {
        Self {
            rx: Box::new(foxhunt_bridge::bridge::Receiver::new(
                BridgeConfig::default(),
                [],
            )),
            day: None,
            read: 0,
        }
    }

    fn feed(&mut self, bytes: &[u8]) {
        use foxhunt_bridge::Frame;
        if self.day.is_some() || self.read > 1 << 20 {
            return;
        }
        self.read += bytes.len();
        let day = &mut self.day;
        self.rx.demux.feed(bytes, &mut |f| {
            if day.is_some() {
                return;
            }
            let epoch = match &f {
                Frame::KrakenXml(r) => r.time_ms.map(|t| t as i64),
                Frame::KrakenCsv(k) => Some(k.record.epoch_ms as i64),
                Frame::Nmea(text) => rmc_day(text),
                _ => None,
            };
            *day = epoch.filter(|t| *t > 0).map(|t| t - t.rem_euclid(DAY_MS));
        });
    }
}

/// Midnight UTC of the day the first dated record of a capture's first file names.
pub fn capture_day(sources: &[Source]) -> Option<i64> {
    let mut f = DayFinder::new();
    let _ = stream(&sources[..1], |b| f.feed(b));
    f.day
}

/// Midnight UTC of an RMC sentence's date.
pub fn rmc_day(body: &str) -> Option<i64> {
    let fields: Vec<&str> = body.split(',').collect();
    if !fields.first()?.ends_with("RMC") {
        return None;
    }
    let d = fields.get(9)?;
    if d.len() != 6 || !d.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let n = |i: usize| d[i..i + 2].parse::<u8>().ok();
    let year = 2000 + i32::from(n(4)?);
    let month = time::Month::try_from(n(2)?).ok()?;
    let date = time::Date::from_calendar_date(year, month, n(0)?).ok()?;
    Some(date.midnight().assume_utc().unix_timestamp() * 1000)
}

/// The true azimuth at `at` (degrees clockwise from north there) whose direction in `frame`
/// is `local_deg`: the inverse of [`LocalFrame::azimuth_to_local`], by a few fixed-point
/// steps (the two differ by the meridians' convergence, a fraction of a degree).
pub fn true_azimuth(frame: &LocalFrame, at: LatLon, local_deg: f64) -> Option<f64> {
    let wrap = |a: f64| a.rem_euclid(360.0);
    let mut a = local_deg;
    for _ in 0..4 {
        let l = frame.azimuth_to_local(at, a).ok()?;
        let d = (l - local_deg + 540.0).rem_euclid(360.0) - 180.0;
        a = wrap(a - d);
    }
    Some(if a >= 360.0 { 0.0 } else { a })
}

/// Turns the bridge's bearings into messages.
#[derive(Debug, Clone)]
pub struct Stamper {
    /// The station id of bearings whose records name none (`None`: the decoder's label).
    pub station: Option<String>,
    /// Midnight UTC of the bridge clock's day 0.
    pub day0_ms: i64,
    /// Whether `day0_ms` is known (else taken from the first bearing, [`Stamper::date_live`]).
    pub dated: bool,
}

impl Stamper {
    /// A live line's day: the one that puts its first bearing (bridge time `first_ms`)
    /// nearest now. Once; a day already known stays.
    pub fn date_live(&mut self, first_ms: i64) {
        if self.dated {
            return;
        }
        let now = now_ms();
        let day0 = self.day0_ms;
        self.day0_ms = [-DAY_MS, 0, DAY_MS]
            .map(|k| day0 + k)
            .into_iter()
            .min_by_key(|d| (d + first_ms - now).abs())
            .unwrap_or(day0);
        self.dated = true;
    }

    /// The message of bearing `m` that `dec` decoded (not checked: the caller decides what a
    /// station id may be).
    pub fn message(&self, dec: &Decoder, m: &BearingMeasurement) -> Result<BearingMessage, String> {
        let d = &dec.decoded;
        let frame = d
            .frame
            .ok_or_else(|| "a bearing before the local frame".to_string())?;
        let info = d
            .stations
            .get(usize::from(m.station))
            .ok_or_else(|| "a bearing of an unknown station".to_string())?;
        let station = match (info.named, &self.station) {
            (false, Some(s)) => s.clone(),
            _ => info.id.clone(),
        };
        let v = m.bearing.vehicle;
        let at = frame
            .to_geodetic([f64::from(v[0]), f64::from(v[1])])
            .map_err(|_| "a bearing's position outside the frame".to_string())?;
        // The core's angle is mathematical (from east, anticlockwise); north-clockwise here.
        let local_deg = (90.0 - f64::from(m.bearing.theta).to_degrees()).rem_euclid(360.0);
        let bearing_deg = true_azimuth(&frame, at, local_deg)
            .ok_or_else(|| "a bearing that cannot be carried to true north".to_string())?;
        Ok(BearingMessage {
            station,
            time_ms: self.day0_ms + m.time_ms,
            lat: at.lat,
            lon: at.lon,
            bearing_deg,
            sigma_deg: f64::from(m.bearing.sigma).to_degrees(),
            freq_mhz: (m.freq_mhz > 0.0).then_some(m.freq_mhz),
            quality: m.quality,
            kind: kind_name(m.kind).to_string(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_true_azimuth_is_carried_back_from_the_frame() {
        let origin = LatLon {
            lat: 47.0,
            lon: 8.0,
        };
        let frame = LocalFrame::new(origin, 0.0).expect("frame");
        for (de, dn) in [(0.0, 0.0), (20_000.0, 5_000.0), (-15_000.0, -30_000.0)] {
            let at = frame.to_geodetic([de, dn]).expect("point");
            for k in 0..72 {
                let truth = f64::from(k) * 5.0 + 0.123;
                let local = frame.azimuth_to_local(at, truth).expect("local");
                let back = true_azimuth(&frame, at, local).expect("true");
                let d = (back - truth + 540.0).rem_euclid(360.0) - 180.0;
                assert!(d.abs() < 1e-9, "{de},{dn} {truth}: {back}");
            }
        }
    }

    #[test]
    fn dates() {
        assert_eq!(parse_date("2026-06-01"), Ok(1_780_272_000_000));
        for bad in ["2026-13-01", "2026-02-30", "26-1", "2026-01-01-01", "x"] {
            assert!(parse_date(bad).is_err(), "{bad}");
        }
        assert_eq!(
            rmc_day("GPRMC,100000.00,A,4700.000,N,00800.000,E,0.0,0.0,010626,,,A"),
            Some(1_780_272_000_000)
        );
        assert_eq!(rmc_day("GPGGA,100000.00,4700.000,N"), None);
        assert_eq!(rmc_day("GPRMC,1,A,,,,,,,01x626"), None);
    }
}
