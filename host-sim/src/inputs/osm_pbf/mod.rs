//! OpenStreetMap PBF (`.osm.pbf`), read by hand: the nodes (plain and dense) and the ways with
//! their tags, what the road graph is built from ([`super::roads`]). Relations, changesets and
//! metadata are skipped. Hand-written because the crates generate their protobuf code at build
//! time, which cost a fresh release build 39 % of its CPU (docs/src/dependencies.md).
//!
//! The file is a run of blobs, each a 4-byte big-endian length, a `BlobHeader` {type,
//! datasize} and a `Blob` {raw or zlib_data, raw_size}: first an `OSMHeader` (the features a
//! reader must know), then `OSMData` blobs, each a `PrimitiveBlock` (a string table and groups
//! of nodes, dense nodes or ways). It is read one blob at a time: memory is one blob, which the
//! format caps at 32 MiB (bigger is refused before it is read), its inflated bytes (capped
//! alike) and the block's string table (8 bytes a string). Anything malformed is a one-line
//! [`PbfError`] naming the file, the blob and what is wrong.

mod block;
mod wire;

use block::primitive_block;
pub use block::{Element, Node, Tags, Way};
use std::fmt;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;
pub use wire::WireError;
use wire::{Fields, Value};

/// A `BlobHeader` longer than this is refused (the format's limit).
pub const MAX_BLOB_HEADER: u64 = 64 * 1024;
/// A blob, as stored and as inflated, longer than this is refused (the format's limit).
pub const MAX_BLOB: u64 = 32 * 1024 * 1024;

/// The required features this reader honours (a reader must refuse a file needing others).
const FEATURES: [&str; 2] = ["OsmSchema-V0.6", "DenseNodes"];

