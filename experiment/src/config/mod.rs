//! Experiment files in TOML: `[terrain]`, `[task]`, `[physics]`, `[algo]`,
//! `[ppo]`, `[sac]`, `[train]`, `[[curriculum]]` and `[residual]` (a
//! lower-level policy within a phase policy's phases, see [`residual`]). Every section but the terrain is optional (defaults
//! where silent); unknown keys are errors.
//!
//! ```toml
//! [algo]
//! name = "ppo"            # the paper's learner; or "sac" (soft actor-critic),
//!                         # or "crossq" (SAC with CrossQ's critics and settings)
//!
//! [sac]                   # learn::sac::SacConfig, used when algo.name = "sac" or
//!                         # "crossq"; its defaults are SacConfig::crossq() for "crossq"
//! updates_per_step = 1.0  # gradient steps per transition collected
//! buffer_size = 200000
//!
//! [ppo]                   # learn::PpoConfig: the paper's values, but minibatch_size = 128
//! learning_rate = 2e-4
//! steps_per_env = 40
//!
//! [train]
//! envs = 16               # parallel worlds
//! iterations = 100        # ignored when a curriculum is given (the sum of its stages)
//! seed = 0
//! checkpoint_every = 10   # iterations
//! keep_checkpoints = 5    # older ones are deleted
//! rerun_envs = [0]        # environments whose rollouts are streamed
//!
//! [[curriculum]]          # stages in order; replaces [terrain]
//! terrain = "varying:2m:2,3,4,5cm,rigid"
//! iterations = 200
//! [[curriculum]]
//! terrain = "elastic:5cm"
//! iterations = 100
//! learning_rate = 5e-5    # optional: the learner's rate in this stage (stages
//!                         # without one use [ppo]/[sac]'s; not with desired_kl)
//! [curriculum.task]       # optional: [task] keys for this stage only, on top of
//! max_paid_progress_m = 0.03  # [task] (not observation or action_prior: the
//!                         # networks' input is fixed for a run)
//! [curriculum.advance]    # optional: end the stage when the policy is ready,
//! survival = 0.95         # iterations then at most (see `advance`)
//! window = 10
//! [[curriculum]]          # a stage whose worlds each train on their own
//! iterations = 300        # terrain level, moving up as they walk (no
//! [curriculum.levels]     # `terrain`; see `levels`)
//! terrains = ["rigid", "elastic:1cm", "elastic:2cm"]
//! ```
//!
//! `[task]` is `robot::task::TaskConfig` and `[physics]` `robot::WorldConfig`,
//! each with its keys, defaults and validation documented beside it; where
//! the file is silent, the task takes quadwalk's defaults ([`default_task`]).
//!
//! The terrain is given either as a spec string or as a table whose keys are
//! the plugin's parameters; both go through the same registry validation:
//!
//! ```toml
//! [terrain]
//! spec = "varying:2m:2,3,4,5cm,rigid"
//! ```
//!
//! ```toml
//! [terrain]
//! plugin = "elastic"
//! depth = "5cm"
//! travel = "12cm"
//! damping = 0.4
//! ```
//!
//! Lists may be TOML arrays: `surfaces = ["2cm", "5cm", "rigid"]`.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};
#[cfg(test)]
use learn::PpoConfig;
use learn::Settings;
use learn::registry::{self, Registration};
pub use residual::ResidualConfig;
use robot::WorldConfig;
use robot::task::TaskConfig;
use serde::{Deserialize, Serialize};
use terrain_plugins::{Registry, TerrainSpec};

pub mod advance;
mod curriculum;
mod defaults;
mod fork;
pub mod levels;
pub mod residual;
mod task_overrides;
mod terrain_table;
mod train_settings;

pub use curriculum::Stage;
pub use defaults::{default_ppo, default_task};
pub use task_overrides::apply_task_overrides;
pub use train_settings::TrainSettings;

use curriculum::curriculum_from_doc;
use defaults::{resolve_learner, resolve_physics, resolve_task};
use terrain_table::terrain_from_table;

/// The sections an experiment file may have: the fixed ones and every
/// registered algorithm's table.
fn known_sections() -> Vec<&'static str> {
    let mut known = vec!["terrain", "task", "physics", "algo"];
    known.extend(registry::tables());
    known.extend(["train", "curriculum", "residual"]);
    known
}

/// A parsed experiment file.
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// the terrain
    pub terrain: TerrainSpec,
    /// the task settings (defaults where the file is silent)
    pub task: TaskConfig,
    /// how the world is simulated (defaults where the file is silent)
    pub physics: WorldConfig,
    /// which learner trains
    pub algo: &'static Registration,
    /// every algorithm table's settings (`[ppo]`, `[sac]`), resolved: the
    /// learner's table by the learner, each other by the first algorithm
    /// registered for it
    pub settings: BTreeMap<&'static str, Box<dyn Settings>>,
    /// the file's algorithm tables as written, kept so that a learner named
    /// on the command line gets its own defaults under the file's values
    pub algo_tables: AlgoTables,
    /// the training run's settings
    pub train: TrainSettings,
    /// curriculum stages, in order (empty: the terrain for all iterations)
    pub curriculum: Vec<Stage>,
    /// `[residual]`: the policy trained moves the feet's targets within the
    /// phases a frozen phase-level policy plans (`None`: the policy is the
    /// phase-level one)
    pub residual: Option<ResidualConfig>,
}

/// The algorithm tables as written. They take no part in comparisons: two
/// experiments are equal when their resolved settings
/// (`Experiment::settings`) are, however the file spelled them.
#[derive(Debug, Clone, Default)]
pub struct AlgoTables(pub BTreeMap<String, toml::Table>);

impl PartialEq for AlgoTables {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// `[algo]`: which learner trains.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AlgoSection {
    name: String,
}

