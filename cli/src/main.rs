//! `quadwalk`: learn quadruped locomotion on ground that gives way.
//!
//! Errors are printed as one line (`error: ...`) with exit code 1; bad flags
//! are reported by clap with exit code 2.

/// Writes a line to standard output, returning the I/O error instead of
/// panicking (a closed pipe, as in `quadwalk terrain list | head`, ends the
/// command quietly).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?
    }};
}

mod bench;
mod commands;
mod config;
mod eval;
mod export;
mod policy;
mod rollout;
mod task_env;
mod train;
mod viz_args;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// quadwalk: quadruped locomotion on non-rigid terrain (rapier3d).
#[derive(Debug, Parser)]
#[command(name = "quadwalk", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List terrain models or show what a terrain spec builds.
    #[command(subcommand)]
    Terrain(TerrainCommand),
    /// Let the robot stand in its squat on a terrain and report how it settles.
    Stand(commands::StandArgs),
    /// Run a policy (the scripted crawl) for a number of phases and report distance, height, reward.
    Rollout(rollout::RolloutArgs),
    /// Run a policy and watch it in the Rerun viewer (rollout with --rerun spawn by default).
    Play(rollout::PlayArgs),
    /// Evaluate a policy on many episodes of unseen seeds: success, distance, falls, the paper's Table I and Fig. 4, PNG figures.
    Eval(Box<eval::EvalArgs>),
    /// Train a policy with PPO, SAC or CrossQ on parallel worlds (checkpoints, --resume, Rerun)
    Train(train::TrainArgs),
    /// Measure physics steps per second of the robot standing, one world per thread.
    Bench(bench::BenchArgs),
    /// Write a trained policy for use or shipping: actor, normaliser, config and metrics, without optimiser state.
    Export(export::ExportArgs),
}

#[derive(Debug, Subcommand)]
enum TerrainCommand {
    /// List the terrain plugins, their parameters and defaults.
    List,
    /// Show a spec's tiles, regions, spring stiffness and expected sink.
    Show {
        /// Terrain spec, e.g. elastic:5cm or varying:2m:2,3,4,5cm,rigid
        spec: String,
        /// Robot description whose mass sets the stiffness (default: the built-in Laikago)
        #[arg(long)]
        robot: Option<PathBuf>,
        /// Seed for the varying terrain's region draw
        #[arg(long, default_value_t = 0)]
        seed: u64,
        /// Print one JSON object instead of text
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Terrain(TerrainCommand::List) => commands::terrain_list(),
        Command::Terrain(TerrainCommand::Show {
            spec,
            robot,
            seed,
            json,
        }) => commands::terrain_show(&spec, robot.as_deref(), seed, json),
        Command::Stand(args) => commands::stand(&args),
        Command::Rollout(args) => rollout::rollout(&args),
        Command::Play(args) => rollout::play(&args),
        Command::Eval(args) => eval::eval(&args),
        Command::Train(args) => train::train(&args),
        Command::Bench(args) => bench::run(&args),
        Command::Export(args) => export::export(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) if is_broken_pipe(&err) => ExitCode::SUCCESS,
        Err(err) => {
            let chain: Vec<String> = err.chain().map(ToString::to_string).collect();
            eprintln!("error: {}", chain.join(": "));
            ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain()
        .filter_map(|e| e.downcast_ref::<std::io::Error>())
        .any(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
}
