//! Positions and headings from a running gpsd (docs/src/formats/gpsd.md): how Linux programs share one
//! GPS receiver.
//!
//! The client connects to gpsd's TCP port (2947 unless told), reads its VERSION banner, sends
//! `?WATCH={"enable":true,"json":true}` and then reads one JSON object per line. A TPV report
//! with a 2D or 3D fix becomes an RMC sentence (time, date, position, speed, track) and an ATT
//! report's `heading` an HDT (`mheading`, when there is no true heading, an HDM), handed to the
//! bridge as if they had come on the serial line: the bridge's one heading rule, speed gate
//! and fix history then treat them like any receiver's. Unknown classes and attributes are
//! ignored; a line longer than gpsd's 10 240 bytes, or one that is not JSON, is skipped and
//! counted.

use foxhunt_bridge::nmea::{Date, Hdm, Hdt, LatLon, Line, Rmc, UtcTime};
use serde_json::Value;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpStream, ToSocketAddrs};
use std::time::Duration;

/// gpsd's port.
pub const DEFAULT_PORT: u16 = 2947;

/// The longest report line gpsd sends (its GPS_JSON_RESPONSE_MAX), bytes.
pub const MAX_LINE: usize = 10_240;

/// Where gpsd listens.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GpsdAddress {
    /// Host name or address.
    pub host: String,
    /// TCP port.
    pub port: u16,
}

impl Default for GpsdAddress {
    fn default() -> Self {
        Self {
            host: "localhost".into(),
            port: DEFAULT_PORT,
        }
    }
}

impl GpsdAddress {
    /// `HOST`, `HOST:PORT`, `[IPv6]:PORT` or empty (localhost:2947); nonsense refused on one
    /// line naming it.
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad = |why: &str| format!("--gpsd wants HOST[:PORT] ({why}), not `{text}`");
        let t = text.trim();
        if t.is_empty() {
            return Ok(Self::default());
        }
        let (host, port) = if let Some(rest) = t.strip_prefix('[') {
            let (h, after) = rest.split_once(']').ok_or_else(|| bad("an unclosed ["))?;
            match after.strip_prefix(':') {
                Some(p) => (h, Some(p)),
                None if after.is_empty() => (h, None),
                None => return Err(bad("text after the address")),
            }
        } else {
            match t.rsplit_once(':') {
                Some((h, _)) if h.contains(':') => (t, None),
                Some((h, p)) => (h, Some(p)),
                None => (t, None),
            }
        };
        if host.is_empty() || host.chars().any(|c| c.is_whitespace() || c == '/') {
            return Err(bad("a host name or address"));
        }
        let port = match port {
            None => DEFAULT_PORT,
            Some(p) => match p.parse::<u16>() {
                Ok(n) if n > 0 => n,
                _ => return Err(bad("a port from 1 to 65535")),
            },
        };
        Ok(Self {
            host: host.to_string(),
            port,
        })
    }
}

impl std::fmt::Display for GpsdAddress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.host.contains(':') {
            write!(f, "[{}]:{}", self.host, self.port)
        } else {
            write!(f, "{}:{}", self.host, self.port)
        }
    }
}

/// What one report line gave.
#[derive(Debug, Clone, PartialEq)]
pub enum Report {
    /// NMEA sentence bodies (without `$`, checksum and line end) for the bridge.
    Sentences(Vec<String>),
    /// A TPV without a fix (mode 0 or 1, or no position).
    NoFix,
    /// Not JSON, too long, or a TPV or ATT with a malformed attribute.
    Malformed,
    /// Another class (VERSION, DEVICES, WATCH, SKY, ...): nothing for the bridge.
    Other,
}

/// The date and time of day of an ISO 8601 UTC time (`2005-06-08T10:34:48.283Z`), or of
/// seconds since 1970 (older gpsd).
fn utc(v: &Value) -> Option<(Date, UtcTime)> {
    let t = match v {
        Value::String(s) => {
            time::OffsetDateTime::parse(s, &time::format_description::well_known::Rfc3339).ok()?
        }
        Value::Number(n) => {
            let s = n.as_f64().filter(|s| s.is_finite() && *s >= 0.0)?;
            time::OffsetDateTime::from_unix_timestamp_nanos((s * 1e9) as i128).ok()?
        }
        _ => return None,
    }
    .to_offset(time::UtcOffset::UTC);
    let year = u16::try_from(t.year()).ok()?;
    let ms = u32::from(t.hour()) * 3_600_000
        + u32::from(t.minute()) * 60_000
        + u32::from(t.second()) * 1000
        + t.millisecond() as u32;
    Some((
        Date {
            year,
            month: t.month() as u8,
            day: t.day(),
        },
        UtcTime { ms_of_day: ms },
    ))
}

