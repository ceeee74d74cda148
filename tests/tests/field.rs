//! Honest in the field (issue 14): the default `locate` pipeline measured on simulated field
//! conditions (host-sim's `field` module: a mounting offset, a multipath stretch, two
//! emitters, correlated reports, pure noise, few bearings, a distant emitter, 20 km drives at
//! 47 and 70 degrees north, 15 % wild bearings), plus the augmented filters and the checks a
//! caller of a particle filter can use.
//!
//! Runs: every condition is measured over [`RUNS`] = 400 seeded runs (the issue asks for at
//! least 100). A coverage bar of 90-98 % around a nominal 95 % is +-2.3 binomial sds at 100
//! runs: a perfectly calibrated ellipse would land outside it in about one condition of the
//! sixteen by chance alone. At 400 runs the sd is 1.1 %, the bar is +-4.5 sds, and only a
//! miscalibrated ellipse fails it. An rmse over 400 runs is known to about +-3.5 % (the
//! relative standard error of a root mean square of 400 two-dimensional errors, 1/sqrt(1600)).
//! The runs are seeded, so every figure is deterministic; each assertion prints the table.

use foxhunt_core::fix::bias::{self, BiasPrior};
use foxhunt_core::fix::consistency::check_cloud;
use foxhunt_core::fix::ellipse::mahalanobis;
use foxhunt_core::fix::init::{InitOptions, initial_biased_particles, initial_particles};
use foxhunt_core::fix::intersection::MIN_CROSSING;
use foxhunt_core::fix::locate::{LocateConfig, Observation};
use foxhunt_core::fix::ml::{MlOptions, ml};
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::{
    BiasedBearingEkf, BiasedEmitter, Filter, Firefly, Gaussian, GaussianUniform, ParticleSet, Sir,
    SirConfig, StaticEmitter, random,
};
use foxhunt_sim::runs::field::{
    Condition, EmitterSummary, FieldDrive, Summary, judge, measure, run_locate, simulate,
};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::sync::OnceLock;

/// Seeded runs per condition.
const RUNS: usize = 400;
const DEG: f32 = std::f32::consts::PI / 180.0;

/// Every condition's figures with the default configuration, computed once for all tests.
fn table() -> &'static [Summary] {
    static TABLE: OnceLock<Vec<Summary>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let config = LocateConfig::default();
        Condition::ALL
            .iter()
            .map(|c| measure(*c, RUNS, &config, BiasPrior::default()))
            .collect()
    })
}

fn summary(c: Condition) -> &'static Summary {
    table()
        .iter()
        .find(|s| s.condition == c)
        .expect("every condition is in the table")
}

/// The whole table, for assertion messages.
fn shown() -> String {
    let rows: Vec<String> = table().iter().map(|s| s.to_string()).collect();
    format!("\n{}\n", rows.join("\n"))
}

/// A calibrated unit: offset known to be 0.
fn calibrated() -> BiasPrior {
    BiasPrior::calibrated(0.0)
}

#[test]
fn coverage_is_honest_in_every_field_condition() {
    for s in table() {
        // Pure noise has no emitter to cover; the uncorrected 70 N drive shows what happens
        // without the bridge's meridian convergence, which the bridge applies.
        if matches!(
            s.condition,
            Condition::PureNoise | Condition::Long70Uncorrected
        ) {
            continue;
        }
        // The open-range conditions leave few fixes, and the curved correlated drive's range
        // is barely observed: their answers (fixes and regions) are judged together.
        let open = Condition::ANSWERS_JUDGED.contains(&s.condition);
        for e in &s.per_emitter {
            let c = if open {
                e.answer_coverage()
            } else {
                e.coverage()
            };
            assert!(
                (0.90..=0.98).contains(&c),
                "{}: 95 % coverage {:.1} % over {} fixes and {} regions{}",
                s.condition.name(),
                100.0 * c,
                e.found,
                e.regions,
                shown()
            );
        }
    }
    println!("{}", shown());
}

#[test]
fn no_condition_misses_by_more_than_three_sigma() {
    // "Beyond 3 sigma": outside the region holding 99.73 % under the ellipse's own
    // distribution (chi-square, or 2 F(2, dof) when the noise was estimated). A calibrated
    // ellipse puts 0.27 % there; the bar is 1 % of the runs, as the adversary's (a condition
    // whose runs end mostly in regions, with a handful of fixes, is judged on its runs: a
    // confident wrong fix is rare or not by how often it happens, not by how few fixes there
    // are beside it).
    for s in table() {
        for e in &s.per_emitter {
            let share = e.beyond_3_sigma as f64 / s.runs.max(1) as f64;
            assert!(
                share <= 0.01,
                "{}: {} of {} fixes beyond 3 sigma in {} runs{}",
                s.condition.name(),
                e.beyond_3_sigma,
                e.found,
                s.runs,
                shown()
            );
        }
    }
}

