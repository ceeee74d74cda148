//! The offsets found with the position, the bound, several sources, calibration, bad priors.

extern crate std;

use super::*;
use crate::error::Error;
use crate::linalg::inverse_scaled;
use crate::model::bearing::{predicted, wrap};
use crate::random;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

const DEG: f32 = core::f32::consts::PI / 180.0;

/// 120 bearings on a circle of `radius` about `centre`, over `arc` radians, offset `b`.
fn arc_drive(
    e: [f32; 2],
    centre: [f32; 2],
    radius: f32,
    arc: f32,
    b: f32,
    sigma: f32,
    rng: &mut XorShiftRng,
) -> [Bearing; 120] {
    core::array::from_fn(|k| {
        let a = arc * k as f32 / 119.0;
        let v = [
            centre[0] + radius * libm::cosf(a),
            centre[1] + radius * libm::sinf(a),
        ];
        Bearing {
            vehicle: v,
            theta: wrap(predicted(&e, &v) + b + sigma * random::normal(rng)),
            sigma,
        }
    })
}

#[test]
fn a_surrounded_emitter_gives_its_offset_and_an_unchanged_position_bound() {
    let mut rng = XorShiftRng::seed_from_u64(1);
    let e = [1200.0, 800.0];
    let bs = arc_drive(
        e,
        e,
        300.0,
        2.0 * core::f32::consts::PI,
        4.0 * DEG,
        0.02,
        &mut rng,
    );
    let f = ml(
        &bs,
        BiasPrior::default(),
        None,
        &crate::Gaussian,
        Default::default(),
    )
    .unwrap();
    // sigma / sqrt(N) = 1.15 deg / 11 = 0.1 deg: 4 degrees found to a few tenths.
    assert!((f.bias - 4.0 * DEG).abs() < 0.4 * DEG, "{}", f.bias / DEG);
    assert!((f.bias_sd - 0.02 / libm::sqrtf(120.0)).abs() < 0.2 * f.bias_sd);
    assert!(libm::hypotf(f.position[0] - e[0], f.position[1] - e[1]) < 5.0);
    // Around the emitter the offset costs the position nothing.
    let plain = crate::fix::crlb::crlb(&e, &bs).unwrap().rmse;
    let aware = crlb(&e, &bs, BiasPrior::default()).unwrap().rmse;
    assert!(aware < 1.01 * plain, "{aware} {plain}");
    assert!(f.parameters > 2.99, "{}", f.parameters);
}

#[test]
fn on_a_short_arc_the_prior_governs_and_the_covariance_shows_it() {
    let mut rng = XorShiftRng::seed_from_u64(2);
    let e = [0.0, 2000.0];
    // A straight road, 400 m long, the emitter broadside 2 km away: an 11 degree spread of
    // bearings, which cannot tell an offset from a sideways shift.
    let bs: [Bearing; 120] = core::array::from_fn(|k| {
        let v = [-200.0 + 400.0 * k as f32 / 119.0, 0.0];
        Bearing {
            vehicle: v,
            theta: wrap(predicted(&e, &v) + 0.02 * random::normal(&mut rng)),
            sigma: 0.02,
        }
    });
    let prior = BiasPrior::default();
    let f = ml(&bs, prior, None, &crate::Gaussian, Default::default()).unwrap();
    let calibrated = ml(
        &bs,
        BiasPrior::calibrated(0.0),
        None,
        &crate::Gaussian,
        Default::default(),
    )
    .unwrap();
    // The offset is barely measured: its sd stays near the prior's.
    assert!(f.bias_sd > 0.9 * prior.sd, "{}", f.bias_sd / DEG);
    assert!(f.parameters < 2.2, "{}", f.parameters);
    // And the position's cross-range sd grows toward range x prior sd (2 km x 6 deg).
    let cross = libm::sqrtf(f.covariance[0][0]);
    let plain = libm::sqrtf(calibrated.covariance[0][0]);
    assert!(cross > 100.0 && cross > 5.0 * plain, "{cross} vs {plain}");
    let bound = crlb(&e, &bs, prior).unwrap();
    assert!(
        (bound.rmse - libm::sqrtf(f.covariance[0][0] + f.covariance[1][1])).abs()
            < 0.1 * bound.rmse
    );
}

#[test]
fn three_by_three_information_matches_the_bound() {
    let mut rng = XorShiftRng::seed_from_u64(3);
    let e = [500.0, 900.0];
    let bs = arc_drive(e, [0.0, 0.0], 400.0, 1.5, 0.0, 0.03, &mut rng);
    let prior = BiasPrior {
        mean: 0.0,
        sd: 0.05,
    };
    let j = information(&e, &bs, prior).unwrap();
    let c = inverse_scaled(&j).unwrap();
    let b = crlb(&e, &bs, prior).unwrap();
    assert!((libm::sqrtf(c[0][0] + c[1][1]) - b.rmse).abs() < 1e-3 * b.rmse);
    assert!((libm::sqrtf(c[2][2]) - b.bias_sd).abs() < 1e-3 * b.bias_sd);
    assert!((j[2][2] - (120.0 / (0.03 * 0.03) + 400.0)).abs() < 1.0);
    // A calibrated unit: the plain 2 x 2 bound.
    let cal = crlb(&e, &bs, BiasPrior::calibrated(0.0)).unwrap();
    let plain = crate::fix::crlb::crlb(&e, &bs).unwrap();
    assert!((cal.rmse - plain.rmse).abs() < 1e-3 * plain.rmse);
}

