use super::*;
use crate::model::bearing::predicted;
use crate::random;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

const EMITTER: [f32; 2] = [1200.0, 800.0];

fn drive(k: usize) -> [f32; 2] {
    // An L: east for 60 s at 10 m/s, then north.
    let s = 10.0 * k as f32;
    if s < 600.0 {
        [s, 0.0]
    } else {
        [600.0, s - 600.0]
    }
}

fn bearing(k: usize, sd: f32, rng: &mut XorShiftRng) -> Bearing {
    let v = drive(k % 200);
    Bearing {
        vehicle: v,
        theta: predicted(&EMITTER, &v) + sd * random::normal(rng),
        sigma: 1.0,
    }
}

#[test]
fn a_drive_converges_and_the_ellipse_holds_the_emitter() {
    let mut rng = XorShiftRng::seed_from_u64(7);
    let mut search = XorShiftRng::seed_from_u64(1);
    let mut t = WindowFix::default();
    let mut last = None;
    for k in 0..150 {
        let f = t
            .push(
                &bearing(k, 1.5 * DEG, &mut rng),
                k as i64 * 1000,
                &mut search,
            )
            .unwrap();
        assert!(f.passes <= MAX_PASSES, "{f:?}");
        last = Some(f);
    }
    let f = last.unwrap();
    assert_eq!(f.status, Status::Valid, "{f:?}");
    let err = libm::hypotf(f.position[0] - EMITTER[0], f.position[1] - EMITTER[1]);
    // 120 bearings of 1.5 degrees at about 1 km: tens of metres; the 95 % ellipse's
    // semi-major axis bounds the error here (one seed, a loose check of the scale).
    assert!(err < f.major, "{err} m against {f:?}");
    assert!(
        (1.0 * DEG..2.2 * DEG).contains(&f.sigma),
        "{}",
        f.sigma / DEG
    );
    assert_eq!(f.window, 120);
}

#[test]
fn wild_bearings_get_no_say() {
    let mut rng = XorShiftRng::seed_from_u64(8);
    let mut search = XorShiftRng::seed_from_u64(1);
    let mut t = WindowFix::default();
    let mut f = None;
    for k in 0..150 {
        let mut b = bearing(k, 1.0 * DEG, &mut rng);
        if k % 5 == 0 {
            b.theta = random::uniform_in(&mut rng, -PI, PI);
        }
        f = Some(t.push(&b, k as i64 * 1000, &mut search).unwrap());
    }
    let f = f.unwrap();
    let err = libm::hypotf(f.position[0] - EMITTER[0], f.position[1] - EMITTER[1]);
    assert!(err < 60.0 && f.status == Status::Valid, "{err} m: {f:?}");
    assert!(f.used < 110, "{f:?}");
}

#[test]
fn parallel_bearings_and_a_parked_vehicle_are_degenerate() {
    let mut search = XorShiftRng::seed_from_u64(1);
    let mut t = WindowFix::default();
    for k in 0..20 {
        // Driving straight at the emitter: one line.
        let v = [60.0 * k as f32, 40.0 * k as f32];
        let b = Bearing {
            vehicle: v,
            theta: predicted(&[6000.0, 4000.0], &v),
            sigma: 1.0,
        };
        let f = t.push(&b, k * 1000, &mut search).unwrap();
        assert!(
            matches!(f.status, Status::TooFew | Status::Degenerate),
            "{f:?}"
        );
    }
    let mut search = XorShiftRng::seed_from_u64(1);
    let mut t = WindowFix::default();
    let mut rng = XorShiftRng::seed_from_u64(9);
    for k in 0..20 {
        let b = Bearing {
            vehicle: [5.0, 5.0],
            theta: random::uniform_in(&mut rng, -PI, PI),
            sigma: 1.0,
        };
        let f = t.push(&b, k * 1000, &mut search).unwrap();
        assert!(!f.status.has_position(), "{f:?}");
    }
}

#[test]
fn the_window_is_bounded_by_count_and_age() {
    let mut rng = XorShiftRng::seed_from_u64(10);
    let mut search = XorShiftRng::seed_from_u64(1);
    let mut t = WindowFix::new(WindowConfig {
        window: 50,
        max_age_ms: 30_000,
        ..WindowConfig::default()
    });
    for k in 0..100 {
        let f = t
            .push(&bearing(k, DEG, &mut rng), k as i64 * 500, &mut search)
            .unwrap();
        assert!(f.window <= 50);
    }
    // 30 s at two a second: 61 would fit the age; the count cuts first.
    assert_eq!(t.len(), 50);
    for k in 100..110 {
        t.push(&bearing(k, DEG, &mut rng), k as i64 * 5000, &mut search)
            .unwrap();
    }
    assert_eq!(t.len(), 7, "30 s of bearings 5 s apart, both ends in");
    assert!(
        t.set_config(WindowConfig {
            window: 0,
            ..WindowConfig::default()
        })
        .is_err()
    );
}

#[test]
fn bad_bearings_are_refused_and_counted() {
    let mut search = XorShiftRng::seed_from_u64(1);
    let mut t = WindowFix::default();
    let b = Bearing {
        vehicle: [f32::NAN, 0.0],
        theta: 0.0,
        sigma: 1.0,
    };
    assert_eq!(t.push(&b, 0, &mut search), Err(WindowError::BadBearing));
    assert_eq!(t.counters().refused, 1);
    assert!(t.is_empty());
}

/// Bearings at drive steps `ks`, each off the truth by its error (degrees), pushed in order:
/// the last update.
fn pushed(ks: &[usize], errors_deg: &[f32]) -> Update {
    let mut search = XorShiftRng::seed_from_u64(1);
    let mut t = WindowFix::default();
    let mut last = None;
    for (i, (&k, &e)) in ks.iter().zip(errors_deg).enumerate() {
        let v = drive(k);
        let b = Bearing {
            vehicle: v,
            theta: predicted(&EMITTER, &v) + e * DEG,
            sigma: 1.0,
        };
        last = t.push(&b, i as i64 * 1000, &mut search).ok();
    }
    last.unwrap()
}

#[test]
fn a_handful_of_bearings_keeps_every_good_one() {
    // Bearings of about 2 degrees: the first three fit with one degree of freedom, often
    // far better than their noise, and the next ones are noise chance allows, not wild.
    let ks = [0, 20, 40, 60, 80];
    let f = pushed(&ks, &[0.3, -0.4, 0.2, 3.0, -2.5]);
    assert_eq!(f.used, 5, "{f:?}");
    assert!(f.sigma > 1.0 * DEG, "{}", f.sigma / DEG);
}

#[test]
fn a_wild_bearing_among_a_handful_is_still_wild() {
    // Ten bearings within a degree and one 40 degrees off: chance does not allow it.
    let ks: [usize; 11] = core::array::from_fn(|i| 12 * i);
    let mut errors = [0.5, -0.8, 0.3, -0.2, 0.9, -0.6, 0.1, 0.7, -0.4, 0.2, 0.0];
    errors[5] = 40.0;
    let f = pushed(&ks, &errors);
    assert_eq!(f.used, 10, "{f:?}");
    assert!(f.sigma < 1.5 * DEG, "{}", f.sigma / DEG);
}
