//! Actor and critic: two separate MLPs (the paper: 256-128, tanh) and a
//! diagonal Gaussian policy whose log standard deviation is a learned,
//! state-independent vector.
//!
//! The policy's samples are unbounded; the learner clips them to [-1, 1]
//! before they reach the environment, and stores the unclipped sample for
//! the PPO ratio (the usual treatment, as in Stable-Baselines3 and rsl_rl).
//! Evaluation uses the mean action, clipped the same way.

use candle_core::{D, Device, Tensor, Var};
use rand_chacha::ChaCha8Rng;

use crate::LearnError;
use crate::mlp::{Mlp, standard_normal, with_zero_rows};
use crate::tanh::TanhImpl;

/// ln(2 pi)
const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// The actor (Gaussian mean), its log-std, and the critic.
#[derive(Debug, Clone)]
pub struct ActorCritic {
    /// observation -> action mean
    pub actor: Mlp,
    /// `A` log standard deviations
    pub log_std: Var,
    /// observation and privileged values -> value
    pub critic: Mlp,
    obs_size: usize,
    privileged_size: usize,
    action_size: usize,
    device: Device,
}

impl ActorCritic {
    /// Fresh networks: `obs_size -> hidden... -> action_size` (output gain
    /// 0.01, so the first actions are near 0) and `obs_size +
    /// privileged_size -> hidden... -> 1` (an asymmetric critic when
    /// `privileged_size > 0`).
    pub fn new(
        (obs_size, privileged_size): (usize, usize),
        action_size: usize,
        hidden: &[usize],
        init_log_std: f64,
        rng: &mut ChaCha8Rng,
    ) -> Result<Self, LearnError> {
        let device = Device::Cpu;
        let sizes = |input: usize, out: usize| {
            std::iter::once(input)
                .chain(hidden.iter().copied())
                .chain(std::iter::once(out))
                .collect::<Vec<_>>()
        };
        let actor = Mlp::new(&sizes(obs_size, action_size), 0.01, rng, &device)?;
        let critic = Mlp::new(&sizes(obs_size + privileged_size, 1), 1.0, rng, &device)?;
        let log_std = Var::from_tensor(&Tensor::full(init_log_std as f32, action_size, &device)?)?;
        Ok(Self {
            actor,
            log_std,
            critic,
            obs_size,
            privileged_size,
            action_size,
            device,
        })
    }

    /// The same networks evaluating `tanh` between their layers.
    pub fn with_tanh(self, tanh: TanhImpl) -> Self {
        Self {
            actor: self.actor.with_tanh(tanh),
            critic: self.critic.with_tanh(tanh),
            ..self
        }
    }

    /// The same networks with the critic also taking `extra` privileged
    /// values after its present input: the first layer's weights for them
    /// are zero, so every value the critic gives is unchanged until
    /// training moves them. The actor is untouched.
    pub fn with_privileged(&self, extra: usize) -> Result<Self, LearnError> {
        let mut critic = self.critic.clone();
        let first = &critic.layers[0];
        critic.layers[0] = crate::mlp::Dense {
            weight: Var::from_tensor(&with_zero_rows(first.weight.as_tensor(), extra)?)?,
            bias: Var::from_tensor(&first.bias.as_tensor().copy()?)?,
        };
        Ok(Self {
            critic,
            privileged_size: self.privileged_size + extra,
            ..self.clone()
        })
    }

    /// The same networks with the actor and the critic both taking `extra`
    /// more observation values after their present input (a critic with
    /// privileged values cannot: they would fall between the two): the
    /// first layers' weights for them are zero, so every action mean and
    /// value is unchanged until training moves them.
    pub fn with_observation(&self, extra: usize) -> Result<Self, LearnError> {
        if self.privileged_size > 0 {
            return Err(LearnError::Mismatch(format!(
                "the critic sees {} privileged values after the observation; the observation cannot grow in front of them",
                self.privileged_size
            )));
        }
        let widen = |mlp: &crate::mlp::Mlp| -> Result<crate::mlp::Mlp, LearnError> {
            let mut mlp = mlp.clone();
            let first = &mlp.layers[0];
            mlp.layers[0] = crate::mlp::Dense {
                weight: Var::from_tensor(&with_zero_rows(first.weight.as_tensor(), extra)?)?,
                bias: Var::from_tensor(&first.bias.as_tensor().copy()?)?,
            };
            Ok(mlp)
        };
        Ok(Self {
            actor: widen(&self.actor)?,
            critic: widen(&self.critic)?,
            obs_size: self.obs_size + extra,
            ..self.clone()
        })
    }

