//! Bearings through an MQTT broker (docs/src/networks.md, "Through an MQTT broker"): the
//! broker's address, the topics, the message a station sends per bearing, and the fusing
//! side's subscription.
//!
//! A message is one bearing as the station's bridge placed it: true, at the station's
//! position, on the station's UTC clock. The fusing side turns it back into the record the
//! bridge reads best, a KrakenSDR XML record (station id, time, position, heading 0 and the
//! bearing as its DOA), so a bearing from the broker takes the very path a recorded one
//! takes: the station table, the stations file's survey, the clock's checks, the fix.
//!
//! QoS 1 delivers at least once: a broker's redelivery, or a station resending after a
//! reconnect, brings a bearing twice. A bearing is its (channel, station, time): the second
//! is dropped ([`Seen`]) before the bridge sees it.
//!
//! Several workers share a network's channels by a [`Shard`] level in the bearings' topics
//! (docs/src/networks.md, "Sharding across workers"): a channel's bearings all go to the shard
//! its name hashes to, so each channel is fused by exactly one worker.

use foxhunt_bridge::kraken::KrakenXml;
use foxhunt_bridge::kraken::Station;
use foxhunt_bridge::nmea::LatLon;
use rumqttc::{Client, Connection, Event, MqttOptions, Packet, QoS};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, VecDeque};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// The broker's default port.
pub const PORT: u16 = 1883;
/// Longest message taken (a bearing's JSON is about 200 bytes): more is not a bearing.
pub const MAX_MESSAGE: usize = 4096;
/// Bearings remembered for the duplicate check: minutes to hours of a network's traffic (a
/// 64-bit key each, about 40 bytes with the set's own), so a redelivery long after the first
/// copy is still caught, in bounded memory.
const REMEMBERED: usize = 1 << 20;
/// Between reconnection attempts.
pub const RETRY: Duration = Duration::from_millis(250);
/// How long the first connection may take before the broker counts as unreachable.
pub const CONNECT_WAIT: Duration = Duration::from_secs(5);

/// `mqtt://HOST[:PORT]/PREFIX`: where the broker is and the topics' first levels.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MqttUrl {
    /// Host name or address.
    pub host: String,
    /// TCP port (1883 by default).
    pub port: u16,
    /// The topics' prefix, without a trailing slash (`foxhunt` by default).
    pub prefix: String,
}

