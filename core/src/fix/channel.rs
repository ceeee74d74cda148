//! Bearings grouped into channels by frequency: one emitter per channel.
//!
//! A KrakenSDR reports up to 16 channels (VFOs), each with its frequency; pairing bearings of
//! different frequencies makes phantom fixes between two transmitters (docs/src/field.md, "Several emitters"). Frequencies
//! are sorted and swept: a channel holds every frequency within `width` of its lowest, the next
//! frequency beyond starts a new channel. Bearings without a frequency form one channel of
//! their own, listed first. [`belongs`] is that rule for one frequency and one channel, for
//! whoever needs to pick a channel's bearings out again.

use super::order::quicksort_by;
use crate::error::{Error, check_finite};

/// Marks an item that belongs to no channel (excluded, or beyond the capacity).
pub const NO_CHANNEL: u8 = u8::MAX;

/// Whether a bearing at `freq` (MHz; `None`: without a frequency) belongs to the channel whose
/// lowest frequency is `lowest` (`None`: the channel of the bearings without one) and whose
/// width is `width` (MHz): from its lowest frequency to `width` above it, both ends included.
/// It is the rule [`group`] assigns by: every bearing [`group`] put in a channel belongs to it
/// and to no other. A negative or NaN width holds nothing.
pub fn belongs(freq: Option<f32>, lowest: Option<f32>, width: f32) -> bool {
    match (freq, lowest) {
        (Some(f), Some(l)) => f >= l && f - l <= width,
        (None, None) => true,
        _ => false,
    }
}

/// The channels of a set of bearings, at most `C` of them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Channels<const C: usize> {
    len: usize,
    /// Mean frequency of each channel, MHz (`None` for the channel without frequency).
    freq: [Option<f32>; C],
    /// Lowest frequency of each channel, MHz (`None` for the channel without frequency).
    lowest: [Option<f32>; C],
    /// Items in each channel.
    count: [u32; C],
    /// Items whose channel did not fit in `C`.
    pub overflow: u32,
}

impl<const C: usize> Channels<C> {
    /// Number of channels.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there is no channel.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Mean frequency of channel `c` (MHz; `Some(None)` for the channel without frequency).
    pub fn freq(&self, c: usize) -> Option<Option<f32>> {
        self.freq.get(..self.len)?.get(c).copied()
    }

    /// Lowest frequency of channel `c`, where it starts (MHz; `Some(None)` for the channel
    /// without frequency): what [`belongs`] takes.
    pub fn lowest(&self, c: usize) -> Option<Option<f32>> {
        self.lowest.get(..self.len)?.get(c).copied()
    }

    /// Items in channel `c`.
    pub fn count(&self, c: usize) -> u32 {
        self.count
            .get(..self.len)
            .and_then(|v| v.get(c))
            .copied()
            .unwrap_or(0)
    }
}

/// Group items into channels. `freq(i)` is item i's frequency: `Some(Some(f))` in MHz,
/// `Some(None)` without one, `None` for an item to leave out. `channel_of[i]` gets the channel
/// index (or [`NO_CHANNEL`]); `order` (at least `n` long) is sorting space. Non-finite or
/// negative frequencies are refused before anything is written. O(n log n).
pub fn group<const C: usize>(
    n: usize,
    freq: impl Fn(usize) -> Option<Option<f32>>,
    width: f32,
    order: &mut [u32],
    channel_of: &mut [u8],
) -> Result<Channels<C>, Error> {
    check_finite(&[width])?;
    if !(width >= 0.0) || order.len() < n || channel_of.len() < n || C > NO_CHANNEL as usize {
        return Err(Error::OutOfRange);
    }
    for i in 0..n {
        if let Some(Some(f)) = freq(i) {
            check_finite(&[f])?;
            if f < 0.0 {
                return Err(Error::OutOfRange);
            }
        }
    }
    let mut out = Channels {
        len: 0,
        freq: [None; C],
        lowest: [None; C],
        count: [0; C],
        overflow: 0,
    };
    // Each channel's mean as its lowest frequency plus the mean offset from it: the offsets
    // are exact (within the width, Sterbenz) and small, and summed with Kahan's compensation,
    // so 20 000 bearings at 433.920 MHz average to 433.920, where a running f32 sum of the
    // frequencies themselves drifted 56 kHz, beyond the channel (the MCU has no f64).
    let mut sums = [0.0f32; C];
    let mut carries = [0.0f32; C];
    let mut k = 0usize;
    let mut untuned = false;
    for i in 0..n {
        channel_of[i] = NO_CHANNEL;
        match freq(i) {
            Some(Some(_)) => {
                order[k] = i as u32;
                k += 1;
            }
            Some(None) => untuned = true,
            None => {}
        }
    }
    // The channel without frequency first.
    if untuned {
        if C == 0 {
            for i in 0..n {
                out.overflow += matches!(freq(i), Some(None)) as u32;
            }
        } else {
            out.len = 1;
            for i in 0..n {
                if matches!(freq(i), Some(None)) {
                    channel_of[i] = 0;
                    out.count[0] += 1;
                }
            }
        }
    }
    let f_of = |i: u32| freq(i as usize).flatten().unwrap_or(0.0);
    quicksort_by(&mut order[..k], |a, b| {
        f_of(*a).total_cmp(&f_of(*b)).then(a.cmp(b))
    });
    let mut lowest = f32::NEG_INFINITY;
    let mut current: Option<usize> = None;
    for &i in &order[..k] {
        let f = f_of(i);
        // Sorted: f is at least `lowest`, and beyond the width it starts the next channel.
        if current.is_none() || !belongs(Some(f), Some(lowest), width) {
            lowest = f;
            current = (out.len < C).then_some(out.len);
            if let Some(c) = current {
                out.lowest[c] = Some(f);
                out.len += 1;
            }
        }
        match current {
            Some(c) => {
                channel_of[i as usize] = c as u8;
                out.count[c] += 1;
                if let (Some(sum), Some(carry)) = (sums.get_mut(c), carries.get_mut(c)) {
                    kahan_add(sum, carry, f - lowest);
                }
            }
            None => out.overflow += 1,
        }
    }
    for c in 0..out.len {
        if out.freq[c].is_none()
            && !(untuned && c == 0)
            && out.count[c] > 0
            && let Some(lowest) = out.lowest[c]
        {
            out.freq[c] = Some(lowest + sums[c] / out.count[c] as f32);
        }
    }
    Ok(out)
}

