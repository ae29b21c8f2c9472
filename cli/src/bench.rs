//! `quadwalk bench`: physics steps per second of the robot standing, one
//! world per thread, each thread stepping its own world.

use std::sync::{Barrier, Mutex};
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use serde_json::json;

use robot::scripted::ScriptedCrawl;
use robot::task::{Task, TaskConfig};
use viz::{RerunSink, RolloutLogger};

use crate::commands::{load_robot, make_world, parse_spec, positive_seconds};
use terrain_plugins::Registry;

/// The default scenes: rigid ground, the paper's elastic scene (15 x 5 tiles
/// around the robot) and the default 40 m long elastic terrain.
pub const DEFAULT_TERRAINS: [&str; 3] = [
    "rigid",
    "elastic:5cm:length=3m:back=1.5m:width=1m",
    "elastic:5cm",
];

/// Arguments of `quadwalk bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Terrain spec to measure (repeat for several); default: rigid, elastic:5cm on 15 x 5 tiles, elastic:5cm 40 m long
    #[arg(long = "terrain")]
    terrains: Vec<String>,
    /// Thread counts to measure, one world per thread (repeat or comma-separate); default: 1 and all cores
    #[arg(long = "threads", value_delimiter = ',', value_parser = clap::value_parser!(u32).range(1..=1024))]
    threads: Vec<u32>,
    /// Simulated seconds each world steps while timed
    #[arg(long, default_value = "10", value_parser = positive_seconds, allow_negative_numbers = true)]
    seconds: f64,
    /// Timed runs per measurement; the median is reported (shared machines are noisy)
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    repeat: u32,
    /// Phases each world runs for the phase-rate measurement (0 skips it)
    #[arg(long, default_value_t = 40)]
    phases: u32,
    /// Print one JSON object instead of a table
    #[arg(long)]
    json: bool,
    /// Experiment file whose `[physics]` table sets the simulation
    /// (default: the built-in physics, `robot::WorldConfig::default`)
    #[arg(long)]
    config: Option<std::path::PathBuf>,
    /// Rerun stream of the world on thread 0 during the phase-rate
    /// measurement (default: off; its figures then include the logging)
    #[command(flatten)]
    rerun: crate::viz_args::RerunArgs,
}

struct Measurement {
    terrain: String,
    tiles: usize,
    threads: usize,
    /// median over the repeats
    steps_per_s: f64,
    /// every repeat, in order
    runs_steps_per_s: Vec<f64>,
}

fn measure(
    registry: &Registry,
    physics: &robot::WorldConfig,
    spec: &str,
    threads: usize,
    seconds: f64,
    repeat: u32,
) -> Result<Measurement> {
    let mut runs = Vec::new();
    let mut last = None;
    for _ in 0..repeat {
        let m = measure_once(registry, physics, spec, threads, seconds)?;
        runs.push(m.steps_per_s);
        last = Some(m);
    }
    let mut sorted = runs.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let last = last.expect("repeat >= 1");
    Ok(Measurement {
        steps_per_s: median,
        runs_steps_per_s: runs,
        ..last
    })
}

/// Runs one world per thread: every thread `prepare`s its state (not
/// timed), all wait until every thread is ready, then each runs `timed` and
/// returns what it measured. A thread that fails to prepare still joins the
/// start, so no other thread waits for it forever.
fn on_each_thread<S, R: Send>(
    threads: usize,
    prepare: impl Fn(usize) -> Result<S> + Sync,
    timed: impl Fn(S) -> R + Sync,
) -> Result<Vec<R>> {
    let start = Barrier::new(threads);
    std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let (start, prepare, timed) = (&start, &prepare, &timed);
                scope.spawn(move || {
                    let state = prepare(t);
                    start.wait();
                    state.map(timed)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .map_err(|_| anyhow::anyhow!("a bench thread panicked"))?
            })
            .collect()
    })
}

fn measure_once(
    registry: &Registry,
    physics: &robot::WorldConfig,
    spec: &str,
    threads: usize,
    seconds: f64,
) -> Result<Measurement> {
    let spec = parse_spec(registry, spec)?;
    let model = load_robot(None)?;
    let steps = (seconds / physics.dt_secs()).round().max(1.0) as u64;
    // one second
    let settle_steps = u64::from(physics.step_rate_hz);
    let runs = on_each_thread(
        threads,
        |_| {
            let mut world = make_world(registry, &spec, model.clone(), 0, [0.0, 0.0], physics)?;
            for _ in 0..settle_steps {
                world.step();
            }
            Ok(world)
        },
        |mut world| {
            let start = Instant::now();
            for _ in 0..steps {
                world.step();
            }
            (start.elapsed().as_secs_f64(), world.terrain().tile_count())
        },
    )?;
    // Worlds start together; the rate counts until the slowest finishes.
    let elapsed = runs.iter().map(|r| r.0).fold(0.0, f64::max);
    Ok(Measurement {
        terrain: spec.to_string(),
        tiles: runs[0].1,
        threads,
        steps_per_s: (steps * threads as u64) as f64 / elapsed,
        runs_steps_per_s: Vec::new(),
    })
}

