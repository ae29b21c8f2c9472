//! The PPO runner: one iteration = reset every environment, [collect]
//! `steps_per_env` steps from each, [advantages] (GAE), `epochs` passes of
//! minibatch [updates], statistics.
//!
//! Every iteration starts from fresh episodes (seeded by the run's seed and
//! the iteration number), so the whole state of a run between iterations is
//! the networks, the optimiser, the normaliser, the sampling RNG and the
//! iteration count: exactly what a checkpoint holds. Resuming from a
//! checkpoint therefore continues bit for bit as the uninterrupted run.
//! An episode still running when the iteration ends is cut there and
//! bootstrapped from the critic.
//!
//! [collect]: Trainer::collect
//! [advantages]: Trainer::advantages
//! [updates]: Trainer::update

use std::time::Instant;

use candle_core::{Tensor, Var};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::actor_critic::{ActorCritic, gaussian_entropy};
use super::buffer::RolloutBuffer;
use super::config::{PpoConfig, adapt_learning_rate};
use super::gae::{Gae, gae};
use super::loss::{Minibatch, ppo_loss};
use crate::LearnError;
use crate::algorithm::{Figure, IterationStats, check_sizes};
use crate::env::{StepResult, VecEnv};
use crate::episodes::{EpisodeCollector, EpisodeStats};
use crate::mirror::Mirror;
use crate::mlp::with_zero_rows;
use crate::normalizer::ObsNormalizer;
use crate::optim::{Adam, check_learning_rate, clip_grad_norm, gradients};
use crate::seeds::{RngState, derive_seed};

/// What one iteration collected.
struct Rollout {
    /// the samples, step-major
    buffer: RolloutBuffer,
    /// the raw observations after the last step (for the bootstrap values)
    last_raw_obs: Vec<f32>,
    /// with `mirror_augmentation`: every sample's mirror image
    mirrored: Option<MirroredSamples>,
    /// the episodes that ended and the rewards
    episodes: EpisodeStats,
    /// seconds stepping the environments
    env_secs: f64,
    /// seconds in the network while collecting
    inference_secs: f64,
}

/// The mirror images of a rollout's samples, in the buffer's order.
struct MirroredSamples {
    /// `T x N x O`: mirrored raw observations, normalised
    obs: Vec<f32>,
    /// `T x N x A`: mirrored sampled actions
    actions: Vec<f32>,
    /// `T x N`: their log-probabilities under the rollout's policy
    log_probs: Vec<f32>,
}

/// What one update did: means over its minibatch steps.
#[derive(Debug, Clone, PartialEq)]
pub struct PpoUpdate {
    /// clipped surrogate loss
    pub policy_loss: f64,
    /// value loss (MSE)
    pub value_loss: f64,
    /// policy entropy after the update
    pub entropy: f64,
    /// approximate KL
    pub approx_kl: f64,
    /// clip fraction
    pub clip_fraction: f64,
    /// `1 - Var(R - V) / Var(R)` of the critic before the update
    pub explained_variance: f64,
    /// gradient norm (actor, critic) before clipping
    pub grad_norm: (f64, f64),
    /// mean policy standard deviation after the update
    pub action_std: f64,
    /// epochs run (fewer than configured when the KL stop fired)
    pub epochs: usize,
    /// the learning rate at the end of the update (moves with
    /// `desired_kl`)
    pub learning_rate: f64,
}

impl PpoUpdate {
    /// The figures of [`IterationStats::figures`], named as
    /// `metrics.jsonl` writes them.
    fn figures(&self) -> Vec<(&'static str, Figure)> {
        vec![
            ("policy_loss", Figure::Value(self.policy_loss)),
            ("value_loss", Figure::Value(self.value_loss)),
            ("entropy", Figure::Value(self.entropy)),
            ("approx_kl", Figure::Value(self.approx_kl)),
            ("clip_fraction", Figure::Value(self.clip_fraction)),
            ("explained_variance", Figure::Value(self.explained_variance)),
            ("grad_norm_actor", Figure::Value(self.grad_norm.0)),
            ("grad_norm_critic", Figure::Value(self.grad_norm.1)),
            ("action_std", Figure::Value(self.action_std)),
            ("epochs", Figure::Count(self.epochs as u64)),
            ("learning_rate", Figure::Value(self.learning_rate)),
        ]
    }
}

