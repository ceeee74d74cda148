//! Captures as the radios would send them: a scenario's drive written as GGA, RMC and PFOXB
//! sentences, byte for byte what `cat /dev/ttyUSB0 > drive.nmea` would record.
//!
//! The GPS reports each route point at a whole second; the DF unit reports half a second later,
//! from the point halfway to the next one (the vehicle drives straight between fixes), so a
//! replay must interpolate the vehicle's position at the bearing's time to place it right. A
//! last fix one step beyond the route closes the drive.

use crate::scenario::{Drive, Scenario};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::{
    Date, LatLon, Line, Pfoxb, Reference, UtcTime, gga_body, pfoxb_body, rmc_body, write_sentence,
};
use foxhunt_core::model::bearing::{predicted, theta_to_azimuth, wrap};
use foxhunt_core::random;
use std::f32::consts::PI;

/// Where the route's first point sits unless `--origin` says otherwise: 47.0 N, 8.0 E.
pub const DEFAULT_ORIGIN: LatLon = LatLon {
    lat: 47.0,
    lon: 8.0,
};

/// How a capture is written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CaptureOptions {
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

fn push(out: &mut Vec<u8>, body: &str) {
    let mut s = String::new();
    // Writing to a String cannot fail.
    let _ = write_sentence(&mut s, body);
    out.extend_from_slice(s.as_bytes());
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
    let mut out = Vec::new();
    let mut line = Line::new();
    let fmt_err = |_| "sentence longer than 96 characters".to_string();
    for (k, p) in points.iter().enumerate() {
        let (time, date) = o.at(u64::from(o.interval_ms) * k as u64);
        // The route's first point is the origin: a replay's local frame (origin: the first
        // fix) then equals the scenario's, shifted by that point.
        let geo = frame
            .to_geodetic([f64::from(p[0] - start[0]), f64::from(p[1] - start[1])])
            .map_err(|_| "route point out of range".to_string())?;
        // Past the last point the vehicle keeps its last leg's speed and course.
        let next = points.get(k + 1).copied().unwrap_or_else(|| {
            let prev = points[k - 1];
            [2.0 * p[0] - prev[0], 2.0 * p[1] - prev[1]]
        });
        let (dx, dy) = (next[0] - p[0], next[1] - p[1]);
        let speed_kn =
            f64::from(dx.hypot(dy)) * 1000.0 / f64::from(o.interval_ms) * 3600.0 / 1852.0;
        let course = f64::from(dx.atan2(dy).to_degrees().rem_euclid(360.0));
        line.clear();
        gga_body(&mut line, time, geo, 9, 0.9).map_err(fmt_err)?;
        push(&mut out, &line);
        line.clear();
        rmc_body(&mut line, time, date, geo, speed_kn, course).map_err(fmt_err)?;
        push(&mut out, &line);
        if k + 1 == points.len() {
            break;
        }
        // The bearing half a second later, from halfway to the next point.
        let vehicle = [(p[0] + next[0]) / 2.0, (p[1] + next[1]) / 2.0];
        let theta = if random::uniform(&mut rng) < wild {
            random::uniform_in(&mut rng, -PI, PI)
        } else {
            wrap(predicted(&s.emitter, &vehicle) + bias + sigma * random::normal(&mut rng))
        };
        let azimuth = f64::from(theta_to_azimuth(theta).to_degrees()) % 360.0;
        let bearing = Pfoxb {
            time: o
                .at(u64::from(o.interval_ms) * k as u64 + u64::from(o.interval_ms / 2))
                .0,
            azimuth_deg: azimuth,
            reference: Reference::True,
            quality: random::uniform_in(&mut rng, 60.0, 100.0).round(),
            freq_mhz: o.freq_mhz,
            position: None,
        };
        line.clear();
        pfoxb_body(&mut line, &bearing).map_err(fmt_err)?;
        push(&mut out, &line);
    }
    damage(&mut out, o, &mut rng);
    Ok(out)
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
