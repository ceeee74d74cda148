//! `foxhunt track`: a ZigBee node tracked indoors from a coordinator's capture.

use crate::inputs::files::{Source, stream};
use crate::outputs::files::Outputs;
use crate::outputs::terminal::{Out, Outcome, note};
use crate::track::indoor::{AnchorsFile, track};
use std::path::PathBuf;

/// Options of `foxhunt track`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Capture file, or `-` for standard input.
    pub capture: PathBuf,
    /// The anchors file.
    #[arg(long)]
    pub anchors: PathBuf,
    /// Print JSON (an array of track points) instead of CSV.
    #[arg(long)]
    pub json: bool,
    /// Draw the room, anchors and track as SVG.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Seed of the particle filter.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Run `foxhunt track`.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    let outputs = Outputs::new([a.capture.as_path(), a.anchors.as_path()], false);
    if let Some(p) = &a.svg {
        outputs.check(p, true)?;
    }
    let file = AnchorsFile::load(&a.anchors)?;
    let mut bytes = Vec::new();
    stream(&[Source::from_path(&a.capture)], |b| {
        bytes.extend_from_slice(b)
    })?;
    let t = track(&bytes, &file, a.seed)?;
    if t.unknown.0 > 0 {
        let addrs: Vec<String> = t.unknown.1.iter().map(|a| format!("0x{a:04x}")).collect();
        note(&format!(
            "foxhunt: skipped {} frames from addresses not in {}: {}",
            t.unknown.0,
            a.anchors.display(),
            addrs.join(", ")
        ));
    }
    if let Some(p) = &a.svg {
        outputs.write(
            p,
            crate::outputs::maps::track_svg(&t, &file).as_bytes(),
            true,
        )?;
    }
    if a.json {
        let text = serde_json::to_string(&t.points).map_err(|e| e.to_string())?;
        out.line(&text)
    } else {
        out.text(&t.csv())
    }
}
