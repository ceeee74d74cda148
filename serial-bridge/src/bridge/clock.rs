//! Each source's clock followed on its own: a record whose time jumps away from its neighbours
//! is that record's problem, not every later record's.
//!
//! A KrakenSDR record carries its unit's epoch milliseconds with no checksum: one corrupt digit
//! moves it by milliseconds to hours. Taken as it is, a time pushed into the future makes
//! every later record of the source older than it, each then refused as going backwards, and
//! the drive is lost after it. Whether a time is the record's own fault or the clock's (a unit
//! whose clock was set, a pause in the records) shows only in the records after it, and no
//! spacing tells a corrupt second from a second record missing, so each record waits for the
//! next one of its source (one per source, two when they disagree):
//! - the next at or after it: the two are in order, it passes (whatever the gap: a pause or a
//!   clock set forward loses nothing);
//! - the next between the clock and it: it jumped forward, or the next one went back: the
//!   record after them says which (the one without which the rest is in order);
//! - it was behind the clock and the next follows it, still behind: the clock stepped back (a
//!   replay, a reset): it passes, for the core to judge; the next back on the clock: it went
//!   back on its own.
//!
//! A refused record is counted `time_jump`. One corrupt time costs one record at most, and
//! waiting costs one record of latency (the last record of a source passes at the end of the
//! stream). Fixed memory: [`CLOCKS`] sources, the one heard the longest ago making room for a
//! new one (its held records pass then).

use super::BearingKind;

/// Sources whose clocks are followed at once: a drive's KrakenSDR stations.
pub const CLOCKS: usize = 4;

/// Who keeps a clock: the record kind and, for a KrakenSDR, its station id (hashed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct ClockKey {
    kind: BearingKind,
    station: u32,
}

impl ClockKey {
    /// The clock of `kind` records from station `station` (empty: a kind without stations).
    pub(super) fn new(kind: BearingKind, station: &str) -> Self {
        // FNV-1a: two stations of one drive colliding would share a clock, nothing worse.
        let station = station.bytes().fold(0x811c_9dc5u32, |h, b| {
            (h ^ u32::from(b)).wrapping_mul(0x0100_0193)
        });
        Self { kind, station }
    }
}

/// One source's clock.
#[derive(Debug, Clone, Copy)]
struct SourceClock<T> {
    key: ClockKey,
    /// The last time passed (`None`: none yet).
    last: Option<i64>,
    /// Records held back, with their times, oldest first: one waiting for the next record, or
    /// two that disagree.
    held: [Option<(i64, T)>; 2],
    /// When the source was last heard (for the one heard the longest ago).
    heard: u32,
}

impl<T: Copy> SourceClock<T> {
    fn new(key: ClockKey, heard: u32) -> Self {
        Self {
            key,
            last: None,
            held: [None; 2],
            heard,
        }
    }

    /// Pass a record at `t`: the clock's time is `t` now (a step back included).
    fn pass(&mut self, t: i64, record: T, out: &mut Judged<T>) {
        self.last = Some(t);
        out.push(record);
    }

    /// Take a record at `t`; what passes goes into `out`.
    fn take(&mut self, t: i64, record: T, out: &mut Judged<T>) {
        let lowest = self.last.unwrap_or(i64::MIN);
        let held = core::mem::take(&mut self.held);
        let hold = |this: &mut Self, a: Option<(i64, T)>| {
            this.held = [a, Some((t, record))];
        };
        match held {
            [None, None] => hold(self, None),
            [Some((h, r)), None] | [None, Some((h, r))] => {
                if h >= lowest {
                    // Ahead of the clock: a record at or after it says they are in order; one
                    // before it leaves two to tell apart, for the next record.
                    if t >= h {
                        self.pass(h, r, out);
                        hold(self, None);
                    } else {
                        hold(self, Some((h, r)));
                    }
                } else if t >= h && t < lowest {
                    // Behind the clock, and the next follows it: the clock stepped back.
                    self.pass(h, r, out);
                    hold(self, None);
                } else if t >= lowest {
                    // The next is back on the clock: the held one went back on its own.
                    out.jumped += 1;
                    hold(self, None);
                } else {
                    hold(self, Some((h, r)));
                }
            }
            [Some((h1, r1)), Some((h2, r2))] => {
                // Two held that disagree (or both behind the clock): the odd one is the one
                // without which the clock, the rest and the new record are in order.
                let fits = |h: i64| lowest <= h && h <= t;
                let (without_first, without_second) = (fits(h2), fits(h1));
                if h1 <= h2 && h2 <= t && t < lowest {
                    // All three behind the clock, in order: it stepped back.
                    self.pass(h1, r1, out);
                    self.pass(h2, r2, out);
                    hold(self, None);
                } else if without_first || without_second {
                    // Both fit between the clock and the new record: the odd one is the one
                    // farther from its place on the line between them (before the clock has a
                    // time: the second).
                    let first_odd = match self.last {
                        Some(l) if without_first && without_second => {
                            (h1 - (l + (t - l) / 3)).abs() > (h2 - (l + 2 * (t - l) / 3)).abs()
                        }
                        _ => !without_second,
                    };
                    out.jumped += 1;
                    if first_odd {
                        self.pass(h2, r2, out);
                    } else {
                        self.pass(h1, r1, out);
                    }
                    hold(self, None);
                } else {
                    // Neither fits. The first in order with the clock, the second followed:
                    // the first passes and the second is judged again (a step back?); else the
                    // first is refused.
                    if h1 >= lowest && h2 <= t {
                        self.pass(h1, r1, out);
                    } else {
                        out.jumped += 1;
                    }
                    self.held = [Some((h2, r2)), None];
                    self.take(t, record, out);
                }
            }
        }
    }
}

