//! df-aggregator's algorithm, written from its description (docs/src/networks.md), as the
//! peer row of the network bench: what a user of that project would get from the same
//! bearings.
//!
//! 1. Each cycle (a second) takes every receiver's latest record on the channel. Every pair of
//!    receivers whose records are within 5 s of each other has its lines of bearing crossed;
//!    a crossing is kept when it lies ahead of the first receiver (within 5 degrees of its
//!    bearing, so not the crossing behind it) and within 100 km. A cycle's crossings are
//!    averaged, confidence-weighted (every record here has the same confidence), into one
//!    point.
//! 2. A single moving receiver (the channel's only one) crosses its current line with its own
//!    lines of the last 20 minutes that are at least 10 s old, taken at least 500 m away and
//!    more than 5 degrees different; each kept crossing is a point of its own.
//! 3. DBSCAN over the points normalised (each axis to zero mean and unit sd): min_samples
//!    5 % of the points (at least 2), eps the knee of the sorted distances to each point's
//!    min_samples-th nearest neighbour (the point of the sorted curve farthest from the chord
//!    joining its ends).
//! 4. The largest cluster's mean is the likely location; its "3 sigma" ellipse is 3 times the
//!    square root of the eigenvalues of the cluster's point covariance (here in metres; the
//!    original works in degrees of latitude and longitude, which only stretches it).
//!
//! Lines are crossed in the plane of the drive's local frame: at the 6-10 km of these
//! networks the great circles and the plane's lines differ by well under a metre.

use foxhunt_core::fix::locate::Observation;

/// A kept crossing's distance limit, metres.
const MAX_RANGE: f32 = 100_000.0;
/// A crossing must lie within this of the first line's bearing, radians.
const AHEAD: f32 = 5.0 * core::f32::consts::PI / 180.0;
/// Records further apart than this are not paired, seconds.
const PAIR_WINDOW: f32 = 5.0;

/// What the peer answers: the cluster mean and its point covariance, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeerFix {
    /// The largest cluster's mean, local metres.
    pub position: [f32; 2],
    /// The cluster's point covariance, m^2.
    pub covariance: [[f32; 2]; 2],
    /// Points in the cluster.
    pub points: usize,
    /// Crossings clustered.
    pub crossings: usize,
}

impl PeerFix {
    /// Whether `truth` lies inside the "3 sigma" ellipse (Mahalanobis distance at most 3).
    pub fn holds(&self, truth: &[f32; 2]) -> bool {
        foxhunt_core::fix::ellipse::mahalanobis(&self.covariance, &self.position, truth)
            .is_some_and(|m| m <= 3.0)
    }

    /// The ellipse's semi-major axis, metres.
    pub fn major(&self) -> f32 {
        let [[a, b], [_, d]] = self.covariance;
        let half = 0.5 * (a + d);
        let root = (0.25 * (a - d) * (a - d) + b * b).sqrt();
        3.0 * (half + root).max(0.0).sqrt()
    }
}

/// Where two lines of bearing cross, if ahead of the first within [`AHEAD`] and in range.
fn cross(a: &Observation, b: &Observation) -> Option<[f32; 2]> {
    let (pa, pb) = (a.bearing.vehicle, b.bearing.vehicle);
    let da = [a.bearing.theta.cos(), a.bearing.theta.sin()];
    let db = [b.bearing.theta.cos(), b.bearing.theta.sin()];
    let det = da[0] * (-db[1]) - da[1] * (-db[0]);
    if det.abs() < 1e-6 {
        return None;
    }
    let r = [pb[0] - pa[0], pb[1] - pa[1]];
    let s = (r[0] * (-db[1]) - r[1] * (-db[0])) / det;
    let p = [pa[0] + s * da[0], pa[1] + s * da[1]];
    let to = (p[1] - pa[1]).atan2(p[0] - pa[0]);
    let off = foxhunt_core::model::bearing::wrap(to - a.bearing.theta).abs();
    let range = (p[0] - pa[0]).hypot(p[1] - pa[1]);
    (s > 0.0 && off <= AHEAD && range <= MAX_RANGE).then_some(p)
}

