//! Initial particles from bearing pairs (seed 002 section 3.3), or along the bearings.
//!
//! Adjacent records see the emitter from almost the same place, so their crossings repeat each
//! other; the seed pairs records a fixed interval apart. Here every offset d = 1 .. m - 1 is
//! visited once, coarse to fine (in bit-reversed order: half the drive apart first, then
//! quarters, three quarters, eighths...), and within an offset the pairs (i, i + d) are strided
//! so no offset takes more than N of them; crossings at a good angle in front of both vehicles
//! become particles. The work is capped ([`InitOptions::max_pairs`]), so a one-hour drive at 20
//! bearings a second (72 000 bearings, 2.6e9 pairs) costs the same few thousand intersections
//! as a short one: O(min(m^2, cap)), never the O(m^3) of revisiting repeated offsets.
//!
//! When too few pairs qualify (a short or straight drive, or an emitter so far away that no
//! pair crosses at the minimum angle), the cloud is spread along the bearings themselves:
//! particle i sits on a randomly chosen bearing (its angle jittered by that bearing's sigma)
//! at a range drawn uniformly in log r between [`InitOptions::min_range`] and
//! [`InitOptions::max_range`] (stratified in log r). That reaches an emitter 10 km away from a
//! 600 m drive, where a cloud drawn around the PLE (biased toward the vehicle, with a covariance
//! computed at the wrong range) misses it and the filter collapses confidently on the wrong
//! spot (chosen: the log-uniform range prior, Peach 1995's range-parameterised idea without
//! the bank of filters).

use super::intersection::intersect;
use crate::error::Error;
use crate::model::bearing::Bearing;
use crate::particles::ParticleSet;
use crate::random;
use rand_core::Rng;

/// Pair intersections tried at most by default: 2^16, as many as a drive of about 360 bearings
/// has in all (m (m - 1) / 2 pairs), so a longer drive costs no more.
pub const MAX_PAIRS: u32 = 65_536;
/// Nearest range of the along-bearings cloud by default, metres: nearer than a few tens of
/// metres a GPS fix's few metres of error ([`super::reach::POSITION_SD_M`]) swing a bearing by
/// several degrees.
pub const CLOUD_MIN_RANGE_M: f32 = 20.0;
/// Farthest range of the along-bearings cloud by default, metres. The cloud is a prior that
/// spends particles: drawn log-uniform in range, every decade between [`CLOUD_MIN_RANGE_M`] and
/// this gets the same share (3.4 decades here), so a farther limit thins the particles at every
/// range. The robust search's cut-off ([`super::robust::MAX_RANGE_M`]), which costs nothing to
/// widen, is twice this.
pub const CLOUD_MAX_RANGE_M: f32 = 50_000.0;

/// How the initial cloud was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitialCloud {
    /// From this many bearing-pair intersections.
    Intersections(u32),
    /// Along the bearings, log-uniform in range (too few pairs crossed well).
    AlongBearings,
}

/// Settings of the initial cloud.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitOptions {
    /// Minimum crossing angle of a pair, radians.
    pub min_angle: f32,
    /// Pair intersections tried at most, whatever the number of bearings.
    pub max_pairs: u32,
    /// Nearest range of the along-bearings cloud, metres (> 0).
    pub min_range: f32,
    /// Farthest range of the along-bearings cloud, metres (> `min_range`).
    pub max_range: f32,
}

impl Default for InitOptions {
    fn default() -> Self {
        Self {
            min_angle: super::intersection::MIN_CROSSING,
            max_pairs: MAX_PAIRS,
            min_range: CLOUD_MIN_RANGE_M,
            max_range: CLOUD_MAX_RANGE_M,
        }
    }
}

impl InitOptions {
    /// `Ok` when every setting is usable.
    pub fn check(&self) -> Result<(), Error> {
        crate::error::check_finite(&[self.min_angle, self.min_range, self.max_range])?;
        if self.min_angle >= 0.0
            && self.max_pairs > 0
            && self.min_range > 0.0
            && self.max_range > self.min_range
        {
            Ok(())
        } else {
            Err(Error::OutOfRange)
        }
    }
}

/// Fill `set` with initial emitter hypotheses from `bearings`, with uniform weights, with the
/// default [`InitOptions`] at crossing angle `min_angle`.
pub fn initial_particles<R: Rng + ?Sized, const N: usize>(
    bearings: &[Bearing],
    min_angle: f32,
    set: &mut ParticleSet<N, 2>,
    rng: &mut R,
) -> Result<InitialCloud, Error> {
    let options = InitOptions {
        min_angle,
        ..InitOptions::default()
    };
    initial_particles_with(bearings, &options, set, rng)
}

