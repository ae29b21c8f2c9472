//! One phase of the task, whole or step by step: [`Task::step_phase`] runs
//! a phase at once; [`Task::begin_phase`], [`Task::step_in_phase`] and
//! [`Task::end_phase`] run the same phase one physics step at a time, so
//! that a lower-level controller can move the feet's targets between steps
//! (the paper's proposal for reacting within a phase). Both give the same
//! outcome bit for bit when nothing is moved.

use nalgebra::Vector3;

use super::{DistanceReward, PhaseOutcome, RewardTerms, Task, Termination};
use crate::controller::{PhasePlan, RobotState};
use crate::snapshot::{NoObserver, PhaseObserver, PhaseStart};

/// A phase under way: its plan, and what its outcome gathers step by step.
#[derive(Debug, Clone)]
pub struct PhaseRun {
    /// the phase's plan (curves, swing leg, start pose)
    pub plan: PhasePlan,
    /// the physics steps taken, 0 to [`Self::steps_per_phase`]
    pub steps: usize,
    /// the phase's physics steps (0.75 s at the world's rate)
    pub steps_per_phase: usize,
    /// why the episode ended in this phase, once it has
    pub termination: Option<Termination>,
    goal_distance_prev_m: f64,
    targets_rad: Vec<f64>,
    torque_norm_sum: f64,
    height_sum_m: f64,
    height_range_m: (f64, f64),
    ik_clamped: usize,
}

impl PhaseRun {
    /// Whether the phase has ended (all its steps taken, or a fall).
    pub fn finished(&self) -> bool {
        self.termination.is_some() || self.steps >= self.steps_per_phase
    }
}

impl Task {
    /// Runs one phase with `action` (27 values, clipped to [-1, 1]) and
    /// writes the next observation into `obs`.
    pub fn step_phase(&mut self, action: &[f32], obs: &mut [f32]) -> PhaseOutcome {
        self.step_phase_observed(action, obs, &mut NoObserver)
    }

    /// [`Self::step_phase`], telling `observer` about the phase's curves,
    /// every physics step and the outcome (for loggers and viewers).
    pub fn step_phase_observed(
        &mut self,
        action: &[f32],
        obs: &mut [f32],
        observer: &mut dyn PhaseObserver,
    ) -> PhaseOutcome {
        let mut run = self.begin_phase(action, observer);
        while !run.finished() {
            self.step_in_phase(&mut run, None, observer);
        }
        self.end_phase(run, obs, observer)
    }

    /// Plans a phase with `action` (27 values, clipped to [-1, 1]) from the
    /// state now; its steps are taken by [`Self::step_in_phase`].
    pub fn begin_phase(&mut self, action: &[f32], observer: &mut dyn PhaseObserver) -> PhaseRun {
        assert!(!self.episode.done, "reset the task after an episode ends");
        let plan = self
            .controller
            .plan_phase(action, &RobotState::of_world(&self.world));
        self.begin_planned(plan, observer)
    }

    /// Begins a phase whose plan holds the base and every foot where they
    /// are (`PhaseController::hold_plan`): a lower level moves them all
    /// through [`Self::step_in_phase`]'s offsets.
    pub fn begin_phase_holding(&mut self, observer: &mut dyn PhaseObserver) -> PhaseRun {
        assert!(!self.episode.done, "reset the task after an episode ends");
        let plan = self
            .controller
            .hold_plan(&RobotState::of_world(&self.world));
        self.begin_planned(plan, observer)
    }

    fn begin_planned(&mut self, plan: PhasePlan, observer: &mut dyn PhaseObserver) -> PhaseRun {
        let goal_distance_prev_m = self.goal_in_base().norm();
        observer.phase_started(
            self,
            &PhaseStart {
                phase: plan.phase,
                sim_time_s: self.world.time_secs(),
                swing_leg: plan.swing_leg,
                base_start: plan.base_start,
                curves: plan.curves,
            },
        );
        PhaseRun {
            plan,
            steps: 0,
            steps_per_phase: self.world.steps_per_phase(),
            termination: None,
            goal_distance_prev_m,
            targets_rad: self.world.joint_targets_rad().to_vec(),
            torque_norm_sum: 0.0,
            height_sum_m: 0.0,
            height_range_m: (f64::INFINITY, f64::NEG_INFINITY),
            ik_clamped: 0,
        }
    }

