//! The benchmark's terrains: open ground (no roads) and three synthetic road networks made here,
//! each about 18 km across, so a start 3-5 km from the emitter has room on every side.
//!
//! - `grid`: a Manhattan grid, 300 m blocks, 12 m/s.
//! - `highway`: an east-west highway (30 m/s) with exits every 2 km; at each exit a side road
//!   north and south (15 m/s, a node every 400 m), joined by country roads every 4 km north and
//!   south of the highway: the only way across the highway is at an exit.
//! - `river`: a 400 m grid (12 m/s) cut north-south by a river at x = 0 that two bridges cross,
//!   4 km south and 3.2 km north of the centre.

use crate::inputs::roads::{RoadGraph, Segment};

/// Half the width of every network, metres.
pub const HALF_M: f32 = 9000.0;

/// Where the benchmark drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Network {
    /// Open terrain: free headings.
    Open,
    /// Manhattan grid.
    Grid,
    /// Highway with exits and side roads.
    Highway,
    /// A river with two bridges.
    River,
}

impl Network {
    /// Every network, in report order.
    pub const ALL: [Network; 4] = [
        Network::Open,
        Network::Grid,
        Network::Highway,
        Network::River,
    ];

    /// Its name in scenario names.
    pub fn name(&self) -> &'static str {
        match self {
            Network::Open => "open",
            Network::Grid => "grid",
            Network::Highway => "highway",
            Network::River => "river",
        }
    }

    /// By name.
    pub fn from_name(s: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|n| n.name() == s)
    }

    /// Its road graph (`None` for open terrain).
    pub fn graph(&self) -> Option<RoadGraph> {
        match self {
            Network::Open => None,
            Network::Grid => Some(grid(300.0, 12.0, |_, _| true)),
            Network::River => Some(grid(400.0, 12.0, |a, b| {
                // Crossing x = 0 only on the bridges.
                let crosses = (a[0] < 0.0) != (b[0] < 0.0);
                !crosses || [-4000.0f32, 3200.0].iter().any(|y| (a[1] - y).abs() < 1.0)
            })),
            Network::Highway => Some(highway()),
        }
    }
}

/// A square grid of `spacing` (centred on the origin, at half-spacing offsets so nothing sits on
/// x = 0) keeping the links `keep` allows.
fn grid(spacing: f32, speed: f32, keep: impl Fn([f32; 2], [f32; 2]) -> bool) -> RoadGraph {
    let n = (2.0 * HALF_M / spacing) as i32;
    let at = |i: i32| -HALF_M + spacing * (i as f32 + 0.5);
    let mut positions = Vec::new();
    for j in 0..n {
        for i in 0..n {
            positions.push([at(i), at(j)]);
        }
    }
    let id = |i: i32, j: i32| (j * n + i) as u32;
    let mut segments: Vec<Segment> = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let p = [at(i), at(j)];
            if i + 1 < n && keep(p, [at(i + 1), at(j)]) {
                segments.push((id(i, j), id(i + 1, j), speed, true));
            }
            if j + 1 < n && keep(p, [at(i), at(j + 1)]) {
                segments.push((id(i, j), id(i, j + 1), speed, true));
            }
        }
    }
    RoadGraph::new(positions, &segments)
}

fn highway() -> RoadGraph {
    const EXIT_M: f32 = 2000.0;
    const STEP_M: f32 = 400.0;
    const COUNTRY_M: f32 = 4000.0;
    let mut positions: Vec<[f32; 2]> = Vec::new();
    let mut index = std::collections::HashMap::new();
    let mut node = |p: [f32; 2], positions: &mut Vec<[f32; 2]>| -> u32 {
        let key = ((p[0] * 10.0).round() as i64, (p[1] * 10.0).round() as i64);
        *index.entry(key).or_insert_with(|| {
            positions.push(p);
            (positions.len() - 1) as u32
        })
    };
    let mut segments: Vec<Segment> = Vec::new();
    let exits: Vec<f32> = (0..)
        .map(|k| -8000.0 + EXIT_M * k as f32)
        .take_while(|x| *x <= 8000.0)
        .collect();
    for w in exits.windows(2) {
        let a = node([w[0], 0.0], &mut positions);
        let b = node([w[1], 0.0], &mut positions);
        segments.push((a, b, 30.0, true));
    }
    let steps = (HALF_M / STEP_M) as i32;
    for x in &exits {
        for sign in [-1.0f32, 1.0] {
            let mut last = node([*x, 0.0], &mut positions);
            for k in 1..=steps {
                let n = node([*x, sign * STEP_M * k as f32], &mut positions);
                segments.push((last, n, 15.0, true));
                last = n;
            }
        }
    }
    // Country roads parallel to the highway, joining the side roads.
    for y in [-2.0 * COUNTRY_M, -COUNTRY_M, COUNTRY_M, 2.0 * COUNTRY_M] {
        for w in exits.windows(2) {
            let mut last = node([w[0], y], &mut positions);
            let parts = (EXIT_M / STEP_M) as i32;
            for k in 1..=parts {
                let n = node([w[0] + STEP_M * k as f32, y], &mut positions);
                segments.push((last, n, 15.0, true));
                last = n;
            }
        }
    }
    RoadGraph::new(positions, &segments)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Nodes reachable from `start`.
    fn reachable(g: &RoadGraph, start: u32) -> usize {
        let mut seen = vec![false; g.len()];
        let mut stack = vec![start];
        while let Some(n) = stack.pop() {
            if std::mem::replace(&mut seen[n as usize], true) {
                continue;
            }
            stack.extend(g.out(n).iter().map(|e| e.to));
        }
        seen.iter().filter(|s| **s).count()
    }

    #[test]
    fn networks_are_connected_and_the_river_has_two_bridges() {
        for net in [Network::Grid, Network::Highway, Network::River] {
            let g = net.graph().unwrap();
            assert_eq!(reachable(&g, 0), g.len(), "{}", net.name());
        }
        let g = Network::River.graph().unwrap();
        let crossings = g
            .segments()
            .filter(|(a, b)| {
                let (p, q) = (g.position(*a).unwrap(), g.position(*b).unwrap());
                (p[0] < 0.0) != (q[0] < 0.0)
            })
            .count();
        assert_eq!(crossings, 2);
        assert!(Network::Open.graph().is_none());
        assert_eq!(Network::from_name("highway"), Some(Network::Highway));
    }
}
