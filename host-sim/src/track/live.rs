//! Tracking on a live line: bearings arrive one by one, each channel's are grouped into
//! updates as they come ([`Window`]) and each update is stepped at once by that channel's
//! tracker, which lives on a thread of its own between updates (the core's filters are sized
//! at compile time and dispatched inside a call, [`track_each`], so the thread is what keeps
//! one across updates). Memory stays bounded: a channel keeps its filter, its open update and
//! its last 512 updates (a station found to be an indoor array has them tracked again with it
//! taken as such), never the points already handed out.
//!
//! Stations join a channel as they are heard, so the state is sized for [`LIVE_SOURCES`]
//! from the start (a recorded capture's is sized for the stations it holds): a later station
//! takes the next free offset, whose prior is the widest any station may have (its own is not
//! known when the tracker starts), and bearings of stations beyond it are dropped. An offset
//! no bearing has reached is left out of the tracker's kernel (the core's `Mover`), so the
//! heard stations are tracked to the bit as a state of those alone tracks them.
//!
//! With RSSI ([`LiveChannels::with_rssi`]) the line tracks one emitter: the anchors' readings
//! and the bearings of the first channel heard join its updates in one time order, as a
//! recorded capture's do, its state sized for the stations a state with RSSI terms holds.

use crate::estimate::stations::StationSetup;
use crate::inputs::stations::PriorFrom;
use crate::track::direction::Directions;
use crate::track::moving::{Settings, TrackPoint, Update, max_sources, track_each};
use crate::track::noise::{LiveScatter, Unstated, as_arrays};
use crate::track::tracks::{Options, memory_s, observable, track_noise, unstated_of};
use crate::track::updates::Window;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::channel::belongs;
use foxhunt_core::fix::observation::Observation;
use foxhunt_core::track::{Layout, Level, Motion};
use std::collections::VecDeque;
use std::sync::mpsc;
use std::thread::JoinHandle;

/// DF stations a live channel tracks: the most a compiled state of bearings alone holds.
pub const LIVE_SOURCES: u8 = max_sources(false) as u8;
/// Channels a live line may hold, as a capture may.
pub const LIVE_CHANNELS: usize = 16;

/// A channel's tracker on its own thread: an update in, its point out.
pub struct LiveTracker {
    updates: Option<mpsc::SyncSender<Update>>,
    points: mpsc::Receiver<TrackPoint>,
    thread: Option<JoinHandle<Result<(), String>>>,
}

impl LiveTracker {
    /// Start a tracker of `settings`; it makes its cloud from the first update it is given.
    pub fn start(settings: Settings) -> Result<Self, String> {
        let (updates, rx) = mpsc::sync_channel::<Update>(1);
        let (tx, points) = mpsc::sync_channel::<TrackPoint>(1);
        let thread = std::thread::Builder::new()
            .name("foxhunt-track".into())
            // The filters are built on the stack, as on the estimation pool's workers.
            .stack_size(crate::estimate::STACK_BYTES)
            .spawn(move || {
                track_each(&mut rx.into_iter(), &settings, &mut |p| {
                    let _ = tx.send(p);
                })
                .map(|_| ())
                .map_err(|e| e.to_string())
            })
            .map_err(|e| format!("cannot start a tracker: {e}"))?;
        Ok(Self {
            updates: Some(updates),
            points,
            thread: Some(thread),
        })
    }

    /// Step update `u`: its point, or why the tracker stopped (it is then spent).
    pub fn step(&mut self, u: Update) -> Result<TrackPoint, String> {
        let sent = self.updates.as_ref().is_some_and(|tx| tx.send(u).is_ok());
        if sent && let Ok(p) = self.points.recv() {
            return Ok(p);
        }
        self.updates = None;
        Err(match self.thread.take().map(JoinHandle::join) {
            Some(Ok(Err(e))) => e,
            Some(Err(_)) => "the tracker failed".into(),
            _ => "the tracker has stopped".into(),
        })
    }
}

