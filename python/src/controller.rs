//! The phase-level controller (`robot::controller`) and a bare simulated
//! robot, from Python: the deployment loop a real robot runs around a
//! policy (quadwalk's or its ONNX file), and quadwalk's world as the robot
//! it can be tried on.
//!
//! A state is a dict (world frame, SI units):
//!
//! | key | shape | |
//! | --- | --- | --- |
//! | `base_position_m` | 3 | |
//! | `base_orientation_xyzw` | 4 | unit quaternion |
//! | `base_linear_velocity_m_per_s` | 3 | |
//! | `base_angular_velocity_rad_per_s` | 3 | |
//! | `hip_heights_m` | 4 | each hip above the ground below it, FR FL RR RL |
//! | `feet_in_world_m` | 4 x 3 | or, instead, `joint_angles_rad` (12): the feet by forward kinematics |
//! | `centre_of_mass_m` | 3 | needed only with the scripted-crawl action prior |
//! | `height_scan_m` | 18 | needed only with `height_scan` on: the base's height above the ground at the points ahead of it (`robot::height_scan`) |
//!
//! `Sim.state()` gives every key (and `joint_angles_rad`,
//! `joint_velocities_rad_per_s`).

use std::sync::Mutex;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use robot::RobotModel;
use robot::WorldConfig;
use robot::action::ACTION_SIZE;
use robot::controller::{PhaseController, PhasePlan, RobotState};
use robot::height_scan::HEIGHT_SCAN_POINTS;
use robot::task::{Task, TaskConfig};
use robot::world::World;

use crate::scene::{Scene, registry, value_error};

/// A 3-vector from `state[key]`.
fn vector(state: &Bound<'_, PyDict>, key: &str) -> PyResult<Vector3<f64>> {
    let values = values(state, key, 3)?;
    Ok(Vector3::new(values[0], values[1], values[2]))
}

/// `n` floats from `state[key]` (any sequence or array, flattened).
fn values(state: &Bound<'_, PyDict>, key: &str, n: usize) -> PyResult<Vec<f64>> {
    let item = state
        .get_item(key)?
        .ok_or_else(|| PyValueError::new_err(format!("state: no {key:?}")))?;
    let numpy = item.py().import("numpy")?;
    let flat = numpy
        .call_method1("asarray", (item, "float64"))?
        .call_method0("ravel")?;
    let list: Vec<f64> = flat
        .extract()
        .map_err(|e| PyValueError::new_err(format!("state[{key:?}]: {e}")))?;
    if list.len() != n {
        return Err(PyValueError::new_err(format!(
            "state[{key:?}] has {} values; it takes {n}",
            list.len()
        )));
    }
    Ok(list)
}

