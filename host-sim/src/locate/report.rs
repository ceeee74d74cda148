//! What `locate` reports (the `--json` object; field names are stable) and what the maps
//! draw, in latitude and longitude and in the drive's local metres.

use crate::guidance::AdviceReport;
use crate::guidance::guide::VerdictReport;
use crate::inputs::capture::Decoded;
use crate::inputs::unit::UnitReport;
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::ellipse::Ellipse;
use foxhunt_core::fix::locate::motion::{MOTION_ALPHA, Motion, SpanFix};
use foxhunt_core::fix::locate::{Region, Source};
use foxhunt_core::model::bearing::theta_to_azimuth;
use serde::Serialize;
use std::collections::BTreeMap;

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
    /// Degrees of freedom of the estimated noise (residuals less unknowns); the ellipse is
    /// then 2 F(2, dof) wide, not chi-square (null: the noise was given).
    pub sigma_dof: Option<f32>,
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
    /// Whether the bearings measured the DF unit's offset (its sd within 3 degrees, by them or
    /// by a calibrated prior); false: the fix holds only while the offset lies within its
    /// prior, which these bearings cannot check (docs/src/field.md, "Past the prior"; null:
    /// the method does not estimate the offset).
    pub offset_measured: Option<bool>,
    /// Present only when the DF unit's offset needs checking (docs/src/field.md, "Past the
    /// prior"): it contradicted its prior and the fix is the one with the offset free, or
    /// another offset far from the fit's is about as likely.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset_check: Option<OffsetCheckReport>,
}

/// A fix whose offset contradicted its prior (field names are stable).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct OffsetCheckReport {
    /// How many of the sds the prior predicts the first fit's offset lay from the prior's
    /// mean.
    pub z: f32,
    /// The prior was relaxed: the fix and its ellipse are the offset-free ones.
    pub relaxed: bool,
    /// Another offset, 30 degrees or more from the fit's, is about as likely: the prior alone
    /// chose this fix.
    pub ambiguous: bool,
}

/// What the bearings of a channel hold when the range is open (no fix): a line of bearing from
/// the observers, its half-width and the range interval (field names are stable;
/// docs/src/field.md, "Regions").
#[derive(Debug, Clone, Copy, Serialize)]
pub struct RegionReport {
    /// The channel's frequency, MHz (null for bearings without one).
    pub freq_mhz: Option<f32>,
    /// The apex (the observers' weighted centroid), latitude, degrees.
    pub lat: f64,
    /// The apex, longitude, degrees.
    pub lon: f64,
    /// The apex, east of the local origin, metres.
    pub east_m: f32,
    /// The apex, north of the local origin, metres.
    pub north_m: f32,
    /// The line of bearing, degrees clockwise from true north.
    pub bearing_deg: f32,
    /// Its half-width at `confidence`, degrees.
    pub half_width_deg: f32,
    /// The nearest range the bearings allow, metres.
    pub min_range_m: f32,
    /// The farthest, metres (null: unbounded).
    pub max_range_m: Option<f32>,
    /// The bearings are parallel (they never cross), not merely crossing too shallowly.
    pub parallel: bool,
    /// Probability inside.
    pub confidence: f32,
    /// Bearing noise used, degrees.
    pub sigma_deg: f32,
    /// Bearings used.
    pub used: u32,
    /// Their effective number.
    pub effective: f32,
}

impl RegionReport {
    /// A field pipeline region in `frame`.
    pub fn of(r: &Region, frame: &LocalFrame) -> Self {
        let g = geodetic(frame, r.apex);
        // 359.99... is north too: 0, not "360.0".
        let b = theta_to_azimuth(r.theta).to_degrees().rem_euclid(360.0);
        Self {
            freq_mhz: r.freq_mhz,
            lat: g.lat,
            lon: g.lon,
            east_m: r.apex[0],
            north_m: r.apex[1],
            bearing_deg: if b >= 359.95 { 0.0 } else { b },
            half_width_deg: r.half_width.to_degrees(),
            min_range_m: r.min_range,
            max_range_m: r.max_range,
            parallel: r.parallel,
            confidence: r.confidence,
            sigma_deg: r.sigma.to_degrees(),
            used: r.used,
            effective: r.effective,
        }
    }
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
    /// What the bearings hold when the range is open (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub region: Option<RegionReport>,
    /// Why there is no emitter, as a code (absent for an emitter): `moving`, `open_range`,
    /// `no_consensus`, `too_noisy`, `too_few`, `geometry`, `offset_beyond_prior`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<&'static str>,
    /// With `moving`: the evidence (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<MotionReport>,
}

