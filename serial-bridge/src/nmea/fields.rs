//! Reading a sentence's fields: exact decimals (integer mantissa and power of ten, converted
//! once to `f64`), times, dates, angles and positions, each field numbered from 1 after the
//! address.

// Field readers index the digits whose count they have checked.
#![allow(clippy::indexing_slicing)]

use super::{Date, LatLon, NmeaError, UtcTime};

/// An exact decimal: mantissa and number of fraction digits.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Decimal {
    pub(crate) mantissa: i64,
    pub(crate) scale: u32,
}

const POW10: [f64; 19] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18,
];

impl Decimal {
    /// `[-|+]digits[.digits]`, at most 18 digits in all.
    pub(crate) fn parse_bytes(s: &[u8]) -> Option<Self> {
        let (negative, s) = match s {
            [b'-', rest @ ..] => (true, rest),
            [b'+', rest @ ..] => (false, rest),
            _ => (false, s),
        };
        let dot = s.iter().position(|&b| b == b'.');
        let (int, frac) = match dot {
            Some(i) => (s.get(..i)?, s.get(i + 1..)?),
            None => (s, &[][..]),
        };
        if int.is_empty() && frac.is_empty() || int.len() + frac.len() > 18 {
            return None;
        }
        let mut m: i64 = 0;
        for &b in int.iter().chain(frac) {
            if !b.is_ascii_digit() {
                return None;
            }
            m = m * 10 + i64::from(b - b'0');
        }
        Some(Self {
            mantissa: if negative { -m } else { m },
            scale: frac.len() as u32,
        })
    }

    fn parse(s: &str) -> Option<Self> {
        Self::parse_bytes(s.as_bytes())
    }

    pub(crate) fn to_f64(self) -> f64 {
        self.mantissa as f64 / POW10[self.scale as usize]
    }
}

pub(crate) fn number(s: &str) -> Option<f64> {
    Decimal::parse(s).map(Decimal::to_f64)
}

/// Fields of a sentence body, numbered from 1 after the address.
pub(super) struct Fields<'a> {
    all: [&'a str; 24],
    pub(super) count: usize,
}

impl<'a> Fields<'a> {
    pub(super) fn split(body: &'a str) -> Self {
        let mut all = [""; 24];
        let mut count = 0;
        for (i, f) in body.split(',').enumerate() {
            if i < all.len() {
                all[i] = f;
                count = i + 1;
            }
        }
        Self { all, count }
    }

    pub(super) fn get(&self, n: usize) -> &'a str {
        if n < self.count { self.all[n] } else { "" }
    }

    pub(super) fn required<T>(
        &self,
        n: usize,
        parse: impl Fn(&str) -> Option<T>,
    ) -> Result<T, NmeaError> {
        parse(self.get(n)).ok_or(NmeaError::BadField(n as u8))
    }

    pub(super) fn optional<T>(
        &self,
        n: usize,
        parse: impl Fn(&str) -> Option<T>,
    ) -> Result<Option<T>, NmeaError> {
        let f = self.get(n);
        if f.is_empty() {
            Ok(None)
        } else {
            parse(f).map(Some).ok_or(NmeaError::BadField(n as u8))
        }
    }
}

fn two_digits(s: &[u8]) -> Option<u32> {
    match s {
        [a, b] if a.is_ascii_digit() && b.is_ascii_digit() => {
            Some(u32::from(a - b'0') * 10 + u32::from(b - b'0'))
        }
        _ => None,
    }
}

/// `hhmmss[.s...]`, fraction rounded to the millisecond.
pub(crate) fn time(s: &str) -> Option<UtcTime> {
    let b = s.as_bytes();
    if b.len() < 6 {
        return None;
    }
    let (h, m, sec) = (
        two_digits(&b[0..2])?,
        two_digits(&b[2..4])?,
        two_digits(&b[4..6])?,
    );
    if h > 23 || m > 59 || sec > 60 {
        return None;
    }
    let mut ms = 0;
    if b.len() > 6 {
        let fraction = s.get(6..).filter(|f| f.starts_with('.'))?;
        let d = Decimal::parse(fraction)?;
        // 0.dddd seconds to ms, rounded half up (GPSD prints milliseconds).
        ms = ((d.to_f64() * 1000.0 + 0.5) as u32).min(999);
    }
    Some(UtcTime {
        ms_of_day: ((h * 60 + m) * 60 + sec) * 1000 + ms,
    })
}

