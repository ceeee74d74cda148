//! A station's bearings sent to an MQTT broker (docs/src/networks.md, "Through an MQTT
//! broker"): QoS 1 on a persistent session, kept until the broker acknowledges them.
//!
//! The client (rumqttc) resends what the broker has not acknowledged when it reconnects to
//! a session the broker kept. A broker that lost the session (restarted without
//! persistence) would lose them with it, so the link keeps its own account: every message
//! handed to the client stays here until its PUBACK, and on a new session all of them are
//! sent again (the fusing side drops the copies it already has). While the broker is away the
//! bearings wait in a bounded backlog: a recorded capture is held back when it is full (none
//! lost), a live line drops the oldest (counted).

use crate::inputs::mqtt::{MqttUrl, RETRY, first_connect};
use crate::outputs::terminal::note;
use rumqttc::{Client, Connection, Event, Outgoing, Packet, QoS};
use std::collections::{BTreeMap, HashMap, VecDeque};
use std::sync::mpsc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// One message to send.
#[derive(Debug, Clone)]
pub struct Message {
    /// Its topic.
    pub topic: String,
    /// Its payload.
    pub payload: Vec<u8>,
}

/// What a link sent, at its end.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Sent {
    /// Messages handed to the link.
    pub messages: u64,
    /// Acknowledged by the broker.
    pub acked: u64,
    /// Dropped from a full backlog (live lines only).
    pub dropped: u64,
    /// Sent again on a new session.
    pub resent: u64,
    /// Times the broker was lost.
    pub outages: u64,
}

/// How a link behaves while the broker is away.
#[derive(Debug, Clone, Copy)]
pub struct Backlog {
    /// Messages kept at most.
    pub capacity: usize,
    /// Drop the oldest when full (a live line, which cannot wait); else hold the sender back.
    pub drop_oldest: bool,
    /// After the last message, how long to wait for the broker's acknowledgements.
    pub linger: Duration,
}

/// The sending side's link to the broker.
pub struct Link {
    tx: Option<mpsc::SyncSender<Message>>,
    thread: Option<JoinHandle<Sent>>,
}

/// The client's request queue: small, so the backlog here is the one that counts.
const REQUESTS: usize = 64;

impl Link {
    /// Connect as `client_id` (a broker that cannot be reached now is the caller's error)
    /// and start the thread that sends.
    pub fn start(url: &MqttUrl, client_id: &str, backlog: Backlog) -> Result<Self, String> {
        let (client, mut conn) = Client::new(url.options(client_id), REQUESTS);
        first_connect(&mut conn, url)?;
        let (tx, rx) = mpsc::sync_channel::<Message>(1024);
        let address = url.address();
        let thread = std::thread::Builder::new()
            .name("foxhunt-mqtt-send".into())
            .spawn(move || Sender::new(client, backlog, address).run(&mut conn, &rx))
            .map_err(|e| format!("cannot start the MQTT sender: {e}"))?;
        Ok(Self {
            tx: Some(tx),
            thread: Some(thread),
        })
    }

    /// Send `m` (blocks while a recorded capture's backlog is full).
    pub fn send(&self, m: Message) -> Result<(), String> {
        self.tx
            .as_ref()
            .and_then(|tx| tx.send(m).ok())
            .ok_or_else(|| "the MQTT sender stopped".to_string())
    }

    /// No more messages: wait for the broker's acknowledgements (up to the linger) and
    /// disconnect.
    pub fn finish(mut self) -> Sent {
        self.tx = None;
        self.thread
            .take()
            .and_then(|t| t.join().ok())
            .unwrap_or_default()
    }
}

/// The sending thread's state: every message from the backlog to its PUBACK.
struct Sender {
    client: Client,
    backlog_of: Backlog,
    address: String,
    /// Waiting for room in the client.
    backlog: VecDeque<(u64, Message)>,
    /// Handed to the client, no packet id seen yet (in the order handed).
    queued: VecDeque<(u64, Message)>,
    /// Sent under a packet id, not yet acknowledged.
    inflight: HashMap<u16, (u64, Message)>,
    next_seq: u64,
    sent: Sent,
}

impl Sender {
    fn new(client: Client, backlog_of: Backlog, address: String) -> Self {
        Self {
            client,
            backlog_of,
            address,
            backlog: VecDeque::new(),
            queued: VecDeque::new(),
            inflight: HashMap::new(),
            next_seq: 0,
            sent: Sent::default(),
        }
    }

