//! The indoor angle-of-arrival scenario (docs/src/tracking.md): a person with a Bluetooth 5.1
//! tag walking a 16 m x 12 m room, four anchors at the walls' middles looking in (boresights
//! 0, 90, 180 and 270 degrees), each reporting 37 angles a second with the error traits of
//! real arrays:
//!
//! - noise: each anchor its own sd, 10, 12, 14 and 16 degrees (told to the trackers, as a
//!   calibration would, widened by [`REPORT_SD_FACTOR`]);
//! - bias: each anchor's offset drawn per run uniformly in -5..+7.5 degrees (the trackers'
//!   prior: that interval's mean, and its sd widened by [`OFFSET_SD_FACTOR`]);
//! - compression: beyond a knee drawn per run and anchor in 40..60 degrees off boresight, the
//!   reported angle is pulled toward boresight, the pull growing over 20 degrees to 19 degrees
//!   (not modelled by any tracker);
//! - quantisation: the angle off boresight reported in 2 degree steps.
//!
//! Each trait can be turned off ([`AoaErrors`]) to find which one costs what.

use foxhunt_core::fix::device::{DeviceClass, TrackTraits};
use foxhunt_core::model::bearing::wrap;
use foxhunt_core::random;
use rand_core::Rng;
use std::f32::consts::{FRAC_PI_2, PI};

const DEG: f32 = PI / 180.0;

/// The room, [width, depth] metres from (0, 0).
pub const ROOM: [f32; 2] = [16.0, 12.0];
/// The walker's speed, m/s.
pub const WALK_SPEED: f32 = 1.2;
/// Reports per second per anchor.
pub const RATE_HZ: f32 = 37.0;
/// Each anchor's bearing noise sd, degrees.
pub const NOISE_DEG: [f32; 4] = [10.0, 12.0, 14.0, 16.0];
/// The interval each anchor's bias is drawn from, degrees.
pub const BIAS_DEG: [f32; 2] = [-5.0, 7.5];
/// The interval each anchor's compression knee is drawn from, degrees off boresight.
pub const KNEE_DEG: [f32; 2] = [40.0, 60.0];
/// How many times its noise sd the trackers give each report: the indoor array class's
/// ([`DeviceClass::track`]). The compression is an error that stays while the walker stays
/// near one place, so reports 27 ms apart are not independent; trusting each as if it were
/// gave ellipses that held the walker 68 % of the time (docs/src/tracking.md). Chosen on
/// this scenario with [`OFFSET_SD_FACTOR`] and [`MEMORY_S`].
pub const REPORT_SD_FACTOR: f32 = CLASS.report_sd_factor;
/// What the class of indoor arrays tells a track.
const CLASS: TrackTraits = DeviceClass::IndoorAoa.track();
/// How many times the bias interval's sd the trackers' offset prior is: the offsets also
/// take up the compression, which depends on where the walker is.
pub const OFFSET_SD_FACTOR: f32 = 2.0;
/// Seconds in which the trackers' offsets forget, the class's (the outdoor 1 500 s would
/// hold on to a compression the walker has since left).
pub const MEMORY_S: Option<f32> = CLASS.memory_s;

/// The sd the trackers give a report of anchor `a`, radians.
pub fn tracked_sd(a: usize) -> f32 {
    REPORT_SD_FACTOR * NOISE_DEG[a] * DEG
}

/// The compression's full pull toward boresight, degrees.
pub const PULL_DEG: f32 = 19.0;
/// Degrees off the knee over which the pull grows to its full size.
pub const RAMP_DEG: f32 = 20.0;
/// The reported angle's step, degrees.
pub const STEP_DEG: f32 = 2.0;

/// The anchors: where each sits and where it looks (radians, east = 0, anticlockwise).
pub const ANCHORS: [([f32; 2], f32); 4] = [
    ([0.0, ROOM[1] / 2.0], 0.0),
    ([ROOM[0] / 2.0, 0.0], FRAC_PI_2),
    ([ROOM[0], ROOM[1] / 2.0], PI),
    ([ROOM[0] / 2.0, ROOM[1]], 3.0 * FRAC_PI_2),
];

