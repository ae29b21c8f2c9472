//! `quadwalk eval`: the flags, the output directory, the PNG figures, the
//! video of the first episode, the Rerun curves and the printed summary;
//! the evaluation itself is `experiment::eval` (`eval.json`, `table1.md`).
//! `--compare` lays several evaluations side by side.

mod compare;
pub(crate) mod plots;

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;
use experiment::Policy;
use experiment::eval::seed_sets::SeedSets;
pub use experiment::eval::{
    DEFAULT_FIRST_SEED, EvalReport, EvalRequest, EvalScene, REPORT_FILE, evaluate, record, slug,
    summary, table_columns, table1,
};
use robot::RobotModel;
use terrain_plugins::Registry;

use crate::commands::SceneArgs;
use crate::video::{VideoArgs, VideoSummary};
use crate::viz_args::RerunArgs;
pub use plots::FIGURE_FILES;

/// Arguments of `quadwalk eval`.
#[derive(Debug, Args)]
pub struct EvalArgs {
    /// Policy: `scripted` (the documented crawl) or a trained checkpoint
    /// (a run directory, one of its checkpoints, or an exported policy;
    /// deterministic mean action)
    #[arg(long, default_value = "scripted")]
    policy: String,
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    task: crate::commands::TaskOverrideArgs,
    /// Episodes to run, on consecutive seeds from --seed (per seed set,
    /// when --seed is given more than once)
    #[arg(long, default_value_t = 32, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    episodes: u32,
    /// Phases per episode (0.75 s each; 400 = 5 minutes), unless it falls first
    #[arg(long, default_value_t = 400, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    phases: u32,
    /// The first episode's seed (start position, terrain draw); episode k
    /// uses seed + k. Repeat it for several seed sets of --episodes each,
    /// run as one evaluation with each set's success printed and written
    /// (e.g. --episodes 10 --seed 1000000 --seed 41000000)
    #[arg(long, default_values_t = [DEFAULT_FIRST_SEED])]
    seed: Vec<u64>,
    /// Sample a trained policy's actions (seeded by the episode's seed)
    /// instead of taking the mean
    #[arg(long)]
    stochastic: bool,
    /// Worker threads, one episode each at a time [default: all cores]
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=1024))]
    threads: Option<u32>,
    /// Run the physics at this rate, Hz, instead of the one the policy
    /// trained at (e.g. 240, the paper's, for a policy trained at 120)
    #[arg(long, value_name = "HZ")]
    step_rate_hz: Option<u32>,
    /// Print the summary and episodes as one JSON object instead of text
    #[arg(long)]
    json: bool,
    /// Where eval.json, table1.md and the figures go [default: the run
    /// directory's eval-<terrain>-seed<seed>/, or runs/eval-scripted-... for
    /// the crawl]
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Lay these evaluations (directories holding eval.json) side by side
    /// instead of running one
    #[arg(long, value_name = "DIR", num_args = 1.., conflicts_with_all = ["policy", "terrain", "config", "robot", "episodes", "phases", "seed", "stochastic", "threads", "step_rate_hz", "video"])]
    compare: Vec<PathBuf>,
    #[command(flatten)]
    rerun: RerunArgs,
    #[command(flatten)]
    video: VideoArgs,
}

/// The default output directory: inside the policy's run directory, or
/// under `runs/` for the scripted crawl; named by the terrain and the first
/// seed, and the number of seed sets when there are several.
fn default_out_dir(policy: &str, spec: &str, sets: &SeedSets) -> PathBuf {
    let seed = sets.first_seeds()[0];
    let seed = match sets.len() {
        1 => format!("{seed}"),
        n => format!("{seed}-{n}sets"),
    };
    let name = format!("eval-{}-seed{seed}", slug(spec));
    if policy == "scripted" {
        return Path::new("runs").join(format!("eval-scripted-{}-seed{seed}", slug(spec)));
    }
    let path = Path::new(policy);
    // An exported policy (shipped, perhaps read-only) is not written into.
    if learn::export::is_exported_policy(path) {
        let stem = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or("policy");
        return Path::new("runs").join(format!("eval-{stem}-{}-seed{seed}", slug(spec)));
    }
    // A run directory holds `latest`; a checkpoint lives inside its run.
    let run = if path.join(learn::checkpoint::LATEST_LINK).exists() {
        path
    } else {
        path.parent().unwrap_or(Path::new("."))
    };
    run.join(name)
}

