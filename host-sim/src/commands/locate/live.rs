//! `foxhunt locate` on a live line (a serial device, or standard input fed by `cat
//! /dev/ttyUSB0 | foxhunt locate -`): the fix is updated as the bytes arrive.
//!
//! A reader thread hands the bytes over in chunks as the line delivers them; the decoder takes
//! every chunk already waiting, then, if new bearings arrived, recomputes the fix and prints
//! one line (a JSON object with `--json`): the fix, or why there is none yet (`{"used": n,
//! "error": "..."}`), with the guidance advice (where to drive next and why, or "good enough"
//! when the stop rule holds; [`crate::guidance::guide`]). A slow line gets an update per bearing; a fast pipe
//! gets one per batch, so a replayed hour of bearings costs a few solves, not one per bearing.
//! When no byte comes for 100 ms the demultiplexer is told the line is idle (a frame waiting
//! on look-ahead is delivered), and `--quiet-exit` counts from the last byte.
//!
//! The bearings' line may be a KrakenSDR's web page ([`crate::inputs::kraken_http`]: its new whole
//! records are the line's bytes), and positions and headings may come from gpsd beside it
//! ([`crate::inputs::gpsd`]: its reports become sentences pushed into the same bridge between the
//! line's chunks). Either way only new bearings make an update line, or a new `$PFOXF` of a DF
//! unit running foxhunt's firmware: every line (`--json`: `unit`, also when there is no fix
//! yet) carries what the unit said ([`crate::inputs::unit`]).

use super::window::{ChannelWindow, PER_STATION, Pending};
use crate::estimate::options::LocateOptions;
use crate::estimate::pool;
use crate::guidance::guide::Guide;
use crate::inputs::capture::{Decoded, Decoder, LineFeed};
use crate::inputs::gpsd::{GpsdAddress, Report, Watch};
use crate::inputs::kraken_http::KrakenUrl;
use crate::inputs::mqtt::{Handed, MqttUrl, Shard, Subscription, channel_name};
use crate::locate::locate_guided;
use crate::locate::report::{Located, NoFix};
use crate::outputs::cot::{self, CotSender, CotUrl};
use crate::outputs::history::recorder::Recorder;
use crate::outputs::terminal::{Out, Stop, note};
use foxhunt_bridge::BridgeConfig;
use foxhunt_bridge::Frame;
use foxhunt_bridge::kraken::KrakenXml;
use foxhunt_core::fix::locate::Observation;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::io::{ErrorKind, Read};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// Where live bytes come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum LiveSource {
    /// A serial device at a baud rate.
    Serial {
        /// Device path.
        path: String,
        /// Baud rate.
        baud: u32,
    },
    /// Standard input.
    Stdin,
    /// KrakenSDRs' web servers, all polled at once; each URL is an input of its own.
    Kraken(Vec<KrakenUrl>),
    /// Every station's bearings through an MQTT broker, on a persistent session of this
    /// client id.
    Mqtt {
        /// The broker and the topics' prefix.
        url: MqttUrl,
        /// The session's client id.
        client_id: String,
        /// This worker's share of the channels (`None`: all of them).
        shard: Option<Shard>,
        /// Bearings kept per channel, the latest ([`super::window`]).
        keep: usize,
    },
}

/// How to read a live line.
#[derive(Debug, Clone)]
pub struct LiveOptions {
    /// The line.
    pub source: LiveSource,
    /// A gpsd giving positions and headings beside the line.
    pub gpsd: Option<GpsdAddress>,
    /// Stop after this long without a byte (`None`: read until the line closes).
    pub quiet_exit: Option<Duration>,
    /// How fixes are computed.
    pub locate: LocateOptions,
    /// Print updates as JSON lines.
    pub json: bool,
    /// Keep the vehicle track (for maps at the end).
    pub keep_track: bool,
    /// Send every fix to TAK.
    pub cot: Option<CotUrl>,
    /// Keep every bearing and update there, and resume from what it holds.
    pub history: Option<Recorder>,
}

