//! Adam, with its moments exposed so that checkpoints can carry them, and
//! gradient-norm clipping (candle has none).

use candle_core::backprop::GradStore;
use candle_core::{Tensor, Var};

use crate::LearnError;

/// The gradient of each var (zeros where the loss does not depend on it),
/// detached from candle's op graph.
///
/// candle builds the gradients out of tensor ops, so a gradient straight
/// from `backward` still references the whole forward and backward graph
/// of its step, activations included. Anything kept across steps (Adam's
/// moments) must hold plain values: a moment computed from an undetached
/// gradient keeps every earlier step's graph alive, and memory grows by
/// megabytes per update.
pub fn gradients(grads: &GradStore, vars: &[(String, Var)]) -> Result<Vec<Tensor>, LearnError> {
    vars.iter()
        .map(|(_, var)| match grads.get(var.as_tensor()) {
            Some(g) => Ok(g.detach()),
            None => Ok(var.as_tensor().zeros_like()?),
        })
        .collect()
}

/// Global L2 norm of `grads`, `sqrt(sum_i sum_j g_ij^2)`.
pub fn global_norm(grads: &[Tensor]) -> Result<f64, LearnError> {
    let mut sum = 0.0f64;
    for g in grads {
        sum += f64::from(g.sqr()?.sum_all()?.to_scalar::<f32>()?);
    }
    Ok(sum.sqrt())
}

/// Rescales `grads` so that their global norm is at most `max_norm`:
/// `g <- g * min(1, max_norm / (norm + 1e-6))`. Returns the norm before.
pub fn clip_grad_norm(grads: &mut [Tensor], max_norm: f64) -> Result<f64, LearnError> {
    let norm = global_norm(grads)?;
    let scale = max_norm / (norm + 1e-6);
    if scale < 1.0 {
        for g in grads.iter_mut() {
            *g = g.affine(scale, 0.0)?;
        }
    }
    Ok(norm)
}

/// Whether `learning_rate` lies in (0, 1): the one range `[ppo]`, `[sac]`
/// and a curriculum stage accept.
pub fn is_learning_rate(learning_rate: f64) -> bool {
    learning_rate > 0.0 && learning_rate < 1.0
}

/// A learning rate must lie in (0, 1) ([`is_learning_rate`]).
pub fn check_learning_rate(learning_rate: f64) -> Result<(), LearnError> {
    if is_learning_rate(learning_rate) {
        Ok(())
    } else {
        Err(LearnError::Config(format!(
            "learning_rate = {learning_rate}: must be in (0, 1)"
        )))
    }
}

/// Adam (Kingma and Ba), with bias correction, no weight decay.
#[derive(Debug, Clone)]
pub struct Adam {
    vars: Vec<(String, Var)>,
    /// first moments, one per var
    pub m: Vec<Tensor>,
    /// second moments, one per var
    pub v: Vec<Tensor>,
    /// updates taken
    pub step: u64,
    /// step size
    pub learning_rate: f64,
    /// moment decay rates
    pub betas: (f64, f64),
    /// denominator guard
    pub eps: f64,
}

