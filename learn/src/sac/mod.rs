//! Soft actor-critic (Haarnoja et al. 2018) on candle, over the same
//! [`crate::VecEnv`] as PPO: twin critics with Polyak-averaged targets (or
//! CrossQ's batch-renormalised critics without targets), a tanh-squashed
//! Gaussian actor, automatic temperature, a replay buffer and an
//! update-to-data ratio of choice.
//!
//! | module | job |
//! | --- | --- |
//! | [`config`] | `SacConfig` (the `[sac]` table) and its checks |
//! | [`squashed`] | the squashed Gaussian: sample and log-probability |
//! | [`losses`] | the soft Bellman target, critic, actor and temperature losses |
//! | [`batch_renorm`] | batch renormalisation (CrossQ's critics) |
//! | [`critics`] | the twin critics: with targets, or CrossQ's |
//! | [`replay`] | the replay buffer |
//! | [`agent`] | collect, update, statistics |
//! | [`checkpoint`] | checkpoints with the replay buffer; exact resume |
//!
//! This file registers two algorithms on the one agent: `sac` and `crossq`
//! (Bhatt et al. 2024: SAC with batch-renormalised critics and no targets,
//! [`SacConfig::crossq`]'s settings). Both read `[sac]` and share the
//! checkpoint format; the variant is a setting.

pub mod agent;
pub mod batch_renorm;
pub mod checkpoint;
pub mod config;
pub mod critics;
pub mod losses;
pub mod replay;
pub mod squashed;

use std::path::Path;

use rand_chacha::ChaCha8Rng;

pub use agent::SacAgent;
pub use config::{SacConfig, SacVariant};

use crate::LearnError;
use crate::algorithm::{Algorithm, IterationStats, no_asymmetric_critic};
use crate::env::VecEnv;
use crate::export::{PolicyFile, load_acting_weights, policy_files};
use crate::onnx::{self, ActionBound, ActorGraph};
use crate::registry::Registration;
use crate::settings::{Settings, SettingsValue, overlay};

/// SAC's entry in [`crate::registry::ALGORITHMS`].
pub static REGISTRATION: Registration = Registration {
    name: "sac",
    table: "sac",
    settings: |table| settings_over(SacConfig::default(), table),
    format: checkpoint::ALGO,
    load_checkpoint: |dir| Ok(Box::new(SacAgent::load(dir)?)),
    load_policy,
};

/// CrossQ's entry in [`crate::registry::ALGORITHMS`].
pub static CROSSQ_REGISTRATION: Registration = Registration {
    name: "crossq",
    table: "sac",
    settings: |table| {
        let settings = settings_over(SacConfig::crossq(), table)?;
        if settings.algorithm() != "crossq" {
            return Err("variant = \"sac\" contradicts algo.name = \"crossq\"".into());
        }
        Ok(settings)
    },
    format: checkpoint::ALGO,
    load_checkpoint: |dir| Ok(Box::new(SacAgent::load(dir)?)),
    load_policy,
};

/// `[sac]` over `base`, checked.
fn settings_over(
    base: SacConfig,
    table: Option<&toml::Table>,
) -> Result<Box<dyn Settings>, String> {
    let config: SacConfig = overlay(&base, table)?;
    config.validate().map_err(|e| e.to_string())?;
    Ok(Box::new(config))
}

/// The registered name of the variant.
fn variant_name(variant: SacVariant) -> &'static str {
    match variant {
        SacVariant::Sac => REGISTRATION.name,
        SacVariant::CrossQ => CROSSQ_REGISTRATION.name,
    }
}

impl Settings for SacConfig {
    fn algorithm(&self) -> &'static str {
        variant_name(self.variant)
    }

    fn learning_rate(&self) -> f64 {
        self.learning_rate
    }

    fn adapts_learning_rate(&self) -> bool {
        false
    }

    fn steps_per_env(&self) -> usize {
        self.steps_per_env
    }

    fn build(
        &self,
        (obs_size, privileged_size): (usize, usize),
        action_size: usize,
        seed: u64,
    ) -> Result<Box<dyn Algorithm>, LearnError> {
        if privileged_size > 0 {
            return Err(no_asymmetric_critic(self.algorithm(), privileged_size));
        }
        Ok(Box::new(SacAgent::new(
            self.clone(),
            obs_size,
            action_size,
            seed,
        )?))
    }
}

impl Algorithm for SacAgent {
    fn name(&self) -> &'static str {
        variant_name(self.config.variant)
    }

    fn iteration(&self) -> u64 {
        self.iteration
    }

    fn steps_per_env(&self) -> usize {
        self.config.steps_per_env
    }

    fn obs_size(&self) -> usize {
        SacAgent::obs_size(self)
    }

    fn action_size(&self) -> usize {
        SacAgent::action_size(self)
    }

    fn iterate(&mut self, env: &mut dyn VecEnv) -> Result<IterationStats, LearnError> {
        SacAgent::iterate(self, env)
    }

    fn set_learning_rate(&mut self, learning_rate: f64) -> Result<(), LearnError> {
        SacAgent::set_learning_rate(self, learning_rate)
    }

    /// tanh of the actor's mean.
    fn act_deterministic(&self, raw_obs: &[f32]) -> Result<Vec<f32>, LearnError> {
        SacAgent::act_deterministic(self, raw_obs)
    }

    fn act_stochastic(
        &self,
        raw_obs: &[f32],
        rng: &mut ChaCha8Rng,
    ) -> Result<Vec<f32>, LearnError> {
        self.act_sampled(raw_obs, rng)
    }

    fn checkpoint_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
        SacAgent::checkpoint_files(self)
    }

    /// The actor and the normaliser; `[sac]`.
    fn policy_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
        policy_files(
            REGISTRATION.format,
            self.iteration,
            self.seed,
            (self.obs_size(), self.action_size()),
            self.actor.named_vars("actor"),
            &self.normalizer,
            REGISTRATION.table,
            self.config.to_table(),
        )
    }

    /// The normaliser and the actor's mean head, squashed by tanh.
    fn actor_graph(&self) -> Result<ActorGraph, LearnError> {
        Ok(ActorGraph::new(
            &self.normalizer,
            onnx::layers_of(&self.actor, Some(self.action_size()))?,
            ActionBound::Tanh,
            onnx::metadata_of(self),
        ))
    }
}

/// An exported SAC or CrossQ policy: an agent of the recorded shape whose
/// actor and normaliser are the file's (critics, optimisers and buffer
/// fresh).
fn load_policy(dir: &Path, file: PolicyFile) -> Result<Box<dyn Algorithm>, LearnError> {
    let config: SacConfig = file.settings(dir, &REGISTRATION)?;
    let clip = config.obs_clip;
    let mut agent = SacAgent::new(config, file.obs_size, file.action_size, file.seed)?;
    agent.iteration = file.iteration;
    agent.normalizer = load_acting_weights(dir, &file, &agent.actor.named_vars("actor"), clip)?;
    Ok(Box::new(agent))
}
