//! NMEA 0183 sentences as GPSD takes them: positions (GGA, RMC, GLL, GNS), course and speed
//! (VTG), headings (HDT, THS, HDG, HDM) from any two-letter talker, and this project's `$PFOXB`.
//!
//! Decoding works on the checked text between `$` and `*` that [`crate::stream`] delivers.
//! Numbers are parsed as exact decimals (integer mantissa and power of ten) and converted once
//! to `f64`, so a latitude agrees with GPSD's to 1e-9 degrees; no float parser is linked.
//! Every sentence type is a plain `Copy` struct with `parse` and `emit` (smoltcp's `Repr`
//! pattern): `emit` writes the body that `parse` reads back, and is what `foxhunt simulate`
//! uses. [`write_sentence`] adds the `$`, the checksum and the line end.
//!
//! Where GPSD still takes a fix, so do we: a GGA whose fix quality is empty or 0 but which
//! names three or more satellites in use is a (2D) fix, as GPSD decides over its regression
//! suite (mtk-3301, myguide-3100); with fewer it is no fix, and so is any GGA naming zero
//! satellites in use (garmin25lp, haicom-305N).

use core::fmt::{self, Write};

/// Why a sentence gave nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum NmeaError {
    /// A sentence type this crate does not decode (GSV, GSA, ...); not an error on the link.
    Unsupported,
    /// The receiver says it has no fix (GGA quality 0, RMC/GLL status V, mode N, empty
    /// position, THS mode V).
    NoFix,
    /// Field `n` (1 = the first after the address) is missing or malformed.
    BadField(u8),
}

impl fmt::Display for NmeaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Unsupported => f.write_str("sentence type not decoded"),
            Self::NoFix => f.write_str("receiver reports no fix"),
            Self::BadField(n) => write!(f, "field {n} missing or malformed"),
        }
    }
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
    /// Fix quality (1 GPS, 2 DGPS, 4 RTK fixed, ...; `None` when the receiver sent 0 or left
    /// it empty beside three or more satellites in use, which GPSD takes as a fix).
    pub quality: Option<u8>,
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

/// GLL: position and (since NMEA 2.0) its time.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gll {
    /// Talker.
    pub talker: [u8; 2],
    /// Position.
    pub position: LatLon,
    /// Time of the fix; NMEA 1.5 receivers leave it out.
    pub time: Option<UtcTime>,
}

/// GNS: the multi-constellation fix.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Gns {
    /// Talker.
    pub talker: [u8; 2],
    /// Time of the fix.
    pub time: UtcTime,
    /// Position.
    pub position: LatLon,
    /// The first constellation's mode letter (A autonomous, D differential, R/F RTK, E
    /// estimated, ...; never N here).
    pub mode: u8,
    /// Satellites used, if given.
    pub satellites: Option<u8>,
    /// Horizontal dilution of precision, if given.
    pub hdop: Option<f32>,
    /// Altitude above mean sea level, metres, if given.
    pub altitude_m: Option<f32>,
}

/// VTG: course and speed over ground.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Vtg {
    /// Talker.
    pub talker: [u8; 2],
    /// Course over ground, degrees true.
    pub course_deg: Option<f64>,
    /// Course over ground, degrees magnetic.
    pub course_magnetic_deg: Option<f64>,
    /// Speed over ground, knots.
    pub speed_kn: Option<f64>,
    /// Speed over ground, km/h.
    pub speed_kmh: Option<f64>,
    /// The old form (NMEA 1.x: `cogT,cogM,kn,kmh` without unit letters).
    pub old_form: bool,
}

impl Vtg {
    /// Speed in m/s: from knots, else from km/h.
    pub fn speed_mps(&self) -> Option<f64> {
        self.speed_kn
            .map(|k| k * KNOT_MPS)
            .or(self.speed_kmh.map(|k| k / 3.6))
    }
}

/// Metres per second in a knot.
pub const KNOT_MPS: f64 = 1852.0 / 3600.0;