pub(super) fn date(s: &str) -> Option<Date> {
    let b = s.as_bytes();
    if b.len() != 6 {
        return None;
    }
    let (d, m, y) = (
        two_digits(&b[0..2])?,
        two_digits(&b[2..4])?,
        two_digits(&b[4..6])?,
    );
    if !(1..=31).contains(&d) || !(1..=12).contains(&m) {
        return None;
    }
    Some(Date {
        year: if y < 80 {
            2000 + y as u16
        } else {
            1900 + y as u16
        },
        month: m as u8,
        day: d as u8,
    })
}

/// `ddmm.mmmm` (or `dddmm.mmmm`) and a hemisphere to signed degrees.
pub(crate) fn angle(
    value: &str,
    hemisphere: &str,
    max_deg: f64,
    positive: u8,
    negative: u8,
) -> Option<f64> {
    let d = Decimal::parse(value)?;
    if d.mantissa < 0 || d.scale > 16 {
        return None;
    }
    // Split off the minutes exactly: value = 100 deg + min.
    let unit = 100 * 10i64.pow(d.scale);
    let deg = d.mantissa / unit;
    let minutes = Decimal {
        mantissa: d.mantissa % unit,
        scale: d.scale,
    }
    .to_f64();
    if minutes >= 60.0 {
        return None;
    }
    let x = deg as f64 + minutes / 60.0;
    if x > max_deg {
        return None;
    }
    match hemisphere.as_bytes() {
        [h] if *h == positive => Some(x),
        [h] if *h == negative => Some(-x),
        _ => None,
    }
}

pub(super) fn position(f: &Fields<'_>, first: usize) -> Result<LatLon, NmeaError> {
    if f.get(first).is_empty() || f.get(first + 2).is_empty() {
        return Err(NmeaError::NoFix);
    }
    let lat = angle(f.get(first), f.get(first + 1), 90.0, b'N', b'S')
        .ok_or(NmeaError::BadField(first as u8))?;
    let lon = angle(f.get(first + 2), f.get(first + 3), 180.0, b'E', b'W')
        .ok_or(NmeaError::BadField(first as u8 + 2))?;
    Ok(LatLon { lat, lon })
}

pub(super) fn small_uint(s: &str) -> Option<u8> {
    if s.is_empty() || s.len() > 3 || !s.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    s.bytes()
        .try_fold(0u16, |a, b| Some(a * 10 + u16::from(b - b'0')))
        .and_then(|v| u8::try_from(v).ok())
}

pub(super) fn non_negative(s: &str) -> Option<f64> {
    number(s).filter(|v| *v >= 0.0)
}

pub(super) fn degrees(s: &str) -> Option<f64> {
    number(s).filter(|v| (0.0..=360.0).contains(v))
}

/// A heading in [0, 360): 360 itself (some units print it for dead ahead) reads as 0.
pub(super) fn heading(s: &str) -> Option<f64> {
    degrees(s).map(|v| if v >= 360.0 { 0.0 } else { v })
}

/// A signed angle from a magnitude field and an `E`/`W` field (east positive).
pub(super) fn east_west(f: &Fields<'_>, n: usize) -> Result<Option<f64>, NmeaError> {
    let Some(v) = f.optional(n, |s| number(s).filter(|v| (0.0..=180.0).contains(v)))? else {
        return Ok(None);
    };
    match f.get(n + 1) {
        "E" => Ok(Some(v)),
        "W" => Ok(Some(-v)),
        _ => Err(NmeaError::BadField(n as u8 + 1)),
    }
}
