//! `quadwalk train`: the flags, the Ctrl-C handler and what the terminal
//! shows (a progress line per iteration, `--json` lines); the run itself is
//! `experiment::train` (the run directory's files are listed in
//! `experiment::train::run_dir`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

use anyhow::{Context, Result, bail};
use clap::Args;
use experiment::Experiment;
use experiment::config::advance::Advance;
use experiment::config::levels::TerrainLevels;
use experiment::train::run_dir::default_run_dir;
use experiment::train::{IterationReport, RunPlan, RunStart, TrainObserver, TrainOutcome};
use learn::registry::Registration;
use learn::{Figure, IterationStats};
use robot::RobotModel;
use terrain_plugins::{Registry, TerrainSpec};
use viz::RerunSink;

use crate::commands::SceneArgs;
use crate::viz_args::RerunArgs;

/// Arguments of `quadwalk train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Learner: ppo (the paper's), sac, or crossq (SAC with CrossQ's critics) [default: ppo, or the config's algo.name]
    #[arg(long, value_parser = parse_algo, conflicts_with = "resume")]
    algo: Option<&'static Registration>,
    /// Parallel environments [default: 16, or the config's train.envs]
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=4096), conflicts_with = "resume")]
    envs: Option<u64>,
    /// Iterations in all (with --resume: the new total) [default: 100, or the config's]
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
    iterations: Option<u64>,
    /// Seed of the run: networks, sampling, start positions, terrain draws [default: 0]
    #[arg(long, conflicts_with = "resume")]
    seed: Option<u64>,
    /// Run directory [default: runs/<terrain>-seed<seed>-<UTC date>-<time>]
    #[arg(long, conflicts_with = "resume")]
    run_dir: Option<PathBuf>,
    /// Continue a run: its directory, or one of its checkpoints
    #[arg(long, value_name = "DIR")]
    resume: Option<PathBuf>,
    /// Start a new run from another run's checkpoint (or run directory): the
    /// config (--config/--terrain) must train the checkpoint's iterations
    /// exactly as that run did (same learner, settings, seed, worlds and,
    /// iteration by iteration, terrain, task and learning rate) and may
    /// differ after them, so the new run is what a run from scratch on the
    /// config gives, without repeating the shared part
    #[arg(long, value_name = "CHECKPOINT", conflicts_with = "resume")]
    fork: Option<PathBuf>,
    /// Threads stepping the worlds [default: all cores]
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1024))]
    threads: Option<u64>,
    /// Iterations between checkpoints [default: 10, or the config's]
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    checkpoint_every: Option<u64>,
    /// Environments whose rollouts are streamed, e.g. 0,3 [default: 0]
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    rerun_envs: Option<Vec<usize>>,
    /// Print each iteration's statistics as one JSON line on stdout
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    rerun: RerunArgs,
}

/// Parses `--algo`.
fn parse_algo(text: &str) -> Result<&'static Registration, String> {
    learn::registry::find(text).map_err(|_| {
        format!(
            "{text:?} is not a learner: use {}",
            learn::registry::names()
        )
    })
}

/// What the terminal shows while a run trains.
struct Terminal {
    /// print each iteration's metrics line on stdout
    json: bool,
    /// what one environment step is (`phases`, or `control steps` for a
    /// residual policy)
    step_unit: &'static str,
}

impl TrainObserver for Terminal {
    fn started(&mut self, start: &RunStart) {
        if let Some((checkpoint, iteration)) = start.forked_from {
            eprintln!(
                "forked from {} at iteration {iteration} (this config trains those iterations as that run did)",
                checkpoint.display()
            );
        }
        self.step_unit = start.step_unit;
        let rate = start.physics.step_rate_hz;
        let physics = if robot::world_config::is_paper_step_rate(&rate) {
            String::new()
        } else {
            format!(", physics at {rate} Hz")
        };
        eprintln!(
            "training ({}) on {}{physics} with {} environments x {} {} per iteration, {} threads; run directory {}",
            start.algo,
            terrain_label(start.terrain, start.levels),
            start.envs,
            start.steps_per_env,
            start.step_unit,
            start.threads,
            start.run_dir.display()
        );
    }