    /// `O`: the values the actor sees.
    pub fn obs_size(&self) -> usize {
        self.obs_size
    }

    /// `P`: the privileged values only the critic sees, after the `O`.
    pub fn privileged_size(&self) -> usize {
        self.privileged_size
    }

    /// The actor's part (the first `O` values) of `k x (O + P)` rows;
    /// the rows themselves when there are no privileged values.
    pub fn actor_part<'a>(&self, rows: &'a [f32]) -> std::borrow::Cow<'a, [f32]> {
        if self.privileged_size == 0 {
            return std::borrow::Cow::Borrowed(rows);
        }
        let width = self.obs_size + self.privileged_size;
        std::borrow::Cow::Owned(
            rows.chunks_exact(width)
                .flat_map(|row| row[..self.obs_size].iter().copied())
                .collect(),
        )
    }

    /// `A`.
    pub fn action_size(&self) -> usize {
        self.action_size
    }

    /// The device (CPU).
    pub fn device(&self) -> &Device {
        &self.device
    }

    /// The actor's parameters with the log-std, named as in checkpoints.
    pub fn actor_vars(&self) -> Vec<(String, Var)> {
        let mut vars = self.actor.named_vars("actor");
        vars.push(("log_std".into(), self.log_std.clone()));
        vars
    }

    /// The critic's parameters, named as in checkpoints.
    pub fn critic_vars(&self) -> Vec<(String, Var)> {
        self.critic.named_vars("critic")
    }

    /// All parameters: actor, log-std, critic.
    pub fn named_vars(&self) -> Vec<(String, Var)> {
        let mut vars = self.actor_vars();
        vars.extend(self.critic_vars());
        vars
    }

    /// The actor's columns (the first `O`) of a `B x (O + P)` tensor.
    pub fn actor_input(&self, obs: &Tensor) -> candle_core::Result<Tensor> {
        if self.privileged_size == 0 {
            Ok(obs.clone())
        } else {
            obs.narrow(1, 0, self.obs_size)
        }
    }

    /// `k x O` observations as a tensor.
    pub fn obs_tensor(&self, obs: &[f32]) -> Result<Tensor, LearnError> {
        let k = obs.len() / self.obs_size;
        Ok(Tensor::from_slice(obs, (k, self.obs_size), &self.device)?)
    }

    /// Action means for `k x O` (normalised) observations, `k x A`.
    pub fn mean_actions(&self, obs: &[f32]) -> Result<Vec<f32>, LearnError> {
        let x = self.obs_tensor(obs)?;
        Ok(self.actor.forward(&x)?.flatten_all()?.to_vec1()?)
    }

    /// Values for `k x (O + P)` (normalised) observations with their
    /// privileged values, `k`.
    pub fn values(&self, obs: &[f32]) -> Result<Vec<f32>, LearnError> {
        let width = self.obs_size + self.privileged_size;
        let k = obs.len() / width;
        let x = Tensor::from_slice(obs, (k, width), &self.device)?;
        Ok(self.critic.forward(&x)?.flatten_all()?.to_vec1()?)
    }

    /// Samples actions for `k x O` observations: returns the unclipped
    /// samples `k x A` and their log-probabilities `k`.
    pub fn sample(
        &self,
        obs: &[f32],
        rng: &mut ChaCha8Rng,
    ) -> Result<(Vec<f32>, Vec<f32>), LearnError> {
        let mean = self.mean_actions(obs)?;
        let log_std: Vec<f32> = self.log_std.as_tensor().to_vec1()?;
        let a = self.action_size;
        let log_std_sum: f64 = log_std.iter().map(|&s| f64::from(s)).sum();
        let mut actions = vec![0.0f32; mean.len()];
        let mut log_probs = Vec::with_capacity(mean.len() / a);
        for (row_mean, row_action) in mean.chunks_exact(a).zip(actions.chunks_exact_mut(a)) {
            let mut square_sum = 0.0f64;
            for ((m, s), out) in row_mean.iter().zip(&log_std).zip(row_action.iter_mut()) {
                let z = standard_normal(rng);
                *out = (f64::from(*m) + f64::from(*s).exp() * z) as f32;
                square_sum += z * z;
            }
            log_probs.push(diagonal_gaussian_log_prob(square_sum, log_std_sum, a));
        }
        Ok((actions, log_probs))
    }

    /// Log-probabilities of `k x A` (unclipped) actions under the policy
    /// for `k x O` observations, `k`, as [`Self::sample`] computes them.
    pub fn log_probs(&self, obs: &[f32], actions: &[f32]) -> Result<Vec<f32>, LearnError> {
        let mean = self.mean_actions(obs)?;
        let log_std: Vec<f32> = self.log_std.as_tensor().to_vec1()?;
        let a = self.action_size;
        let log_std_sum: f64 = log_std.iter().map(|&s| f64::from(s)).sum();
        Ok(mean
            .chunks_exact(a)
            .zip(actions.chunks_exact(a))
            .map(|(row_mean, row_action)| {
                let square_sum: f64 = row_mean
                    .iter()
                    .zip(row_action)
                    .zip(&log_std)
                    .map(|((m, x), s)| {
                        let z = (f64::from(*x) - f64::from(*m)) / f64::from(*s).exp();
                        z * z
                    })
                    .sum();
                diagonal_gaussian_log_prob(square_sum, log_std_sum, a)
            })
            .collect())
    }
}

