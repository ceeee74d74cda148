//! Fixes and lines of bearing to TAK (ATAK, WinTAK, iTAK, a TAK server) as Cursor-on-Target
//! events, over UDP (one event a datagram: a LAN's multicast 239.2.3.1:6969, or one device) or a
//! TCP stream (a TAK server's plain-XML input, events back to back).
//!
//! Every update sends the whole picture: each emitter as a point, its 95 % ellipse as a TAK
//! ellipse shape, each station as a point and its latest line of bearing as a line. Each thing
//! keeps its uid from update to update, so TAK moves it instead of adding another; a lost
//! datagram is superseded by the next update. Written by hand: a few fixed elements of numbers
//! (the station ids escaped), which no CoT crate makes shorter.

use super::maps::{latest_bearings, lonlat, ray_length, xml_text};
use crate::inputs::capture::Decoded;
use crate::locate::report::{EllipseReport, Located, geodetic};
use crate::track::moving::TrackPoint;
use foxhunt_bridge::geo::LocalFrame;
use std::fmt::Write as _;
use std::io::Write as _;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs, UdpSocket};
use std::time::{Duration, SystemTime};

/// How long TAK shows an event without a newer one: five minutes, long enough to outlive a
/// pause in the bearings, short enough that a stopped run's picture ages out.
pub const STALE: Duration = Duration::from_secs(300);

/// "Unknown" for CoT's height and errors (its schema's convention).
const UNKNOWN: f64 = 9_999_999.0;

/// Where the events go.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CotUrl {
    /// `udp://HOST:PORT`: one event a datagram (a multicast group works).
    Udp(String),
    /// `tcp://HOST:PORT`: one connection, events back to back.
    Tcp(String),
}

impl CotUrl {
    /// Parse `udp://HOST:PORT` or `tcp://HOST:PORT`.
    pub fn parse(text: &str) -> Result<Self, String> {
        let (scheme, rest) = text
            .split_once("://")
            .ok_or_else(|| format!("--cot {text}: give udp://HOST:PORT or tcp://HOST:PORT"))?;
        let port_ok = rest
            .rsplit_once(':')
            .is_some_and(|(h, p)| !h.is_empty() && p.parse::<u16>().is_ok_and(|p| p > 0));
        if !port_ok {
            return Err(format!("--cot {text}: give HOST:PORT after {scheme}://"));
        }
        match scheme {
            "udp" => Ok(CotUrl::Udp(rest.into())),
            "tcp" => Ok(CotUrl::Tcp(rest.into())),
            _ => Err(format!(
                "--cot {text}: the scheme is udp or tcp, not {scheme}"
            )),
        }
    }
}

impl std::fmt::Display for CotUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CotUrl::Udp(a) => write!(f, "udp://{a}"),
            CotUrl::Tcp(a) => write!(f, "tcp://{a}"),
        }
    }
}

/// A connection to TAK, opened when the first events are sent.
#[derive(Debug)]
pub struct CotSender {
    url: CotUrl,
    udp: Option<(UdpSocket, SocketAddr)>,
    tcp: Option<TcpStream>,
}

impl CotSender {
    /// A sender to `url` (nothing is opened yet).
    pub fn new(url: CotUrl) -> Self {
        Self {
            url,
            udp: None,
            tcp: None,
        }
    }

