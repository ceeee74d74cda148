//! The heading rule (see the bridge's module doc) and the yaw rate the turning gate reads:
//! the latest heading of each kind, the course over ground behind its speed gate, and the
//! vehicle's heading samples of the best fresh source (a record's own heading is its
//! station's: `stations.rs`).

use super::{Bridge, HeadingSource};

/// A heading and the clock time it arrived.
#[derive(Debug, Clone, Copy)]
pub(super) struct Stamped {
    pub(super) deg: f32,
    pub(super) time_ms: i64,
}

/// Heading samples kept for the yaw rate (16 bytes each), at most one per
/// [`TURN_SPACING_MS`]: 6.4 s or more, the fix span and a window.
pub const TURN_HISTORY: usize = 64;
/// Heading samples closer than this to the one before are skipped, ms.
pub const TURN_SPACING_MS: i64 = 100;

/// Degrees to (-180, 180].
fn wrap_half(x: f32) -> f32 {
    let mut a = x;
    for _ in 0..4 {
        if a > 180.0 {
            a -= 360.0;
        } else if a <= -180.0 {
            a += 360.0;
        }
    }
    a
}

/// Which heading sources the yaw rate prefers: the heading rule's order.
fn rank(s: HeadingSource) -> u8 {
    match s {
        HeadingSource::TrueBearing | HeadingSource::TrueHeading => 0,
        HeadingSource::Record => 1,
        HeadingSource::Magnetic => 2,
        HeadingSource::Course => 3,
    }
}

impl<const A: usize, const S: usize> Bridge<A, S> {
    pub(super) fn true_heading(&mut self, deg: f64) {
        self.counters.headings += 1;
        let time_ms = self.clock.unwrap_or(i64::MIN / 2);
        self.true_heading = Some(Stamped {
            deg: deg as f32,
            time_ms,
        });
        self.turn_sample(HeadingSource::TrueHeading, deg as f32, time_ms);
    }

    pub(super) fn magnetic_heading(&mut self, magnetic_deg: f64, true_deg: Option<f32>) {
        self.counters.headings += 1;
        let stamped = Stamped {
            deg: magnetic_deg as f32,
            time_ms: self.clock.unwrap_or(i64::MIN / 2),
        };
        self.magnetic = Some((stamped, true_deg));
        // The rate of a magnetic heading is the rate of the true one.
        self.turn_sample(HeadingSource::Magnetic, stamped.deg, stamped.time_ms);
    }

    /// A heading sample for the yaw rate. The samples hold one source at a time, the best
    /// the heading rule knows: a better source takes over at once, a lesser one only when the
    /// current one has gone stale (two sources differ by the crab angle, which is no turn).
    pub(super) fn turn_sample(&mut self, source: HeadingSource, deg: f32, time_ms: i64) {
        if self.clock.is_none() && source != HeadingSource::Record {
            return;
        }
        if let Some(last) = self.turns.last() {
            let age = i64::from(self.config.heading_max_age_ms);
            let fresh = (time_ms - last.time_ms).abs() <= age;
            if source != self.turn_source {
                if fresh && rank(source) > rank(self.turn_source) {
                    return;
                }
                self.turns.clear();
            } else if time_ms < last.time_ms {
                self.turns.clear();
            } else if time_ms - last.time_ms < TURN_SPACING_MS {
                return;
            }
        }
        self.turn_source = source;
        if self.turns.is_full() && !self.turns.is_empty() {
            self.turns.remove(0);
        }
        let _ = self.turns.push(Stamped { deg, time_ms });
    }

    /// The vehicle's yaw rate at `time_ms`, degrees per second, from the heading samples of
    /// its heading sensors and course (`yaw_rate`).
    pub fn yaw_rate_at(&self, time_ms: i64) -> Option<f32> {
        let age = i64::from(self.config.heading_max_age_ms);
        let window = i64::from(self.config.yaw_window_ms);
        yaw_rate(&self.turns, time_ms, age, window)
    }

    /// Speed and course at `time_ms`: the speed gate's state and the latest course.
    pub(super) fn motion(&mut self, time_ms: i64, speed_mps: Option<f32>, course_deg: Option<f32>) {
        if let Some(v) = speed_mps {
            if v >= self.config.course_min_speed_mps {
                self.fast_since.get_or_insert(time_ms);
            } else {
                self.fast_since = None;
            }
        }
        if let Some(deg) = course_deg {
            self.course = Some(Stamped { deg, time_ms });
            // Course over ground is a heading only while moving.
            if self.fast_since.is_some() {
                self.turn_sample(HeadingSource::Course, deg, time_ms);
            }
        }
    }

    /// The heading rule (see the module doc): the true heading of the vehicle at `time_ms`
    /// and its source, given the record's own heading.
    pub fn heading_at(&self, time_ms: i64, record: Option<f32>) -> Option<(f32, HeadingSource)> {
        let fresh =
            |s: &Stamped| (time_ms - s.time_ms).abs() <= i64::from(self.config.heading_max_age_ms);
        if let Some(h) = self.true_heading.filter(fresh) {
            return Some((h.deg, HeadingSource::TrueHeading));
        }
        if let Some(h) = record {
            return Some((h, HeadingSource::Record));
        }
        if let Some((m, own)) = self.magnetic.filter(|(m, _)| fresh(m)) {
            let t = own.or(self.config.declination_deg.map(|d| m.deg + d));
            if let Some(t) = t {
                return Some((t, HeadingSource::Magnetic));
            }
        }
        let gap = i64::from(self.config.max_fix_gap_ms);
        let held = self
            .fast_since
            .is_some_and(|s| time_ms - s >= i64::from(self.config.course_hold_ms));
        match self.course {
            Some(c) if held && (time_ms - c.time_ms).abs() <= gap => {
                Some((c.deg, HeadingSource::Course))
            }
            _ => None,
        }
    }
}

/// The yaw rate at `time_ms`, degrees per second, from heading `samples` (oldest first): the
/// heading's total change (summed sample to sample, so a fast spin is not aliased) from the
/// last sample at least `window_ms` (at least 1) before the first sample at or after
/// `time_ms` (the newest if none is yet) to that one. `None` when the samples do not tell:
/// none within `age_ms` of `time_ms`, or none a window before, or a gap between them.
pub(super) fn yaw_rate(
    samples: &[Stamped],
    time_ms: i64,
    age_ms: i64,
    window_ms: i64,
) -> Option<f32> {
    let window = window_ms.max(1);
    let last = samples.len().checked_sub(1)?;
    let bi = samples
        .iter()
        .position(|s| s.time_ms >= time_ms)
        .unwrap_or(last);
    let b = samples.get(bi)?;
    if (b.time_ms - time_ms).abs() > age_ms {
        return None;
    }
    let ai = samples
        .get(..bi)?
        .iter()
        .rposition(|s| s.time_ms <= b.time_ms - window)?;
    let a = samples.get(ai)?;
    let span = b.time_ms - a.time_ms;
    if span > window + age_ms {
        return None;
    }
    let turn: f32 = samples
        .get(ai..=bi)?
        .windows(2)
        .map(|w| match w {
            [p, q] => wrap_half(q.deg - p.deg),
            _ => 0.0,
        })
        .sum();
    Some(libm::fabsf(turn) * 1000.0 / span as f32)
}
