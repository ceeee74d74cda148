//! The DF unit's own sentences on its user port: what it found, how it is, what it was told.
//!
//! Every one is NMEA-style, `$` body `*hh` CR LF with the XOR checksum of NMEA 0183, at most
//! [`MAX_SENTENCE`] bytes `$` to LF, so the bridge's demultiplexer frames them like any other
//! sentence and `foxhunt frames` / `foxhunt locate` read them back with [`UnitSentence::parse`].
//! They are written without `core::fmt` (which would cost the image about 10 KB of flash): the
//! numbers are integers or fixed-point decimals, rounded half up.
//!
//! | sentence | when | fields after the address |
//! |---|---|---|
//! | `$PFOXF` fix | after every bearing | time `hhmmss.ss` (of the newest bearing), latitude `ddmm.mmmmmm`,`N`/`S`, longitude `dddmm.mmmmmm`,`E`/`W`, semi-major axis m (`.1`), semi-minor axis m (`.1`), major-axis direction degrees clockwise from true north in [0, 180) (`.1`), CEP50 m (`.1`), bearings used, bearings in the window, bearing sigma used degrees (`.2`), status |
//! | `$PFOXS` status | once a second | uptime s, painted-stack high-water mark bytes, queue high-water marks bytes (GPS, DF, ZigBee, user output), worst latency ticks, worst fix ticks, reset cause |
//! | `$PFOXL` link | once a second | bytes parsed (GPS, DF, ZigBee), bytes lost to overruns, bytes lost to full queues, output sentences dropped, records rejected, bearings, fixes sent |
//! | `$PFOXR` ready | once, at start | protocol version (1), reset cause |
//! | `$PFOXA` acknowledgement | after each command | command, `OK` or `ERR`, the setting as applied or why not |
//!
//! The fix's ellipse is the 95 % one; the status letter is `A` valid, `E` a fix whose bearings
//! scatter more than the configured limit (not to be trusted), `D` degenerate geometry
//! (parallel bearings, a vehicle that has not moved, a range without bound), `N` fewer than
//! three bearings, `S` searching (no crossing in front of the vehicle yet). With `D`, `N` and
//! `S` the position and ellipse fields are empty. Ticks are core clock cycles of the MCU
//! (168 MHz on the board). Reset causes: `N` power on or pin, `P` panic, `H` hard fault, `W`
//! watchdog. Counters are `u32` and wrap.
#![deny(
    clippy::unwrap_used,
    clippy::expect_used,
    clippy::panic,
    clippy::indexing_slicing,
    clippy::unreachable,
    clippy::todo,
    clippy::unimplemented
)]

use crate::nmea::{LatLon, UtcTime, angle, number, time, xor};
use crate::stream::MAX_SENTENCE;
use crate::track::Status;
use core::num::NonZeroU64;

/// `v` as a `NonZeroU64` (1 for 0): divisors the compiler knows are not zero.
const fn nz(v: u64) -> NonZeroU64 {
    match NonZeroU64::new(v) {
        Some(n) => n,
        None => NonZeroU64::MIN,
    }
}

const TEN: NonZeroU64 = nz(10);
const HUNDRED: NonZeroU64 = nz(100);
const THOUSAND: NonZeroU64 = nz(1000);
const TEN_THOUSAND: NonZeroU64 = nz(10_000);

/// A sentence being written, `$` to LF, in a fixed buffer. A field that does not fit marks it
/// overflowed, and [`SentenceBuf::finish`] then gives nothing: never a cut sentence.
#[derive(Debug, Clone)]
pub struct SentenceBuf {
    buf: [u8; MAX_SENTENCE],
    len: usize,
    overflow: bool,
}

impl SentenceBuf {
    /// A sentence with this address (`PFOXF`, ...).
    pub fn new(address: &str) -> Self {
        let mut s = Self {
            buf: [0; MAX_SENTENCE],
            len: 0,
            overflow: false,
        };
        s.bytes(b"$");
        s.bytes(address.as_bytes());
        s
    }

