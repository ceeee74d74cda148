//! Captures as the radios would send them: a scenario's drive written byte for byte as `cat
//! /dev/ttyUSB0 > drive.nmea` would record it, in the format of a real DF unit
//! ([`CaptureFormat`]).
//!
//! - `pfoxb`: GGA and RMC at each route point, a whole second apart; the DF unit reports
//!   half a second later, from the point halfway to the next one (the vehicle drives straight
//!   between fixes), so a replay must interpolate the vehicle's position at the bearing's
//!   time. A last fix one step beyond the route closes the drive. True bearings.
//! - `agrelo`: GGA, RMC and a true heading (HDT, the course of the leg ahead) at each route
//!   point, then the Doppler unit's `%BBB/Q`, relative to that heading: the format has no
//!   time, so the record is taken at the fix before it, from the fix's point.
//! - `kraken-csv`, `kraken-xml`: what a KrakenSDR writes alone (`mydata.csv`, `doa.xml`):
//!   one record per route point with the unit's own position, heading (the leg's course)
//!   and clock, the bearing relative to the array; no NMEA.
//!
//! Every bearing is the azimuth a DF unit measures at the vehicle, from north there: the
//! scenario's (local-frame) angle turned by the meridians' convergence between the vehicle
//! and the capture's origin, which the bridge turns back. The first record's position is the
//! route's first point in every format, so the capture's local origin is that point.

use crate::runs::scenario::{Drive, Scenario, ScenarioModel};
use crate::runs::writer::CaptureWriter;
use crate::track::indoor::{Anchor, AnchorsFile, PathLossEntry};
use foxhunt_bridge::agrelo::Agrelo;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::kraken::{ArrayType, KrakenCsv, KrakenXml, SPECTRUM_LEN, Station};
use foxhunt_bridge::mt::{AfIncomingMsg, LinkQualityMap};
use foxhunt_bridge::nmea::{Date, Hdt, LatLon, Pfoxb, Reference, UtcTime};
use foxhunt_core::model::bearing::{predicted, theta_to_azimuth, wrap};
use foxhunt_core::random;
use std::f32::consts::PI;

/// Where the route's first point sits unless `--origin` says otherwise: 47.0 N, 8.0 E.
pub const DEFAULT_ORIGIN: LatLon = LatLon {
    lat: 47.0,
    lon: 8.0,
};

/// The record format a drive's bearings are written in (the module doc says how each is laid
/// out).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CaptureFormat {
    /// GGA + RMC + `$PFOXB` true bearings.
    #[default]
    Pfoxb,
    /// GGA + RMC + HDT + Agrelo `%BBB/Q` relative bearings.
    Agrelo,
    /// KrakenSDR "Kraken App" CSV lines with their own position and heading.
    KrakenCsv,
    /// KrakenSDR XML records (the current one-line form) with their own position and heading.
    KrakenXml,
}

impl CaptureFormat {
    /// Every format.
    pub const ALL: [Self; 4] = [Self::Pfoxb, Self::Agrelo, Self::KrakenCsv, Self::KrakenXml];

    /// The name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Pfoxb => "pfoxb",
            Self::Agrelo => "agrelo",
            Self::KrakenCsv => "kraken-csv",
            Self::KrakenXml => "kraken-xml",
        }
    }

    /// The format of a command-line name.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }

    fn kraken(self) -> bool {
        matches!(self, Self::KrakenCsv | Self::KrakenXml)
    }
}

/// How a capture is written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaptureOptions {
    /// The bearings' record format.
    pub format: CaptureFormat,
    /// Where the route's first point sits (the capture's local origin).
    pub origin: LatLon,
    /// UTC time of the first fix.
    pub start: UtcTime,
    /// Date in the RMC sentences.
    pub date: Date,
    /// Which Monte Carlo run's noise to use.
    pub run: usize,
    /// Milliseconds between route points (GPS fixes); each bearing comes half of it later.
    pub interval_ms: u32,
    /// Carrier frequency in the bearing sentences, MHz.
    pub freq_mhz: f64,
    /// Share of wild bearings (uniform over the circle); `None` keeps the scenario's.
    pub wild_fraction: Option<f32>,
    /// A constant multipath bias added to every bearing, degrees.
    pub bias_deg: f32,
    /// Share of bytes corrupted (each XORed with a random non-zero byte) after writing.
    pub corrupt_fraction: f32,
    /// Share of bytes dropped after writing.
    pub drop_fraction: f32,
}

