//! `foxhunt locate`: the fix of a recorded drive, of a live serial line or of standard input,
//! with its maps.

pub mod live;
pub mod window;

use super::{GuidanceArgs, NetworkArgs, method, values};
use crate::estimate::options::{LocateOptions, PARTICLES};
use crate::inputs::calibration::{Calibration, CalibrationCheck};
use crate::inputs::capture::{Decoded, Decoder};
use crate::inputs::files::{InputKind, Source, stream};
use crate::inputs::gpsd::GpsdAddress;
use crate::inputs::kraken_http::KrakenUrl;
use crate::inputs::mqtt::MqttUrl;
use crate::locate::report::Located;
use crate::locate::{locate, locate_guided};
use crate::outputs::cot::{self, CotSender, CotUrl};
use crate::outputs::files::Outputs;
use crate::outputs::history::recorder::{Recorder, replay};
use crate::outputs::history::{Window, parse_time};
use crate::outputs::maps;
use crate::outputs::terminal::{Out, Outcome, Stop, note};
use foxhunt_bridge::BridgeConfig;
use foxhunt_core::Method;
use live::{LiveOptions, LiveSource};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The bundled sample drive (`foxhunt simulate --scenario aoa-drive --out
/// serial-bridge/captures/aoa-drive.nmea`).
pub const SAMPLE_DRIVE: &[u8] = include_bytes!("../../../../serial-bridge/captures/aoa-drive.nmea");

