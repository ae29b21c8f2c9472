//! `quadwalk curves`: the learning curves of training runs side by side, by
//! phases collected and by wall time, in one PNG (a recipe against
//! another, a lever against none).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;

use crate::eval::plots::{self, Curve, Panel};

/// `quadwalk curves` arguments.
#[derive(Debug, Args)]
pub struct CurvesArgs {
    /// Runs to draw: run directories or exported policies (each with its
    /// `metrics.jsonl`), as NAME=DIR to name one in the legend
    #[arg(required = true, value_name = "RUN")]
    runs: Vec<String>,
    /// The PNG to write
    #[arg(long)]
    out: PathBuf,
    /// The metrics key to draw (any number in `metrics.jsonl`; a dotted key
    /// such as `falls_by_cause.pitch_too_large` reads inside an object)
    #[arg(long, default_value = "mean_distance_m")]
    metric: String,
    /// Iterations in the trailing moving average (1: none)
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u64).range(1..))]
    smooth: u64,
}

/// One run's curve: per iteration, phases so far, wall seconds so far and
/// the metric.
#[derive(Debug, Clone, PartialEq)]
pub struct RunCurve {
    /// its legend name
    pub name: String,
    /// (phases so far, wall seconds so far, metric), one per iteration
    pub points: Vec<(f64, f64, f64)>,
}

impl RunCurve {
    /// (x, metric) per iteration, x read off each point by `x` and the
    /// metric [`smoothed`] over `window` iterations.
    pub fn smoothed_points(
        &self,
        x: fn(&(f64, f64, f64)) -> f64,
        window: usize,
    ) -> Vec<(f64, f64)> {
        let metric: Vec<f64> = self.points.iter().map(|p| p.2).collect();
        self.points
            .iter()
            .map(x)
            .zip(smoothed(&metric, window))
            .collect()
    }
}

/// Reads `metrics.jsonl` of `dir`: cumulative phases, cumulative wall time
/// (each iteration's `phases / phases_per_s`) and `metric`.
pub fn read_run(name: &str, dir: &Path, metric: &str) -> Result<RunCurve> {
    read_metrics(
        name,
        &dir.join(experiment::train::run_dir::METRICS_FILE),
        metric,
    )
}

/// [`read_run`] of the metrics file at `path`.
pub fn read_metrics(name: &str, path: &Path, metric: &str) -> Result<RunCurve> {
    let path = path.to_path_buf();
    let text = std::fs::read_to_string(&path)
        .with_context(|| format!("run {name}: cannot read {}", path.display()))?;
    let (mut phases, mut secs, mut points) = (0.0, 0.0, Vec::new());
    for (k, line) in text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
    {
        let record: serde_json::Value = serde_json::from_str(line)
            .with_context(|| format!("{}:{}: not JSON", path.display(), k + 1))?;
        // a dotted key names a value inside an object: `reward_terms.distance`
        let number = |key: &str| {
            record
                .pointer(&format!("/{}", key.replace('.', "/")))
                .and_then(serde_json::Value::as_f64)
                .with_context(|| format!("{}:{}: no number {key:?}", path.display(), k + 1))
        };
        let n = number("phases")?;
        phases += n;
        secs += n / number("phases_per_s")?;
        points.push((phases, secs, number(metric)?));
    }
    if points.is_empty() {
        bail!("run {name}: {} has no iterations", path.display());
    }
    Ok(RunCurve {
        name: name.to_string(),
        points,
    })
}

/// The trailing moving average of `values` over `window` entries.
pub fn smoothed(values: &[f64], window: usize) -> Vec<f64> {
    let mut sum = 0.0;
    values
        .iter()
        .enumerate()
        .map(|(i, v)| {
            sum += v;
            if i >= window {
                sum -= values[i - window];
            }
            sum / (i + 1).min(window) as f64
        })
        .collect()
}

