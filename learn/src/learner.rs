//! One type for "a learner of either algorithm", so that the command line
//! trains, checkpoints, resumes and runs PPO and SAC alike.

use std::path::Path;

use rand_chacha::ChaCha8Rng;

use crate::LearnError;
use crate::env::VecEnv;
use crate::sac::checkpoint::is_sac_checkpoint;
use crate::sac::{SacAgent, SacStats};
use crate::trainer::{IterationStats, Trainer};

/// The algorithms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Algo {
    /// proximal policy optimisation (the paper's)
    #[default]
    Ppo,
    /// soft actor-critic
    Sac,
    /// soft actor-critic with CrossQ's critics and settings
    /// ([`crate::sac::SacConfig::crossq`])
    CrossQ,
}

impl Algo {
    /// The name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ppo => "ppo",
            Self::Sac => "sac",
            Self::CrossQ => "crossq",
        }
    }

    /// The SAC settings an experiment starts from when it names this
    /// algorithm (PPO: SAC's defaults, unused).
    pub fn sac_defaults(self) -> crate::sac::SacConfig {
        match self {
            Self::CrossQ => crate::sac::SacConfig::crossq(),
            Self::Ppo | Self::Sac => crate::sac::SacConfig::default(),
        }
    }

    /// Parses [`Self::name`]'s output.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "ppo" => Some(Self::Ppo),
            "sac" => Some(Self::Sac),
            "crossq" => Some(Self::CrossQ),
            _ => None,
        }
    }
}

/// A learner of either algorithm.
pub enum Learner {
    /// PPO
    Ppo(Box<Trainer>),
    /// SAC
    Sac(Box<SacAgent>),
}

/// What one iteration of either learner did.
#[derive(Debug, Clone, PartialEq)]
pub enum LearnerStats {
    /// PPO's statistics
    Ppo(IterationStats),
    /// SAC's statistics
    Sac(SacStats),
}

impl Learner {
    /// Loads a checkpoint of either algorithm (told apart by its state file).
    /// An exported policy ([`crate::export`]) is refused
    /// ([`crate::checkpoint::resolve_checkpoint`]): it cannot resume.
    pub fn load(dir: &Path) -> Result<Self, LearnError> {
        if is_sac_checkpoint(dir) {
            Ok(Self::Sac(Box::new(SacAgent::load(dir)?)))
        } else {
            Ok(Self::Ppo(Box::new(Trainer::load(dir)?)))
        }
    }

    /// The algorithm.
    pub fn algo(&self) -> Algo {
        match self {
            Self::Ppo(_) => Algo::Ppo,
            Self::Sac(a) => match a.config.variant {
                crate::sac::SacVariant::Sac => Algo::Sac,
                crate::sac::SacVariant::CrossQ => Algo::CrossQ,
            },
        }
    }

    /// Iterations completed.
    pub fn iteration(&self) -> u64 {
        match self {
            Self::Ppo(t) => t.iteration,
            Self::Sac(a) => a.iteration,
        }
    }

    /// Environment steps per environment per iteration.
    pub fn steps_per_env(&self) -> usize {
        match self {
            Self::Ppo(t) => t.config.steps_per_env,
            Self::Sac(a) => a.config.steps_per_env,
        }
    }

    /// Observation values the networks take.
    pub fn obs_size(&self) -> usize {
        match self {
            Self::Ppo(t) => t.policy.obs_size(),
            Self::Sac(a) => a.obs_size(),
        }
    }

    /// Action values the networks give.
    pub fn action_size(&self) -> usize {
        match self {
            Self::Ppo(t) => t.policy.action_size(),
            Self::Sac(a) => a.action_size(),
        }
    }

    /// One iteration: collect and update.
    pub fn iterate(&mut self, env: &mut dyn VecEnv) -> Result<LearnerStats, LearnError> {
        Ok(match self {
            Self::Ppo(t) => LearnerStats::Ppo(t.iterate(env)?),
            Self::Sac(a) => LearnerStats::Sac(a.iterate(env)?),
        })
    }

    /// The checkpoint's files.
    pub fn checkpoint_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
        match self {
            Self::Ppo(t) => t.checkpoint_files(),
            Self::Sac(a) => a.checkpoint_files(),
        }
    }

    /// Sets the learning rate from the next update on (see
    /// [`Trainer::set_learning_rate`], [`SacAgent::set_learning_rate`]).
    pub fn set_learning_rate(&mut self, learning_rate: f64) -> Result<(), LearnError> {
        match self {
            Self::Ppo(t) => t.set_learning_rate(learning_rate),
            Self::Sac(a) => a.set_learning_rate(learning_rate),
        }
    }

    /// The deterministic action (PPO: the clipped mean; SAC: tanh of the mean).
    pub fn act_deterministic(&self, raw_obs: &[f32]) -> Result<Vec<f32>, LearnError> {
        match self {
            Self::Ppo(t) => t.act_deterministic(raw_obs),
            Self::Sac(a) => a.act_deterministic(raw_obs),
        }
    }

    /// A sampled action, drawing on `rng`.
    pub fn act_stochastic(
        &self,
        raw_obs: &[f32],
        rng: &mut ChaCha8Rng,
    ) -> Result<Vec<f32>, LearnError> {
        match self {
            Self::Ppo(t) => t.act_stochastic(raw_obs, rng),
            Self::Sac(a) => a.act_sampled(raw_obs, rng),
        }
    }
}

