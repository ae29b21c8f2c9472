//! `[train]`: how a training run is laid out (worlds, iterations, seed,
//! checkpoints, the environments streamed to Rerun).

use anyhow::{Result, bail};
use serde::{Deserialize, Serialize};

/// `[train]`: how a training run is laid out.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainSettings {
    /// parallel environments (worlds)
    pub envs: usize,
    /// iterations (without a curriculum)
    pub iterations: u64,
    /// the run's seed: networks, sampling, start positions, terrain draws
    pub seed: u64,
    /// a checkpoint every this many iterations (and at the end, and on Ctrl-C)
    pub checkpoint_every: u64,
    /// checkpoints kept (the newest)
    pub keep_checkpoints: usize,
    /// environments whose rollouts go to Rerun
    pub rerun_envs: Vec<usize>,
}

impl Default for TrainSettings {
    fn default() -> Self {
        Self {
            envs: 16,
            iterations: 100,
            seed: 0,
            checkpoint_every: 10,
            keep_checkpoints: 5,
            rerun_envs: vec![0],
        }
    }
}

impl TrainSettings {
    /// Checks the values; the error names the key.
    pub fn validate(&self) -> Result<()> {
        if !(1..=4096).contains(&self.envs) {
            bail!("train.envs = {}: must be in 1..=4096", self.envs);
        }
        if !(1..=10_000_000).contains(&self.iterations) {
            bail!(
                "train.iterations = {}: must be in 1..=10000000",
                self.iterations
            );
        }
        if self.checkpoint_every == 0 {
            bail!("train.checkpoint_every = 0: must be at least 1");
        }
        if self.keep_checkpoints == 0 {
            bail!("train.keep_checkpoints = 0: must be at least 1");
        }
        if let Some(bad) = self.rerun_envs.iter().find(|&&e| e >= self.envs) {
            bail!(
                "train.rerun_envs holds {bad}, but there are only {} environments (0..{})",
                self.envs,
                self.envs
            );
        }
        Ok(())
    }
}