/// What is wrong with a PBF file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Problem {
    /// The file cannot be opened or read (the system's words).
    Read(String),
    /// The file ends inside this part of a blob.
    Truncated(&'static str),
    /// This part's length is over the format's limit.
    TooLarge {
        /// Which part.
        what: &'static str,
        /// Its length, bytes.
        size: u64,
        /// The limit, bytes.
        limit: u64,
    },
    /// Bytes that are not a protobuf message, in this message.
    Wire(&'static str, WireError),
    /// A field of this message has the wrong wire type, or is a repeated field that is not
    /// packed in one piece (what every OSM writer sends).
    Field(&'static str, u32),
    /// A message lacks a required field.
    Missing(&'static str),
    /// A compression this reader does not inflate (only raw and zlib blobs are read).
    Compression(&'static str),
    /// zlib data that does not inflate (the inflater's words).
    Zlib(String),
    /// The inflated length is not the blob's `raw_size`.
    RawSize {
        /// `raw_size`.
        declared: u64,
        /// What the zlib data inflated to.
        inflated: u64,
    },
    /// A tag names a string past the block's string table.
    StringIndex {
        /// The index.
        index: u64,
        /// Strings in the table.
        strings: usize,
    },
    /// A string of the table is not UTF-8.
    NotUtf8(usize),
    /// Columns of one element (or of dense nodes) that should be as long as each other are
    /// not.
    Columns(&'static str),
    /// Delta-coded values whose sum passes 64 bits.
    Overflow(&'static str),
    /// A block's `granularity` is not positive.
    Granularity(i64),
    /// Data before the `OSMHeader` blob (or no blob at all).
    NoHeader,
    /// A history file (`HistoricalInformation`): several versions of each element, deleted
    /// ones among them, which are not a road network.
    History,
    /// A required feature this reader does not know.
    Feature(String),
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Read(e) => write!(f, "cannot read: {e}"),
            Self::Truncated(what) => write!(f, "truncated: the file ends inside {what}"),
            Self::TooLarge { what, size, limit } => {
                write!(
                    f,
                    "{what} of {size} bytes, over the format's limit of {limit}"
                )
            }
            Self::Wire(what, e) => write!(f, "in {what}: {e}"),
            Self::Field(what, n) => write!(f, "field {n} of {what} has the wrong encoding"),
            Self::Missing(what) => write!(f, "{what} is missing"),
            Self::Compression(c) => write!(f, "{c} blobs are not read (only raw and zlib)"),
            Self::Zlib(e) => write!(f, "bad zlib data: {e}"),
            Self::RawSize { declared, inflated } => {
                write!(
                    f,
                    "zlib data inflates to {inflated} bytes, its raw_size says {declared}"
                )
            }
            Self::StringIndex { index, strings } => {
                write!(
                    f,
                    "string index {index} out of range (the table has {strings})"
                )
            }
            Self::NotUtf8(i) => write!(f, "string {i} of the table is not UTF-8"),
            Self::Columns(what) => write!(f, "{what} differ in length"),
            Self::Overflow(what) => write!(f, "delta-coded {what} overflow 64 bits"),
            Self::Granularity(g) => write!(f, "granularity {g} is not positive"),
            Self::NoHeader => write!(f, "no OSMHeader blob before the data: not an OSM PBF file"),
            Self::History => write!(
                f,
                "a history file (HistoricalInformation): give a current extract"
            ),
            Self::Feature(name) => write!(f, "needs feature {name:?}, which this reader lacks"),
        }
    }
}

/// A PBF file that cannot be read: the file, where, and what is wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PbfError {
    /// The file's name as given.
    pub file: String,
    /// Byte offset of the blob at fault (its length prefix), if any.
    pub at: Option<u64>,
    /// What is wrong.
    pub problem: Problem,
}

impl fmt::Display for PbfError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // One line, whatever the system's or the inflater's words.
        let problem = self.problem.to_string().replace(['\n', '\r'], " ");
        match self.at {
            Some(at) => write!(f, "{}: blob at byte {at}: {problem}", self.file),
            None => write!(f, "{}: {problem}", self.file),
        }
    }
}

impl std::error::Error for PbfError {}

/// A PBF file read blob by blob.
#[derive(Debug)]
pub struct PbfReader<R> {
    input: R,
    file: String,
    /// Bytes read so far: where the next blob starts.
    offset: u64,
    header_seen: bool,
    header: Vec<u8>,
    blob: Vec<u8>,
    inflated: Vec<u8>,
}

/// Every node and way of the PBF file at `path`, in file order, through `each`. On an error
/// the elements already given are part of a file that is not read whole.
pub fn read(path: &Path, each: impl FnMut(Element<'_>)) -> Result<(), PbfError> {
    let name = path.display().to_string();
    let file = File::open(path).map_err(|e| PbfError {
        file: name.clone(),
        at: None,
        problem: Problem::Read(e.to_string()),
    })?;
    PbfReader::new(BufReader::new(file), name).read_all(each)
}

impl<R: Read> PbfReader<R> {
    /// A reader of `input`, named `file` in its errors.
    pub fn new(input: R, file: impl Into<String>) -> Self {
        Self {
            input,
            file: file.into(),
            offset: 0,
            header_seen: false,
            header: Vec::new(),
            blob: Vec::new(),
            inflated: Vec::new(),
        }
    }

    /// Every node and way left, through `each`.
    pub fn read_all(mut self, mut each: impl FnMut(Element<'_>)) -> Result<(), PbfError> {
        while self.next_blob(&mut each)? {}
        Ok(())
    }

    /// The next blob's nodes and ways through `each`: false once the file has ended.
    pub fn next_blob(&mut self, each: &mut dyn FnMut(Element<'_>)) -> Result<bool, PbfError> {
        let at = self.offset;
        self.blob_step(each).map_err(|problem| PbfError {
            file: self.file.clone(),
            at: Some(at),
            problem,
        })
    }

    /// Reads up to `len` bytes into `buf` (cleared): how many came before the end of the file.
    fn take(&mut self, len: u64, buf: &mut Vec<u8>) -> Result<u64, Problem> {
        buf.clear();
        // Read as it comes, not reserved from the length: a false length costs nothing.
        let n = (&mut self.input)
            .take(len)
            .read_to_end(buf)
            .map_err(|e| Problem::Read(e.to_string()))? as u64;
        self.offset += n;
        Ok(n)
    }

    fn blob_step(&mut self, each: &mut dyn FnMut(Element<'_>)) -> Result<bool, Problem> {
        let mut header = std::mem::take(&mut self.header);
        let mut blob = std::mem::take(&mut self.blob);
        let r = self.blob_with(&mut header, &mut blob, each);
        self.header = header;
        self.blob = blob;
        r
    }

    fn blob_with(
        &mut self,
        header: &mut Vec<u8>,
        blob: &mut Vec<u8>,
        each: &mut dyn FnMut(Element<'_>),
    ) -> Result<bool, Problem> {
        match self.take(4, header)? {
            0 => {
                return if self.header_seen {
                    Ok(false)
                } else {
                    Err(Problem::NoHeader)
                };
            }
            4 => {}
            _ => return Err(Problem::Truncated("a blob's length")),
        }
        let len = header
            .get(..4)
            .and_then(|b| b.try_into().ok())
            .map_or(0, u32::from_be_bytes) as u64;
        if len > MAX_BLOB_HEADER {
            return Err(Problem::TooLarge {
                what: "a BlobHeader",
                size: len,
                limit: MAX_BLOB_HEADER,
            });
        }
        if self.take(len, header)? < len {
            return Err(Problem::Truncated("a BlobHeader"));
        }
        let (kind, datasize) = blob_header(header)?;
        if datasize > MAX_BLOB {
            return Err(Problem::TooLarge {
                what: "a blob",
                size: datasize,
                limit: MAX_BLOB,
            });
        }
        if self.take(datasize, blob)? < datasize {
            return Err(Problem::Truncated("a blob"));
        }
        match kind {
            BlobKind::Header => {
                osm_header(payload(blob, &mut self.inflated)?)?;
                self.header_seen = true;
            }
            BlobKind::Data if !self.header_seen => return Err(Problem::NoHeader),
            BlobKind::Data => primitive_block(payload(blob, &mut self.inflated)?, each)?,
            // Unknown blob types are skipped, as the format asks.
            BlobKind::Other => {}
        }
        Ok(true)
    }
}

/// A blob's type.
enum BlobKind {
    Header,
    Data,
    Other,
}

/// A `BlobHeader`: the blob's type and length.
fn blob_header(bytes: &[u8]) -> Result<(BlobKind, u64), Problem> {
    let what = "a BlobHeader";
    let (mut kind, mut datasize) = (None, None);
    for f in Fields::new(bytes) {
        match f.map_err(|e| Problem::Wire(what, e))? {
            (1, Value::Bytes(t)) => {
                kind = Some(match t {
                    b"OSMHeader" => BlobKind::Header,
                    b"OSMData" => BlobKind::Data,
                    _ => BlobKind::Other,
                })
            }
            (3, Value::Varint(n)) => datasize = Some(int32(n, what, 3)?),
            (n @ (1 | 3), _) => return Err(Problem::Field(what, n)),
            _ => {}
        }
    }
    let kind = kind.ok_or(Problem::Missing("a BlobHeader's type"))?;
    let size = datasize.ok_or(Problem::Missing("a BlobHeader's datasize"))?;
    // A negative int32 is a size no blob has.
    let size = u64::try_from(size).map_err(|_| Problem::Field(what, 3))?;
    Ok((kind, size))
}

/// An `int32` field: a varint of a sign-extended 32-bit value.
fn int32(n: u64, what: &'static str, field: u32) -> Result<i64, Problem> {
    let v = n as i64;
    i32::try_from(v)
        .map(i64::from)
        .map_err(|_| Problem::Field(what, field))
}

/// A `Blob`'s data, inflated into `inflated` when zlib-compressed.
fn payload<'b>(blob: &'b [u8], inflated: &'b mut Vec<u8>) -> Result<&'b [u8], Problem> {
    let what = "a Blob";
    let (mut raw, mut zlib, mut raw_size) = (None, None, None);
    for f in Fields::new(blob) {
        match f.map_err(|e| Problem::Wire(what, e))? {
            (1, Value::Bytes(b)) => raw = Some(b),
            (2, Value::Varint(n)) => raw_size = Some(int32(n, what, 2)?),
            (3, Value::Bytes(b)) => zlib = Some(b),
            (4, _) => return Err(Problem::Compression("lzma")),
            (5, _) => return Err(Problem::Compression("bzip2")),
            (6, _) => return Err(Problem::Compression("lz4")),
            (7, _) => return Err(Problem::Compression("zstd")),
            (n @ 1..=3, _) => return Err(Problem::Field(what, n)),
            _ => {}
        }
    }
    if let Some(raw) = raw {
        return Ok(raw);
    }
    let zlib = zlib.ok_or(Problem::Missing("a Blob's data"))?;
    let declared = match raw_size {
        Some(n) => Some(u64::try_from(n).map_err(|_| Problem::Field(what, 2))?),
        None => None,
    };
    if let Some(n) = declared.filter(|n| *n > MAX_BLOB) {
        return Err(Problem::TooLarge {
            what: "an inflated blob",
            size: n,
            limit: MAX_BLOB,
        });
    }
    inflated.clear();
    // Inflated as it comes, one byte past the cap to see it passed: a zlib bomb stops there.
    flate2::read::ZlibDecoder::new(zlib)
        .take(MAX_BLOB + 1)
        .read_to_end(inflated)
        .map_err(|e| Problem::Zlib(e.to_string()))?;
    let n = inflated.len() as u64;
    if n > MAX_BLOB {
        return Err(Problem::TooLarge {
            what: "an inflated blob",
            size: n,
            limit: MAX_BLOB,
        });
    }
    if let Some(declared) = declared.filter(|d| *d != n) {
        return Err(Problem::RawSize {
            declared,
            inflated: n,
        });
    }
    Ok(inflated)
}

/// An `OSMHeader`'s `HeaderBlock`: its required features must all be known.
fn osm_header(block: &[u8]) -> Result<(), Problem> {
    let what = "a HeaderBlock";
    for f in Fields::new(block) {
        match f.map_err(|e| Problem::Wire(what, e))? {
            (4, Value::Bytes(name)) => {
                let name = String::from_utf8_lossy(name);
                if name == "HistoricalInformation" {
                    return Err(Problem::History);
                }
                if !FEATURES.contains(&name.as_ref()) {
                    return Err(Problem::Feature(name.into_owned()));
                }
            }
            (4, _) => return Err(Problem::Field(what, 4)),
            _ => {}
        }
    }
    Ok(())
}
