//! The paper's locomotion task on one world: phases driven by the 27-D
//! action, the 102-D observation, the five reward terms, termination, goals.
//!
//! # Phase
//! One action drives one 0.75 s phase in which one foot swings (order
//! front-left, rear-right, front-right, rear-left) while the stance feet
//! hold the world positions they had at the phase start. The three Bezier
//! curves (see [`crate::action`]) are sampled at t = i / 180, i = 1..=180;
//! for every sample the target base pose is
//! `base_target = base_start * (translate(B_pos(t)) * rotate(B_rpy(t)))`
//! (roll, pitch, yaw about the base's x, y, z), each foot's target in that
//! base frame is solved by IK, the joint angles become PD targets, and the
//! world takes one 1/240 s step.
//!
//! # Observation (102 values with every block of the paper switched on)
//!
//! | block | size | unit | frame |
//! | --- | --- | --- | --- |
//! | h_b: height of each hip (abduction) joint above the terrain right below it, FR FL RR RL | 4 | m | world z |
//! | gravity direction | 3 | unit vector | base |
//! | base linear velocity | 3 | m/s | base |
//! | base angular velocity | 3 | rad/s | base |
//! | pitch | 1 | rad | world (Euler) |
//! | foot positions at the start of the three previous phases (oldest first) and now, FR FL RR RL x y z each (switch `foot_history`: off keeps only "now", 12; `foot_history_phases` = 1 or 2 keeps that many newest phase starts) | 48 | m | base |
//! | foot positions 1 and 2 physics steps ago (4.2 and 8.3 ms; switch `short_history`) | 24 | m | base |
//! | foot velocities, (p_now - p_prev_step) / dt (switch `foot_velocity`) | 12 | m/s | base |
//! | goal azimuth phi_g = atan2(goal y, goal x) | 1 | rad | base |
//! | goal position x, y | 2 | m | base |
//! | phase: index of the phase about to run (0 FL, 1 RR, 2 FR, 3 RL) / 4 | 1 | - | - |
//! | only with `height_scan` (not the paper's): the base's height above the ground at 6 rows 0.1-1.1 m ahead x 3 points 0.15 m apart across its heading ([`crate::height_scan`]) | 18 | m | world z, points in the heading frame |
//! | only with [`ActionPrior::ScriptedCrawl`]: the crawl's action for the phase about to run | 27 | action units | - |
//!
//! # Reward (per phase, summed)
//! - R_d = alpha_d (|rho_prev| - |rho|): progress toward the goal since the
//!   phase start (rho: goal x, y in the base frame); alpha_d = 10 when
//!   closer, 1 otherwise. The paper prints |rho| - |rho_prev|, which would
//!   reward walking away; its text ("checks whether the robot is moving
//!   towards the goal") and alpha_d's condition say progress, so the sign is
//!   flipped here.
//!   This per-phase progress pays for rocking (10x for each step forward,
//!   1x for each step back): measured on `elastic:5cm`, a policy collected a
//!   distance term of ~0.13 per phase while its net distance per episode
//!   stayed near 0. `distance_reward = "new_ground"` in `[task]`
//!   ([`DistanceReward::NewGround`]) pays 10x only for ground not covered
//!   before in the episode (progress past the closest approach to the
//!   current goal) and charges 1x for every step away, so rocking does not
//!   pay; for a robot that only ever moves toward the goal it equals the
//!   paper's term, which stays the default. `max_paid_progress_m` caps the
//!   new ground paid in one phase (R_d = 10 min(new ground, cap) - 1 x
//!   the move back): a pace cap, so that walking faster than it earns
//!   nothing and only risks the termination's cost. `distance_reward = "forward"`
//!   ([`DistanceReward::Forward`]) pays `forward_reward_per_m` (default 40)
//!   per metre of progress and charges the same per metre back: at 40 a
//!   gait of 2 cm per phase (8 m in 400 phases) earns 0.8 per phase, what
//!   standing earns from the other four terms. Measured: with the
//!   termination's -10 this pays a lunge (SAC learned to dive 0.4 m in
//!   three phases and fall, docs/notebook/2026-11-30-sac-on-5cm-tiles.md). `distance_reward = "tracking"`
//!   ([`DistanceReward::Tracking`]) pays exp(-((p - p*) / (p*/2))^2) for a
//!   phase's progress p and the target pace p* = `target_progress_m`
//!   (default 2.5 cm per phase, 10 m in 400 phases): at most 1 per phase,
//!   about 0 for standing and for a lunge (legged_gym's velocity-tracking
//!   kernel).
//! - `balance_terms = "penalty"` ([`BalanceTerms::Penalty`]) shifts the
//!   other four terms by their best value (R_o - 0.2, R_s - 0.1,
//!   R_t - 0.56, R_r - 0.2): the same shapes and gradients, but standing
//!   still earns about -0.15 per phase instead of +0.8, so only progress
//!   pays (legged_gym's and Walk in the Park's convention: pay for velocity,
//!   charge for imbalance). The paper's `"paper"` stays the default.
//! - R_o = max(0, 0.02 (10 - |phi_g| in degrees)).
//! - R_s = 0.1 if the mean of h_b > 25 cm.
//! - R_t = max(0, 0.004 (140 - tau_ave)), tau_ave the mean over the phase's
//!   steps of the norm of the 12 applied joint torques (N m).
//! - R_r = max(0, 2 (0.1 - |roll| in rad)).
//!
//! # Termination (checked after every physics step; the phase's reward is then -10)
//! base height (mean h_b) below 20 cm; |pitch| above 15 degrees; any robot
//! link but a foot touching the ground.
//!
//! # Goals and episodes
//! After a reset the robot stands `settle_secs` (0.5 s) in the squat so
//! that each episode starts with the robot loaded on the ground.
//! The first goal is 2 m ahead (+x) of the seeded random start; once the
//! base is within `goal_reached_m` of it or past it along x, the next goal
//! is 2 m further. An episode is truncated (not terminated) after
//! `max_phases` phases.
//!
//! Not the paper's, an option for training: `first_goal_ahead_range_m` and
//! `goal_y_offset_range_m` draw the first goal's distance ahead and the
//! goals' line aside, so that episodes cut at 40 phases (about 2 m of gait)
//! still meet what a long episode does: a goal close by, beside the robot,
//! or just replaced by the next (a 400-phase evaluation passes eight).
//! `orientation_lookahead_m` makes R_o judge the heading by the first goal
//! on the line at least that far away, so passing a goal a little aside
//! (its azimuth swinging toward 90 degrees) does not pay a turn on the spot.
//! `[task.observation] goal_line_ahead_m = L` goes further: the goal blocks
//! of the observation show the point on the goals' line L m ahead of the
//! base along +x (pure pursuit's carrot) instead of the current goal, and
//! R_o heads for that point. The goals still count and still steer R_d, but
//! the policy sees neither a goal coming close nor the jump to the next
//! one, which is where the policies that observe the goals fall. Being
//! part of the observation, it travels with a checkpoint to `eval`, `play`
//! and `rollout`.

