//! [`RolloutLogger`] when quadwalk is built without the `rerun` feature:
//! `--rerun off` works and logs nothing; any other sink is an error that
//! says how to get Rerun back.

use std::path::Path;

use robot::RobotModel;
use robot::snapshot::{PhaseObserver, StepSnapshot};
use robot::task::Task;
use terrain_plugins::Terrain;

use crate::{RerunSink, VizError, VizSettings};

/// Logs nothing: this build has no Rerun.
pub struct RolloutLogger {
    settings: VizSettings,
    warnings: Vec<String>,
}

impl RolloutLogger {
    /// `Off` gives a logger that does nothing; any other sink is an error.
    pub fn open(
        sink: &RerunSink,
        settings: VizSettings,
        _model: &RobotModel,
        _default_file: &Path,
        _recording_name: &str,
    ) -> Result<Self, VizError> {
        match sink {
            RerunSink::Off => Ok(Self {
                settings,
                warnings: Vec::new(),
            }),
            other => Err(VizError::Sink {
                sink: other.to_string(),
                message: "this quadwalk was built without Rerun (cargo feature `rerun`, on by default); rebuild with default features or pass --rerun off".into(),
            }),
        }
    }

    /// Always false.
    pub fn is_active(&self) -> bool {
        false
    }

    /// The settings.
    pub fn settings(&self) -> &VizSettings {
        &self.settings
    }

    /// Always 0.
    pub fn frames_logged(&self) -> usize {
        0
    }

    /// Always empty.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Always empty.
    pub fn take_warnings(&mut self) -> Vec<String> {
        std::mem::take(&mut self.warnings)
    }

    /// Does nothing.
    pub fn set_iteration(&mut self, _iteration: Option<i64>) {}

    /// Does nothing.
    pub fn begin_rollout(&mut self) {}

    /// Does nothing.
    pub fn log_terrain(&mut self, _terrain: &dyn Terrain) {}

    /// Does nothing.
    pub fn log_now(&mut self, _task: &Task) {}

    /// Does nothing.
    pub fn log_snapshot(&mut self, _snap: &StepSnapshot) {}

    /// Does nothing.
    pub fn log_training(&mut self, _iteration: i64, _values: &[(String, f64)]) {}

    /// Does nothing.
    pub fn finish(&mut self) {}

    /// Logs nothing (see the Rerun logger).
    pub fn log_curve(&mut self, _entity: &str, _timeline: &'static str, _points: &[(i64, f64)]) {}
}

impl PhaseObserver for RolloutLogger {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn off_works_and_other_sinks_say_rerun_is_missing() {
        let model = RobotModel::laikago();
        let logger = RolloutLogger::open(
            &RerunSink::Off,
            VizSettings::default(),
            &model,
            Path::new("x.rrd"),
            "t",
        )
        .unwrap();
        assert!(!logger.is_active());
        let err = RolloutLogger::open(
            &RerunSink::Spawn,
            VizSettings::default(),
            &model,
            Path::new("x.rrd"),
            "t",
        )
        .err()
        .unwrap()
        .to_string();
        assert!(
            err.contains("without Rerun") && err.contains("--rerun off"),
            "{err}"
        );
    }
}
