//! The seam every learner fills: an [`Algorithm`] collects from a
//! [`VecEnv`], updates its networks, checkpoints and acts, and reports each
//! iteration as an [`IterationStats`] whose common part is typed and whose
//! algorithm-specific part is named figures. A runner (the train loop,
//! Python) holds a `Box<dyn Algorithm>` and never asks which one it is.
//!
//! Algorithms are listed in [`crate::registry`]; each lives in its own
//! folder (`ppo/`, `sac/`).

use rand_chacha::ChaCha8Rng;

use crate::LearnError;
use crate::env::VecEnv;
use crate::episodes::EpisodeStats;

/// A learner: PPO, SAC, CrossQ, or one added to [`crate::registry::ALGORITHMS`].
pub trait Algorithm: Send {
    /// Its registered name ([`crate::registry::Registration::name`]).
    fn name(&self) -> &'static str;

    /// Iterations completed.
    fn iteration(&self) -> u64;

    /// Environment steps per environment per iteration.
    fn steps_per_env(&self) -> usize;

    /// Observation values the policy takes (without any privileged values
    /// only a critic sees, [`crate::VecEnv::policy_observation_size`]).
    fn obs_size(&self) -> usize;

    /// Action values the networks give.
    fn action_size(&self) -> usize;

    /// One iteration: collect `steps_per_env` steps of every environment of
    /// `env` (fresh episodes seeded by the run's seed and the iteration) and
    /// update. An on-policy learner updates after collecting; an off-policy
    /// one as it collects.
    fn iterate(&mut self, env: &mut dyn VecEnv) -> Result<IterationStats, LearnError>;

    /// Sets the learning rate from the next update on, and in the settings
    /// that checkpoints carry (a curriculum stage's own rate).
    fn set_learning_rate(&mut self, learning_rate: f64) -> Result<(), LearnError>;

    /// Gives the critic `privileged_size` privileged values after the
    /// observation from the next iteration on (a curriculum stage that
    /// turns `privileged_critic` on), its values unchanged until training
    /// moves them; nothing changes when it has them already. A learner
    /// without an asymmetric critic refuses any.
    fn widen_critic(&mut self, privileged_size: usize) -> Result<(), LearnError> {
        if privileged_size == 0 {
            Ok(())
        } else {
            Err(no_asymmetric_critic(self.name(), privileged_size))
        }
    }

    /// Gives the networks an observation of `obs_size` values, the present
    /// ones followed by new ones, from the next iteration on (a curriculum
    /// stage that turns on an observation block), every action and value
    /// unchanged until training moves them; nothing changes at the present
    /// size. A learner that cannot grow its input refuses.
    fn widen_observation(&mut self, obs_size: usize) -> Result<(), LearnError> {
        if obs_size == self.obs_size() {
            Ok(())
        } else {
            Err(LearnError::Config(format!(
                "{} cannot grow its observation from {} to {obs_size} values mid-run; only PPO can",
                self.name(),
                self.obs_size()
            )))
        }
    }

    /// The deterministic actions for raw observations `k x O`, in [-1, 1].
    fn act_deterministic(&self, raw_obs: &[f32]) -> Result<Vec<f32>, LearnError>;

    /// Sampled actions for raw observations `k x O`, drawing on `rng`, in
    /// [-1, 1].
    fn act_stochastic(&self, raw_obs: &[f32], rng: &mut ChaCha8Rng)
    -> Result<Vec<f32>, LearnError>;

    /// The checkpoint's files (name, bytes), ready for
    /// [`crate::checkpoint::write_dir_atomically`]: everything a resumed
    /// run needs to continue bit for bit.
    fn checkpoint_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError>;

    /// The exported policy's files ([`crate::export`]): what acting needs,
    /// nothing else.
    fn policy_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError>;

    /// The deterministic actor as [`crate::onnx`] writes it: normaliser,
    /// network and action bound, computing what `act_deterministic` does.
    fn actor_graph(&self) -> Result<crate::onnx::ActorGraph, LearnError>;
}

