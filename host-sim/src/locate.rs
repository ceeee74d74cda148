//! `foxhunt locate`: every emitter of a drive, with honest uncertainty.
//!
//! The default estimator, `ml-robust`, is the core's field pipeline
//! ([`foxhunt_core::fix::locate`]): bearings grouped into channels by frequency; in each, the
//! point most bearings agree on (a robust search, then a redescending and trimmed ML over the
//! position and the DF unit's mounting offset), its consistency checked (pure noise is "no
//! consistent emitter", not a fix), its ellipse scaled for an estimated noise and correlated
//! bearings; bearings that agree on another point (a reflection, a second transmitter) come
//! out as other sources. Any other estimator of the registry can be asked for by name: it
//! gives one emitter from all bearings, with the bearing noise estimated from its residuals
//! unless given, and no offset.

use crate::capture::Decoded;
use crate::guidance::guide::{Guide, LocatedAdvice};
use crate::runs::{Pipeline, locate_bearings, pipeline, with_estimated_noise};
use crate::unit::UnitReport;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::bias::{BiasPrior, MAX_SOURCES};
use foxhunt_core::fix::consistency::check_cloud;
use foxhunt_core::fix::crlb::crlb;
use foxhunt_core::fix::ellipse::{Ellipse, cep50};
use foxhunt_core::fix::locate::{ChannelOutcome, LocateConfig, NoEmitter, NoiseModel, Source};
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
    /// Seed of the particle methods and of the robust search.
    pub seed: u64,
    /// The DF unit's offset, as a calibration measured it (`None`: unknown, estimated with
    /// the default prior).
    pub offset: Option<BiasPrior>,
    /// Bearings within this many MHz share a channel.
    pub channel_width_mhz: f32,
}

impl Default for LocateOptions {
    fn default() -> Self {
        Self {
            method: Method::MlRobust,
            particles: PARTICLES,
            sigma_deg: None,
            seed: 1,
            offset: None,
            channel_width_mhz: LocateConfig::default().channel_width_mhz,
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
        if !(self.channel_width_mhz >= 0.0 && self.channel_width_mhz.is_finite()) {
            return Err(format!(
                "--channel-width-mhz must be a finite number >= 0, not {}",
                self.channel_width_mhz
            ));
        }
        Ok(())
    }

    /// The pipeline's settings for these options.
    pub fn config(&self) -> LocateConfig {
        let mut c = LocateConfig {
            channel_width_mhz: self.channel_width_mhz,
            ..LocateConfig::default()
        };
        if self.sigma_deg.is_some() {
            c.noise = NoiseModel::Known;
        }
        if let Some(p) = self.offset {
            c.priors = [p; MAX_SOURCES];
        }
        c
    }
}

/// An ellipse in a report: semi-axes and the major axis' direction.
#[derive(Debug, Clone, Copy, Serialize)]
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

impl From<&Ellipse> for EllipseReport {
    fn from(e: &Ellipse) -> Self {
        Self {
            major_m: e.major,
            minor_m: e.minor,
            orientation_deg: (90.0 - e.orientation.to_degrees()).rem_euclid(180.0),
            confidence: e.confidence,
        }
    }
}

/// A latitude and longitude in a report.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct LatLonReport {
    /// Degrees.
    pub lat: f64,
    /// Degrees.
    pub lon: f64,
}

/// A located source: an emitter, or another point some bearings agree on (field names are
/// stable).
#[derive(Debug, Clone, Serialize)]
pub struct SourceReport {
    /// The channel's frequency, MHz (null for bearings without one).
    pub freq_mhz: Option<f32>,
    /// Latitude, degrees.
    pub lat: f64,
    /// Longitude, degrees.
    pub lon: f64,
    /// East of the local origin, metres.
    pub east_m: f32,
    /// North of the local origin, metres.
    pub north_m: f32,
    /// The confidence ellipse.
    pub ellipse: EllipseReport,
    /// Circular error probable (50 %), metres.
    pub cep50_m: f32,
    /// The bound at the fix, metres: the bias-aware CRLB (offset estimated) for `ml-robust`,
    /// the plain CRLB of the geometry otherwise.
    pub crlb_m: f32,
    /// The DF unit's mounting offset estimated with the fix, degrees (null: not estimated).
    pub bias_deg: Option<f32>,
    /// Its standard deviation, degrees.
    pub bias_sd_deg: Option<f32>,
    /// Bearing noise used, degrees.
    pub sigma_deg: f32,
    /// Whether `sigma_deg` was estimated from the residuals.
    pub sigma_estimated: bool,
    /// Bearings used.
    pub used: u32,
    /// Their effective number (correlated bearings count less; null: not estimated).
    pub effective: Option<f32>,
    /// Whether the residuals agree with the noise model (null: the method does not check).
    pub consistent: Option<bool>,
    /// Seconds of the first and last bearing used, from the first bearing of the capture.
    pub time_span_s: Option<[f32; 2]>,
    /// Why an other source is not the emitter (other sources only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<&'static str>,
}

