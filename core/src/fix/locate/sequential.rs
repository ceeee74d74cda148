//! Sequential consensus on one channel: the best-supported source is found, its bearings are
//! removed, and the search repeats on the rest. The first source is the channel's emitter, the
//! later ones (a reflection, a second transmitter) other sources.

use super::super::bias::{BiasPrior, StationSlot};
use super::region::direction_only;
use super::source::{Found, as_region, find_source};
use super::{
    ChannelFreq, ChannelOutcome, Item, LocateConfig, NoEmitter, OtherReason, OtherSource, Region,
    Report, StationOffset,
};
use rand_core::Rng;

/// The station table and the emitters' offsets table, as the caller lent them.
pub(super) struct Tables<'a> {
    /// One row per station.
    pub(super) stations: &'a mut [StationSlot],
    /// Each emitter's per-station offsets.
    pub(super) offsets: &'a mut [StationOffset],
}

/// The sources of one channel: sequential consensus on `run` (its bearings, in input order),
/// pushed into `report`. Returns the channel's outcome.
#[allow(clippy::too_many_arguments)]
pub(super) fn channel_sources<const C: usize, const O: usize, R: Rng + ?Sized>(
    run: &mut [Item],
    scratch: &mut [Item],
    tables: Tables<'_>,
    freq: ChannelFreq,
    config: &LocateConfig,
    report: &mut Report<C, O>,
    rng: &mut R,
) -> ChannelOutcome {
    let Tables { stations, offsets } = tables;
    // Every channel starts from the caller's priors.
    for s in stations.iter_mut() {
        s.reset();
    }
    let mut len = run.len();
    let mut outcome = ChannelOutcome::NoConsistentEmitter(NoEmitter::NoConsensus);
    for k in 0..config.max_sources_per_channel {
        let first = k == 0;
        let set = &run[..len];
        if (len as u32) < config.min_bearings {
            if first {
                outcome = ChannelOutcome::NoConsistentEmitter(NoEmitter::TooFew);
            }
            break;
        }
        let found = find_source(set, scratch, stations, freq, config, rng);
        let (mut source, kept) = match found {
            Ok(Found::Source(s, kept)) => (s, kept),
            // An open range: the channel's answer is its region; a later source's is none
            // (its bearings stay outliers).
            Ok(Found::Region(region, kept)) => {
                if first && let Some(slot) = report.regions.get_mut(report.region_count) {
                    *slot = region;
                    outcome = ChannelOutcome::Region(report.region_count);
                    report.region_count += 1;
                    len -= kept;
                }
                break;
            }
            Err(why) => {
                if first {
                    outcome = ChannelOutcome::NoConsistentEmitter(why);
                    // No point, but perhaps a direction.
                    if matches!(
                        why,
                        NoEmitter::NoConsensus | NoEmitter::TooNoisy | NoEmitter::Geometry(_)
                    ) && let Some(region) = direction_region(set, stations, freq, config)
                        && let Some(slot) = report.regions.get_mut(report.region_count)
                    {
                        *slot = region;
                        outcome = ChannelOutcome::Region(report.region_count);
                        report.region_count += 1;
                        len = 0;
                    }
                }
                break;
            }
        };
        if first {
            source.offsets = record_offsets(stations, offsets, &mut report.offsets_written);
            if let Some(slot) = report.emitters.get_mut(report.emitter_count) {
                *slot = source;
                outcome = ChannelOutcome::Emitter(report.emitter_count);
                report.emitter_count += 1;
            }
            // The same stations saw the other sources: the emitter's offsets are their prior.
            for s in stations.iter_mut().filter(|s| s.used() > 0) {
                let (mean, sd) = s.offset();
                if s.prior_in_force().is_free() && sd > 0.0 {
                    s.set_prior_in_force(BiasPrior { mean, sd });
                }
            }
        } else if let Some(slot) = report.others.get_mut(report.other_count) {
            *slot = OtherSource {
                source,
                why: OtherReason::Weaker,
            };
            report.other_count += 1;
        } else {
            report.rejected.too_many_sources += kept as u32;
        }
        // Remove the source's bearings (the first `kept` of scratch, in input order) from the
        // run, keeping the rest in order.
        len = remove_kept(&mut run[..len], &scratch[..kept]);
    }
    match outcome {
        ChannelOutcome::Emitter(_) | ChannelOutcome::Region(_) => {
            report.rejected.outliers += len as u32
        }
        ChannelOutcome::NoConsistentEmitter(_) => report.rejected.no_emitter += run.len() as u32,
    }
    outcome
}

/// The last fit's offset of every station it used, appended to `offsets` from `written` on (as
/// many as fit); the range written.
fn record_offsets(
    stations: &[StationSlot],
    offsets: &mut [StationOffset],
    written: &mut usize,
) -> [u32; 2] {
    let start = *written;
    for (i, s) in stations.iter().enumerate().filter(|(_, s)| s.used() > 0) {
        let Some(slot) = offsets.get_mut(*written) else {
            break;
        };
        let (bias, sd) = s.offset();
        *slot = StationOffset {
            station: i as u16,
            used: s.used(),
            bias,
            sd,
            measured: s.measured(),
            prior: s.prior_in_force(),
        };
        *written += 1;
    }
    [start as u32, *written as u32]
}

/// The region of a channel's bearings that agree on a direction but no point
/// ([`direction_only`]), all of them used.
fn direction_region(
    set: &[Item],
    stations: &[StationSlot],
    freq: ChannelFreq,
    config: &LocateConfig,
) -> Option<Region> {
    let (w, noise) = direction_only(set, stations, config)?;
    let noise_used = (noise.sigma, true, noise.effective);
    Some(as_region(set, freq, &w, noise_used, config.confidence))
}

/// Drop from `run` every item of `kept` (both in increasing input index); returns the new
/// length of `run`.
fn remove_kept(run: &mut [Item], kept: &[Item]) -> usize {
    let mut j = 0;
    let mut out = 0;
    for i in 0..run.len() {
        let it = run[i];
        while j < kept.len() && kept[j].index < it.index {
            j += 1;
        }
        if j < kept.len() && kept[j].index == it.index {
            continue;
        }
        run[out] = it;
        out += 1;
    }
    out
}
