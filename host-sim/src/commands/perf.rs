//! `foxhunt perf`: the speed tables of the book (docs/src/speed.md).

use crate::outputs::terminal::{Out, Outcome, Stop, note};
use crate::runs::perf::{
    GROWTH_FILTERS, GROWTH_SIZES, growth, growth_table, numpy_table, scale, scale_table,
};

/// Options of `foxhunt perf`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Runs timed per particle count against the numpy peer (at least 1).
    #[arg(long, default_value_t = 20, value_parser = super::values::count_at_least(1, "runs"))]
    pub runs: usize,
    /// Seconds spent timing each cell of the growth table.
    #[arg(long, default_value_t = 0.5,
          value_parser = super::values::f64_where(|s| s > 0.0 && s.is_finite(), "a number of seconds > 0"))]
    pub budget: f64,
    /// Skip a growth cell whose extrapolated step time exceeds this many seconds.
    #[arg(long, default_value_t = 30.0,
          value_parser = super::values::f64_where(|s| s > 0.0, "a number of seconds > 0"))]
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
    /// Instead: a network's load through the running broker at `mqtt://HOST[:PORT]/PREFIX`
    /// (--stations x --channels bearings every 1/--rate-hz s for --seconds, fused by a
    /// `locate --mqtt` worker): bearing-to-fix latency and the worker's peak memory.
    #[arg(long, value_name = "URL")]
    pub mqtt: Option<String>,
    /// With --mqtt: stations sending.
    #[arg(long, default_value_t = 3, requires = "mqtt",
          value_parser = super::values::count_at_least(1, "stations"))]
    pub stations: usize,
    /// With --mqtt: channels (one emitter each) every station hears.
    #[arg(long, default_value_t = 1, requires = "mqtt",
          value_parser = super::values::count_at_least(1, "channels"))]
    pub channels: usize,
    /// With --mqtt: bearings a second per station and channel.
    #[arg(long, default_value_t = 1.0, requires = "mqtt",
          value_parser = super::values::f64_where(|r| r > 0.0 && r <= 1000.0, "a rate in (0, 1000] Hz"))]
    pub rate_hz: f64,
    /// With --mqtt: seconds of sending.
    #[arg(long, default_value_t = 30.0, requires = "mqtt",
          value_parser = super::values::f64_where(|s| s > 0.0 && s <= 3600.0, "seconds in (0, 3600]"))]
    pub seconds: f64,
    /// Instead: the moving-emitter tracker at 1 000 and 10 000 particles on four fixed
    /// stations reporting at 10 Hz: times real time and peak memory.
    #[arg(long, conflicts_with = "mqtt")]
    pub track: bool,
    /// With --mqtt: workers, each fusing a shard of the channels (`locate --mqtt-shard`).
    #[arg(long, default_value_t = 1, requires = "mqtt",
          value_parser = clap::value_parser!(u32).range(1..=i64::from(crate::inputs::mqtt::MAX_SHARDS)))]
    pub workers: u32,
    /// With --mqtt: pin worker k to the k-th processor this process may use (modulo their
    /// count; Linux's `taskset`), so each worker solves on one core of its own: how the
    /// sharding scales, measured.
    #[arg(long, requires = "mqtt")]
    pub pin_workers: bool,
    /// With --mqtt: station k sends k/S of a period after station 0, as stations polling
    /// their receivers on their own clocks do; without it every station sends each tick at
    /// once (a burst: the worst case).
    #[arg(long, requires = "mqtt")]
    pub stagger: bool,
    /// With --mqtt: each worker's bearings kept per channel (`locate --mqtt-keep`).
    #[arg(long, value_name = "N", requires = "mqtt",
          value_parser = super::values::count_at_least(2, "bearings per channel"))]
    pub mqtt_keep: Option<usize>,
    /// With --mqtt: also write the run's latency and memory over time as an SVG plot here.
    #[arg(long, value_name = "FILE", requires = "mqtt")]
    pub svg: Option<std::path::PathBuf>,
}

/// Run `foxhunt perf`.
pub fn run(a: &Args, out: &mut Out) -> Outcome {
    if let Some(url) = &a.mqtt {
        let load = crate::runs::mqtt_load::Load {
            url: crate::inputs::mqtt::MqttUrl::parse(url).map_err(Stop::Usage)?,
            stations: a.stations,
            channels: a.channels,
            rate_hz: a.rate_hz,
            seconds: a.seconds,
            workers: a.workers,
            keep: a.mqtt_keep,
            pin: a.pin_workers,
            stagger: a.stagger,
        };
        let exe = std::env::current_exe().map_err(|e| e.to_string())?;
        let f = crate::runs::mqtt_load::run(&load, &exe)?;
        if let Some(path) = &a.svg {
            std::fs::write(path, crate::runs::mqtt_load::svg(&load, &f))
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        }
        out.line(&crate::runs::mqtt_load::table(&load, &f))?;
        return Ok(());
    }
    if a.track {
        use crate::runs::perf_track::{measure, table};
        let rows = measure(|n| note(&format!("perf: tracking at N = {n}")))?;
        out.line(&table(&rows))?;
        return Ok(());
    }
    if a.no_numpy && a.no_growth && !a.scale {
        return Err(Stop::usage(
            "--no-numpy and --no-growth leave nothing to time: drop one, or add --scale",
        ));
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
