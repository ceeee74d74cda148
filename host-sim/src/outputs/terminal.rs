//! Standard output and standard error, one way for every command: output that ends quietly
//! when its reader goes away and fails loudly when the disk is full, and a command's outcome.

use std::io::{ErrorKind, Write};

/// Why a command stopped early.
#[derive(Debug)]
pub enum Stop {
    /// No result: the input gave no fix (or track), or a file could not be read or written.
    /// One line on standard error, exit status 1.
    Error(String),
    /// The command line cannot be run as given: flags that do not go together, or a value the
    /// command refuses in their context. One line on standard error, exit status 2, as clap's
    /// own usage errors.
    Usage(String),
    /// Standard output's reader went away (`foxhunt ... | head`): end quietly, as Unix tools do.
    Closed,
}

impl Stop {
    /// A usage error.
    pub fn usage(e: impl Into<String>) -> Self {
        Stop::Usage(e.into())
    }

    /// The process's exit status: 0 when the reader went away, 1 without a result, 2 on a
    /// usage error.
    pub fn status(&self) -> u8 {
        match self {
            Stop::Closed => 0,
            Stop::Error(_) => 1,
            Stop::Usage(_) => 2,
        }
    }

    /// The line to print, if any.
    pub fn message(&self) -> Option<&str> {
        match self {
            Stop::Error(e) | Stop::Usage(e) => Some(e),
            Stop::Closed => None,
        }
    }
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

/// Peak resident memory of this process, bytes (`VmHWM` of /proc/self/status; 0 where the
/// system has none): what `--stats` and the benchmarks report.
pub fn peak_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}
