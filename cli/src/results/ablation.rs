//! The observation ablations: each variant's trained policies (one per
//! training seed) evaluated on unseen episodes, and their learning curves
//! side by side.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::number::{fixed, mean_and_range};
use crate::eval::plots::{self, Curve};
use experiment::eval::EvalReport;
use experiment::eval::summary::Summary;

/// One trained policy of a variant and its evaluation.
pub struct Run<'a> {
    /// the variant
    pub variant: &'a str,
    /// the training seed
    pub seed: u64,
    /// the policy path
    pub policy: &'a str,
    /// its evaluation
    pub report: &'a EvalReport,
}

/// The success and distance per variant and seed, one row each.
pub fn markdown(runs: &[Run]) -> String {
    let mut out = String::from(
        "| variant | training seed | policy | terrain | success | distance, m (mean; min-max) | phases survived (mean) | falls by cause |\n| --- | ---: | --- | --- | ---: | --- | ---: | --- |\n",
    );
    for r in runs {
        let s = &r.report.summary;
        let _ = writeln!(
            out,
            "| {} | {} | {} | `{}` | {}/{} | {} | {:.1} | {} |",
            r.variant,
            r.seed,
            r.policy,
            r.report.terrain,
            s.successes,
            s.episodes,
            mean_and_range(&s.distance_m, 2),
            s.phases.mean,
            s.falls_text()
        );
    }
    out
}

/// The variants of `runs`, each once, in the order of first appearance.
fn variants<'a>(runs: &[Run<'a>]) -> Vec<&'a str> {
    let mut variants: Vec<&str> = Vec::new();
    for r in runs {
        if !variants.contains(&r.variant) {
            variants.push(r.variant);
        }
    }
    variants
}

/// Each variant's runs pooled, one row per variant in the order of first
/// appearance: its training seeds, the successes of each run and of all,
/// and the distance and speed over every episode of its runs.
pub fn variants_markdown(runs: &[Run]) -> String {
    let variants = variants(runs);
    let mut out = String::from(
        "| variant | training seeds | success per seed | success | distance, m (mean; min-max) | speed, m/s (mean) | falls by cause |\n| --- | --- | --- | ---: | --- | ---: | --- |\n",
    );
    let phase_secs = robot::action::PHASE_SECS;
    for variant in variants {
        let own: Vec<&Run> = runs.iter().filter(|r| r.variant == variant).collect();
        let episodes: Vec<_> = own
            .iter()
            .flat_map(|r| r.report.episodes.iter().cloned())
            .collect();
        let pooled = Summary::of(&episodes, phase_secs);
        let list =
            |f: &dyn Fn(&Run) -> String| own.iter().map(|r| f(r)).collect::<Vec<_>>().join(", ");
        let _ = writeln!(
            out,
            "| {} | {} | {} | {}/{} | {} | {} | {} |",
            variant,
            list(&|r| r.seed.to_string()),
            list(&|r| format!(
                "{}/{}",
                r.report.summary.successes, r.report.summary.episodes
            )),
            pooled.successes,
            pooled.episodes,
            mean_and_range(&pooled.distance_m, 2),
            fixed(pooled.mean_speed_m_per_s.mean, 3),
            pooled.falls_text()
        );
    }
    out
}

/// The `metrics.jsonl` of a policy: beside an exported policy, or in the
/// run directory of a checkpoint.
pub fn metrics_file(policy: &str) -> Result<PathBuf> {
    let path = Path::new(policy);
    let candidates = [
        path.join(experiment::train::run_dir::METRICS_FILE),
        path.parent().map_or_else(PathBuf::new, |p| {
            p.join(experiment::train::run_dir::METRICS_FILE)
        }),
    ];
    candidates
        .into_iter()
        .find(|p| p.is_file())
        .with_context(|| {
            format!(
                "policy {policy}: no {} beside it or in its run directory",
                experiment::train::run_dir::METRICS_FILE
            )
        })
}

/// Iterations in the trailing moving average of the learning curves: a
/// training iteration's mean distance is over 16-40 episodes, and the
/// variants' raw curves overlap beyond telling apart.
const CURVE_SMOOTHING_ITERATIONS: usize = 20;

/// The learning curves of every run, drawn to `path`: one panel per
/// training seed, one colour per variant (the same in every panel).
pub fn curves_png(path: &Path, runs: &[Run]) -> Result<()> {
    let variants = variants(runs);
    let mut seeds: Vec<u64> = runs.iter().map(|r| r.seed).collect();
    seeds.sort_unstable();
    seeds.dedup();
    let mut panels = Vec::new();
    for &seed in &seeds {
        let mut curves = Vec::new();
        for r in runs.iter().filter(|r| r.seed == seed) {
            let name = format!("{} (seed {seed})", r.variant);
            let run =
                crate::curves::read_metrics(&name, &metrics_file(r.policy)?, "mean_distance_m")?;
            curves.push(Curve {
                label: r.variant.to_string(),
                colour_index: variants.iter().position(|v| *v == r.variant).unwrap_or(0),
                points: run.smoothed_points(|p| p.0, CURVE_SMOOTHING_ITERATIONS),
            });
        }
        panels.push((format!("training seed {seed}"), curves));
    }
    let y_desc = format!(
        "mean distance per training episode, m ({CURVE_SMOOTHING_ITERATIONS}-iteration mean)"
    );
    let panels: Vec<plots::Panel> = panels
        .iter()
        .map(|(title, lines)| plots::Panel {
            title,
            x_desc: "phases trained",
            y_desc: &y_desc,
            lines,
        })
        .collect();
    plots::panels(path, &panels)
}
