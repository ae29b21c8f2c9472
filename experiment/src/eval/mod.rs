//! Evaluation: a policy on many episodes of unseen seeds, run in
//! parallel, measured the way the paper measures (Table I, Fig. 4) and the
//! way a locomotion researcher judges a gait (success, distance
//! percentiles, falls by cause, cost of transport, foot slip), as an
//! [`EvalReport`] (`eval.json`, `table1.md`).
//!
//! An episode is exactly `quadwalk rollout` with the same policy, terrain
//! and seed: the same world (seeded by the episode's seed), the same start,
//! the same actions.

pub mod record;
pub mod response;
pub mod seed_sets;
pub mod summary;
pub mod table1;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, anyhow, bail};
use rayon::prelude::*;
use robot::snapshot::{Both, PhaseObserver};
use robot::task::{Task, TaskConfig};
use robot::{RobotModel, WorldConfig};
use serde::{Deserialize, Serialize};
use terrain_plugins::{Registry, TerrainSpec};

use crate::config::Experiment;
use crate::policy::Policy;
use crate::scene::make_world;
use record::{EpisodeRecord, EpisodeRecorder};
use seed_sets::SeedSetSummary;
use summary::Summary;

/// The first episode seed unless told: far from the seeds training draws
/// its worlds and episodes from (small integers and their derived hashes
/// are where `train --seed` lives; these are never used there by default).
pub const DEFAULT_FIRST_SEED: u64 = 1_000_000;

/// The file every evaluation writes its measurements to.
pub const REPORT_FILE: &str = "eval.json";
/// The format tag inside [`REPORT_FILE`].
const REPORT_FORMAT: &str = "quadwalk-eval/1";

/// What an evaluation writes to [`REPORT_FILE`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EvalReport {
    /// [`REPORT_FORMAT`]
    pub format: String,
    /// the policy argument
    pub policy: String,
    /// the terrain spec
    pub terrain: String,
    /// the first episode's seed
    pub first_seed: u64,
    /// phases each episode could run
    pub max_phases: usize,
    /// whether actions were sampled
    pub stochastic: bool,
    /// the `--task KEY=VALUE` settings over the scene's task that judged it
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub task_overrides: Vec<String>,
    /// the physics rate the episodes ran at, Hz (written when it is not
    /// the paper's 240)
    #[serde(
        default = "paper_step_rate_hz",
        skip_serializing_if = "robot::world_config::is_paper_step_rate"
    )]
    pub step_rate_hz: u32,
    /// the aggregates
    pub summary: Summary,
    /// each seed set's success, when the episodes were more than one set
    /// of consecutive seeds ([`seed_sets::SeedSets`])
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub seed_sets: Vec<SeedSetSummary>,
    /// every episode, in seed order
    pub episodes: Vec<EpisodeRecord>,
}

fn paper_step_rate_hz() -> u32 {
    robot::world_config::PAPER_STEP_RATE_HZ
}

/// A phase's simulated duration, s.
fn phase_secs() -> f64 {
    robot::action::PHASE_SECS
}

/// A file-name-safe form of a terrain spec or a path.
pub fn slug(spec: &str) -> String {
    spec.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' || c == '-' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// One evaluation: a policy on a scene over a list of episode seeds.
pub struct EvalRequest {
    /// `scripted`, or a checkpoint, run directory or exported policy
    pub policy: String,
    /// the terrain, task and physics (a trained policy brings its own
    /// observation layout, action prior and physics)
    pub experiment: Experiment,
    /// the experiment file, when the user gave one (a policy that observes
    /// otherwise than it sets up is then an error)
    pub config_path: Option<PathBuf>,
    /// `KEY=VALUE` settings already applied to `experiment.task`, recorded
    /// in the report
    pub task_overrides: Vec<String>,
    /// the robot
    pub robot: Arc<RobotModel>,
    /// one episode per seed, in this order
    pub seeds: Vec<u64>,
    /// phases each episode may run
    pub phases: u32,
    /// sample a trained policy's actions (seeded by the episode's seed)
    pub stochastic: bool,
    /// worker threads [default: all cores]
    pub threads: Option<usize>,
    /// run the physics at this rate, Hz, instead of the policy's (a policy
    /// trained at 120 Hz judged at the paper's 240)
    pub step_rate_hz: Option<u32>,
}

/// The setting every episode of an evaluation runs in: its terrain, and
/// its task and physics fitted to the policy.
pub struct EvalScene<'a> {
    registry: &'a Registry,
    spec: TerrainSpec,
    model: Arc<RobotModel>,
    task: TaskConfig,
    physics: WorldConfig,
}

