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
//! # demote_fall_share = 0.5   # optional: also down when more than this share fell
//! ```
//!
//! The rule, per world, over the episodes that ended in the iteration
//! (legged_gym moves a robot up once it walked past half its terrain and
//! down when it walked less than half of what its command asked):
//!
//! - **up** one level when none of them fell and the farthest walked at
//!   least `promote_distance_m` along x (at the top level it stays);
//! - **down** one level when one fell and they walked less than half of
//!   `promote_distance_m` on average (at the bottom it stays), or, with
//!   `demote_fall_share = F`, when more than F of them fell however far
//!   they walked;
//! - otherwise, and when none ended, the world keeps its level.
//!
//! The distance rule keeps a gait that walks half of `promote_distance_m`
//! and then falls on its level for good: every episode falls, none moves
//! it. `demote_fall_share` moves such a world down until its falls are
//! rare enough, so the worlds train where the policy mostly stays up.
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
    /// a world whose ended episodes fell in more than this share moves
    /// down, however far they walked (`None`: only the distance rule)
    pub demote_fall_share: Option<f64>,
}

/// `[curriculum.levels]` as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LevelsSection {
    terrains: Vec<String>,
    #[serde(default)]
    promote_distance_m: Option<f64>,
    #[serde(default)]
    demote_fall_share: Option<f64>,
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
        if let Some(share) = self.demote_fall_share
            && !(share.is_finite() && (0.0..1.0).contains(&share))
        {
            return Err(anyhow!(
                "demote_fall_share must be a share of the episodes in [0, 1), got {share}"
            ));
        }
        Ok(TerrainLevels {
            terrains,
            promote_distance_m,
            demote_fall_share: self.demote_fall_share,
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
        let demote = self
            .demote_fall_share
            .map(|share| format!("demote_fall_share = {share:?}\n"))
            .unwrap_or_default();
        format!(
            "\n[curriculum.levels]\nterrains = [{}]\npromote_distance_m = {:?}\n{demote}",
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
    /// how many of them fell
    pub falls: u32,
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
        self.falls += u32::from(fell);
        self.total_m += distance_m;
    }

    /// Whether one of the episodes fell.
    pub fn fell(&self) -> bool {
        self.falls > 0
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
        let fall_share = f64::from(tally.falls) / f64::from(tally.ended);
        let falls_too_often = self
            .demote_fall_share
            .is_some_and(|share| fall_share > share);
        if !tally.fell() && tally.farthest_m >= self.promote_distance_m {
            (level + 1).min(self.top())
        } else if (tally.fell() && mean_m < self.promote_distance_m / 2.0) || falls_too_often {
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
            demote_fall_share: None,
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
    fn with_a_fall_share_a_world_that_walks_far_and_falls_moves_down() {
        let distance_only = levels(3);
        let l = TerrainLevels {
            demote_fall_share: Some(0.5),
            ..levels(3)
        };
        // far, then a fall in every episode: the distance rule keeps the level
        let far_falls = tally(&[(0.8, true), (0.7, true), (0.9, true)]);
        assert_eq!(distance_only.next_level(2, &far_falls), 2);
        assert_eq!(l.next_level(2, &far_falls), 1);
        assert_eq!(l.next_level(0, &far_falls), 0);
        // half of them or fewer: it stays
        assert_eq!(l.next_level(2, &tally(&[(0.8, true), (0.7, false)])), 2);
        assert_eq!(
            l.next_level(2, &tally(&[(0.8, true), (0.7, false), (0.6, false)])),
            2
        );
        // two of three: down
        assert_eq!(
            l.next_level(2, &tally(&[(0.8, true), (0.7, true), (0.6, false)])),
            1
        );
        // the up rule is unchanged
        assert_eq!(l.next_level(1, &tally(&[(1.2, false)])), 2);
        // any fall at all, with a share of 0
        let strict = TerrainLevels {
            demote_fall_share: Some(0.0),
            ..levels(3)
        };
        assert_eq!(
            strict.next_level(2, &tally(&[(1.5, false), (0.9, true), (1.1, false)])),
            1
        );
    }

    #[test]
    fn a_tally_keeps_the_farthest_episode_even_when_all_went_backwards() {
        let t = tally(&[(-0.3, false), (-0.1, true)]);
        assert_eq!((t.ended, t.falls, t.fell()), (2, 1, true));
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
        for bad in ["1.0", "-0.1", "nan"] {
            let err = resolve(&format!(
                "terrains = [\"rigid\", \"elastic:5cm\"]\ndemote_fall_share = {bad}"
            ))
            .unwrap_err();
            assert!(
                err.contains("demote_fall_share") && err.contains("[0, 1)"),
                "{err}"
            );
        }
        let ok = resolve("terrains = [\"rigid\", \"elastic:5cm\"]").unwrap();
        assert_eq!(ok.promote_distance_m, DEFAULT_PROMOTE_DISTANCE_M);
        assert_eq!(ok.demote_fall_share, None);
        assert!(
            !ok.to_toml().contains("demote_fall_share"),
            "{}",
            ok.to_toml()
        );
        let with =
            resolve("terrains = [\"rigid\", \"elastic:5cm\"]\ndemote_fall_share = 0.5").unwrap();
        assert_eq!(with.demote_fall_share, Some(0.5));
        let back = toml::from_str::<LevelsSection>(
            with.to_toml()
                .trim_start()
                .trim_start_matches("[curriculum.levels]"),
        )
        .unwrap()
        .resolve(&registry)
        .unwrap();
        assert_eq!(back, with);
        assert_eq!(ok.top(), 1);
    }
}