    /// Send `events`. A TCP connection that broke is opened again once; what still fails is
    /// this update's error (the next update sends the whole picture again).
    pub fn send(&mut self, events: &[String]) -> Result<(), String> {
        let url = self.url.clone();
        let fail = |e: std::io::Error| format!("TAK at {url}: {e}");
        match &url {
            CotUrl::Udp(addr) => {
                if self.udp.is_none() {
                    let to = resolve(addr).map_err(fail)?;
                    let bind = if to.is_ipv4() { "0.0.0.0:0" } else { "[::]:0" };
                    self.udp = Some((UdpSocket::bind(bind).map_err(fail)?, to));
                }
                if let Some((socket, to)) = &self.udp {
                    for e in events {
                        socket.send_to(e.as_bytes(), to).map_err(fail)?;
                    }
                }
                Ok(())
            }
            CotUrl::Tcp(addr) => {
                let bytes: Vec<u8> = events.iter().flat_map(|e| e.bytes()).collect();
                for attempt in 0..2 {
                    if self.tcp.is_none() {
                        let to = resolve(addr).map_err(fail)?;
                        let s = TcpStream::connect_timeout(&to, Duration::from_secs(3))
                            .map_err(fail)?;
                        s.set_write_timeout(Some(Duration::from_secs(3)))
                            .map_err(fail)?;
                        self.tcp = Some(s);
                    }
                    let wrote = self
                        .tcp
                        .as_mut()
                        .map_or(Ok(()), |s| s.write_all(&bytes).and_then(|()| s.flush()));
                    match wrote {
                        Ok(()) => return Ok(()),
                        Err(e) if attempt == 1 => return Err(fail(e)),
                        Err(_) => self.tcp = None,
                    }
                }
                Ok(())
            }
        }
    }
}

fn resolve(addr: &str) -> std::io::Result<SocketAddr> {
    addr.to_socket_addrs()?
        .next()
        .ok_or_else(|| std::io::Error::other("the host has no address"))
}

/// An event's time stamp: ISO 8601 UTC to the millisecond, as TAK writes them.
fn stamp(t: SystemTime) -> String {
    let t = time::OffsetDateTime::from(t);
    format!(
        "{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:03}Z",
        t.year(),
        u8::from(t.month()),
        t.day(),
        t.hour(),
        t.minute(),
        t.second(),
        t.millisecond()
    )
}

/// One event: its header, point and detail.
struct Event<'a> {
    uid: &'a str,
    kind: &'a str,
    how: &'a str,
    lat: f64,
    lon: f64,
    ce: f64,
    detail: &'a str,
}

impl Event<'_> {
    fn xml(&self, now: SystemTime) -> String {
        let (time, stale) = (stamp(now), stamp(now + STALE));
        format!(
            "<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"yes\"?>\
             <event version=\"2.0\" uid=\"{}\" type=\"{}\" how=\"{}\" time=\"{time}\" \
             start=\"{time}\" stale=\"{stale}\"><point lat=\"{:.7}\" lon=\"{:.7}\" \
             hae=\"{UNKNOWN:.1}\" ce=\"{:.1}\" le=\"{UNKNOWN:.1}\"/><detail>{}</detail></event>",
            xml_text(self.uid),
            self.kind,
            self.how,
            self.lat,
            self.lon,
            self.ce,
            self.detail
        )
    }
}

/// The true azimuth (degrees clockwise from north at `from`) of the frame direction `theta`
/// (radians counter-clockwise from the frame's east) taken at `from`: north at a station
/// kilometres from the frame's origin is not the frame's north (the meridians converge), so the
/// direction is followed 10 m out and measured there with the ellipsoid's radii of curvature.
fn true_azimuth(frame: &LocalFrame, from: [f32; 2], theta: f32) -> f64 {
    const A: f64 = 6_378_137.0;
    const E2: f64 = 6.694_379_990_14e-3;
    let step = [from[0] + 10.0 * theta.cos(), from[1] + 10.0 * theta.sin()];
    let (a, b) = (geodetic(frame, from), geodetic(frame, step));
    let lat = a.lat.to_radians();
    let w = 1.0 - E2 * lat.sin().powi(2);
    let (meridian, normal) = (A * (1.0 - E2) / w.powf(1.5), A / w.sqrt());
    let north = (b.lat - a.lat).to_radians() * meridian;
    let east = (b.lon - a.lon).to_radians() * normal * lat.cos();
    east.atan2(north).to_degrees().rem_euclid(360.0)
}

