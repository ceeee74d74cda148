//! End-to-end tests across the foxhunt crates live in `tests/`; this library holds what they
//! share: a scenario's table for chosen methods, and a row of it by method name.
#![deny(missing_docs)]

use foxhunt_core::Method;
use foxhunt_sim::outputs::tables::Row;
use foxhunt_sim::runs::montecarlo::{Progress, bench};
use foxhunt_sim::runs::scenario::Scenario;

/// The bench rows of canonical scenario `name` for `methods` (and their equal-cost rows), over
/// `runs` seeded runs (`None`: the scenario's own count) at its particle counts.
pub fn table(name: &str, methods: &[Method], runs: Option<usize>) -> Vec<Row> {
    let mut s = Scenario::named(name).unwrap_or_else(|| panic!("{name} is canonical"));
    s.methods = methods.to_vec();
    if let Some(r) = runs {
        s.runs = r;
    }
    bench(&s, &Progress::new(0, false))
}

/// The row of `method` (a registry name, or `baseline=swarm`).
pub fn row<'a>(rows: &'a [Row], method: &str) -> &'a Row {
    rows.iter()
        .find(|r| r.method == method)
        .unwrap_or_else(|| panic!("no {method} row in {rows:?}"))
}

/// The row's rmse / bound, which every row of a canonical table has.
pub fn ratio(rows: &[Row], method: &str) -> f64 {
    row(rows, method)
        .ratio
        .unwrap_or_else(|| panic!("{method}: no ratio"))
}

/// The row's error figure (rmse for a static emitter, mean error for tracking).
pub fn error(rows: &[Row], method: &str) -> f64 {
    row(rows, method)
        .rmse
        .unwrap_or_else(|| panic!("{method}: no estimate"))
}
