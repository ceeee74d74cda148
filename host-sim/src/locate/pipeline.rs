//! `locate` by the field pipeline (`ml-robust`): every channel's emitter and other sources.

use crate::estimate::options::LocateOptions;
use crate::estimate::stations::{
    LocalReference, ReferenceFix, StationSetup, calibrate_on_references, station_setup,
};
use crate::estimate::{PipelineRun, pipeline, pool};
use crate::inputs::capture::Decoded;
use crate::inputs::stations::Reference;
use crate::locate::Parts;
use crate::locate::Unlocated;
use crate::locate::explain::{
    explain, no_emitter, open_range, points_away, reason_code, steady_clause, step_deg,
};
use crate::locate::report::{
    ChannelSummary, Drawn, EllipseReport, MotionReport, OffsetCheckReport, RegionReport,
    SourceReport, geodetic,
};
use crate::locate::stations::{Found, StationReport, station_reports};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_core::fix::locate::Observation;
use foxhunt_core::fix::locate::{ChannelOutcome, NoEmitter, Source};
use foxhunt_core::{Bearing, Error};
use std::borrow::Cow;
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
        offset_measured: Some(!s.offset_check.unmeasured),
        offset_check: s.offset_check.doubtful().then_some(OffsetCheckReport {
            z: s.offset_check.z,
            relaxed: s.offset_check.relaxed,
            ambiguous: s.offset_check.ambiguous,
        }),
    }
}

/// The field pipeline's run of a capture as `locate` makes it, and what it was made of.
pub(crate) struct Solved<'a> {
    /// The run.
    pub run: PipelineRun,
    /// Each station's prior and noise, calibrated on the reference transmitters.
    pub setup: StationSetup,
    /// The bearings solved: each with its stated noise, the references' channels out.
    pub obs: Cow<'a, [Observation]>,
    /// Every station's report.
    pub stations: Vec<StationReport>,
    /// The reference transmitters.
    pub references: Vec<Reference>,
    /// Their channels' measurements of the stations that heard them.
    pub fixes: Vec<ReferenceFix>,
}

/// Each station of `d`'s prior and noise as `o` states them: the stations file's, else the
/// calibration's or the defaults.
pub(crate) fn stations_setup(d: &Decoded, o: &LocateOptions) -> StationSetup {
    let mut setup = station_setup(
        d.stations.iter().map(|s| s.id.as_str()),
        o.network.as_deref(),
        o.offset.unwrap_or_default(),
        o.offset.is_some(),
    );
    o.calibrated_direction(&mut setup.priors);
    setup
}

/// Solve `d` as `locate` does: each station's prior and noise from the stations file (else
/// the defaults), the reference transmitters' channels calibrating the stations that hear
/// them, then every channel by the field pipeline. The one place `locate` and the live map
/// turn a network's options into a fix.
pub(crate) fn solve<'a>(
    d: &'a Decoded,
    o: &LocateOptions,
    frame: &LocalFrame,
) -> Result<Solved<'a>, Unlocated> {
    let network = o.network.as_deref();
    let mut setup = stations_setup(d, o);
    let references: Vec<Reference> = network.map_or_else(Vec::new, |n| n.references.clone());
    let local: Vec<LocalReference> = references
        .iter()
        .filter_map(|r| {
            let p = frame.to_local(r.position).ok()?;
            Some(LocalReference {
                position: [p[0] as f32, p[1] as f32],
                freq_mhz: r.freq_mhz as f32,
            })
        })
        .collect();
    if local.len() < references.len() {
        return Err(
            String::from("a reference transmitter cannot be put in the drive's frame").into(),
        );
    }
    // The user's noise replaces every bearing's own; else a station's stated noise its own.
    // A copy only when something changes: a long capture's observations are most of the
    // memory.
    let noise = |x: &Observation| match o.sigma_deg {
        Some(s) => Some(s.to_radians()),
        None => setup.noise.get(usize::from(x.station)).copied().flatten(),
    };
    let with_noise: Cow<'_, [Observation]> =
        if o.sigma_deg.is_some() || setup.noise.iter().any(Option::is_some) {
            Cow::Owned(
                d.observations
                    .iter()
                    .map(|x| {
                        let mut x = *x;
                        if let Some(s) = noise(&x) {
                            x.bearing.sigma = s;
                        }
                        x
                    })
                    .collect(),
            )
        } else {
            Cow::Borrowed(&d.observations)
        };
    let (obs, fixes) = if local.is_empty() {
        (with_noise, Vec::new())
    } else {
        let (rest, fixes) =
            calibrate_on_references(&with_noise, &local, o.channel_width_mhz, &mut setup);
        (Cow::Owned(rest), fixes)
    };
    let r: PipelineRun = pool()
        .install(|| pipeline(&obs, &o.config(), &setup.priors, o.seed))
        .map_err(|e| explain(e, &bearings_of(&obs)))?;
    let found = Found {
        offsets: &r.offsets,
        directions: &r.found,
    };
    let stations = station_reports(d, network, &setup, found, &fixes, &references);
    Ok(Solved {
        run: r,
        setup,
        obs,
        stations,
        references,
        fixes,
    })
}

