//! Proximal policy optimisation (Schulman et al. 2017), the paper's
//! learner, in rsl_rl's shape: a runner that collects, computes advantages
//! and updates, over an actor-critic and a rollout buffer.
//!
//! | module | job |
//! | --- | --- |
//! | [`config`] | `PpoConfig` (the `[ppo]` table), the paper's values as defaults |
//! | [`actor_critic`] | actor and critic MLPs, the diagonal Gaussian |
//! | [`buffer`] | the rollout buffer, step-major |
//! | [`gae`] | generalised advantage estimation, a pure function |
//! | [`loss`] | the clipped objective, value loss, entropy bonus |
//! | [`trainer`] | collect, advantages, update, statistics |
//! | [`checkpoint`] | PPO's checkpoint; exact resume |
//!
//! This file registers PPO: its settings, its [`Algorithm`] and its
//! exported policy.

pub mod actor_critic;
pub mod buffer;
pub mod checkpoint;
pub mod config;
pub mod gae;
pub mod loss;
pub mod trainer;

use std::path::Path;

use rand_chacha::ChaCha8Rng;

pub use config::PpoConfig;
pub use trainer::{PpoUpdate, Trainer};

use crate::LearnError;
use crate::algorithm::{Algorithm, IterationStats};
use crate::env::VecEnv;
use crate::export::{PolicyFile, load_acting_weights, policy_files};
use crate::onnx::{self, ActionBound, ActorGraph};
use crate::registry::Registration;
use crate::settings::{Settings, SettingsValue, overlay};

/// PPO's entry in [`crate::registry::ALGORITHMS`].
pub static REGISTRATION: Registration = Registration {
    name: "ppo",
    table: "ppo",
    settings: settings_from_table,
    format: "ppo",
    load_checkpoint: |dir| Ok(Box::new(Trainer::load(dir)?)),
    load_policy,
};

/// `[ppo]`: the paper's values with the table's on top, checked.
fn settings_from_table(table: Option<&toml::Table>) -> Result<Box<dyn Settings>, String> {
    let config: PpoConfig = overlay(&PpoConfig::default(), table)?;
    config.validate().map_err(|e| e.to_string())?;
    Ok(Box::new(config))
}

impl Settings for PpoConfig {
    fn algorithm(&self) -> &'static str {
        REGISTRATION.name
    }

    fn learning_rate(&self) -> f64 {
        self.learning_rate
    }

    fn adapts_learning_rate(&self) -> bool {
        self.desired_kl.is_some()
    }

    fn steps_per_env(&self) -> usize {
        self.steps_per_env
    }

    fn build(
        &self,
        obs_size: (usize, usize),
        action_size: usize,
        seed: u64,
    ) -> Result<Box<dyn Algorithm>, LearnError> {
        Ok(Box::new(Trainer::asymmetric(
            self.clone(),
            obs_size,
            action_size,
            seed,
        )?))
    }
}

impl Algorithm for Trainer {
    fn name(&self) -> &'static str {
        REGISTRATION.name
    }

    fn iteration(&self) -> u64 {
        self.iteration
    }

    fn steps_per_env(&self) -> usize {
        self.config.steps_per_env
    }

    fn obs_size(&self) -> usize {
        self.policy.obs_size()
    }

    fn action_size(&self) -> usize {
        self.policy.action_size()
    }

    fn iterate(&mut self, env: &mut dyn VecEnv) -> Result<IterationStats, LearnError> {
        Trainer::iterate(self, env)
    }

    fn set_learning_rate(&mut self, learning_rate: f64) -> Result<(), LearnError> {
        Trainer::set_learning_rate(self, learning_rate)
    }

    fn widen_critic(&mut self, privileged_size: usize) -> Result<(), LearnError> {
        Trainer::widen_critic(self, privileged_size)
    }

    fn widen_observation(&mut self, obs_size: usize) -> Result<(), LearnError> {
        Trainer::widen_observation(self, obs_size)
    }

    fn act_deterministic(&self, raw_obs: &[f32]) -> Result<Vec<f32>, LearnError> {
        Trainer::act_deterministic(self, raw_obs)
    }

    fn act_stochastic(
        &self,
        raw_obs: &[f32],
        rng: &mut ChaCha8Rng,
    ) -> Result<Vec<f32>, LearnError> {
        Trainer::act_stochastic(self, raw_obs, rng)
    }

    fn checkpoint_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
        Trainer::checkpoint_files(self)
    }

    /// The actor with its log-std and the normaliser; `[ppo]`.
    fn policy_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
        policy_files(
            REGISTRATION.format,
            self.iteration,
            self.seed,
            (self.policy.obs_size(), self.policy.action_size()),
            self.policy.actor_vars(),
            &self.normalizer.leading(self.policy.obs_size()),
            REGISTRATION.table,
            self.config.to_table(),
        )
    }

    /// The normaliser of the policy's observation and the actor, its mean
    /// clipped to [-1, 1].
    fn actor_graph(&self) -> Result<ActorGraph, LearnError> {
        Ok(ActorGraph::new(
            &self.normalizer.leading(self.policy.obs_size()),
            onnx::layers_of(&self.policy.actor, None)?,
            ActionBound::Clip,
            onnx::metadata_of(self),
        ))
    }
}

/// An exported PPO policy: a trainer of the recorded shape whose actor and
/// normaliser are the file's (its critic and optimiser are fresh).
fn load_policy(dir: &Path, file: PolicyFile) -> Result<Box<dyn Algorithm>, LearnError> {
    let config: PpoConfig = file.settings(dir, &REGISTRATION)?;
    let clip = config.obs_clip;
    let mut trainer = Trainer::new(config, file.obs_size, file.action_size, file.seed)?;
    trainer.iteration = file.iteration;
    trainer.normalizer = load_acting_weights(dir, &file, &trainer.policy.actor_vars(), clip)?;
    Ok(Box::new(trainer))
}
