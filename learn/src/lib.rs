//! Reinforcement learning on candle, over a [`VecEnv`] of flat `f32`
//! buffers: PPO (the paper's), SAC and CrossQ behind one [`Algorithm`]
//! trait. This crate knows nothing of robots, physics or logging: an
//! iteration returns an [`IterationStats`] that the caller displays.
//!
//! Layout (rsl_rl's split: one folder per algorithm, shared storage of
//! episodes, checkpoints and optimisers; CleanRL's one-equation-per-step
//! comments):
//!
//! | module | job |
//! | --- | --- |
//! | [`algorithm`] | the `Algorithm` trait and what an iteration reports |
//! | [`registry`] | the algorithms, one registration each; loading any checkpoint or policy |
//! | [`settings`] | an algorithm's settings as an experiment file's table |
//! | [`ppo`] | proximal policy optimisation: runner, actor-critic, GAE, loss, checkpoint |
//! | [`sac`] | soft actor-critic and CrossQ: squashed Gaussian, twin critics, temperature, replay buffer |
//! | [`env`] | the `VecEnv` trait and its buffer shapes |
//! | [`episodes`] | episode statistics of a collection, for every algorithm |
//! | [`mlp`] | the multilayer perceptron and normal draws |
//! | [`tanh`] | the networks' activation: libm's or quadwalk's polynomial |
//! | [`normalizer`] | running observation normalisation |
//! | [`optim`] | Adam with exposed moments, gradient-norm clipping |
//! | [`seeds`] | per-iteration seeds and generator positions |
//! | [`checkpoint`] | atomic, checksummed checkpoint directories |
//! | [`export`] | policies for use: the actor and normaliser of a checkpoint |
//! | [`toy`] | a point-mass `VecEnv` that every algorithm must solve (tests, examples) |

pub mod algorithm;
pub mod checkpoint;
pub mod env;
pub mod episodes;
pub mod export;
pub mod mirror;
pub mod mlp;
pub mod normalizer;
pub mod onnx;
pub mod optim;
pub mod ppo;
pub mod registry;
pub mod sac;
pub mod seeds;
pub mod settings;
pub mod tanh;
pub mod toy;

pub use algorithm::{Algorithm, Figure, IterationStats};
pub use env::{StepResult, VecEnv};
pub use mirror::Mirror;
pub use ppo::{PpoConfig, Trainer};
pub use registry::Registration;
pub use settings::{Settings, SettingsValue};

/// What can go wrong in learning.
#[derive(Debug, thiserror::Error)]
pub enum LearnError {
    /// a setting is out of range
    #[error("{0}")]
    Config(String),
    /// the environment and the policy disagree on sizes
    #[error("{0}")]
    Mismatch(String),
    /// a checkpoint cannot be written or read
    #[error("{0}")]
    Checkpoint(String),
    /// a tensor operation failed (a bug, or memory)
    #[error("tensor operation failed: {0}")]
    Tensor(#[from] candle_core::Error),
}
