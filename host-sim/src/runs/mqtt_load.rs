//! `foxhunt perf --mqtt URL`: a network's load through a running MQTT broker (docs/src/speed.md,
//! "Through an MQTT broker"): S stations each sending a bearing on each of C channels R times a
//! second, `foxhunt locate --mqtt` workers fusing them (one, or several each owning a shard of
//! the channels), and how long a bearing takes to be in its channel's published fix.
//!
//! A bearing's latency: from its send to the arrival (at a subscriber beside the stations) of
//! the first fix of its channel whose bearings reach its time (the fix's `time_span_s`; the
//! synthetic bearings' times are their send schedule), published after it was sent; counted
//! for each bearing time on each channel once, from the latest send of that time (stations
//! sending at once share a tick's time: a fix that came before the tick's last station had
//! sent its other channels' bearings is on time), from the channel's first fix on; the
//! start-up, to the last channel's first fix, is its own figure.
//! The workers' peak resident memory is their own `--stats` figure; their resident memory is
//! also sampled every few seconds, to show whether it stays flat over a long run.

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
    /// Workers, each owning a shard of the channels (1: one worker, unsharded topics).
    pub workers: u32,
    /// Each worker's bearings kept per channel (`locate --mqtt-keep`; `None`: its default).
    pub keep: Option<usize>,
    /// Pin worker k to the k-th processor this process may use (`taskset`): one core each,
    /// its solves on one thread.
    pub pin: bool,
    /// Station k sends k/S of a period after station 0 (from the second tick on), as
    /// unsynchronised stations do (each polls its receiver on its own clock); otherwise every
    /// station sends at once, each tick a burst (the worst case).
    pub stagger: bool,
}

/// Seconds between samples of the timeline.
const SAMPLE_S: f64 = 10.0;

/// One sample of a run: latencies of the bearings sent in it, and the workers' memory.
#[derive(Debug, Clone, Copy, Default)]
pub struct Sample {
    /// Its end, seconds from the start of sending.
    pub t_s: f64,
    /// Latency of its bearings, ms: 50th and 99th percentile.
    pub latency_ms: [f64; 2],
    /// The workers' resident memory then, MB (summed).
    pub rss_mb: f64,
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
    /// Bearings whose time no fix reached (of those sent after their channel's first fix).
    pub never: u64,
    /// From the start of sending to the last channel's first fix, ms.
    pub first_fix_ms: f64,
    /// The largest worker's peak resident memory, bytes.
    pub worker_peak_bytes: u64,
    /// Each worker's bearings taken and updates (solves) made.
    pub per_worker: Vec<(u64, u64)>,
    /// Processor seconds each worker used (user and system), as last sampled.
    pub worker_cpu_s: Vec<f64>,
    /// The run sample by sample.
    pub timeline: Vec<Sample>,
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

/// A worker started, its notes as they come.
struct Worker {
    child: std::process::Child,
    notes: mpsc::Receiver<String>,
}

/// Start worker `k` of `load.workers` and wait for its subscription.
fn start_worker(load: &Load, url: &MqttUrl, exe: &Path, k: u32) -> Result<Worker, String> {
    let mut c = if load.pin {
        let cpus = allowed_processors();
        let cpu = cpus
            .get(k as usize % cpus.len().max(1))
            .copied()
            .unwrap_or(0);
        let mut t = Command::new("taskset");
        t.args(["-c", &cpu.to_string()]).arg(exe);
        t
    } else {
        Command::new(exe)
    };
    c.args(["locate", "--stats", "--quiet-exit", "3", "--mqtt"])
        .arg(format!("mqtt://{}/{}", url.address(), url.prefix))
        .args([
            "--mqtt-client-id",
            &format!("foxhunt-perf-worker-{}-{k}", std::process::id()),
        ]);
    if load.workers > 1 {
        c.args(["--mqtt-shard", &format!("{k}/{}", load.workers)]);
    }
    if let Some(n) = load.keep {
        c.args(["--mqtt-keep", &n.to_string()]);
    }
    let mut child = c
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|e| match load.pin {
            true => format!("cannot start the worker under taskset (util-linux): {e}"),
            false => format!("cannot start the worker: {e}"),
        })?;
    let stderr = child.stderr.take().ok_or("no stderr")?;
    let (etx, notes) = mpsc::channel::<String>();
    std::thread::spawn(move || {
        for l in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = etx.send(l);
        }
    });
    let first = notes
        .recv_timeout(Duration::from_secs(10))
        .map_err(|_| "the worker did not subscribe".to_string())?;
    if !first.contains("subscribed") {
        let _ = child.kill();
        return Err(format!("worker: {first}"));
    }
    Ok(Worker { child, notes })
}

