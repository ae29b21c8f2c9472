//! The task's left-right mirror: the observation and the action of the
//! robot reflected in its sagittal (x-z) plane, for symmetry data
//! augmentation (rsl_rl's `symmetry_cfg`, Mittal et al. 2024: every sample
//! is also learned from as its mirror image).
//!
//! The reflection M = diag(1, -1, 1) maps a world or base vector v to M v
//! and a rotation R to M R M: roll and yaw change sign, pitch does not. The
//! robot's legs swap sides (FR <-> FL, RR <-> RL), so the swing order
//! FL, RR, FR, RL maps each phase to the one two later (phase k <-> k + 2
//! mod 4), and the mirror of a trajectory is one the task can run.
//!
//! | block | mirror |
//! | --- | --- |
//! | hip heights, FR FL RR RL | legs swapped |
//! | gravity direction, base linear velocity (base frame) | y negated |
//! | base angular velocity (base frame) | x (roll rate) and z (yaw rate) negated; M w is a pseudo-vector's reflection, -M w |
//! | pitch | kept |
//! | every foot block (positions, velocities; base frame) | legs swapped, y negated |
//! | goal azimuth | negated |
//! | goal position x, y | y negated |
//! | phase k / 4 | (k + 2 mod 4) / 4 |
//! | height scan, rows ahead of right-centre-left points | each row's right and left swapped |
//! | privileged values, 3 per foot | legs swapped |
//!
//! Action (the raw values in [-1, 1] units, before the task clips them):
//! the base position's y, the base orientation's roll and yaw and the
//! swing foot's y negate their offset v = c + h a (bound centre c,
//! half-width h), so a' = -a - 2 c / h. Every bound but the base's last
//! point (P3, [-4, 8] cm) is centred (a' = -a); P3's y maps to
//! a' = -a - 2/3, exact wherever the mirrored offset is inside [-4, 8] cm,
//! i.e. for |P3 y| <= 4 cm.
//!
//! The terrains are symmetric only in distribution (tiles, regions and
//! starts drawn at random), which is what augmentation asks, and the
//! Laikago's URDF is not exactly symmetric (its left and right upper legs
//! differ in inertia by 0.001 kg m^2), so a mirrored phase is what the
//! robot would do to that precision (the test below measures it). With the
//! scripted-crawl action prior the policy's action is a residual on an
//! action in the observation, whose mirror is not this affine map, so the
//! mirror is refused there.

use super::{ActionPrior, ObservationConfig, TaskConfig};
use crate::action::{ACTION_SIZE, bound};
use crate::height_scan::mirrored_point;

/// Why a task has no mirror.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MirrorError {
    /// the scripted-crawl prior's action is in the observation
    #[error(
        "task.action_prior = \"scripted_crawl\" has no left-right mirror (the policy's action is a residual on the crawl's, which the mirror does not map); mirror augmentation needs action_prior = \"none\""
    )]
    ActionPrior,
}

/// What one observation value does under the mirror.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Slot {
    /// takes value `from`, multiplied by `sign`
    From { from: usize, sign: f32 },
    /// the phase value k / 4, mapped to (k + 2 mod 4) / 4
    Phase,
}

/// The left-right mirror of one task's observation (its switches and
/// privileged values) and of the action.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskMirror {
    slots: Vec<Slot>,
}

/// Legs in array order FR FL RR RL: each leg's mirror image.
const MIRROR_LEG: [usize; 4] = [1, 0, 3, 2];

impl TaskMirror {
    /// The mirror of a task with `config`'s observation (its privileged
    /// values included).
    pub fn new(config: &TaskConfig) -> Result<Self, MirrorError> {
        if config.action_prior != ActionPrior::None {
            return Err(MirrorError::ActionPrior);
        }
        Ok(Self::of_observation(&config.observation))
    }

