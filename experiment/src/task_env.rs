//! `TaskEnv`: N locomotion tasks as one `learn::VecEnv`, stepped in
//! parallel on a rayon pool (one world per task, worlds share nothing), with
//! Rerun loggers on the environments the run streams.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use learn::seeds::derive_seed;
use learn::{StepResult, VecEnv};
use rayon::prelude::*;
use robot::action::ACTION_SIZE;
use robot::snapshot::{PhaseObserver, PhaseStart};
use robot::task::{PhaseOutcome, RewardTerms, Task, TaskConfig, TaskMirror, Termination};
use robot::{RobotModel, WorldConfig};
use terrain_plugins::{Registry, TerrainSpec};
use viz::RolloutLogger;

use crate::config::Experiment;
use crate::config::levels::{LevelTally, TerrainLevels};
use crate::residual::{self, ResidualDriver};
use crate::scene::make_world;

/// Per-episode metrics, in the order of `episode_metrics`: the distance
/// and the goals, then per [`Termination::KINDS`] 1 when the episode ended
/// so (`fell_<kind>`), else 0. A task without a stall rule reports all but
/// the last ([`episode_metrics_of`]).
pub const EPISODE_METRICS: [&str; 6] = [
    "distance_m",
    "goals_reached",
    "fell_base_too_low",
    "fell_pitch_too_large",
    "fell_non_foot_contact",
    "fell_stalled",
];

/// The [`EPISODE_METRICS`] an environment with `task` reports: `fell_stalled`
/// only where the task has a stall rule, so that the metrics of runs without
/// one keep their keys.
pub fn episode_metrics_of(task: &TaskConfig) -> &'static [&'static str] {
    let count = EPISODE_METRICS.len() - usize::from(task.stall.is_none());
    &EPISODE_METRICS[..count]
}

/// A logger on one environment, timing what it costs.
pub struct EnvLogger {
    /// the environment it watches
    pub env: usize,
    /// the logger
    pub logger: RolloutLogger,
    /// seconds spent logging
    pub secs: f64,
}

impl EnvLogger {
    /// A new episode: forget the trajectory, log the state after the reset.
    fn log_reset(&mut self, task: &Task) {
        let clock = Instant::now();
        self.logger.begin_rollout();
        self.logger.log_now(task);
        self.secs += clock.elapsed().as_secs_f64();
    }
}

/// Times the observer calls of an environment's logger, if it has one
/// (without one, nothing is told).
struct Timed<'a>(Option<&'a mut EnvLogger>);

impl PhaseObserver for Timed<'_> {
    fn phase_started(&mut self, task: &Task, start: &PhaseStart) {
        if let Some(l) = &mut self.0 {
            let clock = Instant::now();
            l.logger.phase_started(task, start);
            l.secs += clock.elapsed().as_secs_f64();
        }
    }

    fn stepped(&mut self, task: &Task, step_in_phase: usize) {
        if let Some(l) = &mut self.0 {
            let clock = Instant::now();
            l.logger.stepped(task, step_in_phase);
            l.secs += clock.elapsed().as_secs_f64();
        }
    }

    fn phase_ended(&mut self, task: &Task, outcome: &PhaseOutcome) {
        if let Some(l) = &mut self.0 {
            let clock = Instant::now();
            l.logger.phase_ended(task, outcome);
            l.secs += clock.elapsed().as_secs_f64();
        }
    }
}