#[test]
fn a_mounting_offset_is_estimated_to_the_bias_aware_bound() {
    for (c, offset) in [
        (Condition::Bias2, 2.0),
        (Condition::Bias4, 4.0),
        (Condition::Bias4Short, 4.0),
    ] {
        let s = summary(c);
        let e = &s.per_emitter[0];
        // Issue bar: rmse within 1.3x the bias-aware bound.
        assert!(
            e.ratio() <= 1.3,
            "{}: rmse / bias-aware bound {:.2}{}",
            c.name(),
            e.ratio(),
            shown()
        );
        assert_eq!(e.found, RUNS, "{}{}", c.name(), shown());
        // Where the drive observes the offset (the U), its mean estimate is within 0.05
        // degrees of the truth (its sd per run is 0.14 degrees, so the mean of 400 is good to
        // 0.01); on L600 the prior (mean 0, sd 6 degrees) pulls it toward 0, which the
        // covariance accounts for: 3.8 of 4 degrees is within a tenth of the prior's sd.
        let tolerance = if c == Condition::Bias4Short {
            0.6
        } else {
            0.05
        };
        assert!(
            (e.mean_bias_deg - offset).abs() <= tolerance,
            "{}: mean offset {:.3} deg, truth {offset}{}",
            c.name(),
            e.mean_bias_deg,
            shown()
        );
    }
}

/// The offset drives' bar: the rmse within 1.3x the bias-aware bound.
fn within_the_offset_drives_bar(e: &EmitterSummary) {
    assert!(
        e.ratio() <= 1.3,
        "rmse / bound {:.2} (rmse {:.1} m, bound {:.1} m){}",
        e.ratio(),
        e.rmse,
        e.bound,
        shown()
    );
}

#[test]
fn a_direction_dependent_error_is_integrated_out_where_it_is_stated() {
    // direction-dependent-2-5deg: first and second harmonics of 2-5 degrees each on the U
    // drive, the stations file stating 3 degrees per coefficient. Bars over 400 runs: an
    // emitter in every run but a few (the consensus sees bearings bent by up to 10 degrees
    // beside 2 degrees of noise; observed 400 of 400), coverage 90-98 % (the
    // common bar, in `coverage_is_honest_in_every_field_condition`), and the rmse within
    // 1.3x the bound with the harmonics' prior integrated out (the bar of the offset drives;
    // 400 runs know an rmse to +-3.5 %). Ignoring the harmonics (plain ML) misses by
    // 166 m at 100 runs: the pipeline's fix is the one to beat.
    let s = summary(Condition::DirectionDependent);
    let e = &s.per_emitter[0];
    assert!(
        e.found as f64 >= 0.97 * RUNS as f64,
        "found {} of {RUNS}{}",
        e.found,
        shown()
    );
    within_the_offset_drives_bar(e);
    println!(
        "direction-dependent-2-5deg: found {} of {RUNS}, coverage {:.1} %, rmse {:.1} m, bound {:.1} m",
        e.found,
        100.0 * e.coverage(),
        e.rmse,
        e.bound
    );
}

#[test]
fn a_direction_dependent_error_no_one_stated_is_found_and_nothing_else_is() {
    // direction-dependent-unstated: the stated condition's drives with nothing stated. The
    // pipeline tests each moving station's residuals for harmonics of the bearing relative
    // to its course (about the fix, or where a still emitter would stand when the channel
    // was called moving) and, beyond chi-square's 0.01 % point, fixes again with them
    // modelled. Measured over 100 runs: found in 94 (the rest too weak to tell: their wide
    // fixes hold the truth), a fix in all 100 (96 before: 4 called moving), rmse 9.0 m
    // against 8.5 m for the bound with the stated prior (18.2 m before: the estimated noise
    // took the harmonics up), coverage 95 %; no call in any other condition (400 runs: found
    // in 385, a fix in 400, coverage 95.5 %, rmse 8.8 m, no call elsewhere). Bars over 400
    // runs: a fix in 97 % (the stated condition's bar), found in at least 80 % (100 runs know
    // a share of 94 % to +-2.4 %), the rmse within the offset drives' 1.3x of the bound
    // (coverage is held to 90-98 % with every condition's), and at most 1 % of any other
    // condition's runs (4 of 400; the 0.01 % point expects none, the 0.1 % point gave one in
    // 2 200).
    let s = summary(Condition::DirectionUnstated);
    let e = &s.per_emitter[0];
    println!(
        "direction-dependent-unstated: found and modelled in {} of {RUNS}, fixes {}, coverage \
         {:.1} %, rmse {:.1} m, bound {:.1} m",
        s.direction_found,
        e.found,
        100.0 * e.coverage(),
        e.rmse,
        e.bound
    );
    assert!(
        e.found as f64 >= 0.97 * RUNS as f64,
        "fixes in {} of {RUNS}{}",
        e.found,
        shown()
    );
    assert!(
        s.direction_found * 100 >= RUNS * 80,
        "found in {} of {RUNS}{}",
        s.direction_found,
        shown()
    );
    within_the_offset_drives_bar(e);
    let elsewhere: Vec<(&str, usize)> = table()
        .iter()
        .filter(|s| s.condition != Condition::DirectionUnstated)
        .map(|s| (s.condition.name(), s.direction_found))
        .collect();
    println!("found elsewhere: {elsewhere:?}");
    for (name, n) in &elsewhere {
        assert!(n * 100 <= RUNS, "{name}: found in {n} of {RUNS}");
    }
}

