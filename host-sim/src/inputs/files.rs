//! Input files, one way for every command: captures streamed in bounded chunks, side files
//! read whole (they are small), one-line TOML errors.

use serde::de::DeserializeOwned;
use std::fs::File;
use std::io::{ErrorKind, Read};
use std::path::{Path, PathBuf};

/// Where a command's bytes come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A file.
    File(PathBuf),
    /// Standard input (`-`).
    Stdin,
}

impl Source {
    /// `-` is standard input; anything else a file.
    pub fn from_path(p: &Path) -> Self {
        if p.as_os_str() == "-" {
            Source::Stdin
        } else {
            Source::File(p.to_path_buf())
        }
    }

    /// Whether this is a character device (a serial port): read those with `--baud`.
    pub fn is_device(&self) -> bool {
        use std::os::unix::fs::FileTypeExt;
        match self {
            Source::File(p) => std::fs::metadata(p).is_ok_and(|m| m.file_type().is_char_device()),
            Source::Stdin => false,
        }
    }

    /// Open for reading.
    pub fn open(&self) -> Result<Box<dyn Read + Send>, String> {
        match self {
            Source::Stdin => Ok(Box::new(std::io::stdin())),
            Source::File(p) => File::open(p)
                .map(|f| Box::new(f) as Box<dyn Read + Send>)
                .map_err(|e| format!("cannot read {}: {e}", p.display())),
        }
    }

    /// How the source is named in messages.
    pub fn name(&self) -> String {
        match self {
            Source::Stdin => "standard input".into(),
            Source::File(p) => p.display().to_string(),
        }
    }
}

/// Bytes read at a time: memory stays bounded whatever the capture's size.
pub const CHUNK: usize = 64 * 1024;

/// Stream every source in order through `sink`, `CHUNK` bytes at a time; the total read.
pub fn stream(sources: &[Source], mut sink: impl FnMut(&[u8])) -> Result<u64, String> {
    let mut buf = vec![0u8; CHUNK];
    let mut total = 0u64;
    for s in sources {
        if s.is_device() {
            return Err(format!(
                "{} is a serial device: give --baud (4800 for NMEA 0183, 115200 for a ZNP)",
                s.name()
            ));
        }
        let mut r = s.open()?;
        loop {
            match r.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    total += n as u64;
                    sink(&buf[..n]);
                }
                Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                Err(e) => return Err(format!("cannot read {}: {e}", s.name())),
            }
        }
    }
    Ok(total)
}

/// Identity of a file on disk (device and inode), to tell an output that is an input under
/// another name.
pub fn identity(p: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
}

/// Read a small text file (a scenario or anchors file).
pub fn read_text(path: &Path) -> Result<String, String> {
    std::fs::read_to_string(path).map_err(|e| format!("cannot read {}: {e}", path.display()))
}

/// Parse TOML into `T`; the error on one line: `line L, column C: what`.
pub fn parse_toml<T: DeserializeOwned>(text: &str) -> Result<T, String> {
    toml::from_str(text).map_err(|e| toml_error(&e, text))
}

/// A TOML error on one line, with its position in `text` when known.
pub fn toml_error(e: &toml::de::Error, text: &str) -> String {
    let what = e.message().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("line {line}, column {column}: {what}")
        }
        None => what,
    }
}

/// Read and parse a TOML file; errors name the file.
pub fn load_toml<T: DeserializeOwned>(path: &Path) -> Result<T, String> {
    let text = read_text(path)?;
    parse_toml(&text).map_err(|e| format!("{}: {e}", path.display()))
}
