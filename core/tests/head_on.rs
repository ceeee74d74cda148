//! Driving straight at the emitter ("homing"): the range along the line of bearing is barely
//! observed, and the field pipeline must not claim a tight fix that excludes the truth.
//!
//! The drive copies what the guidance benchmark's `homing` policy does: a first 300 m leg in
//! another direction (60 degrees off), then straight at a point half a degree beside the
//! emitter 3.5 km away, 15 m/s, one bearing a second with 4 degree noise the unit states
//! correctly (calibrated, sigmas trusted and checked, as the benchmark's pipeline runs). The
//! pipeline runs every 15 s from 30 s to 180 s (the vehicle 2.4 km down the road). Before the
//! likelihood-ratio reach ([`foxhunt_core::fix::reach`]) the fix settled on the line just in
//! front of the vehicle with a 3-60 m CEP50 while the truth was hundreds of metres to
//! kilometres further on: 10 of 40 drives made such a claim, every claim of CEP50 < 100 m wrong.

use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::locate::{
    ChannelOutcome, LocateConfig, NoiseModel, Observation, Workspace, locate,
};
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::random;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::f32::consts::PI;

const DEG: f32 = PI / 180.0;
const EMITTER: [f32; 2] = [0.0, 3500.0];
const DRIVES: u64 = 40;

/// One seeded head-on drive of 180 bearings.
fn drive(seed: u64) -> Vec<Observation> {
    let mut rng = XorShiftRng::seed_from_u64(seed);
    let first = 60.0 * DEG;
    let turn = [300.0 * first.sin(), 300.0 * first.cos()];
    let heading = (EMITTER[1] - turn[1]).atan2(EMITTER[0] - turn[0]) + 0.5 * DEG;
    (0..180)
        .map(|k| {
            let t = k as f32;
            let v = if t < 20.0 {
                [15.0 * t * first.sin(), 15.0 * t * first.cos()]
            } else {
                let s = 15.0 * (t - 20.0);
                [turn[0] + s * heading.cos(), turn[1] + s * heading.sin()]
            };
            let theta = predicted(&EMITTER, &v) + 4.0 * DEG * random::normal(&mut rng);
            Observation::new(
                Bearing {
                    vehicle: v,
                    theta: wrap(theta),
                    sigma: 4.0 * DEG,
                },
                t,
            )
        })
        .collect()
}

#[test]
fn driving_at_the_emitter_makes_no_confident_wrong_claim() {
    let config = LocateConfig {
        noise: NoiseModel::Known,
        ..LocateConfig::default()
    };
    let (mut wrong_drives, mut fixes, mut inside, mut unobservable, mut claims) = (0, 0, 0, 0, 0);
    let (mut region_held, mut parallel) = (0, 0);
    for seed in 0..DRIVES {
        let o = drive(seed);
        let mut wrong = false;
        for n in (30..=180).step_by(15) {
            let mut work = Workspace::<180, 1>::with_prior(BiasPrior::calibrated(0.0));
            let mut rng = XorShiftRng::seed_from_u64(n as u64);
            let report = locate::<1, 1, _>(&o[..n], &config, work.buffers(), &mut rng)
                .expect("valid settings");
            match report.channels()[0].outcome {
                ChannelOutcome::Emitter(i) => {
                    let e = report.emitters()[i];
                    assert!(e.cep50.is_finite() && e.stretch >= 1.0, "{e:?}");
                    let holds = e.ellipse.contains(&e.position, &EMITTER);
                    fixes += 1;
                    inside += holds as u32;
                    if e.cep50 < 100.0 {
                        claims += 1;
                        wrong |= !holds;
                    }
                }
                // The range unobservable: not a fix, but the line of bearing and the range
                // interval the bearings allow.
                ChannelOutcome::Region(i) => {
                    let r = report.regions()[i];
                    unobservable += 1;
                    region_held += r.contains(&EMITTER) as u32;
                    parallel += r.parallel as u32;
                }
                ChannelOutcome::NoConsistentEmitter(_) => {}
            }
        }
        wrong_drives += wrong as u32;
    }
    let coverage = inside as f32 / fixes.max(1) as f32;
    println!(
        "{wrong_drives} of {DRIVES} drives claimed CEP50 < 100 m with the truth outside ({claims} \
         claims); {fixes} fixes, 95 % ellipse held the truth in {:.1} %; range unobservable {unobservable} times, \
         the 95 % region held the truth in {:.1} %",
        100.0 * coverage,
        100.0 * region_held as f32 / unobservable.max(1) as f32
    );
    // An honest 95 % region misses 5 % of the time, and a drive makes up to 11 checks: 4 of 40
    // (10 %) leaves room for that; the unfixed pipeline had 10 of 40.
    assert!(
        wrong_drives <= 4,
        "{wrong_drives} of {DRIVES} drives claimed a wrong tight fix"
    );
    // Every reported ellipse, tight or not: ~95 % should hold the truth; 85 % allows for the
    // checks of one drive being strongly correlated (about 40 independent draws: 2 sd of a 95 %
    // share is 7 points). The unfixed pipeline held it in 94 % of 436 fixes, its misses the tight ones.
    assert!(
        coverage >= 0.85,
        "coverage {:.1} % of {fixes} fixes",
        100.0 * coverage
    );
    // Most checkpoints of such a drive have no range at all: the state must say so.
    assert!(
        unobservable > 100,
        "range unobservable only {unobservable} times"
    );
    // Each region should hold the truth 95 % of the time; the same 85 % floor as the ellipses
    // (a drive's checkpoints share its bearings: about 40 independent draws).
    let region_coverage = region_held as f32 / unobservable as f32;
    assert!(
        region_coverage >= 0.85,
        "regions held the truth in {:.1} % of {unobservable}",
        100.0 * region_coverage
    );
    // 4 degree noise: the bearings cross (at random), never parallel.
    assert_eq!(parallel, 0, "{parallel} regions called parallel");
}