impl Drop for LiveTracker {
    fn drop(&mut self) {
        // Closing the updates ends the thread's loop.
        self.updates = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One channel of a live line.
struct LiveChannel {
    /// Where its band starts, MHz (none: the bearings without a frequency).
    lowest: Option<f32>,
    /// The frequency its first bearing gave, MHz.
    freq_mhz: Option<f32>,
    /// The line's station index of each source, by source number.
    sources: Vec<u16>,
    /// What no one stated of each source (its noise is then estimated), by source number.
    unstated: Vec<Unstated>,
    /// Its sources' bearings about the track, and their noise where estimated.
    scatter: LiveScatter,
    /// Whether a bearing set its band (an RSSI channel opened by a reading has none yet).
    banded: bool,
    /// Whether an RSSI reading has reached it (its range is then observable from one station).
    levels: bool,
    window: Window,
    tracker: Option<LiveTracker>,
    /// The updates its tracker took (as given, the last [`REPLAYED`]): a tracker started
    /// again when a source is found to be an indoor array takes them first.
    taken: VecDeque<Update>,
}

/// Updates a live channel keeps for a tracker started again ([`LiveChannel::taken`]): the
/// first ones, where sources are found to be arrays (on the indoor walker within two seconds),
/// with room to spare; stepping 512 again takes a second or two at 10 000 particles.
const REPLAYED: usize = 512;

impl LiveChannel {
    /// A tracker of `settings` for this channel: each heard source's offset prior
    /// (`prior_of` its station, `unheard` for a source not yet heard), the sources found to
    /// be indoor arrays taken as such.
    fn start(
        &self,
        settings: &Settings,
        unheard: BiasPrior,
        prior_of: &dyn Fn(u16) -> BiasPrior,
    ) -> Result<LiveTracker, String> {
        let mut settings = settings.clone();
        settings.offsets = (0..usize::from(settings.layout.sources))
            .map(|k| self.sources.get(k).map_or(unheard, |s| prior_of(*s)))
            .collect();
        let arrays = (0..self.sources.len()).filter(|k| self.scatter.array(*k as u16));
        as_arrays(&mut settings, arrays);
        LiveTracker::start(settings)
    }

    /// Start the tracker again and step it through the updates taken: the last one's point
    /// (a tracker that stops on the way leaves none: the next update starts one).
    fn retrack(
        &mut self,
        settings: &Settings,
        unheard: BiasPrior,
        prior_of: &dyn Fn(u16) -> BiasPrior,
    ) -> Result<TrackPoint, String> {
        self.tracker = None;
        let mut tracker = self.start(settings, unheard, prior_of)?;
        let mut last = Err("no update to track".to_string());
        for u in &self.taken {
            let mut u = *u;
            self.scatter.widen(&mut u);
            last = tracker.step(u);
            last.as_ref()?;
        }
        self.tracker = Some(tracker);
        last
    }
}

/// Why a bearing was left out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dropped {
    /// The line already has [`LIVE_CHANNELS`] channels.
    Channels,
    /// Its channel already tracks the stations its state holds
    /// ([`LiveChannels::max_stations`]).
    Stations,
}

/// An update of a channel, ready to step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ready {
    /// The channel's index on the line.
    pub channel: usize,
    /// Its frequency, MHz.
    pub freq_mhz: Option<f32>,
    /// The update.
    pub update: Update,
}

/// Every channel of a live line.
pub struct LiveChannels {
    channels: Vec<LiveChannel>,
    width_mhz: f32,
    settings: Settings,
    unheard: BiasPrior,
    /// Whether RSSI readings join the one channel.
    rssi: bool,
    /// Each station's stated direction-dependent error and its course so far: what the
    /// line's bearings are corrected by before they are pushed ([`Directions`]).
    pub directions: Directions,
}

impl LiveChannels {
    /// Channels `width_mhz` wide, each tracked as `settings` say (their layout is replaced by
    /// [`LIVE_SOURCES`] stations' bearings, their offsets' priors set when a tracker starts);
    /// `unheard`: the offset prior of a station not yet heard when its channel's tracker
    /// started.
    pub fn new(width_mhz: f32, settings: Settings, unheard: BiasPrior) -> Self {
        Self::sized(width_mhz, settings, unheard, false)
    }

