//! `foxhunt serve`: a local web page with a live map of the hunt.
//!
//! The page (host-sim/web, built into the binary) is static: Leaflet (vendored, with its
//! licence) draws what the server sends. One thread decodes the input (a capture replayed in
//! chunks, or standard input as it arrives), recomputes the field pipeline's fix and the
//! guidance advice after every chunk with new bearings (or new sentences of a DF unit, whose
//! own fix is drawn beside the host's), and hands the state to the HTTP server
//! (axum on tokio), which pushes it to every open page as a server-sent event. Roads from an
//! OpenStreetMap extract are the basemap, so the map works offline; online tiles are optional
//! (`--tiles`, a URL template the page passes to Leaflet).
//!
//! Routes: `/` the page, `/app.js`, `/leaflet/*`, `/state` (the latest state, JSON),
//! `/events` (server-sent events `state`, and `end` once the input has ended), `/roads.geojson`, `/config.json`.

pub mod moving;
pub mod state;

use crate::estimate::options::LocateOptions;
use crate::guidance::guide::Guide;
use crate::inputs::capture::Decoder;
use crate::inputs::files::CHUNK;
use crate::inputs::roads::RoadGraph;
use axum::Router;
use axum::extract::State;
use axum::http::header;
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use foxhunt_bridge::BridgeConfig;
use std::convert::Infallible;
use std::future::IntoFuture;
use std::io::{BufRead, Read};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, RwLock};
use std::time::Duration;
use tokio::sync::{Notify, broadcast};
use tokio_stream::StreamExt;
use tokio_stream::wrappers::BroadcastStream;

const INDEX: &str = include_str!("../../../web/index.html");
const APP: &str = include_str!("../../../web/app.js");
const LEAFLET_JS: &str = include_str!("../../../web/leaflet/leaflet.js");
const LEAFLET_CSS: &str = include_str!("../../../web/leaflet/leaflet.css");
const LEAFLET_LICENSE: &str = include_str!("../../../web/leaflet/LICENSE");

/// Where the serve loop reads from.
pub enum Input {
    /// Capture files replayed in order: `lines` lines per chunk, `pace` between chunks.
    Replay {
        /// The files.
        files: Vec<PathBuf>,
        /// Lines per chunk.
        lines: usize,
        /// Pause between chunks.
        pace: Duration,
    },
    /// Standard input, as it arrives.
    Stdin,
    /// A live line (KrakenSDRs' web pages, a broker): each call feeds the decoder what the
    /// line brought and says whether it ended.
    Line(LineFeed),
}

/// A live line's reader, as `foxhunt serve` hands it over: feed the decoder what arrived
/// (blocking a moment when nothing did); `Ok(true)` once the line has ended.
pub type LineFeed = Box<dyn FnMut(&mut Decoder) -> Result<bool, String> + Send>;

impl std::fmt::Debug for Input {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Input::Replay { files, lines, pace } => f
                .debug_struct("Replay")
                .field("files", files)
                .field("lines", lines)
                .field("pace", pace)
                .finish(),
            Input::Stdin => f.write_str("Stdin"),
            Input::Line(_) => f.write_str("Line"),
        }
    }
}

/// Settings of the server.
#[derive(Debug)]
pub struct ServeOptions {
    /// Address to listen on (port 0: any free port, printed on stderr).
    pub addr: String,
    /// The input.
    pub input: Input,
    /// Guidance: the roads (also the basemap) and the stop rule.
    pub guide: Guide,
    /// An online tile URL template (`https://.../{z}/{x}/{y}.png`), if wanted.
    pub tiles: Option<String>,
    /// After the input ends, serve this long more and exit (`None`: until stopped).
    pub linger: Option<Duration>,
    /// How the fix is made (the stations file, the reference transmitters), as `locate`'s.
    pub locate: LocateOptions,
}

struct Shared {
    latest: RwLock<String>,
    /// Every new state; `None` once, when the input has ended.
    tx: broadcast::Sender<Option<String>>,
    /// The input has ended: a page that connects now gets the last state and `end`.
    ended: AtomicBool,
    roads: String,
    config: String,
}

fn text(kind: &'static str, body: &'static str) -> Response {
    ([(header::CONTENT_TYPE, kind)], body).into_response()
}

fn json(body: String) -> Response {
    (
        [
            (header::CONTENT_TYPE, "application/json"),
            (header::CACHE_CONTROL, "no-store"),
        ],
        body,
    )
        .into_response()
}