    fn of_observation(observation: &ObservationConfig) -> Self {
        let mut slots = Vec::new();
        let kept = |k: usize| Slot::From { from: k, sign: 1.0 };
        let negated = |k: usize| Slot::From {
            from: k,
            sign: -1.0,
        };
        for (name, range) in observation.blocks() {
            let start = range.start;
            match name {
                "hip_heights" => slots.extend(MIRROR_LEG.map(|leg| kept(start + leg))),
                "gravity_in_base" | "base_linear_velocity" | "goal_position" => {
                    slots.extend(range.map(|k| if k == start + 1 { negated(k) } else { kept(k) }));
                }
                "base_angular_velocity" => {
                    slots.extend([negated(start), kept(start + 1), negated(start + 2)]);
                }
                "pitch" => slots.push(kept(start)),
                "goal_azimuth" => slots.push(negated(start)),
                "phase" => slots.push(Slot::Phase),
                "height_scan" => {
                    slots.extend((0..range.len()).map(|k| kept(start + mirrored_point(k))));
                }
                // the foot blocks: 12 values (FR FL RR RL, x y z) each
                _ => {
                    assert_eq!(
                        range.len() % 12,
                        0,
                        "observation block {name} is not per foot"
                    );
                    for group in range.step_by(12) {
                        for leg in MIRROR_LEG {
                            let from = group + 3 * leg;
                            slots.extend([kept(from), negated(from + 1), kept(from + 2)]);
                        }
                    }
                }
            }
        }
        if observation.privileged_size() > 0 {
            let privileged_start = observation.size();
            for leg in MIRROR_LEG {
                let from = privileged_start + 3 * leg;
                slots.extend((from..from + 3).map(kept));
            }
        }
        Self { slots }
    }

    /// Values of an observation row (privileged ones included).
    pub fn observation_size(&self) -> usize {
        self.slots.len()
    }

    /// Mirrors one observation row in place.
    pub fn mirror_observation(&self, row: &mut [f32]) {
        assert_eq!(
            row.len(),
            self.slots.len(),
            "the mirror maps rows of {} values",
            self.slots.len()
        );
        let original = row.to_vec();
        for ((out, slot), value) in row.iter_mut().zip(&self.slots).zip(&original) {
            *out = match *slot {
                Slot::From { from, sign } => sign * original[from],
                Slot::Phase => {
                    let k = (f64::from(*value) * 4.0).round() as i64;
                    (k + 2).rem_euclid(4) as f32 / 4.0
                }
            };
        }
    }
}

/// Whether action value `index` is a lateral coordinate (y), a roll or a
/// yaw: the values the mirror negates.
fn is_mirrored_action(index: usize) -> bool {
    let axis = index % 3;
    match index / 9 {
        1 => axis != 1, // roll, yaw
        _ => axis == 1, // base y, swing foot y
    }
}

