//! Every model's fast paths agree with its `ln_likelihood`: the swarms' `fitness` (with the
//! per-measurement work hoisted) and the filters' `add_ln_likelihoods` (the hot loop). Every
//! SIR step uses them; a drift between them would weigh particles by a different model than
//! the one documented.

use foxhunt_core::canonical::RSSI_SIM;
use foxhunt_core::model::bearing::predicted;
use foxhunt_core::{
    Bearing, BiasedEmitter, Cauchy, Gaussian, GaussianUniform, Huber, Likelihood, Model,
    RssiMeasurement, StaticEmitter, StudentT, Tukey, Ungm, UngmObservation, Widened, random,
};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// The fast paths of `model` at `states` for `z` against `ln_likelihood`, within `tol`
/// relative (a few ulp of the log-likelihood; the fast paths use the branch-free atan2, within
/// 3e-7 rad of libm's, which `tol` covers at the residuals drawn).
fn agree<const D: usize, M: Model<D>, L: Likelihood>(
    model: &M,
    states: &[[f32; D]],
    z: &M::Measurement,
    lik: &L,
    tol: f32,
    what: &str,
) {
    let fitness = model.fitness(z, lik);
    let mut batch = vec![0.0f32; states.len()];
    model.add_ln_likelihoods(states, z, lik, &mut batch);
    for (x, b) in states.iter().zip(&batch) {
        let plain = model.ln_likelihood(x, z, lik);
        let fast = fitness(x);
        let scale = plain.abs().max(1.0);
        assert!(
            (fast - plain).abs() <= tol * scale,
            "{what}: fitness {fast} against ln_likelihood {plain} at {x:?}"
        );
        assert!(
            (b - plain).abs() <= tol * scale,
            "{what}: add_ln_likelihoods {b} against ln_likelihood {plain} at {x:?}"
        );
    }
}

fn bearing_states(rng: &mut XorShiftRng) -> Vec<[f32; 2]> {
    (0..500)
        .map(|_| {
            [
                1200.0 + 400.0 * random::normal(rng),
                800.0 + 400.0 * random::normal(rng),
            ]
        })
        .collect()
}

fn each_likelihood(mut check: impl FnMut(&dyn Fn(&str) -> String, Likelihoods)) {
    check(
        &|s| format!("gaussian {s}"),
        Likelihoods::Gaussian(Gaussian),
    );
    check(
        &|s| format!("huber {s}"),
        Likelihoods::Huber(Huber::default()),
    );
    check(&|s| format!("cauchy {s}"), Likelihoods::Cauchy(Cauchy));
    check(
        &|s| format!("student {s}"),
        Likelihoods::StudentT(StudentT::default()),
    );
    check(
        &|s| format!("tukey {s}"),
        Likelihoods::Tukey(Tukey::default()),
    );
    check(
        &|s| format!("mixture {s}"),
        Likelihoods::Mixture(GaussianUniform { eps: 0.05 }),
    );
    check(
        &|s| format!("widened {s}"),
        Likelihoods::Widened(Widened {
            inner: Cauchy,
            factor: 2.0,
        }),
    );
}

/// The likelihoods, each its own type.
enum Likelihoods {
    Gaussian(Gaussian),
    Huber(Huber),
    Cauchy(Cauchy),
    StudentT(StudentT),
    Tukey(Tukey),
    Mixture(GaussianUniform),
    Widened(Widened<Cauchy>),
}

macro_rules! with_likelihood {
    ($l:expr, $lik:ident => $body:expr) => {
        match $l {
            Likelihoods::Gaussian($lik) => $body,
            Likelihoods::Huber($lik) => $body,
            Likelihoods::Cauchy($lik) => $body,
            Likelihoods::StudentT($lik) => $body,
            Likelihoods::Tukey($lik) => $body,
            Likelihoods::Mixture($lik) => $body,
            Likelihoods::Widened($lik) => $body,
        }
    };
}

#[test]
fn bearing_models_fast_paths_agree() {
    let mut rng = XorShiftRng::seed_from_u64(3);
    let states = bearing_states(&mut rng);
    let biased: Vec<[f32; 3]> = states
        .iter()
        .map(|p| [p[0], p[1], 0.05 * random::normal(&mut rng)])
        .collect();
    for k in 0..24 {
        let a = k as f32 * 0.27;
        let v = [1200.0 + 700.0 * a.cos(), 800.0 + 700.0 * a.sin()];
        let z = Bearing {
            vehicle: v,
            theta: predicted(&[1200.0, 800.0], &v) + 0.02 * random::normal(&mut rng),
            sigma: 0.02,
        };
        each_likelihood(|name, l| {
            with_likelihood!(l, lik => {
                agree(&StaticEmitter { process_var: 0.0 }, &states, &z, &lik, 2e-4, &name("static"));
                agree(&BiasedEmitter { process_var: 0.0 }, &biased, &z, &lik, 2e-4, &name("biased"));
            })
        });
    }
}

#[test]
fn rssi_and_ungm_fast_paths_agree() {
    let mut rng = XorShiftRng::seed_from_u64(4);
    let states: Vec<[f32; 4]> = (0..300)
        .map(|_| {
            [
                10.0 * random::uniform(&mut rng),
                random::normal(&mut rng),
                10.0 * random::uniform(&mut rng),
                random::normal(&mut rng),
            ]
        })
        .collect();
    let z = RssiMeasurement::all(RSSI_SIM.expected(&[4.0, 0.0, 6.0, 0.0]));
    let partial = RssiMeasurement {
        present: [true, false, true],
        ..z
    };
    let ungm_states: Vec<[f32; 1]> = (0..300)
        .map(|_| [20.0 * random::normal(&mut rng)])
        .collect();
    let obs = UngmObservation { k: 7, z: 12.5 };
    each_likelihood(|name, l| {
        with_likelihood!(l, lik => {
            agree(&RSSI_SIM, &states, &z, &lik, 1e-5, &name("rssi"));
            agree(&RSSI_SIM, &states, &partial, &lik, 1e-5, &name("rssi, two anchors heard"));
            agree(&Ungm::default(), &ungm_states, &obs, &lik, 1e-5, &name("ungm"));
        })
    });
}