/// The controller's [`RobotState`] from a state dict.
fn robot_state(
    controller: &PhaseController,
    state: &Bound<'_, PyDict>,
    needs_com: bool,
    needs_scan: bool,
) -> PyResult<RobotState> {
    let q = values(state, "base_orientation_xyzw", 4)?;
    let quaternion = Quaternion::new(q[3], q[0], q[1], q[2]);
    let norm = quaternion.norm();
    let unit = (norm - 1.0).abs() < 1e-6;
    if !unit {
        return Err(PyValueError::new_err(format!(
            "state[\"base_orientation_xyzw\"]: not a unit quaternion (norm {norm})"
        )));
    }
    // as given, not renormalised: a state read from quadwalk keeps its bits
    let rotation = UnitQuaternion::new_unchecked(quaternion);
    let base_pose = Isometry3::from_parts(
        Translation3::from(vector(state, "base_position_m")?),
        rotation,
    );
    let hips = values(state, "hip_heights_m", 4)?;
    let feet_in_world_m = if state.contains("feet_in_world_m")? {
        let f = values(state, "feet_in_world_m", 12)?;
        std::array::from_fn(|leg| Vector3::new(f[3 * leg], f[3 * leg + 1], f[3 * leg + 2]))
    } else if state.contains("joint_angles_rad")? {
        let q = values(state, "joint_angles_rad", controller.joint_count())?;
        RobotState::feet_by_kinematics(controller.legs(), controller.leg_joints(), &base_pose, &q)
    } else {
        return Err(PyValueError::new_err(
            "state: give feet_in_world_m (4 x 3) or joint_angles_rad (12)",
        ));
    };
    let centre_of_mass_m = if needs_com {
        vector(state, "centre_of_mass_m").map_err(|e| {
            PyValueError::new_err(format!("{e} (the scripted-crawl prior reads it)"))
        })?
    } else if state.contains("centre_of_mass_m")? {
        vector(state, "centre_of_mass_m")?
    } else {
        Vector3::zeros()
    };
    let height_scan_m = if needs_scan || state.contains("height_scan_m")? {
        let scan = values(state, "height_scan_m", HEIGHT_SCAN_POINTS).map_err(|e| {
            if needs_scan {
                PyValueError::new_err(format!("{e} (the observation's height scan reads it)"))
            } else {
                e
            }
        })?;
        Some(std::array::from_fn(|k| scan[k]))
    } else {
        None
    };
    Ok(RobotState {
        base_pose,
        base_linear_velocity_m_per_s: vector(state, "base_linear_velocity_m_per_s")?,
        base_angular_velocity_rad_per_s: vector(state, "base_angular_velocity_rad_per_s")?,
        feet_in_world_m,
        hip_heights_m: [hips[0], hips[1], hips[2], hips[3]],
        centre_of_mass_m,
        height_scan_m,
    })
}

/// The phase-level controller: observation, phase plan and joint targets
/// from the robot's measured state, as quadwalk's task computes them.
#[pyclass(module = "quadwalk._quadwalk")]
pub struct Controller {
    inner: PhaseController,
    needs_com: bool,
    needs_scan: bool,
    plan: Option<PhasePlan>,
}

impl Controller {
    fn of_task(task: &TaskConfig, physics: &WorldConfig) -> PyResult<Self> {
        let inner = PhaseController::for_model(
            &RobotModel::laikago(),
            task.observation,
            task.action_prior,
            task.swing_height_reference,
        )
        .map_err(value_error)?
        .with_step_rate_hz(physics.step_rate_hz)
        .ok_or_else(|| {
            PyValueError::new_err(format!(
                "step_rate_hz = {} is not a rate a world can step at",
                physics.step_rate_hz
            ))
        })?;
        Ok(Self {
            inner,
            needs_com: task.action_prior != robot::task::ActionPrior::None,
            needs_scan: task.observation.height_scan,
            plan: None,
        })
    }

    fn state(&self, state: &Bound<'_, PyDict>) -> PyResult<RobotState> {
        robot_state(&self.inner, state, self.needs_com, self.needs_scan)
    }

    fn plan(&self) -> PyResult<&PhasePlan> {
        self.plan
            .as_ref()
            .ok_or_else(|| PyValueError::new_err("no phase planned: call plan_phase first"))
    }
}

#[pymethods]
impl Controller {
    /// The controller of the built-in Laikago with the task settings of
    /// the experiment file `config` (its observation, action prior and
    /// swing-height origin; default: quadwalk's).
    #[new]
    #[pyo3(signature = (config=None))]
    fn new(config: Option<&str>) -> PyResult<Self> {
        let scene = Scene::new(None, config, None)?;
        Self::of_task(&scene.experiment.task, &scene.experiment.physics)
    }

    /// The controller a trained policy (an exported policy, a run or a
    /// checkpoint) acts through: its observation layout, action prior and
    /// swing-height origin (those of its last stage).
    #[staticmethod]
    fn for_policy(path: &str) -> PyResult<Self> {
        let policy = experiment::Policy::from_arg(&registry(), path, None).map_err(value_error)?;
        let experiment::Policy::Trained { task, physics, .. } = policy else {
            return Err(PyValueError::new_err(format!(
                "policy {path:?} is not a trained phase-level policy (the scripted crawl and residual policies are not)"
            )));
        };
        Self::of_task(&task, &physics)
    }

    /// Observation values.
    #[getter]
    fn observation_size(&self) -> usize {
        self.inner.observation_size()
    }