    /// Raw bytes.
    pub fn bytes(&mut self, b: &[u8]) -> &mut Self {
        match self.buf.get_mut(self.len..self.len + b.len()) {
            Some(dst) => {
                dst.copy_from_slice(b);
                self.len += b.len();
            }
            None => self.overflow = true,
        }
        self
    }

    /// A comma, then `b`.
    pub fn field(&mut self, b: &[u8]) -> &mut Self {
        self.bytes(b",").bytes(b)
    }

    /// A comma, then `v` in decimal with at least `width` digits.
    pub fn uint(&mut self, v: u32, width: usize) -> &mut Self {
        self.bytes(b",");
        self.digits(u64::from(v), width)
    }

    fn digits(&mut self, v: u64, width: usize) -> &mut Self {
        let mut d = [0u8; 20];
        let mut n = 0;
        let mut x = v;
        while (x > 0 || n < width.max(1)) && n < d.len() {
            if let Some(slot) = d.get_mut(n) {
                *slot = b'0' + (x % 10) as u8;
            }
            x /= 10;
            n += 1;
        }
        for i in (0..n).rev() {
            if let Some(&c) = d.get(i) {
                self.bytes(&[c]);
            }
        }
        self
    }

    /// A comma, then `v` (>= 0) with `decimals` decimals, rounded half up; a value beyond
    /// 10^8 is written as 99999999 and a NaN or negative one as 0 (the fields are sizes).
    pub fn fixed(&mut self, v: f32, decimals: u32) -> &mut Self {
        self.bytes(b",");
        self.decimal(v, decimals)
    }

    fn decimal(&mut self, v: f32, decimals: u32) -> &mut Self {
        let d = decimals.min(4);
        let scale = match d {
            0 => NonZeroU64::MIN,
            1 => TEN,
            2 => HUNDRED,
            3 => THOUSAND,
            _ => TEN_THOUSAND,
        };
        let x = if v.is_nan() || v <= 0.0 {
            0.0
        } else {
            v.min(99_999_999.0)
        };
        let units = (x * scale.get() as f32 + 0.5) as u64;
        self.digits(units / scale, 1);
        if d > 0 {
            self.bytes(b".");
            self.digits(units % scale, d as usize);
        }
        self
    }

    /// A comma, then `v` with `decimals` decimals and a `-` when negative.
    pub fn signed(&mut self, v: f32, decimals: u32) -> &mut Self {
        self.bytes(b",");
        if v < 0.0 {
            self.bytes(b"-");
        }
        self.decimal(libm::fabsf(v), decimals)
    }

    /// A comma and `hhmmss.ss`.
    pub fn time(&mut self, t: UtcTime) -> &mut Self {
        let cs = t.ms_of_day.saturating_add(5) / 10;
        let s = cs / 100;
        self.bytes(b",");
        self.digits(u64::from(s / 3600), 2)
            .digits(u64::from(s / 60 % 60), 2)
            .digits(u64::from(s % 60), 2)
            .bytes(b".")
            .digits(u64::from(cs % 100), 2)
    }

    /// `,ddmm.mmmmmm,H` (three degree digits for a longitude).
    pub fn angle(&mut self, degrees: f64, longitude: bool) -> &mut Self {
        let negative = degrees < 0.0;
        let a = if negative { -degrees } else { degrees };
        // Six decimals of minutes: 1.9 mm.
        let micro = (a * 60.0e6 + 0.5) as u64;
        let (deg, rest) = (micro / 60_000_000, micro % 60_000_000);
        self.bytes(b",");
        self.digits(deg, if longitude { 3 } else { 2 })
            .digits(rest / 1_000_000, 2)
            .bytes(b".")
            .digits(rest % 1_000_000, 6);
        let h = match (longitude, negative) {
            (false, false) => b"N",
            (false, true) => b"S",
            (true, false) => b"E",
            (true, true) => b"W",
        };
        self.field(h)
    }

