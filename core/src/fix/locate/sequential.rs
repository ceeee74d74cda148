//! Sequential consensus on one channel: the best-supported source is found, its bearings are
//! removed, and the search repeats on the rest. The first source is the channel's emitter, the
//! later ones (a reflection, a second transmitter) other sources.

use super::super::bias::{BiasPrior, StationSlot};
use super::motion::{self, MIN_SPAN_BEARINGS, Motion, MotionNoise, SEGMENTS, Split};
use super::region::direction_only;
use super::source::{Found, as_region, check_ambiguity, find_source, noise_scale};
use super::{
    ChannelFreq, ChannelOutcome, Item, LocateConfig, NoEmitter, OtherReason, OtherSource, Region,
    Report, Source, StationOffset,
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
        let mut found = find_source(set, scratch, stations, freq, config, rng);
        // A still emitter's fix, or the middle of a moving one's path? Then, for a fix, whether
        // its offset has a rival.
        let mut motion = None;
        let checked = match &mut found {
            Ok(Found::Source(source, kept)) => {
                let members = scratch.get(..*kept).unwrap_or(&[]);
                if first {
                    motion = motion_of(source, members, stations);
                    source.motion_p = motion.map(|m| m.p_value);
                }
                if motion.is_some_and(|m| m.moving()) {
                    Ok(())
                } else {
                    check_ambiguity(source, members, stations, config)
                }
            }
            _ => Ok(()),
        };
        if let Err(why) = checked {
            found = Err(why);
        }
        let (mut source, kept) = match found {
            Ok(Found::Source(s, kept)) => (s, kept),
            // An open range: the channel's answer is its region; a later source's is none
            // (its bearings stay outliers).
            Ok(Found::Region(region, kept)) => {
                if first
                    && let Some(m) =
                        moving_by_spans(&mut run[..len], scratch, stations, freq, config, rng)
                {
                    outcome = ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(m));
                } else if first && let Some(slot) = report.regions.get_mut(report.region_count) {
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
                    let spread = matches!(
                        why,
                        NoEmitter::NoConsensus | NoEmitter::TooNoisy | NoEmitter::Geometry(_)
                    );
                    // Bearings that meet nowhere: an emitter that moves, or perhaps a
                    // direction.
                    if spread
                        && let Some(m) =
                            moving_by_spans(&mut run[..len], scratch, stations, freq, config, rng)
                    {
                        outcome = ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(m));
                    } else if spread
                        && let Some(region) = direction_region(&run[..len], stations, freq, config)
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
            if let Some(m) = motion.filter(Motion::moving) {
                outcome = ChannelOutcome::NoConsistentEmitter(NoEmitter::Moving(m));
                break;
            }
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

/// No fix from the whole channel `run` (no consensus, too noisy, an open range), but an
/// emitter that moves spreads its bearings along its path and each span of time may hold one:
/// each span's source by the same search ([`find_source`], the stations from their priors);
/// when every span has one, the motion check on their bearings, started from their fixes, at
/// their pooled noise. `Some` only when it says the emitter moves. `run` is reordered on the
/// way and left in input order; the stations are left at their priors.
fn moving_by_spans<R: Rng + ?Sized>(
    run: &mut [Item],
    scratch: &mut [Item],
    stations: &mut [StationSlot],
    freq: ChannelFreq,
    config: &LocateConfig,
    rng: &mut R,
) -> Option<Motion> {
    let time = |it: &Item| it.obs.time_s;
    let split = Split::of(run, time)?;
    if run.len() < SEGMENTS * MIN_SPAN_BEARINGS || scratch.len() < run.len() {
        return None;
    }
    // Each span's bearings together, in input order within it (through scratch).
    let mut bounds = [0usize; SEGMENTS + 1];
    let mut w = 0;
    for (k, bound) in bounds.iter_mut().take(SEGMENTS).enumerate() {
        *bound = w;
        for it in run.iter().filter(|it| split.span(time(it)) == k) {
            scratch[w] = *it;
            w += 1;
        }
    }
    bounds[SEGMENTS] = w;
    run[..w].copy_from_slice(&scratch[..w]);
    let mut members = [(0usize, 0usize); SEGMENTS];
    let mut starts = [[0.0f32; 2]; SEGMENTS];
    // Pooled noise: dof-weighted scale^2, N / N_eff over all spans.
    let (mut scale2_dof, mut dof, mut used, mut effective) = (0.0f32, 0.0f32, 0.0f32, 0.0f32);
    let mut estimated = false;
    let mut every = true;
    for k in 0..SEGMENTS {
        let (a, b) = (bounds[k], bounds[k + 1]);
        for s in stations.iter_mut() {
            s.reset();
        }
        let Ok(Found::Source(source, kept)) =
            find_source(&run[a..b], scratch, stations, freq, config, rng)
        else {
            every = false;
            break;
        };
        // The span as [others | its source's bearings].
        let others = remove_kept(&mut run[a..b], &scratch[..kept]);
        if others + kept != b - a {
            every = false;
            break;
        }
        run[a + others..b].copy_from_slice(&scratch[..kept]);
        members[k] = (a + others, b);
        starts[k] = source.position;
        let scale = noise_scale(&source, &run[a + others..b]);
        scale2_dof += scale * scale * source.dof.max(0.0);
        dof += source.dof.max(0.0);
        used += source.used as f32;
        effective += source.effective;
        estimated |= source.sigma_estimated;
    }
    for s in stations.iter_mut() {
        s.reset();
    }
    let motion = if every && dof > 0.0 && effective > 0.0 {
        let noise = MotionNoise {
            scale: libm::sqrtf(scale2_dof / dof),
            tau: (used / effective).max(1.0),
            dof: estimated.then_some(dof),
        };
        let parts = members.map(|(a, b)| &run[a..b]);
        motion::check(parts, stations, starts, noise, split, time)
    } else {
        None
    };
    super::super::order::heapsort_by(run, |a, b| a.index < b.index);
    motion.filter(Motion::moving)
}

/// The motion check ([`motion::check`]) on a source's bearings `members`, at its noise, the
/// stations' offsets started from its fit.
fn motion_of(source: &Source, members: &[Item], stations: &[StationSlot]) -> Option<Motion> {
    let noise = MotionNoise {
        scale: noise_scale(source, members),
        tau: if source.effective > 0.0 {
            (source.used as f32 / source.effective).max(1.0)
        } else {
            1.0
        },
        dof: source.sigma_estimated.then_some(source.dof),
    };
    let time = |it: &Item| it.obs.time_s;
    let split = Split::of(members, time)?;
    let parts = core::array::from_fn(|k| if k == 0 { members } else { &[][..] });
    motion::check(
        parts,
        stations,
        [source.position; SEGMENTS],
        noise,
        split,
        time,
    )
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
