//! The DF unit's own sentences on its user port: what it found, how it is, what it was told.
//!
//! Every one is NMEA-style, `$` body `*hh` CR LF with the XOR checksum of NMEA 0183, at most
//! [`MAX_SENTENCE`](crate::stream::MAX_SENTENCE) bytes `$` to LF, so the bridge's demultiplexer frames them like any other
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
//!
//! The fixed-buffer writer is in `writer.rs`, the decoding in `parse.rs`.

mod parse;
mod writer;

#[cfg(test)]
mod tests;

pub use writer::SentenceBuf;

use crate::nmea::{LatLon, UtcTime};
use foxhunt_core::fix::window::Status;

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
