//! Each paper's table, the ordering we actually observe (not the paper's where they differ), on
//! reduced run counts, plus the static memory budgets.
//!
//! Tolerances: each assertion compares methods whose figures on the full run count differ by
//! 1.5x or more; with 30 seeded runs the sampling error of an rmse is about +-13 %, so the
//! factors below cannot flip by chance, and the runs are seeded, so they are repeatable. Every
//! assertion prints the figures it compares.

use foxhunt_core::Method::{self, *};
use foxhunt_core::{
    Afsa, BearingEkf, Firefly, Gaussian, Gpf, Gsa, ImprovedFirefly, Pso, RssiTracker, Sir,
    StaticEmitter, Ungm,
};
use foxhunt_tests::{error, ratio, row, table};
use std::mem::size_of;

#[test]
fn aoa_afsa_table() {
    let r = table("aoa-afsa", &[SirSeed, Sir, AfsaPf, Ml], Some(30));
    let (seed, tuned, afsa) = (
        ratio(&r, "sir-seed"),
        ratio(&r, "sir"),
        ratio(&r, "afsa-pf"),
    );
    // The fish swarm does not beat a tuned plain filter, nor does the seeds' SIR.
    assert!(afsa > 1.3 * tuned, "afsa-pf {afsa} vs sir {tuned}");
    assert!(seed > 1.3 * tuned, "sir-seed {seed} vs sir {tuned}");
    // The tuned SIR given AFSA's likelihood budget does better still.
    let equal = row(&r, "sir=afsa-pf");
    let eq = ratio(&r, "sir=afsa-pf");
    assert!(
        eq < afsa / 1.3 && equal.particles > Some(100),
        "sir=afsa-pf {eq} at {:?} vs afsa-pf {afsa}",
        equal.particles
    );
    let ml = ratio(&r, "ml");
    assert!(ml < 1.15, "ml {ml}");
}

#[test]
fn aoa_firefly_table() {
    let r = table("aoa-firefly", &[SirSeed, Sir, FaPf, FaPfImp], Some(30));
    let q = |m| ratio(&r, m);
    // Seed 001's "4x better than PF" does not reproduce: tuned SIR < seeds' SIR < improved
    // FA-PF < standard FA-PF, each step at least 1.5x on the full runs.
    assert!(
        q("sir") * 1.5 < q("sir-seed"),
        "sir {} sir-seed {}",
        q("sir"),
        q("sir-seed")
    );
    assert!(
        q("sir-seed") < q("fa-pf-imp"),
        "sir-seed {} fa-pf-imp {}",
        q("sir-seed"),
        q("fa-pf-imp")
    );
    assert!(
        q("fa-pf-imp") < q("fa-pf"),
        "fa-pf-imp {} fa-pf {}",
        q("fa-pf-imp"),
        q("fa-pf")
    );
}

#[test]
fn aoa_pf_vs_kf_table() {
    let r = table("aoa-pf-vs-kf", &[Sir, Ekf], Some(30));
    // Seed 004 says the PF (N = 500) beats the linearised KF. Started from the same bearing-pair
    // cloud, the EKF is as accurate: within 15 % either way (twice a 30-run standard error).
    let (pf, ekf) = (error(&r, "sir"), error(&r, "ekf"));
    assert!((ekf / pf - 1.0).abs() < 0.15, "pf {pf} ekf {ekf}");
}

#[test]
fn rssi_sim_table() {
    // The full 50 runs at N = 50: two of the rows sit within 15 % of each other.
    let mut s = foxhunt_sim::runs::scenario::Scenario::named("rssi-sim").expect("scenario");
    s.particles = vec![50];
    let r = foxhunt_sim::runs::montecarlo::bench(
        &s,
        &foxhunt_sim::runs::montecarlo::Progress::new(0, false),
    );
    let e = |m| error(&r, m);
    // The bar: our SIR at N = 50 <= seed 003's PF figure, 1.25 m.
    assert!(e("sir-wide") <= 1.25, "sir-wide {}", e("sir-wide"));
    assert!(e("pso-gpf") < 0.8, "pso-gpf {}", e("pso-gpf"));
    assert!(
        e("pso-gpf") < e("gsa-gpf") && e("gsa-gpf") < e("sir-wide"),
        "pso-gpf {} gsa-gpf {} sir-wide {}",
        e("pso-gpf"),
        e("gsa-gpf"),
        e("sir-wide")
    );
    assert!(
        e("sir-wide") * 2.0 < e("sir-seed") && e("sir-wide") * 2.0 < e("gpf"),
        "sir-wide {} sir-seed {} gpf {}",
        e("sir-wide"),
        e("sir-seed"),
        e("gpf")
    );
    // At PSO-GPF's likelihood budget the plain SIR comes close but PSO-GPF still wins: the gap
    // is real but small, so assert only that it stays under 35 %.
    let equal = e("sir-wide=pso-gpf");
    assert!(
        equal < 1.35 * e("pso-gpf") && equal < e("gsa-gpf"),
        "sir-wide=pso-gpf {equal} pso-gpf {} gsa-gpf {}",
        e("pso-gpf"),
        e("gsa-gpf")
    );
}

