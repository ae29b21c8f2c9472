//! One evaluation episode: what is recorded while it runs (an observer on
//! the task's phases and steps) and the record it leaves.
//!
//! Definitions (the paper's, where it gives one):
//! - h_b, the base height: the mean height of the four hip joints above the
//!   terrain right below each (`Task::base_height_m`, the observation's
//!   h_b), sampled after every physics step.
//! - The phase angle: the four-phase cycle FL, RR, FR, RL swing spans
//!   [0, 2 pi), each swing a quarter (FL [0, pi/2] ... RL [3 pi/2, 2 pi], the
//!   paper's Fig. 4). Step i of 180 in a phase whose swing leg has slot s in
//!   that order lies at (s + (i - 1/2) / 180) pi/2, and is binned into 1 degree
//!   bins.
//! - The target landing height of a foot: where the phase's swing-foot
//!   curve sends the foot (its last control point, in the base frame at the
//!   phase start) minus that foot's height in the squat pose, in the same
//!   frame (the paper: "relative to the height of each foot at the default
//!   squat pose"). One value per phase, for the phase's swing foot.
//! - The terrain type of a phase: the label of the terrain region under the
//!   base at the phase's start (`elastic:2cm`, `rigid`); on `varying`
//!   terrain that is the region's surface.
//! - The joints' mechanical energy: the sum over physics steps of
//!   sum_j |tau_j q_dot_j| dt, the PD torque applied in the step times the
//!   joint velocity after it (motors do not recover energy, so negative
//!   work costs as much as positive).
//! - The cost of transport: that energy over m g d, m the robot's mass and
//!   d the distance walked along x (dimensionless; none unless d > 0).
//! - Foot slip: the horizontal speed of each foot's sole (the lowest point
//!   of its sphere, `World::foot_sole_velocities_m_per_s`) times dt, over
//!   the physics steps in which the foot touches the ground
//!   (`World::feet_touching_ground`), summed over the feet: how far the feet
//!   slide, not how far a rolling foot's centre moves.

use std::collections::BTreeMap;

use robot::model::LegName;
use robot::snapshot::{PhaseObserver, PhaseStart};
use robot::task::{PhaseOutcome, SWING_ORDER, Task};
use serde::{Deserialize, Serialize};

use super::response::{ChangeResponse, ResponseTrace};

/// Bins of the phase angle over the four-phase cycle (1 degree each).
pub const ANGLE_BINS: usize = 360;

/// A running count, mean and spread (population standard deviation).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Accumulator {
    /// samples
    pub count: u64,
    /// their sum
    pub sum: f64,
    /// the sum of their squares
    pub sum_sq: f64,
}

impl Accumulator {
    /// Adds one sample.
    pub fn add(&mut self, x: f64) {
        self.count += 1;
        self.sum += x;
        self.sum_sq += x * x;
    }

    /// Adds every sample of `other`.
    pub fn merge(&mut self, other: &Self) {
        self.count += other.count;
        self.sum += other.sum;
        self.sum_sq += other.sum_sq;
    }

    /// The mean; `None` without samples.
    pub fn mean(&self) -> Option<f64> {
        (self.count > 0).then(|| self.sum / self.count as f64)
    }

    /// The population standard deviation; `None` without samples.
    pub fn std(&self) -> Option<f64> {
        let mean = self.mean()?;
        Some(
            (self.sum_sq / self.count as f64 - mean * mean)
                .max(0.0)
                .sqrt(),
        )
    }
}

/// How an episode fell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fall {
    /// `base_too_low`, `pitch_too_large` or `non_foot_contact`
    pub cause: String,
    /// the termination as text, with its value
    pub detail: String,
    /// the links that touched the ground (non-foot contact), else empty
    pub links: Vec<String>,
    /// the phase it fell in (0-based)
    pub phase: usize,
    /// the terrain type of that phase
    pub terrain: String,
    /// the base was within [`TERRAIN_END_MARGIN_M`] of the terrain's far
    /// end: the robot walked off the field (too short for the episode)
    /// rather than falling on it
    #[serde(default)]
    pub at_terrain_end: bool,
    /// the current goal's distance ahead of the base along x at the fall, m
    /// (absent in files written before 2026-12-01); just after a goal is
    /// reached the next one is `goal_spacing_m` (2 m) ahead
    #[serde(default)]
    pub goal_ahead_m: Option<f64>,
}

/// How close to the terrain's far end (its extent's largest x) a fall counts
/// as walking off the field: the front feet reach ~0.4 m ahead of the base,
/// and a step is ~0.1 m.
pub const TERRAIN_END_MARGIN_M: f64 = 1.0;

