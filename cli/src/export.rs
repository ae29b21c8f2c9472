//! `quadwalk export`: a trained policy for use and for shipping, out of a
//! checkpoint: the actor and normaliser (`learn::export`), the experiment
//! it was trained in (`config.toml`), and the run's `metrics.jsonl` up to the
//! exported iteration. `rollout`, `play` and `eval` take the directory as a
//! policy; `train --resume` refuses it.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use learn::checkpoint::{LATEST_LINK, resolve_checkpoint, write_dir_atomically};

use crate::train::{CONFIG_FILE, METRICS_FILE};

/// `quadwalk export` arguments.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The checkpoint: a run directory (its latest) or one of its checkpoints
    #[arg(long)]
    checkpoint: PathBuf,
    /// The new directory to write (must not exist)
    #[arg(long)]
    out: PathBuf,
}

/// The metrics lines of iterations up to `iteration` (lines that do not
/// parse, or carry no iteration, are an error naming the line).
fn metrics_up_to(path: &Path, iteration: u64) -> Result<Vec<u8>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    let mut kept = String::new();
    for (k, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let value: serde_json::Value = serde_json::from_str(line)
            .with_context(|| format!("{} line {}: not JSON", path.display(), k + 1))?;
        let Some(i) = value.get("iteration").and_then(serde_json::Value::as_u64) else {
            bail!("{} line {}: no iteration number", path.display(), k + 1);
        };
        if i <= iteration {
            kept.push_str(line);
            kept.push('\n');
        }
    }
    Ok(kept.into_bytes())
}

/// `quadwalk export`.
pub fn export(registry: &terrain_plugins::Registry, args: &ExportArgs) -> Result<()> {
    if args.out.exists() {
        bail!(
            "--out {}: already exists; export writes a new directory",
            args.out.display()
        );
    }
    let checkpoint = resolve_checkpoint(&args.checkpoint)
        .with_context(|| format!("--checkpoint {}", args.checkpoint.display()))?;
    let learner = learn::Learner::load(&checkpoint)
        .with_context(|| format!("--checkpoint {}", args.checkpoint.display()))?;
    let config_path = checkpoint.join(CONFIG_FILE);
    let config = std::fs::read(&config_path)
        .with_context(|| format!("--checkpoint {}: {CONFIG_FILE}", args.checkpoint.display()))?;
    // the experiment must parse: a policy without its task settings is unusable
    crate::config::Experiment::from_file(&config_path, registry)?;
    let mut files = learner.policy_files()?;
    files.push((CONFIG_FILE.to_string(), config));
    let run_dir = if args.checkpoint.join(LATEST_LINK).exists() {
        args.checkpoint.clone()
    } else {
        std::fs::canonicalize(&checkpoint)
            .ok()
            .and_then(|c| c.parent().map(Path::to_path_buf))
            .unwrap_or_default()
    };
    let metrics = run_dir.join(METRICS_FILE);
    if metrics.is_file() {
        files.push((
            METRICS_FILE.to_string(),
            metrics_up_to(&metrics, learner.iteration())?,
        ));
    }
    write_dir_atomically(&args.out, &files)?;
    let bytes: usize = files.iter().map(|(_, b)| b.len()).sum();
    println!(
        "exported {} iteration {} ({}) to {} ({} files, {:.0} kB)",
        checkpoint.display(),
        learner.iteration(),
        learner.algo().name(),
        args.out.display(),
        files.len(),
        bytes as f64 / 1000.0
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metrics_stop_at_the_exported_iteration_and_bad_lines_are_named() {
        let tmp = tempfile::tempdir().unwrap();
        let path = tmp.path().join("metrics.jsonl");
        std::fs::write(
            &path,
            "{\"iteration\":1}\n{\"iteration\":2}\n\n{\"iteration\":3}\n",
        )
        .unwrap();
        let kept = String::from_utf8(metrics_up_to(&path, 2).unwrap()).unwrap();
        assert_eq!(kept, "{\"iteration\":1}\n{\"iteration\":2}\n");
        std::fs::write(&path, "{\"iteration\":1}\nnot json\n").unwrap();
        let err = format!("{:#}", metrics_up_to(&path, 2).unwrap_err());
        assert!(err.contains("line 2"), "{err}");
    }
}