/// Options of `foxhunt locate`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Capture files (read in order as one stream), `-` for standard input (read live), or
    /// none for the bundled sample drive.
    pub captures: Vec<PathBuf>,
    /// Fix method, by its registry name: ml-robust (every emitter, offsets and consistency
    /// checked), or one emitter by ml, ml-huber, sir, sir-robust, gpf, ekf, afsa-pf, ...
    #[arg(long, default_value = "ml-robust", value_parser = method())]
    pub method: Method,
    /// Bearings whose frequencies lie within this many MHz share a channel (one emitter
    /// each).
    #[arg(long, default_value_t = 0.05,
          value_parser = values::f32_where(|w| w >= 0.0 && w.is_finite(), "a number of MHz >= 0"))]
    pub channel_width_mhz: f32,
    /// Measure the DF unit's mounting offset on the CAPTURE of a drive past a transmitter at
    /// LAT,LON (decimal degrees), and its direction-dependent error where the drive turned
    /// through enough directions, and save them to --calibration FILE, instead of locating.
    /// The transmitter must lie 100 m to 50 km from the bearings, which must agree with it; an
    /// offset beyond --max-offset-deg is reported, not saved.
    #[arg(long, allow_hyphen_values = true, requires = "calibration", value_name = "LAT,LON",
          value_parser = values::lat_lon)]
    pub calibrate: Option<[f64; 2]>,
    /// With --calibrate: the largest offset saved, degrees (a larger one is a mounting or
    /// cabling fault, or the wrong transmitter position, until shown otherwise).
    #[arg(long, default_value_t = CalibrationCheck::default().max_offset_deg,
          requires = "calibrate", value_name = "DEG",
          value_parser = values::f32_where(|d| (0.0..=180.0).contains(&d), "a number of degrees from 0 to 180"))]
    pub max_offset_deg: f32,
    /// A calibration file: with --calibrate where to save it; otherwise the offset (and the
    /// direction-dependent error, where it holds one) to apply.
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Particles of the particle methods (sir, gpf, the swarms; a compiled count): 1000, or
    /// 200 for fa-pf, whose cost grows with their square.
    #[arg(long, value_parser = values::particles)]
    pub particles: Option<usize>,
    /// Bearing noise of the DF unit, degrees, in (0, 90) (default: estimated from the
    /// residuals).
    #[arg(long, allow_hyphen_values = true,
          value_parser = values::f32_where(|s| s > 0.0 && s < 90.0, "a number of degrees between 0 and 90"))]
    pub sigma_deg: Option<f32>,
    /// Print one JSON object (stable field names); live: one per update. Its `advice` (the
    /// first emitter's; before a fix, from the bearings alone): heading_deg (clockwise from
    /// north), compass, target {lat, lon} (the point to drive to), turn (with --roads: kind
    /// straight/left/right/u-turn, angle_deg, at east/north m) and turn_at {lat, lon},
    /// reason (widen-angle, get-closer, calibration-leg, more-bearings, check-unit,
    /// good-enough) and reason_text, good_enough, missing (precision, consistency, bearings;
    /// fix before one), bound_cep50_m, offset_known_cep50_m, predicted_cep50_m, reached_s,
    /// on_roads, line; `advice_error` says why there is none; `unit`, when the input carries
    /// a DF unit's $PFOXF/$PFOXS/$PFOXL sentences, what the unit said (its fix, ellipse,
    /// status, health; live: a new unit fix is an update too). No fix yet: {used, error,
    /// advice, unit}.
    #[arg(long)]
    pub json: bool,
    /// Write PREFIX.geojson, PREFIX.kml and PREFIX.svg.
    #[arg(long, value_name = "PREFIX")]
    pub maps: Option<PathBuf>,
    /// Write the emitter, ellipse, track and bearing rays as GeoJSON.
    #[arg(long)]
    pub geojson: Option<PathBuf>,
    /// Write the same as KML.
    #[arg(long)]
    pub kml: Option<PathBuf>,
    /// Draw the track, bearing rays, the method's particles, ellipse and emitter as SVG.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Seed of the particle methods.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Read the one CAPTURE as a serial device at this baud rate, updating the fix as bytes
    /// arrive (4800 is NMEA 0183's usual rate).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub baud: Option<u32>,
    /// Live: stop after this many seconds without a byte (`inf`: until the line closes, the
    /// default).
    #[arg(long, allow_hyphen_values = true,
          value_parser = values::f64_where(|s| s >= 0.0, "a number of seconds >= 0, or inf"))]
    pub quiet_exit: Option<f64>,
    /// Print `stats: bearings N, seconds S, peak_bytes B` on stderr at the end.
    #[arg(long)]
    pub stats: bool,
    /// Positions and headings from gpsd beside a live line.
    #[command(flatten)]
    pub gpsd: GpsdArgs,
    /// The roads and the stop rule's target of the advice.
    #[command(flatten)]
    pub guidance: GuidanceArgs,
    /// Live: poll a KrakenSDR about twice a second, `http://HOST:8081` (its DOA_value.html,
    /// else doa.xml) or the URL of either page; no CAPTURE. Repeatable: every unit is polled
    /// at once and their bearings fused, each a station of its own (its STATION_ID, else its
    /// URL).
    #[arg(long, value_name = "URL")]
    pub kraken: Vec<String>,
    /// The stations file and the reference transmitters.
    #[command(flatten)]
    pub network: NetworkArgs,
    /// Live: every station's bearings from an MQTT broker, `mqtt://HOST[:PORT]/PREFIX`
    /// (`foxhunt publish` sends them to PREFIX/bearings/CHANNEL/STATION); no CAPTURE. Each
    /// update is one channel's, the longest-waiting first (as many side by side as there are
    /// cores); its fix goes back as one retained message per channel, PREFIX/fixes/CHANNEL
    /// (an emitter of --json's schema). A bearing arriving twice (same channel, station and
    /// time) counts once. End it with --quiet-exit; exit status 0 when some channel's last
    /// update had a fix. A broker that cannot be reached at the start: one line, exit status
    /// 1; one lost later is reconnected to.
    #[arg(long, value_name = "URL")]
    pub mqtt: Option<String>,
    /// With --mqtt: the client id of the broker session, kept while this worker is away so
    /// that the bearings sent meanwhile are delivered when it comes back (one id per worker;
    /// the fixes go out on a second connection, ID-fixes).
    #[arg(
        long,
        value_name = "ID",
        default_value = "foxhunt-locate",
        requires = "mqtt"
    )]
    pub mqtt_client_id: String,
    /// With --mqtt: fuse only shard K of N (`K/N`): the channels whose name hashes to K,
    /// published by `foxhunt publish --shards N` to PREFIX/bearings/K/CHANNEL/STATION. Run
    /// one worker per K, each with its own --mqtt-client-id.
    #[arg(long, value_name = "K/N", requires = "mqtt",
          value_parser = |s: &str| crate::inputs::mqtt::Shard::parse(s))]
    pub mqtt_shard: Option<crate::inputs::mqtt::Shard>,
    /// With --mqtt: bearings kept per channel, the latest: the fix of a long run is that of
    /// its last N bearings on each channel, in bounded memory and solve time.
    #[arg(long, value_name = "N", default_value_t = window::KEEP, requires = "mqtt",
          value_parser = super::values::count_at_least(2, "bearings per channel"))]
    pub mqtt_keep: usize,
    /// Send each fix to TAK (ATAK, WinTAK, iTAK, a TAK server) as Cursor-on-Target events:
    /// `udp://HOST:PORT` (a LAN's multicast is udp://239.2.3.1:6969) or `tcp://HOST:PORT`;
    /// live: every update. Each emitter with its 95 % ellipse, each station with its latest
    /// line of bearing (docs/src/networks.md).
    #[arg(long, value_name = "URL", conflicts_with = "calibrate",
          value_parser = |s: &str| CotUrl::parse(s))]
    pub cot: Option<CotUrl>,
    /// Keep the run's history in FILE, an SQLite database (created if absent;
    /// docs/src/history.md): every bearing (once per channel, station and time) and every
    /// update's fix or why there is none. Live, a worker started again on FILE resumes its
    /// channels from the bearings there. With no CAPTURE or live source: replay FILE's
    /// bearings (--since, --until) and give their fix, FILE only read. A file that is not a
    /// foxhunt history of this schema: one line, exit status 2, the file untouched; one that
    /// another program has locked or another worker writes: exit status 1.
    #[arg(long, value_name = "FILE", conflicts_with = "calibrate")]
    pub db: Option<PathBuf>,
    /// Replay only the bearings taken at or after T: RFC 3339 (2026-06-01T10:00:00Z) or ms
    /// since 1970 UTC.
    #[arg(long, value_name = "T", requires = "db", value_parser = parse_time)]
    pub since: Option<i64>,
    /// Replay only the bearings taken before T (RFC 3339 or ms since 1970 UTC).
    #[arg(long, value_name = "T", requires = "db", value_parser = parse_time)]
    pub until: Option<i64>,
}

