//! Soft actor-critic (Haarnoja et al. 2018) on candle, over the same
//! [`crate::VecEnv`] as PPO: twin critics with Polyak-averaged targets, a
//! tanh-squashed Gaussian actor, automatic temperature, a replay buffer and
//! an update-to-data ratio of choice.
//!
//! | module | job |
//! | --- | --- |
//! | [`config`] | `SacConfig` and its checks |
//! | [`squashed`] | the squashed Gaussian: sample and log-probability |
//! | [`losses`] | the soft Bellman target, critic, actor and temperature losses |
//! | [`replay`] | the replay buffer |
//! | [`agent`] | collect, update, statistics |
//! | [`checkpoint`] | checkpoints with the replay buffer; exact resume |
//!
//! Not yet here (issue 15): the CrossQ variant (batch renormalisation, no
//! target networks) and `quadwalk train --algo sac` (the `[sac]` table,
//! rollouts of a SAC checkpoint).

pub mod agent;
pub mod checkpoint;
pub mod config;
pub mod losses;
pub mod replay;
pub mod squashed;

pub use agent::{SacAgent, SacStats};
pub use config::SacConfig;
