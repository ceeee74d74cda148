//! `foxhunt publish`: a station's bearings sent to an MQTT broker, one JSON message each
//! (docs/src/networks.md, "Through an MQTT broker"), for `foxhunt locate --mqtt` to fuse.
//!
//! The bearings come from any source `locate` reads (capture files, standard input, a serial
//! device, KrakenSDRs' web pages) through the same decoder and bridge, so what is sent is
//! what `locate` would have used: true bearings at the station's position, on UTC.

use super::locate::live::{LiveSource, reader};
use super::locate::{GPSD_NEEDS_A_LINE, Given, GpsdArgs, given, kraken_urls};
use super::values;
use crate::inputs::capture::Decoder;
use crate::inputs::files::{Source, stream};
use crate::inputs::messages::{Stamper, capture_day, now_ms, parse_date, today_ms};
use crate::inputs::mqtt::{MqttUrl, check_station};
use crate::outputs::mqtt::{Backlog, Link, Message};
use crate::outputs::terminal::{Outcome, Stop, note};
use foxhunt_bridge::BridgeConfig;
use foxhunt_bridge::bridge::BearingMeasurement;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Options of `foxhunt publish`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Capture files (read in order, each an input of its own), `-` for standard input, or a
    /// serial device with --baud.
    pub sources: Vec<PathBuf>,
    /// The broker and the topics' prefix: `mqtt://HOST[:PORT]/PREFIX`. Each bearing goes to
    /// PREFIX/bearings/CHANNEL/STATION at QoS 1 (CHANNEL: its frequency in MHz to the kHz,
    /// `145.500`, or `none`).
    #[arg(long, value_name = "URL")]
    pub mqtt: String,
    /// Workers sharing the channels (`locate --mqtt-shard K/N`): each bearing goes to
    /// PREFIX/bearings/K/CHANNEL/STATION instead, K its channel's shard of N (a hash of the
    /// channel's name). Every station of a network must be given the same N.
    #[arg(long, value_name = "N", default_value_t = 1,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(crate::inputs::mqtt::MAX_SHARDS)))]
    pub shards: u32,
    /// The station id of bearings whose records name none ($PFOXB, Agrelo, a KrakenSDR
    /// without a STATION_ID): 1 to 16 characters (default: the record kind, or
    /// FILE:KIND with several files).
    #[arg(long, value_name = "ID")]
    pub station: Option<String>,
    /// The client id of the broker session, kept while this publisher is away so that what
    /// the broker had not acknowledged is sent again when it comes back (default:
    /// foxhunt-publish-STATION with --station, else one per process).
    #[arg(long, value_name = "ID")]
    pub client_id: Option<String>,
    /// Read the one SOURCE as a serial device at this baud rate.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub baud: Option<u32>,
    /// Poll a KrakenSDR's web page (repeatable) instead of a SOURCE.
    #[arg(long, value_name = "URL")]
    pub kraken: Vec<String>,
    /// Positions and headings from gpsd beside a live line (a vehicle's DF unit that sends
    /// bearings alone).
    #[command(flatten)]
    pub gpsd: GpsdArgs,
    /// Recorded captures: send each bearing at its own time, this many times faster than
    /// real time (1: as it happened); default: as fast as the broker takes them.
    #[arg(long, value_name = "X",
          value_parser = values::f64_where(|x| x > 0.0 && x.is_finite(), "a speed-up > 0"))]
    pub pace: Option<f64>,
    /// The UTC date of the capture's first bearing, YYYY-MM-DD, for records that carry only
    /// a time of day (NMEA without RMC); default: the capture's own (a KrakenSDR record's
    /// epoch, an RMC date), else today's.
    #[arg(long, value_name = "DATE")]
    pub date: Option<String>,
    /// Bearings kept while the broker is away: a recorded capture waits when they are
    /// reached, a live line drops the oldest (counted).
    #[arg(long, value_name = "N", default_value_t = 100_000,
          value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    pub buffer: u64,
    /// After the last bearing, seconds to wait for the broker to acknowledge them all
    /// (`inf`: until it does).
    #[arg(long, value_name = "S", default_value_t = 60.0,
          value_parser = values::f64_where(|s| s >= 0.0, "a number of seconds >= 0, or inf"))]
    pub linger: f64,
    /// Live: stop after this many seconds without a byte.
    #[arg(long, value_name = "S",
          value_parser = values::f64_where(|s| s >= 0.0, "a number of seconds >= 0, or inf"))]
    pub quiet_exit: Option<f64>,
}

/// Where the bearings come from.
enum Input {
    Files(Vec<Source>),
    Live(LiveSource),
}

fn input(a: &Args) -> Result<Input, Stop> {
    if !a.kraken.is_empty() {
        let urls = kraken_urls(
            &a.kraken,
            !a.sources.is_empty() || a.baud.is_some(),
            "SOURCE",
        )?;
        return Ok(Input::Live(LiveSource::Kraken(urls)));
    }
    match given(a.baud, &a.sources)? {
        Given::Nothing => Err(Stop::usage(
            "give the bearings' SOURCE: capture files, - for standard input, a serial device \
             with --baud, or --kraken URL",
        )),
        Given::Files(sources) => Ok(Input::Files(sources)),
        Given::Live(source) => Ok(Input::Live(source)),
    }
}

/// Turns the bridge's bearings into messages on their topics.
struct Messages<'a> {
    url: &'a MqttUrl,
    shards: u32,
    stamper: Stamper,
}

impl Messages<'_> {
    fn message(&self, dec: &Decoder, m: &BearingMeasurement) -> Result<Message, String> {
        let msg = self.stamper.message(dec, m)?;
        check_station(&msg.station)?;
        msg.check()?;
        Ok(Message {
            topic: self
                .url
                .sharded_topic(self.shards, &msg.channel(), &msg.station),
            payload: serde_json::to_vec(&msg).map_err(|e| e.to_string())?,
        })
    }
}

