//! The physics world: rapier sets, a terrain and the robot as a multibody
//! with PD-controlled joints, stepped at 240 Hz.
//!
//! Robot: a rapier multibody (reduced coordinates). The PD controller is,
//! by default, the multibody's own implicit joint spring and damping
//! ([`PdModel::ImplicitSpring`]: no solver rows, stable at one substep per
//! step), or a `MotorModel::ForceBased` position motor per joint
//! ([`PdModel::Motor`]); either way the gains are in N m/rad and N m s/rad,
//! with the URDF's effort as the torque limit. Rapier cannot report the
//! joint torque, so the world computes the PD torque itself after each
//! step: tau = clamp(kp (q* - q) - kd q', +-effort).
//!
//! Cost: rapier rebuilds the multibody's mass matrix and two LU
//! factorisations in every substep, so one substep instead of rapier's
//! default four makes a step about three times cheaper (docs/notebook/2026-11-29-physics-three-times-faster.md).
//!
//! Collision groups: robot colliders meet terrain colliders only.

use std::sync::Arc;

use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use terrain_plugins::rapier3d::prelude::*;
use terrain_plugins::{Terrain, robot_collision_groups};

use crate::kinematics::{KinematicsError, LegKinematics};
use crate::model::{Geometry, RobotModel};
use crate::seam::{from_pose, from_vector, to_matrix, to_pose, to_vector};
pub use crate::world_config::{PdModel, WorldConfig, WorldConfigError};

/// The paper's physics step, seconds (240 Hz); a world steps at its
/// config's `step_rate_hz` ([`World::dt_secs`]).
pub const DT_SECS: f64 = 1.0 / 240.0;

/// Toe-centre height below the base in the default wide squat, m.
pub const SQUAT_FOOT_DEPTH_M: f64 = 0.35;
/// Lateral distance of each foot from the body axis in the wide squat, m
/// (a narrow stance tips over on 5 cm springs).
pub const SQUAT_FOOT_WIDTH_M: f64 = 0.2;

/// The index of a revolute joint's free axis (`AngX`) in rapier's 6-DoF
/// spatial layout (three linear, then three angular).
const ANG_X: usize = 3;

/// Two shapes closer than this touch, m (rapier also pairs shapes up to
/// 2 cm apart, for speculative contacts; those do not count).
pub const TOUCH_DISTANCE_M: f64 = 0.001;

/// Why a world could not be made.
#[derive(Debug, thiserror::Error)]
pub enum WorldError {
    /// The model's legs do not fit the analytic IK.
    #[error(transparent)]
    Kinematics(#[from] KinematicsError),
    /// A collision mesh has no convex hull.
    #[error("collision shape of link {0} is degenerate (its convex hull is flat)")]
    DegenerateShape(String),
    /// The default squat is out of reach for this robot.
    #[error(
        "the default squat (feet under the hips, {SQUAT_FOOT_WIDTH_M} m out, {SQUAT_FOOT_DEPTH_M} m below the base) is out of reach for leg {0}"
    )]
    SquatUnreachable(&'static str),
}

/// Which robot parts touch the ground now.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GroundContacts {
    /// per leg (FR, FL, RR, RL): the foot touches the ground
    pub feet: [bool; 4],
    /// names of the links other than feet that touch the ground
    pub non_foot_links: Vec<String>,
}

/// Which robot colliders a contact query examines.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Examined {
    Feet,
    NonFeet,
    All,
}

struct RobotHandles {
    /// rigid body of each model body
    bodies: Vec<RigidBodyHandle>,
    multibody: MultibodyIndex,
    /// multibody link id of each actuated joint's child
    joint_links: Vec<usize>,
    /// (collider, URDF link name, the leg whose foot it is)
    colliders: Vec<(ColliderHandle, String, Option<usize>)>,
}

/// A physics world holding one terrain and one robot.
pub struct World {
    physics: PhysicsWorld,
    terrain: Box<dyn Terrain>,
    model: Arc<RobotModel>,
    legs: [LegKinematics; 4],
    robot: RobotHandles,
    config: WorldConfig,
    targets_rad: Vec<f64>,
    torques_n_m: Vec<f64>,
    efforts_n_m: Vec<f64>,
    limits_rad: Vec<(f64, f64)>,
    squat_rad: Vec<f64>,
    time_secs: f64,
    /// `time_secs` at the terrain's last reset
    terrain_reset_secs: f64,
    steps: u64,
}