/// PPO on a [`VecEnv`].
#[derive(Debug, Clone)]
pub struct Trainer {
    /// settings
    pub config: PpoConfig,
    /// actor and critic
    pub policy: ActorCritic,
    /// optimiser over all of the policy's parameters
    pub adam: Adam,
    /// observation statistics
    pub normalizer: ObsNormalizer,
    /// the run's seed (environment seeds derive from it)
    pub seed: u64,
    /// iterations completed
    pub iteration: u64,
    rng: ChaCha8Rng,
}

impl Trainer {
    /// Fresh networks for `obs_size` observations and `action_size` actions.
    pub fn new(
        config: PpoConfig,
        obs_size: usize,
        action_size: usize,
        seed: u64,
    ) -> Result<Self, LearnError> {
        Self::asymmetric(config, (obs_size, 0), action_size, seed)
    }

    /// Fresh networks whose critic also sees `privileged_size` values after
    /// the actor's `obs_size` ([`VecEnv::policy_observation_size`]); one
    /// normaliser covers both.
    pub fn asymmetric(
        config: PpoConfig,
        (obs_size, privileged_size): (usize, usize),
        action_size: usize,
        seed: u64,
    ) -> Result<Self, LearnError> {
        config.validate()?;
        check_sizes(obs_size, action_size)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let policy = ActorCritic::new(
            (obs_size, privileged_size),
            action_size,
            &config.hidden_sizes,
            config.init_log_std,
            &mut rng,
        )?
        .with_tanh(config.tanh);
        let adam = Adam::new(policy.named_vars(), config.learning_rate)?;
        let normalizer = ObsNormalizer::new(obs_size + privileged_size, config.obs_clip);
        Ok(Self {
            config,
            policy,
            adam,
            normalizer,
            seed,
            iteration: 0,
            rng,
        })
    }

    /// Reassembles a trainer from checkpoint parts (see `checkpoint`).
    pub(crate) fn from_parts(
        config: PpoConfig,
        policy: ActorCritic,
        adam: Adam,
        normalizer: ObsNormalizer,
        seed: u64,
        iteration: u64,
        rng: RngState,
    ) -> Self {
        Self {
            config,
            policy,
            adam,
            normalizer,
            seed,
            iteration,
            rng: rng.generator(),
        }
    }

    /// Gives the critic `privileged_size` privileged values after the
    /// observation, from the next iteration on (a curriculum stage that
    /// turns `privileged_critic` on): the new inputs' first-layer weights
    /// and their Adam moments start at zero, so the critic's values are
    /// unchanged until training moves them, and the normaliser counts the
    /// new values from 0 ([`ObsNormalizer::append`]). Nothing changes when
    /// the critic has them already; a critic cannot lose inputs.
    pub fn widen_critic(&mut self, privileged_size: usize) -> Result<(), LearnError> {
        let have = self.policy.privileged_size();
        if privileged_size == have {
            return Ok(());
        }
        if privileged_size < have {
            return Err(LearnError::Mismatch(format!(
                "the critic sees {have} privileged values; it cannot be cut to {privileged_size}"
            )));
        }
        let extra = privileged_size - have;
        let policy = self.policy.with_privileged(extra)?;
        self.grow_inputs(policy, extra, &["critic.0.weight"])
    }

