//! A network's stations applied to a drive (docs/src/networks.md): each station's offset
//! prior and noise from the stations file, and the reference transmitters' channels
//! calibrating every station that hears them before the emitters' channels are fixed.
//!
//! A reference is a transmitter at a known position: a station's bearings on its channel
//! measure the station's offset directly, offset = mean(measured - true azimuth) with
//! variance sigma^2 / N_eff ([`foxhunt_core::fix::bias::calibrate`]: the robust mean, N_eff
//! from the residuals' correlation). That measurement and the station's prior are combined
//! (precision-weighted) into the prior its emitter bearings are fixed with, so a fixed
//! station, whose offset its own emitter bearings cannot show, is known to a tenth of a
//! degree after a few minutes of a beacon. Each update recomputes it from every reference
//! bearing so far: the calibration is continuous. Where a station's bearings of a reference
//! span enough directions relative to its antenna (a vehicle that turns in view of it:
//! [`MIN_SPAN`](foxhunt_core::fix::bias::MIN_SPAN)), the same bearings measure its
//! direction-dependent error too ([`calibrate_direction`]), and that table with its sd is
//! combined with the station's stated one; a fixed station sees a reference from one
//! direction and measures the offset only.

use super::Priors;
use crate::inputs::stations::{Network, PriorFrom};
use foxhunt_core::fix::bias::{
    BiasPrior, Calibration, DirectionPrior, HARMONICS, calibrate, calibrate_direction,
    relative_to_course,
};
use foxhunt_core::fix::channel;
use foxhunt_core::fix::device::{AS_REPORTED, DeviceClass, TrackTraits, class_noise};
use foxhunt_core::fix::locate::Observation;
use foxhunt_core::model::bearing::{Bearing, wrap};
use serde::Serialize;

/// Where a station's offset prior came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum PriorOrigin {
    /// The default of an uncalibrated unit.
    Default,
    /// `--calibration FILE`, for every station.
    Calibration,
    /// The stations file (its entry, or its `[default]`).
    StationsFile,
    /// A calibration file the stations file names for it.
    StationCalibration,
    /// A reference transmitter it heard on this drive.
    Reference,
}

/// A reference transmitter in the drive's local frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalReference {
    /// Where it is, local metres.
    pub position: [f32; 2],
    /// Its channel's frequency, MHz.
    pub freq_mhz: f32,
}

/// One station's offset measured on one reference's channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceFix {
    /// The station.
    pub station: u16,
    /// The reference (its index).
    pub reference: usize,
    /// The measurement.
    pub calibration: Calibration,
    /// Its direction-dependent error measured with the offset, where the bearings spanned
    /// enough directions ([`MIN_SPAN`](foxhunt_core::fix::bias::MIN_SPAN)).
    pub direction: Option<DirectionPrior>,
    /// How evenly they spanned them (the smallest eigenvalue of the harmonics' information
    /// per bearing; 0.5 an even full turn), where it could be computed.
    pub span: Option<f32>,
}

/// A harmonic table more uncertain than this (sd, radians) is no measurement worth applying:
/// the calibration file's limit ([`crate::inputs::calibration::MAX_HARMONIC_DEG`]).
fn max_direction_sd() -> f32 {
    crate::inputs::calibration::MAX_HARMONIC_DEG.to_radians()
}

/// `prior` and a measured table combined coefficient by coefficient, precision-weighted with
/// the one sd of each (the measurement alone where nothing was stated).
pub fn combine_direction(
    prior: Option<DirectionPrior>,
    measured: DirectionPrior,
) -> DirectionPrior {
    let Some(p) = prior.filter(DirectionPrior::is_free) else {
        return match prior {
            // A table stated exact stays.
            Some(p) if p != DirectionPrior::NONE => p,
            _ => measured,
        };
    };
    if !(measured.sd > 0.0) {
        return measured;
    }
    let (wp, wm) = (1.0 / (p.sd * p.sd), 1.0 / (measured.sd * measured.sd));
    let mean: [f32; HARMONICS] =
        std::array::from_fn(|k| (p.mean[k] * wp + measured.mean[k] * wm) / (wp + wm));
    DirectionPrior {
        mean,
        sd: 1.0 / (wp + wm).sqrt(),
    }
}

