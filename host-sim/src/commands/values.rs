//! Flag values checked as clap parses them: a value outside its range is a usage error (exit
//! status 2), and clap's message quotes the text as it was given (`1e308`, not the `inf` an
//! `f32` would make of it).
//!
//! Each parser is a function of the text, so `--help` and the message name the flag; the
//! message says what the flag wants (`invalid value '100000' for '--sigma-deg <DEG>': not a
//! number of degrees between 0 and 90`).

use foxhunt_core::PARTICLE_COUNTS;

/// A number as `f64` from the text (`inf` and `nan` as Rust reads them), or why not.
fn number(text: &str) -> Result<f64, String> {
    text.trim()
        .parse::<f64>()
        .map_err(|_| "not a number".to_string())
}

/// An `f64` flag that `ok` accepts; `wants` says what it wants ("a number of seconds >= 0").
pub fn f64_where(
    ok: fn(f64) -> bool,
    wants: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |text| {
        let x = number(text)?;
        if ok(x) {
            Ok(x)
        } else {
            Err(format!("not {wants}"))
        }
    }
}

/// An `f32` flag that `ok` accepts (judged on the `f64` of the text, and its `f32` finite
/// where the `f64` is).
pub fn f32_where(
    ok: fn(f64) -> bool,
    wants: &'static str,
) -> impl Fn(&str) -> Result<f32, String> + Clone + Send + Sync + 'static {
    move |text| {
        let x = number(text)?;
        if !ok(x) {
            return Err(format!("not {wants}"));
        }
        let y = x as f32;
        if x.is_finite() && !y.is_finite() {
            return Err(format!("not {wants} (beyond a 32-bit float)"));
        }
        Ok(y)
    }
}

/// A whole number of at least `min` (`wants` names the unit: "runs").
pub fn count_at_least(
    min: usize,
    wants: &'static str,
) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
    move |text| match text.trim().parse::<usize>() {
        Ok(n) if n >= min => Ok(n),
        _ => Err(format!("not a whole number of {wants} >= {min}")),
    }
}

/// A particle count the core is compiled for.
pub fn particles(text: &str) -> Result<usize, String> {
    match text.trim().parse::<usize>() {
        Ok(n) if PARTICLE_COUNTS.contains(&n) => Ok(n),
        _ => Err(format!(
            "not a compiled particle count: one of {}",
            PARTICLE_COUNTS.map(|n| n.to_string()).join(", ")
        )),
    }
}

/// Seconds, at least 0 and finite.
pub fn seconds() -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    f64_where(|s| s >= 0.0 && s.is_finite(), "a number of seconds >= 0")
}

/// A share of records, in [0, 1].
pub fn share() -> impl Fn(&str) -> Result<f32, String> + Clone + Send + Sync + 'static {
    f32_where(|x| (0.0..=1.0).contains(&x), "a share between 0 and 1")
}

/// `LAT,LON` in decimal degrees, latitude in [-90, 90] and longitude in [-180, 180].
pub fn lat_lon(text: &str) -> Result<[f64; 2], String> {
    let bad = || "not LAT,LON in decimal degrees (latitude -90 to 90, longitude -180 to 180)";
    let (lat, lon) = text.split_once(',').ok_or_else(bad)?;
    let p: [f64; 2] = [
        lat.trim().parse().map_err(|_| bad())?,
        lon.trim().parse().map_err(|_| bad())?,
    ];
    if p[0].abs() <= 90.0 && p[1].abs() <= 180.0 {
        Ok(p)
    } else {
        Err(bad().into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_judged_as_given() {
        let sigma = f32_where(
            |x| x > 0.0 && x < 90.0,
            "a number of degrees between 0 and 90",
        );
        assert_eq!(sigma("2.5"), Ok(2.5));
        for bad in ["0", "90", "NaN", "inf", "-1", "x", "100000"] {
            assert!(sigma(bad).is_err(), "{bad}");
        }
        // Finite as text, infinite as f32: refused, not turned into inf.
        let any = f32_where(|x| x > 0.0, "a positive number");
        assert!(any("1e308").is_err_and(|e| e.contains("32-bit")));
        assert_eq!(seconds()("inf").map_err(|_| ()), Err(()));
        assert_eq!(count_at_least(1, "runs")("0").map_err(|_| ()), Err(()));
        assert_eq!(particles("1000"), Ok(1000));
        assert!(particles("123").is_err_and(|e| e.contains("1000")));
        assert_eq!(lat_lon(" 47.5, -8"), Ok([47.5, -8.0]));
        for bad in ["95,8", "47", "a,b", "47,181"] {
            assert!(lat_lon(bad).is_err(), "{bad}");
        }
        assert!(share()("1.5").is_err() && share()("-0.1").is_err() && share()("0.1").is_ok());
    }
}