/// A finite number attribute; `Err` when present but not one.
fn number(o: &serde_json::Map<String, Value>, key: &str) -> Result<Option<f64>, ()> {
    match o.get(key) {
        None => Ok(None),
        Some(v) => v.as_f64().filter(|x| x.is_finite()).map(Some).ok_or(()),
    }
}

fn body(emit: impl FnOnce(&mut Line) -> std::fmt::Result) -> Option<String> {
    let mut line = Line::new();
    emit(&mut line).ok()?;
    Some(line.as_str().to_string())
}

/// Decode one line from gpsd.
pub fn report(line: &str) -> Report {
    if line.len() > MAX_LINE {
        return Report::Malformed;
    }
    let Ok(Value::Object(o)) = serde_json::from_str::<Value>(line.trim()) else {
        return Report::Malformed;
    };
    match o.get("class").and_then(Value::as_str) {
        Some("TPV") => tpv(&o),
        Some("ATT") => att(&o),
        _ => Report::Other,
    }
}

fn tpv(o: &serde_json::Map<String, Value>) -> Report {
    let mode = o.get("mode").and_then(Value::as_u64).unwrap_or(0);
    let (Ok(lat), Ok(lon), Ok(track), Ok(speed)) = (
        number(o, "lat"),
        number(o, "lon"),
        number(o, "track"),
        number(o, "speed"),
    ) else {
        return Report::Malformed;
    };
    let (Some(lat), Some(lon)) = (lat, lon) else {
        return Report::NoFix;
    };
    if mode < 2 {
        return Report::NoFix;
    }
    if !(lat.abs() <= 90.0 && lon.abs() <= 180.0) {
        return Report::Malformed;
    }
    // A fix without a time cannot be placed among the bearings.
    let Some((date, time)) = o.get("time").and_then(utc) else {
        return Report::Malformed;
    };
    let rmc = Rmc {
        talker: *b"GP",
        time,
        date: Some(date),
        position: LatLon { lat, lon },
        speed_kn: speed.filter(|s| *s >= 0.0).map(|s| s * 3600.0 / 1852.0),
        course_deg: track.map(|t| t.rem_euclid(360.0)),
    };
    match body(|l| rmc.emit(l)) {
        Some(b) => Report::Sentences(vec![b]),
        None => Report::Malformed,
    }
}

fn att(o: &serde_json::Map<String, Value>) -> Report {
    let (Ok(heading), Ok(mheading)) = (number(o, "heading"), number(o, "mheading")) else {
        return Report::Malformed;
    };
    let sentence = match (heading, mheading) {
        (Some(h), _) => body(|l| {
            Hdt {
                talker: *b"GP",
                heading_deg: h.rem_euclid(360.0),
            }
            .emit(l)
        }),
        (None, Some(m)) => body(|l| {
            Hdm {
                talker: *b"GP",
                heading_deg: m.rem_euclid(360.0),
            }
            .emit(l)
        }),
        (None, None) => return Report::Other,
    };
    match sentence {
        Some(b) => Report::Sentences(vec![b]),
        None => Report::Malformed,
    }
}

/// A connection to gpsd that has asked for JSON reports.
pub struct Watch {
    reader: BufReader<TcpStream>,
    target: String,
}

impl Watch {
    /// Connect and send `?WATCH`; an error names the address.
    pub fn connect(addr: &GpsdAddress) -> Result<Self, String> {
        let target = addr.to_string();
        let sockets: Vec<_> = (addr.host.as_str(), addr.port)
            .to_socket_addrs()
            .map_err(|e| format!("gpsd at {target}: {e}"))?
            .collect();
        let mut last = format!("gpsd at {target}: no address");
        for s in sockets {
            match TcpStream::connect_timeout(&s, Duration::from_secs(5)) {
                Ok(mut stream) => {
                    stream
                        .write_all(b"?WATCH={\"enable\":true,\"json\":true}\n")
                        .map_err(|e| format!("gpsd at {target}: {e}"))?;
                    return Ok(Self {
                        reader: BufReader::new(stream),
                        target,
                    });
                }
                Err(e) => last = format!("cannot connect to gpsd at {target}: {e}"),
            }
        }
        Err(last)
    }

