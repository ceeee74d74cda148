//! The field entry points (the locate pipeline, the bias-aware fix, the robust search, the
//! statistics, the evidence and channel checks, the augmented filters) fed arbitrary f32 (NaN,
//! +-inf, 1e30, -0.0, subnormals, ordinary values): nothing panics, and whatever comes back Ok
//! is finite.

use foxhunt_core::fix::bias::{self, BiasPrior, Start, StartOffsets, StationSlot};
use foxhunt_core::fix::consistency;
use foxhunt_core::fix::init::{InitOptions, initial_biased_particles};
use foxhunt_core::fix::locate::{LocateConfig, NoiseModel, Observation, Workspace, locate};
use foxhunt_core::fix::reach;
use foxhunt_core::fix::robust::{self, OffsetWindow, RansacOptions, RefineOptions};
use foxhunt_core::{
    Bearing, BiasedBearingEkf, BiasedEmitter, Filter, Gaussian, GaussianUniform, ParticleSet, Sir,
    SirConfig, Tukey, stats,
};
use proptest::prelude::*;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

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

fn finite(v: &[f32]) -> bool {
    v.iter().all(|x| x.is_finite())
}

/// Mostly sane observations of an emitter near (500, 800), with poison mixed in.
fn observations() -> impl Strategy<Value = Vec<Observation>> {
    let sane = (
        -500.0f32..500.0,
        -500.0f32..500.0,
        -0.2f32..0.2,
        0.005f32..0.1,
        0.0f32..100.0,
        prop_oneof![Just(None), Just(Some(145.0f32)), Just(Some(146.5f32))],
        0u16..3,
        any::<bool>(),
    )
        .prop_map(|(x, y, e, s, t, f, src, stamped)| Observation {
            bearing: Bearing {
                vehicle: [x, y],
                theta: (800.0 - y).atan2(500.0 - x) + e,
                sigma: s,
            },
            time_s: t,
            freq_mhz: f,
            station: src,
            stamped,
        });
    let poison = (
        wild(),
        wild(),
        wild(),
        wild(),
        wild(),
        prop_oneof![Just(None), wild().prop_map(Some)],
        any::<u16>(),
        any::<bool>(),
    )
        .prop_map(|(x, y, th, s, t, f, src, stamped)| Observation {
            bearing: Bearing {
                vehicle: [x, y],
                theta: th,
                sigma: s,
            },
            time_s: t,
            freq_mhz: f,
            station: src,
            stamped,
        });
    prop::collection::vec(prop_oneof![6 => sane, 1 => poison], 0..40)
}

