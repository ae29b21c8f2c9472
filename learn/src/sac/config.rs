//! SAC settings (the `[sac]` table of an experiment file, to come). The
//! defaults are Stable-Baselines3's SAC defaults where they fit two CPU
//! cores (learning rate 3e-4, tau 0.005, batch 256, automatic temperature
//! from 1, target entropy -A), with the paper's discount 0.95 and a replay
//! buffer of 200,000 transitions (~160 MB for 102 observations).

use serde::{Deserialize, Serialize};

use crate::LearnError;

/// SAC hyper-parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SacConfig {
    /// hidden layer widths of the actor and of each critic (tanh between layers)
    pub hidden_sizes: Vec<usize>,
    /// Adam step size of the actor, the critics and the temperature
    pub learning_rate: f64,
    /// discount
    pub gamma: f64,
    /// Polyak factor of the target critics: target <- (1 - tau) target + tau critic
    pub tau: f64,
    /// transitions per gradient step
    pub batch_size: usize,
    /// replay buffer capacity, transitions
    pub buffer_size: usize,
    /// transitions collected with uniform random actions before learning starts
    pub learning_starts: usize,
    /// gradient steps per transition collected (the update-to-data ratio)
    pub updates_per_step: f64,
    /// environment steps per environment per iteration (statistics and
    /// checkpoints happen between iterations)
    pub steps_per_env: usize,
    /// the temperature's start value
    pub init_alpha: f64,
    /// the entropy the temperature steers to; absent: -(action size)
    pub target_entropy: Option<f64>,
    /// each network's gradient is rescaled to at most this global L2 norm
    pub max_grad_norm: f64,
    /// normalised observations are clipped to +- this
    pub obs_clip: f64,
}

impl Default for SacConfig {
    fn default() -> Self {
        Self {
            hidden_sizes: vec![256, 256],
            learning_rate: 3e-4,
            gamma: 0.95,
            tau: 0.005,
            batch_size: 256,
            buffer_size: 200_000,
            learning_starts: 1_000,
            updates_per_step: 1.0,
            steps_per_env: 40,
            init_alpha: 1.0,
            target_entropy: None,
            max_grad_norm: 10.0,
            obs_clip: 10.0,
        }
    }
}

impl SacConfig {
    /// Checks every value; the error names the key and the rule.
    pub fn validate(&self) -> Result<(), LearnError> {
        let bad = |key: &str, rule: &str, value: String| {
            Err(LearnError::Config(format!(
                "sac.{key} = {value}: must be {rule}"
            )))
        };
        if self.hidden_sizes.is_empty() || self.hidden_sizes.iter().any(|&h| h == 0 || h > 65_536) {
            return bad(
                "hidden_sizes",
                "a non-empty list of widths in 1..=65536",
                format!("{:?}", self.hidden_sizes),
            );
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !(positive(self.learning_rate) && self.learning_rate < 1.0) {
            return bad("learning_rate", "in (0, 1)", self.learning_rate.to_string());
        }
        if !(positive(self.gamma) && self.gamma <= 1.0) {
            return bad("gamma", "in (0, 1]", self.gamma.to_string());
        }
        if !(positive(self.tau) && self.tau <= 1.0) {
            return bad("tau", "in (0, 1]", self.tau.to_string());
        }
        if self.batch_size == 0 || self.batch_size > 1_000_000 {
            return bad("batch_size", "in 1..=1000000", self.batch_size.to_string());
        }
        if self.buffer_size == 0 || self.buffer_size > 100_000_000 {
            return bad(
                "buffer_size",
                "in 1..=100000000",
                self.buffer_size.to_string(),
            );
        }
        if !(self.updates_per_step.is_finite() && (0.0..=1000.0).contains(&self.updates_per_step)) {
            return bad(
                "updates_per_step",
                "in [0, 1000]",
                self.updates_per_step.to_string(),
            );
        }
        if self.steps_per_env == 0 || self.steps_per_env > 1_000_000 {
            return bad(
                "steps_per_env",
                "in 1..=1000000",
                self.steps_per_env.to_string(),
            );
        }
        if !positive(self.init_alpha) {
            return bad("init_alpha", "positive", self.init_alpha.to_string());
        }
        if let Some(h) = self.target_entropy
            && !h.is_finite()
        {
            return bad("target_entropy", "finite", h.to_string());
        }
        if !positive(self.max_grad_norm) {
            return bad("max_grad_norm", "positive", self.max_grad_norm.to_string());
        }
        if !positive(self.obs_clip) {
            return bad("obs_clip", "positive", self.obs_clip.to_string());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        SacConfig::default().validate().unwrap();
        let err = SacConfig {
            tau: 0.0,
            ..SacConfig::default()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(err.contains("sac.tau = 0"), "{err}");
        let err = SacConfig {
            updates_per_step: f64::NAN,
            ..SacConfig::default()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(err.contains("sac.updates_per_step"), "{err}");
    }
}
