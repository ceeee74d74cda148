//! `foxhunt frames`: every decoded frame of a capture as one JSON object per line, then the
//! counters, for debugging a serial link. Field names are stable: every object has `kind`;
//! positions are `lat`/`lon`, times `time` (`hh:mm:ss.sss` UTC); bearings have `bearing_deg`
//! as the unit reported it and `reference` (`true` or `relative`) after the format's own
//! convention, with `quality` and `freq_mhz` where the format has them.

use crate::outputs::json::Short;
use foxhunt_bridge::agrelo::Agrelo;
use foxhunt_bridge::mt::{AfIncomingMsg, LinkQualityMap};
use foxhunt_bridge::nmea::{LatLon, NmeaError, Reference, Sentence, UtcTime};
use foxhunt_bridge::record::{RecordClass, RecordKind};
use foxhunt_bridge::{Demux, Frame};
use serde_json::{Value, json};

fn time(t: UtcTime) -> String {
    let ms = t.ms_of_day;
    let s = ms / 1000;
    format!(
        "{:02}:{:02}:{:02}.{:03}",
        s / 3600,
        s / 60 % 60,
        s % 60,
        ms % 1000
    )
}

fn position(v: &mut Value, p: LatLon) {
    v["lat"] = json!(p.lat);
    v["lon"] = json!(p.lon);
}

fn talker(t: &[u8; 2]) -> String {
    String::from_utf8_lossy(t).into_owned()
}

fn reference(r: Reference) -> &'static str {
    match r {
        Reference::True => "true",
        Reference::Relative => "relative",
    }
}

/// The JSON object of one of the DF unit's own sentences (`$PFOXF` fix, `$PFOXS` status,
/// `$PFOXL` link, `$PFOXR` ready, `$PFOXA` acknowledgement), if `text` is one.
fn unit_json(text: &str) -> Option<Value> {
    use foxhunt_bridge::telemetry::{TelemetryError, UnitSentence};
    let kind = RecordKind::of_sentence(text);
    if kind.class() != RecordClass::Unit {
        return None;
    }
    let kind = kind.name();
    Some(match UnitSentence::parse(text) {
        Ok(UnitSentence::Fix(f)) => {
            let mut v = json!({"kind": "pfoxf", "time": time(f.time),
                "status": (f.status.letter() as char).to_string(), "used": f.used,
                "window": f.window, "sigma_deg": f.sigma_deg.short()});
            if let Some(p) = f.position {
                position(&mut v, p);
                v["major_m"] = json!(f.major_m.short());
                v["minor_m"] = json!(f.minor_m.short());
                v["orientation_deg"] = json!(f.orientation_deg.short());
                v["cep50_m"] = json!(f.cep50_m.short());
            }
            v
        }
        Ok(UnitSentence::Status(s)) => json!({"kind": "pfoxs", "uptime_s": s.uptime_s,
            "stack_bytes": s.stack_bytes, "queue_high": s.queue_high,
            "latency_ticks": s.latency_ticks, "fix_ticks": s.fix_ticks,
            "reset": s.reset.map(|r| (r.letter() as char).to_string())}),
        Ok(UnitSentence::Link(l)) => json!({"kind": "pfoxl", "bytes": l.bytes,
            "overruns": l.overruns, "full": l.full, "dropped": l.dropped,
            "rejected": l.rejected, "bearings": l.bearings, "fixes": l.fixes}),
        Ok(UnitSentence::Ready(r)) => json!({"kind": "pfoxr", "version": r.version,
            "reset": (r.reset.letter() as char).to_string()}),
        Ok(UnitSentence::Ack(a)) => json!({"kind": "pfoxa", "command": a.command,
            "ok": a.ok, "detail": a.detail}),
        Err(e) => {
            let error = match e {
                TelemetryError::Unsupported => None,
                TelemetryError::BadField(n) => Some(format!("bad_field_{n}")),
            };
            json!({"kind": kind, "sentence": text, "error": error})
        }
    })
}