/// `log p(a) = -1/2 sum_j z_j^2 - sum_j log sigma_j - A/2 ln(2 pi)` from
/// `square_sum` = sum_j z_j^2 and `log_std_sum` = sum_j log sigma_j, for
/// `action_size` = A (what [`ActorCritic::sample`] and
/// [`ActorCritic::log_probs`] compute per row).
fn diagonal_gaussian_log_prob(square_sum: f64, log_std_sum: f64, action_size: usize) -> f32 {
    (-0.5 * square_sum - log_std_sum - 0.5 * action_size as f64 * LN_2PI) as f32
}

/// Log-density of a diagonal Gaussian: `mean`, `actions` `B x A`,
/// `log_std` `A`; result `B`.
///
/// `log p(a) = -1/2 sum_j ((a_j - mu_j) / sigma_j)^2 - sum_j log sigma_j - A/2 ln(2 pi)`
pub fn gaussian_log_prob(
    mean: &Tensor,
    log_std: &Tensor,
    actions: &Tensor,
) -> candle_core::Result<Tensor> {
    let action_size = log_std.dim(0)?;
    let z = actions.sub(mean)?.broadcast_div(&log_std.exp()?)?;
    let quadratic = z.sqr()?.sum(D::Minus1)?.affine(-0.5, 0.0)?;
    let constant = log_std
        .sum_all()?
        .affine(-1.0, -0.5 * action_size as f64 * LN_2PI)?;
    quadratic.broadcast_add(&constant)
}

