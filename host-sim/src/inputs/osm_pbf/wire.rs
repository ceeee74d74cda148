//! The protobuf wire format, the part OSM PBF uses: varints, zigzag-coded signed integers,
//! length-delimited fields and packed repeated scalars. Unknown fields of every wire type
//! (fixed 32 and 64 bits, the deprecated groups) are skipped. Nothing here allocates: a
//! message is a byte slice and its fields are views into it.

use std::fmt;

/// Why bytes are not a protobuf message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WireError {
    /// A varint over 10 bytes, or one whose value passes 64 bits.
    BadVarint,
    /// A varint or a field runs past the end of its message.
    PastEnd,
    /// Wire type 6 or 7 (none such exists).
    BadWireType(u8),
    /// Field number 0 or past 2^29 - 1.
    BadFieldNumber(u64),
    /// A group end without its start, or groups nested past 32 deep.
    BadGroup,
}

impl fmt::Display for WireError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadVarint => write!(f, "bad varint (over 10 bytes or past 64 bits)"),
            Self::PastEnd => write!(f, "a field runs past the end of its message"),
            Self::BadWireType(t) => write!(f, "bad wire type {t}"),
            Self::BadFieldNumber(n) => write!(f, "bad field number {n}"),
            Self::BadGroup => write!(f, "unbalanced or too deeply nested group"),
        }
    }
}

/// Groups deeper than this are refused (OSM PBF has none; this bounds the skipping).
const MAX_GROUP_DEPTH: u32 = 32;

/// The varint at `*pos` in `buf`; `*pos` moves past it.
pub fn varint(buf: &[u8], pos: &mut usize) -> Result<u64, WireError> {
    let mut value = 0u64;
    for k in 0..10 {
        let Some(&b) = buf.get(*pos) else {
            return Err(WireError::PastEnd);
        };
        *pos += 1;
        // The tenth byte holds bit 63 only.
        if k == 9 && b > 1 {
            return Err(WireError::BadVarint);
        }
        value |= u64::from(b & 0x7f) << (7 * k);
        if b < 0x80 {
            return Ok(value);
        }
    }
    Err(WireError::BadVarint)
}

/// A zigzag-coded `sint64`/`sint32`.
pub fn zigzag(n: u64) -> i64 {
    ((n >> 1) as i64) ^ -((n & 1) as i64)
}

/// One field's value as the wire carries it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Value<'a> {
    /// Wire type 0: every integer type and bool.
    Varint(u64),
    /// Wire type 2: strings, bytes, embedded messages, packed repeated scalars.
    Bytes(&'a [u8]),
    /// Wire types 1 and 5 (fixed64, fixed32, double, float): not used by OSM PBF.
    Fixed,
}

/// The fields of a message in order, as (field number, value). Groups are skipped whole. The
/// first error ends the iteration.
#[derive(Debug, Clone)]
pub struct Fields<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Fields<'a> {
    /// The fields of the message `buf`.
    pub fn new(buf: &'a [u8]) -> Self {
        Self { buf, pos: 0 }
    }

    /// The next field's number and wire type, or None at the end.
    fn key(&mut self) -> Result<Option<(u32, u8)>, WireError> {
        if self.pos >= self.buf.len() {
            return Ok(None);
        }
        let key = varint(self.buf, &mut self.pos)?;
        let number = key >> 3;
        if number == 0 || number > (1 << 29) - 1 {
            return Err(WireError::BadFieldNumber(number));
        }
        Ok(Some((number as u32, (key & 7) as u8)))
    }

    /// Moves past `len` bytes.
    fn skip(&mut self, len: u64) -> Result<&'a [u8], WireError> {
        let rest = self.buf.len() - self.pos.min(self.buf.len());
        if len > rest as u64 {
            return Err(WireError::PastEnd);
        }
        let start = self.pos;
        self.pos += len as usize;
        self.buf.get(start..self.pos).ok_or(WireError::PastEnd)
    }

    /// The value of a field of wire type `wire`, or None for a group (skipped to its end).
    fn value(&mut self, wire: u8) -> Result<Option<Value<'a>>, WireError> {
        Ok(Some(match wire {
            0 => Value::Varint(varint(self.buf, &mut self.pos)?),
            1 => {
                self.skip(8)?;
                Value::Fixed
            }
            2 => {
                let len = varint(self.buf, &mut self.pos)?;
                Value::Bytes(self.skip(len)?)
            }
            3 => {
                self.skip_group()?;
                return Ok(None);
            }
            4 => return Err(WireError::BadGroup),
            5 => {
                self.skip(4)?;
                Value::Fixed
            }
            t => return Err(WireError::BadWireType(t)),
        }))
    }

    /// Past a group whose start key was just read, nested groups included.
    fn skip_group(&mut self) -> Result<(), WireError> {
        let mut depth = 1u32;
        while depth > 0 {
            let Some((_, wire)) = self.key()? else {
                return Err(WireError::PastEnd);
            };
            match wire {
                3 => {
                    depth += 1;
                    if depth > MAX_GROUP_DEPTH {
                        return Err(WireError::BadGroup);
                    }
                }
                4 => depth -= 1,
                w => {
                    self.value(w)?;
                }
            }
        }
        Ok(())
    }

    fn step(&mut self) -> Result<Option<(u32, Value<'a>)>, WireError> {
        loop {
            let Some((number, wire)) = self.key()? else {
                return Ok(None);
            };
            if let Some(v) = self.value(wire)? {
                return Ok(Some((number, v)));
            }
        }
    }
}

