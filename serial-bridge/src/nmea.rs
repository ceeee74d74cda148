//! NMEA 0183 sentences: GGA and RMC from any GNSS talker, and this project's `$PFOXB` bearing.
//!
//! Decoding works on the checked text between `$` and `*` that [`crate::stream`] delivers.
//! Numbers are parsed as exact decimals (integer mantissa and power of ten) and converted once
//! to `f64`, so a latitude agrees with GPSD's to 1e-9 degrees; no float parser is linked.
//! Encoding writes the same sentences (the simulator and the tests use it).

use core::fmt::{self, Write};

/// Why a sentence gave nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NmeaError {
    /// A sentence type this crate does not decode (GSV, VTG, ...); not an error on the link.
    Unsupported,
    /// The receiver says it has no fix (GGA quality 0, RMC status V or mode N, empty position).
    NoFix,
    /// Field `n` (1 = the first after the address) is missing or malformed.
    BadField(u8),
}

/// UTC time of day, milliseconds since midnight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct UtcTime {
    /// Milliseconds since 00:00:00 UTC (a leap second gives up to 86 400 999).
    pub ms_of_day: u32,
}

/// Calendar date (UTC).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Date {
    /// Year, four digits (RMC's two digits read as 2000-2099 before 80, else 1980-1999).
    pub year: u16,
    /// Month 1-12.
    pub month: u8,
    /// Day 1-31.
    pub day: u8,
}

/// A geodetic position, decimal degrees (north and east positive).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LatLon {
    /// Latitude, degrees.
    pub lat: f64,
    /// Longitude, degrees.
    pub lon: f64,
}

/// GGA: fix time, position, quality.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gga {
    /// Talker (GP, GN, ...).
    pub talker: [u8; 2],
    /// Time of the fix.
    pub time: UtcTime,
    /// Position.
    pub position: LatLon,
    /// Fix quality (1 GPS, 2 DGPS, 4 RTK fixed, ...; never 0 here).
    pub quality: u8,
    /// Satellites used, if given.
    pub satellites: Option<u8>,
    /// Horizontal dilution of precision, if given.
    pub hdop: Option<f32>,
    /// Altitude above mean sea level, metres, if given.
    pub altitude_m: Option<f32>,
}

/// RMC: time, date, position, speed and course.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rmc {
    /// Talker.
    pub talker: [u8; 2],
    /// Time of the fix.
    pub time: UtcTime,
    /// Date, if given.
    pub date: Option<Date>,
    /// Position.
    pub position: LatLon,
    /// Speed over ground, knots, if given.
    pub speed_kn: Option<f64>,
    /// Course over ground, degrees true, if given.
    pub course_deg: Option<f64>,
}

/// Reference of a DF azimuth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Reference {
    /// Clockwise from true north (`T`).
    True,
    /// Clockwise from the vehicle's heading (`R`).
    Relative,
}

/// `$PFOXB`: one bearing from the direction finder.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pfoxb {
    /// Time of the bearing.
    pub time: UtcTime,
    /// Azimuth, degrees in [0, 360).
    pub azimuth_deg: f64,
    /// What the azimuth is measured from.
    pub reference: Reference,
    /// DF quality 0..100.
    pub quality: f32,
    /// Frequency, MHz.
    pub freq_mhz: f64,
    /// The DF unit's own position, if it sent one.
    pub position: Option<LatLon>,
}

/// A decoded sentence.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Sentence {
    /// GGA.
    Gga(Gga),
    /// RMC.
    Rmc(Rmc),
    /// PFOXB.
    Pfoxb(Pfoxb),
}

/// Talkers whose GGA and RMC are decoded.
pub const TALKERS: [&[u8; 2]; 6] = [b"GP", b"GN", b"GL", b"GA", b"GB", b"BD"];

/// An exact decimal: mantissa and number of fraction digits.
#[derive(Debug, Clone, Copy)]
struct Decimal {
    mantissa: i64,
    scale: u32,
}

const POW10: [f64; 19] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18,
];