impl World {
    /// Builds the terrain and the robot, standing in the default squat at
    /// (x, y) on the terrain, facing +x.
    pub fn new(
        model: Arc<RobotModel>,
        mut terrain: Box<dyn Terrain>,
        config: WorldConfig,
        start_xy_m: [f64; 2],
    ) -> Result<Self, WorldError> {
        let legs = LegKinematics::from_model(&model)?;
        let mut physics = PhysicsWorld::new();
        physics.gravity = Vector::new(0.0, 0.0, -terrain_plugins::STANDARD_GRAVITY_M_PER_S2 as f32);
        physics.integration_parameters.dt = config.dt_secs() as f32;
        physics.integration_parameters.num_solver_iterations = config.solver_iterations;
        physics.integration_parameters.num_internal_pgs_iterations = config.pgs_iterations;
        physics.integration_parameters.max_ccd_substeps = usize::from(config.ccd);
        // length_unit is 1 (metres), so the normalised distance is in m.
        physics
            .integration_parameters
            .normalized_prediction_distance = config.prediction_distance_m as f32;
        terrain.build(&mut physics);

        let robot = insert_robot(&mut physics, &model, &config)?;
        let squat_rad = squat_rad_of(&model, &legs)?;
        let n = model.joints.len();
        let mut world = Self {
            physics,
            terrain,
            efforts_n_m: model.joints.iter().map(|j| j.effort_n_m).collect(),
            limits_rad: model.joint_limits_rad(),
            model,
            legs,
            robot,
            config,
            targets_rad: squat_rad.clone(),
            torques_n_m: vec![0.0; n],
            squat_rad,
            time_secs: 0.0,
            terrain_reset_secs: 0.0,
            steps: 0,
        };
        world.reset_robot(start_xy_m, 0.0);
        Ok(world)
    }

    /// Puts the robot back in the squat at (x, y) with heading `yaw_rad`,
    /// its feet just above the surface, at rest, with the squat as PD target.
    pub fn reset_robot(&mut self, start_xy_m: [f64; 2], yaw_rad: f64) {
        let [x, y] = start_xy_m;
        let foot_radius = self.model.legs[0].foot_radius_m;
        let surface = self.terrain.surface_height_m(&self.physics, x, y);
        let clearance_m = 0.002;
        let base = Isometry3::new(
            Vector3::new(
                x,
                y,
                surface + SQUAT_FOOT_DEPTH_M + foot_radius + clearance_m,
            ),
            Vector3::z() * yaw_rad,
        );
        let squat = self.squat_rad.clone();
        self.place_robot(&base, &squat);
        // On relief the ground under a foot may be higher than under the
        // base: lift the robot until the highest foot clears it too. (Flat
        // terrains and tiles at rest are level: nothing changes there.)
        let under_feet = self
            .feet_in_world_m()
            .iter()
            .map(|f| self.terrain.surface_height_m(&self.physics, f.x, f.y))
            .fold(surface, f64::max);
        if under_feet > surface {
            let lifted = Isometry3::new(
                Vector3::new(
                    x,
                    y,
                    under_feet + SQUAT_FOOT_DEPTH_M + foot_radius + clearance_m,
                ),
                Vector3::z() * yaw_rad,
            );
            self.place_robot(&lifted, &squat);
        }
    }

    /// Puts the robot's base at `base_pose` (world frame) with joint angles
    /// `q_rad` (joint order), at rest, holding `q_rad` as PD targets. For
    /// resets and for crafting states in tests; the robot may start in the
    /// air or in the ground.
    pub fn place_robot(&mut self, base_pose: &Isometry3<f64>, q_rad: &[f64]) {
        assert_eq!(
            q_rad.len(),
            self.targets_rad.len(),
            "one angle per actuated joint"
        );
        let root = self.robot.bodies[0];
        self.physics.bodies[root].set_position(to_pose(base_pose), true);
        let multibody = self
            .physics
            .multibody_joints
            .get_multibody_mut(self.robot.multibody)
            .expect("the robot's multibody exists");
        let mut displacement = vec![0.0f32; multibody.ndofs()];
        for (j, &link_id) in self.robot.joint_links.iter().enumerate() {
            let link = multibody.link(link_id).expect("joint link exists");
            let current = link.joint.coords()[ANG_X];
            displacement[link.assembly_id()] = q_rad[j] as f32 - current;
        }
        multibody.apply_displacements(&displacement);
        multibody.generalized_velocity_mut().fill(0.0);
        multibody.forward_kinematics(&self.physics.bodies, true);
        multibody.update_rigid_bodies(&mut self.physics.bodies, true);
        for &handle in &self.robot.bodies {
            let body = &mut self.physics.bodies[handle];
            body.set_linvel(Vector::ZERO, true);
            body.set_angvel(Vector::ZERO, true);
        }
        self.set_joint_targets_rad(q_rad);
        self.torques_n_m.fill(0.0);
    }