//!
//! # Files
//! | file | concept |
//! | --- | --- |
//! | `mod.rs` | the [`Task`]: reset, the phase loop, goals, snapshots |
//! | `config.rs` | [`TaskConfig`] and its choices ([`DistanceReward`], [`BalanceTerms`], [`ActionPrior`]) |
//! | `observation.rs` | [`ObservationConfig`] and the observation vector |
//! | `mirror.rs` | [`TaskMirror`]: the observation and action reflected left-right |
//! | `reward.rs` | [`RewardTerms`]: the five terms' formulas |
//! | `termination.rs` | [`Termination`] and its rules |

mod config;
mod mirror;
mod observation;
mod phase;
mod reward;
mod termination;

pub use config::{
    ActionPrior, BalanceTerms, BaseHeightReference, DistanceReward, PitchReference, StallRule,
    SwingHeightReference, TaskConfig, TaskConfigError,
};
pub use mirror::{MirrorError, TaskMirror, mirror_action};
pub use observation::{FOOT_HISTORY_PHASES, ObservationConfig};
pub use phase::PhaseRun;
pub use reward::RewardTerms;
pub use termination::Termination;

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::action::ACTION_SIZE;
use crate::controller::{PhaseController, RobotState, feet_in_base_m, point_in_base};
use crate::height_scan::scan_points_xy_m;
use crate::model::LegName;
use crate::snapshot::StepSnapshot;
use crate::world::World;

/// Swing order of the four phases of a cycle.
pub const SWING_ORDER: [LegName; 4] = [
    LegName::FrontLeft,
    LegName::RearRight,
    LegName::FrontRight,
    LegName::RearLeft,
];

/// What one phase did.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseOutcome {
    /// the phase's reward (the sum of the terms, or the termination reward)
    pub reward: f64,
    /// the terms (all zero when terminated)
    pub terms: RewardTerms,
    /// set when the episode terminated during this phase
    pub termination: Option<Termination>,
    /// the episode hit `max_phases`
    pub truncated: bool,
    /// physics steps taken (180 unless terminated)
    pub steps: usize,
    /// IK targets clamped to the workspace during the phase
    pub ik_clamped: usize,
    /// mean of h_b over the phase's steps, m
    pub mean_base_height_m: f64,
    /// smallest and largest mean h_b over the phase's steps, m
    pub base_height_range_m: (f64, f64),
    /// how many goals were reached this phase
    pub goals_reached: usize,
    /// the terrain region under the base at the phase end
    pub region: usize,
}

#[derive(Debug, Clone)]
struct Episode {
    start_xy_m: [f64; 2],
    goal_xy_m: [f64; 2],
    goals_reached: usize,
    /// the closest the base came to the current goal in this episode, m
    closest_goal_distance_m: f64,
    /// the new ground made toward the goals by the end of each phase so
    /// far, from 0 at the start, m (kept only under a [`StallRule`])
    new_ground_by_phase_m: Vec<f64>,
    done: bool,
}

/// The locomotion task on one world.
pub struct Task {
    world: World,
    config: TaskConfig,
    rng: ChaCha8Rng,
    /// the observation, the phase plan and the joint targets
    controller: PhaseController,
    episode: Episode,
}

impl Task {
    /// Wraps a world; `seed` drives the start positions. Call [`Self::reset`]
    /// before the first phase.
    pub fn new(world: World, config: TaskConfig, seed: u64) -> Self {
        let controller = PhaseController::of_world(
            &world,
            config.observation,
            config.action_prior,
            config.swing_height_reference,
        );
        Self {
            world,
            config,
            rng: ChaCha8Rng::seed_from_u64(seed),
            controller,
            episode: Episode {
                start_xy_m: [0.0; 2],
                goal_xy_m: [0.0; 2],
                goals_reached: 0,
                closest_goal_distance_m: 0.0,
                new_ground_by_phase_m: Vec::new(),
                done: true,
            },
        }
    }

    /// Number of observation values.
    pub fn observation_size(&self) -> usize {
        self.config.observation_size()
    }

    /// The action the prior gives for the phase about to run (zeros without
    /// a prior).
    pub fn prior_action(&self) -> [f32; ACTION_SIZE] {
        self.controller
            .prior_action(&RobotState::of_world(&self.world))
    }

