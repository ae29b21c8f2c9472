//! The phase-level controller on its own: what a real robot (or another
//! simulator) runs around a quadwalk policy, without rapier.
//!
//! Given the robot's measured state ([`RobotState`]: base pose and
//! velocity, foot positions, hip heights), the [`PhaseController`] builds
//! the policy's observation, turns the policy's 27-D action into the
//! phase's three Bezier curves ([`PhasePlan`]) and yields, for each of the
//! phase's control steps (180 at the paper's 240 Hz;
//! [`PhaseController::with_step_rate_hz`] sets another rate), the twelve
//! joint targets the PD loop tracks (IK of each foot in the target base
//! frame). It keeps the
//! memory the observation needs (foot positions at the last three phase
//! starts and 1 and 2 steps ago, the phase counter).
//!
//! quadwalk's own [`crate::task::Task`] drives its world through this
//! controller, so the controller driven by quadwalk's world is `quadwalk
//! rollout`, bit for bit. A robot's loop:
//!
//! ```text
//! controller.begin_episode(&state);
//! loop {
//!     controller.observe(&state, goal_xy_m, &mut obs);
//!     let plan = controller.plan_phase(&policy(&obs), &state);
//!     for sample in 1..=controller.steps_per_phase() {
//!         controller.joint_targets(&plan, sample, &mut targets);
//!         robot.set_pd_targets(&targets);
//!         controller.record_step(&state);   // the state before the step
//!         robot.step();                     // controller.dt_secs()
//!         state = robot.measure();
//!     }
//!     controller.end_phase(&plan);
//! }
//! ```

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use crate::action::{ACTION_SIZE, CubicBezier, PhaseCurves, curves_from_action};
use crate::height_scan::{HeightScan, height_scan_m};
use crate::kinematics::LegKinematics;
use crate::model::{LegName, RobotModel};
use crate::scripted::ScriptedCrawl;
use crate::task::{
    ActionPrior, FOOT_HISTORY_PHASES, ObservationConfig, SWING_ORDER, SwingHeightReference,
};
use crate::world::{World, WorldError, squat_rad_of};
use crate::world_config::{PAPER_STEP_RATE_HZ, WorldConfig, dt_secs_at, steps_per_phase_at};

/// What the controller reads of the robot: the measured (or estimated)
/// state, world frame unless named otherwise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotState {
    /// the base's pose (state estimation / odometry)
    pub base_pose: Isometry3<f64>,
    /// the base's linear velocity, m/s
    pub base_linear_velocity_m_per_s: Vector3<f64>,
    /// the base's angular velocity, rad/s
    pub base_angular_velocity_rad_per_s: Vector3<f64>,
    /// the feet (sole-sphere centres), FR FL RR RL, m: from the joint
    /// angles by forward kinematics on a robot ([`Self::feet_by_kinematics`])
    pub feet_in_world_m: [Vector3<f64>; 4],
    /// h_b: each hip (abduction) joint's height above the ground right
    /// below it, FR FL RR RL, m
    pub hip_heights_m: [f64; 4],
    /// the whole robot's centre of mass, m (read by the scripted-crawl
    /// action prior only)
    pub centre_of_mass_m: Vector3<f64>,
    /// the base's height above the ground at the points ahead of it
    /// ([`crate::height_scan`]), m; read only by an observation with
    /// `height_scan` on, `None` where it was not measured
    pub height_scan_m: Option<HeightScan>,
}

impl RobotState {
    /// The state of quadwalk's world, as its task reads it.
    pub fn of_world(world: &World) -> Self {
        let (linear, angular) = world.base_velocity();
        Self {
            base_pose: world.base_pose(),
            base_linear_velocity_m_per_s: linear,
            base_angular_velocity_rad_per_s: angular,
            feet_in_world_m: world.feet_in_world_m(),
            hip_heights_m: world.hip_heights_m(),
            centre_of_mass_m: world.centre_of_mass_m(),
            height_scan_m: None,
        }
    }

    /// [`Self::of_world`] with the height scan of the ground ahead
    /// ([`crate::height_scan::height_scan_m`]).
    pub fn of_world_scanned(world: &World) -> Self {
        Self {
            height_scan_m: Some(height_scan_m(world)),
            ..Self::of_world(world)
        }
    }

