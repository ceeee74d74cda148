//! Moves on a road graph for the core's planner: from a node, every road out of it but the one
//! the vehicle came by (a U-turn only at a dead end), each leg the straight chord between two
//! graph nodes driven at the road's speed.

use crate::inputs::roads::RoadGraph;
use foxhunt_core::guidance::plan::{Leg, Reach};
use foxhunt_core::model::bearing::wrap;

/// Where a vehicle is on the graph: at `node`, having come from `from`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OnRoad {
    /// The node the vehicle is at.
    pub node: u32,
    /// The node it came from (`None` at the start).
    pub from: Option<u32>,
}

/// The graph as a [`Reach`].
#[derive(Debug, Clone, Copy)]
pub struct Roads<'a>(pub &'a RoadGraph);

impl Roads<'_> {
    /// The moves from `at`: (next node, leg).
    pub fn options(&self, at: &OnRoad) -> Vec<(OnRoad, Leg)> {
        let mut v = Vec::new();
        self.moves(at, &mut |s, l| v.push((s, l)));
        v
    }

    /// The move whose direction is nearest `heading` (radians from east), with the change of
    /// direction it takes.
    pub fn nearest_heading(&self, at: &OnRoad, heading: f32) -> Option<(OnRoad, Leg)> {
        self.options(at).into_iter().min_by(|a, b| {
            let da = wrap(a.1.heading() - heading).abs();
            let db = wrap(b.1.heading() - heading).abs();
            da.total_cmp(&db)
        })
    }
}

impl Reach for Roads<'_> {
    type State = OnRoad;
    fn moves(&self, state: &OnRoad, each: &mut dyn FnMut(OnRoad, Leg)) {
        let g = self.0;
        let Some(from) = g.position(state.node) else {
            return;
        };
        let out = g.out(state.node);
        let dead_end = out.iter().all(|e| Some(e.to) == state.from);
        for e in out {
            if Some(e.to) == state.from && !dead_end {
                continue;
            }
            let Some(to) = g.position(e.to) else {
                continue;
            };
            each(
                OnRoad {
                    node: e.to,
                    from: Some(state.node),
                },
                Leg {
                    from,
                    to,
                    seconds: e.length_m / e.speed,
                },
            );
        }
    }
}

/// How near a node (metres) the vehicle counts as at it rather than on a road between two.
const AT_NODE_M: f32 = 15.0;

/// Where a vehicle at `position` heading `heading` (radians from east) joins the graph. Between
/// two junctions: the end of the road it is on that lies ahead, having come from the other
/// end, so the next turn is never one already passed. At a junction (or with no heading): that
/// node, having come from its neighbour that lies most behind the vehicle.
pub fn join(g: &RoadGraph, position: [f32; 2], heading: Option<f32>) -> Option<OnRoad> {
    let node = g.nearest(position)?;
    let at_node = g
        .position(node)
        .is_some_and(|p| (p[0] - position[0]).hypot(p[1] - position[1]) < AT_NODE_M);
    if let (false, Some(h)) = (at_node, heading)
        && let Some((a, b)) = g.nearest_segment(position)
    {
        let off = |n: u32| {
            g.position(n).map_or(f32::INFINITY, |q| {
                wrap((q[1] - position[1]).atan2(q[0] - position[0]) - h).abs()
            })
        };
        let (ahead, behind) = if off(a) <= off(b) { (a, b) } else { (b, a) };
        return Some(OnRoad {
            node: ahead,
            from: Some(behind),
        });
    }
    let from = heading.and_then(|h| {
        let p = g.position(node)?;
        g.out(node)
            .iter()
            .filter_map(|e| {
                let q = g.position(e.to)?;
                let back = (p[1] - q[1]).atan2(p[0] - q[0]);
                Some((e.to, wrap(back - h).abs()))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .filter(|(_, d)| *d < std::f32::consts::FRAC_PI_2)
            .map(|(n, _)| n)
    });
    Some(OnRoad { node, from })
}