/// HDT: true heading (gyro, dual-antenna GNSS).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hdt {
    /// Talker (HE, GP, ...).
    pub talker: [u8; 2],
    /// Heading, degrees true.
    pub heading_deg: f64,
}

/// THS: true heading and its mode.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ths {
    /// Talker.
    pub talker: [u8; 2],
    /// Heading, degrees true.
    pub heading_deg: f64,
    /// Mode: A autonomous, E estimated, M manual, S simulator (V, not valid, is
    /// [`NmeaError::NoFix`]).
    pub mode: u8,
}

/// HDG: a magnetic sensor's heading with its deviation and the local variation.
///
/// Magnetic heading = sensor + deviation; true heading = magnetic + variation (east positive).
/// The fields are read here as NMEA 0183 defines them (GPSD's decoder indexes them one off).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hdg {
    /// Talker (HC, SD, II, ...).
    pub talker: [u8; 2],
    /// Sensor heading, degrees.
    pub sensor_deg: f64,
    /// Deviation, degrees, east positive; `None` when not given.
    pub deviation_deg: Option<f64>,
    /// Magnetic variation, degrees, east positive; `None` when not given.
    pub variation_deg: Option<f64>,
}

impl Hdg {
    /// Magnetic heading, degrees in [0, 360) (deviation taken as 0 when not given).
    pub fn magnetic_deg(&self) -> f64 {
        wrap_deg(self.sensor_deg + self.deviation_deg.unwrap_or(0.0))
    }

    /// True heading with this sentence's own variation, if it carries one.
    pub fn true_deg(&self) -> Option<f64> {
        self.variation_deg
            .map(|v| wrap_deg(self.magnetic_deg() + v))
    }
}

/// HDM: magnetic heading (deprecated in NMEA 4, still sent by autopilots).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Hdm {
    /// Talker.
    pub talker: [u8; 2],
    /// Heading, degrees magnetic.
    pub heading_deg: f64,
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
    /// GLL.
    Gll(Gll),
    /// GNS.
    Gns(Gns),
    /// VTG.
    Vtg(Vtg),
    /// HDT.
    Hdt(Hdt),
    /// THS.
    Ths(Ths),
    /// HDG.
    Hdg(Hdg),
    /// HDM.
    Hdm(Hdm),
    /// PFOXB.
    Pfoxb(Pfoxb),
}

/// The common GNSS talkers (any two capital letters are accepted).
pub const TALKERS: [&[u8; 2]; 6] = [b"GP", b"GN", b"GL", b"GA", b"GB", b"BD"];

/// `x` in [0, 360), for sums of angles each already in (-360, 720).
fn wrap_deg(x: f64) -> f64 {
    let mut a = x;
    // At most two steps for the sums built here; no fmod linked.
    for _ in 0..3 {
        if a >= 360.0 {
            a -= 360.0;
        } else if a < 0.0 {
            a += 360.0;
        }
    }
    if (0.0..360.0).contains(&a) { a } else { 0.0 }
}

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

fn degrees(s: &str) -> Option<f64> {
    number(s).filter(|v| (0.0..=360.0).contains(v))
}

/// A heading in [0, 360): 360 itself (some units print it for dead ahead) reads as 0.
fn heading(s: &str) -> Option<f64> {
    degrees(s).map(|v| if v >= 360.0 { 0.0 } else { v })
}

/// A signed angle from a magnitude field and an `E`/`W` field (east positive).
fn east_west(f: &Fields<'_>, n: usize) -> Result<Option<f64>, NmeaError> {
    let Some(v) = f.optional(n, |s| number(s).filter(|v| (0.0..=180.0).contains(v)))? else {
        return Ok(None);
    };
    match f.get(n + 1) {
        "E" => Ok(Some(v)),
        "W" => Ok(Some(-v)),
        _ => Err(NmeaError::BadField(n as u8 + 1)),
    }
}

/// A sentence's talker and type, if its address is two capital letters and three more.
fn address(body: &str) -> Option<([u8; 2], &[u8])> {
    let a = body.split(',').next()?.as_bytes();
    match a {
        [t0, t1, kind @ ..] if t0.is_ascii_uppercase() && t1.is_ascii_uppercase() => {
            Some(([*t0, *t1], kind))
        }
        _ => None,
    }
}

