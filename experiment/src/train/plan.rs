//! What a run needs before its first iteration: the experiment, the run
//! directory, the learner (new, resumed or forked) and the thread count.

use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use learn::Algorithm;
use learn::checkpoint::resolve_checkpoint;
use learn::registry::load_checkpoint;
use robot::RobotModel;
use terrain_plugins::Registry;

use super::run_dir::{CONFIG_FILE, METRICS_FILE, run_dir_of};
use crate::config::Experiment;
use crate::config::advance::read_history;

/// A run, resolved: [`super::train`] runs it.
pub struct RunPlan {
    /// the experiment, every setting resolved
    pub experiment: Experiment,
    /// where the run writes
    pub run_dir: PathBuf,
    /// the learner, at the iteration the run goes on from
    pub learner: Box<dyn Algorithm>,
    /// threads stepping the worlds
    pub threads: usize,
    /// a fork: the checkpoint the run starts from
    pub fork: Option<PathBuf>,
}

impl RunPlan {
    /// A new run of `experiment` in `run_dir` (which must not hold a run),
    /// from scratch or, with `fork`, from another run's checkpoint that
    /// `experiment` reproduces.
    pub fn fresh(
        registry: &Registry,
        mut experiment: Experiment,
        run_dir: PathBuf,
        model: &RobotModel,
        threads: usize,
        fork: Option<&Path>,
    ) -> Result<Self> {
        if run_dir.join(learn::checkpoint::LATEST_LINK).exists()
            || run_dir.join(METRICS_FILE).exists()
        {
            bail!(
                "run directory {} already holds a run: continue it with --resume {0}, or choose another --run-dir",
                run_dir.display()
            );
        }
        if model.joints.len() != 12 {
            bail!(
                "the robot has {} joints; training needs a 12-DoF quadruped",
                model.joints.len()
            );
        }
        if experiment.residual.is_some() {
            crate::residual::fit_to_phase_policy(registry, &mut experiment)?;
        }
        if let Some(fork) = fork {
            let (learner, checkpoint) = fork_from(fork, &experiment, registry)?;
            return Ok(Self {
                experiment,
                run_dir,
                learner,
                threads,
                fork: Some(checkpoint),
            });
        }
        let (obs, actions, seed) = match experiment.residual {
            Some(_) => (
                crate::residual::OBSERVATION_SIZE,
                crate::residual::ACTION_SIZE,
                experiment.train.seed,
            ),
            None => (
                experiment.task_at(0).observation_size(),
                robot::action::ACTION_SIZE,
                experiment.train.seed,
            ),
        };
        let privileged = match experiment.residual {
            Some(_) => 0,
            None => experiment.task_at(0).observation.privileged_size(),
        };
        let learner = experiment.learner().build((obs, privileged), actions, seed);
        let learner = if privileged > 0 {
            learner.context("[task.observation] privileged_critic")?
        } else {
            learner?
        };
        Ok(Self {
            experiment,
            run_dir,
            learner,
            threads,
            fork: None,
        })
    }

    /// Goes on with the run of `resume` (its directory or one of its
    /// checkpoints) under its own `config.toml`; `iterations` raises the
    /// total of a run without a curriculum.
    pub fn resume(
        registry: &Registry,
        resume: &Path,
        iterations: Option<u64>,
        threads: usize,
    ) -> Result<Self> {
        let checkpoint =
            resolve_checkpoint(resume).with_context(|| format!("--resume {}", resume.display()))?;
        let checkpoint = fs::canonicalize(&checkpoint).unwrap_or(checkpoint);
        let mut experiment = Experiment::from_file(&checkpoint.join(CONFIG_FILE), registry)?;
        let learner = load_checkpoint(&checkpoint)
            .with_context(|| format!("--resume {}", resume.display()))?;
        let run_dir = run_dir_of(&checkpoint).with_context(|| {
            format!(
                "--resume {}: the checkpoint is not inside a run directory (RUN/checkpoints/iter-N); \
                 copy it there or train afresh",
                resume.display()
            )
        })?;
        if let Some(n) = iterations {
            if !experiment.curriculum.is_empty() {
                bail!(
                    "--iterations cannot change a curriculum's length when resuming; to go on with more stages, --fork this run's checkpoint with a config that has them"
                );
            }
            experiment.train.iterations = n;
        }
        Ok(Self {
            experiment,
            run_dir,
            learner,
            threads,
            fork: None,
        })
    }
}

/// A fork's learner (a run directory means its latest checkpoint) and the
/// checkpoint's path, once `experiment` is shown to train the checkpoint's
/// iterations as its run did.
fn fork_from(
    fork: &Path,
    experiment: &Experiment,
    registry: &Registry,
) -> Result<(Box<dyn Algorithm>, PathBuf)> {
    let context = || format!("--fork {}", fork.display());
    let checkpoint = resolve_checkpoint(fork).with_context(context)?;
    let checkpoint = fs::canonicalize(&checkpoint).unwrap_or(checkpoint);
    let learner = load_checkpoint(&checkpoint).with_context(context)?;
    let mut forked =
        Experiment::from_file(&checkpoint.join(CONFIG_FILE), registry).with_context(context)?;
    let done = learner.iteration();
    // stages that move on when ready, decided by the checkpoint's history
    let mut experiment = experiment.clone();
    if experiment.has_advance_rules() || forked.has_advance_rules() {
        let metrics = run_dir_of(&checkpoint)
            .map(|run| run.join(METRICS_FILE))
            .with_context(|| {
                format!(
                    "--fork {}: a curriculum that moves on when ready needs the checkpoint's run directory (its metrics.jsonl tells where the stages ended)",
                    fork.display()
                )
            })?;
        let history = read_history(&metrics, done).with_context(context)?;
        experiment.decide_stages(&history);
        forked.decide_stages(&history);
    }
    if let Some(difference) = experiment.differs_before(&forked, done) {
        bail!(
            "--fork {}: the checkpoint's run trained its {done} iterations otherwise than this config would: {difference} (this config against the checkpoint's); a fork goes on only from a checkpoint that this config reproduces",
            fork.display()
        );
    }
    if done >= experiment.total_iterations() {
        bail!(
            "--fork {}: the checkpoint is at iteration {done}, and this config trains {} in all; nothing is left to train",
            fork.display(),
            experiment.total_iterations()
        );
    }
    Ok((learner, checkpoint))
}
