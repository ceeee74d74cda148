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
mod pipeline;
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
    ChannelSummary, Drawn, LatLonReport, LocateReport, Located, NoFix, SourceReport, rejections,
};
use stations::station_reports;

/// Locate every emitter of a decoded capture.
pub fn locate(d: &Decoded, o: &LocateOptions) -> Result<Located, String> {
    o.check()?;
    let unit = d.unit.report();
    // The unit's own fix is the report of a capture of its output, when it has one.
    if d.observations.is_empty()
        && let Some(u) = unit.clone().filter(|u| u.lat.is_some())
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
    let ((emitters, other_sources, channels, drawn, cloud, sources), stations) =
        if o.method == Method::MlRobust {
            pipeline::located_by_pipeline(d, o, &frame, &mut rejected)?
        } else {
            let setup = station_setup(
                d.stations.iter().map(|s| s.id.as_str()),
                o.network.as_deref(),
                o.offset.unwrap_or_default(),
                o.offset.is_some(),
            );
            let stations = station_reports(d, o.network.as_deref(), &setup, &[], &[], &[]);
            (method::located_by(d, o, &frame, &mut rejected)?, stations)
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
            stations,
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
            stations: Vec::new(),
        },
        drawn: Vec::new(),
        cloud: Vec::new(),
        emitters: Vec::new(),
    }
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
    match locate(d, o) {
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
        Err(error) => {
            let advice = located_advice(guide, d, &[], o);
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
