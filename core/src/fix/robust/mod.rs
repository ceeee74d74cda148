//! A fix that survives multipath: a global start that needs no prior, then a redescending
//! refinement on the bearings that agree with it.
//!
//! Scattered wild bearings are handled by any bounded-influence loss started from the PLE; a
//! consistent ghost (a stretch of the drive that sees a reflection) is not: the PLE lands
//! between the emitter and the ghost, and a loss that must pull it back has to tell, from that
//! start, which bearings are the wild ones (docs/src/field.md, "Multipath": Huber or Cauchy from the PLE, 100-114 m
//! median; RANSAC then ML on the inliers, 34-35 m). So:
//!
//! 1. [`ransac`]: intersections of random bearing pairs are hypotheses; each is scored by how
//!    many bearings of an evenly strided sample pass within the threshold of it, with the best
//!    common offset for that hypothesis (the densest window of its residuals, within the
//!    offset prior's range), so a mounting offset does not hide the emitter. Bounded work:
//!    `hypotheses` scored, `max_attempts` pairs drawn, a sample of at most [`SCORE_SAMPLE`].
//!    Deterministic given the generator.
//! 2. [`refine`]: Tukey's biweight from the best hypothesis, then trimmed ML: keep the bearings
//!    Tukey gave weight to, fit position and offsets by Gaussian ML on them alone, re-estimate
//!    the scale from their residuals (truncation-corrected), cut at [`trim_cut`] scale sigmas
//!    (3, or the Student-t quantile at 1 - 0.01 / n when that is wider: few bearings are not
//!    trimmed on a noisy scale estimate), repeat until the set settles (at most
//!    [`MAX_TRIM_ROUNDS`]). On clean data nothing is trimmed and the answer is the ML fix.
//!
//! [`chance`] says how likely so many bearings would line up on some point by luck (uniform
//! bearings, a search over the hypotheses and offsets tried): pure noise is not an emitter.

mod consensus;
#[cfg(test)]
mod tests;
mod trimmed;

pub use consensus::{Consensus, OffsetWindow, RansacOptions, chance, ransac};
pub use trimmed::{RefineOptions, RobustFix, refine, trim_cut};

/// How far from the drive an emitter is sought, metres (the default
/// [`RansacOptions::max_range`]): a crossing farther than this from the drive's centroid is no
/// hypothesis, the pipeline's far-side stretch of an ellipse is capped here, and a likelihood
/// region that runs out this far is no fix (the range is unobservable: [`super::reach`]). It is
/// a cut-off, not a prior, so it can be wide at no cost to the fixes within it; the filters'
/// initial cloud, which spends particles over its range, stops at half of it
/// ([`super::init::CLOUD_MAX_RANGE_M`]).
pub const MAX_RANGE_M: f32 = 100_000.0;
/// Bearings a hypothesis is scored on at most (an evenly strided sample).
pub const SCORE_SAMPLE: usize = 256;
/// Rounds of trimming at most.
pub const MAX_TRIM_ROUNDS: u32 = 12;
/// Trimmed ML keeps bearings within this many (scaled) sigmas at least...
pub const TRIM_CUT: f32 = 3.0;
/// ...or within the two-sided Student-t quantile at 1 - TRIM_ALPHA / n (n bearings, the
/// residual degrees of freedom): on few bearings a 3-sigma cut would drop good ones (a 2-sigma
/// residual of 9 bearings is not an outlier), on many it stays near 3.5 sigmas.
pub const TRIM_ALPHA: f32 = 0.01;