#[test]
fn correlated_reports_on_a_curved_track_are_honest() {
    // correlated-5hz-curved: the 5 Hz running-mean unit of `correlated-5hz` on a 258 degree
    // arc. Its answers (fixes and regions) are held to the common 90-98 % bar; here, that the
    // offset check does not read the correlated reports as evidence against the prior (on a
    // 34 degree arc it did: runs relaxed the prior onto a spurious minimum 50-60 degrees
    // off, 11 of 100 beyond 3 sigma): an answer in every run but 1 % and the mean offset
    // within 0.5 degrees of the truth (0; one run's offset has an sd well under 1 degree on
    // a drive that turns 258 degrees, so a mean of 400 is good to 0.05, while one run
    // relaxed 50 degrees off shifts it by 0.13).
    let s = summary(Condition::CorrelatedCurved);
    let e = &s.per_emitter[0];
    assert!(
        (e.found + e.regions) as f64 >= 0.99 * RUNS as f64,
        "answers {} of {RUNS}{}",
        e.found + e.regions,
        shown()
    );
    assert!(
        e.mean_bias_deg.abs() <= 0.5,
        "mean offset {:.2} deg{}",
        e.mean_bias_deg,
        shown()
    );
    println!(
        "correlated-5hz-curved: found {}, regions {}, answers held {:.1} %, mean offset {:.2} deg",
        e.found,
        e.regions,
        100.0 * e.answer_coverage(),
        e.mean_bias_deg
    );
}

#[test]
fn a_ghost_stretch_keeps_the_emitter_and_reports_the_ghost() {
    let s = summary(Condition::Multipath);
    let e = &s.per_emitter[0];
    let inside = e.covered as f64 / RUNS as f64;
    // Issue bars: the emitter inside its ellipse in >= 90 % of runs, the ghost reported as
    // another source (here in every run: >= 90 % asked).
    assert!(
        inside >= 0.90,
        "emitter inside its ellipse in {:.1} % of runs{}",
        100.0 * inside,
        shown()
    );
    assert!(
        s.ghost_reported as f64 >= 0.9 * RUNS as f64,
        "ghost reported in {} of {RUNS} runs{}",
        s.ghost_reported,
        shown()
    );
}

#[test]
fn two_frequencies_give_two_honest_emitters() {
    let s = summary(Condition::TwoEmitters);
    assert_eq!(s.per_emitter.len(), 2);
    for e in &s.per_emitter {
        // Each channel's emitter in every run (observed: all), not one phantom between them;
        // their honesty is asserted with every other condition's coverage.
        assert!(
            e.found >= RUNS - 4,
            "found {} of {RUNS}{}",
            e.found,
            shown()
        );
        assert!(e.ratio() <= 1.3, "ratio {:.2}{}", e.ratio(), shown());
    }
}

#[test]
fn pure_noise_is_no_consistent_emitter() {
    let s = summary(Condition::PureNoise);
    // Issue bar: "no consistent emitter" in >= 95 % of runs.
    assert!(
        s.no_emitter as f64 >= 0.95 * RUNS as f64,
        "no consistent emitter in {} of {RUNS} runs{}",
        s.no_emitter,
        shown()
    );
}

#[test]
fn few_bearings_with_estimated_noise_are_honest_or_refused() {
    // Run r has 3 + r % 8 bearings. With 3 (one degree of freedom once the offset has its
    // say) there is no noise to estimate and no chance check to pass: refused. From 8 on an
    // emitter is reported in every run; its F-scaled coverage is asserted with the others.
    let config = LocateConfig::default();
    let mut by_n = [(0usize, 0usize); 8];
    for run in 0..RUNS {
        let d = simulate(Condition::FewBearings, run);
        let r = run_locate(&d, &config, BiasPrior::default(), run as u64).ok();
        let j = judge(&d, r.as_ref().map(|r| &r.report), BiasPrior::default());
        by_n[run % 8].0 += 1;
        by_n[run % 8].1 += j[0].found as usize;
    }
    let shown_n: Vec<String> = by_n
        .iter()
        .enumerate()
        .map(|(k, (runs, found))| format!("n {}: {found}/{runs}", k + 3))
        .collect();
    println!("few bearings, emitters reported: {shown_n:?}");
    assert_eq!(by_n[0].1, 0, "{shown_n:?}");
    for (runs, found) in &by_n[5..] {
        assert!(found == runs, "{shown_n:?}");
    }
}

