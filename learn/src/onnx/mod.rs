//! A trained policy's deterministic actor as one ONNX graph: the
//! observation normaliser, the network and the bound on the action, so
//! that a runtime outside quadwalk (onnxruntime, a robot's computer) gives
//! the actions `quadwalk rollout` takes.
//!
//! The graph, for `observation` (`float`, batch x O, the raw values the
//! task observes) to `action` (`float`, batch x A, in [-1, 1]):
//!
//! ```text
//! z  = clip((double(observation) - mean) / std, -obs_clip, obs_clip)   in double,
//!      as quadwalk's normaliser computes it (std = sqrt(var + 1e-8))
//! h  = tanh(float(z) W_0 + b_0) ... tanh(h W_{n-2} + b_{n-2})
//! a  = bound(h W_{n-1} + b_{n-1})   bound: clip to [-1, 1] (PPO's mean) or tanh (SAC's)
//! ```
//!
//! ONNX IR version 8, operator set 17 (Cast, Sub, Div, Clip, MatMul, Add,
//! Tanh): onnxruntime 1.14 and later read it.

mod proto;

use proto::Message;

use crate::LearnError;

/// ONNX's IR version of the model written.
pub const IR_VERSION: u64 = 8;
/// The ONNX operator set the graph uses.
pub const OPSET: u64 = 17;
/// The graph's input: the raw observation, `float`, batch x O.
pub const INPUT: &str = "observation";
/// The graph's output: the action, `float`, batch x A.
pub const OUTPUT: &str = "action";

/// `TensorProto.DataType`
const FLOAT: u64 = 1;
const DOUBLE: u64 = 11;
/// `AttributeProto.AttributeType.INT`
const ATTRIBUTE_INT: u64 = 2;

/// How the network's last layer becomes an action in [-1, 1].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ActionBound {
    /// clipped (PPO's Gaussian mean)
    Clip,
    /// squashed by tanh (SAC's)
    Tanh,
}

/// One dense layer, `y = x W + b`.
#[derive(Debug, Clone, PartialEq)]
pub struct DenseLayer {
    /// inputs
    pub inputs: usize,
    /// outputs
    pub outputs: usize,
    /// `W`, `inputs x outputs`, row-major
    pub weight: Vec<f32>,
    /// `b`, `outputs`
    pub bias: Vec<f32>,
}

impl DenseLayer {
    /// The layer's values, its outputs cut to the first `outputs` (SAC's
    /// actor gives means, then log-stds: the action needs the means).
    pub fn of(layer: &crate::mlp::Dense, outputs: Option<usize>) -> Result<Self, LearnError> {
        let weight = layer.weight.as_tensor();
        let (inputs, all) = weight.dims2()?;
        let outputs = outputs.unwrap_or(all).min(all);
        Ok(Self {
            inputs,
            outputs,
            weight: weight.narrow(1, 0, outputs)?.flatten_all()?.to_vec1()?,
            bias: layer.bias.as_tensor().narrow(0, 0, outputs)?.to_vec1()?,
        })
    }
}

/// The layers of `mlp`, the last one's outputs cut to `outputs`.
pub fn layers_of(
    mlp: &crate::mlp::Mlp,
    outputs: Option<usize>,
) -> Result<Vec<DenseLayer>, LearnError> {
    let last = mlp.layers.len().saturating_sub(1);
    mlp.layers
        .iter()
        .enumerate()
        .map(|(k, l)| DenseLayer::of(l, if k == last { outputs } else { None }))
        .collect()
}

/// The ONNX model's metadata: what the policy is.
pub fn metadata_of(learner: &dyn crate::Algorithm) -> Vec<(String, String)> {
    vec![
        ("quadwalk.algo".into(), learner.name().into()),
        ("quadwalk.iteration".into(), learner.iteration().to_string()),
        ("quadwalk.obs_size".into(), learner.obs_size().to_string()),
        (
            "quadwalk.action_size".into(),
            learner.action_size().to_string(),
        ),
    ]
}

