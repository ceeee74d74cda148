//! `foxhunt track` on a live line (standard input, a serial device, KrakenSDRs' web pages or
//! an MQTT broker): one line per update as the bearings arrive, the CSV's row or, with
//! `--json`, one object per line. The line is read as `locate` reads it
//! ([`crate::commands::locate::live`]); each channel's updates are stepped by its own
//! tracker ([`crate::track::live`]). An update closes when a bearing comes after its window,
//! or when the line brings nothing new for a moment (so a quiet line's last bearings are
//! tracked at once, not when the next arrive). With an anchors file the line's RSSI is tracked
//! instead ([`rssi`]), an epoch at a time. Memory stays bounded: each bearing and reading
//! leaves the decoder once its tracker has it, and the points are printed, not kept.

use super::Args;
use crate::commands::locate::live::{LiveSource, reader};
use crate::estimate::stations::{StationSetup, station_setup};
use crate::inputs::capture::{Decoder, LineFeed, StationInfo};
use crate::outputs::cot::{self, CotSender};
use crate::outputs::terminal::{Out, Outcome, Stop, note};
use crate::outputs::tracks;
use crate::track::capture::{Reading, TrackDecoder};
use crate::track::indoor::AnchorsFile;
use crate::track::live::{Dropped, LIVE_CHANNELS, LiveChannels, LiveTracker, Ready, unheard};
use crate::track::moving::{Settings, TrackPoint, Update};
use crate::track::noise::array_note;
use crate::track::tracks::{Options, Tracks, offset_prior, one_station, settings, start_region};
use crate::track::updates::{AnchorEpochs, Channel, anchor_positions, level};
use foxhunt_bridge::BridgeConfig;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::observation::Observation;
use foxhunt_core::track::Level;
use std::time::Duration;

/// Track what `source` delivers until it closes (or stays quiet for `quiet_exit`), printing a
/// line per update to `out`.
pub fn run(
    source: LiveSource,
    quiet_exit: Option<Duration>,
    o: &Options,
    a: &Args,
    out: &mut Out,
) -> Outcome {
    let mut dec = Decoder::new(BridgeConfig::default(), false);
    if let LiveSource::Kraken(urls) = &source
        && urls.len() > 1
    {
        // Each unit an input, so one without a STATION_ID is a station of its own.
        for u in urls {
            dec.begin_input(u.base.trim_start_matches("http://"))?;
        }
    }
    let fallback = o.fallback();
    let mut live = LiveChannels::for_options(o);
    let mut line = reader(&source, None, None)?;
    let mut heard = 0usize;
    let mut points = Points::new(a);
    let mut dropped = [false; 2];
    let mut said = Said::default();
    let mut ended = false;
    while !ended {
        ended = line.take(&mut dec, quiet_exit, true)?;
        if ended {
            dec.end();
        }
        // The frame and the stations heard so far, for the points' places and the noise.
        dec.snapshot();
        // Taken out of the decoder, so a line that never ends keeps no bearing it tracked.
        let mut new: Vec<_> = dec.decoded.observations.drain(..).collect();
        heard += new.len();
        new.sort_by(|a, b| a.time_s.total_cmp(&b.time_s));
        // Each station's noise and offset prior from the stations file, else `--sigma`,
        // else the record's own.
        let ids = dec.decoded.stations.iter().map(|s| s.id.as_str());
        let setup = station_setup(ids, o.network.as_ref(), fallback, false);
        let quiet = new.is_empty();
        let mut ready = push_bearings(&mut live, new, o.sigma, &setup, &mut dropped);
        if quiet || ended {
            ready.extend(live.close());
        }
        let shell = Tracks {
            tracks: Vec::new(),
            frame: dec.decoded.frame,
            first_ms: dec.decoded.first_ms,
        };
        let stations = &dec.decoded.stations;
        step_all(
            &mut live,
            ready,
            &setup,
            stations,
            &mut said,
            &mut points,
            &shell,
            out,
        )?;
    }
    points.end(heard, "no bearing on the line: nothing to track")
}

