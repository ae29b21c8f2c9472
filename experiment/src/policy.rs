//! What chooses a rollout's actions: the scripted crawl or a trained
//! checkpoint, and the task settings and physics a checkpoint brings with it.
//! Shared by `rollout`, `play` and `eval`.

use std::path::Path;

use anyhow::{Context, Result, bail};
use robot::WorldConfig;
use robot::scripted::ScriptedCrawl;
use robot::snapshot::PhaseObserver;
use robot::task::{ActionPrior, PhaseOutcome, Task, TaskConfig};

use crate::config::ResidualConfig;
use crate::residual::ResidualDriver;

/// What chooses the actions.
pub enum Policy {
    /// the scripted crawl
    Scripted(ScriptedCrawl),
    /// a trained checkpoint or exported policy (PPO or SAC), mean action
    Trained {
        /// the networks, loaded for acting
        learner: Box<dyn learn::Algorithm>,
        /// the task settings the policy was trained with (its observation
        /// layout and action prior)
        task: Box<TaskConfig>,
        /// the physics it was trained in
        physics: Box<WorldConfig>,
        /// set: sample actions with this generator; unset: the mean action
        sampler: Option<Box<rand_chacha::ChaCha8Rng>>,
    },
    /// a trained residual policy (`[residual]`): its phase policy plans each
    /// phase and it moves the feet's targets at the control rate
    Residual {
        /// the lower-level networks, loaded for acting
        learner: Box<dyn learn::Algorithm>,
        /// the phase policy and the phase under way
        driver: Box<ResidualDriver>,
        /// the task settings it was trained with (its phase policy's
        /// observation layout and action prior)
        task: Box<TaskConfig>,
        /// the physics it was trained in
        physics: Box<WorldConfig>,
        /// set: sample the lower level's actions with this generator
        sampler: Option<Box<rand_chacha::ChaCha8Rng>>,
    },
}

impl Policy {
    /// `scripted`, or the path of a checkpoint, a run directory or an
    /// exported policy (`quadwalk export`); `sample_seed` makes a trained
    /// policy sample its actions.
    pub fn from_arg(
        registry: &terrain_plugins::Registry,
        arg: &str,
        sample_seed: Option<u64>,
    ) -> Result<Self> {
        if arg == "scripted" {
            if sample_seed.is_some() {
                bail!(
                    "--stochastic needs a trained policy; the scripted crawl has no distribution"
                );
            }
            return Ok(Self::Scripted(ScriptedCrawl::default()));
        }
        let path = Path::new(arg);
        if !path.exists() {
            bail!(
                "policy {arg:?} is neither `scripted` nor an existing checkpoint or run directory"
            );
        }
        let dir = if learn::export::is_exported_policy(path) {
            path.to_path_buf()
        } else {
            learn::checkpoint::resolve_checkpoint(path).with_context(|| format!("policy {arg}"))?
        };
        let learner =
            learn::registry::load_for_acting(&dir).with_context(|| format!("policy {arg}"))?;
        let mut config = crate::config::Experiment::from_file(
            &dir.join(crate::train::run_dir::CONFIG_FILE),
            registry,
        )
        .with_context(|| format!("policy {arg}"))?;
        if config.has_advance_rules() {
            // where its stages ended, from the run's metrics beside it
            let run = if learn::export::is_exported_policy(&dir) {
                Some(dir.clone())
            } else {
                // a run's `latest` leads to checkpoints/iter-N inside it
                let checkpoint = std::fs::canonicalize(&dir).unwrap_or_else(|_| dir.clone());
                crate::train::run_dir::run_dir_of(&checkpoint)
            };
            let metrics = run
                .map(|r| r.join(crate::train::run_dir::METRICS_FILE))
                .with_context(|| format!("policy {arg}: its curriculum moves on when ready, and no run directory beside it tells where its stages ended"))?;
            config
                .decide_stages_from(&metrics, learner.iteration())
                .with_context(|| format!("policy {arg}"))?;
        }
        // the task and physics of the stage the policy's last iteration
        // trained in
        let last = learner.iteration().saturating_sub(1);
        let task = config.task_at(last).clone();
        let physics = config.physics_at(last).clone();
        if let Some(mut residual) = config.residual {
            crate::residual::phase_policy_seen_from(&mut residual, path);
            if learner.obs_size() != crate::residual::OBSERVATION_SIZE
                || learner.action_size() != crate::residual::ACTION_SIZE
            {
                bail!(
                    "policy {arg}: a residual policy's networks take {} observations and give {} actions, but these take {} and give {}",
                    crate::residual::OBSERVATION_SIZE,
                    crate::residual::ACTION_SIZE,
                    learner.obs_size(),
                    learner.action_size()
                );
            }
            let phase_policy = crate::residual::load_phase_policy(registry, &residual)
                .with_context(|| format!("policy {arg}"))?;
            return Ok(Self::Residual {
                learner,
                driver: Box::new(ResidualDriver::new(residual, phase_policy)),
                task: Box::new(task),
                physics: Box::new(physics),
                sampler: sample_seed.map(|seed| Box::new(rand::SeedableRng::seed_from_u64(seed))),
            });
        }
        if learner.obs_size() != task.observation_size()
            || learner.action_size() != robot::action::ACTION_SIZE
        {
            bail!(
                "policy {arg}: its networks take {} observations and give {} actions, but its config says {} and {}",
                learner.obs_size(),
                learner.action_size(),
                task.observation_size(),
                robot::action::ACTION_SIZE
            );
        }
        Ok(Self::Trained {
            learner,
            task: Box::new(task),
            physics: Box::new(physics),
            sampler: sample_seed.map(|seed| Box::new(rand::SeedableRng::seed_from_u64(seed))),
        })
    }