impl MqttUrl {
    /// Parse; nonsense refused on one line naming it.
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad =
            |why: &str| format!("--mqtt wants mqtt://HOST[:PORT]/PREFIX ({why}), not `{text}`");
        let Some(rest) = text.strip_prefix("mqtt://") else {
            return Err(bad(if text.starts_with("mqtts://") {
                "TLS is not supported: run the broker's plain listener on a trusted network"
            } else {
                "an mqtt:// URL"
            }));
        };
        let (authority, path) = rest.split_once('/').unwrap_or((rest, ""));
        let (host, port) = match authority.rsplit_once(':') {
            Some((h, p)) => match p.parse::<u16>() {
                Ok(n) if n > 0 => (h, n),
                _ => return Err(bad("a port from 1 to 65535")),
            },
            None => (authority, PORT),
        };
        if host.is_empty() || host.chars().any(|c| c.is_whitespace() || c == '@') {
            return Err(bad("a host"));
        }
        let prefix = path.trim_end_matches('/');
        let prefix = if prefix.is_empty() { "foxhunt" } else { prefix };
        if prefix.contains(['+', '#']) || prefix.starts_with('$') {
            return Err(bad("a prefix without the wildcards + and # or a leading $"));
        }
        Ok(Self {
            host: host.to_string(),
            port,
            prefix: prefix.to_string(),
        })
    }

    /// `HOST:PORT`, for messages.
    pub fn address(&self) -> String {
        format!("{}:{}", self.host, self.port)
    }

    /// The topic of a bearing: `PREFIX/bearings/CHANNEL/STATION`.
    pub fn bearing_topic(&self, channel: &str, station: &str) -> String {
        format!("{}/bearings/{channel}/{station}", self.prefix)
    }

    /// Every bearing: `PREFIX/bearings/#`.
    pub fn bearings_filter(&self) -> String {
        format!("{}/bearings/#", self.prefix)
    }

    /// The topic of a bearing published for `shards` workers: `PREFIX/bearings/CHANNEL/STATION`
    /// for one, else `PREFIX/bearings/SHARD/CHANNEL/STATION` with SHARD the channel's
    /// [`shard_of`].
    pub fn sharded_topic(&self, shards: u32, channel: &str, station: &str) -> String {
        if shards <= 1 {
            self.bearing_topic(channel, station)
        } else {
            let k = shard_of(channel, shards);
            format!("{}/bearings/{k}/{channel}/{station}", self.prefix)
        }
    }

    /// What a worker subscribes to: every bearing, or its shard's (`PREFIX/bearings/K/#`).
    pub fn worker_filter(&self, shard: Option<Shard>) -> String {
        match shard {
            Some(s) if s.count > 1 => format!("{}/bearings/{}/#", self.prefix, s.index),
            _ => self.bearings_filter(),
        }
    }

    /// A channel's fix: `PREFIX/fixes/CHANNEL`.
    pub fn fix_topic(&self, channel: &str) -> String {
        format!("{}/fixes/{channel}", self.prefix)
    }

    /// The broker's options for client `id`: a persistent session (the broker keeps the
    /// subscription and the QoS 1 messages while the client is away).
    pub fn options(&self, id: &str) -> MqttOptions {
        let mut o = MqttOptions::new(id, &self.host, self.port);
        o.set_clean_session(false)
            .set_keep_alive(Duration::from_secs(15))
            .set_max_packet_size(1 << 20, 1 << 20);
        o
    }
}

/// The channel a frequency belongs to in topics: MHz to the kHz (`145.500`), `none` for a
/// bearing without one. A fusing worker groups bearings with its own `--channel-width-mhz`;
/// the topic's channel is what a shard subscribes to.
pub fn channel_name(freq_mhz: Option<f64>) -> String {
    match freq_mhz {
        Some(f) if f > 0.0 && f.is_finite() => format!("{f:.3}"),
        _ => "none".into(),
    }
}

/// Most shards (workers sharing one network's channels).
pub const MAX_SHARDS: u32 = 64;

/// The shard of a channel among `count`: FNV-1a of its topic name, modulo `count`. Fixed by
/// the name alone, so every publisher and worker agree without talking to each other.
pub fn shard_of(channel: &str, count: u32) -> u32 {
    let mut h: u32 = 0x811c_9dc5;
    for b in channel.bytes() {
        h = (h ^ u32::from(b)).wrapping_mul(0x0100_0193);
    }
    h % count.max(1)
}

/// One worker's share of the channels: those whose [`shard_of`] among `count` is `index`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// This worker's shard, from 0.
    pub index: u32,
    /// How many workers share the channels.
    pub count: u32,
}

impl Shard {
    /// `K/N` (0 <= K < N <= 64); nonsense refused on one line naming it.
    pub fn parse(text: &str) -> Result<Self, String> {
        let bad =
            || format!("--mqtt-shard wants K/N with 0 <= K < N <= {MAX_SHARDS}, not `{text}`");
        let (k, n) = text.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            k.trim().parse::<u32>().map_err(|_| bad())?,
            n.trim().parse::<u32>().map_err(|_| bad())?,
        );
        if count == 0 || count > MAX_SHARDS || index >= count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// Whether this worker owns `channel`.
    pub fn owns(&self, channel: &str) -> bool {
        shard_of(channel, self.count) == self.index
    }
}