fn talker_str(t: &[u8; 2]) -> &str {
    core::str::from_utf8(t).unwrap_or("GP")
}

impl Sentence {
    /// Decode the text between `$` and `*` of a checked sentence.
    pub fn parse(body: &str) -> Result<Self, NmeaError> {
        let f = Fields::split(body);
        if f.get(0) == "PFOXB" {
            return Pfoxb::from_fields(&f).map(Self::Pfoxb);
        }
        let Some((talker, kind)) = address(body) else {
            return Err(NmeaError::Unsupported);
        };
        match kind {
            b"GGA" => Gga::from_fields(&f, talker).map(Self::Gga),
            b"RMC" => Rmc::from_fields(&f, talker).map(Self::Rmc),
            b"GLL" => Gll::from_fields(&f, talker).map(Self::Gll),
            b"GNS" => Gns::from_fields(&f, talker).map(Self::Gns),
            b"VTG" => Vtg::from_fields(&f, talker).map(Self::Vtg),
            b"HDT" => Hdt::from_fields(&f, talker).map(Self::Hdt),
            b"THS" => Ths::from_fields(&f, talker).map(Self::Ths),
            b"HDG" => Hdg::from_fields(&f, talker).map(Self::Hdg),
            b"HDM" => Hdm::from_fields(&f, talker).map(Self::Hdm),
            _ => Err(NmeaError::Unsupported),
        }
    }

    /// Write the body that [`Sentence::parse`] reads back.
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        match self {
            Self::Gga(s) => s.emit(out),
            Self::Rmc(s) => s.emit(out),
            Self::Gll(s) => s.emit(out),
            Self::Gns(s) => s.emit(out),
            Self::Vtg(s) => s.emit(out),
            Self::Hdt(s) => s.emit(out),
            Self::Ths(s) => s.emit(out),
            Self::Hdg(s) => s.emit(out),
            Self::Hdm(s) => s.emit(out),
            Self::Pfoxb(s) => s.emit(out),
        }
    }

    /// The time of day a sentence carries, even one that gives no fix: the bridge's clock
    /// keeps running while the receiver has no fix.
    pub fn time_of(body: &str) -> Option<UtcTime> {
        let (_, kind) = address(body)?;
        let n = match kind {
            b"GGA" | b"RMC" | b"GNS" => 1,
            b"GLL" => 5,
            _ => return None,
        };
        time(body.split(',').nth(n)?)
    }
}

/// Parse one sentence type from its body alone (the address must name it).
macro_rules! parse_one {
    ($t:ident, $variant:ident) => {
        impl $t {
            /// Decode a checked sentence body of this type.
            pub fn parse(body: &str) -> Result<Self, NmeaError> {
                match Sentence::parse(body)? {
                    Sentence::$variant(s) => Ok(s),
                    _ => Err(NmeaError::Unsupported),
                }
            }
        }
    };
}

parse_one!(Gga, Gga);
parse_one!(Rmc, Rmc);
parse_one!(Gll, Gll);
parse_one!(Gns, Gns);
parse_one!(Vtg, Vtg);
parse_one!(Hdt, Hdt);
parse_one!(Ths, Ths);
parse_one!(Hdg, Hdg);
parse_one!(Hdm, Hdm);
parse_one!(Pfoxb, Pfoxb);

struct Opt<T>(Option<T>, usize);

impl fmt::Display for Opt<f64> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(v) => write!(f, "{v:.prec$}", prec = self.1),
            None => Ok(()),
        }
    }
}

impl fmt::Display for Opt<f32> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        Opt(self.0.map(f64::from), self.1).fmt(f)
    }
}

impl fmt::Display for Opt<u8> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(v) => write!(f, "{v:0width$}", width = self.1),
            None => Ok(()),
        }
    }
}

/// A signed east/west angle as `magnitude,E|W` (both empty when unknown).
struct EastWest(Option<f64>);

