//! SAC checkpoints, in the layout and with the guarantees of PPO's
//! (`crate::checkpoint`: atomic directories, checksums, named errors):
//!
//! | file | content |
//! | --- | --- |
//! | `weights.safetensors` | `actor.*`, `q1.*`, `q2.*`, then `q1_target.*`, `q2_target.*` (SAC) or each critic's normalisation's running statistics (`q1.norm<k>.running_mean`, CrossQ), `log_alpha`, the normaliser (`obs_norm.mean`, `obs_norm.var`, f64) and the three optimisers' moments (`adam_actor.*`, `adam_critic.*`, `adam_alpha.*`) |
//! | `replay.safetensors` | the replay buffer's stored transitions in storage order (`replay.obs`, `replay.actions`, `replay.rewards`, `replay.next_obs`, `replay.terminated`) |
//! | `state.toml` | format, `algo = "sac"`, iteration, seed, sizes, step and update counters, the update debt, Adam steps, normaliser count, the sampling RNG's position, the ring position, the SAC settings, and both files' FNV-1a 64 checksums |
//!
//! With the buffer inside, a resumed run continues bit for bit (tested). A
//! policy shipped for use needs only the weights; the buffer of a full run
//! is `buffer_size x (2 O + A + 2) x 4` bytes (~190 MB at the defaults for
//! the robot).

use std::path::Path;

use candle_core::{Device, Tensor};
use serde::{Deserialize, Serialize};

use super::agent::SacAgent;
use super::config::SacConfig;
use super::replay::{Batch, ReplayBuffer};
use crate::LearnError;
use crate::checkpoint::{
    FORMAT_VERSION, STATE_FILE, TensorFile, WEIGHTS_FILE, adam_tensors, bad_file, fnv1a64,
    normalizer_tensors, read_checksummed, read_state, resolve_checkpoint, rng_fields,
    rng_from_fields, state_text, tensors_file, var_tensors,
};

/// The replay buffer's file name.
pub const REPLAY_FILE: &str = "replay.safetensors";

/// The `algo` value of a SAC state file (CrossQ's too: the variant is a
/// setting).
pub const ALGO: &str = "sac";

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SacStateFile {
    format: u32,
    algo: String,
    iteration: u64,
    seed: u64,
    obs_size: usize,
    action_size: usize,
    total_steps: u64,
    total_updates: u64,
    update_debt: f64,
    adam_steps: [u64; 3],
    normalizer_count: f64,
    rng_seed_hex: String,
    rng_stream: u64,
    rng_word_pos: String,
    replay_len: usize,
    replay_next: usize,
    weights_fnv1a64: String,
    replay_fnv1a64: String,
    sac: SacConfig,
}

impl SacAgent {
    /// Every var of the networks, named as in the weights file.
    pub fn named_vars(&self) -> Vec<(String, candle_core::Var)> {
        let mut vars = self.actor.named_vars("actor");
        vars.extend(self.critics.named_vars());
        vars.push(("log_alpha".to_string(), self.log_alpha.clone()));
        vars
    }

    /// The checkpoint's files (name, bytes), ready for
    /// [`crate::checkpoint::write_dir_atomically`].
    pub fn checkpoint_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
        let mut tensors = var_tensors(self.named_vars());
        tensors.extend(normalizer_tensors(&self.normalizer)?);
        tensors.extend(adam_tensors(&self.actor_adam, "adam_actor"));
        tensors.extend(adam_tensors(&self.critic_adam, "adam_critic"));
        tensors.extend(adam_tensors(&self.alpha_adam, "adam_alpha"));
        let weights = tensors_file(tensors)?;

