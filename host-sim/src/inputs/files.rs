//! Input files, one way for every command: captures streamed in bounded chunks, side files
//! read whole up to a cap (they are small: a larger one is the wrong file), road extracts
//! streamed up to theirs, and what is not a file refused by name before anything is read.

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

/// What a path is, as an input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// A regular file of this many bytes.
    File(u64),
    /// A pipe (standard input, a FIFO, `<(...)`): read as a stream.
    Pipe,
    /// A serial port (a terminal device): read live with `--baud`.
    Serial,
    /// Another device (`/dev/null`, `/dev/zero`, a disk): no capture.
    Device,
    /// A directory.
    Directory,
    /// A socket or anything else.
    Other,
}

/// Whether the character device of `meta` is a terminal (a serial port, a pseudo-terminal):
/// on Linux sysfs names its class; a device sysfs does not list (a pseudo-terminal) is one
/// unless it is a memory device (`/dev/null`, `/dev/zero`: major 1). Elsewhere every
/// character device is taken for one.
fn is_terminal_device(meta: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    if !cfg!(target_os = "linux") {
        return true;
    }
    let rdev = meta.rdev();
    // glibc's gnu_dev_major and gnu_dev_minor.
    let major = ((rdev >> 8) & 0xfff) | ((rdev >> 32) & !0xfff);
    let minor = (rdev & 0xff) | ((rdev >> 12) & !0xff);
    match std::fs::read_link(format!("/sys/dev/char/{major}:{minor}/subsystem")) {
        Ok(class) => class.ends_with("tty"),
        Err(_) => major != 1,
    }
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

    /// What the source is (`cannot read PATH: ...` when it cannot be looked at).
    pub fn kind(&self) -> Result<InputKind, String> {
        let Source::File(p) = self else {
            return Ok(InputKind::Pipe);
        };
        kind_of(p)
    }

    /// Refuse on one line what cannot be read as a capture: a directory, a device that is not
    /// a serial port, a serial port (read with `--baud`), a missing file.
    pub fn check_capture(&self) -> Result<(), String> {
        let name = self.name();
        match self.kind()? {
            InputKind::File(_) | InputKind::Pipe => Ok(()),
            InputKind::Serial => Err(format!(
                "{name} is a serial device: give --baud (4800 for NMEA 0183, 115200 for a ZNP)"
            )),
            k => Err(not_a_file(&name, k, "a capture")),
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

/// What `path` is (`cannot read PATH: ...` when it cannot be looked at).
pub fn kind_of(path: &Path) -> Result<InputKind, String> {
    use std::os::unix::fs::FileTypeExt;
    let meta =
        std::fs::metadata(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let t = meta.file_type();
    Ok(if t.is_file() {
        InputKind::File(meta.len())
    } else if t.is_fifo() {
        InputKind::Pipe
    } else if t.is_dir() {
        InputKind::Directory
    } else if t.is_char_device() && is_terminal_device(&meta) {
        InputKind::Serial
    } else if t.is_char_device() || t.is_block_device() {
        InputKind::Device
    } else {
        InputKind::Other
    })
}

/// `NAME is a directory, not WANTED`, and the like, for what no input can be.
fn not_a_file(name: &str, kind: InputKind, wanted: &str) -> String {
    let what = match kind {
        InputKind::Directory => "a directory",
        InputKind::Device => "a device (not a serial port)",
        InputKind::Serial => "a serial device",
        InputKind::Other => "neither a file nor a pipe",
        InputKind::File(_) | InputKind::Pipe => "a file",
    };
    format!("{name} is {what}, not {wanted}")
}

/// Bytes read at a time: memory stays bounded whatever the capture's size.
pub const CHUNK: usize = 64 * 1024;

/// Stream every source in order through `sink`, `CHUNK` bytes at a time; the total read.
pub fn stream(sources: &[Source], mut sink: impl FnMut(&[u8])) -> Result<u64, String> {
    let mut buf = vec![0u8; CHUNK];
    let mut total = 0u64;
    for s in sources {
        s.check_capture()?;
    }
    for s in sources {
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

/// The most a side file read whole may hold (a scenario, anchors or calibration file: a few
/// KB each), so that `/dev/zero` or a wrong multi-gigabyte file given as one is refused, not
/// read into memory.
pub const SIDE_FILE_CAP: u64 = 1 << 20;

/// The most a road extract may hold (`--roads`): a city's or a county's OSM data, which is
/// what guidance drives on; cut a larger region with `osmium extract`.
pub const ROADS_CAP: u64 = 512 << 20;

/// `n` bytes in words (`1 MiB`, `512 MiB`, `1.0 GB`).
fn bytes(n: u64) -> String {
    match n {
        n if n >= 1 << 30 && n % (1 << 30) == 0 => format!("{} GiB", n >> 30),
        n if n >= 1 << 20 && n % (1 << 20) == 0 => format!("{} MiB", n >> 20),
        n if n >= 1_000_000_000 => format!("{:.1} GB", n as f64 / 1e9),
        n if n >= 1_000_000 => format!("{:.1} MB", n as f64 / 1e6),
        n => format!("{n} bytes"),
    }
}

/// Open `path` for reading at most `cap` bytes of it as `what` ("a scenario file"): a file
/// larger than `cap`, a directory, a device or a serial port is refused by name before
/// anything is read; a pipe is read up to the cap. The reader fails past the cap.
pub fn open_capped(path: &Path, cap: u64, what: &str) -> Result<impl Read + use<>, String> {
    let name = path.display().to_string();
    match kind_of(path)? {
        InputKind::File(len) if len > cap => {
            return Err(format!(
                "{name} is {}, more than {what} may hold ({})",
                bytes(len),
                bytes(cap)
            ));
        }
        InputKind::File(_) | InputKind::Pipe => {}
        k => return Err(not_a_file(&name, k, what)),
    }
    let file = File::open(path).map_err(|e| format!("cannot read {name}: {e}"))?;
    Ok(Capped {
        inner: file.take(cap + 1),
        read: 0,
        cap,
        what: what.to_string(),
    })
}

/// A reader that fails once more than `cap` bytes have come (a pipe without end).
struct Capped<R> {
    inner: R,
    read: u64,
    cap: u64,
    what: String,
}

impl<R: Read> Read for Capped<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        if self.read > self.cap {
            return Err(std::io::Error::other(format!(
                "more than {} may hold ({})",
                self.what,
                bytes(self.cap)
            )));
        }
        Ok(n)
    }
}

/// Read a side file whole (a scenario, anchors or calibration file: TOML text), at most
/// [`SIDE_FILE_CAP`] bytes.
pub fn read_text(path: &Path) -> Result<String, String> {
    let mut bytes = Vec::new();
    open_capped(
        path,
        SIDE_FILE_CAP,
        "a side file (scenario, anchors, calibration)",
    )?
    .read_to_end(&mut bytes)
    .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    String::from_utf8(bytes).map_err(|e| {
        format!(
            "{}: not text (a byte that is not UTF-8 at {})",
            path.display(),
            e.utf8_error().valid_up_to()
        )
    })
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