/// What the clocks made of a record.
#[derive(Debug, Clone, Copy)]
pub(super) struct Judged<T> {
    /// Records that pass now, in order: held records of a source that made room for the new
    /// one's, held records the new one settled (the new one is held in its turn).
    pub pass: [Option<T>; 4],
    /// Held records refused: their times jumped on their own.
    pub jumped: u32,
}

impl<T: Copy> Judged<T> {
    fn push(&mut self, record: T) {
        if let Some(slot) = self.pass.iter_mut().find(|s| s.is_none()) {
            *slot = Some(record);
        }
    }
}

/// The clocks of every source heard.
#[derive(Debug, Clone)]
pub(super) struct Clocks<T> {
    sources: heapless::Vec<SourceClock<T>, CLOCKS>,
    heard: u32,
}

impl<T: Copy> Clocks<T> {
    pub(super) const fn new() -> Self {
        Self {
            sources: heapless::Vec::new(),
            heard: 0,
        }
    }

    /// The time of `key`'s clock (its last passed record, else its first held), if any.
    pub(super) fn last(&self, key: ClockKey) -> Option<i64> {
        self.sources
            .iter()
            .find(|c| c.key == key)
            .and_then(|c| c.last.or(c.held[0].map(|(t, _)| t)))
    }

    /// Judge a record of source `key` at time `t` (ms on the bridge's continuous clock).
    pub(super) fn judge(&mut self, key: ClockKey, t: i64, record: T) -> Judged<T> {
        let mut out = Judged {
            pass: [None; 4],
            jumped: 0,
        };
        self.heard = self.heard.wrapping_add(1);
        let heard = self.heard;
        let i = match self.sources.iter().position(|c| c.key == key) {
            Some(i) => i,
            None if !self.sources.is_full() => {
                let _ = self.sources.push(SourceClock::new(key, heard));
                self.sources.len() - 1
            }
            None => {
                // Every clock taken: the source heard the longest ago makes room, its held
                // records passing.
                let gone = (0..self.sources.len())
                    .max_by_key(|&i| {
                        self.sources
                            .get(i)
                            .map_or(0, |c| heard.wrapping_sub(c.heard))
                    })
                    .unwrap_or(0);
                if let Some(slot) = self.sources.get_mut(gone) {
                    for (_, r) in slot.held.iter().flatten() {
                        out.push(*r);
                    }
                    *slot = SourceClock::new(key, heard);
                }
                gone
            }
        };
        if let Some(c) = self.sources.get_mut(i) {
            c.heard = heard;
            c.take(t, record, &mut out);
        }
        out
    }

