//! The byte-stream demultiplexer: bytes in any chunking in, whole checked records out.
//!
//! One UART (or one file) may interleave NMEA sentences (`$` ... `*hh` CRLF), TI
//! Monitor-and-Test frames (`0xFE`, LEN, CMD0, CMD1, DATA, FCS), Agrelo bearings (`%`), KrakenSDR
//! XML records (`<`) and KrakenSDR CSV lines (a digit). The demultiplexer keeps the unparsed
//! bytes in a fixed buffer and looks only at the first one; anything else is garbage, skipped
//! and counted (whitespace between records is skipped silently). A candidate that fails its
//! check costs only its first byte: scanning resumes at the next byte, so a corrupt byte never
//! swallows the valid records after it. Binary protocols of GPS receivers (u-blox UBX, SiRF,
//! RTCM) are garbage here: skipped, with the sentences around them kept.
//!
//! The Kraken records are decoded as they arrive, a field or a tag at a time
//! ([`crate::kraken`]), so a 2.5 KB CSV line needs no 2.5 KB buffer. A record that fails
//! after its first field is dropped (counted by reason) and scanning resumes at the field that
//! failed, which may be the start of the next record (a corrupted line end); one that fails
//! in its first field was never a record: its first byte is garbage. CSV has no checksum: a
//! corrupt digit that keeps a field well formed gives a wrong value, as it would for any
//! reader of the format.
//!
//! An 8-bit XOR check passes one forgery in 256. A forged MT frame (a corrupt LEN, or a `0xFE`
//! inside a damaged sentence) would span and swallow the genuine frames after it, so an MT
//! candidate is also refused when a complete, valid frame starts strictly inside it; that
//! decision may have to wait for the bytes of the inner candidate, at most one more MT frame.
//! [`Demux::idle`] (the line went quiet) and [`Demux::finish`] (end of a capture) settle such a
//! wait at once. A sentence cannot be forged across frames: its body must be printable ASCII
//! without `$`, which the bytes of any other frame break.
//!
//! The checks of a candidate (a sentence's line end and checksum, an MT frame's FCS, the
//! overlap rule) are in `scan.rs`; the demultiplexer's buffer and state are here.

// The demultiplexer indexes its own buffer within the start and end it keeps, and its
// checks index the candidate bytes they have measured.
#![allow(clippy::indexing_slicing)]

mod scan;
#[cfg(test)]
mod tests;

use crate::agrelo;
use crate::kraken::{
    CsvDecoder, KrakenCsv, KrakenError, KrakenXml, SPECTRUM_LEN, Step, XmlDecoder,
};
use crate::record::{Framing, RecordKind};
use scan::{Overlap, Reject, Scan, resolve_overlap, scan_mt, scan_sentence_from};

/// Longest NMEA sentence, `$` to LF inclusive: GPSD's limit (`NMEA_MAX` in its `gpsd.h`), since
/// RTK receivers print more decimals than NMEA 0183's 82 characters allow.
pub const MAX_SENTENCE: usize = 130;
/// Longest MT frame: SOF, LEN, CMD0, CMD1, 255 data bytes, FCS.
pub const MAX_MT_FRAME: usize = 255 + 5;
/// Default buffer: room for an MT frame and a second one starting inside it, so every wait
/// for more bytes ends before the buffer is full.
pub const DEFAULT_CAPACITY: usize = 2 * MAX_MT_FRAME + 8;
pub use crate::mt::MT_SOF;