#[test]
fn calibration_measures_the_offset_with_sigma_over_root_n() {
    let mut rng = XorShiftRng::seed_from_u64(4);
    let e = [300.0, 700.0];
    let mut bs = arc_drive(e, [0.0, 0.0], 200.0, 1.0, -3.0 * DEG, 0.03, &mut rng);
    bs[7].theta += 1.0; // a wild bearing
    bs[9].sigma = -1.0; // an unusable one
    let c = calibrate(&bs, e).unwrap();
    assert_eq!((c.used, c.rejected), (118, 2));
    assert!(
        (c.bias + 3.0 * DEG).abs() < 4.0 * c.sd,
        "{} +- {}",
        c.bias / DEG,
        c.sd / DEG
    );
    assert!((c.sigma - 0.03).abs() < 0.005, "{}", c.sigma);
    // White noise: N_eff near N, the sd near sigma / sqrt(N).
    assert!(c.effective > 80.0, "{}", c.effective);
    assert!((c.sd - 0.03 / libm::sqrtf(118.0)).abs() < 0.3 * c.sd);
    assert_eq!(calibrate(&bs[..1], e), Err(Error::TooFewMeasurements));
}

/// A sighting with the station that took it.
#[derive(Clone, Copy)]
struct S(Bearing, usize);
impl Sighting for S {
    fn bearing(&self) -> &Bearing {
        &self.0
    }
    fn station(&self) -> usize {
        self.1
    }
}

#[test]
fn several_stations_get_their_own_offsets() {
    let mut rng = XorShiftRng::seed_from_u64(5);
    let e = [1000.0, 1000.0];
    let bs = arc_drive(e, e, 500.0, 6.0, 0.0, 0.01, &mut rng);
    let items: [S; 120] = core::array::from_fn(|k| {
        let src = k % 2;
        let mut b = bs[k];
        b.theta = wrap(b.theta + if src == 0 { 2.0 * DEG } else { -5.0 * DEG });
        S(b, src)
    });
    let mut stations = [StationSlot::default(); 4];
    let f = ml_sources(
        &items,
        &mut stations,
        Start {
            position: [900.0, 1100.0],
            offsets: StartOffsets::Prior,
        },
        &crate::Gaussian,
        Default::default(),
    )
    .unwrap();
    let b0 = stations[0].offset().0;
    let b1 = stations[1].offset().0;
    assert!((b0 - 2.0 * DEG).abs() < 0.3 * DEG, "{}", b0 / DEG);
    assert!((b1 + 5.0 * DEG).abs() < 0.3 * DEG, "{}", b1 / DEG);
    assert_eq!(f.stations, 2);
    assert_eq!((stations[0].used(), stations[1].used()), (60, 60));
    // Unseen stations keep their prior.
    assert_eq!(stations[2].offset(), (0.0, DEFAULT_BIAS_SD));
    assert_eq!(stations[3].used(), 0);
    assert!(libm::hypotf(f.position[0] - e[0], f.position[1] - e[1]) < 3.0);
}

/// Fixed stations: each sees the emitter from one place, so its offset is the prior's alone
/// and the position's covariance is the prior's share (range x prior sd across each line).
#[test]
fn fixed_stations_lean_on_their_priors_and_the_covariance_shows_it() {
    let mut rng = XorShiftRng::seed_from_u64(6);
    let e = [0.0f32, 0.0];
    let sites = [[-8000.0f32, 0.0], [0.0, -8000.0], [6000.0, 6000.0]];
    let offsets = [2.0 * DEG, -3.0 * DEG, 1.0 * DEG];
    let prior = BiasPrior {
        mean: 0.0,
        sd: 3.0 * DEG,
    };
    let items: [S; 900] = core::array::from_fn(|k| {
        let s = k % 3;
        let v = sites[s];
        S(
            Bearing {
                vehicle: v,
                theta: wrap(predicted(&e, &v) + offsets[s] + 0.03 * random::normal(&mut rng)),
                sigma: 0.03,
            },
            s,
        )
    });
    let mut stations = [StationSlot::new(prior); 3];
    let f = ml_sources(
        &items,
        &mut stations,
        Start {
            position: [100.0, -100.0],
            offsets: StartOffsets::Prior,
        },
        &crate::Gaussian,
        Default::default(),
    )
    .unwrap();
    // Three directions for five unknowns: the bearings tie the offsets to the position and to
    // each other (one combination each), but measure at most about half of any offset, which
    // keeps more than 0.6 of its prior's sd.
    for s in &stations {
        assert!(s.measured() < 0.6, "{}", s.measured());
        assert!(s.offset().1 > 0.6 * prior.sd, "{}", s.offset().1 / DEG);
    }
    // Three stations 8 km out with 3-degree priors: a few hundred metres, not the few metres
    // the noise alone (1.7 degrees over 300 bearings each) would say.
    let rmse = libm::sqrtf(f.covariance[0][0] + f.covariance[1][1]);
    assert!(rmse > 250.0 && rmse < 600.0, "{rmse}");
    let bound = crlb_stations(&e, &items, &mut stations).unwrap();
    assert!(
        (bound.rmse / rmse - 1.0).abs() < 0.05,
        "{} {rmse}",
        bound.rmse
    );
    // And the error is of that size, not the noise's: within 3 sds.
    let err = libm::hypotf(f.position[0] - e[0], f.position[1] - e[1]);
    assert!(err < 3.0 * rmse, "{err} {rmse}");
}

