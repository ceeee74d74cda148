//! `foxhunt track`: an emitter that moves, tracked from recorded captures (bearings of any
//! station and format, the RSSI an anchors file's anchors report in MT frames, or both) or
//! live from a line (`live`).

mod live;

use crate::commands::locate::live::LiveSource;
use crate::commands::locate::{Given, given, network_line};
use crate::commands::values;
use crate::inputs::files::{Source, stream};
use crate::inputs::stations::Network;
use crate::outputs::cot::{self, CotSender, CotUrl};
use crate::outputs::files::Outputs;
use crate::outputs::terminal::{Out, Outcome, Stop, note};
use crate::outputs::tracks;
use crate::track::capture::{Measured, TrackDecoder};
use crate::track::indoor::AnchorsFile;
use crate::track::moving::{
    DEFAULT_METHOD, PARTICLES, TRACK_METHODS, TRACK_PARTICLES, max_sources,
};
use crate::track::noise::{STATED_TOO_SMALL, array_note};
use crate::track::tracks::{OFFSET_SD_DEG, Options, Tracks, WIDTH_MHZ};
use foxhunt_core::Method;
use foxhunt_core::track::Motion;
use std::path::{Path, PathBuf};

/// Options of `foxhunt track`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Capture files (read in order as one stream); `-` alone tracks standard input live, a
    /// serial device with --baud too: one line (a JSON object with --json) per update.
    pub captures: Vec<PathBuf>,
    /// Read the one CAPTURE as a serial device at this baud rate, live.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub baud: Option<u32>,
    /// Live: poll a KrakenSDR's web page, `http://HOST:8081` (repeatable: every unit polled at
    /// once, each a station of its own); no CAPTURE.
    #[arg(long, value_name = "URL")]
    pub kraken: Vec<String>,
    /// Live: every station's bearings from an MQTT broker, `mqtt://HOST[:PORT]/PREFIX` (as
    /// `locate --mqtt` reads them); no CAPTURE.
    #[arg(long, value_name = "URL")]
    pub mqtt: Option<String>,
    /// With --mqtt: the client id of the broker session (one per tracker).
    #[arg(
        long,
        value_name = "ID",
        default_value = "foxhunt-track",
        requires = "mqtt"
    )]
    pub mqtt_client_id: String,
    /// Send each channel's latest point to TAK as Cursor-on-Target (`udp://HOST:PORT` or
    /// `tcp://HOST:PORT`): its position with course and speed, and its 95 % ellipse; live:
    /// every update, a recording: its last point.
    #[arg(long, value_name = "URL", value_parser = |s: &str| CotUrl::parse(s))]
    pub cot: Option<CotUrl>,
    /// Live: stop after this many seconds without a byte (`inf`: until the line closes, the
    /// default).
    #[arg(long, allow_hyphen_values = true,
          value_parser = values::f64_where(|s| s >= 0.0, "a number of seconds >= 0, or inf"))]
    pub quiet_exit: Option<f64>,
    /// The anchors file: where the anchors whose RSSI the captures hold stand (live: the
    /// line's RSSI is tracked, with the bearings of its first channel when it has GPS fixes).
    #[arg(long)]
    pub anchors: Option<PathBuf>,
    /// Print JSON (`{"tracks": [...]}`) instead of CSV.
    #[arg(long)]
    pub json: bool,
    /// Write the tracks and their 95 % ellipses as GeoJSON (needs GPS positions, or an
    /// anchors file with an origin).
    #[arg(long)]
    pub geojson: Option<PathBuf>,
    /// Write the same as KML.
    #[arg(long)]
    pub kml: Option<PathBuf>,
    /// Write the CSV to a file too.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Draw the room, anchors and track as SVG (RSSI from an anchors file).
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// The tracker: sir-robust (the default, a regularised PF), sir, sir-wide, sir-seed,
    /// afsa-pf, fa-pf, fa-pf-imp, gpf, pso-gpf, gsa-gpf, ekf (an IMM of a still and a moving
    /// EKF).
    #[arg(long, default_value = DEFAULT_METHOD.name())]
    pub method: String,
    /// Particles: 200, 1000, 2000 or 10000.
    #[arg(long, default_value_t = PARTICLES)]
    pub particles: usize,
    /// Prior sd of each DF unit's bearing offset, degrees.
    #[arg(long, default_value_t = OFFSET_SD_DEG)]
    pub offset_sd: f32,
    /// How the emitter moves: `outdoor` (a drone, a vehicle: 1 m/s^2, starting at up to
    /// 10 m/s, a stop or start once in ten minutes) or `indoor` (a person walking: 0.5 m/s^2,
    /// 1 m/s, once a minute). Default: indoor for RSSI alone from an anchors file (its own
    /// acceleration), else outdoor.
    #[arg(long, value_parser = ["outdoor", "indoor"])]
    pub motion: Option<String>,
    /// Acceleration sd of the moving emitter, m/s^2 (default: the motion's).
    #[arg(long)]
    pub accel_sd: Option<f32>,
    /// Seconds in which each station's offset forgets what it learned (default: 10 where the
    /// stations file states an `indoor-aoa` class, or a station of which nothing is stated
    /// scatters as one, past 10 degrees: its error changes with where the emitter is; else
    /// 0.15 s a particle, at least 250: 1500 at the default 10000; 1500 for `ekf`).
    #[arg(long)]
    pub memory_s: Option<f32>,
    /// A recording's track smoothed: each point also from the 15 updates after it (a
    /// fixed-lag smoother), so closer to the truth where the emitter turned or stopped.
    #[arg(long)]
    pub smooth: bool,
    /// Every bearing's noise, degrees, stated (default: the stations file's, else each
    /// record's own, a PFOXB's 1, widened to what a unit's bearings show where they scatter
    /// more; past 10 degrees, a station of which nothing is stated is tracked as an indoor
    /// array, `indoor-aoa`).
    #[arg(long)]
    pub sigma: Option<f32>,
    /// A stations file (TOML, as `locate --stations`): each station's noise and offset prior
    /// (docs/src/networks.md).
    #[arg(long, value_name = "FILE")]
    pub stations: Option<PathBuf>,
    /// Channel width for grouping bearings by frequency, MHz.
    #[arg(long, default_value_t = WIDTH_MHZ)]
    pub channel_width: f32,
    /// Seed of the particle filter.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

