//! A toy continuous-control task: a point mass on a plane steered to a
//! target. PPO must solve it inside this crate's tests, so that the learner
//! is known to work without any robot.
//!
//! Observation (4): position (x, y) and the offset to the target
//! (tx - x, ty - y). Action (2): a velocity in [-1, 1]^2; each step moves
//! the mass by `0.1 * action`. Reward: minus the distance to the target
//! after the move. Start and target are uniform in [-1, 1]^2; an episode is
//! truncated after `episode_steps` steps. Episode metric: the final distance.
//! [`PointMass::with_time_for_critic`] appends one privileged value, the
//! share of the episode gone, that only an asymmetric critic sees;
//! [`PointMass::with_time_observed`] the same value for both networks.
//! The task is symmetric about the x axis: [`PointMassMirror`] negates
//! every y.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::env::{StepResult, VecEnv};
use crate::mirror::Mirror;
use crate::seeds::derive_seed;

/// `N` point masses.
#[derive(Debug, Clone)]
pub struct PointMass {
    position: Vec<[f32; 2]>,
    target: Vec<[f32; 2]>,
    steps: Vec<usize>,
    rngs: Vec<ChaCha8Rng>,
    episode_steps: usize,
    time: TimeShown,
}

/// Who sees the share of the episode gone, a fifth observation value.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum TimeShown {
    Nobody,
    CriticOnly,
    Both,
}

impl PointMass {
    /// `num_envs` point masses with episodes of `episode_steps` steps.
    pub fn new(num_envs: usize, episode_steps: usize) -> Self {
        Self {
            position: vec![[0.0; 2]; num_envs],
            target: vec![[0.0; 2]; num_envs],
            steps: vec![0; num_envs],
            rngs: (0..num_envs)
                .map(|i| ChaCha8Rng::seed_from_u64(i as u64))
                .collect(),
            episode_steps,
            time: TimeShown::Nobody,
        }
    }

    /// As [`PointMass::new`], each observation row followed by the share of
    /// the episode gone, for the critic only
    /// ([`VecEnv::policy_observation_size`] is 4).
    pub fn with_time_for_critic(num_envs: usize, episode_steps: usize) -> Self {
        Self {
            time: TimeShown::CriticOnly,
            ..Self::new(num_envs, episode_steps)
        }
    }

    /// As [`PointMass::new`], each observation row followed by the share of
    /// the episode gone, for the policy and the critic.
    pub fn with_time_observed(num_envs: usize, episode_steps: usize) -> Self {
        Self {
            time: TimeShown::Both,
            ..Self::new(num_envs, episode_steps)
        }
    }

    fn start(&mut self, i: usize) {
        let rng = &mut self.rngs[i];
        self.position[i] = [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)];
        self.target[i] = [rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)];
        self.steps[i] = 0;
    }

    fn observe(&self, i: usize, obs: &mut [f32]) {
        let [x, y] = self.position[i];
        let [tx, ty] = self.target[i];
        obs[..4].copy_from_slice(&[x, y, tx - x, ty - y]);
        if self.time != TimeShown::Nobody {
            obs[4] = self.steps[i] as f32 / self.episode_steps as f32;
        }
    }

    fn distance(&self, i: usize) -> f32 {
        let [x, y] = self.position[i];
        let [tx, ty] = self.target[i];
        ((tx - x).powi(2) + (ty - y).powi(2)).sqrt()
    }
}

/// The point mass's mirror about the x axis: y, the target's y offset and
/// the action's y negated (the share of the episode kept).
#[derive(Debug, Clone, Copy)]
pub struct PointMassMirror;

impl Mirror for PointMassMirror {
    fn mirror_observation(&self, row: &mut [f32]) {
        row[1] = -row[1];
        row[3] = -row[3];
    }

    fn mirror_action(&self, row: &mut [f32]) {
        row[1] = -row[1];
    }
}

