//! The per-filter MCU benchmark image: one filter, N = 100, stepped over the aoa-afsa bearings
//! (or, for `gsa-gpf-rssi`, the rssi-sim readings), chosen by semihosting arguments
//! `<filter> <steps>`. `serial-bridge/qemu/steps.sh` runs it twice per filter, with 0 steps and
//! with 60, under the counting plugin: the difference is the instruction cost of the steps.
//!
//! Filters: sir, gpf, ekf, afsa-pf, fa-pf, fa-pf-imp, pso-gpf, gsa-gpf (bearings),
//! gsa-gpf-rssi (RSSI, seed 003's model). On the host this binary is an empty stub.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod image {
    use cortex_m as _;
    use cortex_m_rt::entry;
    use foxhunt_core::model::bearing::predicted;
    use foxhunt_core::{
        Afsa, Bearing, BearingEkf, Filter, Firefly, Gaussian, Gpf, Gsa, ImprovedFirefly,
        ParticleSet, PathLoss, Pso, RssiMeasurement, RssiTracker, Sir, SirConfig, StaticEmitter,
        random,
    };
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;
    use semihosting::{println, process};

    const N: usize = 100;
    const EMITTER: [f32; 2] = [1200.0, 800.0];
    const SIGMA: f32 = 0.019_496;

    /// aoa-afsa: 60 noisy bearings from a 300 m circle around the emitter.
    fn bearings(rng: &mut XorShiftRng) -> [Bearing; 60] {
        let start = libm::atan2f(-EMITTER[1], -EMITTER[0]);
        core::array::from_fn(|k| {
            let a = start + 2.0 * core::f32::consts::PI * k as f32 / 60.0;
            let v = [
                EMITTER[0] + 300.0 * libm::cosf(a),
                EMITTER[1] + 300.0 * libm::sinf(a),
            ];
            Bearing {
                vehicle: v,
                theta: predicted(&EMITTER, &v) + SIGMA * random::normal(rng),
                sigma: SIGMA,
            }
        })
    }

    /// Run `steps` of `f` over the bearings from a N(emitter, 50^2 I) cloud.
    fn run_bearings<F: Filter<2, Measurement = Bearing>>(mut f: F, steps: usize) -> f32 {
        let mut rng = XorShiftRng::seed_from_u64(1);
        let z = bearings(&mut rng);
        let mut cloud = ParticleSet::<N, 2>::new();
        let _ = cloud.draw_gaussian(&EMITTER, &[[2500.0, 0.0], [0.0, 2500.0]], &mut rng);
        let _ = f.initialise(&cloud.states, &mut rng);
        for b in z.iter().cycle().take(steps) {
            let _ = f.step(b, &mut rng);
        }
        f.estimate().mean[0]
    }

    /// rssi-sim: a node walking at 0.5 m/s diagonally, three anchors, 0.5 dB noise.
    fn run_rssi(steps: usize) -> f32 {
        let model = RssiTracker {
            anchors: [[0.0, 5.0], [5.0, 10.0], [10.0, 0.0]],
            sigma: [0.5; 3],
            path_loss: PathLoss {
                p0: -37.8,
                d0: 1.0,
                eta: 2.3,
            },
            dt: 0.5,
            q: [0.5, 1.0, 0.5, 1.0],
            room: Some([10.0, 10.0]),
        };
        let mut rng = XorShiftRng::seed_from_u64(1);
        let mut f = Gpf::<_, _, N, 4, _>::with_swarm(model, Gaussian, Gsa::default());
        let start = [[0.0, 0.5, 0.0, 0.5]; 1];
        let _ = f.initialise(&start, &mut rng);
        let mut x = [0.0f32, 0.5, 0.0, 0.5];
        for _ in 0..steps {
            x = model.confine(model.advance(&x));
            let mut dbm = model.expected(&x);
            for d in dbm.iter_mut() {
                *d += 0.5 * random::normal(&mut rng);
            }
            let _ = f.step(&RssiMeasurement::all(dbm), &mut rng);
        }
        f.estimate().mean[0]
    }

    #[entry]
    fn main() -> ! {
        let args = semihosting::experimental::env::args::<128>();
        let mut it = args.as_ref().ok().into_iter().flatten().flatten();
        let _program = it.next();
        let filter = it.next().unwrap_or("sir");
        let steps = it.next().and_then(|s| s.parse().ok()).unwrap_or(60usize);
        let model = StaticEmitter { process_var: 0.0 };
        let config = SirConfig::default();
        let out = match filter {
            "sir" => run_bearings(Sir::<_, _, N, 2>::new(model, Gaussian, config), steps),
            "gpf" => run_bearings(Gpf::<_, _, N, 2>::new(model, Gaussian), steps),
            "ekf" => run_bearings(BearingEkf::new(0.0), steps),
            "afsa-pf" => run_bearings(
                Sir::<_, _, N, 2, _>::with_swarm(model, Gaussian, config, Afsa::default()),
                steps,
            ),
            "fa-pf" => run_bearings(
                Sir::<_, _, N, 2, _>::with_swarm(model, Gaussian, config, Firefly::default()),
                steps,
            ),
            "fa-pf-imp" => run_bearings(
                Sir::<_, _, N, 2, _>::with_swarm(
                    model,
                    Gaussian,
                    config,
                    ImprovedFirefly::default(),
                ),
                steps,
            ),
            "pso-gpf" => run_bearings(
                Gpf::<_, _, N, 2, _>::with_swarm(model, Gaussian, Pso::default()),
                steps,
            ),
            "gsa-gpf" => run_bearings(
                Gpf::<_, _, N, 2, _>::with_swarm(model, Gaussian, Gsa::default()),
                steps,
            ),
            "gsa-gpf-rssi" => run_rssi(steps),
            other => {
                println!("unknown filter {other}");
                process::exit(2)
            }
        };
        println!("{filter} {steps} steps: estimate x {out}");
        process::exit(if out.is_finite() { 0 } else { 1 })
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
