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

use serde::{Deserialize, Serialize};

use crate::LearnError;
use crate::checkpoint::{
    FORMAT_VERSION, TensorFile, bad_file, fnv1a64, normalizer_tensors, read_checksummed,
    state_text, tensors_file, var_tensors,
};
use crate::config::PpoConfig;
use crate::learner::Learner;
use crate::sac::{SacAgent, SacConfig};
use crate::trainer::Trainer;

/// The exported weights' file name.
pub const POLICY_WEIGHTS_FILE: &str = "policy.safetensors";
/// The exported policy's description file name.
pub const POLICY_STATE_FILE: &str = "policy.toml";

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PolicyStateFile {
    format: u32,
    /// "ppo" or "sac" (CrossQ is a SAC setting)
    algo: String,
    iteration: u64,
    seed: u64,
    obs_size: usize,
    action_size: usize,
    normalizer_count: f64,
    policy_fnv1a64: String,
    ppo: Option<PpoConfig>,
    sac: Option<SacConfig>,
}

/// Whether `dir` holds an exported policy.
pub fn is_exported_policy(dir: &Path) -> bool {
    dir.join(POLICY_STATE_FILE).is_file()
}

impl Learner {
    /// The vars acting needs, named as in checkpoints.
    fn acting_vars(&self) -> Vec<(String, candle_core::Var)> {
        match self {
            Self::Ppo(t) => t.policy.actor_vars(),
            Self::Sac(a) => a.actor.named_vars("actor"),
        }
    }

