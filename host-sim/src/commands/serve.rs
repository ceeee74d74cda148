//! `foxhunt serve`: the live map of a replayed capture or of standard input.

use super::{GuidanceArgs, values};
use crate::inputs::files::{InputKind, Source};
use crate::outputs::serve::{Input, ServeOptions, serve};
use crate::outputs::terminal::{Outcome, Stop};
use std::path::PathBuf;
use std::time::Duration;

/// Options of `foxhunt serve`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Capture files replayed in order, or `-` for standard input (read as it arrives).
    #[arg(required = true)]
    pub captures: Vec<PathBuf>,
    /// Address to listen on (port 0: any free port; the address is printed on stderr).
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: String,
    /// The roads and the stop rule's target.
    #[command(flatten)]
    pub guidance: GuidanceArgs,
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

/// Run `foxhunt serve`.
pub fn run(a: &Args) -> Outcome {
    let input = match a.captures.as_slice() {
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
    };
    let linger = a.linger.map(Duration::from_secs_f64);
    serve(ServeOptions {
        addr: a.addr.clone(),
        input,
        guide: a.guidance.guide()?,
        tiles: a.tiles.clone(),
        linger,
    })
    .map_err(Into::into)
}
