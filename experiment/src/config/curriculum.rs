//! `[[curriculum]]`: stages in order, each with its terrain (or its
//! `[curriculum.levels]`, a terrain per world), iterations and optionally
//! its learning rate, `[curriculum.task]` and `[curriculum.physics]` keys;
//! and what an experiment trains at a given iteration.

use anyhow::{Context, Result, anyhow, bail};
use robot::WorldConfig;
use robot::task::TaskConfig;
use serde::Deserialize;
use terrain_plugins::{Registry, TerrainSpec};

use super::Experiment;
use super::advance::{Advance, AdvanceSection};
use super::defaults::{resolve_physics, resolve_task};
use super::levels::{LevelsSection, TerrainLevels};

/// One curriculum stage.
#[derive(Debug, Clone, PartialEq)]
pub struct Stage {
    /// the terrain of this stage; with `levels`, their top one
    pub terrain: TerrainSpec,
    /// a terrain per world, moving with how each walks
    /// (`[curriculum.levels]`; `None`: every world on `terrain`)
    pub levels: Option<TerrainLevels>,
    /// iterations in this stage; with `advance`, at most
    pub iterations: u64,
    /// moving on when the policy is ready (`[curriculum.advance]`)
    pub advance: Option<Advance>,
    /// where the `advance` rule ended the stage, iterations into it, once a
    /// run's history has decided it ([`Experiment::decide_stages`]); not
    /// part of the file
    pub ended_after: Option<u64>,
    /// the learner's learning rate in this stage (`None`: the `[ppo]` or
    /// `[sac]` one)
    pub learning_rate: Option<f64>,
    /// the stage's `[curriculum.task]` keys, as written (empty: none)
    pub task_overrides: toml::Table,
    /// the task of this stage: `[task]` with the overrides on top (`None`:
    /// `[task]`'s)
    pub task: Option<TaskConfig>,
    /// the stage's `[curriculum.physics]` keys, as written (empty: none)
    pub physics_overrides: toml::Table,
    /// the physics of this stage's worlds: `[physics]` with the overrides on
    /// top (`None`: `[physics]`'s), e.g. a coarser step (`step_rate_hz`)
    /// for the easy levels and the paper's for the ending
    pub physics: Option<WorldConfig>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StageSection {
    #[serde(default)]
    terrain: Option<String>,
    iterations: u64,
    #[serde(default)]
    learning_rate: Option<f64>,
    #[serde(default)]
    task: Option<toml::Table>,
    #[serde(default)]
    physics: Option<toml::Table>,
    #[serde(default)]
    advance: Option<AdvanceSection>,
    #[serde(default)]
    levels: Option<LevelsSection>,
}

impl Stage {
    /// The stage's iterations: where its `advance` rule ended it, else its
    /// `iterations`.
    pub fn length(&self) -> u64 {
        self.ended_after.unwrap_or(self.iterations)
    }
}

/// `[curriculum.task]` keys that would change the networks' input (the
/// observation), which is fixed for a run.
pub(super) const FIXED_TASK_KEYS: [&str; 2] = ["observation", "action_prior"];

impl Experiment {
    /// Total training iterations: the curriculum's sum, else
    /// `train.iterations`. A stage with an `advance` rule counts where it
    /// ended once decided, else its `iterations`: the total is then at most
    /// this.
    pub fn total_iterations(&self) -> u64 {
        if self.curriculum.is_empty() {
            self.train.iterations
        } else {
            self.curriculum.iter().map(Stage::length).sum()
        }
    }

    /// Keeps the first `iterations` iterations: the total without a
    /// curriculum; with one, the stages up to that count, the last of them
    /// cut short (`--iterations` of a new run). A curriculum is not
    /// lengthened: the error names its total.
    pub fn keep_first_iterations(&mut self, iterations: u64) -> Result<()> {
        if self.curriculum.is_empty() {
            self.train.iterations = iterations;
            return Ok(());
        }
        let total = self.total_iterations();
        if iterations > total {
            bail!(
                "--iterations {iterations}: the curriculum has {total} iterations in its stages; pass at most {total}, or add stages to a config"
            );
        }
        let mut left = iterations;
        self.curriculum.retain_mut(|stage| {
            let keep = left > 0;
            stage.iterations = stage.iterations.min(left);
            left -= stage.iterations;
            if let Some(rule) = &mut stage.advance {
                rule.window = rule.window.min(stage.iterations.max(1));
            }
            keep
        });
        Ok(())
    }

