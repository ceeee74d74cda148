//! The pipeline end to end: a clean drive, a repeated capture, a ghost, two channels, bad input
//! and a unit noisier than it claims.

use super::*;
use crate::model::bearing::{Bearing, predicted, wrap};
use crate::random;
use core::f32::consts::PI;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

const DEG: f32 = PI / 180.0;
const E: [f32; 2] = [0.0, 1500.0];

/// `n` positions on a U round (0, 1500) (9 km: east, north, west).
fn u(k: usize, n: usize) -> [f32; 2] {
    let s = 9000.0 * k as f32 / n as f32;
    if s < 3000.0 {
        [-1500.0 + s, 0.0]
    } else if s < 6000.0 {
        [1500.0, s - 3000.0]
    } else {
        [1500.0 - (s - 6000.0), 3000.0]
    }
}

fn obs(v: [f32; 2], target: [f32; 2], error: f32, k: usize) -> Observation {
    Observation::new(
        Bearing {
            vehicle: v,
            theta: wrap(predicted(&target, &v) + error),
            sigma: 2.0 * DEG,
        },
        k as f32,
    )
}

fn drive(rng: &mut XorShiftRng, bias: f32) -> [Observation; 240] {
    core::array::from_fn(|k| obs(u(k, 240), E, bias + 2.0 * DEG * random::normal(rng), k))
}

fn run<const N: usize>(o: &[Observation], config: &LocateConfig) -> Report<4, 4> {
    let mut work = Workspace::<N>::new();
    let mut rng = XorShiftRng::seed_from_u64(7);
    locate::<4, 4, _>(o, config, work.buffers(), &mut rng).unwrap()
}

#[test]
fn a_clean_drive_with_an_offset_gives_one_consistent_emitter() {
    let mut rng = XorShiftRng::seed_from_u64(1);
    let o = drive(&mut rng, 3.0 * DEG);
    let r = run::<512>(&o, &LocateConfig::default());
    assert_eq!(r.emitters().len(), 1);
    assert_eq!(r.channels()[0].outcome, ChannelOutcome::Emitter(0));
    let e = r.emitters()[0];
    let err = libm::hypotf(e.position[0] - E[0], e.position[1] - E[1]);
    assert!(err < 4.0 * e.crlb, "{err} m: {e:?}");
    assert!(e.consistent && e.sigma_estimated && e.used >= 238);
    assert!(
        (e.bias - 3.0 * DEG).abs() < 4.0 * e.bias_sd,
        "{}",
        e.bias / DEG
    );
    assert!((e.sigma - 2.0 * DEG).abs() < 0.3 * DEG, "{}", e.sigma / DEG);
    assert_eq!(
        r.rejected.repeated + r.rejected.invalid + r.rejected.no_emitter,
        0
    );
    assert_eq!((e.index_span, e.time_span), ([0, 239], [0.0, 239.0]));
    // Many white residuals: F scaling close to chi-square's, no widening.
    assert!((e.ellipse_scale - 5.99).abs() < 0.2, "{}", e.ellipse_scale);
    assert!(e.effective > 200.0, "{}", e.effective);
    assert!(r.others().is_empty(), "{:?}", r.others());
}

#[test]
fn a_capture_concatenated_with_itself_is_counted_once() {
    let mut rng = XorShiftRng::seed_from_u64(2);
    let once = drive(&mut rng, 0.0);
    let twice: [Observation; 480] = core::array::from_fn(|k| once[k % 240]);
    let config = LocateConfig::default();
    let a = run::<512>(&once, &config);
    let b = run::<512>(&twice, &config);
    assert_eq!(b.rejected.repeated, 240);
    assert_eq!(a.emitters()[0].position, b.emitters()[0].position);
    assert_eq!(a.emitters()[0].covariance, b.emitters()[0].covariance);
}