impl Decimal {
    /// `[-]digits[.digits]`, at most 18 digits in all.
    fn parse(s: &str) -> Option<Self> {
        let (negative, s) = match s.strip_prefix('-') {
            Some(rest) => (true, rest),
            None => (false, s),
        };
        let (int, frac) = s.split_once('.').unwrap_or((s, ""));
        if int.is_empty() && frac.is_empty() || int.len() + frac.len() > 18 {
            return None;
        }
        let mut m: i64 = 0;
        for b in int.bytes().chain(frac.bytes()) {
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

    fn to_f64(self) -> f64 {
        self.mantissa as f64 / POW10[self.scale as usize]
    }
}

fn number(s: &str) -> Option<f64> {
    Decimal::parse(s).map(Decimal::to_f64)
}

/// Fields of a sentence body, numbered from 1 after the address.
struct Fields<'a> {
    all: [&'a str; 24],
    count: usize,
}

impl<'a> Fields<'a> {
    fn split(body: &'a str) -> Self {
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

    fn get(&self, n: usize) -> &'a str {
        if n < self.count { self.all[n] } else { "" }
    }

    fn required<T>(&self, n: usize, parse: impl Fn(&str) -> Option<T>) -> Result<T, NmeaError> {
        parse(self.get(n)).ok_or(NmeaError::BadField(n as u8))
    }

    fn optional<T>(
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
fn time(s: &str) -> Option<UtcTime> {
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

fn date(s: &str) -> Option<Date> {
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
fn angle(value: &str, hemisphere: &str, max_deg: f64, positive: u8, negative: u8) -> Option<f64> {
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

fn position(f: &Fields<'_>, first: usize) -> Result<LatLon, NmeaError> {
    if f.get(first).is_empty() || f.get(first + 2).is_empty() {
        return Err(NmeaError::NoFix);
    }
    let lat = angle(f.get(first), f.get(first + 1), 90.0, b'N', b'S')
        .ok_or(NmeaError::BadField(first as u8))?;
    let lon = angle(f.get(first + 2), f.get(first + 3), 180.0, b'E', b'W')
        .ok_or(NmeaError::BadField(first as u8 + 2))?;
    Ok(LatLon { lat, lon })
}

fn small_uint(s: &str) -> Option<u8> {
    if s.is_empty() || s.len() > 3 || !s.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    s.bytes()
        .try_fold(0u16, |a, b| Some(a * 10 + u16::from(b - b'0')))
        .and_then(|v| u8::try_from(v).ok())
}

fn non_negative(s: &str) -> Option<f64> {
    number(s).filter(|v| *v >= 0.0)
}

impl Sentence {
    /// Decode the text between `$` and `*` of a checked sentence.
    pub fn parse(body: &str) -> Result<Self, NmeaError> {
        let f = Fields::split(body);
        let address = f.get(0).as_bytes();
        if address == b"PFOXB" {
            return Self::pfoxb(&f);
        }
        let [t0, t1, kind @ ..] = address else {
            return Err(NmeaError::Unsupported);
        };
        let talker = [*t0, *t1];
        if !TALKERS.contains(&&talker) {
            return Err(NmeaError::Unsupported);
        }
        match kind {
            b"GGA" => Self::gga(&f, talker),
            b"RMC" => Self::rmc(&f, talker),
            _ => Err(NmeaError::Unsupported),
        }
    }

    fn gga(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let quality = f.get(6);
        if quality.is_empty() || quality == "0" {
            return Err(NmeaError::NoFix);
        }
        let quality = f.required(6, small_uint)?;
        let position = position(f, 2)?;
        Ok(Self::Gga(Gga {
            talker,
            time: f.required(1, time)?,
            position,
            quality,
            satellites: f.optional(7, small_uint)?,
            hdop: f.optional(8, non_negative)?.map(|v| v as f32),
            altitude_m: f.optional(9, number)?.map(|v| v as f32),
        }))
    }

    fn rmc(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        match f.get(2) {
            "A" => {}
            "V" => return Err(NmeaError::NoFix),
            _ => return Err(NmeaError::BadField(2)),
        }
        // NMEA 2.3 mode indicator: N = data not valid.
        if f.get(12) == "N" {
            return Err(NmeaError::NoFix);
        }
        let position = position(f, 3)?;
        Ok(Self::Rmc(Rmc {
            talker,
            time: f.required(1, time)?,
            date: f.optional(9, date)?,
            position,
            speed_kn: f.optional(7, non_negative)?,
            course_deg: f.optional(8, |s| number(s).filter(|v| (0.0..=360.0).contains(v)))?,
        }))
    }

    fn pfoxb(f: &Fields<'_>) -> Result<Self, NmeaError> {
        let reference = match f.get(3) {
            "T" => Reference::True,
            "R" => Reference::Relative,
            _ => return Err(NmeaError::BadField(3)),
        };
        let position = match f.count {
            6 => None,
            10 => Some(position(f, 6).map_err(|e| match e {
                NmeaError::NoFix => NmeaError::BadField(6),
                e => e,
            })?),
            _ => return Err(NmeaError::BadField(f.count.min(255) as u8)),
        };
        Ok(Self::Pfoxb(Pfoxb {
            time: f.required(1, time)?,
            azimuth_deg: f.required(2, |s| number(s).filter(|v| (0.0..360.0).contains(v)))?,
            reference,
            quality: f.required(4, |s| number(s).filter(|v| (0.0..=100.0).contains(v)))? as f32,
            freq_mhz: f.required(5, |s| number(s).filter(|v| *v > 0.0))?,
            position,
        }))
    }
}

/// XOR of the bytes of a sentence body.
pub fn checksum(body: &str) -> u8 {
    body.bytes().fold(0, |x, b| x ^ b)
}

/// Write `$body*hh\r\n`.
pub fn write_sentence(out: &mut impl Write, body: &str) -> fmt::Result {
    write!(out, "${body}*{:02X}\r\n", checksum(body))
}

/// Formats a time of day as `hhmmss.sss`.
pub struct TimeField(pub UtcTime);

impl fmt::Display for TimeField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ms = self.0.ms_of_day;
        let s = ms / 1000;
        write!(
            f,
            "{:02}{:02}{:02}.{:03}",
            s / 3600,
            s / 60 % 60,
            s % 60,
            ms % 1000
        )
    }
}

/// Formats a latitude or longitude as `ddmm.mmmmmm,H` (`dddmm...` for longitude).
pub struct AngleField {
    /// Degrees, signed.
    pub degrees: f64,
    /// Longitude (three degree digits, E/W) or latitude.
    pub longitude: bool,
}

impl fmt::Display for AngleField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = if self.degrees < 0.0 {
            -self.degrees
        } else {
            self.degrees
        };
        // Six decimals of minutes: 1.9 mm, far below any GPS error.
        let micro_minutes = libm::round(a * 60.0e6) as u64;
        let (deg, rest) = (micro_minutes / 60_000_000, micro_minutes % 60_000_000);
        let hemisphere = match (self.longitude, self.degrees < 0.0) {
            (false, false) => 'N',
            (false, true) => 'S',
            (true, false) => 'E',
            (true, true) => 'W',
        };
        let width = if self.longitude { 3 } else { 2 };
        write!(
            f,
            "{deg:0width$}{:02}.{:06},{hemisphere}",
            rest / 1_000_000,
            rest % 1_000_000
        )
    }
}

/// Formats a position as the four NMEA fields `lat,N|S,lon,E|W`.
pub struct PositionField(pub LatLon);

impl fmt::Display for PositionField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let lat = AngleField {
            degrees: self.0.lat,
            longitude: false,
        };
        let lon = AngleField {
            degrees: self.0.lon,
            longitude: true,
        };
        write!(f, "{lat},{lon}")
    }
}

/// A fixed-capacity line buffer that implements `fmt::Write` (no allocator).
pub type Line = heapless::String<96>;

/// The body of a GGA sentence (talker GP) for a fix.
pub fn gga_body(
    out: &mut Line,
    time: UtcTime,
    p: LatLon,
    satellites: u8,
    hdop: f32,
) -> fmt::Result {
    write!(
        out,
        "GPGGA,{},{},1,{satellites:02},{hdop:.1},0.0,M,0.0,M,,",
        TimeField(time),
        PositionField(p),
    )
}

/// The body of an RMC sentence (talker GP).
pub fn rmc_body(
    out: &mut Line,
    time: UtcTime,
    date: Date,
    p: LatLon,
    speed_kn: f64,
    course_deg: f64,
) -> fmt::Result {
    write!(
        out,
        "GPRMC,{},A,{},{speed_kn:.2},{course_deg:.2},{:02}{:02}{:02},,,A",
        TimeField(time),
        PositionField(p),
        date.day,
        date.month,
        date.year % 100
    )
}

/// The body of a PFOXB sentence.
pub fn pfoxb_body(out: &mut Line, b: &Pfoxb) -> fmt::Result {
    let r = match b.reference {
        Reference::True => 'T',
        Reference::Relative => 'R',
    };
    write!(
        out,
        "PFOXB,{},{:.2},{r},{:.0},{:.3}",
        TimeField(b.time),
        b.azimuth_deg,
        b.quality,
        b.freq_mhz
    )?;
    if let Some(p) = b.position {
        write!(out, ",{}", PositionField(p))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spec_examples() {
        let Ok(Sentence::Gga(g)) =
            Sentence::parse("GPGGA,092750.000,5321.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,")
        else {
            panic!("GGA")
        };
        assert_eq!(g.time.ms_of_day, (9 * 3600 + 27 * 60 + 50) * 1000);
        assert!((g.position.lat - (53.0 + 21.6802 / 60.0)).abs() < 1e-12);
        assert!((g.position.lon + (6.0 + 30.3372 / 60.0)).abs() < 1e-12);
        let Ok(Sentence::Rmc(r)) =
            Sentence::parse("GPRMC,092750.000,A,5321.6802,N,00630.3372,W,0.02,31.66,280511,,,A")
        else {
            panic!("RMC")
        };
        assert_eq!(
            r.date,
            Some(Date {
                year: 2011,
                month: 5,
                day: 28
            })
        );
        assert_eq!((r.speed_kn, r.course_deg), (Some(0.02), Some(31.66)));
        let Ok(Sentence::Pfoxb(b)) = Sentence::parse("PFOXB,092751.00,57.3,T,83,433.920") else {
            panic!("PFOXB")
        };
        assert_eq!(b.time.ms_of_day, (9 * 3600 + 27 * 60 + 51) * 1000);
        assert_eq!(
            (b.azimuth_deg, b.reference, b.quality),
            (57.3, Reference::True, 83.0)
        );
        assert_eq!(checksum("PFOXB,092751.00,57.3,T,83,433.920"), 0x28);
    }

    #[test]
    fn no_fix_and_bad_fields() {
        assert_eq!(
            Sentence::parse("GPGGA,092750.000,,,,,0,0,,,M,,M,,"),
            Err(NmeaError::NoFix)
        );
        assert_eq!(
            Sentence::parse("GNRMC,092750.000,V,5321.6802,N,00630.3372,W,,,280511,,,N"),
            Err(NmeaError::NoFix)
        );
        assert_eq!(
            Sentence::parse("GPGGA,092750.000,5391.6802,N,00630.3372,W,1,8,1.03,61.7,M,55.2,M,,"),
            Err(NmeaError::BadField(2))
        );
        assert_eq!(
            Sentence::parse("PFOXB,092751.00,360.0,T,83,433.920"),
            Err(NmeaError::BadField(2))
        );
        assert_eq!(
            Sentence::parse("PFOXB,092751.00,5,X,83,433.920"),
            Err(NmeaError::BadField(3))
        );
        assert_eq!(Sentence::parse("GPGSV,3,1,12"), Err(NmeaError::Unsupported));
        assert_eq!(Sentence::parse("XXGGA,1"), Err(NmeaError::Unsupported));
    }

    #[test]
    fn encode_then_decode() {
        let p = LatLon {
            lat: -37.784_788_333,
            lon: 175.314_896_667,
        };
        let t = UtcTime {
            ms_of_day: 11_239_500,
        };
        let mut line = Line::new();
        gga_body(&mut line, t, p, 8, 1.1).expect("fits");
        let Ok(Sentence::Gga(g)) = Sentence::parse(&line) else {
            panic!("{line}")
        };
        // Six decimals of minutes: 1e-6 / 60 degrees.
        assert!((g.position.lat - p.lat).abs() < 1e-8 && (g.position.lon - p.lon).abs() < 1e-8);
        assert_eq!(g.time, t);
        let b = Pfoxb {
            time: t,
            azimuth_deg: 359.99,
            reference: Reference::Relative,
            quality: 55.0,
            freq_mhz: 433.92,
            position: Some(p),
        };
        line.clear();
        pfoxb_body(&mut line, &b).expect("fits");
        let Ok(Sentence::Pfoxb(d)) = Sentence::parse(&line) else {
            panic!("{line}")
        };
        assert_eq!(
            (d.azimuth_deg, d.reference, d.quality, d.freq_mhz),
            (359.99, Reference::Relative, 55.0, 433.92)
        );
        assert!(d.position.is_some());
    }
}
