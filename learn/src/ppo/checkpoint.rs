//! PPO's checkpoint (the layout of [`crate::checkpoint`]): `weights.safetensors`
//! holds the policy (`actor.K.weight/bias`, `log_std`,
//! `critic.K.weight/bias`), the normaliser and Adam's moments
//! (`adam.m.NAME`, `adam.v.NAME`); `state.toml` the Adam step, the
//! normaliser count, the sampling RNG's position, the learning rate where
//! `desired_kl` moves it, and `[ppo]`. Its state file names no `algo`.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::config::PpoConfig;
use super::trainer::Trainer;
use crate::LearnError;
use crate::checkpoint::{
    FORMAT_VERSION, STATE_FILE, TensorFile, WEIGHTS_FILE, adam_tensors, bad_file, fnv1a64,
    normalizer_tensors, read_checksummed, read_state, resolve_checkpoint, rng_fields,
    rng_from_fields, state_text, tensors_file, var_tensors,
};
use crate::normalizer::Appended;
use crate::optim::Adam;

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct StateFile {
    format: u32,
    iteration: u64,
    seed: u64,
    obs_size: usize,
    /// values only the critic sees, after the actor's `obs_size` (absent:
    /// none)
    #[serde(default, skip_serializing_if = "is_zero")]
    privileged_size: usize,
    action_size: usize,
    adam_step: u64,
    normalizer_count: f64,
    /// where the values appended to the critic's input mid-run begin in the
    /// normaliser, and its count of them (absent: none appended)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    normalizer_appended_from: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    normalizer_appended_count: Option<f64>,
    rng_seed_hex: String,
    rng_stream: u64,
    rng_word_pos: String,
    weights_fnv1a64: String,
    /// the learning rate now, where `ppo.desired_kl` moves it (absent in
    /// checkpoints written before it could move)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    learning_rate_now: Option<f64>,
    ppo: PpoConfig,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

impl Trainer {
    /// The checkpoint's files (name, bytes), ready for [`write_dir_atomically`].
    pub fn checkpoint_files(&self) -> Result<Vec<(String, Vec<u8>)>, LearnError> {
        let mut tensors = var_tensors(self.policy.named_vars());
        tensors.extend(normalizer_tensors(&self.normalizer)?);
        tensors.extend(adam_tensors(&self.adam, "adam"));
        let weights = tensors_file(tensors)?;
        let (rng_seed_hex, rng_stream, rng_word_pos) = rng_fields(&self.rng_state());
        let state = StateFile {
            format: FORMAT_VERSION,
            iteration: self.iteration,
            seed: self.seed,
            obs_size: self.policy.obs_size(),
            privileged_size: self.policy.privileged_size(),
            action_size: self.policy.action_size(),
            adam_step: self.adam.step,
            normalizer_count: self.normalizer.count,
            normalizer_appended_from: self.normalizer.appended.map(|a| a.from),
            normalizer_appended_count: self.normalizer.appended.map(|a| a.count),
            rng_seed_hex,
            rng_stream,
            rng_word_pos,
            weights_fnv1a64: format!("{:016x}", fnv1a64(&weights)),
            learning_rate_now: self
                .config
                .desired_kl
                .is_some()
                .then_some(self.adam.learning_rate),
            ppo: self.config.clone(),
        };
        Ok(vec![
            (WEIGHTS_FILE.into(), weights),
            (STATE_FILE.into(), state_text(&state)?),
        ])
    }

    /// Loads the checkpoint in `dir` (a checkpoint directory, or a run
    /// directory or link whose `latest` names one).
    pub fn load(dir: &Path) -> Result<Self, LearnError> {
        let dir = resolve_checkpoint(dir)?;
        let state: StateFile = read_state(&dir)?;
        if state.format != FORMAT_VERSION {
            return Err(bad_file(
                &dir,
                STATE_FILE,
                format!(
                    "format {} is not the supported {FORMAT_VERSION}",
                    state.format
                ),
            ));
        }
        state
            .ppo
            .validate()
            .map_err(|e| bad_file(&dir, STATE_FILE, e.to_string()))?;
        let weights = read_checksummed(&dir, WEIGHTS_FILE, STATE_FILE, &state.weights_fnv1a64)?;
        let file = TensorFile::parse(&weights, &dir, WEIGHTS_FILE)?;
        let rng = rng_from_fields(
            &dir,
            &state.rng_seed_hex,
            state.rng_stream,
            &state.rng_word_pos,
        )?;
        // fresh networks of the recorded shape, then every value replaced
        let trainer = Trainer::asymmetric(
            state.ppo.clone(),
            (state.obs_size, state.privileged_size),
            state.action_size,
            state.seed,
        )?;
        file.load_vars(&trainer.policy.named_vars())?;
        let normalizer = file.load_normalizer(
            state.obs_size + state.privileged_size,
            state.normalizer_count,
            state.ppo.obs_clip,
        )?;
        let normalizer = match (
            state.normalizer_appended_from,
            state.normalizer_appended_count,
        ) {
            (None, None) => normalizer,
            (Some(from), Some(count)) => normalizer
                .with_appended(Appended { from, count })
                .map_err(|e| bad_file(&dir, STATE_FILE, e.to_string()))?,
            _ => {
                return Err(bad_file(
                    &dir,
                    STATE_FILE,
                    "normalizer_appended_from and normalizer_appended_count come together".into(),
                ));
            }
        };
        let learning_rate = match (state.ppo.desired_kl, state.learning_rate_now) {
            (Some(_), Some(lr)) if lr.is_finite() && lr > 0.0 => lr,
            (Some(_), Some(lr)) => {
                return Err(bad_file(
                    &dir,
                    STATE_FILE,
                    format!("learning_rate_now = {lr}: must be finite and > 0"),
                ));
            }
            _ => state.ppo.learning_rate,
        };
        let mut adam = Adam::new(trainer.policy.named_vars(), learning_rate)?;
        file.load_adam(&mut adam, "adam", state.adam_step)?;
        Ok(Trainer::from_parts(
            state.ppo,
            trainer.policy,
            adam,
            normalizer,
            state.seed,
            state.iteration,
            rng,
        ))
    }
}

#[cfg(test)]
mod tests {
    use std::fs;

    use super::*;
    use crate::checkpoint::{point_latest, remove_partial_saves, write_dir_atomically};
    use crate::tanh::TanhImpl;

    fn trainer() -> Trainer {
        let config = PpoConfig {
            hidden_sizes: vec![8, 4],
            ..PpoConfig::default()
        };
        let mut t = Trainer::new(config, 5, 2, 11).unwrap();
        t.normalizer
            .update(&[1.0, 2.0, 3.0, 4.0, 5.0, 0.0, 0.0, 1.0, 1.0, 2.0]);
        t.adam.step = 7;
        t.iteration = 3;
        t
    }

    fn save(t: &Trainer, dir: &Path) {
        write_dir_atomically(dir, &t.checkpoint_files().unwrap()).unwrap();
    }

    #[test]
    fn the_adaptive_learning_rate_survives_a_resume() {
        let tmp = tempfile::tempdir().unwrap();
        let mut t = trainer();
        t.config.desired_kl = Some(0.01);
        t.adam.learning_rate = 4.5e-4; // where the schedule has moved it
        save(&t, &tmp.path().join("iter-3"));
        let text = fs::read_to_string(tmp.path().join("iter-3").join(STATE_FILE)).unwrap();
        assert!(text.contains("learning_rate_now = 0.00045"), "{text}");
        let back = Trainer::load(&tmp.path().join("iter-3")).unwrap();
        assert_eq!(back.adam.learning_rate, 4.5e-4);
        assert_eq!(back.config.learning_rate, 2e-4); // the configured start
        // a fixed rate writes no learning_rate_now and loads the configured one
        let fixed = trainer();
        save(&fixed, &tmp.path().join("iter-4"));
        let text = fs::read_to_string(tmp.path().join("iter-4").join(STATE_FILE)).unwrap();
        assert!(!text.contains("learning_rate_now"), "{text}");
        assert_eq!(
            Trainer::load(&tmp.path().join("iter-4"))
                .unwrap()
                .adam
                .learning_rate,
            2e-4
        );
    }

    #[test]
    fn the_polynomial_tanh_survives_a_resume_and_the_default_is_not_written() {
        let tmp = tempfile::tempdir().unwrap();
        let libm = trainer();
        save(&libm, &tmp.path().join("libm"));
        let text = fs::read_to_string(tmp.path().join("libm").join(STATE_FILE)).unwrap();
        assert!(!text.contains("tanh"), "{text}");
        let mut t = trainer();
        t.config.tanh = TanhImpl::Polynomial;
        t.policy = t.policy.clone().with_tanh(TanhImpl::Polynomial);
        save(&t, &tmp.path().join("poly"));
        let text = fs::read_to_string(tmp.path().join("poly").join(STATE_FILE)).unwrap();
        assert!(text.contains("tanh = \"polynomial\""), "{text}");
        let back = Trainer::load(&tmp.path().join("poly")).unwrap();
        assert_eq!(back.config.tanh, TanhImpl::Polynomial);
        assert_eq!(back.policy.actor.tanh, TanhImpl::Polynomial);
        assert_eq!(back.policy.critic.tanh, TanhImpl::Polynomial);
        let obs = [0.3, -1.2, 0.7, 2.0, -0.4];
        assert_eq!(
            back.act_deterministic(&obs).unwrap(),
            t.act_deterministic(&obs).unwrap()
        );
    }

    #[test]
    fn save_then_load_restores_everything() {
        let tmp = tempfile::tempdir().unwrap();
        let t = trainer();
        save(&t, &tmp.path().join("iter-3"));
        point_latest(tmp.path(), Path::new("iter-3")).unwrap();
        let back = Trainer::load(tmp.path()).unwrap();
        assert_eq!(back.iteration, 3);
        assert_eq!(back.adam.step, 7);
        assert_eq!(back.normalizer, t.normalizer);
        assert_eq!(back.rng_state(), t.rng_state());
        assert_eq!(back.config, t.config);
        for ((na, a), (nb, b)) in t.named_vars().iter().zip(back.named_vars().iter()) {
            assert_eq!(na, nb);
            let x: Vec<f32> = a.as_tensor().flatten_all().unwrap().to_vec1().unwrap();
            let y: Vec<f32> = b.as_tensor().flatten_all().unwrap().to_vec1().unwrap();
            assert_eq!(x, y, "{na}");
        }
        // saving the loaded trainer gives the same bytes
        assert_eq!(
            back.checkpoint_files().unwrap(),
            t.checkpoint_files().unwrap()
        );
    }

    #[test]
    fn truncated_or_corrupt_weights_are_named() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("c");
        save(&trainer(), &dir);
        let path = dir.join(WEIGHTS_FILE);
        let bytes = fs::read(&path).unwrap();
        fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        let err = Trainer::load(&dir).unwrap_err().to_string();
        assert!(
            err.contains(WEIGHTS_FILE) && err.contains("damaged or truncated"),
            "{err}"
        );
        let mut flipped = bytes.clone();
        let k = flipped.len() - 10;
        flipped[k] ^= 0x40;
        fs::write(&path, &flipped).unwrap();
        let err = Trainer::load(&dir).unwrap_err().to_string();
        assert!(err.contains("checksum"), "{err}");
    }

    #[test]
    fn bad_state_files_are_named() {
        let tmp = tempfile::tempdir().unwrap();
        let dir = tmp.path().join("c");
        save(&trainer(), &dir);
        let state = dir.join(STATE_FILE);
        let text = fs::read_to_string(&state).unwrap();
        fs::write(&state, &text[..text.len() / 3]).unwrap();
        let err = Trainer::load(&dir).unwrap_err().to_string();
        assert!(
            err.contains(STATE_FILE) && err.contains("not a valid state file"),
            "{err}"
        );
        // a state whose sizes do not match the weights: the tensor is named
        let wrong = text.replace("obs_size = 5", "obs_size = 6");
        fs::write(&state, wrong).unwrap();
        let err = Trainer::load(&dir).unwrap_err().to_string();
        assert!(
            err.contains("actor.0.weight") && err.contains("shape"),
            "{err}"
        );
    }

    #[test]
    fn missing_paths_and_non_checkpoints_are_named() {
        let tmp = tempfile::tempdir().unwrap();
        let err = Trainer::load(&tmp.path().join("nope"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("nope") && err.contains("no such"), "{err}");
        let err = Trainer::load(tmp.path()).unwrap_err().to_string();
        assert!(err.contains("not a checkpoint"), "{err}");
    }

    #[test]
    fn a_stray_partial_save_is_ignored_and_cleaned() {
        let tmp = tempfile::tempdir().unwrap();
        save(&trainer(), &tmp.path().join("iter-3"));
        point_latest(tmp.path(), Path::new("iter-3")).unwrap();
        let stray = tmp.path().join(".iter-4.partial-999");
        fs::create_dir(&stray).unwrap();
        fs::write(stray.join(WEIGHTS_FILE), b"half").unwrap();
        assert_eq!(Trainer::load(tmp.path()).unwrap().iteration, 3);
        remove_partial_saves(tmp.path());
        assert!(!stray.exists());
        assert!(tmp.path().join("iter-3").exists());
    }
}