impl VecEnv for PointMass {
    fn mirror(&self) -> Result<std::sync::Arc<dyn Mirror>, String> {
        Ok(std::sync::Arc::new(PointMassMirror))
    }

    fn num_envs(&self) -> usize {
        self.position.len()
    }

    fn observation_size(&self) -> usize {
        4 + usize::from(self.time != TimeShown::Nobody)
    }

    fn policy_observation_size(&self) -> usize {
        4 + usize::from(self.time == TimeShown::Both)
    }

    fn action_size(&self) -> usize {
        2
    }

    fn reward_term_names(&self) -> Vec<String> {
        vec!["distance".into()]
    }

    fn episode_metric_names(&self) -> Vec<String> {
        vec!["final_distance".into()]
    }

    fn reset_all(&mut self, seed: u64, obs: &mut [f32]) {
        for i in 0..self.num_envs() {
            self.rngs[i] = ChaCha8Rng::seed_from_u64(derive_seed(seed, i as u64));
            self.start(i);
            let o = self.observation_size();
            self.observe(i, &mut obs[i * o..(i + 1) * o]);
        }
    }

    fn step(&mut self, actions: &[f32], out: &mut StepResult) {
        for i in 0..self.num_envs() {
            let (ax, ay) = (
                actions[2 * i].clamp(-1.0, 1.0),
                actions[2 * i + 1].clamp(-1.0, 1.0),
            );
            self.position[i][0] += 0.1 * ax;
            self.position[i][1] += 0.1 * ay;
            self.steps[i] += 1;
            let distance = self.distance(i);
            out.rewards[i] = -distance;
            out.reward_terms[i] = -distance;
            out.terminated[i] = false;
            out.truncated[i] = self.steps[i] >= self.episode_steps;
            let o = self.observation_size();
            let row = i * o..(i + 1) * o;
            if out.truncated[i] {
                self.observe(i, &mut out.final_obs[row.clone()]);
                out.episode_metrics[i] = distance;
                self.start(i);
            }
            self.observe(i, &mut out.obs[row]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::gradients;
    use crate::ppo::PpoConfig;
    use crate::ppo::Trainer;
    use candle_core::Tensor;

    fn toy_config() -> PpoConfig {
        PpoConfig {
            hidden_sizes: vec![32, 32],
            learning_rate: 3e-3,
            gamma: 0.95,
            steps_per_env: 50,
            minibatch_size: 200,
            epochs: 5,
            ..PpoConfig::default()
        }
    }

    /// Random actions (the untrained policy) return about -20 per 25-step
    /// episode; heading straight for the target returns about -5. PPO must
    /// pass -10 within 40 iterations (32,000 steps, a few seconds of CPU).
    #[test]
    fn ppo_learns_to_steer_the_point_mass() {
        let mut env = PointMass::new(16, 25);
        let mut trainer = Trainer::new(toy_config(), 4, 2, 5).unwrap();
        let first = trainer
            .iterate(&mut env)
            .unwrap()
            .episodes
            .mean_return
            .unwrap();
        let mut best = f64::NEG_INFINITY;
        let mut history = vec![first];
        for _ in 1..40 {
            let stats = trainer.iterate(&mut env).unwrap();
            let r = stats.episodes.mean_return.unwrap();
            history.push(r);
            best = best.max(r);
            if r > -10.0 {
                break;
            }
        }
        assert!(
            first < -14.0,
            "the untrained policy should do poorly: {first}"
        );
        assert!(
            best > -10.0,
            "PPO did not learn the point mass: returns {history:?}"
        );
        // the deterministic policy now heads for the target
        let obs = [0.0f32, 0.0, 0.5, -0.5];
        let a = trainer.act_deterministic(&obs).unwrap();
        assert!(
            a[0] > 0.3 && a[1] < -0.3,
            "action {a:?} does not point at (0.5, -0.5)"
        );
    }

    /// With every sample also learned as its mirror image the point mass
    /// is learned, each minibatch step sees twice the rows (as many steps),
    /// the normaliser counts both, and the run is deterministic.
    #[test]
    fn ppo_with_mirror_augmentation_learns_the_point_mass() {
        let run = |iterations: usize| {
            let config = PpoConfig {
                mirror_augmentation: true,
                ..toy_config()
            };
            let mut env = PointMass::new(16, 25);
            let mut trainer = Trainer::new(config, 4, 2, 5).unwrap();
            let returns: Vec<f64> = (0..iterations)
                .map(|_| {
                    let stats = trainer.iterate(&mut env).unwrap();
                    stats.episodes.mean_return.unwrap()
                })
                .collect();
            (returns, trainer)
        };
        let (returns, trainer) = run(60);
        let best = returns.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        assert!(best > -10.0, "PPO with mirrors did not learn: {returns:?}");
        // 800 samples a batch, minibatch 200 (+ their 200 mirrors), 5 epochs
        assert_eq!(trainer.adam.step, 60 * 4 * 5);
        assert_eq!(trainer.normalizer.count, 2.0 * 60.0 * 800.0);
        // the mirror images make the y statistics symmetric
        assert!(trainer.normalizer.mean[1].abs() < 1e-9);
        assert!(trainer.normalizer.mean[3].abs() < 1e-9);
        assert_eq!(run(3).0, run(3).0);
    }

    #[test]
    fn after_many_updates_no_state_holds_an_op_graph() {
        // 8 envs x 16 steps = 128 samples, minibatch 32, 5 epochs: 20 Adam
        // steps per iteration, 200 in all.
        let mut env = PointMass::new(8, 16);
        let mut t = Trainer::new(
            PpoConfig {
                hidden_sizes: vec![32, 16],
                steps_per_env: 16,
                minibatch_size: 32,
                epochs: 5,
                ..PpoConfig::default()
            },
            4,
            2,
            5,
        )
        .unwrap();
        for _ in 0..10 {
            t.iterate(&mut env).unwrap();
        }
        assert_eq!(t.adam.step, 200);
        // Adam's moments are plain values: no op, not a variable. (A moment
        // that tracked its op would keep every earlier step's graph alive.)
        for (k, (m, v)) in t.adam.m.iter().zip(&t.adam.v).enumerate() {
            assert!(!m.track_op(), "first moment {k} holds an op graph");
            assert!(!v.track_op(), "second moment {k} holds an op graph");
        }
        // The parameters are still the trainer's own vars (updated in
        // place, never replaced by a tensor derived from them).
        for ((name, a), (_, b)) in t.policy.named_vars().iter().zip(t.adam.vars()) {
            assert!(a.as_tensor().is_variable(), "{name} is no longer a var");
            assert_eq!(a.as_tensor().id(), b.as_tensor().id(), "{name}");
        }
        // The gradients handed to Adam are detached.
        let obs = Tensor::zeros((3, 4), candle_core::DType::F32, t.policy.device()).unwrap();
        let loss = t.policy.critic.forward(&obs).unwrap().sum_all().unwrap();
        let grads = loss.backward().unwrap();
        for g in gradients(&grads, &t.policy.critic_vars()).unwrap() {
            assert!(!g.track_op());
        }
    }

    #[test]
    fn same_seed_same_training() {
        let run = || {
            let mut env = PointMass::new(4, 10);
            let mut t = Trainer::new(
                PpoConfig {
                    hidden_sizes: vec![8],
                    steps_per_env: 20,
                    minibatch_size: 32,
                    epochs: 2,
                    ..PpoConfig::default()
                },
                4,
                2,
                3,
            )
            .unwrap();
            let stats: Vec<_> = (0..3)
                .map(|_| t.iterate(&mut env).unwrap().figure("policy_loss"))
                .collect();
            (stats, t.checkpoint_files().unwrap())
        };
        assert_eq!(run(), run());
    }

    #[test]
    fn resuming_from_a_checkpoint_equals_the_uninterrupted_run() {
        let config = PpoConfig {
            hidden_sizes: vec![8],
            steps_per_env: 20,
            minibatch_size: 32,
            epochs: 2,
            ..PpoConfig::default()
        };
        let mut env = PointMass::new(4, 10);
        let mut straight = Trainer::new(config.clone(), 4, 2, 3).unwrap();
        for _ in 0..4 {
            straight.iterate(&mut env).unwrap();
        }
        let tmp = tempfile::tempdir().unwrap();
        let mut first = Trainer::new(config, 4, 2, 3).unwrap();
        let mut env = PointMass::new(4, 10);
        for _ in 0..2 {
            first.iterate(&mut env).unwrap();
        }
        crate::checkpoint::write_dir_atomically(
            &tmp.path().join("c"),
            &first.checkpoint_files().unwrap(),
        )
        .unwrap();
        drop(first);
        let mut resumed = Trainer::load(&tmp.path().join("c")).unwrap();
        let mut env = PointMass::new(4, 10);
        for _ in 0..2 {
            resumed.iterate(&mut env).unwrap();
        }
        assert_eq!(
            resumed.checkpoint_files().unwrap(),
            straight.checkpoint_files().unwrap()
        );
    }

    /// An asymmetric critic: the critic sees the privileged value, the
    /// actor and every exported or acting path only the first 4; it learns,
    /// resumes bit for bit, and its export acts as it does.
    /// The ONNX actor graph computes the learner's deterministic action
    /// (its reference evaluation, within float rounding): PPO with an
    /// asymmetric critic (the actor alone, the normaliser's leading part)
    /// and SAC (the mean head, squashed), both after some training so the
    /// normaliser and weights are not their initial values.
    #[test]
    fn the_actor_graph_acts_as_the_learner_does() {
        use crate::algorithm::Algorithm;
        use crate::sac::{SacAgent, SacConfig};
        let mut ppo = Trainer::asymmetric(toy_config(), (4, 1), 2, 5).unwrap();
        let mut env = PointMass::with_time_for_critic(16, 25);
        for _ in 0..5 {
            ppo.iterate(&mut env).unwrap();
        }
        let mut sac = SacAgent::new(
            SacConfig {
                hidden_sizes: vec![32, 32],
                learning_starts: 200,
                steps_per_env: 25,
                ..SacConfig::default()
            },
            4,
            2,
            5,
        )
        .unwrap();
        let mut env = PointMass::new(16, 25);
        for _ in 0..3 {
            sac.iterate(&mut env).unwrap();
        }
        // a grid of observations, some far outside what training saw
        let obs: Vec<f32> = (0..200)
            .flat_map(|k| {
                let t = k as f32 * 0.37;
                [t.sin() * 2.0, t.cos(), (t * 0.5).sin() * 40.0, -t * 0.1]
            })
            .collect();
        for learner in [&ppo as &dyn Algorithm, &sac] {
            let graph = learner.actor_graph().unwrap();
            assert_eq!((graph.obs_size(), graph.action_size()), (4, 2));
            let expected = learner.act_deterministic(&obs).unwrap();
            let got = graph.act(&obs);
            let worst = expected
                .iter()
                .zip(&got)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max);
            assert!(worst < 1e-6, "{}: {worst}", learner.name());
            assert!(expected.iter().any(|a| a.abs() > 0.05), "{expected:?}");
        }
    }

    #[test]
    fn an_asymmetric_critic_learns_resumes_and_exports_the_actor_alone() {
        use crate::algorithm::Algorithm;
        use crate::checkpoint::write_dir_atomically;
        let make = || Trainer::asymmetric(toy_config(), (4, 1), 2, 5).unwrap();
        let mut straight = make();
        assert_eq!(
            straight.policy.critic.layers[0].weight.as_tensor().dims(),
            [5, 32]
        );
        assert_eq!(
            straight.policy.actor.layers[0].weight.as_tensor().dims(),
            [4, 32]
        );
        let mut env = PointMass::with_time_for_critic(16, 25);
        let returns: Vec<f64> = (0..30)
            .map(|_| {
                straight
                    .iterate(&mut env)
                    .unwrap()
                    .episodes
                    .mean_return
                    .unwrap()
            })
            .collect();
        assert!(
            returns[25..].iter().sum::<f64>() / 5.0 > returns[..5].iter().sum::<f64>() / 5.0 + 3.0,
            "{returns:?}"
        );
        // resume from iteration 28 equals the straight run at 30
        let tmp = tempfile::tempdir().unwrap();
        let mut first = make();
        let mut env = PointMass::with_time_for_critic(16, 25);
        for _ in 0..28 {
            first.iterate(&mut env).unwrap();
        }
        write_dir_atomically(&tmp.path().join("c"), &first.checkpoint_files().unwrap()).unwrap();
        let mut resumed = Trainer::load(&tmp.path().join("c")).unwrap();
        for _ in 0..2 {
            resumed.iterate(&mut env).unwrap();
        }
        assert_eq!(
            resumed.checkpoint_files().unwrap(),
            straight.checkpoint_files().unwrap()
        );
        // acting takes the actor's 4 values; the export acts the same
        let obs = [0.1f32, -0.2, 0.5, -0.5];
        let action = straight.act_deterministic(&obs).unwrap();
        write_dir_atomically(&tmp.path().join("p"), &straight.policy_files().unwrap()).unwrap();
        let exported = crate::registry::load_for_acting(&tmp.path().join("p")).unwrap();
        assert_eq!(exported.obs_size(), 4);
        assert_eq!(exported.act_deterministic(&obs).unwrap(), action);
        // an environment without the privileged value does not fit
        let err = straight
            .iterate(&mut PointMass::new(2, 5))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("4 observations") && err.contains("5 (4 for the policy)"),
            "{err}"
        );
    }

    /// A critic given the privileged value mid-run (a curriculum stage that
    /// turns it on): the actor acts as before, the critic learns weights
    /// for the new input, the normaliser counts it from its first batch,
    /// and a checkpoint after the widening resumes bit for bit.
    #[test]
    fn a_critic_widened_mid_run_learns_the_new_value_and_resumes() {
        use crate::checkpoint::write_dir_atomically;
        let make = || {
            let mut t = Trainer::new(toy_config(), 4, 2, 5).unwrap();
            let mut env = PointMass::new(16, 25);
            for _ in 0..5 {
                t.iterate(&mut env).unwrap();
            }
            let obs = [0.1f32, -0.2, 0.5, -0.5];
            let before = t.act_deterministic(&obs).unwrap();
            t.widen_critic(1).unwrap();
            assert_eq!(t.act_deterministic(&obs).unwrap(), before);
            assert_eq!((t.policy.obs_size(), t.policy.privileged_size()), (4, 1));
            t
        };
        let mut straight = make();
        let seen_before = straight.normalizer.count;
        let mut env = PointMass::with_time_for_critic(16, 25);
        for _ in 0..6 {
            straight.iterate(&mut env).unwrap();
        }
        let appended = straight.normalizer.appended.unwrap();
        assert_eq!(appended.from, 4);
        assert_eq!(appended.count, (6 * 16 * 50) as f64);
        assert_eq!(straight.normalizer.count, seen_before + appended.count);
        // the time left (0..1 over an episode) has its own spread, not one
        // diluted by the observations seen before it existed
        assert!(
            (straight.normalizer.var[4] - 1.0 / 12.0).abs() < 0.02,
            "{}",
            straight.normalizer.var[4]
        );
        let new_row: Vec<f32> = straight.policy.critic.layers[0]
            .weight
            .as_tensor()
            .get(4)
            .unwrap()
            .to_vec1()
            .unwrap();
        assert!(new_row.iter().any(|w| w.abs() > 1e-4), "{new_row:?}");
        // widening again to the same size changes nothing; narrowing is refused
        straight.widen_critic(1).unwrap();
        let err = straight.widen_critic(0).unwrap_err().to_string();
        assert!(err.contains("cannot be cut"), "{err}");
        // resume after the widening equals the straight run
        let tmp = tempfile::tempdir().unwrap();
        let mut first = make();
        let mut env = PointMass::with_time_for_critic(16, 25);
        for _ in 0..4 {
            first.iterate(&mut env).unwrap();
        }
        write_dir_atomically(&tmp.path().join("c"), &first.checkpoint_files().unwrap()).unwrap();
        let mut resumed = Trainer::load(&tmp.path().join("c")).unwrap();
        assert_eq!(resumed.normalizer, first.normalizer);
        for _ in 0..2 {
            resumed.iterate(&mut env).unwrap();
        }
        assert_eq!(
            resumed.checkpoint_files().unwrap(),
            straight.checkpoint_files().unwrap()
        );
    }

    /// An observation grown mid-run (a curriculum stage that turns the
    /// height scan on): both networks act and value as before, the actor
    /// learns weights for the new input, and it cannot grow again, shrink,
    /// or grow in front of a critic's privileged values.
    #[test]
    fn an_observation_grown_mid_run_keeps_the_policy_and_learns_the_new_value() {
        let mut t = Trainer::new(toy_config(), 4, 2, 5).unwrap();
        let mut env = PointMass::new(16, 25);
        for _ in 0..5 {
            t.iterate(&mut env).unwrap();
        }
        let obs = [0.1f32, -0.2, 0.5, -0.5];
        let before = t.act_deterministic(&obs).unwrap();
        let normalized = |n: &crate::normalizer::ObsNormalizer, row: &[f32]| {
            let mut row = row.to_vec();
            n.normalize(&mut row);
            row
        };
        let value_before = t.policy.values(&normalized(&t.normalizer, &obs)).unwrap();
        t.widen_observation(5).unwrap();
        assert_eq!(t.policy.obs_size(), 5);
        for time in [0.0f32, 0.5, 1.0] {
            let grown = [obs[0], obs[1], obs[2], obs[3], time];
            assert_eq!(t.act_deterministic(&grown).unwrap(), before);
            let value = t.policy.values(&normalized(&t.normalizer, &grown)).unwrap();
            assert_eq!(value, value_before);
        }
        let mut env = PointMass::with_time_observed(16, 25);
        for _ in 0..6 {
            t.iterate(&mut env).unwrap();
        }
        assert_eq!(t.normalizer.appended.unwrap().from, 4);
        let new_row: Vec<f32> = t.policy.actor.layers[0]
            .weight
            .as_tensor()
            .get(4)
            .unwrap()
            .to_vec1()
            .unwrap();
        assert!(new_row.iter().any(|w| w.abs() > 1e-4), "{new_row:?}");
        t.widen_observation(5).unwrap();
        let err = t.widen_observation(4).unwrap_err().to_string();
        assert!(err.contains("cannot be cut"), "{err}");
        let err = t.widen_observation(6).unwrap_err().to_string();
        assert!(err.contains("grow only once"), "{err}");
        let mut asymmetric = Trainer::new(toy_config(), 4, 2, 5).unwrap();
        asymmetric.widen_critic(1).unwrap();
        let err = asymmetric.widen_observation(5).unwrap_err().to_string();
        assert!(err.contains("privileged values"), "{err}");
    }

    #[test]
    fn a_mismatched_environment_is_refused() {
        let mut t = Trainer::new(
            PpoConfig {
                hidden_sizes: vec![4],
                ..PpoConfig::default()
            },
            5,
            2,
            0,
        )
        .unwrap();
        let err = t
            .iterate(&mut PointMass::new(2, 5))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("4 observations") && err.contains("policy 5"),
            "{err}"
        );
    }
}
