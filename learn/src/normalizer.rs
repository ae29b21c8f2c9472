//! Running observation normalisation: per-dimension mean and variance over
//! every observation seen in training (Chan et al.'s parallel update), in
//! `f64`. Normalised values are `clip((x - mean) / sqrt(var + 1e-8), +-clip)`.
//! The state is part of a checkpoint; a trained policy is only right with
//! the normaliser it was trained with.
//!
//! Values appended to the observation mid-run ([`ObsNormalizer::append`],
//! a critic given privileged values from a curriculum stage on) keep their
//! own count from 0, so their statistics are theirs alone from the first
//! batch instead of being outweighed by the observations seen before they
//! existed.

use crate::LearnError;

/// Running mean and variance of observations.
#[derive(Debug, Clone, PartialEq)]
pub struct ObsNormalizer {
    /// per-dimension mean
    pub mean: Vec<f64>,
    /// per-dimension (population) variance
    pub var: Vec<f64>,
    /// observations seen
    pub count: f64,
    /// normalised values are clipped to +- this
    pub clip: f64,
    /// values appended after the first observations: where they start and
    /// how many observations of them were seen
    pub appended: Option<Appended>,
}

/// The values from `from` on were appended to the observation mid-run and
/// have been seen `count` times.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Appended {
    /// index of the first appended value
    pub from: usize,
    /// observations of them seen
    pub count: f64,
}

const EPSILON: f64 = 1e-8;

impl ObsNormalizer {
    /// Mean 0, variance 1, count 0.
    pub fn new(size: usize, clip: f64) -> Self {
        Self {
            mean: vec![0.0; size],
            var: vec![1.0; size],
            count: 0.0,
            clip,
            appended: None,
        }
    }

    /// Appends `extra` values to the observation, mean 0 and variance 1
    /// until their first batch, counted from 0 on their own.
    pub fn append(&mut self, extra: usize) {
        if extra == 0 {
            return;
        }
        let from = self.size();
        self.mean.extend(std::iter::repeat_n(0.0, extra));
        self.var.extend(std::iter::repeat_n(1.0, extra));
        if self.appended.is_none() {
            self.appended = Some(Appended { from, count: 0.0 });
        }
    }

    /// The count of value `d`'s statistics.
    fn count_of(&self, d: usize) -> f64 {
        match self.appended {
            Some(a) if d >= a.from => a.count,
            _ => self.count,
        }
    }

    /// Observation size.
    pub fn size(&self) -> usize {
        self.mean.len()
    }

    /// Adds a batch of `k x size` observations to the statistics.
    pub fn update(&mut self, batch: &[f32]) {
        let size = self.size();
        assert_eq!(batch.len() % size, 0, "normaliser: batch is not k x {size}");
        let k = (batch.len() / size) as f64;
        if k == 0.0 {
            return;
        }
        for d in 0..size {
            let column = batch.iter().skip(d).step_by(size).map(|&x| f64::from(x));
            let batch_mean = column.clone().sum::<f64>() / k;
            let batch_var = column.map(|x| (x - batch_mean).powi(2)).sum::<f64>() / k;
            let count = self.count_of(d);
            let total = count + k;
            let delta = batch_mean - self.mean[d];
            let m2 = self.var[d] * count + batch_var * k + delta * delta * count * k / total;
            self.mean[d] += delta * k / total;
            self.var[d] = m2 / total;
        }
        self.count += k;
        if let Some(appended) = &mut self.appended {
            appended.count += k;
        }
    }

    /// The statistics of the first `n` values only (what a policy that sees
    /// only them is normalised with).
    pub fn leading(&self, n: usize) -> Self {
        Self {
            mean: self.mean[..n].to_vec(),
            var: self.var[..n].to_vec(),
            count: self.count,
            clip: self.clip,
            appended: self.appended.filter(|a| a.from < n),
        }
    }

    /// The per-dimension divisor, `sqrt(var + 1e-8)`.
    pub fn std(&self) -> Vec<f64> {
        self.var.iter().map(|v| (v + EPSILON).sqrt()).collect()
    }

    /// Normalises `k x size` observations in place.
    pub fn normalize(&self, obs: &mut [f32]) {
        let size = self.size();
        assert_eq!(obs.len() % size, 0, "normaliser: batch is not k x {size}");
        for row in obs.chunks_exact_mut(size) {
            for (d, x) in row.iter_mut().enumerate() {
                let z = (f64::from(*x) - self.mean[d]) / (self.var[d] + EPSILON).sqrt();
                *x = z.clamp(-self.clip, self.clip) as f32;
            }
        }
    }