/// The processors this process may run on (`Cpus_allowed_list` of /proc/self/status, as
/// `0-3,8`; empty where unknown).
fn allowed_processors() -> Vec<usize> {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("Cpus_allowed_list:"))
                .map(processor_list)
        })
        .unwrap_or_default()
}

/// A processor list as Linux writes it (`0-3,8,10-11`); what does not parse is skipped.
fn processor_list(text: &str) -> Vec<usize> {
    let mut out = Vec::new();
    for part in text.trim().split(',') {
        let mut ends = part
            .trim()
            .splitn(2, '-')
            .map(|n| n.trim().parse::<usize>());
        match (ends.next(), ends.next()) {
            (Some(Ok(a)), None) => out.push(a),
            (Some(Ok(a)), Some(Ok(b))) if a <= b && b - a < 4096 => out.extend(a..=b),
            _ => {}
        }
    }
    out
}

/// Resident memory of process `pid`, MB (0 where unknown).
fn rss_mb(pid: u32) -> f64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmRSS:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}

/// Processor seconds process `pid` has used, user and system (0 where unknown): fields 14
/// and 15 of /proc/PID/stat, in Linux's fixed 100 ticks a second.
fn cpu_s(pid: u32) -> f64 {
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .ok()
        .and_then(|s| {
            // The command name may hold spaces: the fields count from its closing bracket.
            let rest = s.rsplit_once(')')?.1;
            let f: Vec<&str> = rest.split_whitespace().collect();
            let ticks = |i: usize| f.get(i)?.parse::<f64>().ok();
            Some((ticks(11)? + ticks(12)?) / 100.0)
        })
        .unwrap_or(0.0)
}