/// Runs the episode of `seed` in `scene` again (the same episode as the
/// evaluation's), drawn into `video`'s file.
fn record_episode(
    registry: &Registry,
    scene: &EvalScene,
    request: &EvalRequest,
    seed: u64,
    video: &VideoArgs,
) -> Result<Option<VideoSummary>> {
    let label = format!("{} (seed {seed})", request.policy);
    let Some(mut recorder) =
        video.recorder(request.robot.clone(), &label, scene.physics().dt_secs())?
    else {
        return Ok(None);
    };
    let mut policy = Policy::from_arg(
        registry,
        &request.policy,
        request.stochastic.then_some(seed),
    )?;
    scene.run_episode(&mut policy, seed, Some(&mut recorder))?;
    recorder.finish().map(Some)
}

/// `quadwalk eval`.
pub fn eval(registry: &Registry, args: &EvalArgs) -> Result<()> {
    if !args.compare.is_empty() {
        return compare::compare(&args.compare, args.out.as_deref(), args.json);
    }
    args.video.check()?;
    let sets =
        SeedSets::new(args.seed.clone(), args.episodes.into()).map_err(anyhow::Error::msg)?;
    let first_seed = sets.first_seeds()[0];
    let mut experiment = args.scene.experiment(registry)?;
    args.task.apply(&mut experiment)?;
    let out_dir = args
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir(&args.policy, &experiment.terrain.to_string(), &sets));
    let request = EvalRequest {
        policy: args.policy.clone(),
        experiment,
        config_path: args.scene.config_path().map(Path::to_path_buf),
        task_overrides: args.task.overrides.clone(),
        robot: args.scene.robot()?,
        seeds: sets.seeds(),
        phases: args.phases,
        stochastic: args.stochastic,
        threads: args.threads.map(|n| n as usize),
        step_rate_hz: args.step_rate_hz,
    };
    // the policy and its fit to the scene are checked before the output
    // directory is made
    let scene = EvalScene::of(registry, &request)?;
    std::fs::create_dir_all(&out_dir)
        .with_context(|| format!("--out {}: cannot create the directory", out_dir.display()))?;
    let quiet = args.json;
    let mut report = scene.run_all(&request, &|n, total, record| {
        if !quiet {
            eprintln!(
                "episode {n}/{total} (seed {}): {:.2} m in {} phases{}",
                record.seed,
                record.distance_m,
                record.phases,
                record
                    .fall
                    .as_ref()
                    .map_or(String::new(), |f| format!(", fell: {}", f.describe()))
            );
        }
    })?;
    if sets.len() > 1 {
        report.seed_sets = sets.summarize(&report.episodes);
    }
    write_outputs(&report, &out_dir)?;
    log_to_rerun(&report, &args.rerun, &request.robot)?;
    let video = record_episode(registry, &scene, &request, first_seed, &args.video)?;
    if args.json {
        let mut value = serde_json::to_value(&report)?;
        if let Some(episodes) = value.get_mut("episodes").and_then(|e| e.as_array_mut()) {
            for e in episodes {
                if let Some(o) = e.as_object_mut() {
                    o.remove("phase_log");
                }
            }
        }
        value["out"] = serde_json::json!(out_dir.display().to_string());
        if let Some(v) = &video {
            value["video"] = serde_json::json!({
                "path": v.path.display().to_string(),
                "frames": v.frames,
                "steps_per_frame": v.steps_per_frame,
                "seed": first_seed,
            });
        }
        out!("{value}");
    } else {
        print_report(&report, &out_dir)?;
        if let Some(v) = &video {
            out!(
                "video           {} (the episode of seed {}: {} frames, one every {} physics steps)",
                v.path.display(),
                first_seed,
                v.frames,
                v.steps_per_frame
            );
        }
    }
    Ok(())
}