/// A station id fit for a topic level and a KrakenSDR record: 1 to 16 printable ASCII
/// bytes, none of `/ + #`.
pub fn check_station(id: &str) -> Result<(), String> {
    let ok = !id.is_empty()
        && id.len() <= foxhunt_bridge::kraken::STATION_LEN
        && id
            .bytes()
            .all(|b| (0x21..0x7f).contains(&b) && !b"/+#".contains(&b));
    if ok {
        Ok(())
    } else {
        Err(format!(
            "station id `{id}` must be 1 to 16 printable ASCII characters without spaces, / + \
             or # (name it with --station)"
        ))
    }
}

/// One bearing on the wire (JSON): what a station's bridge handed on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BearingMessage {
    /// The station's id (its STATION_ID, or the name `publish --station` gave it).
    pub station: String,
    /// When it was taken, ms since 1970 UTC.
    pub time_ms: i64,
    /// The station's latitude there, degrees.
    pub lat: f64,
    /// Its longitude, degrees.
    pub lon: f64,
    /// The true bearing, degrees clockwise from north at the station, [0, 360).
    pub bearing_deg: f64,
    /// The bearing's noise as the station's bridge set it, degrees.
    pub sigma_deg: f64,
    /// The frequency, MHz (absent when the record has none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub freq_mhz: Option<f64>,
    /// DF quality, 0-100.
    pub quality: f32,
    /// The record kind it came in: pfoxb, agrelo, kraken-csv, kraken-xml.
    pub kind: String,
}

impl BearingMessage {
    /// The topic's channel.
    pub fn channel(&self) -> String {
        channel_name(self.freq_mhz)
    }

    /// The message checked: every field in range (one line naming the first that is not).
    pub fn check(&self) -> Result<(), String> {
        check_station(&self.station)?;
        let bad = |what: &str| Err(format!("bearing from `{}`: {what}", self.station));
        if !(-90.0..=90.0).contains(&self.lat) || !(-180.0..=180.0).contains(&self.lon) {
            return bad("position out of range");
        }
        if !(0.0..360.0).contains(&self.bearing_deg) {
            return bad("bearing_deg outside [0, 360)");
        }
        if !(self.sigma_deg > 0.0 && self.sigma_deg < 90.0) {
            return bad("sigma_deg outside (0, 90)");
        }
        if self.freq_mhz.is_some_and(|f| !(f > 0.0 && f < 1e6)) {
            return bad("freq_mhz out of range");
        }
        if !(0.0..=100.0).contains(&self.quality) {
            return bad("quality outside 0-100");
        }
        if self.time_ms < 0 {
            return bad("time_ms before 1970");
        }
        Ok(())
    }

    /// Read a message's payload: JSON of this schema, checked.
    pub fn from_payload(payload: &[u8]) -> Result<Self, String> {
        if payload.len() > MAX_MESSAGE {
            return Err(format!(
                "a message of {} bytes is no bearing",
                payload.len()
            ));
        }
        let m: Self = serde_json::from_slice(payload).map_err(|e| format!("not a bearing: {e}"))?;
        m.check()?;
        Ok(m)
    }

    /// The KrakenSDR XML record the bridge places as this bearing: the station's position,
    /// heading 0 (the bearing is already true) and DOA = 360 - bearing (the record's
    /// anticlockwise convention). Its CONF is the quality, raised to the bridge's KrakenSDR
    /// gate: the station's own bridge already judged the quality by its record kind's rule.
    pub fn record(&self) -> KrakenXml {
        let gate = foxhunt_bridge::BridgeConfig::default().kraken_min_conf;
        KrakenXml {
            station: Station::new(&self.station),
            time_ms: Some(self.time_ms as u64),
            gps_time_ms: None,
            freq_mhz: self.freq_mhz,
            position: Some(LatLon {
                lat: self.lat,
                lon: self.lon,
            }),
            heading_deg: Some(0.0),
            speed_mps: None,
            doa_deg: (360.0 - self.bearing_deg) as f32,
            pwr: None,
            conf: Some(self.quality.max(gate)),
        }
    }
}