/// Run the load against the broker with `exe` (this program) as the workers.
pub fn run(load: &Load, exe: &Path) -> Result<Figures, String> {
    let mut url = load.url.clone();
    url.prefix = format!("{}/perf-{}", url.prefix, std::process::id());
    let mut workers = Vec::new();
    for k in 0..load.workers.max(1) {
        workers.push(start_worker(load, &url, exe, k)?);
    }
    // The workers' memory, sampled while the load runs.
    let pids: Vec<u32> = workers.iter().map(|w| w.child.id()).collect();
    let (mtx, mrx) = mpsc::channel::<(Instant, f64, Vec<f64>)>();
    let sampling = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(true));
    let on = sampling.clone();
    std::thread::spawn(move || {
        while on.load(std::sync::atomic::Ordering::Relaxed) {
            let mb = pids.iter().map(|&p| rss_mb(p)).sum();
            let cpu = pids.iter().map(|&p| cpu_s(p)).collect();
            if mtx.send((Instant::now(), mb, cpu)).is_err() {
                return;
            }
            std::thread::sleep(Duration::from_millis(250));
        }
    });
    let fixes = watch_fixes(&url)?;
    let freqs: Vec<f64> = (0..load.channels).map(|c| 430.0 + 0.2 * c as f64).collect();
    let ticks = (load.rate_hz * load.seconds).round() as u64;
    let epoch0: i64 = 1_780_308_000_000;
    // Each bearing's tick, time (ms from the first tick), channel and send.
    let (stx, srx) = mpsc::channel::<(u64, i64, usize, Instant)>();
    let start = Instant::now() + Duration::from_millis(200);
    let mut threads = Vec::new();
    for k in 0..load.stations {
        let (url, freqs, stx) = (url.clone(), freqs.clone(), stx.clone());
        let (rate, ring, shards) = (load.rate_hz, load.stations, load.workers);
        let phase = match load.stagger {
            true => k as f64 / ring as f64,
            false => 0.0,
        };
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
                // The first tick at once: a worker's clock starts at its first bearing, which
                // is then at the first tick's time whichever station's came first.
                let at_tick = i as f64 + if i == 0 { 0.0 } else { phase };
                let due = start + Duration::from_secs_f64(at_tick / rate);
                let ms = (at_tick * 1000.0 / rate).round() as i64;
                if let Some(w) = due.checked_duration_since(Instant::now()) {
                    std::thread::sleep(w);
                }
                for (c, &f) in freqs.iter().enumerate() {
                    let m = BearingMessage {
                        station: id.clone(),
                        time_ms: epoch0 + ms,
                        lat: at.lat,
                        lon: at.lon,
                        bearing_deg: (truth + 2.0 * gauss(&mut rng)).rem_euclid(360.0),
                        sigma_deg: 2.0,
                        freq_mhz: Some(f),
                        quality: 90.0,
                        kind: "kraken-xml".into(),
                    };
                    link.send(Message {
                        topic: url.sharded_topic(shards, &m.channel(), &m.station),
                        payload: serde_json::to_vec(&m).map_err(|e| e.to_string())?,
                    })?;
                    let _ = stx.send((i, ms, c, Instant::now()));
                }
            }
            Ok(link.finish().acked)
        }));
    }
    drop(stx);
    let mut acked = 0;
    for t in threads {
        acked += t.join().map_err(|_| "a station thread panicked")??;
    }
    // Each channel's bearing times in order, each with its tick and its latest send.
    let mut sent_at: Vec<Vec<(i64, u64, Instant)>> = vec![Vec::new(); freqs.len()];
    for (i, ms, c, t) in srx.iter() {
        if let Some(s) = sent_at.get_mut(c) {
            s.push((ms, i, t));
        }
    }
    for s in &mut sent_at {
        s.sort_by_key(|m| (m.0, std::cmp::Reverse(m.2)));
        s.dedup_by_key(|m| m.0);
    }
    let number = |notes: &[String], key: &str, tail: &str| {
        notes.iter().find_map(|l| {
            let rest = l.split(key).nth(1)?;
            rest.split(tail).next()?.trim().parse::<u64>().ok()
        })
    };
    let mut notes: Vec<Vec<String>> = Vec::new();
    let mut failed = Vec::new();
    for w in &mut workers {
        let status = w.child.wait().map_err(|e| e.to_string())?;
        let n: Vec<String> = w.notes.iter().collect();
        // A worker whose shard holds none of the load's channels (more workers than the
        // hash fills) is told nothing and ends without a fix, saying so: idle, not failed.
        let idle = number(&n, "mqtt: bearings ", ",") == Some(0)
            && n.iter()
                .any(|l| l.contains("no bearing came through the broker"));
        if !status.success() && !idle {
            failed.push(n.join("; "));
        }
        notes.push(n);
    }
    sampling.store(false, std::sync::atomic::Ordering::Relaxed);
    // The fixes still in flight to the watcher.
    std::thread::sleep(Duration::from_millis(300));
    let seen: Vec<(String, f64, Instant)> = fixes.try_iter().collect();
    let memory: Vec<(Instant, f64, Vec<f64>)> = mrx.try_iter().collect();
    // A worker's last sample with a figure (an exited worker reads 0).
    let worker_cpu_s = (0..workers.len())
        .map(|k| {
            memory
                .iter()
                .filter_map(|m| m.2.get(k).copied())
                .fold(0.0, f64::max)
        })
        .collect();
    if !failed.is_empty() {
        return Err(format!("a worker failed: {}", failed.join(" | ")));
    }
    // Each bearing's latency, by the tick it was sent in, from each channel's first fix on:
    // before it the channel has none to update (start-up: its first solve needs every
    // station's first bearings), timed apart.
    let mut lat = Vec::new();
    let mut by_tick: Vec<Vec<f64>> = vec![Vec::new(); ticks as usize];
    let mut never = 0;
    let mut first_fix_ms = 0.0f64;
    for (c, f) in freqs.iter().enumerate() {
        let channel = channel_name(Some(*f));
        let mine: Vec<&(String, f64, Instant)> = seen.iter().filter(|s| s.0 == channel).collect();
        let Some(first) = mine.first().map(|s| s.2) else {
            never += sent_at[c].len() as u64;
            continue;
        };
        first_fix_ms = first_fix_ms.max(first.duration_since(start).as_secs_f64() * 1000.0);
        // The fixes arrive in order: the first that reaches a tick is found from the last
        // tick's.
        let mut from = 0;
        for &(ms, i, sent) in &sent_at[c] {
            if sent < first {
                continue;
            }
            let t = ms as f64 / 1000.0;
            match mine[from..]
                .iter()
                .position(|s| s.1 + 1e-3 >= t && s.2 >= sent)
            {
                Some(j) => {
                    from += j;
                    let latency = mine[from].2.duration_since(sent).as_secs_f64() * 1000.0;
                    lat.push(latency);
                    if let Some(b) = by_tick.get_mut(i as usize) {
                        b.push(latency);
                    }
                }
                None => never += 1,
            }
        }
    }
    let q = |v: &mut Vec<f64>, p: f64| {
        v.sort_by(f64::total_cmp);
        v.get(((v.len() as f64 - 1.0) * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    let per_sample = ((SAMPLE_S * load.rate_hz).round() as usize).max(1);
    let mut timeline = Vec::new();
    for (k, ticks) in by_tick.chunks(per_sample).enumerate() {
        let mut v: Vec<f64> = ticks.iter().flatten().copied().collect();
        let end = start + Duration::from_secs_f64((k + 1) as f64 * SAMPLE_S);
        let rss = memory.iter().rfind(|m| m.0 <= end).map_or(0.0, |m| m.1);
        timeline.push(Sample {
            t_s: ((k * per_sample + ticks.len()) as f64 / load.rate_hz),
            latency_ms: [q(&mut v, 0.5), q(&mut v, 0.99)],
            rss_mb: rss,
        });
    }
    let per_worker: Vec<(u64, u64)> = notes
        .iter()
        .map(|n| {
            (
                number(n, "mqtt: bearings ", ",").unwrap_or(0),
                number(n, "updates ", ",").unwrap_or(0),
            )
        })
        .collect();
    Ok(Figures {
        sent: acked,
        taken: per_worker.iter().map(|w| w.0).sum(),
        fixes: seen.len() as u64,
        latency_ms: [q(&mut lat, 0.5), q(&mut lat, 0.99), q(&mut lat, 1.0)],
        never,
        first_fix_ms,
        worker_peak_bytes: notes
            .iter()
            .filter_map(|n| number(n, "peak_bytes ", "\n"))
            .max()
            .unwrap_or(0),
        per_worker,
        worker_cpu_s,
        timeline,
    })
}

/// Resident memory at the end of the first minute (or the first sample) and at the end, MB.
fn memory_ends(f: &Figures) -> (f64, f64) {
    let first = f
        .timeline
        .iter()
        .find(|s| s.t_s >= 60.0)
        .or(f.timeline.first())
        .map_or(0.0, |s| s.rss_mb);
    (first, f.timeline.last().map_or(0.0, |s| s.rss_mb))
}

/// The load and its figures as a markdown table.
pub fn table(l: &Load, f: &Figures) -> String {
    let (rss_1, rss_end) = memory_ends(f);
    let updates: Vec<String> = f.per_worker.iter().map(|w| w.1.to_string()).collect();
    let cpu: Vec<String> = f.worker_cpu_s.iter().map(|c| format!("{c:.1}")).collect();
    format!(
        "| stations | channels | rate Hz | bearings/s | workers | sent | taken | fixes | updates | \
         worker CPU s | first fix ms | p50 ms | p99 ms | max ms | no fix | RSS MB at 1 min | at \
         end | worker peak MB |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n\
         | {} | {} | {}{} | {:.0} | {}{} | {} | {} | {} | {} | {} | {:.0} | {:.0} | {:.0} | {:.0} | \
         {} | {:.1} | {:.1} | {:.1} |",
        l.stations,
        l.channels,
        l.rate_hz,
        if l.stagger { " (staggered)" } else { "" },
        l.stations as f64 * l.channels as f64 * l.rate_hz,
        l.workers,
        if l.pin { " (pinned)" } else { "" },
        f.sent,
        f.taken,
        f.fixes,
        updates.join(" + "),
        cpu.join(" + "),
        f.first_fix_ms,
        f.latency_ms[0],
        f.latency_ms[1],
        f.latency_ms[2],
        f.never,
        rss_1,
        rss_end,
        f.worker_peak_bytes as f64 / 1e6
    )
}

/// The run's timeline as an SVG plot: each sample's p50 and p99 latency (left scale, ms) and
/// the workers' resident memory (right scale, MB), against the time of sending.
pub fn svg(l: &Load, f: &Figures) -> String {
    let (w, h, left, right, top, bottom) = (640.0, 300.0, 56.0, 56.0, 28.0, 36.0);
    let (pw, ph) = (w - left - right, h - top - bottom);
    let t_max = f.timeline.last().map_or(1.0, |s| s.t_s).max(1.0);
    let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
    let lat_max = f
        .timeline
        .iter()
        .map(|s| finite(s.latency_ms[1]))
        .fold(1.0f64, f64::max)
        * 1.1;
    let mem_max = f.timeline.iter().map(|s| s.rss_mb).fold(1.0f64, f64::max) * 1.1;
    let x = |t: f64| left + pw * t / t_max;
    let line = |pick: &dyn Fn(&Sample) -> f64, max: f64, colour: &str| {
        let pts: Vec<String> = f
            .timeline
            .iter()
            .map(|s| {
                format!(
                    "{:.1},{:.1}",
                    x(s.t_s),
                    top + ph * (1.0 - finite(pick(s)) / max)
                )
            })
            .collect();
        format!(
            "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"1.5\" points=\"{}\"/>\n",
            pts.join(" ")
        )
    };
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
         font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%\" height=\"100%\" \
         fill=\"white\"/>\n<text x=\"{left}\" y=\"16\">{} stations x {} channels x {} Hz = \
         {:.0} bearings/s, {} worker(s): latency p50 (blue), p99 (red), RSS (grey)</text>\n\
         <rect x=\"{left}\" y=\"{top}\" width=\"{pw}\" height=\"{ph}\" fill=\"none\" \
         stroke=\"black\"/>\n",
        l.stations,
        l.channels,
        l.rate_hz,
        l.stations as f64 * l.channels as f64 * l.rate_hz,
        l.workers
    );
    for k in 0..=4 {
        let fr = f64::from(k) / 4.0;
        let y = top + ph * (1.0 - fr);
        out += &format!(
            "<text x=\"{:.0}\" y=\"{:.0}\" text-anchor=\"end\">{:.0} ms</text>\n\
             <text x=\"{:.0}\" y=\"{:.0}\">{:.0} MB</text>\n\
             <text x=\"{:.0}\" y=\"{:.0}\" text-anchor=\"middle\">{:.0} s</text>\n",
            left - 4.0,
            y + 4.0,
            lat_max * fr,
            w - right + 4.0,
            y + 4.0,
            mem_max * fr,
            x(t_max * fr),
            h - bottom + 14.0,
            t_max * fr
        );
    }
    out += &line(&|s| s.latency_ms[0], lat_max, "#1f5fbf");
    out += &line(&|s| s.latency_ms[1], lat_max, "#c0392b");
    out += &line(&|s| s.rss_mb, mem_max, "#888888");
    out += "</svg>\n";
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn processor_lists_read_as_linux_writes_them() {
        assert_eq!(processor_list("0-1\n"), [0, 1]);
        assert_eq!(processor_list("2-3,8,10-11"), [2, 3, 8, 10, 11]);
        assert_eq!(processor_list("5"), [5]);
        assert_eq!(
            processor_list("x,3-1,4"),
            [4],
            "what does not parse is skipped"
        );
        assert!(processor_list("").is_empty());
    }
}
