//! Evidence counted once: repeated bearings, a capture concatenated or replayed, one unit
//! logged twice, time going backwards.
//!
//! A repeated sentence, a capture appended to itself or a replay of part of a drive carries no
//! new information, yet a fix that counts it twice shrinks its ellipse by sqrt(2). A bearing
//! is [`Verdict::Repeated`] when it repeats an earlier one exactly (same time, channel,
//! vehicle position and angle, whatever station it is filed under: one log given twice as two
//! inputs files its unnamed unit under two names, and no two real stations report the same
//! angle to the bit from the same spot at the same time), or, for a station that stamps its own bearings
//! ([`Observation::stamped`]), when the same station already sent a bearing at that time on
//! that channel: the same record arriving by two paths (a KrakenSDR's CSV log and its XML, a
//! poll and a log), whose angles and positions differ only in their rounding. A new bearing
//! older than one the same station already sent on its channel is [`Verdict::Backwards`] (a replay with its
//! times intact, or a clock that jumped): it cannot be placed in the drive's order, and the
//! correlation estimate needs that order. Both are counted and never used; the first
//! occurrence is kept. Three sorts, O(n log n), no table per station.

use super::observation::Observation;
use super::order::quicksort_by;
use crate::error::Error;

/// What one observation is worth (as a tag byte in the working storage: `Verdict as u8`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum Verdict {
    /// New evidence.
    #[default]
    Fresh = 0,
    /// An earlier observation again.
    Repeated = 1,
    /// New, but older than what its station already sent on its channel.
    Backwards = 2,
}

/// How many observations were set aside, by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EvidenceCounts {
    /// Earlier observations again (exact repeats, or a stamped bearing by a second path).
    pub repeated: u32,
    /// Observations older than their station's latest on their channel.
    pub backwards: u32,
}

/// The channel of a frequency to the kHz (two logs of one record round it differently).
fn channel_key(f: Option<f32>) -> i32 {
    match f {
        Some(f) => crate::fastmath::round_half_away(f * 1000.0),
        None => i32::MIN,
    }
}

/// What identifies a stamped bearing: station, time and channel.
fn stamp(o: &Observation) -> (u16, u32, i32) {
    (o.station, o.time_s.to_bits(), channel_key(o.freq_mhz))
}

/// The identity of an observation: two are the same evidence when all of these agree (the
/// station not among them: see the module's words).
fn key(o: &Observation) -> ((u32, i32), u32, u32, u32) {
    (
        (o.time_s.to_bits(), channel_key(o.freq_mhz)),
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
    let tags = &mut tags[..n];
    let mut counts = EvidenceCounts::default();
    for t in tags.iter_mut() {
        *t = Verdict::Fresh as u8;
    }
    let mut repeated = |tags: &mut [u8], i: u32| {
        if let Some(t) = tags.get_mut(i as usize)
            && *t == Verdict::Fresh as u8
        {
            *t = Verdict::Repeated as u8;
            counts.repeated += 1;
        }
    };
    // Exact repeats: identical keys side by side, in input order.
    let reset = |order: &mut [u32]| {
        for (i, slot) in order.iter_mut().enumerate() {
            *slot = i as u32;
        }
    };
    reset(order);
    let key_of = |i: u32| obs(i as usize).map(|o| key(&o));
    quicksort_by(order, |a, b| (key_of(*a), *a).cmp(&(key_of(*b), *b)));
    for w in order.windows(2) {
        if key_of(w[0]) == key_of(w[1]) {
            repeated(tags, w[1]);
        }
    }
    // A stamped bearing by a second path: the same station, time and channel, in input order.
    reset(order);
    let stamp_of = |i: u32| obs(i as usize).filter(|o| o.stamped).map(|o| stamp(&o));
    quicksort_by(order, |a, b| (stamp_of(*a), *a).cmp(&(stamp_of(*b), *b)));
    for w in order.windows(2) {
        if stamp_of(w[0]).is_some() && stamp_of(w[0]) == stamp_of(w[1]) {
            repeated(tags, w[1]);
        }
    }
    // Time order per station and channel among the fresh ones: each stream in input order.
    reset(order);
    let stream_of = |o: &Observation| (o.station, channel_key(o.freq_mhz));
    let stream = |i: u32| obs(i as usize).map(|o| stream_of(&o));
    quicksort_by(order, |a, b| (stream(*a), *a).cmp(&(stream(*b), *b)));
    let mut latest: Option<((u16, i32), f32)> = None;
    for &i in order.iter() {
        let Some(o) = obs(i as usize) else { continue };
        if tags.get(i as usize) != Some(&(Verdict::Fresh as u8)) {
            continue;
        }
        match latest {
            Some((s, t)) if s == stream_of(&o) && o.time_s < t => {
                if let Some(t) = tags.get_mut(i as usize) {
                    *t = Verdict::Backwards as u8;
                    counts.backwards += 1;
                }
            }
            _ => latest = Some((stream_of(&o), o.time_s)),
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
            station: 0,
            stamped: true,
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
        // Another station keeps its own clock, and equal times of a unit that does not stamp
        // its bearings (an Agrelo's take the GPS second) are neither backwards nor repeats.
        drive[6].station = 1;
        drive[4].stamped = false;
        drive[5].stamped = false;
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

    #[test]
    fn one_unit_logged_twice_counts_once() {
        // The CSV log, then the XML log of the same records: angles rounded to 0.01 degree
        // against whole degrees, positions to a few centimetres, frequencies in Hz against MHz.
        let csv: [Observation; 10] = core::array::from_fn(|k| {
            let mut o = obs(k);
            o.freq_mhz = Some(433_920_000.0 / 1e6);
            o
        });
        let mut both = [csv[0]; 30];
        both[..10].copy_from_slice(&csv);
        for k in 0..10 {
            let mut x = csv[k];
            x.bearing.theta += 1e-4;
            x.bearing.vehicle[0] += 0.03;
            x.freq_mhz = Some(433.9201);
            both[10 + k] = x;
            // A second channel at the same times is other evidence.
            let mut y = csv[k];
            y.freq_mhz = Some(433.945);
            both[20 + k] = y;
        }
        let mut order = [0u32; 30];
        let mut v = [0u8; 30];
        let c = sort_out(30, |i| both.get(i).copied(), &mut order, &mut v).unwrap();
        assert_eq!(
            c,
            EvidenceCounts {
                repeated: 10,
                backwards: 0
            }
        );
        assert!(v[10..20].iter().all(|v| *v == Verdict::Repeated as u8));
        assert!(v[20..].iter().all(|v| *v == Verdict::Fresh as u8));
    }

    #[test]
    fn one_log_filed_under_two_stations_counts_once() {
        // The same capture given twice: its unnamed unit is a station per input. A second unit
        // on the vehicle at the same times (same spot, its own angles) is other evidence.
        let mut both = [obs(0); 30];
        for k in 0..10 {
            both[k] = obs(k);
            let mut again = obs(k);
            again.station = 1;
            both[10 + k] = again;
            let mut other = obs(k);
            other.station = 2;
            other.bearing.theta += 0.02;
            both[20 + k] = other;
        }
        let mut order = [0u32; 30];
        let mut v = [0u8; 30];
        let c = sort_out(30, |i| both.get(i).copied(), &mut order, &mut v).unwrap();
        assert_eq!(c.repeated, 10);
        assert!(v[10..20].iter().all(|v| *v == Verdict::Repeated as u8));
        assert!(
            v[..10]
                .iter()
                .chain(&v[20..])
                .all(|v| *v == Verdict::Fresh as u8)
        );
    }
}