/// Hundreds of stations, each a few bearings of its own: the arrow's elimination keeps the
/// work linear and every offset its own.
#[test]
fn hundreds_of_stations_each_with_its_own_offset() {
    let mut rng = XorShiftRng::seed_from_u64(7);
    let e = [300.0f32, -200.0];
    const N: usize = 300;
    let items: [S; 4 * N] = core::array::from_fn(|k| {
        let s = k / 4;
        let a = 2.0 * core::f32::consts::PI * s as f32 / N as f32;
        // Each station drives a short arc 2 km out, so its offset is partly measured.
        let a = a + 0.02 * (k % 4) as f32;
        let v = [2000.0 * libm::cosf(a), 2000.0 * libm::sinf(a)];
        let b = ((s % 7) as f32 - 3.0) * DEG;
        S(
            Bearing {
                vehicle: v,
                theta: wrap(predicted(&e, &v) + b + 0.01 * random::normal(&mut rng)),
                sigma: 0.01,
            },
            s,
        )
    });
    let mut stations = [StationSlot::default(); N];
    let f = ml_sources(
        &items,
        &mut stations,
        Start {
            position: [0.0, 0.0],
            offsets: StartOffsets::Prior,
        },
        &crate::Gaussian,
        Default::default(),
    )
    .unwrap();
    assert_eq!(f.stations, N as u32);
    assert!(libm::hypotf(f.position[0] - e[0], f.position[1] - e[1]) < 5.0);
    // Surrounded by stations, the offsets are found: within 4 sd of the truth each.
    for (s, row) in stations.iter().enumerate() {
        let truth = ((s % 7) as f32 - 3.0) * DEG;
        let (b, sd) = row.offset();
        assert!(
            (b - truth).abs() < 4.0 * sd,
            "{s}: {} +- {}",
            b / DEG,
            sd / DEG
        );
    }
}

#[test]
fn bad_priors_are_refused() {
    let bs = [Bearing {
        vehicle: [0.0, 0.0],
        theta: 0.0,
        sigma: 0.01,
    }; 3];
    let nan = BiasPrior {
        mean: 0.0,
        sd: f32::NAN,
    };
    assert_eq!(
        ml(
            &bs,
            nan,
            Some([1.0, 1.0]),
            &crate::Gaussian,
            Default::default()
        ),
        Err(Error::NonFinite)
    );
    let neg = BiasPrior {
        mean: 0.0,
        sd: -1.0,
    };
    assert_eq!(crlb(&[1.0, 1.0], &bs, neg), Err(Error::OutOfRange));
}

#[test]
fn the_surprise_is_the_fits_distance_from_its_prior_in_predicted_sds() {
    let prior = BiasPrior::default();
    let tau = DEFAULT_BIAS_SD;
    // The data measured 3/4 of the offset's variance: the estimate's spread is tau^2 * 3/4.
    let sd = tau * 0.5;
    let z = prior.surprise(0.3, sd);
    assert!((z - 0.3 / (0.75f32.sqrt() * tau)).abs() < 1e-4, "{z}");
    // A calibrated unit, or no prior, has nothing to contradict.
    assert_eq!(BiasPrior::calibrated(0.1).surprise(1.0, 0.0), 0.0);
    let none = BiasPrior {
        mean: 0.0,
        sd: f32::INFINITY,
    };
    assert_eq!(none.surprise(1.0, 0.1), 0.0);
    // The difference wraps: 350 degrees from a -10 degree prior is 0.
    let near = BiasPrior {
        mean: -10.0 * DEG,
        sd: tau,
    };
    assert!(near.surprise(350.0 * DEG, sd).abs() < 1e-3);
}

#[test]
fn the_circle_finds_a_large_offset_and_leaves_the_fit_as_it_was() {
    // Three quarters of a 600 m circle round an emitter 400 m from its centre: the drive turns,
    // so a 72 degree offset (an array indexed one element off) shows as one clear minimum.
    let mut rng = XorShiftRng::seed_from_u64(7);
    let e = [400.0, 0.0];
    let bs = arc_drive(e, [0.0, 0.0], 600.0, 4.7, 72.0 * DEG, DEG, &mut rng);
    let free = BiasPrior {
        mean: 0.0,
        sd: f32::INFINITY,
    };
    let mut table = [StationSlot::new(free)];
    let start = Start {
        position: e,
        offsets: StartOffsets::Common(72.0 * DEG),
    };
    let fix = ml_sources(
        &bs,
        &mut table,
        start,
        &crate::likelihood::Gaussian,
        BiasedOptions::default(),
    )
    .unwrap();
    let before = table[0].offset();
    let c = offset_circle(&bs, &mut table, 0, fix.position, BiasedOptions::default()).unwrap();
    let best = OffsetCircle::offset(c.best);
    assert!((wrap(best - 72.0 * DEG)).abs() <= 7.5 * DEG, "{c:?}");
    assert!(c.second_gap() > 9.0, "{c:?}");
    assert!(!c.rival(fix.bias, 30.0 * DEG, 9.0), "{c:?}");
    // The table is the fit's again.
    let after = table[0].offset();
    assert!((after.0 - before.0).abs() < 1e-3 && (after.1 - before.1).abs() < 1e-3);
    assert_eq!(table[0].prior_in_force(), free);
}

#[test]
fn an_unmodelled_error_is_a_floor_however_many_bearings() {
    // A calibrated unit (offset known exactly) on a straight road, y = 0 and x in [0, 1500],
    // 3 km from the emitter: without an unmodelled error the bound shrinks as 1 / sqrt(N);
    // with 0.5 degrees it stays above r * 0.5 degrees across the line of bearing (26 m at
    // 3 km), however many bearings: the station's error times the range.
    const MOST: usize = 10_000;
    let e = [750.0f32, 3000.0];
    let floor = 0.5 * DEG;
    let r = 3000.0;
    let mut last = f32::INFINITY;
    for n in [100usize, 1000, MOST] {
        let road: [Bearing; MOST] = core::array::from_fn(|k| {
            let v = [1500.0 * k.min(n - 1) as f32 / (n - 1) as f32, 0.0];
            Bearing {
                vehicle: v,
                theta: predicted(&e, &v),
                sigma: 3.0 * DEG,
            }
        });
        let bearings = &road[..n];
        let plain = crlb(&e, bearings, BiasPrior::calibrated(0.0)).unwrap();
        let row = StationSlot::new(BiasPrior::calibrated(0.0)).with_unmodelled(floor);
        let with = crlb_stations(&e, bearings, &mut [row]).unwrap();
        // Across the line of bearing from the road's middle: x.
        let across = libm::sqrtf(with.covariance[0][0]);
        assert!(across >= 0.95 * r * floor, "n {n}: {across} m");
        assert!(with.rmse <= last, "n {n}: the bound grows");
        last = with.rmse;
        if n == MOST {
            // The noise's share across is 3 / sqrt(1e4) degrees at 3 km (1.6 m); the floor's
            // is not gone.
            assert!(
                libm::sqrtf(plain.covariance[0][0]) < 0.1 * r * floor,
                "{plain:?}"
            );
            assert!(across <= 1.1 * r * floor, "{across}");
        }
    }
}