/// Whether the base is within [`TERRAIN_END_MARGIN_M`] of the far end of
/// `task`'s terrain.
pub fn near_terrain_end(task: &Task) -> bool {
    let base_x_m = task.world().base_pose().translation.vector.x;
    base_x_m >= task.world().terrain().extent().max_m[0] - TERRAIN_END_MARGIN_M
}

/// What to do about a fall at the terrain's end, for an episode of
/// `phases` phases.
pub fn terrain_end_advice(phases: impl std::fmt::Display) -> String {
    format!(
        "the field is too short for {phases} phases; give it a longer one (e.g. length=80m on a tile terrain)"
    )
}

impl Fall {
    /// The detail, with where it happened when that was the terrain's end.
    pub fn describe(&self) -> String {
        if self.at_terrain_end {
            format!("{} at the end of the terrain", self.detail)
        } else {
            self.detail.clone()
        }
    }
}

/// One phase of an episode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseRecord {
    /// the swing leg (`FL`, `RR`, `FR`, `RL`)
    pub swing: String,
    /// the terrain type under the base at the phase's start
    pub terrain: String,
    /// mean h_b over the phase's steps, m
    pub mean_base_height_m: f64,
    /// the swing foot's target landing height relative to its squat height, m
    pub landing_height_m: f64,
    /// how far the base moved along x during the phase, m
    pub distance_m: f64,
}

/// What one terrain type saw in an episode (or, merged, in many).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TerrainSamples {
    /// phases whose terrain type this is
    pub phases: usize,
    /// distance walked along x in those phases, m
    pub distance_m: f64,
    /// falls in those phases, by cause
    pub falls: BTreeMap<String, usize>,
    /// h_b at every physics step, m
    pub base_height_m: Accumulator,
    /// h_b binned by phase angle ([`ANGLE_BINS`] bins), m
    pub base_height_by_angle_m: Vec<Accumulator>,
    /// target landing heights relative to the squat, per swing foot in
    /// [`LegName::ALL`] order (FR, FL, RR, RL), m
    pub landing_height_m: [Accumulator; 4],
}

impl Default for TerrainSamples {
    fn default() -> Self {
        Self {
            phases: 0,
            distance_m: 0.0,
            falls: BTreeMap::new(),
            base_height_m: Accumulator::default(),
            base_height_by_angle_m: vec![Accumulator::default(); ANGLE_BINS],
            landing_height_m: [Accumulator::default(); 4],
        }
    }
}

impl TerrainSamples {
    /// Adds everything `other` saw.
    pub fn merge(&mut self, other: &Self) {
        self.phases += other.phases;
        self.distance_m += other.distance_m;
        for (cause, n) in &other.falls {
            *self.falls.entry(cause.clone()).or_default() += n;
        }
        self.base_height_m.merge(&other.base_height_m);
        for (a, b) in self
            .base_height_by_angle_m
            .iter_mut()
            .zip(&other.base_height_by_angle_m)
        {
            a.merge(b);
        }
        for (a, b) in self
            .landing_height_m
            .iter_mut()
            .zip(&other.landing_height_m)
        {
            a.merge(b);
        }
    }

    /// Records one physics step's h_b at `step_in_phase` (1-based, of
    /// `steps_per_phase`) of a phase whose swing leg is `swing`.
    pub fn add_step(
        &mut self,
        swing: LegName,
        step_in_phase: usize,
        steps_per_phase: usize,
        base_height_m: f64,
    ) {
        self.base_height_m.add(base_height_m);
        self.base_height_by_angle_m[angle_bin(swing, step_in_phase, steps_per_phase)]
            .add(base_height_m);
    }
}

/// The phase-angle bin of step `step_in_phase` (1-based) of a phase
/// swinging `swing`: the bin holding (slot + (i - 1/2) / steps) * 90 degrees.
pub fn angle_bin(swing: LegName, step_in_phase: usize, steps_per_phase: usize) -> usize {
    let slot = SWING_ORDER.iter().position(|&l| l == swing).unwrap_or(0);
    let within = (step_in_phase as f64 - 0.5) / steps_per_phase as f64;
    let per_phase = ANGLE_BINS / 4;
    slot * per_phase + ((within * per_phase as f64) as usize).min(per_phase - 1)
}

