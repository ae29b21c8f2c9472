//! SAC's twin critics in either form:
//!
//! - **targeted** (Haarnoja et al. 2018): two tanh MLPs and their
//!   Polyak-averaged copies, which give the Bellman target;
//! - **CrossQ** (Bhatt et al., ICLR 2024): two ReLU MLPs with batch
//!   renormalisation on the input and after every hidden layer, no target
//!   copies. The target comes from the same critics in the same forward
//!   pass: (s, a) and (s', a') rows go through together, so that the
//!   normalisation sees both distributions, and the (s', a') half is
//!   detached.

use candle_core::{Device, Tensor, Var};
use rand_chacha::ChaCha8Rng;

use super::batch_renorm::{BatchRenorm, Mode};
use crate::LearnError;
use crate::mlp::Mlp;

/// A critic with batch renormalisation: input -> BRN -> [dense -> BRN ->
/// ReLU]* -> dense -> Q.
#[derive(Debug, Clone)]
pub struct BrnCritic {
    /// the dense layers, input first (the last one outputs Q)
    pub dense: Mlp,
    /// the normalisation of the input, then of each hidden layer
    pub norms: Vec<BatchRenorm>,
}

impl BrnCritic {
    /// Layer widths `sizes[0] -> ... -> sizes[last]` (`sizes[last]` = 1),
    /// dense weights drawn as [`Mlp::new`] draws them (gain 1).
    pub fn new(sizes: &[usize], rng: &mut ChaCha8Rng, device: &Device) -> Result<Self, LearnError> {
        let dense = Mlp::new(sizes, 1.0, rng, device)?;
        let norms = sizes[..sizes.len() - 1]
            .iter()
            .map(|&w| BatchRenorm::new(w, device))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { dense, norms })
    }

    /// `x`: `B x in` -> Q, `B`.
    pub fn forward(&self, x: &Tensor, mode: Mode) -> candle_core::Result<Tensor> {
        let mut h = self.norms[0].forward(x, mode)?;
        let last = self.dense.layers.len() - 1;
        for (k, layer) in self.dense.layers.iter().enumerate() {
            h = h
                .matmul(layer.weight.as_tensor())?
                .broadcast_add(layer.bias.as_tensor())?;
            if k < last {
                h = self.norms[k + 1].forward(&h, mode)?.relu()?;
            }
        }
        h.flatten_all()
    }

    /// The learned vars: dense `<prefix>.<k>.weight`/`.bias`, then
    /// `<prefix>.norm<k>.scale`/`.shift`.
    pub fn trainable_vars(&self, prefix: &str) -> Vec<(String, Var)> {
        let mut vars = self.dense.named_vars(prefix);
        for (k, norm) in self.norms.iter().enumerate() {
            vars.extend(norm.trainable_vars(&format!("{prefix}.norm{k}")));
        }
        vars
    }

    /// The learned vars and the running statistics.
    pub fn named_vars(&self, prefix: &str) -> Vec<(String, Var)> {
        let mut vars = self.dense.named_vars(prefix);
        for (k, norm) in self.norms.iter().enumerate() {
            vars.extend(norm.named_vars(&format!("{prefix}.norm{k}")));
        }
        vars
    }
}

/// The twin critics.
#[derive(Debug, Clone)]
pub enum Critics {
    /// tanh MLPs with Polyak-averaged targets
    Targeted {
        /// the critics being learned
        online: [Mlp; 2],
        /// their averaged copies
        target: [Mlp; 2],
    },
    /// batch-renormalised critics, no targets
    CrossQ {
        /// the critics being learned
        online: [BrnCritic; 2],
    },
}

/// A deep copy of `mlp` (a `Var`'s clone shares its storage).
fn deep_copy(mlp: &Mlp) -> Result<Mlp, LearnError> {
    let mut copy = mlp.clone();
    for layer in &mut copy.layers {
        layer.weight = Var::from_tensor(&layer.weight.as_tensor().copy()?)?;
        layer.bias = Var::from_tensor(&layer.bias.as_tensor().copy()?)?;
    }
    Ok(copy)
}