    /// One channel whose updates hold RSSI readings ([`push_level`](Self::push_level)) and
    /// the bearings of the first band heard, `width_mhz` wide (the bearings of other bands are
    /// left out as [`Dropped::Channels`]); its state holds [`max_sources`]`(true)` stations.
    /// `settings` give the RSSI terms' priors.
    pub fn with_rssi(width_mhz: f32, settings: Settings, unheard: BiasPrior) -> Self {
        Self::sized(width_mhz, settings, unheard, true)
    }

    /// Channels of bearings tracked as `o` says: its tracker, motion, seed, the stations
    /// file's memory ([`memory_s`]) and, for a station not yet heard, the widest prior it may
    /// have ([`unheard`]). `track -` and the live map start theirs here.
    pub fn for_options(o: &Options) -> Self {
        let mut settings = Settings::new(Layout::default(), o.motion.unwrap_or(Motion::OUTDOOR));
        settings.method = o.method;
        settings.particles = o.particles;
        settings.seed = o.seed;
        settings.memory_s = memory_s(o);
        if let Some(a) = o.accel_sd {
            settings.motion.accel_sd = a;
        }
        Self::new(o.width_mhz, settings, unheard(o))
    }

    fn sized(width_mhz: f32, mut settings: Settings, unheard: BiasPrior, rssi: bool) -> Self {
        settings.layout = Layout {
            sources: max_sources(rssi) as u8,
            rssi,
        };
        Self {
            channels: Vec::new(),
            width_mhz,
            settings,
            unheard,
            rssi,
            directions: Directions::default(),
        }
    }

    /// Where a tracker started later starts when its first update holds readings alone: a
    /// centre and a spread, metres.
    pub fn start_region(&mut self, region: ([f32; 2], f32)) {
        self.settings.region = Some(region);
    }

    /// Whether RSSI readings join the one channel ([`with_rssi`](Self::with_rssi)).
    pub fn rssi(&self) -> bool {
        self.rssi
    }

    /// Stations a channel tracks; the bearings of later ones are left out.
    pub fn max_stations(&self) -> usize {
        usize::from(self.settings.layout.sources)
    }

    /// Channels the line tracks.
    fn max_channels(&self) -> usize {
        if self.rssi { 1 } else { LIVE_CHANNELS }
    }

    /// The channel a reading (no frequency) or a bearing of `freq_mhz` opens.
    fn open_channel(&mut self, freq_mhz: Option<f32>, banded: bool) -> usize {
        self.channels.push(LiveChannel {
            // The band centred on the first bearing's frequency.
            lowest: freq_mhz.map(|f| f - self.width_mhz / 2.0),
            freq_mhz,
            sources: Vec::new(),
            unstated: Vec::new(),
            scatter: LiveScatter::default(),
            banded,
            levels: false,
            window: Window::default(),
            tracker: None,
            taken: VecDeque::new(),
        });
        self.channels.len() - 1
    }

    /// Take bearing `o` (the line's station index in `o.station`; `unstated`: what no one
    /// stated of its station, learned as it comes, [`LiveScatter`]): the update it closed, if
    /// any, or why it was left out.
    pub fn push(
        &mut self,
        mut o: Observation,
        unstated: Unstated,
    ) -> Result<Option<Ready>, Dropped> {
        // The RSSI channel a reading opened takes the first bearing's band.
        if let Some(ch) = self.channels.first_mut().filter(|c| !c.banded) {
            ch.banded = true;
            ch.lowest = o.freq_mhz.map(|f| f - self.width_mhz / 2.0);
            ch.freq_mhz = o.freq_mhz;
        }
        let c = match self
            .channels
            .iter()
            .position(|c| belongs(o.freq_mhz, c.lowest, self.width_mhz))
        {
            Some(c) => c,
            None if self.channels.len() < self.max_channels() => {
                self.open_channel(o.freq_mhz, true)
            }
            None => return Err(Dropped::Channels),
        };
        let max = self.max_stations();
        let ch = &mut self.channels[c];
        let source = match ch.sources.iter().position(|s| *s == o.station) {
            Some(s) => s,
            None if ch.sources.len() < max => {
                ch.sources.push(o.station);
                ch.unstated.push(unstated);
                ch.sources.len() - 1
            }
            None => return Err(Dropped::Stations),
        };
        o.station = source as u16;
        Ok(ch.window.push(o).map(|update| Ready {
            channel: c,
            freq_mhz: ch.freq_mhz,
            update,
        }))
    }