/// The bearings alone, for the words of an error.
fn bearings_of(obs: &[Observation]) -> Vec<Bearing> {
    obs.iter().map(|x| x.bearing).collect()
}

/// Every channel of the field pipeline's `locate` (emitters, regions and others): a channel
/// whose range is open has its region; an emitter of `located_by_pipeline` is absent when
/// only regions came out (the caller then reports no fix, with them).
pub(crate) fn located_by_pipeline(
    d: &Decoded,
    o: &LocateOptions,
    frame: &LocalFrame,
    rejected: &mut BTreeMap<&'static str, u32>,
) -> Result<(Parts, Vec<StationReport>), Unlocated> {
    let Solved {
        run: r,
        setup,
        obs,
        stations,
        references,
        fixes,
    } = solve(d, o, frame)?;
    let bearings = || bearings_of(&obs);
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
        let mut region = None;
        let mut motion = None;
        let reason = reason_code(c.outcome);
        let outcome = match c.outcome {
            ChannelOutcome::Emitter(_) => "emitter".to_string(),
            ChannelOutcome::Region(i) => {
                let Some(g) = r.regions().get(i).map(|g| RegionReport::of(g, frame)) else {
                    continue;
                };
                // Bearings that meet behind the vehicle point the wrong way: their direction
                // is no answer, the convention is the question.
                let bearings = bearings();
                let text = if points_away(&bearings) {
                    explain(Error::BehindVehicle, &bearings)
                } else {
                    region = Some(g);
                    open_range(&g)
                };
                why_none.get_or_insert((text.clone(), reason));
                text
            }
            ChannelOutcome::NoConsistentEmitter(why) => {
                // A vehicle that never moved, or bearings that never cross, say so plainly.
                let bearings = bearings();
                let geometry = match foxhunt_core::fix::ple::ple(&bearings) {
                    Err(e @ (Error::StationaryVehicle | Error::ParallelBearings)) => {
                        Some(explain(e, &bearings))
                    }
                    _ => None,
                };
                if let NoEmitter::Moving(m) = why {
                    motion = Some(MotionReport::of(&m, frame));
                }
                let text = geometry.unwrap_or_else(|| {
                    let max_sigma = setup.priors.config(&o.config()).max_sigma;
                    // The channel's own bearings: do they step like noise, or follow something?
                    let mine: Vec<Observation> = obs
                        .iter()
                        .filter(|x| same_channel(x.freq_mhz, c.freq_mhz, o.channel_width_mhz))
                        .copied()
                        .collect();
                    let mut heard: Vec<u16> = mine.iter().map(|x| x.station).collect();
                    heard.sort_unstable();
                    heard.dedup();
                    no_emitter(why, c.bearings, &bearings, max_sigma)
                        + &steady_clause(why, step_deg(&mine), heard.len(), max_sigma)
                });
                why_none.get_or_insert((text.clone(), reason));
                text
            }
        };
        channels.push(ChannelSummary {
            freq_mhz: c.freq_mhz,
            bearings: c.bearings,
            outcome,
            region,
            reason,
            motion,
        });
    }
    for (i, r) in references.iter().enumerate() {
        let heard = fixes.iter().filter(|f| f.reference == i);
        channels.push(ChannelSummary {
            freq_mhz: Some(r.freq_mhz as f32),
            bearings: heard.clone().map(|f| f.calibration.used).sum(),
            outcome: format!(
                "reference transmitter {}: calibrated {} stations",
                r.name,
                heard.count()
            ),
            region: None,
            reason: None,
            motion: None,
        });
    }
    if r.emitters().is_empty() && channels.iter().all(|c| c.region.is_none()) {
        let (error, reason) = why_none.unwrap_or_else(|| ("no consistent emitter".into(), None));
        return Err(Unlocated {
            error,
            located: None,
            reason,
            channels,
        });
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
        (
            emitters,
            others,
            channels,
            drawn,
            Vec::new(),
            r.emitters().to_vec(),
        ),
        stations,
    ))
}

/// Whether a bearing on `freq` belongs to the channel at `channel` (MHz, within `width`; no
/// frequency with none).
fn same_channel(freq: Option<f32>, channel: Option<f32>, width: f32) -> bool {
    match (freq, channel) {
        (Some(f), Some(c)) => (f - c).abs() <= width,
        (None, None) => true,
        _ => false,
    }
}
