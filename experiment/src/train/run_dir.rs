//! The files of a run directory: the resolved config, the metrics lines,
//! checkpoints (written atomically, the newest few kept) and a fork's note.
//!
//! | path | content |
//! | --- | --- |
//! | `config.toml` | the resolved experiment (every setting spelt out) |
//! | `metrics.jsonl` | one JSON object per iteration ([`super::metrics::record`]) |
//! | `checkpoints/iter-NNNNNN/` | `weights.safetensors`, `state.toml`, `config.toml` (SAC: and `replay.safetensors`) |
//! | `latest` | link to the newest checkpoint |
//! | `fork.toml` | a run started as a fork: the checkpoint it went on from, and its iteration |

use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use learn::Algorithm;
use learn::checkpoint::{point_latest, write_dir_atomically, write_file_atomically};

use crate::config::Experiment;

/// The resolved experiment's file name, in run and checkpoint directories.
pub const CONFIG_FILE: &str = "config.toml";
/// One JSON object per iteration.
pub const METRICS_FILE: &str = "metrics.jsonl";
/// A fork's note: where its first iterations came from.
pub const FORK_FILE: &str = "fork.toml";

/// `runs/<terrain>-seed<seed>-<UTC date>-<time>`: a new directory per run.
pub fn default_run_dir(experiment: &Experiment) -> PathBuf {
    let terrain = experiment.terrain.to_string();
    let name: String = terrain
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' {
                c
            } else {
                '-'
            }
        })
        .collect();
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let base = format!("{name}-seed{}-{}", experiment.train.seed, utc_stamp(secs));
    let mut dir = PathBuf::from("runs").join(&base);
    let mut k = 2;
    while dir.exists() {
        dir = PathBuf::from("runs").join(format!("{base}-{k}"));
        k += 1;
    }
    dir
}

/// `YYYYMMDD-HHMMSS` (UTC) of a Unix time (Hinnant's civil-from-days).
fn utc_stamp(unix_secs: u64) -> String {
    let days = (unix_secs / 86_400) as i64;
    let rem = unix_secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}{month:02}{day:02}-{:02}{:02}{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

/// Where a checkpoint's run keeps its metrics: `RUN/checkpoints/iter-N` ->
/// `RUN`, `POLICY/checkpoint` -> `POLICY` (`None` for a checkpoint outside
/// either).
pub fn run_dir_of(checkpoint: &Path) -> Option<PathBuf> {
    let parent = checkpoint.parent()?;
    if parent.file_name().is_some_and(|n| n == "checkpoints") {
        return parent.parent().map(Path::to_path_buf);
    }
    // a policy exported with its checkpoint (`export --with-checkpoint`)
    // keeps the run's metrics beside it
    learn::export::is_exported_policy(parent).then(|| parent.to_path_buf())
}

/// Writes the checkpoint of `iteration`, points `latest` at it, prunes old ones.
pub(crate) fn save_checkpoint(
    run_dir: &Path,
    iteration: u64,
    mut files: Vec<(String, Vec<u8>)>,
    config_text: &str,
    keep: usize,
) -> Result<()> {
    let name = format!("iter-{iteration:06}");
    files.push((CONFIG_FILE.to_string(), config_text.as_bytes().to_vec()));
    let dir = run_dir.join("checkpoints").join(&name);
    write_dir_atomically(&dir, &files)?;
    point_latest(run_dir, &Path::new("checkpoints").join(&name))?;
    // keep the newest `keep`
    let mut names: Vec<String> = fs::read_dir(run_dir.join("checkpoints"))
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().to_string())
                .filter(|n| n.starts_with("iter-"))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    if names.len() > keep {
        for old in &names[..names.len() - keep] {
            let _ = fs::remove_dir_all(run_dir.join("checkpoints").join(old));
        }
    }
    Ok(())
}

/// A forked run's start: the forked run's metrics lines up to the
/// checkpoint (when it lies in a run directory), `fork.toml`, and the
/// checkpoint itself, written as this run's own (so that a resume works
/// from the start).
pub(crate) fn start_fork(
    run_dir: &Path,
    checkpoint: &Path,
    learner: &dyn Algorithm,
    config_text: &str,
    keep: usize,
) -> Result<()> {
    let iteration = learner.iteration();
    let source_metrics = run_dir_of(checkpoint).map(|run| run.join(METRICS_FILE));
    if let Some(source) = source_metrics.filter(|p| p.exists()) {
        let text = fs::read_to_string(&source)
            .with_context(|| format!("cannot read {}", source.display()))?;
        write_file_atomically(
            &run_dir.join(METRICS_FILE),
            metrics_up_to(&text, iteration).as_bytes(),
        )?;
    }
    let fork = format!(
        "# this run went on from another run's checkpoint; its first {iteration} iterations are that run's\ncheckpoint = {:?}\niteration = {iteration}\n",
        checkpoint.display().to_string()
    );
    write_file_atomically(&run_dir.join(FORK_FILE), fork.as_bytes())?;
    save_checkpoint(
        run_dir,
        iteration,
        learner.checkpoint_files()?,
        config_text,
        keep,
    )
}

/// Appends one line to a file, creating it.
pub(crate) fn append_line(path: &Path, line: &str) -> Result<()> {
    let mut f = fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| format!("cannot append to {}", path.display()))?;
    writeln!(f, "{line}").with_context(|| format!("cannot append to {}", path.display()))?;
    Ok(())
}

/// On resume: drops the lines of iterations after the checkpoint.
pub(crate) fn keep_metrics_up_to(path: &Path, iteration: u64) -> Result<()> {
    let Ok(text) = fs::read_to_string(path) else {
        return Ok(());
    };
    Ok(write_file_atomically(
        path,
        metrics_up_to(&text, iteration).as_bytes(),
    )?)
}

/// The lines of `metrics.jsonl` text for iterations up to `iteration`.
fn metrics_up_to(text: &str, iteration: u64) -> String {
    text.lines()
        .filter(|line| {
            serde_json::from_str::<serde_json::Value>(line)
                .ok()
                .and_then(|v| v["iteration"].as_u64())
                .is_some_and(|i| i <= iteration)
        })
        .map(|line| format!("{line}\n"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_stamps() {
        assert_eq!(utc_stamp(0), "19700101-000000");
        // 2026-11-22 08:47:05 UTC
        assert_eq!(utc_stamp(1_795_337_225), "20261122-084705");
        // a leap day
        assert_eq!(utc_stamp(951_782_400), "20000229-000000");
    }

    #[test]
    fn metrics_are_cut_at_an_iteration() {
        let text = "{\"iteration\":1}\n{\"iteration\":2}\nnot json\n{\"iteration\":3}\n";
        assert_eq!(
            metrics_up_to(text, 2),
            "{\"iteration\":1}\n{\"iteration\":2}\n"
        );
    }

    #[test]
    fn a_checkpoints_run_is_its_grandparent() {
        assert_eq!(
            run_dir_of(Path::new("runs/a/checkpoints/iter-000010")),
            Some(PathBuf::from("runs/a"))
        );
        assert_eq!(run_dir_of(Path::new("elsewhere/iter-000010")), None);
    }
}