impl<'a> EvalScene<'a> {
    /// The scene of `request`: its terrain, its task and physics fitted to
    /// its policy (which is loaded and checked here, so that a bad policy
    /// fails before anything is written).
    pub fn of(registry: &'a Registry, request: &EvalRequest) -> Result<Self> {
        let experiment = &request.experiment;
        let (mut task, mut physics) = (experiment.task.clone(), experiment.physics.clone());
        let first_seed = request.seeds.first().copied().unwrap_or(DEFAULT_FIRST_SEED);
        let policy = Policy::from_arg(
            registry,
            &request.policy,
            request.stochastic.then_some(first_seed),
        )?;
        policy.check_scene_residual(
            experiment.residual.as_ref(),
            &request
                .config_path
                .as_deref()
                .map_or("the scene".to_string(), |p| p.display().to_string()),
        )?;
        policy.fit_scene(&mut task, &mut physics, request.config_path.as_deref())?;
        if let Some(rate_hz) = request.step_rate_hz {
            physics.step_rate_hz = rate_hz;
            physics
                .validate()
                .map_err(|e| anyhow!("--step-rate-hz {rate_hz}: {e}"))?;
            policy.check_step_rate(&physics, &format!("--step-rate-hz {rate_hz}"))?;
        }
        task.max_phases = request.phases as usize;
        Ok(Self {
            registry,
            spec: experiment.terrain.clone(),
            model: request.robot.clone(),
            task,
            physics,
        })
    }

    /// The physics every episode runs in (the policy's, or the rate
    /// [`EvalRequest::step_rate_hz`] sets).
    pub fn physics(&self) -> &WorldConfig {
        &self.physics
    }

    /// Runs one episode of `policy` with `seed`: the world, start and
    /// actions of `quadwalk rollout --seed SEED`; `observer`, when given, is
    /// told every phase as well (a video recorder, a logger).
    pub fn run_episode(
        &self,
        policy: &mut Policy,
        seed: u64,
        mut observer: Option<&mut dyn PhaseObserver>,
    ) -> Result<EpisodeRecord> {
        let world = make_world(
            self.registry,
            &self.spec,
            self.model.clone(),
            seed,
            [0.0, 0.0],
            &self.physics,
        )?;
        let mut task = Task::new(world, self.task.clone(), seed);
        let mut obs = vec![0.0f32; task.observation_size()];
        task.reset(&mut obs);
        let start = task.start_xy_m();
        let mut recorder = EpisodeRecorder::default();
        let mut reward_total = 0.0;
        if let Some(o) = observer.as_deref_mut() {
            o.episode_started(&task);
        }
        while !task.done() {
            let outcome = match observer.as_deref_mut() {
                Some(o) => policy.run_phase(&mut task, &mut obs, &mut Both(&mut recorder, o))?,
                None => policy.run_phase(&mut task, &mut obs, &mut recorder)?,
            };
            reward_total += outcome.reward;
        }
        let end = task.world().base_pose().translation.vector;
        Ok(recorder.finish(
            seed,
            start,
            [end.x, end.y],
            task.goals_reached(),
            reward_total,
            phase_secs(),
        ))
    }

    /// Runs every episode of `request` in this scene in parallel;
    /// `on_episode` is told each one as it ends (episodes done so far, all
    /// episodes, the record).
    pub fn run_all(
        &self,
        request: &EvalRequest,
        on_episode: &(dyn Fn(usize, usize, &EpisodeRecord) + Sync),
    ) -> Result<EvalReport> {
        let registry = self.registry;
        let first_seed = request.seeds.first().copied().unwrap_or(DEFAULT_FIRST_SEED);
        let sample = |seed: u64| request.stochastic.then_some(seed);
        let threads = request
            .threads
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .context("cannot start the worker threads")?;
        let done = std::sync::atomic::AtomicUsize::new(0);
        let total = request.seeds.len();
        let results: Vec<Result<EpisodeRecord>> = pool.install(|| {
            request
                .seeds
                .par_iter()
                .map_init(
                    // one mean-action policy per worker; a sampling policy is
                    // loaded per episode, its generator seeded by the episode
                    || {
                        (!request.stochastic)
                            .then(|| Policy::from_arg(registry, &request.policy, None))
                    },
                    |shared, &seed| {
                        let mut own;
                        let policy = match shared {
                            Some(loaded) => loaded.as_mut().map_err(|e| anyhow!("{e:#}"))?,
                            None => {
                                own = Policy::from_arg(registry, &request.policy, sample(seed))?;
                                &mut own
                            }
                        };
                        let record = self
                            .run_episode(policy, seed, None)
                            .with_context(|| format!("episode with seed {seed}"))?;
                        let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                        on_episode(n, total, &record);
                        Ok(record)
                    },
                )
                .collect()
        });
        let episodes = results.into_iter().collect::<Result<Vec<_>>>()?;
        let summary = Summary::of(&episodes, phase_secs());
        Ok(EvalReport {
            format: REPORT_FORMAT.to_string(),
            policy: request.policy.clone(),
            terrain: self.spec.to_string(),
            first_seed,
            max_phases: request.phases as usize,
            stochastic: request.stochastic,
            task_overrides: request.task_overrides.clone(),
            step_rate_hz: self.physics.step_rate_hz,
            summary,
            seed_sets: Vec::new(),
            episodes,
        })
    }
}

