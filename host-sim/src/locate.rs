//! `foxhunt locate`: the emitter's position from a recorded drive.
//!
//! The capture's bytes go through the serial bridge (the same code as the firmware) into
//! bearings in local metres; a fix method turns them into a position with its covariance, the
//! 95 % ellipse and CEP50, and the CRLB of the drive's geometry says how good any unbiased fix
//! could be. Bearing noise is estimated from the fix's residuals (a robust MAD scale) unless
//! the user gives it, so the ellipse is honest about the DF unit actually used.

use foxhunt_bridge::bridge::{BridgeConfig, BridgeCounters, Event, Receiver, VehicleFix};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_bridge::stream::StreamCounters;
use foxhunt_core::fix::crlb::crlb;
use foxhunt_core::fix::ellipse::{Ellipse, cep50};
use foxhunt_core::fix::init::initial_particles;
use foxhunt_core::fix::intersection::MIN_CROSSING;
use foxhunt_core::fix::ml::{MlOptions, ml};
use foxhunt_core::model::bearing::{predicted, wrap};
use foxhunt_core::{
    Afsa, Bearing, BearingEkf, Error, Filter, Gaussian, GaussianUniform, Gpf, Huber, ParticleSet,
    Sir, SirConfig, StaticEmitter,
};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use serde::Serialize;
use std::collections::BTreeMap;

/// Particles of the sequential methods.
pub const PARTICLES: usize = 1000;

/// How the position is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LocateMethod {
    /// Maximum likelihood with a Huber loss (wild bearings down-weighted): the most accurate.
    Ml,
    /// Maximum likelihood, Gaussian loss (least squares; wild bearings pull it).
    MlGauss,
    /// SIR particle filter, Gaussian + uniform likelihood, 1000 particles.
    Sir,
    /// Gaussian particle filter, 1000 particles.
    Gpf,
    /// Extended Kalman filter.
    Ekf,
    /// Artificial-fish-swarm particle filter (seed 002), 1000 particles.
    Afsa,
}

/// The 95 % ellipse in the report.
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
    /// The method used.
    pub method: LocateMethod,
    /// Bearing noise used, degrees, and whether it was estimated from the residuals.
    pub sigma_deg: f32,
    /// Whether `sigma_deg` was estimated (not given).
    pub sigma_estimated: bool,
    /// Bearings used.
    pub used: u32,
    /// Measurements and frames rejected, by reason.
    pub rejected: BTreeMap<&'static str, u32>,
}

/// A latitude and longitude in a report.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct LatLonReport {
    /// Degrees.
    pub lat: f64,
    /// Degrees.
    pub lon: f64,
}

/// Everything decoded from a capture.
#[derive(Debug, Clone, Default)]
pub struct Decoded {
    /// Bearings in the local frame.
    pub bearings: Vec<Bearing>,
    /// The vehicle's fixes.
    pub track: Vec<VehicleFix>,
    /// The local frame, if any fix arrived.
    pub frame: Option<LocalFrame>,
    /// Stream counters.
    pub stream: StreamCounters,
    /// Bridge counters.
    pub bridge: BridgeCounters,
}

impl Decoded {
    /// Keep what the bridge hands on: bearings and the vehicle track.
    pub fn absorb(&mut self, e: Event) {
        match e {
            Event::Bearing(b) => self.bearings.push(b.bearing),
            Event::Fix(f) => self.track.push(f),
            Event::Rssi(_) => {}
        }
    }
}

/// Decode a capture (bytes as a UART delivered them).
pub fn decode(bytes: &[u8], config: BridgeConfig) -> Decoded {
    let mut rx = Receiver::<0>::new(config, []);
    let mut d = Decoded::default();
    let mut sink = |e| d.absorb(e);
    rx.feed(bytes, &mut sink);
    rx.finish(&mut sink);
    d.frame = rx.bridge.local_frame().copied();
    let (s, b) = rx.counters();
    d.stream = *s;
    d.bridge = *b;
    d
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
        ("no_course", b.no_heading),
        ("no_fix", b.no_fix),
        ("stale_fix", b.stale_fix),
        ("outlier", outliers),
    ])
}

