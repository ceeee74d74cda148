//! Inputs and outputs, one way for every command: captures streamed in bounded chunks, files
//! written only where the user said (never onto an input), standard output that ends quietly
//! when its reader goes away and fails loudly when the disk is full, one-line TOML errors.

use serde::de::DeserializeOwned;
use std::fs::File;
use std::io::{ErrorKind, Read, Write};
use std::path::{Path, PathBuf};

/// Why a command stopped early.
#[derive(Debug)]
pub enum Stop {
    /// An error to print on one line (exit status 1).
    Error(String),
    /// Standard output's reader went away (`foxhunt ... | head`): end quietly, as Unix tools do.
    Closed,
}

impl From<String> for Stop {
    fn from(e: String) -> Self {
        Stop::Error(e)
    }
}

impl From<&str> for Stop {
    fn from(e: &str) -> Self {
        Stop::Error(e.to_string())
    }
}

/// What every command returns.
pub type Outcome = Result<(), Stop>;

/// A line on standard error that never panics (a closed stderr loses the note, nothing else).
pub fn note(line: &str) {
    let _ = writeln!(std::io::stderr(), "{line}");
}

/// Standard output for reports: buffered, every error turned into a [`Stop`].
pub struct Out {
    inner: std::io::BufWriter<std::io::StdoutLock<'static>>,
}

impl Default for Out {
    fn default() -> Self {
        Self::new()
    }
}

impl Out {
    /// The process's standard output.
    pub fn new() -> Self {
        Self {
            inner: std::io::BufWriter::new(std::io::stdout().lock()),
        }
    }

    /// Write `text` as it is.
    pub fn text(&mut self, text: &str) -> Outcome {
        self.inner.write_all(text.as_bytes()).map_err(write_error)
    }

    /// Write one line.
    pub fn line(&mut self, line: &str) -> Outcome {
        self.text(line)?;
        self.text("\n")
    }

    /// Push what is buffered to the reader (live updates, and before exit: a full disk shows
    /// here).
    pub fn flush(&mut self) -> Outcome {
        self.inner.flush().map_err(write_error)
    }
}

impl Write for Out {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.inner.write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A write error on standard output as a [`Stop`].
pub fn write_error(e: std::io::Error) -> Stop {
    if e.kind() == ErrorKind::BrokenPipe {
        Stop::Closed
    } else {
        Stop::Error(format!("cannot write to standard output: {e}"))
    }
}

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
fn identity(p: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino()))
}

/// Where a command may write: never onto one of its inputs, and never over an existing file
/// the command line did not name unless `--force`.
#[derive(Debug, Default)]
pub struct Outputs {
    inputs: Vec<((u64, u64), PathBuf)>,
    force: bool,
}

impl Outputs {
    /// Outputs of a command reading `inputs`.
    pub fn new<'a>(inputs: impl IntoIterator<Item = &'a Path>, force: bool) -> Self {
        Self {
            inputs: inputs
                .into_iter()
                .filter_map(|p| identity(p).map(|id| (id, p.to_path_buf())))
                .collect(),
            force,
        }
    }

    /// Refuse `path` before any work is done: it is an input, or (when the command line did
    /// not name it) an existing file.
    pub fn check(&self, path: &Path, named: bool) -> Result<(), String> {
        if let Some(id) = identity(path)
            && let Some((_, input)) = self.inputs.iter().find(|(i, _)| *i == id)
        {
            return Err(format!(
                "refusing to write {}: it is the input {}",
                path.display(),
                input.display()
            ));
        }
        if !named && !self.force && path.exists() {
            return Err(format!(
                "refusing to overwrite {}, which the command line did not name (give --force)",
                path.display()
            ));
        }
        Ok(())
    }

    /// Write `bytes` to `path` after [`Outputs::check`]; say so on stderr.
    pub fn write(&self, path: &Path, bytes: &[u8], named: bool) -> Result<(), String> {
        self.check(path, named)?;
        let mut f =
            File::create(path).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        f.write_all(bytes)
            .and_then(|_| f.sync_data())
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        note(&format!("wrote {}", path.display()));
        Ok(())
    }
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