#[test]
fn wild_bearings_stay_within_1_3_of_the_bound() {
    // Issue bar: the robust fix within 1.3x its CRLB, on aoa-afsa-wild and on a drive with
    // 15 % wild bearings and 2 degree noise. With the default offset prior the bound is the
    // bias-aware one; with a calibrated unit, the plain CRLB.
    for c in [Condition::AoaAfsaWild, Condition::Wild15] {
        let e = &summary(c).per_emitter[0];
        assert!(
            e.ratio() <= 1.3,
            "{}: {:.2}{}",
            c.name(),
            e.ratio(),
            shown()
        );
        let cal = measure(c, RUNS, &LocateConfig::default(), calibrated());
        let ce = &cal.per_emitter[0];
        assert!(ce.ratio() <= 1.3, "calibrated {cal}");
        assert!((0.90..=0.98).contains(&ce.coverage()), "calibrated {cal}");
        println!("calibrated {cal}");
    }
}

#[test]
fn clean_accuracy_is_unchanged() {
    // Issue 2's bar: ML within 1.05x the CRLB on aoa-afsa and aoa-drive, over the bench's own
    // 100 runs (observed 1.036 and 1.019). The pipeline with a calibrated unit is the same
    // Gaussian ML once nothing is trimmed, and must meet the same bar on the same runs.
    let cal = calibrated();
    for c in [Condition::AoaAfsa, Condition::AoaDrive] {
        let (mut plain, mut pipeline, mut bound) = (0.0f64, 0.0f64, 0.0f64);
        for run in 0..100 {
            let d = simulate(c, run);
            let t = d.emitters[0].position;
            let bs: Vec<Bearing> = d.observations.iter().map(|o| o.bearing).collect();
            let f = ml(&bs, None, &Gaussian, MlOptions::default()).expect("ML fix");
            let r = run_locate(&d, &LocateConfig::default(), cal, run as u64).expect("pipeline");
            let e = r.emitters().first().expect("an emitter");
            let geometry: Vec<Bearing> = bs
                .iter()
                .map(|b| Bearing {
                    theta: predicted(&t, &b.vehicle),
                    sigma: d.sigma,
                    ..*b
                })
                .collect();
            let crlb = foxhunt_core::fix::crlb::crlb(&t, &geometry).expect("bound");
            bound += (crlb.rmse as f64).powi(2);
            plain += ((f.position[0] - t[0]).hypot(f.position[1] - t[1]) as f64).powi(2);
            pipeline += ((e.position[0] - t[0]).hypot(e.position[1] - t[1]) as f64).powi(2);
        }
        let (plain, pipeline) = ((plain / bound).sqrt(), (pipeline / bound).sqrt());
        assert!(plain <= 1.05, "{}: ML ratio {plain:.3}", c.name());
        assert!(
            pipeline <= 1.05,
            "{}: pipeline ratio {pipeline:.3}",
            c.name()
        );
        println!(
            "{}: ML {plain:.3}, calibrated pipeline {pipeline:.3} x CRLB",
            c.name()
        );
    }
}

/// A SIR with `N` particles over a drive's bearings: its estimate and cloud check.
fn sir_run(d: &FieldDrive, seed: u64) -> (foxhunt_core::Estimate<2>, bool, f32) {
    let bs: Vec<Bearing> = d.observations.iter().map(|o| o.bearing).collect();
    let mut rng = XorShiftRng::seed_from_u64(seed);
    let mut cloud = Box::new(ParticleSet::<1000, 2>::new());
    initial_particles(&bs, MIN_CROSSING, &mut cloud, &mut rng).expect("cloud");
    let mut f = Box::new(Sir::<_, _, 1000, 2>::new(
        StaticEmitter { process_var: 0.0 },
        Gaussian,
        SirConfig::default(),
    ));
    f.initialise(&cloud.states, &mut rng).expect("initialised");
    for b in &bs {
        let _ = f.step(b, &mut rng);
    }
    let e = f.estimate().expect("initialised");
    let t = d.emitters[0].position;
    let m = mahalanobis(&e.covariance, &e.mean, &t).unwrap_or(f32::INFINITY);
    let check = check_cloud(f.particles(), &bs).expect("cloud check");
    (e, check.collapsed, m)
}