#[test]
fn an_unmodelled_error_is_the_offset_priors_share() {
    // One concept: an unmodelled error of sd s on a station is its offset prior's variance
    // plus s^2: a calibrated station with s is the station with the prior 0 +- s, a prior
    // of sd t with s is the prior sqrt(t^2 + s^2), no prior stays none.
    let s = 0.7 * DEG;
    let row = StationSlot::new(BiasPrior::calibrated(0.3)).with_unmodelled(s);
    assert_eq!(row.prior(), BiasPrior { mean: 0.3, sd: s });
    assert_eq!(row.prior_in_force(), row.prior());
    assert_eq!(row.unmodelled(), s);
    let wide = StationSlot::new(BiasPrior {
        mean: 0.0,
        sd: 3.0 * DEG,
    })
    .with_unmodelled(s);
    assert!((wide.prior().sd - libm::hypotf(3.0 * DEG, s)).abs() < 1e-7);
    let none = StationSlot::new(BiasPrior {
        mean: 0.0,
        sd: f32::INFINITY,
    })
    .with_unmodelled(s);
    assert!(none.prior().sd.is_infinite());
    // A row back to its caller's prior keeps the error, counted once.
    let mut again = row;
    again.set_prior_in_force(BiasPrior::calibrated(0.0));
    again.reset();
    assert_eq!(again, row);
    // Fixed stations: three masts with calibrated offsets and an unmodelled error give the
    // bound of three masts whose offset priors have that sd.
    let e = [0.0f32, 0.0];
    let masts = [[6000.0f32, 0.0], [-3000.0, 5000.0], [-3000.0, -5500.0]];
    struct Seen(Bearing, usize);
    impl Sighting for Seen {
        fn bearing(&self) -> &Bearing {
            &self.0
        }
        fn station(&self) -> usize {
            self.1
        }
    }
    let seen: [Seen; 600] = core::array::from_fn(|k| {
        let m = masts[k % 3];
        let b = Bearing {
            vehicle: m,
            theta: predicted(&e, &m),
            sigma: 2.0 * DEG,
        };
        Seen(b, k % 3)
    });
    let mut floored = [StationSlot::new(BiasPrior::calibrated(0.0)).with_unmodelled(s); 3];
    let mut priored = [StationSlot::new(BiasPrior { mean: 0.0, sd: s }); 3];
    let a = crlb_stations(&e, &seen, &mut floored).unwrap();
    let b = crlb_stations(&e, &seen, &mut priored).unwrap();
    assert_eq!(a.covariance, b.covariance);
}

#[test]
fn a_bad_unmodelled_error_is_refused() {
    for bad in [-0.1f32, f32::NAN, f32::INFINITY] {
        let row = StationSlot::new(BiasPrior::default()).with_unmodelled(bad);
        assert!(row.check().is_err(), "{bad}");
    }
    assert!(StationSlot::default().with_unmodelled(0.0).check().is_ok());
}

/// A sighting with its relative bearing (the antenna's front known).
#[derive(Clone, Copy)]
struct Rel(Bearing, f32);
impl Sighting for Rel {
    fn bearing(&self) -> &Bearing {
        &self.0
    }
    fn relative(&self) -> f32 {
        self.1
    }
}

/// The U drive round (0, 1500): east on y = 0, north on x = 1500, west on y = 3000; 240
/// positions with the course of each.
fn u_drive() -> [([f32; 2], f32); 240] {
    core::array::from_fn(|k| {
        let s = 9000.0 * k as f32 / 240.0;
        if s < 3000.0 {
            ([-1500.0 + s, 0.0], 0.0)
        } else if s < 6000.0 {
            ([1500.0, s - 3000.0], core::f32::consts::FRAC_PI_2)
        } else {
            ([1500.0 - (s - 6000.0), 3000.0], core::f32::consts::PI)
        }
    })
}