/// Real-time replay: each bearing waits until its time, scaled.
struct Pace {
    speed: f64,
    start: Option<(i64, Instant)>,
}

impl Pace {
    fn wait(&mut self, time_ms: i64) {
        let (t0, w0) = *self.start.get_or_insert((time_ms, Instant::now()));
        let due = (time_ms - t0).max(0) as f64 / 1000.0 / self.speed;
        let elapsed = w0.elapsed().as_secs_f64();
        if due > elapsed {
            std::thread::sleep(Duration::from_secs_f64(due - elapsed));
        }
    }
}

/// Send the bearings decoded so far; the first error stops the run.
fn drain(
    dec: &mut Decoder,
    messages: &Messages<'_>,
    link: &Link,
    pace: &mut Option<Pace>,
) -> Result<(), String> {
    if dec.decoded.measurements.is_empty() {
        return Ok(());
    }
    dec.snapshot();
    for m in std::mem::take(&mut dec.decoded.measurements) {
        if let Some(p) = pace {
            p.wait(m.time_ms);
        }
        link.send(messages.message(dec, &m)?)?;
    }
    Ok(())
}

/// Run `foxhunt publish`.
pub fn run(a: &Args) -> Outcome {
    let url = MqttUrl::parse(&a.mqtt).map_err(Stop::Usage)?;
    if let Some(s) = &a.station {
        check_station(s).map_err(Stop::Usage)?;
    }
    let day = a
        .date
        .as_deref()
        .map(parse_date)
        .transpose()
        .map_err(Stop::Usage)?;
    let input = input(a)?;
    let live = matches!(input, Input::Live(_));
    let gpsd = a.gpsd.address()?;
    if gpsd.is_some() && !live {
        return Err(Stop::usage(GPSD_NEEDS_A_LINE));
    }
    if a.pace.is_some() && live {
        return Err(Stop::usage(
            "--pace replays a recorded capture; a live line keeps its own pace",
        ));
    }
    if a.quiet_exit.is_some() && !live {
        return Err(Stop::usage(
            "--quiet-exit applies to a live line (--baud, -, --kraken)",
        ));
    }
    let day0_ms = match (&input, day) {
        (_, Some(d)) => d,
        (Input::Files(s), None) => capture_day(s).unwrap_or_else(|| {
            note("no date in the capture: its times are counted from today (give --date)");
            today_ms()
        }),
        // A live line's times of day are today's, or yesterday's just after midnight: the
        // day that puts the first bearing nearest now (taken below, at the first bearing).
        (Input::Live(_), None) => today_ms(),
    };
    let client_id = a.client_id.clone().unwrap_or_else(|| match &a.station {
        Some(s) => format!("foxhunt-publish-{s}"),
        None => format!("foxhunt-publish-{}-{}", std::process::id(), now_ms()),
    });
    let backlog = Backlog {
        capacity: usize::try_from(a.buffer).unwrap_or(usize::MAX),
        drop_oldest: live,
        linger: if a.linger.is_finite() {
            Duration::from_secs_f64(a.linger)
        } else {
            Duration::MAX
        },
    };
    let link = Link::start(&url, &client_id, backlog)?;
    let mut messages = Messages {
        url: &url,
        shards: a.shards,
        stamper: Stamper {
            station: a.station.clone(),
            day0_ms,
            dated: a.date.is_some(),
        },
    };
    let mut pace = a.pace.map(|speed| Pace { speed, start: None });
    let mut dec = Decoder::new(BridgeConfig::default(), false);
    dec.keep_measurements();
    let fed: Result<(), String> = match input {
        Input::Files(sources) => (|| {
            for (s, path) in sources.iter().zip(&a.sources) {
                // As `locate` names its inputs: a unit whose records name no station is
                // FILE:KIND with several files.
                let name = path.file_name().unwrap_or(path.as_os_str());
                dec.begin_input(&name.to_string_lossy())?;
                let mut failed = Ok(());
                stream(std::slice::from_ref(s), |b| {
                    if failed.is_ok() {
                        dec.feed(b);
                        failed = drain(&mut dec, &messages, &link, &mut pace);
                    }
                })?;
                failed?;
            }
            dec.end();
            drain(&mut dec, &messages, &link, &mut pace)
        })(),
        Input::Live(source) => (|| {
            let quiet = a
                .quiet_exit
                .filter(|s| s.is_finite())
                .map(Duration::from_secs_f64);
            if let LiveSource::Kraken(urls) = &source
                && urls.len() > 1
            {
                for u in urls {
                    dec.begin_input(u.base.trim_start_matches("http://"))?;
                }
            }
            let mut line = reader(&source, gpsd.as_ref(), None)?;
            loop {
                let ended = line
                    .take(&mut dec, quiet, true)
                    .map_err(|s| s.message().unwrap_or("stopped").to_string())?;
                if ended {
                    dec.end();
                }
                if let Some(m) = dec.decoded.measurements.first() {
                    messages.stamper.date_live(m.time_ms);
                }
                drain(&mut dec, &messages, &link, &mut None)?;
                if ended {
                    return Ok(());
                }
            }
        })(),
    };
    let sent = link.finish();
    note(&format!(
        "mqtt: bearings {}, acknowledged {}, resent {}, dropped {}, outages {}",
        sent.messages, sent.acked, sent.resent, sent.dropped, sent.outages
    ));
    fed?;
    if sent.acked < sent.messages {
        return Err(Stop::Error(format!(
            "{} of {} bearings not acknowledged by the broker at {}",
            sent.messages - sent.acked,
            sent.messages,
            url.address()
        )));
    }
    Ok(())
}