impl Default for CaptureOptions {
    fn default() -> Self {
        Self {
            format: CaptureFormat::Pfoxb,
            origin: DEFAULT_ORIGIN,
            start: UtcTime {
                ms_of_day: 10 * 3_600_000,
            },
            date: Date {
                year: 2026,
                month: 6,
                day: 1,
            },
            run: 0,
            interval_ms: 1000,
            freq_mhz: 433.92,
            wild_fraction: None,
            bias_deg: 0.0,
            corrupt_fraction: 0.0,
            drop_fraction: 0.0,
        }
    }
}

impl CaptureOptions {
    /// Refuse values no capture can use, naming the option.
    pub fn check(&self) -> Result<(), String> {
        let share = |name: &str, v: f32| {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                Err(format!("--{name} is a share between 0 and 1, not {v}"))
            }
        };
        share("corrupt", self.corrupt_fraction)?;
        share("drop", self.drop_fraction)?;
        if let Some(w) = self.wild_fraction {
            share("wild", w)?;
        }
        if !(self.bias_deg.is_finite() && self.bias_deg.abs() <= 180.0) {
            return Err(format!(
                "--bias-deg must lie between -180 and 180 degrees, not {}",
                self.bias_deg
            ));
        }
        if !(2..=3_600_000).contains(&self.interval_ms) {
            return Err(format!(
                "the interval between fixes must be 2 ms to 1 h, not {} ms",
                self.interval_ms
            ));
        }
        let o = self.origin;
        if !(o.lat.abs() <= 90.0 && o.lon.abs() <= 180.0) {
            return Err(format!(
                "--origin must be a latitude in [-90, 90] and a longitude in [-180, 180], not {},{}",
                o.lat, o.lon
            ));
        }
        Ok(())
    }

    /// Milliseconds since 1970 at `ms` after the first fix (a KrakenSDR's clock).
    fn epoch_ms(&self, ms: u64) -> u64 {
        let midnight = time::Month::try_from(self.date.month)
            .ok()
            .and_then(|m| {
                time::Date::from_calendar_date(i32::from(self.date.year), m, self.date.day).ok()
            })
            .map_or(0, |d| {
                d.midnight().assume_utc().unix_timestamp().max(0) as u64
            });
        midnight * 1000 + u64::from(self.start.ms_of_day) + ms
    }

    /// UTC time and date `ms` after the first fix: a drive past midnight rolls the date.
    fn at(&self, ms: u64) -> (UtcTime, Date) {
        const DAY: u64 = 86_400_000;
        let total = u64::from(self.start.ms_of_day) + ms;
        let date = time::Date::from_calendar_date(
            i32::from(self.date.year),
            time::Month::try_from(self.date.month).unwrap_or(time::Month::January),
            self.date.day,
        )
        .ok()
        .and_then(|d| d.checked_add(time::Duration::days((total / DAY) as i64)))
        .map(|d| Date {
            year: d.year().clamp(0, 9999) as u16,
            month: d.month() as u8,
            day: d.day(),
        })
        .unwrap_or(self.date);
        (
            UtcTime {
                ms_of_day: (total % DAY) as u32,
            },
            date,
        )
    }
}

