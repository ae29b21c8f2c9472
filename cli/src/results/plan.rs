//! The plan of `quadwalk results` (`docs/results/plan.toml`): which policies
//! are evaluated on which terrains, with how many episodes and seeds.
//!
//! ```toml
//! [evaluation]
//! episodes = 10                            # per seed set
//! phases = 400                             # per episode (0.75 s each)
//! seed_sets = [1000000, 5000000, 9000000]  # set k runs seeds s_k .. s_k + episodes - 1
//!
//! [scenarios]                              # Table I and Fig. 4: each on its own terrain
//! tv2 = "policies/tv2"
//! tv8 = "policies/tv8"
//! tc2 = "policies/tc2"
//! tc5 = "policies/tc5"
//!
//! [matrix]                                 # every policy on every terrain
//! policies = ["policies/rigid", "policies/tv2"]
//! terrains = ["rigid", "elastic:5cm", "rigid:friction=0.4"]
//! seed_sets = [1000000]                    # optional: fewer sets for its many cells
//!
//! [[ablation]]                             # one trained policy per variant and seed
//! variant = "full observation"
//! seed = 0
//! policy = "policies/elastic-5cm"
//! terrain = "elastic:5cm"
//!
//! [controllers]                            # controllers side by side (issue 42)
//! terrains = ["varying:2m:2,3,4,5cm,rigid", "soil:4cm"]
//! changes = ["switch:2cm:5cm:30"]          # terrains that change mid-episode
//! change_phases = 60                       # optional: phases of those episodes
//! task = ["base_height_reference=feet"]    # optional: `quadwalk eval --task` settings
//!                                          # that judge every controller alike
//! seed_sets = [1000000]                    # optional: its own seed sets
//! [[controllers.row]]
//! name = "phase level"
//! policy = "policies/tv2"
//! ```
//!
//! Policy paths are relative to the directory `quadwalk results` runs in
//! (the repository's root for the shipped plan). Every table is optional;
//! a plan needs at least one.

use std::path::Path;

use anyhow::{Context, Result, bail};
use serde::Deserialize;
use terrain_plugins::Registry;

/// The whole plan.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    /// how every evaluation runs
    pub evaluation: EvaluationPlan,
    /// the paper's four training scenarios (Table I, Fig. 4)
    pub scenarios: Option<Scenarios>,
    /// policies by terrains
    pub matrix: Option<MatrixPlan>,
    /// the observation ablations, one entry per trained policy
    #[serde(default)]
    pub ablation: Vec<AblationRun>,
    /// controllers side by side on terrains and through a change of the
    /// terrain
    pub controllers: Option<ControllersPlan>,
}

/// `[evaluation]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EvaluationPlan {
    /// episodes per seed set
    pub episodes: u32,
    /// phases per episode
    pub phases: u32,
    /// the first seed of each set of `episodes` consecutive seeds
    pub seed_sets: Vec<u64>,
}

/// `[scenarios]`: the policy trained on each of the paper's terrains.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenarios {
    /// T_v2: stiffness drawn every 2 m
    pub tv2: String,
    /// T_v8: stiffness drawn every 8 m
    pub tv8: String,
    /// T_c^2: 2 cm tiles everywhere
    pub tc2: String,
    /// T_c^5: 5 cm tiles everywhere
    pub tc5: String,
}

/// `[matrix]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MatrixPlan {
    /// the rows
    pub policies: Vec<String>,
    /// the columns: terrain specs (`rigid:friction=0.4` is rigid ground
    /// whose contacts have the friction coefficient 0.4)
    pub terrains: Vec<String>,
    /// the matrix's own seed sets, in place of `[evaluation]`'s (it has
    /// many cells)
    pub seed_sets: Option<Vec<u64>>,
}