    /// The finished sentence, `*hh` and CR LF added, or `None` if it overflowed.
    pub fn finish(&mut self) -> Option<&[u8]> {
        let body = self.buf.get(1..self.len)?;
        let sum = xor(body);
        const HEX: &[u8; 16] = b"0123456789ABCDEF";
        let hi = *HEX.get(usize::from(sum >> 4))?;
        let lo = *HEX.get(usize::from(sum & 15))?;
        self.bytes(&[b'*', hi, lo, b'\r', b'\n']);
        if self.overflow {
            return None;
        }
        self.buf.get(..self.len)
    }
}

/// Why the unit last reset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ResetCause {
    /// Power on or the reset pin.
    PowerOn,
    /// The panic handler.
    Panic,
    /// The hard-fault handler.
    HardFault,
    /// The independent watchdog.
    Watchdog,
}

impl ResetCause {
    /// The sentence letter.
    pub fn letter(self) -> u8 {
        match self {
            Self::PowerOn => b'N',
            Self::Panic => b'P',
            Self::HardFault => b'H',
            Self::Watchdog => b'W',
        }
    }

    fn from_letter(s: &str) -> Option<Self> {
        Some(match s {
            "N" => Self::PowerOn,
            "P" => Self::Panic,
            "H" => Self::HardFault,
            "W" => Self::Watchdog,
            _ => return None,
        })
    }
}

/// `$PFOXF`: the unit's fix after a bearing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FixSentence {
    /// Time of the newest bearing.
    pub time: UtcTime,
    /// The emitter, when the status has a position.
    pub position: Option<LatLon>,
    /// Semi-major axis of the 95 % ellipse, metres.
    pub major_m: f32,
    /// Semi-minor axis, metres.
    pub minor_m: f32,
    /// Major-axis direction, degrees clockwise from true north, [0, 180).
    pub orientation_deg: f32,
    /// CEP50, metres.
    pub cep50_m: f32,
    /// Bearings used.
    pub used: u32,
    /// Bearings in the window.
    pub window: u32,
    /// Bearing sigma used, degrees.
    pub sigma_deg: f32,
    /// What the fix is worth.
    pub status: Status,
}

impl FixSentence {
    /// The sentence, `$` to LF.
    pub fn write(&self) -> SentenceBuf {
        let mut s = SentenceBuf::new("PFOXF");
        s.time(self.time);
        match self.position.filter(|_| self.status.has_position()) {
            Some(p) => {
                s.angle(p.lat, false)
                    .angle(p.lon, true)
                    .fixed(self.major_m, 1)
                    .fixed(self.minor_m, 1)
                    .fixed(self.orientation_deg, 1)
                    .fixed(self.cep50_m, 1);
            }
            None => {
                s.bytes(b",,,,,,,,");
            }
        }
        s.uint(self.used, 1)
            .uint(self.window, 1)
            .fixed(self.sigma_deg, 2)
            .field(&[self.status.letter()]);
        s
    }
}

/// `$PFOXS`: the unit's health, once a second.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StatusSentence {
    /// Seconds since reset.
    pub uptime_s: u32,
    /// Painted-stack high-water mark, bytes.
    pub stack_bytes: u32,
    /// Queue high-water marks, bytes: GPS, DF, ZigBee input, user output.
    pub queue_high: [u32; 4],
    /// Worst latency from a record's last byte to its fix sentence's last byte, ticks.
    pub latency_ticks: u32,
    /// Worst cost of one update of the fix, ticks.
    pub fix_ticks: u32,
    /// Why the unit last reset (`None` before it is known).
    pub reset: Option<ResetCause>,
}

impl StatusSentence {
    /// The sentence, `$` to LF.
    pub fn write(&self) -> SentenceBuf {
        let mut s = SentenceBuf::new("PFOXS");
        s.uint(self.uptime_s, 1).uint(self.stack_bytes, 1);
        for q in self.queue_high {
            s.uint(q, 1);
        }
        s.uint(self.latency_ticks, 1).uint(self.fix_ticks, 1);
        s.field(&[self.reset.map(ResetCause::letter).unwrap_or(b'N')]);
        s
    }
}