    /// The feet in the world from measured joint angles (`q_rad` in the
    /// model's joint order) by each leg's forward kinematics, for a base at
    /// `base_pose`.
    pub fn feet_by_kinematics(
        legs: &[LegKinematics; 4],
        leg_joints: &[[usize; 3]; 4],
        base_pose: &Isometry3<f64>,
        q_rad: &[f64],
    ) -> [Vector3<f64>; 4] {
        std::array::from_fn(|leg| {
            let [a, h, k] = leg_joints[leg];
            let in_base = legs[leg].forward([q_rad[a], q_rad[h], q_rad[k]]);
            (base_pose * Point3::from(in_base)).coords
        })
    }

    /// The feet in the base frame.
    pub fn feet_in_base_m(&self) -> [Vector3<f64>; 4] {
        feet_in_base_m(&self.base_pose, self.feet_in_world_m)
    }

    /// The mean of h_b, m.
    pub fn base_height_m(&self) -> f64 {
        self.hip_heights_m.iter().sum::<f64>() / 4.0
    }

    /// A world point (x, y) in the base frame (x, y; z dropped).
    pub fn in_base(&self, xy_m: [f64; 2]) -> nalgebra::Vector2<f64> {
        point_in_base(&self.base_pose, xy_m)
    }
}

/// World feet in the frame of a base at `base_pose`.
pub fn feet_in_base_m(
    base_pose: &Isometry3<f64>,
    feet_in_world_m: [Vector3<f64>; 4],
) -> [Vector3<f64>; 4] {
    let inv = base_pose.inverse();
    feet_in_world_m.map(|f| (inv * Point3::from(f)).coords)
}

/// A world point (x, y) in the frame of a base at `base_pose` (taken at the
/// base's height; z dropped).
pub fn point_in_base(base_pose: &Isometry3<f64>, [x, y]: [f64; 2]) -> nalgebra::Vector2<f64> {
    let p = base_pose.inverse() * Point3::new(x, y, base_pose.translation.z);
    nalgebra::Vector2::new(p.x, p.y)
}

/// One phase, planned at its start from the action.
#[derive(Debug, Clone, PartialEq)]
pub struct PhasePlan {
    /// the episode's phase index
    pub phase: usize,
    /// the leg that swings
    pub swing_leg: LegName,
    /// the base pose at the phase start (the curves' frame)
    pub base_start: Isometry3<f64>,
    /// the feet in the world at the phase start (the stance feet hold them)
    pub feet_world_start_m: [Vector3<f64>; 4],
    /// the feet in the base frame at the phase start
    pub feet_base_start_m: [Vector3<f64>; 4],
    /// the base position, base orientation and swing-foot curves
    pub curves: PhaseCurves,
}

/// What the observation remembers between control steps.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Memory {
    /// the phase about to run (between phases) or running
    phase: usize,
    /// feet in the base frame at the start of the last three phases, oldest first
    phase_start_feet: [[Vector3<f64>; 4]; FOOT_HISTORY_PHASES],
    /// feet in the base frame 1 and 2 steps ago
    feet_1_step_ago: [Vector3<f64>; 4],
    feet_2_steps_ago: [Vector3<f64>; 4],
    /// each foot's world height when it last landed (at the start of the
    /// phase after its swing; before its first swing, at the episode's
    /// start), m: the origin of its next swing's heights with
    /// [`SwingHeightReference::Touchdown`]
    touchdown_z_world_m: [f64; 4],
}

/// The phase-level controller: observation, phase plan, joint targets.
#[derive(Debug, Clone)]
pub struct PhaseController {
    legs: [LegKinematics; 4],
    leg_joints: [[usize; 3]; 4],
    /// the squat, one angle per joint of the model
    squat_rad: Vec<f64>,
    squat_feet_in_base_m: [Vector3<f64>; 4],
    observation: ObservationConfig,
    action_prior: ActionPrior,
    swing_height_reference: SwingHeightReference,
    /// control steps (physics steps) per second, Hz
    step_rate_hz: u32,
    memory: Memory,
}

