//! `foxhunt perf --mqtt URL`: a network's load through a running MQTT broker (docs/src/speed.md,
//! "Through an MQTT broker"): S stations each sending a bearing on each of C channels R times a
//! second, a `foxhunt locate --mqtt` worker fusing them, and how long a bearing takes to be in
//! its channel's published fix.
//!
//! A bearing's latency: from its send to the arrival (at a subscriber beside the stations) of
//! the first fix of its channel whose bearings reach its time (the fix's `time_span_s`; the
//! synthetic bearings' times are their send schedule). The worker's peak resident memory is its
//! own `--stats` figure.

use crate::inputs::mqtt::{BearingMessage, MqttUrl, channel_name};
use crate::outputs::mqtt::{Backlog, Link, Message};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

/// The load.
#[derive(Debug, Clone)]
pub struct Load {
    /// The broker (its prefix gets a run's own level).
    pub url: MqttUrl,
    /// Stations.
    pub stations: usize,
    /// Channels (one emitter each).
    pub channels: usize,
    /// Bearings a second per station and channel.
    pub rate_hz: f64,
    /// Seconds of sending.
    pub seconds: f64,
}

/// What a load measured.
#[derive(Debug, Clone, Default)]
pub struct Figures {
    /// Bearings sent.
    pub sent: u64,
    /// Bearings the worker took.
    pub taken: u64,
    /// Fixes received.
    pub fixes: u64,
    /// Latency percentiles, ms: 50, 99, max.
    pub latency_ms: [f64; 3],
    /// Bearings whose time no fix reached.
    pub never: u64,
    /// The worker's peak resident memory, bytes.
    pub worker_peak_bytes: u64,
}

/// The synthetic network: stations on a 8 km ring round an emitter at 47 N, 8 E.
fn station(k: usize, n: usize) -> LatLon {
    let a = std::f64::consts::TAU * k as f64 / n as f64;
    LatLon {
        lat: 47.0 + 0.072 * a.cos(),
        lon: 8.0 + 0.105 * a.sin(),
    }
}

/// The true bearing from `at` to the emitter (47 N, 8 E).
fn bearing_to_emitter(at: LatLon) -> Result<f64, String> {
    let f = LocalFrame::new(at, 0.0).map_err(|_| "frame".to_string())?;
    let e = f
        .to_local(LatLon {
            lat: 47.0,
            lon: 8.0,
        })
        .map_err(|_| "emitter".to_string())?;
    Ok(e[0].atan2(e[1]).to_degrees().rem_euclid(360.0))
}

