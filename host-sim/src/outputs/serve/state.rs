//! What the live map shows at one moment, built from the bearings decoded so far: the route,
//! the latest bearing rays, every emitter and other source of the field pipeline with its
//! ellipse, the guidance advice, the CEP50 history and, when the input carries a DF unit's own
//! sentences, the unit's fix as the unit said it. Everything is in latitude and longitude
//! (the page draws, it does not compute).

use crate::estimate::Pipeline;
use crate::estimate::options::LocateOptions;
use crate::guidance::guide::Guide;
use crate::inputs::capture::Decoded;
use crate::inputs::unit::UnitReport;
use crate::locate::explain::open_range;
use crate::locate::pipeline::{solve, stations_setup};
use crate::locate::report::{RegionReport, geodetic};
use crate::locate::stations::{Found, StationReport, station_reports};
use crate::outputs::maps::{ellipse_ring, wedge_ring};
use crate::outputs::serve::moving::{MapTrack, MapTracker};
use foxhunt_bridge::geo::LocalFrame;
use foxhunt_bridge::nmea::LatLon;
use foxhunt_core::fix::ellipse::Ellipse;
use foxhunt_core::fix::locate::{ChannelOutcome, NoEmitter, Source};
use serde::Serialize;

/// Route points sent at most (the route is thinned evenly beyond).
const ROUTE_POINTS: usize = 2000;
/// Latest bearings drawn as rays.
const RAYS: usize = 40;

/// A latitude, longitude pair as Leaflet takes it.
pub type LL = [f64; 2];

/// A located source on the map.
#[derive(Debug, Clone, Serialize)]
pub struct MapSource {
    /// Position.
    pub at: LL,
    /// Its ellipse (closed ring).
    pub ellipse: Vec<LL>,
    /// Confidence of the ellipse.
    pub confidence: f32,
    /// CEP50, metres.
    pub cep50_m: f32,
    /// Channel frequency, MHz.
    pub freq_mhz: Option<f32>,
    /// Bearings it holds.
    pub used: u32,
    /// Residuals consistent with the noise model.
    pub consistent: bool,
    /// The DF unit's offset, degrees, and its sd.
    pub offset_deg: [f32; 2],
}

/// A DF station on the map: fixed ones are drawn as squares, vehicles as their route.
#[derive(Debug, Clone, Serialize)]
pub struct MapStation {
    /// Its id.
    pub id: String,
    /// Whether it stands still.
    pub fixed: bool,
    /// Where its latest bearing was taken.
    pub at: LL,
    /// Its latest line of bearing.
    pub ray: [LL; 2],
    /// Its offset and the offset's sd, degrees (from the fix holding most of its bearings;
    /// the prior's where no fix used it).
    pub offset_deg: [f32; 2],
    /// Where the offset came from: `estimated`, or its prior's origin (`reference`,
    /// `stations-file`, `default`, ...), as `locate`'s station report says.
    pub offset_from: &'static str,
    /// A direction-dependent error no one stated that its residuals showed: the first and
    /// second harmonic's amplitudes, degrees (null: none found, or one stated).
    pub direction_found_deg: Option<[f32; 2]>,
    /// Bearings it gave.
    pub bearings: u32,
}

/// The advice on the map.
#[derive(Debug, Clone, Serialize)]
pub struct MapAdvice {
    /// The advice's fields.
    #[serde(flatten)]
    pub report: crate::guidance::AdviceReport,
    /// The point to drive to.
    pub waypoint_ll: LL,
    /// Where the vehicle is.
    pub vehicle_ll: LL,
    /// The next turn's place, on roads.
    pub turn_ll: Option<LL>,
    /// Each emitter's verdict, in the order of the map's emitters.
    pub emitters: Vec<crate::guidance::guide::VerdictReport>,
    /// The emitters the move is for (numbered from 1; empty when every one is good enough).
    pub for_emitters: Vec<usize>,
    /// The advice in one line.
    pub line: String,
}