/// Where the maps go: (path, named on the command line).
fn map_paths(a: &Args) -> [Option<PathBuf>; 3] {
    let from_prefix = |ext: &str| {
        a.maps.as_ref().map(|p| {
            let mut s = p.as_os_str().to_owned();
            s.push(format!(".{ext}"));
            PathBuf::from(s)
        })
    };
    [
        a.geojson.clone().or_else(|| from_prefix("geojson")),
        a.kml.clone().or_else(|| from_prefix("kml")),
        a.svg.clone().or_else(|| from_prefix("svg")),
    ]
}

/// How the captures are read.
enum Input {
    Sample,
    Files(Vec<Source>),
    Live(LiveSource),
    /// A live line of bearings with gpsd beside it.
    Gpsd(LiveSource, GpsdAddress),
    /// KrakenSDRs' web pages (and perhaps gpsd).
    Kraken(Vec<KrakenUrl>, Option<GpsdAddress>),
    /// An MQTT broker's bearings.
    Mqtt(MqttUrl),
    /// A history's bearings.
    History(PathBuf, Window),
}

/// `--gpsd`: positions and headings from a running gpsd beside a live line of bearings (a
/// vehicle whose DF unit sends bearings alone), for every command that reads one.
#[derive(Debug, clap::Args)]
pub struct GpsdArgs {
    /// Live: positions (TPV) and heading (ATT) from a running gpsd, while the bearings come
    /// from the serial device (--baud), standard input (-) or a KrakenSDR (--kraken):
    /// `--gpsd` for localhost:2947, or `--gpsd=HOST[:PORT]`.
    #[arg(
        long,
        value_name = "HOST[:PORT]",
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = ""
    )]
    pub gpsd: Option<String>,
}

