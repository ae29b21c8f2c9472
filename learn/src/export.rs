//! Policies for use: what acting needs from a checkpoint, and nothing else.
//!
//! | file | content |
//! | --- | --- |
//! | `policy.safetensors` | the actor (`actor.K.weight/bias`; PPO also `log_std`) and the normaliser (`obs_norm.mean`, `obs_norm.var`, f64) |
//! | `policy.toml` | format, algorithm, iteration, seed, sizes, normaliser count, the learner's settings (`[ppo]` or `[sac]`), and the FNV-1a 64 checksum of `policy.safetensors` |
//!
//! No critic, optimiser state or replay buffer: an exported policy acts
//! exactly as its checkpoint does (deterministic and sampled actions, tested
//! bit for bit) but cannot resume training. A PPO export of the paper's
//! networks is ~250 kB (`policies/rigid`), against ~1.5 MB for its
//! checkpoint and ~190 MB for a SAC checkpoint with a full buffer.

use std::path::Path;

use candle_core::Var;
use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::checkpoint::{
    FORMAT_VERSION, TensorFile, bad_file, fnv1a64, normalizer_tensors, read_checksummed,
    state_text, tensors_file, var_tensors,
};
use crate::normalizer::ObsNormalizer;
use crate::registry::Registration;

/// The exported weights' file name.
pub const POLICY_WEIGHTS_FILE: &str = "policy.safetensors";
/// The exported policy's description file name.
pub const POLICY_STATE_FILE: &str = "policy.toml";

/// An exported policy's state file: what it is and how to check its
/// weights; `settings` holds the learner's table (`[ppo]` or `[sac]`).
#[derive(Debug, Serialize, Deserialize)]
pub struct PolicyFile {
    /// the layout's version ([`FORMAT_VERSION`])
    pub format: u32,
    /// the registered format ([`crate::registry::Registration::format`])
    pub algo: String,
    /// iterations trained
    pub iteration: u64,
    /// the run's seed
    pub seed: u64,
    /// observation values the actor takes
    pub obs_size: usize,
    /// action values it gives
    pub action_size: usize,
    /// observations the normaliser has seen
    pub normalizer_count: f64,
    /// FNV-1a 64 of `policy.safetensors`, hex
    pub policy_fnv1a64: String,
    /// the learner's settings, one table named after it
    #[serde(flatten)]
    pub settings: toml::Table,
}

impl PolicyFile {
    /// The learner's settings, read from its table by `registration` and
    /// checked.
    pub fn settings<T: Clone + 'static>(
        &self,
        dir: &Path,
        registration: &Registration,
    ) -> Result<T, LearnError> {
        let bad = |what: String| bad_file(dir, POLICY_STATE_FILE, what);
        let table = self.settings_table(dir, registration.table)?;
        let settings = (registration.settings)(Some(&table)).map_err(bad)?;
        settings
            .as_any()
            .downcast_ref::<T>()
            .cloned()
            .ok_or_else(|| {
                bad(format!(
                    "[{}] does not hold {}'s settings",
                    registration.table, registration.name
                ))
            })
    }

    /// The learner's settings table `name`, the only one the file may hold.
    pub fn settings_table(&self, dir: &Path, name: &str) -> Result<toml::Table, LearnError> {
        match (self.settings.len(), self.settings.get(name)) {
            (1, Some(toml::Value::Table(t))) => Ok(t.clone()),
            _ => Err(bad_file(
                dir,
                POLICY_STATE_FILE,
                format!(
                    "algo {:?} with its settings table: expected [{name}] and no other table, found [{}]",
                    self.algo,
                    self.settings
                        .keys()
                        .cloned()
                        .collect::<Vec<_>>()
                        .join("], [")
                ),
            )),
        }
    }
}

/// Whether `dir` holds an exported policy.
pub fn is_exported_policy(dir: &Path) -> bool {
    dir.join(POLICY_STATE_FILE).is_file()
}

/// The files of an exported policy (name, bytes), ready for
/// [`crate::checkpoint::write_dir_atomically`]: the acting `vars` and the
/// normaliser in the weights, the rest in the state file with the
/// learner's `settings` as the table `table`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn policy_files(
    algo: &str,
    iteration: u64,
    seed: u64,
    (obs_size, action_size): (usize, usize),
    vars: Vec<(String, Var)>,
    normalizer: &ObsNormalizer,
    table: &str,
    settings: toml::Table,
) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
    let mut tensors = var_tensors(vars);
    tensors.extend(normalizer_tensors(normalizer)?);
    let weights = tensors_file(tensors)?;
    let mut tables = toml::Table::new();
    tables.insert(table.to_string(), toml::Value::Table(settings));
    let state = PolicyFile {
        format: FORMAT_VERSION,
        algo: algo.to_string(),
        iteration,
        seed,
        obs_size,
        action_size,
        normalizer_count: normalizer.count,
        policy_fnv1a64: format!("{:016x}", fnv1a64(&weights)),
        settings: tables,
    };
    Ok(vec![
        (POLICY_WEIGHTS_FILE.into(), weights),
        (POLICY_STATE_FILE.into(), state_text(&state)?),
    ])
}

