//! Network conditions (docs/src/networks.md): fixed DF stations around a city, each with its
//! own mounting offset and noise, sometimes a vehicle among them, a reference transmitter or a
//! station that drops out; simulated so the default pipeline and df-aggregator's algorithm
//! ([`peer`]) can be measured on the same seeded runs (`bench --scenario network`).
//!
//! Every run draws afresh (chosen to match the measured network drives of the book):
//! - the emitter at the origin on 433.920 MHz;
//! - fixed stations spread round it (station k at bearing 360 k / S degrees plus up to
//!   +-25 degrees, 6-10 km away), each reporting once a second for 10 minutes;
//! - each station's offset drawn with sd 3 degrees and its noise uniform in 1.5-3 degrees; the
//!   stations file states each station's noise and an offset prior N(0, 3 degrees), the spread
//!   the offsets are drawn from (an honest prior: what a network knows of its masts);
//! - the vehicle (`network-mobile`) drives a 6 km L at 10 m/s (3 km east from (-5, -4) km,
//!   then 3 km north), 2.2-6.4 km from the emitter, its offset drawn and stated the same way;
//! - the reference transmitter (`network-reference`) at a surveyed site 5 km north-east of the
//!   emitter on 145.500 MHz, heard by every station once a second between its emitter bearings;
//! - the dropout (`network-dropout`): four stations, one silent after 2 minutes and another
//!   heard only from minute 6.

mod bench;
mod capture;
pub mod peer;

pub use bench::{bench, locate_network, measure_network};
pub use capture::{START_MS, capture};

use crate::estimate::stations::LocalReference;
use crate::runs::field::{FieldDrive, StationTruth, Truth};
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::device::DeviceClass;
use foxhunt_core::fix::locate::Observation;
use foxhunt_core::model::bearing::{Bearing, predicted, wrap};
use foxhunt_core::random;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::f32::consts::PI;

const DEG: f32 = PI / 180.0;

/// The emitter's channel, MHz.
pub const EMITTER_MHZ: f32 = 433.92;
/// The reference transmitter's channel, MHz.
pub const REFERENCE_MHZ: f32 = 145.5;
/// The sd the offsets are drawn with and the stations file states, radians.
pub const OFFSET_SD: f32 = 3.0 * DEG;
/// Seconds of bearings per station (10 minutes at 1 Hz).
const SECONDS: usize = 600;

/// A simulated network condition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NetworkCondition {
    /// Three fixed stations.
    Fixed3,
    /// Five fixed stations.
    Fixed5,
    /// Two fixed stations and a vehicle.
    Mobile,
    /// Three fixed stations and a reference transmitter they all hear.
    Reference,
    /// Four fixed stations, one silent after 2 minutes, one heard only from minute 6.
    Dropout,
}

impl NetworkCondition {
    /// Every condition, in report order.
    pub const ALL: [NetworkCondition; 5] = [
        NetworkCondition::Fixed3,
        NetworkCondition::Fixed5,
        NetworkCondition::Mobile,
        NetworkCondition::Reference,
        NetworkCondition::Dropout,
    ];

    /// The name printed in reports and given to `--condition`.
    pub fn name(&self) -> &'static str {
        match self {
            NetworkCondition::Fixed3 => "network-fixed3",
            NetworkCondition::Fixed5 => "network-fixed5",
            NetworkCondition::Mobile => "network-mobile",
            NetworkCondition::Reference => "network-reference",
            NetworkCondition::Dropout => "network-dropout",
        }
    }

    /// The name without its `network-` (`bench --scenario network/NAME`).
    pub fn short_name(&self) -> &'static str {
        let n = self.name();
        n.strip_prefix("network-").unwrap_or(n)
    }

    /// A condition by name.
    pub fn named(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|c| c.name() == name)
    }
}

/// One run of a network condition: the drive (its stations' truths and stated priors) and the
/// reference transmitters the stations file names.
#[derive(Debug, Clone, PartialEq)]
pub struct NetworkDrive {
    /// The observations, emitters and stations.
    pub drive: FieldDrive,
    /// The reference transmitters, local metres.
    pub references: Vec<LocalReference>,
    /// Each station's positions in time order (one for a fixed station), local metres: the
    /// capture's records.
    pub tracks: Vec<Vec<[f32; 2]>>,
}

/// The seeded generator of run `run` of `c`.
fn rng(c: NetworkCondition, run: usize) -> XorShiftRng {
    let salt = NetworkCondition::ALL
        .iter()
        .position(|x| *x == c)
        .unwrap_or(0) as u64;
    XorShiftRng::seed_from_u64(
        (salt + 101)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(run as u64),
    )
}

/// A station's drawn truth: fixed or not, offset and noise; its stations-file prior.
fn draw_station(id: String, fixed: bool, rng: &mut XorShiftRng) -> StationTruth {
    StationTruth {
        id,
        fixed,
        offset: OFFSET_SD * random::normal(rng),
        sigma: random::uniform_in(rng, 1.5, 3.0) * DEG,
        prior: BiasPrior {
            mean: 0.0,
            sd: OFFSET_SD,
        },
        // KrakenSDR arrays, simulated without an unmodelled error (their stations file says
        // so).
        class: Some(DeviceClass::Uca),
        unmodelled: Some(0.0),
    }
}