#[test]
fn a_direction_dependent_error_is_taken_out_where_the_drive_turns() {
    // Each harmonic alone, 4 degrees, no noise, on the U drive: ignored it moves the fix by
    // metres; modelled (prior sd 3 degrees each) the fix is where the emitter is, and the
    // position's sd stays near the offset-only bound (the turns separate the harmonics from
    // the position).
    let e = [0.0f32, 1500.0];
    let mut moved = 0.0f32;
    for k in 0..4 {
        let mut c = [0.0f32; 4];
        c[k] = 4.0 * DEG;
        let truth = DirectionPrior { mean: c, sd: 0.0 };
        let items: [Rel; 240] = u_drive().map(|(v, course)| {
            let t = predicted(&e, &v);
            let z = wrap(t + truth.error_at(wrap(t - course)));
            Rel(
                Bearing {
                    vehicle: v,
                    theta: z,
                    sigma: 2.0 * DEG,
                },
                wrap(z - course),
            )
        });
        let start = Start {
            position: e,
            offsets: StartOffsets::Prior,
        };
        let gaussian = crate::likelihood::Gaussian;
        let options = BiasedOptions::default();
        let mut plain = [StationSlot::default()];
        let f0 = ml_sources(&items, &mut plain, start, &gaussian, options).unwrap();
        let prior = DirectionPrior {
            mean: [0.0; 4],
            sd: 3.0 * DEG,
        };
        let mut dd = [StationSlot::default().with_direction(prior, 0.0)];
        let f1 = ml_sources(&items, &mut dd, start, &gaussian, options).unwrap();
        let off = |f: &BiasedFix| libm::hypotf(f.position[0] - e[0], f.position[1] - e[1]);
        moved = moved.max(off(&f0));
        assert!(off(&f1) < 0.5, "harmonic {k}: {:?}", f1.position);
        let sd = |f: &BiasedFix| libm::sqrtf(f.covariance[0][0] + f.covariance[1][1]);
        assert!(
            sd(&f1) >= sd(&f0) && sd(&f1) < 1.5 * sd(&f0),
            "harmonic {k}: sd {} against {}",
            sd(&f1),
            sd(&f0)
        );
        assert!(
            f1.parameters > f0.parameters,
            "{} {}",
            f1.parameters,
            f0.parameters
        );
    }
    assert!(
        moved > 5.0,
        "ignored, the harmonics move the fix: {moved} m at most"
    );
}

/// `n` bearings of a unit with offset `b` and harmonics `c` (of the reported bearing relative
/// to its course, the route's tangent) along `route` (position at step k), of a transmitter at
/// `e`.
fn unit_drive<const N: usize>(
    e: [f32; 2],
    route: impl Fn(f32) -> [f32; 2],
    b: f32,
    c: [f32; HARMONICS],
    sigma: f32,
    rng: &mut XorShiftRng,
) -> [Bearing; N] {
    core::array::from_fn(|k| {
        let v = route(k as f32);
        let (ahead, behind) = (route(k as f32 + 0.01), route(k as f32 - 0.01));
        let course = libm::atan2f(ahead[1] - behind[1], ahead[0] - behind[0]);
        let truth = predicted(&e, &v);
        let prior = DirectionPrior { mean: c, sd: 0.0 };
        // The model as the fix and the calibration take it: the error a function of the
        // reported bearing relative to the course, theta = truth + b + e(theta - course) + n
        // (solved by iteration: |e'| < 1).
        let plain = truth + b + sigma * random::normal(rng);
        let mut theta = plain;
        for _ in 0..8 {
            theta = plain + prior.error_at(wrap(theta - course));
        }
        Bearing {
            vehicle: v,
            theta: wrap(theta),
            sigma,
        }
    })
}

#[test]
fn a_turning_drive_measures_the_harmonics_and_a_straight_pass_says_it_cannot() {
    extern crate std;
    let e = [0.0, 0.0];
    let c = [3.0 * DEG, -1.5 * DEG, 2.0 * DEG, 2.5 * DEG];
    let mut coverage = [0u32; 2];
    const RUNS: u64 = 200;
    let mut worst_span = f32::INFINITY;
    for seed in 0..RUNS {
        let mut rng = XorShiftRng::seed_from_u64(seed);
        // Two laps of a 400 m circle 2 km from the transmitter: the course turns through
        // every direction while the transmitter's azimuth hardly moves.
        let lap = |k: f32| {
            let a = 2.0 * 2.0 * core::f32::consts::PI * k / 240.0;
            [2000.0 + 400.0 * libm::cosf(a), 400.0 * libm::sinf(a)]
        };
        let bs: [Bearing; 240] = unit_drive(e, lap, 4.0 * DEG, c, 2.0 * DEG, &mut rng);
        let mut phi = [0.0f32; 240];
        relative_to_course(&bs, 0.0, &mut phi);
        let m = calibrate_direction(&bs, &phi, e).unwrap();
        worst_span = worst_span.min(m.span);
        assert!(m.measured(), "span {}", m.span);
        // Each coefficient within 1.96 of its own sd (the covariance's diagonal); the offset
        // likewise.
        let inside = (0..HARMONICS).all(|k| {
            libm::fabsf(m.coefficients[k] - c[k]) <= 1.96 * libm::sqrtf(m.covariance[k][k])
        });
        coverage[0] += u32::from(inside);
        coverage[1] += u32::from(libm::fabsf(m.offset.bias - 4.0 * DEG) <= 1.96 * m.offset.sd);
    }
    // Four coefficients at once, each 95 %: about 0.95^4 = 81 % jointly (they are nearly
    // independent on a full turn); 200 runs know a share to +-2.8 %, so 72 % is a miss of
    // three of those, not noise. The offset's own 95 % within 88-99 % likewise.
    let joint = coverage[0] as f32 / RUNS as f32;
    let offset = coverage[1] as f32 / RUNS as f32;
    std::println!(
        "turning: joint coverage {joint:.3}, offset {offset:.3}, worst span {worst_span:.3}"
    );
    assert!((0.72..=0.9).contains(&joint), "{joint}");
    assert!((0.88..=0.99).contains(&offset), "{offset}");
    // A straight road past the transmitter, 1 km off it: the relative bearing sweeps half
    // the circle once, which shows the offset but not the four coefficients.
    let mut rng = XorShiftRng::seed_from_u64(7);
    let road = |k: f32| [-4000.0 + 8000.0 * k / 240.0, 1000.0];
    let bs: [Bearing; 240] = unit_drive(e, road, 4.0 * DEG, c, 2.0 * DEG, &mut rng);
    let mut phi = [0.0f32; 240];
    relative_to_course(&bs, 0.0, &mut phi);
    let m = calibrate_direction(&bs, &phi, e).unwrap();
    std::println!("straight: span {:.4}", m.span);
    assert!(!m.measured(), "span {}", m.span);
    assert_eq!(
        calibrate_direction(&bs, &phi[..3], e),
        Err(Error::OutOfRange)
    );
}