/// `target <- (1 - tau) target + tau source`, var by var.
fn polyak(target: &Mlp, source: &Mlp, tau: f64) -> Result<(), LearnError> {
    for (t, s) in target
        .named_vars("t")
        .iter()
        .zip(source.named_vars("s").iter())
    {
        let mixed =
            t.1.as_tensor()
                .affine(1.0 - tau, 0.0)?
                .add(&s.1.as_tensor().affine(tau, 0.0)?)?;
        t.1.set(&mixed.detach())?;
    }
    Ok(())
}

impl Critics {
    /// Fresh targeted critics of widths `sizes` (targets equal to them).
    pub fn targeted(
        sizes: &[usize],
        rng: &mut ChaCha8Rng,
        device: &Device,
    ) -> Result<Self, LearnError> {
        let online = [
            Mlp::new(sizes, 1.0, rng, device)?,
            Mlp::new(sizes, 1.0, rng, device)?,
        ];
        let target = [deep_copy(&online[0])?, deep_copy(&online[1])?];
        Ok(Self::Targeted { online, target })
    }

    /// Fresh CrossQ critics of widths `sizes`.
    pub fn crossq(
        sizes: &[usize],
        rng: &mut ChaCha8Rng,
        device: &Device,
    ) -> Result<Self, LearnError> {
        Ok(Self::CrossQ {
            online: [
                BrnCritic::new(sizes, rng, device)?,
                BrnCritic::new(sizes, rng, device)?,
            ],
        })
    }

    /// The vars the critic optimiser updates, `q1.*` then `q2.*`.
    pub fn trainable_vars(&self) -> Vec<(String, Var)> {
        match self {
            Self::Targeted { online, .. } => {
                let mut vars = online[0].named_vars("q1");
                vars.extend(online[1].named_vars("q2"));
                vars
            }
            Self::CrossQ { online } => {
                let mut vars = online[0].trainable_vars("q1");
                vars.extend(online[1].trainable_vars("q2"));
                vars
            }
        }
    }

    /// Every var a checkpoint holds: the trainable ones, then the targets
    /// (`q1_target.*`, `q2_target.*`) or the running statistics.
    pub fn named_vars(&self) -> Vec<(String, Var)> {
        match self {
            Self::Targeted { online, target } => {
                let mut vars = online[0].named_vars("q1");
                vars.extend(online[1].named_vars("q2"));
                vars.extend(target[0].named_vars("q1_target"));
                vars.extend(target[1].named_vars("q2_target"));
                vars
            }
            Self::CrossQ { online } => {
                let mut vars = online[0].named_vars("q1");
                vars.extend(online[1].named_vars("q2"));
                vars
            }
        }
    }

    /// Q1 and Q2 of `x` = [observation, action] rows, `B` each, from the
    /// learned critics; CrossQ's in inference mode (the actor's loss).
    pub fn q_values(&self, x: &Tensor) -> candle_core::Result<[Tensor; 2]> {
        match self {
            Self::Targeted { online, .. } => Ok([
                online[0].forward(x)?.flatten_all()?,
                online[1].forward(x)?.flatten_all()?,
            ]),
            Self::CrossQ { online } => Ok([
                online[0].forward(x, Mode::Eval)?,
                online[1].forward(x, Mode::Eval)?,
            ]),
        }
    }

    /// The critics' estimates for the Bellman step: (Q1, Q2) of `now`
    /// (with gradients) and (Q1', Q2') of `next` (detached), `B` each.
    /// Targeted: the learned critics on `now`, the targets on `next`.
    /// CrossQ: both halves in one training-mode pass over `[now; next]`.
    pub fn bellman_pair(
        &self,
        now: &Tensor,
        next: &Tensor,
        mode: Mode,
    ) -> candle_core::Result<([Tensor; 2], [Tensor; 2])> {
        match self {
            Self::Targeted { online, target } => {
                let q = |m: &Mlp, x: &Tensor| m.forward(x)?.flatten_all();
                Ok((
                    [q(&online[0], now)?, q(&online[1], now)?],
                    [q(&target[0], next)?.detach(), q(&target[1], next)?.detach()],
                ))
            }
            Self::CrossQ { online } => {
                let b = now.dim(0)?;
                let joint = Tensor::cat(&[now, next], 0)?;
                let q1 = online[0].forward(&joint, mode)?;
                let q2 = online[1].forward(&joint, mode)?;
                Ok((
                    [q1.narrow(0, 0, b)?, q2.narrow(0, 0, b)?],
                    [q1.narrow(0, b, b)?.detach(), q2.narrow(0, b, b)?.detach()],
                ))
            }
        }
    }