#[test]
fn the_sir_reaches_a_distant_emitter() {
    // Before: a 10 km emitter on L600 came out 11-13 km off with an 8 m CEP50 (a cloud drawn
    // round the PLE never reached it). Now the cloud is spread along the bearings, log-uniform
    // in range, and the SIR's own 95 % ellipse holds the truth in most runs (observed 39 of
    // 40; the bar of 34 is 85 %, below the nominal 95 % since the SIR's weighted covariance
    // of 1000 particles, not an F-scaled one, makes the ellipse).
    let mut inside = 0;
    let mut lines = Vec::new();
    for run in 0..40 {
        let d = simulate(Condition::Distant, run);
        let (e, collapsed, m) = sir_run(&d, run as u64);
        inside += (m * m <= 5.991) as u32;
        let t = d.emitters[0].position;
        lines.push(format!(
            "run {run}: {:.0} m off, {m:.1} sd{}",
            (e.mean[0] - t[0]).hypot(e.mean[1] - t[1]),
            if collapsed { ", flagged collapsed" } else { "" }
        ));
    }
    assert!(inside >= 34, "inside {inside} of 40:\n{}", lines.join("\n"));
    println!("SIR, distant emitter: inside its ellipse in {inside} of 40");
}

#[test]
fn a_collapsed_cloud_is_flagged() {
    // The standard FA-PF collapses its cloud to a handful of points (docs/src/accuracy.md); the check
    // against the CRLB at the cloud's own mean says so, and passes the tuned SIR's cloud.
    let d = simulate(Condition::AoaAfsa, 0);
    let bs: Vec<Bearing> = d.observations.iter().map(|o| o.bearing).collect();
    let mut rng = XorShiftRng::seed_from_u64(1);
    let mut cloud = Box::new(ParticleSet::<100, 2>::new());
    initial_particles(&bs, MIN_CROSSING, &mut cloud, &mut rng).expect("cloud");
    let seeds_config = SirConfig::SEEDS;
    let mut fa = Box::new(Sir::<_, _, 100, 2, Firefly>::with_swarm(
        StaticEmitter { process_var: 1.0 },
        Gaussian,
        seeds_config,
        Firefly::default(),
    ));
    fa.initialise(&cloud.states, &mut rng).expect("initialised");
    for b in &bs {
        let _ = fa.step(b, &mut rng);
    }
    let fa_check = check_cloud(fa.particles(), &bs).expect("check");
    let (_, sir_collapsed, _) = sir_run(&d, 1);
    assert!(fa_check.collapsed, "FA-PF: {fa_check:?}");
    assert!(!sir_collapsed, "the tuned SIR's cloud flagged");
    println!("FA-PF cloud: {fa_check:?}");
}

#[test]
fn the_augmented_filters_estimate_the_offset() {
    // The U drive with a 4 degree offset: the SIR over [x, y, b] and the EKF with a random
    // constant both find it, within 3 of their own sds, over 10 runs each; a SIR cloud that
    // settles confidently elsewhere (a static state's particles deplete) is flagged by the
    // cloud check against the bound at its own mean.
    let prior = BiasPrior::default();
    let mut lines = Vec::new();
    let (mut ok, mut honest) = (0, 0);
    for run in 0..10 {
        let d = simulate(Condition::Bias4, run);
        let bs: Vec<Bearing> = d.observations.iter().map(|o| o.bearing).collect();
        let t = d.emitters[0].position;
        let mut rng = XorShiftRng::seed_from_u64(run as u64);
        let mut cloud = Box::new(ParticleSet::<2000, 3>::new());
        initial_biased_particles(&bs, prior, &InitOptions::default(), &mut cloud, &mut rng)
            .expect("cloud");
        let mut sir = Box::new(Sir::<_, _, 2000, 3>::new(
            BiasedEmitter { process_var: 0.0 },
            GaussianUniform { eps: 0.05 },
            SirConfig::default(),
        ));
        sir.initialise(&cloud.states, &mut rng)
            .expect("initialised");
        for b in &bs {
            let _ = sir.step(b, &mut rng);
        }
        let s = sir.estimate().expect("initialised");
        // The EKF from the robust search's answer, with the offset's prior.
        let r = run_locate(
            &d,
            &LocateConfig::default(),
            BiasPrior::default(),
            run as u64,
        )
        .expect("pipeline");
        let start = r.emitters()[0].position;
        let mut ekf = BiasedBearingEkf::new(0.0);
        ekf.start(
            [start[0] + 50.0, start[1] - 50.0, 0.0],
            [
                [1e4, 0.0, 0.0],
                [0.0, 1e4, 0.0],
                [0.0, 0.0, prior.sd * prior.sd],
            ],
        )
        .expect("started");
        for b in &bs {
            let _ = ekf.step(b, &mut rng);
        }
        let k = ekf.estimate().expect("started");
        let within = |mean: [f32; 3], cov: [[f32; 3]; 3]| {
            let sd_b = cov[2][2].sqrt();
            let pos = mahalanobis(
                &[[cov[0][0], cov[0][1]], [cov[1][0], cov[1][1]]],
                &[mean[0], mean[1]],
                &t,
            )
            .unwrap_or(f32::INFINITY);
            (mean[2] - 4.0 * DEG).abs() <= 3.0 * sd_b && pos <= 3.5
        };
        let flagged = check_cloud(sir.particles(), &bs).expect("check").collapsed;
        let (sir_ok, ekf_ok) = (within(s.mean, s.covariance), within(k.mean, k.covariance));
        ok += (sir_ok && ekf_ok) as u32;
        honest += ((sir_ok || flagged) && ekf_ok) as u32;
        lines.push(format!(
            "run {run}: sir b {:.2} +- {:.2}{}, ekf b {:.2} +- {:.2}",
            s.mean[2] / DEG,
            s.covariance[2][2].sqrt() / DEG,
            if flagged { " (flagged collapsed)" } else { "" },
            k.mean[2] / DEG,
            k.covariance[2][2].sqrt() / DEG
        ));
    }
    // 3 sds in b and 3.5 in position hold 99 % of runs each for calibrated filters; a SIR of
    // 2000 particles over a static 3-D state is not quite that (observed 9 of 10, the tenth
    // flagged): at least 8 within, and none wrong without the flag.
    assert!(
        ok >= 8 && honest == 10,
        "{ok} within, {honest} within or flagged, of 10:\n{}",
        lines.join("\n")
    );
    println!("augmented filters:\n{}", lines.join("\n"));
}