/// Track the RSSI of `file`'s anchors on a byte line (standard input or a serial device, as a
/// ZigBee coordinator's MT frames arrive), the way the line's first measurement says:
/// - readings without a GPS time (a coordinator's line alone): grouped into epochs as a
///   recorded capture without GPS times groups them ([`AnchorEpochs`]: an epoch closes when an
///   anchor is heard again, or when the line goes quiet), each epoch a step of one tracker, in
///   the anchors file's metres (latitudes and longitudes with its `origin`); bearings on such a
///   line are left out (said once);
/// - a line with GPS fixes (a DF unit's, the coordinator's frames beside): each reading timed
///   by the fix before it and the bearings of the first channel heard join one tracker's
///   updates in one time order, as a recorded capture's do ([`Timed`]).
pub fn rssi(
    source: LiveSource,
    quiet_exit: Option<Duration>,
    o: &Options,
    a: &Args,
    file: &AnchorsFile,
    out: &mut Out,
) -> Outcome {
    if !matches!(source, LiveSource::Stdin | LiveSource::Serial { .. }) {
        return Err(Stop::usage(
            "RSSI comes in a coordinator's MT frames: track it live from standard input or a \
             serial device, not --kraken or --mqtt",
        ));
    }
    let fallback = o.fallback();
    let mut dec = TrackDecoder::new(Some(file));
    let mut line = reader(&source, None, None)?;
    let mut points = Points::new(a);
    let mut mode: Option<Mode> = None;
    let (mut heard, mut unknown) = (0usize, 0u32);
    let mut ended = false;
    while !ended {
        ended = line.take(&mut dec, quiet_exit, true)?;
        let readings = dec.take_readings();
        let d = dec.bearings();
        if ended {
            d.end();
        }
        d.snapshot();
        // Taken out of the decoder, so a line that never ends keeps none it tracked.
        let bearings: Vec<Observation> = d.decoded.observations.drain(..).collect();
        heard += readings.len() + bearings.len();
        let (skipped, addrs) = dec.unknown();
        if skipped > 0 && unknown == 0 {
            let addrs: Vec<String> = addrs.iter().map(|a| format!("0x{a:04x}")).collect();
            note(&format!(
                "foxhunt: frames from addresses not in the anchors file are skipped: {}",
                addrs.join(", ")
            ));
        }
        unknown = skipped;
        let timed = !bearings.is_empty() || readings.iter().any(|r| r.after_fix_ms.is_some());
        if mode.is_none() && (timed || !readings.is_empty()) {
            mode = Some(if timed {
                Mode::Timed(Box::new(Timed::new(file, o, fallback)))
            } else {
                Mode::Epochs(Box::new(Epochs::new(file, o, fallback)?))
            });
        }
        let quiet = readings.is_empty() && bearings.is_empty();
        match mode.as_mut() {
            Some(Mode::Epochs(e)) => e.take(
                readings,
                !bearings.is_empty(),
                quiet || ended,
                &mut points,
                out,
            )?,
            Some(Mode::Timed(t)) => {
                let d = dec.bearings();
                t.take(d, readings, bearings, quiet || ended, &mut points, out)?
            }
            None => {}
        }
    }
    points.end(
        heard,
        "no RSSI reading of a listed anchor on the line: nothing to track",
    )
}

/// How a line with an anchors file is tracked, as its first measurement says.
enum Mode<'a> {
    /// Readings without GPS times, in epochs.
    Epochs(Box<Epochs>),
    /// Readings and bearings by their GPS times.
    Timed(Box<Timed<'a>>),
}

/// RSSI without GPS times: one tracker stepped an epoch at a time.
struct Epochs {
    epochs: AnchorEpochs,
    settings: Settings,
    tracker: Option<LiveTracker>,
    shell: Tracks,
    /// Whether the line's bearings were said to be left out.
    said: bool,
}

impl Epochs {
    fn new(file: &AnchorsFile, o: &Options, fallback: BiasPrior) -> Result<Self, Stop> {
        let at = anchor_positions(file, None)?;
        let channel = Channel {
            freq_mhz: None,
            updates: Vec::new(),
            sources: Vec::new(),
            rssi: true,
            anchors: at.clone(),
            left_out: (0, 0),
        };
        let setup = station_setup(std::iter::empty(), None, fallback, false);
        Ok(Self {
            epochs: AnchorEpochs::new(file, at),
            settings: settings(&channel, Some(file), o, &setup),
            tracker: None,
            shell: Tracks {
                tracks: Vec::new(),
                frame: file.frame(),
                first_ms: None,
            },
            said: false,
        })
    }

