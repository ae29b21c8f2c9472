//! `quadwalk train`: PPO (the paper's) or SAC on N parallel worlds, a progress line per
//! iteration, `metrics.jsonl`, atomic checkpoints (every N iterations, at
//! the end and on Ctrl-C), `--resume`, curriculum stages, and the rollouts
//! of chosen environments streamed to Rerun with the training curves.
//!
//! A run directory holds:
//!
//! | path | content |
//! | --- | --- |
//! | `config.toml` | the resolved experiment (every setting spelt out) |
//! | `metrics.jsonl` | one JSON object per iteration (the statistics of `learn::IterationStats` or `learn::sac::SacStats`) |
//! | `checkpoints/iter-NNNNNN/` | `weights.safetensors`, `state.toml`, `config.toml` (SAC: and `replay.safetensors`) |
//! | `latest` | link to the newest checkpoint |
//! | `fork.toml` | a run started with `--fork`: the checkpoint it went on from, and its iteration |

use std::fs;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::Args;
use learn::checkpoint::{
    point_latest, remove_partial_saves, resolve_checkpoint, write_dir_atomically,
    write_file_atomically,
};
use learn::sac::SacAgent;
use learn::{Algo, Learner, LearnerStats, Trainer};
use serde_json::json;
use terrain_plugins::Registry;
use viz::RerunSink;

use crate::commands::SceneArgs;
use crate::config::Experiment;
use crate::task_env::TaskEnv;
use crate::viz_args::{RerunArgs, print_warnings};

/// The resolved experiment's file name, in run and checkpoint directories.
pub const CONFIG_FILE: &str = "config.toml";
/// One JSON object per iteration.
pub const METRICS_FILE: &str = "metrics.jsonl";

/// Arguments of `quadwalk train`.
#[derive(Debug, Args)]
pub struct TrainArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Learner: ppo (the paper's), sac, or crossq (SAC with CrossQ's critics) [default: ppo, or the config's algo.name]
    #[arg(long, value_parser = parse_algo, conflicts_with = "resume")]
    algo: Option<Algo>,
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
fn parse_algo(text: &str) -> Result<Algo, String> {
    Algo::from_name(text)
        .ok_or_else(|| format!("{text:?} is not a learner: use ppo, sac or crossq"))
}

/// Everything a run needs, resolved from flags, config file or checkpoint.
struct Plan {
    experiment: Experiment,
    run_dir: PathBuf,
    trainer: Learner,
    threads: usize,
    /// `--fork`: the checkpoint the run starts from
    fork: Option<PathBuf>,
}

/// `runs/<terrain>-seed<seed>-<UTC date>-<time>`: a new directory per run.
fn default_run_dir(experiment: &Experiment) -> PathBuf {
    let terrain = experiment.terrain.to_string();
    let name: String = terrain
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '.' {
                c
            } else {
                '-'
            }
        })
        .collect();
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let base = format!("{name}-seed{}-{}", experiment.train.seed, utc_stamp(secs));
    let mut dir = PathBuf::from("runs").join(&base);
    let mut k = 2;
    while dir.exists() {
        dir = PathBuf::from("runs").join(format!("{base}-{k}"));
        k += 1;
    }
    dir
}

/// `YYYYMMDD-HHMMSS` (UTC) of a Unix time (Hinnant's civil-from-days).
fn utc_stamp(unix_secs: u64) -> String {
    let days = (unix_secs / 86_400) as i64;
    let rem = unix_secs % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}{month:02}{day:02}-{:02}{:02}{:02}",
        rem / 3600,
        rem % 3600 / 60,
        rem % 60
    )
}

