//! `foxhunt perf`: the speed tables of the book (docs/src/speed.md).

use crate::outputs::terminal::{Out, Outcome, note};
use crate::runs::perf::{
    GROWTH_FILTERS, GROWTH_SIZES, growth, growth_table, numpy_table, scale, scale_table,
};

/// Options of `foxhunt perf`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Runs timed per particle count against the numpy peer (at least 1).
    #[arg(long, default_value_t = 20)]
    pub runs: usize,
    /// Seconds spent timing each cell of the growth table.
    #[arg(long, default_value_t = 0.5)]
    pub budget: f64,
    /// Skip a growth cell whose extrapolated step time exceeds this many seconds.
    #[arg(long, default_value_t = 30.0)]
    pub limit: f64,
    /// Leave out the numpy comparison.
    #[arg(long)]
    pub no_numpy: bool,
    /// Leave out the growth table.
    #[arg(long)]
    pub no_growth: bool,
    /// Add `locate` on large captures (a 1-hour drive at 20 bearings a second, and about
    /// 200 MB): time and peak memory.
    #[arg(long)]
    pub scale: bool,
}

/// Run `foxhunt perf`.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    if a.runs == 0 {
        return Err("--runs must be at least 1, not 0".into());
    }
    if !(a.budget > 0.0 && a.budget.is_finite() && a.limit > 0.0) {
        return Err(format!(
            "--budget and --limit must be positive seconds, not {} and {}",
            a.budget, a.limit
        )
        .into());
    }
    if !a.no_numpy {
        out.line(&numpy_table(a.runs)?)?;
        out.flush()?;
    }
    if !a.no_growth {
        let total = GROWTH_FILTERS.len() * GROWTH_SIZES.len();
        let mut done = 0;
        let rows = growth(a.budget, a.limit, |f, n| {
            done += 1;
            note(&format!("perf: timing {f} at N = {n} ({done}/{total})"));
        });
        out.line(&growth_table(&rows))?;
        out.flush()?;
    }
    if a.scale {
        out.line(&scale_table(&scale()?))?;
    }
    Ok(())
}
