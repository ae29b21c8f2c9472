//! SAC settings (the `[sac]` table of an experiment file). The defaults
//! are Stable-Baselines3's SAC defaults where they fit two CPU cores
//! (learning rate 3e-4, tau 0.005, batch 256, automatic temperature from 1,
//! target entropy -A), with the paper's discount 0.95 and a replay buffer of
//! 200,000 transitions (~160 MB for 102 observations).
//!
//! `variant = "crossq"` selects CrossQ's critics (batch renormalisation, no
//! targets; `tau` is then unused); [`SacConfig::crossq`] holds the settings
//! of the CrossQ paper that fit here (Adam beta1 0.5, learning rate 1e-3,
//! the actor updated every third critic step).

use serde::{Deserialize, Serialize};

use crate::LearnError;

/// Which critics SAC learns with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SacVariant {
    /// twin critics with Polyak-averaged targets (Haarnoja et al. 2018)
    #[default]
    Sac,
    /// twin batch-renormalised critics, no targets (Bhatt et al. 2024)
    CrossQ,
}

/// SAC hyper-parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SacConfig {
    /// the critics: "sac" (with targets) or "crossq"
    pub variant: SacVariant,
    /// hidden layer widths of the actor, and of each critic unless
    /// `critic_hidden_sizes` is given (tanh between layers; CrossQ's critics
    /// use ReLU)
    pub hidden_sizes: Vec<usize>,
    /// hidden layer widths of each critic; absent: `hidden_sizes`
    pub critic_hidden_sizes: Option<Vec<usize>>,
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
    /// critic steps per actor and temperature step (TD3's and CrossQ's
    /// policy delay)
    pub policy_delay: usize,
    /// Adam's first-moment decay, all three optimisers
    pub adam_beta1: f64,
    /// CrossQ: the running statistics' decay per critic step
    pub batch_renorm_momentum: f64,
    /// CrossQ: critic steps of plain batch normalisation before the
    /// renormalisation's correction starts
    pub renorm_warmup_updates: u64,
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
            variant: SacVariant::Sac,
            hidden_sizes: vec![256, 256],
            critic_hidden_sizes: None,
            learning_rate: 3e-4,
            gamma: 0.95,
            tau: 0.005,
            batch_size: 256,
            buffer_size: 200_000,
            learning_starts: 1_000,
            updates_per_step: 1.0,
            steps_per_env: 40,
            policy_delay: 1,
            adam_beta1: 0.9,
            batch_renorm_momentum: 0.99,
            renorm_warmup_updates: 10_000,
            init_alpha: 1.0,
            target_entropy: None,
            max_grad_norm: 10.0,
            obs_clip: 10.0,
        }
    }
}

impl SacConfig {
    /// CrossQ's settings (Bhatt et al. 2024; sbx `CrossQ`): batch-renormalised
    /// critics without targets, Adam beta1 0.5, learning rate 1e-3, the actor
    /// and temperature updated every third critic step; the rest as
    /// [`Default`]. The paper's critics are 2048 wide; here they default to
    /// 256-256: on the 2-core machine one gradient step at batch 256 costs
    /// 52 ms with them, 112 ms with 512-512 and 255 ms with 1024-1024,
    /// against ~15 ms of physics per transition on 5 cm tiles
    /// (`cargo run --release -p learn --example update_cost`, BENCHMARKS.md).
    pub fn crossq() -> Self {
        Self {
            variant: SacVariant::CrossQ,
            critic_hidden_sizes: Some(vec![256, 256]),
            learning_rate: 1e-3,
            adam_beta1: 0.5,
            policy_delay: 3,
            ..Self::default()
        }
    }

    /// The critics' hidden widths.
    pub fn critic_widths(&self) -> &[usize] {
        self.critic_hidden_sizes
            .as_deref()
            .unwrap_or(&self.hidden_sizes)
    }

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
        if let Some(sizes) = &self.critic_hidden_sizes
            && (sizes.is_empty() || sizes.iter().any(|&h| h == 0 || h > 65_536))
        {
            return bad(
                "critic_hidden_sizes",
                "a non-empty list of widths in 1..=65536",
                format!("{sizes:?}"),
            );
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if self.policy_delay == 0 || self.policy_delay > 1000 {
            return bad("policy_delay", "in 1..=1000", self.policy_delay.to_string());
        }
        if !(self.adam_beta1.is_finite() && (0.0..1.0).contains(&self.adam_beta1)) {
            return bad("adam_beta1", "in [0, 1)", self.adam_beta1.to_string());
        }
        if !(self.batch_renorm_momentum.is_finite()
            && (0.0..1.0).contains(&self.batch_renorm_momentum))
        {
            return bad(
                "batch_renorm_momentum",
                "in [0, 1)",
                self.batch_renorm_momentum.to_string(),
            );
        }
        if !crate::optim::is_learning_rate(self.learning_rate) {
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
        SacConfig::crossq().validate().unwrap();
        let err = SacConfig {
            policy_delay: 0,
            ..SacConfig::crossq()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(err.contains("sac.policy_delay = 0"), "{err}");
        let err = SacConfig {
            critic_hidden_sizes: Some(vec![]),
            ..SacConfig::default()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(err.contains("sac.critic_hidden_sizes"), "{err}");
    }

    #[test]
    fn the_variant_reads_from_toml() {
        let c: SacConfig = toml::from_str("variant = \"crossq\"\npolicy_delay = 3").unwrap();
        assert_eq!(c.variant, SacVariant::CrossQ);
        assert_eq!(c.critic_widths(), [256, 256]);
        let err = toml::from_str::<SacConfig>("variant = \"droq\"").unwrap_err();
        assert!(err.to_string().contains("droq"), "{err}");
    }
}