/// A normal draw (Box-Muller).
fn gauss(rng: &mut XorShiftRng) -> f64 {
    let u = (f64::from(rng.next_u32()) + 1.0) / (f64::from(u32::MAX) + 2.0);
    let v = f64::from(rng.next_u32()) / f64::from(u32::MAX);
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// The fixes as they arrive: (channel, end of the bearings' time span s, arrival).
fn watch_fixes(url: &MqttUrl) -> Result<mpsc::Receiver<(String, f64, Instant)>, String> {
    let (tx, rx) = mpsc::channel();
    let mut o = rumqttc::MqttOptions::new(
        format!("foxhunt-perf-watch-{}", std::process::id()),
        &url.host,
        url.port,
    );
    o.set_clean_session(true);
    let (client, mut conn) = rumqttc::Client::new(o, 16);
    crate::inputs::mqtt::first_connect(&mut conn, url)?;
    client
        .subscribe(url.fix_topic("+"), rumqttc::QoS::AtMostOnce)
        .map_err(|e| e.to_string())?;
    std::thread::spawn(move || {
        let _client = client;
        for e in conn.iter() {
            if let Ok(rumqttc::Event::Incoming(rumqttc::Packet::Publish(p))) = e {
                let Ok(v) = serde_json::from_slice::<serde_json::Value>(&p.payload) else {
                    continue;
                };
                let channel = p.topic.rsplit('/').next().unwrap_or("").to_string();
                let end = v["time_span_s"][1].as_f64().unwrap_or(-1.0);
                if tx.send((channel, end, Instant::now())).is_err() {
                    return;
                }
            }
        }
    });
    Ok(rx)
}

/// Run the load against the broker with `exe` (this program) as the worker.
pub fn run(load: &Load, exe: &Path) -> Result<Figures, String> {
    let mut url = load.url.clone();
    url.prefix = format!("{}/perf-{}", url.prefix, std::process::id());
    let worker_id = format!("foxhunt-perf-worker-{}", std::process::id());
    let mut worker = Command::new(exe)
        .args(["locate", "--stats", "--quiet-exit", "3", "--mqtt"])
        .arg(format!("mqtt://{}/{}", url.address(), url.prefix))
        .args(["--mqtt-client-id", &worker_id])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| format!("cannot start the worker: {e}"))?;
    let stderr = worker.stderr.take().ok_or("no stderr")?;
    let (etx, erx) = mpsc::channel::<String>();
    std::thread::spawn(move || {
        for l in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = etx.send(l);
        }
    });
    let first = erx
        .recv_timeout(Duration::from_secs(10))
        .map_err(|_| "the worker did not subscribe".to_string())?;
    if !first.contains("subscribed") {
        let _ = worker.kill();
        return Err(format!("worker: {first}"));
    }
    let fixes = watch_fixes(&url)?;
    let freqs: Vec<f64> = (0..load.channels).map(|c| 430.0 + 0.2 * c as f64).collect();
    let ticks = (load.rate_hz * load.seconds).round() as u64;
    let epoch0: i64 = 1_780_308_000_000;
    // Each tick's send time (the last station's), by tick.
    let (stx, srx) = mpsc::channel::<(u64, Instant)>();
    let start = Instant::now() + Duration::from_millis(200);
    let mut threads = Vec::new();
    for k in 0..load.stations {
        let (url, freqs, stx) = (url.clone(), freqs.clone(), stx.clone());
        let (rate, ring) = (load.rate_hz, load.stations);
        threads.push(std::thread::spawn(move || -> Result<u64, String> {
            let at = station(k, ring);
            let truth = bearing_to_emitter(at)?;
            let id = format!("s{k}");
            let link = Link::start(
                &url,
                &format!("foxhunt-perf-{}-{id}", std::process::id()),
                Backlog {
                    capacity: 1_000_000,
                    drop_oldest: false,
                    linger: Duration::from_secs(30),
                },
            )?;
            let mut rng = XorShiftRng::seed_from_u64(k as u64 + 1);
            for i in 0..ticks {
                let due = start + Duration::from_secs_f64(i as f64 / rate);
                if let Some(w) = due.checked_duration_since(Instant::now()) {
                    std::thread::sleep(w);
                }
                for &f in &freqs {
                    let m = BearingMessage {
                        station: id.clone(),
                        time_ms: epoch0 + (i as f64 * 1000.0 / rate).round() as i64,
                        lat: at.lat,
                        lon: at.lon,
                        bearing_deg: (truth + 2.0 * gauss(&mut rng)).rem_euclid(360.0),
                        sigma_deg: 2.0,
                        freq_mhz: Some(f),
                        quality: 90.0,
                        kind: "kraken-xml".into(),
                    };
                    link.send(Message {
                        topic: url.bearing_topic(&m.channel(), &m.station),
                        payload: serde_json::to_vec(&m).map_err(|e| e.to_string())?,
                    })?;
                }
                let _ = stx.send((i, Instant::now()));
            }
            Ok(link.finish().acked)
        }));
    }
    drop(stx);
    let mut acked = 0;
    for t in threads {
        acked += t.join().map_err(|_| "a station thread panicked")??;
    }
    let mut sent_at = vec![start; ticks as usize];
    for (i, t) in srx.iter() {
        let s = &mut sent_at[i as usize];
        if t > *s {
            *s = t;
        }
    }
    let status = worker.wait().map_err(|e| e.to_string())?;
    // The fixes still in flight to the watcher.
    std::thread::sleep(Duration::from_millis(300));
    let seen: Vec<(String, f64, Instant)> = fixes.try_iter().collect();
    let notes: Vec<String> = erx.try_iter().collect();
    if !status.success() {
        return Err(format!("the worker failed: {}", notes.join("; ")));
    }
    let number = |key: &str, tail: &str| {
        notes.iter().find_map(|l| {
            let rest = l.split(key).nth(1)?;
            rest.split(tail).next()?.trim().parse::<u64>().ok()
        })
    };
    let mut lat = Vec::new();
    let mut never = 0;
    for f in &freqs {
        let channel = channel_name(Some(*f));
        let mine: Vec<&(String, f64, Instant)> = seen.iter().filter(|s| s.0 == channel).collect();
        for (i, sent) in sent_at.iter().enumerate() {
            let t = i as f64 / load.rate_hz;
            match mine.iter().find(|s| s.1 + 1e-3 >= t && s.2 >= *sent) {
                Some(s) => lat.push(s.2.duration_since(*sent).as_secs_f64() * 1000.0),
                None => never += 1,
            }
        }
    }
    lat.sort_by(f64::total_cmp);
    let q = |p: f64| {
        lat.get(((lat.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    Ok(Figures {
        sent: acked,
        taken: number("mqtt: bearings ", ",").unwrap_or(0),
        fixes: seen.len() as u64,
        latency_ms: [q(0.5), q(0.99), q(1.0)],
        never,
        worker_peak_bytes: number("peak_bytes ", "\n").unwrap_or(0),
    })
}

/// The load and its figures as a markdown table.
pub fn table(l: &Load, f: &Figures) -> String {
    format!(
        "| stations | channels | rate Hz | bearings/s | sent | taken | fixes | p50 ms | p99 ms | \
         max ms | no fix | worker peak MB |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n\
         | {} | {} | {} | {:.0} | {} | {} | {} | {:.0} | {:.0} | {:.0} | {} | {:.1} |",
        l.stations,
        l.channels,
        l.rate_hz,
        l.stations as f64 * l.channels as f64 * l.rate_hz,
        f.sent,
        f.taken,
        f.fixes,
        f.latency_ms[0],
        f.latency_ms[1],
        f.latency_ms[2],
        f.never,
        f.worker_peak_bytes as f64 / 1e6
    )
}