fn plan(registry: &Registry, args: &TrainArgs) -> Result<Plan> {
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
        let checkpoint =
            resolve_checkpoint(resume).with_context(|| format!("--resume {}", resume.display()))?;
        let checkpoint = fs::canonicalize(&checkpoint).unwrap_or(checkpoint);
        let mut experiment = Experiment::from_file(&checkpoint.join(CONFIG_FILE), registry)?;
        let trainer =
            Learner::load(&checkpoint).with_context(|| format!("--resume {}", resume.display()))?;
        let run_dir = run_dir_of(&checkpoint).with_context(|| {
                format!(
                    "--resume {}: the checkpoint is not inside a run directory (RUN/checkpoints/iter-N); \
                     copy it there or train afresh",
                    resume.display()
                )
            })?;
        if let Some(n) = args.iterations {
            if !experiment.curriculum.is_empty() {
                bail!(
                    "--iterations cannot change a curriculum's length when resuming; to go on with more stages, --fork this run's checkpoint with a config that has them"
                );
            }
            experiment.train.iterations = n;
        }
        apply_common(&mut experiment, args)?;
        return Ok(Plan {
            experiment,
            run_dir,
            trainer,
            threads,
            fork: None,
        });
    }
    let mut experiment = args.scene.experiment(registry)?;
    // --terrain (or none) with a built-in recipe for it: the recipe, for
    // PPO, its learner
    let recipe = match (args.scene.config_path(), args.algo) {
        (None, None | Some(Algo::Ppo)) => crate::recipes::recipe_for(&experiment),
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
    if run_dir.join(learn::checkpoint::LATEST_LINK).exists() || run_dir.join(METRICS_FILE).exists()
    {
        bail!(
            "run directory {} already holds a run: continue it with --resume {0}, or choose another --run-dir",
            run_dir.display()
        );
    }
    let model = args.scene.robot()?;
    if model.joints.len() != 12 {
        bail!(
            "the robot has {} joints; training needs a 12-DoF quadruped",
            model.joints.len()
        );
    }
    let (obs, actions, seed) = (
        experiment.task.observation_size(),
        robot::action::ACTION_SIZE,
        experiment.train.seed,
    );
    if let Some(fork) = &args.fork {
        let (trainer, checkpoint) = fork_from(fork, &experiment, registry)?;
        return Ok(Plan {
            experiment,
            run_dir,
            trainer,
            threads,
            fork: Some(checkpoint),
        });
    }
    let trainer = match experiment.algo {
        Algo::Ppo => Learner::Ppo(Box::new(Trainer::new(
            experiment.ppo.clone(),
            obs,
            actions,
            seed,
        )?)),
        Algo::Sac | Algo::CrossQ => Learner::Sac(Box::new(SacAgent::new(
            experiment.sac.clone(),
            obs,
            actions,
            seed,
        )?)),
    };
    Ok(Plan {
        experiment,
        run_dir,
        trainer,
        threads,
        fork: None,
    })
}

/// `--fork CHECKPOINT`: the learner of the checkpoint (a run directory means
/// its latest) and the checkpoint's path, once `experiment` is shown to
/// train the checkpoint's iterations as its run did.
fn fork_from(
    fork: &Path,
    experiment: &Experiment,
    registry: &Registry,
) -> Result<(Learner, PathBuf)> {
    let context = || format!("--fork {}", fork.display());
    let checkpoint = resolve_checkpoint(fork).with_context(context)?;
    let checkpoint = fs::canonicalize(&checkpoint).unwrap_or(checkpoint);
    let trainer = Learner::load(&checkpoint).with_context(context)?;
    let forked =
        Experiment::from_file(&checkpoint.join(CONFIG_FILE), registry).with_context(context)?;
    let done = trainer.iteration();
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
    Ok((trainer, checkpoint))
}

