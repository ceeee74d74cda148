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

/// Range of a draw's magnitude (its top 23 bits): x = magnitude * ZIG_W[layer].
const MAGNITUDES: u32 = 1 << 23;

/// Standard normal draw by the ziggurat method (Marsaglia and Tsang 2000, 256 layers; tables
/// generated at build time). 98.5 % of draws cost one `u32`, two table reads and a
/// compare, inlined into the caller's loop; the rest take the wedge test or the exact tail out
/// of line. Exact (not an approximation), and pure f32 arithmetic on `libm`, so the host and
/// the MCU draw the same numbers.
#[inline(always)]
pub fn normal<R: Rng + ?Sized>(rng: &mut R) -> f32 {
    let u = rng.next_u32();
    let layer = (u & 0xff) as usize;
    let magnitude = u >> 9;
    if magnitude < ZIG_K[layer] {
        return with_sign(magnitude as f32 * ZIG_W[layer], u);
    }
    normal_slow(rng, u)
}

/// `x` (>= 0) negated when bit 8 of the draw `u` is set. By bit arithmetic, not a branch: a
/// coin-flip branch is mispredicted half the time, which once cost more than the rest of a draw.
#[inline(always)]
fn with_sign(x: f32, u: u32) -> f32 {
    f32::from_bits(x.to_bits() ^ ((u & 0x100) << 23))
}

/// The ziggurat's rare branches: the wedge test and the tail, starting from the rejected draw
/// `u`, then fresh draws until one is accepted.
#[cold]
#[inline(never)]
fn normal_slow<R: Rng + ?Sized>(rng: &mut R, mut u: u32) -> f32 {
    loop {
        let layer = (u & 0xff) as usize;
        let negative = u & 0x100 != 0;
        let magnitude = u >> 9;
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
        let (f0, f1) = (ZIG_F[layer], ZIG_F[layer + 1]);
        if under_density(layer, x, f0 + uniform(rng) * (f1 - f0)) {
            return sign(x);
        }
        u = rng.next_u32();
    }
}

/// Whether (x, y) in the wedge of `layer` (1..=255) lies under exp(-x^2 / 2). The chord
/// between the layer's edges x1 < x0 and the tangent at x0 bracket the density (below and
/// above it where it is concave, x < 1; the other way round where it is convex), so most
/// points are decided without the exponential.
fn under_density(layer: usize, x: f32, y: f32) -> bool {
    let (f0, f1) = (ZIG_F[layer], ZIG_F[layer + 1]);
    let x0 = ZIG_W[layer] * MAGNITUDES as f32;
    let x1 = ZIG_K[layer] as f32 * ZIG_W[layer];
    let chord = f0 + (f1 - f0) * (x0 - x) / (x0 - x1);
    let tangent = f0 * (1.0 + x0 * (x0 - x));
    let (below, above) = if x1 >= 1.0 {
        (tangent, chord)
    } else if x0 <= 1.0 {
        (chord, tangent)
    } else {
        (f32::NEG_INFINITY, f32::INFINITY)
    };
    y < below || (y <= above && y < crate::fastmath::exp_nonpositive(-0.5 * x * x))
}

/// Four xorshift128 generators in lock step, seeded from the caller's generator.
///
/// A loop that needs a normal per particle coordinate is bound by the latency of one serial
/// generator; four independent lanes let the CPU (and the vectoriser) work on four draws at
/// once. Seeding takes 16 words from the caller's generator, so one seed still fixes every
/// draw, on the host and the MCU alike.
#[derive(Debug, Clone)]
pub struct Lanes {
    x: [u32; 4],
    y: [u32; 4],
    z: [u32; 4],
    w: [u32; 4],
}

impl Lanes {
    /// Four fresh lanes from `rng`.
    pub fn seed_from<R: Rng + ?Sized>(rng: &mut R) -> Self {
        let mut word = || rng.next_u32();
        let mut lanes = Self {
            x: [word(), word(), word(), word()],
            y: [word(), word(), word(), word()],
            z: [word(), word(), word(), word()],
            w: [word(), word(), word(), word()],
        };
        // xorshift's one forbidden state is all zeros.
        for k in 0..4 {
            if (lanes.x[k] | lanes.y[k] | lanes.z[k] | lanes.w[k]) == 0 {
                lanes.w[k] = 0x9E37_79B9;
            }
        }
        lanes
    }

    /// The next word of each lane (Marsaglia's xorshift128, shifts 11, 8, 19).
    #[inline(always)]
    pub fn next_u32x4(&mut self) -> [u32; 4] {
        for k in 0..4 {
            let t = self.x[k] ^ (self.x[k] << 11);
            self.x[k] = self.y[k];
            self.y[k] = self.z[k];
            self.z[k] = self.w[k];
            self.w[k] = self.w[k] ^ (self.w[k] >> 19) ^ (t ^ (t >> 8));
        }
        self.w
    }

    /// Four standard normals by the ziggurat, one per lane; a draw that misses the fast path
    /// finishes on `rng`.
    #[inline(always)]
    pub fn normals<R: Rng + ?Sized>(&mut self, rng: &mut R) -> [f32; 4] {
        let u = self.next_u32x4();
        let mut out = [0.0f32; 4];
        for k in 0..4 {
            let layer = (u[k] & 0xff) as usize;
            let magnitude = u[k] >> 9;
            out[k] = if magnitude < ZIG_K[layer] {
                with_sign(magnitude as f32 * ZIG_W[layer], u[k])
            } else {
                normal_slow(rng, u[k])
            };
        }
        out
    }
}

/// Draw from N(mean, L L^T) given the lower Cholesky factor `l`.
pub fn gaussian<R: Rng + ?Sized, const D: usize>(
    rng: &mut R,
    mean: &[f32; D],
    l: &[[f32; D]; D],
) -> [f32; D] {
    let z = core::array::from_fn(|_| normal(rng));
    correlate(mean, l, &z)
}

/// mean + L z: standard normals `z` turned into a draw from N(mean, L L^T).
#[inline]
pub fn correlate<const D: usize>(mean: &[f32; D], l: &[[f32; D]; D], z: &[f32; D]) -> [f32; D] {
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

    /// The bracketing bounds decide as the density itself does (away from the curve by more
    /// than f32 rounding), in every wedge.
    #[test]
    fn wedge_bounds_agree_with_the_density() {
        let mut rng = XorShiftRng::seed_from_u64(11);
        for layer in 1..256 {
            let (f0, f1) = (ZIG_F[layer], ZIG_F[layer + 1]);
            for _ in 0..2000 {
                let magnitude = ZIG_K[layer] + rng.next_u32() % (MAGNITUDES - ZIG_K[layer]);
                let x = magnitude as f32 * ZIG_W[layer];
                let y = f0 + uniform(&mut rng) * (f1 - f0);
                let exact = libm::exp(-0.5 * (x as f64) * (x as f64));
                if (y as f64 - exact).abs() > 1e-6 {
                    assert_eq!(
                        under_density(layer, x, y),
                        (y as f64) < exact,
                        "{layer} {x} {y}"
                    );
                }
            }
        }
    }
}
