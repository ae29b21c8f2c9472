//! The rollout buffer: what one iteration collected, `T x N` samples stored
//! step-major (index `t * N + env`), as GAE and the update read them.

/// One iteration's samples.
#[derive(Debug, Clone, PartialEq)]
pub struct RolloutBuffer {
    /// `T x N x O`: normalised observations
    pub obs: Vec<f32>,
    /// `T x N x A`: the sampled (unclipped) actions
    pub actions: Vec<f32>,
    /// `T x N`: their log-probabilities when sampled
    pub log_probs: Vec<f32>,
    /// `T x N`: the critic's values when sampled
    pub values: Vec<f32>,
    /// `T x N`: rewards (with the time-limit bootstrap added)
    pub rewards: Vec<f32>,
    /// `T x N`: the episode ended at this step
    pub ended: Vec<bool>,
    num_envs: usize,
    obs_size: usize,
    action_size: usize,
}

impl RolloutBuffer {
    /// An empty buffer for `steps` steps of `num_envs` environments.
    pub fn new(num_envs: usize, obs_size: usize, action_size: usize, steps: usize) -> Self {
        let samples = steps * num_envs;
        Self {
            obs: Vec::with_capacity(samples * obs_size),
            actions: Vec::with_capacity(samples * action_size),
            log_probs: Vec::with_capacity(samples),
            values: Vec::with_capacity(samples),
            rewards: Vec::with_capacity(samples),
            ended: Vec::with_capacity(samples),
            num_envs,
            obs_size,
            action_size,
        }
    }

    /// Appends one step of every environment.
    pub fn push(
        &mut self,
        obs: &[f32],
        actions: &[f32],
        log_probs: &[f32],
        values: &[f32],
        rewards: &[f32],
        ended: impl IntoIterator<Item = bool>,
    ) {
        let n = self.num_envs;
        assert_eq!(
            obs.len(),
            n * self.obs_size,
            "buffer: observations are not N x O"
        );
        assert_eq!(
            actions.len(),
            n * self.action_size,
            "buffer: actions are not N x A"
        );
        assert!(
            log_probs.len() == n && values.len() == n && rewards.len() == n,
            "buffer: per-env values are not N long"
        );
        self.obs.extend_from_slice(obs);
        self.actions.extend_from_slice(actions);
        self.log_probs.extend_from_slice(log_probs);
        self.values.extend_from_slice(values);
        self.rewards.extend_from_slice(rewards);
        let before = self.ended.len();
        self.ended.extend(ended);
        assert_eq!(
            self.ended.len() - before,
            n,
            "buffer: ended flags are not N long"
        );
    }

    /// Samples stored (`T x N`).
    pub fn len(&self) -> usize {
        self.rewards.len()
    }

    /// Whether nothing is stored.
    pub fn is_empty(&self) -> bool {
        self.rewards.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_stored_step_major() {
        let mut b = RolloutBuffer::new(2, 1, 1, 2);
        b.push(
            &[1.0, 2.0],
            &[0.1, 0.2],
            &[-1.0, -2.0],
            &[5.0, 6.0],
            &[1.0, 0.0],
            [false, true],
        );
        b.push(
            &[3.0, 4.0],
            &[0.3, 0.4],
            &[-3.0, -4.0],
            &[7.0, 8.0],
            &[0.5, 0.5],
            [false, false],
        );
        assert_eq!(b.len(), 4);
        assert_eq!(b.obs, vec![1.0, 2.0, 3.0, 4.0]);
        assert_eq!(b.ended, vec![false, true, false, false]);
    }

    #[test]
    #[should_panic(expected = "not N x O")]
    fn a_wrongly_sized_step_is_a_bug() {
        let mut b = RolloutBuffer::new(2, 3, 1, 1);
        b.push(
            &[1.0],
            &[0.0, 0.0],
            &[0.0; 2],
            &[0.0; 2],
            &[0.0; 2],
            [false; 2],
        );
    }
}
