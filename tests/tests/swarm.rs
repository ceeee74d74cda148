//! The swarm issue's reproductions: each paper's table, the ordering we actually observe (not
//! the paper's where they differ), on reduced run counts, plus the static memory budgets.
//!
//! Tolerances: each assertion compares methods whose observed figures on the full run count
//! differ by 1.5x or more; with 30 seeded runs the sampling error of an rmse is about +-13 %, so
//! the factors below cannot flip by chance, and the runs are seeded, so they are repeatable.

use foxhunt_core::{
    Afsa, BearingEkf, Firefly, Gaussian, Gpf, Gsa, ImprovedFirefly, Pso, RssiTracker, Sir,
    StaticEmitter, Ungm,
};
use foxhunt_sim::methods::Method;
use foxhunt_sim::montecarlo::{Row, bench};
use foxhunt_sim::scenario::Scenario;
use foxhunt_sim::tracking::{self, Tracking};
use std::mem::size_of;

fn rows(name: &str, methods: &[Method], runs: usize) -> Vec<Row> {
    let mut s = Scenario::named(name).expect("scenario");
    s.runs = runs;
    bench(&s, methods, false)
}

fn get<'a>(rows: &'a [Row], method: &str) -> &'a Row {
    rows.iter().find(|r| r.method == method).expect("row")
}

#[test]
fn aoa_afsa_table() {
    let r = rows(
        "aoa-afsa",
        &[Method::SirSeed, Method::Sir, Method::AfsaPf, Method::Ml],
        30,
    );
    let (seed, tuned, afsa) = (get(&r, "sir-seed"), get(&r, "sir"), get(&r, "afsa-pf"));
    // Observed (100 runs): seed SIR 1.75x CRLB, AFSA-PF 1.90x, tuned SIR 1.01x, and the SIR
    // given AFSA's likelihood budget 0.96x. The fish swarm does not beat a tuned plain filter.
    assert!(
        afsa.ratio > 1.3 * tuned.ratio,
        "afsa {} tuned {}",
        afsa.ratio,
        tuned.ratio
    );
    assert!(seed.ratio > 1.3 * tuned.ratio);
    let equal = get(&r, "sir=afsa-pf");
    assert!(equal.ratio < afsa.ratio / 1.3 && equal.particles > Some(100));
    assert!(get(&r, "ml").ratio < 1.15);
}

#[test]
fn aoa_firefly_table() {
    let methods = [
        Method::SirSeed,
        Method::Sir,
        Method::FaPf,
        Method::FaPfImproved,
    ];
    let r = rows("aoa-firefly", &methods, 30);
    // Observed (100 runs): tuned SIR 0.93x < seed SIR 1.99x < improved FA-PF 3.1x < standard
    // FA-PF 5.0x. Seed 001's "4x better than PF" does not reproduce.
    let ratio = |m| get(&r, m).ratio;
    assert!(ratio("sir") * 1.5 < ratio("sir-seed"));
    assert!(ratio("sir-seed") < ratio("fa-pf-imp"));
    assert!(ratio("fa-pf-imp") < ratio("fa-pf"));
    // The improved variant is O(N) per iteration, the standard one O(N^2): same evaluations,
    // far less time.
    assert!(get(&r, "fa-pf-imp").time_s < get(&r, "fa-pf").time_s);
}

#[test]
fn aoa_pf_vs_kf_table() {
    let r = rows("aoa-pf-vs-kf", &[Method::Sir, Method::Ekf], 30);
    // Seed 004 says the PF (N = 500) beats the linearised KF. Started from the same bearing-pair
    // cloud, the EKF is as accurate here (observed 0.95x vs 0.96x): within 15 % either way.
    let (pf, ekf) = (get(&r, "sir").rmse, get(&r, "ekf").rmse);
    assert!((ekf / pf - 1.0).abs() < 0.15, "pf {pf} ekf {ekf}");
}

