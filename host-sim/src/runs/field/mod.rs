//! Field conditions as bearing sets: what real DF drives do to a fix (docs/src/field.md), simulated so
//! the default `locate` pipeline can be measured on them over seeded Monte Carlo runs.
//!
//! Each [`Condition`] makes the observations of one run (bearings with time, source and
//! frequency, as a DF unit and the bridge deliver them) and the truth they were made from;
//! [`measure`] runs [`foxhunt_core::fix::locate::locate`] on `runs` of them in parallel and
//! counts what a user would care about: whether an emitter was reported, whether its ellipse
//! holds the truth, how far off it is against the bias-aware bound, whether a ghost came out
//! as another source.
//!
//! The drives (chosen; the canonical routes of docs/src/scenarios.md where one fits):
//! - `u-drive`: 9 km, 240 bearings (one per 37.5 m at 10 m/s), a U round an emitter at
//!   (0, 1500): east along y = 0 from x = -1500, north along x = 1500, west along y = 3000.
//!   Its bearings span more than 180 degrees, so a mounting offset is observable.
//! - `L600` (docs/src/scenarios.md), with the emitter at 1.4 km (aoa-drive) or 10 km.
//! - `open-*`: drives that leave the range open (few 15 degree bearings on 300 m; a short
//!   curved track toward a distant emitter, correlated 5 Hz reports), judged by their regions.
//! - `long`: a 20 km L (10 km east, 10 km north, 400 bearings) placed at 47 or 70 degrees
//!   north and simulated on the WGS-84 ellipsoid: each bearing is the true azimuth at the
//!   vehicle plus noise, turned into the local frame of the drive's start by the meridian
//!   convergence (what the bridge does; `uncorrected` leaves it out, as it did before).

mod bench;
mod calibration;
mod capture;
mod drives;
mod judge;

pub use bench::{BENCH_METHODS, bench};
pub use calibration::{Calibrated, CalibrationRow, calibration_runs};
pub use capture::capture;
pub use drives::{DirectionUnit, l600, simulate, u_route};
pub use judge::{
    EmitterSummary, RunOutcome, Summary, THREE_SIGMA_TAIL, bound_at, bound_with, emitter_for,
    judge, judge_with, measure, region_for, run_locate, run_with,
};

use crate::estimate::Priors;
use foxhunt_core::fix::bias::{BiasPrior, DirectionPrior};
use foxhunt_core::fix::device::{DeviceClass, class_noise};
use foxhunt_core::fix::locate::Observation;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use std::f32::consts::PI;

pub(super) const DEG: f32 = PI / 180.0;

/// Channels a field report holds at most (the host pipeline's).
pub const CHANNELS: usize = 16;
/// Other sources a field report holds at most.
pub const OTHERS: usize = 16;

