//! `foxhunt frames`: every decoded frame of a capture as a JSON line.

use crate::inputs::files::{Source, stream};
use crate::outputs::terminal::{Out, Outcome, write_error};
use std::path::PathBuf;

/// Options of `foxhunt frames`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Capture file, or `-` for standard input.
    pub capture: PathBuf,
}

/// Run `foxhunt frames`.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    let mut bytes = Vec::new();
    stream(&[Source::from_path(&a.capture)], |b| {
        bytes.extend_from_slice(b)
    })?;
    crate::outputs::frames::write_frames(&bytes, out).map_err(write_error)
}
