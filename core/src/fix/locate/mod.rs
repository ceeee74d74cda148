//! One entry point from bearings to emitters, honest about what the bearings hold.
//!
//! [`locate`] takes bearings (with their time, DF station and, if known, frequency) and returns
//! one emitter per channel, the other sources the bearings agree on, and what was rejected and
//! why. In order:
//!
//! 1. **Intake**: unusable observations (non-finite, bad sigma, a station beyond the station
//!    table, no room) are counted by reason.
//! 2. **Evidence counted once** ([`super::evidence`]): repeats (exact, or a stamped bearing of
//!    the same station, time and channel by a second path) and bearings older than their
//!    station's latest are set aside.
//! 3. **Channels** ([`super::channel`]): by frequency, one emitter per channel.
//! 4. **Sequential consensus** per channel ([`super::robust`]): the point most bearings agree
//!    on (RANSAC over pairs, each hypothesis with its best offset), refined by Tukey then
//!    trimmed ML over the position and every station's offset ([`super::bias`], each station
//!    with the prior of its row in the station table); its bearings are removed and the
//!    search repeats on the rest. The cluster with most bearings is the channel's emitter; the
//!    others (a reflection, a second transmitter on the channel) are reported as other sources
//!    with their own fix, count and span, their offsets' prior taken from the emitter's
//!    estimate (the same stations). The emitter's per-station offsets go to the offsets
//!    table ([`Source::offsets`]).
//! 5. **Consistency, always**: a cluster that luck could have lined up (uniform bearings, the
//!    search's size accounted for), or whose estimated noise exceeds
//!    [`LocateConfig::max_sigma`], is "no consistent emitter", a typed outcome, not a fix. The
//!    covariance is widened by N / N_eff (the residuals' autocorrelation), and the ellipse is
//!    scaled by 2 F(2, N_eff - p) when the noise was estimated ([`NoiseModel::Estimated`]), or
//!    by chi-square when the DF unit's sigmas hold ([`NoiseModel::Known`], checked by the
//!    residuals' chi-square; a unit noisier than it claims gets the estimated scale and
//!    `consistent: false`). The ellipse is then made to hold the likelihood-ratio region along
//!    its major axis ([`super::reach`]): driving at the emitter, the Fisher ellipse at a fix on
//!    the line of bearing next to the vehicle is tens of metres while the likelihood stays flat
//!    for kilometres. A region that runs out to [`super::robust::RansacOptions::max_range`] is
//!    no fix but a [`Region`] ([`ChannelOutcome::Region`]): the line of bearing from the
//!    observers, its half-width and the range interval the bearings allow.
//! 6. **Still, or moving** ([`motion`]): the emitter's bearings, in thirds by time, must meet
//!    in one place for their noise and the stations' offsets (a likelihood-ratio test at
//!    [`motion::MOTION_ALPHA`]); a channel without a fix is checked by its thirds' own sources.
//!    An emitter that moves is [`NoEmitter::Moving`], not a fix.
//!
//! No allocation: the caller lends the working storage ([`Buffers`], or a [`Workspace`] of
//! fixed capacity: `B` observations, `S` stations), the report holds at most `C` channels and
//! `O` other sources, and every
//! iterative step has a hard cap (RANSAC's hypotheses and attempts, the solver's iterations,
//! the trimming rounds, the autocorrelation's lags, the sources per channel).
//!
//! ```
//! use foxhunt_core::fix::locate::{LocateConfig, Observation, Workspace, locate};
//! use foxhunt_core::model::bearing::{Bearing, predicted};
//! use rand_core::SeedableRng;
//!
//! // Forty bearings from a drive past an emitter at (300, 400), a 2 degree offset and some
//! // noise on them.
//! let emitter = [300.0f32, 400.0];
//! let obs: [Observation; 40] = core::array::from_fn(|k| {
//!     let v = [25.0 * k as f32, 0.04 * (k * k) as f32];
//!     let error = 0.035 + 0.01 * (1.7 * k as f32).sin();
//!     let bearing = Bearing { vehicle: v, theta: predicted(&emitter, &v) + error, sigma: 0.01 };
//!     Observation::new(bearing, k as f32)
//! });
//! let mut work = Workspace::<64>::new();
//! let mut rng = rand_xorshift::XorShiftRng::seed_from_u64(1);
//! let report = locate::<2, 2, _>(&obs, &LocateConfig::default(), work.buffers(), &mut rng)?;
//! let e = &report.emitters()[0];
//! assert!(e.consistent && e.ellipse.contains(&e.position, &emitter));
//! assert!((e.bias - 0.035).abs() < 3.0 * e.bias_sd);
//! # Ok::<(), foxhunt_core::Error>(())
//! ```

mod config;
pub mod motion;
mod region;
mod report;
mod sequential;
mod source;
#[cfg(test)]
mod tests;
mod workspace;

