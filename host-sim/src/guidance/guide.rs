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
    Advice, AdviceReport, FixView, GuidanceOptions, Situation, advise, advise_move, median_sigma,
    missing_names, stop_verdict, track_heading,
};
use crate::capture::Decoded;
use crate::locate::{LatLonReport, LocateOptions, geodetic};
use crate::roads::RoadGraph;
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
    /// (the bound at the noise the fix found, [`noise_scale`]) and the fix's own CEP50 below
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

    /// [`Guide::advise_every`] as `foxhunt locate` reports it.
    pub fn located(
        &mut self,
        d: &Decoded,
        emitters: &[Source],
        o: &LocateOptions,
    ) -> Result<LocatedAdvice, String> {
        let frame = d.frame.ok_or("no GPS fix yet")?;
        let g = self.advise_every(d, emitters, o)?;
        let a = g.advice;
        let ll = |p: [f32; 2]| {
            let g = geodetic(&frame, p);
            LatLonReport {
                lat: g.lat,
                lon: g.lon,
            }
        };
        let target = ll(a.waypoint);
        let line = g.line_to(Some(&format!("{:.5}, {:.5}", target.lat, target.lon)));
        Ok(LocatedAdvice {
            report: a.report(),
            target,
            turn_at: a.turn.map(|t| ll(t.at)),
            emitters: g.emitters,
            for_emitters: g.for_emitters,
            line,
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
        .filter(|(x, _)| same_channel(x.freq_mhz, f.freq_mhz, o.channel_width_mhz))
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

/// Where the vehicle is, every bearing so far (at `o`'s sigma if it sets one) and the track's
/// heading.
type SoFar = ([f32; 2], Vec<Bearing>, Option<f32>);

/// [`SoFar`] of the drive `d`.
fn drive_so_far(d: &Decoded, o: &LocateOptions) -> Result<SoFar, String> {
    let vehicle = d
        .bearings()
        .last()
        .map(|b| b.vehicle)
        .ok_or("no bearing yet")?;
    let all: Vec<Bearing> = match o.sigma_deg {
        Some(s) => d.bearings_with_sigma(s.to_radians()),
        None => d.bearings().copied().collect(),
    };
    let heading = track_heading(&all);
    Ok((vehicle, all, heading))
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

/// Whether a bearing at `freq` belongs to the channel at `channel` (the pipeline's grouping:
/// within the channel width; bearings without a frequency form their own channel).
fn same_channel(freq: Option<f32>, channel: Option<f32>, width: f32) -> bool {
    match (freq, channel) {
        (Some(f), Some(c)) => (f - c).abs() <= width.max(1e-3),
        (None, None) => true,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bearings_join_their_own_channel_only() {
        assert!(same_channel(Some(146.52), Some(146.52), 0.05));
        assert!(same_channel(Some(146.54), Some(146.52), 0.05));
        assert!(!same_channel(Some(147.0), Some(146.52), 0.05));
        assert!(!same_channel(None, Some(146.52), 0.05));
        assert!(same_channel(None, None, 0.05));
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

    /// The two-emitter field condition's capture (240 bearings on each of two channels).
    fn two_emitters() -> Vec<u8> {
        use crate::field::{Condition, capture};
        capture(Condition::TwoEmitters, 0, crate::simulate::DEFAULT_ORIGIN)
            .map(|(b, _)| b)
            .unwrap_or_default()
    }

    fn decode(bytes: &[u8]) -> Decoded {
        let mut d = crate::capture::Decoder::new(foxhunt_bridge::BridgeConfig::default(), false);
        d.feed(bytes);
        d.finish()
    }

    /// Every number of an advice is finite, every emitter has a verdict, and the move is for
    /// exactly those not good enough.
    fn check(a: &LocatedAdvice, emitters: usize) -> Result<(), String> {
        let r = &a.report;
        let numbers = [
            r.heading_deg,
            r.waypoint[0],
            r.waypoint[1],
            r.predicted_cep50_m,
        ];
        let verdicts = a
            .emitters
            .iter()
            .flat_map(|v| [v.bound_cep50_m, v.offset_known_cep50_m])
            .chain([r.bound_cep50_m, r.offset_known_cep50_m, r.reached_s])
            .flatten();
        let finite = numbers.into_iter().chain(verdicts).all(f32::is_finite)
            && a.target.lat.is_finite()
            && a.target.lon.is_finite();
        if !finite {
            return Err(format!("a number is not finite: {a:?}"));
        }
        if a.emitters.len() != emitters {
            return Err(format!(
                "{} verdicts for {emitters} emitters",
                a.emitters.len()
            ));
        }
        let short: Vec<usize> = a
            .emitters
            .iter()
            .filter(|v| !v.good_enough)
            .map(|v| v.emitter)
            .collect();
        if emitters > 0 && short != a.for_emitters {
            return Err(format!("move for {:?}, short: {short:?}", a.for_emitters));
        }
        if emitters > 0 && r.good_enough != short.is_empty() {
            return Err(format!(
                "good enough {} with {short:?} short",
                r.good_enough
            ));
        }
        Ok(())
    }

    #[test]
    fn two_emitters_each_get_a_verdict_and_the_move_is_for_the_one_short() {
        let bytes = two_emitters();
        let lines: Vec<&[u8]> = bytes.split_inclusive(|b| *b == b'\n').collect();
        // 200 sentences: 100 bearings, 50 per emitter; emitter 1's CEP50 is then below 100 m
        // and emitter 2's above it (77 m and 137 m in this run).
        let d = decode(&lines[..200].concat());
        let o = LocateOptions::default();
        let mut g = Guide::new(None, 100.0).unwrap();
        let l = crate::locate::locate_guided(&d, &o, &mut g).unwrap();
        let cep: Vec<f32> = l.report.emitters.iter().map(|e| e.cep50_m).collect();
        let a = l.report.advice.expect("advice");
        check(&a, 2).unwrap();
        assert!(cep[0] < 100.0 && cep[1] > 100.0, "{cep:?}");
        assert!(
            a.emitters[0].good_enough && !a.emitters[1].good_enough,
            "{a:?}"
        );
        assert_eq!(a.for_emitters, vec![2]);
        assert!(
            a.line
                .contains(" for emitter 2; emitter 1: good enough; emitter 2: "),
            "{}",
            a.line
        );
        // The move is the one for emitter 2 alone (emitter 1 resolved earns nothing more).
        let alone = g.advise(&d, l.emitters.get(1), &o).unwrap();
        assert_eq!(a.report.heading_deg, alone.report().heading_deg, "{a:?}");
        // The whole drive: both good enough, and the line says so for both.
        let d = decode(&bytes);
        let l = crate::locate::locate_guided(&d, &o, &mut g).unwrap();
        let a = l.report.advice.expect("advice");
        check(&a, 2).unwrap();
        assert!(a.report.good_enough && a.for_emitters.is_empty(), "{a:?}");
        assert_eq!(a.line, "good enough: stop (emitters 1, 2)");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// Any prefix of a two-emitter drive, bytes corrupted, any target: advice or a
        /// one-line error, never a panic or a number that is not finite.
        #[test]
        fn any_two_emitter_prefix_advises_soundly(
            cut in 0usize..70_000,
            flips in proptest::collection::vec((0usize..70_000, 1u8..=255), 0..40),
            target in 5.0f32..500.0,
        ) {
            let mut bytes = two_emitters();
            bytes.truncate(cut);
            for (at, x) in flips {
                if let Some(b) = bytes.get_mut(at) {
                    *b ^= x;
                }
            }
            let d = decode(&bytes);
            let mut g = Guide::new(None, target).unwrap();
            let advice = match crate::locate::locate_guided(&d, &LocateOptions::default(), &mut g) {
                Ok(l) => l.report.advice.map(|a| (a, l.report.emitters.len())),
                Err(e) => e.advice.map(|a| (a, 0)),
            };
            if let Some((a, n)) = advice {
                proptest::prop_assert!(check(&a, n).is_ok(), "{:?}", check(&a, n));
                let json = serde_json::to_string(&a).unwrap();
                proptest::prop_assert!(!json.contains("NaN") && !json.contains("inf"), "{}", json);
            }
        }
    }
}
