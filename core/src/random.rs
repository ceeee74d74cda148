//! Uniform and Gaussian draws on top of a caller-supplied `rand_core::Rng`.
//!
//! `rand_core` has no float sampling, so these live here, written on `libm` so that the host and
//! the MCU draw bit-identical numbers from the same seed.

use core::f32::consts::PI;
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

/// Standard normal draw by the Box-Muller transform (one of the pair is discarded, which keeps
/// the generator stateless and the draw sequence easy to reproduce on any target).
#[inline]
pub fn normal<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    let u1 = uniform_open0(rng);
    let u2 = uniform(rng);
    libm::sqrtf(-2.0 * libm::logf(u1)) * libm::cosf(2.0 * PI * u2)
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
    fn normal_moments() {
        let mut rng = XorShiftRng::seed_from_u64(2);
        let n = 200_000;
        let (mut s, mut s2, mut s4) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..n {
            let z = normal(&mut rng) as f64;
            assert!(z.is_finite());
            s += z;
            s2 += z * z;
            s4 += z * z * z * z;
        }
        let mean = s / n as f64;
        let var = s2 / n as f64 - mean * mean;
        let kurt = s4 / n as f64;
        // SE of the mean 2.2e-3, of the variance sqrt(2/n) = 3.2e-3, of E z^4 sqrt(96/n) = 0.022:
        // about 5 sigma each.
        assert!(mean.abs() < 0.012, "mean {mean}");
        assert!((var - 1.0).abs() < 0.016, "var {var}");
        assert!((kurt - 3.0).abs() < 0.11, "E z^4 {kurt}");
    }
}