#[test]
fn a_ghost_is_another_source_and_noise_is_no_emitter() {
    let mut rng = XorShiftRng::seed_from_u64(3);
    let ghost = [900.0, 1800.0];
    let o: [Observation; 240] = core::array::from_fn(|k| {
        let t = if (60..120).contains(&k) { ghost } else { E };
        obs(u(k, 240), t, 2.0 * DEG * random::normal(&mut rng), k)
    });
    let r = run::<512>(&o, &LocateConfig::default());
    let e = r.emitters()[0];
    assert!(
        libm::hypotf(e.position[0] - E[0], e.position[1] - E[1]) < 40.0,
        "{e:?}"
    );
    let g = r.others().first().expect("the ghost");
    assert_eq!(g.why, OtherReason::Weaker);
    assert!(
        libm::hypotf(
            g.source.position[0] - ghost[0],
            g.source.position[1] - ghost[1]
        ) < 150.0,
        "{g:?}"
    );
    assert!((55..=62).contains(&g.source.used), "{}", g.source.used);
    assert!(
        g.source.index_span[0] >= 58 && g.source.index_span[1] <= 121,
        "{:?}",
        g.source.index_span
    );
    // Uniform bearings: no point gathers more than luck would.
    let noise: [Observation; 240] = core::array::from_fn(|k| {
        let mut x = o[k];
        x.bearing.theta = random::uniform_in(&mut rng, -PI, PI);
        x
    });
    let r = run::<512>(&noise, &LocateConfig::default());
    assert!(r.emitters().is_empty());
    assert!(matches!(
        r.channels()[0].outcome,
        ChannelOutcome::NoConsistentEmitter(_)
    ));
    assert_eq!(r.rejected.no_emitter, 240);
}

#[test]
fn two_frequencies_give_two_emitters() {
    let mut rng = XorShiftRng::seed_from_u64(4);
    let b = [-700.0, 2200.0];
    let o: [Observation; 480] = core::array::from_fn(|k| {
        let (t, f) = if k % 2 == 0 { (E, 145.0) } else { (b, 146.52) };
        let mut x = obs(u(k / 2, 240), t, 2.0 * DEG * random::normal(&mut rng), k);
        x.freq_mhz = Some(f);
        x
    });
    let r = run::<512>(&o, &LocateConfig::default());
    assert_eq!(r.emitters().len(), 2, "{:?}", r.channels());
    for (e, t) in r.emitters().iter().zip([E, b]) {
        assert!(
            libm::hypotf(e.position[0] - t[0], e.position[1] - t[1]) < 40.0,
            "{e:?}"
        );
        assert!(e.consistent);
    }
    assert_eq!(
        r.emitters()[1]
            .freq_mhz
            .map(|f| libm::roundf(f * 100.0) as i32),
        Some(14652)
    );
    // Each emitter's channel holds its own frequency only, by the grouping's rule.
    let width = LocateConfig::default().channel_width_mhz;
    let [a, b] = [r.emitters()[0], r.emitters()[1]];
    assert!(a.in_channel(Some(145.0), width) && !a.in_channel(Some(146.52), width));
    assert!(b.in_channel(Some(146.52), width) && !b.in_channel(None, width));
    assert_eq!(r.channels()[1].lowest_mhz, Some(146.52));
    assert!(r.channels()[1].holds(Some(146.54), width));
    assert!(!r.channels()[1].holds(Some(146.6), width));
}

