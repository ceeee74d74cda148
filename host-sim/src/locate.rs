//! `foxhunt locate`: the emitter's position from a drive's bytes.
//!
//! The bytes go through the serial bridge (the same code as the firmware) into bearings in
//! local metres, streamed in chunks so memory is bounded by the bearings kept (16 bytes each),
//! never by the capture; a fix method of the core's registry turns them into a position with
//! its covariance, the 95 % ellipse and CEP50; the CRLB of the drive's geometry says how good
//! any unbiased fix could be. Bearing noise is estimated from the fix's residuals unless the
//! user gives it, so the ellipse is honest about the DF unit actually used.

use crate::runs::locate_bearings;
use foxhunt_bridge::bridge::{BridgeConfig, BridgeCounters, Event, Receiver, VehicleFix};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::stream::StreamCounters;
use foxhunt_bridge::{Frame, nmea::LatLon};
use foxhunt_core::fix::crlb::crlb;
use foxhunt_core::fix::ellipse::{Ellipse, cep50};
use foxhunt_core::model::bearing::{predicted, wrap};
use foxhunt_core::{Bearing, Error, Method};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write;

/// Particles of the sequential methods unless `--particles` says otherwise.
pub const PARTICLES: usize = 1000;

/// The seeds' random-walk jitter for their filters (`sir-seed`, the swarms), m^2 per step: the
/// value of their aoa-afsa scenario. A real drive has no jitter of its own to take.
pub const SEEDS_JITTER_M2: f32 = 1.0;

/// How `locate` computes the fix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocateOptions {
    /// The estimator.
    pub method: Method,
    /// Particles of sequential methods (a compiled count).
    pub particles: usize,
    /// The DF unit's bearing noise, degrees, or `None` to estimate it.
    pub sigma_deg: Option<f32>,
    /// Seed of the particle methods.
    pub seed: u64,
}

impl Default for LocateOptions {
    fn default() -> Self {
        Self {
            method: Method::MlHuber,
            particles: PARTICLES,
            sigma_deg: None,
            seed: 1,
        }
    }
}

impl LocateOptions {
    /// Refuse settings no fix can use, naming the value.
    pub fn check(&self) -> Result<(), String> {
        if let Some(s) = self.sigma_deg
            && !(s > 0.0 && s < 90.0)
        {
            return Err(format!(
                "--sigma-deg must lie between 0 and 90 degrees, not {s}"
            ));
        }
        if self.method.uses_particles() && !foxhunt_core::PARTICLE_COUNTS.contains(&self.particles)
        {
            return Err(format!(
                "--particles {} is not a compiled size; use one of {:?}",
                self.particles,
                foxhunt_core::PARTICLE_COUNTS
            ));
        }
        Ok(())
    }
}

/// The 95 % ellipse in the report: semi-axes.
#[derive(Debug, Clone, Serialize)]
pub struct EllipseReport {
    /// Semi-major axis, metres.
    pub major_m: f32,
    /// Semi-minor axis, metres.
    pub minor_m: f32,
    /// Orientation of the major axis, degrees clockwise from north.
    pub orientation_deg: f32,
    /// Probability inside.
    pub confidence: f32,
}

/// A latitude and longitude in a report.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct LatLonReport {
    /// Degrees.
    pub lat: f64,
    /// Degrees.
    pub lon: f64,
}

/// What `locate` found (the `--json` object; field names are stable).
#[derive(Debug, Clone, Serialize)]
pub struct LocateReport {
    /// Emitter latitude, degrees.
    pub lat: f64,
    /// Emitter longitude, degrees.
    pub lon: f64,
    /// Emitter east of the local origin (the first valid vehicle fix), metres.
    pub east_m: f32,
    /// Emitter north of the local origin, metres.
    pub north_m: f32,
    /// The local origin.
    pub origin: LatLonReport,
    /// The 95 % confidence ellipse.
    pub ellipse: EllipseReport,
    /// Circular error probable (50 %), metres.
    pub cep50_m: f32,
    /// sqrt(trace) of the CRLB of the drive's geometry at the fix, metres.
    pub crlb_m: f32,
    /// The method used (the registry's name).
    pub method: &'static str,
    /// Bearing noise used, degrees.
    pub sigma_deg: f32,
    /// Whether `sigma_deg` was estimated (not given).
    pub sigma_estimated: bool,
    /// Bearings used.
    pub used: u32,
    /// Measurements and frames rejected, by reason.
    pub rejected: BTreeMap<&'static str, u32>,
}