/// Reads and checks the format of `dir`'s state file.
pub fn read_policy_file(dir: &Path) -> Result<PolicyFile, LearnError> {
    let text = std::fs::read_to_string(dir.join(POLICY_STATE_FILE))
        .map_err(|e| bad_file(dir, POLICY_STATE_FILE, format!("cannot read it: {e}")))?;
    let bad_state = |what: String| bad_file(dir, POLICY_STATE_FILE, what);
    let state: PolicyFile = toml::from_str(&text)
        .map_err(|e| bad_state(format!("not a valid policy file: {}", e.message())))?;
    if state.format != FORMAT_VERSION {
        return Err(bad_state(format!(
            "format {} is not the supported {FORMAT_VERSION}",
            state.format
        )));
    }
    Ok(state)
}

/// Loads the exported weights into `vars` (checksum, presence, shapes) and
/// returns the normaliser, clipping at `obs_clip`.
pub(crate) fn load_acting_weights(
    dir: &Path,
    file: &PolicyFile,
    vars: &[(String, Var)],
    obs_clip: f64,
) -> Result<ObsNormalizer, LearnError> {
    let weights = read_checksummed(
        dir,
        POLICY_WEIGHTS_FILE,
        POLICY_STATE_FILE,
        &file.policy_fnv1a64,
    )?;
    let tensors = TensorFile::parse(&weights, dir, POLICY_WEIGHTS_FILE)?;
    tensors.load_vars(vars)?;
    tensors.load_normalizer(file.obs_size, file.normalizer_count, obs_clip)
}

/// The error for an exported policy where a checkpoint is needed.
pub(crate) fn not_a_checkpoint(dir: &Path) -> LearnError {
    LearnError::Checkpoint(format!(
        "{}: an exported policy (no critics, optimiser state or replay buffer): it can act but training cannot resume from it; resume from the run's checkpoint",
        dir.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::Algorithm;
    use crate::checkpoint::write_dir_atomically;
    use crate::registry::{ALGORITHMS, find, load_checkpoint, load_for_acting};
    use crate::toy::PointMass;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A small learner of algorithm `name` after three iterations on the
    /// point mass.
    pub(crate) fn trained(name: &str) -> Box<dyn Algorithm> {
        let registration = find(name).unwrap();
        let table: toml::Table = if registration.table == "ppo" {
            "hidden_sizes = [16]\nsteps_per_env = 10"
        } else {
            "hidden_sizes = [16]\nbatch_size = 8\nlearning_starts = 8\nsteps_per_env = 10"
        }
        .parse()
        .unwrap();
        let settings = (registration.settings)(Some(&table)).unwrap();
        let mut learner = settings.build((4, 0), 2, 1).unwrap();
        let mut env = PointMass::new(4, 10);
        for _ in 0..3 {
            learner.iterate(&mut env).unwrap();
        }
        learner
    }

    #[test]
    fn an_exported_policy_acts_as_its_checkpoint_and_cannot_resume() {
        for registration in ALGORITHMS {
            let name = registration.name;
            let learner = trained(name);
            let tmp = tempfile::tempdir().unwrap();
            let dir = tmp.path().join("policy");
            write_dir_atomically(&dir, &learner.policy_files().unwrap()).unwrap();
            assert!(is_exported_policy(&dir));
            let loaded = load_for_acting(&dir).unwrap();
            assert_eq!((loaded.iteration(), loaded.name()), (3, name));
            let obs = [0.1f32, -0.2, 0.5, -0.5, 1.0, 2.0, -1.0, 0.0];
            assert_eq!(
                loaded.act_deterministic(&obs).unwrap(),
                learner.act_deterministic(&obs).unwrap(),
                "{name}"
            );
            let sampled = |l: &dyn Algorithm| {
                l.act_stochastic(&obs, &mut ChaCha8Rng::seed_from_u64(4))
                    .unwrap()
            };
            assert_eq!(sampled(&*loaded), sampled(&*learner), "{name}");
            // smaller than the checkpoint: no critic, no optimiser state
            let size = |files: &[(String, Vec<u8>)]| files.iter().map(|f| f.1.len()).sum::<usize>();
            assert!(
                size(&learner.policy_files().unwrap()) * 2
                    < size(&learner.checkpoint_files().unwrap()),
                "{name}"
            );
            // training cannot resume from it
            let err = load_checkpoint(&dir).err().unwrap().to_string();
            assert!(err.contains("exported policy"), "{err}");
        }
    }

    #[test]
    fn a_damaged_export_is_named() {
        let learner = trained("ppo");
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("policy");
        write_dir_atomically(&dir, &learner.policy_files().unwrap()).unwrap();
        let weights = dir.join(POLICY_WEIGHTS_FILE);
        let mut bytes = std::fs::read(&weights).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 0xff;
        std::fs::write(&weights, &bytes).unwrap();
        let err = load_for_acting(&dir).err().unwrap().to_string();
        assert!(
            err.contains(POLICY_WEIGHTS_FILE)
                && err.contains("checksum")
                && err.contains(POLICY_STATE_FILE),
            "{err}"
        );
        std::fs::write(dir.join(POLICY_STATE_FILE), "format = 1\nalgo = \"td3\"\n").unwrap();
        let err = load_for_acting(&dir).err().unwrap().to_string();
        assert!(err.contains(POLICY_STATE_FILE), "{err}");
    }
}