/// A located thing's two events: its point (type `a-u-G`, unknown ground; `ce` the ellipse's
/// semi-major axis, a circle that holds the ellipse; `extra`: more detail elements) and its
/// ellipse (`u-d-c-e`, semi-axes in metres, the major axis's angle clockwise from north),
/// linked to the point.
fn located(
    uid: &str,
    name: &str,
    [lat, lon]: [f64; 2],
    e: &EllipseReport,
    remarks: &str,
    extra: &str,
    now: SystemTime,
) -> [String; 2] {
    let point = Event {
        uid,
        kind: "a-u-G",
        how: "m-f",
        lat,
        lon,
        ce: f64::from(e.major_m),
        detail: &format!(
            "<contact callsign=\"{name}\"/>{extra}<remarks>{}</remarks>",
            xml_text(remarks)
        ),
    };
    let ellipse_uid = format!("{uid}-ellipse");
    let shape = format!(
        "<shape><ellipse major=\"{:.1}\" minor=\"{:.1}\" angle=\"{:.1}\"/>\
         <link uid=\"{ellipse_uid}-style\" type=\"b-x-KmlStyle\" relation=\"p-c\"><Style>\
         <LineStyle><color>ff0000ff</color><width>2</width></LineStyle>\
         <PolyStyle><color>400000ff</color></PolyStyle></Style></link></shape>\
         <link uid=\"{uid}\" type=\"a-u-G\" relation=\"p-p\"/>\
         <contact callsign=\"{name}: {:.0} % ellipse\"/>",
        e.major_m,
        e.minor_m,
        e.orientation_deg.rem_euclid(360.0),
        100.0 * e.confidence
    );
    let ellipse = Event {
        uid: &ellipse_uid,
        kind: "u-d-c-e",
        how: "m-f",
        lat,
        lon,
        ce: UNKNOWN,
        detail: &shape,
    };
    [point.xml(now), ellipse.xml(now)]
}

/// The events of a moving emitter's latest track point on channel `freq_mhz` (uid
/// `foxhunt-track-KHZ`): its point, with CoT's `<track>` (course, degrees true, and speed,
/// m/s) so TAK draws where it heads, and its 95 % ellipse. Empty when the point has no
/// ellipse.
pub fn track_events(
    freq_mhz: Option<f32>,
    p: &TrackPoint,
    frame: &LocalFrame,
    now: SystemTime,
) -> Vec<String> {
    let Some(e) = p.ellipse() else {
        return Vec::new();
    };
    let e = EllipseReport::from(&e);
    let uid = format!("foxhunt-track-{}", channel(freq_mhz));
    let name = match freq_mhz {
        Some(f) => format!("moving emitter {f:.3} MHz"),
        None => "moving emitter".into(),
    };
    let g = geodetic(frame, p.position);
    let speed = p.velocity[0].hypot(p.velocity[1]);
    let course = true_azimuth(frame, p.position, p.velocity[1].atan2(p.velocity[0]));
    let remarks = format!(
        "tracked; {:.0} % ellipse {:.0} m x {:.0} m; {speed:.1} m/s toward {course:.0} deg; \
         P(moving) {:.2}",
        100.0 * e.confidence,
        e.major_m,
        e.minor_m,
        p.p_moving
    );
    let track = format!("<track course=\"{course:.1}\" speed=\"{speed:.2}\"/>");
    located(&uid, &name, [g.lat, g.lon], &e, &remarks, &track, now).to_vec()
}

/// The channel's name in uids and callsigns: its frequency in kHz, or `all` for bearings
/// without one.
fn channel(freq_mhz: Option<f32>) -> String {
    freq_mhz.map_or_else(|| "all".into(), |f| format!("{:.0}", f64::from(f) * 1000.0))
}

