//! The `--rerun` flags every command that runs rollouts shares.

use std::path::Path;

use anyhow::{Context, Result};
use clap::Args;
use robot::RobotModel;
use viz::{LogRate, RerunSink, RolloutLogger, VizSettings};

/// Where a run's Rerun stream goes and how often it logs.
#[derive(Debug, Args)]
pub struct RerunArgs {
    /// Rerun stream: off, save[:PATH] (an .rrd file), spawn (a viewer started
    /// from `rerun` on PATH) or connect[:URL] (a running viewer; default
    /// rerun+http://127.0.0.1:9876/proxy, HOST:PORT also works)
    #[arg(long, value_name = "SINK")]
    rerun: Option<RerunSink>,
    /// How often the robot, tiles, contacts and torques are logged: phase
    /// (once per phase), step (every physics step) or a number of steps
    #[arg(long, value_name = "RATE", default_value = "phase")]
    rerun_rate: LogRate,
}

impl RerunArgs {
    /// Opens the logger; `default_sink` applies when `--rerun` is not given,
    /// `default_file` to `save` without a path. Warnings (no viewer) are
    /// printed to stderr; an unwritable file is an error.
    pub fn open(
        &self,
        default_sink: RerunSink,
        model: &RobotModel,
        default_file: &Path,
        recording_name: &str,
    ) -> Result<RolloutLogger> {
        self.open_sink(self.sink(default_sink), model, default_file, recording_name)
    }

    /// The sink: `--rerun`, else `default_sink`.
    pub fn sink(&self, default_sink: RerunSink) -> RerunSink {
        self.rerun.clone().unwrap_or(default_sink)
    }

    /// Opens `sink` with these flags' rate (see [`Self::open`]).
    pub fn open_sink(
        &self,
        sink: RerunSink,
        model: &RobotModel,
        default_file: &Path,
        recording_name: &str,
    ) -> Result<RolloutLogger> {
        let settings = VizSettings {
            rate: self.rerun_rate,
            ..VizSettings::default()
        };
        let mut logger = RolloutLogger::open(&sink, settings, model, default_file, recording_name)
            .context("--rerun")?;
        print_warnings(&mut logger);
        Ok(logger)
    }
}

/// Prints the logger's new warnings to stderr.
pub fn print_warnings(logger: &mut RolloutLogger) {
    for warning in logger.take_warnings() {
        eprintln!("warning: {warning}");
    }
}
