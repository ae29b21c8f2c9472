//! `terrain list`, `terrain show` and `stand`.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Result;
use clap::Args;
use robot::RobotModel;
use serde_json::json;
use terrain_plugins::units::format_length;
use terrain_plugins::{BuildContext, Registry, TerrainSpec};

/// Parses a finite, positive number of seconds.
pub fn positive_seconds(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("{text:?} is not a number of seconds"))?;
    if value.is_finite() && value > 0.0 && value <= 1.0e6 {
        Ok(value)
    } else {
        Err(format!("{text:?} must be a number of seconds in (0, 1e6]"))
    }
}

/// Parses a finite coordinate in metres.
pub fn finite_metres(text: &str) -> Result<f64, String> {
    let value: f64 = text
        .parse()
        .map_err(|_| format!("{text:?} is not a number of metres"))?;
    if value.is_finite() {
        Ok(value)
    } else {
        Err(format!("{text:?} must be finite"))
    }
}

/// Parses a spec with the app's terrain plugins.
pub fn parse_spec(registry: &Registry, spec: &str) -> Result<TerrainSpec> {
    Ok(registry.parse(spec)?)
}

pub use experiment::scene::{load_robot, make_world};

pub fn terrain_list(registry: &Registry) -> Result<()> {
    for plugin in registry.plugins() {
        out!("{:<10} {}", plugin.name(), plugin.summary());
        out!("           usage: {}", Registry::usage(plugin));
        for decl in plugin.params() {
            let default = decl
                .default
                .as_ref()
                .map_or("required".to_string(), |d| format!("default {d}"));
            out!("           {:<10} {} [{}]", decl.name, decl.doc, default);
        }
        out!("");
    }
    Ok(())
}

pub fn terrain_show(
    registry: &Registry,
    spec: &str,
    robot: Option<&Path>,
    seed: u64,
    as_json: bool,
) -> Result<()> {
    let spec = parse_spec(registry, spec)?;
    let model = load_robot(robot)?;
    let ctx = BuildContext {
        supported_mass_kg: model.total_mass_kg(),
        seed,
        ..BuildContext::default()
    };
    let terrain = registry.create_from_spec(&spec, &ctx)?;
    if as_json {
        let e = terrain.extent();
        let regions: Vec<_> = terrain
            .regions()
            .iter()
            .map(|r| {
                json!({
                    "index": r.index,
                    "label": r.label,
                    "x_range_m": [r.x_range_m.0, r.x_range_m.1],
                    "stiffness_n_per_m": r.stiffness_n_per_m,
                    "damping_n_s_per_m": r.damping_n_s_per_m,
                    "expected_sink_m": r.expected_sink_m,
                })
            })
            .collect();
        let tiles = terrain
            .tile_geometry_m()
            .map(|(side, pitch)| json!({ "side_m": side, "pitch_m": pitch }));
        let out = json!({
            "terrain": spec.to_string(),
            "robot_mass_kg": model.total_mass_kg(),
            "tile_count": terrain.tile_count(),
            "tiles": tiles,
            "extent_m": { "min": e.min_m, "max": e.max_m },
            "regions": regions,
            "details": terrain.details(),
        });
        out!("{out}");
        return Ok(());
    }
    out!("terrain      {spec}");
    out!(
        "robot mass   {:.3} kg ({})",
        model.total_mass_kg(),
        model.name
    );
    match terrain.tile_geometry_m() {
        Some((side, pitch)) => out!(
            "tiles        {} tiles, {} side on a {} pitch",
            terrain.tile_count(),
            format_length(side),
            format_length(pitch)
        ),
        None => out!("tiles        none"),
    }
    let e = terrain.extent();
    out!(
        "extent       x {:.2}..{:.2} m, y {:.2}..{:.2} m",
        e.min_m[0],
        e.max_m[0],
        e.min_m[1],
        e.max_m[1]
    );
    out!("regions      {}", terrain.regions().len());
    for r in terrain.regions() {
        let springs = match (r.stiffness_n_per_m, r.damping_n_s_per_m) {
            (Some(k), Some(c)) => format!("stiffness {k:8.1} N/m  damping {c:6.1} N s/m"),
            _ => "rigid".to_string(),
        };
        out!(
            "  {:>3}  x {:7.2}..{:7.2} m  {:<14} {}  expected sink {:.1} cm",
            r.index,
            r.x_range_m.0,
            r.x_range_m.1,
            r.label,
            springs,
            r.expected_sink_m * 100.0
        );
    }
    for line in terrain.details() {
        out!("{line}");
    }
    Ok(())
}

/// The scene flags every simulating command shares.
#[derive(Debug, Args)]
pub struct SceneArgs {
    /// Terrain spec, e.g. rigid, elastic:5cm, varying:2m:2,5cm [default: elastic:5cm]
    #[arg(long, conflicts_with = "config")]
    terrain: Option<String>,
    /// Experiment file (TOML) with [terrain] and optional [task] sections
    #[arg(long)]
    config: Option<PathBuf>,
    /// Robot description (URDF); default: the built-in Laikago
    #[arg(long)]
    robot: Option<PathBuf>,
}

/// `--task KEY=VALUE`: the task settings that judge a run.
#[derive(Debug, Args)]
pub struct TaskOverrideArgs {
    /// A [task] setting on top of the scene's, as KEY=VALUE (repeatable; e.g.
    /// base_height_reference=feet, min_base_height_m=0.15): the terminations
    /// and rewards that judge the run. Not observation or action_prior (a
    /// trained policy brings its own)
    #[arg(long = "task", value_name = "KEY=VALUE")]
    pub overrides: Vec<String>,
}