impl GpsdArgs {
    /// The daemon's address, if one was given.
    pub fn address(&self) -> Result<Option<GpsdAddress>, Stop> {
        self.gpsd
            .as_deref()
            .map(GpsdAddress::parse)
            .transpose()
            .map_err(Stop::Usage)
    }
}

/// What `--gpsd` beside a recorded capture is told.
pub(crate) const GPSD_NEEDS_A_LINE: &str = "--gpsd gives positions beside a live line of \
    bearings: a serial device with --baud, - for standard input, or --kraken URL";

fn input(a: &Args) -> Result<Input, Stop> {
    let gpsd = a.gpsd.address()?;
    let source = !a.captures.is_empty()
        || a.baud.is_some()
        || !a.kraken.is_empty()
        || a.mqtt.is_some()
        || gpsd.is_some();
    if let (Some(db), false) = (&a.db, source) {
        let window = Window {
            since_ms: a.since,
            until_ms: a.until,
        };
        if let (Some(s), Some(u)) = (a.since, a.until)
            && s >= u
        {
            return Err(Stop::usage("--since must come before --until"));
        }
        return Ok(Input::History(db.clone(), window));
    }
    if a.since.is_some() || a.until.is_some() {
        return Err(Stop::usage(
            "--since and --until replay a history: give --db FILE and no CAPTURE or live source",
        ));
    }
    if let Some(url) = &a.mqtt {
        if !a.captures.is_empty() || a.baud.is_some() || !a.kraken.is_empty() || gpsd.is_some() {
            return Err(Stop::usage(
                "--mqtt reads every station's bearings from the broker: give no CAPTURE, \
                 --baud, --kraken or --gpsd",
            ));
        }
        return Ok(Input::Mqtt(MqttUrl::parse(url).map_err(Stop::Usage)?));
    }
    if !a.kraken.is_empty() {
        let urls = kraken_urls(
            &a.kraken,
            !a.captures.is_empty() || a.baud.is_some(),
            "CAPTURE",
        )?;
        return Ok(Input::Kraken(urls, gpsd));
    }
    if let Some(g) = gpsd {
        return match line_input(a)? {
            Input::Live(source) => Ok(Input::Gpsd(source, g)),
            _ => Err(Stop::usage(GPSD_NEEDS_A_LINE)),
        };
    }
    line_input(a)
}

/// The `--kraken` URLs of a command, which reads them instead of its `what` arguments and
/// `--baud` (`other`: some were given too).
pub(crate) fn kraken_urls(
    urls: &[String],
    other: bool,
    what: &str,
) -> Result<Vec<KrakenUrl>, Stop> {
    if other {
        return Err(Stop::usage(format!(
            "--kraken reads the unit's web page: give no {what} and no --baud"
        )));
    }
    urls.iter()
        .map(|u| KrakenUrl::parse(u))
        .collect::<Result<Vec<_>, _>>()
        .map_err(Stop::Usage)
}