    /// Puts the terrain's moving parts back at rest (and its clock, for a
    /// terrain that changes by itself, at zero).
    pub fn reset_terrain(&mut self) {
        self.terrain.reset(&mut self.physics);
        self.terrain_reset_secs = self.time_secs;
    }

    /// Simulated time since the terrain's last reset (the world's making
    /// if none), s: the clock of [`terrain_plugins::Terrain::change_times_secs`].
    pub fn secs_since_terrain_reset(&self) -> f64 {
        self.time_secs - self.terrain_reset_secs
    }

    /// Sets the PD position targets (joint order), clamped to the limits; a
    /// target that is not finite keeps the joint's previous one.
    pub fn set_joint_targets_rad(&mut self, targets_rad: &[f64]) {
        assert_eq!(
            targets_rad.len(),
            self.targets_rad.len(),
            "one target per actuated joint"
        );
        for (j, &target) in targets_rad.iter().enumerate() {
            if target.is_finite() {
                let (lo, hi) = self.limits_rad[j];
                self.targets_rad[j] = target.clamp(lo, hi);
            }
        }
        if self.config.pd == PdModel::Motor {
            let (kp, kd) = (self.config.kp_n_m_per_rad, self.config.kd_n_m_s_per_rad);
            let multibody = multibody_mut(&mut self.physics, self.robot.multibody);
            for (j, &link_id) in self.robot.joint_links.iter().enumerate() {
                let link = multibody.link_mut(link_id).expect("joint link exists");
                link.joint.data.set_motor_position(
                    JointAxis::AngX,
                    self.targets_rad[j] as f32,
                    kp as f32,
                    kd as f32,
                );
            }
        }
    }

    /// Sets each joint's implicit spring for the coming step: rest at the
    /// target, or, where the PD torque at the current state would exceed
    /// the effort, at the angle that makes it equal the cap (see
    /// [`PdModel::ImplicitSpring`]).
    fn set_implicit_springs(&mut self) {
        let (kp, kd) = (self.config.kp_n_m_per_rad, self.config.kd_n_m_s_per_rad);
        let multibody = multibody_mut(&mut self.physics, self.robot.multibody);
        for (j, &link_id) in self.robot.joint_links.iter().enumerate() {
            let dof = multibody
                .link(link_id)
                .expect("joint link exists")
                .assembly_id();
            let qd = f64::from(multibody.generalized_velocity()[dof]);
            let link = multibody.link_mut(link_id).expect("joint link exists");
            let q = f64::from(link.joint.coords()[ANG_X]);
            // tau = kp (q* - q) - kd q', capped at the effort
            let tau = kp * (self.targets_rad[j] - q) - kd * qd;
            let effort = self.efforts_n_m[j];
            let rest = if tau.abs() > effort {
                q + (tau.clamp(-effort, effort) + kd * qd) / kp
            } else {
                self.targets_rad[j]
            };
            link.joint.set_spring(ANG_X, kp as f32, rest as f32);
        }
    }

    /// Physics steps per second, Hz (the config's `step_rate_hz`).
    pub fn step_rate_hz(&self) -> u32 {
        self.config.step_rate_hz
    }

    /// The physics step, s (1 / the config's `step_rate_hz`).
    pub fn dt_secs(&self) -> f64 {
        self.config.dt_secs()
    }

    /// Physics steps in a 0.75 s phase at this world's rate.
    pub fn steps_per_phase(&self) -> usize {
        self.config.steps_per_phase()
    }

    /// One physics step of [`Self::dt_secs`].
    pub fn step(&mut self) {
        if self.config.pd == PdModel::ImplicitSpring {
            self.set_implicit_springs();
        }
        let dt_secs = self.dt_secs();
        self.terrain.before_step(&mut self.physics, dt_secs);
        self.physics.step();
        self.terrain.after_step(&mut self.physics, dt_secs);
        self.time_secs += dt_secs;
        self.steps += 1;
        // The torque the PD applies (rapier does not report it).
        let q = self.joint_positions_rad();
        let qd = self.joint_velocities_rad_per_s();
        for j in 0..q.len() {
            let tau = self.config.kp_n_m_per_rad * (self.targets_rad[j] - q[j])
                - self.config.kd_n_m_s_per_rad * qd[j];
            self.torques_n_m[j] = tau.clamp(-self.efforts_n_m[j], self.efforts_n_m[j]);
        }
    }