    /// The terrain of 0-based iteration `iteration`, and the stage index.
    pub fn terrain_at(&self, iteration: u64) -> (usize, &TerrainSpec) {
        let mut end = 0;
        for (k, stage) in self.curriculum.iter().enumerate() {
            end += stage.length();
            if iteration < end {
                return (k, &stage.terrain);
            }
        }
        match self.curriculum.last() {
            Some(last) => (self.curriculum.len() - 1, &last.terrain),
            None => (0, &self.terrain),
        }
    }

    /// The learning rate of 0-based iteration `iteration` when a curriculum
    /// stage sets one: that stage's, or for a stage that does not, the
    /// learner's configured rate. `None` when no stage sets one (the learner
    /// keeps its own rate, which `[ppo] desired_kl` may move).
    pub fn learning_rate_at(&self, iteration: u64) -> Option<f64> {
        if self.curriculum.iter().all(|s| s.learning_rate.is_none()) {
            return None;
        }
        let (stage, _) = self.terrain_at(iteration);
        Some(
            self.curriculum[stage]
                .learning_rate
                .unwrap_or(self.learner().learning_rate()),
        )
    }

    /// The terrain levels of 0-based iteration `iteration`'s stage, if it
    /// has them.
    pub fn levels_at(&self, iteration: u64) -> Option<&TerrainLevels> {
        if self.curriculum.is_empty() {
            return None;
        }
        self.curriculum[self.terrain_at(iteration).0]
            .levels
            .as_ref()
    }

    /// The task of 0-based iteration `iteration`: its curriculum stage's
    /// when the stage sets `[curriculum.task]` keys, else `[task]`.
    pub fn task_at(&self, iteration: u64) -> &TaskConfig {
        if self.curriculum.is_empty() {
            return &self.task;
        }
        let (stage, _) = self.terrain_at(iteration);
        self.task_of(&self.curriculum[stage])
    }

    /// A stage's task: its own where it sets `[curriculum.task]` keys, else
    /// `[task]`.
    pub(super) fn task_of<'a>(&'a self, stage: &'a Stage) -> &'a TaskConfig {
        stage.task.as_ref().unwrap_or(&self.task)
    }

    /// The physics of 0-based iteration `iteration`'s worlds: its curriculum
    /// stage's when the stage sets `[curriculum.physics]` keys, else
    /// `[physics]`.
    pub fn physics_at(&self, iteration: u64) -> &WorldConfig {
        if self.curriculum.is_empty() {
            return &self.physics;
        }
        let (stage, _) = self.terrain_at(iteration);
        self.physics_of(&self.curriculum[stage])
    }

    /// A stage's physics: its own where it sets `[curriculum.physics]`
    /// keys, else `[physics]`.
    pub(super) fn physics_of<'a>(&'a self, stage: &'a Stage) -> &'a WorldConfig {
        stage.physics.as_ref().unwrap_or(&self.physics)
    }

    /// The learning rate iteration `iteration` trains at: the stage's, else
    /// the learner's configured one; `None` where PPO's adaptive rate
    /// (`desired_kl`) moves it.
    pub(super) fn effective_learning_rate_at(&self, iteration: u64) -> Option<f64> {
        let learner = self.learner();
        self.learning_rate_at(iteration)
            .or((!learner.adapts_learning_rate()).then(|| learner.learning_rate()))
    }

    /// Stage learning rates and PPO's adaptive rate exclude each other.
    pub(super) fn check_stage_rates(&self, source: &str) -> Result<()> {
        if self.learner().adapts_learning_rate()
            && self.curriculum.iter().any(|s| s.learning_rate.is_some())
        {
            bail!(
                "{source}: [[curriculum]] stages set learning_rate and [{}] sets desired_kl, which moves the rate itself; keep one of the two",
                self.algo.table
            );
        }
        Ok(())
    }