/// The whole network's line that `--kraken URLS` or `--mqtt URL` asks a command that follows
/// every channel (`track`, `serve`) for, on a broker session of `client_id`; none when neither
/// is given. `other`: a CAPTURE or `--baud` was given too (a usage error beside either).
pub(crate) fn network_line(
    kraken: &[String],
    mqtt: Option<&str>,
    client_id: &str,
    other: bool,
) -> Result<Option<LiveSource>, Stop> {
    if let Some(url) = mqtt {
        if other || !kraken.is_empty() {
            return Err(Stop::usage(
                "--mqtt reads the broker: give no CAPTURE, --baud or --kraken",
            ));
        }
        return Ok(Some(LiveSource::Mqtt {
            url: MqttUrl::parse(url).map_err(Stop::Usage)?,
            client_id: client_id.to_string(),
            // Every channel; these commands keep no bearing per channel, so `keep` (what a
            // fusing worker holds) bounds nothing here.
            shard: None,
            keep: window::KEEP,
        }));
    }
    if kraken.is_empty() {
        return Ok(None);
    }
    Ok(Some(LiveSource::Kraken(kraken_urls(
        kraken, other, "CAPTURE",
    )?)))
}

/// What a command's CAPTURE arguments and `--baud` ask to read: nothing (the command's
/// default), recorded files, or a live line.
pub(crate) enum Given {
    /// No CAPTURE.
    Nothing,
    /// Recorded captures, checked to be files or pipes.
    Files(Vec<Source>),
    /// A serial device, or standard input (`-`).
    Live(LiveSource),
}

/// Read `paths` and `baud` as `locate` and `publish` take them: one serial device with
/// `--baud`, `-` alone for standard input, else capture files (a serial device among them is
/// a usage error naming `--baud`).
pub(crate) fn given(baud: Option<u32>, paths: &[PathBuf]) -> Result<Given, Stop> {
    match (baud, paths) {
        (Some(baud), [path]) => {
            let name = path.display();
            match crate::inputs::files::kind_of(path) {
                Ok(InputKind::File(_)) => Err(Stop::usage(format!(
                    "--baud reads a serial device, and {name} is a file: drop --baud to read \
                     it as a recorded capture"
                ))),
                Ok(
                    InputKind::Directory | InputKind::Device | InputKind::Pipe | InputKind::Other,
                ) => Err(Stop::usage(format!(
                    "--baud reads a serial device, and {name} is none (a pipe is read with \
                         -, as standard input)"
                ))),
                // A missing device is the open's error, with its own words.
                Ok(InputKind::Serial) | Err(_) => Ok(Given::Live(LiveSource::Serial {
                    path: path.to_string_lossy().into_owned(),
                    baud,
                })),
            }
        }
        (Some(_), _) => Err(Stop::usage(
            "--baud reads one serial device: give exactly one path",
        )),
        (None, []) => Ok(Given::Nothing),
        (None, [one]) if one.as_os_str() == "-" => Ok(Given::Live(LiveSource::Stdin)),
        (None, many) if many.iter().any(|p| p.as_os_str() == "-") => Err(Stop::usage(
            "standard input (-) is read live: give it alone",
        )),
        (None, many) => {
            let sources: Vec<Source> = many.iter().map(|p| Source::from_path(p)).collect();
            for s in &sources {
                if s.kind()? == InputKind::Serial {
                    return Err(Stop::usage(format!(
                        "{} is a serial device: give --baud (4800 for NMEA 0183)",
                        s.name()
                    )));
                }
                s.check_capture()?;
            }
            Ok(Given::Files(sources))
        }
    }
}

fn line_input(a: &Args) -> Result<Input, Stop> {
    Ok(match given(a.baud, &a.captures)? {
        Given::Nothing => Input::Sample,
        Given::Files(sources) => Input::Files(sources),
        Given::Live(source) => Input::Live(source),
    })
}

/// Particles of fa-pf unless `--particles` says otherwise: its firefly move pairs every
/// particle with every brighter one at each bearing, so its time grows with their square (1000
/// on 60 bearings: over 20 s).
const FA_PF_PARTICLES: usize = 200;