    /// The stream ended: every held record passes (nothing came to say otherwise).
    pub(super) fn release(&mut self, mut each: impl FnMut(T)) {
        for c in self.sources.iter_mut() {
            for (t, r) in c.held.iter().flatten() {
                each(*r);
                c.last = Some(*t);
            }
            c.held = [None; 2];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Times through the clocks of one source: which passed (their times, in order) and how
    /// many were refused.
    fn run(times: &[i64]) -> (Vec<i64>, u32) {
        let key = ClockKey::new(BearingKind::KrakenCsv, "k");
        let mut clocks = Clocks::<i64>::new();
        let (mut passed, mut jumps) = (Vec::new(), 0);
        for &t in times {
            let j = clocks.judge(key, t, t);
            passed.extend(j.pass.iter().flatten());
            jumps += j.jumped;
        }
        clocks.release(|t| passed.push(t));
        (passed, jumps)
    }

    fn steady(n: i64) -> Vec<i64> {
        (0..n).map(|k| 1000 * k).collect()
    }

    #[test]
    fn a_steady_clock_passes_everything_in_order() {
        let t = steady(20);
        assert_eq!(run(&t), (t.clone(), 0));
    }

    /// Records a downstream reader loses: those refused, and those passed behind an earlier
    /// one (which it would refuse as going backwards).
    fn lost(passed: &[i64], refused: u32) -> u32 {
        let mut latest = i64::MIN;
        let mut behind = 0;
        for &t in passed {
            if t < latest {
                behind += 1;
            }
            latest = latest.max(t);
        }
        refused + behind
    }

    #[test]
    fn a_time_jumping_forward_or_back_costs_one_record_wherever_it_is() {
        for at in 0..20 {
            for jump in [2_000, 9_000, 60_000, 3_600_000, -1_500, -9_000, -3_600_000] {
                let mut t = steady(20);
                t[at] += jump;
                let (passed, refused) = run(&t);
                assert_eq!(passed.len() as u32 + refused, 20, "at {at}, jump {jump}");
                assert!(
                    lost(&passed, refused) <= 1,
                    "at {at}, jump {jump}: {passed:?}"
                );
                // Past the start (where the spacing is still unknown) and before the end (where
                // no record comes to tell) it is the record itself.
                if (3..18).contains(&at) {
                    let mut want = steady(20);
                    want.remove(at);
                    assert_eq!((passed, refused), (want, 1), "at {at}, jump {jump}");
                }
            }
        }
    }

    #[test]
    fn a_small_jump_within_the_spacing_passes() {
        // 400 ms late on a 1 s clock: still in order, nothing to refuse.
        let mut t = steady(20);
        t[7] += 400;
        assert_eq!(run(&t), (t.clone(), 0));
    }

    #[test]
    fn a_step_that_persists_passes_and_so_does_a_pause() {
        // The clock stepped an hour forward at record 10 (or the unit paused an hour).
        let t: Vec<i64> = (0..20)
            .map(|k| 1000 * k + if k >= 10 { 3_600_000 } else { 0 })
            .collect();
        assert_eq!(run(&t), (t.clone(), 0));
        // A replay from the start: everything passes, for the core to count as repeated.
        let mut replay = steady(10);
        replay.extend(steady(10));
        assert_eq!(run(&replay), (replay.clone(), 0));
    }

    #[test]
    fn equal_times_and_jitter_pass() {
        let t = [0, 0, 1000, 1000, 2100, 2900, 4000, 4000, 5050];
        assert_eq!(run(&t), (t.to_vec(), 0));
    }

    #[test]
    fn sources_keep_their_own_clocks() {
        let mut clocks = Clocks::<(u8, i64)>::new();
        let a = ClockKey::new(BearingKind::KrakenCsv, "a");
        let b = ClockKey::new(BearingKind::KrakenCsv, "b");
        let mut passed = 0;
        for k in 0..20i64 {
            // b's clock runs 20 s ahead of a's: interleaved, neither is refused.
            for (key, s, t) in [(a, 0, 1000 * k), (b, 1, 20_000 + 1000 * k)] {
                let j = clocks.judge(key, t, (s, t));
                assert_eq!(j.jumped, 0);
                passed += j.pass.iter().flatten().count();
            }
        }
        clocks.release(|_| passed += 1);
        assert_eq!(passed, 40);
    }

    #[test]
    fn more_sources_than_clocks_lose_nothing() {
        let mut clocks = Clocks::<i64>::new();
        let mut passed = 0;
        for k in 0..50i64 {
            let key = ClockKey::new(
                BearingKind::KrakenXml,
                ["a", "b", "c", "d", "e", "f"][k as usize % 6],
            );
            let j = clocks.judge(key, 1000 * k, k);
            assert_eq!(j.jumped, 0);
            passed += j.pass.iter().flatten().count();
        }
        clocks.release(|_| passed += 1);
        assert_eq!(passed, 50);
    }
}