/// `$PFOXL`: the links' counters, once a second.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LinkSentence {
    /// Bytes parsed: GPS, DF, ZigBee.
    pub bytes: [u32; 3],
    /// Bytes lost to receiver overruns.
    pub overruns: u32,
    /// Bytes lost to full receive queues.
    pub full: u32,
    /// Sentences the output queue had no room for.
    pub dropped: u32,
    /// Records rejected (framing, fields, gates, no fix, ...).
    pub rejected: u32,
    /// Bearings handed to the tracker.
    pub bearings: u32,
    /// Fix sentences sent.
    pub fixes: u32,
}

impl LinkSentence {
    /// The sentence, `$` to LF.
    pub fn write(&self) -> SentenceBuf {
        let mut s = SentenceBuf::new("PFOXL");
        for b in self.bytes {
            s.uint(b, 1);
        }
        s.uint(self.overruns, 1)
            .uint(self.full, 1)
            .uint(self.dropped, 1)
            .uint(self.rejected, 1)
            .uint(self.bearings, 1)
            .uint(self.fixes, 1);
        s
    }
}

/// `$PFOXR`: the ready banner (the unit's receivers are enabled: bytes sent before it are
/// lost).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReadySentence {
    /// Protocol version of these sentences (1).
    pub version: u32,
    /// Why the unit last reset.
    pub reset: ResetCause,
}

impl ReadySentence {
    /// The sentence, `$` to LF.
    pub fn write(&self) -> SentenceBuf {
        let mut s = SentenceBuf::new("PFOXR");
        s.uint(self.version, 1).field(&[self.reset.letter()]);
        s
    }
}

/// `$PFOXA`: a command's acknowledgement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AckSentence<'a> {
    /// The command's name (`SIGMA`, ...).
    pub command: &'a str,
    /// Whether it was applied.
    pub ok: bool,
    /// The setting as applied, or why not (comma-separated fields).
    pub detail: &'a str,
}

/// A sentence of the unit, decoded.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum UnitSentence<'a> {
    /// `$PFOXF`.
    Fix(FixSentence),
    /// `$PFOXS`.
    Status(StatusSentence),
    /// `$PFOXL`.
    Link(LinkSentence),
    /// `$PFOXR`.
    Ready(ReadySentence),
    /// `$PFOXA`.
    Ack(AckSentence<'a>),
}

/// Why a unit sentence did not decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TelemetryError {
    /// Not one of the unit's sentences.
    Unsupported,
    /// Field `n` (1 = the first after the address) is missing or malformed.
    BadField(u8),
}

impl core::fmt::Display for TelemetryError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Unsupported => f.write_str("not a unit sentence"),
            Self::BadField(n) => write!(f, "unit sentence field {n} missing or malformed"),
        }
    }
}

struct Fields<'a> {
    all: [&'a str; 16],
    count: usize,
}

impl<'a> Fields<'a> {
    fn split(body: &'a str) -> Self {
        let mut all = [""; 16];
        let mut count = 0;
        for (slot, f) in all.iter_mut().zip(body.split(',')) {
            *slot = f;
            count += 1;
        }
        Self { all, count }
    }

    fn get(&self, n: usize) -> Result<&'a str, TelemetryError> {
        let f = if n < self.count {
            self.all.get(n).copied()
        } else {
            None
        };
        f.ok_or(TelemetryError::BadField(n as u8))
    }

    fn uint(&self, n: usize) -> Result<u32, TelemetryError> {
        let s = self.get(n)?;
        if s.is_empty() || s.len() > 10 || !s.bytes().all(|b| b.is_ascii_digit()) {
            return Err(TelemetryError::BadField(n as u8));
        }
        s.parse().map_err(|_| TelemetryError::BadField(n as u8))
    }

    fn real(&self, n: usize) -> Result<f32, TelemetryError> {
        number(self.get(n)?)
            .filter(|v| *v >= 0.0)
            .map(|v| v as f32)
            .ok_or(TelemetryError::BadField(n as u8))
    }
}

