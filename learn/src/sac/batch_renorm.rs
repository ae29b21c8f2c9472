//! Batch renormalisation (Ioffe 2017, "Batch Renormalization: Towards
//! Reducing Minibatch Dependence in Batch-Normalized Models", Algorithm 1),
//! the normalisation CrossQ puts in its critics.
//!
//! In training, with the batch's mean mu_B and standard deviation sigma_B
//! (biased variance, `eps` inside the root) and the running mu, sigma:
//!
//! ```text
//! r = clip(sigma_B / sigma, 1 / r_max, r_max)       (no gradient)
//! d = clip((mu_B - mu) / sigma, -d_max, d_max)      (no gradient)
//! x^ = (x - mu_B) / sigma_B * r + d
//! y = gamma x^ + beta
//! mu <- m mu + (1 - m) mu_B;   sigma^2 <- m sigma^2 + (1 - m) sigma_B^2
//! ```
//!
//! Unclipped, `x^ = (x - mu) / sigma`: the training output is the inference
//! output, with gradients through the batch statistics. Before the warm-up
//! ends r = 1 and d = 0 (plain batch normalisation), as in CrossQ's code
//! (sbx `BatchRenorm`, `warmup_steps`). In inference, `x^ = (x - mu) /
//! sigma`.

use candle_core::{DType, Device, Tensor, Var};

use crate::LearnError;

/// The largest correction factor r (Ioffe 2017's final value).
pub const R_MAX: f64 = 3.0;
/// The largest correction shift d (Ioffe 2017's final value).
pub const D_MAX: f64 = 5.0;
/// Added to every variance before its root (sbx's value).
pub const EPS: f64 = 1e-3;

/// One batch-renormalisation layer over `width` features.
#[derive(Debug, Clone)]
pub struct BatchRenorm {
    /// gamma, `width`, learned
    pub scale: Var,
    /// beta, `width`, learned
    pub shift: Var,
    /// the running mean mu, `width` (a var so that checkpoints carry it;
    /// never given to an optimiser)
    pub running_mean: Var,
    /// the running variance sigma^2, `width`
    pub running_var: Var,
}

/// How a layer normalises.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mode {
    /// batch statistics; the running ones are updated with `momentum`;
    /// `renorm` false during the warm-up (r = 1, d = 0)
    Train {
        /// the running statistics' decay m
        momentum: f64,
        /// whether the r, d correction is on
        renorm: bool,
    },
    /// the running statistics; nothing is updated
    Eval,
}

impl BatchRenorm {
    /// gamma = 1, beta = 0, mu = 0, sigma^2 = 1.
    pub fn new(width: usize, device: &Device) -> Result<Self, LearnError> {
        let ones = || Tensor::ones(width, DType::F32, device);
        let zeros = || Tensor::zeros(width, DType::F32, device);
        Ok(Self {
            scale: Var::from_tensor(&ones()?)?,
            shift: Var::from_tensor(&zeros()?)?,
            running_mean: Var::from_tensor(&zeros()?)?,
            running_var: Var::from_tensor(&ones()?)?,
        })
    }

    /// `x`: `B x width` -> `B x width`.
    pub fn forward(&self, x: &Tensor, mode: Mode) -> candle_core::Result<Tensor> {
        let running_std = self.running_var.as_tensor().affine(1.0, EPS)?.sqrt()?;
        let normalised = match mode {
            Mode::Eval => x
                .broadcast_sub(self.running_mean.as_tensor())?
                .broadcast_div(&running_std)?,
            Mode::Train { momentum, renorm } => {
                let batch_mean = x.mean(0)?;
                let centred = x.broadcast_sub(&batch_mean)?;
                let batch_var = centred.sqr()?.mean(0)?;
                let batch_std = batch_var.affine(1.0, EPS)?.sqrt()?;
                let mut h = centred.broadcast_div(&batch_std)?;
                if renorm {
                    let r = batch_std
                        .detach()
                        .div(&running_std)?
                        .clamp(1.0 / R_MAX, R_MAX)?;
                    let d = batch_mean
                        .detach()
                        .sub(self.running_mean.as_tensor())?
                        .div(&running_std)?
                        .clamp(-D_MAX, D_MAX)?;
                    h = h.broadcast_mul(&r)?.broadcast_add(&d)?;
                }
                let decay = |running: &Var, batch: &Tensor| -> candle_core::Result<()> {
                    let mixed = running
                        .as_tensor()
                        .affine(momentum, 0.0)?
                        .add(&batch.detach().affine(1.0 - momentum, 0.0)?)?;
                    running.set(&mixed.detach())
                };
                decay(&self.running_mean, &batch_mean)?;
                decay(&self.running_var, &batch_var)?;
                h
            }
        };
        normalised
            .broadcast_mul(self.scale.as_tensor())?
            .broadcast_add(self.shift.as_tensor())
    }

    /// The learned vars, named `<prefix>.scale` and `.shift`.
    pub fn trainable_vars(&self, prefix: &str) -> Vec<(String, Var)> {
        vec![
            (format!("{prefix}.scale"), self.scale.clone()),
            (format!("{prefix}.shift"), self.shift.clone()),
        ]
    }

