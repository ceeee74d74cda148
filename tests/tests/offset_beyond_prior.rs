//! An adversary's sweep of the DF unit's mounting offset far past its prior (docs/src/field.md,
//! "Past the prior"): the default pipeline with the default prior (mean 0, sd 6 degrees) on
//! drives whose unit is off by 0 to 180 degrees in 15 degree steps (72 degrees is a
//! five-element array indexed one element off, 90 and 180 a swapped cable).
//!
//! Geometries, 1 degree bearing noise, 60 bearings each:
//! - drives that turn enough to measure the offset: the L600 drive (two 300 m legs at right
//!   angles) with the emitter at 1.44 km (aoa-drive's), and a 300 m loop centred on the route's
//!   start with the same emitter;
//! - straight roads, where the offset is barely told from a cross-range shift: line600 (600 m
//!   east) with the same emitter (the bearings turn 20 degrees), with an emitter 1 km
//!   broadside of its middle (33 degrees) and 500 m broadside (62 degrees).
//!
//! [`SEEDS`] = 40 runs per offset and geometry. On the turning drives 13 x 2 x 40 = 1040 runs,
//! so the 1 % bar is 10 runs, and a pipeline that missed in 2 % of runs (21 expected, sd 4.5)
//! would fail it with 95 % probability.
//!
//! "Misses by more than 3 sigma": the truth outside the fix's 99.73 % region (the
//! two-dimensional equivalent of 3 sigma, the field table's "beyond 3 sigma"): its Mahalanobis
//! distance m under the reported covariance C has a tail probability below 0.0027, the tail
//! being that of the reported ellipse's own distribution (P(2 F(2, dof) > m^2) when the noise
//! was estimated, exp(-m^2 / 2) otherwise). This is stricter than "m above 3 times the 95 %
//! ellipse's scale" (3 sqrt(k), k = 2 F(2, dof) at 0.95), which the sweep also reports.
//! An honest ellipse misses so in 0.27 % of runs; the bar is 1 %.
//!
//! On a straight road no estimator can hold that bar: the bearings of a unit 30 degrees off
//! are those of an emitter elsewhere with a unit 0 degrees off, so the ellipse is right only
//! while the prior is. There the fix must say so: every miss beyond 3 sigma must carry a flag
//! the user reads (the offset relaxed past its prior, a rival offset, or the offset not
//! measured by the drive: `OffsetCheck::unmeasured`), unflagged misses stay within the 1 % bar over
//! all 2 600 runs, and where the data put the offset past its prior without measuring it the
//! answer is no fix ([`NoEmitter::OffsetBeyondPrior`]), which the far straight road must show.
//! On every drive the stop rule never calls a fix that misses so good enough where the offset
//! lies past three prior sds (below that the miss is the honest ellipse's own 0.27 %, which no
//! check can see).

use foxhunt_core::canonical::{AOA_EMITTER, l600, line600, loop300};
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::ellipse::mahalanobis;
use foxhunt_core::fix::locate::{ChannelOutcome, LocateConfig, NoEmitter, Observation, Source};
use foxhunt_core::guidance::stop::{FixQuality, StopRule, verdict};
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::random;
use foxhunt_sim::estimate::{Priors, pipeline};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// Runs per offset and geometry.
const SEEDS: u64 = 40;
const DEG: f32 = std::f32::consts::PI / 180.0;
/// Tail probability of 3 sigma (two-sided, one dimension).
const THREE_SIGMA_TAIL: f64 = 0.0027;

/// One drive: its name, the vehicle's 60 positions, the emitter, and whether it turns enough
/// to measure the offset.
struct Geometry {
    name: &'static str,
    route: Vec<[f32; 2]>,
    emitter: [f32; 2],
    turns: bool,
}

/// The drives of the sweep.
fn geometries() -> Vec<Geometry> {
    let line: Vec<[f32; 2]> = (0..60).map(line600).collect();
    let straight = |name, emitter| Geometry {
        name,
        route: line.clone(),
        emitter,
        turns: false,
    };
    vec![
        Geometry {
            name: "L600",
            route: (0..60).map(l600).collect(),
            emitter: AOA_EMITTER,
            turns: true,
        },
        Geometry {
            name: "loop300",
            route: (0..60).map(|k| loop300([0.0, 0.0], k)).collect(),
            emitter: AOA_EMITTER,
            turns: true,
        },
        straight("line-far", AOA_EMITTER),
        straight("line-1k", [300.0, 1000.0]),
        straight("line-500", [300.0, 500.0]),
    ]
}