    /// Rebuilds a normaliser from stored state, checking it.
    pub fn from_parts(
        mean: Vec<f64>,
        var: Vec<f64>,
        count: f64,
        clip: f64,
    ) -> Result<Self, LearnError> {
        if mean.len() != var.len() {
            return Err(LearnError::Checkpoint(format!(
                "normaliser mean has {} values but variance {}",
                mean.len(),
                var.len()
            )));
        }
        if !(count.is_finite() && count >= 0.0)
            || mean.iter().any(|m| !m.is_finite())
            || var.iter().any(|v| !(v.is_finite() && *v >= 0.0))
        {
            return Err(LearnError::Checkpoint(
                "normaliser state holds a non-finite or negative value".into(),
            ));
        }
        Ok(Self {
            mean,
            var,
            count,
            clip,
            appended: None,
        })
    }

    /// With the stored [`Appended`] state of a checkpoint, checked.
    pub fn with_appended(mut self, appended: Appended) -> Result<Self, LearnError> {
        let fits = appended.from > 0
            && appended.from < self.size()
            && appended.count.is_finite()
            && appended.count >= 0.0;
        if !fits {
            return Err(LearnError::Checkpoint(format!(
                "normaliser: appended values from {} seen {} times do not fit {} values",
                appended.from,
                appended.count,
                self.size()
            )));
        }
        self.appended = Some(appended);
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batched_updates_equal_one_big_update() {
        let data: Vec<f32> = (0..60)
            .map(|i| ((i * 37 % 11) as f32) * 0.5 - 2.0)
            .collect();
        let mut whole = ObsNormalizer::new(3, 10.0);
        whole.update(&data);
        let mut parts = ObsNormalizer::new(3, 10.0);
        for chunk in data.chunks(9) {
            parts.update(chunk);
        }
        for d in 0..3 {
            let column: Vec<f64> = data
                .iter()
                .skip(d)
                .step_by(3)
                .map(|&x| f64::from(x))
                .collect();
            let mean = column.iter().sum::<f64>() / 20.0;
            let var = column.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 20.0;
            assert!((whole.mean[d] - mean).abs() < 1e-12);
            assert!((whole.var[d] - var).abs() < 1e-12);
            assert!((parts.mean[d] - mean).abs() < 1e-12);
            assert!((parts.var[d] - var).abs() < 1e-12);
        }
        assert_eq!(parts.count, 20.0);
    }

    #[test]
    fn normalises_and_clips() {
        let mut n = ObsNormalizer::new(2, 3.0);
        n.update(&[1.0, 10.0, 3.0, 10.0]);
        // dim 0: mean 2, var 1; dim 1: constant 10, var 0
        let mut x = [4.0, 10.0, 100.0, 11.0];
        n.normalize(&mut x);
        assert!((x[0] - 2.0).abs() < 1e-6);
        assert_eq!(x[1], 0.0);
        assert_eq!(x[2], 3.0, "clipped");
        assert_eq!(x[3], 3.0, "a constant dimension saturates at the clip");
    }

    /// Appended values get their batch's statistics from their first
    /// batch (their own count starts at 0), the values before them go on
    /// with theirs, and both equal what one normaliser over each part alone
    /// would have.
    #[test]
    fn appended_values_count_from_their_first_batch() {
        let early: Vec<f32> = (0..200).map(|i| (i % 7) as f32).collect();
        let mut n = ObsNormalizer::new(2, 10.0);
        n.update(&early);
        n.append(1);
        assert_eq!(n.size(), 3);
        let late: Vec<f32> = (0..60)
            .map(|i| {
                if i % 3 == 2 {
                    0.05 * (i % 4) as f32
                } else {
                    (i % 5) as f32
                }
            })
            .collect();
        let mut alone = ObsNormalizer::new(1, 10.0);
        let mut leading = ObsNormalizer::new(2, 10.0);
        leading.update(&early);
        for rows in late.chunks(12) {
            n.update(rows);
            let third: Vec<f32> = rows.iter().skip(2).step_by(3).copied().collect();
            alone.update(&third);
            let first_two: Vec<f32> = rows
                .chunks(3)
                .flat_map(|r| r[..2].iter().copied())
                .collect();
            leading.update(&first_two);
        }
        assert!((n.mean[2] - alone.mean[0]).abs() < 1e-12);
        assert!((n.var[2] - alone.var[0]).abs() < 1e-12);
        assert!(
            n.var[2] < 0.01,
            "the appended values' own spread: {}",
            n.var[2]
        );
        for d in 0..2 {
            assert!((n.mean[d] - leading.mean[d]).abs() < 1e-12);
            assert!((n.var[d] - leading.var[d]).abs() < 1e-12);
        }
        assert_eq!(n.count, 120.0);
        assert_eq!(
            n.appended,
            Some(Appended {
                from: 2,
                count: 20.0
            })
        );
        assert_eq!(n.leading(2).appended, None);
    }

    #[test]
    fn bad_stored_state_is_refused() {
        assert!(ObsNormalizer::from_parts(vec![0.0], vec![1.0, 1.0], 1.0, 5.0).is_err());
        assert!(ObsNormalizer::from_parts(vec![f64::NAN], vec![1.0], 1.0, 5.0).is_err());
        assert!(ObsNormalizer::from_parts(vec![0.0], vec![-1.0], 1.0, 5.0).is_err());
    }
}
