//! The PPO objective on one minibatch (Schulman et al. 2017):
//!
//! ```text
//! ratio_i = exp(log pi(a_i|s_i) - log pi_old(a_i|s_i))
//! L_clip  = -mean_i min(ratio_i A_i, clip(ratio_i, 1 - eps, 1 + eps) A_i)
//! L_value = mean_i (V(s_i) - R_i)^2
//! H       = entropy of the Gaussian (state-independent)
//! L       = L_clip + c_v L_value - c_e H
//! ```
//!
//! Diagnostics: approximate KL `mean((ratio - 1) - ln ratio)` (the
//! low-variance k3 estimator) and the clip fraction `mean(|ratio - 1| > eps)`.

use candle_core::{DType, Tensor};

use super::actor_critic::{ActorCritic, gaussian_entropy, gaussian_log_prob};
use super::config::PpoConfig;
use crate::LearnError;

/// A minibatch as tensors.
#[derive(Debug, Clone)]
pub struct Minibatch {
    /// `B x O`, normalised observations
    pub obs: Tensor,
    /// `B x A`, the unclipped sampled actions
    pub actions: Tensor,
    /// `B`, log-probabilities under the policy that sampled them
    pub old_log_probs: Tensor,
    /// `B`, advantages (already normalised if the config says so)
    pub advantages: Tensor,
    /// `B`, value targets
    pub returns: Tensor,
}

/// The loss and its parts.
#[derive(Debug, Clone)]
pub struct PpoLoss {
    /// `L`, to differentiate
    pub total: Tensor,
    /// `L_clip`
    pub policy_loss: f64,
    /// `L_value`
    pub value_loss: f64,
    /// `H`
    pub entropy: f64,
    /// approximate KL(old || new)
    pub approx_kl: f64,
    /// share of samples whose ratio left [1 - eps, 1 + eps]
    pub clip_fraction: f64,
}