/// One run's bearings: 1 degree noise, the unit's offset `offset` (added to the model
/// bearing, counter-clockwise, as the pipeline reports it).
fn drive(route: &[[f32; 2]], emitter: [f32; 2], offset: f32, seed: u64) -> Vec<Observation> {
    let mut rng = XorShiftRng::seed_from_u64(0x0ff5e7 ^ seed);
    route
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let theta = wrap(predicted(&emitter, v) + offset + DEG * random::normal(&mut rng));
            Observation::new(
                Bearing {
                    vehicle: *v,
                    theta,
                    sigma: DEG,
                },
                k as f32,
            )
        })
        .collect()
}

/// How far the truth lies outside the fix: (tail probability of its Mahalanobis distance,
/// that distance over the 95 % ellipse's).
fn miss(s: &Source, emitter: [f32; 2]) -> (f64, f32) {
    let m = mahalanobis(&s.covariance, &s.position, &emitter).unwrap_or(f32::INFINITY);
    let m2 = f64::from(m * m);
    let tail = if s.sigma_estimated {
        let d = f64::from(s.dof);
        (1.0 + m2 / d).powf(-d / 2.0)
    } else {
        (-m2 / 2.0).exp()
    };
    (tail, m / s.ellipse_scale.sqrt())
}

/// The stop rule on the fix as guidance sees it: the channel's bearings at the fix's noise,
/// the default prior, the fix's own checks.
fn good_enough(s: &Source, obs: &[Observation]) -> bool {
    let bearings: Vec<Bearing> = obs
        .iter()
        .map(|o| Bearing {
            sigma: s.sigma,
            ..o.bearing
        })
        .collect();
    let quality = FixQuality {
        consistent: s.consistent,
        effective: s.effective,
        offset_beyond_prior: s.offset_check.doubtful(),
    };
    verdict(
        s.position,
        &bearings,
        BiasPrior::default(),
        quality,
        &StopRule::default(),
    )
    .is_ok_and(|v| v.good_enough)
}

#[derive(Default)]
struct Tally {
    runs: u32,
    fixes: u32,
    relaxed: u32,
    ambiguous: u32,
    typed: u32,
    covered: u32,
    beyond_3_sigma: u32,
    beyond_3x_95: u32,
    good_enough: u32,
    good_enough_missed: u32,
    unmeasured: u32,
    unflagged_missed: u32,
}

impl Tally {
    fn add(&mut self, t: &Tally) {
        self.runs += t.runs;
        self.fixes += t.fixes;
        self.relaxed += t.relaxed;
        self.ambiguous += t.ambiguous;
        self.typed += t.typed;
        self.covered += t.covered;
        self.beyond_3_sigma += t.beyond_3_sigma;
        self.beyond_3x_95 += t.beyond_3x_95;
        self.good_enough += t.good_enough;
        self.good_enough_missed += t.good_enough_missed;
        self.unmeasured += t.unmeasured;
        self.unflagged_missed += t.unflagged_missed;
    }
}

impl std::fmt::Display for Tally {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:3} fixes of {:3} ({:3} relaxed, {:2} ambiguous), no fix for the offset {:2}; 95 % \
             ellipse holds the truth {:3}; beyond 3 sigma {:2}, beyond 3x the 95 % ellipse {:2}; \
             good enough {:3} ({} beyond 3 sigma); offset unmeasured {:3}; beyond 3 sigma \
             unflagged {:2}",
            self.fixes,
            self.runs,
            self.relaxed,
            self.ambiguous,
            self.typed,
            self.covered,
            self.beyond_3_sigma,
            self.beyond_3x_95,
            self.good_enough,
            self.good_enough_missed,
            self.unmeasured,
            self.unflagged_missed
        )
    }
}