/// Why a capture gives no fix, in words a user can act on.
pub fn explain(e: Error, d: &Decoded) -> String {
    match e {
        Error::TooFewMeasurements if d.bearings.len() == 1 => {
            "only one usable bearing: a fix needs at least two bearings from different places"
                .into()
        }
        Error::TooFewMeasurements => "too few usable bearings for a fix".into(),
        Error::ParallelBearings => {
            "all bearings are parallel: they never cross, so the range is unknown; drive across \
             the line of bearing"
                .into()
        }
        Error::StationaryVehicle => {
            "the vehicle never moved: bearings from one place give a direction, not a position"
                .into()
        }
        Error::ShallowCrossing | Error::DegenerateGeometry => {
            "the bearings cross too shallowly for a fix; drive further across the line of bearing"
                .into()
        }
        Error::BehindVehicle => "the bearings cross behind the vehicle: no emitter there".into(),
        e => format!("no fix: {e}"),
    }
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
    r.sort_by(f32::total_cmp);
    let mad = (1.4826 * r[r.len() / 2]).max(floor);
    let inliers: Vec<f32> = r.into_iter().filter(|x| *x <= 3.0 * mad).collect();
    if inliers.len() < 3 {
        return mad;
    }
    let ss: f32 = inliers.iter().map(|x| x * x).sum();
    (ss / (inliers.len() - 2) as f32 / 0.9733).sqrt().max(floor)
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
    /// Particles (sequential methods).
    pub cloud: Vec<[f32; 2]>,
}

fn filter_solution<F: Filter<2, Measurement = Bearing>>(
    f: &mut F,
    bearings: &[Bearing],
    rng: &mut XorShiftRng,
) -> Result<Solution, Error> {
    let mut cloud = Box::new(ParticleSet::<PARTICLES, 2>::new());
    initial_particles(bearings, MIN_CROSSING, &mut cloud, rng)?;
    f.initialise(&cloud.states, rng)?;
    for b in bearings {
        let _ = f.step(b, rng);
    }
    let e = f.estimate();
    if !e
        .mean
        .iter()
        .chain(e.covariance.iter().flatten())
        .all(|v| v.is_finite())
    {
        return Err(Error::NonFinite);
    }
    Ok(Solution {
        position: e.mean,
        covariance: e.covariance,
        outliers: 0,
        cloud: Vec::new(),
    })
}

/// Solve with `method` on bearings whose sigma is already set.
pub fn solve(method: LocateMethod, bearings: &[Bearing], seed: u64) -> Result<Solution, Error> {
    let mut rng = XorShiftRng::seed_from_u64(seed);
    let batch = |f: foxhunt_core::Fix| Solution {
        position: f.position,
        covariance: f.covariance,
        outliers: f.outliers,
        cloud: Vec::new(),
    };
    let model = StaticEmitter { process_var: 0.0 };
    match method {
        LocateMethod::Ml => ml(bearings, None, &Huber::default(), MlOptions::default()).map(batch),
        LocateMethod::MlGauss => ml(bearings, None, &Gaussian, MlOptions::default()).map(batch),
        LocateMethod::Sir => {
            let lik = GaussianUniform { eps: 0.05 };
            let mut f = Box::new(Sir::<_, _, PARTICLES, 2>::new(
                model,
                lik,
                SirConfig::default(),
            ));
            let mut s = filter_solution(&mut *f, bearings, &mut rng)?;
            s.cloud = f.particles().states.to_vec();
            Ok(s)
        }
        LocateMethod::Gpf => {
            let mut f = Box::new(Gpf::<_, _, PARTICLES, 2>::new(model, Gaussian));
            filter_solution(&mut *f, bearings, &mut rng)
        }
        LocateMethod::Ekf => filter_solution(&mut BearingEkf::new(0.0), bearings, &mut rng),
        LocateMethod::Afsa => {
            let mut f = Box::new(Sir::<_, _, PARTICLES, 2, Afsa>::with_swarm(
                model,
                Gaussian,
                SirConfig::default(),
                Afsa::default(),
            ));
            let mut s = filter_solution(&mut *f, bearings, &mut rng)?;
            s.cloud = f.particles().states.to_vec();
            Ok(s)
        }
    }
}

