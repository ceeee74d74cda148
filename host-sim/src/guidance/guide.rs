//! Guidance as a drive goes on: the road network (placed in the drive's frame once its origin
//! is known), the stop rule's settings, and the advice for the field pipeline's fix after each
//! update. `foxhunt locate` (live lines and the final report) and `foxhunt serve` both advise
//! through [`Guide::advise_every`], so the move, its reason and the verdicts are the same in
//! the terminal, in `--json` lines and on the map.
//!
//! Several emitters (one per channel): each gets its own stop-rule verdict, from its own
//! channel's bearings and fix; the vehicle drives one way, so there is one move, planned for
//! every emitter not yet good enough at once (their hypotheses kept apart, the goal reached
//! only when all of them are below the target: [`foxhunt_core::guidance::plan::plan_for`]).
//! Its reason is that of the one with the largest reported CEP50 (the furthest from the
//! goal); when there are more than the planner serves
//! ([`foxhunt_core::guidance::plan::MAX_EMITTERS`]), the move is for those with the largest
//! CEP50. "Good enough: stop" only when every emitter is.

use super::{
    Advice, FixView, GuidanceOptions, Situation, advise, advise_move, median_sigma, missing_names,
    stop_verdict, track_heading,
};
use crate::estimate::options::LocateOptions;
use crate::inputs::capture::Decoded;
use crate::inputs::roads::RoadGraph;
use foxhunt_core::Bearing;
use foxhunt_core::fix::locate::Source;
use foxhunt_core::guidance::stop::Verdict;
use serde::Serialize;

/// Where to drive and whether to stop, for one drive.
#[derive(Debug, Clone)]
pub struct Guide {
    roads: Option<RoadGraph>,
    placed: bool,
    options: GuidanceOptions,
}

/// One emitter's stop-rule verdict (field names are stable).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct VerdictReport {
    /// Which emitter: its number in the report's emitters (1 = the first).
    pub emitter: usize,
    /// Its channel's frequency, MHz.
    pub freq_mhz: Option<f32>,
    /// The stop rule holds for it.
    pub good_enough: bool,
    /// Why not, machine-readable (as the advice's `reason`).
    pub reason: &'static str,
    /// Why not, in words.
    pub reason_text: String,
    /// What is missing (`precision`, `consistency`, `bearings`; `fix` when the stop rule
    /// could not judge it).
    pub missing: Vec<&'static str>,
    /// Predicted CEP50 from the bias-aware bound at its fix, metres.
    pub bound_cep50_m: Option<f32>,
    /// The same with the offset known, metres.
    pub offset_known_cep50_m: Option<f32>,
    /// Why the stop rule could not judge it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
}

impl VerdictReport {
    fn new(emitter: usize, freq_mhz: Option<f32>, v: &Result<Verdict, String>) -> Self {
        let ok = v.as_ref().ok();
        let reason = ok
            .map(|v| v.reason())
            .unwrap_or(foxhunt_core::guidance::stop::Reason::MoreBearings);
        Self {
            emitter,
            freq_mhz,
            good_enough: ok.is_some_and(|v| v.good_enough),
            reason: reason.name(),
            reason_text: reason.to_string(),
            missing: missing_names(ok),
            bound_cep50_m: ok.map(|v| v.cep50_m),
            offset_known_cep50_m: ok.map(|v| v.offset_known_cep50_m),
            error: v.as_ref().err().cloned(),
        }
    }

    /// `emitter N: good enough`, or its reason and what is missing.
    fn words(&self) -> String {
        let n = self.emitter;
        match (&self.error, self.good_enough) {
            (Some(e), _) => format!("emitter {n}: no verdict ({e})"),
            (None, true) => format!("emitter {n}: good enough"),
            (None, false) => format!(
                "emitter {n}: {} (missing: {})",
                self.reason_text,
                self.missing.join(", ")
            ),
        }
    }
}

/// The advice for every emitter: the one move, and each emitter's verdict.
#[derive(Debug, Clone, PartialEq)]
pub struct Guided {
    /// The move; its reason and verdict are those of the emitter furthest from the goal among
    /// those it serves (every emitter's, when one is reported).
    pub advice: Advice,
    /// Each emitter's verdict, in the order given.
    pub emitters: Vec<VerdictReport>,
    /// The emitters the move is for, numbered from 1, in order.
    pub for_emitters: Vec<usize>,
}

/// `emitter 2` or `emitters 1, 3`.
fn named(list: &[usize]) -> String {
    let n: Vec<String> = list.iter().map(usize::to_string).collect();
    format!(
        "emitter{} {}",
        if list.len() > 1 { "s" } else { "" },
        n.join(", ")
    )
}

