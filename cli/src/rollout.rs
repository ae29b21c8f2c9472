//! `quadwalk rollout` and `quadwalk play`: run a policy on a terrain for a
//! number of phases (or until the episode terminates), stream it to Rerun,
//! and report distance, base height, termination and reward per term.
//! `play` is `rollout` with the viewer on by default.

use std::path::Path;

use anyhow::Result;
use clap::Args;
use robot::task::{RewardTerms, Task};
use serde_json::json;
use viz::RerunSink;

use crate::commands::{SceneArgs, make_world};
use crate::video::{VideoArgs, VideoRecorder};
use crate::viz_args::{RerunArgs, print_warnings};
use experiment::Policy;
use robot::snapshot::Both;
use terrain_plugins::Registry;

/// The flags `rollout` and `play` share with the same defaults.
#[derive(Debug, Args)]
struct RunFlags {
    /// Seed: start position, the varying terrain's draw, and the samples of --stochastic
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Sample a trained policy's actions from its Gaussian instead of taking the mean
    #[arg(long)]
    stochastic: bool,
    /// Print one JSON object instead of text
    #[arg(long)]
    json: bool,
}

/// Arguments of `quadwalk rollout`.
#[derive(Debug, Args)]
pub struct RolloutArgs {
    /// Policy: `scripted` (the documented crawl) or a trained checkpoint
    /// (a run directory, one of its checkpoints, or an exported policy;
    /// deterministic mean action)
    #[arg(long, default_value = "scripted")]
    policy: String,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    task: crate::commands::TaskOverrideArgs,
    /// Phases to run (0.75 s each), unless the episode terminates first
    #[arg(long, default_value_t = 40, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    phases: u32,
    #[command(flatten)]
    flags: RunFlags,
    #[command(flatten)]
    rerun: RerunArgs,
    #[command(flatten)]
    video: VideoArgs,
}

/// Arguments of `quadwalk play`.
#[derive(Debug, Args)]
pub struct PlayArgs {
    /// Policy: `scripted` (the documented crawl) or a trained checkpoint
    /// (a run directory, one of its checkpoints, or an exported policy;
    /// deterministic mean action)
    #[arg(long, default_value = "scripted", conflicts_with = "checkpoint")]
    policy: String,
    /// A trained checkpoint to play (the same as --policy DIR)
    #[arg(long, value_name = "DIR")]
    checkpoint: Option<std::path::PathBuf>,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    task: crate::commands::TaskOverrideArgs,
    /// Phases to run (0.75 s each), unless the episode terminates first
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    phases: u32,
    #[command(flatten)]
    flags: RunFlags,
    /// Rerun stream (default for play: spawn)
    #[command(flatten)]
    rerun: RerunArgs,
    #[command(flatten)]
    video: VideoArgs,
}

/// What `rollout` and `play` share.
struct Run<'a> {
    command: &'static str,
    policy: &'a str,
    scene: &'a SceneArgs,
    task: &'a crate::commands::TaskOverrideArgs,
    phases: u32,
    flags: &'a RunFlags,
    rerun: &'a RerunArgs,
    video: &'a VideoArgs,
    default_sink: RerunSink,
}

/// `quadwalk rollout`.
pub fn rollout(registry: &Registry, args: &RolloutArgs) -> Result<()> {
    run(
        registry,
        &Run {
            command: "rollout",
            policy: &args.policy,
            scene: &args.scene,
            task: &args.task,
            phases: args.phases,
            flags: &args.flags,
            rerun: &args.rerun,
            video: &args.video,
            default_sink: RerunSink::Off,
        },
    )
}

/// `quadwalk play`.
pub fn play(registry: &Registry, args: &PlayArgs) -> Result<()> {
    let checkpoint = args.checkpoint.as_ref().map(|p| p.display().to_string());
    run(
        registry,
        &Run {
            command: "play",
            policy: checkpoint.as_deref().unwrap_or(&args.policy),
            scene: &args.scene,
            task: &args.task,
            phases: args.phases,
            flags: &args.flags,
            rerun: &args.rerun,
            video: &args.video,
            default_sink: RerunSink::Spawn,
        },
    )
}

