//! The algorithms quadwalk knows, one registration each. Adding an
//! algorithm is a folder (its settings, its learner implementing
//! [`Algorithm`], its checkpoint) and one line in [`ALGORITHMS`]: the
//! experiment file's `[algo] name`, `quadwalk train --algo`, resuming,
//! exporting and acting then find it here.

use std::path::Path;

use crate::LearnError;
use crate::algorithm::Algorithm;
use crate::checkpoint::{STATE_FILE, resolve_checkpoint};
use crate::export::{PolicyFile, is_exported_policy, read_policy_file};
use crate::settings::Settings;

/// An algorithm's settings from its experiment table (`None`: its
/// defaults), checked; the error is the table's problem, named.
pub type SettingsFromTable = fn(Option<&toml::Table>) -> Result<Box<dyn Settings>, String>;

/// Loads a checkpoint directory of one format.
pub type CheckpointLoader = fn(&Path) -> Result<Box<dyn Algorithm>, LearnError>;

/// Loads an exported policy of one format, given its parsed state file.
pub type PolicyLoader = fn(&Path, PolicyFile) -> Result<Box<dyn Algorithm>, LearnError>;

/// How quadwalk finds an algorithm.
pub struct Registration {
    /// the name in experiment files and on the command line
    pub name: &'static str,
    /// the experiment file's table of its settings (CrossQ shares SAC's
    /// `[sac]`)
    pub table: &'static str,
    /// its settings: its defaults with `table`'s keys on top (`None`: the
    /// defaults), checked
    pub settings: SettingsFromTable,
    /// the `algo` its checkpoints' and exported policies' state files name
    /// (a checkpoint without one is PPO's; CrossQ's are SAC's)
    pub format: &'static str,
    /// loads a checkpoint directory of this format
    pub load_checkpoint: CheckpointLoader,
    /// loads an exported policy of this format, given its parsed state file
    pub load_policy: PolicyLoader,
}

impl PartialEq for Registration {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl std::fmt::Debug for Registration {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// Every algorithm, the default first.
pub static ALGORITHMS: &[&Registration] = &[
    &crate::ppo::REGISTRATION,
    &crate::sac::REGISTRATION,
    &crate::sac::CROSSQ_REGISTRATION,
];

/// The default algorithm (the paper's PPO).
pub fn default_algorithm() -> &'static Registration {
    ALGORITHMS[0]
}

/// The algorithm called `name`; the error lists the known ones.
pub fn find(name: &str) -> Result<&'static Registration, String> {
    ALGORITHMS
        .iter()
        .copied()
        .find(|r| r.name == name)
        .ok_or_else(|| format!("{name:?}: must be {}", names()))
}

/// The known names, quoted and joined: `"ppo", "sac" or "crossq"`.
pub fn names() -> String {
    let quoted: Vec<String> = ALGORITHMS.iter().map(|r| format!("{:?}", r.name)).collect();
    match quoted.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
        _ => quoted.join(""),
    }
}

/// The experiment tables of every algorithm, each once, in registration
/// order.
pub fn tables() -> Vec<&'static str> {
    let mut tables: Vec<&'static str> = Vec::new();
    for r in ALGORITHMS {
        if !tables.contains(&r.table) {
            tables.push(r.table);
        }
    }
    tables
}

/// The first registration of `format`.
fn by_format(format: &str, what: impl Fn() -> String) -> Result<&'static Registration, LearnError> {
    ALGORITHMS
        .iter()
        .copied()
        .find(|r| r.format == format)
        .ok_or_else(|| {
            LearnError::Checkpoint(format!(
                "{}: algo {format:?} is none of {}",
                what(),
                names()
            ))
        })
}

/// Loads a checkpoint of any algorithm (told apart by the `algo` of its
/// state file): a checkpoint directory, or a run directory whose `latest`
/// names one. An exported policy is refused: it cannot resume.
pub fn load_checkpoint(path: &Path) -> Result<Box<dyn Algorithm>, LearnError> {
    let dir = resolve_checkpoint(path)?;
    let format = std::fs::read_to_string(dir.join(STATE_FILE))
        .ok()
        .and_then(|text| text.parse::<toml::Table>().ok())
        .and_then(|t| t.get("algo").and_then(|v| v.as_str()).map(str::to_string))
        .unwrap_or_else(|| crate::ppo::REGISTRATION.format.to_string());
    let registration = by_format(&format, || dir.join(STATE_FILE).display().to_string())?;
    (registration.load_checkpoint)(&dir)
}