/// A position with covariance, and the particle cloud if the method has one.
#[derive(Debug, Clone)]
pub struct Solution {
    /// Position, local metres.
    pub position: [f32; 2],
    /// Covariance, m^2.
    pub covariance: [[f32; 2]; 2],
    /// Bearings a robust loss treated as outliers (beyond 3 sigma).
    pub outliers: u32,
    /// The method's particles (empty for batch fixes and the EKF).
    pub cloud: Vec<[f32; 2]>,
}

/// A fix: the report and what the maps draw.
#[derive(Debug, Clone)]
pub struct Located {
    /// The report.
    pub report: LocateReport,
    /// The solution behind it.
    pub solution: Solution,
}

/// Sentences and records of one kind seen in a capture, and how many the bridge refused as
/// malformed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct KindTally {
    /// Seen.
    pub seen: u32,
    /// Refused with a bad or out-of-range field.
    pub malformed: u32,
    /// Saying the receiver has no fix (GPS only).
    pub no_fix: u32,
}

/// Everything decoded from a capture.
#[derive(Debug, Clone, Default)]
pub struct Decoded {
    /// Bearings in the local frame.
    pub bearings: Vec<Bearing>,
    /// The vehicle's fixes, kept only when a map asks for them.
    pub track: Vec<VehicleFix>,
    /// Vehicle fixes seen.
    pub fixes: u64,
    /// The local frame, if any fix arrived.
    pub frame: Option<LocalFrame>,
    /// Stream counters.
    pub stream: StreamCounters,
    /// Bridge counters.
    pub bridge: BridgeCounters,
    /// GPS position sentences seen.
    pub gps: KindTally,
    /// Bearing records seen.
    pub bearing_records: KindTally,
}

/// Whether a frame carries a GPS position, a bearing, or something else.
enum Kind {
    Gps,
    Bearing,
    Other,
}

fn kind(f: &Frame<'_>) -> Kind {
    match f {
        Frame::Nmea(text) => match text.get(2..5) {
            _ if text.starts_with('P') => {
                if text.starts_with("PFOXB") {
                    Kind::Bearing
                } else {
                    Kind::Other
                }
            }
            Some("GGA" | "RMC" | "GLL" | "GNS") => Kind::Gps,
            _ => Kind::Other,
        },
        Frame::Agrelo(_) | Frame::KrakenCsv(_) | Frame::KrakenXml(_) => Kind::Bearing,
        Frame::Mt(_) => Kind::Other,
    }
}

/// The bridge fed byte by byte or chunk by chunk, keeping what a fix needs.
pub struct Decoder {
    rx: Receiver<0>,
    /// What has been decoded so far.
    pub decoded: Decoded,
    keep_track: bool,
}

impl Decoder {
    /// A decoder; `keep_track` keeps every vehicle fix (for maps).
    pub fn new(config: BridgeConfig, keep_track: bool) -> Self {
        Self {
            rx: Receiver::new(config, []),
            decoded: Decoded::default(),
            keep_track,
        }
    }

    /// Feed bytes as they arrive.
    pub fn feed(&mut self, bytes: &[u8]) {
        let (demux, bridge) = (&mut self.rx.demux, &mut self.rx.bridge);
        let (d, keep) = (&mut self.decoded, self.keep_track);
        demux.feed(bytes, &mut |f| push(bridge, &f, d, keep));
    }

    /// The line went quiet: settle frames waiting on look-ahead.
    pub fn idle(&mut self) {
        self.rx.demux.idle();
        let (d, keep) = (&mut self.decoded, self.keep_track);
        while let Some(f) = self.rx.demux.next_frame() {
            push(&mut self.rx.bridge, &f, d, keep);
        }
        self.snapshot();
    }

    /// End of the stream: frames still buffered are delivered and bearings waiting for a
    /// later fix are placed with the fixes there are. Idempotent.
    pub fn end(&mut self) {
        let (demux, bridge) = (&mut self.rx.demux, &mut self.rx.bridge);
        let (d, keep) = (&mut self.decoded, self.keep_track);
        demux.finish_into(&mut |f| push(bridge, &f, d, keep));
        bridge.finish(&mut |e| absorb(d, e, keep));
        self.snapshot();
    }