/// `sum += x` with Kahan's compensation: `carry` keeps what the last additions lost.
fn kahan_add(sum: &mut f32, carry: &mut f32, x: f32) {
    let y = x - *carry;
    let t = *sum + y;
    *carry = (t - *sum) - y;
    *sum = t;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frequencies_within_the_width_share_a_channel() {
        let f = [
            Some(Some(146.52)),
            Some(None),
            Some(Some(145.000)),
            Some(Some(146.5205)),
            None,
            Some(Some(145.010)),
            Some(None),
        ];
        let mut order = [0u32; 7];
        let mut of = [0u8; 7];
        let ch = group::<4>(7, |i| f[i], 0.025, &mut order, &mut of).unwrap();
        assert_eq!(ch.len(), 3);
        assert_eq!(of, [2, 0, 1, 2, NO_CHANNEL, 1, 0]);
        assert_eq!(ch.freq(0), Some(None));
        assert!((ch.freq(1).flatten().unwrap() - 145.005).abs() < 1e-3);
        assert_eq!((ch.count(0), ch.count(1), ch.count(2)), (2, 2, 2));
    }

    #[test]
    fn a_channel_holds_from_its_lowest_to_the_width_above_and_belongs_says_so() {
        // Sorted 100, 100.5 | 100.75, 101.25 at width 0.5: 100.75 is within the width of the
        // first channel's mean (100.25) but beyond its lowest, so it starts the second.
        let f = [
            Some(Some(101.25)),
            Some(Some(100.0)),
            Some(None),
            Some(Some(100.75)),
            Some(Some(100.5)),
        ];
        let mut order = [0u32; 5];
        let mut of = [0u8; 5];
        let ch = group::<4>(5, |i| f[i], 0.5, &mut order, &mut of).unwrap();
        assert_eq!(of, [2, 1, 0, 2, 1]);
        assert_eq!(
            (ch.lowest(0), ch.lowest(1), ch.lowest(2), ch.lowest(3)),
            (Some(None), Some(Some(100.0)), Some(Some(100.75)), None)
        );
        for (i, fi) in f.iter().enumerate() {
            for c in 0..ch.len() {
                let lowest = ch.lowest(c).unwrap();
                assert_eq!(
                    belongs(fi.unwrap(), lowest, 0.5),
                    of[i] as usize == c,
                    "{i} {c}"
                );
            }
        }
        // Both ends included; below the lowest, or a frequency against the untuned channel, not.
        assert!(belongs(Some(100.5), Some(100.0), 0.5));
        assert!(!belongs(Some(99.75), Some(100.0), 0.5));
        assert!(!belongs(Some(100.0), None, 0.5) && !belongs(None, Some(100.0), 0.5));
        // Width 0: equal frequencies only; a width no channel could have holds nothing.
        assert!(belongs(Some(100.0), Some(100.0), 0.0));
        assert!(!belongs(Some(100.5), Some(100.0), 0.0));
        assert!(!belongs(Some(100.0), Some(100.0), f32::NAN));
    }

    #[test]
    fn many_bearings_at_one_frequency_average_to_it() {
        // A single-precision running sum of 20 000 frequencies of 433.92 MHz drifted to
        // 433.9759, 56 kHz off and beyond the channel's 50 kHz.
        const N: usize = 20_000;
        let mut order = [0u32; N];
        let mut of = [0u8; N];
        let ch = group::<2>(N, |_| Some(Some(433.92)), 0.05, &mut order, &mut of).unwrap();
        assert_eq!(ch.freq(0), Some(Some(433.92f32)));
        // Two frequencies 20 kHz apart, alternating: their mean to one f32 step at 433 MHz
        // (30 Hz).
        let f = |i: usize| {
            Some(Some(if i.is_multiple_of(2) {
                433.91f32
            } else {
                433.93
            }))
        };
        let ch = group::<2>(N, f, 0.05, &mut order, &mut of).unwrap();
        let mean = ch.freq(0).flatten().unwrap();
        assert!((mean - 433.92).abs() <= 3.1e-5, "{mean}");
    }

    #[test]
    fn channels_beyond_the_capacity_are_counted() {
        let f = [
            Some(Some(1.0)),
            Some(Some(2.0)),
            Some(Some(3.0)),
            Some(Some(3.0)),
        ];
        let mut order = [0u32; 4];
        let mut of = [0u8; 4];
        let ch = group::<2>(4, |i| f[i], 0.1, &mut order, &mut of).unwrap();
        assert_eq!((ch.len(), ch.overflow), (2, 2));
        assert_eq!(of, [0, 1, NO_CHANNEL, NO_CHANNEL]);
        let bad = [Some(Some(f32::NAN))];
        assert_eq!(
            group::<2>(1, |i| bad[i], 0.1, &mut order, &mut of),
            Err(Error::NonFinite)
        );
    }
}