/// One channel and what it came to.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelSummary {
    /// Frequency, MHz (null for bearings without one).
    pub freq_mhz: Option<f32>,
    /// Bearings in the channel.
    pub bearings: u32,
    /// `emitter`, or why there is none.
    pub outcome: String,
}

/// What `locate` found (the `--json` object; field names are stable).
#[derive(Debug, Clone, Serialize)]
pub struct LocateReport {
    /// The estimator (the registry's name).
    pub method: &'static str,
    /// One emitter per channel that has one.
    pub emitters: Vec<SourceReport>,
    /// Other points bearings agree on (reflections, second transmitters on a channel).
    pub other_sources: Vec<SourceReport>,
    /// Every channel and its outcome.
    pub channels: Vec<ChannelSummary>,
    /// Bearings decoded.
    pub used: u32,
    /// Measurements and frames rejected, by reason.
    pub rejected: BTreeMap<&'static str, u32>,
    /// The local frame's origin (the first vehicle fix; without one, the unit's fix).
    pub origin: LatLonReport,
    /// Where to drive next and whether to stop, for every emitter (absent until a
    /// [`crate::guidance::guide::Guide`] has advised).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub advice: Option<LocatedAdvice>,
    /// Why there is no advice, when guidance was asked and gave none.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub advice_error: Option<String>,
    /// What a DF unit running foxhunt's firmware said about its own fix, when the capture
    /// holds its sentences.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unit: Option<UnitReport>,
}

/// A source as the maps draw it, in local metres.
#[derive(Debug, Clone, Copy)]
pub struct Drawn {
    /// Position.
    pub position: [f32; 2],
    /// Its ellipse.
    pub ellipse: Ellipse,
    /// An other source, not an emitter.
    pub other: bool,
}

/// A fix: the report and what the maps draw.
#[derive(Debug, Clone)]
pub struct Located {
    /// The report.
    pub report: LocateReport,
    /// Every source, emitters first.
    pub drawn: Vec<Drawn>,
    /// The method's particles (empty for batch fixes, the EKF and the pipeline).
    pub cloud: Vec<[f32; 2]>,
    /// The field pipeline's emitters (in the report's order), which guidance starts from
    /// (empty for the other methods: the stop rule wants a fix whose consistency and
    /// independent bearings were checked).
    pub emitters: Vec<Source>,
}

/// Rejections by reason, every reason listed (zero included) so scripts can rely on the keys.
fn rejections(d: &Decoded) -> BTreeMap<&'static str, u32> {
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
        ("late", b.late),
        ("turning", b.turning),
        ("outlier", 0),
        ("repeated", 0),
        ("time_backwards", 0),
        ("no_consistent_emitter", 0),
    ])
}

/// No fix yet, as a live update reports it (`--json`: `used`, `error` and the advice made from
/// the bearings alone).
#[derive(Debug, Clone, Serialize)]
pub struct NoFix {
    /// Bearings decoded.
    pub used: u32,
    /// Why there is no fix.
    pub error: String,
    /// Where to drive (across the line of bearing) before there is a fix.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub advice: Option<LocatedAdvice>,
    /// Why there is no advice either.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub advice_error: Option<String>,
    /// What a DF unit running foxhunt's firmware said, as in [`LocateReport::unit`].
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unit: Option<UnitReport>,
}

impl NoFix {
    /// One line for a live update.
    pub fn line(&self) -> String {
        format!(
            "{} bearings: no fix yet: {}{}{}",
            self.used,
            self.error,
            advice_suffix(self.advice.as_ref(), self.advice_error.as_deref()),
            unit_suffix(self.unit.as_ref())
        )
    }
}

/// `; DF unit (...): ...` for a one-line update, when a DF unit spoke.
fn unit_suffix(u: Option<&UnitReport>) -> String {
    u.map(|u| format!("; {}", u.line())).unwrap_or_default()
}

