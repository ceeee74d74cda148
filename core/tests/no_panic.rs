//! Every public entry point of the core, fed arbitrary f32 (NaN, +-inf, 1e30, -0.0, subnormals,
//! ordinary values): nothing panics, and whatever comes back Ok is finite.

use foxhunt_core::fix::{crlb, ellipse, init, intersection, ml, ple};
use foxhunt_core::model::bearing::{azimuth_to_theta, predicted, theta_to_azimuth, wrap};
use foxhunt_core::preprocess::{ObservationPoint, error_weight};
use foxhunt_core::{
    Bearing, BearingEkf, Cauchy, Filter, Gaussian, GaussianUniform, Gpf, Huber, Likelihood,
    ParticleSet, Resampling, Roughening, Sir, SirConfig, StaticEmitter, StudentT, Tukey, linalg,
};
use proptest::prelude::*;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// Any f32, with the troublemakers drawn often.
fn wild() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(f32::NEG_INFINITY),
        Just(1e30f32),
        Just(-1e30f32),
        Just(-0.0f32),
        Just(0.0f32),
        Just(f32::MIN_POSITIVE / 4.0),
        -3000.0f32..3000.0,
        -4.0f32..4.0,
        any::<f32>(),
    ]
}

fn bearing() -> impl Strategy<Value = Bearing> {
    (wild(), wild(), wild(), prop_oneof![wild(), 0.001f32..0.1]).prop_map(|(x, y, t, s)| Bearing {
        vehicle: [x, y],
        theta: t,
        sigma: s,
    })
}

/// Mostly sane bearings with some poison mixed in, so the fixes get past their first check.
fn drive() -> impl Strategy<Value = Vec<Bearing>> {
    let sane = (
        -500.0f32..500.0,
        -500.0f32..500.0,
        -3.2f32..3.2,
        0.001f32..0.1,
    )
        .prop_map(|(x, y, t, s)| Bearing {
            vehicle: [x, y],
            theta: t,
            sigma: s,
        });
    prop::collection::vec(prop_oneof![4 => sane, 1 => bearing()], 0..24)
}