    /// A world moves up a level only after an episode that ended without a
    /// fall, that is one that ran to the task's `max_phases`. Every
    /// iteration starts fresh episodes and cuts them after the learner's
    /// `steps_per_env` steps, so a stage with levels whose episodes are
    /// longer than that could never move a world up.
    pub(super) fn check_stage_levels(&self, source: &str) -> Result<()> {
        let steps = self.learner().steps_per_env();
        for (k, stage) in self.curriculum.iter().enumerate() {
            let max_phases = self.task_of(stage).max_phases;
            if stage.levels.is_some() && max_phases > steps {
                bail!(
                    "{source} [[curriculum]] stage {}: its terrain levels move a world up after an episode that reaches task.max_phases = {max_phases} without a fall, but every iteration starts fresh episodes and [{}] steps_per_env = {steps} cuts them before that, so no world could move up; set steps_per_env to at least max_phases, or max_phases to at most steps_per_env",
                    k + 1,
                    self.algo.table
                );
            }
        }
        Ok(())
    }
}

/// The `[curriculum.task.observation]` keys a stage may set: the critic's
/// privileged values, which the learner adds to the critic's input when the
/// stage starts (the policy's input stays the run's), and the height scan,
/// which it appends to both networks' input (the new inputs' weights start
/// at zero, so the policy acts as before until training moves them).
const STAGE_OBSERVATION_KEYS: [&str; 2] = ["privileged_critic", "height_scan"];

/// A stage's task: `[task]`'s keys with the stage's `[curriculum.task]`
/// keys on top; keys that change the policy's input are refused.
fn stage_task(task_table: &toml::Table, overrides: &toml::Table) -> Result<TaskConfig, String> {
    let fixed = |key: &str| {
        format!(
            "{key} cannot change between stages (it sets the networks' input); set it in [task]"
        )
    };
    if let Some(key) = FIXED_TASK_KEYS
        .iter()
        .find(|k| **k != "observation" && overrides.contains_key(**k))
    {
        return Err(fixed(key));
    }
    let mut merged = task_table.clone();
    for (key, value) in overrides {
        if key != "observation" {
            merged.insert(key.clone(), value.clone());
            continue;
        }
        let toml::Value::Table(observation) = value else {
            return Err("observation must be a table ([curriculum.task.observation])".into());
        };
        if let Some(other) = observation
            .keys()
            .find(|k| !STAGE_OBSERVATION_KEYS.contains(&k.as_str()))
        {
            return Err(format!(
                "{}; of [curriculum.task.observation] only privileged_critic (the critic's input) and height_scan (appended to the networks' input) may be set",
                fixed(&format!("observation.{other}"))
            ));
        }
        let mut base = match task_table.get("observation") {
            Some(toml::Value::Table(t)) => t.clone(),
            _ => toml::Table::new(),
        };
        base.extend(observation.clone());
        merged.insert("observation".into(), toml::Value::Table(base));
    }
    resolve_task(&merged)
}

impl Experiment {
    /// A network cannot lose inputs: once a stage turns `privileged_critic`
    /// or `height_scan` on, every later stage keeps it on. A residual's
    /// critic sees the residual's own observation, so `[residual]` refuses
    /// a privileged critic, and its networks the residual's observation, so
    /// a stage turning the height scan on too. The networks' inputs grow at
    /// most once in a run (the normaliser counts one appended block), and a
    /// height scan turned on by a stage must be the observation's last
    /// values, so neither after a privileged critic nor with an action
    /// prior.
    pub(super) fn check_stage_observations(&self, source: &str) -> Result<()> {
        let privileged = |stage: &Stage| self.task_of(stage).observation.privileged_critic;
        let scanned = |stage: &Stage| self.task_of(stage).observation.height_scan;
        if self.residual.is_some()
            && (self.task.observation.privileged_critic || self.curriculum.iter().any(privileged))
        {
            bail!(
                "{source}: privileged_critic gives the phase-level policy's critic privileged values; a [residual] policy's critic sees the residual's own observation, so it cannot be set with [residual]"
            );
        }
        let mut grown = Vec::new();
        for (key, on) in [
            ("privileged_critic", &privileged as &dyn Fn(&Stage) -> bool),
            ("height_scan", &scanned),
        ] {
            let mut first_on = None;
            for (k, stage) in self.curriculum.iter().enumerate() {
                match (first_on, on(stage)) {
                    (None, true) => first_on = Some(k),
                    (Some(first), false) => bail!(
                        "{source} [[curriculum]] stage {}: the networks see {key} from stage {} on and cannot lose it; set [curriculum.task.observation] {key} = true in this stage too",
                        k + 1,
                        first + 1
                    ),
                    _ => {}
                }
            }
            // turned on by a stage after the first: the inputs grow there
            if let Some(first) = first_on.filter(|&k| k > 0) {
                grown.push((key, first));
            }
        }
        if let [(a, at_a), (b, at_b)] = grown[..] {
            bail!(
                "{source}: stage {} turns {a} on and stage {} {b}: the networks' inputs can grow once in a run; turn one of them on in [task]",
                at_a + 1,
                at_b + 1
            );
        }
        if let Some(&(_, at)) = grown.iter().find(|(key, _)| *key == "height_scan") {
            let task = self.task_of(&self.curriculum[at]);
            if self.residual.is_some() {
                bail!(
                    "{source} [[curriculum]] stage {}: height_scan is the phase-level policy's observation; a [residual] policy's networks see the residual's own",
                    at + 1
                );
            }
            if task.observation.privileged_critic {
                bail!(
                    "{source} [[curriculum]] stage {}: a stage can append the height scan to the networks' input only while the critic has no privileged values (they would fall between); turn height_scan on in [task]",
                    at + 1
                );
            }
            if task.action_prior != robot::task::ActionPrior::None {
                bail!(
                    "{source} [[curriculum]] stage {}: with an action prior the prior's values follow the height scan, so a stage cannot append it; turn height_scan on in [task]",
                    at + 1
                );
            }
        }
        Ok(())
    }