/// `[[ablation]]`: one trained policy of an observation variant.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AblationRun {
    /// the variant's name (`full observation`, `no foot-position history`)
    pub variant: String,
    /// the training seed
    pub seed: u64,
    /// the trained policy (an exported policy or a run directory); its
    /// `metrics.jsonl` gives the learning curve
    pub policy: String,
    /// the terrain it is evaluated on
    pub terrain: String,
}

/// `[controllers]`: controllers (phase level, residual, single level)
/// side by side.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllersPlan {
    /// the rows
    pub row: Vec<ControllerRow>,
    /// the terrains of the success and speed table
    #[serde(default)]
    pub terrains: Vec<String>,
    /// terrains that change by themselves mid-episode (`switch:...`): the
    /// response table and figure
    #[serde(default)]
    pub changes: Vec<String>,
    /// phases of each episode on `changes` (`None`: `[evaluation]`'s); the
    /// response needs the change's time plus 6 s
    pub change_phases: Option<u32>,
    /// `KEY=VALUE` task settings over each terrain's default task
    /// (`quadwalk eval --task`), for every row alike
    #[serde(default)]
    pub task: Vec<String>,
    /// the section's own seed sets, in place of `[evaluation]`'s
    pub seed_sets: Option<Vec<u64>>,
}

/// `[[controllers.row]]`: one controller.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerRow {
    /// what the row is called (`phase level`, `residual`)
    pub name: String,
    /// its policy
    pub policy: String,
}