    /// Gives the actor and the critic an observation of `obs_size` values,
    /// the present ones followed by new ones, from the next iteration on (a
    /// curriculum stage that turns on an observation block, such as the
    /// height scan): as [`Self::widen_critic`], the new inputs' weights and
    /// Adam moments start at zero, so every action and value is unchanged
    /// until training moves them, and the normaliser counts the new values
    /// from 0. Nothing changes at the present size; an observation cannot
    /// shrink, grow in front of a critic's privileged values, or grow twice
    /// (the normaliser keeps one count for appended values, so the networks'
    /// inputs grow once in a run, by this or by [`Self::widen_critic`]).
    pub fn widen_observation(&mut self, obs_size: usize) -> Result<(), LearnError> {
        let have = self.policy.obs_size();
        if obs_size == have {
            return Ok(());
        }
        if obs_size < have {
            return Err(LearnError::Mismatch(format!(
                "the policy sees {have} observation values; it cannot be cut to {obs_size}"
            )));
        }
        let extra = obs_size - have;
        let policy = self.policy.with_observation(extra)?;
        self.grow_inputs(policy, extra, &["actor.0.weight", "critic.0.weight"])
    }

    /// Takes `policy`, whose first layers named in `grown` have `extra`
    /// more input rows than the present policy's, with Adam moments of zero
    /// for the new rows and the normaliser's `extra` appended values.
    fn grow_inputs(
        &mut self,
        policy: ActorCritic,
        extra: usize,
        grown: &[&str],
    ) -> Result<(), LearnError> {
        if let Some(appended) = self.normalizer.appended {
            return Err(LearnError::Mismatch(format!(
                "the networks' inputs grew once already (from value {} on); they can grow only once in a run",
                appended.from
            )));
        }
        let mut adam = Adam::new(policy.named_vars(), self.adam.learning_rate)?;
        for (k, (name, var)) in adam.vars().to_vec().iter().enumerate() {
            let (m, v) = (&self.adam.m[k], &self.adam.v[k]);
            let rows = var.as_tensor().dims().first().copied().unwrap_or(0);
            let changed = rows != m.dims().first().copied().unwrap_or(0);
            if changed != grown.contains(&name.as_str()) {
                return Err(LearnError::Mismatch(format!(
                    "{name} {} shape when the inputs grew",
                    if changed { "changed" } else { "kept its" }
                )));
            }
            if changed {
                adam.m[k] = with_zero_rows(m, extra)?;
                adam.v[k] = with_zero_rows(v, extra)?;
            } else {
                adam.m[k] = m.clone();
                adam.v[k] = v.clone();
            }
        }
        adam.step = self.adam.step;
        adam.betas = self.adam.betas;
        adam.eps = self.adam.eps;
        self.normalizer.append(extra);
        self.policy = policy;
        self.adam = adam;
        Ok(())
    }

    /// Sets the learning rate from the next update on (the configured one
    /// too, so checkpoints carry it): a curriculum stage's own rate.
    pub fn set_learning_rate(&mut self, learning_rate: f64) -> Result<(), LearnError> {
        check_learning_rate(learning_rate)?;
        self.config.learning_rate = learning_rate;
        self.adam.learning_rate = learning_rate;
        Ok(())
    }

    /// The sampling RNG's position.
    pub fn rng_state(&self) -> RngState {
        RngState::of(&self.rng)
    }

    /// The environment seed of iteration `iteration` (0-based).
    pub fn env_seed(&self, iteration: u64) -> u64 {
        derive_seed(self.seed, iteration)
    }

    /// Raw observations `k x O` (the actor's, without privileged values)
    /// normalised.
    fn normalized_actor_obs(&self, raw_obs: &[f32]) -> Vec<f32> {
        let mut obs = raw_obs.to_vec();
        if self.policy.privileged_size() == 0 {
            self.normalizer.normalize(&mut obs);
        } else {
            self.normalizer
                .leading(self.policy.obs_size())
                .normalize(&mut obs);
        }
        obs
    }

    /// Deterministic actions for raw observations `k x O`: normalised, the
    /// policy mean, clipped to [-1, 1].
    pub fn act_deterministic(&self, raw_obs: &[f32]) -> Result<Vec<f32>, LearnError> {
        let obs = self.normalized_actor_obs(raw_obs);
        let mut actions = self.policy.mean_actions(&obs)?;
        actions.iter_mut().for_each(|a| *a = a.clamp(-1.0, 1.0));
        Ok(actions)
    }