    /// Take what the caller sent, within the backlog's bound; whether the caller is done.
    fn take(&mut self, rx: &mpsc::Receiver<Message>) -> bool {
        loop {
            if self.backlog.len() >= self.backlog_of.capacity && !self.backlog_of.drop_oldest {
                return false;
            }
            match rx.try_recv() {
                Ok(m) => {
                    self.sent.messages += 1;
                    if self.backlog.len() >= self.backlog_of.capacity {
                        self.backlog.pop_front();
                        if self.sent.dropped == 0 {
                            note(&format!(
                                "MQTT backlog full ({} bearings): dropping the oldest",
                                self.backlog_of.capacity
                            ));
                        }
                        self.sent.dropped += 1;
                    }
                    self.backlog.push_back((self.next_seq, m));
                    self.next_seq += 1;
                }
                Err(mpsc::TryRecvError::Empty) => return false,
                Err(mpsc::TryRecvError::Disconnected) => return true,
            }
        }
    }

    /// Hand the backlog to the client while it has room.
    fn hand_on(&mut self) {
        while let Some((_, m)) = self.backlog.front() {
            let r = self.client.try_publish(
                m.topic.clone(),
                QoS::AtLeastOnce,
                false,
                m.payload.clone(),
            );
            if r.is_err() {
                return;
            }
            if let Some(m) = self.backlog.pop_front() {
                self.queued.push_back(m);
            }
        }
    }

    /// Everything not acknowledged, back to the front of the backlog in its first order.
    fn requeue(&mut self) {
        let mut again: BTreeMap<u64, Message> = self.inflight.drain().map(|(_, m)| m).collect();
        again.extend(self.queued.drain(..));
        self.sent.resent += again.len() as u64;
        for m in again.into_iter().rev() {
            self.backlog.push_front(m);
        }
    }

    fn unacked(&self) -> usize {
        self.backlog.len() + self.queued.len() + self.inflight.len()
    }

    fn run(mut self, conn: &mut Connection, rx: &mpsc::Receiver<Message>) -> Sent {
        let mut done_at: Option<Instant> = None;
        let mut down = false;
        loop {
            if done_at.is_none() && self.take(rx) {
                done_at = Some(Instant::now());
            }
            self.hand_on();
            if let Some(t) = done_at {
                if self.unacked() == 0 {
                    break;
                }
                if t.elapsed() > self.backlog_of.linger {
                    note(&format!(
                        "MQTT broker at {}: {} bearings not acknowledged after {} s",
                        self.address,
                        self.unacked(),
                        self.backlog_of.linger.as_secs()
                    ));
                    break;
                }
            }
            match conn.recv_timeout(Duration::from_millis(50)) {
                Ok(Ok(Event::Outgoing(Outgoing::Publish(pkid)))) => {
                    // A packet id not in flight is a new message's (a resent one keeps its id).
                    if !self.inflight.contains_key(&pkid)
                        && let Some(m) = self.queued.pop_front()
                    {
                        self.inflight.insert(pkid, m);
                    }
                }
                Ok(Ok(Event::Incoming(Packet::PubAck(a)))) => {
                    if self.inflight.remove(&a.pkid).is_some() {
                        self.sent.acked += 1;
                    }
                }
                Ok(Ok(Event::Incoming(Packet::ConnAck(ack)))) => {
                    if down {
                        note(&format!("MQTT broker at {}: connected again", self.address));
                        down = false;
                    }
                    // A new session: the client dropped what it had not sent or had not had
                    // acknowledged; this link still has it.
                    if !ack.session_present {
                        self.requeue();
                    }
                }
                Ok(Ok(_)) | Err(rumqttc::RecvTimeoutError::Timeout) => {}
                Ok(Err(e)) => {
                    if !down {
                        note(&format!(
                            "MQTT broker at {}: {e}; keeping the bearings until it is back",
                            self.address
                        ));
                        self.sent.outages += 1;
                        down = true;
                    }
                    std::thread::sleep(RETRY);
                }
                Err(rumqttc::RecvTimeoutError::Disconnected) => break,
            }
        }
        let _ = self.client.try_disconnect();
        // Let the DISCONNECT go out.
        let _ = conn.recv_timeout(Duration::from_millis(100));
        self.sent
    }
}
