//! The guidance entry points (beliefs, hypotheses, the planner, the stop rule) fed arbitrary
//! f32 (NaN, +-inf, 1e30, zeros, subnormals, ordinary values): nothing panics, and whatever
//! comes back Ok is finite.

use foxhunt_core::Bearing;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::guidance::belief::{Belief, Hypotheses};
use foxhunt_core::guidance::plan::{Cost, FreeHeadings, Objective, PlanOptions, Pose, plan};
use foxhunt_core::guidance::stop::{FixQuality, StopRule, verdict};
use proptest::prelude::*;

fn wild() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(-1e30f32),
        Just(0.0f32),
        Just(f32::MIN_POSITIVE / 4.0),
        -5000.0f32..5000.0,
        -4.0f32..4.0,
        0.001f32..0.2,
    ]
}

fn bearings() -> impl Strategy<Value = Vec<Bearing>> {
    prop::collection::vec(
        (wild(), wild(), wild(), wild()).prop_map(|(x, y, t, s)| Bearing {
            vehicle: [x, y],
            theta: t,
            sigma: s,
        }),
        0..12,
    )
}

proptest! {
    #[test]
    fn guidance_never_panics_nor_returns_nan(
        bs in bearings(),
        e in (wild(), wild()),
        prior_sd in wild(),
        v in (wild(), wild()),
        objective in 0u8..4,
        depth in 0usize..4,
        sigma in wild(),
        target in wild(),
    ) {
        let prior = BiasPrior { mean: 0.0, sd: prior_sd };
        let e = [e.0, e.1];
        if let Ok(b) = Belief::from_bearings(e, &bs, prior, 2e4) {
            prop_assert!(b.trace().is_finite() && b.cep50().is_finite());
            let objective = match objective {
                0 => Objective::DOptimal,
                1 => Objective::AOptimal,
                2 => Objective::Goal {
                    target_m: target,
                    cost: Cost::Time,
                },
                _ => Objective::Goal {
                    target_m: target,
                    cost: Cost::Distance,
                },
            };
            let options = PlanOptions {
                objective,
                depth,
                horizon_s: 60.0,
                rate_hz: 1.0,
                sigma,
                sample_m: 100.0,
            };
            let headings = FreeHeadings { count: 8, ..FreeHeadings::default() };
            let pose = Pose { position: [v.0, v.1], heading: 0.0 };
            if let Ok(c) = plan(&[b], pose, &headings, options) {
                prop_assert!(c.score.is_finite() && c.leg.seconds.is_finite());
            }
        }
        if let Ok(h) = Hypotheses::spread(e, &[[1e6, 0.0], [0.0, 1e4]], [v.0, v.1], 0.15) {
            prop_assert!(h.points().iter().flatten().all(|x| x.is_finite()));
        }
        let q = FixQuality { consistent: true, effective: 20.0, offset_beyond_prior: false };
        if let Ok(x) = verdict(e, &bs, prior, q, &StopRule::default()) {
            prop_assert!(x.cep50_m.is_finite() && x.offset_known_cep50_m.is_finite());
        }
    }
}