/// A simulated field condition.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Condition {
    /// The U drive with a 2 degree mounting offset.
    Bias2,
    /// The U drive with a 4 degree mounting offset.
    Bias4,
    /// aoa-drive (L600) with a 4 degree offset: the drive cannot see it, the prior governs.
    Bias4Short,
    /// The U drive, a contiguous quarter of it seeing a reflection 950 m from the emitter.
    Multipath,
    /// Two emitters 1 km apart on 145.000 and 146.520 MHz, bearings alternating.
    TwoEmitters,
    /// The U drive at 20 m/s with a DF reporting 5 times a second the running mean of its
    /// last 10 raw bearings (6 degrees each): errors correlated over 2 s.
    Correlated,
    /// The U drive's 240 bearings, every one uniformly random.
    PureNoise,
    /// 3 to 10 bearings spread along the U drive (run r has 3 + r % 8), noise 3 degrees while
    /// the unit claims 2: only the estimated noise is honest.
    FewBearings,
    /// L600 with the emitter 10 km away, 1.117 degree noise.
    Distant,
    /// The 20 km L at 47 degrees north.
    Long47,
    /// The 20 km L at 70 degrees north.
    Long70,
    /// The 20 km L at 70 degrees north without the meridian convergence turned out.
    Long70Uncorrected,
    /// aoa-drive's L600 with 2 degree noise and 15 % wild bearings.
    Wild15,
    /// The canonical aoa-afsa-wild (loop300, 10 % wild, 1.117 degrees).
    AoaAfsaWild,
    /// The canonical aoa-afsa (loop300, clean).
    AoaAfsa,
    /// The canonical aoa-drive (L600, clean).
    AoaDrive,
    /// An open range: 6 to 12 bearings (run r has 6 + r % 7) spread along L600's first 300 m,
    /// 15 degree noise stated as such, the emitter at (1200, 800), the unit's offset drawn from
    /// the default prior (6 degrees sd) each run.
    OpenNoisyFew,
    /// An open range: 60 s on a curved track (a 1.2 km arc of 3 km radius, 15 m/s) with a DF
    /// reporting 5 times a second the running mean of its last 10 raw bearings (8 degrees
    /// each), the emitter 8 km off, the offset drawn from the default prior each run.
    OpenCorrelatedCurved,
    /// A calibrated pseudo-Doppler unit (its offset known to 0.05 degrees) whose true offset
    /// has moved since by an unmodelled error of sd 0.2 to 1 degree (run r: 0.2 + 0.2 (r % 5),
    /// stated in its stations file): 1800 bearings of 3 degrees along 1.5 km of straight road,
    /// the emitter 3 km broadside.
    Systematic,
    /// Four fixed arrays of the indoor angle-of-arrival class at the corners of a 2 x 1.5 km
    /// site, the emitter inside: 15 degree noise quantised to 2 degrees, 37 reports a second
    /// each for 30 s (4440 bearings), each array's offset drawn from the default prior and its
    /// unmodelled error from its class (2 degrees); the stations file states the class.
    AoaArray15,
    /// The U drive's 240 bearings (2 degrees) from a pseudo-Doppler unit whose error depends on
    /// the bearing relative to the vehicle: first and second harmonics, each of an amplitude
    /// drawn from 2-5 degrees with a random phase, an offset from the default prior; its
    /// stations file states the harmonics' prior ([`DIRECTION_ERROR_DEG`] each).
    DirectionDependent,
    /// `correlated-5hz` on a curved track: 9 km at 20 m/s along an arc of 2 km radius (258
    /// degrees), 5 running-mean reports a second (the last 10 raw bearings of 6 degrees; the
    /// unit states 2), the emitter 500 m off the arc's centre.
    CorrelatedCurved,
    /// `direction-dependent-2-5deg`'s drives (the same runs) with nothing stated of the
    /// harmonics: the pipeline finds them in its residuals or gives the wider fix that ignores
    /// them (judged against the bound with the stated prior).
    DirectionUnstated,
}

/// The sd of each harmonic coefficient the `direction-dependent-2-5deg` condition's stations
/// file states, degrees: amplitudes uniform in 2-5 degrees with a random phase give each
/// coefficient an rms of 2.55 degrees (sqrt(E[A^2] / 2), E[A^2] = 13), which 3 holds.
pub const DIRECTION_ERROR_DEG: f32 = 3.0;

impl Condition {
    /// Every condition, in report order.
    pub const ALL: [Condition; 23] = [
        Condition::Bias2,
        Condition::Bias4,
        Condition::Bias4Short,
        Condition::Multipath,
        Condition::TwoEmitters,
        Condition::Correlated,
        Condition::PureNoise,
        Condition::FewBearings,
        Condition::Distant,
        Condition::Long47,
        Condition::Long70,
        Condition::Long70Uncorrected,
        Condition::Wild15,
        Condition::AoaAfsaWild,
        Condition::AoaAfsa,
        Condition::AoaDrive,
        Condition::OpenNoisyFew,
        Condition::OpenCorrelatedCurved,
        Condition::Systematic,
        Condition::AoaArray15,
        Condition::DirectionDependent,
        Condition::CorrelatedCurved,
        Condition::DirectionUnstated,
    ];

    /// The conditions made to leave the range open: judged by their regions too (a region
    /// holds the truth when the bearing is within its half-width and the range within its
    /// interval).
    pub const OPEN_RANGE: [Condition; 2] =
        [Condition::OpenNoisyFew, Condition::OpenCorrelatedCurved];

    /// The conditions whose answers (fixes and regions) are judged together: the open ranges,
    /// and the curved correlated drive, whose range is barely observed (a reported region
    /// counts when it holds the truth).
    pub const ANSWERS_JUDGED: [Condition; 3] = [
        Condition::OpenNoisyFew,
        Condition::OpenCorrelatedCurved,
        Condition::CorrelatedCurved,
    ];

