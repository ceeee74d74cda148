//! Indoor angle of arrival (`move-indoor-aoa`, the book's tracking chapter, "Indoors"): a
//! person walking a room seen by four wall anchors with the error traits of real Bluetooth
//! 5.1 arrays (noise 10-16 degrees, per-anchor bias, compression toward boresight, 2 degree
//! steps, 37 reports a second). The default tracker against per-epoch triangulation on the
//! same seeded runs.
//!
//! Figures, over the updates after the 3 s warm-up of RUNS seeded runs: each method's median
//! and 90th percentile error, their ratio, and the tracker's time-averaged 95 % coverage.
//! Measured (ci profile, 40 runs, the default 10 000 particles): tracker median 0.50 m, p90
//! 1.19 m, coverage 0.957; triangulation median 1.37 m, p90 2.79 m; ratio 0.37 (at 1 000
//! particles: 0.58 m, 1.42 m, 0.940, ratio 0.42).
//!
//! Bars, and why: the promise is a median at most 0.75 of the triangulation's (25 % better)
//! with coverage in 0.90-0.98; the runs are seeded, so the figures are fixed, and they sit
//! well inside the ratio bar and 0.04 inside the coverage band (about 1.5 standard errors of
//! the time-averaged coverage over 40 runs, whose per-run figures spread by about 0.15): the
//! band asserted is the promised one, failing when a change makes the ellipses overconfident
//! or far too wide. The triangulation's median is held to 0.9-1.8 m, around the 1.07 m it
//! gives on the real arrays, so that the scenario stays as hard as the data it stands for.

use foxhunt_sim::runs::moving::MovingScenario;
use foxhunt_sim::runs::moving::bench::{one, quantiles};
use foxhunt_sim::runs::moving::indoor::AoaErrors;
use foxhunt_sim::runs::moving::triangulate::triangulate;
use foxhunt_sim::track::moving::{DEFAULT_METHOD, PARTICLES};

/// Seeded runs.
const RUNS: usize = 40;

/// What the runs gave.
struct Figures {
    tracker: (f32, f32),
    coverage: f64,
    triangulation: (f32, f32),
    triangulation_coverage: f64,
}

fn measure(s: &MovingScenario, runs: usize) -> Figures {
    let per_run = |run: usize| {
        let f = one(s, DEFAULT_METHOD, PARTICLES, false, run).expect("track");
        let (t, _) = triangulate(&s.simulate(run), s.warmup_s);
        (f, t)
    };
    let all: Vec<_> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..2)
            .map(|half| {
                scope.spawn(move || {
                    (0..runs)
                        .filter(|r| r % 2 == half)
                        .map(per_run)
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().expect("runs"))
            .collect()
    });
    let tracked: Vec<f32> = all.iter().flat_map(|(f, _)| f.errors.clone()).collect();
    let triangulated: Vec<f32> = all.iter().flat_map(|(_, t)| t.errors.clone()).collect();
    let share = |c: &mut dyn Iterator<Item = bool>| {
        let (mut yes, mut n) = (0usize, 0usize);
        for b in c {
            yes += usize::from(b);
            n += 1;
        }
        yes as f64 / n.max(1) as f64
    };
    Figures {
        tracker: quantiles(&tracked),
        coverage: share(&mut all.iter().flat_map(|(f, _)| f.covered.iter().copied())),
        triangulation: quantiles(&triangulated),
        triangulation_coverage: share(&mut all.iter().flat_map(|(_, t)| t.covered.iter().copied())),
    }
}

fn report(label: &str, f: &Figures) {
    println!(
        "{label}: tracker median {:.2} m, p90 {:.2} m, coverage {:.3}; triangulation median \
         {:.2} m, p90 {:.2} m, coverage {:.3}; median ratio {:.2}",
        f.tracker.0,
        f.tracker.1,
        f.coverage,
        f.triangulation.0,
        f.triangulation.1,
        f.triangulation_coverage,
        f.tracker.0 / f.triangulation.0
    );
}

#[test]
fn the_tracker_against_per_epoch_triangulation() {
    let s = MovingScenario::named("move-indoor-aoa").expect("scenario");
    let f = measure(&s, RUNS);
    report("every trait", &f);
    let ratio = f.tracker.0 / f.triangulation.0;
    assert!(
        ratio <= 0.75,
        "tracker median {:.2} m is {ratio:.2} of the triangulation's, above 0.75",
        f.tracker.0
    );
    assert!(
        (0.90..=0.98).contains(&f.coverage),
        "coverage {:.3} outside 0.90-0.98",
        f.coverage
    );
    assert!(
        (0.9..=1.8).contains(&f.triangulation.0),
        "triangulation median {:.2} m outside 0.9-1.8 m",
        f.triangulation.0
    );
}

/// Each error trait off in turn (run by hand: `--ignored`), to find which one costs what.
#[test]
#[ignore]
fn each_trait_off_in_turn() {
    let base = MovingScenario::named("move-indoor-aoa").expect("scenario");
    let all = AoaErrors::ALL;
    for (label, errors) in [
        ("every trait", all),
        (
            "no noise",
            AoaErrors {
                noise: false,
                ..all
            },
        ),
        ("no bias", AoaErrors { bias: false, ..all }),
        (
            "no compression",
            AoaErrors {
                compression: false,
                ..all
            },
        ),
        (
            "no quantisation",
            AoaErrors {
                quantise: false,
                ..all
            },
        ),
    ] {
        let s = MovingScenario {
            aoa: Some(errors),
            ..base.clone()
        };
        report(label, &measure(&s, RUNS));
    }
}