/// Entropy of the diagonal Gaussian: `sum_j (log sigma_j + (1 + ln(2 pi)) / 2)`.
pub fn gaussian_entropy(log_std: &Tensor) -> candle_core::Result<Tensor> {
    let action_size = log_std.dim(0)?;
    log_std
        .sum_all()?
        .affine(1.0, 0.5 * (1.0 + LN_2PI) * action_size as f64)
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;

    #[test]
    fn log_prob_matches_the_formula() {
        let dev = Device::Cpu;
        let mean = Tensor::new(&[[0.0f32, 1.0], [0.5, -0.5]], &dev).unwrap();
        let log_std = Tensor::new(&[0.0f32, -1.0], &dev).unwrap();
        let actions = Tensor::new(&[[1.0f32, 1.0], [0.5, 0.0]], &dev).unwrap();
        let lp: Vec<f32> = gaussian_log_prob(&mean, &log_std, &actions)
            .unwrap()
            .to_vec1()
            .unwrap();
        let sigma1 = (-1.0f64).exp();
        let expect0 = -0.5 * 1.0 - (0.0 - 1.0) - LN_2PI;
        let expect1 = -0.5 * (0.5 / sigma1).powi(2) + 1.0 - LN_2PI;
        assert!(
            (f64::from(lp[0]) - expect0).abs() < 1e-5,
            "{} vs {expect0}",
            lp[0]
        );
        assert!(
            (f64::from(lp[1]) - expect1).abs() < 1e-5,
            "{} vs {expect1}",
            lp[1]
        );
        let h: f32 = gaussian_entropy(&log_std).unwrap().to_scalar().unwrap();
        assert!((f64::from(h) - (-1.0 + (1.0 + LN_2PI))).abs() < 1e-5);
    }

    #[test]
    fn sampled_and_recomputed_log_probs_agree_with_the_tensor_formula() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let ac = ActorCritic::new((4, 0), 3, &[8, 8], -0.5, &mut rng).unwrap();
        let obs = [0.1f32, -0.2, 0.3, 0.4, 1.0, 0.0, -1.0, 0.5];
        let (actions, lp) = ac.sample(&obs, &mut rng).unwrap();
        let mean = ac.actor.forward(&ac.obs_tensor(&obs).unwrap()).unwrap();
        let a = Tensor::from_slice(&actions, (2, 3), &Device::Cpu).unwrap();
        let lp2: Vec<f32> = gaussian_log_prob(&mean, ac.log_std.as_tensor(), &a)
            .unwrap()
            .to_vec1()
            .unwrap();
        let lp3 = ac.log_probs(&obs, &actions).unwrap();
        for ((x, y), z) in lp.iter().zip(&lp2).zip(&lp3) {
            assert!((x - y).abs() < 1e-4, "{x} vs {y}");
            assert!((x - z).abs() < 1e-5, "{x} vs {z}");
        }
    }

    /// A critic given privileged values gives the same values as before
    /// whatever they are; the actor is the same.
    #[test]
    fn a_critic_given_privileged_values_values_as_before() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let ac = ActorCritic::new((4, 0), 2, &[8, 8], -0.5, &mut rng).unwrap();
        let wide = ac.with_privileged(3).unwrap();
        assert_eq!((wide.obs_size(), wide.privileged_size()), (4, 3));
        let obs = [0.1f32, -0.2, 0.3, 0.4, 1.0, 0.0, -1.0, 0.5];
        let with_privileged = [
            0.1f32, -0.2, 0.3, 0.4, 5.0, -7.0, 2.0, 1.0, 0.0, -1.0, 0.5, 0.3, 0.2, 9.0,
        ];
        assert_eq!(
            ac.values(&obs).unwrap(),
            wide.values(&with_privileged).unwrap()
        );
        assert_eq!(
            ac.mean_actions(&obs).unwrap(),
            wide.mean_actions(&obs).unwrap()
        );
        let shape = wide.critic.layers[0].weight.as_tensor().dims().to_vec();
        assert_eq!(shape, [7, 8]);
    }

    #[test]
    fn same_seed_same_networks() {
        let a =
            ActorCritic::new((5, 0), 2, &[16], -0.7, &mut ChaCha8Rng::seed_from_u64(9)).unwrap();
        let b =
            ActorCritic::new((5, 0), 2, &[16], -0.7, &mut ChaCha8Rng::seed_from_u64(9)).unwrap();
        for ((na, va), (nb, vb)) in a.named_vars().iter().zip(b.named_vars().iter()) {
            assert_eq!(na, nb);
            let x: Vec<f32> = va.as_tensor().flatten_all().unwrap().to_vec1().unwrap();
            let y: Vec<f32> = vb.as_tensor().flatten_all().unwrap().to_vec1().unwrap();
            assert_eq!(x, y);
        }
        let names: Vec<String> = a.named_vars().into_iter().map(|(n, _)| n).collect();
        assert_eq!(
            names,
            [
                "actor.0.weight",
                "actor.0.bias",
                "actor.1.weight",
                "actor.1.bias",
                "log_std",
                "critic.0.weight",
                "critic.0.bias",
                "critic.1.weight",
                "critic.1.bias"
            ]
        );
    }
}
