//! Episode statistics of one iteration's collection, shared by every
//! learner: the ended episodes' count, returns, lengths and metrics, and the
//! reward per step, in total and per term.

use crate::env::StepResult;

/// What the episodes of one collection did.
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeStats {
    /// episodes that ended (terminated or truncated by the environment)
    pub episodes: usize,
    /// of them, terminated
    pub terminated: usize,
    /// mean undiscounted return of the ended episodes
    pub mean_return: Option<f64>,
    /// mean length (steps) of the ended episodes
    pub mean_length: Option<f64>,
    /// mean of each environment metric over the ended episodes that report
    /// a finite value, named
    pub metrics: Vec<(String, Option<f64>)>,
    /// mean reward per step
    pub mean_step_reward: f64,
    /// mean of each reward term per step, named
    pub reward_terms: Vec<(String, f64)>,
}

/// Accumulates [`EpisodeStats`] step by step.
pub struct EpisodeCollector {
    term_names: Vec<String>,
    metric_names: Vec<String>,
    running_return: Vec<f64>,
    running_length: Vec<usize>,
    episodes: usize,
    terminated: usize,
    return_sum: f64,
    length_sum: f64,
    /// per metric: the sum of its finite values and their count
    metric_sums: Vec<(f64, usize)>,
    term_sums: Vec<f64>,
    reward_sum: f64,
}

impl EpisodeCollector {
    /// A collector for `envs` environments with these reward terms and
    /// episode metrics.
    pub fn new(envs: usize, term_names: Vec<String>, metric_names: Vec<String>) -> Self {
        Self {
            running_return: vec![0.0; envs],
            running_length: vec![0; envs],
            episodes: 0,
            terminated: 0,
            return_sum: 0.0,
            length_sum: 0.0,
            metric_sums: vec![(0.0, 0); metric_names.len()],
            term_sums: vec![0.0; term_names.len()],
            reward_sum: 0.0,
            term_names,
            metric_names,
        }
    }

    /// Environment `i`'s step in `out`: its reward, and its episode when the
    /// step ended one.
    pub fn record(&mut self, out: &StepResult, i: usize) {
        let (t_count, m_count) = (self.term_names.len(), self.metric_names.len());
        let r = f64::from(out.rewards[i]);
        self.reward_sum += r;
        self.running_return[i] += r;
        self.running_length[i] += 1;
        for (k, sum) in self.term_sums.iter_mut().enumerate() {
            *sum += f64::from(out.reward_terms[i * t_count + k]);
        }
        if out.ended(i) {
            self.episodes += 1;
            self.terminated += usize::from(out.terminated[i]);
            self.return_sum += self.running_return[i];
            self.length_sum += self.running_length[i] as f64;
            for (k, sum) in self.metric_sums.iter_mut().enumerate() {
                let v = out.episode_metrics[i * m_count + k];
                if v.is_finite() {
                    sum.0 += f64::from(v);
                    sum.1 += 1;
                }
            }
            self.running_return[i] = 0.0;
            self.running_length[i] = 0;
        }
    }

    /// The statistics, per ended episode and per step of `steps` collected.
    pub fn finish(self, steps: usize) -> EpisodeStats {
        let per_episode = |s: f64| (self.episodes > 0).then(|| s / self.episodes as f64);
        EpisodeStats {
            episodes: self.episodes,
            terminated: self.terminated,
            mean_return: per_episode(self.return_sum),
            mean_length: per_episode(self.length_sum),
            metrics: self
                .metric_names
                .into_iter()
                .zip(self.metric_sums)
                .map(|(name, (sum, count))| (name, (count > 0).then(|| sum / count as f64)))
                .collect(),
            mean_step_reward: self.reward_sum / steps as f64,
            reward_terms: self
                .term_names
                .into_iter()
                .zip(self.term_sums)
                .map(|(name, sum)| (name, sum / steps as f64))
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(rewards: &[f32], ended: &[bool], metric: &[f32]) -> StepResult {
        let n = rewards.len();
        StepResult {
            obs: vec![0.0; n],
            rewards: rewards.to_vec(),
            terminated: ended.to_vec(),
            truncated: vec![false; n],
            final_obs: vec![0.0; n],
            reward_terms: rewards.to_vec(),
            episode_metrics: metric.to_vec(),
        }
    }

    #[test]
    fn episodes_are_counted_when_they_end_and_non_finite_metrics_are_skipped() {
        let mut c = EpisodeCollector::new(2, vec!["r".into()], vec!["distance_m".into()]);
        for (rewards, ended, metric) in [
            ([1.0, 2.0], [false, false], [0.0, 0.0]),
            ([1.0, 2.0], [true, false], [3.0, 0.0]),
            ([1.0, 2.0], [false, true], [0.0, f32::NAN]),
        ] {
            let out = step(&rewards, &ended, &metric);
            for i in 0..2 {
                c.record(&out, i);
            }
        }
        let s = c.finish(6);
        assert_eq!((s.episodes, s.terminated), (2, 2));
        // env 0: 2 steps, return 2; env 1: 3 steps, return 6
        assert_eq!(s.mean_return, Some(4.0));
        assert_eq!(s.mean_length, Some(2.5));
        assert_eq!(s.metrics, vec![("distance_m".to_string(), Some(3.0))]);
        assert_eq!(s.mean_step_reward, 9.0 / 6.0);
        assert_eq!(s.reward_terms, vec![("r".to_string(), 9.0 / 6.0)]);
        let none = EpisodeCollector::new(1, vec![], vec!["m".into()]).finish(1);
        assert_eq!((none.mean_return, none.metrics[0].1), (None, None));
    }
}