async fn latest(State(s): State<Arc<Shared>>) -> Response {
    let body = s.latest.read().map(|l| l.clone()).unwrap_or_default();
    json(body)
}

async fn events(
    State(s): State<Arc<Shared>>,
) -> Sse<impl tokio_stream::Stream<Item = Result<Event, Infallible>>> {
    // Subscribe before reading `ended`: either the end is still to come through the channel,
    // or it has been and nothing more will.
    let rx = BroadcastStream::new(s.tx.subscribe());
    let ended = s.ended.load(Ordering::Acquire);
    let first = s.latest.read().map(|l| l.clone()).unwrap_or_default();
    let state = |d: String| Ok(Event::default().event("state").data(d));
    let live = rx
        .filter_map(|m| m.ok())
        .take_while(Option::is_some)
        .filter_map(move |m| m.map(state))
        .take(if ended { 0 } else { usize::MAX });
    // `end` lets the page close its event source, so a finished replay stops loading (a
    // headless browser then returns) and the browser does not reconnect for ever.
    let stream = tokio_stream::once(state(first))
        .chain(live)
        .chain(tokio_stream::once(Ok(Event::default()
            .event("end")
            .data("input ended"))));
    Sse::new(stream).keep_alive(KeepAlive::default())
}

/// The roads as GeoJSON line strings in longitude, latitude.
pub fn roads_geojson(g: &RoadGraph) -> String {
    let lines: Vec<serde_json::Value> = g
        .segments()
        .filter_map(|(a, b)| {
            let (p, q) = (g.geodetic(a)?, g.geodetic(b)?);
            Some(serde_json::json!([[p.lon, p.lat], [q.lon, q.lat]]))
        })
        .collect();
    serde_json::json!({
        "type": "Feature",
        "properties": {"kind": "roads"},
        "geometry": {"type": "MultiLineString", "coordinates": lines},
    })
    .to_string()
}