/// Writes `eval.json`, `table1.md` and the figures of `report` into `dir`.
pub(crate) fn write_outputs(report: &EvalReport, dir: &Path) -> Result<()> {
    report.write(dir)?;
    let title = format!("{} on {}", report.policy_name(), report.terrain);
    let types: Vec<_> = report.summary.each_terrain_type().collect();
    plots::distance_per_episode(
        &dir.join(FIGURE_FILES[0]),
        &format!("distance per episode: {title}"),
        &report.episodes,
    )?;
    plots::base_height_over_phase(
        &dir.join(FIGURE_FILES[1]),
        &format!("base height over the phase angle: {title}"),
        &types,
    )?;
    plots::landing_height_per_foot(
        &dir.join(FIGURE_FILES[2]),
        &format!("target landing height per foot: {title}"),
        &types,
    )?;
    Ok(())
}

fn log_to_rerun(report: &EvalReport, rerun: &RerunArgs, model: &RobotModel) -> Result<()> {
    let mut logger = rerun.open(
        viz::RerunSink::Off,
        model,
        Path::new("quadwalk-eval.rrd"),
        &format!("eval {} on {}", report.policy, report.terrain),
    )?;
    if !logger.is_active() {
        return Ok(());
    }
    let distances: Vec<(i64, f64)> = report
        .episodes
        .iter()
        .enumerate()
        .map(|(k, e)| (k as i64, e.distance_m))
        .collect();
    logger.log_curve("eval/distance_m", "episode", &distances);
    for t in report.summary.each_terrain_type() {
        let name = slug(&t.terrain);
        let bins = |f: &dyn Fn(f64, f64) -> f64| -> Vec<(i64, f64)> {
            t.base_height_by_angle_m
                .iter()
                .enumerate()
                .filter_map(|(k, b)| Some((k as i64, 100.0 * f(b.mean?, b.std.unwrap_or(0.0)))))
                .collect()
        };
        let path = format!("eval/base_height_cm/{name}");
        logger.log_curve(&format!("{path}/mean"), "phase_angle_deg", &bins(&|m, _| m));
        logger.log_curve(
            &format!("{path}/mean_plus_std"),
            "phase_angle_deg",
            &bins(&|m, s| m + s),
        );
        logger.log_curve(
            &format!("{path}/mean_minus_std"),
            "phase_angle_deg",
            &bins(&|m, s| m - s),
        );
        let landing: Vec<(i64, f64)> = robot::LegName::ALL
            .iter()
            .enumerate()
            .filter_map(|(k, leg)| Some((k as i64, 100.0 * t.landing_height_m[leg.short()].mean?)))
            .collect();
        logger.log_curve(&format!("eval/landing_height_cm/{name}"), "foot", &landing);
    }
    logger.finish();
    crate::viz_args::print_warnings(&mut logger);
    Ok(())
}