    /// Hand each line's outcome to `each` until gpsd closes the connection (`Ok`) or `each`
    /// returns false; a read error ends it.
    pub fn run(mut self, mut each: impl FnMut(Report) -> bool) -> Result<(), String> {
        let target = self.target;
        let failed = |e: std::io::Error| format!("reading gpsd at {target}: {e}");
        let mut buf = Vec::new();
        loop {
            buf.clear();
            // One more byte than a report may have: a longer line is cut there and skipped.
            let n = (&mut self.reader)
                .take(MAX_LINE as u64 + 1)
                .read_until(b'\n', &mut buf)
                .map_err(failed)?;
            if n == 0 {
                return Ok(());
            }
            let r = if buf.last() != Some(&b'\n') && n > MAX_LINE {
                let mut rest = Vec::new();
                self.reader.read_until(b'\n', &mut rest).map_err(failed)?;
                Report::Malformed
            } else {
                std::str::from_utf8(&buf).map_or(Report::Malformed, report)
            };
            if !each(r) {
                return Ok(());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses_and_their_refusals() {
        assert_eq!(
            GpsdAddress::parse("").expect("default"),
            GpsdAddress::default()
        );
        let a = GpsdAddress::parse("gps.local:3000").expect("host:port");
        assert_eq!((a.host.as_str(), a.port), ("gps.local", 3000));
        let a = GpsdAddress::parse("[::1]:2948").expect("v6");
        assert_eq!(
            (a.host.as_str(), a.port, a.to_string()),
            ("::1", 2948, "[::1]:2948".into())
        );
        assert_eq!(
            GpsdAddress::parse("::1").expect("bare v6").port,
            DEFAULT_PORT
        );
        for bad in [
            "host:0",
            "host:99999",
            "host:x",
            ":2947",
            "[::1",
            "a b",
            "/dev/ttyUSB0",
        ] {
            let e = GpsdAddress::parse(bad).expect_err(bad);
            assert!(e.contains(bad) && !e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn reports_as_gpsd_prints_them() {
        // From GPSD's own regression output (the .chk files): a 3D fix, a heading, no fix.
        let tpv = r#"{"class":"TPV","device":"/dev/pts/1","mode":3,"time":"2005-06-08T10:34:48.283Z","ept":0.005,"lat":46.498293369,"lon":7.567411672,"altHAE":1343.127,"track":10.3788,"speed":0.091,"climb":-0.085,"eps":23.25,"newfield":[1,2]}"#;
        let Report::Sentences(s) = report(tpv) else {
            panic!("{:?}", report(tpv))
        };
        assert_eq!(
            s,
            ["GPRMC,103448.283,A,4629.897602,N,00734.044700,E,0.18,10.38,080605,,,A"]
        );
        assert_eq!(
            report(r#"{"class":"ATT","heading":274.070}"#),
            Report::Sentences(vec!["GPHDT,274.07,T".into()])
        );
        assert_eq!(
            report(r#"{"class":"TPV","mode":1,"time":"2005-06-08T10:34:48.283Z"}"#),
            Report::NoFix
        );
        assert_eq!(
            report(r#"{"class":"VERSION","release":"3.25"}"#),
            Report::Other
        );
        for bad in [
            "not json",
            r#"{"class":"TPV","mode":3,"lat":"x","lon":1}"#,
            r#"{"class":"TPV","mode":3,"lat":95,"lon":1,"time":"2005-06-08T10:34:48Z"}"#,
            r#"{"class":"TPV","mode":3,"lat":1,"lon":1,"time":"yesterday"}"#,
        ] {
            assert_eq!(report(bad), Report::Malformed, "{bad}");
        }
        assert_eq!(report(&"x".repeat(MAX_LINE + 1)), Report::Malformed);
    }
}