#[test]
fn calibration_past_a_known_transmitter_measures_the_offset() {
    // 400 calibration drives past the emitter of the 4 degree condition: the offset's
    // estimates scatter with their own sd (about sigma / sqrt(240) = 0.13 degrees) round 4.
    let mut z2 = 0.0f64;
    let mut sd = 0.0f64;
    for run in 0..RUNS {
        let d = simulate(Condition::Bias4, run);
        let bs: Vec<Bearing> = d.observations.iter().map(|o| o.bearing).collect();
        let c = bias::calibrate(&bs, d.emitters[0].position).expect("calibration");
        z2 += (((c.bias - 4.0 * DEG) / c.sd) as f64).powi(2);
        sd += (c.sd / DEG) as f64;
    }
    let (rms_z, sd) = ((z2 / RUNS as f64).sqrt(), sd / RUNS as f64);
    // The normalised errors' rms is 1 for an honest sd: +-10 % (its standard error at 400
    // runs is 3.5 %).
    assert!(
        (0.9..1.1).contains(&rms_z),
        "rms z {rms_z:.3}, sd {sd:.3} deg"
    );
    assert!((sd - 2.0 / 240f64.sqrt()).abs() < 0.02, "sd {sd:.3} deg");
    println!("calibration: rms z {rms_z:.3}, mean sd {sd:.3} deg");
}

#[test]
fn an_hour_at_20_bearings_a_second_does_not_stall() {
    // 72 000 bearings (a 36 km square round the emitter at 10 m/s, 20 a second): the initial
    // cloud and the whole pipeline finish with their capped work and find the emitter.
    let e = [4500.0f32, 4500.0];
    let mut rng = XorShiftRng::seed_from_u64(72);
    let n = 72_000;
    let observations: Vec<Observation> = (0..n)
        .map(|k| {
            let s = 36_000.0 * k as f32 / n as f32;
            let side = (s / 9000.0) as usize;
            let along = s - 9000.0 * side as f32;
            let v = match side {
                0 => [along, 0.0],
                1 => [9000.0, along],
                2 => [9000.0 - along, 9000.0],
                _ => [0.0, 9000.0 - along],
            };
            let b = Bearing {
                vehicle: v,
                theta: wrap(predicted(&e, &v) + 2.0 * DEG * random::normal(&mut rng)),
                sigma: 2.0 * DEG,
            };
            Observation::new(b, k as f32 / 20.0)
        })
        .collect();
    let started = std::time::Instant::now();
    let bs: Vec<Bearing> = observations.iter().map(|o| o.bearing).collect();
    let mut cloud = Box::new(ParticleSet::<1000, 2>::new());
    initial_particles(&bs, MIN_CROSSING, &mut cloud, &mut rng).expect("cloud");
    let cloud_time = started.elapsed();
    let d = FieldDrive {
        observations,
        emitters: Vec::new(),
        ghost: None,
        bias: 0.0,
        sigma: 2.0 * DEG,
        stations: Vec::new(),
    };
    let r = run_locate(&d, &LocateConfig::default(), BiasPrior::default(), 1).expect("pipeline");
    let total = started.elapsed();
    let f = r.emitters().first().expect("an emitter");
    let err = (f.position[0] - e[0]).hypot(f.position[1] - e[1]);
    // The bound with 72 000 bearings is centimetres; 3 m allows for f32 sums over them.
    assert!(
        err < 3.0,
        "{err:.2} m off (initial cloud {cloud_time:?}, whole locate {total:?})"
    );
    println!("72 000 bearings: initial cloud {cloud_time:?}, cloud + locate {total:?}");
}