/// The decode loop: feeds the input to the decoder and publishes a state per chunk with new
/// bearings, and a last one when the input ends.
fn feed(
    input: Input,
    mut guide: Guide,
    locate: &LocateOptions,
    shared: Arc<Shared>,
    done: Arc<Notify>,
) -> Result<(), String> {
    let mut dec = Decoder::new(BridgeConfig::default(), false);
    locate.survey(&mut dec);
    let mut update = 0u64;
    let mut history: Vec<[f64; 2]> = Vec::new();
    let mut reported = (0usize, 0u32);
    let mut tracker = moving::MapTracker::new(locate.network.as_deref());
    let mut publish = |dec: &mut Decoder, end: bool| {
        // New bearings, or a DF unit's new sentences (its user port carries no bearings).
        let n = (dec.decoded.observations.len(), dec.decoded.unit.sentences);
        if n == reported && !end {
            return;
        }
        reported = n;
        dec.snapshot();
        update += 1;
        tracker.update(&dec.decoded, end);
        let st = state::build(
            &dec.decoded,
            update,
            &history,
            &mut guide,
            &tracker,
            locate,
            end,
        );
        history = st.history.clone();
        if let Ok(body) = serde_json::to_string(&st) {
            if let Ok(mut l) = shared.latest.write() {
                *l = body.clone();
            }
            let _ = shared.tx.send(Some(body));
        }
    };
    match input {
        Input::Replay { files, lines, pace } => {
            for f in files {
                let file = std::fs::File::open(&f)
                    .map_err(|e| format!("cannot read {}: {e}", f.display()))?;
                let mut reader = std::io::BufReader::new(file);
                let mut chunk = Vec::new();
                loop {
                    // `lines` lines, each cut at CHUNK bytes and the chunk at CHUNK: memory
                    // stays bounded on a file without line ends.
                    chunk.clear();
                    let mut eof = false;
                    for _ in 0..lines.max(1) {
                        let room = CHUNK.saturating_sub(chunk.len()) as u64;
                        let n = (&mut reader)
                            .take(room)
                            .read_until(b'\n', &mut chunk)
                            .map_err(|e| format!("cannot read {}: {e}", f.display()))?;
                        if n == 0 {
                            eof = room > 0;
                            break;
                        }
                    }
                    dec.feed(&chunk);
                    publish(&mut dec, false);
                    if eof {
                        break;
                    }
                    std::thread::sleep(pace);
                }
            }
        }
        Input::Line(mut take) => loop {
            let ended = take(&mut dec)?;
            if ended {
                break;
            }
            publish(&mut dec, false);
        },
        Input::Stdin => {
            let mut buf = vec![0u8; 4096];
            let mut stdin = std::io::stdin();
            loop {
                match stdin.read(&mut buf) {
                    Ok(0) => break,
                    Ok(n) => {
                        dec.feed(&buf[..n]);
                        publish(&mut dec, false);
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    Err(e) => return Err(format!("reading standard input: {e}")),
                }
            }
        }
    }
    dec.end();
    publish(&mut dec, true);
    crate::outputs::terminal::note(&format!(
        "foxhunt serve: input ended after {} bearings",
        dec.decoded.observations.len()
    ));
    shared.ended.store(true, Ordering::Release);
    let _ = shared.tx.send(None);
    done.notify_one();
    Ok(())
}

/// Run the server until stopped (or `linger` after the input ends).
pub fn serve(o: ServeOptions) -> Result<(), String> {
    if let Some(g) = o.guide.road_graph() {
        crate::outputs::terminal::note(&format!(
            "foxhunt serve: {} road nodes, {} directed segments",
            g.len(),
            g.edge_count()
        ));
    }
    let (tx, _) = broadcast::channel(64);
    let shared = Arc::new(Shared {
        latest: RwLock::new(serde_json::to_string(&state::MapState::default()).unwrap_or_default()),
        tx,
        ended: AtomicBool::new(false),
        roads: o
            .guide
            .road_graph()
            .map(roads_geojson)
            .unwrap_or_else(|| "null".into()),
        config: serde_json::json!({ "tiles": o.tiles }).to_string(),
    });
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the server: {e}"))?;
    runtime.block_on(async move {
        let listener = tokio::net::TcpListener::bind(&o.addr)
            .await
            .map_err(|e| format!("cannot listen on {}: {e}", o.addr))?;
        let addr = listener
            .local_addr()
            .map_err(|e| format!("cannot listen on {}: {e}", o.addr))?;
        crate::outputs::terminal::note(&format!("foxhunt serve: http://{addr}/"));
        let app = Router::new()
            .route(
                "/",
                get(|| async { text("text/html; charset=utf-8", INDEX) }),
            )
            .route(
                "/app.js",
                get(|| async { text("text/javascript; charset=utf-8", APP) }),
            )
            .route(
                "/leaflet/leaflet.js",
                get(|| async { text("text/javascript; charset=utf-8", LEAFLET_JS) }),
            )
            .route(
                "/leaflet/leaflet.css",
                get(|| async { text("text/css; charset=utf-8", LEAFLET_CSS) }),
            )
            .route(
                "/leaflet/LICENSE",
                get(|| async { text("text/plain; charset=utf-8", LEAFLET_LICENSE) }),
            )
            .route("/state", get(latest))
            .route("/events", get(events))
            .route(
                "/roads.geojson",
                get(|State(s): State<Arc<Shared>>| async move { json(s.roads.clone()) }),
            )
            .route(
                "/config.json",
                get(|State(s): State<Arc<Shared>>| async move { json(s.config.clone()) }),
            )
            .with_state(shared.clone());
        let done = Arc::new(Notify::new());
        let (feeder_done, input, guide, locate) = (done.clone(), o.input, o.guide, o.locate);
        let feeder = std::thread::Builder::new()
            .name("foxhunt-serve-input".into())
            // It fixes and advises on every update: the estimating threads' stack.
            .stack_size(crate::estimate::STACK_BYTES)
            .spawn(move || {
                if let Err(e) = feed(input, guide, &locate, shared, feeder_done.clone()) {
                    crate::outputs::terminal::note(&format!("foxhunt serve: {e}"));
                    feeder_done.notify_one();
                }
            })
            .map_err(|e| format!("cannot start the input thread: {e}"))?;
        let linger = o.linger;
        let stop = async move {
            match linger {
                Some(l) => {
                    done.notified().await;
                    tokio::time::sleep(l).await;
                }
                None => std::future::pending::<()>().await,
            }
        };
        // Not a graceful shutdown: an open page's event stream never ends by itself.
        tokio::select! {
            r = axum::serve(listener, app).into_future() => r.map_err(|e| format!("server: {e}"))?,
            () = stop => {}
        }
        drop(feeder);
        Ok(())
    })
}