impl Args {
    fn options(&self) -> Result<Options, Stop> {
        let network = self.stations.as_deref().map(Network::load).transpose()?;
        self.values(network).map_err(Stop::Usage)
    }

    /// The options the flags' values give (a value out of range: why).
    fn values(&self, network: Option<Network>) -> Result<Options, String> {
        let method = Method::from_name(&self.method)
            .filter(|m| TRACK_METHODS.contains(m))
            .ok_or_else(|| {
                let names: Vec<&str> = TRACK_METHODS.iter().map(|m| m.name()).collect();
                format!(
                    "--method {}: not a tracking method (one of {})",
                    self.method,
                    names.join(", ")
                )
            })?;
        if !TRACK_PARTICLES.contains(&self.particles) {
            return Err(format!(
                "--particles {}: give one of 200, 1000, 2000, 10000",
                self.particles
            ));
        }
        let positive = |name: &str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(format!("--{name} {v}: give a finite number > 0"))
            }
        };
        if !(self.offset_sd.is_finite() && self.offset_sd >= 0.0) {
            return Err(format!(
                "--offset-sd {}: give a finite number >= 0",
                self.offset_sd
            ));
        }
        Ok(Options {
            method,
            particles: self.particles,
            offset_sd: self.offset_sd.to_radians(),
            motion: self.motion.as_deref().map(|m| match m {
                "indoor" => Motion::INDOOR,
                _ => Motion::OUTDOOR,
            }),
            accel_sd: self.accel_sd.map(|a| positive("accel-sd", a)).transpose()?,
            memory_s: self.memory_s.map(|m| positive("memory-s", m)).transpose()?,
            sigma: self
                .sigma
                .map(|s| positive("sigma", s).map(f32::to_radians))
                .transpose()?,
            width_mhz: positive("channel-width", self.channel_width)?,
            seed: self.seed,
            network,
            smooth: self.smooth,
        })
    }
}

/// What to say when a capture gave nothing of the anchors.
fn no_anchor(m: &Measured, file: &AnchorsFile) -> Option<String> {
    if !m.readings.is_empty() || !m.decoded.observations.is_empty() {
        return None;
    }
    let heard: Vec<String> = m.unknown.1.iter().map(|a| format!("0x{a:04x}")).collect();
    Some(if heard.is_empty() {
        "no bearing and no AF_INCOMING_MSG frame in the capture: nothing to track".into()
    } else {
        let listed: Vec<String> = file
            .anchor
            .iter()
            .map(|a| format!("0x{:04x}", a.addr))
            .collect();
        format!(
            "no frame from a known anchor: heard {} but the anchors file lists {}",
            heard.join(", "),
            listed.join(", ")
        )
    })
}