/// A short stretch of road far from the transmitter: its relative bearings sweep a few
/// degrees, too few to hold the third and fourth harmonics apart from the table (the wide
/// fit is singular); the calibration falls back to the table alone, as before they were
/// fitted, and says the table is not measured (its span far below the rule's), so the caller
/// takes the offset-only calibration; not an error.
#[test]
fn a_short_arc_is_no_table_and_no_error() {
    extern crate std;
    let e = [0.0, 0.0];
    let c = [3.0 * DEG, -1.5 * DEG, 2.0 * DEG, 2.5 * DEG];
    let mut rng = XorShiftRng::seed_from_u64(11);
    let road = |k: f32| [-1000.0 + 2000.0 * k / 240.0, 10_000.0];
    let bs: [Bearing; 240] = unit_drive(e, road, 4.0 * DEG, c, 2.0 * DEG, &mut rng);
    let mut phi = [0.0f32; 240];
    relative_to_course(&bs, 0.0, &mut phi);
    let m = calibrate_direction(&bs, &phi, e).expect("a calibration");
    std::println!("short arc: span {:.2e}", m.span);
    assert!(!m.measured() && m.span < 1e-3, "span {}", m.span);
}

/// `stations` fixed stations on a ring of `radius` round an emitter at the origin, `each`
/// bearings apiece with noise `sigma` and their own offsets (sd 2 degrees), every station
/// with the default prior; the fit and its table.
fn ring_network(
    stations: usize,
    each: usize,
    radius: f32,
    sigma: f32,
    rng: &mut XorShiftRng,
) -> Result<([S; 160], usize, [StationSlot; 40], BiasedFix), Error> {
    let n = stations * each;
    let offsets: [f32; 40] = core::array::from_fn(|_| 2.0 * DEG * random::normal(rng));
    let items: [S; 160] = core::array::from_fn(|k| {
        let s = (k / each).min(stations - 1);
        ring_sighting(s, stations, radius, offsets[s], sigma, rng)
    });
    let mut table = [StationSlot::default(); 40];
    let fix = fit_ring(&items[..n], &mut table)?;
    Ok((items, n, table, fix))
}

/// A bearing of station `s` of a ring of `stations` `radius` round the emitter at the origin,
/// its offset `offset` and noise of sd `sigma`.
fn ring_sighting(
    s: usize,
    stations: usize,
    radius: f32,
    offset: f32,
    sigma: f32,
    rng: &mut XorShiftRng,
) -> S {
    let a = 2.0 * core::f32::consts::PI * s as f32 / stations as f32 + 0.3;
    let v = [radius * libm::cosf(a), radius * libm::sinf(a)];
    let noise = sigma * random::normal(rng);
    let theta = wrap(predicted(&[0.0, 0.0], &v) + offset + noise);
    S(
        Bearing {
            vehicle: v,
            theta,
            sigma,
        },
        s,
    )
}

/// A ring's bearings fitted from a start off the emitter, each station's offset from its
/// prior.
fn fit_ring(items: &[S], table: &mut [StationSlot]) -> Result<BiasedFix, Error> {
    let start = Start {
        position: [150.0, -100.0],
        offsets: StartOffsets::Prior,
    };
    ml_sources(items, table, start, &crate::Gaussian, Default::default())
}

/// [`no_rival`] for station 0 at `at`: a rival 30 degrees away within a deviance of 9, the
/// ambiguity check's.
fn no_rival_for_0<T: Sighting>(items: &[T], table: &mut [StationSlot], at: [f32; 2]) -> bool {
    no_rival(
        items,
        table,
        0,
        at,
        BiasedOptions::default(),
        30.0 * DEG,
        9.0,
    )
}

#[test]
fn a_network_pins_the_position_and_leaves_a_station_no_rival() {
    // Forty stations 8 km round the emitter, two bearings each: no offset of station 0 far
    // from its fit can fit, and the circle's walk agrees.
    let mut rng = XorShiftRng::seed_from_u64(11);
    let (items, n, mut table, fix) = ring_network(40, 2, 8000.0, 2.0 * DEG, &mut rng).unwrap();
    let before = table[0].offset();
    let options = BiasedOptions::default();
    assert!(no_rival_for_0(&items[..n], &mut table, fix.position));
    assert_eq!(table[0].offset(), before);
    let c = offset_circle(&items[..n], &mut table, 0, fix.position, options).unwrap();
    assert!(!c.rival(table[0].offset().0, 30.0 * DEG, 9.0), "{c:?}");
}

#[test]
fn a_station_alone_or_a_loose_network_walks_the_circle() {
    // One vehicle: nothing else pins the position.
    let mut rng = XorShiftRng::seed_from_u64(12);
    let e = [400.0, 0.0];
    let bs = arc_drive(e, [0.0, 0.0], 600.0, 0.6, 10.0 * DEG, DEG, &mut rng);
    let mut table = [StationSlot::default()];
    let start = Start {
        position: e,
        offsets: StartOffsets::Prior,
    };
    let options = BiasedOptions::default();
    let fix = ml_sources(&bs, &mut table, start, &crate::Gaussian, options).unwrap();
    assert!(!no_rival_for_0(&bs, &mut table, fix.position));
    // Three fixed stations 8 km out: each other station's cross-range is its prior's share,
    // hundreds of metres, so a far rival is not ruled out by the bound.
    let (items, n, mut table, fix) = ring_network(3, 40, 8000.0, 2.0 * DEG, &mut rng).unwrap();
    assert!(!no_rival_for_0(&items[..n], &mut table, fix.position));
}

