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

use crate::agrelo;
use crate::kraken::{
    CsvDecoder, KrakenCsv, KrakenError, KrakenXml, SPECTRUM_LEN, Step, XmlDecoder,
};
use crate::nmea::xor;

/// Longest NMEA sentence, `$` to LF inclusive: GPSD's limit (`NMEA_MAX` in its `gpsd.h`), since
/// RTK receivers print more decimals than NMEA 0183's 82 characters allow.
pub const MAX_SENTENCE: usize = 130;
/// Longest MT frame: SOF, LEN, CMD0, CMD1, 255 data bytes, FCS.
pub const MAX_MT_FRAME: usize = 255 + 5;
/// Default buffer: room for an MT frame and a second one starting inside it, so every wait
/// for more bytes ends before the buffer is full.
pub const DEFAULT_CAPACITY: usize = 2 * MAX_MT_FRAME + 8;
/// Start of frame of an MT frame.
pub const MT_SOF: u8 = 0xFE;

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

pub use crate::mt::MtFrame;

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

/// The verdict on a candidate at the start of some bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scan {
    /// A valid frame of this many bytes.
    Valid(usize),
    /// Not a frame: why.
    Invalid(Reject),
    /// Cannot tell yet: more bytes needed.
    Incomplete,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reject {
    Checksum,
    Malformed,
    TooLong,
    Fcs,
}

fn hex_digit(b: u8) -> Option<u8> {
    match b {
        b'0'..=b'9' => Some(b - b'0'),
        b'A'..=b'F' => Some(b - b'A' + 10),
        b'a'..=b'f' => Some(b - b'a' + 10),
        _ => None,
    }
}

/// Check a sentence candidate starting with `$`.
fn scan_sentence(bytes: &[u8]) -> Scan {
    scan_sentence_from(bytes, 1)
}

/// [`scan_sentence`], skipping bytes before `from` already found plain (printable, no line
/// end): a sentence arriving byte by byte is then scanned once, not once per byte.
fn scan_sentence_from(bytes: &[u8], from: usize) -> Scan {
    let limit = bytes.len().min(MAX_SENTENCE);
    for i in from.max(1)..limit {
        match bytes[i] {
            b'\n' => return check_sentence(&bytes[..=i]),
            // CR LF, CR CR LF (Telit) or a bare LF end a line; a CR before anything else
            // is no line end.
            b'\r' => {
                if bytes.get(i + 1).is_some_and(|&b| b != b'\n' && b != b'\r') {
                    return Scan::Invalid(Reject::Malformed);
                }
            }
            b'$' => return Scan::Invalid(Reject::Malformed),
            0x20..=0x7e => {}
            _ => return Scan::Invalid(Reject::Malformed),
        }
    }
    if bytes.len() >= MAX_SENTENCE {
        Scan::Invalid(Reject::TooLong)
    } else {
        Scan::Incomplete
    }
}

/// `line` runs from `$` to LF; any CRs before the LF belong to the line end.
fn check_sentence(line: &[u8]) -> Scan {
    let mut end = line.len() - 1;
    while end > 1 && line[end - 1] == b'\r' {
        end -= 1;
    }
    let text = &line[1..end];
    if text.len() < 3 || text[text.len() - 3] != b'*' {
        return Scan::Invalid(Reject::Malformed);
    }
    let body = &text[..text.len() - 3];
    let (Some(hi), Some(lo)) = (
        hex_digit(text[text.len() - 2]),
        hex_digit(text[text.len() - 1]),
    ) else {
        return Scan::Invalid(Reject::Malformed);
    };
    if body.contains(&b'*') {
        return Scan::Invalid(Reject::Malformed);
    }
    if xor(body) == (hi << 4 | lo) {
        Scan::Valid(line.len())
    } else {
        Scan::Invalid(Reject::Checksum)
    }
}

