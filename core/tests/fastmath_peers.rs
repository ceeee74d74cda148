//! Why the particle loops run on `fastmath` and not on `micromath`, the design card's fast
//! approximations for microcontrollers: measured against libm on the same dense grids, the
//! hand-written functions are within a few ulp where micromath is off by amounts a filter
//! notices (a bearing residual off by a thousandth of a radian is a tenth of a 1-degree sigma
//! on every particle; exp is wrong below about -88, where log-weights live).
//!
//! The test fails if fastmath loses its accuracy, or if micromath becomes as accurate (then the
//! hand-written code has no reason left: replace it and say so in docs/src/dependencies.md).

use foxhunt_core::fastmath;
use micromath::F32;

/// Largest |f(x) - reference(x)| over `xs`.
fn worst(
    xs: impl Iterator<Item = f32>,
    f: impl Fn(f32) -> f32,
    reference: impl Fn(f32) -> f32,
) -> f64 {
    xs.map(|x| (f64::from(f(x)) - f64::from(reference(x))).abs())
        .fold(0.0, f64::max)
}

fn grid(lo: f32, hi: f32, n: u32) -> impl Iterator<Item = f32> {
    (0..=n).map(move |k| lo + (hi - lo) * k as f32 / n as f32)
}

#[test]
fn fastmath_is_within_ulps_where_micromath_is_not() {
    // atan2 around the whole circle at radius 1 and 1e4 (the bearing residual's inputs).
    let angles = || grid(-std::f32::consts::PI, std::f32::consts::PI, 200_000);
    let mut ours = 0.0f64;
    let mut theirs = 0.0f64;
    for r in [1.0f32, 1.0e4] {
        let (y, x) = (move |t: f32| r * t.sin(), move |t: f32| r * t.cos());
        ours = ours.max(worst(
            angles(),
            |t| fastmath::atan2(y(t), x(t)),
            |t| libm::atan2f(y(t), x(t)),
        ));
        theirs = theirs.max(worst(
            angles(),
            |t| F32(y(t)).atan2(F32(x(t))).0,
            |t| libm::atan2f(y(t), x(t)),
        ));
    }
    // exp on the log-weights' range down to where f32 goes subnormal (relative error;
    // fastmath's is for x <= 0).
    let rel = |f: &dyn Fn(f32) -> f32| {
        grid(-87.0, 0.0, 200_000)
            .map(|x| {
                let e = f64::from(libm::expf(x));
                if e > 0.0 {
                    ((f64::from(f(x)) - e) / e).abs()
                } else {
                    0.0
                }
            })
            .fold(0.0, f64::max)
    };
    let exp_ours = rel(&fastmath::exp_nonpositive);
    let exp_theirs = rel(&|x| F32(x).exp().0);
    // sqrt of squared distances (the swarms'), relative error.
    let sqrt_rel = |f: &dyn Fn(f32) -> f32| {
        grid(1e-6, 1e8, 200_000)
            .map(|x| ((f64::from(f(x)) - f64::from(x).sqrt()) / f64::from(x).sqrt()).abs())
            .fold(0.0, f64::max)
    };
    let sqrt_ours = sqrt_rel(&fastmath::sqrt);
    let sqrt_theirs = sqrt_rel(&|x| F32(x).sqrt().0);
    println!(
        "largest error against libm: atan2 {ours:.2e} rad (micromath {theirs:.2e}); exp relative \
         {exp_ours:.2e} (micromath {exp_theirs:.2e}); sqrt relative {sqrt_ours:.2e} (micromath \
         {sqrt_theirs:.2e})"
    );
    // Ours: a few ulp of f32 (an ulp of pi is 2.4e-7; weights and distances relative).
    assert!(ours < 8e-7, "fastmath atan2 off by {ours:e} rad");
    assert!(exp_ours < 3e-7, "fastmath exp off by {exp_ours:e}");
    assert!(sqrt_ours < 3e-7, "fastmath sqrt off by {sqrt_ours:e}");
    // Theirs: at least ten times worse on every one, or the reason for fastmath is gone.
    assert!(
        theirs > 10.0 * ours,
        "micromath atan2 now within {theirs:e} rad"
    );
    assert!(
        exp_theirs > 10.0 * exp_ours,
        "micromath exp now within {exp_theirs:e}"
    );
    assert!(
        sqrt_theirs > 10.0 * sqrt_ours,
        "micromath sqrt now within {sqrt_theirs:e}"
    );
}
