//! Sequential consensus on one channel: the best-supported source is found, its bearings are
//! removed, and the search repeats on the rest. The first source is the channel's emitter, the
//! later ones (a reflection, a second transmitter) other sources.

use super::super::bias::{BiasPrior, MAX_SOURCES};
use super::source::find_source;
use super::{
    ChannelFreq, ChannelOutcome, Item, LocateConfig, NoEmitter, OtherReason, OtherSource, Report,
};
use rand_core::Rng;

/// The sources of one channel: sequential consensus on `run` (its bearings, in input order),
/// pushed into `report`. Returns the channel's outcome.
pub(super) fn channel_sources<const C: usize, const O: usize, R: Rng + ?Sized>(
    run: &mut [Item],
    scratch: &mut [Item],
    freq: ChannelFreq,
    config: &LocateConfig,
    report: &mut Report<C, O>,
    rng: &mut R,
) -> ChannelOutcome {
    let mut len = run.len();
    let mut priors = config.priors;
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
        let found = find_source(set, scratch, &priors, freq, config, rng);
        let (source, kept, fix_bias) = match found {
            Ok(f) => f,
            Err(why) => {
                if first {
                    outcome = ChannelOutcome::NoConsistentEmitter(why);
                }
                break;
            }
        };
        if first {
            if let Some(slot) = report.emitters.get_mut(report.emitter_count) {
                *slot = source;
                outcome = ChannelOutcome::Emitter(report.emitter_count);
                report.emitter_count += 1;
            }
            // The same DF units saw the other sources: the emitter's offsets are their prior.
            for s in 0..MAX_SOURCES {
                if priors[s].is_free() && fix_bias.1[s] > 0.0 {
                    priors[s] = BiasPrior {
                        mean: fix_bias.0[s],
                        sd: fix_bias.1[s],
                    };
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
        ChannelOutcome::Emitter(_) => report.rejected.outliers += len as u32,
        ChannelOutcome::NoConsistentEmitter(_) => report.rejected.no_emitter += run.len() as u32,
    }
    outcome
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