    /// Sampled actions for raw observations `k x O`: normalised, a draw from
    /// the policy's Gaussian on `rng`, clipped to [-1, 1].
    pub fn act_stochastic(
        &self,
        raw_obs: &[f32],
        rng: &mut ChaCha8Rng,
    ) -> Result<Vec<f32>, LearnError> {
        let obs = self.normalized_actor_obs(raw_obs);
        let (mut actions, _) = self.policy.sample(&obs, rng)?;
        actions.iter_mut().for_each(|a| *a = a.clamp(-1.0, 1.0));
        Ok(actions)
    }

    /// Checks that `env` fits the networks.
    fn check_env(&self, env: &dyn VecEnv) -> Result<(), LearnError> {
        let (o, p) = (self.policy.obs_size(), self.policy.privileged_size());
        if env.observation_size() != o + p
            || env.policy_observation_size() != o
            || env.action_size() != self.policy.action_size()
        {
            let privileged = |total: usize, policy: usize| {
                if total == policy {
                    String::new()
                } else {
                    format!(" ({policy} for the policy)")
                }
            };
            return Err(LearnError::Mismatch(format!(
                "the environment has {} observations{} and {} actions, the policy {}{} and {}",
                env.observation_size(),
                privileged(env.observation_size(), env.policy_observation_size()),
                env.action_size(),
                o + p,
                privileged(o + p, o),
                self.policy.action_size()
            )));
        }
        if env.num_envs() == 0 {
            return Err(LearnError::Config("no environments".into()));
        }
        Ok(())
    }

    /// Runs one iteration: collect, advantages, update.
    pub fn iterate(&mut self, env: &mut dyn VecEnv) -> Result<IterationStats, LearnError> {
        self.check_env(env)?;
        let mirror = if self.config.mirror_augmentation {
            let mirror = env.mirror().map_err(|why| {
                LearnError::Config(format!("ppo.mirror_augmentation = true: {why}"))
            })?;
            Some(mirror)
        } else {
            None
        };
        let started = Instant::now();
        let rollout = self.collect(env, mirror.as_deref())?;
        let update_clock = Instant::now();
        let advantages = self.advantages(&rollout)?;
        let steps = rollout.buffer.rewards.len();
        let update = self.update(rollout.buffer, rollout.mirrored, advantages)?;
        let update_secs = update_clock.elapsed().as_secs_f64();
        self.iteration += 1;
        Ok(IterationStats {
            iteration: self.iteration,
            steps,
            episodes: rollout.episodes,
            env_secs: rollout.env_secs,
            secs: vec![
                ("inference", rollout.inference_secs),
                ("update", update_secs),
            ],
            steps_per_sec: steps as f64 / started.elapsed().as_secs_f64(),
            figures: update.figures(),
            headline: &[("kl", "approx_kl"), ("ev", "explained_variance")],
        })
    }