/// What the deterministic actor computes, in the terms of the graph.
#[derive(Debug, Clone, PartialEq)]
pub struct ActorGraph {
    /// the normaliser's running mean, per observation value
    pub obs_mean: Vec<f64>,
    /// the normaliser's `sqrt(var + 1e-8)`, per observation value
    pub obs_std: Vec<f64>,
    /// normalised values are clipped to +- this
    pub obs_clip: f64,
    /// the network, input first; tanh between layers
    pub layers: Vec<DenseLayer>,
    /// the bound on the last layer's output
    pub bound: ActionBound,
    /// `key = value` pairs stored as the model's metadata (the policy's
    /// algorithm, iteration, observation layout)
    pub metadata: Vec<(String, String)>,
}

impl ActorGraph {
    /// The graph of `layers` behind `normalizer`.
    pub fn new(
        normalizer: &crate::normalizer::ObsNormalizer,
        layers: Vec<DenseLayer>,
        bound: ActionBound,
        metadata: Vec<(String, String)>,
    ) -> Self {
        Self {
            obs_mean: normalizer.mean.clone(),
            obs_std: normalizer.std(),
            obs_clip: normalizer.clip,
            layers,
            bound,
            metadata,
        }
    }

    /// Observation values the graph takes.
    pub fn obs_size(&self) -> usize {
        self.obs_mean.len()
    }

    /// Action values the graph gives.
    pub fn action_size(&self) -> usize {
        self.layers.last().map_or(0, |l| l.outputs)
    }

    /// Checks that the sizes chain: normaliser, layers, biases.
    pub fn check(&self) -> Result<(), LearnError> {
        let bad = |what: String| Err(LearnError::Mismatch(format!("actor graph: {what}")));
        if self.obs_std.len() != self.obs_mean.len() {
            return bad(format!(
                "{} normaliser means, {} deviations",
                self.obs_mean.len(),
                self.obs_std.len()
            ));
        }
        let mut width = self.obs_size();
        for (k, layer) in self.layers.iter().enumerate() {
            if layer.inputs != width
                || layer.weight.len() != layer.inputs * layer.outputs
                || layer.bias.len() != layer.outputs
            {
                return bad(format!(
                    "layer {k} takes {} from {width} values, with {} weights and {} biases for {} outputs",
                    layer.inputs,
                    layer.weight.len(),
                    layer.bias.len(),
                    layer.outputs
                ));
            }
            width = layer.outputs;
        }
        if self.layers.is_empty() {
            return bad("no layers".into());
        }
        Ok(())
    }

    /// The actions for raw observations `k x O`, computed as the graph
    /// defines them (a reference for tests; sums in input order).
    pub fn act(&self, raw_obs: &[f32]) -> Vec<f32> {
        let o = self.obs_size();
        let mut actions = Vec::new();
        for row in raw_obs.chunks_exact(o) {
            let mut h: Vec<f32> = row
                .iter()
                .zip(self.obs_mean.iter().zip(&self.obs_std))
                .map(|(&x, (&mean, &std))| {
                    ((f64::from(x) - mean) / std).clamp(-self.obs_clip, self.obs_clip) as f32
                })
                .collect();
            for (k, layer) in self.layers.iter().enumerate() {
                let mut y = layer.bias.clone();
                for (i, &x) in h.iter().enumerate() {
                    let w = &layer.weight[i * layer.outputs..(i + 1) * layer.outputs];
                    for (y, &w) in y.iter_mut().zip(w) {
                        *y += x * w;
                    }
                }
                if k + 1 < self.layers.len() {
                    y.iter_mut().for_each(|v| *v = v.tanh());
                }
                h = y;
            }
            match self.bound {
                ActionBound::Clip => h.iter_mut().for_each(|v| *v = v.clamp(-1.0, 1.0)),
                ActionBound::Tanh => h.iter_mut().for_each(|v| *v = v.tanh()),
            }
            actions.extend(h);
        }
        actions
    }

