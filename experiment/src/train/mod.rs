//! Training: a [`RunPlan`] run iteration by iteration on N parallel worlds
//! (PPO, SAC or CrossQ), with `metrics.jsonl`, atomic checkpoints (every
//! `checkpoint_every` iterations, at the end, and when stopped), curriculum
//! stages, and Rerun loggers on chosen environments.
//!
//! [`train`] returns when the run is done or stopped; it never exits the
//! process. What a front end shows (progress lines, JSON, warnings) it
//! receives through a [`TrainObserver`]; it stops a run by setting the
//! flag it passes in (the command line's Ctrl-C handler does), and the run
//! then writes the checkpoint of the last completed iteration.

mod levels;
pub mod metrics;
mod plan;
pub mod run_dir;

use std::fs;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use learn::checkpoint::{remove_partial_saves, write_file_atomically};
use learn::{Algorithm, IterationStats, VecEnv};
use robot::{RobotModel, WorldConfig};
use terrain_plugins::{Registry, TerrainSpec};
use viz::RolloutLogger;

pub use plan::RunPlan;
use run_dir::{CONFIG_FILE, METRICS_FILE, append_line, keep_metrics_up_to, save_checkpoint};

use crate::config::Experiment;
use crate::config::advance::{self, Advance};
use crate::config::levels::TerrainLevels;
use crate::task_env::TaskEnv;

/// How a run began, told once before its first iteration.
pub struct RunStart<'a> {
    /// the learner's name (`ppo`, `sac`, `crossq`)
    pub algo: &'static str,
    /// the terrain of the first iteration (with `levels`, the top one)
    pub terrain: &'a TerrainSpec,
    /// the first iteration's terrain levels, if its stage has them
    pub levels: Option<&'a TerrainLevels>,
    /// parallel worlds
    pub envs: usize,
    /// steps per world per iteration
    pub steps_per_env: usize,
    /// what a step is: `phases`, or `control steps` for a residual policy
    pub step_unit: &'static str,
    /// threads stepping the worlds
    pub threads: usize,
    /// the first iteration's physics (its stage's, with
    /// `[curriculum.physics]`)
    pub physics: &'a WorldConfig,
    /// where the run writes
    pub run_dir: &'a std::path::Path,
    /// a fork: the checkpoint it went on from and its iteration
    pub forked_from: Option<(&'a std::path::Path, u64)>,
}

/// One completed iteration.
pub struct IterationReport<'a> {
    /// the learner's statistics
    pub stats: &'a IterationStats,
    /// the line written to `metrics.jsonl`
    pub record: &'a serde_json::Value,
    /// the run's total iterations
    pub total: u64,
    /// wall time since this process started training, s
    pub elapsed_secs: f64,
    /// phases stepped since this process started training
    pub phases_done: usize,
}

/// What a front end is told while a run trains; every method has a silent
/// default.
pub trait TrainObserver {
    /// Before the first iteration.
    fn started(&mut self, _start: &RunStart) {}
    /// A curriculum stage begins (not told for the stage a run starts in).
    fn stage_started(
        &mut self,
        _stage: usize,
        _terrain: &TerrainSpec,
        _levels: Option<&TerrainLevels>,
        _learning_rate: Option<f64>,
        _task_overrides: &toml::Table,
        _physics_overrides: &toml::Table,
    ) {
    }
    /// A stage's `[curriculum.advance]` rule was reached after `iterations`
    /// of its iterations (before its maximum): the next iteration starts the
    /// next stage.
    fn stage_ready(&mut self, _stage: usize, _iterations: u64, _rule: &Advance) {}
    /// After each iteration, once its metrics line is written.
    fn iteration_done(&mut self, _report: &IterationReport) -> Result<()> {
        Ok(())
    }
    /// A Rerun logger's warning (a viewer that went away, ...).
    fn warning(&mut self, _message: &str) {}
}

/// A front end that wants to hear nothing.
pub struct Silent;

impl TrainObserver for Silent {}