/// A read's outcome, sent from the reader thread.
enum Chunk {
    Bytes(Vec<u8>),
    /// Whole records from live input `0` (one of several KrakenSDRs).
    From(u8, Vec<u8>),
    /// Sentence bodies from gpsd.
    Sentences(Vec<String>),
    /// Bearings from the broker, as the records the bridge places.
    Records(Vec<KrakenXml>),
    End,
    Failed(String),
}

/// How long a read waits before the line counts as idle.
const IDLE: Duration = Duration::from_millis(100);
/// At the end, how long the broker has to acknowledge the last fixes.
const FIX_WAIT: Duration = Duration::from_secs(5);

/// Start the thread that polls KrakenSDR `input`: each poll's new records are a chunk.
fn kraken(input: u8, url: &KrakenUrl, tx: mpsc::SyncSender<Chunk>) -> Result<(), String> {
    let url = url.clone();
    std::thread::Builder::new()
        .name(format!("foxhunt-kraken-{input}"))
        .spawn(move || {
            crate::inputs::kraken_http::poll(
                &url,
                |p| p.records.is_empty() || tx.send(Chunk::From(input, p.records)).is_ok(),
                note,
            )
        })
        .map(|_| ())
        .map_err(|e| format!("cannot start the KrakenSDR poller: {e}"))
}

/// Connect to gpsd (an error now is the command's error) and start the thread that reads it.
fn gpsd(addr: &GpsdAddress, tx: mpsc::SyncSender<Chunk>) -> Result<(), String> {
    let watch = Watch::connect(addr)?;
    let name = addr.to_string();
    std::thread::Builder::new()
        .name("foxhunt-gpsd".into())
        .spawn(move || {
            let (mut malformed, mut open) = (0u32, true);
            let r = watch.run(|r| match r {
                Report::Sentences(v) => {
                    open = tx.send(Chunk::Sentences(v)).is_ok();
                    open
                }
                Report::Malformed => {
                    malformed += 1;
                    true
                }
                Report::NoFix | Report::Other => true,
            });
            if open {
                let why = r.err().unwrap_or_else(|| "closed the connection".into());
                note(&format!(
                    "gpsd at {name}: {why}; no more positions from it ({malformed} malformed \
                     reports skipped)"
                ));
            }
        })
        .map(|_| ())
        .map_err(|e| format!("cannot start the gpsd reader: {e}"))
}

/// A live line being read: its chunks as the reader threads hand them over.
pub struct LiveLine {
    rx: mpsc::Receiver<Chunk>,
    last_byte: Instant,
    /// The broker's session, when the bearings come through one.
    pub mqtt: Option<Subscription>,
}

/// Start the threads that read the line (and gpsd); the broker's bearings go to `history`
/// before they are acknowledged.
pub fn reader(
    source: &LiveSource,
    gpsd_at: Option<&GpsdAddress>,
    history: Option<Recorder>,
) -> Result<LiveLine, String> {
    let (tx, rx) = mpsc::sync_channel::<Chunk>(16);
    let line = |rx, mqtt| LiveLine {
        rx,
        last_byte: Instant::now(),
        mqtt,
    };
    if let Some(addr) = gpsd_at {
        gpsd(addr, tx.clone())?;
    }
    let (mut port, name): (Box<dyn Read + Send>, String) = match source {
        LiveSource::Serial { path, baud } => (
            serialport::new(path, *baud)
                .timeout(IDLE)
                .open()
                .map_err(|e| format!("cannot open {path} at {baud} baud: {e}"))?,
            path.clone(),
        ),
        LiveSource::Stdin => (Box::new(std::io::stdin()), "standard input".into()),
        LiveSource::Kraken(urls) => {
            for (i, url) in urls.iter().enumerate() {
                let i = u8::try_from(i).map_err(|_| "at most 256 --kraken URLs".to_string())?;
                kraken(i, url, tx.clone())?;
            }
            return Ok(line(rx, None));
        }
        LiveSource::Mqtt {
            url,
            client_id,
            shard,
            ..
        } => {
            let sub = Subscription::start(
                url,
                client_id,
                *shard,
                move |v, wait| match wait {
                    true => match tx.send(Chunk::Records(v)) {
                        Ok(()) => Handed::Yes,
                        Err(_) => Handed::Closed,
                    },
                    false => match tx.try_send(Chunk::Records(v)) {
                        Ok(()) => Handed::Yes,
                        Err(mpsc::TrySendError::Full(Chunk::Records(v))) => Handed::Busy(v),
                        Err(_) => Handed::Closed,
                    },
                },
                move |m| history.as_ref().is_none_or(|h| h.keep(m)),
                note,
            )?;
            return Ok(line(rx, Some(sub)));
        }
    };
    std::thread::Builder::new()
        .name("foxhunt-line".into())
        .spawn(move || {
            let mut buf = vec![0u8; 4096];
            loop {
                let msg = match port.read(&mut buf) {
                    Ok(0) => Chunk::End,
                    Ok(n) => Chunk::Bytes(buf[..n].to_vec()),
                    Err(e) if matches!(e.kind(), ErrorKind::TimedOut | ErrorKind::WouldBlock) => {
                        continue;
                    }
                    Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                    // A hung-up pseudo-terminal or unplugged adapter ends the stream.
                    Err(e) if e.kind() == ErrorKind::BrokenPipe || e.raw_os_error() == Some(5) => {
                        Chunk::End
                    }
                    Err(e) => Chunk::Failed(format!("reading {name}: {e}")),
                };
                let last = !matches!(msg, Chunk::Bytes(_));
                if tx.send(msg).is_err() || last {
                    return;
                }
            }
        })
        .map_err(|e| format!("cannot start the reader: {e}"))?;
    Ok(line(rx, None))
}