#[test]
fn the_long_drives_need_the_convergence_turned_out() {
    // What the bridge's meridian convergence is for: at 70 N the uncorrected bearings put the
    // fix further off than the corrected ones (the offset estimate absorbs part of it).
    let corrected = &summary(Condition::Long70).per_emitter[0];
    let raw = &summary(Condition::Long70Uncorrected).per_emitter[0];
    assert!(raw.rmse > corrected.rmse, "{}", shown());
}

#[test]
fn field_drives_written_as_bytes_locate_as_the_bearings_do() {
    // The multipath and two-emitter drives through the bytes a DF unit and its GPS send:
    // the command finds what the pipeline finds on the bearings (the ghost as another source,
    // one emitter per frequency), each emitter inside its own ellipse.
    use foxhunt_bridge::nmea::LatLon;
    use foxhunt_sim::inputs::capture::decode;
    use foxhunt_sim::locate::{LocateOptions, locate};
    let origin = LatLon {
        lat: 47.0,
        lon: 8.0,
    };
    for (c, emitters, others) in [(Condition::Multipath, 1, 1), (Condition::TwoEmitters, 2, 0)] {
        let (bytes, truths) = foxhunt_sim::runs::field::capture(c, 0, origin).expect("capture");
        let d = decode(&bytes, Default::default(), false);
        let l = locate(&d, &LocateOptions::default()).expect("a fix");
        let r = &l.report;
        assert_eq!(r.emitters.len(), emitters, "{}: {:?}", c.name(), r.emitters);
        assert!(
            r.other_sources.len() >= others,
            "{}: {:?}",
            c.name(),
            r.other_sources
        );
        for t in &truths {
            // The emitter of the truth's channel (433.920 MHz stands for "no frequency").
            let f = t.freq_mhz.unwrap_or(433.92);
            let i = r
                .emitters
                .iter()
                .position(|e| e.freq_mhz.is_some_and(|g| (g - f).abs() < 0.01))
                .expect("an emitter on the truth's channel");
            let drawn = &l.drawn[i];
            assert!(
                drawn.ellipse.contains(&drawn.position, &t.position),
                "{}: truth {:?} outside the ellipse of {:?}",
                c.name(),
                t.position,
                drawn
            );
        }
    }
}

/// Share of runs (of `drives`) with an emitter, and of those the share whose ellipse holds the
/// truth.
fn found_and_held(drives: impl Iterator<Item = (FieldDrive, u64)>) -> (usize, usize, usize) {
    let config = LocateConfig::default();
    let (mut runs, mut found, mut held) = (0, 0, 0);
    for (d, seed) in drives {
        let r = run_locate(&d, &config, BiasPrior::default(), seed).ok();
        let emitters = r.as_ref().map_or(0, |r| r.emitters().len());
        runs += 1;
        found += usize::from(emitters > 0);
        if let Some(j) = judge(&d, r.as_ref().map(|r| &r.report), BiasPrior::default()).first() {
            held += usize::from(j.covered);
        }
    }
    (runs, found, held)
}

#[test]
fn an_unmodelled_error_is_what_holds_the_truth_under_a_systematic_error() {
    // systematic-0.2-1deg: a calibrated unit whose offset has since moved by 0.2-1 degree,
    // 1800 bearings. Its honesty with the stated unmodelled error is asserted with every
    // condition's; here the same runs with the floor taken out (the stations file stating 0)
    // show what it is for: the ellipse shrinks to the noise's 3 / sqrt(1800) degrees and the
    // truth, moved by r times the residue, lies outside in most runs (observed: 27.3 %
    // coverage, 94.5 % with it). The bar, under 50 %, is far from both.
    let with = &summary(Condition::Systematic).per_emitter[0];
    let drives = (0..RUNS).map(|run| {
        let mut d = simulate(Condition::Systematic, run);
        for s in &mut d.stations {
            s.unmodelled = Some(0.0);
        }
        (d, run as u64)
    });
    let (runs, found, held) = found_and_held(drives);
    let without = held as f64 / found.max(1) as f64;
    println!(
        "systematic-0.2-1deg: coverage {:.1} % with the unmodelled error stated, {:.1} % \
         without ({found} fixes of {runs} runs)",
        100.0 * with.coverage(),
        100.0 * without
    );
    assert!(without < 0.5, "without the floor: {:.1} %", 100.0 * without);
    assert!((0.90..=0.98).contains(&with.coverage()), "{}", shown());
}