/// The capture of one run of a bearing scenario. Local (0, 0) of the capture is the route's
/// first point, at `o.origin`: the emitter lies at `emitter - route[0]` in a replay's frame.
pub fn drive_capture(scenario: &Scenario, o: &CaptureOptions) -> Result<Vec<u8>, String> {
    o.check()?;
    let s: &Drive = scenario
        .drive()
        .ok_or_else(|| format!("`{}` is not a drive (a bearing scenario)", scenario.name))?;
    let frame = LocalFrame::new(o.origin, 0.0).map_err(|_| "origin out of range".to_string())?;
    let n = s.route.len();
    if n < 2 {
        return Err("a drive needs at least two route points".into());
    }
    // The route plus one point beyond its end, on the last leg's line.
    let mut points = s.route.clone();
    let (a, b) = (s.route[n - 2], s.route[n - 1]);
    points.push([2.0 * b[0] - a[0], 2.0 * b[1] - a[1]]);
    let start = s.route[0];
    let mut rng = scenario.rng(o.run);
    let sigma = s.sigma();
    let wild = o.wild_fraction.unwrap_or(s.wild_fraction);
    let bias = o.bias_deg.to_radians();
    let mut w = CaptureWriter::new();
    let local = |p: [f32; 2]| [f64::from(p[0] - start[0]), f64::from(p[1] - start[1])];
    let geodetic = |p: [f32; 2]| {
        frame
            .to_geodetic(local(p))
            .map_err(|_| "route point out of range".to_string())
    };
    let emitter = geodetic(s.emitter)?;
    for (k, p) in points.iter().enumerate() {
        let at_ms = u64::from(o.interval_ms) * k as u64;
        let (time, date) = o.at(at_ms);
        // The route's first point is the origin: a replay's local frame (origin: the first
        // fix) then equals the scenario's, shifted by that point.
        let geo = geodetic(*p)?;
        // Past the last point the vehicle keeps its last leg's speed and course.
        let next = points.get(k + 1).copied().unwrap_or_else(|| {
            let prev = points[k - 1];
            [2.0 * p[0] - prev[0], 2.0 * p[1] - prev[1]]
        });
        let (dx, dy) = (next[0] - p[0], next[1] - p[1]);
        let speed_mps = f64::from(dx.hypot(dy)) * 1000.0 / f64::from(o.interval_ms);
        let speed_kn = speed_mps * 3600.0 / 1852.0;
        let course = f64::from(dx.atan2(dy).to_degrees().rem_euclid(360.0));
        if !o.format.kraken() {
            w.gga(time, geo)?;
            w.rmc(time, date, geo, speed_kn, course)?;
        }
        if k + 1 == points.len() {
            break;
        }
        // PFOXB: half a second later, from halfway to the next point; the others at the
        // point itself.
        let vehicle = match o.format {
            CaptureFormat::Pfoxb => [(p[0] + next[0]) / 2.0, (p[1] + next[1]) / 2.0],
            _ => *p,
        };
        let theta = if random::uniform(&mut rng) < wild {
            random::uniform_in(&mut rng, -PI, PI)
        } else {
            wrap(predicted(&s.emitter, &vehicle) + bias + sigma * random::normal(&mut rng))
        };
        let quality = random::uniform_in(&mut rng, 60.0, 100.0).round();
        let here = geodetic(vehicle)?;
        let azimuth = (f64::from(theta_to_azimuth(theta).to_degrees())
            + convergence_deg(here, emitter, local(vehicle), local(s.emitter)))
        .rem_euclid(360.0);
        match o.format {
            CaptureFormat::Pfoxb => {
                let bearing = Pfoxb {
                    time: o.at(at_ms + u64::from(o.interval_ms / 2)).0,
                    azimuth_deg: azimuth % 360.0,
                    reference: Reference::True,
                    quality,
                    freq_mhz: o.freq_mhz,
                    position: None,
                };
                w.pfoxb(&bearing)?;
            }
            CaptureFormat::Agrelo => {
                // The heading as HDT writes it (two decimals), and the bearing relative to it.
                let heading = (course * 100.0).round() / 100.0 % 360.0;
                w.hdt(&Hdt {
                    talker: *b"HE",
                    heading_deg: heading,
                })?;
                let relative = ((azimuth - heading).rem_euclid(360.0) * 10.0).round() / 10.0;
                w.agrelo(&Agrelo {
                    // 0 is "no bearing": dead ahead is sent as 360, as some units do.
                    bearing_deg: if relative == 0.0 || relative >= 360.0 {
                        360.0
                    } else {
                        relative as f32
                    },
                    quality: (quality / 100.0 * 9.0).round().clamp(1.0, 9.0) as u8,
                    magnetic_deg: None,
                })?;
            }
            CaptureFormat::KrakenCsv | CaptureFormat::KrakenXml => {
                // The heading as the records write it (one decimal).
                let heading = (course * 10.0).round() / 10.0 % 360.0;
                let relative = (azimuth - heading).rem_euclid(360.0) as f32;
                let epoch = o.epoch_ms(at_ms);
                let station = Station::new("foxhunt-sim");
                if o.format == CaptureFormat::KrakenCsv {
                    w.kraken_csv(
                        &KrakenCsv {
                            epoch_ms: epoch,
                            bearing_deg: relative,
                            confidence: quality / 100.0,
                            power_db: -40.0,
                            freq_hz: (o.freq_mhz * 1e6).round() as u64,
                            array: ArrayType::Uca,
                            latency_ms: 100,
                            station,
                            position: Some(here),
                            heading_deg: heading as f32,
                        },
                        &spectrum(relative),
                    )?;
                } else {
                    w.kraken_xml(&KrakenXml {
                        station,
                        time_ms: Some(epoch),
                        gps_time_ms: Some(epoch),
                        freq_mhz: Some(o.freq_mhz),
                        position: Some(here),
                        heading_deg: Some(heading as f32),
                        speed_mps: Some(speed_mps as f32),
                        // The raw anticlockwise angle.
                        doa_deg: (360.0 - relative).rem_euclid(360.0),
                        pwr: Some(60.0),
                        conf: Some(quality),
                    })?;
                }
            }
        }
    }
    let mut out = w.into_bytes();
    damage(&mut out, o, &mut rng);
    Ok(out)
}