impl PhaseController {
    /// The controller of `model` (its legs' kinematics `legs`, its squat
    /// `squat_rad` in joint order), observing with `observation`, adding
    /// `action_prior`'s action to the policy's and counting the swing
    /// foot's heights from `swing_height_reference`.
    pub fn new(
        model: &RobotModel,
        legs: [LegKinematics; 4],
        squat_rad: &[f64],
        observation: ObservationConfig,
        action_prior: ActionPrior,
        swing_height_reference: SwingHeightReference,
    ) -> Self {
        for (kin, leg) in legs.iter().zip(&model.legs) {
            assert_eq!(
                kin.name, leg.name,
                "the kinematics follow the model's leg order"
            );
        }
        let leg_joints = std::array::from_fn(|leg| model.legs[leg].joints);
        let squat_feet_in_base_m = std::array::from_fn(|leg| {
            let [a, h, k] = model.legs[leg].joints;
            legs[leg].forward([squat_rad[a], squat_rad[h], squat_rad[k]])
        });
        let feet = [Vector3::zeros(); 4];
        Self {
            legs,
            leg_joints,
            squat_rad: squat_rad.to_vec(),
            squat_feet_in_base_m,
            observation,
            action_prior,
            swing_height_reference,
            step_rate_hz: PAPER_STEP_RATE_HZ,
            memory: Memory {
                phase: 0,
                phase_start_feet: [feet; FOOT_HISTORY_PHASES],
                feet_1_step_ago: feet,
                feet_2_steps_ago: feet,
                touchdown_z_world_m: [0.0; 4],
            },
        }
    }

    /// The controller of `model` without a world: its legs' kinematics and
    /// squat as quadwalk's world derives them.
    pub fn for_model(
        model: &RobotModel,
        observation: ObservationConfig,
        action_prior: ActionPrior,
        swing_height_reference: SwingHeightReference,
    ) -> Result<Self, WorldError> {
        let legs = LegKinematics::from_model(model)?;
        let squat_rad = squat_rad_of(model, &legs)?;
        Ok(Self::new(
            model,
            legs,
            &squat_rad,
            observation,
            action_prior,
            swing_height_reference,
        ))
    }

    /// The controller of quadwalk's world's robot.
    pub fn of_world(
        world: &World,
        observation: ObservationConfig,
        action_prior: ActionPrior,
        swing_height_reference: SwingHeightReference,
    ) -> Self {
        let mut controller = Self::new(
            world.model(),
            world.legs().clone(),
            world.squat_rad(),
            observation,
            action_prior,
            swing_height_reference,
        );
        controller.step_rate_hz = world.step_rate_hz();
        controller
    }

    /// The controller stepping at `step_rate_hz` (the paper's 240 unless
    /// set): a phase of 0.75 x rate control steps of 1 / rate s each, as
    /// a world with that `[physics] step_rate_hz` steps; `None` for a rate
    /// a world cannot take (see [`crate::world_config::STEP_RATE_RANGE_HZ`]).
    pub fn with_step_rate_hz(mut self, step_rate_hz: u32) -> Option<Self> {
        let physics = WorldConfig {
            step_rate_hz,
            ..WorldConfig::default()
        };
        physics.validate().ok()?;
        self.step_rate_hz = step_rate_hz;
        Some(self)
    }

    /// Control steps in a phase (180 at the paper's
    /// [`PAPER_STEP_RATE_HZ`]).
    pub fn steps_per_phase(&self) -> usize {
        steps_per_phase_at(self.step_rate_hz)
    }

    /// One control step, s.
    pub fn dt_secs(&self) -> f64 {
        dt_secs_at(self.step_rate_hz)
    }

    /// Observation values.
    pub fn observation_size(&self) -> usize {
        self.observation.size()
            + if self.action_prior == ActionPrior::None {
                0
            } else {
                ACTION_SIZE
            }
    }

    /// The phase about to run (between phases) or running.
    pub fn phase(&self) -> usize {
        self.memory.phase
    }

    /// The swing leg of the phase about to run.
    pub fn swing_leg(&self) -> LegName {
        SWING_ORDER[self.memory.phase % 4]
    }

    /// The robot's joints (the length of joint-angle and target vectors).
    pub fn joint_count(&self) -> usize {
        self.squat_rad.len()
    }

    /// The squat every episode starts from, joint angles in the model's
    /// order, rad.
    pub fn squat_rad(&self) -> &[f64] {
        &self.squat_rad
    }