/// [`initial_particles`] with every setting given.
pub fn initial_particles_with<R: Rng + ?Sized, const N: usize>(
    bearings: &[Bearing],
    options: &InitOptions,
    set: &mut ParticleSet<N, 2>,
    rng: &mut R,
) -> Result<InitialCloud, Error> {
    options.check()?;
    let (mut found, _) = crossings(bearings, options, &mut set.states);
    let enough = (N / 10).max(3);
    if found >= enough {
        found = drop_wild_crossings(&mut set.states, found);
    }
    if found >= enough {
        for i in found..N {
            set.states[i] = set.states[i % found];
        }
        set.set_uniform_weights();
        return Ok(InitialCloud::Intersections(found as u32));
    }
    along_bearings(bearings, options, &mut set.states, |_, _| 0.0, rng)?;
    set.set_uniform_weights();
    Ok(InitialCloud::AlongBearings)
}

/// Fill `set` with hypotheses [x, y, b] of the augmented state ([`crate::model::biased`]):
/// each particle's offset b drawn from `prior` (its mean alone for a calibrated unit), its
/// position along a randomly chosen bearing corrected by that offset, log-uniform in range.
/// Crossings are not used: where two bearings cross depends on the offset.
pub fn initial_biased_particles<R: Rng + ?Sized, const N: usize>(
    bearings: &[Bearing],
    prior: super::bias::BiasPrior,
    options: &InitOptions,
    set: &mut ParticleSet<N, 3>,
    rng: &mut R,
) -> Result<(), Error> {
    options.check()?;
    prior.check()?;
    let sd = if prior.sd.is_finite() {
        prior.sd
    } else {
        core::f32::consts::PI
    };
    let mut offsets = [0.0f32; N];
    for b in offsets.iter_mut() {
        *b = prior.mean + sd * random::normal(rng);
    }
    let mut positions = [[0.0f32; 2]; N];
    along_bearings(
        bearings,
        options,
        &mut positions,
        |i, _| offsets.get(i).copied().unwrap_or(prior.mean),
        rng,
    )?;
    for ((x, p), b) in set.states.iter_mut().zip(positions).zip(offsets) {
        *x = [p[0], p[1], b];
    }
    set.set_uniform_weights();
    Ok(())
}

/// Offsets 1 .. m - 1, each once, coarse to fine: the bit-reversed order of 1 .. 2^k.
pub(crate) struct Offsets {
    m: usize,
    bits: u32,
    t: usize,
}

impl Offsets {
    pub(crate) fn new(m: usize) -> Self {
        let bits = usize::BITS - m.leading_zeros();
        Self { m, bits, t: 0 }
    }
}

impl Iterator for Offsets {
    type Item = usize;
    fn next(&mut self) -> Option<usize> {
        if self.bits == 0 {
            return None;
        }
        let end = 1usize << self.bits;
        while self.t + 1 < end {
            self.t += 1;
            let d = self.t.reverse_bits() >> (usize::BITS - self.bits);
            if d > 0 && d < self.m {
                return Some(d);
            }
        }
        None
    }
}

/// Crossings of well-separated bearing pairs into `out`; returns how many, and how many pairs
/// were tried. At most `max_pairs` intersections are tried and each offset gets at most N (or
/// 64) of them, spread evenly along the drive.
fn crossings<const N: usize>(
    bearings: &[Bearing],
    options: &InitOptions,
    out: &mut [[f32; 2]; N],
) -> (usize, u32) {
    let m = bearings.len();
    let per_offset = N.max(64);
    let mut found = 0usize;
    let mut tried = 0u32;
    for d in Offsets::new(m) {
        let pairs = m - d;
        let stride = pairs.div_ceil(per_offset).max(1);
        let mut i = 0;
        while i < pairs {
            if tried >= options.max_pairs || found >= N {
                return (found, tried);
            }
            tried += 1;
            if let (Some(a), Some(b)) = (bearings.get(i), bearings.get(i + d))
                && let Ok(p) = intersect(a, b, options.min_angle)
                && let Some(slot) = out.get_mut(found)
            {
                *slot = p;
                found += 1;
            }
            i += stride;
        }
    }
    (found, tried)
}

/// Places probed for a usable bearing before falling back to the first one.
const PROBE: usize = 16;