/// How much north at `here` is turned clockwise from the frame's north, degrees: the azimuth
/// at `here` of the emitter (the chord in `here`'s own tangent plane, as a DF unit measures
/// it) less the same direction in the frame (`vehicle` to `emitter`, local metres).
fn convergence_deg(here: LatLon, emitter: LatLon, vehicle: [f64; 2], target: [f64; 2]) -> f64 {
    let at_vehicle = LocalFrame::new(here, 0.0)
        .and_then(|f| f.to_local(emitter))
        .map(|t| t[0].atan2(t[1]));
    let in_frame = (target[0] - vehicle[0]).atan2(target[1] - vehicle[1]);
    match at_vehicle {
        // A vehicle on the emitter has no direction to turn.
        Ok(a) if (target[0] - vehicle[0]).hypot(target[1] - vehicle[1]) > 1e-3 => {
            ((a - in_frame).to_degrees() + 180.0).rem_euclid(360.0) - 180.0
        }
        _ => 0.0,
    }
}

/// A KrakenSDR DoA spectrum for a relative bearing: a 20 dB peak 10 degrees wide, indexed
/// anticlockwise from the array's front as the DSP writes it.
fn spectrum(relative_deg: f32) -> Vec<f32> {
    let peak = (360.0 - relative_deg).rem_euclid(360.0);
    (0..SPECTRUM_LEN)
        .map(|i| {
            let d = (i as f32 - peak + 180.0).rem_euclid(360.0) - 180.0;
            20.0 * (-d * d / (2.0 * 5.0 * 5.0)).exp()
        })
        .collect()
}

/// Corrupt and drop bytes as asked, after the capture is written.
fn damage(bytes: &mut Vec<u8>, o: &CaptureOptions, rng: &mut rand_xorshift::XorShiftRng) {
    use rand_core::Rng;
    if o.corrupt_fraction <= 0.0 && o.drop_fraction <= 0.0 {
        return;
    }
    let mut kept = Vec::with_capacity(bytes.len());
    for &b in bytes.iter() {
        if random::uniform(rng) < o.drop_fraction {
            continue;
        }
        if random::uniform(rng) < o.corrupt_fraction {
            kept.push(b ^ (1 + (rng.next_u32() % 255) as u8));
        } else {
            kept.push(b);
        }
    }
    *bytes = kept;
}

/// A simulated indoor capture: its bytes, its anchors file and the node's true positions.
pub type IndoorCapture = (Vec<u8>, AnchorsFile, Vec<[f32; 2]>);

