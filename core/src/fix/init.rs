//! Initial particles from bearing pairs (seed 002 section 3.3).
//!
//! Adjacent records see the emitter from almost the same place, so their crossings repeat each
//! other; the seed pairs records a fixed interval apart. Here the pairs are (i, i + m/k) for
//! k = 2, 3, ... (half the drive apart first, then thirds, quarters...), keeping only crossings
//! at a good angle in front of both vehicles. When too few pairs qualify (a short or straight
//! drive), the cloud is drawn around the bias-compensated PLE with its covariance, inflated.

use super::intersection::intersect;
use crate::error::Error;
use crate::model::bearing::Bearing;
use crate::particles::ParticleSet;
use rand_core::Rng;

/// How the initial cloud was made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InitialCloud {
    /// From this many bearing-pair intersections.
    Intersections(u32),
    /// Around the PLE fix (too few pairs crossed well).
    AroundPle,
}

/// Inflation of the PLE covariance (in standard deviations) for the fallback cloud.
const PLE_INFLATION: f32 = 3.0;

/// Fill `set` with initial emitter hypotheses from `bearings`, with uniform weights.
pub fn initial_particles<R: Rng + ?Sized, const N: usize>(
    bearings: &[Bearing],
    min_angle: f32,
    set: &mut ParticleSet<N, 2>,
    rng: &mut R,
) -> Result<InitialCloud, Error> {
    let m = bearings.len();
    let mut found = 0usize;
    'outer: for k in 2..=m.max(2) {
        for j in 1..k {
            // Only reduced fractions j/k, so no interval is tried twice.
            if gcd(j, k) != 1 {
                continue;
            }
            let offset = m * j / k;
            if offset == 0 || offset >= m {
                continue;
            }
            for i in 0..m - offset {
                if let Ok(p) = intersect(&bearings[i], &bearings[i + offset], min_angle) {
                    set.states[found] = p;
                    found += 1;
                    if found == N {
                        break 'outer;
                    }
                }
            }
        }
    }
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
    let fix = super::ple::bias_compensated_ple(bearings)?;
    let k = PLE_INFLATION * PLE_INFLATION;
    let cov = [
        [k * fix.covariance[0][0], k * fix.covariance[0][1]],
        [k * fix.covariance[1][0], k * fix.covariance[1][1]],
    ];
    set.draw_gaussian(&fix.position, &cov, rng)?;
    Ok(InitialCloud::AroundPle)
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
        let m = median(&mut v[..found]);
        for vi in v.iter_mut().take(found) {
            *vi = libm::fabsf(*vi - m);
        }
        centre[axis] = m;
        scale[axis] = 1.4826 * median(&mut v[..found]);
    }
    let mut kept = 0;
    for i in 0..found {
        let p = states[i];
        let inside = (0..2).all(|a| libm::fabsf(p[a] - centre[a]) <= 5.0 * scale[a] + 1e-3);
        if inside {
            states[kept] = p;
            kept += 1;
        }
    }
    kept
}

fn median(v: &mut [f32]) -> f32 {
    heapsort(v);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Sort ascending in [`f32::total_cmp`] order. The standard library's sort is 4 KB of code,
/// the largest single item of the 64 KiB MCU image, which sorts nothing else; a heapsort is a
/// few hundred bytes and O(n log n) on every input.
fn heapsort(v: &mut [f32]) {
    let n = v.len();
    for root in (0..n / 2).rev() {
        sift_down(v, root, n);
    }
    for end in (1..n).rev() {
        v.swap(0, end);
        sift_down(v, 0, end);
    }
}

/// Restore the max-heap below `root` within `v[..end]`.
fn sift_down(v: &mut [f32], mut root: usize, end: usize) {
    loop {
        let mut child = 2 * root + 1;
        if child >= end {
            return;
        }
        if child + 1 < end && v[child].total_cmp(&v[child + 1]).is_lt() {
            child += 1;
        }
        if v[root].total_cmp(&v[child]).is_ge() {
            return;
        }
        v.swap(root, child);
        root = child;
    }
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    #[test]
    fn heapsort_sorts_like_the_standard_library() {
        let mut rng = XorShiftRng::seed_from_u64(9);
        for n in 0..40 {
            let mut v = [0.0f32; 40];
            for x in v.iter_mut().take(n) {
                // Few distinct values: ties are the hard case.
                *x = (random::uniform(&mut rng) * 7.0) as i32 as f32 - 3.0;
            }
            v[n / 2] = -0.0;
            let mut expected = v;
            expected[..n].sort_unstable_by(f32::total_cmp);
            heapsort(&mut v[..n]);
            assert_eq!(v.map(f32::to_bits), expected.map(f32::to_bits), "n = {n}");
        }
        let mut odd = [5.0f32, 1.0, 4.0];
        assert_eq!(median(&mut odd), 4.0);
        let mut even = [5.0f32, 1.0, 4.0, 2.0];
        assert_eq!(median(&mut even), 3.0);
    }
}
