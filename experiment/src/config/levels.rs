//! `[curriculum.levels]`: terrain levels per world (legged_gym's terrain
//! curriculum). Each world trains on its own level of a list of terrains,
//! easiest first; after every iteration a world that walked far without a
//! fall moves one level up and one that fell without getting far moves one
//! down, so the worlds spread over the levels the policy can nearly walk.
//!
//! ```toml
//! [[curriculum]]
//! iterations = 450            # no `terrain`: the levels are the terrains
//! [curriculum.levels]
//! terrains = ["rigid", "elastic:0.5cm", "elastic:1cm", "elastic:1.5cm", "elastic:2cm"]
//! promote_distance_m = 1.0    # the distance an episode must walk to move up, m
//! ```
//!
//! The rule, per world, over the episodes that ended in the iteration
//! (legged_gym moves a robot up once it walked past half its terrain and
//! down when it walked less than half of what its command asked):
//!
//! - **up** one level when none of them fell and the farthest walked at
//!   least `promote_distance_m` along x (at the top level it stays);
//! - **down** one level when one fell and they walked less than half of
//!   `promote_distance_m` on average (at the bottom it stays);
//! - otherwise, and when none ended, the world keeps its level.
//!
//! Every world starts at the bottom. The levels reached are recorded in
//! each iteration's `metrics.jsonl` line (`levels`, one per world, and
//! `mean_level`), which a resumed or forked run reads back, and carry
//! over into a following stage with levels (clamped to its top). The
//! stage's terrain, where a single one is named (progress lines, the
//! metrics' `terrain`), is the top level.

use anyhow::{Result, anyhow};
use serde::Deserialize;
use terrain_plugins::{Registry, TerrainSpec};

/// [`TerrainLevels::promote_distance_m`] when the file does not set it, m:
/// 1 m in the 40-phase episodes of quadwalk's recipes (2.5 cm a phase).
pub const DEFAULT_PROMOTE_DISTANCE_M: f64 = 1.0;

/// A stage's terrain levels.
#[derive(Debug, Clone, PartialEq)]
pub struct TerrainLevels {
    /// the terrains, easiest (level 0, where every world starts) first
    pub terrains: Vec<TerrainSpec>,
    /// the distance along x the farthest of a world's ended episodes must
    /// walk, none falling, for the world to move up; walking less than
    /// half of it on average with a fall moves it down, m
    pub promote_distance_m: f64,
}

/// `[curriculum.levels]` as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LevelsSection {
    terrains: Vec<String>,
    #[serde(default)]
    promote_distance_m: Option<f64>,
}

impl LevelsSection {
    /// The levels, or the reason they cannot be.
    pub(super) fn resolve(self, registry: &Registry) -> Result<TerrainLevels> {
        if self.terrains.len() < 2 {
            return Err(anyhow!(
                "terrains must list at least two terrains, easiest first (got {})",
                self.terrains.len()
            ));
        }
        let terrains = self
            .terrains
            .iter()
            .enumerate()
            .map(|(k, spec)| {
                registry
                    .parse(spec)
                    .map_err(|e| anyhow!("terrains[{k}] = {spec:?}: {e}"))
            })
            .collect::<Result<Vec<_>>>()?;
        let promote_distance_m = self
            .promote_distance_m
            .unwrap_or(DEFAULT_PROMOTE_DISTANCE_M);
        if !(promote_distance_m.is_finite() && promote_distance_m > 0.0) {
            return Err(anyhow!(
                "promote_distance_m must be a positive distance, m, got {promote_distance_m}"
            ));
        }
        Ok(TerrainLevels {
            terrains,
            promote_distance_m,
        })
    }
}

impl TerrainLevels {
    /// The highest level.
    pub fn top(&self) -> usize {
        self.terrains.len() - 1
    }

    /// The section as an experiment file writes it.
    pub(super) fn to_toml(&self) -> String {
        let terrains: Vec<String> = self
            .terrains
            .iter()
            .map(|t| format!("{:?}", t.to_string()))
            .collect();
        format!(
            "\n[curriculum.levels]\nterrains = [{}]\npromote_distance_m = {:?}\n",
            terrains.join(", "),
            self.promote_distance_m
        )
    }
}