    /// The feet in the base frame in the squat, FR FL RR RL, m.
    pub fn squat_feet_in_base_m(&self) -> &[Vector3<f64>; 4] {
        &self.squat_feet_in_base_m
    }

    /// The legs' kinematics, FR FL RR RL.
    pub fn legs(&self) -> &[LegKinematics; 4] {
        &self.legs
    }

    /// Each leg's joint indices (abduction, hip, knee).
    pub fn leg_joints(&self) -> &[[usize; 3]; 4] {
        &self.leg_joints
    }

    /// Starts an episode from `state`: phase 0, every remembered foot
    /// position the current one.
    pub fn begin_episode(&mut self, state: &RobotState) {
        let feet = state.feet_in_base_m();
        self.memory = Memory {
            phase: 0,
            phase_start_feet: [feet; FOOT_HISTORY_PHASES],
            feet_1_step_ago: feet,
            feet_2_steps_ago: feet,
            touchdown_z_world_m: state.feet_in_world_m.map(|f| f.z),
        };
    }

    /// Makes `phase` the phase about to run (a test's mirrored start).
    #[cfg(test)]
    pub(crate) fn start_at_phase(&mut self, phase: usize) {
        self.memory.phase = phase;
    }

    /// The height the swing foot's P1-P3 heights count from in the phase
    /// about to run from `state`, base frame at the phase start, m: the
    /// foot's height ([`SwingHeightReference::Foot`]), or the point above
    /// (or below) the foot at the world height where it last landed
    /// ([`SwingHeightReference::Touchdown`]).
    pub fn swing_height_origin_m(&self, state: &RobotState) -> f64 {
        let leg = self.swing_leg().index();
        match self.swing_height_reference {
            SwingHeightReference::Foot => state.feet_in_base_m()[leg].z,
            SwingHeightReference::Touchdown => {
                let foot = state.feet_in_world_m[leg];
                let landed = Point3::new(foot.x, foot.y, self.memory.touchdown_z_world_m[leg]);
                (state.base_pose.inverse() * landed).z
            }
        }
    }

    /// The world x, y the observation's goal blocks show for the current
    /// goal `goal_xy_m`: the goal itself (the paper's), or with
    /// `goal_line_ahead_m = L` the point on the goals' line L m ahead of
    /// the base along world +x.
    pub fn observed_goal_xy_m(&self, state: &RobotState, goal_xy_m: [f64; 2]) -> [f64; 2] {
        match self.observation.goal_line_ahead_m {
            None => goal_xy_m,
            Some(ahead_m) => [state.base_pose.translation.x + ahead_m, goal_xy_m[1]],
        }
    }

    /// Writes the policy's observation for `state` heading for
    /// `goal_xy_m` (the layout is in the docs of [`crate::task`]).
    pub fn observe(&self, state: &RobotState, goal_xy_m: [f64; 2], obs: &mut [f32]) {
        let size = self.observation_size();
        assert_eq!(obs.len(), size, "the observation has {size} values");
        let mut out = Vec::with_capacity(size);
        let base = state.base_pose;
        let rotation_inv = base.rotation.inverse();
        out.extend(state.hip_heights_m);
        out.extend((rotation_inv * -Vector3::z()).iter());
        out.extend((rotation_inv * state.base_linear_velocity_m_per_s).iter());
        out.extend((rotation_inv * state.base_angular_velocity_rad_per_s).iter());
        let (_, pitch, _) = base.rotation.euler_angles();
        out.push(pitch);
        let now = state.feet_in_base_m();
        let c = &self.observation;
        let memory = &self.memory;
        if c.foot_history {
            let history = &memory.phase_start_feet;
            let shown = c.foot_history_phases.min(history.len());
            for feet in &history[history.len() - shown..] {
                out.extend(feet.iter().flat_map(|f| f.iter().copied()));
            }
        }
        out.extend(now.iter().flat_map(|f| f.iter().copied()));
        if c.short_history {
            out.extend(
                memory
                    .feet_1_step_ago
                    .iter()
                    .flat_map(|f| f.iter().copied()),
            );
            out.extend(
                memory
                    .feet_2_steps_ago
                    .iter()
                    .flat_map(|f| f.iter().copied()),
            );
        }
        if c.foot_velocity {
            for (p, q) in now.iter().zip(&memory.feet_1_step_ago) {
                out.extend(((p - q) / self.dt_secs()).iter());
            }
        }
        let goal = state.in_base(self.observed_goal_xy_m(state, goal_xy_m));
        out.push(goal.y.atan2(goal.x));
        out.push(goal.x);
        out.push(goal.y);
        out.push((memory.phase % 4) as f64 / 4.0);
        if c.height_scan {
            let scan = state.height_scan_m.expect(
                "the observation's height scan needs a state with it (RobotState::of_world_scanned)",
            );
            out.extend(scan);
        }
        if self.action_prior != ActionPrior::None {
            out.extend(self.prior_action(state).iter().map(|&a| f64::from(a)));
        }
        debug_assert_eq!(out.len(), size);
        for (o, v) in obs.iter_mut().zip(out) {
            *o = v as f32;
        }
    }