    /// The ONNX model (`ModelProto`'s bytes); `producer_version` names
    /// the quadwalk that wrote it.
    pub fn to_onnx(&self, producer_version: &str) -> Result<Vec<u8>, LearnError> {
        self.check()?;
        let mut graph = Message::new();
        let mut initializers = Vec::new();
        let mut nodes = Vec::new();
        let mut node = |op: &str, inputs: &[&str], output: &str, attributes: &[Message]| {
            let mut n = Message::new();
            for input in inputs {
                n = n.string(1, input);
            }
            n = n.string(2, output).string(3, output).string(4, op);
            for a in attributes {
                n = n.message(5, a);
            }
            nodes.push(n);
        };
        let cast_to = |to| {
            Message::new()
                .string(1, "to")
                .int(20, ATTRIBUTE_INT)
                .int(3, to)
        };

        initializers.push(double_tensor(
            "obs_mean",
            &[self.obs_size()],
            &self.obs_mean,
        ));
        initializers.push(double_tensor("obs_std", &[self.obs_size()], &self.obs_std));
        initializers.push(double_tensor("obs_clip_min", &[], &[-self.obs_clip]));
        initializers.push(double_tensor("obs_clip_max", &[], &[self.obs_clip]));
        node("Cast", &[INPUT], "obs_double", &[cast_to(DOUBLE)]);
        node("Sub", &["obs_double", "obs_mean"], "obs_centred", &[]);
        node("Div", &["obs_centred", "obs_std"], "obs_scaled", &[]);
        node(
            "Clip",
            &["obs_scaled", "obs_clip_min", "obs_clip_max"],
            "obs_clipped",
            &[],
        );
        node("Cast", &["obs_clipped"], "h0", &[cast_to(FLOAT)]);
        let last = self.layers.len() - 1;
        for (k, layer) in self.layers.iter().enumerate() {
            let (w, b) = (format!("layer{k}.weight"), format!("layer{k}.bias"));
            initializers.push(float_tensor(
                &w,
                &[layer.inputs, layer.outputs],
                &layer.weight,
            ));
            initializers.push(float_tensor(&b, &[layer.outputs], &layer.bias));
            let (product, sum) = (format!("layer{k}.product"), format!("layer{k}.sum"));
            node("MatMul", &[&format!("h{k}"), &w], &product, &[]);
            node("Add", &[&product, &b], &sum, &[]);
            if k < last {
                node("Tanh", &[&sum], &format!("h{}", k + 1), &[]);
            }
        }
        let out = format!("layer{last}.sum");
        match self.bound {
            ActionBound::Clip => {
                initializers.push(float_tensor("action_min", &[], &[-1.0]));
                initializers.push(float_tensor("action_max", &[], &[1.0]));
                node("Clip", &[&out, "action_min", "action_max"], OUTPUT, &[]);
            }
            ActionBound::Tanh => node("Tanh", &[&out], OUTPUT, &[]),
        }
        for n in &nodes {
            graph = graph.message(1, n);
        }
        graph = graph.string(2, "quadwalk_actor");
        for t in &initializers {
            graph = graph.message(5, t);
        }
        graph = graph
            .string(
                10,
                "quadwalk policy: raw observation -> normaliser -> MLP -> action in [-1, 1]",
            )
            .message(11, &value_info(INPUT, self.obs_size()))
            .message(12, &value_info(OUTPUT, self.action_size()));
        let mut model = Message::new()
            .int(1, IR_VERSION)
            .string(2, "quadwalk")
            .string(3, producer_version)
            .message(7, &graph)
            .message(8, &Message::new().string(1, "").int(2, OPSET));
        for (key, value) in &self.metadata {
            model = model.message(14, &Message::new().string(1, key).string(2, value));
        }
        Ok(model.into_bytes())
    }
}

/// A `TensorProto` of `float`s.
fn float_tensor(name: &str, dims: &[usize], values: &[f32]) -> Message {
    let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    tensor(name, dims, FLOAT, &raw)
}