/// Check an MT candidate starting with `0xFE`.
fn scan_mt(bytes: &[u8]) -> Scan {
    let Some(&len) = bytes.get(1) else {
        return Scan::Incomplete;
    };
    let total = len as usize + 5;
    if bytes.len() < total {
        return Scan::Incomplete;
    }
    let fcs = xor(&bytes[1..total - 1]);
    if fcs == bytes[total - 1] {
        Scan::Valid(total)
    } else {
        Scan::Invalid(Reject::Fcs)
    }
}

fn scan(bytes: &[u8]) -> Scan {
    match bytes.first() {
        Some(b'$') => scan_sentence(bytes),
        Some(&MT_SOF) => scan_mt(bytes),
        _ => Scan::Invalid(Reject::Malformed),
    }
}

/// Whether a frame ending at `at` is followed by another: a valid frame starts there, or the
/// stream ends there. `None`: cannot tell yet.
fn followed(bytes: &[u8], at: usize, ended: bool) -> Option<bool> {
    if at >= bytes.len() {
        return if ended { Some(true) } else { None };
    }
    match scan(&bytes[at..]) {
        Scan::Valid(_) => Some(true),
        Scan::Invalid(_) => Some(false),
        Scan::Incomplete => {
            if ended {
                Some(false)
            } else {
                None
            }
        }
    }
}

/// The verdict on a valid MT candidate of `len` bytes at the start of `bytes`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Overlap {
    /// Deliver it.
    Accept,
    /// A better-supported frame starts inside it: it was forged.
    Refuse,
    /// Wait for more bytes.
    Wait,
}