    /// End of the stream: everything decoded.
    pub fn finish(mut self) -> Decoded {
        self.end();
        self.decoded
    }

    /// Bring the frame and counters up to date (before a fix is computed mid-stream).
    pub fn snapshot(&mut self) {
        self.decoded.frame = self.rx.bridge.local_frame().copied();
        let (s, b) = self.rx.counters();
        self.decoded.stream = *s;
        self.decoded.bridge = *b;
    }

    /// Take one NMEA sentence body (no `$`, checksum or line end) as if it had come on the
    /// line: how gpsd's positions and headings reach the bridge, between the line's bytes.
    pub fn push_sentence(&mut self, body: &str) {
        let (d, keep) = (&mut self.decoded, self.keep_track);
        push(&mut self.rx.bridge, &Frame::Nmea(body), d, keep);
    }
}

fn absorb(d: &mut Decoded, e: Event, keep_track: bool) {
    match e {
        Event::Bearing(b) => d.bearings.push(b.bearing),
        Event::Fix(f) => {
            d.fixes += 1;
            if keep_track {
                d.track.push(f);
            }
        }
        Event::Rssi(_) => {}
    }
}

/// One frame into the bridge, its refusals attributed to its kind.
fn push(bridge: &mut foxhunt_bridge::Bridge<0>, f: &Frame<'_>, d: &mut Decoded, keep_track: bool) {
    let before = *bridge.counters();
    bridge.push(f, &mut |e| absorb(d, e, keep_track));
    let after = bridge.counters();
    let malformed =
        (after.bad_field - before.bad_field) + (after.bad_position - before.bad_position);
    let tally = match kind(f) {
        Kind::Gps => &mut d.gps,
        Kind::Bearing => &mut d.bearing_records,
        Kind::Other => return,
    };
    tally.seen += 1;
    tally.malformed += malformed;
    tally.no_fix += after.no_fix_sentences - before.no_fix_sentences;
}

/// Decode whole captures (bytes as a UART delivered them).
pub fn decode(bytes: &[u8], config: BridgeConfig, keep_track: bool) -> Decoded {
    let mut dec = Decoder::new(config, keep_track);
    dec.feed(bytes);
    dec.finish()
}

/// Rejections by reason, every reason listed (zero included) so scripts can rely on the keys.
pub fn rejections(d: &Decoded, outliers: u32) -> BTreeMap<&'static str, u32> {
    let (s, b) = (&d.stream, &d.bridge);
    BTreeMap::from([
        ("bad_checksum", s.bad_checksum + s.bad_fcs),
        ("malformed", s.malformed + b.bad_field + b.short_mt),
        ("too_long", s.too_long),
        ("overlapping_frame", s.overlapping),
        ("truncated", s.truncated),
        ("garbage_bytes", s.garbage_bytes),
        ("gps_no_fix", b.no_fix_sentences),
        ("bad_position", b.bad_position),
        ("low_quality", b.low_quality),
        ("no_heading", b.no_heading),
        ("no_bearing", b.no_bearing),
        ("no_fix", b.no_fix),
        ("stale_fix", b.stale_fix),
        ("outlier", outliers),
    ])
}

/// Why a capture gives no position for the vehicle, in words a user can act on.
fn no_vehicle_position(d: &Decoded) -> String {
    let g = d.gps;
    if g.seen == 0 {
        let bad = d.stream.bad_checksum + d.stream.malformed;
        return if bad > 0 {
            format!(
                "no GPS fix: no GGA/RMC/GLL/GNS sentence decoded ({bad} sentences failed their \
                 checksum or framing)"
            )
        } else {
            "no GPS fix: the capture holds no GGA/RMC/GLL/GNS sentence, so bearings cannot be \
             placed"
                .into()
        };
    }
    format!(
        "no GPS fix: {} position sentences, {} saying the receiver has no fix, {} with a \
         malformed or out-of-range field",
        g.seen, g.no_fix, g.malformed
    )
}