/// Each station's prior and unmodelled error (with the stated classes' ceiling), where the
/// prior came from, and its noise (radians) if the file or its class states one.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StationSetup {
    /// The priors.
    pub priors: Priors,
    /// Where each station's came from, by station index.
    pub origins: Vec<PriorOrigin>,
    /// Each station's noise, by station index.
    pub noise: Vec<Option<f32>>,
    /// Each station's device class, by station index (`None`: not stated).
    pub classes: Vec<Option<DeviceClass>>,
}

impl StationSetup {
    /// Whether station `s`'s offset prior is its own (stated or measured), not the default.
    pub fn own_prior(&self, s: usize) -> bool {
        self.origins
            .get(s)
            .is_some_and(|o| *o != PriorOrigin::Default)
    }

    /// How a track takes station `s`'s reports: its class's ([`DeviceClass::track`]).
    pub fn track_traits(&self, s: usize) -> TrackTraits {
        self.classes
            .get(s)
            .copied()
            .flatten()
            .map_or(AS_REPORTED, DeviceClass::track)
    }
}

/// The priors and noise of stations `ids` (by station index) from `network`, else the
/// fallback (`--calibration`'s when `calibrated`).
pub fn station_setup<'a>(
    ids: impl Iterator<Item = &'a str>,
    network: Option<&Network>,
    fallback: BiasPrior,
    calibrated: bool,
) -> StationSetup {
    let fallback_from = if calibrated {
        PriorOrigin::Calibration
    } else {
        PriorOrigin::Default
    };
    let default = network
        .and_then(|n| n.default_prior)
        .map_or((fallback, fallback_from), |p| {
            (p, PriorOrigin::StationsFile)
        });
    let mut setup = StationSetup {
        priors: Priors::same(default.0),
        ..StationSetup::default()
    };
    for id in ids {
        let spec = network.and_then(|n| n.station(id));
        let (prior, from) = match spec {
            Some(s) => match s.from {
                PriorFrom::Calibration => (s.prior, PriorOrigin::StationCalibration),
                PriorFrom::StationsFile => (s.prior, PriorOrigin::StationsFile),
                PriorFrom::Default => default,
            },
            None => default,
        };
        setup.priors.stations.push(Some(prior));
        setup.origins.push(from);
        // Its device class (its own, else the file's default) gives what the file does not
        // state: the noise, the unmodelled error; the widest ceiling among the classes holds.
        let class = spec
            .and_then(|s| s.antenna)
            .or(network.and_then(|n| n.default_antenna));
        let of_class = class_noise(class);
        setup.classes.push(class);
        setup.noise.push(
            spec.and_then(|s| s.noise)
                .or(network.and_then(|n| n.default_noise))
                .or(of_class.noise),
        );
        setup.priors.unmodelled.push(Some(
            spec.and_then(|s| s.unmodelled)
                .or(network.and_then(|n| n.default_unmodelled))
                .unwrap_or(of_class.unmodelled),
        ));
        let direction = spec
            .and_then(|s| s.direction)
            .or(network.and_then(|n| n.default_direction));
        let front = spec
            .and_then(|s| s.front)
            .or(network.and_then(|n| n.default_front));
        setup.priors.direction.push(direction.map(|d| (d, front)));
        if class.is_some() {
            let widest = setup.priors.ceiling.unwrap_or(0.0).max(of_class.ceiling);
            setup.priors.ceiling = Some(widest);
        }
    }
    setup.priors.noise_stated = !setup.noise.is_empty() && setup.noise.iter().all(Option::is_some);
    setup
}

/// `prior` and a measurement of the offset (`calibration`) combined, precision-weighted: the
/// measurement alone where there was no prior, the prior alone where it is exact.
pub fn combine(prior: BiasPrior, calibration: &Calibration) -> BiasPrior {
    if !prior.is_free() {
        return prior;
    }
    let m = calibration.prior();
    if !(m.sd > 0.0) {
        return m;
    }
    let wm = 1.0 / (m.sd * m.sd);
    let wp = if prior.sd.is_finite() {
        1.0 / (prior.sd * prior.sd)
    } else {
        0.0
    };
    let d = wrap(m.mean - prior.mean);
    BiasPrior {
        mean: wrap(prior.mean + d * wm / (wm + wp)),
        sd: 1.0 / (wm + wp).sqrt(),
    }
}

