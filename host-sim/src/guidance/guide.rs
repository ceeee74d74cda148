//! Guidance as a drive goes on: the road network (placed in the drive's frame once its origin
//! is known), the stop rule's settings, and the advice for the field pipeline's fix after each
//! update. `foxhunt locate` (live lines and the final report) and `foxhunt serve` both advise
//! through [`Guide::advise`], so the move, its reason and the verdict are the same in the
//! terminal, in `--json` lines and on the map.

use super::{
    Advice, AdviceReport, FixView, GuidanceOptions, Situation, advise, median_sigma, track_heading,
};
use crate::capture::Decoded;
use crate::locate::{LatLonReport, LocateOptions, geodetic};
use crate::roads::RoadGraph;
use foxhunt_core::Bearing;
use foxhunt_core::fix::locate::Source;
use serde::Serialize;

/// Where to drive and whether to stop, for one drive.
#[derive(Debug, Clone)]
pub struct Guide {
    roads: Option<RoadGraph>,
    placed: bool,
    options: GuidanceOptions,
}

/// The advice as `foxhunt locate` reports it: the advice's fields, the point to drive to and
/// the next turn in latitude and longitude, and the one-line form.
#[derive(Debug, Clone, Serialize)]
pub struct LocatedAdvice {
    /// The advice's fields.
    #[serde(flatten)]
    pub report: AdviceReport,
    /// The point to drive to (the end of the first move).
    pub target: LatLonReport,
    /// Where the next road turn is (on roads).
    pub turn_at: Option<LatLonReport>,
    /// The advice in one line.
    pub line: String,
}

impl Guide {
    /// Guidance on `roads` (an extract's graph, not yet placed; `None`: free headings in open
    /// terrain) with the stop rule's target CEP50. Refuses a target no rule can use.
    pub fn new(roads: Option<RoadGraph>, target_cep50_m: f32) -> Result<Self, String> {
        let mut options = if roads.is_some() {
            GuidanceOptions::roads()
        } else {
            GuidanceOptions::default()
        };
        options.stop.target_cep50_m = target_cep50_m;
        options.stop.check().map_err(|_| {
            format!("--target-cep50-m must be a number of metres > 0, not {target_cep50_m}")
        })?;
        Ok(Self {
            roads,
            placed: false,
            options,
        })
    }

    /// The settings advice is computed with.
    pub fn options(&self) -> &GuidanceOptions {
        &self.options
    }

    /// The road network as read (its nodes' latitudes and longitudes are the extract's).
    pub fn road_graph(&self) -> Option<&RoadGraph> {
        self.roads.as_ref()
    }

    /// The roads, placed in `d`'s frame (once it has one).
    pub fn roads(&mut self, d: &Decoded) -> Option<&RoadGraph> {
        if !self.placed
            && let (Some(g), Some(frame)) = (self.roads.as_mut(), d.frame.as_ref())
        {
            g.localise(frame);
            self.placed = true;
        }
        self.roads.as_ref().filter(|_| self.placed)
    }

