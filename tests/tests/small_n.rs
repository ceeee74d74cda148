//! Honest at every sample size: every noise-estimating method's 95 % ellipse holds the truth as
//! often as it claims with 4 to 50 bearings (`foxhunt bench --scenario small-n`, the book's
//! field chapter, "Honest intervals"). The noise comes from n residuals with n - 2 degrees of
//! freedom, so the ellipse is 2 F(2, n - 2) wide: chi-square would claim 95 % and hold far less.
//!
//! Bars: 400 seeded runs a row, so a true 95 % is observed within 95 +- 2.2 % (two standard
//! errors); the bar 90-98 % leaves more than two standard errors on either side. With 4 and 5
//! bearings (2 and 3 degrees of freedom) the particle clouds' regions are conservative (98-100 %:
//! the cloud's spread of a skewed posterior on top of the F scaling): they claim less than they
//! could, never more, and only the lower bar is asserted there. The EKF answers only where its
//! estimate lies inside the bearings' own likelihood region (on 10 bearings about two runs in
//! three: started from a spread cloud it stops kilometres off in the others).

use foxhunt_core::Method;
use foxhunt_sim::runs::small_n::row;

const RUNS: usize = 400;

#[test]
fn every_noise_estimating_method_is_honest_with_a_handful_of_bearings() {
    let mut table = Vec::new();
    let mut failed = Vec::new();
    for n in [4, 5, 7, 10, 20, 50] {
        for m in [
            Method::Ml,
            Method::MlHuber,
            Method::Sir,
            Method::SirRobust,
            Method::Gpf,
            Method::Ekf,
            Method::MlRobust,
            Method::Unit,
        ] {
            // The field pipeline refuses fewer than 5 bearings and at 5 estimates an offset
            // from 2 degrees of freedom: asserted from 7 on (the book gives its n = 5 figure).
            if m == Method::MlRobust && n < 7 {
                continue;
            }
            let r = row(m, n, RUNS);
            let c = r.coverage.unwrap_or(0.0);
            table.push(format!(
                "n {n:>2} {:<10} coverage {:.3} found {:.2}",
                m.name(),
                c,
                r.found.unwrap_or(0.0)
            ));
            let upper = if n <= 5 { 1.0 } else { 0.98 };
            if !(0.90..=upper).contains(&c) {
                failed.push(format!("{} at n = {n}: {c:.3}", m.name()));
            }
        }
    }
    println!("{}", table.join("\n"));
    assert!(
        failed.is_empty(),
        "outside the bars: {failed:?}\n{}",
        table.join("\n")
    );
}