/// `cases` networks' [`bound_and_walk`] (`None`: the case's network could not be fitted),
/// printed each: in how many the bound said no rival, and in how many the walk found one.
fn tally(cases: u32, mut case: impl FnMut(u32) -> Option<(bool, bool)>) -> (u32, u32) {
    extern crate std;
    let (mut said, mut rivals) = (0, 0);
    for k in 0..cases {
        if let Some((none, rival)) = case(k) {
            std::println!("case {k}: no rival said {none}, walk's {rival}");
            said += u32::from(none);
            rivals += u32::from(rival);
        }
    }
    std::println!("no rival said in {said} of {cases} networks; the walk found one in {rivals}");
    (said, rivals)
}

/// The bound and the walk for station 0 of a network fitted at `at`: whether the bound says
/// there is no rival and whether the walk finds one, never both (`case` names the network).
fn bound_and_walk<T: Sighting>(
    items: &[T],
    table: &mut [StationSlot],
    at: [f32; 2],
    case: u32,
) -> (bool, bool) {
    let none = no_rival_for_0(items, table, at);
    let c = offset_circle(items, table, 0, at, BiasedOptions::default()).unwrap();
    let rival = c.rival(table[0].offset().0, 30.0 * DEG, 9.0);
    assert!(!(none && rival), "case {case}: {c:?}");
    (none, rival)
}

#[test]
fn no_rival_is_never_said_where_the_circle_finds_one() {
    // Networks from 2 to 40 stations, 1 to 40 bearings each, 1 to 8 degrees of noise, near
    // and far: where the bound says there is no rival, the walk finds none.
    let mut rng = XorShiftRng::seed_from_u64(13);
    let (said, rivals) = tally(60, |case| {
        let stations = [2usize, 3, 5, 8, 20, 40][(case % 6) as usize];
        let each = (160 / stations)
            .min([1usize, 2, 4, 40][(case / 6 % 4) as usize])
            .max(1);
        let sigma = [1.0, 3.0, 8.0][(case / 24 % 3) as usize] * DEG;
        let radius = [2000.0, 8000.0][(case / 3 % 2) as usize];
        let (items, n, mut table, fix) =
            ring_network(stations, each, radius, sigma, &mut rng).ok()?;
        Some(bound_and_walk(&items[..n], &mut table, fix.position, case))
    });
    // The bound speaks for the larger networks, and the cases hold rivals for it to miss.
    assert!(said >= 10 && rivals >= 3, "{said} {rivals}");
}

/// A ring of `stations` fixed stations `radius` round the emitter at the origin, `each`
/// bearings apiece of noise `sigma` (each station's offset drawn with sd 2 degrees), fitted:
/// networks larger than [`ring_network`]'s arrays hold.
fn big_ring(
    stations: usize,
    each: usize,
    radius: f32,
    sigma: f32,
    rng: &mut XorShiftRng,
) -> Result<(std::vec::Vec<S>, [StationSlot; 64], BiasedFix), Error> {
    let offsets: std::vec::Vec<f32> = (0..stations)
        .map(|_| 2.0 * DEG * random::normal(rng))
        .collect();
    let items = (0..stations * each)
        .map(|k| {
            let s = k % stations;
            ring_sighting(s, stations, radius, offsets[s], sigma, rng)
        })
        .collect::<std::vec::Vec<S>>();
    let mut table = [StationSlot::default(); 64];
    let fix = fit_ring(&items, &mut table[..stations])?;
    Ok((items, table, fix))
}

#[test]
fn a_fixed_stations_own_scatter_spares_a_network_of_many_bearings_the_walk() {
    // Twenty-five masts 8 km round the emitter, forty bearings each: the main station's own
    // bearings keep their scatter wherever a rival would put the position, so the others
    // need only pin the rest (before, that scatter was asked of them too, and the walk ran).
    let mut rng = XorShiftRng::seed_from_u64(5);
    let (items, mut table, fix) = big_ring(25, 40, 8000.0, 2.0 * DEG, &mut rng).unwrap();
    let table = &mut table[..25];
    assert!(no_rival_for_0(&items, table, fix.position));
    let c = offset_circle(&items, table, 0, fix.position, BiasedOptions::default()).unwrap();
    assert!(!c.rival(table[0].offset().0, 30.0 * DEG, 9.0), "{c:?}");
    // A station whose bearings came from two places is not one place's scatter.
    let mut moved = items.clone();
    for b in moved.iter_mut().filter(|b| b.1 == 0).take(20) {
        b.0.vehicle[0] += 50.0;
    }
    let mut plain = [StationSlot::default(); 25];
    let start = Start {
        position: fix.position,
        offsets: StartOffsets::Prior,
    };
    let f = ml_sources(
        &moved,
        &mut plain,
        start,
        &crate::Gaussian,
        Default::default(),
    )
    .unwrap();
    assert!(!no_rival_for_0(&moved, &mut plain, f.position));
}

#[test]
fn a_fixed_stations_scatter_never_hides_a_rival_the_walk_finds() {
    // Networks of 2 to 30 masts with 10 to 60 bearings each, 1 and 8 degrees of noise, near
    // and far: where the bound (with the main station's own scatter) says no rival, the
    // walk finds none.
    let mut rng = XorShiftRng::seed_from_u64(17);
    let (said, rivals) = tally(72, |case| {
        let stations = [2usize, 3, 4, 6, 12, 30][(case % 6) as usize];
        let each = [10usize, 25, 60][(case / 6 % 3) as usize];
        let radius = [2000.0, 8000.0][(case / 18 % 2) as usize];
        let sigma = [1.0, 8.0][(case / 36 % 2) as usize] * DEG;
        let (items, mut table, fix) = big_ring(stations, each, radius, sigma, &mut rng).ok()?;
        Some(bound_and_walk(
            &items,
            &mut table[..stations],
            fix.position,
            case,
        ))
    });
    // Both must happen for the test to mean anything: the bound speaks for 12 (networks of
    // 12 and 30 masts; 6 without the turned step, 1 without the scatter either), the walk
    // finds rivals in 9 (two masts).
    assert!(said >= 10 && rivals >= 1, "said {said}, rivals {rivals}");
}

