//! The settings of [`super::locate`].

use super::super::bias::BiasedOptions;
use super::super::robust::RansacOptions;
use crate::error::{Error, check_finite};

/// How far the bearings' own sigmas are trusted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NoiseModel {
    /// Estimate the noise from the residuals; intervals use the F distribution.
    #[default]
    Estimated,
    /// The sigmas are the unit's, checked by the residuals' chi-square.
    Known,
}

/// Settings of [`super::locate`] (each station's offset prior is in its row of the station
/// table, [`super::Buffers`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocateConfig {
    /// Whether the bearings' sigmas are estimated or trusted.
    pub noise: NoiseModel,
    /// Frequencies within this of a channel's lowest share the channel, MHz
    /// ([`channel::belongs`](super::super::channel::belongs)).
    pub channel_width_mhz: f32,
    /// Probability inside the reported ellipses.
    pub confidence: f32,
    /// Estimated noise above this (radians) means no consistent emitter: the stations' device
    /// class's ceiling ([`ClassNoise::ceiling`](crate::fix::device::ClassNoise::ceiling); the
    /// widest where several classes share a channel), by default an unstated class's.
    pub max_sigma: f32,
    /// A cluster is a source only if luck would line up as many bearings with a chance below
    /// this.
    pub significance: f32,
    /// Whether the bearings' sigmas are their stations' stated noise (a stations file's, or
    /// its device class's): the chance test then judges a cluster's agreement at no less than
    /// that noise, so that a handful of noisy bearings whose scatter happened to be small is
    /// not passed for it (the passed ones' ellipses were too small with their scatter).
    pub noise_stated: bool,
    /// With [`NoiseModel::Known`], a residual chi-square p-value below this marks the unit
    /// noisier than it claims.
    pub consistency: f32,
    /// Sources (emitter and others) sought per channel at most.
    pub max_sources_per_channel: u32,
    /// Bearings a source needs at least.
    pub min_bearings: u32,
    /// The robust search.
    pub ransac: RansacOptions,
    /// The solver.
    pub solver: BiasedOptions,
}

impl Default for LocateConfig {
    fn default() -> Self {
        Self {
            noise: NoiseModel::Estimated,
            channel_width_mhz: 0.05,
            confidence: 0.95,
            max_sigma: crate::fix::device::UNSTATED.ceiling,
            significance: 0.01,
            noise_stated: false,
            consistency: 1e-3,
            max_sources_per_channel: 4,
            min_bearings: 3,
            ransac: RansacOptions::default(),
            solver: BiasedOptions::default(),
        }
    }
}

impl LocateConfig {
    /// `Ok` when every setting is usable.
    pub fn check(&self) -> Result<(), Error> {
        self.ransac.check()?;
        check_finite(&[
            self.channel_width_mhz,
            self.confidence,
            self.max_sigma,
            self.significance,
            self.consistency,
        ])?;
        if self.channel_width_mhz >= 0.0
            && self.confidence > 0.0
            && self.confidence < 1.0
            && self.max_sigma > 0.0
            && self.significance > 0.0
            && self.consistency >= 0.0
            && self.min_bearings >= 3
        {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}
