//! What a DF unit running foxhunt's firmware said: its `$PFOXF` fixes and `$PFOXS`/`$PFOXL`
//! health read back from a capture of its user port (or mixed into any capture), so `locate`
//! shows what the unit computed beside, or instead of, the host's own fix.

use foxhunt_bridge::record::{RecordClass, RecordKind};
use foxhunt_bridge::telemetry::{FixSentence, LinkSentence, StatusSentence, UnitSentence};
use foxhunt_core::fix::window::Status;
use serde::Serialize;

/// The unit's sentences seen so far: counts and the latest of each (memory stays constant
/// however long the unit ran).
#[derive(Debug, Clone, Copy, Default)]
pub struct UnitLog {
    /// `$PFOXF` sentences decoded.
    pub fixes: u32,
    /// The latest fix sentence.
    pub last: Option<FixSentence>,
    /// The latest fix sentence with a position.
    pub last_position: Option<FixSentence>,
    /// The latest status sentence.
    pub status: Option<StatusSentence>,
    /// The latest link sentence.
    pub link: Option<LinkSentence>,
    /// Unit sentences with a missing or malformed field.
    pub malformed: u32,
    /// Unit sentences taken, good or malformed: a live view updates when it grows.
    pub sentences: u32,
}

impl UnitLog {
    /// Take a checked sentence body if it is one of the unit's; false otherwise.
    pub fn push(&mut self, body: &str) -> bool {
        if RecordKind::of_sentence(body).class() != RecordClass::Unit {
            return false;
        }
        let parsed = UnitSentence::parse(body);
        if !matches!(
            parsed,
            Err(foxhunt_bridge::telemetry::TelemetryError::Unsupported)
        ) {
            self.sentences = self.sentences.saturating_add(1);
        }
        match parsed {
            Ok(UnitSentence::Fix(f)) => {
                self.fixes = self.fixes.saturating_add(1);
                self.last = Some(f);
                if f.position.is_some() && f.status.has_position() {
                    self.last_position = Some(f);
                }
            }
            Ok(UnitSentence::Status(s)) => self.status = Some(s),
            Ok(UnitSentence::Link(l)) => self.link = Some(l),
            Ok(UnitSentence::Ready(_) | UnitSentence::Ack(_)) => {}
            Err(foxhunt_bridge::telemetry::TelemetryError::Unsupported) => return false,
            Err(_) => self.malformed = self.malformed.saturating_add(1),
        }
        true
    }

    /// The report, if the unit said anything.
    pub fn report(&self) -> Option<UnitReport> {
        if self.fixes == 0 && self.status.is_none() && self.link.is_none() && self.malformed == 0 {
            return None;
        }
        let shown = self.last_position.or(self.last);
        let position = shown.and_then(|f| f.position.filter(|_| f.status.has_position()));
        Some(UnitReport {
            fixes: self.fixes,
            time: shown.map(|f| clock(f.time.ms_of_day)),
            status: shown.map(|f| (f.status.letter() as char).to_string()),
            status_text: shown.map(|f| meaning(f.status)),
            latest_status: self
                .last
                .filter(|l| Some(*l) != shown)
                .map(|l| (l.status.letter() as char).to_string()),
            lat: position.map(|p| p.lat),
            lon: position.map(|p| p.lon),
            major_m: position.and(shown.map(|f| f.major_m)),
            minor_m: position.and(shown.map(|f| f.minor_m)),
            orientation_deg: position.and(shown.map(|f| f.orientation_deg)),
            cep50_m: position.and(shown.map(|f| f.cep50_m)),
            used: shown.map(|f| f.used),
            window: shown.map(|f| f.window),
            sigma_deg: shown.map(|f| f.sigma_deg),
            uptime_s: self.status.map(|s| s.uptime_s),
            stack_bytes: self.status.map(|s| s.stack_bytes),
            bearings: self.link.map(|l| l.bearings),
            rejected: self.link.map(|l| l.rejected),
            lost_bytes: self.link.map(|l| l.overruns.wrapping_add(l.full)),
            malformed: self.malformed,
        })
    }
}