/// Loads the exported policy in `dir`. It acts as the checkpoint it came
/// from; its critics and optimiser state are fresh and meaningless, so it
/// must not train ([`load_checkpoint`] refuses exports).
pub fn load_policy(dir: &Path) -> Result<Box<dyn Algorithm>, LearnError> {
    let file = read_policy_file(dir)?;
    let registration = by_format(&file.algo, || {
        dir.join(crate::export::POLICY_STATE_FILE)
            .display()
            .to_string()
    })?;
    (registration.load_policy)(dir, file)
}

/// A policy to act with: an exported policy directory, a checkpoint, or a
/// run directory (its `latest` checkpoint).
pub fn load_for_acting(path: &Path) -> Result<Box<dyn Algorithm>, LearnError> {
    if is_exported_policy(path) {
        load_policy(path)
    } else {
        load_checkpoint(path)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_algorithm_is_found_by_its_name_and_reads_its_defaults() {
        assert_eq!(names(), "\"ppo\", \"sac\" or \"crossq\"");
        assert_eq!(tables(), vec!["ppo", "sac"]);
        for r in ALGORITHMS {
            assert_eq!(find(r.name).unwrap().name, r.name);
            let settings = (r.settings)(None).unwrap();
            assert_eq!(settings.algorithm(), r.name);
            // the spelt-out table reads back to the same settings
            let back = (r.settings)(Some(&settings.to_table())).unwrap();
            assert!(*back == *settings, "{}", r.name);
        }
        let err = find("td3").err().unwrap();
        assert!(
            err.contains("\"td3\"") && err.contains("\"crossq\""),
            "{err}"
        );
        let bad: toml::Table = "no_such_key = 1".parse().unwrap();
        for r in ALGORITHMS {
            let err = (r.settings)(Some(&bad)).unwrap_err();
            assert!(err.contains("no_such_key"), "{}: {err}", r.name);
        }
    }

    /// A curriculum stage's rate: used by the next update, written into the
    /// checkpoint and loaded back, for every algorithm; a bad rate is
    /// refused and changes nothing.
    #[test]
    fn a_new_learning_rate_is_used_and_survives_a_checkpoint() {
        let tmp = tempfile::tempdir().unwrap();
        for r in ALGORITHMS {
            let table: toml::Table = if r.table == "ppo" {
                "hidden_sizes = [8]\nminibatch_size = 64"
            } else {
                "hidden_sizes = [8]\nbatch_size = 8\nlearning_starts = 8\nsteps_per_env = 4"
            }
            .parse()
            .unwrap();
            let mut learner = (r.settings)(Some(&table))
                .unwrap()
                .build((4, 0), 2, 3)
                .unwrap();
            let before = learner.checkpoint_files().unwrap();
            for bad in [0.0, -1e-4, 1.0, f64::NAN, f64::INFINITY] {
                let err = learner.set_learning_rate(bad).unwrap_err().to_string();
                assert!(err.contains("learning_rate"), "{err}");
            }
            assert_eq!(learner.checkpoint_files().unwrap(), before, "{}", r.name);
            learner.set_learning_rate(5e-5).unwrap();
            let mut env = crate::toy::PointMass::new(4, 16);
            let stats = learner.iterate(&mut env).unwrap();
            if let Some(rate) = stats.figure("learning_rate") {
                assert_eq!(rate, crate::Figure::Value(5e-5));
            }
            let dir = tmp.path().join(r.name);
            let files = learner.checkpoint_files().unwrap();
            crate::checkpoint::write_dir_atomically(&dir, &files).unwrap();
            let state: toml::Table = std::fs::read_to_string(dir.join(STATE_FILE))
                .unwrap()
                .parse()
                .unwrap();
            let rate = state[r.table]["learning_rate"].as_float();
            assert_eq!(rate, Some(5e-5), "{}", r.name);
            let back = load_checkpoint(&dir).unwrap();
            assert_eq!(back.name(), r.name);
            assert_eq!(back.checkpoint_files().unwrap(), files, "{}", r.name);
        }
    }
}