    /// The action the prior gives for the phase about to run (zeros
    /// without a prior).
    pub fn prior_action(&self, state: &RobotState) -> [f32; ACTION_SIZE] {
        match self.action_prior {
            ActionPrior::None => [0.0; ACTION_SIZE],
            ActionPrior::ScriptedCrawl => ScriptedCrawl::default().act_on(
                self.memory.phase,
                state,
                &self.squat_feet_in_base_m,
            ),
        }
    }

    /// The phase about to run, planned from the policy's `action` (27
    /// values; clipped to [-1, 1], on top of the prior's where there is
    /// one) at `state`.
    pub fn plan_phase(&self, action: &[f32], state: &RobotState) -> PhasePlan {
        assert_eq!(
            action.len(),
            ACTION_SIZE,
            "an action has {ACTION_SIZE} values"
        );
        let composed;
        let action = match self.action_prior {
            ActionPrior::None => action,
            ActionPrior::ScriptedCrawl => {
                let prior = self.prior_action(state);
                composed = std::array::from_fn::<f32, ACTION_SIZE, _>(|i| {
                    (prior[i] + action[i]).clamp(-1.0, 1.0)
                });
                &composed[..]
            }
        };
        let swing = self.swing_leg();
        let feet_base_start_m = state.feet_in_base_m();
        let curves = curves_from_action(
            action,
            feet_base_start_m[swing.index()],
            self.swing_height_origin_m(state),
            self.squat_feet_in_base_m[swing.index()],
            swing.is_hind(),
        );
        self.plan_with(state, feet_base_start_m, curves)
    }

    /// The plan of the phase about to run from `state` along `curves`.
    fn plan_with(
        &self,
        state: &RobotState,
        feet_base_start_m: [Vector3<f64>; 4],
        curves: PhaseCurves,
    ) -> PhasePlan {
        PhasePlan {
            phase: self.memory.phase,
            swing_leg: self.swing_leg(),
            base_start: state.base_pose,
            feet_world_start_m: state.feet_in_world_m,
            feet_base_start_m,
            curves,
        }
    }

    /// A plan for the phase about to run that holds the base and every
    /// foot where they are (the swing leg's curve stays at its start): for
    /// a lower level that moves all the feet itself (a single-level
    /// policy). The phase counts in the history as any other.
    pub fn hold_plan(&self, state: &RobotState) -> PhasePlan {
        let feet_base_start_m = state.feet_in_base_m();
        let still = CubicBezier {
            points: [Vector3::zeros(); 4],
        };
        let swing_foot = CubicBezier {
            points: [feet_base_start_m[self.swing_leg().index()]; 4],
        };
        let curves = PhaseCurves {
            base_position: still,
            base_orientation: still,
            swing_foot,
        };
        self.plan_with(state, feet_base_start_m, curves)
    }

    /// Writes the joint targets of control step `sample` (1 to
    /// [`Self::steps_per_phase`], at t = sample / steps) of `plan` into
    /// `targets_rad` (the legs' joints, in the model's joint order); returns
    /// how many legs' IK was clamped (out of reach or past a limit).
    ///
    /// `base_target = base_start * (translate(B_pos(t)) * rotate(B_rpy(t)))`;
    /// the swing foot follows B_foot(t) in the phase-start base frame, the
    /// stance feet hold their phase-start world positions, each solved by IK
    /// in the target base frame.
    pub fn joint_targets(&self, plan: &PhasePlan, sample: usize, targets_rad: &mut [f64]) -> usize {
        self.joint_targets_moved(plan, sample, None, targets_rad)
    }