/// The events of a fix: every emitter (type `a-u-G`, unknown ground; `ce` the 95 % ellipse's
/// semi-major axis, a circle that holds the ellipse) with its 95 % ellipse (`u-d-c-e`, semi-axes
/// in metres, the major axis's angle clockwise from north), and every station (`a-f-G-E-S`, a
/// friendly sensor; a vehicle where its latest bearing was taken) with its latest line of bearing
/// (`u-d-f`, from the station to the maps' ray
/// length, as measured: the station's estimated offset is in its remarks). Empty without a GPS
/// fix (nothing can be placed).
pub fn events(l: &Located, d: &Decoded, now: SystemTime) -> Vec<String> {
    let Some(frame) = d.frame else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let mut seen: Vec<String> = Vec::new();
    for r in &l.report.emitters {
        // Two emitters on one channel: the second is `...-2`.
        let base = format!("foxhunt-emitter-{}", channel(r.freq_mhz));
        let n = seen.iter().filter(|s| **s == base).count();
        seen.push(base.clone());
        let uid = if n == 0 {
            base
        } else {
            format!("{base}-{}", n + 1)
        };
        let name = match r.freq_mhz {
            Some(f) => format!("emitter {f:.3} MHz"),
            None => "emitter".into(),
        };
        let e = &r.ellipse;
        let mut remarks = String::new();
        let _ = write!(
            remarks,
            "method {}; {:.0} % ellipse {:.0} m x {:.0} m, CEP50 {:.0} m; {} bearings",
            l.report.method,
            100.0 * e.confidence,
            e.major_m,
            e.minor_m,
            r.cep50_m,
            r.used
        );
        out.extend(located(&uid, &name, [r.lat, r.lon], e, &remarks, "", now));
    }
    let reach = ray_length(l, d);
    let latest = latest_bearings(d);
    for s in &l.report.stations {
        let latest = d
            .stations
            .iter()
            .position(|i| i.id == s.id)
            .and_then(|i| latest.get(i).copied().flatten());
        // A vehicle is where its latest bearing was taken; a fixed station where it stands.
        let at = match (s.fixed, latest) {
            (false, Some(b)) => Some(lonlat(&frame, b.vehicle)),
            _ => s.lat.zip(s.lon).map(|(lat, lon)| [lon, lat]),
        };
        let Some([lon, lat]) = at else {
            continue;
        };
        let id = xml_text(&s.id);
        let uid = format!("foxhunt-station-{}", s.id);
        let remarks = format!(
            "{} station; offset {:.2} +- {:.2} deg ({}); {} bearings",
            if s.fixed { "fixed" } else { "mobile" },
            s.offset_deg,
            s.offset_sd_deg,
            s.offset_from,
            s.bearings
        );
        let station = Event {
            uid: &uid,
            kind: "a-f-G-E-S",
            how: "m-g",
            lat,
            lon,
            ce: UNKNOWN,
            detail: &format!("<contact callsign=\"{id}\"/><remarks>{remarks}</remarks>"),
        };
        out.push(station.xml(now));
        let Some(b) = latest else {
            continue;
        };
        let end = [
            b.vehicle[0] + reach * b.theta.cos(),
            b.vehicle[1] + reach * b.theta.sin(),
        ];
        let [a, z] = [lonlat(&frame, b.vehicle), lonlat(&frame, end)];
        let true_deg = true_azimuth(&frame, b.vehicle, b.theta);
        let line = Event {
            uid: &format!("foxhunt-lob-{}", s.id),
            kind: "u-d-f",
            how: "m-f",
            lat: a[1],
            lon: a[0],
            ce: UNKNOWN,
            detail: &format!(
                "<link point=\"{:.7},{:.7}\"/><link point=\"{:.7},{:.7}\"/>\
                 <strokeColor value=\"-65536\"/><strokeWeight value=\"2.0\"/>\
                 <contact callsign=\"{id} {true_deg:.1} deg\"/>\
                 <remarks>line of bearing {true_deg:.1} deg true as measured; {remarks}</remarks>",
                a[1], a[0], z[1], z[0]
            ),
        };
        out.push(line.xml(now));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_parse_or_say_why() {
        assert_eq!(
            CotUrl::parse("udp://239.2.3.1:6969"),
            Ok(CotUrl::Udp("239.2.3.1:6969".into()))
        );
        assert_eq!(
            CotUrl::parse("tcp://tak.local:8087"),
            Ok(CotUrl::Tcp("tak.local:8087".into()))
        );
        for bad in [
            "tak.local:8087",
            "http://a:1",
            "udp://a",
            "udp://:1",
            "tcp://a:0",
        ] {
            let e = CotUrl::parse(bad).expect_err(bad);
            assert!(e.starts_with("--cot ") && !e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn stamps_are_iso_utc_to_the_millisecond() {
        let t = SystemTime::UNIX_EPOCH + Duration::from_millis(1_780_000_000_123);
        assert_eq!(stamp(t), "2026-05-28T20:26:40.123Z");
    }
}
