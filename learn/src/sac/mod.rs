//! Soft actor-critic (Haarnoja et al. 2018) on candle, over the same
//! [`crate::VecEnv`] as PPO: twin critics with Polyak-averaged targets (or
//! CrossQ's batch-renormalised critics without targets), a tanh-squashed
//! Gaussian actor, automatic temperature, a replay buffer and an
//! update-to-data ratio of choice.
//!
//! | module | job |
//! | --- | --- |
//! | [`config`] | `SacConfig` and its checks |
//! | [`squashed`] | the squashed Gaussian: sample and log-probability |
//! | [`losses`] | the soft Bellman target, critic, actor and temperature losses |
//! | [`batch_renorm`] | batch renormalisation (CrossQ's critics) |
//! | [`critics`] | the twin critics: with targets, or CrossQ's |
//! | [`replay`] | the replay buffer |
//! | [`agent`] | collect, update, statistics |
//! | [`checkpoint`] | checkpoints with the replay buffer; exact resume |

pub mod agent;
pub mod batch_renorm;
pub mod checkpoint;
pub mod config;
pub mod critics;
pub mod losses;
pub mod replay;
pub mod squashed;

pub use agent::{SacAgent, SacStats};
pub use config::{SacConfig, SacVariant};
