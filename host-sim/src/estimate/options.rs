//! How `locate` computes a fix: the estimator, its particles and seed, and what is known of
//! the bearings (their noise, the DF unit's offset, the channel width). Guidance reads the
//! same settings, so its advice is about the fix `locate` reports.

use super::Priors;
use crate::inputs::stations::Network;
use foxhunt_core::Method;
use foxhunt_core::fix::bias::{BiasPrior, DirectionPrior};
use foxhunt_core::fix::locate::{LocateConfig, NoiseModel};

/// Particles of the sequential methods unless `--particles` says otherwise.
pub const PARTICLES: usize = 1000;

/// The seeds' random-walk jitter for their filters (`sir-seed`, the swarms), m^2 per step: the
/// value of their aoa-afsa scenario. A real drive has no jitter of its own to take.
pub const SEEDS_JITTER_M2: f32 = 1.0;

/// How `locate` computes the fix.
#[derive(Debug, Clone, PartialEq)]
pub struct LocateOptions {
    /// The estimator.
    pub method: Method,
    /// Particles of sequential methods (a compiled count).
    pub particles: usize,
    /// The DF unit's bearing noise, degrees, or `None` to estimate it.
    pub sigma_deg: Option<f32>,
    /// Seed of the particle methods and of the robust search.
    pub seed: u64,
    /// The DF unit's offset, as a calibration measured it (`None`: unknown, estimated with
    /// the default prior).
    pub offset: Option<BiasPrior>,
    /// The DF unit's direction-dependent error, where a calibration measured it: a known
    /// table with its sd, for every station whose stations file states none.
    pub direction: Option<DirectionPrior>,
    /// Bearings within this many MHz share a channel.
    pub channel_width_mhz: f32,
    /// What is known of the network's stations and reference transmitters (`--stations`,
    /// `--reference`; docs/src/networks.md).
    pub network: Option<std::sync::Arc<Network>>,
}

impl Default for LocateOptions {
    fn default() -> Self {
        Self {
            method: Method::MlRobust,
            particles: PARTICLES,
            sigma_deg: None,
            seed: 1,
            offset: None,
            direction: None,
            channel_width_mhz: LocateConfig::default().channel_width_mhz,
            network: None,
        }
    }
}

impl LocateOptions {
    /// Refuse settings no fix can use, naming the value.
    pub fn check(&self) -> Result<(), String> {
        if let Some(s) = self.sigma_deg
            && !(s > 0.0 && s < 90.0)
        {
            return Err(format!(
                "--sigma-deg must lie between 0 and 90 degrees, not {s}"
            ));
        }
        if self.method.uses_particles() && !foxhunt_core::PARTICLE_COUNTS.contains(&self.particles)
        {
            return Err(format!(
                "--particles {} is not a compiled size; use one of {:?}",
                self.particles,
                foxhunt_core::PARTICLE_COUNTS
            ));
        }
        if !(self.channel_width_mhz >= 0.0 && self.channel_width_mhz.is_finite()) {
            return Err(format!(
                "--channel-width-mhz must be a finite number >= 0, not {}",
                self.channel_width_mhz
            ));
        }
        Ok(())
    }

    /// The pipeline's settings for these options.
    pub fn config(&self) -> LocateConfig {
        let mut c = LocateConfig {
            channel_width_mhz: self.channel_width_mhz,
            ..LocateConfig::default()
        };
        if self.sigma_deg.is_some() {
            c.noise = NoiseModel::Known;
        }
        c
    }

    /// Each station's offset prior for these options: the calibration's, else the default.
    pub fn priors(&self) -> Priors {
        let mut p = Priors::same(self.offset.unwrap_or_default());
        self.calibrated_direction(&mut p);
        p
    }

    /// The calibration's direction-dependent error as the default of `priors`: every station
    /// whose stations file states none takes it (a vehicle's front is its course).
    pub fn calibrated_direction(&self, priors: &mut Priors) {
        if let Some(d) = self.direction {
            priors.default_direction = Some((d, None));
        }
    }

    /// Tell `decoder` where the stations file's surveyed stations stand (before their
    /// bytes).
    pub fn survey(&self, decoder: &mut crate::inputs::capture::Decoder) {
        for s in self.network.iter().flat_map(|n| &n.stations) {
            if let Some(at) = s.position {
                decoder.survey(&s.id, at);
            }
        }
    }
}
