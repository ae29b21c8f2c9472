//! Built-in training recipes: what `quadwalk train --terrain SPEC` runs when
//! no `--config` is given and quadwalk has a recipe for SPEC.
//!
//! A recipe is an experiment file in `configs/`, compiled in, so the command
//! users type first trains what the notebook measured best rather than the
//! bare defaults. Two: `elastic:5cm`, the 5 cm recipe
//! (`configs/elastic-5cm-margin.toml`: a terrain level per world from rigid
//! ground to 5 cm tiles with mirror augmentation, then 5 cm tiles with a
//! training pitch limit below the paper's; the policy observes the goals'
//! line ahead), and the paper's T_v2, `varying:2m:2,3,4,5cm,rigid`
//! (`configs/tv2-levels.toml`: the first 460 iterations of the 5 cm recipe
//! before it, `configs/elastic-5cm-levels.toml`, then the passages between
//! rigid ground and deep tiles). An experiment file whose `[terrain]` names
//! the same spec trains without it.

use anyhow::{Context, Result};
use terrain_plugins::Registry;

use crate::config::Experiment;

/// A recipe: the terrain it is for, where its file lives in the
/// repository, and the file.
pub struct Recipe {
    /// the terrain spec `--terrain` names (as the registry writes it)
    pub terrain: &'static str,
    /// the file in the repository, for messages
    pub path: &'static str,
    /// its text
    pub toml: &'static str,
}

/// Every built-in recipe.
pub const RECIPES: [Recipe; 2] = [
    Recipe {
        terrain: "elastic:5cm",
        path: "configs/elastic-5cm-margin.toml",
        toml: include_str!("../../configs/elastic-5cm-margin.toml"),
    },
    Recipe {
        terrain: "varying:2m:2cm,3cm,4cm,5cm,rigid",
        path: "configs/tv2-levels.toml",
        toml: include_str!("../../configs/tv2-levels.toml"),
    },
];

/// The recipe for `experiment`'s terrain, if quadwalk has one.
pub fn recipe_for(experiment: &Experiment) -> Option<&'static Recipe> {
    let spec = experiment.terrain.to_string();
    RECIPES.iter().find(|r| r.terrain == spec)
}

impl Recipe {
    /// The recipe's experiment.
    pub fn experiment(&self, registry: &Registry) -> Result<Experiment> {
        Experiment::from_toml(self.toml, self.path, registry)
            .with_context(|| format!("the built-in recipe for {}", self.terrain))
    }

    /// One line on what the recipe does, from its stages (consecutive
    /// stages on one terrain counted together; a stage of terrain levels
    /// named by its lowest and highest level).
    pub fn describe(&self, experiment: &Experiment) -> String {
        // consecutive fixed stages on one terrain read as one
        let mut runs: Vec<(String, u64, Option<String>)> = Vec::new();
        for stage in &experiment.curriculum {
            let terrain = match &stage.levels {
                Some(levels) => format!(
                    "levels {}..{}",
                    levels.terrains[0],
                    levels.terrains[levels.top()]
                ),
                None => stage.terrain.to_string(),
            };
            let survival = stage.advance.map(|rule| rule.describe());
            match runs.last_mut() {
                Some((last, n, None)) if *last == terrain && survival.is_none() => {
                    *n += stage.iterations
                }
                _ => runs.push((terrain, stage.iterations, survival)),
            }
        }
        let stages: Vec<String> = runs
            .iter()
            .map(|(terrain, n, survival)| match survival {
                None => format!("{terrain} x{n}"),
                Some(rule) => format!("{terrain} x{n} at most (until {rule})"),
            })
            .collect();
        let at_most = if experiment.has_advance_rules() {
            "at most "
        } else {
            ""
        };
        format!(
            "{}: quadwalk's recipe ({}): {} ({at_most}{} iterations); a --config whose [terrain] spec is {:?} trains without it",
            self.terrain,
            self.path,
            stages.join(" -> "),
            experiment.total_iterations(),
            self.terrain,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_recipe_parses_and_is_for_its_terrain() {
        let registry = Registry::builtin();
        for recipe in &RECIPES {
            let e = recipe.experiment(&registry).unwrap();
            assert_eq!(e.terrain.to_string(), recipe.terrain, "{}", recipe.path);
            assert!(recipe_for(&e).is_some());
            assert!(!e.curriculum.is_empty(), "{}", recipe.path);
            assert!(recipe.describe(&e).contains(recipe.path));
        }
        let five = RECIPES[0].experiment(&registry).unwrap();
        assert_eq!(
            five.curriculum.last().unwrap().terrain.to_string(),
            "elastic:5cm",
            "the 5 cm recipe ends on its terrain"
        );
        assert!(
            RECIPES[0]
                .describe(&five)
                .contains("levels rigid..elastic:5cm x280 -> elastic:5cm x140 (420 iterations)"),
            "{}",
            RECIPES[0].describe(&five)
        );
        // the 5 cm recipe before this one (policies/elastic-5cm's): this one
        // shares its levels (a checkpoint at 280 forks into either), the T_v2
        // recipe its first 460 iterations, stage for stage
        let before = Experiment::from_toml(
            include_str!("../../configs/elastic-5cm-levels.toml"),
            "configs/elastic-5cm-levels.toml",
            &registry,
        )
        .unwrap();
        assert_eq!(five.differs_before(&before, 280), None);
        assert!(five.differs_before(&before, 281).is_some());
        let tv2 = RECIPES[1].experiment(&registry).unwrap();
        assert!(
            RECIPES[1].describe(&tv2).contains(
                "levels rigid..elastic:5cm x280 -> elastic:5cm x180 -> varying:2m:4cm,5cm,rigid x40 (500 iterations)"
            ),
            "{}",
            RECIPES[1].describe(&tv2)
        );
        assert_eq!(
            tv2.curriculum.last().unwrap().terrain.to_string(),
            "varying:2m:4cm,5cm,rigid",
            "T_v2's recipe ends on T_v2's hardest passages"
        );
        assert_eq!(tv2.differs_before(&before, 460), None);
        assert!(tv2.differs_before(&before, 461).is_some());
        let rigid = Experiment::for_terrain(registry.parse("rigid").unwrap());
        assert!(recipe_for(&rigid).is_none());
    }
}
