//! The `quadwalk` command line as a library.
//!
//! A binary runs every command (`terrain`, `stand`, `rollout`, `play`,
//! `eval`, `train`, `bench`, `export`, `results`) through an [`App`], which holds the
//! terrain plugins those commands may use. `quadwalk` itself is
//! `App::new().run()`; a crate with a terrain model of its own builds its
//! own binary the same way, with its plugin added:
//!
//! ```no_run
//! # use terrain_plugins::TerrainPlugin;
//! # fn plugin() -> Box<dyn TerrainPlugin> { unimplemented!() }
//! fn main() -> std::process::ExitCode {
//!     quadwalk_cli::App::new() // the built-in terrains
//!         .add_terrain(plugin()) // and yours
//!         .run()
//! }
//! ```
//!
//! The one [`Registry`] of the app reaches every command: specs on the
//! command line, in experiment files and in checkpoints are parsed with it,
//! worlds are built from it, `terrain list` shows it.
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
mod curves;
mod eval;
mod export;
mod onnx;
mod results;
mod rollout;
mod train;
mod video;
mod viz_args;

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;

use clap::{Parser, Subcommand};
pub use terrain_plugins::{Registry, RegistryError, TerrainPlugin};

/// What other front ends (the Python package) share with the commands: an
/// experiment file's settings, building a world the way `rollout` does, and
/// running a checkpoint.
pub use commands::make_world;
pub use experiment::{Experiment, Policy};

/// The command line with its terrain plugins: build it, add plugins, run it.
pub struct App {
    registry: Registry,
    /// the first plugin that could not be added, reported by [`App::run`]
    refused: Option<RegistryError>,
    /// what a second Ctrl-C during training does ([`App::on_second_interrupt`])
    second_interrupt: Option<fn() -> !>,
}

impl Default for App {
    fn default() -> Self {
        Self::new()
    }
}

impl App {
    /// The command line with the built-in terrain plugins.
    pub fn new() -> Self {
        Self::with_registry(Registry::builtin())
    }

    /// The command line with exactly the plugins of `registry`.
    pub fn with_registry(registry: Registry) -> Self {
        Self {
            registry,
            refused: None,
            second_interrupt: None,
        }
    }

    /// What a second Ctrl-C during `train` does: the binary's choice
    /// (`quadwalk`'s `main` exits with code 130, leaving the last
    /// checkpoint). Without it a second Ctrl-C is only reported: the run
    /// stops, checkpointed, as after the first.
    pub fn on_second_interrupt(mut self, stop_now: fn() -> !) -> Self {
        self.second_interrupt = Some(stop_now);
        self
    }

    /// Adds a terrain plugin. A name already taken (or not a valid name) is
    /// not added; [`App::run`] then reports it and exits with an error
    /// before running any command.
    pub fn add_terrain(mut self, plugin: Box<dyn TerrainPlugin>) -> Self {
        if let Err(err) = self.registry.register(plugin)
            && self.refused.is_none()
        {
            self.refused = Some(err);
        }
        self
    }

    /// The plugins every command will use.
    pub fn registry(&self) -> &Registry {
        &self.registry
    }

    /// Parses the process's arguments and runs the command.
    pub fn run(self) -> ExitCode {
        self.run_from(std::env::args_os())
    }

    /// Parses `args` (the first is the program name) and runs the command:
    /// exit code 0 on success, 1 on an error (printed as one line), 2 on
    /// bad flags.
    pub fn run_from<I, T>(self, args: I) -> ExitCode
    where
        I: IntoIterator<Item = T>,
        T: Into<OsString> + Clone,
    {
        let cli = match Cli::try_parse_from(args) {
            Ok(cli) => cli,
            Err(err) => {
                let _ = err.print();
                return ExitCode::from(u8::try_from(err.exit_code()).unwrap_or(2));
            }
        };
        if let Some(err) = self.refused {
            eprintln!("error: cannot register terrain plugin: {err}");
            return ExitCode::FAILURE;
        }
        report(run_command(
            cli.command,
            &Arc::new(self.registry),
            self.second_interrupt,
        ))
    }
}

/// Runs the command line with `registry`'s terrain plugins (the process's
/// arguments); the same as `App::with_registry(registry).run()`.
pub fn run(registry: Registry) -> ExitCode {
    App::with_registry(registry).run()
}

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
    /// Regenerate the results pages (Table I, Fig. 4, the policy-by-terrain matrix, the ablations) from a plan of evaluations.
    Results(results::ResultsArgs),
    /// Draw training runs' learning curves side by side, by phases and by wall time, in one PNG.
    Curves(curves::CurvesArgs),
    /// Write a trained policy for use or shipping: actor, normaliser, config and metrics, without optimiser state.
    Export(export::ExportArgs),
    /// Write a trained policy's deterministic actor (normaliser, network, action bound) as one ONNX graph.
    Onnx(onnx::OnnxArgs),
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

fn run_command(
    command: Command,
    registry: &Arc<Registry>,
    second_interrupt: Option<fn() -> !>,
) -> anyhow::Result<ExitCode> {
    let done = |result: anyhow::Result<()>| result.map(|()| ExitCode::SUCCESS);
    match command {
        Command::Terrain(TerrainCommand::List) => done(commands::terrain_list(registry)),
        Command::Terrain(TerrainCommand::Show {
            spec,
            robot,
            seed,
            json,
        }) => done(commands::terrain_show(
            registry,
            &spec,
            robot.as_deref(),
            seed,
            json,
        )),
        Command::Stand(args) => done(commands::stand(registry, &args)),
        Command::Rollout(args) => done(rollout::rollout(registry, &args)),
        Command::Play(args) => done(rollout::play(registry, &args)),
        Command::Eval(args) => done(eval::eval(registry, &args)),
        Command::Train(args) => train::train(registry, &args, second_interrupt),
        Command::Bench(args) => done(bench::run(registry, &args)),
        Command::Results(args) => done(results::results(registry, &args)),
        Command::Curves(args) => done(curves::curves(&args)),
        Command::Export(args) => done(export::export(registry, &args)),
        Command::Onnx(args) => done(onnx::onnx(registry, &args)),
    }
}

fn report(result: anyhow::Result<ExitCode>) -> ExitCode {
    match result {
        Ok(code) => code,
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