    /// Collects `steps_per_env` steps of every environment from fresh
    /// episodes, sampling from the policy; episodes cut by the
    /// environment's time limit are bootstrapped from the critic. With a
    /// `mirror`, also each sample's mirror image (the normaliser counts
    /// both).
    fn collect(
        &mut self,
        env: &mut dyn VecEnv,
        mirror: Option<&dyn Mirror>,
    ) -> Result<Rollout, LearnError> {
        let n = env.num_envs();
        let o = env.observation_size();
        let a = env.action_size();
        let steps = self.config.steps_per_env;
        let mut episodes =
            EpisodeCollector::new(n, env.reward_term_names(), env.episode_metric_names());
        let gamma = self.config.gamma;
        let mut env_secs = 0.0;
        let mut inference_secs = 0.0;
        let mut raw_obs = vec![0.0f32; n * o];
        let clock = Instant::now();
        env.reset_all(self.env_seed(self.iteration), &mut raw_obs);
        env_secs += clock.elapsed().as_secs_f64();
        let mut out = StepResult::new(env);

        let mut buffer = RolloutBuffer::new(n, o, a, steps);
        let mut mirrored = mirror.map(|_| MirroredSamples {
            obs: Vec::with_capacity(steps * n * o),
            actions: Vec::with_capacity(steps * n * a),
            log_probs: Vec::with_capacity(steps * n),
        });

        for _ in 0..steps {
            let clock = Instant::now();
            self.normalizer.update(&raw_obs);
            let mirrored_raw_obs = mirror.map(|m| {
                let mut rows = raw_obs.clone();
                rows.chunks_exact_mut(o)
                    .for_each(|row| m.mirror_observation(row));
                self.normalizer.update(&rows);
                rows
            });
            let mut obs = raw_obs.clone();
            self.normalizer.normalize(&mut obs);
            let (actions, log_probs) = self
                .policy
                .sample(&self.policy.actor_part(&obs), &mut self.rng)?;
            if let (Some(m), Some(samples), Some(mut mirrored_obs)) =
                (mirror, mirrored.as_mut(), mirrored_raw_obs)
            {
                self.normalizer.normalize(&mut mirrored_obs);
                let mut mirrored_actions = actions.clone();
                mirrored_actions
                    .chunks_exact_mut(a)
                    .for_each(|row| m.mirror_action(row));
                let log_probs = self
                    .policy
                    .log_probs(&self.policy.actor_part(&mirrored_obs), &mirrored_actions)?;
                samples.obs.extend(mirrored_obs);
                samples.actions.extend(mirrored_actions);
                samples.log_probs.extend(log_probs);
            }
            let values = self.policy.values(&obs)?;
            let clipped: Vec<f32> = actions.iter().map(|x| x.clamp(-1.0, 1.0)).collect();
            inference_secs += clock.elapsed().as_secs_f64();

            let clock = Instant::now();
            env.step(&clipped, &mut out);
            env_secs += clock.elapsed().as_secs_f64();

            // bootstrap episodes cut by the environment's time limit:
            // r_t + gamma V(final_obs)
            let mut rewards = out.rewards.clone();
            let cut: Vec<usize> = (0..n)
                .filter(|&i| out.truncated[i] && !out.terminated[i])
                .collect();
            if !cut.is_empty() {
                let clock = Instant::now();
                let mut final_obs: Vec<f32> = cut
                    .iter()
                    .flat_map(|&i| out.final_obs[i * o..(i + 1) * o].to_vec())
                    .collect();
                self.normalizer.normalize(&mut final_obs);
                let final_values = self.policy.values(&final_obs)?;
                for (&i, v) in cut.iter().zip(final_values) {
                    rewards[i] += (gamma * f64::from(v)) as f32;
                }
                inference_secs += clock.elapsed().as_secs_f64();
            }

            for i in 0..n {
                episodes.record(&out, i);
            }
            buffer.push(
                &obs,
                &actions,
                &log_probs,
                &values,
                &rewards,
                (0..n).map(|i| out.ended(i)),
            );
            raw_obs.copy_from_slice(&out.obs);
        }
        Ok(Rollout {
            buffer,
            mirrored,
            last_raw_obs: raw_obs,
            episodes: episodes.finish(steps * n),
            env_secs,
            inference_secs,
        })
    }

    /// GAE over the rollout, bootstrapped from the critic's values of the
    /// observations after the last step.
    fn advantages(&self, rollout: &Rollout) -> Result<Gae, LearnError> {
        let mut last_obs = rollout.last_raw_obs.clone();
        self.normalizer.normalize(&mut last_obs);
        let last_values = self.policy.values(&last_obs)?;
        let buffer = &rollout.buffer;
        Ok(gae(
            &buffer.rewards,
            &buffer.values,
            &buffer.ended,
            &last_values,
            self.config.gamma,
            self.config.gae_lambda,
        ))
    }