/// The JSON object of one NMEA sentence.
fn sentence_json(text: &str) -> Value {
    if let Some(v) = unit_json(text) {
        return v;
    }
    match Sentence::parse(text) {
        Ok(Sentence::Gga(g)) => {
            let mut v = json!({"kind": "gga", "talker": talker(&g.talker),
                "time": time(g.time), "quality": g.quality, "satellites": g.satellites,
                "hdop": g.hdop.short(), "altitude_m": g.altitude_m.short()});
            position(&mut v, g.position);
            v
        }
        Ok(Sentence::Rmc(r)) => {
            let mut v = json!({"kind": "rmc", "talker": talker(&r.talker),
                "time": time(r.time), "speed_kn": r.speed_kn, "course_deg": r.course_deg,
                "date": r.date.map(|d| format!("{:04}-{:02}-{:02}", d.year, d.month, d.day))});
            position(&mut v, r.position);
            v
        }
        Ok(Sentence::Gll(g)) => {
            let mut v = json!({"kind": "gll", "talker": talker(&g.talker),
                "time": g.time.map(time)});
            position(&mut v, g.position);
            v
        }
        Ok(Sentence::Gns(g)) => {
            let mut v = json!({"kind": "gns", "talker": talker(&g.talker),
                "time": time(g.time), "mode": (g.mode as char).to_string(),
                "satellites": g.satellites, "hdop": g.hdop.short(), "altitude_m": g.altitude_m.short()});
            position(&mut v, g.position);
            v
        }
        Ok(Sentence::Vtg(t)) => json!({"kind": "vtg", "talker": talker(&t.talker),
            "course_deg": t.course_deg, "course_magnetic_deg": t.course_magnetic_deg,
            "speed_kn": t.speed_kn, "speed_kmh": t.speed_kmh, "old_form": t.old_form}),
        Ok(Sentence::Hdt(h)) => json!({"kind": "hdt", "talker": talker(&h.talker),
            "heading_deg": h.heading_deg, "reference": "true"}),
        Ok(Sentence::Ths(h)) => json!({"kind": "ths", "talker": talker(&h.talker),
            "heading_deg": h.heading_deg, "reference": "true",
            "mode": (h.mode as char).to_string()}),
        Ok(Sentence::Hdg(h)) => json!({"kind": "hdg", "talker": talker(&h.talker),
            "sensor_deg": h.sensor_deg, "deviation_deg": h.deviation_deg,
            "variation_deg": h.variation_deg, "heading_deg": h.magnetic_deg(),
            "reference": "magnetic", "true_heading_deg": h.true_deg()}),
        Ok(Sentence::Hdm(h)) => json!({"kind": "hdm", "talker": talker(&h.talker),
            "heading_deg": h.heading_deg, "reference": "magnetic"}),
        Ok(Sentence::Pfoxb(b)) => {
            let mut v = json!({"kind": "pfoxb", "time": time(b.time),
                "bearing_deg": b.azimuth_deg, "azimuth_deg": b.azimuth_deg,
                "reference": reference(b.reference),
                "quality": b.quality.short(), "freq_mhz": b.freq_mhz});
            if let Some(p) = b.position {
                position(&mut v, p);
            }
            v
        }
        Err(e) => {
            let kind = RecordKind::of_sentence(text).name();
            let error = match e {
                NmeaError::Unsupported => None,
                NmeaError::NoFix => Some("no_fix".to_string()),
                NmeaError::BadField(n) => Some(format!("bad_field_{n}")),
            };
            json!({"kind": kind, "sentence": text, "error": error})
        }
    }
}

/// The JSON object of one frame.
pub fn frame_json(f: &Frame<'_>, map: &LinkQualityMap) -> Value {
    match f {
        Frame::Nmea(text) => sentence_json(text),
        Frame::Mt(m) => match AfIncomingMsg::parse(m) {
            Ok(a) => json!({"kind": "af_incoming_msg", "src_addr": a.src_addr,
                "link_quality": a.link_quality, "rssi_dbm": map.rssi_dbm(a.link_quality),
                "timestamp": a.timestamp, "cluster_id": a.cluster_id,
                "src_endpoint": a.src_endpoint, "trans_seq": a.trans_seq, "len": a.data.len()}),
            Err(_) => json!({"kind": "mt", "cmd0": m.cmd0, "cmd1": m.cmd1, "len": m.data.len()}),
        },
        Frame::Agrelo(text) => match Agrelo::parse(text) {
            // Relative to the vehicle, clockwise; 0 means no bearing (`bearing_deg` null).
            Ok(a) => json!({"kind": "agrelo", "bearing_deg": a.bearing().short(),
                "reference": "relative", "quality": a.quality,
                "magnetic_deg": a.magnetic_deg.short(), "record": text}),
            Err(e) => json!({"kind": "agrelo", "record": text, "error": e.to_string()}),
        },
        Frame::KrakenCsv(k) => {
            let r = &k.record;
            let mut v = json!({"kind": "kraken_csv", "bearing_deg": r.bearing_deg.short(),
                "reference": "relative", "quality": r.confidence.short(),
                "power_db": r.power_db.short(),
                "freq_mhz": r.freq_hz as f64 / 1e6, "time": time(UtcTime {
                    ms_of_day: (r.epoch_ms % 86_400_000) as u32 }),
                "epoch_ms": r.epoch_ms, "heading_deg": r.heading_deg.short(),
                "station": r.station.as_str(), "latency_ms": r.latency_ms,
                "spectrum": k.spectrum.map(|s| s.to_vec())});
            if let Some(p) = r.position {
                position(&mut v, p);
            }
            v
        }
        Frame::KrakenXml(r) => {
            // DOA counts anticlockwise from the array's front; true = heading + 360 - DOA.
            let mut v = json!({"kind": "kraken_xml", "bearing_deg": r.doa_deg.short(),
                "reference": "relative", "anticlockwise": true, "quality": r.conf.short(),
                "pwr": r.pwr.short(), "freq_mhz": r.freq_mhz,
                "time": r.time_ms.map(|t| time(UtcTime { ms_of_day: (t % 86_400_000) as u32 })),
                "epoch_ms": r.time_ms, "heading_deg": r.heading_deg.short(),
                "true_bearing_deg": r.true_deg().short(), "station": r.station.as_str()});
            if let Some(p) = r.position {
                position(&mut v, p);
            }
            v
        }
    }
}