    /// Resolves every stage's task and physics again over `[task]` and
    /// `[physics]` as they are now, as reading [`Experiment::to_toml`] back
    /// does (after a residual run takes its phase policy's observation and
    /// physics).
    pub(crate) fn resolve_stages_again(&mut self) -> Result<()> {
        let task_table =
            toml::Table::try_from(&self.task).context("the task settings as a TOML table")?;
        for (k, stage) in self.curriculum.iter_mut().enumerate() {
            if !stage.task_overrides.is_empty() {
                stage.task = Some(stage_task(&task_table, &stage.task_overrides).map_err(|e| {
                    anyhow!("[[curriculum]] stage {} [curriculum.task]: {e}", k + 1)
                })?);
            }
            if !stage.physics_overrides.is_empty() {
                stage.physics = Some(
                    resolve_physics(&self.physics, &stage.physics_overrides).map_err(|e| {
                        anyhow!("[[curriculum]] stage {} [curriculum.physics]: {e}", k + 1)
                    })?,
                );
            }
        }
        Ok(())
    }
}

/// Reads `[[curriculum]]` (the stages' tasks over `task_table`, the
/// `[task]` section, and their physics over `physics`, the `[physics]`
/// section resolved); `source` names the file in errors.
pub(super) fn curriculum_from_doc(
    doc: &toml::Table,
    task_table: &toml::Table,
    physics: &WorldConfig,
    source: &str,
    registry: &Registry,
) -> Result<Vec<Stage>> {
    let Some(value) = doc.get("curriculum") else {
        return Ok(Vec::new());
    };
    let stages: Vec<StageSection> = value.clone().try_into().map_err(|e: toml::de::Error| {
        anyhow!(
            "config {source} [[curriculum]]: {} (each stage needs terrain = \"SPEC\", or [curriculum.levels], and iterations = N)",
            e.message()
        )
    })?;
    if stages.is_empty() {
        bail!("config {source} [[curriculum]]: no stages");
    }
    stages
        .into_iter()
        .enumerate()
        .map(|(k, stage)| {
            if stage.iterations == 0 {
                bail!(
                    "config {source} [[curriculum]] stage {}: iterations must be at least 1",
                    k + 1
                );
            }
            if let Some(rate) = stage.learning_rate {
                learn::optim::check_learning_rate(rate)
                    .map_err(|e| anyhow!("config {source} [[curriculum]] stage {}: {e}", k + 1))?;
            }
            let task_overrides = stage.task.unwrap_or_default();
            let task = if task_overrides.is_empty() {
                None
            } else {
                Some(stage_task(task_table, &task_overrides).map_err(|e| {
                    anyhow!(
                        "config {source} [[curriculum]] stage {} [curriculum.task]: {e}",
                        k + 1
                    )
                })?)
            };
            let physics_overrides = stage.physics.unwrap_or_default();
            let physics = if physics_overrides.is_empty() {
                None
            } else {
                Some(resolve_physics(physics, &physics_overrides).map_err(|e| {
                    anyhow!(
                        "config {source} [[curriculum]] stage {} [curriculum.physics]: {e}",
                        k + 1
                    )
                })?)
            };
            let advance = stage
                .advance
                .map(|rule| rule.resolve(stage.iterations))
                .transpose()
                .map_err(|e| {
                    anyhow!(
                        "config {source} [[curriculum]] stage {} [curriculum.advance]: {e}",
                        k + 1
                    )
                })?;
            let at = || format!("config {source} [[curriculum]] stage {}", k + 1);
            let (terrain, levels) = match (stage.terrain, stage.levels) {
                (Some(spec), None) => (registry.parse(&spec).with_context(at)?, None),
                (None, Some(levels)) => {
                    let levels = levels
                        .resolve(registry)
                        .with_context(|| format!("{} [curriculum.levels]", at()))?;
                    (levels.terrains[levels.top()].clone(), Some(levels))
                }
                (Some(_), Some(_)) => bail!(
                    "{}: a stage with [curriculum.levels] trains on its levels' terrains; leave terrain out",
                    at()
                ),
                (None, None) => bail!(
                    "{}: no terrain; give terrain = \"SPEC\" or [curriculum.levels]",
                    at()
                ),
            };
            Ok(Stage {
                terrain,
                levels,
                iterations: stage.iterations,
                advance,
                ended_after: None,
                learning_rate: stage.learning_rate,
                task_overrides,
                task,
                physics_overrides,
                physics,
            })
        })
        .collect()
}