impl Guided {
    /// Whether every emitter is good enough (with one, its verdict; before a fix, false).
    pub fn good_enough(&self) -> bool {
        self.advice.report().good_enough && self.emitters.iter().all(|e| e.good_enough)
    }

    /// The advice in one line, naming the point to drive to (`to`). One emitter (or none
    /// yet): [`Advice::line_to`]. Several: the move, the emitters it is for, and every
    /// emitter's verdict.
    pub fn line_to(&self, to: Option<&str>) -> String {
        if self.emitters.len() <= 1 {
            return self.advice.line_to(to);
        }
        let all: Vec<usize> = self.emitters.iter().map(|e| e.emitter).collect();
        if self.good_enough() {
            return format!("good enough: stop ({})", named(&all));
        }
        let each: Vec<String> = self.emitters.iter().map(VerdictReport::words).collect();
        format!(
            "{} for {}; {}",
            self.advice.move_to(to),
            named(&self.for_emitters),
            each.join("; ")
        )
    }
}

impl Guide {
    /// Guidance on `roads` (an extract's graph, not yet placed; `None`: free headings in open
    /// terrain) with the stop rule's target CEP50. Refuses a target no rule can use.
    pub fn new(roads: Option<RoadGraph>, target_cep50_m: f32) -> Result<Self, String> {
        let mut options = if roads.is_some() {
            GuidanceOptions::roads()
        } else {
            GuidanceOptions::default()
        };
        options.stop.target_cep50_m = target_cep50_m;
        options.stop.check().map_err(|_| {
            format!("--target-cep50-m must be a number of metres > 0, not {target_cep50_m}")
        })?;
        Ok(Self {
            roads,
            placed: false,
            options,
        })
    }

    /// The settings advice is computed with.
    pub fn options(&self) -> &GuidanceOptions {
        &self.options
    }

    /// The road network as read (its nodes' latitudes and longitudes are the extract's).
    pub fn road_graph(&self) -> Option<&RoadGraph> {
        self.roads.as_ref()
    }

    /// The roads, placed in `d`'s frame (once it has one).
    pub fn roads(&mut self, d: &Decoded) -> Option<&RoadGraph> {
        if !self.placed
            && let (Some(g), Some(frame)) = (self.roads.as_mut(), d.frame.as_ref())
        {
            g.localise(frame);
            self.placed = true;
        }
        self.roads.as_ref().filter(|_| self.placed)
    }

    /// The advice for the drive `d` so far and the pipeline's emitter `fix` (`None`: no fix
    /// yet; the move then crosses the line of bearing), with the bearings' noise, offset prior
    /// and channel width of `o`. Only the fix's own channel's bearings count: another
    /// channel's bearings say nothing about this emitter. "Good enough" needs the stop rule
    /// (the bound at the noise the fix found, `noise_scale`) and the fix's own CEP50 below
    /// the target.
    pub fn advise(
        &mut self,
        d: &Decoded,
        fix: Option<&Source>,
        o: &LocateOptions,
    ) -> Result<Advice, String> {
        let (vehicle, all, heading) = drive_so_far(d, o)?;
        let channel: Vec<Bearing> = match fix {
            Some(f) => channel(d, &all, f, o),
            None => all,
        };
        let situation = Situation {
            bearings: &channel,
            vehicle,
            heading,
            fix: fix.map(view),
            prior: o.offset.unwrap_or_default(),
        };
        let options = self.options;
        let mut a = advise(&situation, self.roads(d), &options)?;
        if let (Some(f), Some(v)) = (fix, a.verdict.as_mut()) {
            *v = claimed(*v, f, &options);
            a.reason = v.reason();
        }
        Ok(a)
    }