    /// The controller that plans the phases and writes the observation.
    pub fn controller(&self) -> &PhaseController {
        &self.controller
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The world, to craft states (tests, tools).
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// The settings.
    pub fn config(&self) -> &TaskConfig {
        &self.config
    }

    /// The current goal, world x, y, m.
    pub fn goal_xy_m(&self) -> [f64; 2] {
        self.episode.goal_xy_m
    }

    /// Where this episode started, world x, y, m.
    pub fn start_xy_m(&self) -> [f64; 2] {
        self.episode.start_xy_m
    }

    /// Phases run in this episode.
    pub fn phase(&self) -> usize {
        self.controller.phase()
    }

    /// Whether the episode has ended (terminated or truncated).
    pub fn done(&self) -> bool {
        self.episode.done
    }

    /// Goals reached in this episode.
    pub fn goals_reached(&self) -> usize {
        self.episode.goals_reached
    }

    /// Where each foot is in the squat, base frame (FR, FL, RR, RL), m.
    pub fn squat_feet_in_base_m(&self) -> &[Vector3<f64>; 4] {
        self.controller.squat_feet_in_base_m()
    }

    /// Re-seeds the start-position draw (as [`Self::new`]'s `seed` does).
    pub fn set_seed(&mut self, seed: u64) {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
    }

    /// Starts an episode at a seeded random position; writes the first
    /// observation into `obs`.
    pub fn reset(&mut self, obs: &mut [f32]) {
        let (x0, x1) = self.config.start_x_range_m;
        let (y0, y1) = self.config.start_y_range_m;
        let x = if x1 > x0 {
            self.rng.random_range(x0..x1)
        } else {
            x0
        };
        let y = if y1 > y0 {
            self.rng.random_range(y0..y1)
        } else {
            y0
        };
        self.reset_at([x, y], obs);
    }

    /// Starts an episode at (x, y), heading +x, with the first goal drawn
    /// from `first_goal_ahead_range_m` and `goal_y_offset_range_m` (no draw
    /// for the paper's fixed goal, so its seeds keep their starts).
    pub fn reset_at(&mut self, start_xy_m: [f64; 2], obs: &mut [f32]) {
        let goal_offset_m = self.draw_goal_offset_m();
        self.world.reset_terrain();
        self.world.reset_robot(start_xy_m, 0.0);
        for _ in 0..(self.config.settle_secs / self.world.dt_secs()).round() as usize {
            self.world.step();
        }
        self.begin_episode_toward(goal_offset_m, obs);
    }

    /// The first goal relative to the start (x ahead, y aside), m.
    fn draw_goal_offset_m(&mut self) -> [f64; 2] {
        let mut draw = |(low, high): (f64, f64)| {
            if high > low {
                self.rng.random_range(low..high)
            } else {
                low
            }
        };
        let ahead_m = match self.config.first_goal_ahead_range_m {
            Some(range) => draw(range),
            None => self.config.goal_spacing_m,
        };
        [ahead_m, draw(self.config.goal_y_offset_range_m)]
    }

    /// Starts an episode from the world as it is now (no reset, no
    /// settling): the goal is `goal_spacing_m` ahead of the base along +x.
    /// For crafted states; [`Self::reset`] is the normal start.
    pub fn begin_episode(&mut self, obs: &mut [f32]) {
        self.begin_episode_toward([self.config.goal_spacing_m, 0.0], obs);
    }

    /// [`Self::begin_episode`] with the first goal at `goal_offset_m`
    /// (ahead, aside) from the base.
    fn begin_episode_toward(&mut self, goal_offset_m: [f64; 2], obs: &mut [f32]) {
        let base = self.world.base_pose().translation.vector;
        let start_xy_m = [base.x, base.y];
        self.controller
            .begin_episode(&RobotState::of_world(&self.world));
        self.episode = Episode {
            start_xy_m,
            goal_xy_m: [
                start_xy_m[0] + goal_offset_m[0],
                start_xy_m[1] + goal_offset_m[1],
            ],
            goals_reached: 0,
            closest_goal_distance_m: 0.0,
            new_ground_by_phase_m: vec![0.0],
            done: false,
        };
        self.episode.closest_goal_distance_m = self.goal_in_base().norm();
        self.observe(obs);
    }

    /// The swing leg of the phase about to run.
    pub fn swing_leg(&self) -> LegName {
        self.controller.swing_leg()
    }

    /// The state now, for loggers and viewers; `tiles_half_side_m` sets the
    /// square around the base whose tiles are included (0: none).
    pub fn snapshot(&self, tiles_half_side_m: f64) -> StepSnapshot {
        // During a phase `phase()` is the running phase; between phases it
        // is the next one.
        let mut snapshot = self.world.snapshot(
            tiles_half_side_m,
            self.phase(),
            Some(self.episode.goal_xy_m),
        );
        snapshot.observed_goal_xy_m = self.observed_goal_xy_m();
        if self.config.observation.height_scan {
            snapshot.height_scan_points_m = scan_points_xy_m(&self.world.base_pose())
                .iter()
                .map(|&[x, y]| [x, y, self.world.surface_height_m(x, y)])
                .collect();
        }
        snapshot
    }

    /// The world x, y of what the observation's goal blocks show, where that
    /// is not the current goal (`goal_line_ahead_m`), m.
    pub fn observed_goal_xy_m(&self) -> Option<[f64; 2]> {
        self.config.observation.goal_line_ahead_m.map(|ahead_m| {
            [
                self.world.base_pose().translation.x + ahead_m,
                self.episode.goal_xy_m[1],
            ]
        })
    }

    fn advance_goals(&mut self) -> usize {
        let mut reached = 0;
        loop {
            let base = self.world.base_pose().translation.vector;
            let [gx, gy] = self.episode.goal_xy_m;
            let distance = (gx - base.x).hypot(gy - base.y);
            if distance < self.config.goal_reached_m || base.x > gx {
                self.episode.goal_xy_m[0] += self.config.goal_spacing_m;
                self.episode.goals_reached += 1;
                reached += 1;
            } else {
                return reached;
            }
        }
    }

    /// Feet in the current base frame.
    fn feet_in_base(&self) -> [Vector3<f64>; 4] {
        feet_in_base_m(&self.world.base_pose(), self.world.feet_in_world_m())
    }

    /// The mean of h_b, m: the base height of the statistics (Table I's
    /// mu(h_b) and sigma(h_b)) and, with the paper's
    /// `base_height_reference`, of the reward and termination.
    pub fn base_height_m(&self) -> f64 {
        self.world.base_height_m()
    }

    /// The base height the termination and the height term R_s judge, m:
    /// `hips_mean_m` (the mean of h_b, [`Self::base_height_m`]) with the
    /// paper's reference, the height above the feet's ground with `feet`.
    pub(super) fn judged_base_height_m(&self, hips_mean_m: f64) -> f64 {
        match self.config.base_height_reference {
            BaseHeightReference::Hips => hips_mean_m,
            BaseHeightReference::Feet => self.world.base_height_above_feet_m(),
        }
    }

    /// h_b: height of each hip (abduction) joint above the terrain right below it.
    pub fn hip_heights_m(&self) -> [f64; 4] {
        self.world.hip_heights_m()
    }

    /// The goal's position in the base frame (x, y; z dropped).
    fn goal_in_base(&self) -> nalgebra::Vector2<f64> {
        self.in_base(self.episode.goal_xy_m)
    }

    /// A world point (x, y) in the base frame (x, y; z dropped).
    fn in_base(&self, xy_m: [f64; 2]) -> nalgebra::Vector2<f64> {
        point_in_base(&self.world.base_pose(), xy_m)
    }

    /// What R_o measures the heading against, in the base frame: the
    /// observed point when the observation shows the goals' line ahead;
    /// otherwise the first goal on the line (the current one, then every
    /// `goal_spacing_m` beyond) at least `orientation_lookahead_m` from the
    /// base.
    fn heading_target_in_base(&self) -> nalgebra::Vector2<f64> {
        if let Some(point_xy_m) = self.observed_goal_xy_m() {
            return self.in_base(point_xy_m);
        }
        let [gx, gy] = self.episode.goal_xy_m;
        let spacing_m = self.config.goal_spacing_m;
        let lookahead_m = self.config.orientation_lookahead_m;
        // a goal k spacings on is at least (k spacings - its distance now)
        // away, so this many cover any lookahead
        let most = (lookahead_m / spacing_m).ceil() as usize + 1;
        let mut target = self.goal_in_base();
        for k in 1..=most {
            if target.norm() >= lookahead_m {
                break;
            }
            target = self.in_base([gx + k as f64 * spacing_m, gy]);
        }
        target
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use nalgebra::{Isometry3, Vector3};

    use super::*;
    use crate::WorldConfig;
    use crate::action::SAMPLES_PER_PHASE;
    use crate::scripted::ScriptedCrawl;

    pub(super) fn task_on(spec: &str, config: TaskConfig, seed: u64) -> Task {
        let world = crate::test_worlds::laikago_on(spec, seed, [0.0, 0.0], WorldConfig::default());
        Task::new(world, config, seed)
    }

    /// A task whose robot is placed at `base` in the squat, episode begun there.
    fn crafted(base: Isometry3<f64>, config: TaskConfig) -> (Task, Vec<f32>) {
        let mut task = task_on("rigid", config, 0);
        let squat = task.world().squat_rad().to_vec();
        task.world_mut().place_robot(&base, &squat);
        let mut obs = vec![0.0; task.observation_size()];
        task.begin_episode(&mut obs);
        (task, obs)
    }

    fn block<'a>(task: &Task, obs: &'a [f32], name: &str) -> &'a [f32] {
        let blocks = task.config().observation.blocks();
        let range = blocks
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap_or_else(|| panic!("no block {name}"))
            .1
            .clone();
        &obs[range]
    }