/// One checked frame, borrowed from the demultiplexer's buffer until the next call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Frame<'a> {
    /// An NMEA sentence whose checksum matched: the text between `$` and `*`.
    Nmea(&'a str),
    /// A Monitor-and-Test frame whose FCS matched.
    Mt(MtFrame<'a>),
    /// An Agrelo record that parses: its text from `%` up to the line end
    /// ([`crate::agrelo::Agrelo::parse`] decodes it).
    Agrelo(&'a str),
    /// A KrakenSDR CSV line, decoded.
    KrakenCsv(KrakenCsvFrame<'a>),
    /// A KrakenSDR / KerberosSDR XML record, decoded.
    KrakenXml(KrakenXml),
}

/// A decoded CSV line and, when the demultiplexer keeps one, its DoA spectrum (dB above its
/// minimum, indexed anticlockwise from the array's front as the unit writes it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KrakenCsvFrame<'a> {
    /// The line's fields.
    pub record: KrakenCsv,
    /// The 360 spectrum values, if kept.
    pub spectrum: Option<&'a [f32]>,
}

impl KrakenCsvFrame<'_> {
    /// The spectrum at a bearing `deg` degrees clockwise from the array's front: value
    /// `(360 − deg) mod 360` of the anticlockwise list.
    pub fn spectrum_clockwise(&self, deg: u16) -> Option<f32> {
        let i = (360 - usize::from(deg % 360)) % SPECTRUM_LEN;
        self.spectrum?.get(i).copied()
    }
}

impl Frame<'_> {
    /// What the frame is: [`RecordKind::of_sentence`] of a sentence, else its format.
    pub fn kind(&self) -> RecordKind {
        match self {
            Self::Nmea(body) => RecordKind::of_sentence(body),
            Self::Mt(_) => RecordKind::Mt,
            Self::Agrelo(_) => RecordKind::Agrelo,
            Self::KrakenCsv(_) => RecordKind::KrakenCsv,
            Self::KrakenXml(_) => RecordKind::KrakenXml,
        }
    }
}

pub use crate::mt::MtFrame;

/// Whitespace between records, skipped without counting it as garbage.
fn blank(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n')
}

/// What the demultiplexer has seen and thrown away, by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StreamCounters {
    /// Bytes received.
    pub bytes: u64,
    /// NMEA sentences delivered.
    pub sentences: u32,
    /// MT frames delivered.
    pub mt_frames: u32,
    /// Bytes skipped while looking for a start of frame.
    pub garbage_bytes: u32,
    /// Sentences whose checksum did not match.
    pub bad_checksum: u32,
    /// Sentences without a `*hh` checksum or with a byte outside printable ASCII.
    pub malformed: u32,
    /// Sentences with no line end within [`MAX_SENTENCE`] bytes.
    pub too_long: u32,
    /// MT frames whose FCS did not match.
    pub bad_fcs: u32,
    /// MT candidates refused because a valid frame starts inside them (forged by corruption).
    pub overlapping: u32,
    /// Unfinished frames dropped at the end of the stream.
    pub truncated: u32,
    /// Agrelo records delivered.
    pub agrelo: u32,
    /// `%` and a digit that did not make an Agrelo record.
    pub agrelo_malformed: u32,
    /// KrakenSDR CSV lines delivered.
    pub kraken_csv: u32,
    /// KrakenSDR XML records delivered.
    pub kraken_xml: u32,
    /// Kraken records with a field that did not parse.
    pub kraken_bad_field: u32,
    /// Kraken records with a field, text or tag longer than the framing holds.
    pub kraken_too_long: u32,
    /// Kraken records of the wrong shape (field count, tag order, no DOA).
    pub kraken_structure: u32,
}

impl StreamCounters {
    const ZERO: Self = Self {
        bytes: 0,
        sentences: 0,
        mt_frames: 0,
        garbage_bytes: 0,
        bad_checksum: 0,
        malformed: 0,
        too_long: 0,
        bad_fcs: 0,
        overlapping: 0,
        truncated: 0,
        agrelo: 0,
        agrelo_malformed: 0,
        kraken_csv: 0,
        kraken_xml: 0,
        kraken_bad_field: 0,
        kraken_too_long: 0,
        kraken_structure: 0,
    };
}