    /// `epochs` passes of shuffled minibatch steps on the clipped
    /// objective, the value loss and the entropy bonus (stopped early by
    /// `target_kl`; the rate moved by `desired_kl`). With `mirrored`
    /// samples each minibatch also holds the mirrors of its samples, with
    /// their advantages and returns.
    fn update(
        &mut self,
        buffer: RolloutBuffer,
        mirrored: Option<MirroredSamples>,
        g: Gae,
    ) -> Result<PpoUpdate, LearnError> {
        let explained_variance = explained_variance(&buffer.values, &g.returns);
        let o = self.policy.obs_size() + self.policy.privileged_size();
        let a = self.policy.action_size();
        let total = buffer.rewards.len();
        let device = self.policy.device().clone();
        // rows 0..total the samples, total..2 total their mirrors
        let (mut obs, mut actions, mut log_probs) = (buffer.obs, buffer.actions, buffer.log_probs);
        let mut returns = g.returns;
        let copies = if let Some(m) = mirrored {
            obs.extend(m.obs);
            actions.extend(m.actions);
            log_probs.extend(m.log_probs);
            returns.extend_from_within(..);
            2
        } else {
            1
        };
        let row_count = copies * total;
        let all_obs = Tensor::from_vec(obs, (row_count, o), &device)?;
        let all_actions = Tensor::from_vec(actions, (row_count, a), &device)?;
        let all_log_probs = Tensor::from_vec(log_probs, row_count, &device)?;
        let all_returns = Tensor::from_vec(returns, row_count, &device)?;
        let advantages = g.advantages;
        let minibatch = self.config.minibatch_size.min(total);
        let actor_vars = self.policy.actor_vars();
        let critic_vars = self.policy.critic_vars();
        let split = actor_vars.len();

        let mut sums = [0.0f64; 6]; // policy, value, kl, clip, actor grad, critic grad
        let mut updates = 0usize;
        let mut epochs_run = 0usize;
        'epochs: for _ in 0..self.config.epochs {
            epochs_run += 1;
            let order = self.permutation(total);
            for chunk in order.chunks(minibatch) {
                let rows: Vec<u32> = (0..copies as u32)
                    .flat_map(|copy| chunk.iter().map(move |&k| k + copy * total as u32))
                    .collect();
                let index = Tensor::from_vec(rows.clone(), rows.len(), &device)?;
                let mut adv: Vec<f32> = rows
                    .iter()
                    .map(|&k| advantages[k as usize % total])
                    .collect();
                if self.config.normalize_advantages {
                    normalize_in_place(&mut adv);
                }
                let batch = Minibatch {
                    obs: all_obs.index_select(&index, 0)?,
                    actions: all_actions.index_select(&index, 0)?,
                    old_log_probs: all_log_probs.index_select(&index, 0)?,
                    advantages: Tensor::from_vec(adv, rows.len(), &device)?,
                    returns: all_returns.index_select(&index, 0)?,
                };
                let loss = ppo_loss(&self.policy, &batch, &self.config)?;
                let grads = loss.total.backward()?;
                let mut actor_grads = gradients(&grads, &actor_vars)?;
                let mut critic_grads = gradients(&grads, &critic_vars)?;
                let actor_norm = clip_grad_norm(&mut actor_grads, self.config.max_grad_norm)?;
                let critic_norm = clip_grad_norm(&mut critic_grads, self.config.max_grad_norm)?;
                actor_grads.extend(critic_grads);
                debug_assert_eq!(actor_grads.len(), split + critic_vars.len());
                self.adam.apply(&actor_grads)?;
                for (sum, value) in sums.iter_mut().zip([
                    loss.policy_loss,
                    loss.value_loss,
                    loss.approx_kl,
                    loss.clip_fraction,
                    actor_norm,
                    critic_norm,
                ]) {
                    *sum += value;
                }
                updates += 1;
                if let Some(desired) = self.config.desired_kl {
                    self.adam.learning_rate =
                        adapt_learning_rate(self.adam.learning_rate, loss.approx_kl, desired);
                }
                if let Some(target) = self.config.target_kl
                    && loss.approx_kl > 1.5 * target
                {
                    break 'epochs;
                }
            }
        }

