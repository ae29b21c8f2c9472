//! One task, and N tasks stepped in parallel, seen from Python.

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use robot::action::ACTION_SIZE;
use robot::task::{PhaseOutcome, RewardTerms, Task};
use std::sync::{Mutex, PoisonError};
use std::time::Instant;

use crate::scene::{Scene, runtime_error};

/// What a phase reports besides the reward, for `info`.
struct PhaseInfo {
    terms: [f64; 5],
    termination: Option<(&'static str, String)>,
    region: String,
    phase: usize,
    goals_reached: usize,
    mean_base_height_m: f64,
    base_xy_m: [f64; 2],
}

impl PhaseInfo {
    fn new(task: &Task, outcome: &PhaseOutcome) -> Self {
        let terrain = task.world().terrain();
        let base = task.world().base_pose().translation.vector;
        Self {
            terms: outcome.terms.values(),
            termination: outcome
                .termination
                .as_ref()
                .map(|t| (t.kind(), t.to_string())),
            region: terrain.regions()[outcome.region].label.clone(),
            phase: task.phase(),
            goals_reached: task.goals_reached(),
            mean_base_height_m: outcome.mean_base_height_m,
            base_xy_m: [base.x, base.y],
        }
    }

    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let info = PyDict::new(py);
        let terms = PyDict::new(py);
        for (name, value) in RewardTerms::NAMES.iter().zip(self.terms) {
            terms.set_item(name, value)?;
        }
        info.set_item("reward_terms", terms)?;
        info.set_item("termination", self.termination.as_ref().map(|t| t.0))?;
        info.set_item(
            "termination_detail",
            self.termination.as_ref().map(|t| t.1.as_str()),
        )?;
        info.set_item("region", &self.region)?;
        info.set_item("phase", self.phase)?;
        info.set_item("goals_reached", self.goals_reached)?;
        info.set_item("mean_base_height_m", self.mean_base_height_m)?;
        info.set_item("base_xy_m", self.base_xy_m.to_vec())?;
        Ok(info)
    }
}

/// Checks an action's length.
fn check_action(len: usize) -> PyResult<()> {
    if len != ACTION_SIZE {
        return Err(PyValueError::new_err(format!(
            "action has {len} values; the phase action has {ACTION_SIZE} (in [-1, 1])"
        )));
    }
    Ok(())
}

/// One quadwalk task: `reset` and `step` one 0.75 s phase at a time.
#[pyclass(module = "quadwalk._quadwalk")]
pub struct Env {
    scene: Scene,
    /// in a mutex only to make the class `Sync`, as pyo3 asks: methods take
    /// `&mut self` and reach it with `get_mut`, without locking
    task: Mutex<Task>,
    seed: u64,
    obs: Vec<f32>,
    /// the task was built and not yet reset
    fresh: bool,
}

#[pymethods]
impl Env {
    /// `terrain`: a spec (default elastic:5cm); `config`: an experiment
    /// file (its terrain unless `terrain` is given); `seed`: the world's
    /// draw and start positions; `max_phases`: the episode length.
    #[new]
    #[pyo3(signature = (terrain=None, config=None, seed=0, max_phases=None))]
    fn new(
        terrain: Option<&str>,
        config: Option<&str>,
        seed: u64,
        max_phases: Option<usize>,
    ) -> PyResult<Self> {
        let scene = Scene::new(terrain, config, max_phases)?;
        let task = scene.task(seed)?;
        let obs = vec![0.0; task.observation_size()];
        Ok(Self {
            scene,
            task: Mutex::new(task),
            seed,
            obs,
            fresh: true,
        })
    }