    /// Joint positions, rad (joint order: FR, FL, RR, RL x abduction, hip, knee).
    pub fn joint_positions_rad(&self) -> Vec<f64> {
        let multibody = self.multibody();
        self.robot
            .joint_links
            .iter()
            .map(|&id| {
                multibody
                    .link(id)
                    .expect("joint link exists")
                    .joint
                    .coords()[ANG_X] as f64
            })
            .collect()
    }

    /// Joint velocities, rad/s (joint order).
    pub fn joint_velocities_rad_per_s(&self) -> Vec<f64> {
        let multibody = self.multibody();
        let velocities = multibody.generalized_velocity();
        self.robot
            .joint_links
            .iter()
            .map(|&id| {
                velocities[multibody.link(id).expect("joint link exists").assembly_id()] as f64
            })
            .collect()
    }

    /// The PD torque applied in the last step, N m (joint order).
    pub fn applied_torques_n_m(&self) -> &[f64] {
        &self.torques_n_m
    }

    /// The current PD targets, rad (joint order).
    pub fn joint_targets_rad(&self) -> &[f64] {
        &self.targets_rad
    }

    /// The default squat's joint angles, rad (joint order).
    pub fn squat_rad(&self) -> &[f64] {
        &self.squat_rad
    }

    /// The base's pose in the world frame.
    pub fn base_pose(&self) -> Isometry3<f64> {
        from_pose(self.physics.bodies[self.robot.bodies[0]].position())
    }

    /// The base's linear (m/s) and angular (rad/s) velocity, world frame.
    pub fn base_velocity(&self) -> (Vector3<f64>, Vector3<f64>) {
        let body = &self.physics.bodies[self.robot.bodies[0]];
        (from_vector(body.linvel()), from_vector(body.angvel()))
    }

    /// Every model body's pose in the world frame (model body order).
    pub fn body_poses(&self) -> Vec<Isometry3<f64>> {
        self.robot
            .bodies
            .iter()
            .map(|&h| from_pose(self.physics.bodies[h].position()))
            .collect()
    }

    /// The robot's centre of mass (all links), world frame, m.
    pub fn centre_of_mass_m(&self) -> Vector3<f64> {
        let (mut mass_kg, mut moment) = (0.0, Vector3::zeros());
        for (body, pose) in self.model().bodies.iter().zip(self.body_poses()) {
            mass_kg += body.mass_kg;
            moment += body.mass_kg * (pose * nalgebra::Point3::from(body.com_in_body_m)).coords;
        }
        moment / mass_kg
    }

    /// Foot (toe centre) positions in the world frame, per leg.
    pub fn feet_in_world_m(&self) -> [Vector3<f64>; 4] {
        self.model.legs.clone().map(|leg| {
            let pose = from_pose(self.physics.bodies[self.robot.bodies[leg.foot_body]].position());
            (pose * Point3::from(leg.foot_in_body_m)).coords
        })
    }

    /// The velocity of each foot's lowest material point (the bottom of its
    /// sphere, where it meets flat ground), world frame, m/s, per leg: zero
    /// while a foot rolls on the ground without sliding, however its centre
    /// moves.
    pub fn foot_sole_velocities_m_per_s(&self) -> [Vector3<f64>; 4] {
        self.model.legs.clone().map(|leg| {
            let body = &self.physics.bodies[self.robot.bodies[leg.foot_body]];
            let centre = from_pose(body.position()) * Point3::from(leg.foot_in_body_m);
            let sole = centre.coords - Vector3::z() * leg.foot_radius_m;
            from_vector(body.velocity_at_point(to_vector(&sole)))
        })
    }

    /// Angle between the base's up axis and the world's, rad.
    pub fn tilt_rad(&self) -> f64 {
        let up = self.base_pose().rotation * Vector3::z();
        up.z.clamp(-1.0, 1.0).acos()
    }

    /// Which robot parts touch the ground now: the exact distance between
    /// each robot collider and every terrain collider the narrow phase pairs
    /// it with is at most [`TOUCH_DISTANCE_M`]. (The narrow phase's own
    /// contact manifolds are not read: with contact recycling their
    /// distances can be several steps old.)
    pub fn ground_contacts(&self) -> GroundContacts {
        self.contacts(Examined::All)
    }

    /// Which feet touch the ground now: [`Self::ground_contacts`]'s `feet`,
    /// without examining the other links.
    pub fn feet_touching_ground(&self) -> [bool; 4] {
        self.contacts(Examined::Feet).feet
    }

    /// The links other than feet that touch the ground now (the termination
    /// check: feet are not examined).
    pub fn non_foot_contacts(&self) -> Vec<String> {
        self.contacts(Examined::NonFeet).non_foot_links
    }