/// N tasks behind `learn::VecEnv`.
///
/// `reset_all` builds every world afresh (a few ms each): a rapier world
/// that has been stepped keeps solver caches and contact state that a reset
/// of bodies does not clear, and an iteration must start from the same
/// state whether the run was resumed or not.
pub struct TaskEnv {
    tasks: Vec<Task>,
    registry: Arc<Registry>,
    terrain: TerrainSpec,
    model: Arc<RobotModel>,
    task_config: TaskConfig,
    physics: WorldConfig,
    terrain_seed: u64,
    /// one slot per task: its logger, if streamed
    loggers: Vec<Option<EnvLogger>>,
    /// the policy's observation values per row
    obs_size: usize,
    /// the critic's privileged values after them
    /// (`[task.observation] privileged_critic`)
    privileged_size: usize,
    pool: rayon::ThreadPool,
    interrupted: Arc<AtomicBool>,
    /// the tasks were just built and never stepped (the first reset need
    /// not build them again)
    pristine: bool,
    /// `[residual]`: each task stepped a control step at a time by its
    /// driver (the policy trained is the lower level)
    residual: Option<Residual>,
    /// `[curriculum.levels]`: each world's level and what its episodes did
    /// this iteration
    levels: Option<WorldLevels>,
}

/// The terrain level of each world, and the tally of its episodes that
/// ended since the levels last moved.
struct WorldLevels {
    config: TerrainLevels,
    level: Vec<usize>,
    tally: Vec<LevelTally>,
}

/// The drivers of a residual run, one per task, and each task's
/// phase-level observation (what the frozen phase policy reads).
struct Residual {
    drivers: Vec<ResidualDriver>,
    phase_obs: Vec<Vec<f32>>,
}

impl TaskEnv {
    /// `experiment.train.envs` worlds on `terrain` with `task` and
    /// `physics` (a stage's), or with `levels`, world `i` on the terrain of
    /// its level `levels.1[i]`; world `i`'s terrain draw is seeded by
    /// `(experiment.train.seed, i)`. Stepped on `threads` threads.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        registry: &Arc<Registry>,
        terrain: &TerrainSpec,
        levels: Option<(&TerrainLevels, Vec<usize>)>,
        task: &TaskConfig,
        physics: &WorldConfig,
        model: &Arc<RobotModel>,
        experiment: &Experiment,
        threads: usize,
        interrupted: Arc<AtomicBool>,
    ) -> Result<Self> {
        let (envs, seed) = (experiment.train.envs, experiment.train.seed);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .context("cannot start the environment threads")?;
        let residual = match &experiment.residual {
            None => None,
            Some(config) => {
                let drivers = (0..envs)
                    .map(|_| {
                        residual::load_phase_policy(registry, config)
                            .map(|p| ResidualDriver::new(config.clone(), p))
                    })
                    .collect::<Result<Vec<_>>>()?;
                Some(Residual {
                    drivers,
                    phase_obs: vec![vec![0.0; task.observation_size()]; envs],
                })
            }
        };
        let (obs_size, privileged_size) = match residual {
            Some(_) => (residual::OBSERVATION_SIZE, 0),
            None => (task.observation_size(), task.observation.privileged_size()),
        };
        let mut env = Self {
            obs_size,
            privileged_size,
            residual,
            loggers: (0..envs).map(|_| None).collect(),
            tasks: Vec::new(),
            registry: registry.clone(),
            terrain: terrain.clone(),
            model: model.clone(),
            task_config: task.clone(),
            physics: physics.clone(),
            terrain_seed: seed,
            pool,
            interrupted,
            pristine: true,
            levels: None,
        };
        if let Some((config, level)) = levels {
            if level.len() != envs || level.iter().any(|&l| l > config.top()) {
                bail!(
                    "the worlds' terrain levels {level:?} are not {envs} levels in 0..={}",
                    config.top()
                );
            }
            if env.residual.is_some() {
                bail!("terrain levels train phase-level policies; a [residual] run has none");
            }
            env.levels = Some(WorldLevels {
                config: config.clone(),
                level,
                tally: vec![LevelTally::default(); envs],
            });
        }
        env.tasks = env.build_tasks(envs)?;
        Ok(env)
    }

    /// Fresh tasks for environments `0..envs`, built in parallel.
    fn build_tasks(&self, envs: usize) -> Result<Vec<Task>> {
        let (registry, terrain, model, config, physics, seed) = (
            &self.registry,
            &self.terrain,
            &self.model,
            &self.task_config,
            &self.physics,
            self.terrain_seed,
        );
        let terrains: Vec<&TerrainSpec> = (0..envs)
            .map(|i| match &self.levels {
                Some(levels) => &levels.config.terrains[levels.level[i]],
                None => terrain,
            })
            .collect();
        self.pool.install(|| {
            (0..envs)
                .into_par_iter()
                .map(|i| {
                    let world = make_world(
                        registry,
                        terrains[i],
                        model.clone(),
                        derive_seed(seed, i as u64),
                        [0.0, 0.0],
                        physics,
                    )?;
                    Ok(Task::new(world, config.clone(), 0))
                })
                .collect()
        })
    }

    /// Streams environment `env` to `logger` (its terrain is logged now).
    pub fn attach_logger(&mut self, env: usize, mut logger: RolloutLogger) {
        logger.log_terrain(self.tasks[env].world().terrain());
        self.loggers[env] = Some(EnvLogger {
            env,
            logger,
            secs: 0.0,
        });
    }

    /// Takes the loggers back (to move them to the next curriculum stage).
    pub fn detach_loggers(&mut self) -> Vec<EnvLogger> {
        self.loggers.iter_mut().filter_map(Option::take).collect()
    }

    /// The loggers.
    pub fn loggers_mut(&mut self) -> impl Iterator<Item = &mut EnvLogger> {
        self.loggers.iter_mut().flatten()
    }

    /// Seconds spent logging since the last call, summed over environments.
    pub fn take_logging_secs(&mut self) -> f64 {
        self.loggers_mut()
            .map(|l| std::mem::take(&mut l.secs))
            .fold(0.0, |a, b| a + b)
    }

    /// With terrain levels: moves each world's level by what its episodes
    /// that ended since the last call did ([`TerrainLevels::next_level`]),
    /// and returns the levels, which the worlds of the next iteration (the
    /// next [`VecEnv::reset_all`]) are built on. `None` without levels.
    pub fn advance_levels(&mut self) -> Option<Vec<usize>> {
        let levels = self.levels.as_mut()?;
        for (level, tally) in levels.level.iter_mut().zip(&mut levels.tally) {
            *level = levels.config.next_level(*level, tally);
            *tally = LevelTally::default();
        }
        Some(levels.level.clone())
    }
}