    /// The phase about to run (between phases) or running.
    #[getter]
    fn phase(&self) -> usize {
        self.inner.phase()
    }

    /// The swing leg of the phase about to run: "FR", "FL", "RR" or "RL".
    #[getter]
    fn swing_leg(&self) -> &'static str {
        self.inner.swing_leg().short()
    }

    /// The squat an episode starts from: the 12 joint angles, rad.
    #[getter]
    fn squat_joint_angles_rad(&self) -> Vec<f64> {
        self.inner.squat_rad().to_vec()
    }

    /// The feet in the base frame in the squat, FR FL RR RL, m (4 x 3).
    #[getter]
    fn squat_feet_in_base_m(&self) -> Vec<[f64; 3]> {
        self.inner
            .squat_feet_in_base_m()
            .iter()
            .map(|f| [f.x, f.y, f.z])
            .collect()
    }

    /// Each leg's hip (abduction) joint in the base frame, FR FL RR RL, m
    /// (4 x 3): where a robot measures h_b from.
    #[getter]
    fn hips_in_base_m(&self) -> Vec<[f64; 3]> {
        self.inner
            .legs()
            .iter()
            .map(|l| [l.abduction_m.x, l.abduction_m.y, l.abduction_m.z])
            .collect()
    }

    /// Control steps per phase: 0.75 s at the physics rate of the
    /// config or policy (180 at the paper's 240 Hz).
    #[getter]
    fn samples_per_phase(&self) -> usize {
        self.inner.steps_per_phase()
    }

    /// Seconds per control step (1/240 at the paper's rate).
    #[getter]
    fn control_step_secs(&self) -> f64 {
        self.inner.dt_secs()
    }

    /// Starts an episode at `state`.
    fn begin_episode(&mut self, state: &Bound<'_, PyDict>) -> PyResult<()> {
        let state = self.state(state)?;
        self.inner.begin_episode(&state);
        self.plan = None;
        Ok(())
    }

    /// The policy's observation (float32) at `state`, heading for the
    /// goal at world `goal_xy_m`.
    fn observe<'py>(
        &self,
        py: Python<'py>,
        state: &Bound<'py, PyDict>,
        goal_xy_m: [f64; 2],
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let state = self.state(state)?;
        let mut obs = vec![0.0; self.inner.observation_size()];
        self.inner.observe(&state, goal_xy_m, &mut obs);
        Ok(PyArray1::from_vec(py, obs))
    }

    /// Plans the phase about to run from the policy's `action` (27 values)
    /// at `state`.
    fn plan_phase(
        &mut self,
        action: PyReadonlyArray1<'_, f32>,
        state: &Bound<'_, PyDict>,
    ) -> PyResult<()> {
        let action = action.as_slice().map_err(value_error)?;
        if action.len() != ACTION_SIZE {
            return Err(PyValueError::new_err(format!(
                "action has {} values; it takes {ACTION_SIZE}",
                action.len()
            )));
        }
        let state = self.state(state)?;
        self.plan = Some(self.inner.plan_phase(action, &state));
        Ok(())
    }

    /// The joint targets (rad, the robot's 12 joints in order) of control
    /// step `sample` (1 to `samples_per_phase`) of the planned phase.
    fn joint_targets<'py>(
        &self,
        py: Python<'py>,
        sample: usize,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let samples = self.inner.steps_per_phase();
        if !(1..=samples).contains(&sample) {
            return Err(PyValueError::new_err(format!(
                "sample {sample}: a phase has samples 1 to {samples}"
            )));
        }
        let plan = self.plan()?;
        let mut targets = vec![0.0; self.inner.joint_count()];
        self.inner.joint_targets(plan, sample, &mut targets);
        Ok(PyArray1::from_vec(py, targets))
    }

    /// Remembers the feet at `state`, the state before a control step.
    fn record_step(&mut self, state: &Bound<'_, PyDict>) -> PyResult<()> {
        let feet = self.state(state)?.feet_in_base_m();
        self.inner.record_step(feet);
        Ok(())
    }

    /// Ends the planned phase.
    fn end_phase(&mut self) -> PyResult<()> {
        let plan = self.plan.take();
        let plan =
            plan.ok_or_else(|| PyValueError::new_err("no phase planned: call plan_phase first"))?;
        self.inner.end_phase(&plan);
        Ok(())
    }
}