/// `; ADVICE` (or `; no advice: WHY`) for a one-line update.
fn advice_suffix(advice: Option<&LocatedAdvice>, error: Option<&str>) -> String {
    match (advice, error) {
        (Some(a), _) => format!("; {}", a.line),
        (None, Some(e)) => format!("; no advice: {e}"),
        (None, None) => String::new(),
    }
}

/// Locate every emitter of `d`, and advise through `guide`: from every emitter of the field
/// pipeline, or, with no fix yet, from the bearings alone. The one place where the
/// final report and the live updates get their advice.
pub fn locate_guided(
    d: &Decoded,
    o: &LocateOptions,
    guide: &mut Guide,
) -> Result<Located, Box<NoFix>> {
    match locate(d, o) {
        Ok(mut l) => {
            let advice = match (l.emitters.is_empty(), o.method) {
                (false, _) | (true, Method::MlRobust) => guide.located(d, &l.emitters, o),
                (true, m) => Err(format!(
                    "the stop rule wants a fix whose consistency and independent bearings are                      checked (--method ml-robust, not {})",
                    m.name()
                )),
            };
            match advice {
                Ok(a) => l.report.advice = Some(a),
                Err(e) => l.report.advice_error = Some(e),
            }
            Ok(l)
        }
        Err(error) => {
            let advice = guide.located(d, &[], o);
            Err(Box::new(NoFix {
                used: d.observations.len() as u32,
                error,
                advice_error: advice.as_ref().err().cloned(),
                advice: advice.ok(),
                unit: d.unit.report(),
            }))
        }
    }
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
    reason(b.late, "older than the GPS fixes kept");
    reason(
        b.turning,
        "taken while the vehicle turned faster than the yaw-rate gate",
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

/// Why the bearings give no fix, in words a user can act on.
pub fn explain(e: Error, bearings: &[Bearing]) -> String {
    match e {
        Error::TooFewMeasurements if bearings.len() == 1 => {
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
        _ if points_away(bearings) => "the bearings point away from where their lines cross \
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

/// Why a channel of `n` bearings has no consistent emitter, in words.
fn no_emitter(why: NoEmitter, n: u32, bearings: &[Bearing]) -> String {
    match why {
        NoEmitter::TooFew if n <= 1 => {
            explain(Error::TooFewMeasurements, bearings.get(..1).unwrap_or(&[]))
        }
        NoEmitter::NoConsensus => "no consistent emitter: no point has more bearings agreeing \
             than chance would give (noise, or bearings of nothing)"
            .into(),
        NoEmitter::TooNoisy => {
            "no consistent emitter: the bearings scatter by more than 10 degrees about any point"
                .into()
        }
        NoEmitter::TooFew => format!(
            "no consistent emitter: {n} bearings are too few to estimate their noise and check \
             the fit (at least 5 that cross well)"
        ),
        NoEmitter::Geometry(e) => format!("no consistent emitter: {}", explain(e, bearings)),
    }
}

/// The geodetic position of local metres `p` in `frame` (the origin when out of range).
pub fn geodetic(frame: &LocalFrame, p: [f32; 2]) -> LatLon {
    frame
        .to_geodetic([f64::from(p[0]), f64::from(p[1])])
        .unwrap_or(frame.origin)
}

/// Locate every emitter of a decoded capture.
pub fn locate(d: &Decoded, o: &LocateOptions) -> Result<Located, String> {
    o.check()?;
    let unit = d.unit.report();
    if d.observations.is_empty()
        && let Some(u) = unit
            .clone()
            .filter(|u| u.lat.is_some() || d.frame.is_none())
    {
        return Ok(unit_only(d, o, u));
    }
    let Some(frame) = d.frame else {
        return Err(no_vehicle_position(d));
    };
    if d.observations.is_empty() {
        return Err(no_bearing(d));
    }
    let mut rejected = rejections(d);
    let (emitters, other_sources, channels, drawn, cloud, sources) = if o.method == Method::MlRobust
    {
        located_by_pipeline(d, o, &frame, &mut rejected)?
    } else {
        located_by(d, o, &frame, &mut rejected)?
    };
    Ok(Located {
        report: LocateReport {
            method: o.method.name(),
            emitters,
            other_sources,
            channels,
            used: d.observations.len() as u32,
            rejected,
            origin: LatLonReport {
                lat: frame.origin.lat,
                lon: frame.origin.lon,
            },
            advice: None,
            advice_error: None,
            unit,
        },
        drawn,
        cloud,
        emitters: sources,
    })
}

/// A capture of a DF unit's own output (its user port): the unit's fix is the report.
fn unit_only(d: &Decoded, o: &LocateOptions, u: UnitReport) -> Located {
    let origin = match (d.frame, u.lat, u.lon) {
        (Some(f), _, _) => LatLonReport {
            lat: f.origin.lat,
            lon: f.origin.lon,
        },
        (None, lat, lon) => LatLonReport {
            lat: lat.unwrap_or(0.0),
            lon: lon.unwrap_or(0.0),
        },
    };
    Located {
        report: LocateReport {
            method: o.method.name(),
            emitters: Vec::new(),
            other_sources: Vec::new(),
            channels: Vec::new(),
            used: 0,
            rejected: rejections(d),
            origin,
            unit: Some(u),
            advice: None,
            advice_error: None,
        },
        drawn: Vec::new(),
        cloud: Vec::new(),
        emitters: Vec::new(),
    }
}

/// What one locate path gives: emitters, other sources, channels, drawn sources, particles,
/// the pipeline's emitters.
type Parts = (
    Vec<SourceReport>,
    Vec<SourceReport>,
    Vec<ChannelSummary>,
    Vec<Drawn>,
    Vec<[f32; 2]>,
    Vec<Source>,
);

/// A pipeline source as the report has it.
fn source_report(s: &Source, frame: &LocalFrame, why: Option<&'static str>) -> SourceReport {
    let g = geodetic(frame, s.position);
    SourceReport {
        freq_mhz: s.freq_mhz,
        lat: g.lat,
        lon: g.lon,
        east_m: s.position[0],
        north_m: s.position[1],
        ellipse: EllipseReport::from(&s.ellipse),
        cep50_m: s.cep50,
        crlb_m: s.crlb,
        bias_deg: Some(s.bias.to_degrees()),
        bias_sd_deg: Some(s.bias_sd.to_degrees()),
        sigma_deg: s.sigma.to_degrees(),
        sigma_estimated: s.sigma_estimated,
        used: s.used,
        effective: Some(s.effective),
        consistent: Some(s.consistent),
        time_span_s: Some(s.time_span),
        why,
    }
}

fn located_by_pipeline(
    d: &Decoded,
    o: &LocateOptions,
    frame: &LocalFrame,
    rejected: &mut BTreeMap<&'static str, u32>,
) -> Result<Parts, String> {
    // A copy only when the user's noise replaces the bearings' own: a long capture's
    // observations are most of the memory.
    let obs: std::borrow::Cow<'_, [_]> = match o.sigma_deg {
        None => std::borrow::Cow::Borrowed(&d.observations),
        Some(s) => std::borrow::Cow::Owned(
            d.observations
                .iter()
                .map(|x| {
                    let mut x = *x;
                    x.bearing.sigma = s.to_radians();
                    x
                })
                .collect(),
        ),
    };
    // The bearings alone, for the words of an error.
    let bearings = || -> Vec<Bearing> { obs.iter().map(|x| x.bearing).collect() };
    let r: Pipeline = crate::montecarlo::pool()
        .install(|| pipeline(&obs, &o.config(), o.seed))
        .map_err(|e| explain(e, &bearings()))?;
    let rj = &r.rejected;
    for (k, v) in [
        ("outlier", rj.outliers),
        ("repeated", rj.repeated),
        ("time_backwards", rj.time_backwards),
        ("no_consistent_emitter", rj.no_emitter),
    ] {
        rejected.insert(k, v);
    }
    let malformed = rejected.get("malformed").copied().unwrap_or(0);
    rejected.insert("malformed", malformed + rj.invalid);
    let mut channels = Vec::new();
    let mut why_none = None;
    for c in r.channels() {
        let outcome = match c.outcome {
            ChannelOutcome::Emitter(_) => "emitter".to_string(),
            ChannelOutcome::NoConsistentEmitter(why) => {
                // A vehicle that never moved, or bearings that never cross, say so plainly.
                let bearings = bearings();
                let geometry = match foxhunt_core::fix::ple::ple(&bearings) {
                    Err(e @ (Error::StationaryVehicle | Error::ParallelBearings)) => {
                        Some(explain(e, &bearings))
                    }
                    _ => None,
                };
                let text = geometry.unwrap_or_else(|| no_emitter(why, c.bearings, &bearings));
                why_none.get_or_insert(text.clone());
                text
            }
        };
        channels.push(ChannelSummary {
            freq_mhz: c.freq_mhz,
            bearings: c.bearings,
            outcome,
        });
    }
    if r.emitters().is_empty() {
        return Err(why_none.unwrap_or_else(|| "no consistent emitter".into()));
    }
    const WEAKER: &str = "fewer bearings agree on it than on its channel's emitter: a \
                          reflection, or a second transmitter on the channel";
    let emitters = r
        .emitters()
        .iter()
        .map(|s| source_report(s, frame, None))
        .collect();
    let others = r
        .others()
        .iter()
        .map(|s| source_report(&s.source, frame, Some(WEAKER)))
        .collect();
    let drawn = r
        .emitters()
        .iter()
        .map(|s| (s, false))
        .chain(r.others().iter().map(|s| (&s.source, true)))
        .map(|(s, other)| Drawn {
            position: s.position,
            ellipse: s.ellipse,
            other,
        })
        .collect();
    Ok((
        emitters,
        others,
        channels,
        drawn,
        Vec::new(),
        r.emitters().to_vec(),
    ))
}

fn located_by(
    d: &Decoded,
    o: &LocateOptions,
    frame: &LocalFrame,
    rejected: &mut BTreeMap<&'static str, u32>,
) -> Result<Parts, String> {
    let mut rng = XorShiftRng::seed_from_u64(o.seed);
    let (s, sigma, estimated) = match o.sigma_deg {
        Some(deg) => {
            let bearings = d.bearings_with_sigma(deg.to_radians());
            let fix = crate::montecarlo::pool().install(|| {
                locate_bearings(
                    o.method,
                    o.particles,
                    SEEDS_JITTER_M2,
                    &bearings,
                    true,
                    &mut rng,
                )
            });
            (fix, deg.to_radians(), false)
        }
        None => {
            let bearings = d.bearings_with_sigma(1.0f32.to_radians());
            let r = crate::montecarlo::pool().install(|| {
                with_estimated_noise(
                    o.method,
                    o.particles,
                    SEEDS_JITTER_M2,
                    &bearings,
                    true,
                    &mut rng,
                )
            });
            match r {
                Ok((fix, sigma)) => (Ok(fix), sigma, true),
                Err(e) => (Err(e), 1.0f32.to_radians(), true),
            }
        }
    };
    let bearings = d.bearings_with_sigma(sigma);
    let s = s.map_err(|e| explain(e, &bearings))?;
    let ellipse =
        Ellipse::from_covariance(&s.covariance, 0.95).map_err(|e| explain(e, &bearings))?;
    let cep = cep50(&s.covariance).map_err(|e| explain(e, &bearings))?;
    let bound = crlb(&s.position, &bearings).map_err(|e| explain(e, &bearings))?;
    rejected.insert("outlier", s.outliers);
    // A particle cloud far tighter than the bearings allow is no estimate of the uncertainty.
    let consistent = (!s.cloud.is_empty())
        .then(|| check_cloud_points(&s.cloud, &bearings))
        .flatten();
    let g = geodetic(frame, s.position);
    let freq = d.observations.first().and_then(|x| x.freq_mhz);
    let report = SourceReport {
        freq_mhz: freq,
        lat: g.lat,
        lon: g.lon,
        east_m: s.position[0],
        north_m: s.position[1],
        ellipse: EllipseReport::from(&ellipse),
        cep50_m: cep,
        crlb_m: bound.rmse,
        bias_deg: None,
        bias_sd_deg: None,
        sigma_deg: sigma.to_degrees(),
        sigma_estimated: estimated,
        used: bearings.len() as u32,
        effective: None,
        consistent,
        time_span_s: None,
        why: None,
    };
    let channel = ChannelSummary {
        freq_mhz: freq,
        bearings: bearings.len() as u32,
        outcome: "emitter".into(),
    };
    let drawn = vec![Drawn {
        position: s.position,
        ellipse,
        other: false,
    }];
    Ok((
        vec![report],
        Vec::new(),
        vec![channel],
        drawn,
        s.cloud,
        Vec::new(),
    ))
}

/// Whether a particle cloud is as wide as the bearings allow (`Some(false)`: collapsed).
fn check_cloud_points(cloud: &[[f32; 2]], bearings: &[Bearing]) -> Option<bool> {
    foxhunt_core::with_particles!(cloud.len(), N => {
        let mut set = Box::new(foxhunt_core::ParticleSet::<N, 2>::new());
        for (s, p) in set.states.iter_mut().zip(cloud) {
            *s = *p;
        }
        check_cloud(&set, bearings).map(|c| !c.collapsed)
    })
    .ok()
}

impl SourceReport {
    fn lines(&self, label: &str, out: &mut String) {
        let freq = self
            .freq_mhz
            .map(|f| format!(" ({f:.3} MHz)"))
            .unwrap_or_default();
        let _ = writeln!(
            out,
            "{label}{freq}  {:.6}, {:.6}  ({:.1} m east, {:.1} m north)",
            self.lat, self.lon, self.east_m, self.north_m
        );
        let _ = writeln!(
            out,
            "  {:.0} % ellipse semi-axes {:.1} m and {:.1} m, major axis {:.0} deg from north; CEP50 {:.1} m; bound {:.1} m",
            100.0 * self.ellipse.confidence,
            self.ellipse.major_m,
            self.ellipse.minor_m,
            self.ellipse.orientation_deg,
            self.cep50_m,
            self.crlb_m
        );
        let offset = match (self.bias_deg, self.bias_sd_deg) {
            (Some(b), Some(sd)) => format!("offset {b:.2} +- {sd:.2} deg; "),
            _ => String::new(),
        };
        let effective = self
            .effective
            .map(|e| format!(" ({e:.1} effective)"))
            .unwrap_or_default();
        let consistent = match self.consistent {
            Some(true) => "; residuals consistent",
            Some(false) => "; NOT consistent: the uncertainty is understated",
            None => "",
        };
        let _ = writeln!(
            out,
            "  {offset}noise {:.2} deg ({}); {} bearings{effective}{consistent}",
            self.sigma_deg,
            if self.sigma_estimated {
                "estimated"
            } else {
                "given"
            },
            self.used,
        );
        if let Some(why) = self.why {
            let _ = writeln!(out, "  {why}");
        }
    }
}

impl LocateReport {
    /// The report as the terminal shows it.
    pub fn text(&self) -> String {
        let mut out = String::new();
        for (i, e) in self.emitters.iter().enumerate() {
            let label = if self.emitters.len() > 1 {
                format!("emitter {}", i + 1)
            } else {
                "emitter".to_string()
            };
            e.lines(&label, &mut out);
        }
        for o in &self.other_sources {
            o.lines("other source", &mut out);
        }
        for c in self.channels.iter().filter(|c| c.outcome != "emitter") {
            let freq = c
                .freq_mhz
                .map(|f| format!("{f:.3} MHz"))
                .unwrap_or_else(|| "bearings without a frequency".into());
            let _ = writeln!(
                out,
                "channel {freq} ({} bearings): {}",
                c.bearings, c.outcome
            );
        }
        match (&self.advice, &self.advice_error) {
            (Some(a), _) => {
                let _ = writeln!(out, "advice: {}", a.line);
            }
            (None, Some(e)) => {
                let _ = writeln!(out, "no advice: {e}");
            }
            (None, None) => {}
        }
        if let Some(u) = &self.unit {
            let _ = writeln!(out, "{}", u.line());
        }
        let rejected: Vec<String> = self
            .rejected
            .iter()
            .filter(|(_, n)| **n > 0)
            .map(|(k, n)| format!("{k} {n}"))
            .collect();
        let _ = writeln!(
            out,
            "method {}; {} bearings; origin {:.6}, {:.6}; rejected: {}",
            self.method,
            self.used,
            self.origin.lat,
            self.origin.lon,
            if rejected.is_empty() {
                "none".to_string()
            } else {
                rejected.join(", ")
            }
        );
        out
    }

    /// One line for a live update (several emitters: numbered as the advice names them).
    pub fn update_line(&self) -> String {
        let several = self.emitters.len() > 1;
        let fixes: Vec<String> = self
            .emitters
            .iter()
            .enumerate()
            .map(|(i, e)| {
                format!(
                    "{}{:.6}, {:.6} CEP50 {:.1} m (bound {:.1} m)",
                    if several {
                        format!("emitter {} ", i + 1)
                    } else {
                        String::new()
                    },
                    e.lat,
                    e.lon,
                    e.cep50_m,
                    e.crlb_m
                )
            })
            .collect();
        format!(
            "{} bearings: {}{}{}",
            self.used,
            if fixes.is_empty() {
                "no emitter".to_string()
            } else {
                fixes.join("; ")
            },
            advice_suffix(self.advice.as_ref(), self.advice_error.as_deref()),
            unit_suffix(self.unit.as_ref())
        )
    }
}