    /// Take bearing `b` as its station is stated: its noise `sigma` (every station's), else
    /// the stations file's or its class's ([`track_noise`]; else the record's own, estimated),
    /// and the stated direction-dependent error taken out ([`Directions`]). As
    /// [`push`](Self::push).
    pub fn push_stated(
        &mut self,
        mut b: Observation,
        sigma: Option<f32>,
        setup: &StationSetup,
    ) -> Result<Option<Ready>, Dropped> {
        let station = usize::from(b.station);
        let stated = track_noise(setup, sigma, station);
        if let Some(s) = stated {
            b.bearing.sigma = s;
        }
        self.directions.correct(&mut b, &setup.priors);
        self.push(b, unstated_of(setup, stated.is_some(), station))
    }

    /// Take RSSI reading `l` taken at `t_s` (the bearings' time base): the update it closed, if
    /// any. Without RSSI ([`new`](Self::new)) readings are not this tracker's: none.
    pub fn push_level(&mut self, t_s: f32, l: Level) -> Option<Ready> {
        if !self.rssi {
            return None;
        }
        if self.channels.is_empty() {
            self.open_channel(None, false);
        }
        let ch = &mut self.channels[0];
        ch.levels = true;
        ch.window.push_level(t_s, l).map(|update| Ready {
            channel: 0,
            freq_mhz: ch.freq_mhz,
            update,
        })
    }

    /// Close every channel's open update (the line went quiet, or ended).
    pub fn close(&mut self) -> Vec<Ready> {
        self.channels
            .iter_mut()
            .enumerate()
            .filter_map(|(c, ch)| {
                ch.window.close().map(|update| Ready {
                    channel: c,
                    freq_mhz: ch.freq_mhz,
                    update,
                })
            })
            .collect()
    }

    /// Step `r` with its channel's tracker (started on the channel's first update heard by two
    /// stations or holding an RSSI reading, and again after one that stopped; `prior_of` gives
    /// the offset prior of a station by its index on the line): its point, `None` while one
    /// station alone has been heard on the channel and no reading (its range is not
    /// observable: [`one_station`](crate::track::tracks::one_station)), or why there is none.
    pub fn step(
        &mut self,
        r: Ready,
        prior_of: &dyn Fn(u16) -> BiasPrior,
    ) -> Result<Option<TrackPoint>, String> {
        let (settings, unheard) = (&self.settings, self.unheard);
        let ch = self.channels.get_mut(r.channel).ok_or("no such channel")?;
        if !observable(ch.sources.len(), ch.levels) {
            return Ok(None);
        }
        let tracker = match ch.tracker.as_mut() {
            Some(t) => t,
            None => {
                ch.taken.clear();
                ch.tracker.insert(ch.start(settings, unheard, prior_of)?)
            }
        };
        let mut u = r.update;
        ch.scatter.widen(&mut u);
        let point = tracker.step(u);
        match &point {
            Ok(p) => {
                if ch.taken.len() == REPLAYED {
                    ch.taken.pop_front();
                }
                ch.taken.push_back(r.update);
                // A source found to be an indoor array: a tracker with the array's offset
                // prior and memory takes the channel's updates again, so its track goes on
                // as if the array had been known from the start (this update's point is the
                // new tracker's).
                if ch.scatter.learn(&r.update, p, &ch.unstated) {
                    return ch.retrack(settings, unheard, prior_of).map(Some);
                }
            }
            // The next update starts a new tracker from its bearings.
            Err(_) => ch.tracker = None,
        }
        point.map(Some)
    }

    /// The stations of channel `c` whose noise is estimated and widened, by their index on
    /// the line: how many times their records' noise they scatter, the noise their bearings
    /// now take (radians), and whether they are taken as indoor arrays.
    pub fn widened(&self, c: usize) -> Vec<(u16, f32, f32, bool)> {
        self.channels.get(c).map_or_else(Vec::new, |ch| {
            ch.sources
                .iter()
                .enumerate()
                .map(|(k, s)| {
                    let k = k as u16;
                    let c = &ch.scatter;
                    (*s, c.shown(k), c.tracked(k), c.array(k))
                })
                .filter(|(_, w, _, _)| *w > 1.0)
                .collect()
        })
    }