impl StreamCounters {
    /// Candidates rejected for any reason.
    pub fn rejected(&self) -> u32 {
        self.bad_checksum
            .saturating_add(self.malformed)
            .saturating_add(self.too_long)
            .saturating_add(self.bad_fcs)
            .saturating_add(self.overlapping)
            .saturating_add(self.truncated)
            .saturating_add(self.agrelo_malformed)
            .saturating_add(self.kraken_bad_field)
            .saturating_add(self.kraken_too_long)
            .saturating_add(self.kraken_structure)
    }
}

/// A record being decoded as it arrives.
#[derive(Debug, Clone, Copy)]
enum Streaming {
    None,
    Csv(CsvDecoder),
    Xml(XmlDecoder),
}

/// The demultiplexer, with a buffer of `CAP` bytes (at least [`DEFAULT_CAPACITY`]) and room
/// for `SPECTRUM` values of a Kraken CSV line's DoA spectrum ([`SPECTRUM_LEN`] to keep it,
/// 0, the default, to drop it).
#[derive(Debug, Clone)]
pub struct Demux<const CAP: usize = DEFAULT_CAPACITY, const SPECTRUM: usize = 0> {
    buf: [u8; CAP],
    start: usize,
    end: usize,
    /// Bytes of the frame last handed out, dropped at the next call.
    delivered: usize,
    /// Settle waits for inner candidates now (line idle or stream ended).
    settle: bool,
    /// The stream has ended: unfinished frames are dropped.
    ended: bool,
    /// The first held byte follows a delivered frame (or starts the stream).
    in_sync: bool,
    /// Bytes of the sentence candidate at the start already found plain.
    plain: usize,
    streaming: Streaming,
    ready: Option<Ready>,
    spectrum: [f32; SPECTRUM],
    counters: StreamCounters,
}

/// A streamed record, ready to hand out.
#[derive(Debug, Clone, Copy)]
enum Ready {
    Csv(KrakenCsv),
    Xml(KrakenXml),
}

impl<const CAP: usize, const SPECTRUM: usize> Default for Demux<CAP, SPECTRUM> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const CAP: usize, const SPECTRUM: usize> Demux<CAP, SPECTRUM> {
    const ROOM: () = assert!(
        CAP >= DEFAULT_CAPACITY,
        "Demux buffer under DEFAULT_CAPACITY"
    );

    /// An empty demultiplexer.
    pub const fn new() -> Self {
        let () = Self::ROOM;
        Self {
            buf: [0; CAP],
            start: 0,
            end: 0,
            delivered: 0,
            settle: false,
            ended: false,
            in_sync: true,
            plain: 0,
            streaming: Streaming::None,
            ready: None,
            spectrum: [0.0; SPECTRUM],
            counters: StreamCounters::ZERO,
        }
    }

    /// Counters so far.
    pub fn counters(&self) -> &StreamCounters {
        &self.counters
    }

    /// Bytes held, not yet delivered or rejected.
    pub fn pending(&self) -> usize {
        self.end - self.start - self.delivered
    }

    /// Take as many of `bytes` as fit; returns how many were taken. Drain frames with
    /// [`Demux::next_frame`] until it returns `None`, then write the rest: after that drain
    /// there is always room for at least one byte.
    pub fn write(&mut self, bytes: &[u8]) -> usize {
        self.release();
        if self.end == CAP && self.start > 0 {
            self.buf.copy_within(self.start..self.end, 0);
            self.end -= self.start;
            self.start = 0;
        } else if self.start == self.end {
            self.start = 0;
            self.end = 0;
        }
        let n = bytes.len().min(CAP - self.end);
        self.buf[self.end..self.end + n].copy_from_slice(&bytes[..n]);
        self.end += n;
        self.counters.bytes += n as u64;
        if n > 0 {
            self.settle = false;
            self.ended = false;
        }
        n
    }

    /// The line went idle: deliver a frame that only waits to rule out an inner frame.
    pub fn idle(&mut self) {
        self.settle = true;
    }

    /// The stream ended: settle every wait and drop unfinished frames (counted as truncated).
    pub fn finish(&mut self) {
        self.settle = true;
        self.ended = true;
    }

