//! The worlds' terrain levels between iterations (`[curriculum.levels]`):
//! where a run starts them, how a stage hands them to the next, and how
//! an iteration's metrics line records them.

use std::path::Path;

use anyhow::{Context, Result, bail};
use serde_json::json;

use crate::config::Experiment;

/// The levels the worlds of 0-based iteration `iteration` train on, for a
/// run that starts there: where the stage before also had levels, those
/// its last iteration's metrics line (`levels`) recorded; else every world
/// at the bottom.
pub fn start_levels(experiment: &Experiment, metrics: &Path, iteration: u64) -> Result<Vec<usize>> {
    let envs = experiment.train.envs;
    if iteration == 0 || experiment.levels_at(iteration - 1).is_none() {
        return Ok(vec![0; envs]);
    }
    let need = || {
        format!(
            "iteration {iteration} trained on terrain levels; the run goes on from the levels its worlds reached, which {} records",
            metrics.display()
        )
    };
    let text = std::fs::read_to_string(metrics).with_context(need)?;
    for line in text.lines() {
        let record: serde_json::Value = serde_json::from_str(line).with_context(need)?;
        if record["iteration"].as_u64() != Some(iteration) {
            continue;
        }
        let levels: Vec<usize> = serde_json::from_value(record["levels"].clone())
            .with_context(|| format!("{}: its line has no levels", need()))?;
        if levels.len() != envs {
            bail!(
                "{}: it records {} levels for {envs} worlds",
                need(),
                levels.len()
            );
        }
        return Ok(levels);
    }
    bail!("{}: its line is missing", need())
}

/// The levels a new stage starts its worlds on: the previous stage's,
/// clamped to this stage's top, where both have levels; else the bottom.
pub fn carry_levels(
    experiment: &Experiment,
    previous: Option<u64>,
    iteration: u64,
    levels: &[usize],
) -> Vec<usize> {
    match (
        previous.and_then(|p| experiment.levels_at(p)),
        experiment.levels_at(iteration),
    ) {
        (Some(_), Some(now)) => levels.iter().map(|&l| l.min(now.top())).collect(),
        _ => vec![0; levels.len()],
    }
}

/// Adds the worlds' levels after an iteration to its metrics line:
/// `levels`, one per world (what a resumed run reads back), and their
/// mean, `mean_level`.
pub fn add_to_record(record: &mut serde_json::Value, levels: &[usize]) {
    let mean = levels.iter().sum::<usize>() as f64 / levels.len().max(1) as f64;
    record["levels"] = json!(levels);
    record["mean_level"] = json!(mean);
}