/// What the unit said, as `locate` reports it (`unit` in its JSON; field names are stable).
/// The fix shown is the unit's latest with a position (else its latest of any status).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct UnitReport {
    /// `$PFOXF` sentences decoded.
    pub fixes: u32,
    /// UTC time of the fix shown, `hh:mm:ss.ss`.
    pub time: Option<String>,
    /// Its status letter (A, E, D, N, S).
    pub status: Option<String>,
    /// What the status means.
    pub status_text: Option<&'static str>,
    /// The latest sentence's status, when it is not the fix shown (the unit lost its fix).
    pub latest_status: Option<String>,
    /// The emitter's latitude, degrees.
    pub lat: Option<f64>,
    /// The emitter's longitude, degrees.
    pub lon: Option<f64>,
    /// 95 % ellipse semi-major axis, metres.
    pub major_m: Option<f32>,
    /// Semi-minor axis, metres.
    pub minor_m: Option<f32>,
    /// Major axis, degrees clockwise from true north.
    pub orientation_deg: Option<f32>,
    /// CEP50, metres.
    pub cep50_m: Option<f32>,
    /// Bearings used in the fix.
    pub used: Option<u32>,
    /// Bearings in the unit's window.
    pub window: Option<u32>,
    /// The bearing sigma the unit used, degrees.
    pub sigma_deg: Option<f32>,
    /// Seconds since the unit's reset (latest `$PFOXS`).
    pub uptime_s: Option<u32>,
    /// The unit's stack high-water mark, bytes.
    pub stack_bytes: Option<u32>,
    /// Bearings the unit handed its tracker (latest `$PFOXL`).
    pub bearings: Option<u32>,
    /// Records the unit rejected.
    pub rejected: Option<u32>,
    /// Bytes the unit lost to receiver overruns and full queues.
    pub lost_bytes: Option<u32>,
    /// Unit sentences that did not decode.
    pub malformed: u32,
}

impl UnitReport {
    /// The one-line form.
    pub fn line(&self) -> String {
        let mut s = format!("DF unit ({} fix sentences): ", self.fixes);
        match (self.lat, self.lon, self.cep50_m) {
            (Some(lat), Some(lon), Some(cep)) => s.push_str(&format!(
                "{lat:.6}, {lon:.6} CEP50 {cep:.1} m, 95 % ellipse {:.1} x {:.1} m at {:.1} deg",
                self.major_m.unwrap_or(0.0),
                self.minor_m.unwrap_or(0.0),
                self.orientation_deg.unwrap_or(0.0)
            )),
            _ => s.push_str("no position"),
        }
        if let (Some(t), Some(text)) = (&self.time, self.status_text) {
            s.push_str(&format!(" at {t} ({text})"));
        }
        if let (Some(u), Some(w)) = (self.used, self.window) {
            s.push_str(&format!("; {u} of {w} bearings"));
        }
        if let Some(sd) = self.sigma_deg {
            s.push_str(&format!(", sigma {sd:.2} deg"));
        }
        if let Some(l) = &self.latest_status {
            s.push_str(&format!("; latest status {l}"));
        }
        if let (Some(r), Some(lost)) = (self.rejected, self.lost_bytes) {
            s.push_str(&format!("; unit rejected {r} records, lost {lost} bytes"));
        }
        if self.malformed > 0 {
            s.push_str(&format!("; {} unit sentences malformed", self.malformed));
        }
        s
    }
}

fn meaning(s: Status) -> &'static str {
    match s {
        Status::Valid => "valid",
        Status::Noisy => "bearings scatter more than 10 degrees: not to be trusted",
        Status::Degenerate => "degenerate geometry",
        Status::TooFew => "fewer than three bearings",
        Status::Searching => "searching",
    }
}

fn clock(ms: u32) -> String {
    let s = ms / 1000;
    format!(
        "{:02}:{:02}:{:02}.{:02}",
        s / 3600,
        s / 60 % 60,
        s % 60,
        ms % 1000 / 10
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_unit_fix_reads_back_with_its_ellipse() {
        let mut log = UnitLog::default();
        assert!(
            log.push(
                "PFOXF,100059.50,4700.446054,N,00800.979846,E,146.2,8.5,54.2,36.5,60,60,1.20,A"
            )
        );
        assert!(log.push("PFOXF,100100.50,,,,,,,,,2,60,1.20,S"));
        assert!(!log.push("GPGGA,100100.00,4700.0,N,00800.0,E,1,08,1.0,400.0,M,48.0,M,,"));
        assert!(log.push("PFOXF,broken"));
        let r = log.report().unwrap();
        assert_eq!(r.fixes, 2);
        assert_eq!(r.malformed, 1);
        assert_eq!(log.sentences, 3, "two fixes and the broken one");
        assert_eq!(r.status.as_deref(), Some("A"));
        assert_eq!(r.latest_status.as_deref(), Some("S"));
        assert!((r.lat.unwrap() - (47.0 + 0.446054 / 60.0)).abs() < 1e-9);
        assert_eq!(r.cep50_m, Some(36.5));
        assert_eq!(r.time.as_deref(), Some("10:00:59.50"));
        let line = r.line();
        assert!(line.contains("CEP50 36.5 m"), "{line}");
        assert!(line.contains("latest status S"), "{line}");
    }

    #[test]
    fn nothing_from_a_unit_reports_nothing() {
        let mut log = UnitLog::default();
        assert!(!log.push("PFOXB,100100.00,123.4,1.5,80"));
        assert!(log.report().is_none());
    }
}