/// How a run ended.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum TrainOutcome {
    /// every iteration ran; `latest` is the last one's checkpoint
    Completed {
        /// iterations in all
        iterations: u64,
        /// the run's `latest` link
        checkpoint: PathBuf,
    },
    /// the stop flag cut iteration `iteration + 1` short; the checkpoint of
    /// iteration `iteration` was written
    Stopped {
        /// the last completed iteration
        iteration: u64,
        /// the run's `latest` link
        checkpoint: PathBuf,
    },
}

/// Runs `plan` to its last iteration or until `stop` is set. `loggers`
/// stream environments to Rerun (environment index, logger); `model` is
/// the robot every world holds.
pub fn train(
    registry: &Arc<Registry>,
    plan: RunPlan,
    model: &Arc<RobotModel>,
    loggers: Vec<(usize, RolloutLogger)>,
    observer: &mut dyn TrainObserver,
    stop: Arc<AtomicBool>,
) -> Result<TrainOutcome> {
    let RunPlan {
        mut experiment,
        run_dir,
        learner: mut trainer,
        threads,
        fork,
    } = plan;
    let start_iteration = trainer.iteration();
    fs::create_dir_all(run_dir.join("checkpoints"))
        .with_context(|| format!("cannot create the run directory {}", run_dir.display()))?;
    remove_partial_saves(&run_dir);
    remove_partial_saves(&run_dir.join("checkpoints"));
    let config_text = experiment.to_toml();
    write_file_atomically(&run_dir.join(CONFIG_FILE), config_text.as_bytes())?;
    if let Some(checkpoint) = &fork {
        run_dir::start_fork(
            &run_dir,
            checkpoint,
            &*trainer,
            &config_text,
            experiment.train.keep_checkpoints,
        )?;
    }
    let metrics_path = run_dir.join(METRICS_FILE);
    keep_metrics_up_to(&metrics_path, start_iteration)?;
    // the episode counts of the iterations done, from which stages that
    // move on when ready are decided
    let mut history = if experiment.has_advance_rules() && start_iteration > 0 {
        advance::read_history(&metrics_path, start_iteration)?
    } else {
        Vec::new()
    };
    experiment.decide_stages(&history);
    if start_iteration >= experiment.total_iterations() {
        bail!(
            "the run in {} has done {start_iteration} of {} iterations already; pass a larger --iterations to go on",
            run_dir.display(),
            experiment.total_iterations()
        );
    }
    let latest = run_dir.join(learn::checkpoint::LATEST_LINK);

    // the worlds of 0-based iteration `iteration`: its stage's terrain (or
    // each world's level, `world_levels`), task and physics
    let build_env = |experiment: &Experiment, iteration, world_levels: &[usize]| {
        TaskEnv::new(
            registry,
            experiment.terrain_at(iteration).1,
            experiment
                .levels_at(iteration)
                .map(|levels| (levels, world_levels.to_vec())),
            experiment.task_at(iteration),
            experiment.physics_at(iteration),
            model,
            experiment,
            threads,
            stop.clone(),
        )
    };
    // a stage that turns `privileged_critic` on widens the critic's input
    // to its environment's privileged values, and one that turns the
    // height scan on both networks' input, before its first iteration
    let widen = |trainer: &mut dyn Algorithm, env: &TaskEnv, iteration: u64| {
        let context = |what: &str| format!("iteration {}: {what}", iteration + 1);
        trainer
            .widen_observation(env.policy_observation_size())
            .with_context(|| context("the networks cannot take the stage's observation"))?;
        let privileged = env.observation_size() - env.policy_observation_size();
        trainer
            .widen_critic(privileged)
            .with_context(|| context("the critic cannot take the stage's privileged values"))
    };
    let mut stage = experiment.terrain_at(start_iteration).0;
    let mut world_levels = levels::start_levels(&experiment, &metrics_path, start_iteration)?;
    let mut env = build_env(&experiment, start_iteration, &world_levels)?;
    widen(&mut *trainer, &env, start_iteration)?;
    for (e, logger) in loggers {
        env.attach_logger(e, logger);
    }
    observer.started(&RunStart {
        algo: trainer.name(),
        terrain: experiment.terrain_at(start_iteration).1,
        levels: experiment.levels_at(start_iteration),
        envs: experiment.train.envs,
        steps_per_env: trainer.steps_per_env(),
        step_unit: if experiment.residual.is_some() {
            "control steps"
        } else {
            "phases"
        },
        threads,
        physics: experiment.physics_at(start_iteration),
        run_dir: &run_dir,
        forked_from: fork.as_deref().map(|c| (c, start_iteration)),
    });
    let started = Instant::now();
    let mut phases_done = 0usize;
    let mut iteration = start_iteration;
    while iteration < experiment.total_iterations() {
        let (next_stage, terrain) = experiment.terrain_at(iteration);
        let terrain = terrain.clone();
        let stage_rate = experiment.learning_rate_at(iteration);
        if next_stage != stage {
            let loggers = env.detach_loggers();
            world_levels = levels::carry_levels(
                &experiment,
                iteration.checked_sub(1),
                iteration,
                &world_levels,
            );
            env = build_env(&experiment, iteration, &world_levels)?;
            widen(&mut *trainer, &env, iteration)?;
            for l in loggers {
                env.attach_logger(l.env, l.logger);
            }
            stage = next_stage;
            observer.stage_started(
                stage,
                &terrain,
                experiment.levels_at(iteration),
                stage_rate,
                &experiment.curriculum[stage].task_overrides,
                &experiment.curriculum[stage].physics_overrides,
            );
        }
        // a stage's own learning rate (set every iteration, so a resume
        // inside a stage runs as the uninterrupted run did)
        if let Some(rate) = stage_rate {
            trainer.set_learning_rate(rate)?;
        }
        for l in env.loggers_mut() {
            l.logger.set_iteration(Some(iteration as i64));
        }
        // the state before this iteration, written if the run is stopped
        // during it
        let before = trainer.checkpoint_files()?;
        let stats = trainer.iterate(&mut env)?;
        if stop.load(Ordering::SeqCst) {
            save_checkpoint(
                &run_dir,
                iteration,
                before,
                &config_text,
                experiment.train.keep_checkpoints,
            )?;
            finish_loggers(&mut env, observer);
            return Ok(TrainOutcome::Stopped {
                iteration,
                checkpoint: latest,
            });
        }
        let logging_secs = env.take_logging_secs();
        phases_done += stats.steps;
        let mut record = metrics::record(&stats, &terrain, logging_secs);
        if let Some(levels) = env.advance_levels() {
            levels::add_to_record(&mut record, &levels);
            world_levels = levels;
        }
        append_line(&metrics_path, &record.to_string())?;
        if experiment.has_advance_rules() {
            history.push(
                advance::EpisodeCounts::of_record(&record)
                    .context("a metrics line without episode counts")?,
            );
            experiment.decide_stages(&history);
            let current = &experiment.curriculum[stage];
            if let (Some(rule), Some(n)) = (current.advance, current.ended_after)
                && n < current.iterations
                && experiment.terrain_at(iteration + 1).0 != stage
            {
                observer.stage_ready(stage, n, &rule);
            }
        }
        let total = experiment.total_iterations();
        let curves = metrics::curves(&stats);
        for l in env.loggers_mut() {
            l.logger.log_training(stats.iteration as i64, &curves);
            for warning in l.logger.take_warnings() {
                observer.warning(&warning);
            }
        }
        observer.iteration_done(&IterationReport {
            stats: &stats,
            record: &record,
            total,
            elapsed_secs: started.elapsed().as_secs_f64(),
            phases_done,
        })?;
        let done = stats.iteration;
        iteration = done;
        if done % experiment.train.checkpoint_every == 0 || done == total {
            save_checkpoint(
                &run_dir,
                done,
                trainer.checkpoint_files()?,
                &config_text,
                experiment.train.keep_checkpoints,
            )?;
        }
    }
    finish_loggers(&mut env, observer);
    Ok(TrainOutcome::Completed {
        iterations: iteration,
        checkpoint: latest,
    })
}

fn finish_loggers(env: &mut TaskEnv, observer: &mut dyn TrainObserver) {
    for l in env.loggers_mut() {
        l.logger.finish();
        for warning in l.logger.take_warnings() {
            observer.warning(&warning);
        }
    }
}