impl LearnerStats {
    /// Iterations completed, this one included.
    pub fn iteration(&self) -> u64 {
        match self {
            Self::Ppo(s) => s.iteration,
            Self::Sac(s) => s.iteration,
        }
    }

    /// Environment steps of this iteration.
    pub fn steps(&self) -> usize {
        match self {
            Self::Ppo(s) => s.steps,
            Self::Sac(s) => s.steps,
        }
    }

    /// Episodes that ended, and of them terminated.
    pub fn episodes(&self) -> (usize, usize) {
        match self {
            Self::Ppo(s) => (s.episodes, s.terminated),
            Self::Sac(s) => (s.episodes, s.terminated),
        }
    }

    /// Mean return and length of the ended episodes.
    pub fn episode_means(&self) -> (Option<f64>, Option<f64>) {
        match self {
            Self::Ppo(s) => (s.mean_episode_return, s.mean_episode_length),
            Self::Sac(s) => (s.mean_episode_return, s.mean_episode_length),
        }
    }

    /// The mean of the environment's episode metric `name`.
    pub fn episode_metric(&self, name: &str) -> Option<f64> {
        let metrics = match self {
            Self::Ppo(s) => &s.episode_metrics,
            Self::Sac(s) => &s.episode_metrics,
        };
        metrics
            .iter()
            .find(|(n, _)| n == name)
            .and_then(|(_, v)| *v)
    }

    /// Mean reward per step and per reward term.
    pub fn step_rewards(&self) -> (f64, &[(String, f64)]) {
        match self {
            Self::Ppo(s) => (s.mean_step_reward, &s.reward_terms),
            Self::Sac(s) => (s.mean_step_reward, &s.reward_terms),
        }
    }

    /// Seconds stepping the environments.
    pub fn env_secs(&self) -> f64 {
        match self {
            Self::Ppo(s) => s.env_secs,
            Self::Sac(s) => s.env_secs,
        }
    }

    /// Environment steps per second over the iteration.
    pub fn steps_per_sec(&self) -> f64 {
        match self {
            Self::Ppo(s) => s.steps_per_sec,
            Self::Sac(s) => s.steps_per_sec,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::write_dir_atomically;
    use crate::config::PpoConfig;
    use crate::sac::SacConfig;
    use crate::toy::PointMass;
    use crate::trainer::Trainer;

    /// A curriculum stage's rate: used by the next update, written into the
    /// checkpoint and loaded back; a bad rate is refused and changes nothing.
    #[test]
    fn a_new_learning_rate_is_used_and_survives_a_checkpoint() {
        let tmp = tempfile::tempdir().unwrap();
        let ppo = Learner::Ppo(Box::new(
            Trainer::new(
                PpoConfig {
                    hidden_sizes: vec![8],
                    minibatch_size: 64,
                    ..PpoConfig::default()
                },
                4,
                2,
                3,
            )
            .unwrap(),
        ));
        let sac = Learner::Sac(Box::new(
            SacAgent::new(
                SacConfig {
                    hidden_sizes: vec![8],
                    batch_size: 8,
                    learning_starts: 8,
                    steps_per_env: 4,
                    ..SacConfig::default()
                },
                4,
                2,
                3,
            )
            .unwrap(),
        ));
        for (k, mut learner) in [ppo, sac].into_iter().enumerate() {
            for bad in [0.0, -1e-4, 1.0, f64::NAN, f64::INFINITY] {
                let err = learner.set_learning_rate(bad).unwrap_err().to_string();
                assert!(err.contains("learning_rate"), "{err}");
            }
            learner.set_learning_rate(5e-5).unwrap();
            let mut env = PointMass::new(4, 16);
            let stats = learner.iterate(&mut env).unwrap();
            let rates = |l: &Learner| match l {
                Learner::Ppo(t) => vec![t.config.learning_rate, t.adam.learning_rate],
                Learner::Sac(a) => vec![
                    a.config.learning_rate,
                    a.actor_adam.learning_rate,
                    a.critic_adam.learning_rate,
                    a.alpha_adam.learning_rate,
                ],
            };
            assert!(rates(&learner).iter().all(|&r| r == 5e-5));
            if let LearnerStats::Ppo(s) = &stats {
                assert_eq!(s.learning_rate, 5e-5);
            }
            let dir = tmp.path().join(format!("learner-{k}"));
            write_dir_atomically(&dir, &learner.checkpoint_files().unwrap()).unwrap();
            let back = Learner::load(&dir).unwrap();
            assert!(
                rates(&back).iter().all(|&r| r == 5e-5),
                "{:?}",
                rates(&back)
            );
        }
    }
}