    /// Takes the run's next physics step toward its plan, each foot's
    /// target moved by `foot_offsets_m` (leg order, in the target base
    /// frame; `None`: the plan's), and checks the termination. Returns
    /// whether the phase goes on.
    pub fn step_in_phase(
        &mut self,
        run: &mut PhaseRun,
        foot_offsets_m: Option<&[Vector3<f64>; 4]>,
        observer: &mut dyn PhaseObserver,
    ) -> bool {
        assert!(!run.finished(), "the phase has ended: end_phase it");
        let i = run.steps + 1;
        run.ik_clamped +=
            self.controller
                .joint_targets_moved(&run.plan, i, foot_offsets_m, &mut run.targets_rad);
        self.world.set_joint_targets_rad(&run.targets_rad);
        self.controller.record_step(self.feet_in_base());
        self.world.step();
        run.steps = i;
        run.torque_norm_sum += self
            .world
            .applied_torques_n_m()
            .iter()
            .map(|t| t * t)
            .sum::<f64>()
            .sqrt();
        let height = self.base_height_m();
        run.height_sum_m += height;
        run.height_range_m = (
            run.height_range_m.0.min(height),
            run.height_range_m.1.max(height),
        );
        run.termination = self.check_termination(self.judged_base_height_m(height));
        observer.stepped(self, i);
        !run.finished()
    }

    /// Where `run`'s plan puts each foot at its next physics step (leg
    /// order, in the base's target frame of that step), m: what a
    /// lower-level controller moves.
    pub fn planned_feet_m(&self, run: &PhaseRun) -> [Vector3<f64>; 4] {
        let sample = (run.steps + 1).min(run.steps_per_phase);
        self.controller.planned_feet_m(&run.plan, sample)
    }

