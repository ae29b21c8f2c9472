//! PPO settings. The paper's values are the defaults where it gives them
//! (actor and critic 256-128 tanh, Adam at 2e-4, gamma 0.95, lambda 0.95,
//! minibatch 4096, 10 epochs); the rest are ours, chosen as in common PPO
//! practice, and every one can be changed in a config file.

use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::tanh::TanhImpl;

/// PPO hyper-parameters (the `[ppo]` table of an experiment file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PpoConfig {
    /// hidden layer widths of both the actor and the critic (tanh between layers)
    pub hidden_sizes: Vec<usize>,
    /// which tanh the networks evaluate: `"libm"` (the platform's C
    /// library, the default) or `"polynomial"` (quadwalk's own, the same
    /// function to within an ulp at a third of the cost; a run with it is a
    /// new run: [`crate::tanh`])
    #[serde(skip_serializing_if = "TanhImpl::is_libm")]
    pub tanh: TanhImpl,
    /// Adam step size
    pub learning_rate: f64,
    /// discount
    pub gamma: f64,
    /// GAE lambda
    pub gae_lambda: f64,
    /// environment steps per environment per iteration; the batch is
    /// `envs x steps_per_env`
    pub steps_per_env: usize,
    /// minibatch size; a batch smaller than this is one minibatch
    pub minibatch_size: usize,
    /// passes over the batch per iteration
    pub epochs: usize,
    /// PPO ratio clip epsilon
    pub clip_range: f64,
    /// weight of the value loss (mean squared error) in the total loss
    pub value_coef: f64,
    /// weight of the entropy bonus
    pub entropy_coef: f64,
    /// gradients are rescaled so that the global L2 norm of each network's
    /// gradient (actor with log-std, critic) is at most this
    pub max_grad_norm: f64,
    /// stop the epochs of an iteration early once the approximate KL of a
    /// minibatch exceeds 1.5 x this (off when absent)
    pub target_kl: Option<f64>,
    /// adapt the learning rate after every minibatch to keep the approximate
    /// KL from the rollout policy near this (rsl_rl's schedule, legged_gym's
    /// default with 0.01): above 2x this the rate is divided by 1.5, below
    /// half of it multiplied by 1.5, within [1e-5, 1e-2]; `learning_rate` is
    /// where it starts (off when absent: a fixed rate)
    pub desired_kl: Option<f64>,
    /// initial log standard deviation of every action dimension. The
    /// default, -1.6 (sigma 0.2 of the [-1, 1] action range), is ours: with
    /// sigma 0.5 the untrained robot falls within 3 phases on rigid ground,
    /// with 0.2 it lasts about 9 (first iteration of `quadwalk train
    /// --terrain rigid --envs 4`), so that there is something to learn from
    pub init_log_std: f64,
    /// learn from every sample and from its left-right mirror image (the
    /// environment's [`crate::Mirror`]): each minibatch holds its samples
    /// and their mirrors, with the same advantages and returns and the
    /// mirrored action's log-probability under the rollout's policy, and
    /// the normaliser counts both (rsl_rl's symmetry data augmentation;
    /// not the paper's). An environment without a mirror is an error
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub mirror_augmentation: bool,
    /// normalise advantages to zero mean, unit variance per minibatch
    pub normalize_advantages: bool,
    /// normalised observations are clipped to +- this
    pub obs_clip: f64,
}

impl Default for PpoConfig {
    fn default() -> Self {
        Self {
            hidden_sizes: vec![256, 128],
            tanh: TanhImpl::Libm,
            learning_rate: 2e-4,
            gamma: 0.95,
            gae_lambda: 0.95,
            steps_per_env: 40,
            minibatch_size: 4096,
            epochs: 10,
            clip_range: 0.2,
            value_coef: 0.5,
            entropy_coef: 0.0,
            max_grad_norm: 1.0,
            target_kl: None,
            desired_kl: None,
            init_log_std: -1.6,
            mirror_augmentation: false,
            normalize_advantages: true,
            obs_clip: 10.0,
        }
    }
}

/// The bounds of the adaptive learning rate ([`PpoConfig::desired_kl`]).
pub const ADAPTIVE_LEARNING_RATE_RANGE: (f64, f64) = (1e-5, 1e-2);

/// rsl_rl's adaptive schedule: the learning rate after a minibatch whose
/// approximate KL from the rollout policy was `kl`.
///
/// lr / 1.5 if kl > 2 desired; lr x 1.5 if 0 < kl < desired / 2; else lr;
/// kept within [`ADAPTIVE_LEARNING_RATE_RANGE`].
pub fn adapt_learning_rate(learning_rate: f64, kl: f64, desired_kl: f64) -> f64 {
    let (low, high) = ADAPTIVE_LEARNING_RATE_RANGE;
    if kl > 2.0 * desired_kl {
        (learning_rate / 1.5).max(low)
    } else if kl > 0.0 && kl < desired_kl / 2.0 {
        (learning_rate * 1.5).min(high)
    } else {
        learning_rate
    }
}

