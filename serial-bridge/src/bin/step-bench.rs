//! The per-filter MCU benchmark image: one filter of the core's registry, N = 100, stepped over
//! the aoa-afsa bearings (or, with the suffix `-rssi`, the rssi-sim readings), chosen by
//! semihosting arguments `<filter> <steps>`. `serial-bridge/qemu/steps.sh` runs it twice per
//! filter, with 0 steps and with 60, under the counting plugin: the difference is the
//! instruction cost of the steps.
//!
//! Filters: any sequential method's registry name (sir, gpf, ekf, afsa-pf, fa-pf, fa-pf-imp,
//! pso-gpf, gsa-gpf, ...) on bearings, or a particle method with `-rssi` (gsa-gpf-rssi: seed
//! 003's model). Guidance: `guidance-d` (a greedy D-optimal choice among 16 free headings of
//! 300 m, one hypothesis) and `guidance-look` (the look-ahead: 9 headings within 90 degrees,
//! three legs deep, 729 sequences, over three hypotheses), each "step" one whole decision from
//! the aoa-afsa bearings with an unknown offset. The moving-emitter tracker:
//! `track-<N>-<part> <steps> [seed]` (N 128 or 256; parts in its `track` module, measured by
//! `serial-bridge/qemu/track-steps.sh`). On the host this binary is an empty stub.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "step-bench/track.rs"]
mod track;

#[cfg(target_os = "none")]
#[path = "shared/stack.rs"]
mod stack;

#[cfg(target_os = "none")]
mod image {
    use cortex_m as _;
    // The PAC's interrupt vectors: cortex-m-rt links with its `device` feature on.
    use cortex_m_rt::entry;
    use foxhunt_core::canonical::{AOA_EMITTER, AOA_SIGMA, RSSI_SIM, RSSI_SIM_START, loop300};
    use foxhunt_core::estimator::{with_bearing_filter, with_particle_filter};
    use foxhunt_core::model::bearing::predicted;
    use foxhunt_core::{
        Bearing, Error, Filter, Method, ParticleSet, RssiMeasurement, RssiTracker, WithFilter,
        random,
    };
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;
    use semihosting::{println, process};
    use stm32f4 as _;

    const N: usize = 100;