/// Frames of a capture as JSON lines, fed in chunks (memory stays bounded whatever the
/// capture's size), then the counters line.
pub struct FramesWriter {
    demux: Demux<600>,
    map: LinkQualityMap,
    /// Lines of each kind.
    kinds: std::collections::BTreeMap<&'static str, u64>,
    /// The first write error: nothing more is written after it.
    failed: Option<std::io::Error>,
}

impl Default for FramesWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl FramesWriter {
    /// A writer with nothing fed yet.
    pub fn new() -> Self {
        Self {
            demux: Demux::new(),
            map: LinkQualityMap::default(),
            kinds: Default::default(),
            failed: None,
        }
    }

    fn sink<'s>(
        map: &'s LinkQualityMap,
        kinds: &'s mut std::collections::BTreeMap<&'static str, u64>,
        failed: &'s mut Option<std::io::Error>,
        out: &'s mut impl std::io::Write,
    ) -> impl FnMut(Frame<'_>) + 's {
        move |f: Frame<'_>| {
            if failed.is_some() {
                return;
            }
            let v = frame_json(&f, map);
            *kinds.entry(frame_kind(&f, &v)).or_default() += 1;
            if let Err(e) = writeln!(out, "{v}") {
                *failed = Some(e);
            }
        }
    }

    /// The frames completed by `bytes`, written to `out`.
    pub fn feed(&mut self, bytes: &[u8], out: &mut impl std::io::Write) -> std::io::Result<()> {
        {
            let mut sink = Self::sink(&self.map, &mut self.kinds, &mut self.failed, &mut *out);
            self.demux.feed(bytes, &mut sink);
        }
        self.failed.take().map_or(Ok(()), Err)
    }

    /// The frames still buffered, then the counters line.
    pub fn finish(mut self, out: &mut impl std::io::Write) -> std::io::Result<()> {
        {
            let mut sink = Self::sink(&self.map, &mut self.kinds, &mut self.failed, &mut *out);
            self.demux.finish_into(&mut sink);
        }
        if let Some(e) = self.failed.take() {
            return Err(e);
        }
        let c = self.demux.counters();
        writeln!(
            out,
            "{}",
            json!({"kind": "counters", "bytes": c.bytes, "sentences": c.sentences,
                "mt_frames": c.mt_frames, "garbage_bytes": c.garbage_bytes,
                "bad_checksum": c.bad_checksum, "malformed": c.malformed, "too_long": c.too_long,
                "bad_fcs": c.bad_fcs, "overlapping": c.overlapping, "truncated": c.truncated,
                "agrelo": c.agrelo, "agrelo_malformed": c.agrelo_malformed,
                "kraken_csv": c.kraken_csv, "kraken_xml": c.kraken_xml,
                "kraken_bad_field": c.kraken_bad_field, "kraken_too_long": c.kraken_too_long,
                "kraken_structure": c.kraken_structure, "kinds": self.kinds})
        )
    }
}