/// The refusal of a learner whose critics see only what its actor sees,
/// asked for `privileged_size` privileged values.
pub(crate) fn no_asymmetric_critic(algorithm: &str, privileged_size: usize) -> LearnError {
    LearnError::Config(format!(
        "{algorithm}'s critics see what its actor sees: {privileged_size} privileged observation values (an asymmetric critic) are PPO's only"
    ))
}

/// Checks the network sizes a new learner is asked for.
pub fn check_sizes(obs_size: usize, action_size: usize) -> Result<(), LearnError> {
    if obs_size == 0 || action_size == 0 {
        return Err(LearnError::Config(format!(
            "observation size {obs_size} and action size {action_size} must both be positive"
        )));
    }
    Ok(())
}

/// A figure an algorithm reports about its update.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Figure {
    /// a count (epochs run, gradient steps)
    Count(u64),
    /// a measured value (a loss, a learning rate)
    Value(f64),
    /// a value not measured in this iteration (a loss before learning
    /// starts)
    Missing,
}

impl Figure {
    /// `Value(v)` for `Some(v)`, else `Missing`.
    pub fn from_option(value: Option<f64>) -> Self {
        value.map_or(Self::Missing, Self::Value)
    }

    /// The figure as a number, when it is one.
    pub fn as_f64(self) -> Option<f64> {
        match self {
            Self::Count(n) => Some(n as f64),
            Self::Value(v) => Some(v),
            Self::Missing => None,
        }
    }
}

/// What one iteration of any algorithm did.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationStats {
    /// iterations completed, this one included (1 after the first)
    pub iteration: u64,
    /// environment steps collected in this iteration
    pub steps: usize,
    /// the episodes that ended and the rewards per step
    pub episodes: EpisodeStats,
    /// seconds stepping the environments
    pub env_secs: f64,
    /// seconds in the other parts of the iteration, named (`"inference"`,
    /// `"update"`)
    pub secs: Vec<(&'static str, f64)>,
    /// environment steps per second over the whole iteration
    pub steps_per_sec: f64,
    /// the algorithm's own figures (losses, temperature, learning rate),
    /// named as `metrics.jsonl` writes them, in the order it reports them
    pub figures: Vec<(&'static str, Figure)>,
    /// the figures a one-line progress display shows: (label, figure name)
    pub headline: &'static [(&'static str, &'static str)],
}

impl IterationStats {
    /// The figure called `name`, when the algorithm reports one.
    pub fn figure(&self, name: &str) -> Option<Figure> {
        self.figures
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, f)| *f)
    }

    /// The mean of the environment's episode metric `name`.
    pub fn episode_metric(&self, name: &str) -> Option<f64> {
        self.episodes
            .metrics
            .iter()
            .find(|(n, _)| n == name)
            .and_then(|(_, v)| *v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figures_are_found_by_name_and_read_as_numbers() {
        let stats = IterationStats {
            iteration: 1,
            steps: 4,
            episodes: EpisodeStats {
                episodes: 0,
                terminated: 0,
                mean_return: None,
                mean_length: None,
                metrics: vec![("distance_m".into(), Some(2.0))],
                mean_step_reward: 0.0,
                reward_terms: vec![],
            },
            env_secs: 0.0,
            secs: vec![],
            steps_per_sec: 1.0,
            figures: vec![
                ("epochs", Figure::Count(3)),
                ("loss", Figure::from_option(Some(0.5))),
                ("alpha", Figure::from_option(None)),
            ],
            headline: &[("l", "loss")],
        };
        assert_eq!(stats.figure("epochs").and_then(Figure::as_f64), Some(3.0));
        assert_eq!(stats.figure("loss"), Some(Figure::Value(0.5)));
        assert_eq!(stats.figure("alpha").and_then(Figure::as_f64), None);
        assert_eq!(stats.figure("kl"), None);
        assert_eq!(stats.episode_metric("distance_m"), Some(2.0));
        assert_eq!(stats.episode_metric("speed"), None);
    }
}
