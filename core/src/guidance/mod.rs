//! Where to drive next to learn the most about the emitter, and when to stop.
//!
//! No DF tool tells the driver this; the KrakenSDR app only homes along the averaged bearing.
//! Here (docs/src/guidance.md):
//! - [`belief`]: the bias-aware Fisher information of the bearings so far, over [x, y, offset],
//!   at a hypothesised emitter position, and the bearing a candidate position would add
//!   (a rank-one update); several hypotheses where the posterior is wide.
//! - [`plan`]: greedy D- and A-optimal scores of candidate moves, and a look-ahead over
//!   sequences of moves within a horizon; free headings in open terrain, any other
//!   [`plan::Reach`] (a road graph) on the host.
//! - [`stop`]: the stop rule (predicted CEP50 below a target, consistent residuals, enough
//!   independent bearings) and, when it does not hold, what is missing and what limits the fix:
//!   "widen the angle", "get closer", "drive a calibration leg".
//!
//! ```
//! use foxhunt_core::fix::bias::BiasPrior;
//! use foxhunt_core::guidance::belief::{Belief, Hypotheses, beliefs, MAX_POINTS};
//! use foxhunt_core::guidance::plan::{plan, Cost, FreeHeadings, Objective, PlanOptions, Pose};
//! use foxhunt_core::model::bearing::{Bearing, predicted};
//!
//! // Twenty bearings from 300 m of road east, of an emitter about 3 km north.
//! let e = [0.0f32, 3000.0];
//! let sigma = 4.0f32.to_radians();
//! let bs: [Bearing; 20] = core::array::from_fn(|k| {
//!     let v = [15.0 * k as f32, 0.0];
//!     Bearing { vehicle: v, theta: predicted(&e, &v), sigma }
//! });
//! let h = Hypotheses::at(e);
//! let mut b = [Belief::from_bearings(e, &bs, BiasPrior::default(), 2e4)?; MAX_POINTS];
//! let n = beliefs(&h, &bs, BiasPrior::default(), 2e4, &mut b);
//! let options = PlanOptions {
//!     objective: Objective::Goal { target_m: 100.0, cost: Cost::Time },
//!     depth: 3,
//!     horizon_s: 60.0,
//!     rate_hz: 1.0,
//!     sigma,
//!     sample_m: 100.0,
//! };
//! let pose = Pose { position: [285.0, 0.0], heading: 0.0 };
//! let next = plan(&b[..n], pose, &FreeHeadings::default(), options)?;
//! // Not away from the emitter.
//! assert!(next.leg.heading().sin() > -0.1);
//! # Ok::<(), foxhunt_core::Error>(())
//! ```

pub mod belief;
pub mod plan;
pub mod stop;
