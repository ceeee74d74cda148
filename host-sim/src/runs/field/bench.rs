//! The field bench: the pipeline beside the plain methods on every condition.

use super::Condition;
use super::drives::simulate;
use super::judge::THREE_SIGMA_TAIL;
use super::judge::measure;
use crate::outputs::tables::Row;
use foxhunt_core::Method;
use foxhunt_core::fix::bias::BiasPrior;
use foxhunt_core::fix::consistency::ellipse_scale;
use foxhunt_core::fix::ellipse::mahalanobis;
use foxhunt_core::fix::locate::LocateConfig;
use foxhunt_core::model::bearing::Bearing;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use rayon::prelude::*;

use super::judge::bound_with;

/// The estimators the field bench compares: the pipeline, and for context the plain fixes and
/// filters a user could ask `locate` for (run as `locate` runs them: noise estimated from the
/// residuals, no offset, one emitter from all bearings).
pub const BENCH_METHODS: [Method; 7] = [
    Method::MlRobust,
    Method::Ml,
    Method::MlHuber,
    Method::SirRobust,
    Method::Gpf,
    Method::Ekf,
    Method::Unit,
];

/// Particles of the particle methods in the field bench (what `locate` uses).
const BENCH_PARTICLES: usize = 1000;

/// A field-bench row with nothing measured yet.
fn row(label: &str, method: Method, runs: usize) -> Row {
    Row::new(label.to_string(), method, BENCH_PARTICLES, runs)
}

/// The pipeline's rows for a condition: one per true emitter.
fn pipeline_rows(c: Condition, runs: usize) -> Vec<Row> {
    let t = std::time::Instant::now();
    let config = LocateConfig::default();
    let s = measure(c, runs, &config, BiasPrior::default());
    let seconds = t.elapsed().as_secs_f64() / runs.max(1) as f64;
    let label = format!("field/{}", c.name());
    let mut note = Vec::new();
    if c == Condition::Multipath {
        note.push(format!(
            "ghost reported as another source in {} of {runs}",
            s.ghost_reported
        ));
    }
    if s.direction_found > 0 {
        note.push(format!(
            "a direction-dependent error found and modelled in {} of {runs}",
            s.direction_found
        ));
    }
    if s.per_emitter.is_empty() {
        let mut r = row(&label, Method::MlRobust, runs);
        r.found = Some((runs - s.no_emitter) as f64 / runs.max(1) as f64);
        r.time_s = seconds;
        r.note = Some(format!(
            "no consistent emitter in {} of {runs} runs (there is none)",
            s.no_emitter
        ));
        return vec![r];
    }
    let several = s.per_emitter.len() > 1;
    s.per_emitter
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let label = if several {
                format!("{label}#{}", i + 1)
            } else {
                label.clone()
            };
            let mut r = row(&label, Method::MlRobust, runs);
            let found = e.found.max(1) as f64;
            r.found = Some(e.found as f64 / runs.max(1) as f64);
            r.time_s = seconds;
            if e.found > 0 {
                r.rmse = Some(e.rmse);
                r.coverage = Some(e.covered as f64 / found);
                r.cep50_share = Some(e.within_cep50 as f64 / found);
                r.beyond_3_sigma = Some(e.beyond_3_sigma);
            }
            r.crlb = Some(e.bound).filter(|b| b.is_finite());
            r.ratio = r.rmse.zip(r.crlb).map(|(e, b)| e / b);
            r.failures = runs - e.found;
            let mut n = note.clone();
            n.push(format!("mean offset {:.2} deg", e.mean_bias_deg));
            if e.regions > 0 {
                n.push(format!(
                    "an open range's region in {} runs, holding the truth in {}; fixes and \
                     regions held it in {:.1} %",
                    e.regions,
                    e.regions_covered,
                    100.0 * e.answer_coverage()
                ));
            }
            r.note = Some(n.join("; "));
            r
        })
        .collect()
}

/// One plain-method run judged: error (m; NaN with no truth), inside the 95 % ellipse, within
/// CEP50, beyond 3 sigma, the bias-aware bound (m).
type Judged = (f64, bool, bool, bool, f64);