/// Which of the arrays' error traits a run has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AoaErrors {
    /// Random noise of each anchor's sd.
    pub noise: bool,
    /// A per-anchor bias.
    pub bias: bool,
    /// Compression toward boresight.
    pub compression: bool,
    /// 2 degree steps.
    pub quantise: bool,
}

impl AoaErrors {
    /// Every trait, as the real arrays.
    pub const ALL: AoaErrors = AoaErrors {
        noise: true,
        bias: true,
        compression: true,
        quantise: true,
    };
}

/// The trackers' prior of each anchor's offset: the mean of the uniform the bias is drawn
/// from, and [`OFFSET_SD_FACTOR`] times its sd.
pub fn bias_prior() -> (f32, f32) {
    let [lo, hi] = BIAS_DEG;
    (
        (lo + hi) / 2.0 * DEG,
        OFFSET_SD_FACTOR * (hi - lo) / 12f32.sqrt() * DEG,
    )
}

/// One run's draws of an anchor: its bias and its compression knee, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnchorDraw {
    /// Added to every angle.
    pub bias: f32,
    /// Off-boresight angle where the pull starts.
    pub knee: f32,
}

impl AnchorDraw {
    /// Draws an anchor's bias and knee (both drawn whatever `errors` says, so turning a trait
    /// off leaves the others' draws as they were).
    pub fn draw<R: Rng>(rng: &mut R, errors: &AoaErrors) -> Self {
        let bias = random::uniform_in(rng, BIAS_DEG[0], BIAS_DEG[1]) * DEG;
        let knee = random::uniform_in(rng, KNEE_DEG[0], KNEE_DEG[1]) * DEG;
        Self {
            bias: if errors.bias { bias } else { 0.0 },
            knee,
        }
    }
}

/// The angle anchor `a` reports for the true bearing `theta` (radians), drawing its noise
/// from `rng` (drawn whatever `errors` says, for the same reason as [`AnchorDraw::draw`]).
pub fn report<R: Rng>(
    rng: &mut R,
    a: usize,
    theta: f32,
    draw: &AnchorDraw,
    errors: &AoaErrors,
) -> f32 {
    let boresight = ANCHORS[a].1;
    let z = NOISE_DEG[a] * DEG * random::normal(rng);
    let mut off = wrap(theta - boresight) + draw.bias + if errors.noise { z } else { 0.0 };
    if errors.compression {
        off = compress(off, draw.knee);
    }
    if errors.quantise {
        let step = STEP_DEG * DEG;
        off = (off / step).round() * step;
    }
    wrap(boresight + off)
}

/// The array's compression: beyond `knee` off boresight the angle is pulled toward it, the
/// pull growing linearly over [`RAMP_DEG`] to [`PULL_DEG`].
pub fn compress(off: f32, knee: f32) -> f32 {
    let beyond = off.abs() - knee;
    if beyond <= 0.0 {
        return off;
    }
    let pull = PULL_DEG * DEG * (beyond / (RAMP_DEG * DEG)).min(1.0);
    off.signum() * (off.abs() - pull)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;

    #[test]
    fn compression_pulls_toward_boresight_beyond_the_knee_only() {
        let knee = 50.0 * DEG;
        assert_eq!(compress(30.0 * DEG, knee), 30.0 * DEG);
        assert!((compress(-80.0 * DEG, knee) + 61.0 * DEG).abs() < 1e-5);
        assert!((compress(60.0 * DEG, knee) - 50.5 * DEG).abs() < 1e-5);
    }

    #[test]
    fn reports_are_quantised_and_biased() {
        let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(7);
        let errors = AoaErrors {
            noise: false,
            compression: false,
            ..AoaErrors::ALL
        };
        let d = AnchorDraw {
            bias: 3.0 * DEG,
            knee: 50.0 * DEG,
        };
        let r = report(&mut rng, 1, FRAC_PI_2 + 10.3 * DEG, &d, &errors);
        assert!((r - (FRAC_PI_2 + 14.0 * DEG)).abs() < 1e-4, "{}", r / DEG);
    }
}
