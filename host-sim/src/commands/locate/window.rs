//! A live worker's memory bound: each channel keeps its latest bearings, a fixed number of
//! them (docs/src/networks.md, "Through an MQTT broker"). A network sends without end; a fix
//! over every bearing ever heard would grow in memory and in solve time with the run, while
//! a still emitter's fix from its latest few thousand bearings is as good and follows it
//! when it moves or stops.

use foxhunt_core::fix::locate::Observation;
use std::collections::{BTreeMap, HashMap, HashSet};
use std::time::Instant;

/// The bearings kept per channel by default: minutes of a small network, seconds of a large
/// one (200 stations at 2 Hz fill it in 10 s).
pub const KEEP: usize = 4096;

/// Each channel's latest `keep` bearings, the older dropped.
#[derive(Debug, Clone)]
pub struct ChannelWindow {
    keep: usize,
    /// Bearings dropped so far.
    pub dropped: u64,
    /// Each full channel's bearings dropped so far, and as many when its stations were last
    /// counted: counted when it fills, and again each time its window has turned over.
    turnover: HashMap<i64, (u64, Option<u64>)>,
    /// Channels found crowded, each named once.
    named: HashSet<i64>,
    /// Each channel's bearings among the first `counted` of the observations.
    count: HashMap<i64, usize>,
    /// Observations counted so far.
    counted: usize,
    /// Channels found crowded and not yet taken by [`ChannelWindow::crowded`]: (key,
    /// stations).
    crowded: Vec<(i64, usize)>,
}

/// Bearings per station a channel's window should hold: each station's offset takes about
/// one of its bearings, the noise estimate needs the rest. A window of 256 bearings from 200
/// stations left too few in 7-8 % of its solves (docs/src/speed.md, "Through an MQTT broker").
pub const PER_STATION: usize = 2;

/// A bearing's channel as the topics name it ([`crate::inputs::mqtt::channel_name`]): its
/// frequency to the kHz.
fn channel_key(o: &Observation) -> i64 {
    match o.freq_mhz {
        Some(f) if f > 0.0 && f.is_finite() => {
            foxhunt_core::fastmath::round_half_away_f64(f64::from(f) * 1000.0)
        }
        _ => -1,
    }
}

impl ChannelWindow {
    /// Keep `keep` bearings per channel (at least 1).
    pub fn new(keep: usize) -> Self {
        Self {
            keep: keep.max(1),
            dropped: 0,
            turnover: HashMap::new(),
            named: HashSet::new(),
            count: HashMap::new(),
            counted: 0,
            crowded: Vec::new(),
        }
    }

    /// Drop each channel's oldest bearings beyond the bound, keeping the order of the rest;
    /// how many were dropped. The observations are in arrival order, so a channel's oldest are
    /// its first. A worker calls this at every solve with the bearings that arrived since the
    /// last call appended: those are counted, not the whole window again, and the scan for the
    /// oldest stops once every full channel has dropped its excess (they are at the front).
    pub fn trim(&mut self, obs: &mut Vec<Observation>) -> usize {
        // Bearings taken out by someone else: count them all again.
        if obs.len() < self.counted {
            self.count.clear();
            self.counted = 0;
        }
        for o in obs.get(self.counted..).unwrap_or(&[]) {
            *self.count.entry(channel_key(o)).or_default() += 1;
        }
        self.counted = obs.len();
        // How many each channel still has to drop.
        let mut excess: BTreeMap<i64, usize> = self
            .count
            .iter()
            .filter(|&(_, &n)| n > self.keep)
            .map(|(&k, &n)| (k, n - self.keep))
            .collect();
        if excess.is_empty() {
            return 0;
        }
        let mut due = Vec::new();
        for (&key, &n) in &excess {
            let (dropped, counted) = self.turnover.entry(key).or_insert((0, None));
            if !self.named.contains(&key)
                && counted.is_none_or(|c| *dropped - c >= self.keep as u64)
            {
                *counted = Some(*dropped);
                due.push(key);
            }
            *dropped += n as u64;
            self.count.insert(key, self.keep);
        }
        let before = obs.len();
        let mut left: usize = excess.values().sum();
        let (mut read, mut write) = (0, 0);
        while left > 0 && read < before {
            let o = obs[read];
            read += 1;
            match excess.get_mut(&channel_key(&o)) {
                Some(n) if *n > 0 => {
                    *n -= 1;
                    left -= 1;
                }
                _ => {
                    obs[write] = o;
                    write += 1;
                }
            }
        }
        obs.copy_within(read.., write);
        obs.truncate(write + before - read);
        self.counted = obs.len();
        let gone = before - obs.len();
        self.dropped += gone as u64;
        // A full channel, when it fills and each time its window has turned over: are its
        // stations too many for it?
        for key in due {
            let mut stations: Vec<u16> = obs
                .iter()
                .filter(|o| channel_key(o) == key)
                .map(|o| o.station)
                .collect();
            stations.sort_unstable();
            stations.dedup();
            if self.keep < PER_STATION * stations.len() {
                self.named.insert(key);
                self.crowded.push((key, stations.len()));
            }
        }
        gone
    }