/// The live line the arguments ask for, if any.
fn live_source(a: &Args) -> Result<Option<LiveSource>, Stop> {
    let other = !a.captures.is_empty() || a.baud.is_some();
    if let Some(line) = network_line(&a.kraken, a.mqtt.as_deref(), &a.mqtt_client_id, other)? {
        return Ok(Some(line));
    }
    match given(a.baud, &a.captures)? {
        Given::Nothing => Err(Stop::usage(
            "give a CAPTURE, - for standard input, --kraken or --mqtt",
        )),
        Given::Files(_) => Ok(None),
        Given::Live(source) => Ok(Some(source)),
    }
}

/// Run `foxhunt track`.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    let options = a.options()?;
    if let Some(source) = live_source(a)? {
        if a.geojson.is_some() || a.kml.is_some() || a.csv.is_some() || a.svg.is_some() {
            return Err(Stop::usage(
                "a live track prints each update: write --geojson, --kml, --csv and --svg from \
                 the recorded capture",
            ));
        }
        if a.smooth {
            return Err(Stop::usage(
                "--smooth smooths a recording (each point from the 15 updates after it): a live \
                 track prints each update as it comes",
            ));
        }
        let quiet = a
            .quiet_exit
            .filter(|s| s.is_finite())
            .map(std::time::Duration::from_secs_f64);
        return match a.anchors.as_deref().map(AnchorsFile::load).transpose()? {
            Some(file) => live::rssi(source, quiet, &options, a, &file, out),
            None => live::run(source, quiet, &options, a, out),
        };
    }
    let mut inputs: Vec<&std::path::Path> = a.captures.iter().map(PathBuf::as_path).collect();
    inputs.extend(a.anchors.as_deref());
    inputs.extend(a.stations.as_deref());
    let outputs = Outputs::new(inputs, false);
    for p in [&a.geojson, &a.kml, &a.csv, &a.svg].into_iter().flatten() {
        outputs.check(p, true)?;
    }
    let file = a.anchors.as_deref().map(AnchorsFile::load).transpose()?;
    if a.svg.is_some() && file.is_none() {
        return Err(Stop::usage("--svg draws the anchors' room: give --anchors"));
    }
    let mut dec = TrackDecoder::new(file.as_ref());
    let sources: Vec<Source> = a.captures.iter().map(|p| Source::from_path(p)).collect();
    stream(&sources, |b| dec.feed(b))?;
    let m = dec.finish();
    if let (Some(f), Some(path)) = (&file, &a.anchors) {
        if let Some(e) = no_anchor(&m, f) {
            return Err(e.into());
        }
        if m.unknown.0 > 0 {
            let addrs: Vec<String> = m.unknown.1.iter().map(|a| format!("0x{a:04x}")).collect();
            note(&format!(
                "foxhunt: skipped {} frames from addresses not in {}: {}",
                m.unknown.0,
                path.display(),
                addrs.join(", ")
            ));
        }
    }
    let t = crate::track::tracks::tracks(&m, file.as_ref(), &options)?;
    note_left_out(&t);
    note_noise(&t);
    untracked(&t)?;
    write_files(a, &t, file.as_ref(), &outputs)?;
    if let Some(url) = &a.cot {
        let frame = t.frame.as_ref().ok_or(
            "--cot needs the track on the earth: a capture with GPS positions, or an anchors \
             file with an `origin`",
        )?;
        let now = std::time::SystemTime::now();
        let events: Vec<String> = t
            .tracks
            .iter()
            .filter_map(|c| c.points.last().map(|p| (c.freq_mhz, p)))
            .flat_map(|(f, p)| cot::track_events(f, p, frame, now))
            .collect();
        CotSender::new(url.clone())
            .send(&events)
            .map_err(Stop::Error)?;
    }
    if a.json {
        let text = serde_json::to_string(&tracks::json(&t)).map_err(|e| e.to_string())?;
        out.line(&text)
    } else {
        out.text(&tracks::csv(&t))
    }
}

/// Say which channels' tracks left stations out, and how many bearings that cost.
pub(crate) fn note_left_out(t: &Tracks) {
    for c in t.tracks.iter().filter(|c| c.left_out.0 > 0) {
        let what = c
            .freq_mhz
            .map_or(String::new(), |f| format!(" on {f:.3} MHz"));
        let (stations, bearings) = c.left_out;
        note(&format!(
            "foxhunt: a track holds at most {} DF stations a channel ({} beside RSSI): the \
             track{what} follows those with the most bearings; {stations} other stations' \
             {bearings} bearings are left out",
            max_sources(false),
            max_sources(true)
        ));
    }
}