impl Experiment {
    /// Reads an experiment file; its terrain specs are parsed with `registry`.
    pub fn from_file(path: &Path, registry: &Registry) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("config {}: cannot read it", path.display()))?;
        Self::from_toml(&text, &path.display().to_string(), registry)
    }

    /// Parses TOML text; `source` names it in errors; terrain specs are
    /// parsed with `registry`.
    pub fn from_toml(text: &str, source: &str, registry: &Registry) -> Result<Self> {
        let doc: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            anyhow!("config {source}: not valid TOML: {}", e.message())
        })?;
        let known = known_sections();
        for key in doc.keys() {
            if !known.contains(&key.as_str()) {
                bail!(
                    "config {source}: unknown section or key {key:?} (known: {})",
                    known.join(", ")
                );
            }
        }
        let task_table = match doc.get("task") {
            None => toml::Table::new(),
            Some(toml::Value::Table(table)) => table.clone(),
            Some(_) => bail!("config {source} [task]: must be a table"),
        };
        let physics = match doc.get("physics") {
            None => WorldConfig::default(),
            Some(toml::Value::Table(table)) => resolve_physics(&WorldConfig::default(), table)
                .map_err(|e| anyhow!("config {source} [physics]: {e}"))?,
            Some(_) => bail!("config {source} [physics]: must be a table"),
        };
        let curriculum = curriculum_from_doc(&doc, &task_table, &physics, source, registry)?;
        let terrain = match (doc.get("terrain"), curriculum.first()) {
            (None, Some(first)) => first.terrain.clone(),
            _ => terrain_from_table(&doc, source, registry)?,
        };
        let mut algo_tables = BTreeMap::new();
        for table in registry::tables() {
            match doc.get(table) {
                None => {}
                Some(toml::Value::Table(t)) => {
                    algo_tables.insert(table.to_string(), t.clone());
                }
                Some(_) => bail!("config {source} [{table}]: must be a table"),
            }
        }
        let algo = match doc.get("algo") {
            None => registry::default_algorithm(),
            Some(value) => {
                let section: AlgoSection =
                    value.clone().try_into().map_err(|e: toml::de::Error| {
                        anyhow!("config {source} [algo]: {}", e.message())
                    })?;
                registry::find(&section.name)
                    .map_err(|e| anyhow!("config {source} [algo]: name = {e}"))?
            }
        };
        let train: TrainSettings = match doc.get("train") {
            None => TrainSettings::default(),
            Some(value) => value.clone().try_into().map_err(|e: toml::de::Error| {
                anyhow!("config {source} [train]: {}", e.message())
            })?,
        };
        train
            .validate()
            .with_context(|| format!("config {source} [train]"))?;
        let task = resolve_task(&task_table).map_err(|e| anyhow!("config {source} [task]: {e}"))?;
        let residual = match doc.get("residual") {
            None => None,
            Some(value) => {
                let residual: ResidualConfig =
                    value.clone().try_into().map_err(|e: toml::de::Error| {
                        anyhow!("config {source} [residual]: {}", e.message())
                    })?;
                residual
                    .validate(physics.steps_per_phase())
                    .with_context(|| format!("config {source} [residual]"))?;
                for (k, stage) in curriculum.iter().enumerate() {
                    if let Some(stage_physics) = &stage.physics {
                        residual
                            .validate(stage_physics.steps_per_phase())
                            .with_context(|| {
                                format!(
                                    "config {source} [residual] in [[curriculum]] stage {}'s physics",
                                    k + 1
                                )
                            })?;
                    }
                }
                Some(residual)
            }
        };
        let algo_tables = AlgoTables(algo_tables);
        let settings = algo_tables
            .resolve(algo)
            .map_err(|e| anyhow!("config {source} {e}"))?;
        let experiment = Self {
            terrain,
            task,
            physics,
            algo,
            settings,
            algo_tables,
            train,
            curriculum,
            residual,
        };
        experiment.check_stage_rates(&format!("config {source}"))?;
        experiment.check_stage_observations(&format!("config {source}"))?;
        experiment.check_stage_levels(&format!("config {source}"))?;
        if experiment.residual.is_some() && experiment.curriculum.iter().any(|s| s.levels.is_some())
        {
            bail!(
                "config {source}: [curriculum.levels] moves phase-level policies between terrains by how they walk; a [residual] run cannot have them"
            );
        }
        Ok(experiment)
    }

    /// Switches the learner (`--algo`): its table's settings become the
    /// algorithm's defaults under the file's values.
    pub fn set_algo(&mut self, algo: &'static Registration) -> Result<()> {
        self.settings = self
            .algo_tables
            .resolve(algo)
            .map_err(|e| anyhow!("--algo {}: {e}", algo.name))?;
        self.algo = algo;
        self.check_stage_rates(&format!("--algo {}", algo.name))?;
        self.check_stage_levels(&format!("--algo {}", algo.name))
    }

    /// The learner's settings.
    pub fn learner(&self) -> &dyn Settings {
        &*self.settings[self.algo.table]
    }

    /// The experiment for a terrain spec with every other setting at its
    /// default.
    pub fn for_terrain(terrain: TerrainSpec) -> Self {
        Self {
            terrain,
            task: default_task(),
            physics: WorldConfig::default(),
            algo: registry::default_algorithm(),
            settings: AlgoTables::default()
                .resolve(registry::default_algorithm())
                .expect("the default settings are valid"),
            algo_tables: AlgoTables::default(),
            train: TrainSettings::default(),
            curriculum: Vec::new(),
            residual: None,
        }
    }

    /// The whole experiment as TOML, every value spelt out; parsing it
    /// gives this experiment back.
    pub fn to_toml(&self) -> String {
        let mut text = format!(
            "# quadwalk experiment, every setting resolved\n\n[terrain]\nspec = {:?}\n\n",
            self.terrain.to_string()
        );
        // a struct, not a `toml::Table`, so that the keys keep the order
        // `TaskConfig` declares them in
        #[derive(Serialize)]
        struct TaskTable<'a> {
            task: &'a TaskConfig,
        }
        let task = TaskTable { task: &self.task };
        text.push_str(&toml::to_string(&task).expect("task settings serialise"));
        text.push('\n');
        text.push_str(&format!("[physics]\n{}\n", physics_toml(&self.physics)));
        text.push_str(&format!("[algo]\nname = {:?}\n\n", self.algo.name));
        let mut tables = toml::Table::new();
        for (name, settings) in &self.settings {
            tables.insert(name.to_string(), toml::Value::Table(settings.to_table()));
        }
        tables.insert(
            "train".into(),
            toml::Value::try_from(&self.train).expect("train settings serialise"),
        );
        text.push_str(&toml::to_string(&tables).expect("a table serialises"));
        for stage in &self.curriculum {
            text.push_str("\n[[curriculum]]\n");
            if stage.levels.is_none() {
                text.push_str(&format!("terrain = {:?}\n", stage.terrain.to_string()));
            }
            text.push_str(&format!("iterations = {}\n", stage.iterations));
            if let Some(rate) = stage.learning_rate {
                text.push_str(&format!("learning_rate = {rate:?}\n"));
            }
            if let Some(rule) = &stage.advance {
                text.push_str(&format!(
                    "\n[curriculum.advance]\nsurvival = {:?}\n",
                    rule.survival
                ));
                if let Some(d) = rule.distance_m {
                    text.push_str(&format!("distance_m = {d:?}\n"));
                }
                text.push_str(&format!("window = {}\n", rule.window));
            }
            if let Some(levels) = &stage.levels {
                text.push_str(&levels.to_toml());
            }
            if !stage.task_overrides.is_empty() {
                let (tables, keys): (toml::Table, toml::Table) = stage
                    .task_overrides
                    .clone()
                    .into_iter()
                    .partition(|(_, v)| v.is_table());
                text.push_str("\n[curriculum.task]\n");
                text.push_str(&toml::to_string(&keys).expect("a table serialises"));
                for (name, table) in tables {
                    text.push_str(&format!("\n[curriculum.task.{name}]\n"));
                    text.push_str(&toml::to_string(&table).expect("a table serialises"));
                }
            }
            if !stage.physics_overrides.is_empty() {
                text.push_str("\n[curriculum.physics]\n");
                text.push_str(
                    &toml::to_string(&stage.physics_overrides).expect("a table serialises"),
                );
            }
        }
        if let Some(residual) = &self.residual {
            text.push_str(
                "
[residual]
",
            );
            text.push_str(&toml::to_string(residual).expect("residual settings serialise"));
        }
        text
    }
}

/// The `[physics]` table's keys and values for `physics` (without the
/// header): every key spelt out, in the order an experiment file lists them.
pub fn physics_toml(physics: &WorldConfig) -> String {
    toml::to_string(physics).expect("physics settings serialise")
}

/// The `[physics]` settings as JSON, under the keys of the experiment file.
pub fn physics_json(physics: &WorldConfig) -> serde_json::Value {
    serde_json::to_value(physics).expect("physics settings serialise")
}

impl AlgoTables {
    /// Every algorithm table's settings with `algo` the learner: its table
    /// resolved by it, each other table by the first algorithm registered
    /// for it. The error names the table.
    fn resolve(
        &self,
        algo: &'static Registration,
    ) -> Result<BTreeMap<&'static str, Box<dyn Settings>>> {
        let mut settings = BTreeMap::new();
        for first in registry::ALGORITHMS {
            let table = first.table;
            if settings.contains_key(table) {
                continue;
            }
            let reader = if algo.table == table { algo } else { first };
            let resolved = resolve_learner(reader, self.0.get(table))
                .map_err(|e| anyhow!("[{table}]: {e}"))?;
            settings.insert(table, resolved);
        }
        Ok(settings)
    }
}

#[cfg(test)]
impl Experiment {
    /// The `[ppo]` settings.
    pub(crate) fn ppo(&self) -> &PpoConfig {
        self.settings["ppo"]
            .as_any()
            .downcast_ref()
            .expect("[ppo] holds PPO settings")
    }

    /// The `[sac]` settings.
    pub(crate) fn sac(&self) -> &learn::sac::SacConfig {
        self.settings["sac"]
            .as_any()
            .downcast_ref()
            .expect("[sac] holds SAC settings")
    }

