//! Checking a candidate at the start of the held bytes: a sentence's line end and checksum,
//! an MT frame's FCS, and whether a valid MT candidate was forged over the frames inside it.

use super::{MAX_SENTENCE, MT_SOF};
use crate::nmea::xor;

/// The verdict on a candidate at the start of some bytes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Scan {
    /// A valid frame of this many bytes.
    Valid(usize),
    /// Not a frame: why.
    Invalid(Reject),
    /// Cannot tell yet: more bytes needed.
    Incomplete,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Reject {
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
pub(super) fn scan_sentence_from(bytes: &[u8], from: usize) -> Scan {
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
pub(super) fn scan_mt(bytes: &[u8]) -> Scan {
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
pub(super) enum Overlap {
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
pub(super) fn resolve_overlap(bytes: &[u8], len: usize, ended: bool, in_sync: bool) -> Overlap {
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
