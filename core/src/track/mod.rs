//! Tracking an emitter that moves: a drone's controller, a vehicle, a tagged animal, a person
//! with a tag indoors (docs/src/tracking.md).
//!
//! The state is the emitter's position and velocity, the motion mode (still or moving) and the
//! static parameters of the sensors: each DF source's bearing offset and, for RSSI, a power
//! offset and a path-loss exponent correction shared by every anchor. Components, in order
//! ([`Layout`]):
//!
//! | index | component |
//! |---|---|
//! | 0, 1 | position east, north (metres) |
//! | 2, 3 | velocity east, north (m/s) |
//! | 4 | motion mode: 0 still, 1 moving (a particle's mode; a filter's mean is P(moving)) |
//! | 5 .. 5 + S | the offset of DF source 0 .. S - 1 (radians, added to the true bearing) |
//! | 5 + S, 6 + S | RSSI: power offset (dB) and path-loss exponent correction (if used) |
//!
//! The motion ([`Motion`]) is a jump-Markov pair of models: still (position fixed, velocity
//! zero) and nearly constant velocity (white-noise acceleration with a stated sd), switching
//! at stated rates; a particle carries its mode, so the weighted share of moving particles is
//! the probability that the emitter moves. The measurements of one update time are an
//! [`Epoch`]: bearings ([`Observation`](crate::fix::observation::Observation)s, each naming its
//! source) and RSSI readings ([`Level`]s, each with its anchor's path loss), from fixed or
//! moving stations alike. [`Mover`] is the [`Model`](crate::Model) every particle filter of the
//! registry runs on ([`crate::estimator::with_moving_filter`]); [`imm::ImmEkf`] is the Kalman
//! baseline (an interacting multiple model of two EKFs); [`smooth::FixedLag`] sharpens a
//! recorded track; [`bound`] gives the posterior Cramér-Rao bound.

pub mod bound;
pub mod epoch;
pub mod imm;
pub mod init;
pub mod motion;
pub mod mover;
pub mod smooth;

pub use epoch::{Epoch, Level};
pub use motion::Motion;
pub use mover::{Forgetting, Layout, Mover};

/// Index of the east position.
pub const EAST: usize = 0;
/// Index of the north position.
pub const NORTH: usize = 1;
/// Index of the east velocity.
pub const VEL_EAST: usize = 2;
/// Index of the north velocity.
pub const VEL_NORTH: usize = 3;
/// Index of the motion mode (0 still, 1 moving).
pub const MODE: usize = 4;
/// Index of the first static parameter (source 0's offset).
pub const PARAMETERS: usize = 5;

/// The position block of a state's covariance: what an ellipse is drawn from.
pub fn position_covariance<const D: usize>(cov: &[[f32; D]; D]) -> [[f32; 2]; 2] {
    [[cov[0][0], cov[0][1]], [cov[1][0], cov[1][1]]]
}