impl<'a> Iterator for Fields<'a> {
    type Item = Result<(u32, Value<'a>), WireError>;

    fn next(&mut self) -> Option<Self::Item> {
        let r = self.step();
        if r.is_err() {
            self.pos = self.buf.len();
        }
        r.transpose()
    }
}

/// The varints of a packed repeated field. The first error ends the iteration.
#[derive(Debug, Clone, Default)]
pub struct Packed<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Packed<'a> {
    /// The varints packed in `buf`.
    pub fn new(buf: &'a [u8]) -> Self {
        Self { buf, pos: 0 }
    }
}

impl Iterator for Packed<'_> {
    type Item = Result<u64, WireError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.buf.len() {
            return None;
        }
        let r = varint(self.buf, &mut self.pos);
        if r.is_err() {
            self.pos = self.buf.len();
        }
        Some(r)
    }
}

/// A packed repeated `sint64` delta-coded (each value the difference from the one before):
/// the running sums. An overflowing sum is an error, like a bad varint.
#[derive(Debug, Clone, Default)]
pub struct Deltas<'a> {
    packed: Packed<'a>,
    sum: i64,
}

/// An error in a delta-coded field: the wire's, or a sum past 64 bits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeltaError {
    /// A bad varint.
    Wire(WireError),
    /// The running sum overflows 64 bits.
    Overflow,
}

impl<'a> Deltas<'a> {
    /// The running sums of the deltas packed in `buf`.
    pub fn new(buf: &'a [u8]) -> Self {
        Self {
            packed: Packed::new(buf),
            sum: 0,
        }
    }
}

impl Iterator for Deltas<'_> {
    type Item = Result<i64, DeltaError>;

    fn next(&mut self) -> Option<Self::Item> {
        let r = match self.packed.next()? {
            Err(e) => Err(DeltaError::Wire(e)),
            Ok(v) => self
                .sum
                .checked_add(zigzag(v))
                .ok_or(DeltaError::Overflow)
                .inspect(|s| self.sum = *s),
        };
        if r.is_err() {
            self.packed.pos = self.packed.buf.len();
        }
        Some(r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varints_and_zigzag_decode() {
        let mut pos = 0;
        assert_eq!(varint(&[0x96, 0x01], &mut pos), Ok(150));
        assert_eq!(pos, 2);
        let max = [0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01];
        assert_eq!(varint(&max, &mut 0), Ok(u64::MAX));
        let mut over = max;
        over[9] = 0x02;
        assert_eq!(varint(&over, &mut 0), Err(WireError::BadVarint));
        assert_eq!(varint(&[0x80; 11], &mut 0), Err(WireError::BadVarint));
        assert_eq!(varint(&[0x80, 0x80], &mut 0), Err(WireError::PastEnd));
        assert_eq!([0, 1, 2, 3, u64::MAX].map(zigzag), [0, -1, 1, -2, i64::MIN]);
    }

    #[test]
    fn fields_skip_what_is_not_read() {
        // 1: varint 150; 2: fixed64; 3: a group holding a field and a nested group; 4: fixed32;
        // 5: bytes "ab".
        let msg = [
            0x08, 0x96, 0x01, 0x11, 1, 2, 3, 4, 5, 6, 7, 8, 0x1b, 0x08, 0x01, 0x1b, 0x1c, 0x1c,
            0x25, 1, 2, 3, 4, 0x2a, 0x02, b'a', b'b',
        ];
        let got: Vec<_> = Fields::new(&msg).collect();
        assert_eq!(
            got,
            vec![
                Ok((1, Value::Varint(150))),
                Ok((2, Value::Fixed)),
                Ok((4, Value::Fixed)),
                Ok((5, Value::Bytes(b"ab"))),
            ]
        );
        // A length past the end, a lone group end, wire type 7, field 0: each one error, then
        // nothing.
        for (bad, e) in [
            (&[0x2a, 0x05, b'a'][..], WireError::PastEnd),
            (
                &[0x2a, 0xff, 0xff, 0xff, 0xff, 0x0f][..],
                WireError::PastEnd,
            ),
            (&[0x0c][..], WireError::BadGroup),
            (&[0x0f, 0x00][..], WireError::BadWireType(7)),
            (&[0x00, 0x00][..], WireError::BadFieldNumber(0)),
            (&[0x0b][..], WireError::PastEnd),
        ] {
            let got: Vec<_> = Fields::new(bad).collect();
            assert_eq!(got, vec![Err(e)], "{bad:?}");
        }
    }

    #[test]
    fn deltas_sum_and_refuse_overflow() {
        // 5, +3, -2 (zigzag 10, 6, 3).
        let got: Vec<_> = Deltas::new(&[10, 6, 3]).collect();
        assert_eq!(got, vec![Ok(5), Ok(8), Ok(6)]);
        // i64::MAX then +1.
        let mut bytes = vec![0xfe, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0x01];
        bytes.push(2);
        let got: Vec<_> = Deltas::new(&bytes).collect();
        assert_eq!(got, vec![Ok(i64::MAX), Err(DeltaError::Overflow)]);
    }
}