    /// [`Experiment::from_toml`] with the built-in terrains.
    pub(crate) fn from_toml_builtin(text: &str, source: &str) -> Result<Self> {
        Self::from_toml(text, source, &Registry::builtin())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use robot::PdModel;
    use robot::task::{ActionPrior, BalanceTerms, DistanceReward};

    fn terrain_from_toml(text: &str, source: &str) -> Result<TerrainSpec> {
        Experiment::from_toml_builtin(text, source).map(|e| e.terrain)
    }

    #[test]
    fn a_foot_history_one_phase_shorter_is_set_checked_and_written_back() {
        let e = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[task.observation]\nfoot_history_phases = 2\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(e.task.observation.foot_history_phases, 2);
        assert_eq!(e.task.observation_size(), 102 - 12);
        let text = e.to_toml();
        assert!(text.contains("foot_history_phases = 2\n"), "{text}");
        assert_eq!(
            Experiment::from_toml_builtin(&text, "round trip").unwrap(),
            e
        );
        // the paper's 3 is not written (files stay as they were)
        let full =
            Experiment::from_toml_builtin("[terrain]\nspec = \"rigid\"\n", "t.toml").unwrap();
        assert!(!full.to_toml().contains("foot_history_phases"));
        for (bad, says) in [
            ("foot_history_phases = 0", "must be 1 to 3"),
            ("foot_history_phases = 4", "must be 1 to 3"),
            (
                "foot_history = false\nfoot_history_phases = 2",
                "keep one of the two",
            ),
        ] {
            let err = format!(
                "{:#}",
                Experiment::from_toml_builtin(
                    &format!("[terrain]\nspec = \"rigid\"\n[task.observation]\n{bad}\n"),
                    "t.toml"
                )
                .unwrap_err()
            );
            assert!(err.contains("t.toml") && err.contains(says), "{bad}: {err}");
        }
    }

    #[test]
    fn task_section_sets_the_task_and_refuses_unknown_keys() {
        let e = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[task]\nmax_phases = 12\ndistance_reward = \"new_ground\"\naction_prior = \"scripted_crawl\"\n[task.observation]\nfoot_history = false\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(e.task.max_phases, 12);
        assert_eq!(e.task.action_prior, ActionPrior::ScriptedCrawl);
        assert_eq!(e.task.observation_size(), 102 - 36 + 27);
        assert_eq!(e.task.distance_reward, DistanceReward::NewGround);
        let f = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[task]\ndistance_reward = \"forward\"\nforward_reward_per_m = 30.0\ntarget_progress_m = 0.03\nbalance_terms = \"penalty\"\n[algo]\nname = \"sac\"\n[sac]\nupdates_per_step = 2.0\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(f.task.distance_reward, DistanceReward::Forward);
        assert_eq!(f.task.forward_reward_per_m, 30.0);
        assert_eq!(f.task.target_progress_m, 0.03);
        assert_eq!(f.task.balance_terms, BalanceTerms::Penalty);
        assert_eq!(f.algo.name, "sac");
        assert_eq!(f.sac().updates_per_step, 2.0);
        assert_eq!(
            Experiment::from_toml_builtin(&f.to_toml(), "round trip").unwrap(),
            f
        );
        // --algo crossq: CrossQ's defaults under the file's [sac] values
        let mut g = f.clone();
        g.set_algo(registry::find("crossq").unwrap()).unwrap();
        assert_eq!(g.sac().variant, learn::sac::SacVariant::CrossQ);
        assert_eq!(g.sac().policy_delay, 3);
        assert_eq!(g.sac().updates_per_step, 2.0);
        assert_eq!(
            Experiment::from_toml_builtin(&g.to_toml(), "round trip")
                .unwrap()
                .sac(),
            g.sac()
        );
        let crossq = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[algo]\nname = \"crossq\"\n[sac]\nlearning_rate = 3e-4\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(crossq.sac().learning_rate, 3e-4);
        assert_eq!(crossq.sac().adam_beta1, 0.5);
        let err = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[algo]\nname = \"crossq\"\n[sac]\nvariant = \"sac\"\n",
            "t.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("[sac]") && err.contains("contradicts"),
            "{err}"
        );
        let err = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[sac]\npolicy_delay = 0\n",
            "t.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("t.toml [sac]") && err.contains("policy_delay"),
            "{err}"
        );
        assert_eq!(
            Experiment::from_toml_builtin("[terrain]\nspec = \"rigid\"\n", "t.toml")
                .unwrap()
                .task
                .distance_reward,
            DistanceReward::NewGround,
            "quadwalk's default: no pay for rocking"
        );
        assert_eq!(
            TaskConfig::default().distance_reward,
            DistanceReward::Progress,
            "the library's default is the paper's term"
        );
        assert_eq!(
            TaskConfig::default().action_prior,
            ActionPrior::None,
            "the paper's action by default"
        );
        assert!(!e.task.observation.foot_history);
        assert_eq!(e.task.observation.size(), 102 - 36);
        // the first goal: the paper's (goal_spacing_m ahead) unless drawn
        assert_eq!(e.task.first_goal_ahead_range_m, None);
        assert_eq!(e.task.goal_y_offset_range_m, (0.0, 0.0));
        let goals = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[task]\nfirst_goal_ahead_range_m = [0.1, 2.3]\ngoal_y_offset_range_m = [-0.4, 0.4]\norientation_lookahead_m = 1.0\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(goals.task.first_goal_ahead_range_m, Some((0.1, 2.3)));
        assert_eq!(goals.task.goal_y_offset_range_m, (-0.4, 0.4));
        assert_eq!(goals.task.orientation_lookahead_m, 1.0);
        assert_eq!(
            e.task.orientation_lookahead_m, 0.0,
            "the paper's: the current goal"
        );
        assert_eq!(
            Experiment::from_toml_builtin(&goals.to_toml(), "round trip").unwrap(),
            goals
        );
        // the goal blocks show the goals' line ahead: same size, round trip
        assert_eq!(e.task.observation.goal_line_ahead_m, None, "the paper's");
        let line = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[task.observation]\ngoal_line_ahead_m = 1.5\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(line.task.observation.goal_line_ahead_m, Some(1.5));
        assert_eq!(line.task.observation_size(), 102);
        assert_eq!(
            Experiment::from_toml_builtin(&line.to_toml(), "round trip").unwrap(),
            line
        );
        for (text, expected) in [
            (
                "[terrain]\nspec = \"rigid\"\n[task]\nmax_phase = 3\n",
                "unknown field `max_phase`",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\nmax_phases = 0\n",
                "at least 1",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\ngoal_spacing_m = -2.0\n",
                "positive",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\nstart_x_range_m = [1.0, 0.0]\n",
                "low <= high",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\nfirst_goal_ahead_range_m = [0.0, 2.0]\n",
                "first_goal_ahead_range_m must be [low, high] with 0 < low <= high, got [0, 2]",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\norientation_lookahead_m = -1.0\n",
                "orientation_lookahead_m must be in [0, 100] m, got -1",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\ngoal_y_offset_range_m = [0.4, -0.4]\n",
                "goal_y_offset_range_m must be [low, high] with low <= high",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task.observation]\nfoot_speed = true\n",
                "unknown field `foot_speed`",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task.observation]\ngoal_line_ahead_m = 0.0\n",
                "observation.goal_line_ahead_m must be in (0, 100] m, got 0",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\norientation_lookahead_m = 1.0\n[task.observation]\ngoal_line_ahead_m = 1.0\n",
                "orientation_lookahead_m = 1 and observation.goal_line_ahead_m = 1 both set R_o's heading target",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\ndistance_reward = \"backward\"\n",
                "distance_reward must be \"progress\" (the paper's), \"new_ground\", \"forward\" or \"tracking\", got \"backward\"",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[task]\naction_prior = \"crawl\"\n",
                "action_prior must be \"none\" (the paper's) or \"scripted_crawl\", got \"crawl\"",
            ),
        ] {
            let err = format!(
                "{:#}",
                Experiment::from_toml_builtin(text, "t.toml").unwrap_err()
            );
            assert!(
                err.contains(expected) && err.contains("t.toml [task]"),
                "{text:?} gave {err:?}"
            );
        }
    }

    #[test]
    fn keeping_the_first_iterations_cuts_a_curriculum_and_never_lengthens_it() {
        let text = "[[curriculum]]\nterrain = \"rigid\"\niterations = 3\n[[curriculum]]\nterrain = \"elastic:5cm\"\niterations = 2\n";
        let e = Experiment::from_toml_builtin(text, "c.toml").unwrap();
        let cut = |n: u64| {
            let mut cut = e.clone();
            cut.keep_first_iterations(n).map(|()| {
                cut.curriculum
                    .iter()
                    .map(|s| (s.terrain.to_string(), s.iterations))
                    .collect::<Vec<_>>()
            })
        };
        assert_eq!(cut(2).unwrap(), vec![("rigid".to_string(), 2)]);
        assert_eq!(cut(3).unwrap(), vec![("rigid".to_string(), 3)]);
        assert_eq!(
            cut(4).unwrap(),
            vec![("rigid".to_string(), 3), ("elastic:5cm".to_string(), 1)]
        );
        assert_eq!(cut(5).unwrap().len(), 2);
        let err = format!("{:#}", cut(6).unwrap_err());
        assert!(err.contains("the curriculum has 5 iterations"), "{err}");
        // without a curriculum it is the total
        let mut plain =
            Experiment::from_toml_builtin("[terrain]\nspec = \"rigid\"\n", "p.toml").unwrap();
        plain.keep_first_iterations(7).unwrap();
        assert_eq!(plain.total_iterations(), 7);
    }

    #[test]
    fn resolved_toml_parses_back_to_the_same_experiment() {
        let text = "[[curriculum]]\nterrain = \"varying:2m:2,3,4,5cm,rigid\"\niterations = 3\n[[curriculum]]\nterrain = \"elastic:5cm\"\niterations = 2\n[ppo]\nlearning_rate = 1e-3\ntarget_kl = 0.02\n[train]\nenvs = 4\nrerun_envs = [0, 3]\n[task]\nmax_phases = 12\ndistance_reward = \"new_ground\"\naction_prior = \"scripted_crawl\"\n[task.observation]\nshort_history = false\n";
        let e = Experiment::from_toml_builtin(text, "c.toml").unwrap();
        assert_eq!(e.total_iterations(), 5);
        assert_eq!(e.terrain.to_string(), "varying:2m:2cm,3cm,4cm,5cm,rigid");
        assert_eq!(e.terrain_at(2).0, 0);
        assert_eq!(e.terrain_at(3).1.to_string(), "elastic:5cm");
        assert_eq!(e.terrain_at(99).0, 1);
        assert_eq!(e.learning_rate_at(0), None); // no stage sets one
        let back = Experiment::from_toml_builtin(&e.to_toml(), "resolved").unwrap();
        assert_eq!(back, e);
        // a stage's own learning rate; the others run at [ppo]'s
        let staged = text.replace("iterations = 2\n", "iterations = 2\nlearning_rate = 5e-5\n");
        let e = Experiment::from_toml_builtin(&staged, "c.toml").unwrap();
        assert_eq!(e.curriculum[1].learning_rate, Some(5e-5));
        assert_eq!(e.learning_rate_at(0), Some(1e-3));
        assert_eq!(e.learning_rate_at(3), Some(5e-5));
        assert_eq!(e.learning_rate_at(99), Some(5e-5));
        assert!(
            e.to_toml().contains("learning_rate = 5e-5\n"),
            "{}",
            e.to_toml()
        );
        assert_eq!(
            Experiment::from_toml_builtin(&e.to_toml(), "resolved").unwrap(),
            e
        );
        let plain = Experiment::for_terrain(Registry::builtin().parse("rigid").unwrap());
        assert_eq!(
            Experiment::from_toml_builtin(&plain.to_toml(), "r").unwrap(),
            plain
        );
    }

    /// `e` written out holds `section` and reads back as `e`.
    fn writes_and_reads_back(e: &Experiment, section: &str) {
        let resolved = e.to_toml();
        assert!(resolved.contains(section), "{resolved}");
        assert_eq!(
            &Experiment::from_toml_builtin(&resolved, "resolved").unwrap(),
            e
        );
    }

    /// A stage may turn the height scan on: the networks' input grows by
    /// its 18 values at the stage and keeps them; it grows once in a run,
    /// and only at the observation's end (no privileged critic or action
    /// prior before it, no residual).
    #[test]
    fn a_stage_appends_the_height_scan_for_good_once() {
        let stages = |task: &str, second: &str, third: &str| {
            format!(
                "[task]\nmax_phases = 10\n{task}\n[[curriculum]]\nterrain = \"rigid\"\niterations = 3\n\n[[curriculum]]\nterrain = \"elastic:5cm:slope=10\"\niterations = 2\n{second}\n[[curriculum]]\nterrain = \"elastic:5cm:slope=10\"\niterations = 2\n{third}"
            )
        };
        let scan = "\n[curriculum.task.observation]\nheight_scan = true\n";
        let e = Experiment::from_toml_builtin(&stages("", scan, scan), "c.toml").unwrap();
        assert!(!e.task_at(2).observation.height_scan);
        assert_eq!(e.task_at(2).observation_size(), 102);
        for late in [3, 6] {
            assert_eq!(
                e.task_at(late).observation_size(),
                102 + 18,
                "iteration {late}"
            );
        }
        writes_and_reads_back(&e, "[curriculum.task.observation]\nheight_scan = true\n");
        let refused = |task: &str, second: &str, third: &str, expected: &str| {
            let err = Experiment::from_toml_builtin(&stages(task, second, third), "c.toml")
                .unwrap_err()
                .to_string();
            assert!(err.contains(expected), "{err}");
        };
        refused(
            "",
            scan,
            "",
            "stage 3: the networks see height_scan from stage 2 on and cannot lose it",
        );
        refused(
            "",
            scan,
            "\n[curriculum.task.observation]\nheight_scan = true\nprivileged_critic = true\n",
            "stage 3 turns privileged_critic on and stage 2 height_scan: the networks' inputs can grow once in a run",
        );
        refused(
            "\n[task.observation]\nprivileged_critic = true\n",
            scan,
            scan,
            "stage 2: a stage can append the height scan to the networks' input only while the critic has no privileged values",
        );
        refused(
            "action_prior = \"scripted_crawl\"\n",
            scan,
            scan,
            "stage 2: with an action prior the prior's values follow the height scan",
        );
        // from the start, with a prior or a privileged critic, it is the
        // run's observation
        let from_start = stages(
            "action_prior = \"scripted_crawl\"\n[task.observation]\nheight_scan = true\nprivileged_critic = true\n",
            "",
            "",
        );
        let e = Experiment::from_toml_builtin(&from_start, "c.toml").unwrap();
        assert_eq!(e.task_at(0).observation_size(), 102 + 18 + 27);
    }

    /// A stage may turn the critic's privileged values on (the policy's
    /// input stays the run's); later stages must keep them; the resolved
    /// file writes the stage's observation table where it belongs.
    #[test]
    fn a_stage_turns_the_privileged_critic_on_for_good() {
        let stages = |third: &str| {
            format!(
                "[task.observation]\nshort_history = true\n\n[[curriculum]]\nterrain = \"rigid\"\niterations = 3\n\n[[curriculum]]\nterrain = \"soil:4cm\"\niterations = 2\n\n[curriculum.task]\nbase_height_reference = \"feet\"\n\n[curriculum.task.observation]\nprivileged_critic = true\n\n[[curriculum]]\nterrain = \"soil:4cm\"\niterations = 2\n{third}"
            )
        };
        let text = stages("\n[curriculum.task.observation]\nprivileged_critic = true\n");
        let e = Experiment::from_toml_builtin(&text, "c.toml").unwrap();
        assert!(!e.task_at(2).observation.privileged_critic);
        assert_eq!(e.task_at(2).observation.privileged_size(), 0);
        for late in [3, 5] {
            let task = e.task_at(late);
            assert!(task.observation.privileged_critic, "iteration {late}");
            assert_eq!(task.observation_size(), e.task.observation_size());
        }
        assert_eq!(
            e.task_at(3).base_height_reference,
            robot::task::BaseHeightReference::Feet
        );
        writes_and_reads_back(
            &e,
            "[curriculum.task.observation]\nprivileged_critic = true\n",
        );
        // a later stage without it
        let err = Experiment::from_toml_builtin(&stages(""), "c.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("stage 3: the networks see privileged_critic from stage 2 on"),
            "{err}"
        );
        // a residual's critic sees the residual's observation
        let residual = format!("{text}\n[residual]\nphase_policy = \"none\"\n");
        let err = Experiment::from_toml_builtin(&residual, "c.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("c.toml: privileged_critic") && err.contains("[residual]"),
            "{err}"
        );
    }

    #[test]
    fn terrain_levels_need_episodes_that_end_within_an_iteration() {
        let levels = "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\n\n[[curriculum]]\niterations = 3\n[curriculum.levels]\nterrains = [\"rigid\", \"elastic:1cm\"]\n";
        // 40-phase episodes in 40-step iterations: the recipes' layout
        Experiment::from_toml_builtin(levels, "l.toml").unwrap();
        // 20-step iterations cut every 40-phase episode: no world could move up
        let short = format!("{levels}[ppo]\nsteps_per_env = 20\n");
        let err = format!(
            "{:#}",
            Experiment::from_toml_builtin(&short, "l.toml").unwrap_err()
        );
        assert!(
            err.contains("l.toml [[curriculum]] stage 2: its terrain levels move a world up after an episode that reaches task.max_phases = 40 without a fall")
                && err.contains("[ppo] steps_per_env = 20 cuts them"),
            "{err}"
        );
        // shorter episodes fit, and a stage without levels is not concerned
        Experiment::from_toml_builtin(&format!("{short}[task]\nmax_phases = 20\n"), "l.toml")
            .unwrap();
        Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[ppo]\nsteps_per_env = 20\n",
            "r.toml",
        )
        .unwrap();
        // a stage's own max_phases counts
        let long = levels.replace(
            "terrains = [\"rigid\", \"elastic:1cm\"]\n",
            "terrains = [\"rigid\", \"elastic:1cm\"]\n[curriculum.task]\nmax_phases = 60\n",
        );
        let err = format!(
            "{:#}",
            Experiment::from_toml_builtin(&long, "l.toml").unwrap_err()
        );
        assert!(err.contains("task.max_phases = 60"), "{err}");
        // switching the learner checks its steps
        let mut e = Experiment::from_toml_builtin(
            &format!("{levels}[sac]\nsteps_per_env = 10\n"),
            "l.toml",
        )
        .unwrap();
        let err = format!(
            "{:#}",
            e.set_algo(registry::find("sac").unwrap()).unwrap_err()
        );
        assert!(
            err.contains("--algo sac [[curriculum]] stage 2")
                && err.contains("[sac] steps_per_env = 10"),
            "{err}"
        );
    }

    #[test]
    fn a_stage_of_terrain_levels_names_its_top_and_round_trips() {
        let levels = "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\n\n[[curriculum]]\niterations = 3\n[curriculum.levels]\nterrains = [\"rigid\", \"elastic:1cm\", \"elastic:2cm\"]\npromote_distance_m = 0.5\n[curriculum.task]\nmax_paid_progress_m = 0.03\n";
        let e = Experiment::from_toml_builtin(levels, "l.toml").unwrap();
        assert!(e.levels_at(1).is_none());
        let stage = e.levels_at(2).expect("stage 2 has levels");
        assert_eq!(stage.top(), 2);
        assert_eq!(stage.promote_distance_m, 0.5);
        assert_eq!(e.terrain_at(4).1.to_string(), "elastic:2cm");
        assert_eq!(e.task_at(4).max_paid_progress_m, Some(0.03));
        writes_and_reads_back(
            &e,
            "[curriculum.levels]\nterrains = [\"rigid\", \"elastic:1cm\", \"elastic:2cm\"]\npromote_distance_m = 0.5\n",
        );
        // two runs whose stage 2 has other levels train differently there
        let other = Experiment::from_toml_builtin(
            &levels.replace("promote_distance_m = 0.5", "promote_distance_m = 1.0"),
            "o.toml",
        )
        .unwrap();
        assert_eq!(e.differs_before(&other, 2), None);
        let difference = e.differs_before(&other, 3).unwrap();
        assert!(
            difference.contains("iteration 3's terrain levels"),
            "{difference}"
        );
        for (bad, says) in [
            (
                levels.replace(
                    "[[curriculum]]\niterations = 3\n",
                    "[[curriculum]]\nterrain = \"rigid\"\niterations = 3\n",
                ),
                "l.toml [[curriculum]] stage 2: a stage with [curriculum.levels] trains on its levels' terrains; leave terrain out",
            ),
            (
                "[[curriculum]]\niterations = 3\n".to_string(),
                "l.toml [[curriculum]] stage 1: no terrain",
            ),
            (
                levels.replace("\"elastic:1cm\"", "\"elastic:1xm\""),
                "terrains[1] = \"elastic:1xm\"",
            ),
            (
                format!("{levels}\n[residual]\nphase_policy = \"none\"\n"),
                "l.toml: [curriculum.levels] moves phase-level policies",
            ),
        ] {
            let err = Experiment::from_toml_builtin(&bad, "l.toml").unwrap_err();
            let err = format!("{err:#}");
            assert!(err.contains(says), "{err}");
        }
    }

    /// A two-stage curriculum on rigid ground whose second stage has
    /// `stage_keys` is refused with an error naming `c.toml` and saying
    /// `expected`.
    fn assert_stage_2_refused(stage_keys: &str, expected: &str) {
        let text = format!(
            "[[curriculum]]\nterrain = \"rigid\"\niterations = 3\n\n[[curriculum]]\nterrain = \"rigid\"\niterations = 2\n\n{stage_keys}"
        );
        let err = format!(
            "{:#}",
            Experiment::from_toml_builtin(&text, "c.toml").unwrap_err()
        );
        assert!(
            err.contains(expected) && err.contains("c.toml"),
            "{stage_keys:?} gave {err:?}"
        );
    }

    #[test]
    fn a_stage_sets_task_keys_over_the_task_section() {
        let text = "[task]\nmax_phases = 12\ntermination_reward = -10.0\n\n[[curriculum]]\nterrain = \"rigid\"\niterations = 3\n\n[[curriculum]]\nterrain = \"elastic:5cm\"\niterations = 2\n\n[curriculum.task]\ntermination_reward = -30.0\nmax_paid_progress_m = 0.04\n";
        let e = Experiment::from_toml_builtin(text, "c.toml").unwrap();
        // stage 1 runs [task]; stage 2 [task] with its two keys on top
        assert_eq!(e.task_at(0), &e.task);
        assert_eq!(e.task.termination_reward, -10.0);
        assert_eq!(e.task.max_paid_progress_m, None);
        let late = e.task_at(3);
        assert_eq!(late.termination_reward, -30.0);
        assert_eq!(late.max_paid_progress_m, Some(0.04));
        assert_eq!(late.max_phases, 12, "[task]'s other keys stand");
        assert_eq!(late.distance_reward, DistanceReward::NewGround);
        assert_eq!(e.task_at(99), late);
        // the resolved file keeps the stage's keys as written
        let resolved = e.to_toml();
        assert!(
            resolved.contains(
                "[curriculum.task]\nmax_paid_progress_m = 0.04\ntermination_reward = -30.0\n"
            ),
            "{resolved}"
        );
        assert_eq!(
            Experiment::from_toml_builtin(&resolved, "resolved").unwrap(),
            e
        );
        // a pace cap in [task] round-trips too
        let capped = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[task]\nmax_paid_progress_m = 0.05\n",
            "c.toml",
        )
        .unwrap();
        assert_eq!(capped.task.max_paid_progress_m, Some(0.05));
        assert_eq!(
            Experiment::from_toml_builtin(&capped.to_toml(), "resolved").unwrap(),
            capped
        );
        for (stage_keys, expected) in [
            (
                "[curriculum.task.observation]\nfoot_history = false\n",
                "stage 2 [curriculum.task]: observation.foot_history cannot change between stages (it sets the networks' input); set it in [task]; of [curriculum.task.observation] only privileged_critic (the critic's input) and height_scan (appended to the networks' input) may be set",
            ),
            (
                "[curriculum.task]\naction_prior = \"scripted_crawl\"\n",
                "stage 2 [curriculum.task]: action_prior cannot change between stages",
            ),
            (
                "[curriculum.task]\nmax_phase = 3\n",
                "stage 2 [curriculum.task]: unknown field `max_phase`",
            ),
            (
                "[curriculum.task]\nmax_paid_progress_m = 0.0\n",
                "max_paid_progress_m must be a positive number (m per phase), got 0",
            ),
            (
                "[curriculum.task]\ndistance_reward = \"tracking\"\nmax_paid_progress_m = 0.04\n",
                "max_paid_progress_m caps distance_reward = \"new_ground\" only, but distance_reward = \"tracking\"",
            ),
        ] {
            assert_stage_2_refused(stage_keys, expected);
        }
    }

    #[test]
    fn physics_section_sets_the_world_and_round_trips() {
        let e = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[physics]\npd = \"motor\"\nsubsteps = 4\npgs_iterations = 1\nccd = false\nkd_n_m_s_per_rad = 5.0\nprediction_distance_m = 0.005\n",
            "p.toml",
        )
        .unwrap();
        assert_eq!(e.physics.pd, PdModel::Motor);
        assert_eq!(e.physics.solver_iterations, 4);
        assert_eq!(e.physics.pgs_iterations, 1);
        assert!(!e.physics.ccd);
        assert_eq!(e.physics.kd_n_m_s_per_rad, 5.0);
        assert_eq!(e.physics.prediction_distance_m, 0.005);
        assert_eq!(
            e.physics.kp_n_m_per_rad,
            WorldConfig::default().kp_n_m_per_rad
        );
        assert_eq!(
            Experiment::from_toml_builtin(&e.to_toml(), "resolved").unwrap(),
            e
        );
        let plain =
            Experiment::from_toml_builtin("[terrain]\nspec = \"rigid\"\n", "p.toml").unwrap();
        assert_eq!(plain.physics, WorldConfig::default());
        for (text, expected) in [
            (
                "[physics]\npd = \"pid\"\n",
                "pd must be \"implicit_spring\" or \"motor\", got \"pid\"",
            ),
            (
                "[physics]\nsubsteps = 0\n",
                "substeps must be in 1..=64, got 0",
            ),
            (
                "[physics]\npgs_iterations = 100\n",
                "pgs_iterations must be in 1..=64",
            ),
            (
                "[physics]\nkp_n_m_per_rad = 0.0\n",
                "kp_n_m_per_rad must be positive",
            ),
            (
                "[physics]\nkd_n_m_s_per_rad = -1.0\n",
                "kd_n_m_s_per_rad must be a finite number >= 0",
            ),
            (
                "[physics]\nfriction = nan\n",
                "friction must be a finite number >= 0",
            ),
            (
                "[physics]\nprediction_distance_m = 0.5\n",
                "prediction_distance_m must be in (0, 0.1] m, got 0.5",
            ),
            ("[physics]\nsolver = 3\n", "unknown field `solver`"),
        ] {
            let text = format!("[terrain]\nspec = \"rigid\"\n{text}");
            let err = format!(
                "{:#}",
                Experiment::from_toml_builtin(&text, "p.toml").unwrap_err()
            );
            assert!(
                err.contains(expected) && err.contains("p.toml [physics]"),
                "{text:?} gave {err:?}"
            );
        }
    }

    #[test]
    fn a_stage_sets_physics_keys_over_the_physics_section() {
        // the levels at 120 Hz, the ending at [physics]'s 240 Hz with 4
        // solver iterations
        let text = "[physics]\nsubsteps = 4\n\n[[curriculum]]\nterrain = \"rigid\"\niterations = 3\n\n[curriculum.physics]\nstep_rate_hz = 120\n\n[[curriculum]]\nterrain = \"elastic:5cm\"\niterations = 2\n";
        let e = Experiment::from_toml_builtin(text, "c.toml").unwrap();
        let early = e.physics_at(0);
        assert_eq!(early.step_rate_hz, 120);
        assert_eq!(early.steps_per_phase(), 90);
        assert_eq!(early.solver_iterations, 4, "[physics]'s other keys stand");
        assert_eq!(e.physics_at(2), early);
        assert_eq!(e.physics_at(3), &e.physics);
        assert_eq!(e.physics_at(3).step_rate_hz, 240);
        assert_eq!(e.physics_at(99), &e.physics);
        // the resolved file keeps the stage's keys as written and parses back
        let resolved = e.to_toml();
        assert!(
            resolved.contains("[curriculum.physics]\nstep_rate_hz = 120\n"),
            "{resolved}"
        );
        assert_eq!(
            Experiment::from_toml_builtin(&resolved, "resolved").unwrap(),
            e
        );
        // a fork is the same training up to the stage whose physics differ
        let all_240 = Experiment::from_toml_builtin(
            "[physics]\nsubsteps = 4\n\n[[curriculum]]\nterrain = \"rigid\"\niterations = 3\n\n[[curriculum]]\nterrain = \"elastic:5cm\"\niterations = 2\n",
            "d.toml",
        )
        .unwrap();
        let difference = e.differs_before(&all_240, 1).unwrap();
        assert!(
            difference.contains("iteration 1's [physics] settings")
                && difference.contains("step_rate_hz: 120 against step_rate_hz: 240"),
            "{difference}"
        );
        let ends_at_120 = Experiment::from_toml_builtin(
            &format!("{text}\n[curriculum.physics]\nstep_rate_hz = 120\n"),
            "f.toml",
        )
        .unwrap();
        assert_eq!(e.differs_before(&ends_at_120, 3), None);
        assert!(
            e.differs_before(&ends_at_120, 4)
                .unwrap()
                .starts_with("iteration 4's [physics] settings"),
        );
        for (stage_keys, expected) in [
            (
                "[curriculum.physics]\nstep_rate_hz = 130\n",
                "stage 2 [curriculum.physics]: step_rate_hz must be a multiple of 4",
            ),
            (
                "[curriculum.physics]\nstep_rate = 120\n",
                "stage 2 [curriculum.physics]: unknown field `step_rate`",
            ),
            (
                "[curriculum.physics]\nsubsteps = 0\n",
                "stage 2 [curriculum.physics]: substeps must be in 1..=64, got 0",
            ),
            (
                // a residual acts every control_steps physics steps: 12
                // divides the 240 Hz phase's 180, not the 120 Hz one's 90
                "[curriculum.physics]\nstep_rate_hz = 120\n\n[residual]\nphase_policy = \"p\"\ncontrol_steps = 12\n",
                "[residual] in [[curriculum]] stage 2's physics: control_steps = 12 must divide the phase's 90 physics steps",
            ),
        ] {
            assert_stage_2_refused(stage_keys, expected);
        }
    }

    #[test]
    fn a_shipped_policys_config_is_what_training_writes() {
        // `quadwalk train` writes `Experiment::to_toml` into the run and the
        // export copies it: the shipped files must come back byte for byte,
        // or `--fork`'s config check and the READMEs' `cmp` would break.
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../policies");
        let mut checked = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path().join("config.toml");
            if !path.exists() {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let e = Experiment::from_file(&path, &Registry::builtin())
                .unwrap_or_else(|e| panic!("{e:#}"));
            assert_eq!(e.to_toml(), text, "{}", path.display());
            checked += 1;
        }
        assert!(checked >= 3, "policies/ has {checked} configs");
    }

    #[test]
    fn bench_json_names_every_physics_key_of_the_file() {
        let physics = WorldConfig {
            prediction_distance_m: 0.005,
            ..WorldConfig::default()
        };
        let json = physics_json(&physics);
        let table: toml::Table = toml::from_str(&physics_toml(&physics)).unwrap();
        let mut json_keys: Vec<&String> = json.as_object().unwrap().keys().collect();
        let mut file_keys: Vec<&String> = table.keys().collect();
        json_keys.sort();
        file_keys.sort();
        assert_eq!(json_keys, file_keys);
        assert_eq!(json["prediction_distance_m"], 0.005);
        assert_eq!(json["substeps"], 1);
        assert_eq!(json["kp_n_m_per_rad"], 600.0);
        assert_eq!(json["pd"], "implicit_spring");
    }

    #[test]
    fn the_shipped_configs_parse() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../configs");
        let mut seen = Vec::new();
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "toml") {
                let e = Experiment::from_file(&path, &Registry::builtin())
                    .unwrap_or_else(|e| panic!("{e:#}"));
                seen.push((path.file_stem().unwrap().to_string_lossy().to_string(), e));
            }
        }
        seen.sort_by(|a, b| a.0.cmp(&b.0));
        let names: Vec<&str> = seen.iter().map(|(n, _)| n.as_str()).collect();
        // the paper's scenarios (quadwalk's own recipes sit beside them)
        const PAPER: [&str; 4] = ["tv2", "tv8", "tc2", "tc5"];
        for name in PAPER.into_iter().chain(["ablation-no-foot-history"]) {
            assert!(names.contains(&name), "{name} missing: {names:?}");
        }
        let get = |name: &str| &seen.iter().find(|(n, _)| n == name).unwrap().1;
        // T_c^5 is one file: T_v2, then constant 5 cm
        let tc5 = get("tc5");
        assert_eq!(tc5.curriculum.len(), 2);
        assert_eq!(
            tc5.curriculum[0].terrain.to_string(),
            "varying:2m:2cm,3cm,4cm,5cm,rigid"
        );
        assert_eq!(tc5.curriculum[1].terrain.to_string(), "elastic:5cm");
        assert_eq!(
            get("ablation-no-foot-history").task.observation.size(),
            102 - 36
        );
        assert_eq!(
            get("ablation-no-foot-velocity").task.observation.size(),
            102 - 12
        );
        assert_eq!(
            get("ablation-no-short-history").task.observation.size(),
            102 - 24
        );
        // the paper's configs keep the paper's reward and minibatch exactly
        for (name, e) in &seen {
            let papers_ablation = name.starts_with("ablation") && !name.starts_with("ablation-5cm");
            if PAPER.contains(&name.as_str()) || papers_ablation {
                assert_eq!(e.task.distance_reward, DistanceReward::Progress, "{name}");
                assert_eq!(e.task.balance_terms, BalanceTerms::Paper, "{name}");
                assert_eq!(
                    *e.ppo(),
                    PpoConfig {
                        steps_per_env: e.ppo().steps_per_env,
                        ..PpoConfig::default()
                    },
                    "{name}"
                );
            }
        }
        // the 5 cm recipe's ablations: that recipe, the observation changed
        let line = get("elastic-5cm-line");
        for (name, size) in [
            ("ablation-5cm-no-foot-history", 102 - 36),
            ("ablation-5cm-history-2-phases", 102 - 12),
            ("ablation-5cm-no-foot-velocity", 102 - 12),
        ] {
            let a = get(name);
            assert_eq!(a.task.observation.size(), size, "{name}");
            assert_eq!(a.ppo(), line.ppo(), "{name}");
            assert_eq!(a.task.distance_reward, line.task.distance_reward, "{name}");
            let terrains = |e: &Experiment| -> Vec<(String, u64)> {
                e.curriculum
                    .iter()
                    .map(|s| (s.terrain.to_string(), s.iterations))
                    .collect()
            };
            assert_eq!(terrains(a), terrains(line), "{name}");
        }
        // the shipped policies' recipes are quadwalk's defaults
        let rigid = get("rigid");
        assert_eq!(rigid.task, default_task());
        assert_eq!(*rigid.ppo(), default_ppo());
        // the 5 cm curriculum starts as the rigid recipe, deepens the tiles,
        // then steps the learning rate down on 5 cm tiles, where it caps
        // the pace paid for
        let deepening = get("elastic-5cm-curriculum");
        assert_eq!(
            (&deepening.task, &deepening.ppo()),
            (&rigid.task, &rigid.ppo())
        );
        let stages_of = |e: &Experiment| -> Vec<(String, u64, Option<f64>, Option<f64>)> {
            e.curriculum
                .iter()
                .map(|s| {
                    let task = e.task_of(s);
                    (
                        s.terrain.to_string(),
                        s.iterations,
                        s.learning_rate,
                        task.max_paid_progress_m,
                    )
                })
                .collect()
        };
        let stages = stages_of(deepening);
        let expected = [
            ("rigid", 260, None, None),
            ("elastic:2cm", 60, None, None),
            ("elastic:3cm", 60, None, None),
            ("elastic:4cm", 60, None, None),
            ("elastic:5cm", 260, None, Some(0.03)),
            ("elastic:5cm", 60, Some(1e-4), Some(0.03)),
            ("elastic:5cm", 60, Some(5e-5), Some(0.03)),
            ("elastic:5cm", 20, Some(2e-5), Some(0.03)),
        ];
        assert_eq!(
            stages,
            expected.map(|(t, n, r, c)| (t.to_string(), n, r, c)),
            "{stages:?}"
        );
        let capped = deepening.task_at(deepening.total_iterations() - 1);
        assert_eq!(
            (capped.termination_reward, capped.distance_reward),
            (rigid.task.termination_reward, rigid.task.distance_reward),
            "the cap is the stages' only task change"
        );
        assert_eq!(deepening.curriculum[0].iterations, rigid.train.iterations);
        assert_eq!(
            deepening.learning_rate_at(0),
            Some(rigid.ppo().learning_rate)
        );
        // the first T_v2 recipe (2/40): the same stages, ending on T_v2
        let tv2 = get("tv2-curriculum");
        assert_eq!((&tv2.task, &tv2.ppo()), (&rigid.task, &rigid.ppo()));
        assert_eq!(tv2.terrain.to_string(), "varying:2m:2cm,3cm,4cm,5cm,rigid");
        // the 5 cm curriculum's stages with those from `first` on moved to
        // T_v2
        let on_tv2_from = |first: usize| -> Vec<_> {
            stages
                .iter()
                .enumerate()
                .map(|(k, (t, n, r, c))| {
                    let t = if k >= first {
                        tv2.terrain.to_string()
                    } else {
                        t.clone()
                    };
                    (t, *n, *r, *c)
                })
                .collect()
        };
        // every 5 cm stage (the fifth on) on T_v2
        assert_eq!(stages[4].0, "elastic:5cm");
        assert_eq!(stages_of(tv2), on_tv2_from(4));
        // so a checkpoint of either at iteration 440 is where the other is
        // too (`train --fork`), and the rigid recipe's run is the first 260
        // iterations of both
        assert_eq!(tv2.differs_before(deepening, 440), None);
        assert_eq!(
            tv2.differs_before(deepening, 441).as_deref(),
            Some("iteration 441's terrain: varying:2m:2cm,3cm,4cm,5cm,rigid against elastic:5cm")
        );
        assert_eq!(deepening.differs_before(rigid, 260), None);
        // T_v2 after 200 iterations of 5 cm tiles: the 5 cm curriculum to 640
        let after_5cm = get("tv2-after-5cm");
        assert_eq!(after_5cm.differs_before(deepening, 640), None);
        assert_eq!(
            after_5cm.differs_before(deepening, 641).as_deref(),
            Some("iteration 641's terrain: varying:2m:2cm,3cm,4cm,5cm,rigid against elastic:5cm")
        );
        assert_eq!(after_5cm.train.keep_checkpoints, 25);
        // the 5 cm curriculum with the goals drawn from the first tile stage
        let goals = get("elastic-5cm-goals");
        assert_eq!(stages_of(goals), stages);
        assert_eq!(goals.differs_before(rigid, 260), None);
        for (k, stage) in goals.curriculum.iter().enumerate().skip(1) {
            let task = stage
                .task
                .as_ref()
                .expect("every tile stage draws the goals");
            assert_eq!(
                (
                    task.first_goal_ahead_range_m,
                    task.goal_y_offset_range_m,
                    task.orientation_lookahead_m
                ),
                (Some((0.3, 2.3)), (-0.1, 0.1), 1.0),
                "stage {k}"
            );
            let plain = deepening.task_of(&deepening.curriculum[k]);
            assert_eq!(
                TaskConfig {
                    first_goal_ahead_range_m: None,
                    goal_y_offset_range_m: (0.0, 0.0),
                    orientation_lookahead_m: 0.0,
                    ..task.clone()
                },
                *plain,
                "stage {k}: the goals are its only change"
            );
        }
        assert!(
            deepening
                .differs_before(rigid, 261)
                .is_some_and(|d| d.starts_with("iteration 261's terrain")),
            "{:?}",
            deepening.differs_before(rigid, 261)
        );
        // the built-in recipe: the 5 cm curriculum observing the goals' line
        // 1 m ahead, its only change, in every stage
        let line = get("elastic-5cm-line");
        assert_eq!(stages_of(line), stages);
        assert_eq!(line.ppo(), deepening.ppo());
        for iteration in [0, 260, 500, 839] {
            let task = line.task_at(iteration);
            assert_eq!(task.observation.goal_line_ahead_m, Some(1.0));
            let mut paper_goal = task.clone();
            paper_goal.observation.goal_line_ahead_m = None;
            assert_eq!(&paper_goal, deepening.task_at(iteration), "{iteration}");
        }
        // policies/tv2's recipe until 2026-12-02 (32/40): the built-in 5 cm
        // recipe to iteration 700, then T_v2 where that recipe steps its
        // rate down on 5 cm tiles
        let tv2_line = get("tv2-line");
        assert_eq!(tv2_line.differs_before(line, 700), None);
        assert_eq!(
            tv2_line.differs_before(line, 701).as_deref(),
            Some("iteration 701's terrain: varying:2m:2cm,3cm,4cm,5cm,rigid against elastic:5cm")
        );
        assert_eq!(stages_of(tv2_line), on_tv2_from(5));
        assert_eq!(tv2_line.terrain, tv2.terrain);
        for iteration in [0, 700, 839] {
            assert_eq!(
                tv2_line.task_at(iteration),
                line.task_at(iteration),
                "{iteration}"
            );
        }
        // policies/tv2's recipe since 2026-12-02: the whole built-in 5 cm
        // recipe, then 100 iterations of T_v2 and 240 on its hardest
        // passages (rigid ground and 4-5 cm tiles), the training episodes
        // starting anywhere in the first 30 m
        let after_line = get("tv2-after-line");
        assert_eq!(after_line.differs_before(line, 840), None);
        assert_eq!(after_line.total_iterations(), 1180);
        let (t_v2, passages) = (tv2.terrain.to_string(), "varying:2m:4cm,5cm,rigid");
        for (iteration, rate, terrain) in [
            (840, 5e-5, t_v2.as_str()),
            (879, 5e-5, &t_v2),
            (880, 2e-5, &t_v2),
            (939, 2e-5, &t_v2),
            (940, 2e-5, passages),
            (1179, 2e-5, passages),
        ] {
            assert_eq!(after_line.terrain_at(iteration).1.to_string(), terrain);
            assert_eq!(after_line.learning_rate_at(iteration), Some(rate));
            let task = after_line.task_at(iteration);
            assert_eq!(task.start_x_range_m, (-0.5, 30.0));
            let mut line_task = line.task_at(839).clone();
            line_task.start_x_range_m = task.start_x_range_m;
            assert_eq!(task, &line_task, "{iteration}");
        }
    }

    #[test]
    fn silent_sections_get_quadwalks_defaults_and_a_ppo_table_overrides_them() {
        let e = Experiment::from_toml_builtin("[terrain]\nspec = \"rigid\"\n", "t.toml").unwrap();
        assert_eq!(e.task.distance_reward, DistanceReward::NewGround);
        assert_eq!(e.task.balance_terms, BalanceTerms::Penalty);
        assert_eq!(e.ppo().minibatch_size, 128);
        assert_eq!(e, Experiment::for_terrain(e.terrain.clone()));
        let e = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[ppo]\nepochs = 5\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!((e.ppo().minibatch_size, e.ppo().epochs), (128, 5));
        let err = Experiment::from_toml_builtin(
            "[terrain]\nspec = \"rigid\"\n[ppo]\nepoch = 5\n",
            "t.toml",
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.contains("t.toml [ppo]") && err.contains("epoch"),
            "{err}"
        );
    }

    #[test]
    fn bad_training_sections_name_the_key() {
        for (text, expected) in [
            (
                "[terrain]\nspec = \"rigid\"\n[ppo]\ngamma = 2.0\n",
                "ppo.gamma = 2",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[ppo]\ngama = 0.9\n",
                "unknown field `gama`",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[train]\nenvs = 0\n",
                "train.envs = 0",
            ),
            (
                "[terrain]\nspec = \"rigid\"\n[train]\nenvs = 2\nrerun_envs = [2]\n",
                "rerun_envs holds 2",
            ),
            (
                "[[curriculum]]\nterrain = \"elastic:9\"\niterations = 2\n",
                "stage 1",
            ),
            (
                "[[curriculum]]\nterrain = \"rigid\"\niterations = 0\n",
                "at least 1",
            ),
            ("[[curriculum]]\nterrain = \"rigid\"\n", "iterations"),
            (
                "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\nlearning_rate = 0.0\n",
                "stage 1: learning_rate = 0: must be in (0, 1)",
            ),
            (
                "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\nlearning_rate = 1.5\n",
                "stage 1: learning_rate = 1.5: must be in (0, 1)",
            ),
            (
                "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\nlearning_rate = 1e-4\n[ppo]\ndesired_kl = 0.01\n",
                "keep one of the two",
            ),
            (
                "[[curriculum]]\nterrain = \"rigid\"\niterations = 2\nlearing_rate = 1e-4\n",
                "unknown field `learing_rate`",
            ),
        ] {
            let err = format!(
                "{:#}",
                Experiment::from_toml_builtin(text, "t.toml").unwrap_err()
            );
            assert!(
                err.contains(expected) && err.contains("t.toml"),
                "{text:?} gave {err:?}"
            );
        }
    }

    #[test]
    fn spec_and_table_forms_give_the_same_terrain() {
        let a =
            terrain_from_toml("[terrain]\nspec = \"elastic:5cm:travel=12cm\"\n", "a.toml").unwrap();
        let b = terrain_from_toml(
            "[terrain]\nplugin = \"elastic\"\ndepth = \"5cm\"\ntravel = \"12cm\"\n",
            "b.toml",
        )
        .unwrap();
        assert_eq!(a, b);
        let c = terrain_from_toml("[terrain]\nplugin = \"varying\"\nevery = \"2m\"\nsurfaces = [\"2cm\", \"5cm\", \"rigid\"]\ndamping = 0.4\n", "c.toml").unwrap();
        assert_eq!(c.to_string(), "varying:2m:2cm,5cm,rigid:damping=0.4");
        // Regions of any surface spec: parentheses optional in a TOML list.
        let d = terrain_from_toml("[terrain]\nplugin = \"varying\"\nevery = \"2m\"\nsurfaces = [\"5cm\", \"soil:4cm:yield=0.4\", \"(rigid:friction=0.1)\", \"steps:5cm:30cm\", \"slope:10\"]\n", "d.toml").unwrap();
        assert_eq!(
            d.to_string(),
            "varying:2m:5cm,(soil:4cm:yield=0.4),(rigid:friction=0.1),(steps:5cm:30cm),(slope:10)"
        );
        let written = format!("[terrain]\nspec = \"{d}\"\n");
        assert_eq!(terrain_from_toml(&written, "e.toml").unwrap(), d);
    }

    #[test]
    fn bad_files_name_the_file_and_the_problem() {
        let cases = [
            ("[terrain]\nspec = \"elastic:5\"\n", "has no unit"),
            (
                "[terrain]\nplugin = \"elastic\"\ndepth = \"30cm\"\n",
                "beyond the tile travel",
            ),
            (
                "[terrain]\nplugin = \"elastic\"\ndepht = \"3cm\"\n",
                "has no parameter \"depht\"",
            ),
            (
                "[terrain]\nspec = \"rigid\"\nplugin = \"rigid\"\n",
                "not both",
            ),
            (
                "[terrian]\nspec = \"rigid\"\n",
                "unknown section or key \"terrian\"",
            ),
            ("[terrain]\nspec = 5\n", "spec must be a string"),
            ("[terrain\n", "not valid TOML"),
            ("", "no [terrain] section"),
            (
                "[terrain]\nplugin = \"elastic\"\ndepth = true\n",
                "not a string, number or list",
            ),
        ];
        for (text, expected) in cases {
            let err = format!("{:#}", terrain_from_toml(text, "x.toml").unwrap_err());
            assert!(err.contains(expected), "{text:?} gave {err:?}");
            assert!(err.contains("x.toml"), "{err:?}");
        }
    }
}