    #[test]
    fn observation_has_102_values_in_documented_blocks_and_ablations_shrink_it() {
        let full = ObservationConfig::default();
        assert_eq!(full.size(), 102);
        let blocks = full.blocks();
        assert_eq!(blocks.last().unwrap().1.end, 102);
        let sizes: Vec<usize> = blocks.iter().map(|(_, r)| r.len()).collect();
        assert_eq!(sizes, vec![4, 3, 3, 3, 1, 36, 12, 24, 12, 1, 2, 1]);
        assert_eq!(
            ObservationConfig {
                foot_history: false,
                ..full
            }
            .size(),
            66
        );
        assert_eq!(
            ObservationConfig {
                short_history: false,
                ..full
            }
            .size(),
            78
        );
        assert_eq!(
            ObservationConfig {
                foot_velocity: false,
                ..full
            }
            .size(),
            90
        );
        // one phase shorter: the two newest phase starts (24 values)
        assert_eq!(
            ObservationConfig {
                foot_history_phases: 2,
                ..full
            }
            .size(),
            90
        );
        let none = ObservationConfig {
            foot_history: false,
            foot_history_phases: 3,
            short_history: false,
            foot_velocity: false,
            goal_line_ahead_m: None,
            privileged_critic: false,
            height_scan: false,
        };
        assert_eq!(none.size(), 30);
        assert_eq!(none.blocks().last().unwrap().1.end, 30);
        // the height scan: 18 values, the last block
        let scanned = ObservationConfig {
            height_scan: true,
            ..full
        };
        assert_eq!(scanned.size(), 102 + 18);
        assert_eq!(scanned.blocks().last().unwrap(), &("height_scan", 102..120));
    }

    /// With `height_scan` on, the observation ends with the base's height
    /// above the ground at each scan point, and viewers get the points on
    /// the ground.
    #[test]
    fn the_height_scan_block_is_the_base_height_above_each_point_and_viewers_get_the_points() {
        let config = TaskConfig {
            observation: ObservationConfig {
                height_scan: true,
                ..ObservationConfig::default()
            },
            ..TaskConfig::default()
        };
        let base = Isometry3::new(
            Vector3::new(0.3, 0.1, 0.5),
            Vector3::z() * std::f64::consts::FRAC_PI_4,
        );
        let (task, obs) = crafted(base, config);
        let scan = block(&task, &obs, "height_scan");
        let points = task.snapshot(0.0).height_scan_points_m;
        assert_eq!((scan.len(), points.len()), (18, 18));
        let z = task.world().base_pose().translation.z;
        for (h, [x, y, ground]) in scan.iter().zip(points) {
            assert!((ground - task.world().surface_height_m(x, y)).abs() < 1e-12);
            assert!(
                (f64::from(*h) - (z - ground)).abs() < 1e-5,
                "{h} at {x}, {y}"
            );
        }
        // the nearest row's centre, 0.1 m ahead along the 45-degree heading
        let [x, y, _] = task.snapshot(0.0).height_scan_points_m[1];
        let base_xy = task.world().base_pose().translation;
        let (dx, dy) = (x - base_xy.x, y - base_xy.y);
        assert!(
            (dx - 0.1 / 2f64.sqrt()).abs() < 1e-3 && (dy - dx).abs() < 1e-3,
            "{dx}, {dy}"
        );
    }

    #[test]
    fn a_robot_rolled_10_degrees_sees_gravity_tilted_10_degrees() {
        let roll = 10f64.to_radians();
        let base = Isometry3::new(Vector3::new(0.0, 0.0, 0.6), Vector3::x() * roll);
        let (task, obs) = crafted(base, TaskConfig::default());
        let g = block(&task, &obs, "gravity_in_base");
        let expected = [0.0, -roll.sin(), -roll.cos()];
        for (a, b) in g.iter().zip(expected) {
            assert!((*a as f64 - b).abs() < 1e-5, "{g:?} vs {expected:?}");
        }
        assert!(block(&task, &obs, "pitch")[0].abs() < 1e-5);
    }

    #[test]
    fn a_goal_straight_ahead_has_azimuth_zero_and_position_2_0() {
        let base = Isometry3::translation(0.3, -0.1, 0.6);
        let (task, obs) = crafted(base, TaskConfig::default());
        assert!(block(&task, &obs, "goal_azimuth")[0].abs() < 1e-6);
        let p = block(&task, &obs, "goal_position");
        assert!((p[0] - 2.0).abs() < 1e-5 && p[1].abs() < 1e-5, "{p:?}");
        // Turned 90 degrees left, the goal is on the right: azimuth -90 degrees, position (0, -2).
        let turned = Isometry3::new(
            Vector3::new(0.3, -0.1, 0.6),
            Vector3::z() * std::f64::consts::FRAC_PI_2,
        );
        let (task, obs) = crafted(turned, TaskConfig::default());
        assert!(
            (block(&task, &obs, "goal_azimuth")[0] as f64 + std::f64::consts::FRAC_PI_2).abs()
                < 1e-5
        );
        let p = block(&task, &obs, "goal_position");
        assert!(p[0].abs() < 1e-5 && (p[1] + 2.0).abs() < 1e-5, "{p:?}");
    }

    #[test]
    fn hip_heights_feet_histories_and_phase_read_the_crafted_state() {
        let base = Isometry3::translation(0.0, 0.0, 0.6);
        let (task, obs) = crafted(base, TaskConfig::default());
        // Hips sit 3 cm below the base origin; rigid ground at z = 0.
        for h in block(&task, &obs, "hip_heights") {
            assert!((*h as f64 - 0.57).abs() < 1e-5, "{h}");
        }
        let now = block(&task, &obs, "feet_now");
        let squat = task.squat_feet_in_base_m();
        for leg in 0..4 {
            for k in 0..3 {
                assert!((now[3 * leg + k] as f64 - squat[leg][k]).abs() < 1e-5);
            }
        }
        // At an episode's start every history entry is the current feet.
        let history = block(&task, &obs, "feet_at_previous_phase_starts");
        for chunk in history.chunks(12) {
            assert_eq!(chunk, now);
        }
        let short = block(&task, &obs, "feet_4_and_8_ms_ago");
        assert_eq!(&short[..12], now);
        assert!(
            block(&task, &obs, "foot_velocities")
                .iter()
                .all(|v| *v == 0.0)
        );
        assert_eq!(block(&task, &obs, "phase"), &[0.0]);
        let velocity: Vec<f32> = [
            block(&task, &obs, "base_linear_velocity"),
            block(&task, &obs, "base_angular_velocity"),
        ]
        .concat();
        assert!(velocity.iter().all(|v| *v == 0.0));
    }