    /// The line's station index of the one station heard on channel `c` so far, if one alone is.
    pub fn lone_station(&self, c: usize) -> Option<u16> {
        match self.channels.get(c)?.sources.as_slice() {
            [one] => Some(*one),
            _ => None,
        }
    }
}

/// The offset prior of a station not yet heard when its channel's tracker starts: the widest
/// of the priors the stations file states, its device classes' ([`offset_prior`](
/// crate::track::tracks::offset_prior)) and `--offset-sd`'s, centred on zero (a station the
/// file names without a prior has `--offset-sd`'s, or its class's, as a recording gives it).
pub fn unheard(o: &Options) -> BiasPrior {
    let widest = o
        .network
        .iter()
        .flat_map(|n| {
            let classes = n
                .stations
                .iter()
                .map(|s| s.antenna)
                .chain([n.default_antenna]);
            n.stations
                .iter()
                .filter(|s| s.from != PriorFrom::Default)
                .map(|s| s.prior.sd)
                .chain(n.default_prior.map(|p| p.sd))
                .chain(classes.flatten().filter_map(|c| c.track().offset_sd))
        })
        .fold(o.offset_sd, f32::max);
    BiasPrior {
        sd: widest,
        ..o.fallback()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::track::moving::track;
    use foxhunt_core::model::bearing::Bearing;
    use foxhunt_core::track::Motion;

    /// Three stations around an emitter at (1000, 2000) m, each bearing at second `k`.
    fn bearings(seconds: usize) -> Vec<Observation> {
        let emitter = [1000.0f32, 2000.0];
        let stations = [[0.0f32, 0.0], [3000.0, 500.0], [500.0, 4500.0]];
        let mut out = Vec::new();
        for k in 0..seconds {
            for (i, s) in stations.iter().enumerate() {
                let bearing = Bearing {
                    vehicle: *s,
                    theta: (emitter[1] - s[1]).atan2(emitter[0] - s[0]),
                    sigma: 2f32.to_radians(),
                };
                let mut o = Observation::new(bearing, k as f32 + 0.01 * i as f32);
                o.station = 7 + i as u16;
                o.freq_mhz = Some(433.92);
                out.push(o);
            }
        }
        out
    }

    #[test]
    fn a_live_channel_tracks_as_the_recorded_capture_does() {
        let obs = bearings(30);
        let mut settings = Settings::new(
            Layout {
                sources: LIVE_SOURCES,
                rssi: false,
            },
            Motion::OUTDOOR,
        );
        settings.particles = 200;
        let prior = BiasPrior {
            mean: 0.0,
            sd: 2f32.to_radians(),
        };
        let mut live = LiveChannels::new(0.025, settings.clone(), prior);
        let mut points = Vec::new();
        for o in &obs {
            if let Some(r) = live.push(*o, Unstated::Nothing).unwrap() {
                points.push(live.step(r, &|_| prior).unwrap().expect("a point"));
            }
        }
        for r in live.close() {
            points.push(live.step(r, &|_| prior).unwrap().expect("a point"));
        }
        // The same bearings, numbered as the live line numbers its stations, in one call.
        let mut numbered = obs.clone();
        for o in numbered.iter_mut() {
            o.station -= 7;
        }
        let updates = crate::track::updates::bearing_updates(&numbered);
        // A recording's state holds its three stations alone (the live one has room for six):
        // the offsets no bearing reached stay out of the kernel, so the points are the same.
        settings.layout.sources = 3;
        settings.offsets = vec![prior; 3];
        let batch = track(&updates, &settings).unwrap();
        assert_eq!(points.len(), 30, "one point per second's update");
        assert_eq!(points, batch.points, "live and recorded points differ");
        let last = points.last().unwrap().position;
        println!("last point {last:?}");
        assert!((last[0] - 1000.0).hypot(last[1] - 2000.0) < 300.0);
    }

    #[test]
    fn a_channel_heard_by_one_station_has_no_point_until_a_second_is_heard() {
        let mut settings = Settings::new(Layout::default(), Motion::OUTDOOR);
        settings.particles = 200;
        let prior = BiasPrior {
            mean: 0.0,
            sd: 2f32.to_radians(),
        };
        let mut live = LiveChannels::new(0.025, settings, prior);
        let obs = bearings(20);
        let (mut none, mut points) = (0, 0);
        // Ten seconds of station 7 alone, then every station.
        for o in obs.iter().filter(|o| o.time_s >= 10.0 || o.station == 7) {
            if let Some(r) = live.push(*o, Unstated::Nothing).unwrap() {
                match live.step(r, &|_| prior).unwrap() {
                    None => {
                        assert_eq!(live.lone_station(r.channel), Some(7));
                        none += 1;
                    }
                    Some(_) => points += 1,
                }
            }
        }
        assert_eq!(none, 10, "no point while one station is heard");
        assert_eq!(points, 9, "a point for every later update but the open one");
        assert_eq!(live.lone_station(0), None);
    }

    #[test]
    fn one_station_with_rssi_is_tracked_once_a_reading_comes_and_not_before() {
        let mut settings = Settings::new(Layout::default(), Motion::OUTDOOR);
        settings.particles = 200;
        let prior = BiasPrior {
            mean: 0.0,
            sd: 2f32.to_radians(),
        };
        let mut live = LiveChannels::with_rssi(0.025, settings, prior);
        assert_eq!(live.max_stations(), 4, "a state with RSSI terms holds four");
        let obs: Vec<Observation> = bearings(10)
            .into_iter()
            .filter(|o| o.station == 7)
            .collect();
        let mut steps = Vec::new();
        for o in &obs[..5] {
            if let Some(r) = live.push(*o, Unstated::Nothing).unwrap() {
                steps.push(live.step(r, &|_| prior).unwrap().is_some());
            }
        }
        assert_eq!(steps, [false; 4], "one station's bearings alone: no point");
        let level = crate::track::updates::tests::reading([1000.0, 1500.0], -80.0);
        // A reading within the open update's window joins it; later, it opens its own.
        assert!(live.push_level(4.1, level).is_none());
        let r = live
            .push_level(4.5, level)
            .expect("closes the bearing's update");
        assert_eq!(r.update.epoch.levels().len(), 1);
        // The tracker starts from that update, its bearing and reading.
        live.start_region(([1000.0, 1500.0], 500.0));
        assert!(
            live.step(r, &|_| prior).unwrap().is_some(),
            "a reading measures range"
        );
        let r = live
            .push(obs[5], Unstated::Nothing)
            .unwrap()
            .expect("closes the reading's update");
        assert_eq!(r.update.epoch.bearings().len(), 0);
        assert!(live.step(r, &|_| prior).unwrap().is_some());
        // A bearing of another channel is not this line's.
        let mut other = obs[6];
        other.freq_mhz = Some(145.0);
        assert_eq!(live.push(other, Unstated::Nothing), Err(Dropped::Channels));
    }

    #[test]
    fn a_seventh_station_and_a_seventeenth_channel_are_dropped() {
        let settings = Settings::new(Layout::default(), Motion::OUTDOOR);
        let mut live = LiveChannels::new(0.025, settings, BiasPrior::default());
        let mut o = bearings(1)[0];
        for s in 0..u16::from(LIVE_SOURCES) {
            o.station = s;
            assert!(live.push(o, Unstated::Nothing).is_ok());
        }
        assert_eq!(LIVE_SOURCES, 6, "what a recording's state holds");
        o.station = 6;
        assert_eq!(live.push(o, Unstated::Nothing), Err(Dropped::Stations));
        for c in 1..16 {
            o.station = 0;
            o.freq_mhz = Some(100.0 + c as f32);
            assert!(live.push(o, Unstated::Nothing).is_ok());
        }
        o.freq_mhz = Some(300.0);
        assert_eq!(live.push(o, Unstated::Nothing), Err(Dropped::Channels));
        // A bearing within the band of a known channel still lands.
        o.freq_mhz = Some(433.93);
        assert!(live.push(o, Unstated::Nothing).is_ok());
    }
}