    /// Each hip (abduction joint) in the world frame, m, per leg.
    pub fn hips_in_world_m(&self) -> [Point3<f64>; 4] {
        let base = self.base_pose();
        self.legs
            .each_ref()
            .map(|leg| base * Point3::from(leg.abduction_m))
    }

    /// h_b: height of each hip (abduction) joint above the terrain right
    /// below it, m.
    pub fn hip_heights_m(&self) -> [f64; 4] {
        self.hips_in_world_m()
            .map(|hip| hip.z - self.surface_height_m(hip.x, hip.y))
    }

    /// The mean hip (abduction joint) height above the mean surface height
    /// under the feet that touch the ground (under all four feet when none
    /// does), m: the base's height above what it stands on. Where the feet
    /// have sunk the ground below them (soil) this is h_b plus the holes'
    /// depth; on rigid flat ground it is h_b.
    pub fn base_height_above_feet_m(&self) -> f64 {
        let hips_z_m = self.hips_in_world_m().iter().map(|hip| hip.z).sum::<f64>() / 4.0;
        let feet = self.feet_in_world_m();
        let touching = self.feet_touching_ground();
        let standing = touching.iter().any(|&t| t);
        let (sum_m, count) = feet
            .iter()
            .zip(touching)
            .filter(|(_, touches)| *touches || !standing)
            .fold((0.0, 0usize), |(sum, n), (foot, _)| {
                (sum + self.surface_height_m(foot.x, foot.y), n + 1)
            });
        hips_z_m - sum_m / count as f64
    }

    /// The inclination of the rest surface under the robot along its
    /// heading, radians, in the sense of the base's pitch (nalgebra's Euler
    /// pitch, about y: a base lying on ground that rises ahead has a
    /// negative pitch, and so has this): -atan2(rise, run) from the rest
    /// height below the mean of the front hips to that below the mean of
    /// the rear hips. 0 where the ground at rest is level.
    pub fn ground_pitch_rad(&self) -> f64 {
        let (mut front, mut rear) = self.front_and_rear_means_m(self.hips_in_world_m());
        front.z = self.rest_height_m(front.x, front.y);
        rear.z = self.rest_height_m(rear.x, rear.y);
        pitch_of_rise_rad(front, rear)
    }

    /// The inclination along the robot's heading of the ground its feet
    /// stand on, radians, in the sense of the base's pitch (as
    /// [`Self::ground_pitch_rad`]): -atan2(rise, run) from the surface
    /// height now (holes included) below the mean of the rear feet to that
    /// below the mean of the front feet. Where the ground does not give
    /// this is the rest surface's inclination between the feet; on soil it
    /// includes the holes the feet stand in, so a base that leans with the
    /// front feet's deeper holes leans with its ground.
    pub fn feet_ground_pitch_rad(&self) -> f64 {
        let ground_under_feet = self
            .feet_in_world_m()
            .map(|foot| Point3::new(foot.x, foot.y, self.surface_height_m(foot.x, foot.y)));
        let (front, rear) = self.front_and_rear_means_m(ground_under_feet);
        pitch_of_rise_rad(front, rear)
    }

    /// The means of the front legs' and of the rear legs' points (one per
    /// leg, in the legs' order), m.
    fn front_and_rear_means_m(&self, points: [Point3<f64>; 4]) -> (Vector3<f64>, Vector3<f64>) {
        let (mut front, mut rear) = ((Vector3::zeros(), 0), (Vector3::zeros(), 0));
        for (leg, point) in self.legs().iter().zip(points) {
            let pair = if leg.abduction_m.x > 0.0 {
                &mut front
            } else {
                &mut rear
            };
            pair.0 += point.coords;
            pair.1 += 1;
        }
        let mean = |(sum, n): (Vector3<f64>, usize)| sum / n.max(1) as f64;
        (mean(front), mean(rear))
    }

    /// The mean of h_b, the base height the task's reward and termination
    /// use, m.
    pub fn base_height_m(&self) -> f64 {
        self.hip_heights_m().iter().sum::<f64>() / 4.0
    }

    /// The state now, for loggers and viewers: `tiles_half_side_m` sets the
    /// square around the base whose tiles are included (0: none); `phase`
    /// and `goal_xy_m` are the caller's (the task's).
    pub fn snapshot(
        &self,
        tiles_half_side_m: f64,
        phase: usize,
        goal_xy_m: Option<[f64; 2]>,
    ) -> crate::snapshot::StepSnapshot {
        let base = self.base_pose();
        let (roll, pitch, yaw) = base.rotation.euler_angles();
        let mut tiles = Vec::new();
        if tiles_half_side_m > 0.0 {
            let centre = [base.translation.x, base.translation.y];
            self.terrain().tiles_in(
                self.physics(),
                terrain_plugins::Rect::around(centre, tiles_half_side_m),
                &mut tiles,
            );
        }
        crate::snapshot::StepSnapshot {
            sim_time_s: self.time_secs(),
            phase,
            body_poses: self.body_poses(),
            base_rpy_rad: [roll, pitch, yaw],
            base_height_m: self.base_height_m(),
            joint_torques_n_m: self.applied_torques_n_m().to_vec(),
            contact_points_m: self.ground_contact_points_m(),
            tiles,
            goal_xy_m,
            observed_goal_xy_m: None,
            height_scan_points_m: Vec::new(),
        }
    }