    fn release(&mut self) {
        if self.delivered > 0 {
            self.start += self.delivered;
            self.delivered = 0;
            self.plain = 0;
        }
    }

    fn drop_first(&mut self) {
        self.start += 1;
        self.in_sync = false;
        self.plain = 0;
    }

    /// A record decoded as it arrives: one step. `Some(true)`: a record is ready in
    /// `self.ready`; `Some(false)`: go on; `None`: more bytes needed.
    fn stream_step(&mut self) -> Option<bool> {
        let data = &self.buf[self.start..self.end];
        let (first, step) = match &mut self.streaming {
            Streaming::None => return Some(false),
            Streaming::Csv(d) => {
                let first = d.at_start();
                let spectrum: &mut [f32] = if SPECTRUM >= SPECTRUM_LEN {
                    &mut self.spectrum
                } else {
                    &mut []
                };
                (first, d.step(data, self.ended, spectrum).map(Ready::Csv))
            }
            Streaming::Xml(d) => (d.at_start(), d.step(data).map(Ready::Xml)),
        };
        match step {
            Step::NeedMore if !self.ended => None,
            Step::NeedMore => {
                self.streaming = Streaming::None;
                if first {
                    self.counters.garbage_bytes += 1;
                    self.drop_first();
                } else {
                    self.counters.truncated += 1;
                    self.in_sync = false;
                }
                Some(false)
            }
            Step::Took(n) => {
                self.start += n;
                Some(false)
            }
            Step::Done(n, r) => {
                self.start += n;
                self.streaming = Streaming::None;
                self.in_sync = true;
                match r {
                    Ready::Csv(_) => self.counters.kraken_csv += 1,
                    Ready::Xml(_) => self.counters.kraken_xml += 1,
                }
                self.ready = Some(r);
                Some(true)
            }
            Step::Reject(e, skip) => {
                self.streaming = Streaming::None;
                if first {
                    self.counters.garbage_bytes += 1;
                    self.drop_first();
                } else {
                    let c = &mut self.counters;
                    match e {
                        KrakenError::BadField(_) => c.kraken_bad_field += 1,
                        KrakenError::TooLong => c.kraken_too_long += 1,
                        KrakenError::Structure | KrakenError::NoBearing => c.kraken_structure += 1,
                    }
                    self.start += skip;
                    self.in_sync = false;
                    self.plain = 0;
                }
                Some(false)
            }
        }
    }