        let log_std: Vec<f32> = self.policy.log_std.as_tensor().to_vec1()?;
        let mean = |s: f64| s / updates.max(1) as f64;
        Ok(PpoUpdate {
            policy_loss: mean(sums[0]),
            value_loss: mean(sums[1]),
            entropy: f64::from(
                gaussian_entropy(self.policy.log_std.as_tensor())?.to_scalar::<f32>()?,
            ),
            approx_kl: mean(sums[2]),
            clip_fraction: mean(sums[3]),
            explained_variance,
            grad_norm: (mean(sums[4]), mean(sums[5])),
            action_std: log_std.iter().map(|s| f64::from(s.exp())).sum::<f64>()
                / log_std.len() as f64,
            epochs: epochs_run,
            learning_rate: self.adam.learning_rate,
        })
    }

    /// A uniformly random permutation of `0..n` (Fisher-Yates on the
    /// trainer's RNG).
    fn permutation(&mut self, n: usize) -> Vec<u32> {
        let mut order: Vec<u32> = (0..n as u32).collect();
        for i in (1..n).rev() {
            let j = self.rng.random_range(0..=i);
            order.swap(i, j);
        }
        order
    }

    /// All parameters, named as in checkpoints.
    pub fn named_vars(&self) -> Vec<(String, Var)> {
        self.policy.named_vars()
    }
}

/// Zero mean, unit variance (unchanged when the spread is ~0).
fn normalize_in_place(values: &mut [f32]) {
    let n = values.len() as f64;
    if values.len() < 2 {
        return;
    }
    let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let var = values
        .iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n;
    let std = var.sqrt() + 1e-8;
    for v in values.iter_mut() {
        *v = ((f64::from(*v) - mean) / std) as f32;
    }
}

/// `1 - Var(R - V) / Var(R)`; 0 when the returns do not vary.
pub fn explained_variance(values: &[f32], returns: &[f32]) -> f64 {
    let n = returns.len() as f64;
    let var = |xs: &mut dyn Iterator<Item = f64>| {
        let xs: Vec<f64> = xs.collect();
        let mean = xs.iter().sum::<f64>() / n;
        xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n
    };
    let var_returns = var(&mut returns.iter().map(|&r| f64::from(r)));
    if var_returns < 1e-12 {
        return 0.0;
    }
    let var_residual = var(&mut returns
        .iter()
        .zip(values)
        .map(|(&r, &v)| f64::from(r) - f64::from(v)));
    1.0 - var_residual / var_returns
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn explained_variance_of_perfect_and_useless_critics() {
        let returns = [1.0f32, 2.0, 3.0, 4.0];
        assert!((explained_variance(&returns, &returns) - 1.0).abs() < 1e-12);
        assert!(explained_variance(&[2.5; 4], &returns).abs() < 1e-12);
        assert_eq!(explained_variance(&[0.0; 3], &[1.0; 3]), 0.0);
    }

    #[test]
    fn desired_kl_moves_the_learning_rate_within_its_bounds() {
        let run = |desired_kl: Option<f64>| {
            let config = PpoConfig {
                hidden_sizes: vec![16],
                minibatch_size: 64,
                desired_kl,
                ..PpoConfig::default()
            };
            let mut env = crate::toy::PointMass::new(4, 16);
            let mut t = Trainer::new(config, env.observation_size(), env.action_size(), 3).unwrap();
            let stats = t.iterate(&mut env).unwrap();
            let rate = stats.figure("learning_rate").and_then(Figure::as_f64);
            assert_eq!(rate, Some(t.adam.learning_rate));
            t.adam.learning_rate
        };
        // 10 epochs x 1 minibatch of 64: ten adaptations
        assert_eq!(run(None), 2e-4); // fixed
        assert_eq!(run(Some(1e-12)), 1e-5); // every KL above 2 d: down to the floor
        assert_eq!(run(Some(1e3)), 1e-2); // every KL below d / 2: up to the ceiling
    }

    #[test]
    fn permutation_is_a_permutation() {
        let mut t = Trainer::new(
            PpoConfig {
                hidden_sizes: vec![4],
                ..PpoConfig::default()
            },
            3,
            2,
            1,
        )
        .unwrap();
        let mut p = t.permutation(100);
        assert_ne!(p, (0..100).collect::<Vec<u32>>());
        p.sort_unstable();
        assert_eq!(p, (0..100).collect::<Vec<u32>>());
    }
}
