//! The MCU's run replayed on the host: the same [`Unit`] fed the same bytes of each port in
//! the order the MCU read them.
//!
//! The unit's sentences depend only on the order in which the ports' frames reach it (see
//! [`crate::unit`]). The firmware logs (through defmt) one line per read that completed a frame,
//! `feed <port> <bytes so far>`, and one per quiet-line settle that did, `idle <port> <bytes so
//! far>`; [`Step::parse`] reads those lines back and [`replay`] runs them. Reads that completed
//! no frame need no line: their bytes only wait in a demultiplexer, and go in with the next
//! read of their port.

use crate::unit::{Fed, Port, Unit};

/// One logged step of the MCU's run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// The port's bytes up to this count were fed (at least one frame completed).
    Feed {
        /// The port.
        port: Port,
        /// Bytes of the port fed so far.
        end: u64,
    },
    /// The port went quiet after this many bytes, and a held frame was settled.
    Idle {
        /// The port.
        port: Port,
        /// Bytes of the port fed so far.
        end: u64,
    },
}

impl Step {
    /// A step from a decoded log line ending in `feed P N` or `idle P N`; `None` for other
    /// lines.
    pub fn parse(line: &str) -> Option<Self> {
        let mut words = line.split_whitespace().rev();
        let end: u64 = words.next()?.parse().ok()?;
        let port = Port::from_index(words.next()?.parse().ok()?)?;
        match words.next()? {
            "feed" => Some(Self::Feed { port, end }),
            "idle" => Some(Self::Idle { port, end }),
            _ => None,
        }
    }
}

/// Why a log does not fit the streams.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReplayError {
    /// A step's byte count runs past its port's stream, or back before an earlier step.
    Offset {
        /// Index of the step.
        step: usize,
    },
}

impl core::fmt::Display for ReplayError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Offset { step } => write!(f, "step {step} does not fit its port's stream"),
        }
    }
}

/// Run `steps` on `unit` with the bytes each port received (`streams`, by [`Port`] index);
/// the unit's sentences go to `out`. Returns what the steps did in all.
pub fn replay(
    unit: &mut Unit,
    streams: [&[u8]; 4],
    steps: impl IntoIterator<Item = Step>,
    out: &mut impl FnMut(&[u8]) -> bool,
) -> Result<Fed, ReplayError> {
    let mut at = [0usize; 4];
    let mut total = Fed::default();
    for (k, step) in steps.into_iter().enumerate() {
        let (port, end) = match step {
            Step::Feed { port, end } | Step::Idle { port, end } => (port, end),
        };
        let i = port as usize;
        let (Some(stream), Some(from)) = (streams.get(i), at.get(i).copied()) else {
            return Err(ReplayError::Offset { step: k });
        };
        let end = usize::try_from(end).map_err(|_| ReplayError::Offset { step: k })?;
        let bytes = stream
            .get(from..end)
            .ok_or(ReplayError::Offset { step: k })?;
        let fed = match step {
            Step::Feed { .. } => unit.feed(port, bytes, out),
            Step::Idle { .. } => {
                if !bytes.is_empty() {
                    return Err(ReplayError::Offset { step: k });
                }
                unit.idle(port, out)
            }
        };
        if let Some(a) = at.get_mut(i) {
            *a = end;
        }
        total.frames += fed.frames;
        total.fixes += fed.fixes;
    }
    Ok(total)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CAPTURE: &[u8] = include_bytes!("../captures/aoa-drive.nmea");

    #[test]
    fn a_logged_interleaving_replays_to_the_same_bytes() {
        // Split by port, fed line by line as a log would say, then replayed.
        let mut streams: [Vec<u8>; 4] = Default::default();
        let mut steps = Vec::new();
        let mut direct = Vec::new();
        let mut unit = Unit::default();
        for line in CAPTURE.split_inclusive(|b| *b == b'\n') {
            let port = Port::of_record(line).unwrap_or(Port::Gps);
            let s = &mut streams[port as usize];
            // Half a line, then the rest: only the read that completes it is logged.
            let (a, b) = line.split_at(line.len() / 2);
            for part in [a, b] {
                s.extend_from_slice(part);
                let fed = unit.feed(port, part, &mut |x| {
                    direct.extend_from_slice(x);
                    true
                });
                if fed.frames > 0 {
                    steps.push(Step::Feed {
                        port,
                        end: s.len() as u64,
                    });
                }
            }
        }
        assert_eq!(
            steps.len(),
            CAPTURE
                .split(|b| *b == b'\n')
                .filter(|l| !l.is_empty())
                .count()
        );
        let text: Vec<String> = steps
            .iter()
            .map(|s| match s {
                Step::Feed { port, end } => format!("INFO  feed {} {end}", *port as u8),
                Step::Idle { port, end } => format!("INFO  idle {} {end}", *port as u8),
            })
            .collect();
        let parsed: Vec<Step> = text.iter().filter_map(|l| Step::parse(l)).collect();
        assert_eq!(parsed, steps);
        let mut again = Vec::new();
        let mut host = Unit::default();
        let fed = replay(
            &mut host,
            [&streams[0], &streams[1], &streams[2], &streams[3]],
            parsed,
            &mut |x| {
                again.extend_from_slice(x);
                true
            },
        )
        .unwrap();
        assert_eq!(fed.fixes, 60);
        assert_eq!(again, direct);
        let bad = [Step::Feed {
            port: Port::Df,
            end: 1 << 40,
        }];
        assert_eq!(
            replay(&mut host, [&[]; 4], bad, &mut |_| true),
            Err(ReplayError::Offset { step: 0 })
        );
    }
}