    /// Where the robot touches the ground now, world frame, m: one point
    /// (midway between the two surfaces) per robot collider and terrain
    /// collider within [`TOUCH_DISTANCE_M`] of each other, with the leg
    /// whose foot it is (`None` for other links). Same exact test as
    /// [`Self::ground_contacts`].
    pub fn ground_contact_points_m(&self) -> Vec<(Vector3<f64>, Option<usize>)> {
        let mut points = Vec::new();
        for (handle, _, foot_leg) in &self.robot.colliders {
            let collider = &self.physics.colliders[*handle];
            for other in self.paired_colliders(*handle) {
                if let Ok(Some(contact)) = terrain_plugins::rapier3d::parry::query::contact(
                    collider.position(),
                    collider.shape(),
                    other.position(),
                    other.shape(),
                    TOUCH_DISTANCE_M as f32,
                ) {
                    let mid = (contact.point1 + contact.point2) * 0.5;
                    points.push((from_vector(mid), *foot_leg));
                }
            }
        }
        points
    }

    /// The colliders the narrow phase pairs with `handle`.
    fn paired_colliders(&self, handle: ColliderHandle) -> impl Iterator<Item = &Collider> + '_ {
        self.physics.contact_pairs_with(handle).map(move |pair| {
            let other = if pair.collider1 == handle {
                pair.collider2
            } else {
                pair.collider1
            };
            &self.physics.colliders[other]
        })
    }

    fn contacts(&self, examined: Examined) -> GroundContacts {
        let mut contacts = GroundContacts::default();
        for (handle, link, foot_leg) in &self.robot.colliders {
            let known = match (foot_leg, examined) {
                (Some(_), Examined::NonFeet) | (None, Examined::Feet) => true,
                (Some(leg), _) => contacts.feet[*leg],
                (None, _) => contacts.non_foot_links.contains(link),
            };
            if known {
                continue;
            }
            let collider = &self.physics.colliders[*handle];
            let touching = self.paired_colliders(*handle).any(|other| {
                terrain_plugins::rapier3d::parry::query::distance(
                    collider.position(),
                    collider.shape(),
                    other.position(),
                    other.shape(),
                )
                .is_ok_and(|d| d.distance as f64 <= TOUCH_DISTANCE_M)
            });
            if !touching {
                continue;
            }
            match foot_leg {
                Some(leg) => contacts.feet[*leg] = true,
                None => contacts.non_foot_links.push(link.clone()),
            }
        }
        contacts
    }

    /// The terrain.
    pub fn terrain(&self) -> &dyn Terrain {
        self.terrain.as_ref()
    }

    /// The rapier world (read-only).
    pub fn physics(&self) -> &PhysicsWorld {
        &self.physics
    }

    /// The robot model.
    pub fn model(&self) -> &RobotModel {
        &self.model
    }

    /// Per-leg kinematics (FK/IK in the base frame).
    pub fn legs(&self) -> &[LegKinematics; 4] {
        &self.legs
    }

    /// Simulated time since the world was made, s.
    pub fn time_secs(&self) -> f64 {
        self.time_secs
    }

    /// Physics steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Height of the terrain surface right below (x, y), m.
    pub fn surface_height_m(&self, x_m: f64, y_m: f64) -> f64 {
        self.terrain.surface_height_m(&self.physics, x_m, y_m)
    }

    /// Height of the terrain surface right below (x, y) with nothing on it, m.
    pub fn rest_height_m(&self, x_m: f64, y_m: f64) -> f64 {
        self.terrain.rest_height_m(x_m, y_m)
    }

    fn multibody(&self) -> &Multibody {
        self.physics
            .multibody_joints
            .get_multibody(self.robot.multibody)
            .expect("the robot's multibody exists")
    }
}

/// The robot's multibody in `physics`.
fn multibody_mut(physics: &mut PhysicsWorld, index: MultibodyIndex) -> &mut Multibody {
    physics
        .multibody_joints
        .get_multibody_mut(index)
        .expect("the robot's multibody exists")
}

