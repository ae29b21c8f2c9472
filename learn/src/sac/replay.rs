//! The replay buffer: a ring of transitions (s, a, r, s', terminated) in
//! flat `f32` storage, the oldest overwritten once full, sampled uniformly.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// A batch of transitions, row-major (`B x O`, `B x A`, `B`).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Batch {
    /// observations, `B x O`
    pub obs: Vec<f32>,
    /// actions taken (in [-1, 1]), `B x A`
    pub actions: Vec<f32>,
    /// rewards, `B`
    pub rewards: Vec<f32>,
    /// next observations (the last one before a reset when the episode ended), `B x O`
    pub next_obs: Vec<f32>,
    /// 1 where the episode ended in a terminal state, else 0, `B`
    pub terminated: Vec<f32>,
}

/// A ring of at most `capacity` transitions.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayBuffer {
    obs_size: usize,
    action_size: usize,
    capacity: usize,
    /// where the next transition goes
    next: usize,
    /// transitions stored (at most `capacity`)
    len: usize,
    storage: Batch,
}

impl ReplayBuffer {
    /// An empty buffer for `capacity` transitions.
    pub fn new(obs_size: usize, action_size: usize, capacity: usize) -> Self {
        Self {
            obs_size,
            action_size,
            capacity,
            next: 0,
            len: 0,
            storage: Batch {
                obs: vec![0.0; capacity * obs_size],
                actions: vec![0.0; capacity * action_size],
                rewards: vec![0.0; capacity],
                next_obs: vec![0.0; capacity * obs_size],
                terminated: vec![0.0; capacity],
            },
        }
    }

    /// Transitions stored.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Most transitions it holds.
    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Stores one transition, overwriting the oldest when full.
    pub fn push(
        &mut self,
        obs: &[f32],
        action: &[f32],
        reward: f32,
        next_obs: &[f32],
        terminated: bool,
    ) {
        let (o, a, k) = (self.obs_size, self.action_size, self.next);
        self.storage.obs[k * o..(k + 1) * o].copy_from_slice(obs);
        self.storage.actions[k * a..(k + 1) * a].copy_from_slice(action);
        self.storage.rewards[k] = reward;
        self.storage.next_obs[k * o..(k + 1) * o].copy_from_slice(next_obs);
        self.storage.terminated[k] = if terminated { 1.0 } else { 0.0 };
        self.next = (k + 1) % self.capacity;
        self.len = (self.len + 1).min(self.capacity);
    }

    /// The stored transitions in storage order (rows `0..len`) and the
    /// slot the next one goes to: what a checkpoint keeps.
    pub fn stored(&self) -> (Batch, usize) {
        let indices: Vec<usize> = (0..self.len).collect();
        (self.gather(&indices), self.next)
    }

    /// A buffer of `capacity` holding `stored` (rows in storage order) with
    /// the next transition going to slot `next`; `None` when the sizes do
    /// not fit.
    pub fn from_stored(
        obs_size: usize,
        action_size: usize,
        capacity: usize,
        stored: &Batch,
        next: usize,
    ) -> Option<Self> {
        let len = stored.rewards.len();
        let fits = len <= capacity
            && stored.obs.len() == len * obs_size
            && stored.next_obs.len() == len * obs_size
            && stored.actions.len() == len * action_size
            && stored.terminated.len() == len
            && (next < capacity)
            && (len == capacity || next == len % capacity);
        if !fits {
            return None;
        }
        let mut buffer = Self::new(obs_size, action_size, capacity);
        buffer.storage.obs[..stored.obs.len()].copy_from_slice(&stored.obs);
        buffer.storage.next_obs[..stored.next_obs.len()].copy_from_slice(&stored.next_obs);
        buffer.storage.actions[..stored.actions.len()].copy_from_slice(&stored.actions);
        buffer.storage.rewards[..len].copy_from_slice(&stored.rewards);
        buffer.storage.terminated[..len].copy_from_slice(&stored.terminated);
        buffer.len = len;
        buffer.next = next;
        Some(buffer)
    }

    /// `batch_size` transitions drawn uniformly (with replacement) from
    /// those stored. Panics when empty.
    pub fn sample(&self, batch_size: usize, rng: &mut ChaCha8Rng) -> Batch {
        assert!(!self.is_empty(), "sampling an empty replay buffer");
        let indices: Vec<usize> = (0..batch_size)
            .map(|_| rng.random_range(0..self.len))
            .collect();
        self.gather(&indices)
    }

    /// The transitions at `indices` (positions in storage).
    pub fn gather(&self, indices: &[usize]) -> Batch {
        let (o, a) = (self.obs_size, self.action_size);
        let mut out = Batch::default();
        for &k in indices {
            out.obs
                .extend_from_slice(&self.storage.obs[k * o..(k + 1) * o]);
            out.actions
                .extend_from_slice(&self.storage.actions[k * a..(k + 1) * a]);
            out.rewards.push(self.storage.rewards[k]);
            out.next_obs
                .extend_from_slice(&self.storage.next_obs[k * o..(k + 1) * o]);
            out.terminated.push(self.storage.terminated[k]);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;

    #[test]
    fn the_ring_keeps_the_newest_transitions() {
        let mut buffer = ReplayBuffer::new(2, 1, 3);
        assert!(buffer.is_empty());
        for k in 0..5 {
            let x = k as f32;
            buffer.push(&[x, -x], &[x / 10.0], x, &[x + 1.0, 0.0], k == 4);
        }
        assert_eq!(buffer.len(), 3);
        // slots: 0 <- 3, 1 <- 4, 2 <- 2
        let b = buffer.gather(&[0, 1, 2]);
        assert_eq!(b.rewards, [3.0, 4.0, 2.0]);
        assert_eq!(b.obs, [3.0, -3.0, 4.0, -4.0, 2.0, -2.0]);
        assert_eq!(b.actions, [0.3, 0.4, 0.2]);
        assert_eq!(b.next_obs, [4.0, 0.0, 5.0, 0.0, 3.0, 0.0]);
        assert_eq!(b.terminated, [0.0, 1.0, 0.0]);
    }

    #[test]
    fn a_stored_buffer_comes_back_whole() {
        let mut buffer = ReplayBuffer::new(2, 1, 3);
        for k in 0..4 {
            let x = k as f32;
            buffer.push(&[x, x], &[x], x, &[x, 0.0], k % 2 == 0);
        }
        let (stored, next) = buffer.stored();
        assert_eq!(next, 1);
        let back = ReplayBuffer::from_stored(2, 1, 3, &stored, next).unwrap();
        assert_eq!(back, buffer);
        assert!(ReplayBuffer::from_stored(2, 1, 2, &stored, next).is_none());
        assert!(ReplayBuffer::from_stored(3, 1, 3, &stored, next).is_none());
    }

    #[test]
    fn sampling_draws_only_stored_transitions_and_all_of_them() {
        let mut buffer = ReplayBuffer::new(1, 1, 100);
        for k in 0..10 {
            buffer.push(&[k as f32], &[0.0], k as f32, &[0.0], false);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let b = buffer.sample(2000, &mut rng);
        assert_eq!(b.rewards.len(), 2000);
        let mut seen = [0usize; 10];
        for r in &b.rewards {
            assert!((0.0..10.0).contains(r));
            seen[*r as usize] += 1;
        }
        // uniform: each of the 10 about 200 times
        assert!(seen.iter().all(|&n| (140..260).contains(&n)), "{seen:?}");
    }
}
