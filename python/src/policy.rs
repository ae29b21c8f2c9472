//! A quadwalk checkpoint's mean action, from Python.

use numpy::{
    PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::scene::{runtime_error, value_error};

/// A trained policy (a run directory, one of its checkpoints, or an
/// exported policy): `act` gives the deterministic (mean) action
/// `quadwalk rollout --policy DIR` takes for the same observation.
#[pyclass(module = "quadwalk._quadwalk", unsendable)]
pub struct Policy {
    learner: Box<dyn learn::Algorithm>,
    config_path: String,
}

#[pymethods]
impl Policy {
    /// Loads the checkpoint at `path`.
    #[staticmethod]
    fn load(path: &str) -> PyResult<Self> {
        let registry = crate::scene::registry();
        if path == "scripted" {
            return Err(PyValueError::new_err(
                "policy \"scripted\": the scripted crawl needs the task, not an observation; load a checkpoint",
            ));
        }
        let policy = experiment::Policy::from_arg(&registry, path, None).map_err(value_error)?;
        let experiment::Policy::Trained { learner, .. } = policy else {
            return Err(PyValueError::new_err(format!(
                "policy {path:?} is not a trained phase-level policy (the scripted crawl and residual policies are not)"
            )));
        };
        let dir = learn::checkpoint::resolve_checkpoint(std::path::Path::new(path))
            .unwrap_or_else(|_| std::path::PathBuf::from(path));
        Ok(Self {
            learner,
            config_path: dir.join("config.toml").display().to_string(),
        })
    }

    /// The mean action (27 values) for one observation.
    fn act<'py>(
        &self,
        py: Python<'py>,
        obs: PyReadonlyArray1<'py, f32>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let obs = obs.as_slice().map_err(value_error)?;
        if obs.len() != self.learner.obs_size() {
            return Err(PyValueError::new_err(format!(
                "observation has {} values; the policy takes {}",
                obs.len(),
                self.learner.obs_size()
            )));
        }
        let action = self.learner.act_deterministic(obs).map_err(runtime_error)?;
        Ok(PyArray1::from_vec(py, action))
    }

    /// The mean actions (n x 27) for a batch of observations (n x obs).
    fn act_batch<'py>(
        &self,
        py: Python<'py>,
        obs: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let shape = obs.shape().to_vec();
        if shape[1] != self.learner.obs_size() {
            return Err(PyValueError::new_err(format!(
                "observations have shape {shape:?}; the policy takes {} values each",
                self.learner.obs_size()
            )));
        }
        let mut out = Vec::with_capacity(shape[0] * self.learner.action_size());
        for row in obs.as_array().rows() {
            let row: Vec<f32> = row.iter().copied().collect();
            out.extend(
                self.learner
                    .act_deterministic(&row)
                    .map_err(runtime_error)?,
            );
        }
        PyArray1::from_vec(py, out).reshape([shape[0], self.learner.action_size()])
    }

    /// Observation values the policy takes.
    #[getter]
    fn observation_size(&self) -> usize {
        self.learner.obs_size()
    }

    /// The experiment file the policy was trained with: pass it to
    /// `make_env(config=...)` to run it in the task it knows.
    #[getter]
    fn config_path(&self) -> &str {
        &self.config_path
    }
}