/// The joint angles of the squat every episode starts from, in the
/// model's joint order: each foot `SQUAT_FOOT_DEPTH_M` below its abduction
/// joint and `SQUAT_FOOT_WIDTH_M` to its side, by IK.
pub fn squat_rad_of(model: &RobotModel, legs: &[LegKinematics; 4]) -> Result<Vec<f64>, WorldError> {
    let mut squat_rad = vec![0.0; model.joints.len()];
    for (leg, kin) in model.legs.iter().zip(legs) {
        let target = Vector3::new(
            kin.abduction_m.x,
            SQUAT_FOOT_WIDTH_M * leg.name.side_sign(),
            -SQUAT_FOOT_DEPTH_M,
        );
        let sol = kin.inverse(target);
        if sol.clamped {
            return Err(WorldError::SquatUnreachable(leg.name.short()));
        }
        for (k, &j) in leg.joints.iter().enumerate() {
            squat_rad[j] = sol.q_rad[k];
        }
    }
    Ok(squat_rad)
}

fn insert_robot(
    physics: &mut PhysicsWorld,
    model: &RobotModel,
    config: &WorldConfig,
) -> Result<RobotHandles, WorldError> {
    let zero = vec![0.0; model.joints.len()];
    let poses = model.body_poses_in_base(&zero);
    let mut bodies = Vec::with_capacity(model.bodies.len());
    let mut colliders = Vec::new();
    for (body, pose) in model.bodies.iter().zip(&poses) {
        let mass = MassProperties::with_inertia_matrix(
            to_vector(&body.com_in_body_m),
            body.mass_kg as f32,
            to_matrix(&body.inertia_kg_m2),
        );
        let rigid_body = RigidBodyBuilder::dynamic()
            .pose(to_pose(pose))
            .additional_mass_properties(mass)
            .can_sleep(false);
        let handle = physics.insert_body(rigid_body);
        for shape in &body.collisions {
            let mut shape_pose = shape.shape_in_body;
            let builder = match &shape.geometry {
                Geometry::Box { half_extents_m: h } => {
                    ColliderBuilder::cuboid(h.x as f32, h.y as f32, h.z as f32)
                }
                Geometry::Sphere { radius_m } => ColliderBuilder::ball(*radius_m as f32),
                Geometry::Capsule {
                    radius_m,
                    half_length_m,
                } => ColliderBuilder::capsule_z(*half_length_m as f32, *radius_m as f32),
                Geometry::Cylinder {
                    radius_m,
                    half_length_m,
                } => {
                    // rapier's cylinders run along y, URDF's along z.
                    shape_pose *= UnitQuaternion::from_axis_angle(
                        &Vector3::x_axis(),
                        std::f64::consts::FRAC_PI_2,
                    );
                    ColliderBuilder::cylinder(*half_length_m as f32, *radius_m as f32)
                }
                Geometry::ConvexHull { points_m } => {
                    let points: Vec<Vector> = points_m.iter().map(to_vector).collect();
                    ColliderBuilder::convex_hull(&points)
                        .ok_or_else(|| WorldError::DegenerateShape(shape.link.clone()))?
                }
            };
            let collider = builder
                .position(to_pose(&shape_pose))
                .density(0.0)
                .friction(config.friction as f32)
                .collision_groups(robot_collision_groups());
            let collider_handle = physics.insert_collider(collider, Some(handle));
            let foot_leg = shape
                .is_foot
                .then(|| model.legs.iter().position(|l| l.foot_body == bodies.len()))
                .flatten();
            colliders.push((collider_handle, shape.link.clone(), foot_leg));
        }
        bodies.push(handle);
    }

    // Joints: the frame whose x is the joint axis, so rapier's AngX is the joint.
    for joint in &model.joints {
        let axis = joint.axis_in_child.into_inner();
        let align = UnitQuaternion::rotation_between(&Vector3::x(), &axis).unwrap_or_else(|| {
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI)
        });
        let frame2 = Isometry3::from_parts(nalgebra::Translation3::identity(), align);
        let frame1 = joint.child_in_parent * frame2;
        let mut builder = GenericJointBuilder::new(JointAxesMask::LOCKED_REVOLUTE_AXES)
            .local_frame1(to_pose(&frame1))
            .local_frame2(to_pose(&frame2));
        if config.pd == PdModel::Motor {
            builder = builder
                .motor_model(JointAxis::AngX, MotorModel::ForceBased)
                .motor_position(
                    JointAxis::AngX,
                    0.0,
                    config.kp_n_m_per_rad as f32,
                    config.kd_n_m_s_per_rad as f32,
                );
            if joint.effort_n_m.is_finite() {
                builder = builder.motor_max_force(JointAxis::AngX, joint.effort_n_m as f32);
            }
        }
        if let Some((lo, hi)) = joint.limits_rad {
            builder = builder.limits(JointAxis::AngX, [lo as f32, hi as f32]);
        }
        physics
            .multibody_joints
            .insert(
                bodies[joint.parent],
                bodies[joint.child],
                builder.build(),
                true,
            )
            .expect("a tree of new bodies makes a valid multibody");
    }
    let root_link = physics
        .multibody_joints
        .rigid_body_link(bodies[0])
        .expect("the root is in the multibody");
    let multibody = root_link.multibody;
    let joint_links: Vec<usize> = model
        .joints
        .iter()
        .map(|j| {
            physics
                .multibody_joints
                .rigid_body_link(bodies[j.child])
                .expect("every child is a link")
                .id
        })
        .collect();
    if config.pd == PdModel::ImplicitSpring {
        // kd as the joints' implicit damping; the springs are set before
        // every step (World::set_implicit_springs).
        let multibody = multibody_mut(physics, multibody);
        for &link_id in &joint_links {
            let dof = multibody
                .link(link_id)
                .expect("joint link exists")
                .assembly_id();
            multibody.damping_mut()[dof] = config.kd_n_m_s_per_rad as f32;
        }
    }
    Ok(RobotHandles {
        bodies,
        multibody,
        joint_links,
        colliders,
    })
}