impl TaskOverrideArgs {
    /// `experiment`'s task with the overrides on top.
    pub fn apply(&self, experiment: &mut experiment::config::Experiment) -> Result<()> {
        experiment.task =
            experiment::config::apply_task_overrides(&experiment.task, &self.overrides)
                .map_err(anyhow::Error::msg)?;
        Ok(())
    }
}

impl SceneArgs {
    /// The experiment these flags name: the config file, or the terrain
    /// spec (default `elastic:5cm`) with the default task.
    pub fn experiment(&self, registry: &Registry) -> Result<experiment::config::Experiment> {
        match (&self.config, &self.terrain) {
            (Some(path), _) => experiment::config::Experiment::from_file(path, registry),
            (None, terrain) => Ok(experiment::config::Experiment::for_terrain(parse_spec(
                registry,
                terrain.as_deref().unwrap_or("elastic:5cm"),
            )?)),
        }
    }

    /// The experiment file, when --config was given.
    pub fn config_path(&self) -> Option<&Path> {
        self.config.as_deref()
    }

    /// Whether --terrain or --config was given.
    pub fn is_given(&self) -> bool {
        self.terrain.is_some() || self.config.is_some()
    }

    /// The robot these flags name.
    pub fn robot(&self) -> Result<Arc<RobotModel>> {
        load_robot(self.robot.as_deref())
    }
}

/// Arguments of `quadwalk stand`.
#[derive(Debug, Args)]
pub struct StandArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Simulated seconds to stand
    #[arg(long, default_value = "10", value_parser = positive_seconds, allow_negative_numbers = true)]
    seconds: f64,
    /// Base start x, m
    #[arg(long, default_value = "0", value_parser = finite_metres, allow_negative_numbers = true)]
    x: f64,
    /// Base start y, m
    #[arg(long, default_value = "0", value_parser = finite_metres, allow_negative_numbers = true)]
    y: f64,
    /// Seed (the varying terrain's region draw)
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print one JSON object instead of text
    #[arg(long)]
    json: bool,
    /// Rerun stream (default: off); `phase` rate means every 0.75 s here
    #[command(flatten)]
    rerun: crate::viz_args::RerunArgs,
}

pub fn stand(registry: &Registry, args: &StandArgs) -> Result<()> {
    let experiment = args.scene.experiment(registry)?;
    let (spec, physics) = (experiment.terrain, experiment.physics);
    let model = args.scene.robot()?;
    let mut world = make_world(
        registry,
        &spec,
        model.clone(),
        args.seed,
        [args.x, args.y],
        &physics,
    )?;
    let mut logger = args.rerun.open(
        viz::RerunSink::Off,
        &model,
        Path::new("quadwalk-stand.rrd"),
        &format!("stand on {spec}"),
    )?;
    logger.log_terrain(world.terrain());
    let tiles_half_side_m = logger.settings().tiles_half_side_m;
    let rate = logger.settings().rate;
    let steps_per_phase = world.steps_per_phase();
    if logger.is_active() {
        logger.log_snapshot(&world.snapshot(tiles_half_side_m, 0, None));
    }
    let report = robot::stand::stand_observed(&mut world, args.seconds, &mut |world, step| {
        let step_in_phase = (step as usize % steps_per_phase) + 1;
        if logger.is_active() && rate.logs_step(step_in_phase, steps_per_phase) {
            let phase = step as usize / steps_per_phase;
            logger.log_snapshot(&world.snapshot(tiles_half_side_m, phase, None));
        }
    });
    logger.finish();
    crate::viz_args::print_warnings(&mut logger);
    if args.json {
        let out = json!({
            "terrain": spec.to_string(),
            "robot": model.name,
            "robot_mass_kg": model.total_mass_kg(),
            "start_xy_m": [args.x, args.y],
            "region": report.region,
            "seconds": report.seconds,
            "steps": report.steps,
            "base_height_m": report.base_height_m,
            "base_height_drift_m": report.base_height_drift_m,
            "max_tilt_deg": report.max_tilt_deg,
            "mean_loaded_sink_m": report.mean_loaded_sink_m,
            "expected_sink_m": report.expected_sink_m,
            "window_secs": report.window_secs,
            "non_foot_contacts": report.non_foot_contacts,
            "rerun_frames": logger.frames_logged(),
        });
        out!("{out}");
    } else {
        out!("terrain             {spec} (region {})", report.region);
        out!(
            "robot               {} ({:.3} kg)",
            model.name,
            model.total_mass_kg()
        );
        out!(
            "stood               {:.2} s ({} steps)",
            report.seconds,
            report.steps
        );
        out!("base height         {:.4} m", report.base_height_m);
        out!(
            "base height drift   {:.2} mm over the last {:.1} s",
            report.base_height_drift_m * 1000.0,
            report.window_secs
        );
        out!("max tilt            {:.2} deg", report.max_tilt_deg);
        out!(
            "mean loaded sink    {:.2} cm (expected {:.2} cm)",
            report.mean_loaded_sink_m * 100.0,
            report.expected_sink_m * 100.0
        );
        let contacts = if report.non_foot_contacts.is_empty() {
            "none".to_string()
        } else {
            report.non_foot_contacts.join(", ")
        };
        out!("non-foot contacts   {contacts}");
    }
    Ok(())
}