impl LiveLine {
    /// Block for the first chunk (or the idle timeout), then feed `dec` all that is waiting;
    /// whether the line ended (closed, or quiet for `quiet_exit`). Without `block`, only what
    /// is already waiting (nothing waiting is not the line being idle).
    pub fn take(
        &mut self,
        dec: &mut impl LineFeed,
        quiet_exit: Option<Duration>,
        block: bool,
    ) -> Result<bool, Stop> {
        let mut next = if block {
            self.rx.recv_timeout(IDLE)
        } else {
            match self.rx.try_recv() {
                Ok(c) => Ok(c),
                Err(mpsc::TryRecvError::Empty) => return Ok(false),
                Err(mpsc::TryRecvError::Disconnected) => Err(mpsc::RecvTimeoutError::Disconnected),
            }
        };
        loop {
            match next {
                Ok(Chunk::Bytes(b)) => {
                    self.last_byte = Instant::now();
                    dec.feed(&b);
                }
                Ok(Chunk::From(i, b)) => {
                    self.last_byte = Instant::now();
                    dec.bearings().switch_input(i);
                    dec.feed(&b);
                }
                Ok(Chunk::Records(v)) => {
                    self.last_byte = Instant::now();
                    for r in v {
                        dec.bearings().push_frame(&Frame::KrakenXml(r));
                    }
                }
                Ok(Chunk::Sentences(v)) => {
                    for s in &v {
                        dec.bearings().push_sentence(s);
                    }
                }
                Ok(Chunk::End) | Err(mpsc::RecvTimeoutError::Disconnected) => return Ok(true),
                Ok(Chunk::Failed(e)) => return Err(Stop::Error(e)),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    dec.idle();
                    return Ok(quiet_exit.is_some_and(|q| self.last_byte.elapsed() >= q));
                }
            }
            next = match self.rx.try_recv() {
                Ok(c) => Ok(c),
                Err(mpsc::TryRecvError::Empty) => return Ok(false),
                Err(mpsc::TryRecvError::Disconnected) => Err(mpsc::RecvTimeoutError::Disconnected),
            };
        }
    }
}

/// Each channel's bearings (`channels`, by key, of the observations `d` holds) located on
/// its own, side by side on the thread pool, each with the rest of `d` and a copy of `guide`
/// (a channel's fix does not depend on what else its worker fuses: the same on one worker as
/// on a shard); `d` is left as it came.
fn each_channel(
    d: &mut Decoded,
    channels: Vec<(i64, Vec<Observation>)>,
    o: &LocateOptions,
    guide: &Guide,
) -> Vec<(i64, Result<Located, Box<NoFix>>)> {
    let all = std::mem::take(&mut d.observations);
    let rest = &*d;
    let located = pool().install(|| {
        channels
            .into_par_iter()
            .map(|(key, observations)| {
                let one = Decoded {
                    observations,
                    ..rest.clone()
                };
                (key, locate_guided(&one, o, &mut guide.clone()))
            })
            .collect()
    });
    d.observations = all;
    located
}