    /// Step the epochs `readings` close (all when `close`); `bearings`: the chunk had some.
    fn take(
        &mut self,
        readings: Vec<Reading>,
        bearings: bool,
        close: bool,
        points: &mut Points,
        out: &mut Out,
    ) -> Outcome {
        if bearings && !std::mem::replace(&mut self.said, true) {
            note(
                "foxhunt: the line's RSSI readings have no GPS time to put bearings beside: \
                 its bearings are left out (a line with GPS fixes tracks both)",
            );
        }
        let mut ready: Vec<Update> = readings
            .iter()
            .filter_map(|r| self.epochs.push(*r))
            .collect();
        if close {
            ready.extend(self.epochs.close());
        }
        for u in ready {
            let t = match self.tracker.as_mut() {
                Some(t) => t,
                None => self
                    .tracker
                    .insert(LiveTracker::start(self.settings.clone())?),
            };
            let point = t.step(u);
            if point.is_err() {
                // The next epoch starts a new tracker.
                self.tracker = None;
            }
            points.print(&self.shell, None, point, out)?;
        }
        Ok(())
    }
}

/// A line with GPS fixes: the anchors' readings, each timed by the fix before it, and the
/// bearings of the first channel heard, in one tracker ([`LiveChannels::with_rssi`]), in the
/// line's GPS frame (the anchors file's `origin` places its anchors there).
struct Timed<'a> {
    o: &'a Options,
    live: LiveChannels,
    file: AnchorsFile,
    /// The anchors in the line's frame, once it has one.
    at: Option<Vec<[f32; 2]>>,
    /// Bridge time of the track's zero, ms: the first bearing's when the line's first timed
    /// measurements hold one (as a recorded capture's), else the first reading's fix.
    base_ms: Option<i64>,
    dropped: [bool; 2],
    said: Said,
    /// Whether readings before the first fix were said to be left out.
    untimed: bool,
    fallback: BiasPrior,
}

impl<'a> Timed<'a> {
    fn new(file: &AnchorsFile, o: &'a Options, fallback: BiasPrior) -> Self {
        // A channel of bearings and RSSI, as a recording's: its settings are those of one.
        let channel = Channel {
            freq_mhz: None,
            updates: Vec::new(),
            sources: vec![0],
            rssi: true,
            anchors: Vec::new(),
            left_out: (0, 0),
        };
        let setup = station_setup(std::iter::empty(), None, fallback, false);
        let s = settings(&channel, Some(file), o, &setup);
        Self {
            o,
            live: LiveChannels::with_rssi(o.width_mhz, s, unheard(o)),
            file: file.clone(),
            at: None,
            base_ms: None,
            dropped: [false; 2],
            said: Said::default(),
            untimed: false,
            fallback,
        }
    }