/// Run `foxhunt locate`.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    let started = Instant::now();
    let calibrating = a.calibrate.is_some();
    let particles = match a.particles {
        Some(_) if !a.method.uses_particles() => {
            return Err(Stop::usage(format!(
                "--particles sets the particle count of the particle methods; {} has no \
                 particles",
                a.method.name()
            )));
        }
        Some(n) => n,
        None if a.method == Method::FaPf => FA_PF_PARTICLES,
        None => PARTICLES,
    };
    if calibrating && a.captures.is_empty() && a.kraken.is_empty() && a.mqtt.is_none() {
        return Err(Stop::usage(
            "--calibrate measures the offset on a drive past the transmitter: give that \
             drive's CAPTURE",
        ));
    }
    let calibration = match (&a.calibration, calibrating) {
        // A file that cannot be read fails (exit 1); one that reads but is no calibration (a
        // value no calibration gives) is a usage error (exit 2), like a bad option value.
        (Some(f), false) => {
            let text = crate::inputs::files::read_text(f)?;
            Some(
                Calibration::from_toml(&text)
                    .map_err(|e| Stop::Usage(format!("{}: {e}", f.display())))?,
            )
        }
        _ => None,
    };
    let options = LocateOptions {
        method: a.method,
        particles,
        sigma_deg: a.sigma_deg,
        seed: a.seed,
        offset: calibration.as_ref().map(Calibration::prior),
        direction: calibration.as_ref().and_then(Calibration::direction),
        channel_width_mhz: a.channel_width_mhz,
        network: a.network.network()?,
    };
    options.check().map_err(Stop::Usage)?;
    // `inf` (the default): until the line closes.
    let quiet = a
        .quiet_exit
        .filter(|s| s.is_finite())
        .map(Duration::from_secs_f64);
    let input = input(a)?;
    let live = matches!(
        input,
        Input::Live(_) | Input::Gpsd(..) | Input::Kraken(..) | Input::Mqtt(_)
    );
    if calibrating && live {
        return Err(Stop::usage(
            "--calibrate reads a recorded drive, not a live line",
        ));
    }
    if a.quiet_exit.is_some() && !live {
        return Err(Stop::usage(
            "--quiet-exit applies to a live line (--baud, or -)",
        ));
    }
    // Refuse every output that would destroy an input before reading anything.
    let mut inputs: Vec<&Path> = a.captures.iter().map(PathBuf::as_path).collect();
    if !calibrating {
        inputs.extend(a.calibration.as_deref());
    }
    inputs.extend(a.network.stations.as_deref());
    // The history is read (a replay) or written only as a history.
    inputs.extend(a.db.as_deref());
    let outputs = Outputs::new(inputs, false);
    let paths = map_paths(a);
    for p in paths.iter().flatten() {
        outputs.check(p, true)?;
    }
    if let (Some(f), true) = (&a.calibration, calibrating) {
        outputs.check(f, true)?;
    }
    let keep_track = paths.iter().any(Option::is_some);
    let mut guide = a.guidance.guide()?;
    // The history this run writes (a replay only reads its own).
    let history = match &a.db {
        Some(db) if !matches!(input, Input::History(..)) => Some(Recorder::open(db)?),
        _ => None,
    };
    let decoded = match input {
        Input::Sample => {
            let mut dec = Decoder::new(BridgeConfig::default(), keep_track);
            options.survey(&mut dec);
            dec.feed(SAMPLE_DRIVE);
            dec.finish()
        }
        Input::Files(sources) => {
            let mut dec = Decoder::new(BridgeConfig::default(), keep_track);
            // The bearings to the history on the capture's day.
            let day = || crate::inputs::messages::capture_day(&sources);
            let mut stamper = history.as_ref().map(|h| (h, stamp(h, &mut dec, day())));
            // Each file is an input of its own: a unit whose records name no station is one
            // station per file.
            for (s, path) in sources.iter().zip(&a.captures) {
                let name = path.file_name().unwrap_or(path.as_os_str());
                dec.begin_input(&name.to_string_lossy())?;
                // Now this input's unnamed units have their labels.
                options.survey(&mut dec);
                stream(std::slice::from_ref(s), |b| {
                    dec.feed(b);
                    if let Some((h, s)) = &mut stamper {
                        h.keep_decoded(s, &mut dec);
                    }
                })?;
            }
            dec.end();
            if let Some((h, s)) = &mut stamper {
                h.keep_decoded(s, &mut dec);
            }
            dec.finish()
        }
        Input::History(db, window) => {
            let mut dec = Decoder::new(BridgeConfig::default(), keep_track);
            options.survey(&mut dec);
            replay(&db, window, &mut dec)?;
            dec.finish()
        }
        Input::Live(_) | Input::Gpsd(..) | Input::Kraken(..) | Input::Mqtt(_) => {
            let (source, gpsd) = match input {
                Input::Gpsd(source, g) => (source, Some(g)),
                Input::Kraken(url, g) => (LiveSource::Kraken(url), g),
                Input::Mqtt(url) => (
                    LiveSource::Mqtt {
                        url,
                        client_id: a.mqtt_client_id.clone(),
                        shard: a.mqtt_shard,
                        keep: a.mqtt_keep,
                    },
                    None,
                ),
                Input::Live(source) => (source, None),
                Input::Sample | Input::Files(_) | Input::History(..) => (LiveSource::Stdin, None),
            };
            let o = LiveOptions {
                source,
                gpsd,
                quiet_exit: quiet,
                locate: options.clone(),
                json: a.json,
                keep_track,
                cot: a.cot.clone(),
                history: history.clone(),
            };
            let end = live::run(&o, &mut guide, out)?;
            // The live updates were the output; a final fix goes only to the maps.
            if keep_track && let Ok(l) = locate(&end.decoded, &options) {
                write_maps(&l, &end.decoded, &paths, &outputs)?;
            }
            finish(a, &end.decoded, started);
            // The last update says how the line ended: with a fix, or why there is none.
            return end.no_fix.map_or(Ok(()), |e| Err(Stop::Error(e)));
        }
    };
    if let (Some(target), Some(file)) = (a.calibrate, &a.calibration) {
        // How well the bearings agree with a point of their own choosing, for the check that
        // they agree with the transmitter given.
        let free = locate(&decoded, &LocateOptions::default())
            .ok()
            .and_then(|l| {
                l.emitters
                    .iter()
                    .max_by_key(|e| e.used)
                    .map(|e| e.sigma.to_degrees())
            });
        let check = CalibrationCheck {
            max_offset_deg: a.max_offset_deg,
            free_fit_noise_deg: free,
        };
        let c = Calibration::measure(&decoded, target, &check)?;
        outputs.write(file, c.to_toml().as_bytes(), true)?;
        let text = if a.json {
            serde_json::to_string(&c).map_err(|e| e.to_string())?
        } else {
            c.text()
        };
        out.line(text.trim_end())?;
        finish(a, &decoded, started);
        return Ok(());
    }
    let located = locate_guided(&decoded, &options, &mut guide);
    if let Some(h) = &history {
        h.keep_update(&located);
    }
    let result = match located {
        Ok(l) => {
            write_maps(&l, &decoded, &paths, &outputs)?;
            if let Some(url) = &a.cot {
                let events = cot::events(&l, &decoded, std::time::SystemTime::now());
                CotSender::new(url.clone())
                    .send(&events)
                    .map_err(Stop::Error)?;
            }
            if a.json {
                let text = serde_json::to_string(&l.report).map_err(|e| e.to_string())?;
                out.line(&text)?;
            } else {
                out.text(&l.report.text())?;
            }
            Ok(())
        }
        Err(no_fix) => {
            // `--json` promises one object on standard output: why there is none, and the
            // advice from the bearings alone.
            // No fix, but regions (an open range): printed and drawn; still exit status 1.
            if let Some(l) = &no_fix.located {
                write_maps(l, &decoded, &paths, &outputs)?;
            } else if no_fix.reason == Some(crate::locate::explain::MOVING) {
                write_track_maps(a, &decoded, &options, &paths, &outputs)?;
            }
            if a.json {
                let text = serde_json::to_string(&no_fix).map_err(|e| e.to_string())?;
                out.line(&text)?;
            } else if let Some(l) = &no_fix.located {
                out.text(&l.report.text())?;
                if let Some(a) = &no_fix.across {
                    out.line(&format!("across: {}", a.line))?;
                }
            }
            Err(Stop::Error(no_fix.error))
        }
    };
    out.flush()?;
    finish(a, &decoded, started);
    result
}

