//! Sorting without the standard library's sort: a heapsort, a few hundred bytes of code and
//! O(n log n) on every input.
//!
//! The standard library's sort is 4 KB of code, the largest single item of the 64 KiB MCU
//! image, which sorts little else; the fixes sort residuals (medians, windows), bearing keys
//! (repeated evidence) and frequencies (channels) with this one. The field pipeline's hot sorts,
//! which the firmware does not run, take faster ones: the robust search's scoring a radix sort
//! ([`radix_sort`]), each solve's sorts of its bearings by key core's quicksort
//! ([`quicksort_by`]).

use core::cmp::Ordering;

/// Sort `v` ascending by `less` (a strict weak order), in place. Not stable: callers that need
/// ties in input order put the index into the key.
pub fn heapsort_by<T: Copy>(v: &mut [T], mut less: impl FnMut(&T, &T) -> bool) {
    let n = v.len();
    for root in (0..n / 2).rev() {
        sift_down(v, root, n, &mut less);
    }
    for end in (1..n).rev() {
        v.swap(0, end);
        sift_down(v, 0, end, &mut less);
    }
}

/// Restore the max-heap below `root` within `v[..end]`.
fn sift_down<T: Copy>(
    v: &mut [T],
    mut root: usize,
    end: usize,
    less: &mut impl FnMut(&T, &T) -> bool,
) {
    loop {
        let mut child = 2 * root + 1;
        if child >= end {
            return;
        }
        if child + 1 < end && less(&v[child], &v[child + 1]) {
            child += 1;
        }
        if !less(&v[root], &v[child]) {
            return;
        }
        v.swap(root, child);
        root = child;
    }
}

/// Sort ascending in [`f32::total_cmp`] order.
pub fn heapsort(v: &mut [f32]) {
    heapsort_by(v, |a, b| a.total_cmp(b).is_lt());
}

/// Values [`radix_sort`] sorts by radix; longer slices take core's quicksort.
pub const RADIX_MAX: usize = 256;

/// Sort ascending in [`f32::total_cmp`] order: the same order as [`heapsort`] (a total order
/// has one sorted arrangement, so the same bits), in four counting passes over the bytes of
/// each value's order key, for the robust search's scoring (a few hundred residuals sorted per
/// hypothesis, hundreds of hypotheses per fix), which runs where the field pipeline runs, the
/// host. Core's pattern-defeating quicksort, which it replaces there, compares about
/// n log2 n = 2 000 times for 256 residuals and mispredicts a branch at many of them; a pass
/// that every value would leave where it is (one byte shared by all) is skipped. Slices
/// longer than [`RADIX_MAX`] take the quicksort. The MCU's windowed fix keeps the heapsort.
pub fn radix_sort(v: &mut [f32]) {
    let n = v.len();
    if n > RADIX_MAX {
        v.sort_unstable_by(f32::total_cmp);
        return;
    }
    // total_cmp's key: the sign bit flipped on positives, every bit on negatives, as unsigned.
    let order_key = |x: f32| {
        let b = x.to_bits();
        b ^ (((b as i32) >> 31) as u32 | 0x8000_0000)
    };
    let from_key = |k: u32| {
        let b = k ^ ((!((k as i32) >> 31)) as u32 | 0x8000_0000);
        f32::from_bits(b)
    };
    let mut keys = [0u32; RADIX_MAX];
    let mut spare = [0u32; RADIX_MAX];
    let mut counts = [[0u16; 256]; 4];
    for (k, x) in keys.iter_mut().zip(v.iter()) {
        *k = order_key(*x);
        for (pass, c) in counts.iter_mut().enumerate() {
            c[((*k >> (8 * pass)) & 0xff) as usize] += 1;
        }
    }
    let (mut from, mut to) = (&mut keys[..n], &mut spare[..n]);
    for (pass, c) in counts.iter_mut().enumerate() {
        if c.iter().any(|&m| usize::from(m) == n) {
            continue;
        }
        let mut start = 0u16;
        for m in c.iter_mut() {
            let here = *m;
            *m = start;
            start += here;
        }
        for &k in from.iter() {
            let slot = &mut c[((k >> (8 * pass)) & 0xff) as usize];
            to[usize::from(*slot)] = k;
            *slot += 1;
        }
        core::mem::swap(&mut from, &mut to);
    }
    for (x, k) in v.iter_mut().zip(from.iter()) {
        *x = from_key(*k);
    }
}

/// Sort `v` ascending by `cmp` (a total order) with core's pattern-defeating quicksort: about
/// half the heapsort's comparisons and far fewer mispredicted branches. For the field
/// pipeline's sorts of its bearings by a key computed at every comparison (evidence, channels),
/// which only the host runs: the firmware's windowed fix has no such step. Not stable: callers
/// that need ties in input order break them by the index.
pub fn quicksort_by<T>(v: &mut [T], cmp: impl FnMut(&T, &T) -> Ordering) {
    v.sort_unstable_by(cmp);
}

/// Median of `v` (sorted in place); 0 for an empty slice.
pub fn median(v: &mut [f32]) -> f32 {
    heapsort(v);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::random;
    use rand_core::{Rng, SeedableRng};
    use rand_xorshift::XorShiftRng;

    #[test]
    fn the_radix_sort_sorts_like_the_standard_library() {
        let mut rng = XorShiftRng::seed_from_u64(11);
        let specials = [
            -0.0f32,
            0.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::MIN_POSITIVE,
            -1e-40,
        ];
        for n in (0..=RADIX_MAX + 8).step_by(7).chain([RADIX_MAX]) {
            for kind in 0..3 {
                let mut v = [0.0f32; RADIX_MAX + 8];
                for (i, x) in v.iter_mut().take(n).enumerate() {
                    let u = random::uniform(&mut rng);
                    *x = match kind {
                        // Residuals: a narrow spread about zero, both signs.
                        0 => (u - 0.5) * 0.3,
                        // Few distinct values: ties.
                        1 => (u * 7.0) as i32 as f32 - 3.0,
                        // Any bits at all, the specials among them.
                        _ if i % 5 == 0 => specials[i / 5 % specials.len()],
                        _ => f32::from_bits(rng.next_u32()),
                    };
                }
                let mut expected = v;
                expected[..n].sort_unstable_by(f32::total_cmp);
                radix_sort(&mut v[..n]);
                assert_eq!(
                    v.map(f32::to_bits),
                    expected.map(f32::to_bits),
                    "n {n} kind {kind}"
                );
            }
        }
    }

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
        let mut v = [3.0f32, -0.0, 0.0, -1.0, f32::INFINITY, 2.0];
        let mut w = v;
        heapsort(&mut v);
        radix_sort(&mut w);
        assert_eq!(v.map(f32::to_bits), w.map(f32::to_bits));
        let mut odd = [5.0f32, 1.0, 4.0];
        assert_eq!(median(&mut odd), 4.0);
        let mut even = [5.0f32, 1.0, 4.0, 2.0];
        assert_eq!(median(&mut even), 3.0);
    }

    #[test]
    fn keys_with_indices_sort_stably() {
        let mut v = [(3u32, 0u32), (1, 1), (3, 2), (1, 3), (2, 4)];
        heapsort_by(&mut v, |a, b| a < b);
        assert_eq!(v, [(1, 1), (1, 3), (2, 4), (3, 0), (3, 2)]);
    }
}
