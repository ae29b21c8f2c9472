//! A scripted crawl: a statically stable walk written in the paper's action
//! space, used as a baseline policy and for benchmarks.
//!
//! The paper's phases swing the legs in a fixed order (FL, RR, FR, RL), and
//! its action cannot skip a phase. The crawl lets the swing foot of most
//! phases stay on the ground ("shift" and "hold" phases) and lifts a foot in
//! only four phases of a 16-phase cycle, one per leg:
//!
//! | phase in cycle | 0 1 | 2 | 3 4 | 5 | 6 ... 11 | 12 | 13 14 | 15 |
//! | --- | --- | --- | --- | --- | --- | --- | --- | --- |
//! | swing leg | FL RR | FR | RL FL | RR | ... | FL | RR FR | RL |
//! | foot | down | **lifts** | down | **lifts** | down | **lifts** | down | **lifts** |
//! | centre of mass goes to | FR's spot | held | RR's spot | held | FL's spot | held | RL's spot | held |
//!
//! Before a foot lifts, the base moves the centre of mass (COM) toward the
//! centroid of the other three feet, where each of them would carry a third
//! of the weight. On springy tiles this is what keeps the body level: with
//! the COM far from it the three stance tiles sink unequally, the body tips
//! toward the lifted corner and the "swing" foot stays loaded (measured on
//! 2 cm tiles as FR lifted with the COM 4 cm ahead of that centroid: roll
//! 5.7 and pitch 4.6 degrees toward FR, and the foot never left its tile).
//! The spot is `side_offset_m` to the side away from the lifting foot and
//! `fore_aft_offset_m` away from its end (behind the centroid of all four
//! feet for a front foot, ahead of it for a hind foot), measured from the
//! centroid of the four feet; with the default squat the three-foot
//! centroid is about 7 cm to the side and 7 cm fore or aft, and the defaults
//! (8 and 5 cm) walked farthest on 2 cm tiles. The lifts are grouped so that
//! the COM crosses sides only while all four feet are down: the right feet
//! lift with the COM on the left (FR then RR), the left feet with the COM on
//! the right (FL then RL), and the sideways moves fit the action's bound on
//! the last base control point ([-4, 8] cm per phase).
//!
//! A lifting foot rises `lift_m` straight up, moves to `step_m / 2` ahead of
//! its place in the squat pattern around the current centroid of the feet,
//! and comes down `press_m` below its start height (so that it loads the
//! tile it lands on). Foot targets are clipped to the action's bounds.
//!
//! Every phase also levels the base: every orientation control point takes
//! out `level_gain` of the roll and pitch at the phase start and `yaw_gain`
//! of the yaw, and the height control points bring the mean hip height back
//! to `base_height_target_m` by the phase end. Base moves are expressed in
//! the base frame at the phase start, as the action defines them.
//!
//! Everything the crawl reads is the robot's own state: foot positions and
//! base pose (in the observation) and the COM (from the model's link masses).

use nalgebra::{Point3, Vector3};

use crate::LegName;
use crate::action::{ACTION_SIZE, bound};
use crate::controller::RobotState;
use crate::task::{SWING_ORDER, Task};

/// Phases per crawl cycle.
pub const CYCLE_PHASES: usize = 16;
/// The phases of a cycle whose swing foot lifts (FR, RR, FL, RL).
pub const LIFT_PHASES: [usize; 4] = [2, 5, 12, 15];

/// The crawl's settings, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScriptedCrawl {
    /// how far the COM goes to the side away from the lifting foot, m
    pub side_offset_m: f64,
    /// how far the COM goes away from the lifting foot's end (front or
    /// hind), m
    pub fore_aft_offset_m: f64,
    /// how far a lifting foot lands ahead of its place in the squat pattern
    /// around the centroid of the feet, times two, m
    pub step_m: f64,
    /// swing height above the foot's start height, m
    pub lift_m: f64,
    /// how far below its start height the swing foot is put down, m
    pub press_m: f64,
    /// the mean hip height the crawl holds, m
    pub base_height_target_m: f64,
    /// fraction of the height error taken out by the phase end
    pub height_gain: f64,
    /// fraction of the roll and pitch taken out by every orientation control
    /// point
    pub level_gain: f64,
    /// fraction of the yaw taken out by every orientation control point
    pub yaw_gain: f64,
}

