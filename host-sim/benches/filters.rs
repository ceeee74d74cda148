//! Criterion benchmarks: one step of every particle filter and the EKF at N = 100, 1 000 and
//! 10 000 (throughput in particle updates per second), and whole canonical runs of every
//! method of every scenario's table. Every filter comes from the core's registry.
//!
//! `cargo bench -p foxhunt-sim --bench filters` (add `-- step/sir` to pick one group). The
//! O(N^2) swarms (gsa-gpf, fa-pf) take seconds to minutes per step at N = 10 000, so the full
//! set runs for a long while; `foxhunt perf` gives the same growth with a time limit.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use foxhunt_core::estimator::with_bearing_filter;
use foxhunt_core::fix::init::initial_particles;
use foxhunt_core::fix::intersection::MIN_CROSSING;
use foxhunt_core::{Bearing, Error, Filter, Method, ParticleSet, WithFilter, with_particles};
use foxhunt_sim::runs::run::{bearing_run, tracking_run};
use foxhunt_sim::runs::scenario::Scenario;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::hint::black_box;

/// The sequential methods timed step by step.
const STEPPED: [Method; 8] = [
    Method::Sir,
    Method::Gpf,
    Method::AfsaPf,
    Method::FaPfImp,
    Method::PsoGpf,
    Method::GsaGpf,
    Method::FaPf,
    Method::Ekf,
];

/// The visitor that benches one step of a started filter, cycling through the bearings.
struct StepBench<'a, 'c> {
    c: &'c mut Criterion,
    method: Method,
    n: usize,
    cloud: &'a [[f32; 2]],
    bearings: &'a [Bearing],
}

impl WithFilter<2, Bearing> for StepBench<'_, '_> {
    type Output = Result<(), Error>;
    fn visit<F: Filter<2, Measurement = Bearing>>(self, f: &mut F) -> Self::Output {
        let mut rng = XorShiftRng::seed_from_u64(7);
        f.initialise(self.cloud, &mut rng)?;
        let mut g = self.c.benchmark_group(format!("step/{}", self.method));
        if self.method.uses_particles() {
            g.throughput(Throughput::Elements(self.n as u64));
        }
        if self.n >= 10_000 {
            // Criterion's least: the O(N^2) swarms' steps take seconds here.
            g.sample_size(10);
        }
        let mut k = 0;
        let id = if self.method.uses_particles() {
            BenchmarkId::from_parameter(self.n)
        } else {
            BenchmarkId::from_parameter("-")
        };
        g.bench_function(id, |b| {
            b.iter(|| {
                k = (k + 1) % self.bearings.len();
                black_box(f.step(&self.bearings[k], &mut rng).ok())
            })
        });
        g.finish();
        Ok(())
    }
}

/// One step of `method` at `n` particles, started from aoa-afsa's bearing-pair cloud.
fn step_group(c: &mut Criterion, method: Method, n: usize) -> Result<(), Error> {
    let s = Scenario::named("aoa-afsa").ok_or(Error::Unsupported)?;
    let d = s.drive().ok_or(Error::Unsupported)?;
    let mut rng = s.rng(0);
    let bearings = d.simulate(&mut rng);
    with_particles!(n, N => {
        let mut cloud = Box::new(ParticleSet::<N, 2>::new());
        initial_particles(&bearings, MIN_CROSSING, &mut cloud, &mut rng)?;
        let b = StepBench { c, method, n, cloud: &cloud.states, bearings: &bearings };
        with_bearing_filter::<N, _>(method, 0.0, b)?
    })
}

fn filter_steps(c: &mut Criterion) {
    for n in [100, 1000, 10_000] {
        for m in STEPPED {
            // The EKF has no N: one group.
            if m.uses_particles() || n == 100 {
                let _ = step_group(c, m, n);
            }
        }
    }
}

/// Whole canonical runs of every method of every scenario's table, at its first N.
fn whole_runs(c: &mut Criterion) {
    for s in Scenario::all() {
        let n = s.particles[0];
        let mut g = c.benchmark_group(format!("run/{}", s.label(n)));
        g.sample_size(10);
        for &m in &s.methods {
            match s.drive() {
                Some(d) => g.bench_function(m.name(), |b| {
                    b.iter(|| black_box(bearing_run(d, m, n, &mut s.rng(0)).ok()))
                }),
                None => g.bench_function(m.name(), |b| {
                    b.iter(|| black_box(tracking_run(&s, m, n, 0).0.ok()))
                }),
            };
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