/// Take the reference channels' bearings out of `observations` and calibrate every station
/// that heard a reference on them: its prior in `setup` becomes the combination of its prior
/// and its measurements ([`combine`]). Returns the emitter channels' bearings and the
/// measurements. A station with fewer than two usable bearings on a reference's channel
/// keeps its prior.
pub fn calibrate_on_references(
    observations: &[Observation],
    references: &[LocalReference],
    width_mhz: f32,
    setup: &mut StationSetup,
) -> (Vec<Observation>, Vec<ReferenceFix>) {
    // Without a reference nothing is taken out, and no station's course need be followed (a
    // live update would otherwise walk every bearing so far).
    if references.is_empty() {
        return (observations.to_vec(), Vec::new());
    }
    let on = |o: &Observation| {
        references.iter().position(|r| {
            channel::belongs(o.freq_mhz, Some(r.freq_mhz - width_mhz / 2.0), width_mhz)
        })
    };
    let stations = observations
        .iter()
        .map(|o| usize::from(o.station) + 1)
        .max()
        .unwrap_or(0);
    // Each bearing relative to its station's antenna: a moving station's course over all its
    // bearings (every channel's), a fixed one's stated front.
    let relative = relative_bearings(observations, stations, setup);
    // Per reference and station, its bearings in time order, with their relative bearings.
    type Heard = (Vec<Bearing>, Vec<f32>);
    let mut heard: Vec<Vec<Heard>> = vec![vec![Heard::default(); stations]; references.len()];
    let mut rest = Vec::with_capacity(observations.len());
    for (o, phi) in observations.iter().zip(&relative) {
        match on(o) {
            Some(r) => {
                if let Some((list, phis)) = heard
                    .get_mut(r)
                    .and_then(|h| h.get_mut(usize::from(o.station)))
                {
                    list.push(o.bearing);
                    phis.push(*phi);
                }
            }
            None => rest.push(*o),
        }
    }
    let mut fixes = Vec::new();
    for (r, per_station) in heard.iter().enumerate() {
        for (s, (bearings, phis)) in per_station.iter().enumerate() {
            let at = references[r].position;
            let joint = calibrate_direction(bearings, phis, at).ok();
            let span = joint.map(|j| j.span);
            let (calibration, direction) = match joint {
                Some(j) if j.measured() && j.sd() <= max_direction_sd() => {
                    (j.offset, Some(j.prior()))
                }
                _ => match calibrate(bearings, at) {
                    Ok(c) => (c, None),
                    Err(_) => continue,
                },
            };
            fixes.push(ReferenceFix {
                station: s as u16,
                reference: r,
                calibration,
                direction,
                span,
            });
        }
    }
    for f in &fixes {
        let s = usize::from(f.station);
        if setup.priors.stations.len() <= s {
            setup.priors.stations.resize(s + 1, None);
            setup.origins.resize(s + 1, PriorOrigin::Default);
        }
        let prior = setup.priors.of(s);
        setup.priors.stations[s] = Some(combine(prior, &f.calibration));
        setup.origins[s] = PriorOrigin::Reference;
        if let Some(measured) = f.direction {
            if setup.priors.direction.len() <= s {
                setup.priors.direction.resize(s + 1, None);
            }
            let stated = setup.priors.direction[s].or(setup.priors.default_direction);
            let front = stated.and_then(|(_, front)| front);
            let table = combine_direction(stated.map(|(p, _)| p), measured);
            setup.priors.direction[s] = Some((table, front));
        }
    }
    (rest, fixes)
}