/// -atan2(rise, run) from `rear` to `front` (world frame, m): the pitch, in
/// the sense of the base's, of a line that rises toward the front.
fn pitch_of_rise_rad(front: Vector3<f64>, rear: Vector3<f64>) -> f64 {
    let run = (front.xy() - rear.xy()).norm();
    -(front.z - rear.z).atan2(run)
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, SMatrix};
    use terrain_plugins::rapier3d::dynamics::sparse_dofs::add_quadform_on_dofs;

    use super::*;

    #[test]
    fn the_robots_body_jacobians_vanish_outside_their_ancestors_dofs() {
        // The vendored rapier (third_party/rapier3d) assembles the mass matrix
        // on each link's own and its ancestors' DOFs only, assuming the body
        // Jacobian is zero elsewhere. Checked on the Laikago settling onto 5 cm
        // tiles with its legs moving, where the result must equal nalgebra's
        // dense quadratic form bit for bit.
        let mut world =
            crate::test_worlds::laikago_on("elastic:5cm", 0, [0.0, 0.0], WorldConfig::default());
        let mut targets = world.joint_targets_rad().to_vec();
        for (j, target) in targets.iter_mut().enumerate() {
            *target += 0.05 * (j as f64 - 5.5) / 5.5;
        }
        world.set_joint_targets_rad(&targets);
        for _ in 0..60 {
            world.step();
        }
        let multibody = world.multibody();
        let ndofs = multibody.ndofs();
        assert_eq!(ndofs, 18, "a floating base and 12 hinges");
        let mid = SMatrix::<f32, 6, 6>::from_fn(|r, c| 1.0 / (1.0 + r as f32 + 2.0 * c as f32));
        let mut ranges = Vec::new();
        let mut legs_checked = 0;
        for link_id in 0..multibody.num_links() {
            multibody.link_dof_ranges(link_id, &mut ranges);
            let jacobian = multibody.body_jacobian(link_id);
            let within = |c: usize| ranges.iter().any(|&(c0, n)| (c0..c0 + n).contains(&c));
            for c in (0..ndofs).filter(|&c| !within(c)) {
                assert!(
                    jacobian.column(c).iter().all(|&x| x == 0.0),
                    "link {link_id}, column {c}: {:?}",
                    jacobian.column(c)
                );
            }
            let dofs: usize = ranges.iter().map(|&(_, n)| n).sum();
            if dofs == 9 {
                legs_checked += 1;
                assert!(jacobian.iter().any(|&x| x != 0.0));
            }
            let mut dense = DMatrix::<f32>::zeros(ndofs, ndofs);
            dense.quadform(1.0, &mid, jacobian, 1.0);
            let mut on_dofs = DMatrix::<f32>::zeros(ndofs, ndofs);
            add_quadform_on_dofs(&mut on_dofs, &mid, jacobian, &ranges);
            for (i, (a, b)) in dense.iter().zip(on_dofs.iter()).enumerate() {
                assert_eq!(a.to_bits(), b.to_bits(), "link {link_id}, entry {i}");
            }
        }
        assert_eq!(legs_checked, 4, "four lower legs, each on 6 + 3 DOFs");
    }
}
