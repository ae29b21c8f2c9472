//! SAC's three objectives (Haarnoja et al. 2018, "Soft Actor-Critic
//! Algorithms and Applications", eqs. 5, 7 and 18), as pure functions of
//! batch tensors so that each is tested on a fixed batch.

use candle_core::Tensor;

/// The soft Bellman target (eq. 5 with the clipped double Q of TD3):
///
/// ```text
/// y = r + gamma (1 - terminated) (min(Q1'(s', a'), Q2'(s', a')) - alpha log pi(a' | s'))
/// ```
///
/// `rewards`, `terminated` (1 for an episode that ended in a terminal
/// state, 0 otherwise; a time-limit cut bootstraps), `next_q1`, `next_q2`,
/// `next_log_pi`: all `B`. The result carries no gradient.
pub fn soft_target(
    rewards: &Tensor,
    terminated: &Tensor,
    next_q1: &Tensor,
    next_q2: &Tensor,
    next_log_pi: &Tensor,
    alpha: f64,
    gamma: f64,
) -> candle_core::Result<Tensor> {
    let soft_value = next_q1
        .minimum(next_q2)?
        .sub(&next_log_pi.affine(alpha, 0.0)?)?;
    let continues = terminated.affine(-1.0, 1.0)?;
    rewards
        .add(&continues.mul(&soft_value)?.affine(gamma, 0.0)?)
        .map(|y| y.detach())
}

/// The critics' loss: `1/2 (mean (Q1 - y)^2 + mean (Q2 - y)^2)` (eq. 5 for
/// both critics; Stable-Baselines3's scale). All `B`; a scalar.
pub fn critic_loss(q1: &Tensor, q2: &Tensor, target: &Tensor) -> candle_core::Result<Tensor> {
    let e1 = q1.sub(target)?.sqr()?.mean_all()?;
    let e2 = q2.sub(target)?.sqr()?.mean_all()?;
    e1.add(&e2)?.affine(0.5, 0.0)
}

/// The actor's loss (eq. 7): `mean(alpha log pi(a~ | s) - min(Q1, Q2)(s, a~))`
/// with a~ the reparameterised sample. All `B`; a scalar.
pub fn actor_loss(
    log_pi: &Tensor,
    q1: &Tensor,
    q2: &Tensor,
    alpha: f64,
) -> candle_core::Result<Tensor> {
    log_pi.affine(alpha, 0.0)?.sub(&q1.minimum(q2)?)?.mean_all()
}

/// The temperature's loss (eq. 18, in log alpha as SB3 and CleanRL):
/// `-mean(log_alpha (log pi + target_entropy))` with log pi held fixed, so
/// alpha grows while the policy's entropy is below the target. `log_alpha`
/// is a one-element tensor, `log_pi` `B`; a scalar.
pub fn temperature_loss(
    log_alpha: &Tensor,
    log_pi: &Tensor,
    target_entropy: f64,
) -> candle_core::Result<Tensor> {
    let deficit = log_pi.detach().affine(1.0, target_entropy)?;
    deficit
        .broadcast_mul(log_alpha)?
        .mean_all()?
        .affine(-1.0, 0.0)
}

#[cfg(test)]
mod tests {
    use candle_core::{Device, Var};

    use super::*;

    fn v(values: &[f32]) -> Tensor {
        Tensor::new(values, &Device::Cpu).unwrap()
    }

    fn scalar(t: &Tensor) -> f64 {
        f64::from(t.to_scalar::<f32>().unwrap())
    }

    #[test]
    fn the_soft_target_bootstraps_unless_terminated() {
        let y = soft_target(
            &v(&[1.0, -0.5, 2.0]),
            &v(&[0.0, 1.0, 0.0]),
            &v(&[3.0, 10.0, -1.0]),
            &v(&[2.5, 12.0, 0.5]),
            &v(&[-1.0, 4.0, 2.0]),
            0.2,
            0.9,
        )
        .unwrap();
        let y: Vec<f32> = y.to_vec1().unwrap();
        // 1 + 0.9 (min(3, 2.5) - 0.2 * -1) = 1 + 0.9 * 2.7 = 3.43
        assert!((y[0] - 3.43).abs() < 1e-6);
        // terminated: the reward alone
        assert!((y[1] - -0.5).abs() < 1e-6);
        // 2 + 0.9 (-1 - 0.4) = 0.74
        assert!((y[2] - 0.74).abs() < 1e-6);
    }

    #[test]
    fn the_critic_loss_is_half_the_two_mean_squared_errors() {
        let loss = critic_loss(&v(&[1.0, 2.0]), &v(&[0.0, 4.0]), &v(&[1.5, 2.5])).unwrap();
        // Q1: (0.25 + 0.25) / 2 = 0.25; Q2: (2.25 + 2.25) / 2 = 2.25
        assert!((scalar(&loss) - 0.5 * (0.25 + 2.25)).abs() < 1e-6);
    }

    #[test]
    fn the_actor_loss_trades_entropy_against_the_smaller_q() {
        let loss = actor_loss(&v(&[-1.0, 0.5]), &v(&[2.0, 1.0]), &v(&[3.0, -1.0]), 0.1).unwrap();
        // mean(0.1 * -1 - 2, 0.1 * 0.5 - -1) = mean(-2.1, 1.05) = -0.525
        assert!((scalar(&loss) - -0.525).abs() < 1e-6);
    }

    #[test]
    fn the_temperature_rises_when_entropy_is_below_target() {
        let log_alpha = Var::from_tensor(&v(&[0.0])).unwrap();
        // target entropy -2; log pi = 3 means entropy ~ -3 < -2
        let log_pi = v(&[3.0, 3.0]);
        let loss = temperature_loss(log_alpha.as_tensor(), &log_pi, -2.0).unwrap();
        // -mean(0 * (3 - 2)) = 0; gradient d/dlog_alpha = -(3 - 2) = -1
        assert!(scalar(&loss).abs() < 1e-9);
        let grads = loss.backward().unwrap();
        let g: Vec<f32> = grads.get(log_alpha.as_tensor()).unwrap().to_vec1().unwrap();
        assert!((g[0] - -1.0).abs() < 1e-6, "{g:?}");
        // gradient descent then raises log alpha
        let log_alpha = Var::from_tensor(&v(&[0.5])).unwrap();
        let loss = temperature_loss(log_alpha.as_tensor(), &v(&[1.0, 1.0]), -2.0).unwrap();
        // -(0.5 * (1 - 2)) = 0.5; gradient +1: alpha falls when entropy is above target
        assert!((scalar(&loss) - 0.5).abs() < 1e-6);
    }
}
