//! PPO (proximal policy optimisation) and SAC (soft actor-critic) on candle, over a [`VecEnv`] of flat
//! `f32` buffers. This crate knows nothing of robots, physics or logging:
//! an iteration returns an [`IterationStats`] that the caller displays.
//!
//! Layout (rsl_rl's split, CleanRL's one-equation-per-step comments):
//!
//! | module | job |
//! | --- | --- |
//! | [`env`] | the `VecEnv` trait and its buffer shapes |
//! | [`config`] | `PpoConfig`, the paper's values as defaults |
//! | [`policy`] | actor and critic MLPs, the diagonal Gaussian |
//! | [`normalizer`] | running observation normalisation |
//! | [`buffer`] | the rollout buffer, step-major |
//! | [`gae`] | generalised advantage estimation, a pure function |
//! | [`ppo`] | the clipped objective, value loss, entropy bonus |
//! | [`optim`] | Adam with exposed moments, gradient-norm clipping |
//! | [`learner`] | either algorithm behind one type (train, checkpoint, act) |
//! | [`trainer`] | collect, update, statistics; seeds |
//! | [`checkpoint`] | atomic, checksummed checkpoints |
//! | [`export`] | policies for use: the actor and normaliser of a checkpoint |
//! | [`sac`] | soft actor-critic: squashed Gaussian, twin critics, temperature, replay buffer |
//! | [`toy`] | a point-mass `VecEnv` that PPO must solve (tests, examples) |

pub mod buffer;
pub mod checkpoint;
pub mod config;
pub mod env;
pub mod episodes;
pub mod export;
pub mod gae;
pub mod learner;
pub mod normalizer;
pub mod optim;
pub mod policy;
pub mod ppo;
pub mod sac;
pub mod toy;
pub mod trainer;

pub use config::PpoConfig;
pub use env::{StepResult, VecEnv};
pub use learner::{Algo, Learner, LearnerStats};
pub use trainer::{IterationStats, Trainer};

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