/// The DF unit's own fix (its latest `$PFOXF` with a position), beside the host's.
#[derive(Debug, Clone, Serialize)]
pub struct MapUnit {
    /// What the unit said, as `locate --json` reports it under `unit`.
    #[serde(flatten)]
    pub report: UnitReport,
    /// Its position, when the fix shown has one.
    pub at: Option<LL>,
    /// Its 95 % ellipse (closed ring; empty without a position or when too large to draw).
    pub ellipse: Vec<LL>,
    /// The report in one line.
    pub line: String,
}

/// One update of the live map (the `/state` body and every server-sent event).
#[derive(Debug, Clone, Serialize, Default)]
pub struct MapState {
    /// Update number (0: nothing yet).
    pub update: u64,
    /// Bearings so far.
    pub bearings: usize,
    /// The local origin.
    pub origin: Option<LL>,
    /// The vehicle's route.
    pub route: Vec<LL>,
    /// The latest bearings: from the vehicle to a point along the bearing.
    pub rays: Vec<[LL; 2]>,
    /// Every DF station heard.
    pub stations: Vec<MapStation>,
    /// One emitter per channel.
    pub emitters: Vec<MapSource>,
    /// Other sources (reflections, a second transmitter on a channel).
    pub others: Vec<MapSource>,
    /// The channels whose range is open: their lines of bearing and range intervals.
    pub regions: Vec<MapRegion>,
    /// The channels whose emitter moves: each one's track, ellipse and velocity.
    pub tracks: Vec<MapTrack>,
    /// Why there is no fix, when there is none.
    pub fix_error: Option<String>,
    /// The suggested move.
    pub advice: Option<MapAdvice>,
    /// Why there is no advice, when there is none.
    pub advice_error: Option<String>,
    /// The DF unit's own fix, when the input carries its sentences.
    pub unit: Option<MapUnit>,
    /// (bearings, CEP50 m) of every update with a fix.
    pub history: Vec<[f64; 2]>,
    /// The input has ended.
    pub done: bool,
}

fn ll(frame: &LocalFrame, p: [f32; 2]) -> LL {
    let g = geodetic(frame, p);
    [g.lat, g.lon]
}

/// The source's ellipse ring, in latitude and longitude.
fn ring(frame: &LocalFrame, s: &Source) -> Vec<LL> {
    ellipse_ring(s.position, &s.ellipse)
        .into_iter()
        .map(|p| ll(frame, p))
        .collect()
}

fn map_source(frame: &LocalFrame, s: &Source) -> MapSource {
    MapSource {
        at: ll(frame, s.position),
        ellipse: ring(frame, s),
        confidence: s.ellipse.confidence,
        cep50_m: s.cep50,
        freq_mhz: s.freq_mhz,
        used: s.used,
        consistent: s.consistent,
        offset_deg: [s.bias.to_degrees(), s.bias_sd.to_degrees()],
    }
}

/// Largest unit ellipse drawn, metres: a sentence may say anything that parses, and far
/// beyond a hunt's scale the tangent plane no longer holds the ring (the panel still says it).
const UNIT_ELLIPSE_MAX_M: f32 = 500_000.0;

/// The ring of an ellipse of semi-axes `major`, `minor` metres, the major axis `orientation`
/// degrees clockwise from north, around `at`; empty when it cannot be drawn.
fn unit_ring(at: LatLon, major: f32, minor: f32, orientation_deg: f32) -> Vec<LL> {
    // Also refuses NaN (the parser gives none, but the page must never get one).
    if !(major.max(minor) <= UNIT_ELLIPSE_MAX_M && orientation_deg.is_finite()) {
        return Vec::new();
    }
    let Ok(frame) = LocalFrame::new(at, 0.0) else {
        return Vec::new();
    };
    let e = Ellipse {
        major,
        minor,
        // The ring's angle is counter-clockwise from east.
        orientation: (90.0 - orientation_deg).to_radians(),
        confidence: 0.95,
    };
    ellipse_ring([0.0, 0.0], &e)
        .into_iter()
        .map(|p| {
            let g = frame.to_geodetic([f64::from(p[0]), f64::from(p[1])]).ok()?;
            Some([g.lat, g.lon])
        })
        .collect::<Option<Vec<LL>>>()
        .unwrap_or_default()
}

