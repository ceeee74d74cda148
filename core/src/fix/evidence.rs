//! Evidence counted once: repeated bearings, a capture concatenated or replayed, time going
//! backwards.
//!
//! A repeated sentence, a capture appended to itself or a replay of part of a drive carries no
//! new information, yet a fix that counts it twice shrinks its ellipse by sqrt(2). A bearing
//! that repeats an earlier one exactly (same source, time, vehicle position and angle) is
//! [`Verdict::Repeated`]; one that is new but older than a bearing the same source already
//! sent is [`Verdict::Backwards`] (a replay with its times intact, or a clock that jumped): it
//! cannot be placed in the drive's order, and the correlation estimate needs that order. Both
//! are counted and never used; the first occurrence is kept.

use super::observation::Observation;
use super::order::heapsort_by;
use crate::error::Error;

/// What one observation is worth (as a tag byte in the working storage: `Verdict as u8`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum Verdict {
    /// New evidence.
    #[default]
    Fresh = 0,
    /// An exact repeat of an earlier observation.
    Repeated = 1,
    /// New, but older than what its source already sent.
    Backwards = 2,
}

/// How many observations were set aside, by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EvidenceCounts {
    /// Exact repeats of earlier observations.
    pub repeated: u32,
    /// Observations older than their source's latest.
    pub backwards: u32,
}

/// The identity of an observation: two are the same evidence when all of these agree.
fn key(o: &Observation) -> (u8, u32, u32, u32, u32) {
    (
        o.source,
        o.time_s.to_bits(),
        o.bearing.theta.to_bits(),
        o.bearing.vehicle[0].to_bits(),
        o.bearing.vehicle[1].to_bits(),
    )
}

/// Judge `n` observations (`obs(i)` is the i-th) into `tags` (`Verdict as u8`, at least `n`
/// long), using `order` (at least `n` long) as sorting space. O(n log n). Observations are
/// judged in input order: the first of identical ones is the fresh one.
pub fn sort_out(
    n: usize,
    obs: impl Fn(usize) -> Option<Observation>,
    order: &mut [u32],
    tags: &mut [u8],
) -> Result<EvidenceCounts, Error> {
    if order.len() < n || tags.len() < n || n > u32::MAX as usize {
        return Err(Error::OutOfRange);
    }
    let order = &mut order[..n];
    for (i, slot) in order.iter_mut().enumerate() {
        *slot = i as u32;
    }
    let key_of = |i: u32| obs(i as usize).map(|o| key(&o));
    heapsort_by(order, |a, b| (key_of(*a), *a) < (key_of(*b), *b));
    let mut counts = EvidenceCounts::default();
    for t in tags.iter_mut().take(n) {
        *t = Verdict::Fresh as u8;
    }
    for w in order.windows(2) {
        if key_of(w[0]) == key_of(w[1])
            && let Some(t) = tags.get_mut(w[1] as usize)
        {
            *t = Verdict::Repeated as u8;
            counts.repeated += 1;
        }
    }
    // Time order per source, among the fresh ones (sources index a small table).
    let mut latest = [f32::NEG_INFINITY; 256];
    for (i, t) in tags.iter_mut().enumerate().take(n) {
        let Some(o) = obs(i) else { continue };
        if *t != Verdict::Fresh as u8 {
            continue;
        }
        let Some(last) = latest.get_mut(o.source as usize) else {
            continue;
        };
        if o.time_s < *last {
            *t = Verdict::Backwards as u8;
            counts.backwards += 1;
        } else {
            *last = o.time_s;
        }
    }
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bearing::Bearing;

    fn obs(k: usize) -> Observation {
        Observation {
            bearing: Bearing {
                vehicle: [10.0 * k as f32, 0.0],
                theta: 0.01 * k as f32,
                sigma: 0.02,
            },
            time_s: k as f32,
            freq_mhz: None,
            source: 0,
        }
    }

    #[test]
    fn a_capture_concatenated_with_itself_counts_once() {
        let drive: [Observation; 40] = core::array::from_fn(|k| obs(k % 20));
        let mut order = [0u32; 40];
        let mut v = [0u8; 40];
        let c = sort_out(40, |i| drive.get(i).copied(), &mut order, &mut v).unwrap();
        assert_eq!(
            c,
            EvidenceCounts {
                repeated: 20,
                backwards: 0
            }
        );
        assert!(v[..20].iter().all(|v| *v == Verdict::Fresh as u8));
        assert!(v[20..].iter().all(|v| *v == Verdict::Repeated as u8));
    }

    #[test]
    fn repeated_sentences_and_time_going_backwards() {
        let mut drive: [Observation; 8] = core::array::from_fn(obs);
        drive[3] = drive[2]; // a repeated sentence
        drive[6].time_s = 1.5; // a bearing from the past, not a repeat
        let mut order = [0u32; 8];
        let mut v = [0u8; 8];
        let c = sort_out(8, |i| drive.get(i).copied(), &mut order, &mut v).unwrap();
        assert_eq!(
            c,
            EvidenceCounts {
                repeated: 1,
                backwards: 1
            }
        );
        assert_eq!(
            (v[3], v[6]),
            (Verdict::Repeated as u8, Verdict::Backwards as u8)
        );
        // Another source keeps its own clock, and equal times are not backwards.
        drive[6].source = 1;
        drive[5].time_s = drive[4].time_s;
        let c = sort_out(8, |i| drive.get(i).copied(), &mut order, &mut v).unwrap();
        assert_eq!(
            c,
            EvidenceCounts {
                repeated: 1,
                backwards: 0
            }
        );
        let short = sort_out(8, |i| drive.get(i).copied(), &mut order[..3], &mut v);
        assert_eq!(short, Err(Error::OutOfRange));
    }
}