    #[test]
    fn a_history_one_phase_shorter_keeps_the_two_newest_phase_starts() {
        let shorter = TaskConfig {
            observation: ObservationConfig {
                foot_history_phases: 2,
                ..ObservationConfig::default()
            },
            ..TaskConfig::default()
        };
        let mut full = task_on("rigid", TaskConfig::default(), 5);
        let mut short = task_on("rigid", shorter, 5);
        let (mut obs_f, mut obs_s) = (vec![0.0; 102], vec![0.0; 90]);
        full.reset(&mut obs_f);
        short.reset(&mut obs_s);
        // the same actions on the same world: three phase starts apart
        let action = [0.1f32; ACTION_SIZE];
        for _ in 0..3 {
            full.step_phase(&action, &mut obs_f);
            short.step_phase(&action, &mut obs_s);
        }
        let history_f = block(&full, &obs_f, "feet_at_previous_phase_starts");
        let history_s = block(&short, &obs_s, "feet_at_previous_phase_starts");
        assert_eq!(history_f.len(), 36);
        assert_eq!(history_s, &history_f[12..]);
        assert_ne!(
            &history_f[..12],
            &history_f[24..],
            "the phase starts differ"
        );
        assert_eq!(
            block(&full, &obs_f, "feet_now"),
            block(&short, &obs_s, "feet_now")
        );
    }

    #[test]
    fn on_the_crawl_prior_a_zero_action_walks_the_crawl_and_a_residual_is_added() {
        let prior = TaskConfig {
            action_prior: ActionPrior::ScriptedCrawl,
            ..TaskConfig::default()
        };
        let mut residual = task_on("elastic:2cm", prior, 3);
        let mut plain = task_on("elastic:2cm", TaskConfig::default(), 3);
        assert_eq!(residual.observation_size(), 102 + ACTION_SIZE);
        let (mut obs_r, mut obs_p) = (vec![0.0; 102 + ACTION_SIZE], vec![0.0; 102]);
        residual.reset(&mut obs_r);
        plain.reset(&mut obs_p);
        let crawl = ScriptedCrawl::default();
        for phase in 0..6 {
            // the paper's blocks, then the crawl's action for the coming phase
            assert_eq!(&obs_r[..102], &obs_p[..], "phase {phase}");
            let crawl_action = crawl.act(&plain);
            assert_eq!(&obs_r[102..], &crawl_action[..], "phase {phase}");
            // phases 0-2 a zero residual, then 0.3 on every value (clipped)
            let r = if phase < 3 { 0.0 } else { 0.3 };
            let composed: Vec<f32> = crawl_action
                .iter()
                .map(|a| (a + r).clamp(-1.0, 1.0))
                .collect();
            let out_r = residual.step_phase(&[r; ACTION_SIZE], &mut obs_r);
            let out_p = plain.step_phase(&composed, &mut obs_p);
            assert_eq!(out_r.reward, out_p.reward, "phase {phase}");
            assert_eq!(
                residual.world().base_pose(),
                plain.world().base_pose(),
                "phase {phase}"
            );
        }
        assert_eq!(
            ActionPrior::from_name("scripted_crawl"),
            Some(ActionPrior::ScriptedCrawl)
        );
        assert_eq!(
            ActionPrior::from_name(ActionPrior::None.name()),
            Some(ActionPrior::None)
        );
        assert_eq!(ActionPrior::from_name("crawl"), None);
    }

    /// At 120 Hz a phase is 90 steps of 1/120 s, 0.75 s as at 240 Hz,
    /// and the crawl moves the base on 5 cm tiles as at 240 Hz: within
    /// 1 cm along x over 12 phases (it crawls back 1.8-1.9 cm from this
    /// start at both rates), its mean height within 2 mm.
    #[test]
    fn at_half_the_paper_rate_a_phase_lasts_as_long_and_the_crawl_moves_alike() {
        let mut moved = Vec::new();
        for step_rate_hz in [240, 120] {
            let physics = WorldConfig {
                step_rate_hz,
                ..WorldConfig::default()
            };
            let world = crate::test_worlds::laikago_on("elastic:5cm", 3, [0.0, 0.0], physics);
            let mut task = Task::new(world, TaskConfig::default(), 3);
            let mut obs = vec![0.0; task.observation_size()];
            task.reset(&mut obs);
            let (x0, t0) = (
                task.world().base_pose().translation.x,
                task.world().time_secs(),
            );
            let mut height_sum_m = 0.0;
            for phase in 0..12 {
                let outcome = task.step_phase(&ScriptedCrawl::default().act(&task), &mut obs);
                assert!(
                    outcome.termination.is_none(),
                    "{step_rate_hz} Hz phase {phase}"
                );
                assert_eq!(outcome.steps, step_rate_hz as usize * 3 / 4);
                height_sum_m += outcome.mean_base_height_m;
            }
            let secs = task.world().time_secs() - t0;
            assert!(
                (secs - 12.0 * 0.75).abs() < 1e-9,
                "{step_rate_hz} Hz: {secs} s"
            );
            moved.push((
                task.world().base_pose().translation.x - x0,
                height_sum_m / 12.0,
            ));
        }
        let ((x240, h240), (x120, h120)) = (moved[0], moved[1]);
        assert!(
            (x240 - x120).abs() < 0.01,
            "{x240} m at 240 Hz, {x120} m at 120 Hz"
        );
        assert!(
            (h240 - h120).abs() < 0.002,
            "{h240} m at 240 Hz, {h120} m at 120 Hz"
        );
    }

    #[test]
    fn a_phase_reports_the_terms_it_earned() {
        let mut task = task_on("rigid", TaskConfig::default(), 3);
        let mut obs = vec![0.0; 102];
        task.reset(&mut obs);
        let goal_distance = |task: &Task| {
            let [gx, gy] = task.goal_xy_m();
            let base = task.world().base_pose().translation.vector;
            (gx - base.x).hypot(gy - base.y)
        };
        let before = goal_distance(&task);
        let outcome = task.step_phase(&ScriptedCrawl::default().act(&task), &mut obs);
        let after = goal_distance(&task);
        assert!(outcome.termination.is_none());
        assert_eq!(outcome.steps, SAMPLES_PER_PHASE);
        let t = outcome.terms;
        assert!((outcome.reward - t.total()).abs() < 1e-12);
        assert_eq!(t.height, 0.1, "the squat stands above 25 cm");
        assert!(t.torque > 0.0 && t.torque < 0.56, "{t:?}");
        assert!(t.roll > 0.0 && t.roll <= 0.2, "{t:?}");
        assert!(t.orientation > 0.0, "{t:?}");
        // R_d from the goal distance before and after (the base stays level
        // to within a degree, so the base-frame distance is the horizontal one)
        let expected = RewardTerms::distance_term(before, after);
        assert!(
            after != before && (t.distance - expected).abs() < 1e-3,
            "{t:?} vs {expected}"
        );
        assert_eq!(block(&task, &obs, "phase"), &[0.25]);
    }

