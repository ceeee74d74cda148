use super::*;
use crate::likelihood::{Gaussian, GaussianUniform};
use crate::model::bearing::{Bearing, predicted};
use crate::model::rssi::PathLoss;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

const LAYOUT: Layout = Layout {
    sources: 2,
    rssi: true,
};
const LAW: PathLoss = PathLoss {
    p0: -40.0,
    d0: 1.0,
    eta: 2.5,
};

fn bearing(v: [f32; 2], theta: f32, source: u8) -> Observation {
    let mut o = Observation::new(
        Bearing {
            vehicle: v,
            theta,
            sigma: 0.03,
        },
        0.0,
    );
    o.station = u16::from(source);
    o
}

#[test]
fn weights_are_the_predictive_density_before_conditioning() {
    let m = Mover::<4>::new(Motion::OUTDOOR, LAYOUT);
    let mut rng = XorShiftRng::seed_from_u64(3);
    let mut states: [[f32; 14]; 37] = core::array::from_fn(|_| {
        core::array::from_fn(|j| match j {
            0 | 1 => random::uniform_in(&mut rng, -2000.0, 2000.0),
            5 | 7 => random::uniform_in(&mut rng, -0.2, 0.2),
            6 | 8 => random::uniform_in(&mut rng, 0.0, 0.01),
            9 => random::uniform_in(&mut rng, -5.0, 5.0),
            10 => random::uniform_in(&mut rng, -0.5, 0.5),
            11 => 36.0,
            12 => 0.1,
            13 => 0.04,
            _ => 0.0,
        })
    });
    let lik = GaussianUniform { eps: 0.05 };
    for z in [
        {
            let mut e = Epoch::<4>::new(1.0);
            e.push_bearing(bearing([900.0, -300.0], 1.0, 1)).unwrap();
            e
        },
        {
            let mut e = Epoch::<4>::new(1.0);
            e.push_level(Level {
                anchor: [50.0, 60.0],
                dbm: -95.0,
                sigma_db: 4.0,
                law: LAW,
            })
            .unwrap();
            e
        },
    ] {
        let before = states;
        let mut lw = [0.0f32; 37];
        m.update_all(&mut states, &z, &lik, &mut lw);
        for ((x, w), after) in before.iter().zip(lw).zip(states.iter()) {
            let slow = m.ln_likelihood(x, &z, &lik);
            assert!((w - slow).abs() <= 1e-4 * slow.abs().max(1.0), "{w} {slow}");
            // Conditioning never widens.
            assert!(after[6] <= x[6] && after[8] <= x[8] && after[11] <= x[11]);
            assert!(after[13] <= x[13]);
        }
    }
}

#[test]
fn a_particle_on_the_emitter_learns_the_offset_at_the_kalman_rate() {
    let m = Mover::<4>::new(
        Motion::OUTDOOR,
        Layout {
            sources: 1,
            rssi: false,
        },
    );
    let p = [1000.0f32, 500.0];
    let mut x = [p[0], p[1], 0.0, 0.0, 0.0, 0.0, 0.01];
    for k in 0..100 {
        let v = [0.0, 10.0 * k as f32];
        let mut z = Epoch::<4>::new(1.0);
        // The unit reads 0.05 rad high, alternately 0.03 either side.
        let noise = if k % 2 == 0 { 0.03 } else { -0.03 };
        z.push_bearing(bearing(v, predicted(&p, &v) + 0.05 + noise, 0))
            .unwrap();
        let mut lw = [0.0];
        let mut one = [x];
        m.update_all(&mut one, &z, &Gaussian, &mut lw);
        x = one[0];
    }
    // Prior variance 0.01, 100 bearings of variance 9e-4: posterior 1 / (100 + 1111).
    assert!((x[5] - 0.05).abs() < 0.003, "{x:?}");
    assert!((x[6] - 1.0 / (100.0 + 100.0 / 9e-4)).abs() < 1e-7, "{x:?}");
}