pub use super::observation::Observation;
pub use config::{LocateConfig, NoiseModel};
pub use region::PARALLEL_SPREAD;
pub use report::{
    ChannelOutcome, ChannelReport, NoEmitter, OffsetBeyond, OffsetCheck, OtherReason, OtherSource,
    Region, Rejected, Report, Source, StationOffset,
};
pub use workspace::{Buffers, Item, Workspace, relative_bearings};

use super::channel::{self, NO_CHANNEL};
use super::evidence::{self, Verdict};
use crate::error::{Error, check_finite};
use rand_core::Rng;

/// A channel's frequencies, as its report and its sources carry them (MHz; `None` for the
/// channel of the bearings without one).
#[derive(Debug, Clone, Copy, PartialEq)]
struct ChannelFreq {
    /// The mean of its bearings' frequencies.
    mean: Option<f32>,
    /// The lowest, where the channel starts ([`channel::belongs`]).
    lowest: Option<f32>,
}

/// What an observation's intake check says.
fn intake(o: &Observation) -> Result<(), Error> {
    o.bearing.check()?;
    check_finite(&[o.time_s])?;
    if let Some(f) = o.freq_mhz {
        check_finite(&[f])?;
        if f < 0.0 {
            return Err(Error::OutOfRange);
        }
    }
    Ok(())
}

/// Locate every emitter the observations hold. See the module docs for the steps.
pub fn locate<const C: usize, const O: usize, R: Rng + ?Sized>(
    observations: &[Observation],
    config: &LocateConfig,
    work: Buffers<'_>,
    rng: &mut R,
) -> Result<Report<C, O>, Error> {
    config.check()?;
    let cap = work.capacity();
    let Buffers {
        items,
        scratch,
        order,
        tags,
        stations,
        offsets,
    } = work;
    for s in stations.iter() {
        s.check()?;
    }
    let mut report = Report::<C, O>::new();
    let rej = &mut report.rejected;
    // 1. Intake.
    let mut n = 0usize;
    for (i, o) in observations.iter().enumerate() {
        if usize::from(o.station) >= stations.len() {
            rej.unknown_station += 1;
        } else if intake(o).is_err() {
            rej.invalid += 1;
        } else if n >= cap || i > u32::MAX as usize {
            rej.over_capacity += 1;
        } else if let Some(slot) = items.get_mut(n) {
            *slot = Item::new(*o, i as u32);
            n += 1;
        }
    }
    workspace::relative_bearings(&mut items[..n], stations);
    // 2. Evidence counted once.
    let counts = {
        let seen = &items[..n];
        evidence::sort_out(n, |i| seen.get(i).map(|it| it.obs), order, tags)?
    };
    rej.repeated = counts.repeated;
    rej.time_backwards = counts.backwards;
    let mut kept = 0;
    for i in 0..n {
        if tags[i] == Verdict::Fresh as u8 {
            items[kept] = items[i];
            kept += 1;
        }
    }
    let n = kept;
    report.accepted = n as u32;
    // 3. Channels: tags[i] becomes the channel of items[i].
    let channels = {
        let seen = &items[..n];
        channel::group::<C>(
            n,
            |i| seen.get(i).map(|it| it.obs.freq_mhz),
            config.channel_width_mhz,
            order,
            tags,
        )?
    };
    rej.too_many_channels = channels.overflow;
    // Each channel's bearings made contiguous, in input order within it (channels in order,
    // the unchannelled last): sorted through `scratch`, the channel of position k kept in
    // order[k].
    for (k, slot) in order.iter_mut().enumerate().take(n) {
        *slot = k as u32;
    }
    super::order::quicksort_by(&mut order[..n], |a, b| {
        (tags[*a as usize], *a).cmp(&(tags[*b as usize], *b))
    });
    for (s, &i) in scratch.iter_mut().zip(order.iter()).take(n) {
        *s = items[i as usize];
    }
    let mut channelled = 0;
    for k in 0..n {
        let c = tags[order[k] as usize];
        items[k] = scratch[k];
        order[k] = c as u32;
        if c != NO_CHANNEL {
            channelled = k + 1;
        }
    }
    let n = channelled;
    // 4-5. Each channel.
    let mut start = 0usize;
    for c in 0..channels.len() {
        let mut end = start;
        while end < n && order[end] == c as u32 {
            end += 1;
        }
        let freq = ChannelFreq {
            mean: channels.freq(c).flatten(),
            lowest: channels.lowest(c).flatten(),
        };
        let outcome = sequential::channel_sources(
            &mut items[start..end],
            &mut scratch[start..end],
            sequential::Tables { stations, offsets },
            freq,
            config,
            &mut report,
            rng,
        );
        if let Some(slot) = report.channels.get_mut(report.channel_count) {
            *slot = ChannelReport {
                freq_mhz: freq.mean,
                lowest_mhz: freq.lowest,
                bearings: (end - start) as u32,
                outcome,
            };
            report.channel_count += 1;
        }
        start = end;
    }
    Ok(report)
}