    #[test]
    fn on_a_slope_the_pitch_is_judged_against_the_ground_when_asked() {
        // The robot in the air above a 20-degree rigid slope, lying along it
        // (nose up 20 degrees, heading +x, uphill).
        for (spec, x_m, degrees) in [
            ("slope:20", 1.0, 20.0),
            ("varying:4m:5cm,(elastic:5cm:slope=20)", 5.0, 20.0),
        ] {
            let tan = f64::tan(f64::to_radians(degrees));
            for (reference, expected_fall) in [
                (PitchReference::World, true),
                (PitchReference::Ground, false),
                (PitchReference::Feet, false),
            ] {
                let mut task = task_on(
                    spec,
                    TaskConfig {
                        pitch_reference: reference,
                        ..TaskConfig::default()
                    },
                    0,
                );
                let ground_m = task.world().rest_height_m(x_m, 0.0);
                let pose = Isometry3::new(
                    Vector3::new(x_m, 0.0, ground_m + 0.6),
                    Vector3::y() * -degrees.to_radians(),
                );
                let squat = task.world().squat_rad().to_vec();
                task.world_mut().place_robot(&pose, &squat);
                // the ground's pitch is the slope's, in the base pitch's sense
                let ground_pitch = task.world().ground_pitch_rad();
                assert!(
                    (ground_pitch + tan.atan()).abs() < 1e-3,
                    "{spec}: {}",
                    ground_pitch.to_degrees()
                );
                let termination = task.check_termination(task.base_height_m());
                assert_eq!(
                    matches!(termination, Some(Termination::PitchTooLarge { .. })),
                    expected_fall,
                    "{spec} {reference:?}: {termination:?}"
                );
                assert!(expected_fall || termination.is_none(), "{termination:?}");
            }
        }
        // level ground at rest: no inclination, tiles included
        let task = task_on("elastic:5cm", TaskConfig::default(), 0);
        assert_eq!(task.world().ground_pitch_rad(), 0.0);
    }

    #[test]
    fn with_the_feet_pitch_reference_a_base_leaning_into_fresh_soil_is_judged_against_its_feet() {
        // Rigid ground, then soil: a seed whose first region after the start
        // is soil puts a soil edge ahead of the robot.
        let spec = "varying:4m:rigid,(soil:4cm)";
        let (seed, edge_x_m) = (0..64)
            .find_map(|seed| {
                let task = task_on(spec, TaskConfig::default(), seed);
                let regions = task.world().terrain().regions();
                let next = regions.iter().find(|r| r.x_range_m.0 > 0.0)?;
                let start = regions.iter().find(|r| r.x_range_m.1 == next.x_range_m.0)?;
                (next.label.starts_with("soil") && start.label == "rigid")
                    .then_some((seed, next.x_range_m.0))
            })
            .expect("a seed with soil after the rigid start");
        let config = TaskConfig {
            min_base_height_m: 0.01,
            ..TaskConfig::default()
        };
        let mut task = task_on(spec, config, seed);
        // the front feet 8 cm onto the soil, the rear ones on rigid ground
        let front_foot_ahead_m =
            task.world().feet_in_world_m()[0].x - task.world().base_pose().translation.x;
        assert!(front_foot_ahead_m > 0.1, "{front_foot_ahead_m}");
        task.world_mut()
            .reset_robot([edge_x_m - front_foot_ahead_m + 0.08, 0.0], 0.0);
        let until_secs = task.world().time_secs() + 1.0;
        while task.world().time_secs() < until_secs {
            task.world_mut().step();
        }
        let world = task.world();
        let holes_m: Vec<f64> = world
            .feet_in_world_m()
            .iter()
            .map(|f| world.rest_height_m(f.x, f.y) - world.surface_height_m(f.x, f.y))
            .collect();
        let (front, rear): (Vec<_>, Vec<_>) = world
            .legs()
            .iter()
            .zip(&holes_m)
            .partition(|(leg, _)| leg.abduction_m.x > 0.0);
        assert!(front.iter().all(|(_, h)| **h > 0.01), "{holes_m:?}");
        assert!(rear.iter().all(|(_, h)| h.abs() < 1e-9), "{holes_m:?}");
        // the rest surface is level, the ground under the feet falls ahead,
        // and the base leans with it (nose down: a positive pitch)
        assert_eq!(world.ground_pitch_rad(), 0.0);
        let feet_pitch = world.feet_ground_pitch_rad();
        let (_, base_pitch, _) = world.base_pose().rotation.euler_angles();
        assert!(feet_pitch > 0.02, "{}", feet_pitch.to_degrees());
        assert!(base_pitch > 0.02, "{}", base_pitch.to_degrees());
        let against_feet = base_pitch - feet_pitch;
        assert!(
            against_feet.abs() < 0.5 * base_pitch,
            "base {} feet {}",
            base_pitch.to_degrees(),
            feet_pitch.to_degrees()
        );
        // A limit between the two: the horizontal calls it a fall, the feet's
        // ground does not; the rest surface's inclination is the horizontal's.
        task.config.max_pitch_deg = 0.5 * (base_pitch + against_feet.abs()).to_degrees();
        for (reference, falls) in [
            (PitchReference::World, true),
            (PitchReference::Ground, true),
            (PitchReference::Feet, false),
        ] {
            task.config.pitch_reference = reference;
            let termination = task.check_termination(task.base_height_m());
            assert_eq!(
                matches!(termination, Some(Termination::PitchTooLarge { .. })),
                falls,
                "{reference:?}: {termination:?}"
            );
        }
    }