/// quadwalk's world without the task: a simulated robot that a
/// [`Controller`] drives step by step (`state()`, `step(targets)`). Its
/// episodes start as the environment's with the same seed do.
#[pyclass(module = "quadwalk._quadwalk")]
pub struct Sim {
    /// the environment's task, whose reset places and settles the robot;
    /// in a mutex only to make the class `Sync`, reached with `get_mut`
    task: Mutex<Task>,
}

impl Sim {
    fn world(&mut self) -> &mut World {
        self.task
            .get_mut()
            .unwrap_or_else(|e| e.into_inner())
            .world_mut()
    }
}

#[pymethods]
impl Sim {
    /// The world `quadwalk.make_env(terrain, config, seed)` steps (same
    /// terrain draw, physics and start positions).
    #[new]
    #[pyo3(signature = (terrain=None, config=None, seed=0))]
    fn new(terrain: Option<&str>, config: Option<&str>, seed: u64) -> PyResult<Self> {
        let scene = Scene::new(terrain, config, None)?;
        Ok(Self {
            task: Mutex::new(scene.task(seed)?),
        })
    }

    /// Starts an episode as the environment's `reset()` does: fresh
    /// terrain, the robot in its squat at the next drawn start, settled.
    fn reset(&mut self, py: Python<'_>) {
        let task = self.task.get_mut().unwrap_or_else(|e| e.into_inner());
        py.detach(|| {
            let mut obs = vec![0.0; task.observation_size()];
            task.reset(&mut obs);
        });
    }

    /// One physics step, s (1/240 at the paper's rate).
    #[getter]
    fn dt_secs(&mut self) -> f64 {
        self.world().dt_secs()
    }

    /// Sets the PD targets (rad, 12) and takes one physics step (1/240 s
    /// at the paper's rate, the config's `[physics] step_rate_hz`).
    fn step(&mut self, targets_rad: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let targets = targets_rad.as_slice().map_err(value_error)?.to_vec();
        let world = self.world();
        if targets.len() != world.joint_targets_rad().len() {
            return Err(PyValueError::new_err(format!(
                "targets have {} values; the robot has {} joints",
                targets.len(),
                world.joint_targets_rad().len()
            )));
        }
        world.set_joint_targets_rad(&targets);
        world.step();
        Ok(())
    }

    /// The robot's state (the keys in the module docs, and its joint
    /// angles and velocities).
    fn state<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let world = self.world();
        let s = RobotState::of_world_scanned(world);
        let d = PyDict::new(py);
        let v = |v: Vector3<f64>| [v.x, v.y, v.z];
        d.set_item("base_position_m", v(s.base_pose.translation.vector))?;
        let q = s.base_pose.rotation.quaternion();
        d.set_item("base_orientation_xyzw", [q.i, q.j, q.k, q.w])?;
        d.set_item(
            "base_linear_velocity_m_per_s",
            v(s.base_linear_velocity_m_per_s),
        )?;
        d.set_item(
            "base_angular_velocity_rad_per_s",
            v(s.base_angular_velocity_rad_per_s),
        )?;
        d.set_item("hip_heights_m", s.hip_heights_m)?;
        d.set_item("feet_in_world_m", s.feet_in_world_m.map(v))?;
        d.set_item("centre_of_mass_m", v(s.centre_of_mass_m))?;
        d.set_item("height_scan_m", s.height_scan_m)?;
        d.set_item("joint_angles_rad", world.joint_positions_rad())?;
        d.set_item(
            "joint_velocities_rad_per_s",
            world.joint_velocities_rad_per_s(),
        )?;
        Ok(d)
    }

    /// Simulated time, s.
    #[getter]
    fn time_secs(&mut self) -> f64 {
        self.world().time_secs()
    }
}
