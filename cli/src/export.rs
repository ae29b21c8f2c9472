//! `quadwalk export`: a trained policy for use and for shipping, out of a
//! checkpoint: the actor and normaliser (`learn::export`), the experiment
//! it was trained in (`config.toml`), and the run's `metrics.jsonl` up to the
//! exported iteration; with `--with-checkpoint`, the checkpoint itself in
//! `checkpoint/`; with `--onnx`, the deterministic actor as `policy.onnx`. `rollout`, `play` and `eval` take the directory as a
//! policy; `train --resume` refuses it, and `train --fork OUT/checkpoint`
//! goes on from its checkpoint.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use learn::checkpoint::{LATEST_LINK, resolve_checkpoint, write_dir_atomically};

use experiment::train::run_dir::{CONFIG_FILE, METRICS_FILE};

/// `quadwalk export` arguments.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The checkpoint: a run directory (its latest) or one of its checkpoints
    #[arg(long)]
    checkpoint: PathBuf,
    /// The new directory to write (must not exist)
    #[arg(long)]
    out: PathBuf,
    /// Also copy the checkpoint itself (critic, optimiser state, sampling
    /// generator: ~1.5 MB) into OUT/checkpoint/, so that `train --fork
    /// OUT/checkpoint` goes on from it exactly as from the run
    #[arg(long)]
    with_checkpoint: bool,
    /// Also write the deterministic actor as one ONNX graph,
    /// OUT/policy.onnx (see `quadwalk onnx`)
    #[arg(long)]
    onnx: bool,
}

/// The exported policy's ONNX graph (`export --onnx`).
pub const ONNX_FILE: &str = "policy.onnx";

/// The folder of an exported policy that holds its checkpoint
/// (`export --with-checkpoint`).
pub const CHECKPOINT_DIR: &str = "checkpoint";

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
    let learner = learn::registry::load_checkpoint(&checkpoint)
        .with_context(|| format!("--checkpoint {}", args.checkpoint.display()))?;
    let config_path = checkpoint.join(CONFIG_FILE);
    let config = std::fs::read(&config_path)
        .with_context(|| format!("--checkpoint {}: {CONFIG_FILE}", args.checkpoint.display()))?;
    // the experiment must parse: a policy without its task settings is unusable
    experiment::config::Experiment::from_file(&config_path, registry)?;
    let mut files = learner.policy_files()?;
    files.push((CONFIG_FILE.to_string(), config));
    let run_dir = if args.checkpoint.join(LATEST_LINK).exists() {
        Some(args.checkpoint.clone())
    } else {
        std::fs::canonicalize(&checkpoint)
            .ok()
            .and_then(|c| experiment::train::run_dir::run_dir_of(&c))
    };
    let metrics = run_dir.map(|r| r.join(METRICS_FILE));
    if let Some(metrics) = metrics.filter(|m| m.is_file()) {
        files.push((
            METRICS_FILE.to_string(),
            metrics_up_to(&metrics, learner.iteration())?,
        ));
    }
    if args.with_checkpoint {
        // the checkpoint's own files, byte for byte (its state names their
        // checksum)
        for name in [
            learn::checkpoint::WEIGHTS_FILE,
            learn::checkpoint::STATE_FILE,
            CONFIG_FILE,
        ] {
            let path = checkpoint.join(name);
            let bytes =
                std::fs::read(&path).with_context(|| format!("cannot read {}", path.display()))?;
            files.push((format!("{CHECKPOINT_DIR}/{name}"), bytes));
        }
    }
    if args.onnx {
        let graph = learner
            .actor_graph()
            .with_context(|| format!("--checkpoint {}: --onnx", args.checkpoint.display()))?;
        files.push((
            ONNX_FILE.to_string(),
            graph.to_onnx(env!("CARGO_PKG_VERSION"))?,
        ));
    }
    write_dir_atomically(&args.out, &files)?;
    let bytes: usize = files.iter().map(|(_, b)| b.len()).sum();
    println!(
        "exported {} iteration {} ({}) to {} ({} files, {:.0} kB)",
        checkpoint.display(),
        learner.iteration(),
        learner.name(),
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
