//! Plain snapshots of a running task for viewers and loggers, and the hook
//! through which a phase reports its progress.
//!
//! Nothing here knows about any viewer: a logger (the `viz` crate streams to
//! Rerun) implements [`PhaseObserver`], is handed to
//! [`crate::task::Task::step_phase_observed`], and builds a
//! [`StepSnapshot`] with [`crate::task::Task::snapshot`] whenever it wants
//! one. Every position is in the world frame, in metres; angles in radians.

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use terrain_plugins::TileState;

use crate::action::PhaseCurves;
use crate::model::LegName;
use crate::task::{PhaseOutcome, Task};

/// The state of the robot, its surroundings and its controller at one
/// physics step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepSnapshot {
    /// simulated time since the world was made, s
    pub sim_time_s: f64,
    /// index of the phase this step belongs to (phases run before it in this
    /// episode)
    pub phase: usize,
    /// every model body's pose (model body order; body 0 is the base)
    pub body_poses: Vec<Isometry3<f64>>,
    /// base roll, pitch, yaw (nalgebra's Euler angles), rad
    pub base_rpy_rad: [f64; 3],
    /// mean hip height above the ground below each hip (h_b), m
    pub base_height_m: f64,
    /// PD torque of every actuated joint (joint order), N m
    pub joint_torques_n_m: Vec<f64>,
    /// where the robot touches the ground, with the leg whose foot it is
    pub contact_points_m: Vec<(Vector3<f64>, Option<usize>)>,
    /// tiles whose centre lies in the square around the base that the caller
    /// asked for (empty on terrains without tiles)
    pub tiles: Vec<TileState>,
    /// the current goal, x and y, m (`None` where there is no task, e.g.
    /// `stand`)
    pub goal_xy_m: Option<[f64; 2]>,
    /// the point the observation's goal blocks show when it is not the
    /// current goal (`[task.observation] goal_line_ahead_m`), x and y, m
    pub observed_goal_xy_m: Option<[f64; 2]>,
    /// the points of the observation's height scan on the ground (x, y and
    /// the surface's height there), m; empty where the task does not
    /// observe one (`[task.observation] height_scan`)
    pub height_scan_points_m: Vec<[f64; 3]>,
}

/// What a phase is about to do: its three curves and where they are.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseStart {
    /// index of the phase in its episode
    pub phase: usize,
    /// simulated time at the phase start, s
    pub sim_time_s: f64,
    /// the leg that swings
    pub swing_leg: LegName,
    /// the base pose at the phase start: the frame of the curves
    pub base_start: Isometry3<f64>,
    /// the phase's curves (base frame at the phase start)
    pub curves: PhaseCurves,
}

impl PhaseStart {
    /// The base position curve sampled at `samples` + 1 evenly spaced
    /// parameters, world frame, m.
    pub fn base_curve_m(&self, samples: usize) -> Vec<Vector3<f64>> {
        sample(samples)
            .map(|t| (self.base_start * Point3::from(self.curves.base_position.at(t))).coords)
            .collect()
    }

    /// The base target pose (position and orientation curves together) at
    /// `samples` + 1 evenly spaced parameters, world frame.
    pub fn base_targets(&self, samples: usize) -> Vec<Isometry3<f64>> {
        sample(samples)
            .map(|t| {
                let rpy = self.curves.base_orientation.at(t);
                self.base_start
                    * Isometry3::from_parts(
                        Translation3::from(self.curves.base_position.at(t)),
                        UnitQuaternion::from_euler_angles(rpy.x, rpy.y, rpy.z),
                    )
            })
            .collect()
    }

    /// The swing foot curve sampled at `samples` + 1 evenly spaced
    /// parameters, world frame, m.
    pub fn swing_foot_curve_m(&self, samples: usize) -> Vec<Vector3<f64>> {
        sample(samples)
            .map(|t| (self.base_start * Point3::from(self.curves.swing_foot.at(t))).coords)
            .collect()
    }

    /// Where the swing foot is sent to land (its last control point), world
    /// frame, m.
    pub fn landing_m(&self) -> Vector3<f64> {
        (self.base_start * Point3::from(self.curves.swing_foot.points[3])).coords
    }
}

fn sample(samples: usize) -> impl Iterator<Item = f64> {
    let n = samples.max(1);
    (0..=n).map(move |i| i as f64 / n as f64)
}

/// Told what a phase does as it runs. Every method has an empty default.
pub trait PhaseObserver {
    /// An episode begins: the task is reset and settled, no phase has run.
    /// Told by whoever runs the whole episode (`Task` itself does not), as
    /// an evaluation does for a video of its episode.
    fn episode_started(&mut self, _task: &Task) {}
    /// Before the first physics step of a phase.
    fn phase_started(&mut self, _task: &Task, _start: &PhaseStart) {}
    /// After physics step `step_in_phase` (1-based) of the running phase.
    fn stepped(&mut self, _task: &Task, _step_in_phase: usize) {}
    /// After the phase ended (all its steps, or the step that terminated
    /// it); `task.phase()` already counts it.
    fn phase_ended(&mut self, _task: &Task, _outcome: &PhaseOutcome) {}
}

/// An observer that does nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoObserver;

impl PhaseObserver for NoObserver {}

/// Two observers told the same things, in order.
pub struct Both<'a>(pub &'a mut dyn PhaseObserver, pub &'a mut dyn PhaseObserver);

impl PhaseObserver for Both<'_> {
    fn episode_started(&mut self, task: &Task) {
        self.0.episode_started(task);
        self.1.episode_started(task);
    }

    fn phase_started(&mut self, task: &Task, start: &PhaseStart) {
        self.0.phase_started(task, start);
        self.1.phase_started(task, start);
    }

    fn stepped(&mut self, task: &Task, step_in_phase: usize) {
        self.0.stepped(task, step_in_phase);
        self.1.stepped(task, step_in_phase);
    }

    fn phase_ended(&mut self, task: &Task, outcome: &PhaseOutcome) {
        self.0.phase_ended(task, outcome);
        self.1.phase_ended(task, outcome);
    }
}