#[test]
fn the_rssi_terms_are_learned_from_readings_at_several_ranges() {
    let m = Mover::<4>::new(
        Motion::OUTDOOR,
        Layout {
            sources: 0,
            rssi: true,
        },
    );
    let p = [0.0f32, 0.0];
    // Power 4 dB above the law, exponent 0.3 steeper; noise-free readings.
    let truth = PathLoss {
        p0: LAW.p0 + 4.0,
        eta: LAW.eta + 0.3,
        ..LAW
    };
    let mut x = [0.0f32; 10];
    x[7] = 100.0;
    x[9] = 1.0;
    for k in 0..200 {
        let anchor = [10.0 + 20.0 * (k % 10) as f32, 0.0];
        let mut z = Epoch::<4>::new(1.0);
        z.push_level(Level {
            anchor,
            dbm: truth.rssi(anchor[0]),
            sigma_db: 2.0,
            law: LAW,
        })
        .unwrap();
        let mut one = [x];
        m.update_all(&mut one, &z, &Gaussian, &mut [0.0]);
        x = one[0];
        let _ = p;
    }
    assert!(
        (x[5] - 4.0).abs() < 0.2 && (x[6] - 0.3).abs() < 0.02,
        "{x:?}"
    );
    assert!(x[7] < 1.0 && x[9] < 0.01, "{x:?}");
}

#[test]
fn still_stays_moving_moves_and_switches_happen_at_their_rates() {
    let motion = Motion {
        accel_sd: 0.5,
        start_rate: 0.1,
        stop_rate: 0.2,
        start_speed_sd: 3.0,
    };
    let m = Mover::<4>::new(motion, Layout::default());
    let mut rng = XorShiftRng::seed_from_u64(9);
    let z = Epoch::<4>::new(1.0);
    let mut still = [[0.0f32; 5]; 4000];
    m.propagate_all(&mut still, &z, &mut rng);
    let started = still.iter().filter(|x| x[MODE] > 0.5).count() as f32 / 4000.0;
    // 1 - exp(-0.1) = 0.095; binomial sd over 4000 draws is 0.005.
    assert!((started - 0.0952).abs() < 0.02, "{started}");
    for x in still.iter().filter(|x| x[MODE] < 0.5) {
        assert_eq!(x[..4], [0.0; 4]);
    }
    let mut moving = [[0.0f32, 0.0, 10.0, 0.0, 1.0]; 4000];
    m.propagate_all(&mut moving, &z, &mut rng);
    let stopped = moving.iter().filter(|x| x[MODE] < 0.5).count() as f32 / 4000.0;
    assert!((stopped - 0.1813).abs() < 0.025, "{stopped}");
    let went: f32 = moving
        .iter()
        .filter(|x| x[MODE] > 0.5)
        .map(|x| x[0])
        .sum::<f32>()
        / moving.iter().filter(|x| x[MODE] > 0.5).count() as f32;
    assert!((went - 10.0).abs() < 0.1, "{went}");
}

#[test]
fn the_kernel_moves_the_position_with_the_offset_means_and_the_layout_must_fit() {
    let m = Mover::<4>::new(
        Motion::OUTDOOR,
        Layout {
            sources: 1,
            rssi: false,
        },
    );
    // Position and source 0's offset mean (component 5); not its variance, nor unused room.
    let mut cov = [[0.0f32; 8]; 8];
    for (j, row) in cov.iter_mut().enumerate() {
        row[j] = 1.0;
    }
    let mask: [bool; 8] = m.regularised(&cov);
    assert_eq!(mask, [true, true, false, false, false, true, false, false]);
    // Nor an offset mean the cloud does not spread (a source not heard yet).
    cov[5][5] = 0.0;
    let mask: [bool; 8] = m.regularised(&cov);
    assert_eq!(mask, [true, true, false, false, false, false, false, false]);
    let mut z = Epoch::<4>::new(1.0);
    z.push_bearing(bearing([0.0, 0.0], 0.0, 0)).unwrap();
    assert_eq!(
        <Mover<4> as Model<6>>::check(&m, &z),
        Err(Error::OutOfRange)
    );
    assert_eq!(<Mover<4> as Model<7>>::check(&m, &z), Ok(()));
    z.push_bearing(bearing([0.0, 0.0], 0.0, 1)).unwrap();
    assert_eq!(
        <Mover<4> as Model<7>>::check(&m, &z),
        Err(Error::OutOfRange)
    );
}