/// Each observation's bearing relative to its station's antenna, as the fix takes it: a
/// station's bearings in time order, its front its course where it moves, else the front
/// `setup` states for it (north where none).
fn relative_bearings(
    observations: &[Observation],
    stations: usize,
    setup: &StationSetup,
) -> Vec<f32> {
    let mut by_station: Vec<Vec<usize>> = vec![Vec::new(); stations];
    for (k, o) in observations.iter().enumerate() {
        by_station[usize::from(o.station)].push(k);
    }
    let mut relative = vec![0.0f32; observations.len()];
    for (s, indices) in by_station.iter().enumerate() {
        let front = Priors::front(setup.priors.direction_of(s).and_then(|(_, front)| front));
        let bearings: Vec<Bearing> = indices.iter().map(|&k| observations[k].bearing).collect();
        let mut phis = vec![0.0f32; bearings.len()];
        relative_to_course(&bearings, front, &mut phis);
        for (&k, phi) in indices.iter().zip(phis) {
            relative[k] = phi;
        }
    }
    relative
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cal(bias_deg: f32, sd_deg: f32) -> Calibration {
        Calibration {
            bias: bias_deg.to_radians(),
            sd: sd_deg.to_radians(),
            sigma: 0.03,
            used: 100,
            rejected: 0,
            effective: 100.0,
        }
    }

    #[test]
    fn a_measurement_and_a_prior_combine_by_their_precisions() {
        let prior = BiasPrior {
            mean: 0.0,
            sd: 3f32.to_radians(),
        };
        // A measurement nine times as precise: the mean moves 90 % of the way.
        let c = combine(prior, &cal(2.0, 1.0));
        assert!(
            (c.mean.to_degrees() - 1.8).abs() < 1e-3,
            "{}",
            c.mean.to_degrees()
        );
        assert!((c.sd.to_degrees() - 0.948_683).abs() < 1e-3);
        // No prior: the measurement; an exact prior: the prior.
        let none = BiasPrior {
            mean: 0.0,
            sd: f32::INFINITY,
        };
        assert_eq!(combine(none, &cal(2.0, 1.0)), cal(2.0, 1.0).prior());
        let exact = BiasPrior::calibrated(0.5);
        assert_eq!(combine(exact, &cal(2.0, 1.0)), exact);
    }

    #[test]
    fn a_station_that_turns_in_view_of_a_reference_measures_its_harmonics_a_fixed_one_its_offset() {
        use foxhunt_core::fix::bias::DirectionPrior;
        use foxhunt_core::model::bearing::predicted;
        use foxhunt_core::random;
        use rand_core::SeedableRng;
        let reference = LocalReference {
            position: [0.0, 0.0],
            freq_mhz: 145.5,
        };
        let table = [3.0f32, -2.0, 1.5, 2.5].map(f32::to_radians);
        let unit = DirectionPrior {
            mean: table,
            sd: 0.0,
        };
        let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(3);
        let mut observations = Vec::new();
        // Station 0 drives a lap of a 600 m circle 2.5 km from the reference (400 bearings);
        // station 1 stands still 3 km north of it.
        for k in 0..400 {
            let a = 2.0 * std::f32::consts::PI * k as f32 / 400.0;
            let v = [2500.0 + 600.0 * a.cos(), 600.0 * a.sin()];
            let truth = predicted(&reference.position, &v);
            // Model-consistent: the error of the reported bearing relative to the course.
            let plain = truth + 0.05 + 0.02 * random::normal(&mut rng);
            let course = a + std::f32::consts::FRAC_PI_2;
            let mut theta = plain;
            for _ in 0..8 {
                theta = plain + unit.error_at(wrap(theta - course));
            }
            for (station, vehicle, theta) in [
                (0u16, v, theta),
                (
                    1,
                    [0.0, 3000.0],
                    -std::f32::consts::FRAC_PI_2 + 0.02 * random::normal(&mut rng),
                ),
            ] {
                observations.push(Observation {
                    bearing: Bearing {
                        vehicle,
                        theta: wrap(theta),
                        sigma: 0.02,
                    },
                    time_s: k as f32,
                    freq_mhz: Some(145.5),
                    station,
                    stamped: true,
                });
            }
        }
        let mut setup = station_setup(
            ["car", "mast"].into_iter(),
            None,
            BiasPrior::default(),
            false,
        );
        let (rest, fixes) = calibrate_on_references(&observations, &[reference], 0.05, &mut setup);
        assert!(rest.is_empty());
        let car = fixes.iter().find(|f| f.station == 0).expect("car");
        let mast = fixes.iter().find(|f| f.station == 1).expect("mast");
        let measured = car.direction.expect("the car turned");
        // 400 bearings of 1.15 degrees: each coefficient to about 0.08 degrees; 0.4 is five of
        // those, beyond noise.
        for k in 0..4 {
            assert!(
                (measured.mean[k] - table[k]).abs() < 0.4f32.to_radians(),
                "{:?}",
                measured.mean.map(f32::to_degrees)
            );
        }
        assert!(
            measured.sd > 0.0 && measured.sd < 0.2f32.to_radians(),
            "{}",
            measured.sd
        );
        // The car's table is applied to its emitter bearings, with the measurement's sd.
        let (applied, _) = setup.priors.direction[0].expect("applied");
        assert_eq!(applied, measured);
        // The mast sees the reference from one direction: its offset only.
        // (Its relative bearings are all one: the fit is degenerate, no span at all.)
        assert!(mast.direction.is_none() && mast.span.is_none_or(|s| s < 0.01));
        assert!(setup.priors.direction.get(1).copied().flatten().is_none());
    }
}
