//! The static-emitter figures, reproduced on the canonical scenarios with the bench's own
//! seeded Monte Carlo runs (100 runs, seed 1: the same rows `foxhunt bench` prints, so every
//! figure here can be rerun from the command line).
//!
//! Tolerances: with 100 runs, rmse is known to about +-7 % (the relative standard error of a
//! root mean square of 100 two-dimensional errors is 1/sqrt(2 * 200)); the runs are seeded, so
//! each figure is deterministic. Each assertion prints the observed figure.

use foxhunt_core::Method;
use foxhunt_sim::runs::run::bearing_run;
use foxhunt_sim::runs::scenario::Scenario;
use foxhunt_tests::{error, ratio, row, table};

#[test]
fn ml_fix_reaches_the_crlb() {
    // The bar: rmse / CRLB <= 1.05 on aoa-afsa and aoa-drive.
    for name in ["aoa-afsa", "aoa-drive"] {
        let rows = table(name, &[Method::Ml], None);
        assert_eq!(row(&rows, "ml").failures, 0, "{name}");
        let r = ratio(&rows, "ml");
        assert!(r <= 1.05, "{name}: ML ratio {r}");
    }
}

#[test]
fn tuned_sir_closes_the_gap_of_the_plain_sir() {
    let rows = table(
        "aoa-afsa",
        &[Method::SirSeed, Method::Sir, Method::Gpf],
        None,
    );
    let (plain, tuned, gpf) = (
        ratio(&rows, "sir-seed"),
        ratio(&rows, "sir"),
        ratio(&rows, "gpf"),
    );
    // The bar for the best sequential filter at N = 100: <= 1.3.
    assert!(tuned <= 1.3, "tuned SIR ratio {tuned}");
    // The GPF trails it: 1.29 over 400 runs (`foxhunt bench --runs 400`); 1.6 is that figure
    // plus three standard errors of a 100-run ratio (7 % each).
    assert!(gpf <= 1.6, "GPF ratio {gpf}");
    // The seeds' fixed-jitter SIR forgets old bearings and sits near 2x: the gap is real, not a
    // weakened baseline (1.5-2.2 is that figure +-3 standard errors and more).
    assert!((1.5..2.2).contains(&plain), "plain SIR ratio {plain}");
}

#[test]
fn robust_fixes_survive_wild_bearings() {
    let methods = [Method::Ml, Method::MlHuber, Method::SirRobust];
    let clean = table("aoa-afsa", &methods, None);
    let wild = table("aoa-afsa-wild", &methods, None);
    let (huber_clean, huber_wild) = (error(&clean, "ml-huber"), error(&wild, "ml-huber"));
    // The bar: the robust ML stays within 1.3x of its clean rmse.
    assert!(
        huber_wild <= 1.3 * huber_clean,
        "Huber ML: {huber_wild} wild vs {huber_clean} clean ({:.3}x)",
        huber_wild / huber_clean
    );
    // The Gaussian ML beside it is ruined (tens of times its clean error; 5x leaves room):
    // the robust loss is doing the work.
    let (gauss_clean, gauss_wild) = (error(&clean, "ml"), error(&wild, "ml"));
    assert!(
        gauss_wild > 5.0 * gauss_clean,
        "Gaussian ML {gauss_wild} wild vs {gauss_clean} clean"
    );
    // The Gaussian + uniform SIR stays near the bound.
    let sir = ratio(&wild, "sir-robust");
    assert!(sir <= 1.3, "sir-robust ratio {sir}");
}

#[test]
fn bias_compensation_removes_the_ple_bias_on_a_drive() {
    let rows = table(
        "aoa-drive",
        &[Method::Ple, Method::BcPle, Method::Wiv],
        None,
    );
    let (ple, bc, wiv) = (
        ratio(&rows, "ple"),
        ratio(&rows, "bc-ple"),
        ratio(&rows, "wiv"),
    );
    // On the L-shaped drive the PLE is pulled toward the vehicle (over 2x the CRLB); the
    // compensated PLE and the WIV are not (1.2 and 1.1: near the bound, +3 standard errors).
    assert!(ple > 1.8, "PLE {ple}");
    assert!(bc < 0.6 * ple && bc <= 1.2, "BC-PLE {bc} (PLE {ple})");
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
    assert!(files > 10, "{files} files");
}

#[test]
fn same_seed_same_result_bit_for_bit() {
    let s = Scenario::named("aoa-afsa").expect("scenario");
    let d = s.drive().expect("a drive");
    for m in [
        Method::Sir,
        Method::SirRobust,
        Method::Gpf,
        Method::Ekf,
        Method::Ml,
    ] {
        let once = |run| {
            bearing_run(d, m, 100, &mut s.rng(run))
                .map(|f| f.position.map(f32::to_bits))
                .map_err(|e| e.to_string())
        };
        assert_eq!(once(3), once(3), "{m}");
        assert_ne!(once(3), once(4), "{m}: runs differ");
    }
}
