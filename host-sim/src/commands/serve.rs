//! `foxhunt serve`: the live map of a replayed capture, of standard input, or of a live line
//! (KrakenSDRs' web pages, an MQTT broker).

use super::{GuidanceArgs, NetworkArgs, values};
use crate::commands::locate::live::{LiveSource, reader};
use crate::commands::locate::network_line;
use crate::estimate::options::LocateOptions;
use crate::inputs::files::{InputKind, Source};
use crate::outputs::serve::{Input, ServeOptions, serve};
use crate::outputs::terminal::{Outcome, Stop};
use std::path::PathBuf;
use std::time::Duration;

/// Options of `foxhunt serve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Capture files replayed in order, or `-` for standard input (read as it arrives).
    pub captures: Vec<PathBuf>,
    /// Live: poll a KrakenSDR's web page, `http://HOST:8081` (repeatable: every unit polled
    /// at once, each a station of its own); no CAPTURE.
    #[arg(long, value_name = "URL")]
    pub kraken: Vec<String>,
    /// Live: every station's bearings from an MQTT broker, `mqtt://HOST[:PORT]/PREFIX` (as
    /// `locate --mqtt` reads them); no CAPTURE.
    #[arg(long, value_name = "URL")]
    pub mqtt: Option<String>,
    /// With --mqtt: the client id of the broker session.
    #[arg(
        long,
        value_name = "ID",
        default_value = "foxhunt-serve",
        requires = "mqtt"
    )]
    pub mqtt_client_id: String,
    /// Live: the input ends after this many seconds without a bearing's bytes (default: the
    /// line is followed until stopped).
    #[arg(long, value_parser = values::seconds())]
    pub quiet_exit: Option<f64>,
    /// Address to listen on (port 0: any free port; the address is printed on stderr).
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: String,
    /// The roads and the stop rule's target.
    #[command(flatten)]
    pub guidance: GuidanceArgs,
    /// The stations file and the reference transmitters, as `locate` takes them: the map's
    /// fix, stations and tracks are `locate`'s and `track`'s with them.
    #[command(flatten)]
    pub network: NetworkArgs,
    /// Online map tiles, a URL template such as `https://tile.example/{z}/{x}/{y}.png`.
    #[arg(long)]
    pub tiles: Option<String>,
    /// Replay: lines of the capture per update (at least 1).
    #[arg(long, default_value_t = 20, value_parser = values::count_at_least(1, "lines"))]
    pub chunk_lines: usize,
    /// Replay: seconds between updates.
    #[arg(long, default_value_t = 0.2, value_parser = values::seconds())]
    pub pace: f64,
    /// Exit this many seconds after the input ends (default: serve until stopped).
    #[arg(long, value_parser = values::seconds())]
    pub linger: Option<f64>,
}

/// The live line `--kraken` or `--mqtt` asks for, read as `locate` reads it.
fn line(a: &Args) -> Result<Option<Input>, Stop> {
    let other = !a.captures.is_empty();
    let Some(source) = network_line(&a.kraken, a.mqtt.as_deref(), &a.mqtt_client_id, other)? else {
        return Ok(None);
    };
    let names: Vec<String> = match &source {
        LiveSource::Kraken(urls) if urls.len() > 1 => urls
            .iter()
            .map(|u| u.base.trim_start_matches("http://").to_string())
            .collect(),
        _ => Vec::new(),
    };
    let quiet = a.quiet_exit.map(Duration::from_secs_f64);
    let mut line = reader(&source, None, None)?;
    let mut started = false;
    Ok(Some(Input::Line(Box::new(move |dec| {
        if !started {
            started = true;
            // Several KrakenSDRs: each URL an input, so a unit without a STATION_ID is a
            // station of its own.
            for n in &names {
                dec.begin_input(n)?;
            }
        }
        line.take(dec, quiet, true).map_err(|s| match s {
            Stop::Error(e) | Stop::Usage(e) => e,
            Stop::Closed => "the line closed".into(),
        })
    }))))
}

/// Run `foxhunt serve`.
pub fn run(a: &Args) -> Outcome {
    // The stations file read and checked before a line is polled or the server starts.
    let locate = LocateOptions {
        network: a.network.network()?,
        ..LocateOptions::default()
    };
    let input = match (line(a)?, a.captures.as_slice()) {
        (Some(live), _) => live,
        (None, []) => {
            return Err(Stop::usage(
                "give a CAPTURE, - for standard input, --kraken or --mqtt",
            ));
        }
        (None, captures) => replayed(a, captures)?,
    };
    serve_input(a, input, locate)
}

/// Capture files to replay, or standard input.
fn replayed(a: &Args, captures: &[PathBuf]) -> Result<Input, Stop> {
    Ok(match captures {
        [one] if one.as_os_str() == "-" => Input::Stdin,
        many if many.iter().any(|p| p.as_os_str() == "-") => {
            return Err(Stop::usage(
                "standard input (-) is read live: give it alone",
            ));
        }
        many => {
            // Every file readable as a capture before the server starts: a missing file or a
            // device is the command's error, not a page that never fills.
            for p in many {
                let source = Source::from_path(p);
                if source.kind()? == InputKind::Serial {
                    return Err(Stop::usage(format!(
                        "{} is a serial device: serve reads it as standard input, `cat {0} | \
                         foxhunt serve -` (after `stty -F {0} 4800 raw`)",
                        p.display()
                    )));
                }
                source.check_capture()?;
            }
            Input::Replay {
                files: many.to_vec(),
                lines: a.chunk_lines,
                pace: Duration::from_secs_f64(a.pace),
            }
        }
    })
}

/// Serve `input`, located as `locate` says.
fn serve_input(a: &Args, input: Input, locate: LocateOptions) -> Outcome {
    let linger = a.linger.map(Duration::from_secs_f64);
    serve(ServeOptions {
        addr: a.addr.clone(),
        input,
        guide: a.guidance.guide()?,
        tiles: a.tiles.clone(),
        linger,
        locate,
    })
    .map_err(Into::into)
}
