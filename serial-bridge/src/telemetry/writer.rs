//! A sentence written in a fixed buffer without `core::fmt`: integers and fixed-point
//! decimals, rounded half up.

use crate::nmea::{UtcTime, xor};
use crate::stream::MAX_SENTENCE;
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