#[test]
fn bad_observations_are_counted_by_reason() {
    let mut rng = XorShiftRng::seed_from_u64(5);
    let mut o = drive(&mut rng, 0.0);
    o[3].bearing.theta = f32::NAN;
    o[4].bearing.sigma = 0.0;
    o[5].station = 9; // beyond the 4 rows of the station table
    o[6].freq_mhz = Some(-1.0);
    o[7].time_s = 1.5; // older than o[6]: time went backwards
    let r = run::<200>(&o, &LocateConfig::default());
    let rej = r.rejected;
    assert_eq!(
        (rej.invalid, rej.unknown_station, rej.time_backwards),
        (3, 1, 1)
    );
    // 236 usable, 200 fit: the rest is over capacity.
    assert_eq!(rej.over_capacity, 36);
    assert_eq!(r.emitters().len(), 1);
    let bad = LocateConfig {
        confidence: 1.0,
        ..LocateConfig::default()
    };
    let mut work = Workspace::<8>::new();
    let mut rng = XorShiftRng::seed_from_u64(0);
    assert_eq!(
        locate::<1, 1, _>(&o, &bad, work.buffers(), &mut rng).map(|_| ()),
        Err(Error::OutOfRange)
    );
}

#[test]
fn a_unit_noisier_than_it_claims_is_inconsistent_when_trusted() {
    let mut rng = XorShiftRng::seed_from_u64(6);
    // 4 degree noise, the unit claims 2.
    let o: [Observation; 240] =
        core::array::from_fn(|k| obs(u(k, 240), E, 4.0 * DEG * random::normal(&mut rng), k));
    let known = LocateConfig {
        noise: NoiseModel::Known,
        ..LocateConfig::default()
    };
    let r = run::<512>(&o, &known);
    let e = r.emitters()[0];
    assert!(!e.consistent && e.sigma_estimated, "{e:?}");
    assert!((e.sigma - 4.0 * DEG).abs() < 0.6 * DEG, "{}", e.sigma / DEG);
    assert!(e.p_value < 1e-3);
    // A unit that tells the truth is trusted: chi-square scale, its own sigma.
    let honest: [Observation; 240] =
        core::array::from_fn(|k| obs(u(k, 240), E, 2.0 * DEG * random::normal(&mut rng), k));
    let r = run::<512>(&honest, &known);
    let e = r.emitters()[0];
    assert!(e.consistent && !e.sigma_estimated, "{e:?}");
    assert!((e.ellipse_scale - 5.991).abs() < 1e-3 && e.sigma == 2.0 * DEG);
}

/// Three fixed stations 6-9 km out, each with its own offset: the fix leans on their priors
/// and says so (a few hundred metres, holding the truth), and each station's offset is in
/// the offsets table.
#[test]
fn a_network_of_fixed_stations_is_honest_about_its_offsets() {
    let mut rng = XorShiftRng::seed_from_u64(8);
    let e = [0.0f32, 0.0];
    let sites = [[-8000.0f32, 1000.0], [2000.0, -6000.0], [6000.0, 6000.0]];
    let offsets = [2.5 * DEG, -3.0 * DEG, 1.5 * DEG];
    let o: [Observation; 600] = core::array::from_fn(|k| {
        let s = k % 3;
        let mut x = obs(
            sites[s],
            e,
            offsets[s] + 2.0 * DEG * random::normal(&mut rng),
            k / 3,
        );
        x.station = s as u16;
        x
    });
    let prior = crate::fix::bias::BiasPrior {
        mean: 0.0,
        sd: 3.0 * DEG,
    };
    let mut work = Workspace::<600, 3>::with_prior(prior);
    let mut rng = XorShiftRng::seed_from_u64(9);
    let r = locate::<1, 1, _>(&o, &LocateConfig::default(), work.buffers(), &mut rng).unwrap();
    let em = r.emitters()[0];
    let err = libm::hypotf(em.position[0] - e[0], em.position[1] - e[1]);
    assert!(em.ellipse.contains(&em.position, &e), "{err} m: {em:?}");
    assert!(em.ellipse.major > 200.0, "{em:?}");
    let table = r.offsets_of(&em, work.offsets());
    assert_eq!(table.len(), 3);
    for (s, t) in table.iter().enumerate() {
        assert_eq!((t.station as usize, t.used), (s, 200));
        // The prior governs: its sd stays most of the prior's.
        assert!(t.measured < 0.6 && t.sd > 0.6 * prior.sd, "{t:?}");
    }
}