/// Mirrors one raw action (27 values) in place: a' = -a - 2 c / h for the
/// values whose offset the reflection negates (module docs).
pub fn mirror_action(action: &mut [f32]) {
    assert_eq!(
        action.len(),
        ACTION_SIZE,
        "an action has {ACTION_SIZE} values"
    );
    for (index, a) in action.iter_mut().enumerate() {
        if is_mirrored_action(index) {
            let b = bound(index, false);
            let centre_over_half_width = (b.hi + b.lo) / (b.hi - b.lo);
            *a = (-f64::from(*a) - 2.0 * centre_over_half_width) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;
    use crate::action::ACTION_SIZE;
    use crate::task::tests::task_on;
    use crate::task::{DistanceReward, Task};

    fn random_row(n: usize, seed: u64) -> Vec<f32> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(|_| rng.random_range(-1.0f32..1.0)).collect()
    }

    #[test]
    fn mirroring_twice_gives_back_every_observation_and_action() {
        for (foot_history, short_history, foot_velocity, privileged_critic) in [
            (true, true, true, false),
            (true, true, true, true),
            (false, false, false, true),
            (true, false, true, false),
        ] {
            let config = TaskConfig {
                observation: ObservationConfig {
                    foot_history,
                    short_history,
                    foot_velocity,
                    privileged_critic,
                    ..ObservationConfig::default()
                },
                ..TaskConfig::default()
            };
            let mirror = TaskMirror::new(&config).unwrap();
            let size = config.observation.size() + config.observation.privileged_size();
            assert_eq!(mirror.observation_size(), size);
            let mut row = random_row(size, 7);
            let phase = size - config.observation.privileged_size() - 1;
            row[phase] = 0.25;
            let original = row.clone();
            mirror.mirror_observation(&mut row);
            assert_eq!(row[phase], 0.75, "phase RR mirrors to RL");
            assert_ne!(row, original);
            mirror.mirror_observation(&mut row);
            assert_eq!(row, original);
        }
        let mut action = random_row(ACTION_SIZE, 8);
        let original = action.clone();
        mirror_action(&mut action);
        assert_eq!(action[0], original[0], "base x is kept");
        assert_eq!(action[1], -original[1], "base y (P1) is negated");
        assert!(
            (action[7] - (-original[7] - 2.0 / 3.0)).abs() < 1e-6,
            "P3 y about its off-centre bound"
        );
        assert_eq!(action[10], original[10], "pitch is kept");
        mirror_action(&mut action);
        for (a, b) in action.iter().zip(&original) {
            assert!((a - b).abs() < 1e-6);
        }
    }

    #[test]
    fn the_crawl_prior_has_no_mirror() {
        let config = TaskConfig {
            action_prior: ActionPrior::ScriptedCrawl,
            ..TaskConfig::default()
        };
        let error = TaskMirror::new(&config).unwrap_err();
        assert!(error.to_string().contains("action_prior"), "{error}");
    }

    /// Two robots on rigid ground, on the x axis: one about to swing FL,
    /// the other FR. The mirror of the first one's observation is the
    /// second's; after the first runs an action and the second its mirror,
    /// their observations (privileged values included) and rewards are
    /// still each other's mirror, to the robot's and the solver's own
    /// asymmetry (the URDF's left and right upper legs differ in inertia by
    /// 0.001 kg m^2; rapier solves contacts in order). Unmirrored, the two
    /// observations differ by far more.
    #[test]
    fn a_mirrored_action_from_a_mirrored_state_gives_the_mirrored_phase() {
        let config = TaskConfig {
            distance_reward: DistanceReward::NewGround,
            observation: ObservationConfig {
                goal_line_ahead_m: Some(1.0),
                privileged_critic: true,
                height_scan: true,
                ..ObservationConfig::default()
            },
            ..TaskConfig::default()
        };
        let mirror = TaskMirror::new(&config).unwrap();
        let size = mirror.observation_size();
        let obs_size = config.observation.size();
        let observe = |task: &Task, obs: &mut Vec<f32>| {
            task.observe(&mut obs[..obs_size]);
            task.observe_privileged(&mut obs[obs_size..]);
        };
        let mut left = task_on("rigid", config.clone(), 3);
        let mut right = task_on("rigid", config, 3);
        let (mut obs_left, mut obs_right) = (vec![0.0; size], vec![0.0; size]);
        left.reset_at([0.0, 0.0], &mut obs_left[..obs_size]);
        right.reset_at([0.0, 0.0], &mut obs_right[..obs_size]);
        right.controller.start_at_phase(2);
        observe(&left, &mut obs_left);
        observe(&right, &mut obs_right);
        let mirrored = |obs: &[f32]| {
            let mut row = obs.to_vec();
            mirror.mirror_observation(&mut row);
            row
        };
        let worst = |a: &[f32], b: &[f32]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max)
        };
        assert!(
            worst(&mirrored(&obs_left), &obs_right) < 1e-3,
            "at the start"
        );

        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let action: Vec<f32> = (0..ACTION_SIZE)
            .map(|_| rng.random_range(-0.5f32..0.5))
            .collect();
        let mut action_mirrored = action.clone();
        mirror_action(&mut action_mirrored);
        let outcome_left = left.step_phase(&action, &mut obs_left[..obs_size]);
        let outcome_right = right.step_phase(&action_mirrored, &mut obs_right[..obs_size]);
        assert!(outcome_left.termination.is_none() && outcome_right.termination.is_none());
        observe(&left, &mut obs_left);
        observe(&right, &mut obs_right);
        assert!(
            (outcome_left.reward - outcome_right.reward).abs() < 0.03,
            "reward {} against {}",
            outcome_left.reward,
            outcome_right.reward
        );
        let after = mirrored(&obs_left);
        // every value to 0.05 (m, m/s, rad/s), the feet's positions to 1 mm
        assert!(worst(&after, &obs_right) < 0.05, "{after:?}\n{obs_right:?}");
        let feet = config_block(&left, "feet_now");
        assert!(worst(&after[feet.clone()], &obs_right[feet]) < 1e-3);
        let phase = config_block(&left, "phase").start;
        assert!(worst(&obs_left[..phase], &obs_right[..phase]) > 0.3);
    }

    fn config_block(task: &Task, name: &str) -> std::ops::Range<usize> {
        task.config()
            .observation
            .blocks()
            .into_iter()
            .find(|(n, _)| *n == name)
            .map(|(_, range)| range)
            .unwrap()
    }
}
