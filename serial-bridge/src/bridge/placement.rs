//! Where the vehicle was: the fixes of the last span, kept by time, and a bearing's place
//! between them.

use super::{Bridge, Event, Pending, VehicleFix};
use crate::nmea::{LatLon, UtcTime};

/// Fixes the bridge holds for placing bearings (48 bytes each): 64 fixes cover the default
/// 5 s span up to a 12 Hz GPS. A faster receiver fills the history before the span: then the
/// fix whose removal widens the spacing least is dropped (never the oldest), so the span
/// holds at a coarser spacing (20 Hz: one fix in 80 ms).
pub const FIX_HISTORY: usize = 64;

/// `p` and `q` mixed by `w` (0: `p`), the longitude the short way round.
fn lerp_position(p: LatLon, q: LatLon, w: f64) -> LatLon {
    let mut d = q.lon - p.lon;
    if d > 180.0 {
        d -= 360.0;
    } else if d < -180.0 {
        d += 360.0;
    }
    let mut lon = p.lon + w * d;
    if lon > 180.0 {
        lon -= 360.0;
    } else if lon < -180.0 {
        lon += 360.0;
    }
    LatLon {
        lat: p.lat + w * (q.lat - p.lat),
        lon,
    }
}

impl<const A: usize, const S: usize> Bridge<A, S> {
    pub(super) fn fix(
        &mut self,
        time: UtcTime,
        position: LatLon,
        speed_mps: Option<f32>,
        course_deg: Option<f32>,
        sink: &mut impl FnMut(Event),
    ) {
        let Ok(local) = self.local(position) else {
            self.counters.bad_position += 1;
            return;
        };
        let time_ms = self.unwrap_time(time.ms_of_day);
        self.motion(time_ms, speed_mps, course_deg);
        if let Some(last) = self.fixes.last_mut()
            && last.time_ms == time_ms
        {
            // The sentences of one epoch: one fix, with the RMC's speed and course.
            last.speed_mps = speed_mps.or(last.speed_mps);
            last.course_deg = course_deg.or(last.course_deg);
            return;
        }
        if self.fixes.last().is_some_and(|l| l.time_ms > time_ms) {
            // Time went backwards (a new capture, a receiver reset): the old fixes say
            // nothing about the new times.
            self.fixes.clear();
            self.dropped = true;
        }
        let fix = VehicleFix {
            time_ms,
            position,
            local,
            speed_mps,
            course_deg,
        };
        self.keep(fix);
        self.first_fix_ms.get_or_insert(time_ms);
        self.counters.fixes += 1;
        sink(Event::Fix(fix));
        // Every waiting bearing this fix reaches, in arrival order; the others wait on. Not
        // only those before the first that waits on: one bearing whose time jumped ahead would
        // hold every later one back until the queue overflowed (a corrupt digit costing many).
        for _ in 0..self.waiting.len() {
            let Some(p) = self.waiting.pop_front() else {
                break;
            };
            if p.time_ms > time_ms {
                let _ = self.waiting.push_back(p);
            } else {
                self.place(&p, sink);
            }
        }
    }

    /// Add `fix` to the history: fixes more than the span behind it leave (the last one at or
    /// before the span's start stays, to interpolate there); a full history drops the fix
    /// whose neighbours are closest in time (never the oldest, so the span holds).
    fn keep(&mut self, fix: VehicleFix) {
        let start = fix.time_ms - i64::from(self.config.fix_span_ms);
        let old = self
            .fixes
            .iter()
            .rposition(|f| f.time_ms <= start)
            .unwrap_or(0);
        if old > 0 {
            self.dropped = true;
            let kept = self.fixes.len() - old;
            for i in 0..kept {
                if let Some(&f) = self.fixes.get(i + old)
                    && let Some(slot) = self.fixes.get_mut(i)
                {
                    *slot = f;
                }
            }
            self.fixes.truncate(kept);
        }
        if self.fixes.is_full() {
            // Among the fixes with a neighbour on each side (the newest has none yet: the new
            // fix is its later neighbour), the one whose loss leaves the smallest gap.
            let thin = (1..self.fixes.len())
                .filter_map(|i| {
                    let before = self.fixes.get(i - 1)?.time_ms;
                    let after = self.fixes.get(i + 1).map_or(fix.time_ms, |f| f.time_ms);
                    Some((after - before, i))
                })
                .min()
                .map_or(0, |(_, i)| i);
            if thin == 0 {
                self.dropped = true;
            }
            if thin < self.fixes.len() {
                self.fixes.remove(thin);
            }
        }
        // Room was made above, so this cannot fail.
        let _ = self.fixes.push(fix);
    }

    /// Place a bearing at the vehicle's position at its time.
    pub(super) fn place(&mut self, p: &Pending, sink: &mut impl FnMut(Event)) {
        let gap = i64::from(self.config.max_fix_gap_ms);
        let before = self.fixes.iter().rev().find(|f| f.time_ms <= p.time_ms);
        let after = self.fixes.iter().find(|f| f.time_ms >= p.time_ms);
        if before.is_none() && self.dropped && self.first_fix_ms.is_some_and(|t| t <= p.time_ms) {
            // The fixes before it have left the history: placing it at the oldest kept fix
            // would put it where the vehicle was later.
            self.counters.late += 1;
            return;
        }
        let near = |f: &&VehicleFix| (f.time_ms - p.time_ms).abs() <= gap;
        let position = match (before.filter(near), after.filter(near)) {
            (Some(a), Some(b)) if b.time_ms > a.time_ms => {
                let w = (p.time_ms - a.time_ms) as f64 / (b.time_ms - a.time_ms) as f64;
                let wf = w as f32;
                Some((
                    [
                        a.local[0] + wf * (b.local[0] - a.local[0]),
                        a.local[1] + wf * (b.local[1] - a.local[1]),
                    ],
                    lerp_position(a.position, b.position, w),
                ))
            }
            (Some(a), _) => Some((a.local, a.position)),
            (None, Some(b)) => Some((b.local, b.position)),
            (None, None) => None,
        };
        match position {
            Some((v, at)) => self.emit(p, v, at, sink),
            None if self.fixes.is_empty() => self.counters.no_fix += 1,
            None => self.counters.stale_fix += 1,
        }
    }
}