/// The bearings already taken, by the hash of their (channel, station, time).
pub type Seen = crate::inputs::seen::Seen<u64, REMEMBERED>;

/// A bearing's key in [`Seen`]: a station and a time identify it on its channel. Hashed to 64
/// bits (the standard library's SipHash with its fixed keys) so that a million keys take tens of
/// MB, not hundreds: two bearings of a day's traffic share a key with odds of about 1e-8.
pub fn bearing_key(m: &BearingMessage) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (m.channel(), m.station.as_str(), m.time_ms).hash(&mut h);
    h.finish()
}

/// What the fusing side's subscription counted.
#[derive(Debug, Default)]
pub struct Counts {
    /// Bearings handed on.
    pub bearings: AtomicU64,
    /// Copies dropped as already seen.
    pub duplicates: AtomicU64,
    /// Bearings on this worker's shard topic whose channel is another shard's (a publisher
    /// told another shard count).
    pub misrouted: AtomicU64,
    /// Messages that were no bearing (each noted once on stderr, the first few).
    pub refused: AtomicU64,
    /// Fixes handed to the client.
    pub fixes_sent: AtomicU64,
    /// Fixes the broker acknowledged.
    pub fixes_acked: AtomicU64,
    /// The session is being closed: a lost connection is no news.
    pub closing: AtomicBool,
}

/// Whether the fusing side took a batch of bearings.
#[derive(Debug)]
pub enum Handed {
    /// Taken.
    Yes,
    /// Busy: the batch back, to grow and try again.
    Busy(Vec<KrakenXml>),
    /// Gone: stop reading.
    Closed,
}

/// Bearings held while the fusing side is busy before the reader waits for it (and the
/// broker queues the rest): some minutes of a large network.
const BATCH_WAITS: usize = 200_000;

/// The fusing side's link: bearings in on a persistent session, fixes out on a connection of
/// their own.
pub struct Subscription {
    client: Client,
    /// The topics it subscribed to.
    filter: String,
    /// Its counters.
    pub counts: Arc<Counts>,
    fixes: Arc<Fixes>,
}

/// The fixes on their way to the broker, on a connection of their own: on the bearings'
/// connection a fix queued behind a burst's thousands of acknowledgements, up to 150 ms at
/// 200 stations (docs/src/speed.md, "Fixes on their own connection").
struct Fixes {
    client: Client,
    url: MqttUrl,
    counts: Arc<Counts>,
    /// Each channel's latest fix not yet handed to the client (its queue was full): only
    /// the latest matters, the broker retains one per channel. Handed on by the next
    /// publish and by the connection's thread as the queue empties.
    waiting: Mutex<BTreeMap<String, String>>,
    /// Whether `waiting` holds any (the connection's thread looks at each event).
    any: AtomicBool,
}

impl Fixes {
    /// Connect as `client_id`'s fix publisher (a clean session: a fix that did not get
    /// through is replaced by the channel's next) and start the thread that drives the
    /// connection, reconnecting after an outage as the bearings' does.
    fn start(url: &MqttUrl, client_id: &str, counts: Arc<Counts>) -> Result<Arc<Self>, String> {
        let mut options = url.options(&format!("{client_id}-fixes"));
        options.set_clean_session(true);
        let (client, mut conn) = client(options, 64);
        first_connect(&mut conn, url)?;
        let fixes = Arc::new(Self {
            client,
            url: url.clone(),
            counts,
            waiting: Mutex::new(BTreeMap::new()),
            any: AtomicBool::new(false),
        });
        let f = fixes.clone();
        std::thread::Builder::new()
            .name("foxhunt-mqtt-fixes".into())
            .spawn(move || {
                loop {
                    if f.any.load(Ordering::Relaxed) {
                        f.flush();
                    }
                    match conn.recv_timeout(Duration::from_millis(50)) {
                        Err(rumqttc::RecvTimeoutError::Timeout) => {}
                        Err(rumqttc::RecvTimeoutError::Disconnected) => return,
                        Ok(Ok(Event::Incoming(Packet::PubAck(_)))) => {
                            f.counts.fixes_acked.fetch_add(1, Ordering::Relaxed);
                        }
                        Ok(Ok(_)) => {}
                        // The bearings' connection notes the outage.
                        Ok(Err(_)) if f.counts.closing.load(Ordering::Relaxed) => return,
                        Ok(Err(_)) => std::thread::sleep(RETRY),
                    }
                }
            })
            .map_err(|e| format!("cannot start the MQTT fix publisher: {e}"))?;
        Ok(fixes)
    }