    #[test]
    fn with_the_feet_reference_the_base_is_measured_from_the_holes_the_feet_stand_in() {
        // Rigid flat ground: both references give the hips' height.
        let mut obs = vec![0.0; 102];
        let mut task = task_on("rigid", TaskConfig::default(), 0);
        task.reset(&mut obs);
        let (hips, feet) = (
            task.base_height_m(),
            task.world().base_height_above_feet_m(),
        );
        assert!((hips - feet).abs() < 1e-9, "{hips} vs {feet}");

        // Soil: the crawl's feet dig holes that stay, the ground below the
        // hips stays up.
        let mut task = task_on(
            "soil:4cm",
            TaskConfig {
                min_base_height_m: 0.01,
                ..TaskConfig::default()
            },
            0,
        );
        task.reset(&mut obs);
        let crawl = ScriptedCrawl::default();
        for _ in 0..8 {
            let out = task.step_phase(&crawl.act(&task), &mut obs);
            assert!(out.termination.is_none(), "{out:?}");
        }
        let world = task.world();
        let (hips, feet) = (task.base_height_m(), world.base_height_above_feet_m());
        // what the feet stand on: the measure is the hips' mean height above
        // the soles of the feet that touch the ground (a sole rests on its
        // tile's top up to the contact's penetration)
        let hips_z_m = world.hips_in_world_m().iter().map(|hip| hip.z).sum::<f64>() / 4.0;
        let touching = world.feet_touching_ground();
        let radius_m = world.model().legs[0].foot_radius_m;
        let soles: Vec<f64> = world
            .feet_in_world_m()
            .iter()
            .zip(touching)
            .filter(|(_, t)| *t)
            .map(|(foot, _)| foot.z - radius_m)
            .collect();
        assert!(soles.len() >= 2, "{touching:?}");
        let above_soles = hips_z_m - soles.iter().sum::<f64>() / soles.len() as f64;
        assert!(
            (feet - above_soles).abs() < 0.005,
            "{feet} vs {above_soles}"
        );
        // the holes under the standing feet are deeper than the soil's
        // standing sink, and h_b counts them as a lower base
        let holes_m: Vec<f64> = world
            .feet_in_world_m()
            .iter()
            .zip(touching)
            .filter(|(_, t)| *t)
            .map(|(f, _)| world.rest_height_m(f.x, f.y) - world.surface_height_m(f.x, f.y))
            .collect();
        let mean_hole_m = holes_m.iter().sum::<f64>() / holes_m.len() as f64;
        assert!(mean_hole_m > 0.04, "{holes_m:?}");
        assert!(feet - hips > 0.02, "hips {hips} feet {feet}");

        // A limit between the two: the paper's reference calls it a fall,
        // the feet's does not.
        task.config.min_base_height_m = 0.5 * (hips + feet);
        for (reference, falls) in [
            (BaseHeightReference::Hips, true),
            (BaseHeightReference::Feet, false),
        ] {
            task.config.base_height_reference = reference;
            let termination = task.check_termination(task.judged_base_height_m(hips));
            assert_eq!(
                matches!(termination, Some(Termination::BaseTooLow { .. })),
                falls,
                "{reference:?}: {termination:?}"
            );
        }
    }

    #[test]
    fn each_termination_rule_fires() {
        // Base too low: a robot whose hips are below the limit.
        let (mut task, mut obs) = crafted(
            Isometry3::translation(0.0, 0.0, 0.6),
            TaskConfig {
                min_base_height_m: 0.65,
                ..TaskConfig::default()
            },
        );
        let out = task.step_phase(&[0.0; ACTION_SIZE], &mut obs);
        assert!(
            matches!(out.termination, Some(Termination::BaseTooLow { .. })),
            "{out:?}"
        );
        assert_eq!(out.reward, -10.0);
        assert_eq!(out.steps, 1);
        assert!(task.done());

        // Pitch: placed nose-down 20 degrees in the air.
        let pitched = Isometry3::new(
            Vector3::new(0.0, 0.0, 0.8),
            Vector3::y() * 20f64.to_radians(),
        );
        let (mut task, mut obs) = crafted(pitched, TaskConfig::default());
        let out = task.step_phase(&[0.0; ACTION_SIZE], &mut obs);
        assert!(
            matches!(out.termination, Some(Termination::PitchTooLarge { pitch_deg }) if pitch_deg > 15.0),
            "{out:?}"
        );

        // Non-foot contact: the body set down on the ground.
        let (mut task, mut obs) = crafted(
            Isometry3::translation(0.0, 0.0, 0.12),
            TaskConfig {
                min_base_height_m: 0.0,
                ..TaskConfig::default()
            },
        );
        let out = task.step_phase(&[0.0; ACTION_SIZE], &mut obs);
        match out.termination {
            Some(Termination::NonFootContact { links }) => assert!(
                links.iter().any(|l| l == "chassis" || l.contains("leg")),
                "{links:?}"
            ),
            other => panic!("expected a non-foot contact, got {other:?}"),
        }
    }

    #[test]
    fn goals_advance_two_metres_at_a_time() {
        let (mut task, mut obs) =
            crafted(Isometry3::translation(0.0, 0.0, 0.4), TaskConfig::default());
        assert_eq!(task.goal_xy_m(), [2.0, 0.0]);
        let squat = task.world().squat_rad().to_vec();
        task.world_mut()
            .place_robot(&Isometry3::translation(2.1, 0.0, 0.4), &squat);
        let out = task.step_phase(&[0.0; ACTION_SIZE], &mut obs);
        assert_eq!(out.goals_reached, 1, "{out:?}");
        assert_eq!(task.goal_xy_m(), [4.0, 0.0]);
    }

    #[test]
    fn first_goals_are_drawn_from_their_ranges_and_the_paper_goal_draws_nothing() {
        // The paper's goal: 2 m straight ahead of the start, and no draw, so
        // a seed's starts are the ones it had before the option existed.
        let starts = |config: TaskConfig| {
            let mut task = task_on("rigid", config, 7);
            let mut obs = vec![0.0; 102];
            (0..6)
                .map(|_| {
                    task.reset(&mut obs);
                    let [sx, sy] = task.start_xy_m();
                    let [gx, gy] = task.goal_xy_m();
                    ([sx, sy], [gx - sx, gy - sy], obs.clone())
                })
                .collect::<Vec<_>>()
        };
        let paper = starts(TaskConfig {
            settle_secs: 0.0,
            ..TaskConfig::default()
        });
        for (_, offset, _) in &paper {
            assert!(
                (offset[0] - 2.0).abs() < 1e-9 && offset[1].abs() < 1e-9,
                "{offset:?}"
            );
        }
        let pinned = starts(TaskConfig {
            settle_secs: 0.0,
            first_goal_ahead_range_m: Some((2.0, 2.0)),
            goal_y_offset_range_m: (0.0, 0.0),
            ..TaskConfig::default()
        });
        assert_eq!(
            paper.iter().map(|e| e.0).collect::<Vec<_>>(),
            pinned.iter().map(|e| e.0).collect::<Vec<_>>(),
            "degenerate ranges draw nothing: the same starts"
        );

        let drawn = TaskConfig {
            settle_secs: 0.0,
            first_goal_ahead_range_m: Some((0.1, 2.3)),
            goal_y_offset_range_m: (-0.4, 0.4),
            ..TaskConfig::default()
        };
        let episodes = starts(drawn.clone());
        assert_eq!(episodes[0].0, paper[0].0, "the start is drawn first");
        let layout = task_on("rigid", drawn.clone(), 7);
        for (_, [ahead, aside], obs) in &episodes {
            assert!((0.1..2.3).contains(ahead), "ahead {ahead}");
            assert!((-0.4..0.4).contains(aside), "aside {aside}");
            // the observation's goal block is that goal in the base frame
            // (the robot stands level, heading +x, after a reset)
            let goal = block(&layout, obs, "goal_position");
            assert!(
                (f64::from(goal[0]) - ahead).abs() < 0.02
                    && (f64::from(goal[1]) - aside).abs() < 0.02,
                "{goal:?} against [{ahead}, {aside}]"
            );
        }
        let aheads: Vec<f64> = episodes.iter().map(|e| e.1[0]).collect();
        assert!(
            aheads.windows(2).any(|w| (w[0] - w[1]).abs() > 0.1),
            "the draws differ between episodes: {aheads:?}"
        );
        let again = starts(drawn);
        assert_eq!(
            episodes.iter().map(|e| e.1).collect::<Vec<_>>(),
            again.iter().map(|e| e.1).collect::<Vec<_>>(),
            "a seed draws the same goals"
        );
    }