impl fmt::Display for EastWest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(v) if v < 0.0 => write!(f, "{:.1},W", -v),
            Some(v) => write!(f, "{v:.1},E"),
            None => f.write_str(","),
        }
    }
}

impl Gga {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let quality = f.optional(6, small_uint)?;
        let satellites = f.optional(7, small_uint)?;
        // GPSD's rules (see the module doc): quality 0 or empty is a fix when three or more
        // satellites are in use; no satellites in use is no fix whatever the quality says.
        let no_quality = matches!(quality, None | Some(0));
        if no_quality && satellites.is_none_or(|n| n < 3) || satellites == Some(0) {
            return Err(NmeaError::NoFix);
        }
        let position = position(f, 2)?;
        Ok(Self {
            talker,
            time: f.required(1, time)?,
            position,
            quality: quality.filter(|&q| q > 0),
            satellites,
            hdop: f.optional(8, non_negative)?.map(|v| v as f32),
            altitude_m: f.optional(9, number)?.map(|v| v as f32),
        })
    }

    /// Write the body (`GPGGA,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}GGA,{},{},{},{},{},{},M,0.0,M,,",
            talker_str(&self.talker),
            TimeField(self.time),
            PositionField(self.position),
            Opt(self.quality, 1),
            Opt(self.satellites, 2),
            Opt(self.hdop, 1),
            Opt(self.altitude_m, 1),
        )
    }
}

impl Rmc {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
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
        Ok(Self {
            talker,
            time: f.required(1, time)?,
            date: f.optional(9, date)?,
            position,
            speed_kn: f.optional(7, non_negative)?,
            course_deg: f.optional(8, degrees)?,
        })
    }

    /// Write the body (`GPRMC,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}RMC,{},A,{},{},{},",
            talker_str(&self.talker),
            TimeField(self.time),
            PositionField(self.position),
            Opt(self.speed_kn, 2),
            Opt(self.course_deg, 2),
        )?;
        if let Some(d) = self.date {
            write!(out, "{:02}{:02}{:02}", d.day, d.month, d.year % 100)?;
        }
        out.write_str(",,,A")
    }
}

impl Gll {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        // Status (NMEA 2.0) and mode (2.3): V / N are no fix.
        match f.get(6) {
            "" | "A" => {}
            "V" => return Err(NmeaError::NoFix),
            _ => return Err(NmeaError::BadField(6)),
        }
        if f.get(7) == "N" {
            return Err(NmeaError::NoFix);
        }
        let position = position(f, 1)?;
        Ok(Self {
            talker,
            position,
            time: f.optional(5, time)?,
        })
    }

    /// Write the body (`GPGLL,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}GLL,{},",
            talker_str(&self.talker),
            PositionField(self.position)
        )?;
        if let Some(t) = self.time {
            write!(out, "{}", TimeField(t))?;
        }
        out.write_str(",A,A")
    }
}

impl Gns {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let mode = f.get(6).as_bytes();
        // One letter per constellation; the fix is valid when any has one.
        if !mode.iter().all(u8::is_ascii_uppercase) {
            return Err(NmeaError::BadField(6));
        }
        let Some(&first) = mode.iter().find(|&&m| m != b'N') else {
            return Err(NmeaError::NoFix);
        };
        let position = position(f, 2)?;
        Ok(Self {
            talker,
            time: f.required(1, time)?,
            position,
            mode: first,
            satellites: f.optional(7, small_uint)?,
            hdop: f.optional(8, non_negative)?.map(|v| v as f32),
            altitude_m: f.optional(9, number)?.map(|v| v as f32),
        })
    }

    /// Write the body (`GNGNS,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        let mode = if self.mode.is_ascii_uppercase() && self.mode != b'N' {
            self.mode as char
        } else {
            'A'
        };
        write!(
            out,
            "{}GNS,{},{},{mode},{},{},{},0.0,,",
            talker_str(&self.talker),
            TimeField(self.time),
            PositionField(self.position),
            Opt(self.satellites, 2),
            Opt(self.hdop, 1),
            Opt(self.altitude_m, 1),
        )
    }
}