fn finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn check_fix(r: Result<foxhunt_core::Fix, foxhunt_core::Error>) {
    if let Ok(f) = r {
        assert!(finite(&f.position), "{f:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn angles(a in wild(), b in wild(), c in wild(), d in wild()) {
        let w = wrap(a);
        if a.is_finite() {
            prop_assert!(w > -core::f32::consts::PI - 1e-6 && w <= core::f32::consts::PI + 1e-6);
        }
        let _ = (predicted(&[a, b], &[c, d]), azimuth_to_theta(a), theta_to_azimuth(b));
    }

    #[test]
    fn likelihoods(r in wild(), s in wild(), p in wild()) {
        let _ = (Gaussian.ln(r, s), Gaussian.irls_weight(r, s));
        let _ = (Huber { c: p }.ln(r, s), Huber { c: p }.irls_weight(r, s));
        let _ = (Cauchy.ln(r, s), Cauchy.irls_weight(r, s));
        let _ = (StudentT { nu: p }.ln(r, s), StudentT { nu: p }.irls_weight(r, s));
        let _ = (GaussianUniform { eps: p }.ln(r, s), GaussianUniform { eps: p }.irls_weight(r, s));
        let _ = (Tukey { c: p }.ln(r, s), Tukey { c: p }.irls_weight(r, s));
        let h = Huber::default().irls_weight(r, s);
        prop_assert!(h.is_nan() || h <= 1.0);
        let t = Tukey::default().irls_weight(r, s);
        prop_assert!(t.is_nan() || (0.0..=1.0).contains(&t));
    }

    #[test]
    fn linear_algebra(m in prop::array::uniform4(wild())) {
        let a = [[m[0], m[1]], [m[2], m[3]]];
        if let Some(inv) = linalg::inverse2(&a) { prop_assert!(finite(&[inv[0][0], inv[0][1], inv[1][0], inv[1][1]])); }
        let _ = linalg::solve2(&a, &[m[1], m[2]]);
        let _ = linalg::eigen2(&a);
        let _ = linalg::cholesky(&a);
        if let Ok(e) = ellipse::Ellipse::from_covariance(&a, m[0]) {
            prop_assert!(finite(&[e.major, e.minor, e.orientation]));
        }
        if let Ok(c) = ellipse::cep50(&a) { prop_assert!(c.is_finite()); }
    }

    #[test]
    fn particle_sets(lw in prop::array::uniform8(wild()), xs in prop::array::uniform8(wild()), seed in any::<u64>()) {
        let mut rng = XorShiftRng::seed_from_u64(seed);
        let mut p = ParticleSet::<8, 1>::new();
        p.log_weights = lw;
        for (s, x) in p.states.iter_mut().zip(xs) { *s = [x]; }
        match p.normalise() {
            Ok(ess) => {
                prop_assert!((1.0..=8.0 + 1e-4).contains(&ess), "ess {ess}");
                prop_assert!(p.weights.iter().all(|w| w.is_finite() && *w >= 0.0));
            }
            Err(_) => prop_assert!(p.weights.iter().all(|w| (*w - 0.125).abs() < 1e-6)),
        }
        let m = p.mean();
        let _ = p.covariance(&m);
        let _ = p.spread();
        for s in [Resampling::Multinomial, Resampling::Stratified, Resampling::Systematic, Resampling::Residual] {
            let mut counts = [0u32; 8];
            let mut w = [0.0f32; 8];
            for (wi, l) in w.iter_mut().zip(lw) { *wi = l; }
            s.counts(&w, &mut rng, &mut counts);
            prop_assert_eq!(counts.iter().sum::<u32>(), 8);
            p.resample(s, &mut rng);
        }
        let mean = [xs[0]];
        let cov = [[xs[1]]];
        for r in [Roughening::None, Roughening::Gordon { k: xs[2] }, Roughening::Shrinkage { scale: xs[3] }] {
            r.apply(&mut p, &mean, &cov, &mut rng);
        }
        let _ = p.draw_gaussian(&mean, &cov, &mut rng);
    }

    #[test]
    fn batch_fixes(bs in drive(), start in prop::array::uniform2(wild()), angle in wild()) {
        check_fix(ple::ple(&bs));
        check_fix(ple::bias_compensated_ple(&bs));
        check_fix(ple::wiv(&bs, 3));
        check_fix(ml::ml(&bs, None, &Gaussian, Default::default()));
        check_fix(ml::ml(&bs, Some(start), &Huber::default(), Default::default()));
        check_fix(ml::ml(&bs, None, &Cauchy, Default::default()));
        if let Ok(c) = crlb::crlb(&start, &bs) { prop_assert!(c.rmse.is_finite() && c.rmse > 0.0); }
        let _ = crlb::information(&start, &bs);
        if let [a, b, ..] = bs.as_slice()
            && let Ok(p) = intersection::intersect(a, b, angle)
        {
            prop_assert!(finite(&p));
        }
        let mut rng = XorShiftRng::seed_from_u64(1);
        let mut set = ParticleSet::<16, 2>::new();
        if init::initial_particles(&bs, angle, &mut set, &mut rng).is_ok() {
            prop_assert!(set.states.iter().all(|x| finite(x)));
        }
    }

    #[test]
    fn filters(cloud in prop::collection::vec(prop::array::uniform2(wild()), 0..6), zs in prop::collection::vec(bearing(), 0..8), q in wild(), k in wild()) {
        let mut rng = XorShiftRng::seed_from_u64(9);
        let config = SirConfig { policy: foxhunt_core::ResamplePolicy::BelowEss(k), roughening: Roughening::Shrinkage { scale: k }, ..Default::default() };
        let mut sir = Sir::<_, _, 16, 2>::new(StaticEmitter { process_var: q }, Cauchy, config);
        let mut gpf = Gpf::<_, _, 16, 2>::new(StaticEmitter { process_var: q }, Gaussian);
        let mut ekf = BearingEkf::new(q);
        let _ = sir.initialise(&cloud, &mut rng);
        let _ = gpf.initialise(&cloud, &mut rng);
        let _ = ekf.initialise(&cloud, &mut rng);
        for z in &zs {
            if let Ok(e) = sir.step(z, &mut rng) { prop_assert!(finite(&e.mean), "sir {e:?}"); }
            if let Ok(e) = gpf.step(z, &mut rng) { prop_assert!(finite(&e.mean), "gpf {e:?}"); }
            if let Ok(e) = ekf.step(z, &mut rng) { prop_assert!(finite(&e.mean), "ekf {e:?}"); }
        }
    }

    #[test]
    fn preprocessing(pairs in prop::collection::vec((wild(), wild()), 0..12), gate in wild()) {
        let mut p = ObservationPoint::new(gate);
        for (a, q) in pairs {
            let _ = error_weight(q);
            let _ = p.push(a, q);
        }
        if let Some(b) = p.bearing() { prop_assert!(b.is_finite()); }
    }
}

/// Every swarm variant, in SIR and GPF, on the bearing, RSSI and UNGM models: arbitrary
/// measurements (NaN, inf, wild values) and likelihoods that vanish (a Gaussian + uniform with
/// eps = 0 gives ln L = -inf far out) never panic, and every Ok estimate is finite.
mod swarms {
    use super::*;
    use foxhunt_core::{
        Afsa, Firefly, Gsa, ImprovedFirefly, Model, PathLoss, Pso, RssiMeasurement, RssiTracker,
        Swarm, Ungm, UngmObservation,
    };

    fn run_sir<M: Model<D> + Copy, S: Swarm<D> + Copy, L: Likelihood, const D: usize>(
        model: M,
        lik: L,
        swarm: S,
        cloud: &[[f32; D]],
        zs: &[M::Measurement],
    ) {
        let mut rng = XorShiftRng::seed_from_u64(5);
        let mut sir = Sir::<M, L, 12, D, S>::with_swarm(model, lik, SirConfig::default(), swarm);
        let mut gpf = Gpf::<M, L, 12, D, S>::with_swarm(model, lik, swarm);
        let _ = sir.initialise(cloud, &mut rng);
        let _ = gpf.initialise(cloud, &mut rng);
        for z in zs {
            if let Ok(e) = sir.step(z, &mut rng) {
                assert!(finite(&e.mean), "sir {e:?}");
            }
            if let Ok(e) = gpf.step(z, &mut rng) {
                assert!(finite(&e.mean), "gpf {e:?}");
            }
        }
    }

    fn all_swarms<M: Model<D> + Copy, L: Likelihood, const D: usize>(
        model: M,
        lik: L,
        cloud: &[[f32; D]],
        zs: &[M::Measurement],
    ) {
        let quick = foxhunt_core::FireflyParams {
            iterations: 2,
            ..Default::default()
        };
        let afsa = Afsa {
            tries: 3,
            iterations: 2,
            ..Afsa::default()
        };
        run_sir(model, lik, afsa, cloud, zs);
        run_sir(model, lik, Firefly { params: quick }, cloud, zs);
        run_sir(
            model,
            lik,
            ImprovedFirefly {
                params: quick,
                ..Default::default()
            },
            cloud,
            zs,
        );
        run_sir(
            model,
            lik,
            Pso {
                iterations: 2,
                ..Pso::default()
            },
            cloud,
            zs,
        );
        run_sir(
            model,
            lik,
            Gsa {
                iterations: 3,
                ..Gsa::default()
            },
            cloud,
            zs,
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        #[test]
        fn bearing_model(zs in prop::collection::vec(bearing(), 1..5), c in prop::array::uniform2(wild())) {
            let cloud = [[1000.0, 800.0], [1010.0, 790.0], c];
            all_swarms(StaticEmitter { process_var: 1.0 }, Gaussian, &cloud, &zs);
            all_swarms(StaticEmitter { process_var: 0.0 }, GaussianUniform { eps: 0.0 }, &cloud, &zs);
        }

        #[test]
        fn rssi_model(dbm in prop::collection::vec(prop::array::uniform3(wild()), 1..4), sigma in wild()) {
            let model = RssiTracker {
                anchors: [[0.0, 5.0], [5.0, 10.0], [10.0, 0.0]],
                sigma: [0.5, 0.5, sigma],
                path_loss: PathLoss { p0: -37.8, d0: 1.0, eta: 2.3 },
                dt: 0.5,
                q: [0.5, 1.0, 0.5, 1.0],
                room: Some([10.0, sigma]),
            };
            let zs: Vec<_> = dbm.into_iter().map(RssiMeasurement::all).collect();
            let cloud = [[1.0, 0.5, 1.0, 0.5], [2.0, 0.0, 1.0, 0.0]];
            all_swarms(model, Gaussian, &cloud, &zs);
        }

        #[test]
        fn ungm_model(obs in prop::collection::vec((0u32..60, wild()), 1..5), x in wild()) {
            let zs: Vec<_> = obs.into_iter().map(|(k, z)| UngmObservation { k, z }).collect();
            all_swarms(Ungm::default(), Gaussian, &[[0.1], [x]], &zs);
            all_swarms(Ungm { process_var: x, measurement_var: 1.0 }, Cauchy, &[[0.1], [2.0]], &zs);
        }
    }
}

/// Found by the property test above: a covariance near f32's range made the ellipse's axes
/// overflow to infinity instead of failing cleanly.
#[test]
fn huge_covariance_gives_finite_axes_or_an_error() {
    let a = [[3.256_047e38, 1e30], [1e30, 1e30]];
    if let Ok(e) = ellipse::Ellipse::from_covariance(&a, 0.95) {
        assert!(e.major.is_finite() && e.minor.is_finite());
    }
    if let Ok(c) = ellipse::cep50(&a) {
        assert!(c.is_finite());
    }
}