impl<'a> UnitSentence<'a> {
    /// Decode the text between `$` and `*` of a checked sentence.
    pub fn parse(body: &'a str) -> Result<Self, TelemetryError> {
        let f = Fields::split(body);
        let bad = TelemetryError::BadField;
        match f.get(0)? {
            "PFOXF" => {
                let status = f
                    .get(13)?
                    .as_bytes()
                    .first()
                    .and_then(|c| Status::from_letter(*c))
                    .filter(|_| f.get(13).is_ok_and(|s| s.len() == 1))
                    .ok_or(bad(13))?;
                let position = if status.has_position() {
                    let lat = angle(f.get(2)?, f.get(3)?, 90.0, b'N', b'S').ok_or(bad(2))?;
                    let lon = angle(f.get(4)?, f.get(5)?, 180.0, b'E', b'W').ok_or(bad(4))?;
                    Some(LatLon { lat, lon })
                } else {
                    if (2..10).any(|n| f.get(n).map_or(true, |s| !s.is_empty())) {
                        return Err(bad(2));
                    }
                    None
                };
                let size = |n| {
                    if position.is_some() {
                        f.real(n)
                    } else {
                        Ok(0.0)
                    }
                };
                if f.count != 14 {
                    return Err(bad(14));
                }
                Ok(Self::Fix(FixSentence {
                    time: time(f.get(1)?).ok_or(bad(1))?,
                    position,
                    major_m: size(6)?,
                    minor_m: size(7)?,
                    orientation_deg: size(8)?,
                    cep50_m: size(9)?,
                    used: f.uint(10)?,
                    window: f.uint(11)?,
                    sigma_deg: f.real(12)?,
                    status,
                }))
            }
            "PFOXS" => {
                if f.count != 10 {
                    return Err(bad(10));
                }
                Ok(Self::Status(StatusSentence {
                    uptime_s: f.uint(1)?,
                    stack_bytes: f.uint(2)?,
                    queue_high: [f.uint(3)?, f.uint(4)?, f.uint(5)?, f.uint(6)?],
                    latency_ticks: f.uint(7)?,
                    fix_ticks: f.uint(8)?,
                    reset: Some(ResetCause::from_letter(f.get(9)?).ok_or(bad(9))?),
                }))
            }
            "PFOXL" => {
                if f.count != 10 {
                    return Err(bad(10));
                }
                Ok(Self::Link(LinkSentence {
                    bytes: [f.uint(1)?, f.uint(2)?, f.uint(3)?],
                    overruns: f.uint(4)?,
                    full: f.uint(5)?,
                    dropped: f.uint(6)?,
                    rejected: f.uint(7)?,
                    bearings: f.uint(8)?,
                    fixes: f.uint(9)?,
                }))
            }
            "PFOXR" => Ok(Self::Ready(ReadySentence {
                version: f.uint(1)?,
                reset: ResetCause::from_letter(f.get(2)?).ok_or(bad(2))?,
            })),
            "PFOXA" => {
                let command = f.get(1)?;
                let ok = match f.get(2)? {
                    "OK" => true,
                    "ERR" => false,
                    _ => return Err(bad(2)),
                };
                // The detail is the rest of the body after the third comma.
                let mut commas = 0;
                let mut start = body.len();
                for (i, b) in body.bytes().enumerate() {
                    if b == b',' {
                        commas += 1;
                        if commas == 3 {
                            start = i + 1;
                            break;
                        }
                    }
                }
                Ok(Self::Ack(AckSentence {
                    command,
                    ok,
                    detail: body.get(start..).unwrap_or(""),
                }))
            }
            _ => Err(TelemetryError::Unsupported),
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing, clippy::panic)]
mod tests {
    use super::*;
    use crate::stream::{Demux, Frame};

    fn body(s: &[u8]) -> String {
        let mut d = Demux::<{ crate::stream::DEFAULT_CAPACITY }>::new();
        let mut out = Vec::new();
        d.feed(s, &mut |f| {
            if let Frame::Nmea(t) = f {
                out.push(t.to_string());
            }
        });
        assert_eq!(out.len(), 1, "{}", String::from_utf8_lossy(s));
        out.remove(0)
    }