/// Phases per second: each world runs the scripted crawl through the task
/// (IK for 180 samples, PD control, 180 physics steps, observation, reward),
/// starting a new episode whenever one ends. Episode resets are not timed.
/// With `logger`, the world on thread 0 is streamed.
fn measure_phases(
    registry: &Registry,
    physics: &robot::WorldConfig,
    spec: &str,
    threads: usize,
    phases: u32,
    logger: Option<&Mutex<RolloutLogger>>,
) -> Result<f64> {
    let spec = parse_spec(registry, spec)?;
    let model = load_robot(None)?;
    let timed = on_each_thread(
        threads,
        |t| {
            let world = make_world(
                registry,
                &spec,
                model.clone(),
                t as u64,
                [0.0, 0.0],
                physics,
            )?;
            let mut task = Task::new(world, TaskConfig::default(), t as u64);
            let mut obs = vec![0.0f32; task.observation_size()];
            task.reset(&mut obs);
            Ok((task, obs, t))
        },
        |(mut task, mut obs, t)| {
            let crawl = ScriptedCrawl::default();
            let mut streamed = logger.filter(|_| t == 0).map(|l| {
                let mut guard = l.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                guard.begin_rollout();
                guard.log_terrain(task.world().terrain());
                guard.log_now(&task);
                guard
            });
            // Only whole phases (180 steps) count; a phase cut short by a
            // termination is neither timed nor counted.
            let (mut timed, mut whole) = (0.0, 0u32);
            while whole < phases {
                if task.done() {
                    task.reset(&mut obs);
                    if let Some(l) = streamed.as_deref_mut() {
                        l.begin_rollout();
                        l.log_now(&task);
                    }
                }
                let start = Instant::now();
                let action = crawl.act(&task);
                let outcome = match streamed.as_deref_mut() {
                    Some(l) => task.step_phase_observed(&action, &mut obs, l),
                    None => task.step_phase(&action, &mut obs),
                };
                if outcome.steps == task.world().steps_per_phase() {
                    timed += start.elapsed().as_secs_f64();
                    whole += 1;
                }
            }
            timed
        },
    )?;
    let slowest = timed.into_iter().fold(0.0, f64::max);
    Ok((phases as usize * threads) as f64 / slowest)
}

pub fn run(registry: &Registry, args: &BenchArgs) -> Result<()> {
    let terrains: Vec<String> = if args.terrains.is_empty() {
        DEFAULT_TERRAINS.iter().map(ToString::to_string).collect()
    } else {
        args.terrains.clone()
    };
    let physics = match &args.config {
        Some(path) => experiment::config::Experiment::from_file(path, registry)?.physics,
        None => robot::WorldConfig::default(),
    };
    // Check every spec before the long runs start.
    for spec in &terrains {
        parse_spec(registry, spec)?;
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut threads: Vec<usize> = args.threads.iter().map(|&t| t as usize).collect();
    if threads.is_empty() {
        threads.push(1);
        if cores > 1 {
            threads.push(cores);
        }
    }
    let logger = args.rerun.open(
        RerunSink::Off,
        &robot::RobotModel::laikago(),
        std::path::Path::new("quadwalk-bench.rrd"),
        "bench",
    )?;
    let logger = logger.is_active().then(|| Mutex::new(logger));
    if logger.is_some() {
        eprintln!("note: the phase rates below include Rerun logging of the world on thread 0");
    }
    let mut results = Vec::new();
    let mut phase_rates = Vec::new();
    for spec in &terrains {
        for &n in &threads {
            let m = measure(registry, &physics, spec, n, args.seconds, args.repeat)?;
            if !args.json {
                out!(
                    "{:<48} {:>6} tiles  {:>2} thread(s)  {:>9.0} steps/s  {:>8.0} steps/s per world",
                    m.terrain,
                    m.tiles,
                    m.threads,
                    m.steps_per_s,
                    m.steps_per_s / m.threads as f64
                );
            }
            if args.phases > 0 {
                let phases_per_s =
                    measure_phases(registry, &physics, spec, n, args.phases, logger.as_ref())?;
                if !args.json {
                    out!(
                        "{:<48} {:>6} {:>2} thread(s)  {:>9.1} phases/s  {:>8.1} ms per phase per world",
                        m.terrain,
                        "",
                        n,
                        phases_per_s,
                        1000.0 * n as f64 / phases_per_s
                    );
                }
                phase_rates.push((m.terrain.clone(), n, phases_per_s));
            }
            results.push(m);
        }
    }
    if args.json {
        let rows: Vec<_> = results
            .iter()
            .map(|m| {
                let single = results
                    .iter()
                    .find(|o| o.terrain == m.terrain && o.threads == 1)
                    .map(|o| o.steps_per_s);
                let phases_per_s = phase_rates
                    .iter()
                    .find(|(t, n, _)| *t == m.terrain && *n == m.threads)
                    .map(|(_, _, p)| *p);
                json!({
                    "terrain": m.terrain,
                    "tiles": m.tiles,
                    "threads": m.threads,
                    "steps_per_s": m.steps_per_s,
                    "steps_per_s_per_world": m.steps_per_s / m.threads as f64,
                    "speedup_vs_1_thread": single.map(|s| m.steps_per_s / s),
                    "runs_steps_per_s": m.runs_steps_per_s,
                    "phases_per_s": phases_per_s,
                    "ms_per_phase_per_world": phases_per_s.map(|p| 1000.0 * m.threads as f64 / p),
                })
            })
            .collect();
        out!(
            "{}",
            json!({
                "cores": cores,
                "seconds_per_world": args.seconds,
                "repeat": args.repeat,
                "dt_s": physics.dt_secs(),
                "physics": experiment::config::physics_json(&physics),
                "results": rows
            })
        );
    }
    if let Some(logger) = logger {
        let mut logger = logger
            .into_inner()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        logger.finish();
        crate::viz_args::print_warnings(&mut logger);
    }
    Ok(())
}