    /// The exported policy's files (name, bytes), ready for
    /// [`crate::checkpoint::write_dir_atomically`].
    pub fn policy_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
        let normalizer = match self {
            Self::Ppo(t) => &t.normalizer,
            Self::Sac(a) => &a.normalizer,
        };
        let mut tensors = var_tensors(self.acting_vars());
        tensors.extend(normalizer_tensors(normalizer)?);
        let weights = tensors_file(tensors)?;
        let (algo, seed, ppo, sac) = match self {
            Self::Ppo(t) => ("ppo", t.seed, Some(t.config.clone()), None),
            Self::Sac(a) => ("sac", a.seed, None, Some(a.config.clone())),
        };
        let state = PolicyStateFile {
            format: FORMAT_VERSION,
            algo: algo.to_string(),
            iteration: self.iteration(),
            seed,
            obs_size: self.obs_size(),
            action_size: self.action_size(),
            normalizer_count: normalizer.count,
            policy_fnv1a64: format!("{:016x}", fnv1a64(&weights)),
            ppo,
            sac,
        };
        Ok(vec![
            (POLICY_WEIGHTS_FILE.into(), weights),
            (POLICY_STATE_FILE.into(), state_text(&state)?),
        ])
    }

    /// Loads the exported policy in `dir`. The learner acts as the
    /// checkpoint it came from; its critics and optimiser state are fresh
    /// and meaningless, so it must not train (`quadwalk train --resume`
    /// refuses exports, [`Learner::load`]).
    pub fn load_policy(dir: &Path) -> Result<Self, LearnError> {
        let text = std::fs::read_to_string(dir.join(POLICY_STATE_FILE))
            .map_err(|e| bad_file(dir, POLICY_STATE_FILE, format!("cannot read it: {e}")))?;
        let bad_state = |what: String| bad_file(dir, POLICY_STATE_FILE, what);
        let state: PolicyStateFile = toml::from_str(&text)
            .map_err(|e| bad_state(format!("not a valid policy file: {}", e.message())))?;
        if state.format != FORMAT_VERSION {
            return Err(bad_state(format!(
                "format {} is not the supported {FORMAT_VERSION}",
                state.format
            )));
        }
        let (o, a) = (state.obs_size, state.action_size);
        let (mut learner, clip) = match (state.algo.as_str(), state.ppo, state.sac) {
            ("ppo", Some(ppo), None) => {
                ppo.validate().map_err(|e| bad_state(e.to_string()))?;
                let clip = ppo.obs_clip;
                let mut trainer = Trainer::new(ppo, o, a, state.seed)?;
                trainer.iteration = state.iteration;
                (Self::Ppo(Box::new(trainer)), clip)
            }
            ("sac", None, Some(sac)) => {
                sac.validate().map_err(|e| bad_state(e.to_string()))?;
                let clip = sac.obs_clip;
                let mut agent = SacAgent::new(sac, o, a, state.seed)?;
                agent.iteration = state.iteration;
                (Self::Sac(Box::new(agent)), clip)
            }
            (algo, ..) => {
                return Err(bad_state(format!(
                    "algo {algo:?} with its settings table: expected \"ppo\" with [ppo] or \"sac\" with [sac]"
                )));
            }
        };
        let weights = read_checksummed(
            dir,
            POLICY_WEIGHTS_FILE,
            POLICY_STATE_FILE,
            &state.policy_fnv1a64,
        )?;
        let file = TensorFile::parse(&weights, dir, POLICY_WEIGHTS_FILE)?;
        file.load_vars(&learner.acting_vars())?;
        let normalizer = file.load_normalizer(o, state.normalizer_count, clip)?;
        match &mut learner {
            Self::Ppo(t) => t.normalizer = normalizer,
            Self::Sac(a) => a.normalizer = normalizer,
        }
        Ok(learner)
    }

    /// A policy to act with: an exported policy directory, a checkpoint, or
    /// a run directory (its `latest` checkpoint).
    pub fn load_for_acting(path: &Path) -> Result<Self, LearnError> {
        if is_exported_policy(path) {
            Self::load_policy(path)
        } else {
            Self::load(path)
        }
    }
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
    use crate::checkpoint::write_dir_atomically;
    use crate::toy::PointMass;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn trained(algo: crate::Algo) -> Learner {
        let mut env = PointMass::new(4, 10);
        let mut learner = match algo {
            crate::Algo::Ppo => Learner::Ppo(Box::new(
                Trainer::new(
                    PpoConfig {
                        hidden_sizes: vec![16],
                        steps_per_env: 10,
                        ..PpoConfig::default()
                    },
                    4,
                    2,
                    1,
                )
                .unwrap(),
            )),
            _ => Learner::Sac(Box::new(
                SacAgent::new(
                    SacConfig {
                        hidden_sizes: vec![16],
                        batch_size: 8,
                        learning_starts: 8,
                        steps_per_env: 10,
                        ..algo.sac_defaults()
                    },
                    4,
                    2,
                    1,
                )
                .unwrap(),
            )),
        };
        for _ in 0..3 {
            learner.iterate(&mut env).unwrap();
        }
        learner
    }

    #[test]
    fn an_exported_policy_acts_as_its_checkpoint_and_cannot_resume() {
        for algo in [crate::Algo::Ppo, crate::Algo::Sac, crate::Algo::CrossQ] {
            let learner = trained(algo);
            let tmp = tempfile::tempdir().unwrap();
            let dir = tmp.path().join("policy");
            write_dir_atomically(&dir, &learner.policy_files().unwrap()).unwrap();
            assert!(is_exported_policy(&dir));
            let loaded = Learner::load_for_acting(&dir).unwrap();
            assert_eq!(loaded.iteration(), 3);
            let obs = [0.1f32, -0.2, 0.5, -0.5, 1.0, 2.0, -1.0, 0.0];
            assert_eq!(
                loaded.act_deterministic(&obs).unwrap(),
                learner.act_deterministic(&obs).unwrap(),
                "{algo:?}"
            );
            let sampled = |l: &Learner| {
                l.act_stochastic(&obs, &mut ChaCha8Rng::seed_from_u64(4))
                    .unwrap()
            };
            assert_eq!(sampled(&loaded), sampled(&learner), "{algo:?}");
            // smaller than the checkpoint: no critic, no optimiser state
            let size = |files: &[(String, Vec<u8>)]| files.iter().map(|f| f.1.len()).sum::<usize>();
            assert!(
                size(&learner.policy_files().unwrap()) * 2
                    < size(&learner.checkpoint_files().unwrap()),
                "{algo:?}"
            );
            // training cannot resume from it
            let err = Learner::load(&dir).err().unwrap().to_string();
            assert!(err.contains("exported policy"), "{err}");
        }
    }

    #[test]
    fn a_damaged_export_is_named() {
        let learner = trained(crate::Algo::Ppo);
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("policy");
        write_dir_atomically(&dir, &learner.policy_files().unwrap()).unwrap();
        let weights = dir.join(POLICY_WEIGHTS_FILE);
        let mut bytes = std::fs::read(&weights).unwrap();
        let last = bytes.len() - 1;
        bytes[last] ^= 0xff;
        std::fs::write(&weights, &bytes).unwrap();
        let err = Learner::load_for_acting(&dir).err().unwrap().to_string();
        assert!(
            err.contains(POLICY_WEIGHTS_FILE)
                && err.contains("checksum")
                && err.contains(POLICY_STATE_FILE),
            "{err}"
        );
        std::fs::write(dir.join(POLICY_STATE_FILE), "format = 1\nalgo = \"td3\"\n").unwrap();
        let err = Learner::load_for_acting(&dir).err().unwrap().to_string();
        assert!(err.contains(POLICY_STATE_FILE), "{err}");
    }
}