    /// Starts an episode; with `seed`, in a world built afresh from it (the
    /// episode `quadwalk rollout --seed SEED` runs). Returns the observation.
    #[pyo3(signature = (seed=None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: Option<u64>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        if let Some(seed) = seed
            && !(self.fresh && seed == self.seed)
        {
            let scene = &self.scene;
            *self.task_mut() = py.detach(|| scene.task(seed))?;
            self.seed = seed;
        }
        let (task, obs) = (Self::unlocked(&mut self.task), &mut self.obs);
        py.detach(|| task.reset(obs));
        self.fresh = false;
        Ok(PyArray1::from_slice(py, &self.obs))
    }

    /// Runs one phase with `action` (27 values in [-1, 1]); returns
    /// (observation, reward, terminated, truncated, info). The GIL is
    /// released while the physics runs.
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        action: Vec<f32>,
    ) -> PyResult<(
        Bound<'py, PyArray1<f32>>,
        f64,
        bool,
        bool,
        Bound<'py, PyDict>,
    )> {
        check_action(action.len())?;
        if self.fresh || self.task_mut().done() {
            return Err(PyRuntimeError::new_err(
                "the episode is over (or never began): call reset() first",
            ));
        }
        let (task, obs) = (Self::unlocked(&mut self.task), &mut self.obs);
        let (outcome, info) = py.detach(|| {
            let outcome = task.step_phase(&action, obs);
            let info = PhaseInfo::new(task, &outcome);
            (outcome, info)
        });
        Ok((
            PyArray1::from_slice(py, &self.obs),
            outcome.reward,
            outcome.termination.is_some(),
            outcome.truncated && outcome.termination.is_none(),
            info.to_dict(py)?,
        ))
    }

    /// Observation values.
    #[getter]
    fn observation_size(&mut self) -> usize {
        self.task_mut().observation_size()
    }

    /// Phases after which an episode is truncated.
    #[getter]
    fn max_phases(&self) -> usize {
        self.scene.experiment.task.max_phases
    }

    /// The terrain spec, canonical.
    #[getter]
    fn terrain(&self) -> String {
        self.scene.experiment.terrain.to_string()
    }

    /// The seed of the current world.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }

    /// The base position, world frame, m.
    #[getter]
    fn base_position_m(&mut self) -> [f64; 3] {
        let p = self.task_mut().world().base_pose().translation.vector;
        [p.x, p.y, p.z]
    }

    /// The current goal's world x, y (what a navigation layer gives a
    /// robot's controller), m.
    #[getter]
    fn goal_xy_m(&mut self) -> [f64; 2] {
        self.task_mut().goal_xy_m()
    }

    /// Where the episode started (x, y), m.
    #[getter]
    fn start_xy_m(&mut self) -> [f64; 2] {
        self.task_mut().start_xy_m()
    }
}

impl Env {
    fn task_mut(&mut self) -> &mut Task {
        Self::unlocked(&mut self.task)
    }

    fn unlocked(task: &mut Mutex<Task>) -> &mut Task {
        task.get_mut().unwrap_or_else(PoisonError::into_inner)
    }

    fn unlocked_all(tasks: &mut Mutex<Vec<Task>>) -> &mut Vec<Task> {
        tasks.get_mut().unwrap_or_else(PoisonError::into_inner)
    }
}

/// When a finished task starts its next episode (Gymnasium's autoreset
/// modes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Autoreset {
    /// on the step after the one that ended it (that step's action is
    /// ignored, its reward 0): Gymnasium's default, RLlib's
    NextStep,
    /// within the step that ended it: the step returns the new episode's
    /// first observation and the last one in `final_obs` (Stable-Baselines3's
    /// convention)
    SameStep,
}

impl Autoreset {
    fn parse(text: &str) -> PyResult<Self> {
        match text {
            "next_step" => Ok(Self::NextStep),
            "same_step" => Ok(Self::SameStep),
            other => Err(PyValueError::new_err(format!(
                "autoreset {other:?}: expected \"next_step\" or \"same_step\""
            ))),
        }
    }
}

/// N tasks stepped in parallel in Rust (the GIL released), with
/// Gymnasium's next-step autoreset (a step given to a task whose episode
/// ended resets it instead: reward 0, not terminated, not truncated) or its
/// same-step autoreset (the step that ends an episode starts the next one).
#[pyclass(module = "quadwalk._quadwalk")]
pub struct VecEnv {
    scene: Scene,
    /// in a mutex only to make the class `Sync` (see [`Env`])
    tasks: Mutex<Vec<Task>>,
    seeds: Vec<u64>,
    obs_size: usize,
    obs: Vec<f32>,
    /// same-step autoreset: each task's last observation of the episode
    /// that ended in the last step (rows of tasks that did not end are 0)
    final_obs: Vec<f32>,
    autoreset: Autoreset,
    pool: rayon::ThreadPool,
    reset_once: bool,
    /// wall time of the last `step`'s parallel phase (the Rust side), s
    last_step_secs: f64,
}

