//! The multilayer perceptron every learner builds its networks from, and
//! the standard normal draws their sampling uses.

use candle_core::{DType, Device, Tensor, Var};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

use crate::LearnError;
use crate::tanh::TanhImpl;

/// `t` (`rows x cols`) with `extra` rows of zeros below: a layer's weight,
/// or its optimiser moments, given `extra` more inputs that it ignores.
pub fn with_zero_rows(t: &Tensor, extra: usize) -> candle_core::Result<Tensor> {
    let zeros = Tensor::zeros((extra, t.dim(1)?), t.dtype(), t.device())?;
    Tensor::cat(&[t, &zeros], 0)
}

/// A dense layer, `y = x W + b`, `W` stored `in x out`.
#[derive(Debug, Clone)]
pub struct Dense {
    /// `in x out`
    pub weight: Var,
    /// `out`
    pub bias: Var,
}

/// A multilayer perceptron with tanh between layers and a linear output.
#[derive(Debug, Clone)]
pub struct Mlp {
    /// the layers, input first
    pub layers: Vec<Dense>,
    /// which tanh runs between the layers
    pub tanh: TanhImpl,
}

impl Mlp {
    /// Layer widths `sizes[0] -> sizes[1] -> ...`. Weights are uniform with
    /// variance `gain^2 / fan_in` (gain 1 for hidden layers, `output_gain`
    /// for the last), biases zero, drawn from `rng`.
    pub fn new(
        sizes: &[usize],
        output_gain: f64,
        rng: &mut ChaCha8Rng,
        device: &Device,
    ) -> Result<Self, LearnError> {
        let mut layers = Vec::new();
        for (k, pair) in sizes.windows(2).enumerate() {
            let (fan_in, fan_out) = (pair[0], pair[1]);
            let gain = if k + 2 == sizes.len() {
                output_gain
            } else {
                1.0
            };
            let half_width = gain * (3.0 / fan_in as f64).sqrt();
            let weights: Vec<f32> = (0..fan_in * fan_out)
                .map(|_| rng.random_range(-half_width..=half_width) as f32)
                .collect();
            layers.push(Dense {
                weight: Var::from_tensor(&Tensor::from_vec(weights, (fan_in, fan_out), device)?)?,
                bias: Var::from_tensor(&Tensor::zeros(fan_out, DType::F32, device)?)?,
            });
        }
        Ok(Self {
            layers,
            tanh: TanhImpl::Libm,
        })
    }

    /// The same network evaluating `tanh` between its layers.
    pub fn with_tanh(self, tanh: TanhImpl) -> Self {
        Self { tanh, ..self }
    }

    /// `x`: `B x in` -> `B x out`.
    pub fn forward(&self, x: &Tensor) -> candle_core::Result<Tensor> {
        let mut h = x.clone();
        for (k, layer) in self.layers.iter().enumerate() {
            h = h
                .matmul(layer.weight.as_tensor())?
                .broadcast_add(layer.bias.as_tensor())?;
            if k + 1 < self.layers.len() {
                h = self.tanh.apply(&h)?;
            }
        }
        Ok(h)
    }

    /// The layers' vars named `<prefix>.<layer>.weight` and `.bias`.
    pub fn named_vars(&self, prefix: &str) -> Vec<(String, Var)> {
        self.layers
            .iter()
            .enumerate()
            .flat_map(|(k, l)| {
                [
                    (format!("{prefix}.{k}.weight"), l.weight.clone()),
                    (format!("{prefix}.{k}.bias"), l.bias.clone()),
                ]
            })
            .collect()
    }
}

/// One standard normal draw (Box-Muller), deterministic for a given `rng`.
pub fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>(); // (0, 1]
    let u2: f64 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;

    #[test]
    fn standard_normal_has_unit_moments() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let xs: Vec<f64> = (0..20_000).map(|_| standard_normal(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        assert!(
            mean.abs() < 0.03 && (var - 1.0).abs() < 0.05,
            "{mean} {var}"
        );
    }
}
