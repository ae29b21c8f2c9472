//! The observation: which blocks are on and how the vector is written
//! (the table is in the module docs of [`super`]).

use super::Task;
use crate::controller::RobotState;
use crate::height_scan::HEIGHT_SCAN_POINTS;

/// The previous phases whose start foot positions the paper observes.
pub const FOOT_HISTORY_PHASES: usize = 3;

/// Which optional observation blocks are on (the paper's ablations), and
/// which point the goal blocks show.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ObservationConfig {
    /// foot positions at the start of previous phases (12 values each)
    pub foot_history: bool,
    /// how many previous phases' starts `foot_history` shows, newest last:
    /// the paper's 3 (36 values), or 1-2 for its "one less phase" ablation
    #[serde(skip_serializing_if = "is_full_history")]
    pub foot_history_phases: usize,
    /// foot positions 4 and 8 ms ago (24 values)
    pub short_history: bool,
    /// foot velocities (12 values)
    pub foot_velocity: bool,
    /// `None` (the paper's): the goal blocks (azimuth, position) show the
    /// current goal. `Some(L)`: they show the point on the goals' line L m
    /// ahead of the base along +x, which moves with the robot and never
    /// jumps, and R_o heads for it too (not the paper's; see the module
    /// docs of [`super`]), m
    #[serde(skip_serializing_if = "Option::is_none")]
    pub goal_line_ahead_m: Option<f64>,
    /// the critic also sees, per foot (leg order: FR, FL, RR, RL), what a robot cannot
    /// measure: the sink of the ground under the foot, the standing sink of
    /// its region (how soft it is) and whether the foot touches the ground
    /// ([`PRIVILEGED_SIZE`] values after the policy's observation, for an
    /// asymmetric actor-critic; not the paper's). The policy's observation
    /// is unchanged.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub privileged_critic: bool,
    /// the base's height above the ground at 18 points up to 1.1 m ahead
    /// of it ([`crate::height_scan`]; not the paper's): the last block
    /// (only an action prior's values follow it), so that a curriculum
    /// stage that turns it on appends to the policy's input
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub height_scan: bool,
}

/// Values [`ObservationConfig::privileged_critic`] appends for the critic:
/// 3 per foot.
pub const PRIVILEGED_SIZE: usize = 12;

/// Whether `phases` is the paper's whole foot-position history (an
/// experiment file leaves it out then).
fn is_full_history(phases: &usize) -> bool {
    *phases == FOOT_HISTORY_PHASES
}

impl Default for ObservationConfig {
    fn default() -> Self {
        Self {
            foot_history: true,
            foot_history_phases: FOOT_HISTORY_PHASES,
            short_history: true,
            foot_velocity: true,
            goal_line_ahead_m: None,
            privileged_critic: false,
            height_scan: false,
        }
    }
}

impl ObservationConfig {
    /// The blocks in order, with their index ranges (see the module docs).
    pub fn blocks(&self) -> Vec<(&'static str, std::ops::Range<usize>)> {
        let mut sizes = vec![
            ("hip_heights", 4),
            ("gravity_in_base", 3),
            ("base_linear_velocity", 3),
            ("base_angular_velocity", 3),
            ("pitch", 1),
        ];
        if self.foot_history {
            sizes.push((
                "feet_at_previous_phase_starts",
                12 * self.foot_history_phases,
            ));
        }
        sizes.push(("feet_now", 12));
        if self.short_history {
            sizes.push(("feet_4_and_8_ms_ago", 24));
        }
        if self.foot_velocity {
            sizes.push(("foot_velocities", 12));
        }
        sizes.extend([("goal_azimuth", 1), ("goal_position", 2), ("phase", 1)]);
        if self.height_scan {
            sizes.push(("height_scan", HEIGHT_SCAN_POINTS));
        }
        let mut start = 0;
        sizes
            .into_iter()
            .map(|(name, n)| {
                start += n;
                (name, start - n..start)
            })
            .collect()
    }

    /// Number of observation values with these switches.
    pub fn size(&self) -> usize {
        self.blocks().last().map_or(0, |(_, range)| range.end)
    }

    /// Number of privileged values for the critic (0 unless
    /// `privileged_critic`).
    pub fn privileged_size(&self) -> usize {
        if self.privileged_critic {
            PRIVILEGED_SIZE
        } else {
            0
        }
    }
}

impl Task {
    /// Writes the observation (see the module docs for the layout): the
    /// controller's, for the world's state and the current goal.
    pub fn observe(&self, obs: &mut [f32]) {
        let state = if self.config.observation.height_scan {
            RobotState::of_world_scanned(&self.world)
        } else {
            RobotState::of_world(&self.world)
        };
        self.controller.observe(&state, self.episode.goal_xy_m, obs);
    }

    /// Writes the critic's privileged values
    /// ([`ObservationConfig::privileged_critic`]), per foot: the sink of
    /// the ground under it (m, positive down), its region's standing sink
    /// (m, 0 on rigid ground) and 1 where it touches the ground, else 0.
    pub fn observe_privileged(&self, out: &mut [f32]) {
        let size = self.config.observation.privileged_size();
        assert_eq!(out.len(), size, "the privileged values are {size}");
        if size == 0 {
            return;
        }
        let world = &self.world;
        let terrain = world.terrain();
        let touching = world.feet_touching_ground();
        for ((foot, touches), slot) in world
            .feet_in_world_m()
            .iter()
            .zip(touching)
            .zip(out.chunks_exact_mut(3))
        {
            let sink_m =
                world.rest_height_m(foot.x, foot.y) - world.surface_height_m(foot.x, foot.y);
            let region = &terrain.regions()[terrain.region_index_at(foot.x, foot.y)];
            slot[0] = sink_m as f32;
            slot[1] = region.expected_sink_m as f32;
            slot[2] = f32::from(u8::from(touches));
        }
    }
}