/// Fill `out` along usable bearings, log-uniform in range (stratified) between the options'
/// ranges. `offset(i, rng)` is subtracted from the bearing angle of particle i (a bias
/// hypothesis for the augmented state; 0 for the plain one).
pub(crate) fn along_bearings<R: Rng + ?Sized>(
    bearings: &[Bearing],
    options: &InitOptions,
    out: &mut [[f32; 2]],
    mut offset: impl FnMut(usize, &mut R) -> f32,
    rng: &mut R,
) -> Result<(), Error> {
    let m = bearings.len();
    let Some(first) = super::usable(bearings).next() else {
        return Err(Error::TooFewMeasurements);
    };
    let (lo, hi) = (libm::logf(options.min_range), libm::logf(options.max_range));
    let n = out.len().max(1) as f32;
    for (i, slot) in out.iter_mut().enumerate() {
        // A uniformly chosen bearing; an unusable one is replaced by the next usable within
        // a few places (or the first usable one), so the cost stays O(1) per particle.
        let k = ((random::uniform(rng) * m as f32) as usize).min(m - 1);
        let b = bearings
            .iter()
            .cycle()
            .skip(k)
            .take(PROBE.min(m))
            .find(|b| b.check().is_ok())
            .unwrap_or(first);
        let u = (i as f32 + random::uniform(rng)) / n;
        let r = libm::expf(lo + u * (hi - lo));
        let angle = b.theta - offset(i, rng) + b.sigma * random::normal(rng);
        *slot = [
            b.vehicle[0] + r * libm::cosf(angle),
            b.vehicle[1] + r * libm::sinf(angle),
        ];
    }
    if out.iter().flatten().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite)
    }
}