fn map_unit(report: UnitReport) -> MapUnit {
    let at = match (report.lat, report.lon) {
        (Some(lat), Some(lon)) if lat.is_finite() && lon.is_finite() => Some([lat, lon]),
        _ => None,
    };
    let ellipse = match (at, report.major_m, report.minor_m, report.orientation_deg) {
        (Some([lat, lon]), Some(a), Some(b), Some(o)) => unit_ring(LatLon { lat, lon }, a, b, o),
        _ => Vec::new(),
    };
    MapUnit {
        line: report.line(),
        at,
        ellipse,
        report,
    }
}

/// Every station with its latest bearing (a ray `reach` metres long) and its offset, as
/// `reports` (`locate`'s) give them.
fn map_stations(
    d: &Decoded,
    frame: &LocalFrame,
    reports: Vec<StationReport>,
    reach: f32,
) -> Vec<MapStation> {
    let latest = crate::outputs::maps::latest_bearings(d);
    reports
        .into_iter()
        .filter_map(|r| {
            let i = d.stations.iter().position(|s| s.id == r.id)?;
            let b = latest[i]?;
            let end = [
                b.vehicle[0] + reach * b.theta.cos(),
                b.vehicle[1] + reach * b.theta.sin(),
            ];
            Some(MapStation {
                id: r.id,
                fixed: r.fixed,
                at: ll(frame, b.vehicle),
                ray: [ll(frame, b.vehicle), ll(frame, end)],
                offset_deg: [r.offset_deg, r.offset_sd_deg],
                offset_from: r.offset_from,
                direction_found_deg: r.direction_found.as_ref().map(|f| f.amplitudes_deg),
                bearings: r.bearings,
            })
        })
        .collect()
}

/// Every station as `locate` reports it when no fix came out: its prior's offset.
fn unsolved_stations(d: &Decoded, o: &LocateOptions) -> Vec<StationReport> {
    let setup = stations_setup(d, o);
    station_reports(d, o.network.as_deref(), &setup, Found::default(), &[], &[])
}

fn no_emitter(r: &Pipeline) -> String {
    match r.channels().first().map(|c| c.outcome) {
        Some(ChannelOutcome::NoConsistentEmitter(why)) => match why {
            NoEmitter::NoConsensus => "no point gathers more bearings than luck would".into(),
            NoEmitter::TooNoisy => "the bearings are too noisy for a fix".into(),
            NoEmitter::TooFew => "too few bearings for a checked fix".into(),
            NoEmitter::Geometry(e) => format!("no fix yet: {e}"),
            NoEmitter::OffsetBeyondPrior(b) => crate::locate::explain::offset_beyond(&b),
            NoEmitter::Moving(m) => crate::locate::explain::moving(&m),
        },
        _ => "no bearing yet".into(),
    }
}

/// An open range on the map: the observers' line of bearing and its range interval.
#[derive(Debug, Clone, Serialize)]
pub struct MapRegion {
    /// The region as `foxhunt locate --json` reports it.
    #[serde(flatten)]
    pub report: RegionReport,
    /// Its wedge (an unbounded one drawn as far as the rays).
    pub wedge: Vec<LL>,
    /// It in words.
    pub line: String,
}