impl Vtg {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let old_form = f.get(2) != "T";
        let (cog, cog_m, kn, kmh, mode) = if old_form {
            (1, 2, 3, 4, 5)
        } else {
            (1, 3, 5, 7, 9)
        };
        if f.get(mode) == "N" {
            return Err(NmeaError::NoFix);
        }
        Ok(Self {
            talker,
            course_deg: f.optional(cog, degrees)?,
            course_magnetic_deg: f.optional(cog_m, degrees)?,
            speed_kn: f.optional(kn, non_negative)?,
            speed_kmh: f.optional(kmh, non_negative)?,
            old_form,
        })
    }

    /// Write the body (`GPVTG,...`), in the form it was read in.
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        let t = talker_str(&self.talker);
        let (c, m) = (Opt(self.course_deg, 2), Opt(self.course_magnetic_deg, 2));
        let (k, h) = (Opt(self.speed_kn, 2), Opt(self.speed_kmh, 2));
        if self.old_form {
            write!(out, "{t}VTG,{c},{m},{k},{h}")
        } else {
            write!(out, "{t}VTG,{c},T,{m},M,{k},N,{h},K,A")
        }
    }
}

impl Hdt {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        if f.get(1).is_empty() {
            return Err(NmeaError::NoFix);
        }
        if !matches!(f.get(2), "T" | "") {
            return Err(NmeaError::BadField(2));
        }
        Ok(Self {
            talker,
            heading_deg: f.required(1, heading)?,
        })
    }

    /// Write the body (`HEHDT,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}HDT,{:.2},T",
            talker_str(&self.talker),
            self.heading_deg
        )
    }
}

impl Ths {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        let mode = match f.get(2).as_bytes() {
            [b'V'] => return Err(NmeaError::NoFix),
            [m @ (b'A' | b'E' | b'M' | b'S')] => *m,
            _ => return Err(NmeaError::BadField(2)),
        };
        if f.get(1).is_empty() {
            return Err(NmeaError::NoFix);
        }
        Ok(Self {
            talker,
            heading_deg: f.required(1, heading)?,
            mode,
        })
    }

    /// Write the body (`GNTHS,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}THS,{:.2},{}",
            talker_str(&self.talker),
            self.heading_deg,
            self.mode as char
        )
    }
}

impl Hdg {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        if f.get(1).is_empty() {
            return Err(NmeaError::NoFix);
        }
        Ok(Self {
            talker,
            sensor_deg: f.required(1, heading)?,
            deviation_deg: east_west(f, 2)?,
            variation_deg: east_west(f, 4)?,
        })
    }

    /// Write the body (`HCHDG,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}HDG,{:.1},{},{}",
            talker_str(&self.talker),
            self.sensor_deg,
            EastWest(self.deviation_deg),
            EastWest(self.variation_deg)
        )
    }
}

impl Hdm {
    fn from_fields(f: &Fields<'_>, talker: [u8; 2]) -> Result<Self, NmeaError> {
        if f.get(1).is_empty() {
            return Err(NmeaError::NoFix);
        }
        if !matches!(f.get(2), "M" | "") {
            return Err(NmeaError::BadField(2));
        }
        Ok(Self {
            talker,
            heading_deg: f.required(1, heading)?,
        })
    }

    /// Write the body (`HCHDM,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        write!(
            out,
            "{}HDM,{:.3},M",
            talker_str(&self.talker),
            self.heading_deg
        )
    }
}

impl Pfoxb {
    fn from_fields(f: &Fields<'_>) -> Result<Self, NmeaError> {
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
        Ok(Self {
            time: f.required(1, time)?,
            azimuth_deg: f.required(2, |s| number(s).filter(|v| (0.0..360.0).contains(v)))?,
            reference,
            quality: f.required(4, |s| number(s).filter(|v| (0.0..=100.0).contains(v)))? as f32,
            freq_mhz: f.required(5, |s| number(s).filter(|v| *v > 0.0))?,
            position,
        })
    }