    /// Step what `readings` and `bearings` (of decoder `d`) close, all when `close`.
    fn take(
        &mut self,
        d: &mut Decoder,
        readings: Vec<Reading>,
        bearings: Vec<Observation>,
        close: bool,
        points: &mut Points,
        out: &mut Out,
    ) -> Outcome {
        let first_ms = d.decoded.first_ms;
        if self.base_ms.is_none() {
            self.base_ms = match bearings.is_empty() {
                false => first_ms,
                true => readings.iter().find_map(|r| r.after_fix_ms),
            };
        }
        let Some(base) = self.base_ms else {
            return Ok(());
        };
        if self.at.is_none() && !readings.is_empty() && d.decoded.frame.is_some() {
            let at = anchor_positions(&self.file, d.decoded.frame.as_ref())?;
            // A tracker whose first update holds readings alone starts about the anchors.
            self.live.start_region(start_region(None, &at));
            self.at = Some(at);
        }
        // Bearings in the track's time (theirs counts from the first bearing), and readings.
        let shift = first_ms.map_or(0.0, |f| (f - base) as f32 / 1000.0);
        let mut all: Vec<(f32, Result<Observation, Level>)> = bearings
            .into_iter()
            .map(|mut b| {
                b.time_s += shift;
                (b.time_s, Ok(b))
            })
            .collect();
        for r in &readings {
            match (r.after_fix_ms, self.at.as_deref()) {
                (Some(ms), Some(at)) => {
                    let t = (ms - base) as f32 / 1000.0;
                    all.push((t, Err(level(&self.file, at, r))));
                }
                _ if !std::mem::replace(&mut self.untimed, true) => note(
                    "foxhunt: RSSI readings before the line's first GPS fix have no time: \
                     they are left out",
                ),
                _ => {}
            }
        }
        // Stable: at equal times the bearings first, as a recorded capture merges them.
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        let ids = d.decoded.stations.iter().map(|s| s.id.as_str());
        let setup = station_setup(ids, self.o.network.as_ref(), self.fallback, false);
        let mut ready = Vec::new();
        for (t, m) in all {
            match m {
                Ok(b) => ready.extend(push_bearing(
                    &mut self.live,
                    b,
                    self.o.sigma,
                    &setup,
                    &mut self.dropped,
                )),
                Err(l) => ready.extend(self.live.push_level(t, l)),
            }
        }
        if close {
            ready.extend(self.live.close());
        }
        let shell = Tracks {
            tracks: Vec::new(),
            frame: d.decoded.frame,
            first_ms: Some(base),
        };
        let stations = &d.decoded.stations;
        step_all(
            &mut self.live,
            ready,
            &setup,
            stations,
            &mut self.said,
            points,
            &shell,
            out,
        )
    }
}

/// Push `new` bearings (time order) to `live` ([`push_bearing`]): the updates they closed.
fn push_bearings(
    live: &mut LiveChannels,
    new: Vec<Observation>,
    sigma: Option<f32>,
    setup: &StationSetup,
    dropped: &mut [bool; 2],
) -> Vec<Ready> {
    new.into_iter()
        .filter_map(|b| push_bearing(live, b, sigma, setup, dropped))
        .collect()
}

/// Push bearing `b` to `live` with its station's noise (`sigma`, else the stations file's,
/// else the record's own, then estimated) and its stated direction-dependent error taken out,
/// saying once of each kind what was left out: the
/// update it closed.
fn push_bearing(
    live: &mut LiveChannels,
    b: Observation,
    sigma: Option<f32>,
    setup: &StationSetup,
    dropped: &mut [bool; 2],
) -> Option<Ready> {
    match live.push_stated(b, sigma, setup) {
        Ok(r) => r,
        Err(why) => {
            let k = why as usize;
            if !dropped[k] {
                dropped[k] = true;
                note(&match why {
                    Dropped::Channels if live.rssi() => "foxhunt: a live line with an anchors \
                             file tracks one emitter, its RSSI and the bearings of the first \
                             channel heard: the bearings of other channels are left out"
                        .to_string(),
                    Dropped::Channels => format!(
                        "foxhunt: more than {LIVE_CHANNELS} channels on the line: the \
                             bearings of later ones are left out"
                    ),
                    Dropped::Stations => format!(
                        "foxhunt: more than {} stations on a channel: a live track \
                             follows the first {} heard, the others' bearings are left out",
                        live.max_stations(),
                        live.max_stations()
                    ),
                });
            }
            None
        }
    }
}

/// What a live line says once.
#[derive(Debug, Default)]
struct Said {
    /// Channels heard by one station alone.
    lone: Vec<usize>,
    /// Stations (channel, line index, taken as an indoor array) whose noise was estimated
    /// wider than their records'.
    widened: Vec<(usize, u16, bool)>,
}