    /// The name printed in reports.
    pub fn name(&self) -> &'static str {
        match self {
            Condition::Bias2 => "bias-2deg",
            Condition::Bias4 => "bias-4deg",
            Condition::Bias4Short => "bias-4deg-L600",
            Condition::Multipath => "multipath",
            Condition::TwoEmitters => "two-emitters",
            Condition::Correlated => "correlated-5hz",
            Condition::PureNoise => "pure-noise",
            Condition::FewBearings => "few-bearings",
            Condition::Distant => "distant-10km",
            Condition::Long47 => "long-20km-47n",
            Condition::Long70 => "long-20km-70n",
            Condition::Long70Uncorrected => "long-20km-70n-uncorrected",
            Condition::Wild15 => "wild-15pct-2deg",
            Condition::AoaAfsaWild => "aoa-afsa-wild",
            Condition::AoaAfsa => "aoa-afsa",
            Condition::AoaDrive => "aoa-drive",
            Condition::OpenNoisyFew => "open-15deg-few",
            Condition::OpenCorrelatedCurved => "open-5hz-curved",
            Condition::Systematic => "systematic-0.2-1deg",
            Condition::AoaArray15 => "aoa-array-15deg",
            Condition::DirectionDependent => "direction-dependent-2-5deg",
            Condition::CorrelatedCurved => "correlated-5hz-curved",
            Condition::DirectionUnstated => "direction-dependent-unstated",
        }
    }

    /// What its stations file says of each station (as `locate --stations` reads it), the
    /// offset prior `default` where it states none: the drive's ([`FieldDrive::priors`]), and
    /// the direction-dependent error's prior where the condition states one.
    pub fn priors(&self, d: &FieldDrive, default: BiasPrior) -> Priors {
        let mut p = d.priors(default);
        if *self == Condition::DirectionDependent {
            let stated = DirectionPrior {
                mean: [0.0; 4],
                sd: DIRECTION_ERROR_DEG * DEG,
            };
            p.direction = vec![Some((stated, None))];
        }
        p
    }

    /// What the bound knows of each station: [`Condition::priors`], and for
    /// `direction-dependent-unstated` the stated condition's (the error is there, stated or
    /// not).
    pub fn bound_priors(&self, d: &FieldDrive, default: BiasPrior) -> Priors {
        match self {
            Condition::DirectionUnstated => Condition::DirectionDependent.priors(d, default),
            c => c.priors(d, default),
        }
    }
}

/// One emitter of a simulated drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Position, local metres.
    pub position: [f32; 2],
    /// Its frequency, MHz, if the unit reports one.
    pub freq_mhz: Option<f32>,
}

/// A station of a network drive (docs/src/networks.md): what the simulation made of it.
#[derive(Debug, Clone, PartialEq)]
pub struct StationTruth {
    /// Its id, as its records carry it.
    pub id: String,
    /// Whether it stands still (a mast) or drives.
    pub fixed: bool,
    /// Its true offset, radians.
    pub offset: f32,
    /// Its true bearing noise, radians.
    pub sigma: f32,
    /// The offset prior its stations file states.
    pub prior: BiasPrior,
    /// The device class its stations file states (`None`: unstated).
    pub class: Option<DeviceClass>,
    /// Sd of the unmodelled error its stations file states, radians (`None`: its class's).
    pub unmodelled: Option<f32>,
}

/// The observations of one run and what made them.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldDrive {
    /// The observations, in time order.
    pub observations: Vec<Observation>,
    /// The emitters (none for pure noise).
    pub emitters: Vec<Truth>,
    /// A reflection some bearings see, if any.
    pub ghost: Option<[f32; 2]>,
    /// The unit's true mounting offset, radians.
    pub bias: f32,
    /// The true bearing noise, radians (the sd of a reported bearing's error).
    pub sigma: f32,
    /// The stations of a network drive, by station index (empty: one DF unit, station 0,
    /// with the prior the run is given).
    pub stations: Vec<StationTruth>,
}

impl FieldDrive {
    /// What its stations file says of each station (as `locate --stations` reads it): the
    /// drive's own prior where it states one, else `default`; each station's unmodelled error
    /// (its own, else its class's), the stated classes' ceiling, and whether every station's
    /// class states its noise.
    pub fn priors(&self, default: BiasPrior) -> Priors {
        let classes = self.stations.iter().filter_map(|s| s.class);
        Priors {
            default,
            stations: self.stations.iter().map(|s| Some(s.prior)).collect(),
            unmodelled: self
                .stations
                .iter()
                .map(|s| Some(s.unmodelled.unwrap_or(class_noise(s.class).unmodelled)))
                .collect(),
            ceiling: classes.map(|c| c.noise().ceiling).reduce(f32::max),
            noise_stated: !self.stations.is_empty()
                && self
                    .stations
                    .iter()
                    .all(|s| class_noise(s.class).noise.is_some()),
            ..Priors::default()
        }
    }
}

/// The seeded generator of run `run` of a condition (independent streams per condition).
pub fn rng(condition: Condition, run: usize) -> XorShiftRng {
    let salt = Condition::ALL
        .iter()
        .position(|c| *c == condition)
        .unwrap_or(0) as u64;
    XorShiftRng::seed_from_u64(
        (salt + 1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(run as u64),
    )
}

/// A condition by name (`Condition::name`).
pub fn condition(name: &str) -> Option<Condition> {
    Condition::ALL.into_iter().find(|c| c.name() == name)
}