/// Resolve a valid MT candidate against the frames that may start inside it.
///
/// A genuine frame is normally followed by another frame; a forged one ends at a random byte.
/// So the candidate is delivered at once when no valid frame starts inside it (the usual case)
/// or when a valid frame follows it; it is refused when a valid inner frame is itself followed
/// by a valid frame (or ends where the candidate does, or at the end of the stream). Each
/// forgery must then pass two independent 8-bit checks.
fn resolve_overlap(bytes: &[u8], len: usize, ended: bool, in_sync: bool) -> Overlap {
    let mut inner_valid = false;
    let mut undecided = false;
    for i in 1..len {
        if bytes[i] == b'$' || bytes[i] == MT_SOF {
            match scan(&bytes[i..]) {
                Scan::Valid(_) => inner_valid = true,
                Scan::Incomplete if !ended => undecided = true,
                _ => {}
            }
        }
    }
    if !inner_valid && !undecided {
        return Overlap::Accept;
    }
    if followed(bytes, len, ended) == Some(true) {
        // Out of sync, still refuse when an inner frame ends exactly where the candidate does:
        // the candidate is then most likely a forged span over that genuine frame. In sync,
        // the candidate wins (a payload may carry a whole frame).
        let same_end = inner_valid
            && !in_sync
            && (1..len).any(|i| {
                (bytes[i] == b'$' || bytes[i] == MT_SOF)
                    && scan(&bytes[i..]) == Scan::Valid(len - i)
            });
        return if same_end {
            Overlap::Refuse
        } else {
            Overlap::Accept
        };
    }
    for i in 1..len {
        if (bytes[i] == b'$' || bytes[i] == MT_SOF)
            && let Scan::Valid(li) = scan(&bytes[i..])
        {
            // Against a candidate right after a delivered frame (in sync) an inner frame
            // counts only if it runs past the candidate's end (a payload may carry whole
            // frames) and a frame, not just the end of the stream, follows it.
            let end = i + li;
            if in_sync && (end <= len || end >= bytes.len()) {
                continue;
            }
            match followed(bytes, end, ended) {
                Some(true) => return Overlap::Refuse,
                None => undecided = true,
                Some(false) => {}
            }
        }
    }
    if followed(bytes, len, ended).is_none() {
        undecided = true;
    }
    if undecided {
        Overlap::Wait
    } else {
        Overlap::Accept
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
            let verdict = match first {
                b'%' => {
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
                b'<' => {
                    self.streaming = Streaming::Xml(XmlDecoder::new());
                    continue;
                }
                b'0'..=b'9' => {
                    self.streaming = Streaming::Csv(CsvDecoder::new());
                    continue;
                }
                b' ' | b'\t' | b'\r' | b'\n' => {
                    self.start += 1;
                    self.plain = 0;
                    continue;
                }
                b'$' => {
                    let v = scan_sentence_from(data, self.plain);
                    if v == Scan::Incomplete {
                        // Resume after the plain bytes next time; a trailing CR is checked
                        // again, with the byte that follows it.
                        let n = data.len().min(MAX_SENTENCE);
                        self.plain = if data[n - 1] == b'\r' { n - 1 } else { n };
                    }
                    v
                }
                MT_SOF => scan_mt(data),
                _ => {
                    // The first byte starts nothing: skip it and what follows up to a byte
                    // that may start a record (or whitespace, skipped silently).
                    let skip = 1 + data[1..]
                        .iter()
                        .position(|&b| {
                            matches!(
                                b,
                                b'$' | MT_SOF | b'%' | b'<' | b'0'
                                    ..=b'9' | b' ' | b'\t' | b'\r' | b'\n'
                            )
                        })
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

#[cfg(test)]
mod tests {
    use super::*;

    fn frames(stream: &[u8]) -> (std::vec::Vec<std::string::String>, StreamCounters) {
        let mut d = Demux::<DEFAULT_CAPACITY>::new();
        let mut out = std::vec::Vec::new();
        let mut sink = |f: Frame<'_>| out.push(std::format!("{f:?}"));
        d.feed(stream, &mut sink);
        d.finish_into(&mut sink);
        (out, *d.counters())
    }

    #[test]
    fn sentence_and_mt_frame_interleaved_with_garbage() {
        let mut s = std::vec::Vec::new();
        s.extend_from_slice(
            b"xx$GPRMC,092750.000,A,5321.6802,N,00630.3372,W,0.02,31.66,280511,,,A*43\r\n",
        );
        s.extend_from_slice(&[0x00, 0xFE, 0x02, 0x44, 0x81, 0xFE, 0xFE, 0x02 ^ 0x44 ^ 0x81]);
        s.extend_from_slice(
            b"$GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,*76\n",
        );
        let (out, c) = frames(&s);
        assert_eq!(out.len(), 3, "{out:?}");
        assert!(out[0].starts_with("Nmea(\"GPRMC,092750.000"));
        assert!(out[1].contains("data: [254, 254]"), "{}", out[1]);
        assert_eq!((c.sentences, c.mt_frames, c.garbage_bytes), (2, 1, 3));
    }

    fn sentence(body: &str) -> std::string::String {
        let mut s = std::string::String::new();
        crate::nmea::write_sentence(&mut s, body).expect("string");
        s
    }

    #[test]
    fn bad_checksum_costs_one_frame() {
        let good = sentence("GPXXX,2");
        let s = std::format!("$GPGGA,1*00\r\n{good}");
        let (out, c) = frames(s.as_bytes());
        assert_eq!(c.bad_checksum, 1);
        assert_eq!(out.len(), 1, "{out:?}");
    }

    #[test]
    fn over_long_line_is_dropped_and_counted() {
        let long = sentence(&"A".repeat(200));
        let s = std::format!("{long}{}", sentence("GPXXX,2"));
        let (out, c) = frames(s.as_bytes());
        assert_eq!(c.too_long, 1);
        assert_eq!(out.len(), 1);
    }

    #[test]
    fn truncated_frame_at_the_end_is_counted() {
        let s = std::format!("{}$GPGGA,12", sentence("GPXXX,2"));
        let (out, c) = frames(s.as_bytes());
        assert_eq!((out.len(), c.truncated), (1, 1));
    }

    #[test]
    fn forged_mt_frame_cannot_swallow_the_sentences_inside_it() {
        // A damaged sentence holds a 0xFE whose LEN spans the next sentence and ends inside the
        // one after, where a byte happens to match its FCS: refused, because the sentence it
        // spans is valid and followed by another.
        let (b, d) = (sentence("GPBBB,2"), sentence("GPDDD,4"));
        for k in 0..10_000 {
            let c = sentence(&std::format!("GPCCC,{k}"));
            let cmd1 = b"PpQq"[k % 4];
            for len in b.len()..b.len() + c.len() - 1 {
                let mut s = b"$GPAAA,1".to_vec();
                s.extend_from_slice(&[MT_SOF, len as u8, b'G', cmd1]);
                let o = s.len() - 4;
                s.extend_from_slice(b.as_bytes());
                s.extend_from_slice(c.as_bytes());
                s.extend_from_slice(d.as_bytes());
                if scan_mt(&s[o..]) != Scan::Valid(len + 5) {
                    continue;
                }
                let (out, counters) = frames(&s);
                assert_eq!(counters.overlapping, 1);
                let want: std::vec::Vec<_> = [&b, &c, &d]
                    .iter()
                    .map(|x| std::format!("Nmea({:?})", &x[1..x.len() - 5]))
                    .collect();
                assert_eq!(out, want);
                return;
            }
        }
        panic!("no forgery found to test with");
    }

    #[test]
    fn a_decision_needing_more_than_the_buffer_does_not_stall() {
        // O: an MT frame of 255 data bytes whose last data byte is 0xFE, so an inner candidate
        // I starts there with O's FCS as its LEN (250), valid thanks to the filler after O,
        // and followed by the start of a 260-byte candidate: deciding I's support needs bytes
        // beyond the 528-byte buffer.
        let mut o = std::vec![MT_SOF, 255, 0x44, 0x81];
        o.extend(std::iter::repeat_n(0u8, 254));
        o.push(MT_SOF);
        let fcs_without_first = o[1..].iter().fold(0u8, |x, b| x ^ b);
        o[4] = fcs_without_first ^ 250; // makes O's FCS 250
        o.push(250);
        assert_eq!(scan_mt(&o), Scan::Valid(260));
        let i_start = o.len() - 2;
        let mut s = o;
        s.extend(std::iter::repeat_n(0u8, i_start + 255 - s.len()));
        let i_fcs = s[i_start + 1..i_start + 254].iter().fold(0u8, |x, b| x ^ b);
        s[i_start + 254] = i_fcs;
        assert_eq!(scan_mt(&s[i_start..]), Scan::Valid(255));
        s.extend_from_slice(&[MT_SOF, 0xFF]);
        s.extend(std::iter::repeat_n(0x55u8, 600));
        let mut d = Demux::<DEFAULT_CAPACITY>::new();
        let mut n = 0;
        d.feed(&s, &mut |_| n += 1);
        d.finish_into(&mut |_| n += 1);
        assert_eq!(d.counters().bytes, s.len() as u64);
        // Settled with what the buffer held: O is delivered (no valid frame follows its inner
        // candidate within the buffer), and the 260-byte candidate after it fails its FCS.
        let c = d.counters();
        assert_eq!(
            (n, c.mt_frames, c.bad_fcs, c.overlapping),
            (1, 1, 1, 0),
            "{c:?}"
        );
    }

    #[test]
    fn gpsd_grade_line_ends_lengths_and_binary_neighbours() {
        let rtk = "GPGGA,132820.60,4134.49821229,N,09345.03351845,W,2,09,1.0,278.020,M,-31.442,M,7.6,0133";
        let mut s = std::vec::Vec::new();
        // u-blox UBX (0xB5 0x62) and SiRF (0xA0 0xA2 ... 0xB0 0xB3) frames, one with an MT
        // start byte and a '$' in its payload, between sentences with every line end.
        s.extend_from_slice(&[
            0xB5, 0x62, 0x01, 0x07, 0x04, 0x00, 0xFE, 0x10, b'$', 0x00, 0x3A, 0x9C,
        ]);
        s.extend_from_slice(std::format!("${rtk}*7E\r\r\n").as_bytes());
        s.extend_from_slice(&[0xA0, 0xA2, 0x00, 0x02, 0xFE, 0x05, 0x01, 0x03, 0xB0, 0xB3]);
        s.extend_from_slice(sentence("GPXXX,1").trim_end().as_bytes());
        s.extend_from_slice(b"\n");
        s.extend_from_slice(sentence("GPXXX,2").as_bytes());
        let (out, c) = frames(&s);
        let want = [
            std::format!("Nmea({rtk:?})"),
            "Nmea(\"GPXXX,1\")".into(),
            "Nmea(\"GPXXX,2\")".into(),
        ];
        assert_eq!(out, want, "{c:?}");
        // 130 bytes from '$' to LF is GPSD's limit; 131 is too long.
        for (len, ok) in [(130, true), (131, false)] {
            let body = std::format!("GPXXX,{}", "9".repeat(len - 12));
            let line = sentence(&body);
            assert_eq!(line.len(), len);
            let (out, c) = frames(line.as_bytes());
            assert_eq!((out.len() == 1, c.too_long == 1), (ok, !ok), "{len}");
        }
    }

    #[test]
    fn a_kraken_line_in_odd_reads_keeps_its_spectrum_only_when_asked() {
        let line = crate::kraken::tests::issue_11_line();
        let mut keep = Demux::<DEFAULT_CAPACITY, SPECTRUM_LEN>::new();
        let mut drop = Demux::<DEFAULT_CAPACITY>::new();
        let mut seen = std::vec::Vec::new();
        for chunk in line.as_bytes().chunks(7) {
            keep.feed(chunk, &mut |f| {
                if let Frame::KrakenCsv(k) = f {
                    // Index 0 is the front; clockwise 1 degree is anticlockwise index 359.
                    seen.push((k.spectrum_clockwise(0), k.spectrum_clockwise(1)));
                }
            });
            drop.feed(chunk, &mut |f| {
                if let Frame::KrakenCsv(k) = f {
                    assert_eq!(k.spectrum, None);
                    assert_eq!(k.record.epoch_ms, 1_679_512_414_650);
                }
            });
        }
        assert_eq!(seen, [(Some(0.07), Some(3.59))]);
        assert_eq!(
            (keep.counters().kraken_csv, drop.counters().kraken_csv),
            (1, 1)
        );
        // Nothing of the 2.5 KB line is held once it is read.
        assert_eq!(keep.pending(), 0);
    }

    #[test]
    fn a_form_feed_after_digits_is_garbage_not_a_stall() {
        // Found by the flipped-byte property: ',' ^ 0x20 is a form feed, ASCII whitespace
        // that no record starts with; the scan once stopped on it without moving.
        let s = std::format!("1600000000005\x0c 134.5{}", sentence("GPXXX,1"));
        let (out, c) = frames(s.as_bytes());
        assert_eq!(out, ["Nmea(\"GPXXX,1\")"]);
        // 13 digits, the form feed and "134.5"; the space is skipped silently.
        assert_eq!(c.garbage_bytes, 19, "{c:?}");
    }

    #[test]
    fn a_payload_carrying_whole_frames_is_one_frame() {
        // Found by cargo-fuzz: this payload holds two valid MT frames back to back; the
        // outer frame comes first and in sync, so it is delivered whole.
        let data = [
            0xFE, 0xFE, 0x01, 0x01, 0xFF, 0x00, 0xFF, 0xFE, 0x01, 0x01, 0x00, 0x00, 0x00, 0xFE,
            0xFC, 0xFF,
        ];
        let mut wire = [0u8; 32];
        let n = MtFrame {
            cmd0: 0x01,
            cmd1: 0x81,
            data: &data,
        }
        .encode(&mut wire)
        .expect("fits");
        let (out, _) = frames(&wire[..n]);
        assert_eq!(out.len(), 1, "{out:?}");
    }
}