    /// Keep `json` as `channel`'s latest fix and hand on what waits.
    fn publish(&self, channel: &str, json: String) {
        if let Ok(mut waiting) = self.waiting.lock() {
            waiting.insert(channel.to_string(), json);
            self.hand_on(&mut waiting);
        }
    }

    /// Hand the waiting fixes to the client while it has room; whether none waits.
    fn flush(&self) -> bool {
        self.waiting
            .lock()
            .map(|mut waiting| self.hand_on(&mut waiting))
            .unwrap_or(true)
    }

    /// [`Fixes::flush`] with the waiting fixes already locked.
    fn hand_on(&self, waiting: &mut BTreeMap<String, String>) -> bool {
        while let Some((channel, json)) = waiting.pop_first() {
            let topic = self.url.fix_topic(&channel);
            if self
                .client
                .try_publish(topic, QoS::AtLeastOnce, true, json.clone())
                .is_err()
            {
                waiting.insert(channel, json);
                break;
            }
            self.counts.fixes_sent.fetch_add(1, Ordering::Relaxed);
        }
        let empty = waiting.is_empty();
        self.any.store(!empty, Ordering::Relaxed);
        empty
    }
}

/// A client of `options` with a request queue of `cap`, its socket sending each packet at
/// once: with Nagle's algorithm (rumqttc's default) a small message waits for the peer's
/// delayed acknowledgement of the last, tens of milliseconds a bearing or a fix
/// (docs/src/speed.md, "Through an MQTT broker").
pub fn client(options: MqttOptions, cap: usize) -> (Client, Connection) {
    let (client, mut conn) = Client::new(options, cap);
    let mut network = conn.eventloop.network_options();
    network.set_tcp_nodelay(true);
    conn.eventloop.set_network_options(network);
    (client, conn)
}

/// Wait for the first connection: a broker that cannot be reached is the command's error.
pub fn first_connect(conn: &mut Connection, url: &MqttUrl) -> Result<bool, String> {
    let start = Instant::now();
    loop {
        match conn.recv_timeout(CONNECT_WAIT) {
            Ok(Ok(Event::Incoming(Packet::ConnAck(ack)))) => return Ok(ack.session_present),
            Ok(Ok(_)) => {}
            Ok(Err(e)) => {
                return Err(format!(
                    "cannot reach the MQTT broker at {}: {e}",
                    url.address()
                ));
            }
            Err(_) => {
                return Err(format!(
                    "cannot reach the MQTT broker at {}: no answer in {} s",
                    url.address(),
                    CONNECT_WAIT.as_secs()
                ));
            }
        }
        if start.elapsed() > CONNECT_WAIT {
            return Err(format!(
                "cannot reach the MQTT broker at {}: no answer in {} s",
                url.address(),
                CONNECT_WAIT.as_secs()
            ));
        }
    }
}

impl std::fmt::Debug for Subscription {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Subscription")
            .field("url", &self.fixes.url)
            .field("counts", &self.counts)
            .finish_non_exhaustive()
    }
}