    /// The channels found crowded since the last call, each once: its key (kHz) and the
    /// stations its full window held, fewer than [`PER_STATION`] bearings a station.
    pub fn crowded(&mut self) -> Vec<(i64, usize)> {
        std::mem::take(&mut self.crowded)
    }

    /// The window's size.
    pub fn keep(&self) -> usize {
        self.keep
    }
}

/// The channels with bearings no fix has used yet, each with when the oldest of them arrived.
/// A worker solves the longest-waiting channel next, one channel at a time, and takes what
/// arrived after each solve: a bearing then waits for at most one solve of each other channel,
/// not for a whole update of every channel and the next (docs/src/speed.md, "Through an MQTT
/// broker").
#[derive(Debug, Default)]
pub struct Pending {
    since: HashMap<i64, Instant>,
}

impl Pending {
    /// `new` bearings arrived at `now`.
    pub fn arrived(&mut self, new: &[Observation], now: Instant) {
        for o in new {
            self.since.entry(channel_key(o)).or_insert(now);
        }
    }

    /// Whether every channel's bearings have been solved.
    pub fn is_empty(&self) -> bool {
        self.since.is_empty()
    }

    /// The longest-waiting channel's key and its bearings with its neighbours' within
    /// `width_mhz` (a channel may hold several keys: the fix groups them as it would the whole
    /// capture's), in time order (by station within a time, else as they came), those
    /// channels no longer pending; `None` when nothing waits. A broker delivers a bearing held
    /// up by an outage after later ones; in time order the fix is the same whatever the
    /// delivery's order.
    pub fn next(&mut self, obs: &[Observation], width_mhz: f32) -> Option<(i64, Vec<Observation>)> {
        let (&key, _) = self.since.iter().min_by_key(|&(k, t)| (*t, *k))?;
        let near = |k: i64| {
            k == key
                || (k >= 0 && key >= 0 && (k - key).abs() as f64 <= f64::from(width_mhz) * 1000.0)
        };
        self.since.retain(|&k, _| !near(k));
        let mut one: Vec<Observation> = obs
            .iter()
            .filter(|o| near(channel_key(o)))
            .copied()
            .collect();
        one.sort_by(|a, b| {
            a.time_s
                .total_cmp(&b.time_s)
                .then(a.station.cmp(&b.station))
        });
        Some((key, one))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use foxhunt_core::Bearing;

    fn obs(freq: f32, t: f32) -> Observation {
        Observation {
            bearing: Bearing {
                vehicle: [0.0, 0.0],
                theta: 0.0,
                sigma: 0.02,
            },
            time_s: t,
            freq_mhz: Some(freq),
            station: 0,
            stamped: true,
        }
    }

    #[test]
    fn each_channel_keeps_its_latest_in_order() {
        let mut v = Vec::new();
        for i in 0..10 {
            v.push(obs(145.5, i as f32));
            if i % 2 == 0 {
                v.push(obs(433.92, i as f32));
            }
        }
        let mut w = ChannelWindow::new(3);
        assert_eq!(w.trim(&mut v), 7 + 2);
        let times = |f: f32| -> Vec<f32> {
            v.iter()
                .filter(|o| o.freq_mhz == Some(f))
                .map(|o| o.time_s)
                .collect()
        };
        assert_eq!(times(145.5), vec![7.0, 8.0, 9.0]);
        assert_eq!(times(433.92), vec![4.0, 6.0, 8.0]);
        // Arrival order kept across channels.
        assert!(v.windows(2).all(|p| p[0].time_s <= p[1].time_s));
        assert_eq!(w.trim(&mut v), 0);
        assert_eq!(w.dropped, 9);
    }

    #[test]
    fn a_channels_key_is_its_frequency_rounded_to_the_khz() {
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut draw = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            rng
        };
        let edges = [
            0.0005f32,
            0.0015,
            145.5005,
            433.9205,
            1e9,
            3.4e38,
            f32::MIN_POSITIVE,
        ];
        let random = (0..100_000).map(|_| f32::from_bits((draw() >> 33) as u32 & 0x7fff_ffff));
        for f in edges
            .into_iter()
            .chain(random)
            .filter(|f| f.is_finite() && *f > 0.0)
        {
            assert_eq!(
                channel_key(&obs(f, 0.0)),
                (f64::from(f) * 1000.0).round() as i64,
                "{f}"
            );
        }
    }

