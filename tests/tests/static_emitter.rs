//! The static-emitter figures the core issue must show, reproduced on the canonical scenarios
//! with the bench's own seeded Monte Carlo runs (100 runs, seed 1: the same rows
//! `foxhunt bench` prints, so every figure here can be rerun from the command line).
//!
//! Tolerances: with 100 runs, rmse is known to about +-7 % (the relative standard error of a
//! root mean square of 100 two-dimensional errors is 1/sqrt(2 * 200)); the runs are seeded, so
//! each figure is deterministic, and the margins below are what separates the asserted bar from
//! the observed figure.

use foxhunt_sim::methods::Method;
use foxhunt_sim::montecarlo::{Row, bench};
use foxhunt_sim::scenario::Scenario;

fn run(name: &str, methods: &[Method]) -> Vec<Row> {
    let s = Scenario::named(name).expect("canonical scenario");
    bench(&s, methods, false)
}

fn row(rows: &[Row], m: Method) -> &Row {
    rows.iter().find(|r| r.method == m.name()).expect("row")
}

#[test]
fn ml_fix_reaches_the_crlb() {
    // Issue bar: rmse / CRLB <= 1.05 on aoa-afsa and aoa-drive (observed 0.95 and 0.90).
    for name in ["aoa-afsa", "aoa-drive"] {
        let rows = run(name, &[Method::Ml]);
        let r = row(&rows, Method::Ml);
        assert_eq!(r.failures, 0, "{name}");
        assert!(r.ratio <= 1.05, "{name}: ML ratio {}", r.ratio);
    }
}

#[test]
fn tuned_sir_closes_the_gap_of_the_plain_sir() {
    let rows = run("aoa-afsa", &[Method::SirSeed, Method::Sir, Method::Gpf]);
    let plain = row(&rows, Method::SirSeed).ratio;
    let tuned = row(&rows, Method::Sir).ratio;
    let gpf = row(&rows, Method::Gpf).ratio;
    // Issue bar for the best sequential filter at N = 100: <= 1.3 (observed 1.06).
    assert!(tuned <= 1.3, "tuned SIR ratio {tuned}");
    // The GPF trails it: 1.29 over 400 runs (`foxhunt bench --runs 400`), 1.40 on these 100;
    // 1.6 is that 400-run figure plus three standard errors of a 100-run ratio (7 % each).
    assert!(gpf <= 1.6, "GPF ratio {gpf}");
    // The seeds' fixed-jitter SIR sits near 1.8 (observed 1.75): the gap is real, not a
    // weakened baseline.
    assert!((1.5..2.2).contains(&plain), "plain SIR ratio {plain}");
}

#[test]
fn robust_fixes_survive_wild_bearings() {
    let methods = [Method::Ml, Method::MlHuber, Method::SirRobust];
    let clean = run("aoa-afsa", &methods);
    let wild = run("aoa-afsa-wild", &methods);
    let huber_clean = row(&clean, Method::MlHuber).rmse;
    let huber_wild = row(&wild, Method::MlHuber).rmse;
    // Issue bar: the robust ML stays within 1.3x of its clean rmse (observed 1.17x).
    assert!(
        huber_wild <= 1.3 * huber_clean,
        "Huber ML: {huber_wild} wild vs {huber_clean} clean"
    );
    // The Gaussian ML beside it is ruined (observed 33x): the robust loss is doing the work.
    let gauss_wild = row(&wild, Method::Ml).rmse;
    assert!(
        gauss_wild > 5.0 * row(&clean, Method::Ml).rmse,
        "Gaussian ML {gauss_wild}"
    );
    // The Gaussian + uniform SIR stays at the bound (observed 0.99).
    assert!(row(&wild, Method::SirRobust).ratio <= 1.3);
}

#[test]
fn bias_compensation_removes_the_ple_bias_on_a_drive() {
    let rows = run("aoa-drive", &[Method::Ple, Method::BcPle, Method::Wiv]);
    let ple = row(&rows, Method::Ple).ratio;
    let bc = row(&rows, Method::BcPle).ratio;
    let wiv = row(&rows, Method::Wiv).ratio;
    // On the L-shaped drive the PLE is pulled toward the vehicle (observed 2.5x the CRLB); the
    // compensated PLE (1.0x) and the WIV (0.9x) are not.
    assert!(ple > 1.8, "PLE {ple}");
    assert!(bc < 0.6 * ple && bc <= 1.2, "BC-PLE {bc}");
    assert!(wiv <= 1.1, "WIV {wiv}");
}

#[test]
fn the_core_holds_no_allocator() {
    // The MCU cross-build (in .ci/run) proves it links without one; this guards the source.
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../core/src");
    let mut stack = vec![dir];
    let mut files = 0;
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("core/src") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let text = std::fs::read_to_string(&p).expect("source");
                assert!(!text.contains("extern crate alloc"), "{}", p.display());
                assert!(!text.contains("alloc::"), "{}", p.display());
                files += 1;
            }
        }
    }
    assert!(files > 10);
}

#[test]
fn same_seed_same_result_bit_for_bit() {
    let s = Scenario::named("aoa-afsa").expect("scenario");
    for m in [
        Method::Sir,
        Method::SirRobust,
        Method::Gpf,
        Method::Ekf,
        Method::Ml,
    ] {
        let once = |run| {
            let mut rng = s.rng(run);
            let bearings = s.simulate(&mut rng);
            m.run(&s, &bearings, &mut rng).map(|p| p.map(f32::to_bits))
        };
        assert_eq!(once(3), once(3), "{}", m.name());
        assert_ne!(once(3), once(4), "{}: runs differ", m.name());
    }
}
