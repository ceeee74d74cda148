//! The canonical scenarios' constants (docs/src/scenarios.md) that the no_std images need as much as
//! the host: the emitters, the bearing noise, the routes and the RSSI trackers. The bench, the
//! firmware image, the MCU step bench and the tests all read them from here.

use crate::model::rssi::{PathLoss, RssiTracker};
use core::f32::consts::TAU;

/// The emitter of aoa-afsa and aoa-drive, metres east and north.
pub const AOA_EMITTER: [f32; 2] = [1200.0, 800.0];
/// Their bearing noise variance, rad^2 (seed 002).
pub const AOA_BEARING_VAR: f32 = 3.801e-4;
/// Its square root, radians (about 1.117 degrees).
pub const AOA_SIGMA: f32 = 0.019_496;

/// Points of the loop300 route.
pub const LOOP300_POINTS: usize = 60;
/// Radius of the loop300 route, metres.
pub const LOOP300_RADIUS: f32 = 300.0;

/// Point `k` of loop300: 60 points evenly on a 300 m circle about `emitter`, from the circle's
/// point nearest the origin, counter-clockwise (k wraps around the circle).
pub fn loop300(emitter: [f32; 2], k: usize) -> [f32; 2] {
    let start = libm::atan2f(-emitter[1], -emitter[0]);
    let a = start + TAU * (k % LOOP300_POINTS) as f32 / LOOP300_POINTS as f32;
    [
        emitter[0] + LOOP300_RADIUS * libm::cosf(a),
        emitter[1] + LOOP300_RADIUS * libm::sinf(a),
    ]
}

/// Points of the L600 and line600 routes.
pub const ROUTE600_POINTS: usize = 60;

/// Point `k` (0..60) of L600: 30 points east from (0, 0) at 10 m, then 30 north at x = 290.
pub fn l600(k: usize) -> [f32; 2] {
    if k < 30 {
        [10.0 * k as f32, 0.0]
    } else {
        [290.0, 10.0 * (k - 29) as f32]
    }
}

/// Point `k` of line600: east from (0, 0) at 10 m spacing.
pub fn line600(k: usize) -> [f32; 2] {
    [10.0 * k as f32, 0.0]
}

/// The indoor path loss of seed 003: -37.8 dBm at 1 m, exponent 2.3.
pub const RSSI_PATH_LOSS: PathLoss = PathLoss {
    p0: -37.8,
    d0: 1.0,
    eta: 2.3,
};

/// Process noise of the constant-velocity node, [x, vx, y, vy].
pub const RSSI_Q: [f32; 4] = [0.5, 1.0, 0.5, 1.0];

/// rssi-sim: a 10 x 10 m room, three anchors, 0.5 dB noise, 0.5 s epochs.
pub const RSSI_SIM: RssiTracker<3> = RssiTracker {
    anchors: [[0.0, 5.0], [5.0, 10.0], [10.0, 0.0]],
    sigma: [0.5; 3],
    path_loss: RSSI_PATH_LOSS,
    dt: 0.5,
    q: RSSI_Q,
    room: Some([10.0, 10.0]),
};
/// rssi-sim's initial state [x, vx, y, vy].
pub const RSSI_SIM_START: [f32; 4] = [0.0, 0.5, 0.0, 0.5];

/// rssi-lab: a 6 x 6 m room, three anchors, sqrt(3) dB noise.
pub const RSSI_LAB: RssiTracker<3> = RssiTracker {
    anchors: [[0.0, 3.0], [3.0, 6.0], [6.0, 0.0]],
    sigma: [1.732_050_8; 3],
    path_loss: RSSI_PATH_LOSS,
    dt: 0.5,
    q: RSSI_Q,
    room: Some([6.0, 6.0]),
};
/// rssi-lab's initial state.
pub const RSSI_LAB_START: [f32; 4] = [0.0, 0.4, 0.0, 0.4];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sigmas_are_the_roots_of_the_variances() {
        assert!((AOA_SIGMA * AOA_SIGMA - AOA_BEARING_VAR).abs() < 1e-8);
        assert_eq!(RSSI_LAB.sigma[0], libm::sqrtf(3.0));
    }

    #[test]
    fn routes_have_their_shapes() {
        assert_eq!(l600(29), [290.0, 0.0]);
        assert_eq!(l600(30), [290.0, 10.0]);
        assert_eq!(l600(59), [290.0, 300.0]);
        let p = loop300(AOA_EMITTER, 0);
        let r = libm::hypotf(p[0] - AOA_EMITTER[0], p[1] - AOA_EMITTER[1]);
        assert!((r - 300.0).abs() < 1e-3);
        // The start is the point nearest the origin.
        assert!(libm::hypotf(p[0], p[1]) < libm::hypotf(AOA_EMITTER[0], AOA_EMITTER[1]) - 299.0);
    }
}