impl Default for ScriptedCrawl {
    fn default() -> Self {
        Self {
            side_offset_m: 0.08,
            fore_aft_offset_m: 0.05,
            step_m: 0.25,
            lift_m: 0.10,
            press_m: 0.0,
            base_height_target_m: 0.28,
            height_gain: 1.0,
            level_gain: 1.0,
            yaw_gain: 0.5,
        }
    }
}

/// Whether the swing foot of episode phase `phase` lifts.
pub fn lifts_in_phase(phase: usize) -> bool {
    LIFT_PHASES.contains(&(phase % CYCLE_PHASES))
}

impl ScriptedCrawl {
    /// Where the COM should be while `leg` is in the air, relative to the
    /// centroid of the four feet (world x, y; the robot heading +x), m.
    pub fn com_spot_m(&self, leg: LegName) -> [f64; 2] {
        let fore_aft = if leg.is_hind() {
            self.fore_aft_offset_m
        } else {
            -self.fore_aft_offset_m
        };
        [fore_aft, -leg.side_sign() * self.side_offset_m]
    }

    /// The crawl's action for the phase about to run on `task`.
    pub fn act(&self, task: &Task) -> [f32; ACTION_SIZE] {
        self.act_on(
            task.phase(),
            &RobotState::of_world(task.world()),
            task.squat_feet_in_base_m(),
        )
    }

