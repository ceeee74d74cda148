//! The terminal's words for what `locate` found: the report, and one line per live update.

use crate::inputs::unit::UnitReport;
use crate::locate::explain::range_words;
use crate::locate::report::LocatedAdvice;
use crate::locate::report::{LocateReport, NoFix, RegionReport, SourceReport};
use std::fmt::Write;

impl NoFix {
    /// One line for a live update.
    pub fn line(&self) -> String {
        format!(
            "{} bearings: no fix yet: {}{}{}",
            self.used,
            self.error,
            advice_suffix(self.advice.as_ref(), self.advice_error.as_deref()),
            unit_suffix(self.unit.as_ref())
        )
    }
}

/// `; DF unit (...): ...` for a one-line update, when a DF unit spoke.
fn unit_suffix(u: Option<&UnitReport>) -> String {
    u.map(|u| format!("; {}", u.line())).unwrap_or_default()
}

/// `; ADVICE` (or `; no advice: WHY`) for a one-line update.
fn advice_suffix(advice: Option<&LocatedAdvice>, error: Option<&str>) -> String {
    match (advice, error) {
        (Some(a), _) => format!("; {}", a.line),
        (None, Some(e)) => format!("; no advice: {e}"),
        (None, None) => String::new(),
    }
}

impl RegionReport {
    /// `region: bearing 123.4° ± 5.6° from LAT, LON, range 1.2 km to unbounded` (with the
    /// frequency when `freq` is asked for), and the region's noise and bearings.
    pub fn lines(&self, freq: bool, out: &mut String) {
        let f = match (freq, self.freq_mhz) {
            (true, Some(f)) => format!(" ({f:.3} MHz)"),
            _ => String::new(),
        };
        let _ = writeln!(
            out,
            "region{f}: bearing {:.1}° ± {:.1}° from {:.6}, {:.6}, range {}",
            self.bearing_deg,
            self.half_width_deg,
            self.lat,
            self.lon,
            range_words(self)
        );
        let _ = writeln!(
            out,
            "  {:.0} % region; noise {:.2} deg; {} bearings ({:.1} effective)",
            100.0 * self.confidence,
            self.sigma_deg,
            self.used,
            self.effective
        );
    }
}

impl SourceReport {
    fn lines(&self, label: &str, out: &mut String) {
        let freq = self
            .freq_mhz
            .map(|f| format!(" ({f:.3} MHz)"))
            .unwrap_or_default();
        let _ = writeln!(
            out,
            "{label}{freq}  {:.6}, {:.6}  ({:.1} m east, {:.1} m north)",
            self.lat, self.lon, self.east_m, self.north_m
        );
        let _ = writeln!(
            out,
            "  {:.0} % ellipse semi-axes {:.1} m and {:.1} m, major axis {:.0} deg from north; CEP50 {:.1} m; bound {:.1} m",
            100.0 * self.ellipse.confidence,
            self.ellipse.major_m,
            self.ellipse.minor_m,
            self.ellipse.orientation_deg,
            self.cep50_m,
            self.crlb_m
        );
        let offset = match (self.bias_deg, self.bias_sd_deg) {
            (Some(b), Some(sd)) => format!("offset {b:.2} +- {sd:.2} deg; "),
            _ => String::new(),
        };
        let effective = self
            .effective
            .map(|e| format!(" ({e:.1} effective)"))
            .unwrap_or_default();
        let consistent = match self.consistent {
            Some(true) => "; residuals consistent",
            Some(false) => "; NOT consistent: the uncertainty is understated",
            None => "",
        };
        let how = match (self.sigma_estimated, self.sigma_dof) {
            (true, Some(d)) => format!("estimated, {d:.0} degrees of freedom"),
            (true, None) => "estimated".to_string(),
            (false, _) => "given".to_string(),
        };
        let _ = writeln!(
            out,
            "  {offset}noise {:.2} deg ({how}); {} bearings{effective}{consistent}",
            self.sigma_deg, self.used,
        );
        if self.offset_measured == Some(false) && self.offset_check.is_none() {
            let _ = writeln!(
                out,
                "  offset not measured by these bearings: the fix holds while it lies within its \
                 prior; turn (or calibrate) to check"
            );
        }
        if let Some(c) = self.offset_check {
            let what = if c.relaxed {
                format!(
                    "the offset lay {:.1} sds beyond its prior, which was relaxed (this fix and \
                     its ellipse are the offset-free ones)",
                    c.z.abs()
                )
            } else {
                "another offset 30 deg or more away fits about as well (the prior alone chose \
                 this fix)"
                    .to_string()
            };
            let _ = writeln!(
                out,
                "  offset check: {what}: check the antenna (mounting, array indexing, cables), \
                 then calibrate"
            );
        }
        if let Some(why) = self.why {
            let _ = writeln!(out, "  {why}");
        }
    }
}