/// Why a capture with a vehicle track gives no usable bearing.
fn no_bearing(d: &Decoded) -> String {
    let (r, b) = (d.bearing_records, &d.bridge);
    if r.seen == 0 {
        return "no bearing record in the capture (no $PFOXB, Agrelo or KrakenSDR record)".into();
    }
    let mut why = Vec::new();
    let mut reason = |n: u32, text: &str| {
        if n > 0 {
            why.push(format!("{n} {text}"));
        }
    };
    reason(r.malformed, "with a malformed or out-of-range field");
    reason(b.low_quality, "at or below the quality gate");
    reason(b.no_heading, "relative with no heading to turn them by");
    reason(b.no_bearing, "saying the DF unit had no bearing");
    reason(b.no_fix, "before any GPS fix");
    reason(
        b.stale_fix,
        "with no GPS fix within the allowed gap of their time",
    );
    format!(
        "no usable bearing: of {} bearing records, {}",
        r.seen,
        if why.is_empty() {
            "none reached the bridge".into()
        } else {
            why.join(", ")
        }
    )
}

/// Why the bearings give no fix, in words a user can act on.
pub fn explain(e: Error, d: &Decoded) -> String {
    match e {
        Error::TooFewMeasurements if d.bearings.len() == 1 => {
            "only one usable bearing: a fix needs at least two bearings from different places"
                .into()
        }
        Error::TooFewMeasurements => "too few usable bearings for a fix".into(),
        Error::ParallelBearings => "all bearings are parallel: they never cross, so the range is \
             unknown; drive across the line of bearing"
            .into(),
        Error::StationaryVehicle => {
            "the vehicle never moved: bearings from one place give a direction, not a position"
                .into()
        }
        _ if points_away(&d.bearings) => "the bearings point away from where their lines cross \
             (they meet behind the vehicle): is the DF unit's angle convention reversed (180 \
             degrees) or mirrored?"
            .into(),
        Error::ShallowCrossing => {
            "the bearings cross too shallowly for a fix; drive further across the line of bearing"
                .into()
        }
        Error::DegenerateGeometry => "the bearings do not pin down a point (their information is \
             singular); drive across the line of bearing"
            .into(),
        Error::BehindVehicle => "the bearings meet behind the vehicle: no emitter there".into(),
        e => format!("no fix: {e}"),
    }
}

/// Whether nearly all of at least five bearings point away from where their lines cross (the
/// pseudo-linear fix, which treats a bearing as an undirected line): the sign of a reversed or
/// mirrored DF convention. Fewer, or a mixed picture, is a geometry problem instead.
fn points_away(bearings: &[Bearing]) -> bool {
    let Ok(f) = foxhunt_core::fix::ple::ple(bearings) else {
        return false;
    };
    let away = bearings
        .iter()
        .filter(|b| b.residual(&f.position).cos() < 0.0)
        .count();
    bearings.len() >= 5 && 10 * away >= 9 * bearings.len()
}

fn with_sigma(bearings: &[Bearing], sigma: f32) -> Vec<Bearing> {
    bearings.iter().map(|b| Bearing { sigma, ..*b }).collect()
}

/// Bearing noise from the residuals at `p`: a MAD scale (1.4826 x median |r|) finds the
/// inliers (within 3 of it), whose RMS over n - 2 degrees of freedom, corrected for the
/// truncation (a Gaussian cut at 3 sigma keeps 0.9733 of its variance), is the estimate: about
/// 9 % standard error at 60 bearings against the MAD's 15 %. At least 0.05 degrees.
pub fn estimate_sigma(bearings: &[Bearing], p: &[f32; 2]) -> f32 {
    let floor = 0.05f32.to_radians();
    let mut r: Vec<f32> = bearings
        .iter()
        .map(|b| wrap(b.theta - predicted(p, &b.vehicle)).abs())
        .filter(|r| r.is_finite())
        .collect();
    if r.len() < 3 {
        return 1.0f32.to_radians();
    }
    let mid = r.len() / 2;
    let (_, median, _) = r.select_nth_unstable_by(mid, f32::total_cmp);
    let mad = (1.4826 * *median).max(floor);
    let inliers: Vec<f32> = r.into_iter().filter(|x| *x <= 3.0 * mad).collect();
    if inliers.len() < 3 {
        return mad;
    }
    let ss: f64 = inliers.iter().map(|x| f64::from(x * x)).sum();
    ((ss / (inliers.len() - 2) as f64 / 0.9733).sqrt() as f32).max(floor)
}