/// Locate the emitter of a decoded capture. `sigma_deg`: the DF unit's bearing noise, or
/// `None` to estimate it.
pub fn locate(
    d: &Decoded,
    method: LocateMethod,
    sigma_deg: Option<f32>,
    seed: u64,
) -> Result<(LocateReport, Solution), String> {
    let frame = d.frame.ok_or(
        "no GPS fix in the capture: bearings cannot be placed without the vehicle's position",
    )?;
    if d.bearings.is_empty() {
        return Err(
            if d.bridge.no_fix + d.bridge.stale_fix + d.bridge.low_quality > 0 {
                format!(
                    "no usable bearing: {} without a GPS fix near their time, {} below the quality gate",
                    d.bridge.no_fix + d.bridge.stale_fix,
                    d.bridge.low_quality
                )
            } else {
                "no bearing ($PFOXB) sentence in the capture".into()
            },
        );
    }
    let (sigma, estimated) = match sigma_deg {
        Some(s) if s.is_finite() && s > 0.0 => (s.to_radians(), false),
        Some(s) => return Err(format!("--sigma-deg must be a positive number, not {s}")),
        None => {
            // Two passes of the robust ML: the first with a nominal 1 degree, the second with
            // the noise its residuals show.
            let first = with_sigma(&d.bearings, 1.0f32.to_radians());
            let f = ml(&first, None, &Huber::default(), MlOptions::default())
                .map_err(|e| explain(e, d))?;
            (estimate_sigma(&first, &f.position), true)
        }
    };
    let bearings = with_sigma(&d.bearings, sigma);
    let s = solve(method, &bearings, seed).map_err(|e| explain(e, d))?;
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
        method,
        sigma_deg: sigma.to_degrees(),
        sigma_estimated: estimated,
        used: bearings.len() as u32,
        rejected: rejections(d, s.outliers),
    };
    Ok((report, s))
}

/// The emitter point, the ellipse polygon, the track and the bearing lines as GeoJSON
/// (RFC 7946: longitude first; polygons closed).
pub fn geojson(r: &LocateReport, s: &Solution, d: &Decoded) -> serde_json::Value {
    use serde_json::json;
    let Some(frame) = d.frame else {
        return json!({"type": "FeatureCollection", "features": []});
    };
    let ll = |e: f32, n: f32| -> [f64; 2] {
        let p = frame
            .to_geodetic([f64::from(e), f64::from(n)])
            .unwrap_or(LatLon { lat: 0.0, lon: 0.0 });
        [p.lon, p.lat]
    };
    let e = Ellipse::from_covariance(&s.covariance, 0.95).ok();
    let mut ring: Vec<[f64; 2]> = Vec::new();
    if let Some(e) = e {
        let (c, si) = (e.orientation.cos(), e.orientation.sin());
        for k in 0..=72 {
            let t = k as f32 * std::f32::consts::TAU / 72.0;
            let (a, b) = (e.major * t.cos(), e.minor * t.sin());
            ring.push(ll(
                s.position[0] + a * c - b * si,
                s.position[1] + a * si + b * c,
            ));
        }
        ring[72] = ring[0];
    }
    let track: Vec<[f64; 2]> = d
        .track
        .iter()
        .map(|f| [f.position.lon, f.position.lat])
        .collect();
    let reach = 1.5 * (s.position[0].hypot(s.position[1]) + 1.0);
    let mut features = vec![
        json!({"type": "Feature", "properties": {"kind": "emitter", "method": r.method,
            "cep50_m": r.cep50_m, "crlb_m": r.crlb_m},
            "geometry": {"type": "Point", "coordinates": [r.lon, r.lat]}}),
        json!({"type": "Feature", "properties": {"kind": "track"},
            "geometry": {"type": "LineString", "coordinates": track}}),
    ];
    if !ring.is_empty() {
        features.push(
            json!({"type": "Feature", "properties": {"kind": "ellipse", "confidence": 0.95},
            "geometry": {"type": "Polygon", "coordinates": [ring]}}),
        );
    }
    for b in &d.bearings {
        let end = [
            b.vehicle[0] + reach * b.theta.cos(),
            b.vehicle[1] + reach * b.theta.sin(),
        ];
        features.push(json!({"type": "Feature", "properties": {"kind": "bearing"},
            "geometry": {"type": "LineString", "coordinates": [ll(b.vehicle[0], b.vehicle[1]), ll(end[0], end[1])]}}));
    }
    json!({"type": "FeatureCollection", "features": features})
}