/// An emitter 1000 km beyond a 1 km drive, bearings with a little noise: the lines are
/// parallel to within a tenth of a degree, the range is open, and the answer is a parallel
/// region holding the truth, not a fix.
#[test]
fn parallel_bearings_are_a_parallel_region() {
    let e = [0.0f32, 1.0e6];
    let mut rng = XorShiftRng::seed_from_u64(3);
    let obs: [Observation; 40] = core::array::from_fn(|k| {
        let v = [25.0 * k as f32, 0.0];
        let bearing = Bearing {
            vehicle: v,
            theta: wrap(predicted(&e, &v) + 0.0002 * random::normal(&mut rng)),
            sigma: 0.0002,
        };
        Observation::new(bearing, k as f32)
    });
    let mut work = Workspace::<64>::new();
    let config = LocateConfig::default();
    let report = locate::<1, 1, _>(&obs, &config, work.buffers(), &mut rng).unwrap();
    let ChannelOutcome::Region(i) = report.channels()[0].outcome else {
        panic!("{:?}", report.channels()[0]);
    };
    let r = report.regions()[i];
    assert!(r.parallel && r.max_range.is_none(), "{r:?}");
    assert!(r.contains(&e), "{r:?}");
}

/// A 280 m drive with 8 bearings of 15 degree noise toward an emitter 1.4 km off: the
/// bearings cross, but agree on no point luck could not have lined up; they agree on a
/// direction. Each run is a region, not called parallel, that holds the truth about 95 % of
/// the time: at least 15 of 20 (P(fewer) = 3e-4 for an honest 95 % region).
#[test]
fn noisy_crossing_bearings_are_no_parallel_region() {
    let e = [1200.0f32, 800.0];
    let (mut regions, mut held) = (0, 0);
    for seed in 0..20u64 {
        let mut rng = XorShiftRng::seed_from_u64(seed);
        let obs: [Observation; 8] = core::array::from_fn(|k| {
            let v = [40.0 * k as f32, 0.0];
            let bearing = Bearing {
                vehicle: v,
                theta: wrap(predicted(&e, &v) + 15.0 * PI / 180.0 * random::normal(&mut rng)),
                sigma: 15.0 * PI / 180.0,
            };
            Observation::new(bearing, k as f32)
        });
        let mut work = Workspace::<64>::new();
        let report =
            locate::<1, 1, _>(&obs, &LocateConfig::default(), work.buffers(), &mut rng).unwrap();
        if let ChannelOutcome::Region(i) = report.channels()[0].outcome {
            let r = report.regions()[i];
            regions += 1;
            assert!(!r.parallel, "{r:?}");
            assert!(r.min_range >= 0.0 && r.half_width > 0.0, "{r:?}");
            held += r.contains(&e) as u32;
        }
    }
    assert!(
        regions == 20 && held >= 15,
        "{regions} regions, {held} held"
    );
}

/// Four masts at the corners of an 8 km square, each reporting every 2 s for 10 minutes (2
/// degree noise, offsets within the 2 degree prior), on an emitter at `at(t)`.
fn masts(at: impl Fn(f32) -> [f32; 2], seed: u64) -> [Observation; 1200] {
    let mut rng = XorShiftRng::seed_from_u64(seed);
    let sites = [
        [0.0f32, 0.0],
        [8000.0, 0.0],
        [8000.0, 8000.0],
        [0.0, 8000.0],
    ];
    let offsets = [1.5 * DEG, -2.0 * DEG, 0.5 * DEG, 2.5 * DEG];
    core::array::from_fn(|k| {
        let s = k % 4;
        let t = 2.0 * (k / 4) as f32;
        let mut x = obs(
            sites[s],
            at(t),
            offsets[s] + 2.0 * DEG * random::normal(&mut rng),
            0,
        );
        x.time_s = t;
        x.station = s as u16;
        x
    })
}

