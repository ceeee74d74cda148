//! Branch-free `exp` and `atan2` for the per-particle loops, and a `sqrt` for the swarms.
//!
//! `libm`'s versions are exact to half an ulp but branch on the argument's range, which keeps
//! the compiler from vectorising a loop over particles and costs a call per particle. These use
//! one range reduction by selects and a short minimax polynomial (Cephes' coefficients), good
//! to a few ulp: far below any measurement noise (a bearing residual is off by < 3e-7 rad, a
//! weight by < 3e-7 relative). The tests below bound the error against `libm` over dense grids.
//! Pure IEEE f32 arithmetic, so the host and the MCU compute the same bits.

use core::f32::consts::{FRAC_PI_2, FRAC_PI_4, LOG2_E, PI};

/// Below this, `exp(x)` is under f32's smallest normal: the result is flushed to 0.
const EXP_MIN: f32 = -87.33;

/// 1.5 * 2^23: adding and subtracting it rounds an f32 to the nearest integer.
const ROUND: f32 = 12_582_912.0;

/// `x` rounded to the nearest integer (ties to even), as a float and as an integer; exact for
/// |x| < 2^22. Float-to-int `as` casts saturate and catch NaN, which costs compares and
/// keeps loops scalar; this reads the integer out of the rounded float's bits instead.
#[inline(always)]
pub fn round_to_int(x: f32) -> (f32, i32) {
    let t = x + ROUND;
    (t - ROUND, t.to_bits().wrapping_sub(ROUND.to_bits()) as i32)
}

/// `libm::roundf(x) as i32` (halves away from zero, saturating, NaN to 0) without the call:
/// the channel of every bearing is its frequency so rounded, several times a solve. Below
/// 2^23 in magnitude the fraction x - trunc(x) is exact; above, x is whole.
#[inline]
pub fn round_half_away(x: f32) -> i32 {
    if !(libm::fabsf(x) < 8_388_608.0) {
        return x as i32;
    }
    let whole = x as i32;
    let fraction = x - whole as f32;
    whole + i32::from(fraction >= 0.5) - i32::from(fraction <= -0.5)
}

/// [`round_half_away`] in f64: `libm::round(x) as i64`, exact the same way below 2^52 (a live
/// worker's channel of each bearing its window holds, at every solve).
#[inline]
pub fn round_half_away_f64(x: f64) -> i64 {
    if !(libm::fabs(x) < 4_503_599_627_370_496.0) {
        return x as i64;
    }
    let whole = x as i64;
    let fraction = x - whole as f64;
    whole + i64::from(fraction >= 0.5) - i64::from(fraction <= -0.5)
}