/// The task's left-right mirror as the learner reads it: the observation
/// with its privileged values, and the phase action.
struct PhaseMirror(TaskMirror);

impl learn::Mirror for PhaseMirror {
    fn mirror_observation(&self, row: &mut [f32]) {
        self.0.mirror_observation(row);
    }

    fn mirror_action(&self, row: &mut [f32]) {
        robot::task::mirror_action(row);
    }
}

impl VecEnv for TaskEnv {
    fn num_envs(&self) -> usize {
        self.tasks.len()
    }

    fn mirror(&self) -> Result<Arc<dyn learn::Mirror>, String> {
        if self.residual.is_some() {
            return Err(
                "a [residual] run's control-step observation has no left-right mirror".into(),
            );
        }
        let mirror = TaskMirror::new(&self.task_config).map_err(|e| e.to_string())?;
        debug_assert_eq!(mirror.observation_size(), self.observation_size());
        Ok(Arc::new(PhaseMirror(mirror)))
    }

    fn observation_size(&self) -> usize {
        self.obs_size + self.privileged_size
    }

    fn policy_observation_size(&self) -> usize {
        self.obs_size
    }

    fn action_size(&self) -> usize {
        match self.residual {
            Some(_) => residual::ACTION_SIZE,
            None => ACTION_SIZE,
        }
    }

    fn reward_term_names(&self) -> Vec<String> {
        match self.residual {
            Some(_) => RESIDUAL_REWARD_TERMS
                .iter()
                .map(ToString::to_string)
                .collect(),
            None => RewardTerms::NAMES.iter().map(ToString::to_string).collect(),
        }
    }