/// The stamper of a recorded capture's bearings going to `h`: on the capture's `day`, today's
/// when it names none.
fn stamp(h: &Recorder, dec: &mut Decoder, day: Option<i64>) -> crate::inputs::messages::Stamper {
    let mut s = h.stamper(dec);
    s.dated = true;
    match day {
        Some(d) => s.day0_ms = d,
        None => note("history: no date in the capture, its times are counted from today"),
    }
    s
}

fn write_maps(
    l: &Located,
    d: &Decoded,
    paths: &[Option<PathBuf>; 3],
    outputs: &Outputs,
) -> Result<(), Stop> {
    let [geojson, kml, svg] = paths;
    if let Some(p) = geojson {
        outputs.write(p, maps::geojson(l, d).to_string().as_bytes(), true)?;
    }
    if let Some(p) = kml {
        outputs.write(p, maps::kml(l, d).as_bytes(), true)?;
    }
    if let Some(p) = svg {
        outputs.write(p, maps::svg(l, d).as_bytes(), true)?;
    }
    Ok(())
}

/// An emitter that moves has no still fix to draw: the maps asked for get its track instead,
/// as `foxhunt track` (at its defaults, with this run's stations, noise, channel width and
/// seed) draws it. An SVG (a still fix's picture) is not written, and the user is told.
fn write_track_maps(
    a: &Args,
    decoded: &Decoded,
    options: &LocateOptions,
    paths: &[Option<PathBuf>; 3],
    outputs: &Outputs,
) -> Result<(), Stop> {
    let [geojson, kml, svg] = paths;
    if geojson.is_none() && kml.is_none() && svg.is_none() {
        return Ok(());
    }
    let mut o = crate::commands::track::default_options()?;
    o.network = options.network.as_deref().cloned();
    o.sigma = a.sigma_deg.map(f32::to_radians);
    o.width_mhz = a.channel_width_mhz;
    o.seed = a.seed;
    let measured = crate::track::capture::Measured {
        decoded: decoded.clone(),
        ..Default::default()
    };
    let t = crate::track::tracks::tracks(&measured, None, &o)?;
    crate::commands::track::note_left_out(&t);
    crate::commands::track::note_noise(&t);
    if let Err(why) = crate::commands::track::untracked(&t) {
        note(&format!(
            "the emitter moves, and it has {why}: no map written"
        ));
        return Ok(());
    }
    crate::commands::track::write_maps(&t, [geojson.as_deref(), kml.as_deref()], outputs)?;
    let written: Vec<String> = [geojson, kml]
        .into_iter()
        .flatten()
        .map(|p| p.display().to_string())
        .collect();
    if !written.is_empty() {
        note(&format!(
            "the emitter moves: its track (as `foxhunt track` gives it) is in {}",
            written.join(" and ")
        ));
    }
    if let Some(p) = svg {
        note(&format!(
            "{}: not written: an SVG draws a still fix; the emitter moves (--geojson or --kml \
             draw its track)",
            p.display()
        ));
    }
    Ok(())
}

/// `--stats`: the bearings, the time and the memory.
fn finish(a: &Args, d: &Decoded, started: Instant) {
    if a.stats {
        note(&format!(
            "stats: bearings {}, seconds {:.3}, peak_bytes {}",
            d.observations.len(),
            started.elapsed().as_secs_f64(),
            crate::outputs::terminal::peak_bytes()
        ));
    }
}