    /// Moves the targets toward the critics (targeted); nothing for CrossQ.
    pub fn soft_update(&self, tau: f64) -> Result<(), LearnError> {
        if let Self::Targeted { online, target } = self {
            for (t, c) in target.iter().zip(online) {
                polyak(t, c, tau)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn crossq_critics_normalise_the_joint_batch_and_detach_the_next_half() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let critics = Critics::crossq(&[3, 8, 1], &mut rng, &Device::Cpu).unwrap();
        let now = Var::from_tensor(
            &Tensor::new(&[[0.0f32, 1.0, 2.0], [1.0, -1.0, 0.5]], &Device::Cpu).unwrap(),
        )
        .unwrap();
        let next = Var::from_tensor(
            &Tensor::new(&[[5.0f32, 5.0, 5.0], [4.0, 6.0, 5.0]], &Device::Cpu).unwrap(),
        )
        .unwrap();
        let mode = Mode::Train {
            momentum: 0.0,
            renorm: false,
        };
        let ([q1, _], [n1, _]) = critics
            .bellman_pair(now.as_tensor(), next.as_tensor(), mode)
            .unwrap();
        assert_eq!(q1.dims(), [2]);
        assert_eq!(n1.dims(), [2]);
        // momentum 0: the running input mean is the mean of all four rows
        let Critics::CrossQ { online } = &critics else {
            unreachable!()
        };
        let mean: Vec<f32> = online[0].norms[0]
            .running_mean
            .as_tensor()
            .to_vec1()
            .unwrap();
        for (m, expected) in mean.iter().zip([2.5f32, 2.75, 3.125]) {
            assert!((m - expected).abs() < 1e-5, "{mean:?}");
        }
        // the same rows, one pass: the halves are those of the joint pass
        let joint = Tensor::cat(&[now.as_tensor(), next.as_tensor()], 0).unwrap();
        let all: Vec<f32> = online[0].forward(&joint, mode).unwrap().to_vec1().unwrap();
        let got: Vec<f32> = Tensor::cat(&[&q1, &n1], 0).unwrap().to_vec1().unwrap();
        for (a, g) in all.iter().zip(&got) {
            assert!((a - g).abs() < 1e-5, "{all:?} {got:?}");
        }
        // gradients reach the inputs of the "now" rows only through the
        // first half (the next half is detached)
        let loss = q1.sum_all().unwrap().add(&n1.sum_all().unwrap()).unwrap();
        let grads = loss.backward().unwrap();
        assert!(grads.get(now.as_tensor()).is_some());
        // `next` still influences q1 through the batch statistics, so its
        // gradient may exist; the detached half adds nothing: check that
        // the loss without it has the same gradient on a dense weight.
        let w = &online[0].dense.layers[0].weight;
        let with_next: Vec<f32> = grads
            .get(w.as_tensor())
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        let ([q1b, _], _) = critics
            .bellman_pair(now.as_tensor(), next.as_tensor(), mode)
            .unwrap();
        let grads = q1b.sum_all().unwrap().backward().unwrap();
        let without: Vec<f32> = grads
            .get(w.as_tensor())
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        for (a, b) in with_next.iter().zip(&without) {
            assert!((a - b).abs() < 1e-5);
        }
        // the optimiser's vars leave the running statistics out
        let trainable = critics.trainable_vars();
        assert!(trainable.iter().all(|(n, _)| !n.contains("running")));
        assert_eq!(critics.named_vars().len(), trainable.len() + 2 * 2 * 2);
    }

    #[test]
    fn targeted_critics_keep_their_checkpoint_names() {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let critics = Critics::targeted(&[3, 4, 1], &mut rng, &Device::Cpu).unwrap();
        let names: Vec<String> = critics.named_vars().into_iter().map(|(n, _)| n).collect();
        assert_eq!(names[0], "q1.0.weight");
        assert!(names.contains(&"q2_target.1.bias".to_string()));
        assert_eq!(critics.trainable_vars().len(), 8);
    }
}