/// Summary statistics of a series.
fn stats(values: &[f64]) -> serde_json::Value {
    let n = values.len().max(1) as f64;
    let mean = values.iter().sum::<f64>() / n;
    let std = (values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt();
    let min = values.iter().copied().fold(f64::INFINITY, f64::min);
    let max = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    json!({ "mean": mean, "std": std, "min": min, "max": max })
}

fn run(registry: &Registry, args: &Run) -> Result<()> {
    args.video.check()?;
    let mut experiment = args.scene.experiment(registry)?;
    args.task.apply(&mut experiment)?;
    let mut policy = Policy::from_arg(
        registry,
        args.policy,
        args.flags.stochastic.then_some(args.flags.seed),
    )?;
    policy.check_scene_residual(
        experiment.residual.as_ref(),
        &args
            .scene
            .config_path()
            .map_or("the scene".to_string(), |p| {
                format!("--config {}", p.display())
            }),
    )?;
    let (spec, mut task_config, mut physics) =
        (experiment.terrain, experiment.task, experiment.physics);
    policy.fit_scene(&mut task_config, &mut physics, None)?;
    task_config.max_phases = args.phases as usize;
    let model = args.scene.robot()?;
    let world = make_world(
        registry,
        &spec,
        model.clone(),
        args.flags.seed,
        [0.0, 0.0],
        &physics,
    )?;
    let mut task = Task::new(world, task_config, args.flags.seed);
    let mut logger = args.rerun.open(
        args.default_sink.clone(),
        task.world().model(),
        Path::new(&format!("quadwalk-{}.rrd", args.command)),
        &format!(
            "{} {} on {spec} (seed {})",
            args.command, args.policy, args.flags.seed
        ),
    )?;
    let mut video = args.video.recorder(
        model,
        &format!("{} (seed {})", args.policy, args.flags.seed),
        task.world().dt_secs(),
    )?;
    let mut obs = vec![0.0f32; task.observation_size()];
    task.reset(&mut obs);
    let start = task.start_xy_m();
    logger.log_terrain(task.world().terrain());
    logger.log_now(&task);
    if let Some(v) = &mut video {
        v.frame(&task);
    }

    let mut terms_sum = [0.0f64; 5];
    let mut reward_sum = 0.0;
    let mut heights = Vec::new();
    let (mut min_h, mut max_h) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut termination = None;
    let mut ik_clamped = 0;
    let mut regions: Vec<String> = Vec::new();
    let mut phases = 0;
    while !task.done() {
        let outcome = match &mut video {
            Some(v) => policy.run_phase(&mut task, &mut obs, &mut Both(&mut logger, v))?,
            None => policy.run_phase(&mut task, &mut obs, &mut logger)?,
        };
        print_warnings(&mut logger);
        phases += 1;
        reward_sum += outcome.reward;
        for (sum, v) in terms_sum.iter_mut().zip(outcome.terms.values()) {
            *sum += v;
        }
        heights.push(outcome.mean_base_height_m);
        min_h = min_h.min(outcome.base_height_range_m.0);
        max_h = max_h.max(outcome.base_height_range_m.1);
        ik_clamped += outcome.ik_clamped;
        let base = task.world().base_pose().translation.vector;
        let terrain = task.world().terrain();
        let label = &terrain.regions()[terrain.region_index_at(base.x, base.y)].label;
        if regions.last() != Some(label) {
            regions.push(label.clone());
        }
        termination = outcome.termination;
    }
    logger.finish();
    print_warnings(&mut logger);
    let video = video.map(VideoRecorder::finish).transpose()?;
    let base = task.world().base_pose().translation.vector;
    let distance_m = base.x - start[0];
    let lateral_drift_m = base.y - start[1];
    let (_, _, yaw) = task.world().base_pose().rotation.euler_angles();
    let reward_terms: serde_json::Map<String, serde_json::Value> = RewardTerms::NAMES
        .iter()
        .zip(terms_sum)
        .map(|(n, v)| (n.to_string(), json!(v)))
        .collect();
    let height = stats(&heights);
    // a fall within 1 m of the field's far end: walked off a field too short
    let at_terrain_end = termination.is_some() && experiment::eval::record::near_terrain_end(&task);
    if args.flags.json {
        let terminated = match &termination {
            None => json!(false),
            Some(t) => json!(t.kind()),
        };
        let out = json!({
            "policy": args.policy,
            "terrain": spec.to_string(),
            "seed": args.flags.seed,
            "start_xy_m": start,
            "phases": phases,
            "sim_seconds": task.world().time_secs(),
            "distance_m": distance_m,
            "lateral_drift_m": lateral_drift_m,
            "final_yaw_deg": yaw.to_degrees(),
            "terminated": terminated,
            "termination_detail": termination.as_ref().map(ToString::to_string),
            "at_terrain_end": at_terrain_end,
            "goals_reached": task.goals_reached(),
            "reward_total": reward_sum,
            "reward_terms": reward_terms,
            "base_height_m": { "mean": height["mean"], "std": height["std"], "min": min_h, "max": max_h },
            "ik_clamped": ik_clamped,
            "regions": regions,
            "rerun_frames": logger.frames_logged(),
            "video": video.as_ref().map(|v| json!({
                "path": v.path.display().to_string(),
                "frames": v.frames,
                "steps_per_frame": v.steps_per_frame,
            })),
        });
        out!("{out}");
    } else {
        out!(
            "policy          {} on {spec} (seed {})",
            args.policy,
            args.flags.seed
        );
        out!("start           x {:.2} m, y {:.2} m", start[0], start[1]);
        out!(
            "phases          {phases} ({:.1} s)",
            task.world().time_secs()
        );
        out!(
            "distance        {distance_m:.2} m forward, {lateral_drift_m:+.2} m sideways, yaw {:+.1} deg",
            yaw.to_degrees()
        );
        out!("goals reached   {}", task.goals_reached());
        let ended = termination
            .as_ref()
            .map_or("no (ran all phases)".to_string(), |t| {
                if at_terrain_end {
                    format!(
                        "yes: {t}, at the end of the terrain (x = {:.1} m): {}",
                        task.world().terrain().extent().max_m[0],
                        experiment::eval::record::terrain_end_advice(args.phases)
                    )
                } else {
                    format!("yes: {t}")
                }
            });
        out!("terminated      {ended}");
        out!(
            "base height     mean {:.3} m, std {:.3} m, min {min_h:.3} m, max {max_h:.3} m",
            height["mean"].as_f64().unwrap_or(0.0),
            height["std"].as_f64().unwrap_or(0.0)
        );
        out!("reward          {reward_sum:.3} total");
        for (name, v) in RewardTerms::NAMES.iter().zip(terms_sum) {
            out!("  {name:<12}  {v:.3}");
        }
        out!("regions         {}", regions.join(" -> "));
        out!("IK clamps       {ik_clamped}");
        if logger.frames_logged() > 0 {
            out!("rerun frames    {}", logger.frames_logged());
        }
        if let Some(v) = &video {
            out!(
                "video           {} ({} frames, one every {} physics steps)",
                v.path.display(),
                v.frames,
                v.steps_per_frame
            );
        }
    }
    Ok(())
}