/// A simulated indoor capture: AF_INCOMING_MSG frames of every anchor each epoch, and the
/// node's true positions.
pub fn indoor_capture(name: &str, run: usize) -> Result<IndoorCapture, String> {
    let s = Scenario::named(name)
        .ok_or_else(|| format!("`{name}` is not an RSSI scenario (rssi-sim, rssi-lab)"))?;
    let ScenarioModel::Rssi {
        tracker: t,
        start,
        steps,
    } = s.model
    else {
        return Err(format!(
            "`{name}` is not an RSSI scenario (rssi-sim, rssi-lab)"
        ));
    };
    let file = AnchorsFile {
        room: t.room,
        dt_s: t.dt,
        sigma_db: t.sigma[0],
        process_q: t.q,
        path_loss: PathLossEntry {
            p0_dbm: t.path_loss.p0,
            d0_m: t.path_loss.d0,
            eta: t.path_loss.eta,
        },
        origin: None,
        power_sd_db: 0.0,
        exponent_sd: 0.0,
        anchor: (0..3)
            .map(|i| Anchor {
                addr: 0x0101 + i as u16,
                x: t.anchors[i][0],
                y: t.anchors[i][1],
                p0_dbm: None,
                eta: None,
            })
            .collect(),
    };
    let (states, readings) =
        crate::runs::tracking::simulate_rssi(&t, start, steps, &mut s.rng(run));
    let dbm: Vec<[f32; 3]> = readings.iter().map(|m| m.dbm).collect();
    let map = LinkQualityMap::default();
    let mut w = CaptureWriter::new();
    let mut seq = 0u8;
    for (k, z) in dbm.iter().enumerate() {
        for (i, a) in file.anchor.iter().enumerate() {
            let msg = AfIncomingMsg {
                group_id: 0,
                cluster_id: 0x0402,
                src_addr: a.addr,
                src_endpoint: 1,
                dst_endpoint: 1,
                was_broadcast: false,
                link_quality: map.link_quality(z[i]),
                security_use: false,
                timestamp: (k as f32 * t.dt * 1000.0) as u32,
                trans_seq: seq,
                data: &[0x18, seq, 0x0a],
            };
            seq = seq.wrapping_add(1);
            w.af_incoming_msg(&msg)?;
        }
    }
    let truth = states.iter().map(|x| [x[0], x[2]]).collect();
    Ok((w.into_bytes(), file, truth))
}

#[cfg(test)]
mod tests {
    use super::*;
    use foxhunt_bridge::bridge::{BridgeConfig, Event, Receiver};

    #[test]
    fn capture_replays_to_the_scenario_bearings() {
        let scenario = Scenario::named("aoa-drive").expect("scenario");
        let s = scenario.drive().expect("a drive");
        let bytes = drive_capture(&scenario, &CaptureOptions::default()).expect("capture");
        let mut rx = Receiver::<0>::new(BridgeConfig::default(), []);
        let mut bearings = Vec::new();
        let mut sink = |e| {
            if let Event::Bearing(b) = e {
                bearings.push(b.bearing);
            }
        };
        rx.feed(&bytes, &mut sink);
        rx.finish(&mut sink);
        assert_eq!(bearings.len(), s.route.len());
        // Each bearing sits halfway along its leg: the interpolation recovered the position
        // to a centimetre (NMEA positions carry 1e-6 minutes, about 2 mm).
        for (k, b) in bearings.iter().enumerate() {
            let p = s.route[k];
            let q = s.route.get(k + 1).copied().unwrap_or_else(|| {
                let prev = s.route[k - 1];
                [2.0 * p[0] - prev[0], 2.0 * p[1] - prev[1]]
            });
            let o = s.route[0];
            let mid = [(p[0] + q[0]) / 2.0 - o[0], (p[1] + q[1]) / 2.0 - o[1]];
            let err = (b.vehicle[0] - mid[0]).hypot(b.vehicle[1] - mid[1]);
            assert!(err < 0.01, "bearing {k}: {err} m off");
        }
    }
}

#[cfg(test)]
mod time_tests {
    use super::*;

    #[test]
    fn a_drive_past_midnight_rolls_the_date() {
        let o = CaptureOptions {
            start: UtcTime {
                ms_of_day: 86_399_000,
            },
            date: Date {
                year: 2026,
                month: 12,
                day: 31,
            },
            ..CaptureOptions::default()
        };
        let (t, d) = o.at(1500);
        assert_eq!(t.ms_of_day, 500);
        assert_eq!(
            d,
            Date {
                year: 2027,
                month: 1,
                day: 1
            }
        );
        let (t, d) = o.at(3 * 86_400_000);
        assert_eq!((t.ms_of_day, d.day, d.month), (86_399_000, 3, 1));
    }
}