    /// Every var, the running statistics (`.running_mean`, `.running_var`)
    /// after the learned ones.
    pub fn named_vars(&self, prefix: &str) -> Vec<(String, Var)> {
        let mut vars = self.trainable_vars(prefix);
        vars.push((format!("{prefix}.running_mean"), self.running_mean.clone()));
        vars.push((format!("{prefix}.running_var"), self.running_var.clone()));
        vars
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn column(values: &[f32]) -> Tensor {
        Tensor::from_vec(values.to_vec(), (values.len(), 1), &Device::Cpu).unwrap()
    }

    fn values(t: &Tensor) -> Vec<f32> {
        t.flatten_all().unwrap().to_vec1().unwrap()
    }

    fn set(var: &Var, v: f32) {
        var.set(&Tensor::new(&[v], &Device::Cpu).unwrap()).unwrap();
    }

    #[test]
    fn during_the_warm_up_it_is_batch_normalisation() {
        let layer = BatchRenorm::new(1, &Device::Cpu).unwrap();
        set(&layer.running_mean, 10.0);
        let x = column(&[1.0, 2.0, 3.0, 6.0]);
        let y = values(
            &layer
                .forward(
                    &x,
                    Mode::Train {
                        momentum: 0.9,
                        renorm: false,
                    },
                )
                .unwrap(),
        );
        // mean 3, biased variance (4 + 1 + 0 + 9) / 4 = 3.5
        let std = (3.5f64 + EPS).sqrt();
        for (yi, xi) in y.iter().zip([1.0, 2.0, 3.0, 6.0]) {
            assert!((f64::from(*yi) - (xi - 3.0) / std).abs() < 1e-5, "{y:?}");
        }
        // running: 0.9 * 10 + 0.1 * 3 = 9.3; 0.9 * 1 + 0.1 * 3.5 = 1.25
        assert!((values(layer.running_mean.as_tensor())[0] - 9.3).abs() < 1e-5);
        assert!((values(layer.running_var.as_tensor())[0] - 1.25).abs() < 1e-5);
    }

    #[test]
    fn renormalised_training_output_equals_the_inference_output_within_the_clip() {
        let layer = BatchRenorm::new(1, &Device::Cpu).unwrap();
        // running mu 2.5, sigma^2 2.0: r = sqrt(3.5 / 2) < 3, d = 0.5 / sqrt(2) < 5
        set(&layer.running_mean, 2.5);
        set(&layer.running_var, 2.0);
        let x = column(&[1.0, 2.0, 3.0, 6.0]);
        let eval = values(&layer.forward(&x, Mode::Eval).unwrap());
        let std = (2.0f64 + EPS).sqrt();
        for (e, xi) in eval.iter().zip([1.0, 2.0, 3.0, 6.0]) {
            assert!((f64::from(*e) - (xi - 2.5) / std).abs() < 1e-5, "{eval:?}");
        }
        let train = values(
            &layer
                .forward(
                    &x,
                    Mode::Train {
                        momentum: 0.99,
                        renorm: true,
                    },
                )
                .unwrap(),
        );
        for (t, e) in train.iter().zip(&eval) {
            assert!((t - e).abs() < 1e-5, "train {train:?} eval {eval:?}");
        }
    }

    #[test]
    fn the_correction_is_clipped_and_carries_no_gradient() {
        let layer = BatchRenorm::new(1, &Device::Cpu).unwrap();
        // running sigma^2 1e-4: sigma_B / sigma is far above 3, so r = 3;
        // (mu_B - mu) / sigma = 3 / 0.033 is far above 5, so d = 5
        set(&layer.running_var, 1e-4);
        let x = Var::from_tensor(&column(&[1.0, 2.0, 3.0, 6.0])).unwrap();
        let y = layer
            .forward(
                x.as_tensor(),
                Mode::Train {
                    momentum: 0.5,
                    renorm: true,
                },
            )
            .unwrap();
        let std = (3.5f64 + EPS).sqrt();
        let out = values(&y);
        for (yi, xi) in out.iter().zip([1.0, 2.0, 3.0, 6.0]) {
            let expected = (xi - 3.0) / std * R_MAX + D_MAX;
            assert!((f64::from(*yi) - expected).abs() < 1e-4, "{out:?}");
        }
        // sum(y) = sum(x^_B) * 3 + 4 * 5: its gradient through the batch
        // statistics sums to zero per feature whatever r and d are, because
        // r and d are constants and sum(x^_B) = 0 for every x.
        let grads = y.sum_all().unwrap().backward().unwrap();
        let g = values(grads.get(x.as_tensor()).unwrap());
        assert!(g.iter().all(|v| v.abs() < 1e-4), "{g:?}");
        // and the shift's gradient is the batch size
        let gb = values(grads.get(layer.shift.as_tensor()).unwrap());
        assert!((gb[0] - 4.0).abs() < 1e-5, "{gb:?}");
    }
}