/// The points df-aggregator clusters from one channel's observations (time order):
/// each cycle's averaged pair crossings, or a single moving receiver's crossings with its own
/// past.
pub fn points(observations: &[Observation], moving: &[bool]) -> Vec<[f32; 2]> {
    let mut out = Vec::new();
    // Each receiver's latest record, updated a cycle (a whole second) at a time.
    let stations = moving.len();
    let mut latest: Vec<Option<Observation>> = vec![None; stations];
    let mut history: Vec<Vec<Observation>> = vec![Vec::new(); stations];
    let mut i = 0;
    while i < observations.len() {
        let cycle = observations[i].time_s.floor();
        let mut fresh = Vec::new();
        while i < observations.len() && observations[i].time_s.floor() == cycle {
            let o = observations[i];
            if let Some(slot) = latest.get_mut(usize::from(o.station)) {
                *slot = Some(o);
                fresh.push(o);
            }
            i += 1;
        }
        // Pairs of receivers' latest records.
        let mut sum = [0.0f32; 2];
        let mut n = 0usize;
        for a in 0..stations {
            for b in a + 1..stations {
                let (Some(ra), Some(rb)) = (latest[a], latest[b]) else {
                    continue;
                };
                if (ra.time_s - rb.time_s).abs() > PAIR_WINDOW
                    || cycle - ra.time_s.max(rb.time_s) > PAIR_WINDOW
                {
                    continue;
                }
                if let Some(p) = cross(&ra, &rb) {
                    sum[0] += p[0];
                    sum[1] += p[1];
                    n += 1;
                }
            }
        }
        if n > 0 {
            out.push([sum[0] / n as f32, sum[1] / n as f32]);
        }
        // A single moving receiver against its own past lines.
        for o in fresh {
            let s = usize::from(o.station);
            if stations != 1 || !moving[s] {
                continue;
            }
            for old in history[s].iter().rev() {
                let age = o.time_s - old.time_s;
                if age > 1200.0 {
                    break;
                }
                let apart = (o.bearing.vehicle[0] - old.bearing.vehicle[0])
                    .hypot(o.bearing.vehicle[1] - old.bearing.vehicle[1]);
                let turn = foxhunt_core::model::bearing::wrap(o.bearing.theta - old.bearing.theta);
                if age >= 10.0
                    && apart >= 500.0
                    && turn.abs() > AHEAD
                    && let Some(p) = cross(&o, old)
                {
                    out.push(p);
                }
            }
            history[s].push(o);
        }
    }
    out
}

/// DBSCAN's labels: the cluster of each point, `None` for noise.
fn dbscan(points: &[[f32; 2]], eps: f32, min_samples: usize) -> Vec<Option<usize>> {
    let n = points.len();
    let near = |i: usize| -> Vec<usize> {
        (0..n)
            .filter(|&j| (points[i][0] - points[j][0]).hypot(points[i][1] - points[j][1]) <= eps)
            .collect()
    };
    let mut label: Vec<Option<usize>> = vec![None; n];
    let mut visited = vec![false; n];
    let mut clusters = 0;
    for i in 0..n {
        if visited[i] {
            continue;
        }
        visited[i] = true;
        let seeds = near(i);
        if seeds.len() < min_samples {
            continue;
        }
        label[i] = Some(clusters);
        let mut queue = seeds;
        while let Some(j) = queue.pop() {
            if label[j].is_none() {
                label[j] = Some(clusters);
            }
            if visited[j] {
                continue;
            }
            visited[j] = true;
            let more = near(j);
            if more.len() >= min_samples {
                queue.extend(
                    more.into_iter()
                        .filter(|&k| !visited[k] || label[k].is_none()),
                );
            }
        }
        clusters += 1;
    }
    label
}

/// The knee of an ascending curve: the value farthest from the chord joining its ends.
fn knee(sorted: &[f32]) -> Option<f32> {
    let (first, last) = (*sorted.first()?, *sorted.last()?);
    let n = (sorted.len() - 1).max(1) as f32;
    // Both axes scaled to [0, 1], as a knee finder does.
    let span = (last - first).max(f32::MIN_POSITIVE);
    sorted
        .iter()
        .enumerate()
        .map(|(i, &y)| (i as f32 / n - (y - first) / span, y))
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, y)| y)
}

