//! `locate` by the field pipeline (`ml-robust`): every channel's emitter and other sources.

use crate::estimate::options::LocateOptions;
use crate::estimate::{Pipeline, pipeline, pool};
use crate::inputs::capture::Decoded;
use crate::locate::Parts;
use crate::locate::explain::{explain, no_emitter};
use crate::locate::report::{ChannelSummary, Drawn, EllipseReport, SourceReport, geodetic};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_core::fix::locate::{ChannelOutcome, Source};
use foxhunt_core::{Bearing, Error};
use std::collections::BTreeMap;

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
        sigma_dof: s.sigma_estimated.then_some(s.dof),
        used: s.used,
        effective: Some(s.effective),
        consistent: Some(s.consistent),
        time_span_s: Some(s.time_span),
        why,
    }
}

pub(crate) fn located_by_pipeline(
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
    let r: Pipeline = pool()
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
                let text = geometry.unwrap_or_else(|| {
                    no_emitter(why, c.bearings, &bearings, o.config().max_sigma)
                });
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