    #[test]
    fn trimming_as_bearings_arrive_keeps_what_trimming_everything_at_once_keeps() {
        // The reference: each channel's latest `keep` of everything that ever arrived.
        let keep = 5;
        let mut all = Vec::new();
        let mut v = Vec::new();
        let mut w = ChannelWindow::new(keep);
        let freqs = [145.5, 433.92, 446.0];
        for round in 0..60usize {
            for k in 0..(round * 7 % 11) {
                let o = obs(freqs[(round + k * k) % 3], all.len() as f32);
                all.push(o);
                v.push(o);
            }
            w.trim(&mut v);
            let mut left: HashMap<i64, usize> = HashMap::new();
            let mut want: Vec<Observation> = all
                .iter()
                .rev()
                .filter(|o| {
                    let n = left.entry(channel_key(o)).or_default();
                    *n += 1;
                    *n <= keep
                })
                .copied()
                .collect();
            want.reverse();
            assert_eq!(v, want, "round {round}");
            assert_eq!(w.dropped as usize, all.len() - v.len());
        }
    }

    #[test]
    fn a_window_too_small_for_its_stations_is_named_once() {
        let mut v = Vec::new();
        for t in 0..3 {
            for station in 0..5 {
                v.push(Observation {
                    station,
                    ..obs(145.5, t as f32)
                });
            }
            v.push(obs(433.92, t as f32));
        }
        // 145.5: 5 stations in a window of 8 bearings; 433.92: one station, never full.
        let mut w = ChannelWindow::new(8);
        w.trim(&mut v);
        assert_eq!(w.crowded(), vec![(145_500, 5)]);
        v.push(obs(145.5, 4.0));
        w.trim(&mut v);
        assert!(w.crowded().is_empty());
        // Room for two a station: not crowded.
        let mut w = ChannelWindow::new(10);
        v.extend((0..5).map(|station| Observation {
            station,
            ..obs(145.5, 5.0)
        }));
        w.trim(&mut v);
        assert!(w.crowded().is_empty());
        // Filled by one station, then crowded by four: named once its window has turned over.
        let mut w = ChannelWindow::new(4);
        let mut v: Vec<Observation> = (0..5).map(|t| obs(145.5, t as f32)).collect();
        w.trim(&mut v);
        assert!(w.crowded().is_empty());
        let mut named = Vec::new();
        for t in 5..12 {
            v.extend((0..4).map(|station| Observation {
                station,
                ..obs(145.5, t as f32)
            }));
            w.trim(&mut v);
            named.extend(w.crowded());
        }
        assert_eq!(named, vec![(145_500, 4)]);
    }

    #[test]
    fn the_longest_waiting_channel_is_solved_first_with_its_neighbours() {
        let t0 = Instant::now();
        let later = t0 + std::time::Duration::from_millis(5);
        let v = [
            obs(433.92, 0.0),
            obs(145.5, 3.0),
            obs(433.921, 2.0),
            obs(145.5, 1.0),
        ];
        let mut p = Pending::default();
        p.arrived(&v[1..2], t0);
        p.arrived(&v[..1], later);
        p.arrived(&v[2..], later);
        // 145.500 waited longest (its bearings put in time order); then 433.920 with 433.921,
        // 1 kHz apart in a 50 kHz channel.
        let (key, first) = p.next(&v, 0.05).expect("145.5");
        assert_eq!(key, 145_500);
        assert_eq!(
            first.iter().map(|o| o.time_s).collect::<Vec<_>>(),
            [1.0, 3.0]
        );
        let (key, second) = p.next(&v, 0.05).expect("433.92");
        assert_eq!(key, 433_920);
        assert_eq!(
            second.iter().map(|o| o.time_s).collect::<Vec<_>>(),
            [0.0, 2.0]
        );
        assert!(p.is_empty());
        assert!(p.next(&v, 0.05).is_none());
    }
}
