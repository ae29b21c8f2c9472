//! The tanh-squashed diagonal Gaussian of SAC (Haarnoja et al. 2018,
//! appendix C): u ~ N(mu, sigma^2), a = tanh(u), so actions lie in (-1, 1),
//! and
//!
//! ```text
//! log pi(a | s) = log N(u; mu, sigma) - sum_j log(1 - tanh(u_j)^2)
//! ```
//!
//! with `log(1 - tanh(u)^2) = 2 (ln 2 - u - softplus(-2 u))`, which stays
//! finite where tanh(u) rounds to +-1 (the form Stable-Baselines3's and
//! CleanRL's `+ 1e-6` guard approximates).

use candle_core::{D, Tensor};

/// ln(2 pi)
const LN_2PI: f64 = 1.837_877_066_409_345_5;

/// Bounds of the actor's log standard deviation (SB3's and CleanRL's).
pub const LOG_STD_RANGE: (f64, f64) = (-5.0, 2.0);

/// softplus(x) = ln(1 + e^x), stable for large |x|: max(x, 0) + ln(1 + e^-|x|).
pub fn softplus(x: &Tensor) -> candle_core::Result<Tensor> {
    let positive = x.relu()?;
    let tail = x.abs()?.neg()?.exp()?.affine(1.0, 1.0)?.log()?;
    positive.add(&tail)
}

/// The actor's raw log-std squashed into [`LOG_STD_RANGE`] smoothly:
/// `lo + (hi - lo) (tanh(x) + 1) / 2` (CleanRL's form).
pub fn bounded_log_std(raw: &Tensor) -> candle_core::Result<Tensor> {
    let (lo, hi) = LOG_STD_RANGE;
    raw.tanh()?.affine(0.5 * (hi - lo), lo + 0.5 * (hi - lo))
}

/// Reparameterised sample and its log-probability: `mean`, `log_std`,
/// `noise` (standard normal draws) all `B x A`; returns the actions
/// `tanh(mean + exp(log_std) noise)` (`B x A`) and log pi (`B`). Gradients
/// flow to `mean` and `log_std`.
pub fn sample(
    mean: &Tensor,
    log_std: &Tensor,
    noise: &Tensor,
) -> candle_core::Result<(Tensor, Tensor)> {
    let u = mean.add(&log_std.exp()?.mul(noise)?)?;
    let action = u.tanh()?;
    let action_size = mean.dim(D::Minus1)?;
    // log N(u; mu, sigma) = -noise^2 / 2 - log sigma - ln(2 pi) / 2, per component
    let gaussian = noise
        .sqr()?
        .affine(-0.5, 0.0)?
        .sub(log_std)?
        .sum(D::Minus1)?
        .affine(1.0, -0.5 * LN_2PI * action_size as f64)?;
    Ok((action, gaussian.sub(&log_det_tanh(&u)?)?))
}

/// sum_j log(1 - tanh(u_j)^2) = sum_j 2 (ln 2 - u_j - softplus(-2 u_j)), `B`.
pub fn log_det_tanh(u: &Tensor) -> candle_core::Result<Tensor> {
    let inner = softplus(&u.affine(-2.0, 0.0)?)?.add(u)?;
    inner
        .affine(-2.0, 2.0 * std::f64::consts::LN_2)?
        .sum(D::Minus1)
}

#[cfg(test)]
mod tests {
    use candle_core::Device;

    use super::*;

    fn t(rows: &[[f32; 2]]) -> Tensor {
        let flat: Vec<f32> = rows.iter().flatten().copied().collect();
        Tensor::from_vec(flat, (rows.len(), 2), &Device::Cpu).unwrap()
    }

    #[test]
    fn the_squashed_log_probability_is_the_change_of_variables() {
        let mean = t(&[[0.3, -1.2], [0.0, 2.0]]);
        let log_std = t(&[[-0.5, 0.2], [0.0, -1.0]]);
        let noise = t(&[[1.1, -0.4], [0.0, 0.7]]);
        let (action, log_pi) = sample(&mean, &log_std, &noise).unwrap();
        let action: Vec<Vec<f32>> = action.to_vec2().unwrap();
        let log_pi: Vec<f32> = log_pi.to_vec1().unwrap();
        let m = [[0.3f64, -1.2], [0.0, 2.0]];
        let s = [[-0.5f64, 0.2], [0.0, -1.0]];
        let e = [[1.1f64, -0.4], [0.0, 0.7]];
        for b in 0..2 {
            let mut expected = 0.0;
            for j in 0..2 {
                let u = m[b][j] + s[b][j].exp() * e[b][j];
                assert!((f64::from(action[b][j]) - u.tanh()).abs() < 1e-6);
                // Gaussian density of u, then the Jacobian of tanh
                let sigma = s[b][j].exp();
                expected += -0.5 * ((u - m[b][j]) / sigma).powi(2)
                    - sigma.ln()
                    - 0.5 * LN_2PI
                    - (1.0 - u.tanh().powi(2)).ln();
            }
            assert!(
                (f64::from(log_pi[b]) - expected).abs() < 1e-4,
                "row {b}: {} vs {expected}",
                log_pi[b]
            );
        }
    }

    #[test]
    fn the_jacobian_stays_finite_where_tanh_saturates() {
        // tanh(20) rounds to 1 in f32: the naive log(1 - a^2) is -inf
        let u = t(&[[20.0, -20.0]]);
        let v: Vec<f32> = log_det_tanh(&u).unwrap().to_vec1().unwrap();
        // 2 (ln 2 - 20 - softplus(-40)) per component ~ -38.61
        let expected = 2.0 * 2.0 * (std::f64::consts::LN_2 - 20.0);
        assert!((f64::from(v[0]) - expected).abs() < 1e-3, "{v:?}");
    }

    #[test]
    fn softplus_and_the_log_std_bounds() {
        let x = t(&[[-30.0, 0.0], [1.0, 30.0]]);
        let y: Vec<Vec<f32>> = softplus(&x).unwrap().to_vec2().unwrap();
        assert!(y[0][0] >= 0.0 && y[0][0] < 1e-12);
        assert!((y[0][1] - std::f32::consts::LN_2).abs() < 1e-6);
        assert!((f64::from(y[1][0]) - (1.0 + 1f64.exp()).ln()).abs() < 1e-6);
        assert!((y[1][1] - 30.0).abs() < 1e-5);
        let b: Vec<Vec<f32>> = bounded_log_std(&x).unwrap().to_vec2().unwrap();
        assert!((b[0][0] - -5.0).abs() < 1e-5 && (b[1][1] - 2.0).abs() < 1e-5);
        assert!((b[0][1] - -1.5).abs() < 1e-6);
    }
}
