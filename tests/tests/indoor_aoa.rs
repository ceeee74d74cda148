//! Indoor angle of arrival (`move-indoor-aoa`, the book's tracking chapter, "Indoors"): a
//! person walking a room seen by four wall anchors with the error traits of real Bluetooth
//! 5.1 arrays (noise 10-16 degrees, per-anchor bias, compression toward boresight, 2 degree
//! steps, 37 reports a second). The default tracker against per-epoch triangulation on the
//! same seeded runs.

use foxhunt_sim::runs::moving::MovingScenario;
use foxhunt_sim::runs::moving::bench::{one, quantiles};
use foxhunt_sim::runs::moving::indoor::AoaErrors;
use foxhunt_sim::runs::moving::triangulate::triangulate;
use foxhunt_sim::track::moving::{DEFAULT_METHOD, PARTICLES};

/// Seeded runs.
const RUNS: usize = 24;

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
}

/// Each error trait off in turn (run by hand: `--ignored`), to find which one costs what.
#[test]
#[ignore]
fn each_trait_off_in_turn() {
    let base = MovingScenario::named("move-indoor-aoa").expect("scenario");
    let all = AoaErrors::ALL;
    for (label, errors) in [
        ("every trait", all),
        ("no noise", AoaErrors { noise: false, ..all }),
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
