//! The consensus past a ghost and an offset, pure noise, clean data, bad settings.

use super::*;
use crate::error::Error;
use crate::fix::bias::{BiasPrior, StationSlot};
use crate::likelihood::Gaussian;
use crate::model::bearing::{Bearing, predicted, wrap};
use crate::random;
use core::f32::consts::PI;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

const DEG: f32 = PI / 180.0;

/// 240 bearings on a U around (0, 1500): east along y = 0, north, back west along
/// y = 3000; a quarter of them (60..120) see a ghost at `ghost`, a share `wild` are
/// uniform.
fn u_drive(ghost: Option<[f32; 2]>, wild: f32, bias: f32, rng: &mut XorShiftRng) -> [Bearing; 240] {
    let e = [0.0, 1500.0];
    core::array::from_fn(|k| {
        let s = 8000.0 * k as f32 / 240.0;
        let v = if s < 3000.0 {
            [-1500.0 + s, 0.0]
        } else if s < 5000.0 {
            [1500.0, 0.0 + (s - 3000.0) * 1.5]
        } else {
            [1500.0 - (s - 5000.0), 3000.0]
        };
        let target = match ghost {
            Some(g) if (60..120).contains(&k) => g,
            _ => e,
        };
        let theta = if random::uniform(rng) < wild {
            random::uniform_in(rng, -PI, PI)
        } else {
            predicted(&target, &v) + bias + 2.0 * DEG * random::normal(rng)
        };
        Bearing {
            vehicle: v,
            theta: wrap(theta),
            sigma: 2.0 * DEG,
        }
    })
}

#[test]
fn consensus_finds_the_emitter_past_a_ghost_and_an_offset() {
    let mut rng = XorShiftRng::seed_from_u64(1);
    let bs = u_drive(Some([900.0, 1800.0]), 0.1, 4.0 * DEG, &mut rng);
    let mut priors = [StationSlot::new(BiasPrior::default())];
    let c = ransac(
        &bs,
        &RansacOptions::default(),
        OffsetWindow::from_stations(&bs, &priors),
        &mut rng,
    )
    .unwrap();
    let e = [0.0, 1500.0];
    assert!(
        libm::hypotf(c.position[0] - e[0], c.position[1] - e[1]) < 150.0,
        "{c:?}"
    );
    assert!(c.inliers > 120, "{c:?}");
    let mut scratch = bs;
    let f = refine(&bs, &mut scratch, &mut priors, &c, RefineOptions::default()).unwrap();
    let err = libm::hypotf(f.fix.position[0] - e[0], f.fix.position[1] - e[1]);
    assert!(err < 40.0, "{err} m: {f:?}");
    assert!(
        (f.fix.bias - 4.0 * DEG).abs() < 1.0 * DEG,
        "{}",
        f.fix.bias / DEG
    );
    // The ghost's 60 and most wild bearings are out; the emitter's are in.
    assert!((140..=170).contains(&f.kept), "{}", f.kept);
    assert!((0.85..1.2).contains(&f.scale), "{}", f.scale);
    assert!(chance(f.kept, 240, c.threshold, c.hypotheses, 18.0 * DEG).unwrap() < 1e-20);
}

#[test]
fn pure_noise_is_not_significant() {
    let mut rng = XorShiftRng::seed_from_u64(2);
    let bs = u_drive(None, 1.0, 0.0, &mut rng);
    let priors = [StationSlot::new(BiasPrior::default())];
    let c = ransac(
        &bs,
        &RansacOptions::default(),
        OffsetWindow::from_stations(&bs, &priors),
        &mut rng,
    )
    .unwrap();
    let p = chance(
        c.inliers,
        c.candidates,
        c.threshold,
        c.hypotheses,
        18.0 * DEG,
    )
    .unwrap();
    assert!(p > 0.01, "{p}: {c:?}");
}

#[test]
fn clean_data_keep_every_bearing() {
    let mut rng = XorShiftRng::seed_from_u64(3);
    let bs = u_drive(None, 0.0, 0.0, &mut rng);
    let mut priors = [StationSlot::new(BiasPrior::calibrated(0.0))];
    let c = ransac(
        &bs,
        &RansacOptions::default(),
        OffsetWindow::from_stations(&bs, &priors),
        &mut rng,
    )
    .unwrap();
    let mut scratch = bs;
    let f = refine(&bs, &mut scratch, &mut priors, &c, RefineOptions::default()).unwrap();
    // At most the 0.27 % a 3-sigma cut takes from a Gaussian (plus one).
    assert!(f.kept >= 237, "{}", f.kept);
    let plain = super::super::ml::ml(&bs, None, &Gaussian, Default::default()).unwrap();
    let d = libm::hypotf(
        f.fix.position[0] - plain.position[0],
        f.fix.position[1] - plain.position[1],
    );
    assert!(d < 2.0, "{d} m from the plain ML");
}

#[test]
fn bad_settings_and_sets_are_refused() {
    let mut rng = XorShiftRng::seed_from_u64(4);
    let bs = u_drive(None, 0.0, 0.0, &mut rng);
    let w = OffsetWindow {
        centre: 0.0,
        half_width: 0.0,
    };
    let bad = RansacOptions {
        hypotheses: 0,
        ..Default::default()
    };
    assert_eq!(ransac(&bs, &bad, w, &mut rng), Err(Error::OutOfRange));
    assert_eq!(
        ransac(&bs[..1], &RansacOptions::default(), w, &mut rng),
        Err(Error::TooFewMeasurements)
    );
    assert_eq!(chance(5, 10, 0.0, 10, 0.0), Err(Error::OutOfRange));
    assert_eq!(chance(1, 10, 0.1, 10, 0.0), Ok(1.0));
}