/// A forked run's start: the forked run's metrics lines up to the
/// checkpoint (when it lies in a run directory), `fork.toml`, and the
/// checkpoint itself, written as this run's own (so that `--resume` works
/// from the start).
fn start_fork(
    run_dir: &Path,
    checkpoint: &Path,
    trainer: &Learner,
    config_text: &str,
    keep: usize,
) -> Result<()> {
    let iteration = trainer.iteration();
    let source_metrics = run_dir_of(checkpoint).map(|run| run.join(METRICS_FILE));
    if let Some(source) = source_metrics.filter(|p| p.exists()) {
        let text = fs::read_to_string(&source)
            .with_context(|| format!("cannot read {}", source.display()))?;
        write_file_atomically(
            &run_dir.join(METRICS_FILE),
            metrics_up_to(&text, iteration).as_bytes(),
        )?;
    }
    let fork = format!(
        "# this run went on from another run's checkpoint; its first {iteration} iterations are that run's\ncheckpoint = {:?}\niteration = {iteration}\n",
        checkpoint.display().to_string()
    );
    write_file_atomically(&run_dir.join("fork.toml"), fork.as_bytes())?;
    save_checkpoint(
        run_dir,
        iteration,
        trainer.checkpoint_files()?,
        config_text,
        keep,
    )
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

/// `quadwalk train`.
pub fn train(registry: &Arc<Registry>, args: &TrainArgs) -> Result<()> {
    let Plan {
        experiment,
        run_dir,
        mut trainer,
        threads,
        fork,
    } = plan(registry, args)?;
    let total = experiment.total_iterations();
    let start_iteration = trainer.iteration();
    if start_iteration >= total {
        bail!(
            "the run in {} has done {start_iteration} of {total} iterations already; pass a larger --iterations to go on",
            run_dir.display()
        );
    }
    fs::create_dir_all(run_dir.join("checkpoints"))
        .with_context(|| format!("cannot create the run directory {}", run_dir.display()))?;
    remove_partial_saves(&run_dir);
    remove_partial_saves(&run_dir.join("checkpoints"));
    let config_text = experiment.to_toml();
    write_file_atomically(&run_dir.join(CONFIG_FILE), config_text.as_bytes())?;
    if let Some(checkpoint) = &fork {
        start_fork(
            &run_dir,
            checkpoint,
            &trainer,
            &config_text,
            experiment.train.keep_checkpoints,
        )?;
        eprintln!(
            "forked from {} at iteration {start_iteration} (this config trains those iterations as that run did)",
            checkpoint.display()
        );
    }
    let metrics_path = run_dir.join(METRICS_FILE);
    keep_metrics_up_to(&metrics_path, start_iteration)?;

    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupted.clone();
        ctrlc::set_handler(move || {
            if flag.swap(true, Ordering::SeqCst) {
                eprintln!("\nsecond Ctrl-C: stopping now; the last checkpoint stands");
                std::process::exit(130);
            }
            eprintln!("\nCtrl-C: writing a checkpoint and stopping (Ctrl-C again to stop at once)");
        })
        .context("cannot install the Ctrl-C handler")?;
    }

    let model = args.scene.robot()?;
    // the worlds of 0-based iteration `iteration`: its stage's terrain and task
    let build_env = |iteration| {
        TaskEnv::new(
            registry,
            experiment.terrain_at(iteration).1,
            experiment.task_at(iteration),
            &model,
            &experiment,
            threads,
            interrupted.clone(),
        )
    };
    let mut stage = experiment.terrain_at(start_iteration).0;
    let mut env = build_env(start_iteration)?;
    let sink = args.rerun.sink(RerunSink::Spawn);
    for (k, &e) in experiment.train.rerun_envs.iter().enumerate() {
        let logger = args.rerun.open_sink(
            sink_for_env(&sink, e, k == 0),
            &model,
            Path::new("quadwalk-train.rrd"),
            &format!("train env {e} ({})", run_dir.display()),
        )?;
        if logger.is_active() {
            env.attach_logger(e, logger);
        }
    }

    eprintln!(
        "training ({}) on {} with {} environments x {} phases per iteration, {threads} threads; run directory {}",
        trainer.algo().name(),
        experiment.terrain_at(start_iteration).1,
        experiment.train.envs,
        trainer.steps_per_env(),
        run_dir.display()
    );
    let started = Instant::now();
    let mut phases_done = 0usize;
    for iteration in start_iteration..total {
        let (next_stage, terrain) = experiment.terrain_at(iteration);
        let stage_rate = experiment.learning_rate_at(iteration);
        if next_stage != stage {
            let loggers = env.detach_loggers();
            env = build_env(iteration)?;
            for l in loggers {
                env.attach_logger(l.env, l.logger);
            }
            stage = next_stage;
            let rate = stage_rate.map_or(String::new(), |r| format!(", learning rate {r:e}"));
            let overrides = &experiment.curriculum[stage].task_overrides;
            let task = if overrides.is_empty() {
                String::new()
            } else {
                let keys: Vec<String> = overrides
                    .iter()
                    .map(|(k, v)| format!("{k} = {v}"))
                    .collect();
                format!(", task: {}", keys.join(", "))
            };
            eprintln!("curriculum stage {}: {terrain}{rate}{task}", stage + 1);
        }
        // a stage's own learning rate (set every iteration, so a resume
        // inside a stage runs as the uninterrupted run did)
        if let Some(rate) = stage_rate {
            trainer.set_learning_rate(rate)?;
        }
        for l in env.loggers_mut() {
            l.logger.set_iteration(Some(iteration as i64));
        }
        // the state before this iteration, written if Ctrl-C cuts it short
        let before = trainer.checkpoint_files()?;
        let stats = trainer.iterate(&mut env)?;
        if interrupted.load(Ordering::SeqCst) {
            save_checkpoint(
                &run_dir,
                iteration,
                before,
                &config_text,
                experiment.train.keep_checkpoints,
            )?;
            finish_loggers(&mut env);
            eprintln!(
                "stopped by Ctrl-C during iteration {}; checkpoint of iteration {iteration} in {}",
                iteration + 1,
                run_dir.join(learn::checkpoint::LATEST_LINK).display()
            );
            std::process::exit(130);
        }
        let logging_secs = env.take_logging_secs();
        phases_done += stats.steps();
        let record = metrics_record(&stats, terrain, logging_secs);
        append_line(&metrics_path, &record.to_string())?;
        if args.json {
            out!("{record}");
        }
        let curves = training_curves(&stats);
        for l in env.loggers_mut() {
            l.logger.log_training(stats.iteration() as i64, &curves);
            print_warnings(&mut l.logger);
        }
        progress(&stats, total, started.elapsed().as_secs_f64(), phases_done);
        let done = stats.iteration();
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
    finish_loggers(&mut env);
    eprintln!(
        "done: {total} iterations; checkpoint {}",
        run_dir.join(learn::checkpoint::LATEST_LINK).display()
    );
    Ok(())
}

fn finish_loggers(env: &mut TaskEnv) {
    for l in env.loggers_mut() {
        l.logger.finish();
        print_warnings(&mut l.logger);
    }
}

/// The curves streamed to Rerun per iteration.
fn training_curves(stats: &LearnerStats) -> Vec<(String, f64)> {
    let (mean_return, mean_length) = stats.episode_means();
    let mut curves = vec![
        ("mean_return", mean_return),
        ("mean_distance_m", stats.episode_metric("distance_m")),
        ("mean_episode_length", mean_length),
    ];
    match stats {
        LearnerStats::Ppo(s) => curves.extend([
            ("policy_loss", Some(s.policy_loss)),
            ("value_loss", Some(s.value_loss)),
            ("entropy", Some(s.entropy)),
            ("approx_kl", Some(s.approx_kl)),
            ("clip_fraction", Some(s.clip_fraction)),
            ("explained_variance", Some(s.explained_variance)),
            ("learning_rate", Some(s.learning_rate)),
        ]),
        LearnerStats::Sac(s) => curves.extend([
            ("critic_loss", s.critic_loss),
            ("actor_loss", s.actor_loss),
            ("alpha", Some(s.alpha)),
            ("entropy", s.entropy),
        ]),
    }
    curves.push(("phases_per_s", Some(stats.steps_per_sec())));
    curves
        .into_iter()
        .filter_map(|(n, v)| v.map(|v| (n.to_string(), v)))
        .collect()
}

/// The JSON line of one iteration.
fn metrics_record(
    stats: &LearnerStats,
    terrain: &terrain_plugins::TerrainSpec,
    logging_secs: f64,
) -> serde_json::Value {
    let (mean_step_reward, reward_terms) = stats.step_rewards();
    let terms: serde_json::Map<String, serde_json::Value> = reward_terms
        .iter()
        .map(|(n, v)| (n.clone(), json!(v)))
        .collect();
    let (episodes, terminated) = stats.episodes();
    let (mean_return, mean_length) = stats.episode_means();
    let mut record = json!({
        "iteration": stats.iteration(),
        "terrain": terrain.to_string(),
        "phases": stats.steps(),
        "episodes": episodes,
        "terminated": terminated,
        "mean_return": mean_return,
        "mean_episode_length": mean_length,
        "mean_distance_m": stats.episode_metric("distance_m"),
        "mean_goals_reached": stats.episode_metric("goals_reached"),
        "mean_phase_reward": mean_step_reward,
        "reward_terms": terms,
        "phases_per_s": stats.steps_per_sec(),
    });
    let fields = match stats {
        LearnerStats::Ppo(s) => json!({
            "policy_loss": s.policy_loss,
            "value_loss": s.value_loss,
            "entropy": s.entropy,
            "approx_kl": s.approx_kl,
            "clip_fraction": s.clip_fraction,
            "explained_variance": s.explained_variance,
            "grad_norm_actor": s.grad_norm.0,
            "grad_norm_critic": s.grad_norm.1,
            "action_std": s.action_std,
            "epochs": s.epochs,
            "learning_rate": s.learning_rate,
            "secs": {
                "env": s.env_secs - logging_secs,
                "logging": logging_secs,
                "inference": s.inference_secs,
                "update": s.update_secs,
            },
        }),
        LearnerStats::Sac(s) => json!({
            "total_phases": s.total_steps,
            "updates": s.updates,
            "critic_loss": s.critic_loss,
            "actor_loss": s.actor_loss,
            "alpha": s.alpha,
            "entropy": s.entropy,
            "secs": {
                "env": s.env_secs - logging_secs,
                "logging": logging_secs,
                "update": s.update_secs,
            },
        }),
    };
    if let (Some(record), Some(fields)) = (record.as_object_mut(), fields.as_object()) {
        record.extend(fields.clone());
    }
    record
}

/// One progress line per iteration on stderr.
fn progress(stats: &LearnerStats, total: u64, elapsed_secs: f64, phases_done: usize) {
    let width = 20;
    let iteration = stats.iteration();
    let filled = (iteration as usize * width / total.max(1) as usize).min(width);
    let bar: String = "#".repeat(filled) + &".".repeat(width - filled);
    let fmt = |v: Option<f64>, unit: &str| v.map_or("-".to_string(), |v| format!("{v:.2}{unit}"));
    let rate = phases_done as f64 / elapsed_secs.max(1e-9);
    let (mean_return, mean_length) = stats.episode_means();
    let learner = match stats {
        LearnerStats::Ppo(s) => format!("kl {:.4} | ev {:.2}", s.approx_kl, s.explained_variance),
        LearnerStats::Sac(s) => format!(
            "alpha {:.3} | q loss {} | updates {}",
            s.alpha,
            fmt(s.critic_loss, ""),
            s.updates
        ),
    };
    eprintln!(
        "[{bar}] iter {iteration}/{total} | {rate:.1} phases/s | return {} | distance {} | length {} | {learner}",
        fmt(mean_return, ""),
        fmt(stats.episode_metric("distance_m"), " m"),
        fmt(mean_length, ""),
    );
}

/// Writes the checkpoint of `iteration`, points `latest` at it, prunes old ones.
fn save_checkpoint(
    run_dir: &Path,
    iteration: u64,
    mut files: Vec<(String, Vec<u8>)>,
    config_text: &str,
    keep: usize,
) -> Result<()> {
    let name = format!("iter-{iteration:06}");
    files.push((CONFIG_FILE.to_string(), config_text.as_bytes().to_vec()));
    let dir = run_dir.join("checkpoints").join(&name);
    write_dir_atomically(&dir, &files)?;
    point_latest(run_dir, &Path::new("checkpoints").join(&name))?;
    // keep the newest `keep`
    let mut names: Vec<String> = fs::read_dir(run_dir.join("checkpoints"))
        .map(|entries| {
            entries
                .flatten()
                .map(|e| e.file_name().to_string_lossy().to_string())
                .filter(|n| n.starts_with("iter-"))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    if names.len() > keep {
        for old in &names[..names.len() - keep] {
            let _ = fs::remove_dir_all(run_dir.join("checkpoints").join(old));
        }
    }
    Ok(())
}

fn append_line(path: &Path, line: &str) -> Result<()> {
    let mut f = fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .with_context(|| format!("cannot append to {}", path.display()))?;
    writeln!(f, "{line}").with_context(|| format!("cannot append to {}", path.display()))?;
    Ok(())
}

/// Where a checkpoint's run keeps its metrics: `RUN/checkpoints/iter-N` ->
/// `RUN`, `POLICY/checkpoint` -> `POLICY` (`None` for a checkpoint outside
/// either).
pub(crate) fn run_dir_of(checkpoint: &Path) -> Option<PathBuf> {
    let parent = checkpoint.parent()?;
    if parent.file_name().is_some_and(|n| n == "checkpoints") {
        return parent.parent().map(Path::to_path_buf);
    }
    // a policy exported with its checkpoint (`export --with-checkpoint`)
    // keeps the run's metrics beside it
    learn::export::is_exported_policy(parent).then(|| parent.to_path_buf())
}

/// On resume: drops the lines of iterations after the checkpoint.
fn keep_metrics_up_to(path: &Path, iteration: u64) -> Result<()> {
    let Ok(text) = fs::read_to_string(path) else {
        return Ok(());
    };
    Ok(write_file_atomically(
        path,
        metrics_up_to(&text, iteration).as_bytes(),
    )?)
}

/// The lines of `metrics.jsonl` text for iterations up to `iteration`.
fn metrics_up_to(text: &str, iteration: u64) -> String {
    text.lines()
        .filter(|line| {
            serde_json::from_str::<serde_json::Value>(line)
                .ok()
                .and_then(|v| v["iteration"].as_u64())
                .is_some_and(|i| i <= iteration)
        })
        .map(|line| format!("{line}\n"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utc_stamps() {
        assert_eq!(utc_stamp(0), "19700101-000000");
        // 2026-11-22 08:47:05 UTC
        assert_eq!(utc_stamp(1_795_337_225), "20261122-084705");
        // a leap day
        assert_eq!(utc_stamp(951_782_400), "20000229-000000");
    }
}
