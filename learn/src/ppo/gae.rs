//! Generalised advantage estimation, as a pure function.
//!
//! For one environment, with `d_t = 1` when the episode ended at step `t`:
//!
//! ```text
//! delta_t = r_t + gamma * (1 - d_t) * V(s_{t+1}) - V(s_t)
//! A_t     = delta_t + gamma * lambda * (1 - d_t) * A_{t+1}
//! R_t     = A_t + V(s_t)            (the value target)
//! ```
//!
//! `V(s_T)` after the last stored step is `last_values`. An episode cut by a
//! time limit is not terminal: the collector adds `gamma * V(final_obs)` to
//! its last reward and marks it ended, which is the same bootstrap.

/// Advantages and value targets, both `T x N` (step-major, like the inputs).
#[derive(Debug, Clone, PartialEq)]
pub struct Gae {
    /// `A_t`
    pub advantages: Vec<f32>,
    /// `R_t = A_t + V(s_t)`
    pub returns: Vec<f32>,
}

/// GAE over a `T x N` rollout (index `t * num_envs + env`): `rewards`,
/// `values` (`V(s_t)`), `ended` (`d_t`); `last_values` is `V(s_T)` per env.
/// Sums run in `f64`.
pub fn gae(
    rewards: &[f32],
    values: &[f32],
    ended: &[bool],
    last_values: &[f32],
    gamma: f64,
    lambda: f64,
) -> Gae {
    let num_envs = last_values.len();
    assert!(num_envs > 0, "gae: no environments");
    assert_eq!(
        rewards.len(),
        values.len(),
        "gae: rewards and values differ in length"
    );
    assert_eq!(
        rewards.len(),
        ended.len(),
        "gae: rewards and ended differ in length"
    );
    assert_eq!(rewards.len() % num_envs, 0, "gae: length is not T x N");
    let steps = rewards.len() / num_envs;
    let mut advantages = vec![0.0f32; rewards.len()];
    let mut returns = vec![0.0f32; rewards.len()];
    for (env, &last_value) in last_values.iter().enumerate() {
        let mut next_value = f64::from(last_value);
        let mut next_advantage = 0.0f64;
        for t in (0..steps).rev() {
            let i = t * num_envs + env;
            let not_ended = if ended[i] { 0.0 } else { 1.0 };
            let value = f64::from(values[i]);
            let delta = f64::from(rewards[i]) + gamma * not_ended * next_value - value;
            let advantage = delta + gamma * lambda * not_ended * next_advantage;
            advantages[i] = advantage as f32;
            returns[i] = (advantage + value) as f32;
            next_value = value;
            next_advantage = advantage;
        }
    }
    Gae {
        advantages,
        returns,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One env, three steps, gamma 0.5, lambda 0.5, no episode end:
    ///
    /// ```text
    /// r = [1, 2, 3], V = [0.5, 1.0, 1.5], V(s_3) = 2
    /// delta_2 = 3 + 0.5*2   - 1.5 = 2.5      A_2 = 2.5
    /// delta_1 = 2 + 0.5*1.5 - 1.0 = 1.75     A_1 = 1.75 + 0.25*2.5   = 2.375
    /// delta_0 = 1 + 0.5*1.0 - 0.5 = 1.0      A_0 = 1.0  + 0.25*2.375 = 1.59375
    /// R = A + V = [2.09375, 3.375, 4.0]
    /// ```
    #[test]
    fn matches_hand_computed_values() {
        let g = gae(
            &[1.0, 2.0, 3.0],
            &[0.5, 1.0, 1.5],
            &[false; 3],
            &[2.0],
            0.5,
            0.5,
        );
        assert_eq!(g.advantages, vec![1.59375, 2.375, 2.5]);
        assert_eq!(g.returns, vec![2.09375, 3.375, 4.0]);
    }

    /// The episode ends at step 1: nothing flows back across it.
    ///
    /// ```text
    /// r = [1, 2, 3], V = [0.5, 1.0, 1.5], d = [0, 1, 0], V(s_3) = 2, gamma = lambda = 0.5
    /// A_2 = 3 + 0.5*2 - 1.5 = 2.5
    /// A_1 = 2 - 1.0 = 1.0                      (ended: no bootstrap, no A_2)
    /// A_0 = (1 + 0.5*1.0 - 0.5) + 0.25*1.0 = 1.25
    /// ```
    #[test]
    fn episode_end_cuts_the_sum() {
        let g = gae(
            &[1.0, 2.0, 3.0],
            &[0.5, 1.0, 1.5],
            &[false, true, false],
            &[2.0],
            0.5,
            0.5,
        );
        assert_eq!(g.advantages, vec![1.25, 1.0, 2.5]);
        assert_eq!(g.returns, vec![1.75, 2.0, 4.0]);
    }

    /// Two envs interleaved step-major give the same as each alone.
    #[test]
    fn environments_are_independent() {
        let a = gae(&[1.0, 0.0], &[0.2, 0.3], &[false, true], &[5.0], 0.9, 0.8);
        let b = gae(&[-1.0, 2.0], &[0.0, 0.1], &[false, false], &[1.0], 0.9, 0.8);
        let both = gae(
            &[1.0, -1.0, 0.0, 2.0],
            &[0.2, 0.0, 0.3, 0.1],
            &[false, false, true, false],
            &[5.0, 1.0],
            0.9,
            0.8,
        );
        assert_eq!(
            both.advantages,
            vec![
                a.advantages[0],
                b.advantages[0],
                a.advantages[1],
                b.advantages[1]
            ]
        );
    }

    /// lambda = 1 with no ends gives the discounted return minus V.
    #[test]
    fn lambda_one_is_monte_carlo() {
        let g = gae(
            &[1.0, 1.0, 1.0],
            &[0.3, -0.2, 0.7],
            &[false; 3],
            &[0.0],
            0.9,
            1.0,
        );
        let mc = [1.0 + 0.9 + 0.81, 1.0 + 0.9, 1.0];
        for (r, m) in g.returns.iter().zip(mc) {
            assert!((f64::from(*r) - m).abs() < 1e-6, "{r} vs {m}");
        }
    }
}