impl VecEnv {
    fn obs_array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        PyArray1::from_slice(py, &self.obs).reshape([self.seeds.len(), self.obs_size])
    }
}

#[pymethods]
impl VecEnv {
    /// `num_envs` tasks; task i's world and starts are drawn from
    /// `seed + i` (the single `Env` with that seed); stepped on `threads`
    /// threads (default: all cores); `autoreset` "next_step" (default) or
    /// "same_step".
    #[new]
    #[pyo3(signature = (num_envs, terrain=None, config=None, seed=0, max_phases=None, threads=None, autoreset="next_step"))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        num_envs: usize,
        terrain: Option<&str>,
        config: Option<&str>,
        seed: u64,
        max_phases: Option<usize>,
        threads: Option<usize>,
        autoreset: &str,
    ) -> PyResult<Self> {
        let autoreset = Autoreset::parse(autoreset)?;
        if num_envs == 0 {
            return Err(PyValueError::new_err(
                "num_envs 0: at least one environment",
            ));
        }
        if threads == Some(0) {
            return Err(PyValueError::new_err("threads 0: at least one thread"));
        }
        let scene = Scene::new(terrain, config, max_phases)?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads.unwrap_or(0))
            .build()
            .map_err(runtime_error)?;
        let seeds: Vec<u64> = (0..num_envs as u64).map(|i| seed.wrapping_add(i)).collect();
        let tasks = py.detach(|| {
            pool.install(|| {
                seeds
                    .par_iter()
                    .map(|&s| scene.task(s))
                    .collect::<PyResult<Vec<_>>>()
            })
        })?;
        let obs_size = tasks[0].observation_size();
        Ok(Self {
            obs: vec![0.0; num_envs * obs_size],
            final_obs: vec![0.0; num_envs * obs_size],
            autoreset,
            scene,
            tasks: Mutex::new(tasks),
            seeds,
            obs_size,
            pool,
            reset_once: false,
            last_step_secs: 0.0,
        })
    }

    /// Starts every task's episode; with `seed`, task i in a world built
    /// afresh from `seed + i`. Returns the observations (num_envs x obs).
    #[pyo3(signature = (seed=None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: Option<u64>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let fresh = !self.reset_once;
        let (scene, pool, obs_size) = (&self.scene, &self.pool, self.obs_size);
        let (tasks, seeds, obs) = (
            Env::unlocked_all(&mut self.tasks),
            &mut self.seeds,
            &mut self.obs,
        );
        py.detach(|| {
            pool.install(|| {
                tasks
                    .par_iter_mut()
                    .zip(seeds.par_iter_mut())
                    .zip(obs.par_chunks_mut(obs_size))
                    .enumerate()
                    .try_for_each(|(i, ((task, task_seed), obs))| {
                        if let Some(seed) = seed {
                            let wanted = seed.wrapping_add(i as u64);
                            if !(fresh && wanted == *task_seed) {
                                *task = scene.task(wanted)?;
                                *task_seed = wanted;
                            }
                        }
                        task.reset(obs);
                        Ok::<_, PyErr>(())
                    })
            })
        })?;
        self.reset_once = true;
        self.obs_array(py)
    }

    /// Runs one phase in every task with `actions` (num_envs x 27). Returns
    /// (observations, rewards, terminated, truncated, infos): infos holds
    /// `reward_terms` (num_envs x 5, in `REWARD_TERMS` order),
    /// `termination` (the cause or None), `region`, `phase`, `autoreset`
    /// (next-step mode: the task was reset by this step, its action ignored);
    /// in same-step mode also `final_obs` (num_envs x obs: the last
    /// observation of each episode that ended in this step, whose task then
    /// started its next one; rows of the others are 0) and `_final_obs`
    /// (which rows hold one).
    #[allow(clippy::type_complexity)]
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<(
        Bound<'py, PyArray2<f32>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyArray1<bool>>,
        Bound<'py, PyDict>,
    )> {
        let n = self.seeds.len();
        let shape = actions.shape().to_vec();
        if shape != [n, ACTION_SIZE] {
            return Err(PyValueError::new_err(format!(
                "actions have shape {shape:?}; expected [{n}, {ACTION_SIZE}] (num_envs x the phase action)"
            )));
        }
        if !self.reset_once {
            return Err(PyRuntimeError::new_err("call reset() before step()"));
        }
        let actions: Vec<f32> = actions.as_array().iter().copied().collect();
        let (pool, obs_size, same_step) = (
            &self.pool,
            self.obs_size,
            self.autoreset == Autoreset::SameStep,
        );
        let (tasks, obs, final_obs) = (
            Env::unlocked_all(&mut self.tasks),
            &mut self.obs,
            &mut self.final_obs,
        );
        let started = Instant::now();
        let results: Vec<Option<(PhaseOutcome, PhaseInfo)>> = py.detach(|| {
            pool.install(|| {
                tasks
                    .par_iter_mut()
                    .zip(obs.par_chunks_mut(obs_size))
                    .zip(final_obs.par_chunks_mut(obs_size))
                    .zip(actions.par_chunks(ACTION_SIZE))
                    .map(|(((task, obs), final_obs), action)| {
                        if task.done() {
                            // next-step mode only: same-step mode resets below
                            task.reset(obs);
                            return None;
                        }
                        let outcome = task.step_phase(action, obs);
                        let info = PhaseInfo::new(task, &outcome);
                        if same_step && task.done() {
                            final_obs.copy_from_slice(obs);
                            task.reset(obs);
                        } else if same_step {
                            final_obs.fill(0.0);
                        }
                        Some((outcome, info))
                    })
                    .collect()
            })
        });
        self.last_step_secs = started.elapsed().as_secs_f64();
        let mut rewards = vec![0.0f64; n];
        let mut terminated = vec![false; n];
        let mut truncated = vec![false; n];
        let mut terms = vec![0.0f64; n * 5];
        let (mut causes, mut regions, mut phases, mut autoreset) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (i, result) in results.iter().enumerate() {
            match result {
                Some((outcome, info)) => {
                    rewards[i] = outcome.reward;
                    terminated[i] = outcome.termination.is_some();
                    truncated[i] = outcome.truncated && outcome.termination.is_none();
                    terms[i * 5..i * 5 + 5].copy_from_slice(&info.terms);
                    causes.push(info.termination.as_ref().map(|t| t.0));
                    regions.push(info.region.clone());
                    phases.push(info.phase);
                    autoreset.push(false);
                }
                None => {
                    causes.push(None);
                    let task = &Env::unlocked_all(&mut self.tasks)[i];
                    let base = task.world().base_pose().translation.vector;
                    let terrain = task.world().terrain();
                    regions.push(
                        terrain.regions()[terrain.region_index_at(base.x, base.y)]
                            .label
                            .clone(),
                    );
                    phases.push(0);
                    autoreset.push(true);
                }
            }
        }
        let infos = PyDict::new(py);
        infos.set_item(
            "reward_terms",
            PyArray1::from_vec(py, terms).reshape([n, 5])?,
        )?;
        infos.set_item("termination", causes)?;
        infos.set_item("region", regions)?;
        infos.set_item("phase", phases)?;
        if same_step {
            let ended: Vec<bool> = terminated
                .iter()
                .zip(&truncated)
                .map(|(&a, &b)| a || b)
                .collect();
            infos.set_item(
                "final_obs",
                PyArray1::from_slice(py, &self.final_obs).reshape([n, self.obs_size])?,
            )?;
            infos.set_item("_final_obs", PyArray1::from_vec(py, ended))?;
        }
        infos.set_item("autoreset", PyArray1::from_vec(py, autoreset))?;
        Ok((
            self.obs_array(py)?,
            PyArray1::from_vec(py, rewards),
            PyArray1::from_vec(py, terminated),
            PyArray1::from_vec(py, truncated),
            infos,
        ))
    }

    /// Wall time the last `step` spent stepping the worlds in Rust, s: the
    /// rest of a `step` call is the Python layer's cost.
    #[getter]
    fn last_step_secs(&self) -> f64 {
        self.last_step_secs
    }

    /// Environments.
    #[getter]
    fn num_envs(&self) -> usize {
        self.seeds.len()
    }

    /// Observation values per environment.
    #[getter]
    fn observation_size(&self) -> usize {
        self.obs_size
    }

    /// Phases after which an episode is truncated.
    #[getter]
    fn max_phases(&self) -> usize {
        self.scene.experiment.task.max_phases
    }

    /// The terrain spec, canonical.
    #[getter]
    fn terrain(&self) -> String {
        self.scene.experiment.terrain.to_string()
    }
}
