//! What an environment is built from: the terrain registry, an experiment
//! (terrain, task, physics) and the robot; and the registry seen from Python.

use std::path::Path;
use std::sync::{Arc, OnceLock};

use experiment::Experiment;
use experiment::scene::make_world;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use robot::RobotModel;
use robot::task::Task;
use terrain_plugins::Registry;

/// The terrain the environments use when neither a terrain nor a config is
/// given: the paper's 5 cm tiles.
pub const DEFAULT_TERRAIN: &str = "elastic:5cm";

/// The terrain plugins every environment, policy and `terrains()` of the
/// package uses: the built-in ones, made once (the package's counterpart of
/// the `quadwalk` binary's `App::new()`).
pub fn registry() -> Arc<Registry> {
    static REGISTRY: OnceLock<Arc<Registry>> = OnceLock::new();
    REGISTRY
        .get_or_init(|| Arc::new(Registry::builtin()))
        .clone()
}

/// A `ValueError` carrying an error's whole chain on one line.
pub fn value_error(error: impl Into<anyhow::Error>) -> PyErr {
    PyValueError::new_err(format!("{:#}", error.into()))
}

/// A `RuntimeError` carrying an error's whole chain on one line.
pub fn runtime_error(error: impl Into<anyhow::Error>) -> PyErr {
    PyRuntimeError::new_err(format!("{:#}", error.into()))
}

/// Everything a task is built from.
#[derive(Clone)]
pub struct Scene {
    /// the terrain plugins (the built-in ones)
    pub registry: Arc<Registry>,
    /// terrain, task settings and physics
    pub experiment: Experiment,
    /// the robot
    pub model: Arc<RobotModel>,
}

impl Scene {
    /// From a terrain spec and/or an experiment file (TOML): the file's
    /// settings, its terrain replaced by `terrain` when both are given;
    /// `max_phases` replaces the task's episode length.
    pub fn new(
        terrain: Option<&str>,
        config: Option<&str>,
        max_phases: Option<usize>,
    ) -> PyResult<Self> {
        let registry = registry();
        let parse = |spec: &str| {
            registry
                .parse(spec)
                .map_err(|e| PyValueError::new_err(format!("terrain {spec:?}: {e}")))
        };
        let mut experiment = match config {
            Some(path) => Experiment::from_file(Path::new(path), &registry).map_err(value_error)?,
            None => Experiment::for_terrain(parse(terrain.unwrap_or(DEFAULT_TERRAIN))?),
        };
        if let (Some(path), Some(_)) = (config, &experiment.residual) {
            return Err(PyValueError::new_err(format!(
                "config {path} [residual]: the Python environment steps whole phases; a lower-level residual policy is trained with `quadwalk train --config {path}`"
            )));
        }
        if let (Some(_), Some(spec)) = (config, terrain) {
            experiment.terrain = parse(spec)?;
        }
        if let Some(phases) = max_phases {
            if phases == 0 {
                return Err(PyValueError::new_err(
                    "max_phases 0: an episode needs at least one phase",
                ));
            }
            experiment.task.max_phases = phases;
        }
        Ok(Self {
            registry,
            experiment,
            model: Arc::new(RobotModel::laikago()),
        })
    }

    /// A fresh task whose world and start positions are drawn from `seed`
    /// (as `quadwalk rollout --seed`).
    pub fn task(&self, seed: u64) -> PyResult<Task> {
        let world = make_world(
            &self.registry,
            &self.experiment.terrain,
            self.model.clone(),
            seed,
            [0.0, 0.0],
            &self.experiment.physics,
        )
        .map_err(value_error)?;
        Ok(Task::new(world, self.experiment.task.clone(), seed))
    }
}

/// The built-in terrain plugins: a list of dicts with `name`, `summary`
/// and `params` (each a dict: `name`, `default` (None: required), `doc`).
#[pyfunction]
pub fn terrains(py: Python<'_>) -> PyResult<Vec<Py<pyo3::types::PyDict>>> {
    registry()
        .plugins()
        .map(|plugin| {
            let entry = pyo3::types::PyDict::new(py);
            entry.set_item("name", plugin.name())?;
            entry.set_item("summary", plugin.summary())?;
            let params = plugin
                .params()
                .iter()
                .map(|decl| {
                    let p = pyo3::types::PyDict::new(py);
                    p.set_item("name", decl.name)?;
                    p.set_item("default", decl.default.as_ref().map(|v| v.to_string()))?;
                    p.set_item("doc", decl.doc)?;
                    Ok(p.unbind())
                })
                .collect::<PyResult<Vec<_>>>()?;
            entry.set_item("params", params)?;
            Ok(entry.unbind())
        })
        .collect()
}
