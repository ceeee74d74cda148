//! foxhunt-core: find a radio emitter from bearings (or RSSI) with particle filters, an EKF and
//! batch fixes, each measured against the Cramér-Rao bound.
//!
//! Everything here runs without an allocator: particle arrays are sized by const generics, so a
//! filter can live in a `static` on a microcontroller. Randomness comes only from a
//! caller-supplied [`rand_core::Rng`], so one seed gives the same answer on the host and the MCU.
//! No entry point panics on any input. The entry points that return a `Result` never return NaN
//! either: bad input gives an [`Error`] instead. Plain numeric helpers (a likelihood's `ln`, a
//! `wrap` of an angle) pass non-finite input through; their callers check first.
//!
//! Every estimator has one name in [`estimator`] (the registry that builds it); batch fixes
//! live in [`fix`], the recursive filters in [`filter`], the bounds beside them.
//!
//! ```
//! use foxhunt_core::fix::{crlb::crlb, ellipse::Ellipse, ml::{MlOptions, ml}};
//! use foxhunt_core::model::bearing::{Bearing, predicted};
//! use foxhunt_core::Gaussian;
//!
//! // A vehicle drives east then north past an emitter 1.2 km east, 800 m north; its DF unit
//! // reports each bearing 1 degree off, alternately left and right.
//! let emitter = [1200.0f32, 800.0];
//! let sigma = 1.0f32.to_radians();
//! let bearings: Vec<Bearing> = (0..60)
//!     .map(|k| {
//!         let v = if k < 30 { [10.0 * k as f32, 0.0] } else { [290.0, 10.0 * (k - 29) as f32] };
//!         let noise = if k % 2 == 0 { sigma } else { -sigma };
//!         Bearing { vehicle: v, theta: predicted(&emitter, &v) + noise, sigma }
//!     })
//!     .collect();
//! let fix = ml(&bearings, None, &Gaussian, MlOptions::default())?;
//! let bound = crlb(&fix.position, &bearings)?;
//! let ellipse = Ellipse::from_covariance(&fix.covariance, 0.95)?;
//! assert!(ellipse.contains(&fix.position, &emitter));
//! assert!(bound.rmse > 10.0 && bound.rmse < 200.0);
//! # Ok::<(), foxhunt_core::Error>(())
//! ```
#![no_std]
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod error;
pub mod fastmath;
pub mod linalg;
pub mod particles;
pub mod random;
pub mod resample;
pub mod stats;

pub use error::Error;
pub use particles::ParticleSet;
pub use resample::{ResamplePolicy, Resampling};
pub mod likelihood;
pub mod model;

pub use likelihood::{
    Cauchy, Gaussian, GaussianUniform, Huber, Likelihood, StudentT, Tukey, Widened,
};
pub use model::Model;
pub use model::bearing::{Bearing, StaticEmitter};
pub use model::biased::BiasedEmitter;
pub use model::rssi::{PathLoss, RssiMeasurement, RssiTracker};
pub use model::ungm::{Ungm, UngmObservation};
pub mod fix;
pub mod guidance;

pub use fix::Fix;
pub mod filter;
pub mod roughen;

pub use estimator::{Method, PARTICLE_COUNTS, WithFilter};
pub use filter::ekf::{BearingEkf, BiasedBearingEkf};
pub use filter::gpf::Gpf;
pub use filter::sir::{Sir, SirConfig};
pub use filter::{Estimate, Filter, StepStatus};
pub use roughen::Roughening;
pub mod canonical;
pub mod estimator;
pub mod preprocess;
pub mod swarm;
pub mod track;

pub use swarm::afsa::Afsa;
pub use swarm::firefly::{Firefly, FireflyParams, ImprovedFirefly};
pub use swarm::gsa::Gsa;
pub use swarm::pso::Pso;
pub use swarm::{NoSwarm, Swarm};
