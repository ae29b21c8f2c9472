//! An algorithm's settings as an experiment holds them: read from the
//! algorithm's table of an experiment file, written back spelt out, compared,
//! and turned into a fresh learner. The experiment layer sees only this
//! trait, so a registered algorithm brings its own table.

use std::any::Any;
use std::fmt::Debug;

use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::LearnError;
use crate::algorithm::Algorithm;

/// One algorithm's settings. A `Clone + Serialize` type gets
/// [`SettingsValue`] for free; it writes the rest.
pub trait Settings: SettingsValue + Debug + Send + Sync {
    /// The registered name of the algorithm they are for.
    fn algorithm(&self) -> &'static str;

    /// The learning rate updates start with.
    fn learning_rate(&self) -> f64;

    /// Whether the algorithm moves its learning rate itself (PPO's
    /// `desired_kl`): a curriculum stage may then not set one.
    fn adapts_learning_rate(&self) -> bool;

    /// Environment steps per environment per iteration. Every iteration
    /// starts fresh episodes, so no episode runs longer than this: one
    /// still running when the iteration ends is cut there.
    fn steps_per_env(&self) -> usize;

    /// A fresh learner for `obs_size` observations (and `privileged_size`
    /// values after them that only a critic may see,
    /// [`crate::VecEnv::policy_observation_size`]) and `action_size`
    /// actions, seeded by `seed`. An algorithm without an asymmetric critic
    /// refuses privileged values.
    fn build(
        &self,
        obs_size: (usize, usize),
        action_size: usize,
        seed: u64,
    ) -> Result<Box<dyn Algorithm>, LearnError>;
}

/// What settings are as values: spelt out as a table, copied, and seen as
/// their concrete type.
pub trait SettingsValue {
    /// Every setting spelt out, as the experiment file's table.
    fn to_table(&self) -> toml::Table;

    /// A boxed copy.
    fn clone_box(&self) -> Box<dyn Settings>;

    /// The concrete settings (`PpoConfig`, `SacConfig`), for callers that
    /// know the algorithm.
    fn as_any(&self) -> &dyn Any;
}

impl<T: Settings + Clone + Serialize + 'static> SettingsValue for T {
    fn to_table(&self) -> toml::Table {
        to_table(self).expect("settings serialise to a table")
    }

    fn clone_box(&self) -> Box<dyn Settings> {
        Box::new(self.clone())
    }

    fn as_any(&self) -> &dyn Any {
        self
    }
}

impl Clone for Box<dyn Settings> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// Two settings are equal when they are for the same algorithm and spell
/// out the same table.
impl PartialEq for dyn Settings + '_ {
    fn eq(&self, other: &Self) -> bool {
        self.algorithm() == other.algorithm() && self.to_table() == other.to_table()
    }
}

/// `base` with the values of `table` on top. Keys `base` does not know are
/// errors, through the type's `deny_unknown_fields`; the message is TOML's.
pub fn overlay<T: Serialize + DeserializeOwned>(
    base: &T,
    table: Option<&toml::Table>,
) -> Result<T, String> {
    let mut merged = to_table(base)?;
    if let Some(table) = table {
        for (key, value) in table {
            merged.insert(key.clone(), value.clone());
        }
    }
    toml::Value::Table(merged)
        .try_into()
        .map_err(|e: toml::de::Error| e.message().to_string())
}

/// `value` as a TOML table.
pub fn to_table<T: Serialize>(value: &T) -> Result<toml::Table, String> {
    match toml::Value::try_from(value).map_err(|e| e.to_string())? {
        toml::Value::Table(t) => Ok(t),
        _ => Err("settings do not serialise to a table".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ppo::PpoConfig;

    #[test]
    fn a_table_goes_on_top_of_its_base_and_unknown_keys_are_named() {
        let base = PpoConfig::default();
        let table: toml::Table = "epochs = 3".parse().unwrap();
        let merged: PpoConfig = overlay(&base, Some(&table)).unwrap();
        assert_eq!(merged.epochs, 3);
        assert_eq!(merged.learning_rate, base.learning_rate);
        let bad: toml::Table = "epoch = 3".parse().unwrap();
        let err = overlay(&base, Some(&bad)).unwrap_err();
        assert!(err.contains("epoch"), "{err}");
        let table = to_table(&merged).unwrap();
        assert_eq!(table["epochs"].as_integer(), Some(3));
    }
}