    /// [`Self::joint_targets`] with each foot's target moved by
    /// `foot_offsets_m` (leg order, in the target base frame of this
    /// sample) before IK: a lower-level controller's correction of the
    /// plan within the phase. `None` is the plan itself.
    pub fn joint_targets_moved(
        &self,
        plan: &PhasePlan,
        sample: usize,
        foot_offsets_m: Option<&[Vector3<f64>; 4]>,
        targets_rad: &mut [f64],
    ) -> usize {
        let feet_m = self.planned_feet_m(plan, sample);
        let mut clamped = 0;
        for (kin, joints) in self.legs.iter().zip(&self.leg_joints) {
            let mut foot_in_target = feet_m[kin.name.index()];
            if let Some(offsets) = foot_offsets_m {
                foot_in_target += offsets[kin.name.index()];
            }
            let solution = kin.inverse(foot_in_target);
            clamped += solution.clamped as usize;
            for (k, &j) in joints.iter().enumerate() {
                targets_rad[j] = solution.q_rad[k];
            }
        }
        clamped
    }

    /// Where `plan` puts each foot at control step `sample` (leg order), in
    /// the base's target frame of that sample, m: the points the IK of
    /// [`Self::joint_targets`] solves for.
    pub fn planned_feet_m(&self, plan: &PhasePlan, sample: usize) -> [Vector3<f64>; 4] {
        let t = sample as f64 / self.steps_per_phase() as f64;
        let curves = &plan.curves;
        let rpy = curves.base_orientation.at(t);
        let offset = Isometry3::from_parts(
            Translation3::from(curves.base_position.at(t)),
            UnitQuaternion::from_euler_angles(rpy.x, rpy.y, rpy.z),
        );
        let base_target = plan.base_start * offset;
        let world_from_target_inv = base_target.inverse();
        let mut feet_m = [Vector3::zeros(); 4];
        for kin in &self.legs {
            let foot_world = if kin.name == plan.swing_leg {
                plan.base_start * Point3::from(curves.swing_foot.at(t))
            } else {
                Point3::from(plan.feet_world_start_m[kin.name.index()])
            };
            feet_m[kin.name.index()] = (world_from_target_inv * foot_world).coords;
        }
        feet_m
    }

    /// Remembers the feet of `state`, the state before a control step is
    /// taken (the observation's short history).
    pub fn record_step(&mut self, state_feet_in_base_m: [Vector3<f64>; 4]) {
        self.memory.feet_2_steps_ago = self.memory.feet_1_step_ago;
        self.memory.feet_1_step_ago = state_feet_in_base_m;
    }