impl PpoConfig {
    /// Checks every value; the error names the key and the rule.
    pub fn validate(&self) -> Result<(), LearnError> {
        let bad = |key: &str, rule: &str, value: String| {
            Err(LearnError::Config(format!(
                "ppo.{key} = {value}: must be {rule}"
            )))
        };
        if self.hidden_sizes.is_empty() || self.hidden_sizes.iter().any(|&h| h == 0 || h > 65_536) {
            return bad(
                "hidden_sizes",
                "a non-empty list of widths in 1..=65536",
                format!("{:?}", self.hidden_sizes),
            );
        }
        let in_open_unit = |v: f64| v.is_finite() && v > 0.0 && v <= 1.0;
        if !crate::optim::is_learning_rate(self.learning_rate) {
            return bad("learning_rate", "in (0, 1)", self.learning_rate.to_string());
        }
        if !in_open_unit(self.gamma) {
            return bad("gamma", "in (0, 1]", self.gamma.to_string());
        }
        if !(self.gae_lambda.is_finite() && (0.0..=1.0).contains(&self.gae_lambda)) {
            return bad("gae_lambda", "in [0, 1]", self.gae_lambda.to_string());
        }
        if self.steps_per_env == 0 || self.steps_per_env > 1_000_000 {
            return bad(
                "steps_per_env",
                "in 1..=1000000",
                self.steps_per_env.to_string(),
            );
        }
        if self.minibatch_size == 0 {
            return bad(
                "minibatch_size",
                "at least 1",
                self.minibatch_size.to_string(),
            );
        }
        if self.epochs == 0 || self.epochs > 1000 {
            return bad("epochs", "in 1..=1000", self.epochs.to_string());
        }
        if !(self.clip_range.is_finite() && self.clip_range > 0.0 && self.clip_range < 1.0) {
            return bad("clip_range", "in (0, 1)", self.clip_range.to_string());
        }
        for (key, value) in [
            ("value_coef", self.value_coef),
            ("entropy_coef", self.entropy_coef),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return bad(key, "finite and >= 0", value.to_string());
            }
        }
        if !(self.max_grad_norm.is_finite() && self.max_grad_norm > 0.0) {
            return bad(
                "max_grad_norm",
                "finite and > 0",
                self.max_grad_norm.to_string(),
            );
        }
        if let Some(kl) = self.target_kl
            && !(kl.is_finite() && kl > 0.0)
        {
            return bad("target_kl", "finite and > 0", kl.to_string());
        }
        if let Some(kl) = self.desired_kl
            && !(kl.is_finite() && kl > 0.0)
        {
            return bad("desired_kl", "finite and > 0", kl.to_string());
        }
        if !(self.init_log_std.is_finite() && (-10.0..=2.0).contains(&self.init_log_std)) {
            return bad("init_log_std", "in [-10, 2]", self.init_log_std.to_string());
        }
        if !(self.obs_clip.is_finite() && self.obs_clip > 0.0) {
            return bad("obs_clip", "finite and > 0", self.obs_clip.to_string());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_papers_and_valid() {
        let c = PpoConfig::default();
        assert_eq!(c.hidden_sizes, vec![256, 128]);
        assert_eq!(c.learning_rate, 2e-4);
        assert_eq!((c.gamma, c.gae_lambda), (0.95, 0.95));
        assert_eq!((c.minibatch_size, c.epochs), (4096, 10));
        c.validate().unwrap();
    }

    #[test]
    fn the_adaptive_learning_rate_follows_rsl_rls_schedule() {
        let d = 0.01;
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b;
        assert!(close(adapt_learning_rate(3e-4, 0.03, d), 2e-4)); // KL > 2 d: / 1.5
        assert!(close(adapt_learning_rate(2e-4, 0.004, d), 3e-4)); // KL < d / 2: x 1.5
        assert_eq!(adapt_learning_rate(2e-4, 0.01, d), 2e-4); // within: kept
        assert_eq!(adapt_learning_rate(2e-4, 0.02, d), 2e-4); // exactly 2 d: kept
        assert_eq!(adapt_learning_rate(2e-4, 0.0, d), 2e-4); // no KL measured: kept
        assert_eq!(adapt_learning_rate(1.2e-5, 1.0, d), 1e-5); // floor
        assert_eq!(adapt_learning_rate(9e-3, 1e-6, d), 1e-2); // ceiling
        let bad = PpoConfig {
            desired_kl: Some(0.0),
            ..PpoConfig::default()
        };
        let err = bad.validate().unwrap_err().to_string();
        assert!(err.contains("ppo.desired_kl = 0"), "{err}");
    }

    #[test]
    fn toml_round_trip_and_unknown_keys() {
        let c = PpoConfig {
            target_kl: Some(0.02),
            desired_kl: Some(0.01),
            ..PpoConfig::default()
        };
        let text = toml::to_string(&c).unwrap();
        let back: PpoConfig = toml::from_str(&text).unwrap();
        assert_eq!(back, c);
        let err = toml::from_str::<PpoConfig>("learning_rat = 0.1").unwrap_err();
        assert!(err.to_string().contains("learning_rat"), "{err}");
    }

    #[test]
    fn bad_values_name_the_key() {
        let c = PpoConfig {
            gamma: 1.5,
            ..PpoConfig::default()
        };
        let err = c.validate().unwrap_err().to_string();
        assert!(err.contains("ppo.gamma = 1.5"), "{err}");
        let c = PpoConfig {
            hidden_sizes: vec![],
            ..PpoConfig::default()
        };
        assert!(
            c.validate()
                .unwrap_err()
                .to_string()
                .contains("hidden_sizes")
        );
    }
}