    fn episode_metric_names(&self) -> Vec<String> {
        episode_metrics_of(&self.task_config)
            .iter()
            .map(ToString::to_string)
            .collect()
    }

    fn reset_all(&mut self, seed: u64, obs: &mut [f32]) {
        let (o, width) = (self.obs_size, self.observation_size());
        // A stepped rapier world keeps solver and contact state that a body
        // reset does not clear; rebuilding makes every iteration (and a
        // resumed run) start from the same worlds.
        if !std::mem::replace(&mut self.pristine, false) {
            self.tasks = self
                .build_tasks(self.tasks.len())
                .expect("worlds that were built once build again");
        }
        if let Some(residual) = &mut self.residual {
            let Residual { drivers, phase_obs } = residual;
            self.pool.install(|| {
                self.tasks
                    .par_iter_mut()
                    .zip(obs.par_chunks_mut(width))
                    .zip(self.loggers.par_iter_mut())
                    .zip(drivers.par_iter_mut())
                    .zip(phase_obs.par_iter_mut())
                    .enumerate()
                    .for_each(|(i, ((((task, row), logger), driver), phase_row))| {
                        task.set_seed(derive_seed(seed, i as u64));
                        begin_residual_episode(task, driver, phase_row, row, logger);
                    });
            });
            return;
        }
        self.pool.install(|| {
            self.tasks
                .par_iter_mut()
                .zip(obs.par_chunks_mut(width))
                .zip(self.loggers.par_iter_mut())
                .enumerate()
                .for_each(|(i, ((task, row), logger))| {
                    task.set_seed(derive_seed(seed, i as u64));
                    task.reset(&mut row[..o]);
                    task.observe_privileged(&mut row[o..]);
                    if let Some(l) = logger {
                        l.log_reset(task);
                    }
                });
        });
    }

    fn interrupted(&self) -> bool {
        self.interrupted.load(Ordering::Relaxed)
    }

    /// Steps every task one phase. After Ctrl-C no physics runs: the step
    /// returns zeros at once and the trainer discards the iteration.
    fn step(&mut self, actions: &[f32], out: &mut StepResult) {
        let (o, width) = (self.obs_size, self.observation_size());
        let t = RewardTerms::NAMES.len();
        let m = episode_metrics_of(&self.task_config).len();
        if self.interrupted.load(Ordering::Relaxed) {
            out.rewards.fill(0.0);
            out.truncated.fill(true);
            out.terminated.fill(false);
            out.final_obs.fill(0.0);
            out.reward_terms.fill(0.0);
            out.episode_metrics.fill(0.0);
            return;
        }
        if let Some(residual) = &mut self.residual {
            step_residual(
                m,
                &self.pool,
                &mut self.tasks,
                &mut self.loggers,
                residual,
                actions,
                out,
            );
            return;
        }
        let StepResult {
            obs,
            rewards,
            terminated,
            truncated,
            final_obs,
            reward_terms,
            episode_metrics,
        } = out;
        self.pool.install(|| {
            self.tasks
                .par_iter_mut()
                .zip(self.loggers.par_iter_mut())
                .zip(actions.par_chunks(ACTION_SIZE))
                .zip(obs.par_chunks_mut(width))
                .zip(final_obs.par_chunks_mut(width))
                .zip(reward_terms.par_chunks_mut(t))
                .zip(episode_metrics.par_chunks_mut(m))
                .zip(rewards.par_iter_mut())
                .zip(terminated.par_iter_mut())
                .zip(truncated.par_iter_mut())
                .for_each(
                    |(
                        (
                            (
                                (
                                    (((((task, logger), action), obs_row), final_row), terms),
                                    metrics,
                                ),
                                reward,
                            ),
                            term,
                        ),
                        trunc,
                    )| {
                        let (policy_row, privileged_row) = obs_row.split_at_mut(o);
                        let outcome = task.step_phase_observed(
                            action,
                            policy_row,
                            &mut Timed(logger.as_mut()),
                        );
                        task.observe_privileged(privileged_row);
                        *reward = outcome.reward as f32;
                        for (slot, value) in terms.iter_mut().zip(outcome.terms.values()) {
                            *slot = value as f32;
                        }
                        *term = outcome.termination.is_some();
                        *trunc = outcome.truncated && !*term;
                        if *term || *trunc {
                            final_row.copy_from_slice(obs_row);
                            write_episode_metrics(task, outcome.termination.as_ref(), metrics);
                            task.reset(&mut obs_row[..o]);
                            task.observe_privileged(&mut obs_row[o..]);
                            if let Some(l) = logger {
                                l.log_reset(task);
                            }
                        }
                    },
                );
        });
        if let Some(levels) = &mut self.levels {
            let ended = terminated.iter().zip(truncated.iter());
            for ((tally, (&term, &trunc)), row) in levels
                .tally
                .iter_mut()
                .zip(ended)
                .zip(episode_metrics.chunks_exact(m))
            {
                if term || trunc {
                    tally.add(f64::from(row[0]), term);
                }
            }
        }
    }
}