    /// Fits the scene's task settings and physics to the policy: a trained
    /// policy runs with the observation layout, action prior, swing-height
    /// origin and physics it was trained with (those of the stage of its
    /// last iteration); the scripted crawl refuses an action prior (it is
    /// the prior). With `strict`, set when the task settings came from the
    /// user's own experiment file, a checkpoint whose observation, prior or
    /// swing-height origin differs from that file's is an error naming the
    /// file instead of being applied silently.
    pub fn fit_scene(
        &self,
        task_config: &mut TaskConfig,
        physics: &mut WorldConfig,
        strict: Option<&Path>,
    ) -> Result<()> {
        match self {
            Self::Trained {
                task,
                physics: trained_in,
                ..
            }
            | Self::Residual {
                task,
                physics: trained_in,
                ..
            } => {
                if let Some(file) = strict
                    && (task_config.observation != task.observation
                        || task_config.action_prior != task.action_prior)
                {
                    bail!(
                        "the checkpoint observes {} values (observation {:?}, action_prior {:?}) but {} sets up {} ({:?}, action_prior {:?}); evaluate it with --terrain, or with a config whose [task] matches the checkpoint's",
                        task.observation_size(),
                        task.observation,
                        task.action_prior.name(),
                        file.display(),
                        task_config.observation_size(),
                        task_config.observation,
                        task_config.action_prior.name()
                    );
                }
                if let Some(file) = strict
                    && task_config.swing_height_reference != task.swing_height_reference
                {
                    bail!(
                        "the checkpoint's actions count the swing foot's heights from swing_height_reference = {:?} but {} sets {:?}; evaluate it with --terrain, or with a config whose [task] matches the checkpoint's",
                        task.swing_height_reference.name(),
                        file.display(),
                        task_config.swing_height_reference.name()
                    );
                }
                task_config.observation = task.observation;
                task_config.action_prior = task.action_prior;
                task_config.swing_height_reference = task.swing_height_reference;
                *physics = (**trained_in).clone();
            }
            Self::Scripted(_) if task_config.action_prior != ActionPrior::None => bail!(
                "--policy scripted runs the crawl itself; its config sets action_prior = {:?}, which adds the crawl to a trained policy's actions (use action_prior = \"none\")",
                task_config.action_prior.name()
            ),
            Self::Scripted(_) => {}
        }
        Ok(())
    }

    /// Refuses a physics rate a residual policy cannot act at: its
    /// `control_steps` must divide the phase's steps at `physics`'s rate
    /// (`source` names where the rate came from).
    pub fn check_step_rate(&self, physics: &WorldConfig, source: &str) -> Result<()> {
        if let Self::Residual { driver, .. } = self {
            driver
                .config()
                .validate(physics.steps_per_phase())
                .with_context(|| format!("{source}: the residual policy's [residual]"))?;
        }
        Ok(())
    }

    /// Refuses a scene whose experiment file has a `[residual]` table
    /// (`scene_residual`, from `source`) that is not this policy's own: the
    /// table says what `quadwalk train` trains, and a rollout's policy is
    /// the one given to run, so a different table would be ignored.
    pub fn check_scene_residual(
        &self,
        scene_residual: Option<&ResidualConfig>,
        source: &str,
    ) -> Result<()> {
        let Some(wanted) = scene_residual else {
            return Ok(());
        };
        match self {
            Self::Residual { driver, .. } if driver.config() == wanted => Ok(()),
            _ => bail!(
                "{source} [residual]: the table trains a lower-level policy with `quadwalk train`; the policy run here is the one given as the policy, which is not that residual policy (drop the table, or run the residual run itself)"
            ),
        }
    }

    /// The action for the task's next phase, given its observation (a
    /// residual policy has none: it acts within the phase, see
    /// [`Self::run_phase`]).
    pub fn action(&mut self, task: &Task, obs: &[f32]) -> Result<Vec<f32>> {
        Ok(match self {
            Self::Scripted(crawl) => crawl.act(task).to_vec(),
            Self::Trained {
                learner,
                sampler: Some(rng),
                ..
            } => learner.act_stochastic(obs, rng)?,
            Self::Trained { learner, .. } => learner.act_deterministic(obs)?,
            Self::Residual { .. } => bail!(
                "a residual policy acts within each phase at the control rate, not once per phase: run it with run_phase (as rollout, play and eval do)"
            ),
        })
    }

    /// Runs the task's next phase from its observation `obs` (and writes
    /// the next one there): the phase of this policy's action, or, for a
    /// residual policy, its phase policy's phase moved at the control rate.
    pub fn run_phase(
        &mut self,
        task: &mut Task,
        obs: &mut [f32],
        observer: &mut dyn PhaseObserver,
    ) -> Result<PhaseOutcome> {
        let Self::Residual {
            learner,
            driver,
            sampler,
            ..
        } = self
        else {
            let action = self.action(task, obs)?;
            return Ok(task.step_phase_observed(&action, obs, observer));
        };
        if task.phase() == 0 {
            driver.reset();
        }
        driver.begin_phase(task, obs, observer)?;
        let mut own = [0.0f32; crate::residual::OBSERVATION_SIZE];
        loop {
            driver.observe(task, &mut own);
            let action = match sampler {
                Some(rng) => learner.act_stochastic(&own, rng)?,
                None => learner.act_deterministic(&own)?,
            };
            if let Some(outcome) = driver.control_step(task, &action, obs, observer).phase {
                return Ok(outcome);
            }
        }
    }
}