/// The peer's answer from one channel's observations (`moving`: which stations move), or
/// `None` when it finds no cluster.
pub fn locate(observations: &[Observation], moving: &[bool]) -> Option<PeerFix> {
    let pts = points(observations, moving);
    let n = pts.len();
    if n < 2 {
        return None;
    }
    // Normalised: each axis to zero mean, unit sd.
    let mean = |k: usize| pts.iter().map(|p| f64::from(p[k])).sum::<f64>() / n as f64;
    let (mx, my) = (mean(0), mean(1));
    let sd = |k: usize, m: f64| {
        (pts.iter()
            .map(|p| (f64::from(p[k]) - m).powi(2))
            .sum::<f64>()
            / n as f64)
            .sqrt()
            .max(1e-9)
    };
    let (sx, sy) = (sd(0, mx), sd(1, my));
    let z: Vec<[f32; 2]> = pts
        .iter()
        .map(|p| {
            [
                ((f64::from(p[0]) - mx) / sx) as f32,
                ((f64::from(p[1]) - my) / sy) as f32,
            ]
        })
        .collect();
    let min_samples = (n / 20).max(2);
    let mut kth: Vec<f32> = z
        .iter()
        .map(|a| {
            let mut d: Vec<f32> = z.iter().map(|b| (a[0] - b[0]).hypot(a[1] - b[1])).collect();
            // The point itself is its own nearest neighbour, as in scikit-learn's search.
            let k = min_samples.min(n - 1);
            *d.select_nth_unstable_by(k, f32::total_cmp).1
        })
        .collect();
    kth.sort_by(f32::total_cmp);
    let eps = knee(&kth)?;
    if !(eps > 0.0) {
        return None;
    }
    let labels = dbscan(&z, eps, min_samples);
    let clusters = labels.iter().flatten().max().map_or(0, |m| m + 1);
    let biggest =
        (0..clusters).max_by_key(|c| labels.iter().filter(|l| **l == Some(*c)).count())?;
    let member: Vec<[f32; 2]> = pts
        .iter()
        .zip(&labels)
        .filter(|(_, l)| **l == Some(biggest))
        .map(|(p, _)| *p)
        .collect();
    let m = member.len() as f64;
    let cx = member.iter().map(|p| f64::from(p[0])).sum::<f64>() / m;
    let cy = member.iter().map(|p| f64::from(p[1])).sum::<f64>() / m;
    let (mut xx, mut xy, mut yy) = (0.0, 0.0, 0.0);
    for p in &member {
        let (dx, dy) = (f64::from(p[0]) - cx, f64::from(p[1]) - cy);
        xx += dx * dx;
        xy += dx * dy;
        yy += dy * dy;
    }
    // numpy's cov: the sample covariance (m - 1).
    let d = (m - 1.0).max(1.0);
    Some(PeerFix {
        position: [cx as f32, cy as f32],
        covariance: [
            [(xx / d) as f32, (xy / d) as f32],
            [(xy / d) as f32, (yy / d) as f32],
        ],
        points: member.len(),
        crossings: n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use foxhunt_core::model::bearing::{Bearing, predicted};

    fn obs(at: [f32; 2], target: [f32; 2], t: f32, station: u16, error: f32) -> Observation {
        Observation {
            station,
            ..Observation::new(
                Bearing {
                    vehicle: at,
                    theta: predicted(&target, &at) + error,
                    sigma: 0.02,
                },
                t,
            )
        }
    }

    #[test]
    fn crossings_behind_a_station_are_not_kept() {
        let a = obs([0.0, 0.0], [1000.0, 1000.0], 0.0, 0, 0.0);
        let b = obs([2000.0, 0.0], [1000.0, 1000.0], 0.0, 1, 0.0);
        let p = cross(&a, &b).expect("ahead of both");
        assert!((p[0] - 1000.0).abs() < 0.5 && (p[1] - 1000.0).abs() < 0.5);
        // The same lines pointed away from each other cross behind the first.
        let mut away = a;
        away.bearing.theta += core::f32::consts::PI;
        assert!(cross(&away, &b).is_none());
    }

    #[test]
    fn three_clean_stations_cluster_on_the_emitter() {
        let e = [300.0, -200.0];
        let masts = [[-6000.0, 0.0], [4000.0, 5000.0], [3000.0, -7000.0]];
        // Small scattered errors (up to 0.15 degrees) spread the crossings round the emitter.
        let mut state = 12345u32;
        let mut o = Vec::new();
        for t in 0..100 {
            for (s, m) in masts.iter().enumerate() {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let err = ((state >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * 0.005;
                o.push(obs(*m, e, t as f32, s as u16, err));
            }
        }
        let f = locate(&o, &[false; 3]).expect("a cluster");
        assert!(
            (f.position[0] - e[0]).hypot(f.position[1] - e[1]) < 30.0,
            "{:?}",
            f.position
        );
        assert!(f.holds(&e));
    }

    #[test]
    fn the_knee_is_where_the_curve_turns() {
        let mut c: Vec<f32> = (0..90).map(|i| 0.01 * i as f32).collect();
        c.extend((0..10).map(|i| 1.0 + i as f32));
        assert!((knee(&c).unwrap() - 0.89).abs() < 0.02, "{:?}", knee(&c));
    }
}
