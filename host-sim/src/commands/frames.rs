//! `foxhunt frames`: every decoded frame of a capture as a JSON line.

use crate::inputs::files::{Source, stream};
use crate::outputs::frames::FramesWriter;
use crate::outputs::terminal::{Out, Outcome, write_error};
use std::path::PathBuf;

/// Options of `foxhunt frames`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Capture file, or `-` for standard input.
    pub capture: PathBuf,
}

/// Run `foxhunt frames`: frames are written as the capture is read, in bounded memory.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    let mut w = FramesWriter::new();
    let mut failed = None;
    stream(&[Source::from_path(&a.capture)], |b| {
        if failed.is_none() {
            failed = w.feed(b, out).err();
        }
    })?;
    if let Some(e) = failed {
        return Err(write_error(e));
    }
    w.finish(out).map_err(write_error)
}
