//! Where the vehicle can go: a move is a [`Leg`], the moves from a state are a [`Reach`];
//! [`FreeHeadings`] is open terrain (a road graph is another [`Reach`], on the host).

use core::f32::consts::{PI, TAU};

/// A stretch of driving.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    /// Where it starts, metres.
    pub from: [f32; 2],
    /// Where it ends, metres.
    pub to: [f32; 2],
    /// How long it takes, seconds (> 0).
    pub seconds: f32,
}

impl Leg {
    /// Its length, metres.
    pub fn length(&self) -> f32 {
        libm::hypotf(self.to[0] - self.from[0], self.to[1] - self.from[1])
    }

    /// Its direction, radians counter-clockwise from east.
    pub fn heading(&self) -> f32 {
        libm::atan2f(self.to[1] - self.from[1], self.to[0] - self.from[0])
    }

    /// The first `share` (0..1) of it.
    pub(super) fn part(&self, share: f32) -> Leg {
        Leg {
            from: self.from,
            to: [
                self.from[0] + share * (self.to[0] - self.from[0]),
                self.from[1] + share * (self.to[1] - self.from[1]),
            ],
            seconds: share * self.seconds,
        }
    }
}

/// Where the vehicle can go from a state (a position and heading, a road node and the edge it
/// came by...).
pub trait Reach {
    /// What the planner needs to know to continue from the end of a move.
    type State: Copy;
    /// Call `each` with every move from `state`: the state at its end and the leg.
    fn moves(&self, state: &Self::State, each: &mut dyn FnMut(Self::State, Leg));
}

/// Free headings in open terrain: legs of a fixed length in `count` evenly spaced directions,
/// those within `max_turn` of the current heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreeHeadings {
    /// Directions (at most 64).
    pub count: u32,
    /// Length of a leg, metres.
    pub leg_m: f32,
    /// Speed, m/s.
    pub speed: f32,
    /// Largest turn at the start of a leg, radians (pi: any direction, a U-turn included).
    pub max_turn: f32,
}

/// A free-heading state: where the vehicle is and which way it points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Position, metres.
    pub position: [f32; 2],
    /// Heading, radians counter-clockwise from east.
    pub heading: f32,
}

impl Reach for FreeHeadings {
    type State = Pose;
    fn moves(&self, state: &Pose, each: &mut dyn FnMut(Pose, Leg)) {
        if !(self.speed > 0.0) || !(self.leg_m > 0.0) {
            return;
        }
        let count = self.count.clamp(1, 64);
        for k in 0..count {
            let h = TAU * k as f32 / count as f32;
            let turn = libm::fabsf(crate::model::bearing::wrap(h - state.heading));
            if turn > self.max_turn + 1e-4 {
                continue;
            }
            let to = [
                state.position[0] + self.leg_m * libm::cosf(h),
                state.position[1] + self.leg_m * libm::sinf(h),
            ];
            each(
                Pose {
                    position: to,
                    heading: h,
                },
                Leg {
                    from: state.position,
                    to,
                    seconds: self.leg_m / self.speed,
                },
            );
        }
    }
}

impl Default for FreeHeadings {
    fn default() -> Self {
        Self {
            count: 16,
            leg_m: 300.0,
            speed: 15.0,
            max_turn: PI,
        }
    }
}
