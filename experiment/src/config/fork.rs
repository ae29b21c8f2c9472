//! Whether one experiment trains its first iterations exactly as another
//! did (`train --fork`): the first difference, named.

use super::Experiment;

impl Experiment {
    /// Where this experiment's first `iterations` iterations would differ
    /// from `other`'s (`None`: they are the same training, so a checkpoint
    /// of `other` at `iterations` is where this experiment would be too).
    /// Compared: the learner and its settings, the number of worlds and the
    /// seed, and for every iteration before `iterations` its terrain (and
    /// terrain levels), physics, task and learning rate. Not compared: what does not change
    /// the training (checkpoint cadence, Rerun environments, the stages'
    /// layout beyond what each iteration runs). Stages that move on when
    /// ready are compared where the run's history ended them: both
    /// experiments must have decided their stages from it
    /// ([`Experiment::decide_stages`]).
    pub fn differs_before(&self, other: &Experiment, iterations: u64) -> Option<String> {
        if self.algo != other.algo {
            return Some(format!(
                "the learner: {} against {}",
                self.algo.name, other.algo.name
            ));
        }
        if self.learner() != other.learner() {
            return Some(format!(
                "the [{}] settings: {}",
                self.algo.table,
                debug_difference(&self.learner(), &other.learner())
            ));
        }
        if self.train.envs != other.train.envs {
            return Some(format!(
                "train.envs: {} against {}",
                self.train.envs, other.train.envs
            ));
        }
        if self.train.seed != other.train.seed {
            return Some(format!(
                "train.seed: {} against {}",
                self.train.seed, other.train.seed
            ));
        }
        // Each iteration's settings are constant between stage boundaries:
        // check at 0 and at every boundary of either curriculum before
        // `iterations`.
        let boundaries = |e: &Experiment| {
            e.curriculum
                .iter()
                .scan(0, |end, stage| {
                    *end += stage.length();
                    Some(*end)
                })
                .collect::<Vec<u64>>()
        };
        let mut starts: Vec<u64> = std::iter::once(0)
            .chain(boundaries(self))
            .chain(boundaries(other))
            .filter(|&i| i < iterations)
            .collect();
        starts.sort_unstable();
        starts.dedup();
        for i in starts {
            let (a, b) = (self.terrain_at(i).1, other.terrain_at(i).1);
            if a != b {
                return Some(format!("iteration {}'s terrain: {a} against {b}", i + 1));
            }
            if self.physics_at(i) != other.physics_at(i) {
                return Some(format!(
                    "iteration {}'s [physics] settings: {}",
                    i + 1,
                    debug_difference(self.physics_at(i), other.physics_at(i))
                ));
            }
            if self.levels_at(i) != other.levels_at(i) {
                return Some(format!(
                    "iteration {}'s terrain levels: {:?} against {:?}",
                    i + 1,
                    self.levels_at(i),
                    other.levels_at(i)
                ));
            }
            if self.task_at(i) != other.task_at(i) {
                return Some(format!(
                    "iteration {}'s task: {}",
                    i + 1,
                    debug_difference(self.task_at(i), other.task_at(i))
                ));
            }
            let (a, b) = (
                self.effective_learning_rate_at(i),
                other.effective_learning_rate_at(i),
            );
            if a != b {
                let show = |r: Option<f64>| r.map_or("adaptive".to_string(), |r| format!("{r:e}"));
                return Some(format!(
                    "iteration {}'s learning rate: {} against {}",
                    i + 1,
                    show(a),
                    show(b)
                ));
            }
        }
        None
    }
}

/// The fields in which two values' `{:?}` texts differ, as "a against b"
/// (`max_phases: 40 against max_phases: 1`).
fn debug_difference(a: &impl std::fmt::Debug, b: &impl std::fmt::Debug) -> String {
    let (a, b) = (format!("{a:?}"), format!("{b:?}"));
    let fields = |text: &str| -> Vec<String> {
        text.split(", ")
            .map(|f| {
                f.rsplit(" { ")
                    .next()
                    .unwrap_or(f)
                    .trim_end_matches([' ', '}'])
                    .to_string()
            })
            .collect()
    };
    let (fa, fb) = (fields(&a), fields(&b));
    let only_a: Vec<&String> = fa.iter().filter(|f| !fb.contains(f)).collect();
    let only_b: Vec<&String> = fb.iter().filter(|f| !fa.contains(f)).collect();
    if only_a.is_empty() && only_b.is_empty() {
        return format!("{a} against {b}");
    }
    let join = |v: Vec<&String>| v.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ");
    format!("{} against {}", join(only_a), join(only_b))
}