impl Adam {
    /// Adam over `vars` with zero moments.
    pub fn new(vars: Vec<(String, Var)>, learning_rate: f64) -> Result<Self, LearnError> {
        let zeros = vars
            .iter()
            .map(|(_, v)| v.as_tensor().zeros_like())
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            vars,
            m: zeros.clone(),
            v: zeros,
            step: 0,
            learning_rate,
            betas: (0.9, 0.999),
            eps: 1e-8,
        })
    }

    /// The vars, in the order of the moments.
    pub fn vars(&self) -> &[(String, Var)] {
        &self.vars
    }

    /// One update with `grads` (one per var, in order):
    ///
    /// ```text
    /// m <- b1 m + (1 - b1) g;   v <- b2 v + (1 - b2) g^2
    /// theta <- theta - lr * (m / (1 - b1^t)) / (sqrt(v / (1 - b2^t)) + eps)
    /// ```
    ///
    /// The gradients are detached first and the moments stay detached, so
    /// the optimiser's state never holds an op graph whatever the caller
    /// passes (see [`gradients`]).
    pub fn apply(&mut self, grads: &[Tensor]) -> Result<(), LearnError> {
        assert_eq!(grads.len(), self.vars.len(), "adam: one gradient per var");
        self.step += 1;
        let (b1, b2) = self.betas;
        let t = self.step as i32;
        let correction1 = 1.0 - b1.powi(t);
        let correction2 = 1.0 - b2.powi(t);
        for (k, g) in grads.iter().enumerate() {
            let g = g.detach();
            self.m[k] = (self.m[k].affine(b1, 0.0)? + g.affine(1.0 - b1, 0.0)?)?;
            self.v[k] = (self.v[k].affine(b2, 0.0)? + g.sqr()?.affine(1.0 - b2, 0.0)?)?;
            let m_hat = self.m[k].affine(1.0 / correction1, 0.0)?;
            let denom = self.v[k]
                .affine(1.0 / correction2, 0.0)?
                .sqrt()?
                .affine(1.0, self.eps)?;
            let update = m_hat.div(&denom)?.affine(self.learning_rate, 0.0)?;
            let var = &self.vars[k].1;
            // `set` copies the values into the var's storage; the var keeps
            // no reference to `update`.
            var.set(&var.as_tensor().detach().sub(&update)?)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use candle_core::Device;

    use super::*;

    #[test]
    fn clipping_rescales_to_the_limit_and_keeps_direction() {
        let dev = Device::Cpu;
        let mut grads = vec![
            Tensor::new(&[3.0f32, 0.0], &dev).unwrap(),
            Tensor::new(&[[0.0f32, 4.0]], &dev).unwrap(),
        ];
        let before = clip_grad_norm(&mut grads, 1.0).unwrap();
        assert!((before - 5.0).abs() < 1e-6);
        assert!((global_norm(&grads).unwrap() - 1.0).abs() < 1e-5);
        let a: Vec<f32> = grads[0].to_vec1().unwrap();
        let b: Vec<Vec<f32>> = grads[1].to_vec2().unwrap();
        assert!((a[0] - 0.6).abs() < 1e-5 && a[1] == 0.0);
        assert!((b[0][1] - 0.8).abs() < 1e-5);
        // under the limit: untouched
        let mut small = vec![Tensor::new(&[0.3f32, 0.4], &dev).unwrap()];
        clip_grad_norm(&mut small, 1.0).unwrap();
        assert_eq!(small[0].to_vec1::<f32>().unwrap(), vec![0.3, 0.4]);
    }

    #[test]
    fn adam_first_steps_match_hand_computation() {
        // With bias correction the first step is lr * g / (|g| + eps) = lr * sign(g).
        let dev = Device::Cpu;
        let var = Var::from_tensor(&Tensor::new(&[1.0f32, -2.0], &dev).unwrap()).unwrap();
        let mut adam = Adam::new(vec![("x".into(), var.clone())], 0.1).unwrap();
        adam.apply(&[Tensor::new(&[0.5f32, -4.0], &dev).unwrap()])
            .unwrap();
        let x: Vec<f32> = var.as_tensor().to_vec1().unwrap();
        assert!(
            (x[0] - 0.9).abs() < 1e-6 && (x[1] + 1.9).abs() < 1e-6,
            "{x:?}"
        );
        // second step, gradient 1 for x[0]: m = 0.9*0.05 + 0.1 = 0.145, m_hat = 0.145/0.19;
        // v = 0.999*0.00025 + 0.001 = 0.00124975, v_hat = v/0.001999
        adam.apply(&[Tensor::new(&[1.0f32, 0.0], &dev).unwrap()])
            .unwrap();
        let m_hat = 0.145 / 0.19;
        let v_hat = 0.001_249_75 / (1.0 - 0.999f64.powi(2));
        let expect = 0.9 - 0.1 * m_hat / (v_hat.sqrt() + 1e-8);
        let x: Vec<f32> = var.as_tensor().to_vec1().unwrap();
        assert!(
            (f64::from(x[0]) - expect).abs() < 1e-5,
            "{} vs {expect}",
            x[0]
        );
    }

    #[test]
    fn adam_minimises_a_quadratic() {
        let dev = Device::Cpu;
        let var = Var::from_tensor(&Tensor::new(&[3.0f32, -2.0], &dev).unwrap()).unwrap();
        let mut adam = Adam::new(vec![("x".into(), var.clone())], 0.05).unwrap();
        for _ in 0..500 {
            let loss = var.as_tensor().sqr().unwrap().sum_all().unwrap();
            let grads = loss.backward().unwrap();
            let g = gradients(&grads, adam.vars()).unwrap();
            adam.apply(&g).unwrap();
        }
        let x: Vec<f32> = var.as_tensor().to_vec1().unwrap();
        assert!(x.iter().all(|v| v.abs() < 0.05), "{x:?}");
    }
}