/// A drive of `n` bearings along the U of `noise` (stated as the indoor-aoa class's), the
/// offset drawn from the default prior, the stations file stating the class; `bearing`
/// makes each bearing from the vehicle's position, heading and the true bearing.
fn aoa_drive(
    n: usize,
    run: usize,
    bearing: impl Fn([f32; 2], f32, f32, &mut XorShiftRng) -> f32,
) -> FieldDrive {
    use foxhunt_core::fix::device::DeviceClass;
    use foxhunt_sim::runs::field::{StationTruth, Truth, u_route};
    let mut rng = XorShiftRng::seed_from_u64(0xA0A0 + run as u64 * 7919 + n as u64);
    let class = DeviceClass::IndoorAoa.noise();
    let stated = class.noise.expect("the class states its noise");
    let emitter = [0.0f32, 1500.0];
    let offset = BiasPrior::default().sd * random::normal(&mut rng);
    let route = u_route(n.max(2));
    let observations: Vec<Observation> = route
        .iter()
        .enumerate()
        .take(n)
        .map(|(k, v)| {
            let next = route[(k + 1).min(route.len() - 1)];
            let before = route[k.saturating_sub(1)];
            let heading = (next[1] - before[1]).atan2(next[0] - before[0]);
            let truth = predicted(&emitter, v);
            let theta = wrap(bearing(*v, heading, truth, &mut rng) + offset);
            Observation::new(
                Bearing {
                    vehicle: *v,
                    theta,
                    sigma: stated,
                },
                k as f32,
            )
        })
        .collect();
    FieldDrive {
        observations,
        emitters: vec![Truth {
            position: emitter,
            freq_mhz: None,
        }],
        ghost: None,
        stations: vec![StationTruth {
            id: "aoa".into(),
            fixed: false,
            offset,
            sigma: stated,
            prior: BiasPrior::default(),
            class: Some(DeviceClass::IndoorAoa),
            unmodelled: None,
        }],
        bias: offset,
        sigma: stated,
    }
}

#[test]
fn a_noisy_class_is_a_fix_with_enough_bearings_and_pure_noise_is_not() {
    // A unit of the indoor-aoa class (ceiling 25 degrees) with 15 and 20 degree noise along
    // the U, 10 to 1000 bearings, 200 runs a cell: a fix once enough bearings back it (the
    // chance check is what asks for enough: a cluster of a few 20 degree bearings is what
    // luck gives), its ellipse F-scaled; with fewer, no fix (at most 5 %). Beside it the same
    // class's pure noise, bearings uniform on the circle or the unit's own boresight
    // (straight ahead, a unit locked on nothing) with its noise: no emitter in >= 95 % of
    // runs at every n. 200 runs give a coverage to +-1.5 %: the bar 90-98 % is three sds
    // either side of 95 %.
    const CELL: usize = 200;
    let mut table = Vec::new();
    for noise in [15.0f32, 20.0] {
        for n in [10usize, 20, 50, 200, 1000] {
            let drives = (0..CELL).map(|run| {
                let d = aoa_drive(n, run, |_, _, truth, rng| {
                    truth + noise * DEG * random::normal(rng)
                });
                (d, run as u64)
            });
            let (runs, found, held) = found_and_held(drives);
            table.push(format!(
                "{noise} deg, n {n}: a fix in {found} of {runs}, its ellipse holds the truth in \
                 {held}"
            ));
            let coverage = held as f64 / found.max(1) as f64;
            if n < 20 {
                // Too few to back a fix at this noise. The chance test judges the cluster's
                // agreement at no less than the class's stated noise: judged at their own
                // scatter, the lucky few whose scatter happened to be small passed (10
                // bearings of 15 degrees: 39 fixes in 200 runs, 27 holding the truth; of 20
                // degrees: 10, 6), their ellipses too small with them. Observed now: none.
                assert!(found * 20 <= runs, "{table:#?}");
            } else {
                // Enough bearings: a fix in nearly every run (20 bearings of 20 degrees: in
                // 183 of 200, the rest refused by the chance check), honest.
                let share = if n >= 50 { 95 } else { 85 };
                assert!(found * 100 >= runs * share, "{table:#?}");
                assert!((0.90..=0.98).contains(&coverage), "{table:#?}");
            }
        }
    }
    for (what, uniform) in [("uniform", true), ("boresight", false)] {
        for n in [10usize, 50, 200, 1000] {
            let drives = (0..CELL).map(|run| {
                let d = aoa_drive(n, run, |_, heading, _, rng| {
                    if uniform {
                        random::uniform_in(rng, -std::f32::consts::PI, std::f32::consts::PI)
                    } else {
                        heading + 13.0 * DEG * random::normal(rng)
                    }
                });
                (d, run as u64)
            });
            let (runs, found, _) = found_and_held(drives);
            table.push(format!(
                "pure noise ({what}), n {n}: a fix in {found} of {runs}"
            ));
            assert!(found * 20 <= runs, "{table:#?}");
        }
    }
    println!("{table:#?}");
}