/// How a live line ended.
#[derive(Debug)]
pub struct LiveEnd {
    /// Everything decoded (for the maps and the statistics).
    pub decoded: Decoded,
    /// Why the last update had no fix (`None`: it had one; a broker's network: some channel's
    /// last update had one).
    pub no_fix: Option<String>,
}

/// Read the line until it closes or stays quiet, printing each updated fix and `guide`'s advice
/// to `out`: a line per update, and one at the end if the line brought nothing to update on
/// (why there is no fix). What was decoded, and whether the last update had a fix.
pub fn run(o: &LiveOptions, guide: &mut Guide, out: &mut Out) -> Result<LiveEnd, Stop> {
    o.locate.check()?;
    // A broker's bearings were judged on their stations' clocks where they were decoded
    // (`foxhunt publish`): they pass as they come, each channel's put in time order before
    // its solve ([`Pending::next`]).
    let broker = matches!(o.source, LiveSource::Mqtt { .. });
    let config = BridgeConfig {
        judged_clocks: broker,
        ..BridgeConfig::default()
    };
    let mut dec = Decoder::new(config, o.keep_track);
    // Several KrakenSDRs: each URL an input, so a unit without a STATION_ID is a station of
    // its own.
    if let LiveSource::Kraken(urls) = &o.source
        && urls.len() > 1
    {
        for u in urls {
            dec.begin_input(u.base.trim_start_matches("http://"))?;
        }
    }
    o.locate.survey(&mut dec);
    // The history's bearings first, before the line starts: a bearing the broker delivers now
    // is stored and handed on once, after them. The broker's messages are stored as they
    // come, every other source's bearings from the decoder.
    let mut stamper = None;
    if let Some(h) = &o.history {
        h.resume(&mut dec)?;
        if !matches!(o.source, LiveSource::Mqtt { .. }) {
            stamper = Some(h.stamper(&mut dec));
        }
    }
    let mut line = reader(&o.source, o.gpsd.as_ref(), o.history.clone())?;
    let mut tak = o.cot.clone().map(CotSender::new);
    // A broker's bearings: each channel's latest kept.
    let mut window = match &o.source {
        LiveSource::Mqtt { keep, .. } => Some(ChannelWindow::new(*keep)),
        _ => None,
    };
    let mut reported = (0u64, 0u32);
    let mut ended = false;
    // Each channel's last update's outcome (why it had no fix; `None`: it had one), by its
    // key; empty until one is printed.
    let mut last: BTreeMap<i64, Option<String>> = BTreeMap::new();
    let mut updates = 0u64;
    // A broker's channels waiting for a solve, and the bearings already counted in them.
    let mut pending = Pending::default();
    let mut seen = 0usize;
    let width = o.locate.channel_width_mhz;
    while !ended || !pending.is_empty() {
        if !ended {
            // With channels waiting, only what has arrived meanwhile: the next solve is due.
            ended = line.take(&mut dec, o.quiet_exit, pending.is_empty())?;
            if ended {
                // Bearings still waiting for a later fix are placed with the fixes there are.
                dec.end();
            }
        }
        if let (Some(h), Some(stamper)) = (&o.history, stamper.as_mut()) {
            h.keep_decoded(stamper, &mut dec);
        }
        // New bearings, or a new fix sentence of a DF unit (its user port carries no bearings);
        // counted before the window drops the oldest.
        let dropped = window.as_ref().map_or(0, |w| w.dropped);
        let n = (
            dropped + dec.decoded.observations.len() as u64,
            dec.decoded.unit.fixes,
        );
        // A broker's network is solved a channel at a time, the longest-waiting first
        // ([`Pending`]), as many at once as there are cores; any other line's bearings all at
        // once.
        let mut channels = Vec::new();
        if let Some(w) = window.as_mut() {
            let new = dec.decoded.observations.get(seen..).unwrap_or(&[]);
            pending.arrived(new, Instant::now());
            w.trim(&mut dec.decoded.observations);
            for (key, stations) in w.crowded() {
                let channel = match key {
                    k if k >= 0 => format!("channel {} MHz", channel_name(Some(k as f64 / 1e3))),
                    _ => "the bearings without a frequency".into(),
                };
                note(&format!(
                    "{channel}: its window of {} bearings (--mqtt-keep) filled with {stations} \
                     stations' bearings: each station's offset takes about one, too few are \
                     left to estimate the noise; keep at least {}",
                    w.keep(),
                    PER_STATION * stations
                ));
            }
            seen = dec.decoded.observations.len();
            for _ in 0..pool().current_num_threads() {
                channels.extend(pending.next(&dec.decoded.observations, width));
            }
        }
        let due = match window {
            Some(_) => !channels.is_empty(),
            None => n != reported,
        };
        // New bearings (or a unit's fix) make an update; a line that ends without any makes
        // one too, so that it says why there is no fix.
        if !(due || (ended && last.is_empty())) {
            continue;
        }
        reported = n;
        dec.snapshot();
        // Each update's channel key (-1: every channel at once).
        let located: Vec<(i64, _)> = if channels.is_empty() {
            let mut l = locate_guided(&dec.decoded, &o.locate, guide);
            // A worker the broker gave no bearing: that is why, not what a capture lacks.
            if let (Some(sub), Err(e)) = (&line.mqtt, &mut l)
                && count(&sub.counts.bearings) == 0
            {
                e.error = match count(&sub.counts.refused) {
                    0 => format!(
                        "no bearing came through the broker on {}: nothing to fuse",
                        sub.filter()
                    ),
                    r => format!(
                        "no usable bearing came through the broker on {}: {r} messages \
                         refused (the notes say why)",
                        sub.filter()
                    ),
                };
            }
            vec![(-1, l)]
        } else {
            each_channel(&mut dec.decoded, channels, &o.locate, guide)
        };
        for (key, located) in located {
            updates += 1;
            // TAK missing an update is no reason to stop following the emitter: the next
            // update sends the whole picture again.
            if let (Some(tak), Ok(l)) = (tak.as_mut(), &located)
                && let Err(e) =
                    tak.send(&cot::events(l, &dec.decoded, std::time::SystemTime::now()))
            {
                note(&format!("{e}; this update not sent"));
            }
            let text = match (&located, o.json) {
                (Ok(l), true) => serde_json::to_string(&l.report).map_err(|e| e.to_string())?,
                (Ok(l), false) => l.report.update_line(),
                (Err(e), true) => serde_json::to_string(e).map_err(|e| e.to_string())?,
                (Err(e), false) => e.line(),
            };
            if let (Some(sub), Ok(l)) = (&line.mqtt, &located) {
                for e in &l.report.emitters {
                    let json = serde_json::to_string(e).map_err(|e| e.to_string())?;
                    sub.publish_fix(&channel_name(e.freq_mhz.map(f64::from)), json);
                }
            }
            if let Some(h) = &o.history {
                h.keep_update(&located);
            }
            last.insert(key, located.err().map(|e| e.error));
            out.line(&text)?;
            out.flush()?;
        }
    }
    if let Some(sub) = &line.mqtt {
        if !sub.close(FIX_WAIT) {
            note("the MQTT broker did not acknowledge every fix before the end");
        }
        let c = &sub.counts;
        note(&format!(
            "mqtt: bearings {}, duplicates {}, refused {}, other shard {}, fixes {}, updates {}, \
             dropped past the window {}",
            count(&c.bearings),
            count(&c.duplicates),
            count(&c.refused),
            count(&c.misrouted),
            count(&c.fixes_acked),
            updates,
            window.as_ref().map_or(0, |w| w.dropped)
        ));
    }
    Ok(LiveEnd {
        decoded: dec.finish(),
        // A fix on any channel is a fix; else why the last update had none.
        no_fix: match last.values().any(Option::is_none) {
            true => None,
            false => last.into_values().flatten().last(),
        },
    })
}

/// A broker counter's value now.
fn count(a: &std::sync::atomic::AtomicU64) -> u64 {
    a.load(std::sync::atomic::Ordering::Relaxed)
}