impl Plan {
    /// Reads and checks the plan at `path`: every spec parses with
    /// `registry`, every count is positive, every policy path exists.
    pub fn read(path: &Path, registry: &Registry) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("--plan {}: cannot read the plan", path.display()))?;
        let plan: Self = toml::from_str(&text)
            .with_context(|| format!("--plan {}: not a results plan", path.display()))?;
        plan.check(registry)
            .with_context(|| format!("--plan {}", path.display()))?;
        Ok(plan)
    }

    fn check(&self, registry: &Registry) -> Result<()> {
        let e = &self.evaluation;
        if e.episodes == 0 {
            bail!("evaluation.episodes = 0: must be at least 1");
        }
        if e.phases == 0 {
            bail!("evaluation.phases = 0: must be at least 1");
        }
        let check_sets = |key: &str, sets: &[u64]| -> Result<()> {
            if sets.is_empty() {
                bail!("{key} is empty: give at least one first seed");
            }
            let mut sorted = sets.to_vec();
            sorted.sort_unstable();
            for pair in sorted.windows(2) {
                if pair[1] - pair[0] < u64::from(e.episodes) {
                    bail!(
                        "{key} {} and {} overlap: each set runs {} consecutive seeds",
                        pair[0],
                        pair[1],
                        e.episodes
                    );
                }
            }
            Ok(())
        };
        check_sets("evaluation.seed_sets", &e.seed_sets)?;
        if let Some(sets) = self.matrix.as_ref().and_then(|m| m.seed_sets.as_ref()) {
            check_sets("matrix.seed_sets", sets)?;
        }
        if let Some(sets) = self.controllers.as_ref().and_then(|c| c.seed_sets.as_ref()) {
            check_sets("controllers.seed_sets", sets)?;
        }
        if self.scenarios.is_none()
            && self.matrix.is_none()
            && self.ablation.is_empty()
            && self.controllers.is_none()
        {
            bail!(
                "the plan has no [scenarios], [matrix], [[ablation]] or [controllers]: nothing to evaluate"
            );
        }
        let policy = |key: &str, p: &str| -> Result<()> {
            if p != "scripted" && !Path::new(p).exists() {
                bail!("{key} = {p:?}: no such policy (a path, or `scripted`)");
            }
            Ok(())
        };
        let spec = |key: &str, s: &str| -> Result<()> {
            registry
                .parse(s)
                .map(|_| ())
                .with_context(|| format!("{key} = {s:?}"))
        };
        if let Some(s) = &self.scenarios {
            for (key, p) in [
                ("scenarios.tv2", &s.tv2),
                ("scenarios.tv8", &s.tv8),
                ("scenarios.tc2", &s.tc2),
                ("scenarios.tc5", &s.tc5),
            ] {
                policy(key, p)?;
            }
        }
        if let Some(m) = &self.matrix {
            if m.policies.is_empty() || m.terrains.is_empty() {
                bail!("[matrix] needs at least one policy and one terrain");
            }
            for p in &m.policies {
                policy("matrix.policies", p)?;
            }
            for t in &m.terrains {
                spec("matrix.terrains", t)?;
            }
        }
        for run in &self.ablation {
            if run.variant.trim().is_empty() {
                bail!(
                    "[[ablation]] with policy {:?}: variant is empty",
                    run.policy
                );
            }
            policy("ablation.policy", &run.policy)?;
            spec("ablation.terrain", &run.terrain)?;
        }
        if let Some(c) = &self.controllers {
            if c.row.is_empty() || (c.terrains.is_empty() && c.changes.is_empty()) {
                bail!(
                    "[controllers] needs at least one [[controllers.row]] and one terrain or change"
                );
            }
            for row in &c.row {
                if row.name.trim().is_empty() {
                    bail!(
                        "[[controllers.row]] with policy {:?}: name is empty",
                        row.policy
                    );
                }
                policy("controllers.row.policy", &row.policy)?;
            }
            for t in &c.terrains {
                spec("controllers.terrains", t)?;
            }
            for t in &c.changes {
                spec("controllers.changes", t)?;
                let terrain = registry
                    .create(t, &terrain_plugins::BuildContext::default())
                    .with_context(|| format!("controllers.changes = {t:?}"))?;
                if terrain.change_times_secs().is_empty() {
                    bail!(
                        "controllers.changes = {t:?}: this terrain never changes by itself (a change is e.g. switch:2cm:5cm:30)"
                    );
                }
            }
            if c.change_phases == Some(0) {
                bail!("controllers.change_phases = 0: must be at least 1");
            }
            experiment::config::apply_task_overrides(&experiment::config::default_task(), &c.task)
                .map_err(|e| anyhow::anyhow!("controllers.task: {e}"))?;
        }
        Ok(())
    }

    /// The phases of each episode on the controllers' changing terrains.
    pub fn change_phases(&self) -> u32 {
        self.controllers
            .as_ref()
            .and_then(|c| c.change_phases)
            .unwrap_or(self.evaluation.phases)
    }

    /// The seeds of `sets`, set by set.
    pub fn seeds_of(&self, sets: &[u64]) -> Vec<u64> {
        sets.iter()
            .flat_map(|&s| (0..u64::from(self.evaluation.episodes)).map(move |k| s + k))
            .collect()
    }

    /// The seed sets of the matrix's cells.
    pub fn matrix_seed_sets(&self) -> &[u64] {
        self.matrix
            .as_ref()
            .and_then(|m| m.seed_sets.as_deref())
            .unwrap_or(&self.evaluation.seed_sets)
    }

    /// The seed sets of the controllers' cells.
    pub fn controllers_seed_sets(&self) -> &[u64] {
        self.controllers
            .as_ref()
            .and_then(|c| c.seed_sets.as_deref())
            .unwrap_or(&self.evaluation.seed_sets)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Plan> {
        let plan: Plan = toml::from_str(text)?;
        plan.check(&Registry::builtin())?;
        Ok(plan)
    }

    #[test]
    fn a_plan_lists_its_seeds_set_by_set() {
        let plan = parse(
            "[evaluation]\nepisodes = 2\nphases = 3\nseed_sets = [10, 20]\n[matrix]\npolicies = [\"scripted\"]\nterrains = [\"rigid\", \"rigid:friction=0.4\"]\n",
        )
        .unwrap();
        assert_eq!(plan.seeds_of(&plan.evaluation.seed_sets), [10, 11, 20, 21]);
        assert_eq!(plan.matrix_seed_sets(), [10, 20]);
        assert_eq!(plan.matrix.unwrap().terrains[1], "rigid:friction=0.4");
        let own = parse(
            "[evaluation]\nepisodes = 2\nphases = 3\nseed_sets = [10, 20]\n[matrix]\npolicies = [\"scripted\"]\nterrains = [\"rigid\"]\nseed_sets = [40]\n",
        )
        .unwrap();
        assert_eq!(own.matrix_seed_sets(), [40]);
        let controllers = parse(
            "[evaluation]\nepisodes = 2\nphases = 3\nseed_sets = [10]\n[controllers]\nterrains = [\"rigid\"]\nchanges = [\"switch:2cm:5cm:30\"]\nchange_phases = 60\n[[controllers.row]]\nname = \"crawl\"\npolicy = \"scripted\"\n",
        )
        .unwrap();
        assert_eq!(controllers.change_phases(), 60);
        assert_eq!(controllers.controllers_seed_sets(), [10]);
        let own_sets = parse(
            "[evaluation]\nepisodes = 2\nphases = 3\nseed_sets = [10]\n[controllers]\nterrains = [\"rigid\"]\nseed_sets = [50, 60]\n[[controllers.row]]\nname = \"crawl\"\npolicy = \"scripted\"\n",
        )
        .unwrap();
        assert_eq!(own_sets.controllers_seed_sets(), [50, 60]);
        assert_eq!(controllers.controllers.unwrap().row[0].name, "crawl");
        assert_eq!(own.seeds_of(own.matrix_seed_sets()), [40, 41]);
    }

    #[test]
    fn bad_plans_name_the_setting() {
        let base = "[evaluation]\nepisodes = 2\nphases = 3\n";
        let err = |text: &str| format!("{:#}", parse(text).unwrap_err());
        let matrix = "[matrix]\npolicies = [\"scripted\"]\nterrains = [\"rigid\"]\n";
        assert!(
            err(&format!("{base}seed_sets = [10, 11]\n{matrix}")).contains("overlap"),
            "overlapping sets"
        );
        assert!(err(&format!("{base}seed_sets = []\n{matrix}")).contains("seed_sets is empty"));
        assert!(
            err(&format!("{base}seed_sets = [1]\n")).contains("nothing to evaluate"),
            "no tables"
        );
        let e = err(&format!(
            "{base}seed_sets = [1]\n[matrix]\npolicies = [\"no/such/policy\"]\nterrains = [\"rigid\"]\n"
        ));
        assert!(e.contains("no/such/policy"), "{e}");
        let e = err(&format!(
            "{base}seed_sets = [1]\n[matrix]\npolicies = [\"scripted\"]\nterrains = [\"marsh:5cm\"]\n"
        ));
        assert!(e.contains("marsh:5cm"), "{e}");
        let controllers = |body: &str| {
            err(&format!(
                "{base}seed_sets = [1]\n[controllers]\n{body}\n[[controllers.row]]\nname = \"crawl\"\npolicy = \"scripted\"\n"
            ))
        };
        let e = controllers("terrains = [\"rigid\"]\nchanges = [\"elastic:5cm\"]");
        assert!(e.contains("never changes by itself"), "{e}");
        let e = controllers("terrains = []");
        assert!(e.contains("one terrain or change"), "{e}");
        let e = controllers("changes = [\"switch:2cm:5cm:30\"]\nchange_phases = 0");
        assert!(e.contains("change_phases = 0"), "{e}");
        let e = controllers("terrains = [\"rigid\"]\ntask = [\"base_height_reference=belly\"]");
        assert!(
            e.contains("controllers.task: --task \"base_height_reference=belly\""),
            "{e}"
        );
        let e = err(&format!("{base}seed_sets = [1]\nepisodez = 3\n{matrix}"));
        assert!(e.contains("episodez"), "unknown keys are refused: {e}");
    }
}
