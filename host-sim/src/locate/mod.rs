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

pub mod advice;
pub mod explain;
mod method;
pub(crate) mod pipeline;
pub mod report;
pub mod stations;

pub use crate::estimate::options::LocateOptions;
use crate::estimate::stations::station_setup;
use crate::guidance::guide::Guide;
use crate::inputs::capture::Decoded;
use crate::inputs::unit::UnitReport;
use advice::located_advice;
use explain::{no_bearing, no_vehicle_position};
use foxhunt_core::Method;
use foxhunt_core::fix::locate::Source;
use report::{
    AcrossReport, ChannelSummary, Drawn, LatLonReport, LocateReport, Located, NoFix, RegionReport,
    SourceReport, geodetic, rejections,
};
use stations::{Found, station_reports};

/// Why there is no fix, and, when the field pipeline's channels hold regions (an open range),
/// the report without a fix that the maps and the live page draw them from.
#[derive(Debug, Clone)]
pub struct Unlocated {
    /// Why there is no fix, in words.
    pub error: String,
    /// The report of the channels (no emitter, a region in at least one).
    pub located: Option<Box<Located>>,
    /// Why, as a code ([`ChannelSummary::reason`]), when the field pipeline ran.
    pub reason: Option<&'static str>,
    /// Every channel, when the field pipeline ran and no channel has a region.
    pub channels: Vec<ChannelSummary>,
}

impl From<String> for Unlocated {
    fn from(error: String) -> Self {
        Self {
            error,
            located: None,
            reason: None,
            channels: Vec::new(),
        }
    }
}

/// Locate every emitter of a decoded capture.
pub fn locate(d: &Decoded, o: &LocateOptions) -> Result<Located, String> {
    locate_answer(d, o).map_err(|u| u.error)
}

/// Locate every emitter of a decoded capture; no fix but regions (open ranges) is an error
/// that keeps them.
pub fn locate_answer(d: &Decoded, o: &LocateOptions) -> Result<Located, Unlocated> {
    o.check()?;
    let unit = d.unit.report();
    // The unit's own fix is the report of a capture of its output, when it has one.
    if d.observations.is_empty()
        && let Some(u) = unit.clone().filter(|u| u.lat.is_some())
    {
        return Ok(unit_only(d, o, u));
    }
    let Some(frame) = d.frame else {
        return Err(no_vehicle_position(d).into());
    };
    if d.observations.is_empty() {
        return Err(no_bearing(d).into());
    }
    let mut rejected = rejections(d);
    let ((emitters, other_sources, channels, drawn, cloud, sources), stations) = if o.method
        == Method::MlRobust
    {
        pipeline::located_by_pipeline(d, o, &frame, &mut rejected)?
    } else {
        let setup = station_setup(
            d.stations.iter().map(|s| s.id.as_str()),
            o.network.as_deref(),
            o.offset.unwrap_or_default(),
            o.offset.is_some(),
        );
        let stations = station_reports(d, o.network.as_deref(), &setup, Found::default(), &[], &[]);
        (method::located_by(d, o, &frame, &mut rejected)?, stations)
    };
    let located = Located {
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
            stations,
        },
        drawn,
        cloud,
        emitters: sources,
    };
    // Regions but no emitter: no fix, the regions kept for the report.
    let open = located
        .report
        .channels
        .iter()
        .find(|c| c.region.is_some())
        .map(|c| c.outcome.clone());
    match open {
        Some(error) if located.report.emitters.is_empty() => Err(Unlocated {
            error,
            located: Some(Box::new(located)),
            reason: Some("open_range"),
            channels: Vec::new(),
        }),
        _ => Ok(located),
    }
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
            stations: Vec::new(),
        },
        drawn: Vec::new(),
        cloud: Vec::new(),
        emitters: Vec::new(),
    }
}

/// A leg across a region's line of bearing from the vehicle's last position (none before a
/// GPS fix).
fn across_region(d: &Decoded, r: &RegionReport) -> Option<AcrossReport> {
    use crate::guidance::across::{LineOfBearing, across};
    let frame = d.frame?;
    let bearings: Vec<foxhunt_core::Bearing> = d.bearings().copied().collect();
    let vehicle = bearings.last()?.vehicle;
    let heading = crate::guidance::track_heading(&bearings)
        .map(|h| foxhunt_core::model::bearing::theta_to_azimuth(h).to_degrees());
    let line = LineOfBearing {
        bearing_deg: r.bearing_deg,
        half_width_deg: r.half_width_deg,
        min_range_m: r.min_range_m,
    };
    let leg = across(&line, vehicle, heading);
    let g = geodetic(&frame, leg.to);
    Some(AcrossReport {
        leg,
        target: LatLonReport {
            lat: g.lat,
            lon: g.lon,
        },
        line: format!(
            "drive {} heading {:.0} deg, across the line of bearing, to {:.5}, {:.5}: the \
             bearing's turn gives the range",
            explain::distance_words(leg.distance_m),
            leg.heading_deg,
            g.lat,
            g.lon
        ),
    })
}

/// What one locate path gives: emitters, other sources, channels, drawn sources, particles,
/// the pipeline's emitters.
pub(crate) type Parts = (
    Vec<SourceReport>,
    Vec<SourceReport>,
    Vec<ChannelSummary>,
    Vec<Drawn>,
    Vec<[f32; 2]>,
    Vec<Source>,
);

/// Locate every emitter of `d`, and advise through `guide`: from every emitter of the field
/// pipeline, or, with no fix yet, from the bearings alone. The one place where the
/// final report and the live updates get their advice.
pub fn locate_guided(
    d: &Decoded,
    o: &LocateOptions,
    guide: &mut Guide,
) -> Result<Located, Box<NoFix>> {
    match locate_answer(d, o) {
        Ok(mut l) => {
            let advice = match (l.emitters.is_empty(), o.method) {
                (false, _) | (true, Method::MlRobust) => located_advice(guide, d, &l.emitters, o),
                (true, m) => Err(format!(
                    "the stop rule wants a fix whose consistency and independent bearings are \
                     checked (--method ml-robust, not {})",
                    m.name()
                )),
            };
            match advice {
                Ok(a) => l.report.advice = Some(a),
                Err(e) => l.report.advice_error = Some(e),
            }
            Ok(l)
        }
        Err(Unlocated {
            error,
            mut located,
            reason,
            channels: unplaced,
        }) => {
            // An emitter that moves has no still fix to stop on: follow it instead.
            let advice = if reason == Some(explain::MOVING) {
                Err(
                    "the emitter moves: no stop rule for a still fix; follow it with \
                     `foxhunt track`"
                        .to_string(),
                )
            } else {
                located_advice(guide, d, &[], o)
            };
            if let Some(l) = located.as_mut() {
                l.report.advice = advice.as_ref().ok().cloned();
                l.report.advice_error = advice.as_ref().err().cloned();
            }
            let channels = located
                .as_ref()
                .map(|l| l.report.channels.clone())
                .unwrap_or(unplaced);
            let motion = channels
                .iter()
                .find(|c| c.reason == reason)
                .and_then(|c| c.motion);
            let region = channels.iter().find_map(|c| c.region);
            Err(Box::new(NoFix {
                used: d.observations.len() as u32,
                error,
                reason,
                motion,
                across: region.and_then(|r| across_region(d, &r)),
                region,
                channels,
                located,
                advice_error: advice.as_ref().err().cloned(),
                advice: advice.ok(),
                unit: d.unit.report(),
            }))
        }
    }
}
