//! `foxhunt serve`: the live map of a replayed capture or of standard input.

use super::GuidanceArgs;
use crate::outputs::serve::{Input, ServeOptions, serve};
use crate::outputs::terminal::Outcome;
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
    /// Replay: lines of the capture per update.
    #[arg(long, default_value_t = 20)]
    pub chunk_lines: usize,
    /// Replay: seconds between updates.
    #[arg(long, default_value_t = 0.2)]
    pub pace: f64,
    /// Exit this many seconds after the input ends (default: serve until stopped).
    #[arg(long)]
    pub linger: Option<f64>,
}

fn seconds(name: &str, s: f64) -> Result<Duration, String> {
    if s >= 0.0 && s.is_finite() {
        Ok(Duration::from_secs_f64(s))
    } else {
        Err(format!("--{name} wants a number of seconds >= 0, not {s}"))
    }
}

/// Run `foxhunt serve`.
pub fn run(a: &Args) -> Outcome {
    let input = match a.captures.as_slice() {
        [one] if one.as_os_str() == "-" => Input::Stdin,
        many if many.iter().any(|p| p.as_os_str() == "-") => {
            return Err("standard input (-) is read live: give it alone".into());
        }
        many => Input::Replay {
            files: many.to_vec(),
            lines: a.chunk_lines.max(1),
            pace: seconds("pace", a.pace)?,
        },
    };
    let linger = a.linger.map(|l| seconds("linger", l)).transpose()?;
    serve(ServeOptions {
        addr: a.addr.clone(),
        input,
        guide: a.guidance.guide()?,
        tiles: a.tiles.clone(),
        linger,
    })
    .map_err(Into::into)
}