impl Subscription {
    /// Connect as `client_id` and as its fix publisher, `client_id-fixes` (an error now is
    /// the command's), subscribe to every bearing
    /// under the prefix (`shard`'s only, with one), and start the thread that
    /// hands the new bearings' records to `take` in batches (its flag: it may block until
    /// the fusing side has room). Each new bearing goes to `keep` first, before the broker
    /// is told it arrived (a history that stores it; false: it had it already, a copy).
    pub fn start(
        url: &MqttUrl,
        client_id: &str,
        shard: Option<Shard>,
        mut take: impl FnMut(Vec<KrakenXml>, bool) -> Handed + Send + 'static,
        mut keep: impl FnMut(&BearingMessage) -> bool + Send + 'static,
        note: fn(&str),
    ) -> Result<Self, String> {
        let mut options = url.options(client_id);
        // Acknowledged once checked and held here (not before: a message that is no bearing
        // is still acknowledged, after its note). Holding the acknowledgements until the fix
        // had used them would stall the broker's few messages in flight behind each solve,
        // and overflow its queue for this worker.
        options.set_manual_acks(true);
        let (client, mut conn) = client(options, 64);
        let filter = url.worker_filter(shard);
        first_connect(&mut conn, url)?;
        // Also on a session the broker kept: the same client id may have subscribed under
        // another prefix, and subscribing again to the same filter changes nothing.
        client
            .try_subscribe(filter.clone(), QoS::AtLeastOnce)
            .map_err(|e| e.to_string())?;
        let counts = Arc::new(Counts::default());
        let fixes = Fixes::start(url, client_id, counts.clone())?;
        let (c, cl, address) = (counts.clone(), client.clone(), url.address());
        std::thread::Builder::new()
            .name("foxhunt-mqtt".into())
            .spawn(move || {
                let mut seen = Seen::default();
                let mut down = false;
                // New bearings not yet handed on (the fusing side was busy).
                let mut batch: Vec<KrakenXml> = Vec::new();
                // Acknowledgements the client's queue had no room for yet.
                let mut unacked: VecDeque<rumqttc::Publish> = VecDeque::new();
                loop {
                    if !batch.is_empty() {
                        // Never block here while the batch is small: the connection must
                        // keep reading, or the broker's queue for this worker overflows.
                        let wait = batch.len() >= BATCH_WAITS;
                        match take(std::mem::take(&mut batch), wait) {
                            Handed::Yes => {}
                            Handed::Busy(back) => batch = back,
                            Handed::Closed => return,
                        }
                    }
                    while let Some(p) = unacked.front() {
                        if cl.try_ack(p).is_err() {
                            break;
                        }
                        unacked.pop_front();
                    }
                    let event = match conn.recv_timeout(Duration::from_millis(50)) {
                        Err(rumqttc::RecvTimeoutError::Timeout) => continue,
                        Err(rumqttc::RecvTimeoutError::Disconnected) => return,
                        Ok(e) => e,
                    };
                    match event {
                        Ok(Event::Incoming(Packet::Publish(p))) => {
                            match BearingMessage::from_payload(&p.payload) {
                                Ok(m) if shard.is_some_and(|s| !s.owns(&m.channel())) => {
                                    if c.misrouted.fetch_add(1, Ordering::Relaxed) == 0 {
                                        note(&format!(
                                            "{}: channel {} is not this worker's shard: its \
                                             publisher was told another shard count; skipped",
                                            p.topic,
                                            m.channel()
                                        ));
                                    }
                                }
                                Ok(m) if seen.first_time(bearing_key(&m)) && keep(&m) => {
                                    c.bearings.fetch_add(1, Ordering::Relaxed);
                                    batch.push(m.record());
                                }
                                Ok(_) => {
                                    c.duplicates.fetch_add(1, Ordering::Relaxed);
                                }
                                Err(e) => {
                                    if c.refused.fetch_add(1, Ordering::Relaxed) < 5 {
                                        note(&format!("{}: {e}; skipped", p.topic));
                                    }
                                }
                            }
                            unacked.push_back(p);
                        }
                        Ok(Event::Incoming(Packet::ConnAck(ack))) => {
                            if down {
                                note(&format!("MQTT broker at {address}: connected again"));
                                down = false;
                            }
                            // A broker that lost the session lost the subscription too.
                            if !ack.session_present {
                                let _ = cl.try_subscribe(filter.clone(), QoS::AtLeastOnce);
                            }
                        }
                        Ok(Event::Incoming(Packet::SubAck(_))) => {
                            note(&format!("mqtt: subscribed to {filter} at {address}"));
                        }
                        Ok(_) => {}
                        Err(e) => {
                            if c.closing.load(Ordering::Relaxed) {
                                return;
                            }
                            if !down {
                                note(&format!("MQTT broker at {address}: {e}; reconnecting"));
                                down = true;
                            }
                            // What was received but not acknowledged is redelivered.
                            unacked.clear();
                            std::thread::sleep(RETRY);
                        }
                    }
                }
            })
            .map_err(|e| format!("cannot start the MQTT reader: {e}"))?;
        Ok(Self {
            client,
            filter: url.worker_filter(shard),
            counts,
            fixes,
        })
    }