/// One evaluation episode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EpisodeRecord {
    /// the episode's seed (start position, terrain draw)
    pub seed: u64,
    /// where the base started, m
    pub start_xy_m: [f64; 2],
    /// phases run (until the fall, or all of them)
    pub phases: usize,
    /// distance along the walking direction (+x), m
    pub distance_m: f64,
    /// sideways drift, m
    pub lateral_drift_m: f64,
    /// distance over the phases' simulated time, m/s
    pub mean_speed_m_per_s: f64,
    /// goals reached
    pub goals_reached: usize,
    /// the fall, if it fell
    pub fall: Option<Fall>,
    /// mean over physics steps of the joint torques' norm (tau_ave), N m
    pub mean_torque_n_m: f64,
    /// the joints' mechanical energy, J (absent in files written before
    /// 2026-12-02)
    #[serde(default)]
    pub mechanical_energy_j: f64,
    /// mechanical energy / (m g distance); `None` unless it walked forward
    #[serde(default)]
    pub cost_of_transport: Option<f64>,
    /// horizontal travel of the feet while touching the ground, m
    #[serde(default)]
    pub foot_slip_m: f64,
    /// the robot's weight m g, N
    #[serde(default)]
    pub robot_weight_n: f64,
    /// the episode's return
    pub reward_total: f64,
    /// on a terrain that changes by itself: when, s after its reset
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub terrain_change_secs: Option<f64>,
    /// and the robot's response to it (`None` if it fell or the episode
    /// ended before the response's window did)
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub change_response: Option<ChangeResponse>,
    /// every phase
    pub phase_log: Vec<PhaseRecord>,
    /// the samples of each terrain type this episode walked on (in memory
    /// only: the evaluation's summary carries them merged)
    #[serde(skip)]
    pub by_terrain: BTreeMap<String, TerrainSamples>,
}

impl EpisodeRecord {
    /// Whether the episode ran all its phases without falling.
    pub fn succeeded(&self) -> bool {
        self.fall.is_none()
    }
}

/// Records an episode as the task runs it: attach to
/// `Task::step_phase_observed`.
#[derive(Default)]
pub struct EpisodeRecorder {
    by_terrain: BTreeMap<String, TerrainSamples>,
    phase_log: Vec<PhaseRecord>,
    torque_norm: Accumulator,
    current: Option<(LegName, String, f64)>,
    fall: Option<Fall>,
    mechanical_energy_j: f64,
    foot_slip_m: f64,
    /// the robot's mass, kg (read in the first step)
    mass_kg: f64,
    /// the world's physics step, s (read in the first step)
    dt_secs: f64,
    /// on a terrain that changes by itself: the base heights around the
    /// first change
    response: Option<ResponseTrace>,
}

impl EpisodeRecorder {
    fn terrain_label(task: &Task) -> String {
        let base = task.world().base_pose().translation.vector;
        let terrain = task.world().terrain();
        terrain.regions()[terrain.region_index_at(base.x, base.y)]
            .label
            .clone()
    }

    /// The record of the episode just run.
    #[allow(clippy::too_many_arguments)]
    pub fn finish(
        self,
        seed: u64,
        start_xy_m: [f64; 2],
        end_xy_m: [f64; 2],
        goals_reached: usize,
        reward_total: f64,
        phase_secs: f64,
    ) -> EpisodeRecord {
        let distance_m = end_xy_m[0] - start_xy_m[0];
        let phases = self.phase_log.len();
        let weight_n = self.mass_kg * terrain_plugins::STANDARD_GRAVITY_M_PER_S2;
        EpisodeRecord {
            seed,
            start_xy_m,
            phases,
            distance_m,
            lateral_drift_m: end_xy_m[1] - start_xy_m[1],
            mean_speed_m_per_s: if phases > 0 {
                distance_m / (phases as f64 * phase_secs)
            } else {
                0.0
            },
            goals_reached,
            fall: self.fall,
            mean_torque_n_m: self.torque_norm.mean().unwrap_or(0.0),
            mechanical_energy_j: self.mechanical_energy_j,
            cost_of_transport: (distance_m > 0.0 && weight_n > 0.0)
                .then(|| self.mechanical_energy_j / (weight_n * distance_m)),
            foot_slip_m: self.foot_slip_m,
            robot_weight_n: weight_n,
            reward_total,
            terrain_change_secs: self.response.as_ref().map(|t| t.at_secs),
            change_response: self
                .response
                .as_ref()
                .and_then(|t| t.response(self.dt_secs)),
            phase_log: self.phase_log,
            by_terrain: self.by_terrain,
        }
    }
}

impl PhaseObserver for EpisodeRecorder {
    fn phase_started(&mut self, task: &Task, start: &PhaseStart) {
        let label = Self::terrain_label(task);
        let swing = start.swing_leg;
        let squat_z_m = task.squat_feet_in_base_m()[swing.index()].z;
        let landing_m = start.curves.swing_foot.points[3].z - squat_z_m;
        let samples = self.by_terrain.entry(label.clone()).or_default();
        samples.phases += 1;
        samples.landing_height_m[swing.index()].add(landing_m);
        self.phase_log.push(PhaseRecord {
            swing: swing.short().to_string(),
            terrain: label.clone(),
            mean_base_height_m: 0.0,
            landing_height_m: landing_m,
            distance_m: 0.0,
        });
        self.current = Some((swing, label, start.base_start.translation.vector.x));
    }