/// Fixed station positions: `n` spread round the origin 6-10 km out.
fn masts(n: usize, rng: &mut XorShiftRng) -> Vec<[f32; 2]> {
    (0..n)
        .map(|k| {
            let a = 2.0 * PI * k as f32 / n as f32 + random::uniform_in(rng, -25.0, 25.0) * DEG;
            let r = random::uniform_in(rng, 6000.0, 10_000.0);
            [r * a.cos(), r * a.sin()]
        })
        .collect()
}

/// The vehicle's 6 km L at 10 m/s, one position a second.
fn l_route() -> Vec<[f32; 2]> {
    (0..SECONDS)
        .map(|k| {
            let s = 10.0 * k as f32;
            if s < 3000.0 {
                [-5000.0 + s, -4000.0]
            } else {
                [-2000.0, -4000.0 + (s - 3000.0)]
            }
        })
        .collect()
}

/// Run `run` of condition `c`.
pub fn simulate(c: NetworkCondition, run: usize) -> NetworkDrive {
    let mut rng = rng(c, run);
    let rng = &mut rng;
    let emitter = [0.0f32, 0.0];
    let fixed = match c {
        NetworkCondition::Fixed3 | NetworkCondition::Reference => 3,
        NetworkCondition::Fixed5 => 5,
        NetworkCondition::Mobile => 2,
        NetworkCondition::Dropout => 4,
    };
    let mut tracks: Vec<Vec<[f32; 2]>> = masts(fixed, rng).into_iter().map(|p| vec![p]).collect();
    let mut stations: Vec<StationTruth> = (0..fixed)
        .map(|k| draw_station(format!("mast-{}", k + 1), true, rng))
        .collect();
    if c == NetworkCondition::Mobile {
        tracks.push(l_route());
        stations.push(draw_station("car-1".into(), false, rng));
    }
    let references = if c == NetworkCondition::Reference {
        vec![LocalReference {
            position: [3536.0, 3536.0],
            freq_mhz: REFERENCE_MHZ,
        }]
    } else {
        Vec::new()
    };
    // Which seconds station s is heard.
    let heard = |s: usize, t: usize| match c {
        NetworkCondition::Dropout if s == 1 => t < 120,
        NetworkCondition::Dropout if s == 2 => t >= 360,
        _ => true,
    };
    let mut observations = Vec::new();
    for t in 0..SECONDS {
        for (s, st) in stations.iter().enumerate() {
            if !heard(s, t) {
                continue;
            }
            let at = tracks[s][t.min(tracks[s].len() - 1)];
            let bearing = |target: [f32; 2], rng: &mut XorShiftRng| Bearing {
                vehicle: at,
                theta: wrap(predicted(&target, &at) + st.offset + st.sigma * random::normal(rng)),
                sigma: st.sigma,
            };
            let b = bearing(emitter, rng);
            observations.push(Observation {
                freq_mhz: Some(EMITTER_MHZ),
                station: s as u16,
                ..Observation::new(b, t as f32)
            });
            for r in &references {
                let b = bearing(r.position, rng);
                observations.push(Observation {
                    freq_mhz: Some(r.freq_mhz),
                    station: s as u16,
                    ..Observation::new(b, t as f32 + 0.5)
                });
            }
        }
    }
    NetworkDrive {
        drive: FieldDrive {
            observations,
            emitters: vec![Truth {
                position: emitter,
                freq_mhz: Some(EMITTER_MHZ),
            }],
            ghost: None,
            bias: 0.0,
            sigma: 2.0 * DEG,
            stations,
        },
        references,
        tracks,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stations_bearings_carry_its_own_offset() {
        let n = simulate(NetworkCondition::Fixed3, 0);
        for (s, st) in n.drive.stations.iter().enumerate() {
            let mine: Vec<f32> = n
                .drive
                .observations
                .iter()
                .filter(|o| usize::from(o.station) == s)
                .map(|o| wrap(o.bearing.theta - predicted(&[0.0, 0.0], &o.bearing.vehicle)))
                .collect();
            assert_eq!(mine.len(), SECONDS);
            let mean = mine.iter().sum::<f32>() / mine.len() as f32;
            // 600 bearings of sd <= 3 degrees: the mean within 4 sd of the offset.
            assert!(
                (mean - st.offset).abs() < 4.0 * st.sigma / (SECONDS as f32).sqrt(),
                "station {s}: {} against {}",
                mean.to_degrees(),
                st.offset.to_degrees()
            );
        }
    }

    #[test]
    fn the_dropout_silences_one_station_and_starts_another_late() {
        let n = simulate(NetworkCondition::Dropout, 3);
        let count = |s: u16| {
            n.drive
                .observations
                .iter()
                .filter(|o| o.station == s)
                .count()
        };
        assert_eq!(
            [count(0), count(1), count(2), count(3)],
            [600, 120, 240, 600]
        );
    }
}