/// Build the map's state after `update` updates; `history` carries the CEP50 history from
/// the last state; `guide` advises (with roads: a road turn); `tracker` has tracked every
/// channel (drawn where the emitter moves); `o`: `locate`'s options (the stations file, the
/// reference transmitters), so the map shows what `locate` says.
pub fn build(
    d: &Decoded,
    update: u64,
    history: &[[f64; 2]],
    guide: &mut Guide,
    tracker: &MapTracker,
    o: &LocateOptions,
    done: bool,
) -> MapState {
    let bearings: Vec<foxhunt_core::Bearing> = d.bearings().copied().collect();
    let mut st = MapState {
        update,
        bearings: bearings.len(),
        history: history.to_vec(),
        done,
        unit: d.unit.report().map(map_unit),
        ..MapState::default()
    };
    let Some(frame) = d.frame else {
        st.fix_error = Some("no GPS fix yet".into());
        return st;
    };
    st.origin = Some([frame.origin.lat, frame.origin.lon]);
    let stride = bearings.len().div_ceil(ROUTE_POINTS).max(1);
    st.route = bearings
        .iter()
        .step_by(stride)
        .chain(bearings.last())
        .map(|b| ll(&frame, b.vehicle))
        .collect();
    let solved = solve(d, o, &frame);
    let report = solved
        .as_ref()
        .map(|s| &s.run.report)
        .map_err(|u| u.error.clone());
    let sources: Vec<Source> = report
        .as_ref()
        .map(|r| r.emitters().to_vec())
        .unwrap_or_default();
    let emitter = sources.first().copied();
    let reach = emitter
        .map(|e| {
            let v = bearings.last().map(|b| b.vehicle).unwrap_or([0.0; 2]);
            1.5 * (e.position[0] - v[0]).hypot(e.position[1] - v[1])
        })
        .unwrap_or(3000.0)
        .clamp(500.0, 20_000.0);
    let reports = match &solved {
        Ok(s) => s.stations.clone(),
        Err(_) => unsolved_stations(d, o),
    };
    st.stations = map_stations(d, &frame, reports, reach);
    st.rays = bearings[bearings.len().saturating_sub(RAYS)..]
        .iter()
        .map(|b| {
            let end = [
                b.vehicle[0] + reach * b.theta.cos(),
                b.vehicle[1] + reach * b.theta.sin(),
            ];
            [ll(&frame, b.vehicle), ll(&frame, end)]
        })
        .collect();
    match &report {
        Ok(r) => {
            st.emitters = r.emitters().iter().map(|s| map_source(&frame, s)).collect();
            st.others = r
                .others()
                .iter()
                .map(|o| map_source(&frame, &o.source))
                .collect();
            st.regions = r
                .regions()
                .iter()
                .map(|g| {
                    let report = RegionReport::of(g, &frame);
                    MapRegion {
                        wedge: wedge_ring(&report, reach)
                            .into_iter()
                            .map(|p| ll(&frame, p))
                            .collect(),
                        line: open_range(&report),
                        report,
                    }
                })
                .collect();
            // The channels the pipeline finds moving get their track instead of a fix.
            let moving: Vec<Option<f32>> = r
                .channels()
                .iter()
                .filter(|c| {
                    matches!(
                        c.outcome,
                        ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(_))
                    )
                })
                .map(|c| c.freq_mhz)
                .collect();
            st.tracks = tracker.tracks(&frame, &moving);
            if st.emitters.is_empty() {
                st.fix_error = Some(
                    st.regions
                        .first()
                        .map_or_else(|| no_emitter(r), |g| g.line.clone()),
                );
            }
        }
        Err(e) => st.fix_error = Some(e.clone()),
    }
    if let Some(e) = emitter {
        st.history.push([bearings.len() as f64, f64::from(e.cep50)]);
    }
    let Some(vehicle) = bearings.last().map(|b| b.vehicle) else {
        st.advice_error = Some("no bearing yet".into());
        return st;
    };
    match guide.advise_every(d, &sources, o) {
        Ok(g) => {
            let a = g.advice;
            st.advice = Some(MapAdvice {
                report: a.report(),
                waypoint_ll: ll(&frame, a.waypoint),
                vehicle_ll: ll(&frame, vehicle),
                turn_ll: a.turn.map(|t| ll(&frame, t.at)),
                line: g.line_to(None),
                emitters: g.emitters,
                for_emitters: g.for_emitters,
            })
        }
        Err(e) => st.advice_error = Some(e),
    }
    st
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_units_ellipse_points_along_its_orientation() {
        let at = LatLon {
            lat: 47.0,
            lon: 8.0,
        };
        let ring = unit_ring(at, 400.0, 20.0, 90.0);
        assert_eq!(ring.len(), 73);
        // t = 0 lies on the major axis: 400 m east (90 deg clockwise from north).
        let frame = LocalFrame::new(at, 0.0).unwrap();
        let en = frame
            .to_local(LatLon {
                lat: ring[0][0],
                lon: ring[0][1],
            })
            .unwrap();
        assert!(
            (en[0] - 400.0).abs() < 0.01 && en[1].abs() < 0.01,
            "t = 0 at {en:?}"
        );
    }

    /// Run 0 of network condition `c` about 47.0, 8.0: its records decoded, its stations file.
    fn network_run(c: crate::runs::network::NetworkCondition) -> (Decoded, String) {
        let origin = LatLon {
            lat: 47.0,
            lon: 8.0,
        };
        let (bytes, toml, _) = crate::runs::network::capture(c, 0, origin).unwrap();
        let d = crate::inputs::capture::decode(&bytes, Default::default(), false);
        (d, toml)
    }

    /// The map once `d` has been decoded to its end, located as `o` says.
    fn map(d: &Decoded, o: &LocateOptions) -> MapState {
        let mut guide = Guide::new(None, 100.0).unwrap();
        let tracker = MapTracker::new(o.network.as_deref());
        build(d, 1, &[], &mut guide, &tracker, o, true)
    }

    #[test]
    fn every_station_is_on_the_map_with_its_latest_bearing_and_offset() {
        let (d, _) = network_run(crate::runs::network::NetworkCondition::Mobile);
        let st = map(&d, &LocateOptions::default());
        let ids: Vec<(&str, bool)> = st
            .stations
            .iter()
            .map(|s| (s.id.as_str(), s.fixed))
            .collect();
        assert_eq!(ids, [("mast-1", true), ("mast-2", true), ("car-1", false)]);
        for s in &st.stations {
            // The ray starts where the station stood and its offset is the fit's, a few degrees;
            // 600 bearings each (the car loses one to the yaw gate at its corner).
            assert_eq!(s.ray[0], s.at);
            assert!(
                s.offset_deg[0].abs() < 12.0 && s.offset_deg[1] > 0.0,
                "{s:?}"
            );
            assert!(s.bearings >= 595, "{s:?}");
        }
    }

    #[test]
    fn the_map_fixes_with_the_stations_file_and_its_references_as_locate_does() {
        // Three masts and a beacon they all hear: the stations file states each mast's noise
        // and prior, and the beacon calibrates them.
        let (d, toml) = network_run(crate::runs::network::NetworkCondition::Reference);
        let network = crate::inputs::stations::Network::from_text(&toml).unwrap();
        let o = LocateOptions {
            network: Some(std::sync::Arc::new(network)),
            ..LocateOptions::default()
        };
        let st = map(&d, &o);
        let located = crate::locate::locate(&d, &o).unwrap();
        // The map's emitter is `locate --stations`'s, to the bit.
        let (e, l) = (&st.emitters[0], &located.report.emitters[0]);
        assert_eq!(e.at, [l.lat, l.lon]);
        assert_eq!(e.cep50_m, l.cep50_m);
        // Every mast's offset as `locate` reports it, the beacon's calibration among them.
        assert_eq!(st.stations.len(), located.report.stations.len());
        for (m, r) in st.stations.iter().zip(&located.report.stations) {
            assert_eq!(
                (m.id.as_str(), m.offset_deg, m.offset_from),
                (
                    r.id.as_str(),
                    [r.offset_deg, r.offset_sd_deg],
                    r.offset_from
                )
            );
        }
        let priors: Vec<_> = located
            .report
            .stations
            .iter()
            .map(|r| r.prior_from)
            .collect();
        println!("priors {priors:?}");
        assert!(
            priors
                .iter()
                .all(|p| *p == crate::estimate::stations::PriorOrigin::Reference),
            "{priors:?}"
        );
        // Without the file the beacon's channel is an emitter of its own and no mast is
        // calibrated: the map is not the same.
        let plain = map(&d, &LocateOptions::default());
        assert!(plain.stations.iter().all(|s| s.offset_from != "reference"));
        assert_ne!(
            plain.emitters.len(),
            st.emitters.len(),
            "{:?}",
            plain.emitters
        );
    }

    #[test]
    fn a_direction_dependent_error_found_is_on_the_map() {
        // A unit whose error follows the direction relative to the vehicle, nothing stated:
        // `locate` finds it, and the map's station says so with its harmonics.
        let (bytes, _) = crate::runs::field::capture(
            crate::runs::field::Condition::DirectionUnstated,
            3,
            crate::runs::simulate::DEFAULT_ORIGIN,
        )
        .unwrap();
        let d = crate::inputs::capture::decode(&bytes, Default::default(), false);
        let o = LocateOptions::default();
        let st = map(&d, &o);
        let located = crate::locate::locate(&d, &o).unwrap();
        let want = located.report.stations[0]
            .direction_found
            .as_ref()
            .map(|f| f.amplitudes_deg);
        println!("found {want:?}");
        assert!(want.is_some());
        assert_eq!(st.stations[0].direction_found_deg, want);
    }

    #[test]
    fn an_open_range_is_drawn_as_its_region() {
        // Six 15 degree bearings on 300 m: no fix, a region; the page gets its wedge and words.
        let (bytes, truths) = crate::runs::field::capture(
            crate::runs::field::Condition::OpenNoisyFew,
            0,
            crate::runs::simulate::DEFAULT_ORIGIN,
        )
        .unwrap();
        let d = crate::inputs::capture::decode(&bytes, Default::default(), false);
        let st = map(&d, &LocateOptions::default());
        assert!(st.emitters.is_empty(), "{:?}", st.emitters);
        assert_eq!(st.regions.len(), 1, "{:?}", st.fix_error);
        let r = &st.regions[0];
        // A closed wedge from the apex (its range starts at 0) out to the rays' length.
        assert!(
            r.wedge.len() > 10 && r.wedge.first() == r.wedge.last(),
            "{r:?}"
        );
        assert_eq!(r.wedge[0], [r.report.lat, r.report.lon]);
        assert!(r.line.starts_with("the range is open"), "{}", r.line);
        assert_eq!(st.fix_error.as_deref(), Some(r.line.as_str()));
        // The truth (1200, 800) m lies 56 degrees from the route's start: within the wedge.
        let t = truths[0].position;
        let b = t[0].atan2(t[1]).to_degrees();
        assert!(
            (b - r.report.bearing_deg).abs() <= r.report.half_width_deg,
            "{r:?}"
        );
        let json = serde_json::to_string(&st).unwrap();
        assert!(json.contains("\"regions\":[{") && json.contains("\"wedge\""));
    }

    #[test]
    fn an_ellipse_beyond_drawing_is_left_undrawn() {
        let at = LatLon {
            lat: 47.0,
            lon: 8.0,
        };
        assert!(unit_ring(at, 1.0e12, 1.0, 0.0).is_empty());
        assert!(unit_ring(at, f32::NAN, 1.0, 0.0).is_empty());
        assert!(unit_ring(at, 10.0, 1.0, f32::INFINITY).is_empty());
    }
}