    /// The advice for the drive `d` so far and the pipeline's emitter `fix` (`None`: no fix
    /// yet; the move then crosses the line of bearing), with the bearings' noise, offset prior
    /// and channel width of `o`. Only the fix's own channel's bearings count: another
    /// channel's bearings say nothing about this emitter. "Good enough" needs the stop rule
    /// (the bound at the noise the fix found, [`noise_scale`]) and the fix's own CEP50 below
    /// the target.
    pub fn advise(
        &mut self,
        d: &Decoded,
        fix: Option<&Source>,
        o: &LocateOptions,
    ) -> Result<Advice, String> {
        let vehicle = d
            .bearings()
            .last()
            .map(|b| b.vehicle)
            .ok_or("no bearing yet")?;
        let all: Vec<Bearing> = match o.sigma_deg {
            Some(s) => d.bearings_with_sigma(s.to_radians()),
            None => d.bearings().copied().collect(),
        };
        let heading = track_heading(&all);
        let channel: Vec<Bearing> = match fix {
            Some(f) => {
                let mut c: Vec<Bearing> = d
                    .observations
                    .iter()
                    .zip(&all)
                    .filter(|(x, _)| same_channel(x.freq_mhz, f.freq_mhz, o.channel_width_mhz))
                    .map(|(_, b)| *b)
                    .collect();
                let scale = noise_scale(f, &c);
                for b in &mut c {
                    b.sigma *= scale;
                }
                c
            }
            None => all,
        };
        let situation = Situation {
            bearings: &channel,
            vehicle,
            heading,
            fix: fix.map(|f| FixView {
                position: f.position,
                covariance: f.covariance,
                consistent: f.consistent,
                effective: f.effective,
            }),
            prior: o.offset.unwrap_or_default(),
        };
        let options = self.options;
        let mut a = advise(&situation, self.roads(d), &options)?;
        // The bound is the best case; the fix's own CEP50 is what is claimed. "Good enough"
        // beside a reported CEP50 above the target would tell the driver to stop too soon.
        if let (Some(f), Some(v)) = (fix, a.verdict.as_mut())
            && !(f.cep50 < options.stop.target_cep50_m)
        {
            v.missing.precision = true;
            v.good_enough = false;
            a.reason = v.reason();
        }
        Ok(a)
    }

    /// [`Guide::advise`] as `foxhunt locate` reports it.
    pub fn located(
        &mut self,
        d: &Decoded,
        fix: Option<&Source>,
        o: &LocateOptions,
    ) -> Result<LocatedAdvice, String> {
        let frame = d.frame.ok_or("no GPS fix yet")?;
        let a = self.advise(d, fix, o)?;
        let ll = |p: [f32; 2]| {
            let g = geodetic(&frame, p);
            LatLonReport {
                lat: g.lat,
                lon: g.lon,
            }
        };
        let target = ll(a.waypoint);
        let line = a.line_to(Some(&format!("{:.5}, {:.5}", target.lat, target.lon)));
        Ok(LocatedAdvice {
            report: a.report(),
            target,
            turn_at: a.turn.map(|t| ll(t.at)),
            line,
        })
    }
}

/// How much noisier the fix found the bearings than they say: its noise over their median
/// sigma, times sqrt(N / N_eff) for correlated bearings (the pipeline widens its covariance by
/// N / N_eff). The stop rule's bound and the planner's predictions then hold at the noise the
/// reported fix used, so "good enough" never stands beside a reported CEP50 the bearings'
/// stated noise would have shrunk.
fn noise_scale(f: &Source, bearings: &[Bearing]) -> f32 {
    let stated = median_sigma(bearings).unwrap_or(f.sigma);
    let noise = if stated > 0.0 { f.sigma / stated } else { 1.0 };
    let correlated = if f.effective > 0.0 {
        (f.used as f32 / f.effective).sqrt()
    } else {
        1.0
    };
    let s = noise * correlated.max(1.0);
    if s.is_finite() && s > 0.0 { s } else { 1.0 }
}

/// Whether a bearing at `freq` belongs to the channel at `channel` (the pipeline's grouping:
/// within the channel width; bearings without a frequency form their own channel).
fn same_channel(freq: Option<f32>, channel: Option<f32>, width: f32) -> bool {
    match (freq, channel) {
        (Some(f), Some(c)) => (f - c).abs() <= width.max(1e-3),
        (None, None) => true,
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bearings_join_their_own_channel_only() {
        assert!(same_channel(Some(146.52), Some(146.52), 0.05));
        assert!(same_channel(Some(146.54), Some(146.52), 0.05));
        assert!(!same_channel(Some(147.0), Some(146.52), 0.05));
        assert!(!same_channel(None, Some(146.52), 0.05));
        assert!(same_channel(None, None, 0.05));
    }

    #[test]
    fn a_target_no_rule_can_use_is_refused_by_name() {
        for t in [0.0, -5.0, f32::NAN, f32::INFINITY] {
            let e = Guide::new(None, t).unwrap_err();
            assert!(e.contains("--target-cep50-m"), "{e}");
        }
        let g = Guide::new(None, 50.0).unwrap();
        assert_eq!(g.options().stop.target_cep50_m, 50.0);
    }
}