#[test]
fn rssi_sim_table() {
    // The full 50 runs: two of the rows sit within 15 % of each other.
    let t = Tracking::named("rssi-sim").expect("scenario");
    let r = tracking::bench(&t, &[50], false);
    // Observed (N = 50): PSO-GPF 0.40 m < GSA-GPF 0.89 < tuned SIR 1.02 < GPF 2.45 < the seeds'
    // Gaussian PF 2.63. Issue bar: our SIR at N = 50 <= seed 003's PF figure, 1.25 m.
    let e = |m| get(&r, m).rmse;
    assert!(e("sir") <= 1.25, "sir {}", e("sir"));
    assert!(e("pso-gpf") < 0.8, "pso-gpf {}", e("pso-gpf"));
    assert!(e("pso-gpf") < e("gsa-gpf") && e("gsa-gpf") < e("sir"));
    assert!(e("sir") * 2.0 < e("pf") && e("sir") * 2.0 < e("gpf"));
    // At PSO-GPF's likelihood budget (N = 500) the plain SIR comes close but PSO-GPF still wins
    // (observed 0.49 m vs 0.41 m; 0.42 vs 0.40 with another normal sampler): the gap is real
    // but small, so assert only that it stays under 35 %.
    let equal = get(&r, "sir=pso-gpf").rmse;
    assert!(
        equal < 1.35 * e("pso-gpf") && equal < e("gsa-gpf"),
        "sir=pso-gpf {equal}"
    );
}

#[test]
fn rssi_lab_table() {
    let t = Tracking::named("rssi-lab").expect("scenario");
    let r = tracking::bench(&t, &t.particle_counts(), false);
    // Observed (N = 100): every method within 0.77-0.86 m, 1.8-2.0x the PCRB (0.43 m): with
    // 3 dB of RSSI noise in a 6 m room no swarm move separates from the plain filters.
    for row in r.iter().filter(|r| !r.method.contains('=')) {
        assert!(
            (1.0..2.6).contains(&row.ratio),
            "{}: {} x PCRB",
            row.method,
            row.ratio
        );
    }
}

#[test]
fn ungm_table() {
    let t = Tracking::named("ungm").expect("scenario");
    let r = tracking::bench(&t, &[50], false);
    // Issue bar: our PF at N = 50 at least as good as seed 001's PF figure 3.0190 (observed
    // 1.97, seed 001's error metric). The improved FA-PF does not reach its 1.4322 (observed 2.42).
    let e = |m| get(&r, m).rmse;
    assert!(e("pf") <= 3.019, "pf {}", e("pf"));
    assert!(e("fa-pf-imp") > e("pf"));
}

#[test]
fn static_memory_budgets() {
    type Bearing100<S> = Sir<StaticEmitter, Gaussian, 100, 2, S>;
    type BearingGpf100<S> = Gpf<StaticEmitter, Gaussian, 100, 2, S>;
    let sizes = [
        ("sir", size_of::<Bearing100<foxhunt_core::NoSwarm>>()),
        ("afsa-pf", size_of::<Bearing100<Afsa>>()),
        ("fa-pf", size_of::<Bearing100<Firefly>>()),
        ("fa-pf-imp", size_of::<Bearing100<ImprovedFirefly>>()),
        ("gpf", size_of::<BearingGpf100<foxhunt_core::NoSwarm>>()),
        ("pso-gpf", size_of::<BearingGpf100<Pso>>()),
        ("gsa-gpf", size_of::<BearingGpf100<Gsa>>()),
        ("ekf", size_of::<BearingEkf>()),
    ];
    for (name, bytes) in sizes {
        // Issue bar: every filter with N = 100, D = 2 fits in 16 KiB (observed about 1.7 KiB on
        // the host; the MCU's 32-bit words make it smaller still).
        assert!(bytes <= 16 * 1024, "{name}: {bytes} bytes");
    }
    let gsa_rssi = size_of::<Gpf<RssiTracker<3>, Gaussian, 50, 4, Gsa>>();
    assert!(
        gsa_rssi <= 8 * 1024,
        "GSA-GPF N = 50, D = 4: {gsa_rssi} bytes"
    );
    assert!(size_of::<Sir<Ungm, Gaussian, 50, 1, ImprovedFirefly>>() <= 8 * 1024);
}