    fn stage_started(
        &mut self,
        stage: usize,
        terrain: &TerrainSpec,
        levels: Option<&TerrainLevels>,
        learning_rate: Option<f64>,
        task_overrides: &toml::Table,
        physics_overrides: &toml::Table,
    ) {
        let rate = learning_rate.map_or(String::new(), |r| format!(", learning rate {r:e}"));
        let keys = |label: &str, table: &toml::Table| {
            if table.is_empty() {
                return String::new();
            }
            let keys: Vec<String> = table.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            format!(", {label}: {}", keys.join(", "))
        };
        eprintln!(
            "curriculum stage {}: {}{rate}{}{}",
            stage + 1,
            terrain_label(terrain, levels),
            keys("task", task_overrides),
            keys("physics", physics_overrides)
        );
    }

    fn stage_ready(&mut self, stage: usize, iterations: u64, rule: &Advance) {
        eprintln!(
            "curriculum stage {} ready after {iterations} iterations ({} reached)",
            stage + 1,
            rule.describe()
        );
    }

    fn iteration_done(&mut self, report: &IterationReport) -> Result<()> {
        if self.json {
            out!("{}", report.record);
        }
        progress(
            report.stats,
            report.total,
            report.elapsed_secs,
            report.phases_done,
            self.step_unit,
            report.record["mean_level"].as_f64(),
        );
        Ok(())
    }

    fn warning(&mut self, message: &str) {
        eprintln!("warning: {message}");
    }
}

/// A stage's terrain as the progress lines name it: the spec, or its
/// levels, easiest first.
fn terrain_label(terrain: &TerrainSpec, levels: Option<&TerrainLevels>) -> String {
    match levels {
        None => terrain.to_string(),
        Some(levels) => {
            let names: Vec<String> = levels.terrains.iter().map(ToString::to_string).collect();
            format!("terrain levels {}", names.join(", "))
        }
    }
}

/// The flag the Ctrl-C handler sets, installed once per process (so that
/// an `App` may train more than once); a second Ctrl-C calls
/// `second_interrupt` where the binary gave one.
fn stop_flag(second_interrupt: Option<fn() -> !>) -> Result<Arc<AtomicBool>> {
    static STOP: OnceLock<Arc<AtomicBool>> = OnceLock::new();
    if let Some(flag) = STOP.get() {
        flag.store(false, Ordering::SeqCst);
        return Ok(flag.clone());
    }
    let flag = Arc::new(AtomicBool::new(false));
    let handler_flag = flag.clone();
    ctrlc::set_handler(move || {
        if handler_flag.swap(true, Ordering::SeqCst) {
            match second_interrupt {
                Some(stop_now) => {
                    eprintln!("\nsecond Ctrl-C: stopping now; the last checkpoint stands");
                    stop_now();
                }
                None => eprintln!("\nsecond Ctrl-C: already stopping"),
            }
            return;
        }
        eprintln!("\nCtrl-C: writing a checkpoint and stopping (Ctrl-C again to stop at once)");
    })
    .context("cannot install the Ctrl-C handler")?;
    Ok(STOP.get_or_init(|| flag).clone())
}

