//! Seed sets: one evaluation of several sets of consecutive episode seeds
//! (`quadwalk eval --seed A --seed B --episodes N`), with each set's
//! success, so that a bar such as "at least 9 of 10 on every set" reads
//! off one run instead of one run per set.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use super::record::EpisodeRecord;

/// Sets of `episodes_per_set` consecutive seeds, each from its first seed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SeedSets {
    first_seeds: Vec<u64>,
    episodes_per_set: u64,
}

/// One set's share of an evaluation (`eval.json`'s `seed_sets`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeedSetSummary {
    /// the set's first episode seed
    pub first_seed: u64,
    /// episodes run in the set
    pub episodes: usize,
    /// those that ran every phase without a fall
    pub successes: usize,
    /// mean distance along x per episode, m
    pub mean_distance_m: f64,
}

impl SeedSets {
    /// Sets starting at `first_seeds`, in that order, of `episodes_per_set`
    /// seeds each (seed + k, wrapping at the largest u64 as a single set
    /// does). The error names the two sets that would run the same seed.
    pub fn new(first_seeds: Vec<u64>, episodes_per_set: u64) -> Result<Self, String> {
        if first_seeds.is_empty() {
            return Err("no seed set: give at least one first seed".into());
        }
        if episodes_per_set == 0 {
            return Err("a seed set needs at least one episode".into());
        }
        let sets = Self {
            first_seeds,
            episodes_per_set,
        };
        let mut owner: HashMap<u64, u64> = HashMap::new();
        for &first in &sets.first_seeds {
            for seed in sets.seeds_of(first) {
                if let Some(other) = owner.insert(seed, first) {
                    return Err(format!(
                        "--seed {other} and --seed {first} would both run seed {seed}: each set runs {} consecutive seeds (--episodes), so the sets' first seeds must be at least that far apart",
                        sets.episodes_per_set
                    ));
                }
            }
        }
        Ok(sets)
    }

    /// How many sets.
    pub fn len(&self) -> usize {
        self.first_seeds.len()
    }

    /// Always false: a [`SeedSets`] holds at least one set.
    pub fn is_empty(&self) -> bool {
        self.first_seeds.is_empty()
    }

    /// Each set's first seed, in order.
    pub fn first_seeds(&self) -> &[u64] {
        &self.first_seeds
    }

    /// Every episode's seed, set after set.
    pub fn seeds(&self) -> Vec<u64> {
        self.first_seeds
            .iter()
            .flat_map(|&first| self.seeds_of(first))
            .collect()
    }

    fn seeds_of(&self, first: u64) -> impl Iterator<Item = u64> + use<> {
        (0..self.episodes_per_set).map(move |k| first.wrapping_add(k))
    }

    /// Each set's success and mean distance over `episodes` (an
    /// evaluation's records, any order; a seed no set holds is left out).
    pub fn summarize(&self, episodes: &[EpisodeRecord]) -> Vec<SeedSetSummary> {
        self.first_seeds
            .iter()
            .map(|&first| {
                // seed + k for k < episodes_per_set, wrapping as `seeds_of`
                let own: Vec<&EpisodeRecord> = episodes
                    .iter()
                    .filter(|e| e.seed.wrapping_sub(first) < self.episodes_per_set)
                    .collect();
                let n = own.len();
                SeedSetSummary {
                    first_seed: first,
                    episodes: n,
                    successes: own.iter().filter(|e| e.succeeded()).count(),
                    mean_distance_m: if n == 0 {
                        0.0
                    } else {
                        own.iter().map(|e| e.distance_m).sum::<f64>() / n as f64
                    },
                }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_run_consecutive_seeds_in_order_and_may_not_share_one() {
        let sets = SeedSets::new(vec![1_000_000, 41_000_000], 3).unwrap();
        assert_eq!(sets.len(), 2);
        assert_eq!(
            sets.seeds(),
            [
                1_000_000, 1_000_001, 1_000_002, 41_000_000, 41_000_001, 41_000_002
            ]
        );
        // one set is what a single --seed always ran, wrapping included
        assert_eq!(
            SeedSets::new(vec![u64::MAX], 2).unwrap().seeds(),
            [u64::MAX, 0]
        );
        // sets closer than their length would run a seed twice
        let err = SeedSets::new(vec![10, 12], 3).unwrap_err();
        assert!(
            err.contains("--seed 10 and --seed 12 would both run seed 12")
                && err.contains("3 consecutive seeds"),
            "{err}"
        );
        let err = SeedSets::new(vec![7, 7], 1).unwrap_err();
        assert!(err.contains("--seed 7 and --seed 7"), "{err}");
        assert!(SeedSets::new(vec![], 3).is_err());
        assert!(SeedSets::new(vec![1], 0).is_err());
    }

    #[test]
    fn each_set_counts_its_own_episodes_wrapping_included() {
        use crate::eval::summary::tests::crafted;
        let sets = SeedSets::new(vec![u64::MAX, 40], 2).unwrap();
        // distances are one metre per phase: 2, 1, 3 and 4 m
        let episodes = [
            crafted(40, &["rigid", "rigid"], None),
            crafted(u64::MAX, &["rigid"], Some(("base_too_low", &[]))),
            crafted(0, &["rigid", "rigid", "rigid"], None),
            crafted(41, &["rigid"; 4], Some(("pitch_too_large", &[]))),
            crafted(7, &["rigid"], None),
        ];
        let summaries = sets.summarize(&episodes);
        assert_eq!(
            summaries,
            [
                SeedSetSummary {
                    first_seed: u64::MAX,
                    episodes: 2,
                    successes: 1,
                    mean_distance_m: 2.0,
                },
                SeedSetSummary {
                    first_seed: 40,
                    episodes: 2,
                    successes: 1,
                    mean_distance_m: 3.0,
                },
            ],
            "seed 7 is in no set"
        );
    }
}
