//! What the windowed fix is told: its noise model and window, and why a setting or a bearing
//! is refused.

use super::{DEG, MIN_SIGMA, WINDOW};

/// How the bearings' noise is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Noise {
    /// Every bearing's sigma is this (radians) times its relative weight; the residuals only
    /// check it (a unit clearly noisier than it claims gets the estimated scale).
    Known(f32),
    /// Estimated from the residuals; this (radians) is where the estimate starts.
    Estimated(f32),
}

impl Noise {
    /// Where the scale starts, radians.
    pub(super) fn start(self) -> f32 {
        match self {
            Self::Known(s) | Self::Estimated(s) => s,
        }
    }
}

/// WindowFix settings (the unit's configuration commands change them at run time).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct WindowConfig {
    /// Bearings kept at most (1 to [`WINDOW`]).
    pub window: u16,
    /// Bearings older than the newest by more than this are dropped, ms.
    pub max_age_ms: u32,
    /// The noise model.
    pub noise: Noise,
    /// An estimated noise above this (radians) makes the fix "noisy", not valid (by default
    /// the ceiling of a unit of unstated class, [`crate::fix::device::UNSTATED`]).
    pub max_sigma: f32,
}

impl Default for WindowConfig {
    fn default() -> Self {
        Self {
            window: 120,
            max_age_ms: 300_000,
            noise: Noise::Estimated(2.0 * DEG),
            max_sigma: crate::fix::device::UNSTATED.ceiling,
        }
    }
}

impl WindowConfig {
    /// `Ok` when every setting is usable.
    pub fn check(&self) -> Result<(), WindowError> {
        let sigma = self.noise.start();
        let ok = (1..=WINDOW as u16).contains(&self.window)
            && self.max_age_ms > 0
            && sigma.is_finite()
            && (MIN_SIGMA..=45.0 * DEG).contains(&sigma)
            && self.max_sigma.is_finite()
            && self.max_sigma > 0.0;
        if ok {
            Ok(())
        } else {
            Err(WindowError::Setting)
        }
    }
}

/// Why a bearing or a setting was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum WindowError {
    /// A non-finite value or a non-positive sigma.
    BadBearing,
    /// A setting out of range.
    Setting,
}

impl core::fmt::Display for WindowError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            Self::BadBearing => "bearing not finite or without a positive sigma",
            Self::Setting => "tracker setting out of range",
        })
    }
}