    /// The advice for every emitter of the pipeline (`emitters`, in its order; none: from
    /// the bearings alone), as the module doc says. With one emitter (or none) the move and
    /// its words are [`Guide::advise`]'s.
    pub fn advise_every(
        &mut self,
        d: &Decoded,
        emitters: &[Source],
        o: &LocateOptions,
    ) -> Result<Guided, String> {
        if emitters.len() <= 1 {
            let fix = emitters.first();
            let a = self.advise(d, fix, o)?;
            let verdicts: Vec<VerdictReport> = fix
                .map(|f| {
                    let v = a.verdict.ok_or_else(|| "no verdict".to_string());
                    vec![VerdictReport::new(1, f.freq_mhz, &v)]
                })
                .unwrap_or_default();
            let for_emitters = if verdicts.iter().any(|v| !v.good_enough) {
                vec![1]
            } else {
                Vec::new()
            };
            return Ok(Guided {
                advice: a,
                emitters: verdicts,
                for_emitters,
            });
        }
        let (vehicle, all, heading) = drive_so_far(d, o)?;
        let prior = o.offset.unwrap_or_default();
        let options = self.options;
        let channels: Vec<Vec<Bearing>> = emitters.iter().map(|f| channel(d, &all, f, o)).collect();
        let situations: Vec<Situation<'_>> = emitters
            .iter()
            .zip(&channels)
            .map(|(f, c)| Situation {
                bearings: c,
                vehicle,
                heading,
                fix: Some(view(f)),
                prior,
            })
            .collect();
        let verdicts: Vec<Result<Verdict, String>> = situations
            .iter()
            .zip(emitters)
            .map(|(s, f)| {
                median_sigma(s.bearings).ok_or("no usable bearing yet")?;
                let v = stop_verdict(s, &options)?.ok_or("no fix")?;
                Ok(claimed(v, f, &options))
            })
            .collect();
        if verdicts.iter().all(|v| v.is_err())
            && let Some(Err(e)) = verdicts.first()
        {
            return Err(e.clone());
        }
        // Those not yet good enough, the furthest from the goal (largest CEP50) first; when
        // every one is, the move is planned for them all.
        let mut order: Vec<usize> = (0..emitters.len())
            .filter(|&i| {
                !verdicts
                    .get(i)
                    .is_some_and(|v| v.as_ref().is_ok_and(|v| v.good_enough))
            })
            .collect();
        let resolved = order.is_empty();
        if resolved {
            order = (0..emitters.len()).collect();
        }
        let cep = |i: &usize| emitters.get(*i).map(|e| e.cep50).unwrap_or(f32::NAN);
        order.sort_by(|a, b| cep(b).total_cmp(&cep(a)));
        let served: Vec<Situation<'_>> = order
            .iter()
            .filter_map(|&i| situations.get(i).copied())
            .collect();
        let lead = order.first().and_then(|&i| verdicts.get(i));
        let lead = lead.and_then(|v| v.as_ref().ok()).copied();
        let (advice, counted) = advise_move(&served, lead, self.roads(d), &options)?;
        let mut for_emitters: Vec<usize> = if resolved {
            Vec::new()
        } else {
            counted
                .iter()
                .filter_map(|&k| order.get(k).map(|i| i + 1))
                .collect()
        };
        for_emitters.sort_unstable();
        Ok(Guided {
            advice,
            emitters: verdicts
                .iter()
                .zip(emitters)
                .enumerate()
                .map(|(i, (v, f))| VerdictReport::new(i + 1, f.freq_mhz, v))
                .collect(),
            for_emitters,
        })
    }
}

/// The guidance view of a pipeline fix.
fn view(f: &Source) -> FixView {
    FixView {
        position: f.position,
        covariance: f.covariance,
        consistent: f.consistent,
        effective: f.effective,
        offset_beyond_prior: f.offset_check.doubtful(),
    }
}

/// The fix `f`'s own channel's bearings of `all` (those of `d`'s observations, in order), their
/// sigmas scaled to the noise the fix found ([`noise_scale`]): another channel's bearings say
/// nothing about this emitter.
fn channel(d: &Decoded, all: &[Bearing], f: &Source, o: &LocateOptions) -> Vec<Bearing> {
    let mut c: Vec<Bearing> = d
        .observations
        .iter()
        .zip(all)
        .filter(|(x, _)| f.in_channel(x.freq_mhz, o.channel_width_mhz))
        .map(|(_, b)| *b)
        .collect();
    let scale = noise_scale(f, &c);
    for b in &mut c {
        b.sigma *= scale;
    }
    c
}

/// The stop rule's verdict `v` held to the fix's own claim: the bound is the best case, the
/// fix's CEP50 is what is claimed, and "good enough" beside a reported CEP50 above the target
/// would tell the driver to stop too soon.
fn claimed(mut v: Verdict, f: &Source, o: &GuidanceOptions) -> Verdict {
    if !(f.cep50 < o.stop.target_cep50_m) {
        v.missing.precision = true;
        v.good_enough = false;
    }
    v
}

/// Where the guided vehicle is ([`guided_station`]), every bearing so far (at `o`'s sigma if
/// it sets one) and the vehicle's heading.
type SoFar = ([f32; 2], Vec<Bearing>, Option<f32>);

