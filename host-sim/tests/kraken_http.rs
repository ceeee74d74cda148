//! `foxhunt locate --kraken URL` against a local web server standing in for a KrakenSDR:
//! it serves a drive's records as pages that change under the poller, with empty replies,
//! half-written ones and records repeated from the page before. Every record must count
//! once: the live fix equals the fix of the same records read from a file.

use foxhunt_sim::inputs::capture::decode;
use foxhunt_sim::locate::{LocateOptions, locate};
use foxhunt_sim::runs::scenario::Scenario;
use foxhunt_sim::runs::simulate::{CaptureFormat, CaptureOptions, drive_capture};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Duration;

mod common;

/// The drive's records (one per bearing) in `format`.
fn records(format: CaptureFormat) -> (Vec<String>, Vec<u8>) {
    let scenario = Scenario::named("aoa-drive").expect("scenario");
    let o = CaptureOptions {
        format,
        ..CaptureOptions::default()
    };
    let bytes = drive_capture(&scenario, &o).expect("capture");
    let text = String::from_utf8(bytes.clone()).expect("ASCII");
    (text.lines().map(str::to_string).collect(), bytes)
}

/// Reply `r` of the stand-in: five new records a poll, the five before them again, every
/// fourth reply empty and every third cut in the middle of its last record; once the drive
/// is served, its last page again and again.
fn page(records: &[String], r: usize) -> String {
    if r % 4 == 3 {
        return String::new();
    }
    let end = (5 * (r + 1)).min(records.len());
    let start = end.saturating_sub(10);
    let mut text: String = records[start..end]
        .iter()
        .map(|l| format!("{l}\n"))
        .collect();
    if r % 3 == 2 && end < records.len() {
        let next = &records[end];
        text.push_str(&next[..next.len() / 2]);
    }
    text
}

/// Serve `records` at `path` (and 404 elsewhere) until `done`; the server's port.
fn serve(
    records: Vec<String>,
    path: &'static str,
    done: Arc<AtomicBool>,
) -> (u16, Arc<AtomicUsize>) {
    let server = tiny_http::Server::http("127.0.0.1:0").expect("server");
    let port = server.server_addr().to_ip().expect("ip").port();
    let served = Arc::new(AtomicUsize::new(0));
    let count = served.clone();
    std::thread::spawn(move || {
        let mut r = 0;
        while !done.load(Ordering::Relaxed) {
            let Ok(Some(req)) = server.recv_timeout(Duration::from_millis(50)) else {
                continue;
            };
            let reply = if req.url() == path {
                let body = page(&records, r);
                r += 1;
                count.store(r, Ordering::Relaxed);
                tiny_http::Response::from_string(body)
            } else {
                tiny_http::Response::from_string("no such page").with_status_code(404)
            };
            let _ = req.respond(reply);
        }
    });
    (port, served)
}

fn live(format: CaptureFormat, path: &'static str, url_page: &str) {
    let (recs, bytes) = records(format);
    let done = Arc::new(AtomicBool::new(false));
    let (port, served) = serve(recs.clone(), path, done.clone());
    let url = format!("http://127.0.0.1:{port}{url_page}");
    let updates = common::json_lines(
        &["locate", "--kraken", &url, "--quiet-exit", "2", "--json"].map(String::from),
    );
    done.store(true, Ordering::Relaxed);
    let used: Vec<u64> = updates.iter().filter_map(|v| v["used"].as_u64()).collect();
    // An update for each poll that brought new bearings, never for a repeat.
    assert!(used.windows(2).all(|w| w[0] < w[1]), "{used:?}");
    let last = updates.last().expect("updates");
    // The same records read once from a file: the same bearings, the same fix.
    let d = decode(&bytes, Default::default(), false);
    let file = locate(&d, &LocateOptions::default()).expect("a fix").report;
    eprintln!(
        "{}: {} replies served (a quarter empty, a third cut short, each record twice); \
         {} updates, {} bearings used as from the file's {}",
        format.name(),
        served.load(Ordering::Relaxed),
        updates.len(),
        last["used"],
        file.used
    );
    assert_eq!(last["used"].as_u64(), Some(u64::from(file.used)), "{last}");
    let east = last["emitters"][0]["east_m"].as_f64().expect("east");
    let north = last["emitters"][0]["north_m"].as_f64().expect("north");
    let file = &file.emitters[0];
    // f32 printed through JSON and back: equal to its printed digits.
    assert!(
        (east - f64::from(file.east_m)).abs() < 1e-3
            && (north - f64::from(file.north_m)).abs() < 1e-3,
        "live {east}, {north}; file {}, {}",
        file.east_m,
        file.north_m
    );
}

#[test]
fn a_kraken_csv_page_polled_live_counts_each_record_once() {
    live(CaptureFormat::KrakenCsv, "/DOA_value.html", "");
}

#[test]
fn a_kraken_xml_page_is_found_when_the_csv_page_is_missing() {
    // The base URL: DOA_value.html answers 404, so the poller reads doa.xml.
    live(CaptureFormat::KrakenXml, "/doa.xml", "/");
}