    #[test]
    fn a_fix_round_trips_through_the_demultiplexer() {
        let fix = FixSentence {
            time: UtcTime {
                ms_of_day: 36_061_250,
            },
            position: Some(LatLon {
                lat: 47.010_123_4,
                lon: -8.005_432_1,
            }),
            major_m: 123.45,
            minor_m: 6.04,
            orientation_deg: 179.96,
            cep50_m: 40.0,
            used: 117,
            window: 120,
            sigma_deg: 1.234,
            status: Status::Valid,
        };
        let mut w = fix.write();
        let line = w.finish().unwrap().to_vec();
        assert_eq!(
            String::from_utf8_lossy(&line),
            "$PFOXF,100101.25,4700.607404,N,00800.325926,W,123.5,6.0,180.0,40.0,117,120,1.23,A*0C\r\n"
        );
        let text = body(&line);
        let Ok(UnitSentence::Fix(back)) = UnitSentence::parse(&text) else {
            panic!("{text}")
        };
        let p = back.position.unwrap();
        assert!((p.lat - 47.010_123_4).abs() < 1e-7 && (p.lon + 8.005_432_1).abs() < 1e-7);
        assert_eq!(
            (back.used, back.window, back.status),
            (117, 120, Status::Valid)
        );
        assert!((back.major_m - 123.5).abs() < 1e-4 && (back.sigma_deg - 1.23).abs() < 1e-6);
    }

    #[test]
    fn a_fix_without_position_has_empty_fields() {
        let fix = FixSentence {
            time: UtcTime { ms_of_day: 0 },
            position: None,
            major_m: 0.0,
            minor_m: 0.0,
            orientation_deg: 0.0,
            cep50_m: 0.0,
            used: 0,
            window: 2,
            sigma_deg: 2.0,
            status: Status::TooFew,
        };
        let mut w = fix.write();
        let line = w.finish().unwrap().to_vec();
        let text = body(&line);
        assert_eq!(text, "PFOXF,000000.00,,,,,,,,,0,2,2.00,N");
        assert_eq!(UnitSentence::parse(&text), Ok(UnitSentence::Fix(fix)));
        // A status with a position needs one.
        assert!(UnitSentence::parse("PFOXF,000000.00,,,,,,,,,0,2,2.00,A").is_err());
    }

    #[test]
    fn status_link_ready_and_ack_round_trip_at_their_widest() {
        let s = StatusSentence {
            uptime_s: u32::MAX,
            stack_bytes: 4096,
            queue_high: [u32::MAX; 4],
            latency_ticks: u32::MAX,
            fix_ticks: u32::MAX,
            reset: Some(ResetCause::Watchdog),
        };
        let l = LinkSentence {
            bytes: [u32::MAX; 3],
            overruns: u32::MAX,
            full: u32::MAX,
            dropped: u32::MAX,
            rejected: u32::MAX,
            bearings: u32::MAX,
            fixes: u32::MAX,
        };
        let (mut sw, mut lw) = (s.write(), l.write());
        let (st, lt) = (body(sw.finish().unwrap()), body(lw.finish().unwrap()));
        assert_eq!(UnitSentence::parse(&st), Ok(UnitSentence::Status(s)));
        assert_eq!(UnitSentence::parse(&lt), Ok(UnitSentence::Link(l)));
        let r = ReadySentence {
            version: 1,
            reset: ResetCause::Panic,
        };
        let rt = body(r.write().finish().unwrap());
        assert_eq!(rt, "PFOXR,1,P");
        assert_eq!(UnitSentence::parse(&rt), Ok(UnitSentence::Ready(r)));
        assert_eq!(
            UnitSentence::parse("PFOXA,WINDOW,OK,60,300"),
            Ok(UnitSentence::Ack(AckSentence {
                command: "WINDOW",
                ok: true,
                detail: "60,300"
            }))
        );
        assert_eq!(
            UnitSentence::parse("GPGGA,1"),
            Err(TelemetryError::Unsupported)
        );
    }

    #[test]
    fn an_overflowing_sentence_is_never_cut() {
        let mut s = SentenceBuf::new("PFOXA");
        for _ in 0..20 {
            s.field(b"ABCDEFGH");
        }
        assert!(s.finish().is_none());
    }
}
