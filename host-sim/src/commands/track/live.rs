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
use crate::estimate::stations::station_setup;
use crate::inputs::capture::{Decoder, LineFeed};
use crate::outputs::cot::{self, CotSender};
use crate::outputs::terminal::{Out, Outcome, Stop, note};
use crate::outputs::tracks;
use crate::track::capture::TrackDecoder;
use crate::track::indoor::AnchorsFile;
use crate::track::live::{Dropped, LIVE_CHANNELS, LIVE_SOURCES, LiveChannels, LiveTracker, Ready};
use crate::track::moving::{Settings, TrackPoint, Update};
use crate::track::tracks::{Options, Tracks, one_station, settings};
use crate::track::updates::{AnchorEpochs, Channel, anchor_positions};
use foxhunt_bridge::BridgeConfig;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::track::{Layout, Motion};
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
    let fallback = BiasPrior {
        mean: 0.0,
        sd: o.offset_sd,
    };
    let mut settings = Settings::new(Layout::default(), o.motion.unwrap_or(Motion::OUTDOOR));
    settings.method = o.method;
    settings.particles = o.particles;
    settings.seed = o.seed;
    settings.memory_s = o.memory_s;
    if let Some(a) = o.accel_sd {
        settings.motion.accel_sd = a;
    }
    let mut live = LiveChannels::new(o.width_mhz, settings, unheard(o, fallback));
    let mut line = reader(&source, None, None)?;
    let mut heard = 0usize;
    let mut points = Points::new(a);
    let mut dropped = [false; 2];
    // Channels said to be heard by one station alone (each said once).
    let mut lone: Vec<usize> = Vec::new();
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
        let mut ready: Vec<Ready> = Vec::new();
        for mut b in new.iter().copied() {
            let station = usize::from(b.station);
            if let Some(s) = o.sigma.or(setup.noise.get(station).copied().flatten()) {
                b.bearing.sigma = s;
            }
            match live.push(b) {
                Ok(r) => ready.extend(r),
                Err(why) => {
                    let k = why as usize;
                    if !dropped[k] {
                        dropped[k] = true;
                        note(&match why {
                            Dropped::Channels => format!(
                                "foxhunt: more than {LIVE_CHANNELS} channels on the line: the \
                                 bearings of later ones are left out"
                            ),
                            Dropped::Stations => format!(
                                "foxhunt: more than {LIVE_SOURCES} stations on a channel: a live \
                                 track follows the first {LIVE_SOURCES} heard, the others' \
                                 bearings are left out"
                            ),
                        });
                    }
                }
            }
        }
        if new.is_empty() || ended {
            ready.extend(live.close());
        }
        let shell = Tracks {
            tracks: Vec::new(),
            frame: dec.decoded.frame,
            first_ms: dec.decoded.first_ms,
        };
        let prior_of = |s: u16| setup.priors.of(usize::from(s));
        for r in ready {
            let point = match live.step(r, &prior_of) {
                Ok(Some(p)) => Ok(p),
                Ok(None) => {
                    if !lone.contains(&r.channel) {
                        lone.push(r.channel);
                        let station = live
                            .lone_station(r.channel)
                            .and_then(|s| dec.decoded.stations.get(usize::from(s)))
                            .map_or("no station", |s| s.id.as_str());
                        points.untracked(r.freq_mhz, &one_station(station));
                    }
                    continue;
                }
                Err(e) => Err(e),
            };
            points.print(&shell, r.freq_mhz, point, out)?;
        }
    }
    points.end(heard, "no bearing on the line: nothing to track")
}

/// Track the RSSI of `file`'s anchors on a byte line (standard input or a serial device, as a
/// ZigBee coordinator's MT frames arrive): the readings grouped into epochs as a recorded
/// capture without GPS times groups them ([`AnchorEpochs`]: an epoch closes when an anchor is
/// heard again, or when the line goes quiet), each epoch a step of one tracker, in the anchors
/// file's metres (latitudes and longitudes with its `origin`).
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
    let shell = Tracks {
        tracks: Vec::new(),
        frame: file.frame(),
        first_ms: None,
    };
    let channel = Channel {
        freq_mhz: None,
        updates: Vec::new(),
        sources: Vec::new(),
        rssi: true,
        left_out: (0, 0),
    };
    let fallback = BiasPrior {
        mean: 0.0,
        sd: o.offset_sd,
    };
    let setup = station_setup(std::iter::empty(), None, fallback, false);
    let mut tracker = None;
    let settings = settings(&channel, Some(file), o, &setup);
    let mut epochs = AnchorEpochs::new(file, anchor_positions(file, None)?);
    let mut dec = TrackDecoder::new(Some(file));
    let mut line = reader(&source, None, None)?;
    let mut points = Points::new(a);
    let (mut heard, mut unknown, mut bearings) = (0usize, 0u32, false);
    let mut ended = false;
    while !ended {
        ended = line.take(&mut dec, quiet_exit, true)?;
        let new = dec.take_readings();
        heard += new.len();
        // Bearings on the same line are not this track's: said once, and not kept.
        let d = dec.bearings();
        d.snapshot();
        if !d.decoded.observations.is_empty() && !std::mem::replace(&mut bearings, true) {
            note(
                "foxhunt: a live line tracks bearings or an anchors file's RSSI, not both: \
                 its bearings are left out (track both from a recorded capture)",
            );
        }
        d.decoded.observations.clear();
        let (skipped, addrs) = dec.unknown();
        if skipped > 0 && unknown == 0 {
            let addrs: Vec<String> = addrs.iter().map(|a| format!("0x{a:04x}")).collect();
            note(&format!(
                "foxhunt: frames from addresses not in the anchors file are skipped: {}",
                addrs.join(", ")
            ));
        }
        unknown = skipped;
        let mut ready: Vec<Update> = new.iter().filter_map(|r| epochs.push(*r)).collect();
        if new.is_empty() || ended {
            ready.extend(epochs.close());
        }
        for u in ready {
            let t = match tracker.as_mut() {
                Some(t) => t,
                None => tracker.insert(LiveTracker::start(settings.clone())?),
            };
            let point = t.step(u);
            if point.is_err() {
                // The next epoch starts a new tracker.
                tracker = None;
            }
            points.print(&shell, None, point, out)?;
        }
    }
    points.end(
        heard,
        "no RSSI reading of a listed anchor on the line: nothing to track",
    )
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

/// The offset prior of a station not yet heard when its channel's tracker starts: the widest
/// of the stations file's and `--offset-sd`'s, centred on zero.
fn unheard(o: &Options, fallback: BiasPrior) -> BiasPrior {
    let widest = o
        .network
        .iter()
        .flat_map(|n| {
            n.stations
                .iter()
                .map(|s| s.prior.sd)
                .chain(n.default_prior.map(|p| p.sd))
        })
        .fold(fallback.sd, f32::max);
    BiasPrior {
        mean: 0.0,
        sd: widest,
    }
}