    /// Ends `plan`'s phase: its start joins the phase-start history, the
    /// foot that swung in the phase before it is remembered where it
    /// landed (its height at `plan`'s start), and the next phase is the one
    /// about to run.
    pub fn end_phase(&mut self, plan: &PhasePlan) {
        let history = &mut self.memory.phase_start_feet;
        history.rotate_left(1);
        history[FOOT_HISTORY_PHASES - 1] = plan.feet_base_start_m;
        if let Some(previous) = plan.phase.checked_sub(1) {
            let landed = SWING_ORDER[previous % 4].index();
            self.memory.touchdown_z_world_m[landed] = plan.feet_world_start_m[landed].z;
        }
        self.memory.phase += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::WorldConfig;
    use crate::task::{Task, TaskConfig};

    fn world_on(spec: &str) -> World {
        world_at(spec, WorldConfig::default())
    }

    fn world_at(spec: &str, physics: WorldConfig) -> World {
        crate::test_worlds::laikago_on(spec, 3, [0.0, 0.0], physics)
    }

    /// A robot's loop (the module docs' loop, on a second world standing in
    /// for the robot) gives the task's observations, joint targets and
    /// motion bit for bit, for the goal the task heads for, with either
    /// origin of the swing foot's heights, at the paper's 240 Hz and at
    /// 120 Hz (a controller set to the rate by hand steps as one taken
    /// from the world).
    #[test]
    fn the_controller_on_its_own_drives_a_world_as_the_task_does() {
        for (swing_height_reference, step_rate_hz) in [
            (SwingHeightReference::Foot, 240),
            (SwingHeightReference::Touchdown, 240),
            (SwingHeightReference::Foot, 120),
        ] {
            drive_a_world_as_the_task_does(
                TaskConfig {
                    observation: ObservationConfig {
                        goal_line_ahead_m: Some(1.0),
                        ..ObservationConfig::default()
                    },
                    swing_height_reference,
                    ..TaskConfig::default()
                },
                WorldConfig {
                    step_rate_hz,
                    ..WorldConfig::default()
                },
            );
        }
    }

    fn drive_a_world_as_the_task_does(config: TaskConfig, physics: WorldConfig) {
        let start = [1.3, -0.4];
        let mut task = Task::new(world_at("elastic:5cm", physics.clone()), config.clone(), 0);
        let mut task_obs = vec![0.0; task.observation_size()];
        task.reset_at(start, &mut task_obs);

        let mut robot = world_at("elastic:5cm", physics.clone());
        robot.reset_terrain();
        robot.reset_robot(start, 0.0);
        for _ in 0..(config.settle_secs / robot.dt_secs()).round() as usize {
            robot.step();
        }
        let mut controller = PhaseController::new(
            robot.model(),
            robot.legs().clone(),
            robot.squat_rad(),
            config.observation,
            config.action_prior,
            config.swing_height_reference,
        )
        .with_step_rate_hz(physics.step_rate_hz)
        .expect("a world's rate");
        assert_eq!(controller.steps_per_phase(), physics.steps_per_phase());
        controller.begin_episode(&RobotState::of_world(&robot));
        let mut obs = vec![0.0; controller.observation_size()];
        let mut targets = robot.joint_targets_rad().to_vec();
        let crawl = ScriptedCrawl::default();
        for phase in 0..16 {
            let state = RobotState::of_world(&robot);
            controller.observe(&state, task.goal_xy_m(), &mut obs);
            assert_eq!(obs, task_obs, "phase {phase}'s observation");
            let action = crawl.act_on(
                controller.phase(),
                &state,
                controller.squat_feet_in_base_m(),
            );
            assert_eq!(action, crawl.act(&task), "phase {phase}'s action");
            let plan = controller.plan_phase(&action, &state);
            for sample in 1..=controller.steps_per_phase() {
                controller.joint_targets(&plan, sample, &mut targets);
                robot.set_joint_targets_rad(&targets);
                controller.record_step(RobotState::of_world(&robot).feet_in_base_m());
                robot.step();
            }
            controller.end_phase(&plan);
            let outcome = task.step_phase(&action, &mut task_obs);
            assert!(outcome.termination.is_none(), "phase {phase}: {outcome:?}");
            assert_eq!(robot.joint_targets_rad(), task.world().joint_targets_rad());
            assert_eq!(
                robot.base_pose(),
                task.world().base_pose(),
                "after phase {phase}"
            );
        }
        assert_eq!(controller.phase(), task.phase());
        let moved = robot.base_pose().translation.x - start[0];
        assert!(moved > 0.02, "the crawl walks: {moved} m");
    }

    /// With [`SwingHeightReference::Touchdown`] the swing foot's P1-P3 are
    /// those of the paper's origin raised by how far the foot has sunk
    /// since it landed (along the base's z), P0 is the foot: on soil, where
    /// the feet sink centimetres under the crawl, and on rigid ground,
    /// where they do not.
    #[test]
    fn with_touchdown_a_sunk_foot_swings_from_where_it_landed() {
        for (spec, least_deepest_m, most_deepest_m) in
            [("soil:4cm", 0.02, 0.15), ("rigid", 0.0, 0.003)]
        {
            let mut world = world_on(spec);
            world.reset_terrain();
            world.reset_robot([0.0, 0.0], 0.0);
            for _ in 0..120 {
                world.step();
            }
            let controller = |reference| {
                PhaseController::of_world(
                    &world,
                    ObservationConfig::default(),
                    ActionPrior::None,
                    reference,
                )
            };
            let mut touchdown = controller(SwingHeightReference::Touchdown);
            let mut paper = controller(SwingHeightReference::Foot);
            let state = RobotState::of_world(&world);
            touchdown.begin_episode(&state);
            paper.begin_episode(&state);
            // each foot's world height where it landed, kept by the test
            let mut landed_z = state.feet_in_world_m.map(|f| f.z);
            let crawl = ScriptedCrawl::default();
            let mut targets = world.joint_targets_rad().to_vec();
            let mut deepest_m: f64 = 0.0;
            for phase in 0..12 {
                let state = RobotState::of_world(&world);
                if phase > 0 {
                    let leg = SWING_ORDER[(phase - 1) % 4].index();
                    landed_z[leg] = state.feet_in_world_m[leg].z;
                }
                let action =
                    crawl.act_on(touchdown.phase(), &state, touchdown.squat_feet_in_base_m());
                let plan = touchdown.plan_phase(&action, &state);
                let same = paper.plan_phase(&action, &state);
                let leg = plan.swing_leg.index();
                let sink_m = landed_z[leg] - state.feet_in_world_m[leg].z;
                let raise_m =
                    touchdown.swing_height_origin_m(&state) - state.feet_in_base_m()[leg].z;
                // the world's vertical seen in a base tilted by a few degrees
                assert!(
                    (raise_m - sink_m).abs() <= 0.02 * sink_m.abs() + 1e-9,
                    "{spec} phase {phase}: raised {raise_m} m for a sink of {sink_m} m"
                );
                deepest_m = deepest_m.max(sink_m);
                let (a, b) = (
                    &same.curves.swing_foot.points,
                    &plan.curves.swing_foot.points,
                );
                assert_eq!(a[0], b[0], "P0 is the foot");
                for p in 1..4 {
                    assert_eq!((a[p].x, a[p].y), (b[p].x, b[p].y));
                    assert!(
                        (b[p].z - a[p].z - raise_m).abs() < 1e-12,
                        "{spec} phase {phase} P{p}"
                    );
                }
                assert_eq!(plan.curves.base_position, same.curves.base_position);
                for sample in 1..=touchdown.steps_per_phase() {
                    touchdown.joint_targets(&plan, sample, &mut targets);
                    world.set_joint_targets_rad(&targets);
                    world.step();
                }
                touchdown.end_phase(&plan);
                paper.end_phase(&same);
            }
            assert!(
                (least_deepest_m..=most_deepest_m).contains(&deepest_m),
                "{spec}: the deepest sink since a landing {deepest_m} m"
            );
        }
    }

    /// On a robot the feet come from the joint encoders: forward
    /// kinematics of rapier's joint angles puts them where rapier's bodies
    /// are, within float rounding of rapier's single-precision poses.
    #[test]
    fn feet_by_kinematics_match_the_simulated_feet() {
        let mut world = world_on("elastic:5cm");
        world.reset_robot([0.0, 0.0], 0.3);
        for _ in 0..120 {
            world.step();
        }
        let controller = PhaseController::of_world(
            &world,
            ObservationConfig::default(),
            ActionPrior::None,
            SwingHeightReference::Foot,
        );
        let feet = RobotState::feet_by_kinematics(
            controller.legs(),
            controller.leg_joints(),
            &world.base_pose(),
            &world.joint_positions_rad(),
        );
        for (fk, sim) in feet.iter().zip(world.feet_in_world_m()) {
            assert!((fk - sim).norm() < 1e-5, "{fk} against {sim}");
        }
    }

    #[test]
    fn the_phase_start_history_keeps_the_three_newest_oldest_first() {
        let world = world_on("rigid");
        let mut controller = PhaseController::of_world(
            &world,
            ObservationConfig::default(),
            ActionPrior::None,
            SwingHeightReference::Foot,
        );
        let state = RobotState::of_world(&world);
        controller.begin_episode(&state);
        let mut plan = controller.plan_phase(&[0.0; ACTION_SIZE], &state);
        for k in 1..=4 {
            plan.feet_base_start_m = [Vector3::repeat(k as f64); 4];
            controller.end_phase(&plan);
        }
        let firsts: Vec<f64> = controller
            .memory
            .phase_start_feet
            .iter()
            .map(|f| f[0].x)
            .collect();
        assert_eq!(firsts, [2.0, 3.0, 4.0]);
        assert_eq!(controller.phase(), 4);
        assert_eq!(controller.swing_leg(), SWING_ORDER[0]);
    }
}