/// `quadwalk curves`.
pub fn curves(args: &CurvesArgs) -> Result<()> {
    let runs: Vec<RunCurve> = args
        .runs
        .iter()
        .map(|arg| {
            let (name, dir) = match arg.split_once('=') {
                Some((name, dir)) => (name.to_string(), PathBuf::from(dir)),
                None => (arg.clone(), PathBuf::from(arg)),
            };
            read_run(&name, &dir, &args.metric)
        })
        .collect::<Result<_>>()?;
    let line = |k: usize, run: &RunCurve, x: fn(&(f64, f64, f64)) -> f64| Curve {
        label: run.name.clone(),
        colour_index: k,
        points: run.smoothed_points(x, args.smooth as usize),
    };
    let by_phases: Vec<Curve> = runs
        .iter()
        .enumerate()
        .map(|(k, r)| line(k, r, |p| p.0 / 1000.0))
        .collect();
    let by_time: Vec<Curve> = runs
        .iter()
        .enumerate()
        .map(|(k, r)| line(k, r, |p| p.1 / 60.0))
        .collect();
    let y_desc = format!("{} ({}-iteration mean)", args.metric, args.smooth);
    plots::panels(
        &args.out,
        &[
            Panel {
                title: "by phases collected",
                x_desc: "phases (thousands)",
                y_desc: &y_desc,
                lines: &by_phases,
            },
            Panel {
                title: "by wall time of the iterations",
                x_desc: "minutes",
                y_desc: &y_desc,
                lines: &by_time,
            },
        ],
    )?;
    for run in &runs {
        let (phases, secs, _) = run.points[run.points.len() - 1];
        println!(
            "{}: {} iterations, {:.0} phases, {:.1} min",
            run.name,
            run.points.len(),
            phases,
            secs / 60.0
        );
    }
    println!("wrote {}", args.out.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_moving_average_trails_and_starts_short() {
        assert_eq!(smoothed(&[1.0, 3.0, 5.0, 7.0], 2), [1.0, 2.0, 4.0, 6.0]);
        assert_eq!(smoothed(&[2.0, 4.0], 1), [2.0, 4.0]);
    }

    #[test]
    fn a_run_accumulates_phases_and_time_and_names_what_is_missing() {
        let tmp = tempfile::tempdir().unwrap();
        std::fs::write(
            tmp.path().join("metrics.jsonl"),
            "{\"phases\":640,\"phases_per_s\":64.0,\"mean_distance_m\":0.5}\n{\"phases\":640,\"phases_per_s\":128.0,\"mean_distance_m\":1.0}\n",
        )
        .unwrap();
        let run = read_run("a", tmp.path(), "mean_distance_m").unwrap();
        assert_eq!(run.points, [(640.0, 10.0, 0.5), (1280.0, 15.0, 1.0)]);
        std::fs::write(
            tmp.path().join("metrics.jsonl"),
            "{\"phases\":640,\"phases_per_s\":64.0,\"falls_by_cause\":{\"pitch_too_large\":0.25}}\n",
        )
        .unwrap();
        let run = read_run("a", tmp.path(), "falls_by_cause.pitch_too_large").unwrap();
        assert_eq!(run.points, [(640.0, 10.0, 0.25)]);
        let err = format!(
            "{:#}",
            read_run("a", tmp.path(), "falls_by_cause.base_too_low").unwrap_err()
        );
        assert!(err.contains("\"falls_by_cause.base_too_low\""), "{err}");
        std::fs::write(
            tmp.path().join("metrics.jsonl"),
            "{\"phases\":640,\"phases_per_s\":64.0,\"mean_distance_m\":0.5}\n{\"phases\":640,\"phases_per_s\":128.0,\"mean_distance_m\":1.0}\n",
        )
        .unwrap();
        let err = format!("{:#}", read_run("a", tmp.path(), "kl").unwrap_err());
        assert!(err.contains("line 1") || err.contains(":1:"), "{err}");
        assert!(err.contains("\"kl\""), "{err}");
        let err = format!(
            "{:#}",
            read_run("b", &tmp.path().join("none"), "kl").unwrap_err()
        );
        assert!(err.contains("run b: cannot read"), "{err}");
    }
}
