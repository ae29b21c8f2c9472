//! quadwalk's settings where an experiment file is silent, and how a
//! table's keys go on top of a base (`[task]`, `[physics]`, `[ppo]`,
//! `[sac]`).

use anyhow::{Result, anyhow};
use learn::registry::Registration;
use learn::{PpoConfig, Settings, SettingsValue};
use robot::WorldConfig;
use robot::task::{BalanceTerms, DistanceReward, TaskConfig};
use serde::Serialize;

/// `base` with the values of `table` on top (keys `base` does not know are
/// errors, through the type's `deny_unknown_fields`).
pub(super) fn overlay<T: Serialize + serde::de::DeserializeOwned>(
    base: &T,
    table: Option<&toml::Table>,
) -> Result<T> {
    learn::settings::overlay(base, table).map_err(|e| anyhow!("{e}"))
}

/// The task settings where an experiment is silent: the paper's, but for
/// the two reward choices with which PPO learns to walk here (docs/notebook/2026-11-30-policies-that-walk.md
/// "Policies that walk"): R_d pays only for new ground (the paper's term
/// pays for rocking, and a policy learned to rock), and the balance terms
/// are penalties (the paper's pay ~0.8 per phase for standing still).
/// `configs/tv2.toml` and the paper's other configs spell out the paper's
/// values.
pub fn default_task() -> TaskConfig {
    TaskConfig {
        distance_reward: DistanceReward::NewGround,
        balance_terms: BalanceTerms::Penalty,
        ..TaskConfig::default()
    }
}

/// PPO where an experiment is silent: the paper's, but minibatches of 128
/// (50 Adam steps per 640-phase iteration; the paper's 4096 makes one
/// minibatch of 640, 10 steps).
pub fn default_ppo() -> PpoConfig {
    PpoConfig {
        minibatch_size: 128,
        ..PpoConfig::default()
    }
}

/// The settings of `algo` from its experiment table: the algorithm's
/// defaults, then quadwalk's where it has its own ([`default_ppo`] for
/// `[ppo]`), then the file's `table` on top; checked by the algorithm.
pub(super) fn resolve_learner(
    algo: &'static Registration,
    table: Option<&toml::Table>,
) -> Result<Box<dyn Settings>, String> {
    let mut merged = if algo.table == learn::ppo::REGISTRATION.table {
        default_ppo().to_table()
    } else {
        toml::Table::new()
    };
    if let Some(table) = table {
        merged.extend(table.clone());
    }
    (algo.settings)(Some(&merged))
}

/// `[task]`'s table resolved over [`default_task`].
pub(super) fn resolve_task(table: &toml::Table) -> Result<TaskConfig, String> {
    let task: TaskConfig = overlay(&default_task(), Some(table)).map_err(|e| e.to_string())?;
    task.validate().map_err(|e| e.to_string())?;
    Ok(task)
}

/// `base` with `table`'s `[physics]` keys on top, checked: the `[physics]`
/// section over the defaults, or a stage's `[curriculum.physics]` over it.
pub(super) fn resolve_physics(
    base: &WorldConfig,
    table: &toml::Table,
) -> Result<WorldConfig, String> {
    let physics: WorldConfig = overlay(base, Some(table)).map_err(|e| e.to_string())?;
    physics.validate().map_err(|e| e.to_string())?;
    Ok(physics)
}