fn print_report(report: &EvalReport, out_dir: &Path) -> Result<()> {
    let s = &report.summary;
    let range = |first: u64, n: usize| format!("{first}..{}", first.wrapping_add(n as u64 - 1));
    let seeds = match report.seed_sets.as_slice() {
        [] => format!("seeds {}", range(report.first_seed, s.episodes)),
        sets => format!(
            "seed sets {}",
            sets.iter()
                .map(|set| range(set.first_seed, set.episodes))
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    out!(
        "eval            {} on {}: {} episodes x {} phases, {seeds}",
        report.policy,
        report.terrain,
        s.episodes,
        report.max_phases,
    );
    if !robot::world_config::is_paper_step_rate(&report.step_rate_hz) {
        out!(
            "physics         {} Hz ({} steps a phase; the paper's: 240)",
            report.step_rate_hz,
            robot::world_config::steps_per_phase_at(report.step_rate_hz)
        );
    }
    out!(
        "success         {}/{} ran every phase ({:.1} %)",
        s.successes,
        s.episodes,
        100.0 * s.success_rate
    );
    for set in &report.seed_sets {
        out!(
            "  seed set      {}: {}/{} ran every phase, {:.2} m mean",
            range(set.first_seed, set.episodes),
            set.successes,
            set.episodes,
            set.mean_distance_m
        );
    }
    let d = &s.distance_m;
    out!(
        "distance        mean {:.2} m, median {:.2}, p10 {:.2}, p90 {:.2} (min {:.2}, max {:.2})",
        d.mean,
        d.median,
        d.p10,
        d.p90,
        d.min,
        d.max
    );
    out!(
        "speed           mean {:.3} m/s; phases survived mean {:.1}; goals mean {:.1}; torque mean {:.1} N m",
        s.mean_speed_m_per_s.mean,
        s.phases.mean,
        s.goals_reached.mean,
        s.mean_torque_n_m.mean
    );
    out!(
        "energy          cost of transport {} (joints' mechanical energy / (m g distance)); foot slip mean {:.2} cm per phase",
        s.cost_of_transport
            .map_or("- (no distance walked)".to_string(), |c| format!("{c:.2}")),
        100.0 * s.foot_slip_m_per_phase.mean
    );
    out!("falls           {}", s.falls_text());
    if !s.falls_by_link.is_empty() {
        let links: Vec<_> = s
            .falls_by_link
            .iter()
            .map(|(l, n)| format!("{l} {n}"))
            .collect();
        out!("  by link       {}", links.join(", "));
    }
    let after_a_goal: usize = s.falls_after_a_goal_by_goal_ahead.iter().sum();
    if after_a_goal > 0 {
        let bins: Vec<_> = summary::GOAL_AHEAD_BINS
            .iter()
            .zip(s.falls_after_a_goal_by_goal_ahead)
            .map(|(bin, n)| format!("{bin} {n}"))
            .collect();
        out!(
            "  after a goal  {after_a_goal}, by the next goal's distance ahead: {} (a goal reached puts the next one goal_spacing_m, 2 m by default, ahead: falls bunched at >= 1.5 m came just after a goal switch)",
            bins.join(", ")
        );
    }
    if s.falls_at_terrain_end > 0 {
        out!(
            "  at the end    {} at the far end of the terrain (walked off it): {}",
            s.falls_at_terrain_end,
            record::terrain_end_advice(report.max_phases)
        );
    }
    if let Some(r) = &s.change_response {
        out!(
            "response        to the terrain's change at {} s: {} episodes walked from 3 s before to 6 s after it ({} fell or ended first); base level change mean {:+.2} cm; excess dip mean {:.2} cm (max {:.2}); recovery mean {:.2} s (max {:.2})",
            r.at_secs,
            r.episodes,
            r.without,
            100.0 * r.level_change_m.mean,
            100.0 * r.excess_dip_m.mean,
            100.0 * r.excess_dip_m.max,
            r.recovery_secs.mean,
            r.recovery_secs.max
        );
    }
    out!("per terrain type");
    out!(
        "  {:<22} {:>7} {:>10} {:>9} {:>11}",
        "terrain",
        "phases",
        "distance",
        "speed",
        "falls/100ph"
    );
    for t in &s.terrain_types {
        out!(
            "  {:<22} {:>7} {:>8.2} m {:>5.3} m/s {:>11.2}",
            t.terrain,
            t.phases,
            t.distance_m,
            t.mean_speed_m_per_s,
            t.falls_per_100_phases
        );
    }
    let columns: Vec<(String, &summary::TerrainSummary)> = table_columns(s)
        .into_iter()
        .map(|t| (t.terrain.clone(), t))
        .collect();
    out!("Table I (cm)");
    for line in table1::markdown(&columns).lines() {
        out!("  {line}");
    }
    out!(
        "wrote           {} ({REPORT_FILE}, table1.md, {})",
        out_dir.display(),
        FIGURE_FILES.join(", ")
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_directories_default_to_the_run_or_runs() {
        let one = |seed| SeedSets::new(vec![seed], 10).unwrap();
        assert_eq!(
            default_out_dir("scripted", "varying:2m:2,5cm", &one(7)),
            Path::new("runs/eval-scripted-varying_2m_2_5cm-seed7")
        );
        assert_eq!(
            default_out_dir(
                "scripted",
                "rigid",
                &SeedSets::new(vec![7, 41], 10).unwrap()
            ),
            Path::new("runs/eval-scripted-rigid-seed7-2sets")
        );
        let run = std::env::temp_dir().join(format!("qw-eval-run-{}", std::process::id()));
        std::fs::create_dir_all(run.join(learn::checkpoint::LATEST_LINK)).unwrap();
        assert_eq!(
            default_out_dir(run.to_str().unwrap(), "elastic:5cm", &one(1)),
            run.join("eval-elastic_5cm-seed1")
        );
        assert_eq!(
            default_out_dir(run.join("checkpoint-3").to_str().unwrap(), "rigid", &one(1)),
            run.join("eval-rigid-seed1")
        );
        std::fs::remove_dir_all(&run).unwrap();
    }
}