    /// The topics it subscribed to (`PREFIX/bearings/#`, or its shard's).
    pub fn filter(&self) -> &str {
        &self.filter
    }

    /// Publish a channel's fix (JSON), retained at QoS 1: a worker or map that subscribes
    /// later gets the latest at once. Never blocks (the reader thread may be waiting on the
    /// caller): a fix the client has no room for waits, replaced by a newer one.
    pub fn publish_fix(&self, channel: &str, json: String) {
        self.fixes.publish(channel, json);
    }

    /// Wait up to `wait` for every fix to be handed on and acknowledged by the broker, then
    /// disconnect; whether all were.
    pub fn close(&self, wait: Duration) -> bool {
        let start = Instant::now();
        let c = &self.counts;
        let done = || {
            self.fixes.flush()
                && c.fixes_acked.load(Ordering::Relaxed) >= c.fixes_sent.load(Ordering::Relaxed)
        };
        let mut all = done();
        while !all && start.elapsed() < wait {
            std::thread::sleep(Duration::from_millis(20));
            all = done();
        }
        c.closing.store(true, Ordering::Relaxed);
        let _ = self.client.try_disconnect();
        let _ = self.fixes.client.try_disconnect();
        all
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls() {
        let u = MqttUrl::parse("mqtt://127.0.0.1:18830/net/a").expect("url");
        assert_eq!(
            (u.host.as_str(), u.port, u.prefix.as_str()),
            ("127.0.0.1", 18830, "net/a")
        );
        assert_eq!(
            u.bearing_topic("145.500", "mast-1"),
            "net/a/bearings/145.500/mast-1"
        );
        let d = MqttUrl::parse("mqtt://broker").expect("url");
        assert_eq!((d.port, d.prefix.as_str()), (1883, "foxhunt"));
        for bad in [
            "http://x",
            "mqtt://:1",
            "mqtt://h:0/p",
            "mqtt://h/a/#",
            "mqtts://h",
        ] {
            assert!(MqttUrl::parse(bad).is_err(), "{bad}");
        }
    }

    fn message() -> BearingMessage {
        BearingMessage {
            station: "mast-1".into(),
            time_ms: 1_700_000_000_000,
            lat: 47.05,
            lon: 8.01,
            bearing_deg: 123.456,
            sigma_deg: 1.0,
            freq_mhz: Some(145.5),
            quality: 80.0,
            kind: "kraken-xml".into(),
        }
    }

    #[test]
    fn a_message_round_trips_and_its_record_is_the_bearing() {
        let m = message();
        let json = serde_json::to_vec(&m).expect("json");
        let back = BearingMessage::from_payload(&json).expect("parse");
        assert_eq!(back, m);
        let r = back.record();
        assert!((f64::from(r.true_deg().expect("true")) - 123.456).abs() < 1e-4);
        assert_eq!(m.channel(), "145.500");
    }

    #[test]
    fn bad_messages_are_refused() {
        assert!(BearingMessage::from_payload(b"{").is_err());
        assert!(BearingMessage::from_payload(&vec![b' '; MAX_MESSAGE + 1]).is_err());
        for m in [
            BearingMessage {
                lat: 91.0,
                ..message()
            },
            BearingMessage {
                bearing_deg: 360.0,
                ..message()
            },
            BearingMessage {
                sigma_deg: 0.0,
                ..message()
            },
            BearingMessage {
                station: "a/b".into(),
                ..message()
            },
            BearingMessage {
                station: "seventeen-bytes-x".into(),
                ..message()
            },
            BearingMessage {
                quality: f32::NAN,
                ..message()
            },
        ] {
            let json = serde_json::to_vec(&m).expect("json");
            assert!(BearingMessage::from_payload(&json).is_err(), "{m:?}");
        }
    }

    #[test]
    fn shards_split_the_channels_once() {
        let url = MqttUrl::parse("mqtt://h/net").expect("url");
        let channels: Vec<String> = (0..16)
            .map(|c| channel_name(Some(430.0 + 0.2 * f64::from(c))))
            .collect();
        let shards: Vec<Shard> = (0..2).map(|k| Shard { index: k, count: 2 }).collect();
        let mut owned = [0usize; 2];
        for ch in &channels {
            let owners: Vec<&Shard> = shards.iter().filter(|s| s.owns(ch)).collect();
            assert_eq!(owners.len(), 1, "{ch}");
            let k = owners[0].index;
            owned[k as usize] += 1;
            // The publisher's topic falls under its owner's filter only.
            let topic = url.sharded_topic(2, ch, "s1");
            assert_eq!(topic, format!("net/bearings/{k}/{ch}/s1"));
            assert!(topic.starts_with(url.worker_filter(Some(*owners[0])).trim_end_matches('#')));
        }
        // A hash balances channels only on average: the benchmark's 16 channels split 10/6
        // (docs/src/speed.md counts on that split).
        assert_eq!(owned, [10, 6]);
        assert_eq!(
            url.sharded_topic(1, "145.500", "a"),
            url.bearing_topic("145.500", "a")
        );
        assert_eq!(url.worker_filter(None), "net/bearings/#");
        for bad in ["2/2", "0/0", "1", "a/2", "0/65"] {
            assert!(Shard::parse(bad).is_err(), "{bad}");
        }
        assert_eq!(Shard::parse("1/3"), Ok(Shard { index: 1, count: 3 }));
    }

    #[test]
    fn a_bearing_counts_once_per_channel_station_and_time() {
        let mut seen = Seen::default();
        let m = message();
        assert!(seen.first_time(bearing_key(&m)));
        assert!(!seen.first_time(bearing_key(&m)));
        assert!(seen.first_time(bearing_key(&BearingMessage {
            freq_mhz: Some(433.9),
            ..m.clone()
        })));
        assert!(seen.first_time(bearing_key(&BearingMessage {
            time_ms: m.time_ms + 1,
            ..m
        })));
    }

    proptest::proptest! {
        /// Any payload: a bearing or one line saying why not, never a panic.
        #[test]
        fn any_payload_is_a_bearing_or_an_error(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..600)) {
            let _ = BearingMessage::from_payload(&bytes);
        }

        /// A bearing's record gives the bridge back its true bearing.
        #[test]
        fn a_record_keeps_the_bearing(bearing in 0.0f64..360.0, lat in -80.0f64..80.0, lon in -180.0f64..180.0) {
            let m = BearingMessage { bearing_deg: bearing, lat, lon, ..message() };
            proptest::prop_assert!(m.check().is_ok());
            let r = m.record();
            let t = f64::from(r.true_deg().expect("true"));
            let d = (t - bearing + 540.0).rem_euclid(360.0) - 180.0;
            // f32 DOA: 360 has 3e-5 degrees between neighbours.
            proptest::prop_assert!(d.abs() < 1e-4, "{} {}", t, bearing);
        }
    }
}