fn check_source(s: &foxhunt_core::fix::locate::Source) {
    let v = [
        s.position[0],
        s.position[1],
        s.covariance[0][0],
        s.covariance[0][1],
        s.covariance[1][1],
        s.ellipse.major,
        s.ellipse.minor,
        s.ellipse.orientation,
        s.ellipse_scale,
        s.cep50,
        s.crlb,
        s.bias,
        s.bias_sd,
        s.sigma,
        s.effective,
        s.dof,
        s.p_value,
        s.chance,
    ];
    assert!(finite(&v), "{s:?}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn the_pipeline(obs in observations(), seed in any::<u64>(), sd in wild(), width in wild(), known in any::<bool>()) {
        let mut rng = XorShiftRng::seed_from_u64(seed);
        let mut work = Workspace::<32>::new();
        let config = LocateConfig {
            noise: if known { NoiseModel::Known } else { NoiseModel::Estimated },
            ..LocateConfig::default()
        };
        if let Ok(r) = locate::<3, 3, _>(&obs, &config, work.buffers(), &mut rng) {
            for e in r.emitters() { check_source(e); }
            for o in r.others() { check_source(&o.source); }
            let rej = r.rejected;
            let total = rej.invalid + rej.unknown_station + rej.over_capacity + rej.repeated + rej.time_backwards + r.accepted;
            prop_assert_eq!(total as usize, obs.len());
        }
        // Arbitrary settings and priors are refused, never a panic.
        let odd = LocateConfig {
            channel_width_mhz: width,
            ..LocateConfig::default()
        };
        let mut odd_work = Workspace::<32, 3>::with_prior(BiasPrior { mean: 0.0, sd });
        let _ = locate::<2, 1, _>(&obs, &odd, odd_work.buffers(), &mut rng);
    }

    #[test]
    fn bias_aware_fixes(obs in observations(), start in prop::array::uniform2(wild()), mean in wild(), sd in wild()) {
        let bs: Vec<Bearing> = obs.iter().map(|o| o.bearing).collect();
        let prior = BiasPrior { mean, sd };
        for p in [prior, BiasPrior::default(), BiasPrior::calibrated(0.0)] {
            if let Ok(f) = bias::ml(&bs, p, Some(start), &Tukey::default(), Default::default()) {
                prop_assert!(finite(&f.position) && finite(&[f.bias, f.bias_sd, f.chi2, f.parameters]));
            }
            let mut table = [StationSlot::new(p); 3];
            if let Ok(f) = bias::ml_sources(&obs, &mut table, Start { position: start, offsets: StartOffsets::Prior }, &GaussianUniform::default(), Default::default()) {
                prop_assert!(finite(&f.position) && finite(&f.covariance.concat()));
            }
            if let Ok(c) = bias::crlb(&start, &bs, p) { prop_assert!(c.rmse.is_finite() && c.rmse > 0.0); }
            // The profile likelihood and the region's reach, any line, any scale.
            let options = bias::BiasedOptions { scale: sd.abs(), position_sd_m: mean.abs(), ..Default::default() };
            let begin = Start { position: start, offsets: StartOffsets::Common(0.0) };
            if let Ok(q) = bias::profile(&obs, &mut table, begin, [mean, sd], &Gaussian, options) {
                prop_assert!(finite(&q.position) && finite(&[q.deviance, q.along_sd]));
            }
            if let Ok(f) = bias::ml_sources(&obs, &mut table, begin, &Gaussian, Default::default()) {
                let fit = reach::Fit { fix: &f, scale: sd, inflation: mean };
                if let Ok(r) = reach::reach(&obs, &mut table, fit, &f.covariance, 5.99, 1e5) {
                    prop_assert!(finite(&r.covariance.concat()) && r.stretch.is_finite());
                }
            }
        }
        if let Ok(c) = bias::calibrate(&bs, start) { prop_assert!(finite(&[c.bias, c.sd, c.sigma, c.effective])); }
        let mut rng = XorShiftRng::seed_from_u64(3);
        let window = OffsetWindow { centre: mean, half_width: sd };
        if let Ok(c) = robust::ransac(&obs, &RansacOptions::default(), window, &mut rng) {
            prop_assert!(finite(&c.position));
            let mut scratch = obs.clone();
            let mut table = [StationSlot::default(); 3];
            if let Ok(f) = robust::refine(&obs, &mut scratch, &mut table, &c, RefineOptions::default()) {
                prop_assert!(finite(&f.fix.position) && f.scale.is_finite());
            }
        }
        let tau = consistency::correlation_time(bs.iter().map(|b| b.theta), bs.len() as u32);
        prop_assert!(tau.is_finite() && tau >= 1.0);
    }

    #[test]
    fn statistics(a in wild(), b in wild(), x in wild(), k in any::<u32>(), n in any::<u32>()) {
        for r in [
            stats::ln_gamma(a), stats::ln_beta(a, b), stats::beta_inc(a, b, x),
            stats::beta_inc_upper(a, b, x), stats::gamma_inc(a, x), stats::gamma_inc_upper(a, x),
            stats::chi2_sf(x, a), stats::chi2_quantile(x, a), stats::f_quantile(x, a, b),
            stats::t_quantile(x, a), stats::binomial_tail(k % 1000, n % 1000, x),
            consistency::ellipse_scale(x, Some(a)), consistency::chi2_p_value(a, b),
            robust::chance(k % 500, n % 500, a, k, b),
        ]
        .into_iter()
        .flatten()
        {
            prop_assert!(r.is_finite(), "{r}");
        }
    }

    #[test]
    fn augmented_filters(obs in observations(), mean in wild(), sd in wild(), q in wild()) {
        let bs: Vec<Bearing> = obs.iter().map(|o| o.bearing).collect();
        let mut rng = XorShiftRng::seed_from_u64(11);
        let mut set = ParticleSet::<16, 3>::new();
        let prior = BiasPrior { mean, sd };
        if initial_biased_particles(&bs, prior, &InitOptions::default(), &mut set, &mut rng).is_ok() {
            prop_assert!(set.states.iter().all(|x| finite(x)));
        }
        let mut sir = Sir::<_, _, 16, 3>::new(BiasedEmitter { process_var: q }, GaussianUniform::default(), SirConfig::default());
        let mut ekf = BiasedBearingEkf::new(q);
        let _ = sir.initialise(&set.states, &mut rng);
        let _ = ekf.initialise(&set.states, &mut rng);
        for z in &bs {
            if let Ok(e) = sir.step(z, &mut rng) { prop_assert!(finite(&e.mean)); }
            if let Ok(e) = ekf.step(z, &mut rng) { prop_assert!(finite(&e.mean)); }
        }
        if let Ok(c) = consistency::check_cloud(sir.particles(), &bs) {
            prop_assert!(c.information_ratio.is_finite());
        }
    }
}
