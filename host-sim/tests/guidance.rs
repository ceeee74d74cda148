//! The closed-loop guidance benchmark at a CI size (the book's figures come from
//! `foxhunt bench --scenario guidance`, 100 runs per row).

use foxhunt_sim::runs::guidance::bench::{Row, Set, measure, rows};
use foxhunt_sim::runs::guidance::networks::Network;
use foxhunt_sim::runs::montecarlo::Progress;

const RUNS: usize = 30;

/// The median distance to the goal of policy `m` (infinite if not reached).
fn distance_km(r: &[Row], m: &str) -> f64 {
    r.iter()
        .find(|x| x.method == m)
        .and_then(|x| x.distance_km)
        .unwrap_or(f64::INFINITY)
}

#[test]
fn open_terrain_guided_policies_need_well_under_homings_distance() {
    let set = Set {
        network: Network::Open,
        offset: false,
    };
    let r = rows(&measure(&[set], RUNS, 1, &Progress::new(0, false)));
    let distance = |m: &str| distance_km(&r, m);
    let homing = distance("homing");
    let best = ["perpendicular", "greedy-d", "greedy-a", "lookahead"]
        .iter()
        .map(|m| distance(m))
        .fold(f64::INFINITY, f64::min);
    // The bar is 0.7x; 100 runs give 0.55x (2.18 against 3.97 km). The median of 30
    // runs moves by about a check interval (75 m) either way, well inside the margin.
    assert!(
        best <= 0.7 * homing,
        "best guided {best} km against homing {homing} km"
    );
    for x in &r {
        assert_eq!(x.runs, RUNS);
        assert!(x.reached > 0.8, "{x:?}");
    }
}

#[test]
fn with_an_unknown_offset_the_final_ellipse_still_holds_the_truth() {
    let set = Set {
        network: Network::Open,
        offset: true,
    };
    let r = rows(&measure(&[set], RUNS, 1, &Progress::new(0, false)));
    let look = r.iter().find(|x| x.method == "lookahead").unwrap();
    // The bar is 90 %; at 100 runs every policy's final ellipse holds the truth in 99-100 %.
    // With 30 runs, 90 % is 3 misses: a 95 % ellipse misses more than that in 18 % of sets of
    // 30, so the test asks for the 95 % ellipse's own share less two sd (95 - 8 = 87 %).
    assert!(look.final_inside >= 0.87, "{look:?}");
    // The offset limits the fix at some decisions, and the advice says so.
    assert!(look.calibration_advice > 0.1, "{look:?}");
    assert_eq!(look.scenario, "guidance/open-offset4");
}

#[test]
fn on_the_highway_the_road_aware_look_ahead_beats_greedy_forced_onto_roads() {
    let set = Set {
        network: Network::Highway,
        offset: false,
    };
    let r = rows(&measure(&[set], RUNS, 1, &Progress::new(0, false)));
    let distance = |m: &str| distance_km(&r, m);
    let (look, greedy) = (distance("lookahead"), distance("greedy-d"));
    println!("highway, {RUNS} runs: lookahead {look} km, greedy-d {greedy} km");
    // 100 runs give 2.25 against 2.77 km (the look-ahead shorter in 67 paired runs, longer in
    // 7). The highway is where the two tied (3.30 km both) while the planner counted seconds
    // and the first move was taken blind. A 30-run median moves by about two checks (300 m at
    // 30 m/s), so the test asks for a strict win, not the 100-run margin.
    assert!(
        look < greedy,
        "lookahead {look} km against greedy-d forced onto roads {greedy} km"
    );
}