/// Say, per station, the noise its track estimated (its records' widened to its bearings'
/// scatter: [`crate::track::noise`]), or that the noise stated for it is too small (its
/// ellipses are then too small).
pub(crate) fn note_noise(t: &Tracks) {
    for c in &t.tracks {
        let what = c
            .freq_mhz
            .map_or(String::new(), |f| format!(" on {f:.3} MHz"));
        for s in &c.noise {
            let (id, n) = (&s.id, &s.noise);
            let given = n.given.to_degrees();
            if s.stated && n.scatter > STATED_TOO_SMALL {
                note(&format!(
                    "foxhunt: {id}'s bearings scatter {:.1} times the noise stated for them \
                     ({given:.1} deg) about the track{what}: its ellipses are too small; state \
                     the unit's noise (--sigma, or the stations file's noise_deg)",
                    n.scatter
                ));
            } else if !s.stated && n.widened > 1.0 {
                note(&format!(
                    "foxhunt: {id}'s bearings scatter {:.1} times their records' noise \
                     ({given:.1} deg) about the track{what}: tracked with {:.1} deg, \
                     estimated (--sigma or the stations file's noise_deg states it){}",
                    n.shown(),
                    n.tracked().to_degrees(),
                    array_note(n.array)
                ));
            }
        }
    }
}

/// Say which channels have no track and why (one line each on standard error); when no
/// channel has one, the first's reason as the error instead.
pub(crate) fn untracked(t: &Tracks) -> Result<(), String> {
    let mut why = t.tracks.iter().filter_map(|c| {
        let on = c
            .freq_mhz
            .map_or(String::new(), |f| format!(" on {f:.3} MHz"));
        c.untracked.as_ref().map(|w| format!("no track{on}: {w}"))
    });
    if t.tracks.iter().all(|c| c.points.is_empty()) {
        return Err(why
            .next()
            .unwrap_or_else(|| "no update could be tracked".into()));
    }
    for w in why {
        note(&format!("foxhunt: {w}"));
    }
    Ok(())
}

/// The tracks and their 95 % ellipses on the earth, as GeoJSON and KML, to the paths given
/// (also what `locate` writes for an emitter that moves).
pub(crate) fn write_maps(
    t: &Tracks,
    [geojson, kml]: [Option<&Path>; 2],
    outputs: &Outputs,
) -> Result<(), String> {
    if let Some(p) = geojson {
        let g = tracks::geojson(t).ok_or(
            "--geojson needs the track on the earth: a capture with GPS positions, or an \
             anchors file with an `origin`",
        )?;
        let text = serde_json::to_string(&g).map_err(|e| e.to_string())?;
        outputs.write(p, text.as_bytes(), true)?;
    }
    if let Some(p) = kml {
        let k = tracks::kml(t).ok_or(
            "--kml needs the track on the earth: a capture with GPS positions, or an anchors \
             file with an `origin`",
        )?;
        outputs.write(p, k.as_bytes(), true)?;
    }
    Ok(())
}

/// `track`'s options at every flag's default: what `locate` tracks an emitter that moves with.
pub fn default_options() -> Result<Options, String> {
    #[derive(clap::Parser)]
    struct Defaults {
        #[command(flatten)]
        args: Args,
    }
    use clap::Parser;
    let d = Defaults::try_parse_from(["track"]).map_err(|e| e.to_string())?;
    d.args.values(None)
}

/// The files asked for.
fn write_files(
    a: &Args,
    t: &Tracks,
    file: Option<&AnchorsFile>,
    outputs: &Outputs,
) -> Result<(), String> {
    write_maps(t, [a.geojson.as_deref(), a.kml.as_deref()], outputs)?;
    if let Some(p) = &a.csv {
        outputs.write(p, tracks::csv(t).as_bytes(), true)?;
    }
    if let (Some(p), Some(f)) = (&a.svg, file) {
        let path: Vec<[f32; 2]> = t
            .tracks
            .iter()
            .flat_map(|c| c.points.iter().map(|p| p.position))
            .collect();
        outputs.write(
            p,
            crate::outputs::maps::track_svg(&path, f).as_bytes(),
            true,
        )?;
    }
    Ok(())
}
