//! The environment interface PPO trains on: `N` environments stepped together
//! over flat `f32` buffers.
//!
//! Shapes (row-major, environment index first):
//!
//! | buffer | shape | meaning |
//! | --- | --- | --- |
//! | observations | `N x O` | `O = observation_size()` |
//! | actions | `N x A` | `A = action_size()`, each value in [-1, 1] (the learner clips before stepping) |
//! | `rewards` | `N` | reward of the step just taken |
//! | `terminated` | `N` | the episode ended in a terminal state (no bootstrap) |
//! | `truncated` | `N` | the episode was cut by a time limit (bootstrap from `final_obs`) |
//! | `final_obs` | `N x O` | for an env whose episode ended this step: its last observation, before the reset; other rows unspecified |
//! | `reward_terms` | `N x T` | `T = reward_term_names().len()`: the reward split into named terms (for statistics) |
//! | `episode_metrics` | `N x M` | `M = episode_metric_names().len()`: per-episode figures (distance walked, ...), valid in rows whose episode ended this step |
//!
//! An environment whose episode ends is reset by [`VecEnv::step`] itself:
//! the row of `obs` then holds the first observation of the next episode.
//!
//! An environment may append privileged values to each observation row (an
//! asymmetric actor-critic, rsl_rl's privileged observations): the first
//! `policy_observation_size()` values of a row are what the policy sees,
//! the rest only the critic (the simulator's state a robot cannot measure).

/// `N` environments stepped together.
pub trait VecEnv {
    /// `N`.
    fn num_envs(&self) -> usize;
    /// `O`: the values of an observation row, privileged ones included.
    fn observation_size(&self) -> usize;
    /// The leading values of a row that the policy sees (the rest are
    /// privileged, for the critic only). Default: all of them.
    fn policy_observation_size(&self) -> usize {
        self.observation_size()
    }
    /// `A`.
    fn action_size(&self) -> usize;
    /// Names of the reward terms, `T` of them (may be empty).
    fn reward_term_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Names of the per-episode metrics, `M` of them (may be empty).
    fn episode_metric_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Starts a fresh episode in every environment. Environment `i` draws its
    /// randomness from `(seed, i)` only, so that a rollout is a function of
    /// the seed and the actions. Writes `N x O` observations into `obs`.
    fn reset_all(&mut self, seed: u64, obs: &mut [f32]);
    /// Applies `N x A` actions and fills `out` (see the module docs).
    fn step(&mut self, actions: &[f32], out: &mut StepResult);
    /// The environment's left-right mirror (for
    /// [`crate::PpoConfig::mirror_augmentation`]), or why it has none.
    fn mirror(&self) -> Result<std::sync::Arc<dyn crate::Mirror>, String> {
        Err("the environment has no left-right mirror".into())
    }
    /// Whether the run was asked to stop (Ctrl-C): a learner may then cut
    /// its iteration short, whose results the caller discards.
    fn interrupted(&self) -> bool {
        false
    }
}

/// What one [`VecEnv::step`] writes. Sized by [`StepResult::new`].
#[derive(Debug, Clone, PartialEq)]
pub struct StepResult {
    /// `N x O`: the next observations (after a reset for ended episodes)
    pub obs: Vec<f32>,
    /// `N`
    pub rewards: Vec<f32>,
    /// `N`
    pub terminated: Vec<bool>,
    /// `N`
    pub truncated: Vec<bool>,
    /// `N x O`: the last observation of episodes that ended this step
    pub final_obs: Vec<f32>,
    /// `N x T`
    pub reward_terms: Vec<f32>,
    /// `N x M`
    pub episode_metrics: Vec<f32>,
}

impl StepResult {
    /// Buffers for `env`.
    pub fn new(env: &dyn VecEnv) -> Self {
        let n = env.num_envs();
        let o = env.observation_size();
        Self {
            obs: vec![0.0; n * o],
            rewards: vec![0.0; n],
            terminated: vec![false; n],
            truncated: vec![false; n],
            final_obs: vec![0.0; n * o],
            reward_terms: vec![0.0; n * env.reward_term_names().len()],
            episode_metrics: vec![0.0; n * env.episode_metric_names().len()],
        }
    }

    /// Whether env `i`'s episode ended this step.
    pub fn ended(&self, i: usize) -> bool {
        self.terminated[i] || self.truncated[i]
    }
}