/// Offsets up to three prior sds (18 degrees) are the prior's own tail: there an honest fix
/// misses beyond 3 sigma in 0.27 % of runs whatever the stop rule says. Beyond, the stop rule
/// must never call a fix that misses so good enough.
const PRIOR_3_SD_DEG: u64 = 18;

#[test]
fn no_confident_wrong_fix_for_any_mounting_offset() {
    let config = LocateConfig::default();
    let priors = Priors::same(BiasPrior::default());
    let mut total = Tally::default();
    let mut turning = Tally::default();
    let mut per_drive = Vec::new();
    let mut stop_beyond_prior = 0;
    let mut rows = Vec::new();
    for Geometry {
        name,
        route,
        emitter,
        turns,
    } in geometries()
    {
        let mut drive_total = Tally::default();
        for step in 0..=12u64 {
            let offset_deg = 15 * step;
            let mut t = Tally::default();
            for seed in 0..SEEDS {
                // Each offset its own noise: the runs of the sweep are independent.
                let seed = seed + 1000 * step;
                let obs = drive(&route, emitter, offset_deg as f32 * DEG, seed);
                t.runs += 1;
                let Ok(run) = pipeline(&obs, &config, &priors, seed) else {
                    continue;
                };
                let Some(s) = run.report.emitters().first() else {
                    let why = run.report.channels().first().map(|c| c.outcome);
                    t.typed += u32::from(matches!(
                        why,
                        Some(ChannelOutcome::NoConsistentEmitter(
                            NoEmitter::OffsetBeyondPrior(_)
                        ))
                    ));
                    continue;
                };
                t.fixes += 1;
                t.relaxed += u32::from(s.offset_check.relaxed);
                t.ambiguous += u32::from(s.offset_check.ambiguous);
                let (tail, over) = miss(s, emitter);
                t.covered += u32::from(over <= 1.0);
                let missed = tail < THREE_SIGMA_TAIL;
                t.beyond_3_sigma += u32::from(missed);
                t.beyond_3x_95 += u32::from(over > 3.0);
                let unmeasured = s.offset_check.unmeasured;
                t.unmeasured += u32::from(unmeasured);
                t.unflagged_missed +=
                    u32::from(missed && !unmeasured && !s.offset_check.doubtful());
                let stop = good_enough(s, &obs);
                t.good_enough += u32::from(stop);
                t.good_enough_missed += u32::from(stop && missed);
                if offset_deg > PRIOR_3_SD_DEG && stop && missed {
                    stop_beyond_prior += 1;
                }
            }
            rows.push(format!("{name:8} {offset_deg:3} deg: {t}"));
            total.add(&t);
            drive_total.add(&t);
            if turns {
                turning.add(&t);
            }
        }
        per_drive.push(format!("{name:8}: {drive_total}"));
    }
    let share = |n: u32, of: u32| 100.0 * f64::from(n) / f64::from(of.max(1));
    let shown = format!(
        "\n{}\n{}\nall: {total}\nturning drives: {turning}\nbeyond 3 sigma in {:.2} % of the turning \
         drives' runs, {:.2} % of all; unflagged {:.2} % of all; the fixes' 95 % coverage {:.1} %\n",
        rows.join("\n"),
        per_drive.join("\n"),
        share(turning.beyond_3_sigma, turning.runs),
        share(total.beyond_3_sigma, total.runs),
        share(total.unflagged_missed, total.runs),
        share(total.covered, total.fixes),
    );
    println!("{shown}");
    assert!(
        f64::from(turning.beyond_3_sigma) <= 0.01 * f64::from(turning.runs),
        "more than 1 % of the turning drives' runs miss by more than 3 sigma:{shown}"
    );
    assert!(
        f64::from(total.unflagged_missed) <= 0.01 * f64::from(total.runs),
        "more than 1 % of runs miss by more than 3 sigma with no flag:{shown}"
    );
    assert!(
        total.typed > 0,
        "no drive gave the typed no-fix for an offset past its prior:{shown}"
    );
    assert_eq!(
        stop_beyond_prior, 0,
        "good enough on a fix beyond 3 sigma with the offset past the prior's 3 sd:{shown}"
    );
}
