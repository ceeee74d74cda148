//! Uniform and Gaussian draws on top of a caller-supplied `rand_core::Rng`.
//!
//! `rand_core` has no float sampling, so these live here, written on `libm` so that the host and
//! the MCU draw bit-identical numbers from the same seed.

use rand_core::Rng;

/// Uniform on [0, 1): the top 24 bits of one `u32`, exactly representable in `f32`.
#[inline]
pub fn uniform<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Uniform on (0, 1]: never zero, safe under a logarithm.
#[inline]
pub fn uniform_open0<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    ((rng.next_u32() >> 8) as f32 + 1.0) * (1.0 / 16_777_216.0)
}

/// Uniform on [lo, hi).
#[inline]
pub fn uniform_in<R: Rng + ?Sized>(rng: &mut R, lo: f32, hi: f32) -> f32 {
    lo + (hi - lo) * uniform(rng)
}

mod ziggurat {
    include!(concat!(env!("OUT_DIR"), "/ziggurat.rs"));
}
use ziggurat::{ZIG_F, ZIG_K, ZIG_R, ZIG_W};

/// Standard normal draw by the ziggurat method (Marsaglia and Tsang 2000, 128 layers; tables
/// generated at build time). About 99 % of draws cost one `u32`, two table reads and a
/// compare; the rest take the wedge test or the exact tail. Exact (not an approximation), and
/// pure f32 arithmetic on `libm`, so the host and the MCU draw the same numbers.
#[inline]
pub fn normal<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    loop {
        let u = rng.next_u32();
        let layer = (u & 0x7f) as usize;
        let negative = u & 0x80 != 0;
        let magnitude = u >> 8;
        let x = magnitude as f32 * ZIG_W[layer];
        let sign = |v: f32| if negative { -v } else { v };
        if magnitude < ZIG_K[layer] {
            return sign(x);
        }
        if layer == 0 {
            // Beyond the base layer: the exact tail x > R (Marsaglia 1964).
            loop {
                let t = -libm::logf(uniform_open0(rng)) / ZIG_R;
                let y = -libm::logf(uniform_open0(rng));
                if 2.0 * y > t * t {
                    return sign(ZIG_R + t);
                }
            }
        }
        // In the wedge between the layer's inner and outer edge: accept under the density.
        let f0 = ZIG_F[layer];
        let f1 = ZIG_F[layer + 1];
        if f0 + uniform(rng) * (f1 - f0) < libm::expf(-0.5 * x * x) {
            return sign(x);
        }
    }
}

/// Draw from N(mean, L L^T) given the lower Cholesky factor `l`.
pub fn gaussian<R: Rng + ?Sized, const D: usize>(
    rng: &mut R,
    mean: &[f32; D],
    l: &[[f32; D]; D],
) -> [f32; D] {
    let mut z = [0.0f32; D];
    for v in z.iter_mut() {
        *v = normal(rng);
    }
    let mut x = *mean;
    for (i, xi) in x.iter_mut().enumerate() {
        for (lij, zj) in l[i].iter().zip(z.iter()).take(i + 1) {
            *xi += lij * zj;
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;
    use rand_xorshift::XorShiftRng;

    #[test]
    fn uniform_moments() {
        let mut rng = XorShiftRng::seed_from_u64(1);
        let n = 200_000;
        let (mut s, mut s2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let u = uniform(&mut rng) as f64;
            assert!((0.0..1.0).contains(&u));
            s += u;
            s2 += u * u;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        // Standard error of the mean is sqrt(1/12/n) = 6.5e-4: 5 sigma tolerance.
        assert!((mean - 0.5).abs() < 3.3e-3, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 2e-3, "var {var}");
    }

    #[test]
    fn normal_moments_and_tails() {
        let mut rng = XorShiftRng::seed_from_u64(2);
        let n = 400_000;
        let (mut s, mut s2, mut s4) = (0.0f64, 0.0f64, 0.0f64);
        let mut beyond = [0u32; 4];
        for _ in 0..n {
            let z = normal(&mut rng) as f64;
            assert!(z.is_finite());
            s += z;
            s2 += z * z;
            s4 += z * z * z * z;
            for (k, b) in beyond.iter_mut().enumerate() {
                if z.abs() > (k + 1) as f64 {
                    *b += 1;
                }
            }
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        let kurt = s4 / n as f64;
        // Standard errors: mean 1.6e-3, variance sqrt(2/n) = 2.2e-3, E z^4 sqrt(96/n) = 0.015:
        // about 5 of each.
        assert!(mean.abs() < 0.008, "mean {mean}");
        assert!((var - 1.0).abs() < 0.011, "var {var}");
        assert!((kurt - 3.0).abs() < 0.077, "E z^4 {kurt}");
        // P(|z| > k) for k = 1..4 (0.3173, 0.0455, 0.0027, 6.3e-5), each within 5 binomial
        // standard errors: the tail and the wedges are sampled right, not just the moments.
        for (k, p) in [0.317_310_5, 0.045_500_26, 0.002_699_8, 6.334e-5]
            .iter()
            .enumerate()
        {
            let observed = beyond[k] as f64 / n as f64;
            let se = (p * (1.0 - p) / n as f64).sqrt();
            assert!(
                (observed - p).abs() < 5.0 * se,
                "P(|z| > {}) = {observed}, not {p}",
                k + 1
            );
        }
    }
}