fn masts_locate(o: &[Observation]) -> Report<1, 1> {
    let prior = crate::fix::bias::BiasPrior {
        mean: 0.0,
        sd: 2.0 * DEG,
    };
    let mut work = Workspace::<1200, 4>::with_prior(prior);
    let mut rng = XorShiftRng::seed_from_u64(3);
    locate::<1, 1, _>(o, &LocateConfig::default(), work.buffers(), &mut rng).unwrap()
}

/// A drone crossing the square at 12 m/s is said to move, with its early and late spans
/// where it was; the same drone hovering is fixed, its motion check passed.
#[test]
fn a_drone_crossing_the_city_moves_and_a_hovering_one_is_fixed() {
    let crossing = masts(|t| [400.0 + 12.0 * t, 2500.0], 11);
    let r = masts_locate(&crossing);
    let ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(m)) = r.channels()[0].outcome else {
        panic!("{:?}", r.channels()[0]);
    };
    assert!(r.emitters().is_empty());
    assert!(m.moving() && m.apart_sd > 10.0, "{m:?}");
    // The early third's centre is at t = 100 s, (1600, 2500); the late one's at t = 500 s.
    for (span, t) in [(m.early, 100.0), (m.late, 500.0)] {
        let truth = [400.0 + 12.0 * t, 2500.0];
        let err = libm::hypotf(span.position[0] - truth[0], span.position[1] - truth[1]);
        assert!(err < 1200.0, "{err} m: {span:?}");
    }
    let hovering = masts(|_| [4000.0, 4500.0], 12);
    let r = masts_locate(&hovering);
    let e = r.emitters()[0];
    let p = e.motion_p.expect("checked");
    assert!(p > motion::MOTION_ALPHA, "{p}: {e:?}");
}

/// A vehicle's U drive round a still emitter with a 4 degree mounting offset: the thirds see
/// it from three sides and the offset shifts each third's own fix differently, but the shared
/// offset explains them all: not moving.
#[test]
fn a_mounting_offset_round_a_u_drive_is_not_motion() {
    let mut rng = XorShiftRng::seed_from_u64(21);
    let o = drive(&mut rng, 4.0 * DEG);
    let r = run::<512>(&o, &LocateConfig::default());
    let e = r.emitters()[0];
    let p = e.motion_p.expect("checked");
    assert!(p > motion::MOTION_ALPHA, "{p}: {e:?}");
}

/// Four arrays at the middles of a 16 x 12 m room's walls, each looking in and reporting a
/// walker circling in the room's north-west quarter with 12 degrees of noise: the bearings
/// point every way, agree on no point and share no direction. Before the direction's scatter
/// had a ceiling, their mean direction from the room's middle passed Rayleigh's test (1 200
/// bearings) with a scatter of 76 degrees and a half-width of 4.7: a region from the room's
/// middle that missed the walker.
#[test]
fn arrays_round_a_room_share_no_direction() {
    let mut rng = XorShiftRng::seed_from_u64(5);
    let sites = [[0.0f32, 6.0], [8.0, 0.0], [16.0, 6.0], [8.0, 12.0]];
    let o: [Observation; 1200] = core::array::from_fn(|k| {
        let s = k % 4;
        let t = 0.2 * (k / 4) as f32;
        let walker = [
            4.0 + 2.0 * libm::cosf(0.1 * t),
            8.0 + 2.0 * libm::sinf(0.1 * t),
        ];
        let mut x = obs(sites[s], walker, 12.0 * DEG * random::normal(&mut rng), 0);
        x.time_s = t;
        x.station = s as u16;
        x
    });
    let r = masts_locate(&o);
    let outcome = r.channels()[0].outcome;
    assert!(
        matches!(outcome, ChannelOutcome::NoConsistentEmitter(_)),
        "{outcome:?}: {:?}",
        r.regions()
    );
}