/// An ended episode's [`EPISODE_METRICS`] (as many as `metrics` holds):
/// the distance along x from its start, m, the goals reached, and which
/// termination (if any) ended it.
fn write_episode_metrics(task: &Task, termination: Option<&Termination>, metrics: &mut [f32]) {
    let base_x_m = task.world().base_pose().translation.vector.x;
    metrics[0] = (base_x_m - task.start_xy_m()[0]) as f32;
    metrics[1] = task.goals_reached() as f32;
    for (slot, kind) in metrics[2..].iter_mut().zip(Termination::KINDS) {
        *slot = f32::from(u8::from(termination.is_some_and(|t| t.kind() == kind)));
    }
}

/// The reward terms of a residual run's control steps.
pub const RESIDUAL_REWARD_TERMS: [&str; 2] = ["phase", "offset"];

/// A residual task's new episode: the task reset, the driver's first phase
/// planned, the lower-level observation written into `row`.
fn begin_residual_episode(
    task: &mut Task,
    driver: &mut ResidualDriver,
    phase_row: &mut [f32],
    row: &mut [f32],
    logger: &mut Option<EnvLogger>,
) {
    task.reset(phase_row);
    driver.reset();
    if let Some(l) = logger {
        l.log_reset(task);
    }
    begin_residual_phase(task, driver, phase_row, logger);
    driver.observe(task, row);
}

/// The driver's next phase, planned from the phase-level observation.
fn begin_residual_phase(
    task: &mut Task,
    driver: &mut ResidualDriver,
    phase_row: &[f32],
    logger: &mut Option<EnvLogger>,
) {
    driver
        .begin_phase(task, phase_row, &mut Timed(logger.as_mut()))
        .expect("the phase policy acts on its own observation");
}