/// Wild bearings make wild crossings. Keep the crossings within 5 robust standard deviations
/// (1.4826 MAD) of the coordinate-wise median, compacting them to the front; returns how many
/// remain. O(N log N) with an in-place heapsort of a stack copy.
fn drop_wild_crossings<const N: usize>(states: &mut [[f32; 2]; N], found: usize) -> usize {
    let mut centre = [0.0f32; 2];
    let mut scale = [0.0f32; 2];
    for axis in 0..2 {
        let mut v = [0.0f32; N];
        for (vi, s) in v.iter_mut().zip(states.iter()).take(found) {
            *vi = s[axis];
        }
        let m = super::order::median(&mut v[..found]);
        for vi in v.iter_mut().take(found) {
            *vi = libm::fabsf(*vi - m);
        }
        centre[axis] = m;
        scale[axis] = 1.4826 * super::order::median(&mut v[..found]);
    }
    // A floor for exact data, whose MAD is 0: f32 crossings a kilometre out differ by a few
    // millimetres.
    let floor = |a: usize| 0.01 + 1e-5 * libm::fabsf(centre[a]);
    let mut kept = 0;
    for i in 0..found {
        let p = states[i];
        let inside = (0..2).all(|a| libm::fabsf(p[a] - centre[a]) <= 5.0 * scale[a] + floor(a));
        if inside {
            states[kept] = p;
            kept += 1;
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::bearing::predicted;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    #[test]
    fn offsets_visit_each_once_coarse_first() {
        for m in [0usize, 1, 2, 3, 7, 8, 60, 61, 1000] {
            let mut seen = [false; 1000];
            let mut count = 0;
            for d in Offsets::new(m) {
                assert!(d >= 1 && d < m, "m {m}: {d}");
                assert!(!seen[d], "m {m}: {d} twice");
                seen[d] = true;
                count += 1;
            }
            assert_eq!(count, m.saturating_sub(1), "m {m}");
        }
        let first: [usize; 4] = {
            let mut o = Offsets::new(60);
            core::array::from_fn(|_| o.next().unwrap_or(0))
        };
        assert_eq!(first, [32, 16, 48, 8]);
    }

    fn drive(emitter: [f32; 2], m: usize) -> [Bearing; 600] {
        core::array::from_fn(|k| {
            // An L: east along y = 0, then north (a 600 m drive whatever m is).
            let s = 600.0 * (k % m) as f32 / m as f32;
            let v = if s < 300.0 {
                [s, 0.0]
            } else {
                [300.0, s - 300.0]
            };
            Bearing {
                vehicle: v,
                theta: predicted(&emitter, &v),
                sigma: 0.02,
            }
        })
    }

    #[test]
    fn crossings_land_on_a_near_emitter() {
        let e = [1200.0, 800.0];
        let bs = drive(e, 60);
        let mut set = ParticleSet::<100, 2>::new();
        let mut rng = XorShiftRng::seed_from_u64(1);
        let how = initial_particles(&bs[..60], 0.17, &mut set, &mut rng).unwrap();
        // Every distinct pair of this drive that crosses at 10 degrees or more, each once.
        let mut qualifying = 0;
        for i in 0..60 {
            for j in i + 1..60 {
                qualifying += intersect(&bs[i], &bs[j], 0.17).is_ok() as u32;
            }
        }
        assert_eq!(how, InitialCloud::Intersections(qualifying));
        assert!(qualifying > 30, "{qualifying}");
        for p in set.states {
            assert!(libm::hypotf(p[0] - e[0], p[1] - e[1]) < 1.0, "{p:?}");
        }
    }

    #[test]
    fn a_far_emitter_is_reached_along_the_bearings() {
        let e = [8000.0, 6000.0];
        let bs = drive(e, 60);
        let mut set = ParticleSet::<1000, 2>::new();
        let mut rng = XorShiftRng::seed_from_u64(2);
        let how = initial_particles(&bs[..60], 0.17, &mut set, &mut rng).unwrap();
        assert_eq!(how, InitialCloud::AlongBearings);
        // Some particles within 10 % of the range and 2 sigma of the bearing of the truth.
        let near = set
            .states
            .iter()
            .filter(|p| libm::hypotf(p[0] - e[0], p[1] - e[1]) < 1000.0)
            .count();
        assert!(
            near >= 10,
            "{near} particles within 1 km of a 10 km emitter"
        );
        let far = set
            .states
            .iter()
            .filter(|p| libm::hypotf(p[0], p[1]) > 20_000.0)
            .count();
        assert!(far > 0, "the cloud reaches past the emitter");
    }

    #[test]
    fn the_work_is_capped_when_no_pair_crosses() {
        // Every bearing parallel (an emitter far ahead of a straight road): no pair qualifies,
        // and the search stops at max_pairs tries instead of trying all 180 000 pairs.
        let bs: [Bearing; 600] = core::array::from_fn(|k| Bearing {
            vehicle: [k as f32, 0.0],
            theta: 0.001,
            sigma: 0.02,
        });
        let mut out = [[0.0f32; 2]; 100];
        let options = InitOptions {
            max_pairs: 500,
            ..InitOptions::default()
        };
        assert_eq!(crossings(&bs, &options, &mut out), (0, 500));
        // Where pairs cross, the cloud fills long before the cap, from many offsets.
        let crossing = drive([300.0, 800.0], 600);
        let (found, tried) = crossings(&crossing, &options, &mut out);
        assert_eq!(found, 100);
        assert!(tried < 500, "{tried}");
    }

    #[test]
    fn the_augmented_cloud_spans_the_offset_prior() {
        let e = [1200.0, 800.0];
        let bs = drive(e, 60);
        let mut set = ParticleSet::<500, 3>::new();
        let mut rng = XorShiftRng::seed_from_u64(4);
        let prior = super::super::bias::BiasPrior {
            mean: 0.02,
            sd: 0.05,
        };
        initial_biased_particles(
            &bs[..60],
            prior,
            &InitOptions::default(),
            &mut set,
            &mut rng,
        )
        .unwrap();
        let mean_b = set.states.iter().map(|x| x[2]).sum::<f32>() / 500.0;
        let var_b = set
            .states
            .iter()
            .map(|x| (x[2] - mean_b) * (x[2] - mean_b))
            .sum::<f32>()
            / 500.0;
        assert!((mean_b - 0.02).abs() < 0.01 && (libm::sqrtf(var_b) - 0.05).abs() < 0.01);
        // Each particle sits on its bearing turned back by its own offset.
        let on_line = set
            .states
            .iter()
            .filter(|x| {
                bs[..60].iter().any(|b| {
                    libm::fabsf(crate::model::bearing::wrap(
                        b.theta - x[2] - predicted(&[x[0], x[1]], &b.vehicle),
                    )) < 4.0 * b.sigma
                })
            })
            .count();
        assert!(on_line > 490, "{on_line}");
        // A calibrated unit: every offset is the calibration.
        initial_biased_particles(
            &bs[..60],
            super::super::bias::BiasPrior::calibrated(0.01),
            &InitOptions::default(),
            &mut set,
            &mut rng,
        )
        .unwrap();
        assert!(set.states.iter().all(|x| x[2] == 0.01));
    }

    #[test]
    fn options_are_checked() {
        let mut set = ParticleSet::<10, 2>::new();
        let mut rng = XorShiftRng::seed_from_u64(3);
        let bad = InitOptions {
            min_range: 0.0,
            ..InitOptions::default()
        };
        let bs = drive([1.0e3, 1.0e3], 60);
        assert_eq!(
            initial_particles_with(&bs[..60], &bad, &mut set, &mut rng),
            Err(Error::OutOfRange)
        );
    }
}