    /// Write the body (`PFOXB,...`).
    pub fn emit(&self, out: &mut impl Write) -> fmt::Result {
        let r = match self.reference {
            Reference::True => 'T',
            Reference::Relative => 'R',
        };
        write!(
            out,
            "PFOXB,{},{:.2},{r},{:.0},{:.3}",
            TimeField(self.time),
            self.azimuth_deg,
            self.quality,
            self.freq_mhz
        )?;
        if let Some(p) = self.position {
            write!(out, ",{}", PositionField(p))?;
        }
        Ok(())
    }
}

/// XOR of the bytes of a sentence body: the one checksum of NMEA 0183 (the framing in
/// [`crate::stream`] checks it with this function too).
pub fn checksum(body: &str) -> u8 {
    xor(body.as_bytes())
}

/// XOR of some bytes: NMEA's checksum and the MT frame check sequence, the one place either
/// is computed.
pub fn xor(bytes: &[u8]) -> u8 {
    bytes.iter().fold(0, |x, b| x ^ b)
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
pub type Line = heapless::String<128>;

/// The body of a GGA sentence (talker GP) for a fix: [`Gga::emit`] with quality 1.
pub fn gga_body(
    out: &mut Line,
    time: UtcTime,
    p: LatLon,
    satellites: u8,
    hdop: f32,
) -> fmt::Result {
    Gga {
        talker: *b"GP",
        time,
        position: p,
        quality: Some(1),
        satellites: Some(satellites),
        hdop: Some(hdop),
        altitude_m: Some(0.0),
    }
    .emit(out)
}

/// The body of an RMC sentence (talker GP): [`Rmc::emit`].
pub fn rmc_body(
    out: &mut Line,
    time: UtcTime,
    date: Date,
    p: LatLon,
    speed_kn: f64,
    course_deg: f64,
) -> fmt::Result {
    Rmc {
        talker: *b"GP",
        time,
        date: Some(date),
        position: p,
        speed_kn: Some(speed_kn),
        course_deg: Some(course_deg),
    }
    .emit(out)
}

/// The body of a PFOXB sentence: [`Pfoxb::emit`].
pub fn pfoxb_body(out: &mut Line, b: &Pfoxb) -> fmt::Result {
    b.emit(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(s: &Sentence) -> Line {
        let mut line = Line::new();
        s.emit(&mut line).expect("fits");
        line
    }

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
    fn protocols_examples_of_the_gpsd_grade_sentences() {
        // PROTOCOLS.md section 4, each with the checksum the receiver sent.
        assert_eq!(checksum("GPVTG,330.63,T,345.26,M,0.00,N,0.00,K,A"), 0x20);
        let v = Vtg::parse("GPVTG,330.63,T,345.26,M,0.00,N,0.00,K,A").expect("VTG");
        assert_eq!(
            (v.course_deg, v.course_magnetic_deg, v.speed_kn, v.old_form),
            (Some(330.63), Some(345.26), Some(0.0), false)
        );
        let old = Vtg::parse("GPVTG,054.7,034.4,005.5,010.2").expect("old VTG");
        assert!(old.old_form && old.course_deg == Some(54.7) && old.speed_kn == Some(5.5));
        assert_eq!(checksum("GPHDT,274.07,T"), 0x03);
        assert_eq!(
            Hdt::parse("GPHDT,274.07,T").map(|h| h.heading_deg),
            Ok(274.07)
        );
        assert_eq!(checksum("GNTHS,244.28,A"), 0x11);
        let t = Ths::parse("GNTHS,244.28,A").expect("THS");
        assert_eq!((t.heading_deg, t.mode), (244.28, b'A'));
        assert_eq!(Ths::parse("GNTHS,,V"), Err(NmeaError::NoFix));
        assert_eq!(checksum("SDHDG,229.8,,,1.3,E"), 0x36);
        let h = Hdg::parse("SDHDG,229.8,,,1.3,E").expect("HDG");
        assert_eq!((h.deviation_deg, h.variation_deg), (None, Some(1.3)));
        assert!((h.true_deg().expect("variation") - 231.1).abs() < 1e-9);
        assert_eq!(checksum("APHDM,218.634,M"), 0x39);
        assert_eq!(
            Hdm::parse("APHDM,218.634,M").map(|h| h.heading_deg),
            Ok(218.634)
        );
        let long = "GPGGA,132820.60,4134.49821229,N,09345.03351845,W,2,09,1.0,278.020,M,-31.442,M,7.6,0133";
        assert_eq!(checksum(long), 0x7E);
        let g = Gga::parse(long).expect("RTK GGA");
        assert!((g.position.lat - (41.0 + 34.498_212_29 / 60.0)).abs() < 1e-12);
    }

    #[test]
    fn hdg_signs_deviation_west_variation_west() {
        // Sensor 100, deviation 2 W: magnetic 98; variation 5.5 W: true 92.5.
        let h = Hdg::parse("HCHDG,100.0,2.0,W,5.5,W").expect("HDG");
        assert_eq!(h.magnetic_deg(), 98.0);
        assert_eq!(h.true_deg(), Some(92.5));
        // Across north: 359 + 3 E = 2.
        let h = Hdg::parse("HCHDG,359.0,,,3.0,E").expect("HDG");
        assert!((h.true_deg().expect("var") - 2.0).abs() < 1e-9);
        assert_eq!(
            Hdg::parse("HCHDG,10.0,1.0,X,,"),
            Err(NmeaError::BadField(3))
        );
    }

    #[test]
    fn gll_gns_and_empty_quality_gga() {
        let l = Gll::parse("GPGLL,4916.45,N,12311.12,W,225444,A").expect("GLL");
        assert_eq!(
            l.time.map(|t| t.ms_of_day),
            Some((22 * 3600 + 54 * 60 + 44) * 1000)
        );
        assert!((l.position.lon + (123.0 + 11.12 / 60.0)).abs() < 1e-12);
        assert_eq!(
            Gll::parse("GPGLL,4916.45,N,12311.12,W,225444,V"),
            Err(NmeaError::NoFix)
        );
        assert!(
            Gll::parse("GPGLL,4916.45,N,12311.12,W").is_ok(),
            "NMEA 1.5 GLL"
        );
        let n = Gns::parse("GNGNS,122310.2,3722.425671,N,12258.856215,W,AAN,14,0.9,1005.543,6.5,,")
            .expect("GNS");
        assert_eq!((n.mode, n.satellites), (b'A', Some(14)));
        assert_eq!(
            Gns::parse("GNGNS,122310.2,,,,,NNN,0,,,,,"),
            Err(NmeaError::NoFix)
        );
        // myguide-3100 in GPSD's suite: empty quality, 3 satellites a fix, 2 none.
        let g = Gga::parse("GPGGA,105027.80,5612.9956,N,00306.6983,W,,3,2.506,160.002,M,,M,,")
            .expect("empty quality with three satellites");
        assert_eq!(g.quality, None);
        assert_eq!(
            Gga::parse("GPGGA,105025.80,5612.9999,N,00306.7096,W,,2,60.000,160.002,M,,M,,"),
            Err(NmeaError::NoFix)
        );
        // mtk-3301: quality 0 with 3 satellites is GPSD's 2D fix.
        assert!(
            Gga::parse("GPGGA,081434.590,5212.978993,N,00653.097906,E,0,3,,102.907,M,47.093,M,,")
                .is_ok()
        );
        assert_eq!(
            Sentence::parse("IIHDT,10.5,T").map(|_| ()),
            Ok(()),
            "any talker"
        );
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
        assert_eq!(Sentence::parse("xxGGA,1"), Err(NmeaError::Unsupported));
    }

    #[test]
    fn every_type_round_trips_through_emit_and_parse() {
        let p = LatLon {
            lat: -37.784_788_333,
            lon: 175.314_896_667,
        };
        let t = UtcTime {
            ms_of_day: 11_239_500,
        };
        let all = [
            Sentence::Gga(Gga {
                talker: *b"GN",
                time: t,
                position: p,
                quality: Some(4),
                satellites: Some(12),
                hdop: Some(0.5),
                altitude_m: Some(61.5),
            }),
            Sentence::Rmc(Rmc {
                talker: *b"GP",
                time: t,
                date: Some(Date {
                    year: 2026,
                    month: 6,
                    day: 1,
                }),
                position: p,
                speed_kn: Some(12.25),
                course_deg: Some(359.5),
            }),
            Sentence::Gll(Gll {
                talker: *b"GL",
                position: p,
                time: Some(t),
            }),
            Sentence::Gns(Gns {
                talker: *b"GN",
                time: t,
                position: p,
                mode: b'D',
                satellites: Some(9),
                hdop: Some(1.5),
                altitude_m: None,
            }),
            Sentence::Vtg(Vtg {
                talker: *b"GP",
                course_deg: Some(330.63),
                course_magnetic_deg: None,
                speed_kn: Some(1.5),
                speed_kmh: Some(2.78),
                old_form: false,
            }),
            Sentence::Vtg(Vtg {
                talker: *b"GP",
                course_deg: Some(54.7),
                course_magnetic_deg: Some(34.4),
                speed_kn: Some(5.5),
                speed_kmh: Some(10.19),
                old_form: true,
            }),
            Sentence::Hdt(Hdt {
                talker: *b"HE",
                heading_deg: 274.07,
            }),
            Sentence::Ths(Ths {
                talker: *b"GN",
                heading_deg: 244.28,
                mode: b'E',
            }),
            Sentence::Hdg(Hdg {
                talker: *b"HC",
                sensor_deg: 229.8,
                deviation_deg: Some(-2.5),
                variation_deg: Some(1.3),
            }),
            Sentence::Hdm(Hdm {
                talker: *b"AP",
                heading_deg: 218.634,
            }),
            Sentence::Pfoxb(Pfoxb {
                time: t,
                azimuth_deg: 359.99,
                reference: Reference::Relative,
                quality: 55.0,
                freq_mhz: 433.92,
                position: Some(p),
            }),
        ];
        for s in all {
            let line = body(&s);
            let back = Sentence::parse(&line).unwrap_or_else(|e| panic!("{line}: {e}"));
            // Six decimals of minutes: positions agree to 1e-6 / 60 degrees.
            let same = match (s, back) {
                (Sentence::Gga(a), Sentence::Gga(b)) => {
                    near(a.position, b.position)
                        && Gga {
                            position: a.position,
                            ..b
                        } == a
                }
                (Sentence::Rmc(a), Sentence::Rmc(b)) => {
                    near(a.position, b.position)
                        && Rmc {
                            position: a.position,
                            ..b
                        } == a
                }
                (Sentence::Gll(a), Sentence::Gll(b)) => {
                    near(a.position, b.position)
                        && Gll {
                            position: a.position,
                            ..b
                        } == a
                }
                (Sentence::Gns(a), Sentence::Gns(b)) => {
                    near(a.position, b.position)
                        && Gns {
                            position: a.position,
                            ..b
                        } == a
                }
                (Sentence::Pfoxb(a), Sentence::Pfoxb(b)) => {
                    a.position.zip(b.position).is_some_and(|(x, y)| near(x, y))
                        && Pfoxb {
                            position: a.position,
                            ..b
                        } == a
                }
                (a, b) => a == b,
            };
            assert!(same, "{line}: {s:?} came back as {back:?}");
        }
    }

    fn near(a: LatLon, b: LatLon) -> bool {
        (a.lat - b.lat).abs() < 1e-8 && (a.lon - b.lon).abs() < 1e-8
    }

    #[test]
    fn the_old_free_encoders_match_emit() {
        let p = LatLon {
            lat: 47.0,
            lon: 8.0,
        };
        let t = UtcTime { ms_of_day: 1000 };
        let mut line = Line::new();
        gga_body(&mut line, t, p, 8, 1.1).expect("fits");
        let g = Gga::parse(&line).expect("GGA");
        assert_eq!((g.satellites, g.quality), (Some(8), Some(1)));
    }
}