    /// The next checked frame, or `None` when more bytes are needed.
    pub fn next_frame(&mut self) -> Option<Frame<'_>> {
        self.release();
        loop {
            if !matches!(self.streaming, Streaming::None) {
                if !self.stream_step()? {
                    continue;
                }
                return match self.ready.take()? {
                    Ready::Csv(record) => Some(Frame::KrakenCsv(KrakenCsvFrame {
                        record,
                        spectrum: (SPECTRUM >= SPECTRUM_LEN).then_some(&self.spectrum[..]),
                    })),
                    Ready::Xml(r) => Some(Frame::KrakenXml(r)),
                };
            }
            let data = &self.buf[self.start..self.end];
            let first = *data.first()?;
            let verdict = match Framing::of(first) {
                Some(Framing::Agrelo) => {
                    match agrelo::scan(data, self.ended) {
                        agrelo::Scan::Valid { text, end } => {
                            self.counters.agrelo += 1;
                            self.delivered = text + end;
                            self.in_sync = true;
                            let t = &self.buf[self.start..self.start + text];
                            // Checked ASCII, so this never fails.
                            return Some(Frame::Agrelo(core::str::from_utf8(t).unwrap_or("%")));
                        }
                        agrelo::Scan::Invalid { started: true } => {
                            self.counters.agrelo_malformed += 1;
                        }
                        agrelo::Scan::Invalid { started: false } => {
                            self.counters.garbage_bytes += 1;
                        }
                        agrelo::Scan::Incomplete if self.ended => {
                            self.counters.garbage_bytes += 1;
                        }
                        agrelo::Scan::Incomplete => return None,
                    }
                    self.drop_first();
                    continue;
                }
                Some(Framing::KrakenXml) => {
                    self.streaming = Streaming::Xml(XmlDecoder::new());
                    continue;
                }
                Some(Framing::KrakenCsv) => {
                    self.streaming = Streaming::Csv(CsvDecoder::new());
                    continue;
                }
                None if blank(first) => {
                    self.start += 1;
                    self.plain = 0;
                    continue;
                }
                Some(Framing::Sentence) => {
                    let v = scan_sentence_from(data, self.plain);
                    if v == Scan::Incomplete {
                        // Resume after the plain bytes next time; a trailing CR is checked
                        // again, with the byte that follows it.
                        let n = data.len().min(MAX_SENTENCE);
                        self.plain = if data[n - 1] == b'\r' { n - 1 } else { n };
                    }
                    v
                }
                Some(Framing::Mt) => scan_mt(data),
                None => {
                    // The first byte starts nothing: skip it and what follows up to a byte
                    // that may start a record (or whitespace, skipped silently).
                    let skip = 1 + data[1..]
                        .iter()
                        .position(|&b| Framing::of(b).is_some() || blank(b))
                        .unwrap_or(data.len() - 1);
                    self.counters.garbage_bytes =
                        self.counters.garbage_bytes.saturating_add(skip as u32);
                    self.start += skip;
                    self.in_sync = false;
                    self.plain = 0;
                    continue;
                }
            };
            match verdict {
                Scan::Incomplete if self.ended => {
                    self.counters.truncated += 1;
                    self.drop_first();
                }
                Scan::Incomplete => return None,
                Scan::Invalid(reason) => {
                    let c = &mut self.counters;
                    match reason {
                        Reject::Checksum => c.bad_checksum += 1,
                        Reject::Malformed => c.malformed += 1,
                        Reject::TooLong => c.too_long += 1,
                        Reject::Fcs => c.bad_fcs += 1,
                    }
                    self.drop_first();
                }
                Scan::Valid(len) if first == MT_SOF => {
                    match resolve_overlap(data, len, self.ended, self.in_sync) {
                        Overlap::Refuse => {
                            self.counters.overlapping += 1;
                            self.drop_first();
                        }
                        // A decision that needs more look-ahead than the buffer holds is settled
                        // with what it holds, so a full buffer never stalls the stream.
                        Overlap::Wait if !self.settle && data.len() < CAP => return None,
                        Overlap::Accept | Overlap::Wait => {
                            self.counters.mt_frames += 1;
                            self.delivered = len;
                            self.in_sync = true;
                            let f = &self.buf[self.start..self.start + len];
                            return Some(Frame::Mt(MtFrame {
                                cmd0: f[2],
                                cmd1: f[3],
                                data: &f[4..len - 1],
                            }));
                        }
                    }
                }
                Scan::Valid(len) => {
                    self.counters.sentences += 1;
                    self.delivered = len;
                    self.in_sync = true;
                    let line = &self.buf[self.start..self.start + len];
                    let star = line.iter().rposition(|&b| b == b'*').unwrap_or(1);
                    // Printable ASCII was checked, so this never fails.
                    let text = core::str::from_utf8(&line[1..star]).unwrap_or("");
                    return Some(Frame::Nmea(text));
                }
            }
        }
    }

    /// Feed `bytes` and hand every frame they complete to `sink`.
    pub fn feed(&mut self, mut bytes: &[u8], sink: &mut impl FnMut(Frame<'_>)) {
        loop {
            while let Some(frame) = self.next_frame() {
                sink(frame);
            }
            if bytes.is_empty() {
                return;
            }
            let n = self.write(bytes);
            bytes = &bytes[n..];
        }
    }

    /// End the stream and hand every frame still held to `sink`.
    pub fn finish_into(&mut self, sink: &mut impl FnMut(Frame<'_>)) {
        self.finish();
        while let Some(frame) = self.next_frame() {
            sink(frame);
        }
    }
}