/// The Gaussian without its summed form: every bearing counts alone.
#[derive(Debug, Clone, Copy)]
struct OneByOne;

impl crate::likelihood::Likelihood for OneByOne {
    fn ln(&self, r: f32, sigma: f32) -> f32 {
        crate::Gaussian.ln(r, sigma)
    }
    fn irls_weight(&self, r: f32, sigma: f32) -> f32 {
        crate::Gaussian.irls_weight(r, sigma)
    }
}

#[test]
fn a_fixed_stations_bearings_summed_give_the_fix_they_give_one_by_one() {
    // Rings of masts, each mast's bearings from one place: the solver's summed form (one term a
    // mast) and the bearings one by one find the same fix, offsets and ellipse. Twenty-one
    // masts put one due west of the emitter, its bearings either side of +-180 degrees; the
    // position's share of the sd (position_sd_m) makes the sd depend on the position.
    use crate::likelihood::Likelihood;
    let mut rng = XorShiftRng::seed_from_u64(23);
    for (stations, each, sigma, position_sd_m) in [
        (3, 40, 2.0, 0.0),
        (8, 5, 1.0, 0.0),
        (21, 30, 8.0, 0.0),
        (21, 12, 3.0, 20.0),
    ] {
        let (items, _, _) = big_ring(stations, each, 6000.0, sigma * DEG, &mut rng).unwrap();
        let options = BiasedOptions {
            position_sd_m,
            ..Default::default()
        };
        let start = Start {
            position: [150.0, -100.0],
            offsets: StartOffsets::Prior,
        };
        let mut summed = [StationSlot::default(); 64];
        let mut alone = [StationSlot::default(); 64];
        let (summed, alone) = (&mut summed[..stations], &mut alone[..stations]);
        let a = ml_sources(&items, summed, start, &crate::Gaussian, options).unwrap();
        let b = ml_sources(&items, alone, start, &OneByOne, options).unwrap();
        let moved = libm::hypotf(a.position[0] - b.position[0], a.position[1] - b.position[1]);
        let sd = |f: &BiasedFix| libm::sqrtf(f.covariance[0][0] + f.covariance[1][1]);
        let offsets = summed
            .iter()
            .zip(alone.iter())
            .map(|(x, y)| libm::fabsf(x.offset().0 - y.offset().0))
            .fold(0.0f32, f32::max);
        std::println!(
            "{stations} x {each}, {sigma} deg: fixes {moved:.4} m apart, sd {:.3} and {:.3} m, \
             offsets {:.2e} deg apart",
            sd(&a),
            sd(&b),
            offsets / DEG
        );
        // The two differ only in f32 rounding and where the solver's tolerance stops it.
        assert!(moved < 0.05 * sd(&b), "{moved} m against sd {}", sd(&b));
        assert!(libm::fabsf(sd(&a) / sd(&b) - 1.0) < 1e-3);
        assert!(offsets < 1e-3 * DEG);
        assert!(
            libm::fabsf(a.chi2 / b.chi2 - 1.0) < 1e-3,
            "{} {}",
            a.chi2,
            b.chi2
        );
    }
    // The summed form is the Gaussian's; a loss that needs every residual has none.
    assert!(crate::Gaussian.ln_sum(2.0, 0.1, 0.01, 1.0).is_some());
    assert!(OneByOne.ln_sum(2.0, 0.1, 0.01, 1.0).is_none());
    assert!(
        crate::likelihood::Huber::default()
            .ln_sum(2.0, 0.1, 0.01, 1.0)
            .is_none()
    );
}

#[test]
fn a_stations_one_place_is_one_direction_for_any_loss() {
    // Masts' bearings under Tukey (no summed form): each mast's direction taken once a pass
    // gives the very cost and normal equations of each bearing taking its own.
    use super::problem::{At, set_up};
    let mut rng = XorShiftRng::seed_from_u64(29);
    let (items, mut table, fix) = big_ring(21, 12, 6000.0, 3.0 * DEG, &mut rng).unwrap();
    let table = &mut table[..21];
    let start = Start {
        position: fix.position,
        offsets: StartOffsets::Fitted,
    };
    let tukey = crate::likelihood::Tukey::default();
    let (problem, p, _) = set_up(&items, table, start, &tukey, BiasedOptions::default()).unwrap();
    assert!(
        table
            .iter()
            .all(|s| s.place.is_some() && s.summed.is_none())
    );
    let probe = [p[0] + 250.0, p[1] - 400.0];
    let aimed = problem.cost(table, probe, At::Current);
    problem.accumulate(table, probe, None);
    let blocks: std::vec::Vec<StationSlot> = table.to_vec();
    for s in table.iter_mut() {
        s.place = None;
    }
    let alone = problem.cost(table, probe, At::Current);
    problem.accumulate(table, probe, None);
    std::println!("cost {aimed} aimed, {alone} one by one");
    assert_eq!(aimed.to_bits(), alone.to_bits());
    for (a, b) in blocks.iter().zip(table.iter()) {
        let mut a = *a;
        a.place = None;
        a.toward = b.toward;
        assert_eq!(a, *b);
    }
}