    /// Ends a finished run: the phase's reward, the goals, the episode's
    /// end, and the next observation into `obs`.
    pub fn end_phase(
        &mut self,
        run: PhaseRun,
        obs: &mut [f32],
        observer: &mut dyn PhaseObserver,
    ) -> PhaseOutcome {
        assert!(run.finished(), "a phase ends after its last step or a fall");
        let PhaseRun {
            plan,
            steps,
            mut termination,
            goal_distance_prev_m: goal_distance_prev,
            torque_norm_sum,
            height_sum_m: height_sum,
            height_range_m: height_range,
            ik_clamped,
            ..
        } = run;
        self.controller.end_phase(&plan);

        let mean_base_height_m = height_sum / steps as f64;
        // |rho|, to the goal of the phase (before a goal reached moves it on)
        let goal_distance = self.goal_in_base().norm();
        if termination.is_none() {
            // the new ground the phase made toward the goal
            let new_ground_m = (self.episode.closest_goal_distance_m - goal_distance).max(0.0);
            termination = self.check_stall(new_ground_m);
        }
        let (reward, terms, goals_reached) = if termination.is_some() {
            (self.config.termination_reward, RewardTerms::default(), 0)
        } else {
            let (roll, _, _) = self.world.base_pose().rotation.euler_angles();
            let terms = RewardTerms {
                distance: match self.config.distance_reward {
                    DistanceReward::Progress => {
                        RewardTerms::distance_term(goal_distance_prev, goal_distance)
                    }
                    DistanceReward::NewGround => RewardTerms::new_ground_term(
                        self.episode.closest_goal_distance_m,
                        goal_distance_prev,
                        goal_distance,
                        self.config.max_paid_progress_m.unwrap_or(f64::INFINITY),
                        self.config.new_ground_paid_per_m(),
                    ),
                    DistanceReward::Forward => RewardTerms::forward_term(
                        goal_distance_prev,
                        goal_distance,
                        self.config.forward_reward_per_m,
                    ),
                    DistanceReward::Tracking => RewardTerms::tracking_term(
                        goal_distance_prev - goal_distance,
                        self.config.target_progress_m,
                    ),
                },
                orientation: {
                    let heading = self.heading_target_in_base();
                    RewardTerms::orientation_term(heading.y.atan2(heading.x))
                },
                height: RewardTerms::height_term(self.judged_base_height_m(self.base_height_m())),
                torque: RewardTerms::torque_term(torque_norm_sum / steps as f64),
                roll: RewardTerms::roll_term(roll),
            }
            .with_balance(self.config.balance_terms);
            let goals = self.advance_goals();
            // The closest approach to the goal now ahead (a new goal starts afresh).
            let now = self.goal_in_base().norm();
            self.episode.closest_goal_distance_m = if goals > 0 {
                now
            } else {
                self.episode.closest_goal_distance_m.min(now)
            };
            (terms.total(), terms, goals)
        };
        let truncated = termination.is_none() && self.phase() >= self.config.max_phases;
        self.episode.done = termination.is_some() || truncated;
        self.observe(obs);
        let outcome = PhaseOutcome {
            reward,
            terms,
            termination,
            truncated,
            steps,
            ik_clamped,
            mean_base_height_m,
            base_height_range_m: height_range,
            goals_reached,
            region: {
                let base = self.world.base_pose().translation.vector;
                self.world.terrain().region_index_at(base.x, base.y)
            },
        };
        observer.phase_ended(self, &outcome);
        outcome
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scripted::ScriptedCrawl;
    use crate::task::TaskConfig;
    use crate::task::tests::task_on;

    #[test]
    fn a_phase_step_by_step_is_the_phase_at_once_and_moved_feet_move_the_robot() {
        // The crawl's first eight phases on 5 cm tiles, once whole and once a
        // step at a time with nothing moved: the same observations, rewards
        // and base poses, bit for bit.
        let mut whole = task_on("elastic:5cm", TaskConfig::default(), 3);
        let mut stepped = task_on("elastic:5cm", TaskConfig::default(), 3);
        let n = whole.observation_size();
        let (mut obs_a, mut obs_b) = (vec![0.0; n], vec![0.0; n]);
        whole.reset(&mut obs_a);
        stepped.reset(&mut obs_b);
        let crawl = ScriptedCrawl::default();
        for _ in 0..8 {
            let action = crawl.act(&whole);
            let a = whole.step_phase(&action, &mut obs_a);
            let mut run = stepped.begin_phase(&action, &mut NoObserver);
            let mut steps = 0;
            while stepped.step_in_phase(&mut run, None, &mut NoObserver) {
                steps += 1;
            }
            assert_eq!(steps + 1, stepped.world().steps_per_phase());
            let b = stepped.end_phase(run, &mut obs_b, &mut NoObserver);
            assert_eq!(a.reward.to_bits(), b.reward.to_bits());
            assert_eq!(obs_a, obs_b);
            assert_eq!(whole.world().base_pose(), stepped.world().base_pose());
        }

        // Every foot's target 3 cm lower in the base frame for a whole
        // phase: the legs extend and the base rises by about that much.
        let mut moved = task_on("rigid", TaskConfig::default(), 3);
        let mut plain = task_on("rigid", TaskConfig::default(), 3);
        moved.reset(&mut obs_a);
        plain.reset(&mut obs_b);
        let action = crawl.act(&plain);
        plain.step_phase(&action, &mut obs_b);
        let down = [Vector3::new(0.0, 0.0, -0.03); 4];
        let mut run = moved.begin_phase(&action, &mut NoObserver);
        while moved.step_in_phase(&mut run, Some(&down), &mut NoObserver) {}
        moved.end_phase(run, &mut obs_a, &mut NoObserver);
        let rise_m =
            moved.world().base_pose().translation.z - plain.world().base_pose().translation.z;
        assert!((0.02..0.04).contains(&rise_m), "the base rose {rise_m} m");
    }

    #[test]
    fn new_ground_is_paid_its_weight_per_metre_and_nothing_else_changes() {
        // The crawl's first eight phases on rigid ground paid 10 (the
        // default) and 20 per metre of new ground: the same motion, and each
        // phase's distance term differs by 10 x the new ground it made.
        let paid = |per_m| TaskConfig {
            distance_reward: DistanceReward::NewGround,
            new_ground_reward_per_m: per_m,
            ..TaskConfig::default()
        };
        let mut ten = task_on("rigid", paid(None), 3);
        let mut twenty = task_on("rigid", paid(Some(20.0)), 3);
        let n = ten.observation_size();
        let (mut obs_a, mut obs_b) = (vec![0.0; n], vec![0.0; n]);
        ten.reset(&mut obs_a);
        twenty.reset(&mut obs_b);
        let crawl = ScriptedCrawl::default();
        let mut made_m = 0.0;
        for phase in 1..=8 {
            let action = crawl.act(&ten);
            let closest_before_m = ten.episode.closest_goal_distance_m;
            let a = ten.step_phase(&action, &mut obs_a);
            let b = twenty.step_phase(&action, &mut obs_b);
            assert_eq!(obs_a, obs_b, "phase {phase}");
            let new_ground_m = closest_before_m - ten.episode.closest_goal_distance_m;
            made_m += new_ground_m;
            let extra = b.terms.distance - a.terms.distance;
            assert!(
                (extra - 10.0 * new_ground_m).abs() < 1e-9,
                "phase {phase}: {extra} for {new_ground_m} m"
            );
            assert_eq!(a.terms.orientation, b.terms.orientation);
        }
        assert!(made_m > 0.05, "the crawl made {made_m} m");
    }
}
