//! Reading the unit's sentences back.

use super::{
    AckSentence, FixSentence, LinkSentence, ReadySentence, ResetCause, StatusSentence,
    TelemetryError, UnitSentence,
};
use crate::nmea::{LatLon, angle, number, time};
use foxhunt_core::fix::window::Status;

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
                let (major_m, minor_m) = (size(6)?, size(7)?);
                // An ellipse's semi-minor axis is the smaller; its major axis points within
                // [0, 180] (180.0 is 179.96 at one decimal); no fix uses more bearings than
                // its window holds.
                if minor_m > major_m {
                    return Err(bad(7));
                }
                let orientation_deg = size(8)?;
                if orientation_deg > 180.0 {
                    return Err(bad(8));
                }
                let (used, window) = (f.uint(10)?, f.uint(11)?);
                if used > window {
                    return Err(bad(10));
                }
                Ok(Self::Fix(FixSentence {
                    time: time(f.get(1)?).ok_or(bad(1))?,
                    position,
                    major_m,
                    minor_m,
                    orientation_deg,
                    cep50_m: size(9)?,
                    used,
                    window,
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