    #[test]
    fn the_orientation_term_heads_for_the_first_goal_past_the_lookahead() {
        // the base 10 cm short of the goal at (2, 0) and 25 cm aside of it
        let at = |lookahead_m: f64| {
            let (mut task, _) = crafted(
                Isometry3::translation(1.9, 0.25, 0.4),
                TaskConfig {
                    orientation_lookahead_m: lookahead_m,
                    ..TaskConfig::default()
                },
            );
            task.episode.goal_xy_m = [2.0, 0.0];
            let target = task.heading_target_in_base();
            (
                target,
                RewardTerms::orientation_term(target.y.atan2(target.x)),
            )
        };
        // the paper's: the current goal, 68 degrees to the right, pays nothing
        let (goal, paid) = at(0.0);
        assert!(
            (goal.x - 0.1).abs() < 1e-6 && (goal.y + 0.25).abs() < 1e-6,
            "{goal:?}"
        );
        assert_eq!(paid, 0.0);
        // a 1 m lookahead: the next goal, (4, 0), 6.8 degrees to the right
        let (next, paid) = at(1.0);
        assert!(
            (next.x - 2.1).abs() < 1e-6 && (next.y + 0.25).abs() < 1e-6,
            "{next:?}"
        );
        let azimuth_deg = (0.25f64 / 2.1).atan().to_degrees();
        assert!((paid - 0.02 * (10.0 - azimuth_deg)).abs() < 1e-6, "{paid}");
        // a goal already far enough is kept; a long lookahead skips several
        assert_eq!(at(0.2).0, goal);
        let (far, _) = at(5.0);
        assert!((far.x - 6.1).abs() < 1e-6, "{far:?}");
    }

    /// The critic's privileged values: on 5 cm tiles a standing robot's
    /// feet all sink, by less than twice the region's standing sink (the
    /// rear feet carry more: 4.5 cm against 1.9 cm at the front after the
    /// reset's settle), and touch the ground; on rigid ground nothing
    /// sinks. The policy's observation is unchanged.
    #[test]
    fn the_privileged_values_give_each_feet_sink_softness_and_contact() {
        let config = TaskConfig {
            observation: ObservationConfig {
                privileged_critic: true,
                ..ObservationConfig::default()
            },
            ..TaskConfig::default()
        };
        assert_eq!(config.observation_size(), 102);
        assert_eq!(config.observation.privileged_size(), 12);
        for (spec, sink_m) in [("elastic:5cm", 0.05f32), ("rigid", 0.0)] {
            let mut task = task_on(spec, config.clone(), 1);
            let mut obs = vec![0.0; task.observation_size()];
            task.reset(&mut obs);
            let mut privileged = vec![0.0; 12];
            task.observe_privileged(&mut privileged);
            for foot in privileged.chunks_exact(3) {
                assert_eq!(foot[1], sink_m, "{spec}: {privileged:?}");
                assert_eq!(foot[2], 1.0, "{spec}: {privileged:?}");
                if sink_m == 0.0 {
                    assert!(foot[0].abs() < 1e-3, "{spec}: {privileged:?}");
                } else {
                    assert!(
                        foot[0] > 0.01 && foot[0] < 2.0 * sink_m,
                        "{spec}: {privileged:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_goal_line_ahead_moves_with_the_base_and_r_o_heads_for_it() {
        let line_ahead = |ahead_m: f64| TaskConfig {
            observation: ObservationConfig {
                goal_line_ahead_m: Some(ahead_m),
                ..ObservationConfig::default()
            },
            ..TaskConfig::default()
        };
        // the base 10 cm short of the goal at (2, 0) and 25 cm aside of it,
        // heading +x: the point 1 m ahead on the line is (2.9, 0), at
        // (1, -0.25) in the base frame, whichever goal is current
        let (mut task, _) = crafted(Isometry3::translation(1.9, 0.25, 0.4), line_ahead(1.0));
        task.episode.goal_xy_m = [2.0, 0.0];
        let mut obs = vec![0.0; task.observation_size()];
        task.observe(&mut obs);
        let p = block(&task, &obs, "goal_position");
        assert!(
            (p[0] - 1.0).abs() < 1e-5 && (p[1] + 0.25).abs() < 1e-5,
            "{p:?}"
        );
        let azimuth = f64::from(block(&task, &obs, "goal_azimuth")[0]);
        assert!((azimuth - (-0.25f64).atan2(1.0)).abs() < 1e-5, "{azimuth}");
        let target = task.heading_target_in_base();
        assert!((target.x - 1.0).abs() < 1e-6 && (target.y + 0.25).abs() < 1e-6);
        // the next goal current (as right after passing this one): the same point
        task.episode.goal_xy_m = [4.0, 0.0];
        let mut after = vec![0.0; task.observation_size()];
        task.observe(&mut after);
        assert_eq!(block(&task, &after, "goal_position"), p);
        // viewers get the point in the world frame; the paper's task has none
        let [x, y] = task.snapshot(0.0).observed_goal_xy_m.unwrap();
        assert!((x - 2.9).abs() < 1e-6 && y.abs() < 1e-12, "{x}, {y}");
        let (paper, _) = crafted(
            Isometry3::translation(1.9, 0.25, 0.4),
            TaskConfig::default(),
        );
        assert_eq!(paper.snapshot(0.0).observed_goal_xy_m, None);
        assert!(paper.snapshot(0.0).height_scan_points_m.is_empty());
        // turned 90 degrees left at the line: the point is on the right, at (0, -1)
        let (task, obs) = crafted(
            Isometry3::new(
                Vector3::new(0.3, 0.0, 0.6),
                Vector3::z() * std::f64::consts::FRAC_PI_2,
            ),
            line_ahead(1.0),
        );
        let p = block(&task, &obs, "goal_position");
        assert!(p[0].abs() < 1e-5 && (p[1] + 1.0).abs() < 1e-5, "{p:?}");
        // the same observation size as the paper's: only what the blocks show changes
        assert_eq!(task.observation_size(), 102);
    }

    #[test]
    fn same_seed_same_rollout_bit_for_bit() {
        let run = |seed| {
            let mut task = task_on(
                "varying:2m:2,3cm,rigid",
                TaskConfig {
                    max_phases: 6,
                    ..TaskConfig::default()
                },
                seed,
            );
            let mut obs = vec![0.0; 102];
            task.reset(&mut obs);
            let mut trace = vec![obs.clone()];
            let crawl = ScriptedCrawl::default();
            while !task.done() {
                let out = task.step_phase(&crawl.act(&task), &mut obs);
                trace.push(obs.clone());
                trace.push(vec![out.reward as f32]);
            }
            trace
        };
        let a = run(5);
        assert_eq!(a, run(5));
        assert_ne!(a, run(6), "another seed starts elsewhere");
    }
}