/// The evidence that an emitter moves (docs/src/field.md, "An emitter that moves"; field
/// names are stable): where the early and the late bearings meet, how far apart against
/// their uncertainty, and the test.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct MotionReport {
    /// Where the first third of the bearings (in time) meets.
    pub early: SpanReport,
    /// Where the last third meets.
    pub late: SpanReport,
    /// How far apart, metres.
    pub apart_m: f32,
    /// The same in standard deviations of their difference (the stations' offsets counted
    /// once).
    pub apart_sd: f32,
    /// How likely an emitter that stands still gives spans this far apart.
    pub p_value: f32,
    /// The level below which the check says "moving".
    pub false_alarm: f32,
}

/// One span of time's position in the motion check.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SpanReport {
    /// Latitude, degrees.
    pub lat: f64,
    /// Longitude, degrees.
    pub lon: f64,
    /// East of the local origin, metres.
    pub east_m: f32,
    /// North of the local origin, metres.
    pub north_m: f32,
    /// Its 95 % ellipse.
    pub ellipse: Option<EllipseReport>,
    /// Seconds of its first and last bearing.
    pub time_span_s: [f32; 2],
    /// Its bearings.
    pub used: u32,
}

impl MotionReport {
    /// The core's evidence in `frame`.
    pub fn of(m: &Motion, frame: &LocalFrame) -> Self {
        let span = |s: &SpanFix| {
            let g = geodetic(frame, s.position);
            SpanReport {
                lat: g.lat,
                lon: g.lon,
                east_m: s.position[0],
                north_m: s.position[1],
                ellipse: Ellipse::from_covariance(&s.covariance, 0.95)
                    .ok()
                    .map(|e| EllipseReport::from(&e)),
                time_span_s: s.time_span,
                used: s.used,
            }
        };
        Self {
            early: span(&m.early),
            late: span(&m.late),
            apart_m: m.apart_m,
            apart_sd: m.apart_sd,
            p_value: m.p_value,
            false_alarm: MOTION_ALPHA,
        }
    }
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
    /// Every station that handed on bearings: who, where, and its offset with where that
    /// came from (docs/src/networks.md).
    pub stations: Vec<crate::locate::stations::StationReport>,
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

/// No fix yet, as a live update reports it (`--json`: `used`, `error` and the advice made from
/// the bearings alone).
#[derive(Debug, Clone, Serialize)]
pub struct NoFix {
    /// Bearings decoded.
    pub used: u32,
    /// Why there is no fix.
    pub error: String,
    /// Why, as a code (as [`ChannelSummary::reason`]; absent before the field pipeline ran).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reason: Option<&'static str>,
    /// With `moving`: the evidence.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub motion: Option<MotionReport>,
    /// What the bearings hold when the range is open: the first channel's region (absent
    /// when none has one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub region: Option<RegionReport>,
    /// Every channel and what it came to, when the field pipeline got that far (absent
    /// otherwise).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<ChannelSummary>,
    /// With a region: a leg across its line of bearing, to measure the range (absent
    /// otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub across: Option<AcrossReport>,
    /// The report without a fix, for the maps to draw the regions (not in the JSON).
    #[serde(skip)]
    pub located: Option<Box<Located>>,
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

/// Where to drive when the range is open: across the line of bearing
/// ([`crate::guidance::across`]).
#[derive(Debug, Clone, Serialize)]
pub struct AcrossReport {
    /// The leg's heading and length.
    #[serde(flatten)]
    pub leg: crate::guidance::across::Across,
    /// Where it ends.
    pub target: LatLonReport,
    /// The advice in one line.
    pub line: String,
}

/// Rejections by reason, every reason listed (zero included) so scripts can rely on the keys.
pub fn rejections(d: &Decoded) -> BTreeMap<&'static str, u32> {
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
        ("stations_full", b.stations_full),
        ("time_jump", b.time_jump),
        ("outlier", 0),
        ("repeated", 0),
        ("time_backwards", 0),
        ("no_consistent_emitter", 0),
    ])
}

/// The geodetic position of local metres `p` in `frame` (the origin when out of range).
pub fn geodetic(frame: &LocalFrame, p: [f32; 2]) -> LatLon {
    frame
        .to_geodetic([f64::from(p[0]), f64::from(p[1])])
        .unwrap_or(frame.origin)
}

/// The advice as `foxhunt locate` reports it: the advice's fields, the point to drive to and
/// the next turn in latitude and longitude, and the one-line form.
#[derive(Debug, Clone, Serialize)]
pub struct LocatedAdvice {
    /// The advice's fields.
    #[serde(flatten)]
    pub report: AdviceReport,
    /// The point to drive to (the end of the first move).
    pub target: LatLonReport,
    /// Where the next road turn is (on roads).
    pub turn_at: Option<LatLonReport>,
    /// Each emitter's verdict, in the order of the report's emitters (empty before a fix).
    pub emitters: Vec<VerdictReport>,
    /// The emitters the move is for (numbered as the report's emitters, from 1): those not
    /// yet good enough (empty when all are, or before a fix).
    pub for_emitters: Vec<usize>,
    /// The advice in one line.
    pub line: String,
}