/// One control step of every residual task (see [`crate::residual`]), `m`
/// episode metrics a task.
fn step_residual(
    m: usize,
    pool: &rayon::ThreadPool,
    tasks: &mut [Task],
    loggers: &mut [Option<EnvLogger>],
    residual: &mut Residual,
    actions: &[f32],
    out: &mut StepResult,
) {
    let t = RESIDUAL_REWARD_TERMS.len();
    let Residual { drivers, phase_obs } = residual;
    let StepResult {
        obs,
        rewards,
        terminated,
        truncated,
        final_obs,
        reward_terms,
        episode_metrics,
    } = out;
    pool.install(|| {
        tasks
            .par_iter_mut()
            .zip(loggers.par_iter_mut())
            .zip(drivers.par_iter_mut())
            .zip(phase_obs.par_iter_mut())
            .zip(actions.par_chunks(residual::ACTION_SIZE))
            .zip(obs.par_chunks_mut(residual::OBSERVATION_SIZE))
            .zip(final_obs.par_chunks_mut(residual::OBSERVATION_SIZE))
            .zip(reward_terms.par_chunks_mut(t))
            .zip(episode_metrics.par_chunks_mut(m))
            .zip(rewards.par_iter_mut())
            .zip(terminated.par_iter_mut().zip(truncated.par_iter_mut()))
            .for_each(
                |(
                    (
                        (
                            (
                                ((((((task, logger), driver), phase_row), action), row), final_row),
                                terms,
                            ),
                            metrics,
                        ),
                        reward,
                    ),
                    (term, trunc),
                )| {
                    let outcome =
                        driver.control_step(task, action, phase_row, &mut Timed(logger.as_mut()));
                    *reward = outcome.reward as f32;
                    terms[0] = (outcome.reward - outcome.offset_reward) as f32;
                    terms[1] = outcome.offset_reward as f32;
                    let (ended, cut) = outcome.phase.as_ref().map_or((false, false), |p| {
                        (
                            p.termination.is_some(),
                            p.truncated && p.termination.is_none(),
                        )
                    });
                    *term = ended;
                    *trunc = cut;
                    if outcome.phase.is_some() && !ended && !cut {
                        begin_residual_phase(task, driver, phase_row, logger);
                    }
                    driver.observe(task, row);
                    if ended || cut {
                        final_row.copy_from_slice(row);
                        let termination =
                            outcome.phase.as_ref().and_then(|p| p.termination.as_ref());
                        write_episode_metrics(task, termination, metrics);
                        begin_residual_episode(task, driver, phase_row, row, logger);
                    }
                },
            );
    });
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;
    use std::sync::atomic::AtomicBool;

    use learn::{StepResult, VecEnv};
    use robot::RobotModel;
    use terrain_plugins::Registry;

    use super::*;

    /// Every world of `env` reset with `seed` and stepped one phase of zero
    /// actions, which ends its one-phase episode.
    fn one_phase_of_zero_actions(env: &mut TaskEnv, seed: u64) -> StepResult {
        let n = env.num_envs();
        env.reset_all(seed, &mut vec![0.0; n * env.observation_size()]);
        let mut out = StepResult::new(env);
        env.step(&vec![0.0; n * env.action_size()], &mut out);
        assert!((0..n).all(|i| out.ended(i)), "one-phase episodes end");
        out
    }

    /// The episode metrics of world 0's first episode, of two worlds on
    /// rigid ground, one-phase episodes and zero actions, with the `[task]`
    /// lines given.
    fn first_episode_metrics(task_lines: &str) -> Vec<(String, f32)> {
        let registry = Arc::new(Registry::builtin());
        let text = format!(
            "[terrain]\nspec = \"rigid\"\n[task]\nmax_phases = 1\n{task_lines}[train]\nenvs = 2\n"
        );
        let experiment = Experiment::from_toml(&text, "test.toml", &registry).unwrap();
        let mut env = TaskEnv::new(
            &registry,
            &experiment.terrain,
            None,
            &experiment.task,
            &experiment.physics,
            &Arc::new(RobotModel::laikago()),
            &experiment,
            1,
            Arc::new(AtomicBool::new(false)),
        )
        .unwrap();
        let out = one_phase_of_zero_actions(&mut env, 3);
        let names = env.episode_metric_names();
        assert_eq!(names, episode_metrics_of(&experiment.task));
        let m = names.len();
        names
            .into_iter()
            .zip(out.episode_metrics[..m].to_vec())
            .collect()
    }

    #[test]
    fn an_ended_episode_reports_the_termination_that_ended_it() {
        let fell = |metrics: &[(String, f32)]| -> Vec<f32> {
            metrics[2..].iter().map(|(_, v)| *v).collect()
        };
        // a phase of standing stays within the paper's limits: cut by the
        // time limit, no cause
        let survived = first_episode_metrics("");
        assert_eq!(fell(&survived), [0.0, 0.0, 0.0], "{survived:?}");
        // a pitch limit of 0.01 degrees ends it by pitch
        let pitched = first_episode_metrics("max_pitch_deg = 0.01\n");
        assert_eq!(fell(&pitched), [0.0, 1.0, 0.0], "{pitched:?}");
        // a minimum base height above the standing base ends it by height
        let low = first_episode_metrics("min_base_height_m = 0.6\n");
        assert_eq!(fell(&low), [1.0, 0.0, 0.0], "{low:?}");
        // a phase of standing makes no ground: a one-phase stall window
        // ends it, and only then is fell_stalled reported
        let stalled = first_episode_metrics("stall = { phases = 1, new_ground_m = 0.05 }\n");
        assert_eq!(fell(&stalled), [0.0, 0.0, 0.0, 1.0], "{stalled:?}");
        assert_eq!(stalled.last().unwrap().0, "fell_stalled");
        for kind in Termination::KINDS {
            assert!(EPISODE_METRICS.contains(&format!("fell_{kind}").as_str()));
        }
    }

    /// Each world's standing sink on its terrain (0 on rigid ground), m.
    fn standing_sinks_m(env: &TaskEnv) -> Vec<f64> {
        env.tasks
            .iter()
            .map(|task| {
                let terrain = task.world().terrain();
                terrain.regions()[terrain.region_index_at(0.0, 0.0)].expected_sink_m
            })
            .collect()
    }

    /// Three worlds on levels rigid, 2 cm and 5 cm tiles, one-phase
    /// episodes of zero actions with the `[task]` lines given: each world
    /// is built on its level; after the iteration the levels move by what
    /// the episodes did, and the next reset builds each world on its new
    /// level. Returns the levels after the step.
    fn levels_after_one_phase(task_lines: &str) -> Vec<usize> {
        let registry = Arc::new(Registry::builtin());
        let text = format!(
            "[[curriculum]]\niterations = 1\n[curriculum.levels]\nterrains = [\"rigid\", \"elastic:2cm\", \"elastic:5cm\"]\n\n[task]\nmax_phases = 1\n{task_lines}[train]\nenvs = 3\n"
        );
        let experiment = Experiment::from_toml(&text, "levels.toml", &registry).unwrap();
        let levels = experiment.levels_at(0).unwrap();
        let mut env = TaskEnv::new(
            &registry,
            &experiment.terrain,
            Some((levels, vec![0, 1, 2])),
            &experiment.task,
            &experiment.physics,
            &Arc::new(RobotModel::laikago()),
            &experiment,
            2,
            Arc::new(AtomicBool::new(false)),
        )
        .unwrap();
        let sinks = standing_sinks_m;
        let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-9);
        assert!(close(&sinks(&env), &[0.0, 0.02, 0.05]), "{:?}", sinks(&env));
        let out = one_phase_of_zero_actions(&mut env, 5);
        let m = EPISODE_METRICS.len();
        let expected: Vec<usize> = (0..3)
            .map(|i| {
                let mut tally = LevelTally::default();
                tally.add(f64::from(out.episode_metrics[i * m]), out.terminated[i]);
                levels.next_level(i, &tally)
            })
            .collect();
        let after = env.advance_levels().expect("the worlds have levels");
        assert_eq!(after, expected);
        // the tallies start again: nothing ended since, nothing moves
        assert_eq!(env.advance_levels().unwrap(), after);
        env.reset_all(6, &mut vec![0.0; 3 * env.observation_size()]);
        let built: Vec<f64> = after.iter().map(|&l| [0.0, 0.02, 0.05][l]).collect();
        assert!(close(&sinks(&env), &built), "{:?}", sinks(&env));
        after
    }

    #[test]
    fn each_world_trains_on_its_level_and_moves_by_what_its_episodes_did() {
        // a phase of standing: no fall, but not the metre that moves a world up
        assert_eq!(levels_after_one_phase(""), [0, 1, 2]);
        // every episode falls at once (a 0.01-degree pitch limit): each
        // world moves down, the bottom one stays
        assert_eq!(levels_after_one_phase("max_pitch_deg = 0.01\n"), [0, 0, 1]);
    }
}
