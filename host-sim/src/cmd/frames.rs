//! `foxhunt frames`: every decoded frame of a capture as a JSON line.

use crate::io::{Out, Outcome, Source, stream, write_error};
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
    crate::frames::write_frames(&bytes, out).map_err(write_error)
}