    /// The crawl's action for episode phase `phase` of a robot at `state`
    /// whose squat puts its feet at `squat` (base frame).
    pub fn act_on(
        &self,
        phase: usize,
        state: &RobotState,
        squat: &[Vector3<f64>; 4],
    ) -> [f32; ACTION_SIZE] {
        let swing = SWING_ORDER[phase % 4];
        let hind = swing.is_hind();
        let lift = lifts_in_phase(phase);
        let base = state.base_pose;
        let world_to_base = base.inverse();
        let feet = state.feet_in_world_m;
        let centroid = |f: &[Vector3<f64>; 4]| f.iter().sum::<Vector3<f64>>() / 4.0;
        let feet_centroid = centroid(&feet);
        let squat_centroid = centroid(squat);

        // The swing foot: now, and where it lands (base frame at the phase start).
        let s = swing.index();
        let foot_now = (world_to_base * Point3::from(feet[s])).coords;
        let mut landing = foot_now;
        if lift {
            let pattern = base.rotation * (squat[s] - squat_centroid);
            let target_world = Vector3::new(
                feet_centroid.x + pattern.x + self.step_m / 2.0,
                feet_centroid.y + pattern.y,
                feet[s].z,
            );
            landing = (world_to_base * Point3::from(target_world)).coords;
        }

        // The COM spot for the next foot to lift (this one if it lifts).
        let mut next = phase;
        while !lifts_in_phase(next) {
            next += 1;
        }
        let spot = self.com_spot_m(SWING_ORDER[next % 4]);
        let com = state.centre_of_mass_m;
        let shift_world = Vector3::new(
            feet_centroid.x + spot[0] - com.x,
            feet_centroid.y + spot[1] - com.y,
            0.0,
        );
        let shift = base.rotation.inverse() * shift_world;
        let (roll, pitch, yaw) = base.rotation.euler_angles();
        let rise = self.height_gain * (self.base_height_target_m - state.base_height_m());

        // Control-point values in SI, as the action's bounds define them.
        let mut si = [0.0f64; ACTION_SIZE];
        for p in 0..3 {
            // Lifting: hold the spot reached before. Shifting: move steadily.
            let fraction = if lift { 1.0 } else { (p + 1) as f64 / 3.0 };
            si[p * 3] = fraction * shift.x;
            si[p * 3 + 1] = fraction * shift.y;
            si[p * 3 + 2] = (p + 1) as f64 / 3.0 * rise;
            si[9 + p * 3] = -self.level_gain * roll;
            si[9 + p * 3 + 1] = -self.level_gain * pitch;
            si[9 + p * 3 + 2] = -self.yaw_gain * yaw;
        }
        let squat_foot = squat[s];
        let foot_points = if lift {
            [
                [foot_now.x, foot_now.y, self.lift_m],
                [landing.x, landing.y, self.lift_m],
                [landing.x, landing.y, -self.press_m],
            ]
        } else {
            [[foot_now.x, foot_now.y, 0.0]; 3]
        };
        for (p, point) in foot_points.iter().enumerate() {
            si[18 + p * 3] = point[0] - squat_foot.x;
            si[18 + p * 3 + 1] = point[1] - squat_foot.y;
            si[18 + p * 3 + 2] = point[2];
        }
        let mut action = [0.0f32; ACTION_SIZE];
        for (i, a) in action.iter_mut().enumerate() {
            *a = bound(i, hind).unmap(si[i]) as f32;
        }
        action
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::WorldConfig;
    use crate::action::curves_from_action;
    use crate::task::TaskConfig;

    fn task_on(spec: &str) -> (Task, Vec<f32>) {
        let world = crate::test_worlds::laikago_on(spec, 0, [0.0, 0.0], WorldConfig::default());
        let mut task = Task::new(world, TaskConfig::default(), 0);
        let mut obs = vec![0.0; task.observation_size()];
        task.reset(&mut obs);
        (task, obs)
    }

    #[test]
    fn each_leg_lifts_once_per_cycle_with_the_com_on_the_far_side() {
        let lifted: Vec<LegName> = (0..CYCLE_PHASES)
            .filter(|&k| lifts_in_phase(k))
            .map(|k| SWING_ORDER[k % 4])
            .collect();
        assert_eq!(
            lifted,
            [
                LegName::FrontRight,
                LegName::RearRight,
                LegName::FrontLeft,
                LegName::RearLeft
            ]
        );
        // No two lifts in a row: the foot just put down takes its load first.
        for k in 0..CYCLE_PHASES {
            assert!(!(lifts_in_phase(k) && lifts_in_phase(k + 1)), "phase {k}");
        }
        let crawl = ScriptedCrawl::default();
        for leg in lifted {
            let [x, y] = crawl.com_spot_m(leg);
            assert!(y * leg.side_sign() < 0.0, "{leg:?}: away from its side");
            assert!(
                x * if leg.is_hind() { 1.0 } else { -1.0 } > 0.0,
                "{leg:?}: away from its end"
            );
        }
    }

    #[test]
    fn a_lift_phase_raises_the_foot_and_a_shift_phase_keeps_it_down() {
        let (mut task, mut obs) = task_on("rigid");
        let crawl = ScriptedCrawl::default();
        for phase in 0..3 {
            let action = crawl.act(&task);
            assert!(action.iter().all(|a| a.abs() <= 1.0));
            let swing = task.swing_leg();
            let feet = task.world().feet_in_world_m();
            let base = task.world().base_pose();
            let now = (base.inverse() * Point3::from(feet[swing.index()])).coords;
            let squat = task.squat_feet_in_base_m()[swing.index()];
            let curves = curves_from_action(&action, now, now.z, squat, swing.is_hind());
            let top = curves.swing_foot.at(0.5);
            let end = curves.swing_foot.at(1.0);
            if lifts_in_phase(phase) {
                // 3/4 of the lift at mid-phase (Bezier with P1 = P2 = lift), landing ahead
                assert!(
                    (top.z - now.z - 0.75 * crawl.lift_m).abs() < 0.01,
                    "{top} {now}"
                );
                assert!(
                    end.x > now.x + 0.05,
                    "the foot steps forward: {end} from {now}"
                );
            } else {
                assert!((top - now).norm() < 0.005 && (end - now).norm() < 0.005);
            }
            task.step_phase(&action, &mut obs);
        }
    }

    #[test]
    fn the_com_reaches_the_spot_before_the_first_lift() {
        let (mut task, mut obs) = task_on("rigid");
        let crawl = ScriptedCrawl::default();
        for _ in 0..2 {
            task.step_phase(&crawl.act(&task), &mut obs);
        }
        // Phase 2 lifts FR: the COM is at FR's spot within 1.5 cm.
        let feet = task.world().feet_in_world_m();
        let centroid = feet.iter().sum::<Vector3<f64>>() / 4.0;
        let com = task.world().centre_of_mass_m();
        let [x, y] = crawl.com_spot_m(LegName::FrontRight);
        let error = ((com.x - centroid.x - x).powi(2) + (com.y - centroid.y - y).powi(2)).sqrt();
        assert!(error < 0.015, "COM {:.3} from FR's spot", error);
    }
}