    fn stepped(&mut self, task: &Task, step_in_phase: usize) {
        let Some((swing, label, _)) = &self.current else {
            return;
        };
        let world = task.world();
        let torques = world.applied_torques_n_m();
        self.torque_norm
            .add(torques.iter().map(|t| t * t).sum::<f64>().sqrt());
        let power_w: f64 = torques
            .iter()
            .zip(world.joint_velocities_rad_per_s())
            .map(|(tau, qd)| (tau * qd).abs())
            .sum();
        self.mechanical_energy_j += power_w * world.dt_secs();
        if self.mass_kg == 0.0 {
            self.mass_kg = world.model().total_mass_kg();
            self.dt_secs = world.dt_secs();
            self.response = world
                .terrain()
                .change_times_secs()
                .first()
                .map(|&at| ResponseTrace::new(at));
        }
        if let Some(trace) = &mut self.response {
            // the base above the ground at rest below it (see `response`)
            let base = world.base_pose().translation.vector;
            trace.add(
                world.secs_since_terrain_reset(),
                base.z - world.rest_height_m(base.x, base.y),
            );
        }
        let touching = world.feet_touching_ground();
        for (sole, _) in world
            .foot_sole_velocities_m_per_s()
            .iter()
            .zip(touching)
            .filter(|(_, touches)| *touches)
        {
            self.foot_slip_m += sole.x.hypot(sole.y) * world.dt_secs();
        }
        if let Some(samples) = self.by_terrain.get_mut(label) {
            samples.add_step(
                *swing,
                step_in_phase,
                world.steps_per_phase(),
                task.base_height_m(),
            );
        }
    }

    fn phase_ended(&mut self, task: &Task, outcome: &PhaseOutcome) {
        let Some((_, label, start_x_m)) = self.current.take() else {
            return;
        };
        let distance_m = task.world().base_pose().translation.vector.x - start_x_m;
        if let Some(record) = self.phase_log.last_mut() {
            record.mean_base_height_m = outcome.mean_base_height_m;
            record.distance_m = distance_m;
        }
        let samples = self.by_terrain.entry(label.clone()).or_default();
        samples.distance_m += distance_m;
        if let Some(termination) = &outcome.termination {
            *samples
                .falls
                .entry(termination.kind().to_string())
                .or_default() += 1;
            self.fall = Some(Fall {
                cause: termination.kind().to_string(),
                detail: termination.to_string(),
                links: match termination {
                    robot::task::Termination::NonFootContact { links } => links.clone(),
                    _ => Vec::new(),
                },
                phase: self.phase_log.len() - 1,
                terrain: label,
                at_terrain_end: near_terrain_end(task),
                goal_ahead_m: Some(
                    task.goal_xy_m()[0] - task.world().base_pose().translation.vector.x,
                ),
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_accumulator_gives_mean_and_population_spread() {
        let mut a = Accumulator::default();
        assert_eq!(a.mean(), None);
        for x in [2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0] {
            a.add(x);
        }
        assert!((a.mean().unwrap() - 5.0).abs() < 1e-12);
        assert!((a.std().unwrap() - 2.0).abs() < 1e-12);
        let mut b = Accumulator::default();
        b.add(5.0);
        a.merge(&b);
        assert_eq!(a.count, 9);
        assert!((a.mean().unwrap() - 5.0).abs() < 1e-12);
    }

    #[test]
    fn steps_fall_into_the_papers_phase_angle_quarters() {
        // FL swings in [0, 90) degrees, RR in [90, 180), FR in [180, 270),
        // RL in [270, 360): the paper's Fig. 4 order.
        assert_eq!(angle_bin(LegName::FrontLeft, 1, 180), 0);
        assert_eq!(angle_bin(LegName::FrontLeft, 2, 180), 0);
        assert_eq!(angle_bin(LegName::FrontLeft, 3, 180), 1);
        assert_eq!(angle_bin(LegName::FrontLeft, 180, 180), 89);
        assert_eq!(angle_bin(LegName::RearRight, 1, 180), 90);
        assert_eq!(angle_bin(LegName::FrontRight, 90, 180), 180 + 44);
        assert_eq!(angle_bin(LegName::RearLeft, 180, 180), 359);
        // every bin of a quarter gets the same number of steps
        let mut counts = [0usize; 90];
        for i in 1..=180 {
            counts[angle_bin(LegName::FrontLeft, i, 180)] += 1;
        }
        assert!(counts.iter().all(|&c| c == 2));
    }
}