/// The kind a frame's line names (its record kind's name, or the MT frame's).
fn frame_kind(f: &Frame<'_>, v: &Value) -> &'static str {
    match v["kind"].as_str() {
        Some("af_incoming_msg") => "af_incoming_msg",
        _ => f.kind().name(),
    }
}

/// Every frame of `bytes` as a JSON line, then the counters line, into `out`.
pub fn write_frames(bytes: &[u8], out: &mut impl std::io::Write) -> std::io::Result<()> {
    let mut w = FramesWriter::new();
    w.feed(bytes, out)?;
    w.finish(out)
}

#[cfg(test)]
mod unit_sentence_tests {
    use super::*;

    #[test]
    fn the_units_sentences_print_their_fields() {
        let v = sentence_json(
            "PFOXF,100101.25,4700.607404,N,00800.325926,W,123.5,6.0,180.0,40.0,117,120,1.23,A",
        );
        assert_eq!(v["kind"], "pfoxf");
        assert_eq!(v["status"], "A");
        assert_eq!(v["used"], 117);
        assert_eq!(v["major_m"], 123.5);
        assert!((v["lon"].as_f64().unwrap() + 8.005_432_1).abs() < 1e-7);
        let s = sentence_json("PFOXS,3,2816,76,41,0,86,43375,42859,N");
        assert_eq!(s["kind"], "pfoxs");
        assert_eq!(s["latency_ticks"], 43375);
        assert_eq!(sentence_json("PFOXA,GATE,ERR,ARGUMENT")["ok"], false);
        assert_eq!(sentence_json("PFOXF,garbage")["error"], "bad_field_13");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sentence(body: &str) -> String {
        let mut s = String::new();
        foxhunt_bridge::nmea::write_sentence(&mut s, body).expect("string");
        s
    }

    #[test]
    fn every_kind_with_its_stable_fields() {
        let mut bytes = String::new();
        for body in [
            "GPGGA,120000.000,4700.0000,N,00800.0000,E,1,08,1.0,0.0,M,0.0,M,,",
            "GPRMC,120000.000,A,4700.0000,N,00800.0000,E,0.0,,010626,,,A",
            "GPGLL,4700.0000,N,00800.0000,E,120000.000,A,A",
            "GNGNS,120000.000,4700.0000,N,00800.0000,E,AA,10,0.9,400.0,48.0,,",
            "GPVTG,330.63,T,345.26,M,0.00,N,0.00,K,A",
            "GPHDT,274.07,T",
            "GNTHS,244.28,A",
            "SDHDG,229.8,,,1.3,E",
            "APHDM,218.634,M",
            "PFOXB,120000.50,57.3,T,83,433.920",
        ] {
            bytes.push_str(&sentence(body));
        }
        bytes.push_str("%136.5/8/158\r\n");
        bytes.push_str("1679512414650, 134, 0.41, -48.5, 151880000, UCA, 100, dingus, 66.961348, -66.4438057, 0, 0, GPS, R, R, R, R");
        bytes.push_str(&", 0.07".repeat(360));
        bytes.push_str(" \n<DATA><STATION_ID>K3CPK-1</STATION_ID><TIME>1568052311</TIME><FREQUENCY>162.4</FREQUENCY><LOCATION><LATITUDE>39.124526</LATITUDE><LONGITUDE>-76.519717</LONGITUDE><HEADING>0</HEADING></LOCATION><DOA>120</DOA><PWR>19.3</PWR><CONF>15</CONF></DATA>");
        let mut out = Vec::new();
        write_frames(bytes.as_bytes(), &mut out).expect("write");
        let lines: Vec<Value> = String::from_utf8(out)
            .expect("utf-8")
            .lines()
            .map(|l| serde_json::from_str(l).expect("JSON"))
            .collect();
        let kinds: Vec<&str> = lines.iter().filter_map(|v| v["kind"].as_str()).collect();
        assert_eq!(
            kinds,
            [
                "gga",
                "rmc",
                "gll",
                "gns",
                "vtg",
                "hdt",
                "ths",
                "hdg",
                "hdm",
                "pfoxb",
                "agrelo",
                "kraken_csv",
                "kraken_xml",
                "counters"
            ]
        );
        for v in &lines[..4] {
            assert_eq!(
                (v["lat"].as_f64(), v["lon"].as_f64()),
                (Some(47.0), Some(8.0)),
                "{v}"
            );
            assert_eq!(v["time"], "12:00:00.000", "{v}");
        }
        let bearings = &lines[9..13];
        for v in bearings {
            for key in ["bearing_deg", "reference", "quality"] {
                assert!(v.get(key).is_some(), "{key} in {v}");
            }
        }
        assert_eq!(bearings[0]["reference"], "true");
        assert_eq!(bearings[1]["bearing_deg"], 136.5);
        assert_eq!(bearings[1]["reference"], "relative");
        assert_eq!(bearings[2]["bearing_deg"], 134.0);
        assert_eq!(bearings[2]["quality"], 0.41);
        assert_eq!(bearings[2]["freq_mhz"], 151.88);
        assert_eq!(bearings[2]["time"], "19:13:34.650");
        assert_eq!(bearings[3]["bearing_deg"], 120.0);
        assert_eq!(bearings[3]["true_bearing_deg"], 240.0);
        assert_eq!(bearings[3]["freq_mhz"], 162.4);
        assert_eq!(lines[13]["kraken_csv"], 1);
        assert_eq!(lines[13]["kinds"]["gga"], 1);
        assert_eq!(lines[13]["kinds"]["kraken_xml"], 1);
    }
}