/// A plain method's row for a condition: one fix from all bearings, judged against the
/// nearest true emitter.
fn method_row(c: Condition, m: Method, runs: usize) -> Row {
    let label = format!("field/{}", c.name());
    let t = std::time::Instant::now();
    let outcomes: Vec<Option<Judged>> = crate::estimate::pool().install(|| {
        (0..runs)
            .into_par_iter()
            .map(|run| {
                let d = simulate(c, run);
                let bearings: Vec<Bearing> = d.observations.iter().map(|o| o.bearing).collect();
                let mut rng = XorShiftRng::seed_from_u64(run as u64);
                let (f, _) = crate::estimate::noise::with_estimated_noise(
                    m,
                    BENCH_PARTICLES,
                    0.0,
                    &bearings,
                    false,
                    &mut rng,
                )
                .ok()?;
                let Some(t) = d.emitters.iter().min_by(|a, b| {
                    let da = (a.position[0] - f.position[0]).hypot(a.position[1] - f.position[1]);
                    let db = (b.position[0] - f.position[0]).hypot(b.position[1] - f.position[1]);
                    da.total_cmp(&db)
                }) else {
                    // No emitter at all (pure noise): any fix is a wrong one.
                    return Some((f64::NAN, false, false, true, f64::NAN));
                };
                let m =
                    mahalanobis(&f.covariance, &f.position, &t.position).unwrap_or(f32::INFINITY);
                let error = (f.position[0] - t.position[0]).hypot(f.position[1] - t.position[1]);
                let priors = c.priors(&d, BiasPrior::default());
                let bound = f64::from(bound_with(&d, t, &priors));
                Some((
                    error as f64,
                    m * m <= f.ellipse_scale,
                    error <= f.cep50,
                    // Beyond the 99.73 % region of the fix's own distribution (2 F(2, dof)).
                    m * m > ellipse_scale(1.0 - THREE_SIGMA_TAIL, f.dof).unwrap_or(f32::INFINITY),
                    bound,
                ))
            })
            .collect()
    });
    let mut r = row(&label, m, runs);
    r.time_s = t.elapsed().as_secs_f64() / runs.max(1) as f64;
    let ok: Vec<_> = outcomes.iter().flatten().collect();
    r.failures = runs - ok.len();
    r.found = Some(ok.len() as f64 / runs.max(1) as f64);
    let judged: Vec<_> = ok.iter().filter(|o| o.0.is_finite()).collect();
    if judged.is_empty() {
        if !ok.is_empty() {
            r.note = Some(format!(
                "a fix in {} of {runs} runs where there is no emitter: the method cannot say so",
                ok.len()
            ));
        }
        return r;
    }
    let k = judged.len() as f64;
    r.rmse = Some((judged.iter().map(|o| o.0 * o.0).sum::<f64>() / k).sqrt());
    r.coverage = Some(judged.iter().filter(|o| o.1).count() as f64 / k);
    r.cep50_share = Some(judged.iter().filter(|o| o.2).count() as f64 / k);
    r.beyond_3_sigma = Some(judged.iter().filter(|o| o.3).count());
    let bound = (judged.iter().map(|o| o.4 * o.4).sum::<f64>() / k).sqrt();
    r.crlb = Some(bound).filter(|b| b.is_finite());
    r.ratio = r.rmse.zip(r.crlb).map(|(e, b)| e / b);
    if c == Condition::TwoEmitters {
        r.note = Some("one fix for two emitters, judged against the nearer".into());
    }
    r
}

/// The field bench: every condition of `conditions`, the pipeline and the plain methods, over
/// `runs` seeded runs each.
pub fn bench(conditions: &[Condition], runs: usize) -> Vec<Row> {
    let mut rows = Vec::new();
    for &c in conditions {
        rows.extend(pipeline_rows(c, runs));
        for &m in BENCH_METHODS.iter().skip(1) {
            rows.push(method_row(c, m, runs));
        }
    }
    rows
}