impl LocateReport {
    /// The report as the terminal shows it.
    pub fn text(&self) -> String {
        let mut out = String::new();
        for (i, e) in self.emitters.iter().enumerate() {
            let label = if self.emitters.len() > 1 {
                format!("emitter {}", i + 1)
            } else {
                "emitter".to_string()
            };
            e.lines(&label, &mut out);
        }
        for o in &self.other_sources {
            o.lines("other source", &mut out);
        }
        let several = self.channels.len() > 1;
        for c in self.channels.iter().filter(|c| c.outcome != "emitter") {
            if let Some(r) = &c.region {
                r.lines(several, &mut out);
            }
            let freq = c
                .freq_mhz
                .map(|f| format!("{f:.3} MHz"))
                .unwrap_or_else(|| "bearings without a frequency".into());
            let _ = writeln!(
                out,
                "channel {freq} ({} bearings): {}",
                c.bearings, c.outcome
            );
        }
        // A network's stations, or a unit's whose prior came from somewhere: each one's
        // offset and where it came from.
        let told = self.stations.iter().any(|s| {
            s.prior_from != crate::estimate::stations::PriorOrigin::Default
                || !s.references.is_empty()
                || s.direction_found.is_some()
        });
        if self.stations.len() > 1 || told {
            let _ = writeln!(out, "stations:");
            for s in &self.stations {
                s.line(&mut out);
            }
        }
        match (&self.advice, &self.advice_error) {
            (Some(a), _) => {
                let _ = writeln!(out, "advice: {}", a.line);
            }
            (None, Some(e)) => {
                let _ = writeln!(out, "no advice: {e}");
            }
            (None, None) => {}
        }
        if let Some(u) = &self.unit {
            let _ = writeln!(out, "{}", u.line());
        }
        let rejected: Vec<String> = self
            .rejected
            .iter()
            .filter(|(_, n)| **n > 0)
            .map(|(k, n)| format!("{k} {n}"))
            .collect();
        let _ = writeln!(
            out,
            "method {}; {} bearings; origin {:.6}, {:.6}; rejected: {}",
            self.method,
            self.used,
            self.origin.lat,
            self.origin.lon,
            if rejected.is_empty() {
                "none".to_string()
            } else {
                rejected.join(", ")
            }
        );
        out
    }

    /// One line for a live update (several emitters: numbered as the advice names them).
    pub fn update_line(&self) -> String {
        let several = self.emitters.len() > 1;
        let fixes: Vec<String> = self
            .emitters
            .iter()
            .enumerate()
            .map(|(i, e)| {
                format!(
                    "{}{:.6}, {:.6} CEP50 {:.1} m (bound {:.1} m)",
                    if several {
                        format!("emitter {} ", i + 1)
                    } else {
                        String::new()
                    },
                    e.lat,
                    e.lon,
                    e.cep50_m,
                    e.crlb_m
                )
            })
            .collect();
        format!(
            "{} bearings: {}{}{}",
            self.used,
            if fixes.is_empty() {
                "no emitter".to_string()
            } else {
                fixes.join("; ")
            },
            advice_suffix(self.advice.as_ref(), self.advice_error.as_deref()),
            unit_suffix(self.unit.as_ref())
        )
    }
}