/// The run the flags describe: a resumed one, or a new one (a built-in
/// recipe for `--terrain` alone, a fork with `--fork`).
fn plan(registry: &Registry, args: &TrainArgs, model: &RobotModel) -> Result<RunPlan> {
    let threads = match args.threads {
        Some(t) => t as usize,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    if let Some(resume) = &args.resume {
        if args.scene.is_given() {
            bail!(
                "--resume continues the run with its own config.toml; --terrain and --config cannot be given with it"
            );
        }
        let mut plan = RunPlan::resume(registry, resume, args.iterations, threads)?;
        apply_common(&mut plan.experiment, args)?;
        return Ok(plan);
    }
    let mut experiment = args.scene.experiment(registry)?;
    // --terrain (or none) with a built-in recipe for it: the recipe, for
    // PPO, its learner
    let default_learner = args
        .algo
        .is_none_or(|a| a == learn::registry::default_algorithm());
    let recipe = match args.scene.config_path() {
        None if default_learner => experiment::recipes::recipe_for(&experiment),
        _ => None,
    };
    if let Some(recipe) = recipe {
        experiment = recipe.experiment(registry)?;
        eprintln!("{}", recipe.describe(&experiment));
    }
    if let Some(envs) = args.envs {
        experiment.train.envs = envs as usize;
    }
    if let Some(n) = args.iterations {
        experiment.keep_first_iterations(n)?;
    }
    if let Some(seed) = args.seed {
        experiment.train.seed = seed;
    }
    if let Some(algo) = args.algo {
        experiment.set_algo(algo)?;
    }
    apply_common(&mut experiment, args)?;
    let run_dir = args
        .run_dir
        .clone()
        .unwrap_or_else(|| default_run_dir(&experiment));
    RunPlan::fresh(
        registry,
        experiment,
        run_dir,
        model,
        threads,
        args.fork.as_deref(),
    )
}

/// `quadwalk train`: exit code 130 when Ctrl-C stopped the run.
pub fn train(
    registry: &Arc<Registry>,
    args: &TrainArgs,
    second_interrupt: Option<fn() -> !>,
) -> Result<ExitCode> {
    let model = args.scene.robot()?;
    let plan = plan(registry, args, &model)?;
    let stop = stop_flag(second_interrupt)?;
    let sink = args.rerun.sink(RerunSink::Spawn);
    let mut loggers = Vec::new();
    for (k, &e) in plan.experiment.train.rerun_envs.iter().enumerate() {
        let logger = args.rerun.open_sink(
            sink_for_env(&sink, e, k == 0),
            &model,
            Path::new("quadwalk-train.rrd"),
            &format!("train env {e} ({})", plan.run_dir.display()),
        )?;
        if logger.is_active() {
            loggers.push((e, logger));
        }
    }
    let mut terminal = Terminal {
        json: args.json,
        step_unit: "phases",
    };
    match experiment::train::train(registry, plan, &model, loggers, &mut terminal, stop)? {
        TrainOutcome::Completed {
            iterations,
            checkpoint,
        } => {
            eprintln!(
                "done: {iterations} iterations; checkpoint {}",
                checkpoint.display()
            );
            Ok(ExitCode::SUCCESS)
        }
        TrainOutcome::Stopped {
            iteration,
            checkpoint,
        } => {
            eprintln!(
                "stopped by Ctrl-C during iteration {}; checkpoint of iteration {iteration} in {}",
                iteration + 1,
                checkpoint.display()
            );
            Ok(ExitCode::from(130))
        }
    }
}

/// Flags that may change on a resume as on a fresh run.
fn apply_common(experiment: &mut Experiment, args: &TrainArgs) -> Result<()> {
    if let Some(every) = args.checkpoint_every {
        experiment.train.checkpoint_every = every;
    }
    if let Some(envs) = &args.rerun_envs {
        experiment.train.rerun_envs = envs.clone();
    }
    experiment.train.validate().context("flags")?;
    Ok(())
}

/// Where env `env`'s stream goes: `save:PATH` gives env 0 PATH and env k
/// `PATH` with `-envK` before the extension.
fn sink_for_env(sink: &RerunSink, env: usize, first: bool) -> RerunSink {
    match sink {
        RerunSink::Save(Some(path)) if !first => {
            let stem = path
                .file_stem()
                .map_or("run".into(), |s| s.to_string_lossy().to_string());
            let ext = path
                .extension()
                .map_or("rrd".into(), |s| s.to_string_lossy().to_string());
            RerunSink::Save(Some(path.with_file_name(format!("{stem}-env{env}.{ext}"))))
        }
        other => other.clone(),
    }
}

/// One progress line per iteration on stderr: the episodes and the
/// algorithm's headline figures.
fn progress(
    stats: &IterationStats,
    total: u64,
    elapsed_secs: f64,
    steps_done: usize,
    step_unit: &str,
    mean_level: Option<f64>,
) {
    let width = 20;
    let iteration = stats.iteration;
    let filled = (iteration as usize * width / total.max(1) as usize).min(width);
    let bar: String = "#".repeat(filled) + &".".repeat(width - filled);
    let fmt = |v: Option<f64>, unit: &str| v.map_or("-".to_string(), |v| format!("{v:.2}{unit}"));
    let rate = steps_done as f64 / elapsed_secs.max(1e-9);
    let learner: Vec<String> = stats
        .headline
        .iter()
        .map(|(label, name)| {
            let value = match stats.figure(name) {
                Some(Figure::Count(n)) => n.to_string(),
                Some(Figure::Value(v)) => format!("{v:.4}"),
                Some(Figure::Missing) | None => "-".to_string(),
            };
            format!("{label} {value}")
        })
        .collect();
    let level = mean_level.map_or(String::new(), |l| format!(" | level {l:.2}"));
    eprintln!(
        "[{bar}] iter {iteration}/{total} | {rate:.1} {step_unit}/s | return {} | distance {} | length {}{level} | {}",
        fmt(stats.episodes.mean_return, ""),
        fmt(stats.episode_metric("distance_m"), " m"),
        fmt(stats.episodes.mean_length, ""),
        learner.join(" | ")
    );
}