/// A `TensorProto` of `double`s.
fn double_tensor(name: &str, dims: &[usize], values: &[f64]) -> Message {
    let raw: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    tensor(name, dims, DOUBLE, &raw)
}

fn tensor(name: &str, dims: &[usize], data_type: u64, raw: &[u8]) -> Message {
    let mut t = Message::new();
    for &d in dims {
        t = t.int(1, d as u64);
    }
    t.int(2, data_type).string(8, name).bytes(9, raw)
}

/// A `ValueInfoProto`: a `float` tensor of `batch x width`.
fn value_info(name: &str, width: usize) -> Message {
    let shape = Message::new()
        .message(1, &Message::new().string(2, "batch"))
        .message(1, &Message::new().int(1, width as u64));
    let tensor_type = Message::new().int(1, FLOAT).message(2, &shape);
    Message::new()
        .string(1, name)
        .message(2, &Message::new().message(1, &tensor_type))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small() -> ActorGraph {
        ActorGraph {
            obs_mean: vec![0.5, -1.0],
            obs_std: vec![2.0, 1e-4],
            obs_clip: 5.0,
            layers: vec![
                DenseLayer {
                    inputs: 2,
                    outputs: 3,
                    weight: vec![1.0, 0.0, -1.0, 0.5, 0.5, 0.5],
                    bias: vec![0.0, 0.1, 0.2],
                },
                DenseLayer {
                    inputs: 3,
                    outputs: 1,
                    weight: vec![2.0, 2.0, 2.0],
                    bias: vec![0.0],
                },
            ],
            bound: ActionBound::Clip,
            metadata: vec![("algo".into(), "ppo".into())],
        }
    }

    #[test]
    fn the_reference_normalises_clips_and_bounds_as_the_graph_says() {
        let g = small();
        // z = ((2.5 - 0.5) / 2, clip((-1 - -1) / 1e-4)) = (1, 0)
        let h = [1f32.tanh(), 0.1f32.tanh(), (-1.0f32 + 0.2).tanh()];
        let expected = (2.0 * (h[0] + h[1] + h[2])).clamp(-1.0, 1.0);
        assert_eq!(g.act(&[2.5, -1.0]), [expected]);
        // the second value is 1e4 deviations off: clipped to 5, and so on
        let a = g.act(&[0.5, 0.0])[0];
        let h = [0.0f32, (0.1f32 + 2.5).tanh(), (0.2f32 + 2.5).tanh()];
        assert_eq!(a, (2.0 * (h[0] + h[1] + h[2])).clamp(-1.0, 1.0));
        let tanh = ActorGraph {
            bound: ActionBound::Tanh,
            ..small()
        };
        assert!(tanh.act(&[9.0, 9.0])[0] < 1.0);
    }

    #[test]
    fn sizes_that_do_not_chain_are_refused() {
        let mut g = small();
        g.layers[1].inputs = 4;
        let err = g.to_onnx("test").unwrap_err().to_string();
        assert!(err.contains("layer 1 takes 4 from 3 values"), "{err}");
        let mut g = small();
        g.obs_std.pop();
        assert!(
            g.check()
                .unwrap_err()
                .to_string()
                .contains("2 normaliser means, 1 deviations")
        );
    }

    #[test]
    fn the_model_names_its_input_output_opset_and_weights() {
        let bytes = small().to_onnx("0.1.0").unwrap();
        let contains = |s: &[u8]| bytes.windows(s.len()).any(|w| w == s);
        for name in [
            INPUT,
            OUTPUT,
            "layer1.weight",
            "obs_std",
            "quadwalk",
            "MatMul",
            "Clip",
        ] {
            assert!(contains(name.as_bytes()), "{name}");
        }
        // the first layer's weights travel as raw little-endian floats
        let raw: Vec<u8> = small().layers[0]
            .weight
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        assert!(contains(&raw));
        // ir_version 8 first
        assert_eq!(bytes[..2], [0x08, 0x08]);
    }
}