        let (stored, next) = self.buffer.stored();
        let len = stored.rewards.len();
        let (o, a) = (self.obs_size(), self.action_size());
        let device = Device::Cpu;
        let replay = tensors_file(vec![
            (
                "replay.obs".into(),
                Tensor::from_vec(stored.obs, (len, o), &device)?,
            ),
            (
                "replay.actions".into(),
                Tensor::from_vec(stored.actions, (len, a), &device)?,
            ),
            (
                "replay.rewards".into(),
                Tensor::from_vec(stored.rewards, len, &device)?,
            ),
            (
                "replay.next_obs".into(),
                Tensor::from_vec(stored.next_obs, (len, o), &device)?,
            ),
            (
                "replay.terminated".into(),
                Tensor::from_vec(stored.terminated, len, &device)?,
            ),
        ])?;
        let (rng_seed_hex, rng_stream, rng_word_pos) = rng_fields(&self.rng_state());
        let state = SacStateFile {
            format: FORMAT_VERSION,
            algo: ALGO.to_string(),
            iteration: self.iteration,
            seed: self.seed,
            obs_size: o,
            action_size: a,
            total_steps: self.total_steps,
            total_updates: self.total_updates,
            update_debt: self.update_debt,
            adam_steps: [
                self.actor_adam.step,
                self.critic_adam.step,
                self.alpha_adam.step,
            ],
            normalizer_count: self.normalizer.count,
            rng_seed_hex,
            rng_stream,
            rng_word_pos,
            replay_len: len,
            replay_next: next,
            weights_fnv1a64: format!("{:016x}", fnv1a64(&weights)),
            replay_fnv1a64: format!("{:016x}", fnv1a64(&replay)),
            sac: self.config.clone(),
        };
        Ok(vec![
            (WEIGHTS_FILE.into(), weights),
            (REPLAY_FILE.into(), replay),
            (STATE_FILE.into(), state_text(&state)?),
        ])
    }

    /// Loads the checkpoint in `dir` (a checkpoint directory, or a run
    /// directory whose `latest` names one).
    pub fn load(dir: &Path) -> Result<Self, LearnError> {
        let dir = resolve_checkpoint(dir)?;
        let state: SacStateFile = read_state(&dir)?;
        let bad_state = |what: String| bad_file(&dir, STATE_FILE, what);
        if state.format != FORMAT_VERSION || state.algo != ALGO {
            return Err(bad_state(format!(
                "format {} algo {:?} is not the supported {FORMAT_VERSION} {ALGO:?}",
                state.format, state.algo
            )));
        }
        state.sac.validate().map_err(|e| bad_state(e.to_string()))?;
        if !(state.update_debt.is_finite() && state.update_debt >= 0.0) {
            return Err(bad_state(format!(
                "update_debt {} is not a non-negative number",
                state.update_debt
            )));
        }
        let weights = read_checksummed(&dir, WEIGHTS_FILE, STATE_FILE, &state.weights_fnv1a64)?;
        let replay = read_checksummed(&dir, REPLAY_FILE, STATE_FILE, &state.replay_fnv1a64)?;
        let rng = rng_from_fields(
            &dir,
            &state.rng_seed_hex,
            state.rng_stream,
            &state.rng_word_pos,
        )?;
        let (o, a) = (state.obs_size, state.action_size);
        let mut agent = SacAgent::new(state.sac.clone(), o, a, state.seed)?;
        let file = TensorFile::parse(&weights, &dir, WEIGHTS_FILE)?;
        file.load_vars(&agent.named_vars())?;
        agent.normalizer = file.load_normalizer(o, state.normalizer_count, state.sac.obs_clip)?;
        let [actor_step, critic_step, alpha_step] = state.adam_steps;
        file.load_adam(&mut agent.actor_adam, "adam_actor", actor_step)?;
        file.load_adam(&mut agent.critic_adam, "adam_critic", critic_step)?;
        file.load_adam(&mut agent.alpha_adam, "adam_alpha", alpha_step)?;

        let file = TensorFile::parse(&replay, &dir, REPLAY_FILE)?;
        let n = state.replay_len;
        let rows = |name: &str, cols: usize| -> Result<Vec<f32>, LearnError> {
            Ok(file
                .get_finite(name, &[n, cols])?
                .flatten_all()?
                .to_vec1()?)
        };
        let stored = Batch {
            obs: rows("replay.obs", o)?,
            actions: rows("replay.actions", a)?,
            rewards: file.get_finite("replay.rewards", &[n])?.to_vec1()?,
            next_obs: rows("replay.next_obs", o)?,
            terminated: file.get_finite("replay.terminated", &[n])?.to_vec1()?,
        };
        agent.buffer =
            ReplayBuffer::from_stored(o, a, state.sac.buffer_size, &stored, state.replay_next)
                .ok_or_else(|| {
                    bad_state(format!(
                        "replay_len {n} and replay_next {} do not fit a buffer of {}",
                        state.replay_next, state.sac.buffer_size
                    ))
                })?;
        agent.iteration = state.iteration;
        agent.total_steps = state.total_steps;
        agent.total_updates = state.total_updates;
        agent.update_debt = state.update_debt;
        agent.set_rng_state(&rng);
        Ok(agent)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checkpoint::write_dir_atomically;
    use crate::toy::PointMass;

    fn config() -> SacConfig {
        SacConfig {
            hidden_sizes: vec![8],
            batch_size: 16,
            buffer_size: 100,
            learning_starts: 20,
            steps_per_env: 10,
            updates_per_step: 0.5,
            ..SacConfig::default()
        }
    }

    fn resume_equals_the_uninterrupted_run(config: SacConfig) {
        let mut straight = SacAgent::new(config.clone(), 4, 2, 3).unwrap();
        let mut env = PointMass::new(4, 10);
        for _ in 0..5 {
            straight.iterate(&mut env).unwrap();
        }
        let tmp = tempfile::tempdir().unwrap();
        let mut first = SacAgent::new(config.clone(), 4, 2, 3).unwrap();
        let mut env = PointMass::new(4, 10);
        for _ in 0..3 {
            first.iterate(&mut env).unwrap();
        }
        // the ring has wrapped (120 transitions in 100 slots)
        assert_eq!(first.buffer.len(), 100);
        write_dir_atomically(&tmp.path().join("c"), &first.checkpoint_files().unwrap()).unwrap();
        drop(first);
        let expected = match config.variant {
            crate::sac::SacVariant::Sac => "sac",
            crate::sac::SacVariant::CrossQ => "crossq",
        };
        let loaded = crate::registry::load_checkpoint(&tmp.path().join("c")).unwrap();
        assert_eq!(loaded.name(), expected);
        let mut resumed = SacAgent::load(&tmp.path().join("c")).unwrap();
        assert_eq!(resumed.config, config);
        let mut env = PointMass::new(4, 10);
        for _ in 0..2 {
            resumed.iterate(&mut env).unwrap();
        }
        assert_eq!(
            resumed.checkpoint_files().unwrap(),
            straight.checkpoint_files().unwrap()
        );
    }

    #[test]
    fn resuming_from_a_checkpoint_equals_the_uninterrupted_run() {
        resume_equals_the_uninterrupted_run(config());
    }

    /// CrossQ's running statistics, its warm-up position and the delayed
    /// actor resume exactly too (the warm-up ends inside the run).
    #[test]
    fn resuming_crossq_equals_the_uninterrupted_run() {
        resume_equals_the_uninterrupted_run(SacConfig {
            critic_hidden_sizes: Some(vec![8]),
            renorm_warmup_updates: 30,
            ..SacConfig {
                variant: crate::sac::SacVariant::CrossQ,
                policy_delay: 3,
                adam_beta1: 0.5,
                ..config()
            }
        });
    }

    #[test]
    fn damaged_and_foreign_checkpoints_are_named() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("c");
        let mut agent = SacAgent::new(config(), 4, 2, 3).unwrap();
        agent.iterate(&mut PointMass::new(4, 10)).unwrap();
        write_dir_atomically(&dir, &agent.checkpoint_files().unwrap()).unwrap();
        let replay = dir.join(REPLAY_FILE);
        let bytes = std::fs::read(&replay).unwrap();
        std::fs::write(&replay, &bytes[..bytes.len() / 2]).unwrap();
        let err = SacAgent::load(&dir).err().unwrap().to_string();
        assert!(
            err.contains(REPLAY_FILE) && err.contains("checksum"),
            "{err}"
        );
        // a PPO checkpoint is not a SAC one
        let ppo = crate::Trainer::new(
            crate::PpoConfig {
                hidden_sizes: vec![4],
                ..crate::PpoConfig::default()
            },
            4,
            2,
            0,
        )
        .unwrap();
        let ppo_dir = tmp.path().join("ppo");
        write_dir_atomically(&ppo_dir, &ppo.checkpoint_files().unwrap()).unwrap();
        let loaded = crate::registry::load_checkpoint(&ppo_dir).unwrap();
        assert_eq!(loaded.name(), "ppo");
        let err = SacAgent::load(&ppo_dir).err().unwrap().to_string();
        assert!(err.contains(STATE_FILE), "{err}");
    }
}