#[test]
fn rssi_lab_table() {
    let r = table("rssi-lab", &[SirSeed, SirWide, Gpf, PsoGpf, GsaGpf], None);
    // With 3 dB of RSSI noise in a 6 m room no swarm move separates from the plain filters:
    // every method within 1.0-2.6x the PCRB.
    for row in r.iter().filter(|r| !r.method.contains('=')) {
        let q = row.ratio.unwrap_or(f64::NAN);
        assert!((1.0..2.6).contains(&q), "{}: {q} x PCRB", row.method);
    }
}

#[test]
fn ungm_table() {
    let r = table("ungm", &[SirSeed, FaPfImp], None);
    // The bar: our PF at N = 50 at least as good as seed 001's PF figure 3.0190 (its error
    // metric). The improved FA-PF does not reach the paper's 1.4322, nor our PF.
    let e = |m| error(&r, m);
    assert!(e("sir-seed") <= 3.019, "sir-seed {}", e("sir-seed"));
    assert!(
        e("fa-pf-imp") > e("sir-seed"),
        "fa-pf-imp {} sir-seed {}",
        e("fa-pf-imp"),
        e("sir-seed")
    );
}

#[test]
fn every_method_of_every_table_is_one_registry_name() {
    for s in foxhunt_sim::runs::scenario::Scenario::all() {
        for m in &s.methods {
            assert_eq!(Method::from_name(m.name()), Some(*m), "{}", s.name);
        }
    }
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
        // The bar: every filter with N = 100, D = 2 fits in 16 KiB.
        assert!(bytes <= 16 * 1024, "{name}: {bytes} bytes");
    }
    let gsa_rssi = size_of::<Gpf<RssiTracker<3>, Gaussian, 50, 4, Gsa>>();
    assert!(
        gsa_rssi <= 8 * 1024,
        "GSA-GPF N = 50, D = 4: {gsa_rssi} bytes"
    );
    let ungm = size_of::<Sir<Ungm, Gaussian, 50, 1, ImprovedFirefly>>();
    assert!(ungm <= 8 * 1024, "FA-PF-imp UNGM N = 50: {ungm} bytes");
}

#[test]
fn every_scenario_gives_finite_rows_at_every_compiled_count() {
    // One run of every method of every table at every count `bench --particles` accepts: a
    // row is finite, or says plainly why it was not run (an O(N^2) swarm above 1 000
    // particles, AFSA above its u16 fish index). Never a null row passed off as a result.
    // The runs are shortened (12 bearings, 6 tracking steps): what is checked is that every
    // method is built and answers at every count, not its accuracy.
    use foxhunt_sim::runs::montecarlo::{Progress, bench};
    use foxhunt_sim::runs::scenario::ScenarioModel;
    for n in foxhunt_core::PARTICLE_COUNTS {
        for mut s in foxhunt_sim::runs::scenario::Scenario::all() {
            s.runs = 1;
            s.particles = vec![n];
            match &mut s.model {
                ScenarioModel::Bearing(d) => {
                    let step = d.route.len() / 12;
                    d.route = d.route.iter().step_by(step.max(1)).copied().collect();
                }
                ScenarioModel::Rssi { steps, .. } | ScenarioModel::Ungm { steps } => *steps = 6,
            }
            for r in bench(&s, &Progress::new(0, false)) {
                let finite = r.rmse.is_some_and(f64::is_finite) && r.ratio.is_some_and(|q| q > 0.0);
                let said = r.note.as_deref().is_some_and(|n| n.starts_with("not run"));
                assert!(finite || said, "{} {} N = {n}: {r:?}", r.scenario, r.method);
            }
        }
    }
}