    /// Step a started filter `steps` times cycling through `z`, print its estimate's mean and
    /// the likelihood evaluations spent (what a change of code must leave alone, and the
    /// machine-independent half of a change of cost); the mean's first coordinate.
    struct Run<'a, Z, const D: usize> {
        cloud: &'a [[f32; D]],
        z: &'a [Z],
        steps: usize,
        rng: &'a mut XorShiftRng,
    }

    impl<Z, const D: usize> WithFilter<D, Z> for Run<'_, Z, D> {
        type Output = Result<f32, Error>;
        fn visit<F: Filter<D, Measurement = Z>>(self, f: &mut F) -> Self::Output {
            f.initialise(self.cloud, self.rng)?;
            for z in self.z.iter().cycle().take(self.steps) {
                let _ = f.step(z, self.rng);
            }
            let mean = f.estimate()?.mean;
            println!("mean {mean:?}, {} evaluations", f.evaluations());
            Ok(mean[0])
        }
    }

    /// aoa-afsa's 60 noisy bearings, from a N(emitter, 50^2 I) cloud.
    fn run_bearings(method: Method, steps: usize) -> Result<f32, Error> {
        let mut rng = XorShiftRng::seed_from_u64(1);
        let z: [Bearing; 60] = core::array::from_fn(|k| {
            let v = loop300(AOA_EMITTER, k);
            Bearing {
                vehicle: v,
                theta: predicted(&AOA_EMITTER, &v) + AOA_SIGMA * random::normal(&mut rng),
                sigma: AOA_SIGMA,
            }
        });
        let mut cloud = ParticleSet::<N, 2>::new();
        cloud.draw_gaussian(&AOA_EMITTER, &[[2500.0, 0.0], [0.0, 2500.0]], &mut rng)?;
        let run = Run {
            cloud: &cloud.states,
            z: &z,
            steps,
            rng: &mut rng,
        };
        with_bearing_filter::<N, _>(method, 0.0, run)?
    }

    /// rssi-sim's node walking from its start, 0.5 dB noise, started at the true state.
    fn run_rssi(method: Method, steps: usize) -> Result<f32, Error> {
        let model: RssiTracker<3> = RSSI_SIM;
        let mut rng = XorShiftRng::seed_from_u64(1);
        let mut x = RSSI_SIM_START;
        let z: [RssiMeasurement<3>; 60] = core::array::from_fn(|_| {
            x = model.confine(model.advance(&x));
            let mut dbm = model.expected(&x);
            for d in dbm.iter_mut() {
                *d += 0.5 * random::normal(&mut rng);
            }
            RssiMeasurement::all(dbm)
        });
        let start = [RSSI_SIM_START; 1];
        let run = Run {
            cloud: &start,
            z: &z,
            steps,
            rng: &mut rng,
        };
        with_particle_filter::<N, 4, _, _>(method, model, run)?
    }

    /// `steps` guidance decisions from aoa-afsa's bearings (offset unknown); the sequences
    /// scored per decision.
    fn run_guidance(look: bool, steps: usize) -> Result<u32, Error> {
        use foxhunt_core::fix::bias::BiasPrior;
        use foxhunt_core::guidance::belief::{Belief, Hypotheses, MAX_POINTS, beliefs};
        use foxhunt_core::guidance::plan::{
            Cost, FreeHeadings, Objective, PlanOptions, Pose, plan,
        };
        let mut rng = XorShiftRng::seed_from_u64(1);
        let z: [Bearing; 60] = core::array::from_fn(|k| {
            let v = loop300(AOA_EMITTER, k);
            Bearing {
                vehicle: v,
                theta: predicted(&AOA_EMITTER, &v) + AOA_SIGMA * random::normal(&mut rng),
                sigma: AOA_SIGMA,
            }
        });
        let prior = BiasPrior::default();
        let vehicle = z[59].vehicle;
        let h = if look {
            Hypotheses::spread(AOA_EMITTER, &[[4.0e6, 0.0], [0.0, 1.0e4]], vehicle, 0.15)?
        } else {
            Hypotheses::at(AOA_EMITTER)
        };
        let mut b = [Belief::from_bearings(AOA_EMITTER, &z, prior, 2.0e4)?; MAX_POINTS];
        let n = beliefs(&h, &z, prior, 2.0e4, &mut b);
        let (objective, depth, max_turn) = if look {
            (
                Objective::Goal {
                    target_m: 1e-3,
                    cost: Cost::Time,
                },
                3,
                core::f32::consts::FRAC_PI_2,
            )
        } else {
            (Objective::DOptimal, 1, core::f32::consts::PI)
        };
        let options = PlanOptions {
            objective,
            depth,
            horizon_s: 20.0 * depth as f32,
            rate_hz: 1.0,
            sigma: AOA_SIGMA,
            sample_m: 100.0,
        };
        let free = FreeHeadings {
            max_turn,
            ..FreeHeadings::default()
        };
        let mut sequences = 0;
        for k in 0..steps {
            let pose = Pose {
                position: vehicle,
                heading: 0.1 * k as f32,
            };
            sequences = plan(&b[..n], pose, &free, options)?.sequences;
        }
        println!("hypotheses {n}");
        Ok(sequences)
    }

    /// The stack pointer where the stack was last repainted.
    static PAINTED_AT: core::sync::atomic::AtomicUsize = core::sync::atomic::AtomicUsize::new(0);

    /// Paint the stack below the current frame again (as the firmware does after its start,
    /// `src/bin/firmware/hw.rs`) and note where: the lowest word written since then says what
    /// the calls below that frame needed.
    #[inline(never)]
    fn repaint_stack() {
        let sp = cortex_m::register::msp::read() as usize;
        PAINTED_AT.store(sp, core::sync::atomic::Ordering::Relaxed);
        crate::stack::paint_below(sp);
    }

    /// `track-<N>-<part>`: the tracker's run; prints its error, its state's bytes (what a
    /// firmware would hold as a static) and the stack its steps needed below the frame that
    /// holds the state (repainted once the first cloud is made).
    fn run_track(spec: &str, steps: usize, seed: u64) -> Result<f32, Error> {
        let (n, part) = spec.split_once('-').ok_or(Error::Unsupported)?;
        let part = crate::track::Part::named(part).ok_or(Error::Unsupported)?;
        let ran = match n {
            "128" => crate::track::run::<128>(part, steps, seed, repaint_stack)?,
            "256" => crate::track::run::<256>(part, steps, seed, repaint_stack)?,
            _ => return Err(Error::Unsupported),
        };
        println!(
            "state {} B, step stack {} B, D {}, rmse {} m after {} s",
            ran.bytes,
            PAINTED_AT
                .load(core::sync::atomic::Ordering::Relaxed)
                .saturating_sub(crate::stack::lowest_written(0)),
            crate::track::D,
            ran.rmse,
            crate::track::WARMUP_S,
        );
        Ok(ran.error)
    }

    #[entry]
    fn main() -> ! {
        let args = semihosting::experimental::env::args::<128>();
        let mut it = args.as_ref().ok().into_iter().flatten().flatten();
        let _program = it.next();
        let filter = it.next().unwrap_or("sir");
        let steps = it.next().and_then(|s| s.parse().ok()).unwrap_or(60usize);
        if let Some(spec) = filter.strip_prefix("track-") {
            let seed = it.next().and_then(|s| s.parse().ok()).unwrap_or(1);
            match run_track(spec, steps, seed) {
                Ok(e) => {
                    println!("{filter} {steps} steps: error {e} m");
                    process::exit(if e.is_finite() { 0 } else { 1 })
                }
                Err(e) => {
                    println!("{filter}: {e}");
                    process::exit(1)
                }
            }
        }
        if let Some(kind) = filter.strip_prefix("guidance-") {
            match run_guidance(kind == "look", steps) {
                Ok(n) => {
                    println!("{filter} {steps} decisions: {n} sequences each");
                    process::exit(0)
                }
                Err(e) => {
                    println!("{filter}: {e}");
                    process::exit(1)
                }
            }
        }
        let (name, rssi) = match filter.strip_suffix("-rssi") {
            Some(base) => (base, true),
            None => (filter, false),
        };
        let Some(method) = Method::from_name(name) else {
            println!("unknown filter {filter}");
            process::exit(2)
        };
        let out = if rssi {
            run_rssi(method, steps)
        } else {
            run_bearings(method, steps)
        };
        match out {
            Ok(x) => {
                println!("{filter} {steps} steps: estimate x {x}");
                process::exit(if x.is_finite() { 0 } else { 1 })
            }
            Err(e) => {
                println!("{filter}: {e}");
                process::exit(1)
            }
        }
    }

    /// A panic prints and exits 1 (QEMU's exit status).
    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
        println!("{info}");
        process::exit(1)
    }
}

#[cfg(not(target_os = "none"))]
fn main() {}
