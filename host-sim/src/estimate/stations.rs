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
//! bearing so far: the calibration is continuous.

use super::Priors;
use crate::inputs::stations::{Network, PriorFrom};
use foxhunt_core::fix::bias::{BiasPrior, Calibration, calibrate};
use foxhunt_core::fix::channel;
use foxhunt_core::fix::device::class_noise;
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
            .or(network.and_then(|n| n.default_front))
            .unwrap_or(std::f32::consts::FRAC_PI_2);
        setup.priors.direction.push(direction.map(|d| (d, front)));
        if class.is_some() {
            let widest = setup.priors.ceiling.unwrap_or(0.0).max(of_class.ceiling);
            setup.priors.ceiling = Some(widest);
        }
    }
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
    // Per reference and station, its bearings in time order.
    let mut heard: Vec<Vec<Vec<Bearing>>> = vec![vec![Vec::new(); stations]; references.len()];
    let mut rest = Vec::with_capacity(observations.len());
    for o in observations {
        match on(o) {
            Some(r) => {
                if let Some(list) = heard
                    .get_mut(r)
                    .and_then(|h| h.get_mut(usize::from(o.station)))
                {
                    list.push(o.bearing);
                }
            }
            None => rest.push(*o),
        }
    }
    let mut fixes = Vec::new();
    for (r, per_station) in heard.iter().enumerate() {
        for (s, bearings) in per_station.iter().enumerate() {
            let Ok(c) = calibrate(bearings, references[r].position) else {
                continue;
            };
            fixes.push(ReferenceFix {
                station: s as u16,
                reference: r,
                calibration: c,
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
    }
    (rest, fixes)
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
}
