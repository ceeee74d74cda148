//! `foxhunt frames`: every decoded frame of a capture as one JSON object per line, then the
//! counters, for debugging a serial link. Field names are stable: every object has `kind`;
//! positions are `lat`/`lon`, times `time` (`hh:mm:ss.sss` UTC); bearings have `bearing_deg`
//! as the unit reported it and `reference` (`true` or `relative`) after the format's own
//! convention, with `quality` and `freq_mhz` where the format has them.

use foxhunt_bridge::agrelo::Agrelo;
use foxhunt_bridge::mt::{AfIncomingMsg, LinkQualityMap};
use foxhunt_bridge::nmea::{LatLon, NmeaError, Reference, Sentence, UtcTime};
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

/// The JSON object of one NMEA sentence.
fn sentence_json(text: &str) -> Value {
    match Sentence::parse(text) {
        Ok(Sentence::Gga(g)) => {
            let mut v = json!({"kind": "gga", "talker": talker(&g.talker),
                "time": time(g.time), "quality": g.quality, "satellites": g.satellites,
                "hdop": g.hdop, "altitude_m": g.altitude_m});
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
                "satellites": g.satellites, "hdop": g.hdop, "altitude_m": g.altitude_m});
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
                "quality": b.quality, "freq_mhz": b.freq_mhz});
            if let Some(p) = b.position {
                position(&mut v, p);
            }
            v
        }
        Err(e) => {
            let kind = match text.get(2..5) {
                _ if text.starts_with("PFOXB") => "pfoxb",
                Some("GGA") => "gga",
                Some("RMC") => "rmc",
                Some("GLL") => "gll",
                Some("GNS") => "gns",
                Some("VTG") => "vtg",
                Some("HDT") => "hdt",
                Some("THS") => "ths",
                Some("HDG") => "hdg",
                Some("HDM") => "hdm",
                _ => "nmea",
            };
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
            Ok(a) => json!({"kind": "agrelo", "bearing_deg": a.bearing(),
                "reference": "relative", "quality": a.quality,
                "magnetic_deg": a.magnetic_deg, "record": text}),
            Err(e) => json!({"kind": "agrelo", "record": text, "error": e.to_string()}),
        },
        Frame::KrakenCsv(k) => {
            let r = &k.record;
            let mut v = json!({"kind": "kraken_csv", "bearing_deg": r.bearing_deg,
                "reference": "relative", "quality": r.confidence, "power_db": r.power_db,
                "freq_mhz": r.freq_hz as f64 / 1e6, "time": time(UtcTime {
                    ms_of_day: (r.epoch_ms % 86_400_000) as u32 }),
                "epoch_ms": r.epoch_ms, "heading_deg": r.heading_deg,
                "station": r.station.as_str(), "latency_ms": r.latency_ms,
                "spectrum": k.spectrum.map(|s| s.to_vec())});
            if let Some(p) = r.position {
                position(&mut v, p);
            }
            v
        }
        Frame::KrakenXml(r) => {
            // DOA counts anticlockwise from the array's front; true = heading + 360 - DOA.
            let mut v = json!({"kind": "kraken_xml", "bearing_deg": r.doa_deg,
                "reference": "relative", "anticlockwise": true, "quality": r.conf,
                "pwr": r.pwr, "freq_mhz": r.freq_mhz,
                "time": r.time_ms.map(|t| time(UtcTime { ms_of_day: (t % 86_400_000) as u32 })),
                "epoch_ms": r.time_ms, "heading_deg": r.heading_deg,
                "true_bearing_deg": r.true_deg(), "station": r.station.as_str()});
            if let Some(p) = r.position {
                position(&mut v, p);
            }
            v
        }
    }
}

/// Every frame of `bytes` as a JSON line, then the counters line, into `out`.
pub fn write_frames(bytes: &[u8], out: &mut impl std::io::Write) -> std::io::Result<()> {
    let map = LinkQualityMap::default();
    let mut demux = Demux::<600>::new();
    let mut result = Ok(());
    let mut sink = |f: Frame<'_>| {
        if result.is_ok() {
            result = writeln!(out, "{}", frame_json(&f, &map));
        }
    };
    demux.feed(bytes, &mut sink);
    demux.finish_into(&mut sink);
    result?;
    let c = demux.counters();
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
            "kraken_structure": c.kraken_structure})
    )
}