/// e^x for x <= 0 (log-weights shifted by their maximum). Relative error < 3e-7; 0 below
/// e^-87.33 (subnormal weights are negligible beside the maximum's 1); NaN stays NaN.
#[inline(always)]
pub fn exp_nonpositive(x: f32) -> f32 {
    // ln 2 split so that n * LN2_HI is exact for |n| < 2^9.
    const LN2_HI: f32 = 0.693_359_4;
    const LN2_LO: f32 = -2.121_944_4e-4;
    let xc = if x < EXP_MIN { EXP_MIN } else { x };
    let (n, ni) = round_to_int(xc * LOG2_E);
    let r = (xc - n * LN2_HI) - n * LN2_LO;
    let p = ((((1.987_569_2e-4 * r + 1.398_199_9e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r
        + 0.166_666_65)
        * r
        + 0.5;
    let er = p * (r * r) + r + 1.0;
    // 2^n built from its exponent bits: n is in [-126, 0] after the clamp.
    let scale = f32::from_bits((ni.wrapping_add(127) as u32) << 23);
    let y = er * scale;
    if x < EXP_MIN {
        0.0
    } else if x.is_nan() {
        x
    } else {
        y
    }
}

/// sqrt(x), within 2 ulp. Where the target has a square-root instruction that `libm`
/// reaches (SSE2, AArch64 NEON) this is `libm::sqrtf`, correctly rounded. Elsewhere (the
/// Cortex-M4F: its VSQRT needs `unsafe` asm, which this crate forbids) `libm::sqrtf` is a
/// software loop of about a hundred instructions and the swarms take one per particle pair, so
/// this is [`sqrt_newton`]: a dozen multiplies. The swarms' moves may then differ in the last
/// bits between such a target and the host; the SIR path takes no square root per particle.
#[inline(always)]
pub fn sqrt(x: f32) -> f32 {
    if cfg!(any(
        target_feature = "sse2",
        all(target_arch = "aarch64", target_feature = "neon")
    )) {
        libm::sqrtf(x)
    } else {
        sqrt_newton(x)
    }
}

/// sqrt(x) within 2 ulp by multiplies alone: the exponent-halving guess of 1/sqrt(x), two
/// Newton steps and one correction of the product x / sqrt(x). Zero, subnormals, infinity,
/// negatives and NaN take `libm` (exact, and rare).
#[inline(always)]
pub fn sqrt_newton(x: f32) -> f32 {
    if !(f32::MIN_POSITIVE..f32::INFINITY).contains(&x) {
        return libm::sqrtf(x);
    }
    let h = 0.5 * x;
    let mut y = f32::from_bits(0x5f37_5a86u32.wrapping_sub(x.to_bits() >> 1));
    y *= 1.5 - h * y * y;
    y *= 1.5 - h * y * y;
    let s = x * y;
    s + y * (h - 0.5 * s * s)
}

/// (sin x, cos x), absolute error < 3e-7 for |x| <= 8192 (bearings and their sums); beyond
/// that, and for NaN or infinity, `libm::sincosf`. `libm`'s is computed in f64, which the
/// Cortex-M4F emulates in software: about two thousand instructions, once per measurement,
/// 20 per particle at N = 100. Cody-Waite reduction by pi/2 (three parts, exact products
/// for |n| < 2^13) and Cephes' minimax polynomials on [-pi/4, pi/4].
#[inline]
pub fn sincos(x: f32) -> (f32, f32) {
    const P1: f32 = 1.570_312_5;
    const P2: f32 = 4.837_513e-4;
    const P3: f32 = 7.549_79e-8;
    if !(libm::fabsf(x) <= 8192.0) {
        return libm::sincosf(x);
    }
    let (n, quadrant) = round_to_int(x * core::f32::consts::FRAC_2_PI);
    let r = ((x - n * P1) - n * P2) - n * P3;
    let z = r * r;
    let sin = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * r + r;
    let cos = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    match quadrant & 3 {
        0 => (sin, cos),
        1 => (cos, -sin),
        2 => (-sin, -cos),
        _ => (-cos, sin),
    }
}

/// atan2(y, x) in [-pi, pi], absolute error < 3e-7 rad. Quadrant and signed zeros as `libm`
/// for finite input; NaN in gives NaN out (infinite input may too: callers treat a particle
/// with a NaN log-likelihood as impossible).
#[inline(always)]
pub fn atan2(y: f32, x: f32) -> f32 {
    const TAN_PI_8: f32 = 0.414_213_57;
    let (ax, ay) = (libm::fabsf(x), libm::fabsf(y));
    let (lo, hi) = if ay > ax { (ax, ay) } else { (ay, ax) };
    // atan(lo / hi) with lo / hi in [0, 1]; above tan(pi/8) use
    // atan(a) = pi/4 + atan((a - 1) / (a + 1)), written on lo and hi to keep one division.
    let wide = lo > TAN_PI_8 * hi;
    let (num, den, base) = if wide {
        (lo - hi, lo + hi, FRAC_PI_4)
    } else {
        (lo, hi, 0.0)
    };
    // 0 / 0 (the origin) is defined as angle 0, as libm does.
    let t = if den > 0.0 { num / den } else { 0.0 };
    let z = t * t;
    let a = base
        + (((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z * t
        + t;
    let a = if ay > ax { FRAC_PI_2 - a } else { a };
    let a = if x.is_sign_negative() { PI - a } else { a };
    let a = if y.is_sign_negative() { -a } else { a };
    if x.is_nan() || y.is_nan() {
        f32::NAN
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounds_halves_away_from_zero_as_libm_does() {
        let mut bits = 0x9e37_79b9u32;
        let edges = [
            0.5f32,
            -0.5,
            1.5,
            -1.5,
            2.5,
            0.499_999_97,
            -0.499_999_97,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            3e9,
            -3e9,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            -0.0,
        ];
        let random = (0..200_000).map(|_| {
            bits ^= bits << 13;
            bits ^= bits >> 17;
            bits ^= bits << 5;
            f32::from_bits(bits)
        });
        let near = (0..20_000).map(|k| (k as f32 - 10_000.0) * 0.25 + 0.5);
        for x in edges.into_iter().chain(random).chain(near) {
            assert_eq!(round_half_away(x), libm::roundf(x) as i32, "{x}");
            let wide = f64::from(x) * 1000.0 + 0.5;
            assert_eq!(
                round_half_away_f64(wide),
                libm::round(wide) as i64,
                "{wide}"
            );
        }
    }

    #[test]
    fn rounds_to_nearest() {
        for (x, n) in [
            (0.4f32, 0),
            (0.6, 1),
            (-0.6, -1),
            (2.5, 2),
            (-126.2, -126),
            (4e6, 4_000_000),
        ] {
            assert_eq!(round_to_int(x), (n as f32, n), "{x}");
        }
    }

    #[test]
    fn exp_matches_libm() {
        let mut worst = 0.0f64;
        let mut x = 0.0f32;
        while x > -87.0 {
            let exact = libm::exp(x as f64);
            let rel = ((exp_nonpositive(x) as f64 - exact) / exact).abs();
            worst = worst.max(rel);
            x -= 1.37e-4;
        }
        // A few ulp of f32 (1 ulp = 6e-8 relative at best, 1.2e-7 at worst).
        assert!(worst < 3e-7, "worst relative error {worst}");
        assert_eq!(exp_nonpositive(0.0), 1.0);
        assert_eq!(exp_nonpositive(-100.0), 0.0);
        assert_eq!(exp_nonpositive(f32::NEG_INFINITY), 0.0);
        assert!(exp_nonpositive(f32::NAN).is_nan());
    }

    #[test]
    fn atan2_matches_libm() {
        let mut worst = 0.0f64;
        // Every direction, at radii from 1e-30 to 1e30.
        for k in 0..200_000 {
            let phi = -3.2 + 6.4 * k as f64 / 200_000.0;
            for r in [1e-30f64, 1e-3, 1.0, 317.0, 1e7, 1e30] {
                let (y, x) = ((r * phi.sin()) as f32, (r * phi.cos()) as f32);
                let exact = libm::atan2(y as f64, x as f64);
                worst = worst.max((atan2(y, x) as f64 - exact).abs());
            }
        }
        assert!(worst < 3e-7, "worst absolute error {worst} rad");
        // Axes and signed zeros as libm.
        for (y, x) in [
            (0.0f32, 1.0f32),
            (0.0, -1.0),
            (-0.0, -1.0),
            (1.0, 0.0),
            (-1.0, 0.0),
            (0.0, 0.0),
            (-0.0, 0.0),
            (3.0, -3.0),
        ] {
            assert!(
                (atan2(y, x) - libm::atan2f(y, x)).abs() < 3e-7,
                "({y}, {x})"
            );
        }
        assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan());
    }

    #[test]
    fn sqrt_matches_libm() {
        let mut worst = 0.0f64;
        // Every binade from the smallest normal to the largest finite, 4 000 points each.
        let mut x = f32::MIN_POSITIVE;
        while x < f32::MAX / 2.0 {
            for k in 0..4000 {
                let v = x * (1.0 + k as f32 / 4000.0);
                let exact = libm::sqrt(v as f64);
                worst = worst.max(((sqrt_newton(v) as f64 - exact) / exact).abs());
            }
            x *= 2.0;
        }
        // 2 ulp at worst (1 ulp is 1.2e-7 relative at most).
        assert!(worst < 2.4e-7, "worst relative error {worst}");
        for v in [0.0f32, -0.0, 1e-40, 1.0, 4.0, f32::INFINITY] {
            assert_eq!(sqrt_newton(v), libm::sqrtf(v), "{v}");
        }
        assert!((sqrt_newton(f32::MAX) / libm::sqrtf(f32::MAX) - 1.0).abs() < 2.4e-7);
        assert!(sqrt_newton(-1.0).is_nan() && sqrt_newton(f32::NAN).is_nan());
    }

    #[test]
    fn sincos_matches_libm() {
        let mut worst = 0.0f64;
        let mut x = -8192.0f32;
        while x <= 8192.0 {
            let (s, c) = sincos(x);
            worst = worst
                .max((s as f64 - libm::sin(x as f64)).abs())
                .max((c as f64 - libm::cos(x as f64)).abs());
            x += 0.000_731 * (1.0 + x.abs());
        }
        for k in -100_000..=100_000 {
            let x = k as f32 * 4e-5;
            let (s, c) = sincos(x);
            worst = worst
                .max((s as f64 - libm::sin(x as f64)).abs())
                .max((c as f64 - libm::cos(x as f64)).abs());
        }
        assert!(worst < 3e-7, "worst absolute error {worst}");
        assert_eq!(sincos(1e6), libm::sincosf(1e6));
        assert!(sincos(f32::NAN).0.is_nan() && sincos(f32::INFINITY).1.is_nan());
    }
}