/// Runs every episode of `request` in parallel, silently: the same
/// episodes as `quadwalk rollout` with each seed.
pub fn evaluate(registry: &Registry, request: &EvalRequest) -> Result<EvalReport> {
    EvalScene::of(registry, request)?.run_all(request, &|_, _, _| {})
}

/// The Table I columns of one evaluation: each terrain type, preceded by
/// the pooled column when there is more than one.
pub fn table_columns(summary: &Summary) -> Vec<&summary::TerrainSummary> {
    let types: Vec<_> = summary.each_terrain_type().collect();
    if types.len() > 1 {
        summary.terrain_types.iter().collect()
    } else {
        types
    }
}

impl EvalReport {
    /// The policy's short name for titles (a path's last component).
    pub fn policy_name(&self) -> String {
        Path::new(&self.policy)
            .file_name()
            .map_or(self.policy.clone(), |n| n.to_string_lossy().to_string())
    }

    /// Writes [`REPORT_FILE`] and `table1.md` (Table I, one column per
    /// terrain type) into `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = dir.join(REPORT_FILE);
        std::fs::write(&path, serde_json::to_string_pretty(self)?)
            .with_context(|| format!("cannot write {}", path.display()))?;
        let columns: Vec<(String, &summary::TerrainSummary)> = table_columns(&self.summary)
            .into_iter()
            .map(|t| (t.terrain.clone(), t))
            .collect();
        let seeds = match self.seed_sets.as_slice() {
            [] => format!("seeds {}..", self.first_seed),
            sets => format!(
                "seed sets {}",
                sets.iter()
                    .map(|set| format!("{}..", set.first_seed))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let table = format!(
            "# Table I: {} on {} ({} episodes, {seeds})\n\nMean and standard deviation of the base height h_b and the mean (and standard deviation) of each foot's target landing height relative to its squat height, cm, per terrain type under the robot (`all`: every phase pooled).\n\n{}",
            self.policy,
            self.terrain,
            self.summary.episodes,
            table1::markdown(&columns)
        );
        let path = dir.join("table1.md");
        std::fs::write(&path, table).with_context(|| format!("cannot write {}", path.display()))?;
        Ok(())
    }

    /// Reads a report written by `eval`.
    pub fn read(dir: &Path) -> Result<Self> {
        let path = dir.join(REPORT_FILE);
        let text = std::fs::read_to_string(&path).with_context(|| {
            format!(
                "{}: no evaluation here (run `quadwalk eval --out {}` first)",
                path.display(),
                dir.display()
            )
        })?;
        let report: Self = serde_json::from_str(&text)
            .with_context(|| format!("{}: not an evaluation report", path.display()))?;
        if report.format != REPORT_FORMAT {
            bail!(
                "{}: format {:?}, this quadwalk reads {REPORT_FORMAT:?}",
                path.display(),
                report.format
            );
        }
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    /// What `write` writes, `read` gives back bit for bit (serde_json's
    /// `float_roundtrip`): a results page regenerated from cached
    /// evaluations is the page the fresh ones wrote.
    #[test]
    fn numbers_read_back_bit_for_bit() {
        // two of them read back one ulp off without `float_roundtrip`
        for x in [
            0.233_333_333_333_333_34_f64,
            0.496_760_259_179_265_64,
            1.0 / 3.0,
            0.1 + 0.2,
            2.0_f64.sqrt(),
            1e-300,
            12_345.678_901_234_567,
        ] {
            let text = serde_json::to_string_pretty(&vec![x]).unwrap();
            let back: Vec<f64> = serde_json::from_str(&text).unwrap();
            assert_eq!(back[0].to_bits(), x.to_bits(), "{text}");
        }
    }
}