/// [`SoFar`] of the drive `d`.
fn drive_so_far(d: &Decoded, o: &LocateOptions) -> Result<SoFar, String> {
    let guided = guided_station(d)?;
    let all: Vec<Bearing> = match o.sigma_deg {
        Some(s) => d.bearings_with_sigma(s.to_radians()),
        None => d.bearings().copied().collect(),
    };
    // Where the guided vehicle is and where it heads: its own bearings, not the network's.
    let own: Vec<Bearing>;
    let track: &[Bearing] = match guided {
        Some(k) => {
            own = d
                .observations
                .iter()
                .zip(&all)
                .filter(|(x, _)| x.station == k)
                .map(|(_, b)| *b)
                .collect();
            &own
        }
        None => &all,
    };
    let vehicle = track.last().map(|b| b.vehicle).ok_or("no bearing yet")?;
    let heading = track_heading(track);
    Ok((vehicle, all, heading))
}

/// The station the advice guides: the one of the latest bearing among those that moved
/// (`None`: none has yet, so the one of the latest bearing, as a lone unit before it drives
/// off). Several stations heard and none moved is a network of fixed stations: no vehicle to
/// guide, and no advice for a mast to drive.
fn guided_station(d: &Decoded) -> Result<Option<u16>, String> {
    if d.stations.len() > 1 && d.stations.iter().all(|s| s.fixed) {
        return Err(format!(
            "every station stands still ({} stations, none moved): no vehicle to guide",
            d.stations.len()
        ));
    }
    Ok(d.observations
        .iter()
        .rev()
        .find(|x| {
            d.stations
                .get(usize::from(x.station))
                .is_some_and(|s| !s.fixed)
        })
        .map(|x| x.station))
}

/// How much noisier the fix found the bearings than they say: its noise over their median
/// sigma, times sqrt(N / N_eff) for correlated bearings (the pipeline widens its covariance by
/// N / N_eff). The stop rule's bound and the planner's predictions then hold at the noise the
/// reported fix used, so "good enough" never stands beside a reported CEP50 the bearings'
/// stated noise would have shrunk.
fn noise_scale(f: &Source, bearings: &[Bearing]) -> f32 {
    let stated = median_sigma(bearings).unwrap_or(f.sigma);
    let noise = if stated > 0.0 { f.sigma / stated } else { 1.0 };
    let correlated = if f.effective > 0.0 {
        (f.used as f32 / f.effective).sqrt()
    } else {
        1.0
    };
    let s = noise * correlated.max(1.0);
    if s.is_finite() && s > 0.0 { s } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inputs::capture::StationInfo;
    use foxhunt_core::fix::locate::Observation;

    fn station(id: &str, fixed: bool) -> StationInfo {
        StationInfo {
            id: id.into(),
            named: true,
            fixed,
            position: None,
            span_m: if fixed { 0.0 } else { 900.0 },
            bearings: 2,
        }
    }

    fn heard(station: u16, at: [f32; 2], t: f32) -> Observation {
        Observation {
            bearing: Bearing {
                vehicle: at,
                theta: 0.0,
                sigma: 0.03,
            },
            time_s: t,
            freq_mhz: None,
            station,
            stamped: true,
        }
    }

    #[test]
    fn the_advice_guides_the_vehicle_not_the_last_mast_heard() {
        // A car (station 1) driving east between two masts' bearings: the advice starts at the
        // car and heads east, though a mast was heard last.
        let mut d = Decoded {
            stations: vec![station("mast", true), station("car", false)],
            observations: vec![
                heard(1, [0.0, 0.0], 0.0),
                heard(0, [5000.0, 5000.0], 0.5),
                heard(1, [100.0, 0.0], 1.0),
                heard(0, [5000.0, 5000.0], 1.5),
            ],
            ..Decoded::default()
        };
        let o = LocateOptions::default();
        let (vehicle, all, heading) = drive_so_far(&d, &o).expect("a vehicle");
        assert_eq!(vehicle, [100.0, 0.0]);
        assert_eq!(all.len(), 4);
        assert!(heading.expect("a heading").abs() < 1e-6);
        // Two masts and nothing that moves: no vehicle, and the words say so.
        d.stations[1] = station("mast 2", true);
        let e = drive_so_far(&d, &o).unwrap_err();
        assert!(e.contains("no vehicle to guide"), "{e}");
        // One unit that has not driven off yet is still guided from where it stands.
        d.stations.truncate(1);
        d.observations.retain(|x| x.station == 0);
        assert_eq!(drive_so_far(&d, &o).expect("the unit").0, [5000.0, 5000.0]);
    }

    #[test]
    fn a_target_no_rule_can_use_is_refused_by_name() {
        for t in [0.0, -5.0, f32::NAN, f32::INFINITY] {
            let e = Guide::new(None, t).unwrap_err();
            assert!(e.contains("--target-cep50-m"), "{e}");
        }
        let g = Guide::new(None, 50.0).unwrap();
        assert_eq!(g.options().stop.target_cep50_m, 50.0);
    }
}
