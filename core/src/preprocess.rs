//! DF quality gating and weighting (seed 002 section 3.2, eqs. 19-21).
//!
//! A DF unit takes several bearings at each observation point and rates each with a quality Q
//! in 0..100. The seed keeps only Q > 40, then pulls each bearing toward the running mean of its
//! point by an error weight W(Q) (eq. 20: the worse the bearing, the larger W), and reports the
//! running mean of the corrected bearings (eq. 21) as the point's bearing.
//!
//! Eq. 20 reached us garbled: as printed, W rises with Q inside each band and jumps between
//! bands. The reconstruction here (chosen) keeps the printed band values but makes W fall with
//! quality inside each band, so W is non-increasing in Q overall:
//! W = (100 - Q)/150 for Q >= 85; (85 - Q)/375 + 1/8 for 70 <= Q < 85;
//! (70 - Q)/600 + 1/4 below 70 (the last band extended down to the gate).
//! Bearings are averaged as angles: offsets from the point's first bearing, wrapped, so a
//! point straddling north averages to north, not south.

use crate::error::Error;
use crate::model::bearing::wrap;

/// Default gate: the seed keeps bearings with Q > 40.
pub const DEFAULT_MIN_QUALITY: f32 = 40.0;

/// The seed's error weight W(Q) (eq. 20, reconstructed; see the module docs). Q is clamped to
/// [0, 100]; a non-finite Q gets the largest weight.
pub fn error_weight(quality: f32) -> f32 {
    let q = if quality.is_finite() {
        quality.clamp(0.0, 100.0)
    } else {
        0.0
    };
    if q >= 85.0 {
        (100.0 - q) / 150.0
    } else if q >= 70.0 {
        (85.0 - q) / 375.0 + 0.125
    } else {
        (70.0 - q) / 600.0 + 0.25
    }
}

/// The bearings of one observation point, gated, corrected and averaged.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObservationPoint {
    /// Bearings with quality at or below this are rejected.
    pub min_quality: f32,
    count: u32,
    rejected: u32,
    reference: f32,
    raw_mean: f32,
    corrected_mean: f32,
}

impl Default for ObservationPoint {
    fn default() -> Self {
        Self::new(DEFAULT_MIN_QUALITY)
    }
}

impl ObservationPoint {
    /// An empty point with the given quality gate.
    pub const fn new(min_quality: f32) -> Self {
        Self {
            min_quality,
            count: 0,
            rejected: 0,
            reference: 0.0,
            raw_mean: 0.0,
            corrected_mean: 0.0,
        }
    }

    /// Add a bearing (radians, any angle convention) of quality `quality` (0..100). Rejected
    /// bearings are counted and leave the mean unchanged.
    pub fn push(&mut self, angle: f32, quality: f32) -> Result<(), Error> {
        let checked = if !angle.is_finite() || !quality.is_finite() {
            Err(Error::NonFinite)
        } else if !(0.0..=100.0).contains(&quality) {
            Err(Error::OutOfRange)
        } else if quality <= self.min_quality {
            Err(Error::LowQuality)
        } else {
            Ok(())
        };
        if let Err(e) = checked {
            self.rejected = self.rejected.saturating_add(1);
            return Err(e);
        }
        if self.count == 0 {
            self.reference = wrap(angle);
        }
        self.count += 1;
        let n = self.count as f32;
        let offset = wrap(angle - self.reference);
        // Eq. 19: running mean of the raw bearings.
        self.raw_mean = ((n - 1.0) * self.raw_mean + offset) / n;
        // Eq. 20 correction toward the mean, then eq. 21: running mean of the corrected ones.
        let corrected = offset - (offset - self.raw_mean) * error_weight(quality);
        self.corrected_mean = ((n - 1.0) * self.corrected_mean + corrected) / n;
        Ok(())
    }

    /// The point's bearing (radians, wrapped to (-pi, pi]), or `None` if nothing passed the gate.
    pub fn bearing(&self) -> Option<f32> {
        (self.count > 0).then(|| wrap(self.reference + self.corrected_mean))
    }

    /// Bearings accepted so far.
    pub fn accepted(&self) -> u32 {
        self.count
    }

    /// Bearings rejected so far (low quality, out of range, non-finite).
    pub fn rejected(&self) -> u32 {
        self.rejected
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::PI;

    #[test]
    fn weight_falls_with_quality() {
        let mut last = f32::INFINITY;
        for q in 41..=100 {
            let w = error_weight(q as f32);
            assert!(w <= last + 1e-7, "W({q}) = {w} rises");
            assert!((0.0..=0.3).contains(&w));
            last = w;
        }
        assert_eq!(error_weight(100.0), 0.0);
        assert!((error_weight(85.0) - 0.1).abs() < 1e-6);
    }

    #[test]
    fn gate_counts_and_keeps_good_bearings() {
        let mut p = ObservationPoint::default();
        assert_eq!(p.push(1.0, 30.0), Err(Error::LowQuality));
        assert_eq!(p.push(f32::NAN, 90.0), Err(Error::NonFinite));
        assert_eq!(p.push(1.0, 120.0), Err(Error::OutOfRange));
        assert_eq!(p.bearing(), None);
        p.push(1.0, 90.0).unwrap();
        p.push(1.02, 60.0).unwrap();
        let b = p.bearing().unwrap();
        assert!(b > 1.0 && b < 1.01 + 1e-4, "{b}");
        assert_eq!((p.accepted(), p.rejected()), (2, 3));
    }

    #[test]
    fn averages_across_the_cut() {
        let mut p = ObservationPoint::default();
        p.push(PI - 0.01, 90.0).unwrap();
        p.push(-PI + 0.01, 90.0).unwrap();
        let b = p.bearing().unwrap();
        assert!(libm::fabsf(wrap(b - PI)) < 1e-3, "{b}");
    }
}