/// What a world's episodes that ended in one iteration did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LevelTally {
    /// episodes ended
    pub ended: u32,
    /// whether one of them fell
    pub fell: bool,
    /// the farthest one's distance along x, m
    pub farthest_m: f64,
    /// their distances' sum, m
    pub total_m: f64,
}

impl LevelTally {
    /// Counts one ended episode.
    pub fn add(&mut self, distance_m: f64, fell: bool) {
        self.farthest_m = if self.ended == 0 {
            distance_m
        } else {
            self.farthest_m.max(distance_m)
        };
        self.ended += 1;
        self.fell |= fell;
        self.total_m += distance_m;
    }
}

impl TerrainLevels {
    /// A world's level after an iteration at `level` whose ended episodes
    /// are `tally` (the rule in the module docs).
    pub fn next_level(&self, level: usize, tally: &LevelTally) -> usize {
        if tally.ended == 0 {
            return level;
        }
        let mean_m = tally.total_m / f64::from(tally.ended);
        if !tally.fell && tally.farthest_m >= self.promote_distance_m {
            (level + 1).min(self.top())
        } else if tally.fell && mean_m < self.promote_distance_m / 2.0 {
            level.saturating_sub(1)
        } else {
            level
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn levels(n: usize) -> TerrainLevels {
        let registry = Registry::builtin();
        TerrainLevels {
            terrains: (0..n)
                .map(|k| registry.parse(&format!("elastic:{}cm", k + 1)).unwrap())
                .collect(),
            promote_distance_m: 1.0,
        }
    }

    fn tally(episodes: &[(f64, bool)]) -> LevelTally {
        let mut t = LevelTally::default();
        for &(d, fell) in episodes {
            t.add(d, fell);
        }
        t
    }

    #[test]
    fn a_world_moves_up_after_walking_far_without_a_fall_and_down_after_falling_near() {
        let l = levels(3);
        // far and upright: up, but not past the top
        assert_eq!(l.next_level(0, &tally(&[(1.2, false)])), 1);
        assert_eq!(l.next_level(2, &tally(&[(1.2, false)])), 2);
        // the farthest of several counts, when none fell
        assert_eq!(l.next_level(1, &tally(&[(0.2, false), (1.0, false)])), 2);
        // a fall blocks the move up; far enough on average, it stays
        assert_eq!(l.next_level(1, &tally(&[(1.5, false), (0.6, true)])), 1);
        // a fall after less than half the distance on average: down, not below 0
        assert_eq!(l.next_level(1, &tally(&[(0.3, true)])), 0);
        assert_eq!(l.next_level(0, &tally(&[(0.3, true)])), 0);
        assert_eq!(l.next_level(2, &tally(&[(0.9, false), (0.05, true)])), 1);
        // standing without a fall: neither up nor down
        assert_eq!(l.next_level(1, &tally(&[(0.1, false)])), 1);
        // nothing ended: nothing to judge
        assert_eq!(l.next_level(1, &LevelTally::default()), 1);
    }

    #[test]
    fn a_tally_keeps_the_farthest_episode_even_when_all_went_backwards() {
        let t = tally(&[(-0.3, false), (-0.1, true)]);
        assert_eq!((t.ended, t.fell), (2, true));
        assert!((t.farthest_m + 0.1).abs() < 1e-12, "{t:?}");
        assert!((t.total_m + 0.4).abs() < 1e-12, "{t:?}");
    }

    #[test]
    fn bad_levels_are_named() {
        let registry = Registry::builtin();
        let resolve = |text: &str| {
            toml::from_str::<LevelsSection>(text)
                .unwrap()
                .resolve(&registry)
                .map_err(|e| e.to_string())
        };
        let err = resolve("terrains = [\"rigid\"]").unwrap_err();
        assert!(err.contains("at least two"), "{err}");
        let err = resolve("terrains = [\"rigid\", \"elastic:5xm\"]").unwrap_err();
        assert!(err.contains("terrains[1] = \"elastic:5xm\""), "{err}");
        let err =
            resolve("terrains = [\"rigid\", \"elastic:5cm\"]\npromote_distance_m = 0").unwrap_err();
        assert!(err.contains("promote_distance_m"), "{err}");
        let ok = resolve("terrains = [\"rigid\", \"elastic:5cm\"]").unwrap();
        assert_eq!(ok.promote_distance_m, DEFAULT_PROMOTE_DISTANCE_M);
        assert_eq!(ok.top(), 1);
    }
}
