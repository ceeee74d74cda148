//! Criterion benchmarks: one step of every filter at N = 100, 1 000 and 10 000 particles
//! (throughput in particle updates per second), and whole canonical runs of every method of
//! every scenario (bearing and tracking).
//!
//! `cargo bench -p foxhunt-sim --bench filters` (add `-- step/sir` to pick one group). The
//! O(N^2) swarms (gsa-gpf, fa-pf) take seconds to minutes per step at N = 10 000, so the full
//! set runs for a long while; `foxhunt perf` gives the same growth with a time limit.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use foxhunt_core::fix::init::initial_particles;
use foxhunt_core::fix::intersection::MIN_CROSSING;
use foxhunt_core::{
    Afsa, Bearing, BearingEkf, Filter, Firefly, Gaussian, Gpf, Gsa, ImprovedFirefly, ParticleSet,
    Pso, Sir, SirConfig, StaticEmitter,
};
use foxhunt_sim::methods::Method;
use foxhunt_sim::scenario::Scenario;
use foxhunt_sim::tracking::{self, Tracking};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::hint::black_box;

/// The bearings of one aoa-afsa run and a filter started from their bearing-pair cloud.
fn setup<const N: usize, F: Filter<2, Measurement = Bearing>>(
    make: impl Fn() -> F,
) -> (Box<F>, Vec<Bearing>, XorShiftRng) {
    let s = Scenario::named("aoa-afsa").expect("scenario");
    let mut rng = s.rng(0);
    let bearings = s.simulate(&mut rng);
    let mut cloud = Box::new(ParticleSet::<N, 2>::new());
    initial_particles(&bearings, MIN_CROSSING, &mut cloud, &mut rng).expect("cloud");
    let mut f = Box::new(make());
    f.initialise(&cloud.states, &mut rng).expect("initialise");
    (f, bearings, XorShiftRng::seed_from_u64(7))
}

fn step_group<const N: usize, F: Filter<2, Measurement = Bearing>>(
    c: &mut Criterion,
    name: &str,
    make: impl Fn() -> F,
) {
    let mut g = c.benchmark_group(format!("step/{name}"));
    g.throughput(Throughput::Elements(N as u64));
    if N >= 10_000 {
        // Criterion's least: the O(N^2) swarms' steps take seconds here.
        g.sample_size(10);
    }
    let (mut f, bearings, mut rng) = setup::<N, F>(make);
    let mut k = 0;
    g.bench_function(BenchmarkId::from_parameter(N), |b| {
        b.iter(|| {
            k = (k + 1) % bearings.len();
            black_box(f.step(&bearings[k], &mut rng).ok())
        })
    });
    g.finish();
}

macro_rules! steps {
    ($c:expr, $($n:literal),*) => {$(
        let model = StaticEmitter { process_var: 0.0 };
        let config = SirConfig::default();
        step_group::<$n, _>($c, "sir", || Sir::<_, _, $n, 2>::new(model, Gaussian, config));
        step_group::<$n, _>($c, "gpf", || Gpf::<_, _, $n, 2>::new(model, Gaussian));
        step_group::<$n, _>($c, "afsa-pf", || {
            Sir::<_, _, $n, 2, _>::with_swarm(model, Gaussian, config, Afsa::default())
        });
        step_group::<$n, _>($c, "fa-pf-imp", || {
            Sir::<_, _, $n, 2, _>::with_swarm(model, Gaussian, config, ImprovedFirefly::default())
        });
        step_group::<$n, _>($c, "pso-gpf", || {
            Gpf::<_, _, $n, 2, _>::with_swarm(model, Gaussian, Pso::default())
        });
        // The O(N^2) swarms: seconds to minutes per step at N = 10 000.
        step_group::<$n, _>($c, "gsa-gpf", || {
            Gpf::<_, _, $n, 2, _>::with_swarm(model, Gaussian, Gsa::default())
        });
        step_group::<$n, _>($c, "fa-pf", || {
            Sir::<_, _, $n, 2, _>::with_swarm(model, Gaussian, config, Firefly::default())
        });
    )*};
}

fn filter_steps(c: &mut Criterion) {
    steps!(c, 100, 1000, 10000);
    step_group::<1, _>(c, "ekf", || BearingEkf::new(0.0));
}

/// Whole canonical runs of every method of every scenario's table: the bearing scenarios at
/// their N (aoa-afsa 100, aoa-firefly 80, ...) and the tracking ones at their first N.
fn whole_runs(c: &mut Criterion) {
    for name in foxhunt_sim::scenario::NAMES {
        let s = Scenario::named(name).expect("scenario");
        let mut g = c.benchmark_group(format!("run/{name}"));
        g.sample_size(10);
        for m in Method::for_scenario(name) {
            let mut rng = s.rng(0);
            let bearings = s.simulate(&mut rng);
            g.bench_function(m.name(), |b| {
                b.iter(|| black_box(m.run(&s, &bearings, &mut rng).ok()))
            });
        }
        g.finish();
    }
    for name in tracking::NAMES {
        let s = Tracking::named(name).expect("scenario");
        let n = s.particle_counts()[0];
        let mut g = c.benchmark_group(format!("run/{name}/N={n}"));
        g.sample_size(10);
        for m in s.methods() {
            g.bench_function(m.name(), |b| {
                b.iter(|| black_box(tracking::dispatch(&s, m, n, 0).ok()))
            });
        }
        g.finish();
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2));
    targets = filter_steps, whole_runs
}
criterion_main!(benches);