/// `L` and its parts for `batch` under the current `policy`.
pub fn ppo_loss(
    policy: &ActorCritic,
    batch: &Minibatch,
    config: &PpoConfig,
) -> Result<PpoLoss, LearnError> {
    let eps = config.clip_range;
    let mean = policy.actor.forward(&policy.actor_input(&batch.obs)?)?;
    let log_probs = gaussian_log_prob(&mean, policy.log_std.as_tensor(), &batch.actions)?;
    let log_ratio = log_probs.sub(&batch.old_log_probs)?;
    let ratio = log_ratio.exp()?;
    let unclipped = ratio.mul(&batch.advantages)?;
    let clipped = ratio.clamp(1.0 - eps, 1.0 + eps)?.mul(&batch.advantages)?;
    let policy_loss = unclipped.minimum(&clipped)?.mean_all()?.neg()?;

    let values = policy.critic.forward(&batch.obs)?.squeeze(1)?;
    let value_loss = values.sub(&batch.returns)?.sqr()?.mean_all()?;

    let entropy = gaussian_entropy(policy.log_std.as_tensor())?;
    let total = (policy_loss.clone() + value_loss.affine(config.value_coef, 0.0)?)?
        .sub(&entropy.affine(config.entropy_coef, 0.0)?)?;

    let approx_kl = ratio.affine(1.0, -1.0)?.sub(&log_ratio)?.mean_all()?;
    let clip_fraction = ratio
        .affine(1.0, -1.0)?
        .abs()?
        .gt(eps)?
        .to_dtype(DType::F32)?
        .mean_all()?;
    let scalar = |t: &Tensor| -> Result<f64, LearnError> { Ok(f64::from(t.to_scalar::<f32>()?)) };
    Ok(PpoLoss {
        policy_loss: scalar(&policy_loss)?,
        value_loss: scalar(&value_loss)?,
        entropy: scalar(&entropy)?,
        approx_kl: scalar(&approx_kl)?,
        clip_fraction: scalar(&clip_fraction)?,
        total,
    })
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Var};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// A policy whose mean and value are 0 everywhere and whose log-std is 0:
    /// every weight zeroed.
    fn zero_policy() -> ActorCritic {
        let ac = ActorCritic::new((2, 0), 1, &[3], 0.0, &mut ChaCha8Rng::seed_from_u64(0)).unwrap();
        for (_, var) in ac.named_vars() {
            var.set(&var.as_tensor().zeros_like().unwrap()).unwrap();
        }
        ac
    }

    /// Two samples, A = 1, sigma = 1, mean 0, value 0, eps = 0.2, c_v = 0.5, c_e = 0.01:
    ///
    /// ```text
    /// log pi(a) = -a^2/2 - ln(2 pi)/2
    /// sample 1: a = 0, old log p = log pi(0) - ln 1.5  -> ratio 1.5,  A = +1
    ///           min(1.5 * 1, 1.2 * 1) = 1.2            (clipped)
    /// sample 2: a = 1, old log p = log pi(1) - ln 0.5  -> ratio 0.5,  A = +2
    ///           min(0.5 * 2, 0.8 * 2) = 1.0            (unclipped objective is smaller)
    /// L_clip  = -(1.2 + 1.0) / 2 = -1.1
    /// L_value = ((0 - 1)^2 + (0 - (-3))^2) / 2 = 5
    /// H       = 0 + (1 + ln 2 pi)/2 = 1.418938533
    /// L       = -1.1 + 0.5 * 5 - 0.01 * 1.418938533 = 1.385810615
    /// KL      = ((0.5 - ln 1.5) + (-0.5 - ln 0.5)) / 2 = (0.094534892 + 0.193147181) / 2 = 0.143841036
    /// clip fraction = 2 / 2 (both ratios are outside [0.8, 1.2])
    /// ```
    #[test]
    fn loss_on_a_fixed_batch_matches_hand_computation() {
        let dev = Device::Cpu;
        let policy = zero_policy();
        let ln_2pi = (2.0 * std::f64::consts::PI).ln();
        let log_pi = |a: f64| -0.5 * a * a - 0.5 * ln_2pi;
        let batch = Minibatch {
            obs: Tensor::new(&[[0.3f32, -0.7], [1.0, 2.0]], &dev).unwrap(),
            actions: Tensor::new(&[[0.0f32], [1.0]], &dev).unwrap(),
            old_log_probs: Tensor::new(
                &[
                    (log_pi(0.0) - 1.5f64.ln()) as f32,
                    (log_pi(1.0) - 0.5f64.ln()) as f32,
                ],
                &dev,
            )
            .unwrap(),
            advantages: Tensor::new(&[1.0f32, 2.0], &dev).unwrap(),
            returns: Tensor::new(&[1.0f32, -3.0], &dev).unwrap(),
        };
        let config = PpoConfig {
            clip_range: 0.2,
            value_coef: 0.5,
            entropy_coef: 0.01,
            ..PpoConfig::default()
        };
        let loss = ppo_loss(&policy, &batch, &config).unwrap();
        let total = f64::from(loss.total.to_scalar::<f32>().unwrap());
        assert!(
            (loss.policy_loss - -1.1).abs() < 1e-5,
            "{}",
            loss.policy_loss
        );
        assert!((loss.value_loss - 5.0).abs() < 1e-5, "{}", loss.value_loss);
        assert!(
            (loss.entropy - 1.418_938_533).abs() < 1e-5,
            "{}",
            loss.entropy
        );
        assert!((total - 1.385_810_615).abs() < 1e-5, "{total}");
        assert!(
            (loss.approx_kl - 0.143_841_036).abs() < 1e-5,
            "{}",
            loss.approx_kl
        );
        assert_eq!(loss.clip_fraction, 1.0);
    }

    /// At the old policy (ratio 1) the gradient of L_clip with respect to the
    /// mean is the score-function gradient: d/dmu (-A log pi(a)) = -A (a - mu) / sigma^2.
    #[test]
    fn gradient_at_ratio_one_is_the_policy_gradient() {
        let dev = Device::Cpu;
        let policy = zero_policy();
        let ln_2pi = (2.0 * std::f64::consts::PI).ln();
        let a = 0.5f64;
        let batch = Minibatch {
            obs: Tensor::new(&[[0.0f32, 0.0]], &dev).unwrap(),
            actions: Tensor::new(&[[a as f32]], &dev).unwrap(),
            old_log_probs: Tensor::new(&[(-0.5 * a * a - 0.5 * ln_2pi) as f32], &dev).unwrap(),
            advantages: Tensor::new(&[2.0f32], &dev).unwrap(),
            returns: Tensor::new(&[0.0f32], &dev).unwrap(),
        };
        let config = PpoConfig {
            entropy_coef: 0.0,
            ..PpoConfig::default()
        };
        let loss = ppo_loss(&policy, &batch, &config).unwrap();
        let grads = loss.total.backward().unwrap();
        // the output bias of the actor moves the mean one-for-one
        let bias: &Var = &policy.actor.layers[1].bias;
        let g: Vec<f32> = grads.get(bias.as_tensor()).unwrap().to_vec1().unwrap();
        assert!((f64::from(g[0]) - (-2.0 * a)).abs() < 1e-5, "{g:?}");
    }
}