/// Step each of `ready` with its channel's tracker and print its point; a channel heard by
/// one station alone is said once and has no point, a station whose noise is estimated wider
/// than its records' is said once.
#[allow(clippy::too_many_arguments)]
fn step_all(
    live: &mut LiveChannels,
    ready: Vec<Ready>,
    setup: &StationSetup,
    stations: &[StationInfo],
    said: &mut Said,
    points: &mut Points,
    shell: &Tracks,
    out: &mut Out,
) -> Outcome {
    let prior_of = |s: u16| offset_prior(setup, usize::from(s));
    for r in ready {
        let point = match live.step(r, &prior_of) {
            Ok(Some(p)) => Ok(p),
            Ok(None) => {
                if !said.lone.contains(&r.channel) {
                    said.lone.push(r.channel);
                    let station = live
                        .lone_station(r.channel)
                        .and_then(|s| stations.get(usize::from(s)))
                        .map_or("no station", |s| s.id.as_str());
                    points.untracked(r.freq_mhz, &one_station(station));
                }
                continue;
            }
            Err(e) => Err(e),
        };
        for (station, w, tracked, array) in live.widened(r.channel) {
            if !said.widened.contains(&(r.channel, station, array)) {
                said.widened.push((r.channel, station, array));
                let id = stations
                    .get(usize::from(station))
                    .map_or("a station", |s| s.id.as_str());
                let on = r
                    .freq_mhz
                    .map_or(String::new(), |f| format!(" on {f:.3} MHz"));
                note(&format!(
                    "foxhunt: {id}'s bearings scatter {w:.1} times their records' noise about \
                     the track{on}: from here they take {:.1} deg, estimated (--sigma or the \
                     stations file's noise_deg states it){}{}",
                    tracked.to_degrees(),
                    array_note(array),
                    if array {
                        "; the channel's updates are tracked again with it taken as such"
                    } else {
                        ""
                    },
                ));
            }
        }
        points.print(shell, r.freq_mhz, point, out)?;
    }
    Ok(())
}

/// Where a live track's points go: standard output (the CSV's row, or with `--json` one
/// object a line) and TAK; and why none did.
struct Points {
    json: bool,
    tak: Option<CotSender>,
    printed: usize,
    failed: Option<String>,
}

impl Points {
    fn new(a: &Args) -> Self {
        Self {
            json: a.json,
            tak: a.cot.clone().map(CotSender::new),
            printed: 0,
            failed: None,
        }
    }

    /// Say once that the channel on `freq_mhz` is not tracked, and `why` (also the line's
    /// error if no point is printed).
    fn untracked(&mut self, freq_mhz: Option<f32>, why: &str) {
        let what = freq_mhz.map_or(String::new(), |f| format!(" on {f:.3} MHz"));
        let e = format!("no track{what} yet: {why}");
        note(&format!("foxhunt: {e}"));
        self.failed.get_or_insert(e);
    }

    /// Print `point` of the channel on `freq_mhz`, or say why the update has none.
    fn print(
        &mut self,
        shell: &Tracks,
        freq_mhz: Option<f32>,
        point: Result<TrackPoint, String>,
        out: &mut Out,
    ) -> Outcome {
        let p = match point {
            Ok(p) => p,
            Err(e) => {
                let what = freq_mhz.map_or(String::new(), |f| format!(" on {f:.3} MHz"));
                let e = format!("cannot track{what}: {e}");
                note(&format!("foxhunt: {e}"));
                self.failed = Some(e);
                return Ok(());
            }
        };
        if self.printed == 0 && !self.json {
            out.line(tracks::CSV_HEADER)?;
        }
        self.printed += 1;
        let text = if self.json {
            tracks::live_point(shell, freq_mhz, &p).to_string()
        } else {
            tracks::csv_line(shell, freq_mhz, &p).trim_end().to_string()
        };
        out.line(&text)?;
        out.flush()?;
        // TAK missing an update is no reason to stop tracking: the next one sends the latest
        // point again.
        if let (Some(tak), Some(frame)) = (self.tak.as_mut(), shell.frame.as_ref())
            && let Err(e) = tak.send(&cot::track_events(
                freq_mhz,
                &p,
                frame,
                std::time::SystemTime::now(),
            ))
        {
            note(&format!("foxhunt: {e}; this update not sent"));
        }
        Ok(())
    }

    /// The line is done: fine if a point was printed, else why none was (`nothing`: when the
    /// line brought no measurement, `heard` of them).
    fn end(self, heard: usize, nothing: &str) -> Outcome {
        if self.printed > 0 {
            return Ok(());
        }
        Err(Stop::Error(self.failed.unwrap_or_else(|| {
            if heard == 0 {
                nothing.into()
            } else {
                "no update could be tracked".into()
            }
        })))
    }
}