/// Locate the emitter of a decoded capture.
pub fn locate(d: &Decoded, o: &LocateOptions) -> Result<Located, String> {
    o.check()?;
    let Some(frame) = d.frame else {
        return Err(no_vehicle_position(d));
    };
    if d.bearings.is_empty() {
        return Err(no_bearing(d));
    }
    let (sigma, estimated) = match o.sigma_deg {
        Some(s) => (s.to_radians(), false),
        None => {
            // Two passes of the robust ML: the first with a nominal 1 degree, the second with
            // the noise its residuals show.
            let first = with_sigma(&d.bearings, 1.0f32.to_radians());
            let f = foxhunt_core::estimator::batch_fix(Method::MlHuber, &first)
                .map_err(|e| explain(e, d))?;
            (estimate_sigma(&first, &f.position), true)
        }
    };
    let bearings = with_sigma(&d.bearings, sigma);
    let mut rng = XorShiftRng::seed_from_u64(o.seed);
    let s = crate::montecarlo::pool()
        .install(|| {
            locate_bearings(
                o.method,
                o.particles,
                SEEDS_JITTER_M2,
                &bearings,
                true,
                &mut rng,
            )
        })
        .map_err(|e| explain(e, d))?;
    let e = Ellipse::from_covariance(&s.covariance, 0.95).map_err(|e| explain(e, d))?;
    let cep = cep50(&s.covariance).map_err(|e| explain(e, d))?;
    let bound = crlb(&s.position, &bearings).map_err(|e| explain(e, d))?;
    let geo = frame
        .to_geodetic([f64::from(s.position[0]), f64::from(s.position[1])])
        .map_err(|_| "the fix lies outside the valid latitude/longitude range".to_string())?;
    let orientation = (90.0 - e.orientation.to_degrees()).rem_euclid(180.0);
    let report = LocateReport {
        lat: geo.lat,
        lon: geo.lon,
        east_m: s.position[0],
        north_m: s.position[1],
        origin: LatLonReport {
            lat: frame.origin.lat,
            lon: frame.origin.lon,
        },
        ellipse: EllipseReport {
            major_m: e.major,
            minor_m: e.minor,
            orientation_deg: orientation,
            confidence: e.confidence,
        },
        cep50_m: cep,
        crlb_m: bound.rmse,
        method: o.method.name(),
        sigma_deg: sigma.to_degrees(),
        sigma_estimated: estimated,
        used: bearings.len() as u32,
        rejected: rejections(d, s.outliers),
    };
    Ok(Located {
        report,
        solution: Solution {
            position: s.position,
            covariance: s.covariance,
            outliers: s.outliers,
            cloud: s.cloud,
        },
    })
}

impl LocateReport {
    /// The report as the terminal shows it.
    pub fn text(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "emitter      {:.6}, {:.6}  ({:.1} m east, {:.1} m north of {:.6}, {:.6})",
            self.lat, self.lon, self.east_m, self.north_m, self.origin.lat, self.origin.lon
        );
        let _ = writeln!(
            out,
            "95 % ellipse semi-axes {:.1} m and {:.1} m, major axis {:.0} deg from north; CEP50 {:.1} m",
            self.ellipse.major_m, self.ellipse.minor_m, self.ellipse.orientation_deg, self.cep50_m
        );
        let _ = writeln!(
            out,
            "CRLB         {:.1} m for this drive's geometry (best any unbiased fix can do)",
            self.crlb_m
        );
        let _ = writeln!(
            out,
            "method       {}, bearing noise {:.2} deg ({})",
            self.method,
            self.sigma_deg,
            if self.sigma_estimated {
                "estimated from the residuals"
            } else {
                "given"
            }
        );
        let rejected: Vec<String> = self
            .rejected
            .iter()
            .filter(|(_, n)| **n > 0)
            .map(|(k, n)| format!("{k} {n}"))
            .collect();
        let _ = writeln!(
            out,
            "bearings     {} used; rejected: {}",
            self.used,
            if rejected.is_empty() {
                "none".to_string()
            } else {
                rejected.join(", ")
            }
        );
        out
    }

    /// One line for a live update.
    pub fn update_line(&self) -> String {
        format!(
            "{} bearings: {:.6}, {:.6}  CEP50 {:.1} m, CRLB {:.1} m",
            self.used, self.lat, self.lon, self.cep50_m, self.crlb_m
        )
    }
}

/// The geodetic position of local metres `p` in `frame` (the origin when out of range).
pub fn geodetic(frame: &LocalFrame, p: [f32; 2]) -> LatLon {
    frame
        .to_geodetic([f64::from(p[0]), f64::from(p[1])])
        .unwrap_or(frame.origin)
}
