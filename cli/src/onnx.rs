//! `quadwalk onnx`: a trained policy's deterministic actor as one ONNX
//! graph (`learn::onnx`): the 102 raw observation values (or however many
//! the policy's observation config has) in, the action in [-1, 1] out,
//! with the normaliser and the bound inside, for onnxruntime or a robot's
//! computer.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;

/// `quadwalk onnx` arguments.
#[derive(Debug, Args)]
pub struct OnnxArgs {
    /// The policy: an exported policy, a run directory (its latest
    /// checkpoint) or one of its checkpoints
    #[arg(long)]
    policy: String,
    /// The ONNX file to write (must not exist)
    #[arg(long)]
    out: PathBuf,
}

/// The ONNX model of `policy`'s deterministic actor.
pub fn onnx_bytes(registry: &terrain_plugins::Registry, policy: &str) -> Result<Vec<u8>> {
    let learner = match experiment::Policy::from_arg(registry, policy, None)? {
        experiment::Policy::Trained { learner, .. } => learner,
        experiment::Policy::Scripted(_) => {
            bail!("policy {policy:?}: the scripted crawl is not a network; give a trained policy")
        }
        experiment::Policy::Residual { .. } => bail!(
            "policy {policy:?}: a residual policy acts within its phase policy's phases at the control rate; its ONNX export is not written yet (export its phase policy)"
        ),
    };
    let graph = learner
        .actor_graph()
        .with_context(|| format!("policy {policy}"))?;
    Ok(graph.to_onnx(env!("CARGO_PKG_VERSION"))?)
}

/// `quadwalk onnx`.
pub fn onnx(registry: &terrain_plugins::Registry, args: &OnnxArgs) -> Result<()> {
    if args.out.exists() {
        bail!(
            "--out {}: already exists; remove it to write it again",
            args.out.display()
        );
    }
    let bytes = onnx_bytes(registry, &args.policy)?;
    learn::checkpoint::write_file_atomically(&args.out, &bytes)
        .with_context(|| format!("--out {}", args.out.display()))?;
    println!(
        "wrote {} ({:.0} kB): input `{}` (raw observation), output `{}` (action in [-1, 1])",
        args.out.display(),
        bytes.len() as f64 / 1000.0,
        learn::onnx::INPUT,
        learn::onnx::OUTPUT
    );
    Ok(())
}
