//! The task's settings and their named choices, as an experiment file's
//! `[task]` table spells them (serde), and their validation.
//!
//! ```toml
//! [task]
//! max_phases = 40
//! goal_spacing_m = 2.0
//! start_x_range_m = [-0.5, 0.5]
//! first_goal_ahead_range_m = [0.3, 2.3]  # optional: the first goal's distance ahead
//!                                # is drawn from this range (default: goal_spacing_m)
//! goal_y_offset_range_m = [-0.1, 0.1]    # the goals' line aside of the start (default [0, 0])
//! distance_reward = "new_ground" # "progress" is the paper's; or "forward", "tracking"
//! forward_reward_per_m = 40.0    # R_d per metre with "forward" (both ways)
//! target_progress_m = 0.025      # the pace per phase "tracking" pays most for
//! max_paid_progress_m = 0.04     # optional: "new_ground" pays at most this much
//!                                # new ground per phase (a pace cap), m
//! new_ground_reward_per_m = 20.0 # optional: "new_ground" pays this per metre of
//!                                # new ground (default 10, the paper's alpha_d)
//! orientation_lookahead_m = 1.0  # optional: R_o heads for the first goal at least
//!                                # this far away (default 0: the current goal, the paper's)
//! balance_terms = "penalty"      # R_o, R_s, R_t, R_r shifted by their best value
//!                                # (standing earns ~0); "paper": the paper's
//! pitch_reference = "world"      # the paper's: the pitch termination measures from
//!                                # the horizontal; "ground": from the rest surface's
//!                                # inclination under the robot (slopes, hills);
//!                                # "feet": from the ground under the feet now,
//!                                # the holes they stand in included (soil)
//! base_height_reference = "hips" # the paper's: the base-height termination and R_s
//!                                # measure h_b, from the ground right below each hip;
//!                                # "feet": from the ground under the feet that touch
//!                                # it (soil, where the feet stand in their own holes)
//! action_prior = "none"          # the paper's; or "scripted_crawl": the policy's
//!                                # action is a residual on the crawl (+27 observations)
//! swing_height_reference = "foot" # the paper's: the swing foot's height control
//!                                # points count from its height at the phase start;
//!                                # "touchdown": from its height when it last landed
//!                                # (a foot sunk in soil lifts out of its hole)
//! stall = { phases = 10, new_ground_m = 0.05 } # optional: the episode ends (paid
//!                                # termination_reward) once its last 10 phases made
//!                                # less than 5 cm of new ground toward the goals
//!
//! [task.observation]      # the paper's ablations
//! foot_history = false    # drop the three previous phase-start foot positions (-36)
//! foot_history_phases = 2 # or keep only the 2 (or 1) newest of them (-12 each)
//! short_history = true    # foot positions 4 and 8 ms ago (24)
//! foot_velocity = true    # foot velocities (12)
//! goal_line_ahead_m = 1.0 # optional: the goal blocks show the point on the goals'
//!                         # line this far ahead of the base, and R_o heads for it
//!                         # (default: the current goal, the paper's; not with
//!                         # orientation_lookahead_m)
//! ```
//!
//! A key the table omits takes [`TaskConfig::default`]'s value (the
//! paper's); unknown keys are errors. [`TaskConfig::validate`] checks the
//! values and their relations.

use serde::{Deserialize, Serialize};

use super::observation::{FOOT_HISTORY_PHASES, ObservationConfig};
use crate::action::ACTION_SIZE;

/// A task setting out of its range, or two that contradict each other.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct TaskConfigError(pub String);

/// Which distance term R_d pays (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum DistanceReward {
    /// The paper's: alpha_d (|rho_prev| - |rho|), alpha_d = 10 when closer,
    /// 1 otherwise.
    #[default]
    Progress,
    /// 10 x progress past the closest approach to the current goal so far in
    /// the episode (at most `max_paid_progress_m` of it per phase), minus 1 x
    /// the phase's move away from it.
    NewGround,
    /// `forward_reward_per_m` x progress toward the goal, the same weight
    /// both ways.
    Forward,
    /// exp(-((p - p*) / (p* / 2))^2) for a phase's progress p toward the goal
    /// and the target `target_progress_m` p*: at most 1 per phase, earned
    /// at the target pace, nothing for standing or for a lunge.
    Tracking,
}

impl DistanceReward {
    /// The name used in configuration files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Progress => "progress",
            Self::NewGround => "new_ground",
            Self::Forward => "forward",
            Self::Tracking => "tracking",
        }
    }

    /// Parses [`Self::name`]'s output.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "progress" => Some(Self::Progress),
            "new_ground" => Some(Self::NewGround),
            "forward" => Some(Self::Forward),
            "tracking" => Some(Self::Tracking),
            _ => None,
        }
    }
}

/// How the balance terms R_o, R_s, R_t, R_r pay (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum BalanceTerms {
    /// The paper's: each term is at least 0.
    #[default]
    Paper,
    /// Each term shifted by its best value, so at most 0.
    Penalty,
}

impl BalanceTerms {
    /// The name used in configuration files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Paper => "paper",
            Self::Penalty => "penalty",
        }
    }

    /// Parses [`Self::name`]'s output.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "paper" => Some(Self::Paper),
            "penalty" => Some(Self::Penalty),
            _ => None,
        }
    }
}

/// What the pitch termination measures the base's pitch against.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum PitchReference {
    /// The paper's: the horizontal.
    #[default]
    World,
    /// The rest surface under the robot along its heading (its inclination
    /// between the ground below the front hips and below the rear hips, see
    /// `World::ground_pitch_rad`): on a slope the termination judges the
    /// base against the slope, as it judges it against flat ground; the
    /// same as `World` wherever the ground at rest is level (every flat
    /// terrain, tiles included).
    Ground,
    /// The ground the feet stand on now (its inclination between the
    /// surface below the front feet and below the rear feet, see
    /// `World::feet_ground_pitch_rad`): on soil the holes the feet have
    /// made count, so a base that leans with its front feet's deeper holes
    /// is judged against that ground, as `base_height_reference = "feet"`
    /// judges the base's height; the same as `Ground` on ground that does
    /// not give, up to where the feet stand rather than the hips.
    Feet,
}

impl PitchReference {
    /// Whether this is the paper's reference, the horizontal.
    pub fn is_world(&self) -> bool {
        *self == Self::World
    }

    /// The name used in configuration files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::World => "world",
            Self::Ground => "ground",
            Self::Feet => "feet",
        }
    }

    /// Parses [`Self::name`]'s output.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "world" => Some(Self::World),
            "ground" => Some(Self::Ground),
            "feet" => Some(Self::Feet),
            _ => None,
        }
    }
}

/// What the base-height termination and the height term R_s measure the
/// hips' height from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum BaseHeightReference {
    /// The paper's: h_b, each hip's height above the terrain right below
    /// it, averaged over the four hips.
    #[default]
    Hips,
    /// The mean hip height above the mean surface under the feet that touch
    /// the ground (all four feet when none does; see
    /// `World::base_height_above_feet_m`). On ground that stays down the
    /// feet stand in holes of their own making while the ground below the
    /// hips is untouched, so h_b counts the holes' depth as a fall; this
    /// measures the base from what it stands on. On rigid flat ground both
    /// are the hips' height.
    Feet,
}

impl BaseHeightReference {
    /// Whether this is the paper's reference, the ground below the hips.
    pub fn is_hips(&self) -> bool {
        *self == Self::Hips
    }

    /// The name used in configuration files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Hips => "hips",
            Self::Feet => "feet",
        }
    }

    /// Parses [`Self::name`]'s output.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "hips" => Some(Self::Hips),
            "feet" => Some(Self::Feet),
            _ => None,
        }
    }
}

/// What a policy's action is added to (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum ActionPrior {
    /// The paper's: the action is the phase's action.
    #[default]
    None,
    /// The action is a residual on the scripted crawl's action, which also
    /// ends the observation (27 more values).
    ScriptedCrawl,
}

impl ActionPrior {
    /// The name used in configuration files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::None => "none",
            Self::ScriptedCrawl => "scripted_crawl",
        }
    }

    /// Parses [`Self::name`]'s output.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "none" => Some(Self::None),
            "scripted_crawl" => Some(Self::ScriptedCrawl),
            _ => None,
        }
    }

    /// Observation values the prior adds (after the paper's blocks).
    pub fn observation_size(&self) -> usize {
        match self {
            Self::None => 0,
            Self::ScriptedCrawl => ACTION_SIZE,
        }
    }
}

/// What the swing foot's height control points (the action's z of P1-P3)
/// count from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum SwingHeightReference {
    /// The paper's: the foot's height at the phase start.
    #[default]
    Foot,
    /// The foot's height when it last landed: the world height at which its
    /// last swing ended (at the start of the phase after that swing), or its
    /// height at the episode's start before its first swing. A foot that has
    /// sunk since it landed (soil, a soft tile) has its curve raised by the
    /// sink, so the same action lifts it out of its hole, and its landing
    /// counts from the height of its last landing rather than from the
    /// hole's bottom; known to a robot from its own foot positions, as the
    /// observation's are.
    Touchdown,
}

impl SwingHeightReference {
    /// Whether this is the paper's reference, the foot's current height.
    pub fn is_foot(&self) -> bool {
        *self == Self::Foot
    }

    /// The name used in configuration files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Foot => "foot",
            Self::Touchdown => "touchdown",
        }
    }

    /// Parses [`Self::name`]'s output.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "foot" => Some(Self::Foot),
            "touchdown" => Some(Self::Touchdown),
            _ => None,
        }
    }
}

/// A termination for episodes that stop making ground: the episode ends
/// when its last `phases` phases made less than `new_ground_m` of new ground
/// toward the goals (the closest approach to the goal shortened, as
/// [`DistanceReward::NewGround`] measures it before its pace cap). Standing
/// still then ends an episode as a fall does, so that under a
/// `termination_reward` that a clumsy gait often pays, standing is no
/// safer than walking.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StallRule {
    /// the window, phases (1 to `max_phases`)
    pub phases: usize,
    /// the new ground the window must make, m
    pub new_ground_m: f64,
}

/// Settings of the task (the `[task]` table; fields in the order an
/// experiment file lists them).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TaskConfig {
    /// distance from one goal to the next (and from the start to the first), m
    pub goal_spacing_m: f64,
    /// a goal counts as reached within this distance, m
    pub goal_reached_m: f64,
    /// the first goal's distance ahead of the start (+x) is drawn uniformly
    /// from this range (`None`: `goal_spacing_m`, the paper's), m; a goal
    /// anywhere from beside the robot to a spacing ahead, as an episode
    /// longer than a training rollout meets it
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_goal_ahead_range_m: Option<(f64, f64)>,
    /// the goals' line (their world y) is the start's y plus a draw from
    /// this range (the paper's: (0, 0), straight ahead), m
    pub goal_y_offset_range_m: (f64, f64),
    /// phases before an episode is truncated
    pub max_phases: usize,
    /// start x is drawn uniformly from this range, m
    pub start_x_range_m: (f64, f64),
    /// start y is drawn uniformly from this range, m
    pub start_y_range_m: (f64, f64),
    /// termination: the base height (as `base_height_reference` measures
    /// it; the paper's: the mean of h_b) below this, m
    pub min_base_height_m: f64,
    /// termination: |pitch| above this, degrees
    pub max_pitch_deg: f64,
    /// what the pitch termination measures the pitch against (left out of
    /// a written file when it is the paper's, so that the files of runs
    /// from before it existed read back byte for byte)
    #[serde(skip_serializing_if = "PitchReference::is_world")]
    pub pitch_reference: PitchReference,
    /// what the base-height termination and R_s measure the hips' height
    /// from (left out of a written file when it is the paper's)
    #[serde(skip_serializing_if = "BaseHeightReference::is_hips")]
    pub base_height_reference: BaseHeightReference,
    /// the reward of a terminated phase
    pub termination_reward: f64,
    /// termination: an episode that stops making ground ends (`None`, the
    /// paper's: never)
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stall: Option<StallRule>,
    /// after a reset the robot stands this long holding the squat, so that
    /// it starts loaded on the ground (tiles sunk), s
    pub settle_secs: f64,
    /// which distance term R_d pays
    pub distance_reward: DistanceReward,
    /// R_d's weight per metre with [`DistanceReward::Forward`]
    pub forward_reward_per_m: f64,
    /// the progress per phase [`DistanceReward::Tracking`] pays most for, m
    pub target_progress_m: f64,
    /// [`DistanceReward::NewGround`] pays at most this much new ground per
    /// phase (`None`: all of it), m: a pace cap, so that speed past it
    /// earns nothing and only risks a fall
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_paid_progress_m: Option<f64>,
    /// [`DistanceReward::NewGround`]'s pay per metre of new ground
    /// (`None`: [`DEFAULT_NEW_GROUND_REWARD_PER_M`], the paper's alpha_d for
    /// an approach); what a step back costs stays 1 per metre
    #[serde(skip_serializing_if = "Option::is_none")]
    pub new_ground_reward_per_m: Option<f64>,
    /// R_o judges the heading by the azimuth of the first goal on the line
    /// (the current one, then those `goal_spacing_m` apart beyond it) at
    /// least this far from the base, m; 0 (the paper's): the current goal,
    /// whose azimuth swings toward 90 degrees as the robot passes it a few
    /// centimetres aside, paying a turn on the spot
    pub orientation_lookahead_m: f64,
    /// how the balance terms pay
    pub balance_terms: BalanceTerms,
    /// what the policy's action is added to
    pub action_prior: ActionPrior,
    /// what the swing foot's height control points count from (left out of
    /// a written file when it is the paper's)
    #[serde(skip_serializing_if = "SwingHeightReference::is_foot")]
    pub swing_height_reference: SwingHeightReference,
    /// observation switches
    pub observation: ObservationConfig,
}

/// [`TaskConfig::new_ground_reward_per_m`] when the file does not set it:
/// the paper's alpha_d for an approach (R_d pays 10 per metre closer).
pub const DEFAULT_NEW_GROUND_REWARD_PER_M: f64 = 10.0;

impl TaskConfig {
    /// What [`DistanceReward::NewGround`] pays per metre of new ground.
    pub fn new_ground_paid_per_m(&self) -> f64 {
        self.new_ground_reward_per_m
            .unwrap_or(DEFAULT_NEW_GROUND_REWARD_PER_M)
    }

    /// Number of observation values: the switched-on blocks and the prior's.
    pub fn observation_size(&self) -> usize {
        self.observation.size() + self.action_prior.observation_size()
    }

    /// Checks every value's range and the settings that exclude each other;
    /// the error names the key (as the `[task]` table spells it).
    pub fn validate(&self) -> Result<(), TaskConfigError> {
        let fail = |message: String| Err(TaskConfigError(message));
        for (name, v) in [
            ("goal_spacing_m", self.goal_spacing_m),
            ("goal_reached_m", self.goal_reached_m),
            ("min_base_height_m", self.min_base_height_m),
            ("max_pitch_deg", self.max_pitch_deg),
            ("target_progress_m", self.target_progress_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return fail(format!("{name} must be a positive number, got {v}"));
            }
        }
        for (name, (a, b)) in [
            ("goal_y_offset_range_m", self.goal_y_offset_range_m),
            ("start_x_range_m", self.start_x_range_m),
            ("start_y_range_m", self.start_y_range_m),
        ] {
            if !(a.is_finite() && b.is_finite() && a <= b) {
                return fail(format!(
                    "{name} must be [low, high] with low <= high, got [{a}, {b}]"
                ));
            }
        }
        if let Some((a, b)) = self.first_goal_ahead_range_m
            && !(a.is_finite() && b.is_finite() && 0.0 < a && a <= b)
        {
            return fail(format!(
                "first_goal_ahead_range_m must be [low, high] with 0 < low <= high, got [{a}, {b}]"
            ));
        }
        if self.max_phases == 0 {
            return fail("max_phases must be at least 1".to_string());
        }
        if !self.termination_reward.is_finite() {
            return fail("termination_reward must be finite".to_string());
        }
        if !(self.settle_secs.is_finite() && self.settle_secs >= 0.0) {
            return fail(format!(
                "settle_secs must be >= 0, got {}",
                self.settle_secs
            ));
        }
        if let Some(StallRule {
            phases,
            new_ground_m,
        }) = self.stall
        {
            if phases == 0 || phases > self.max_phases {
                return fail(format!(
                    "stall.phases must be 1 to max_phases ({}), got {phases}",
                    self.max_phases
                ));
            }
            if !(new_ground_m.is_finite() && new_ground_m > 0.0) {
                return fail(format!(
                    "stall.new_ground_m must be a positive number (m in stall.phases phases), got {new_ground_m}"
                ));
            }
        }
        let per_m = self.forward_reward_per_m;
        if !(per_m.is_finite() && (0.0..=1e4).contains(&per_m)) {
            return fail(format!(
                "forward_reward_per_m must be in [0, 10000], got {per_m}"
            ));
        }
        // A key that shapes distance_reward = "new_ground" only: set with
        // another distance reward it would be silently ignored.
        let new_ground_only = |key: &str, verb: &str| -> Result<(), TaskConfigError> {
            if self.distance_reward == DistanceReward::NewGround {
                return Ok(());
            }
            fail(format!(
                "{key} {verb} distance_reward = \"new_ground\" only, but distance_reward = {:?}",
                self.distance_reward.name()
            ))
        };
        if let Some(cap) = self.max_paid_progress_m {
            if !(cap.is_finite() && cap > 0.0) {
                return fail(format!(
                    "max_paid_progress_m must be a positive number (m per phase), got {cap}"
                ));
            }
            new_ground_only("max_paid_progress_m", "caps")?;
        }
        if let Some(per_m) = self.new_ground_reward_per_m {
            if !(per_m.is_finite() && per_m > 0.0 && per_m <= 1e4) {
                return fail(format!(
                    "new_ground_reward_per_m must be in (0, 10000] (reward per metre), got {per_m}"
                ));
            }
            new_ground_only("new_ground_reward_per_m", "weighs")?;
        }
        let lookahead_m = self.orientation_lookahead_m;
        if !(lookahead_m.is_finite() && (0.0..=100.0).contains(&lookahead_m)) {
            return fail(format!(
                "orientation_lookahead_m must be in [0, 100] m, got {lookahead_m}"
            ));
        }
        let o = &self.observation;
        if !(1..=FOOT_HISTORY_PHASES).contains(&o.foot_history_phases) {
            return fail(format!(
                "observation.foot_history_phases must be 1 to {FOOT_HISTORY_PHASES} (the previous phases whose start foot positions are observed), got {}",
                o.foot_history_phases
            ));
        }
        if !o.foot_history && o.foot_history_phases != FOOT_HISTORY_PHASES {
            return fail(
                "observation.foot_history_phases sets the length of the foot-position history, but foot_history = false turns it off; keep one of the two"
                    .to_string(),
            );
        }
        if let Some(ahead_m) = o.goal_line_ahead_m {
            if !(ahead_m.is_finite() && 0.0 < ahead_m && ahead_m <= 100.0) {
                return fail(format!(
                    "observation.goal_line_ahead_m must be in (0, 100] m, got {ahead_m}"
                ));
            }
            if lookahead_m > 0.0 {
                return fail(format!(
                    "orientation_lookahead_m = {lookahead_m} and observation.goal_line_ahead_m = {ahead_m} both set R_o's heading target (with goal_line_ahead_m, R_o heads for the observed point); keep one of the two"
                ));
            }
        }
        Ok(())
    }
}

impl Default for TaskConfig {
    fn default() -> Self {
        Self {
            goal_spacing_m: 2.0,
            goal_reached_m: 0.3,
            first_goal_ahead_range_m: None,
            goal_y_offset_range_m: (0.0, 0.0),
            max_phases: 40,
            start_x_range_m: (-0.5, 0.5),
            start_y_range_m: (-0.2, 0.2),
            min_base_height_m: 0.20,
            max_pitch_deg: 15.0,
            pitch_reference: PitchReference::default(),
            base_height_reference: BaseHeightReference::default(),
            termination_reward: -10.0,
            stall: None,
            observation: ObservationConfig::default(),
            settle_secs: 0.5,
            distance_reward: DistanceReward::default(),
            forward_reward_per_m: 40.0,
            target_progress_m: 0.025,
            max_paid_progress_m: None,
            new_ground_reward_per_m: None,
            orientation_lookahead_m: 0.0,
            balance_terms: BalanceTerms::default(),
            action_prior: ActionPrior::default(),
            swing_height_reference: SwingHeightReference::default(),
        }
    }
}

impl TryFrom<String> for DistanceReward {
    type Error = TaskConfigError;
    fn try_from(name: String) -> Result<Self, Self::Error> {
        Self::from_name(&name).ok_or_else(|| TaskConfigError(format!("distance_reward must be \"progress\" (the paper's), \"new_ground\", \"forward\" or \"tracking\", got {name:?}")))
    }
}

impl From<DistanceReward> for String {
    fn from(value: DistanceReward) -> Self {
        value.name().to_string()
    }
}

impl TryFrom<String> for BalanceTerms {
    type Error = TaskConfigError;
    fn try_from(name: String) -> Result<Self, Self::Error> {
        Self::from_name(&name).ok_or_else(|| {
            TaskConfigError(format!(
                "balance_terms must be \"paper\" (the paper's) or \"penalty\", got {name:?}"
            ))
        })
    }
}

impl From<BalanceTerms> for String {
    fn from(value: BalanceTerms) -> Self {
        value.name().to_string()
    }
}

impl TryFrom<String> for PitchReference {
    type Error = TaskConfigError;
    fn try_from(name: String) -> Result<Self, Self::Error> {
        Self::from_name(&name).ok_or_else(|| {
            TaskConfigError(format!(
                "pitch_reference must be \"world\" (the paper's), \"ground\" or \"feet\", got {name:?}"
            ))
        })
    }
}

impl From<PitchReference> for String {
    fn from(value: PitchReference) -> Self {
        value.name().to_string()
    }
}

impl TryFrom<String> for BaseHeightReference {
    type Error = TaskConfigError;
    fn try_from(name: String) -> Result<Self, Self::Error> {
        Self::from_name(&name).ok_or_else(|| {
            TaskConfigError(format!(
                "base_height_reference must be \"hips\" (the paper's) or \"feet\", got {name:?}"
            ))
        })
    }
}

impl From<BaseHeightReference> for String {
    fn from(value: BaseHeightReference) -> Self {
        value.name().to_string()
    }
}

impl TryFrom<String> for ActionPrior {
    type Error = TaskConfigError;
    fn try_from(name: String) -> Result<Self, Self::Error> {
        Self::from_name(&name).ok_or_else(|| {
            TaskConfigError(format!(
                "action_prior must be \"none\" (the paper's) or \"scripted_crawl\", got {name:?}"
            ))
        })
    }
}

impl From<ActionPrior> for String {
    fn from(value: ActionPrior) -> Self {
        value.name().to_string()
    }
}

impl TryFrom<String> for SwingHeightReference {
    type Error = TaskConfigError;
    fn try_from(name: String) -> Result<Self, Self::Error> {
        Self::from_name(&name).ok_or_else(|| {
            TaskConfigError(format!(
                "swing_height_reference must be \"foot\" (the paper's) or \"touchdown\", got {name:?}"
            ))
        })
    }
}

impl From<SwingHeightReference> for String {
    fn from(value: SwingHeightReference) -> Self {
        value.name().to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn from_toml(text: &str) -> Result<TaskConfig, String> {
        let task: TaskConfig = toml::from_str(text).map_err(|e| e.message().to_string())?;
        task.validate().map_err(|e| e.to_string())?;
        Ok(task)
    }

    #[test]
    fn an_empty_table_is_the_papers_task_and_every_task_round_trips() {
        assert_eq!(from_toml("").unwrap(), TaskConfig::default());
        let task = TaskConfig {
            first_goal_ahead_range_m: Some((0.3, 2.3)),
            max_paid_progress_m: Some(0.03),
            new_ground_reward_per_m: Some(20.0),
            distance_reward: DistanceReward::NewGround,
            balance_terms: BalanceTerms::Penalty,
            action_prior: ActionPrior::ScriptedCrawl,
            pitch_reference: PitchReference::Ground,
            base_height_reference: BaseHeightReference::Feet,
            swing_height_reference: SwingHeightReference::Touchdown,
            stall: Some(StallRule {
                phases: 10,
                new_ground_m: 0.05,
            }),
            observation: ObservationConfig {
                foot_history_phases: 2,
                goal_line_ahead_m: Some(1.0),
                ..ObservationConfig::default()
            },
            ..TaskConfig::default()
        };
        let text = toml::to_string(&task).unwrap();
        assert!(text.contains("distance_reward = \"new_ground\""), "{text}");
        assert!(text.contains("[observation]\n"), "{text}");
        assert_eq!(from_toml(&text).unwrap(), task);
        // the paper's defaults leave the optional keys out
        let plain = toml::to_string(&TaskConfig::default()).unwrap();
        for key in [
            "first_goal_ahead_range_m",
            "max_paid_progress_m",
            "new_ground_reward_per_m",
            "foot_history_phases",
            "goal_line_ahead_m",
            "pitch_reference",
            "base_height_reference",
            "swing_height_reference",
            "stall",
        ] {
            assert!(!plain.contains(key), "{key} in {plain}");
        }
    }

    #[test]
    fn bad_values_and_contradictions_name_the_key() {
        for (text, expected) in [
            ("max_phase = 3", "unknown field `max_phase`"),
            ("max_phases = 0", "max_phases must be at least 1"),
            (
                "goal_reached_m = -0.3",
                "goal_reached_m must be a positive number",
            ),
            (
                "start_y_range_m = [0.2, -0.2]",
                "start_y_range_m must be [low, high]",
            ),
            ("settle_secs = -1.0", "settle_secs must be >= 0"),
            (
                "forward_reward_per_m = 1e5",
                "forward_reward_per_m must be in [0, 10000]",
            ),
            (
                "distance_reward = \"progress\"\nmax_paid_progress_m = 0.03",
                "max_paid_progress_m caps distance_reward = \"new_ground\" only",
            ),
            (
                "distance_reward = \"new_ground\"\nnew_ground_reward_per_m = 0.0",
                "new_ground_reward_per_m must be in (0, 10000] (reward per metre), got 0",
            ),
            (
                "new_ground_reward_per_m = 20.0",
                "new_ground_reward_per_m weighs distance_reward = \"new_ground\" only, but distance_reward = \"progress\"",
            ),
            (
                "balance_terms = \"reward\"",
                "balance_terms must be \"paper\"",
            ),
            (
                "pitch_reference = \"slope\"",
                "pitch_reference must be \"world\" (the paper's), \"ground\" or \"feet\", got \"slope\"",
            ),
            (
                "base_height_reference = \"base\"",
                "base_height_reference must be \"hips\" (the paper's) or \"feet\", got \"base\"",
            ),
            (
                "swing_height_reference = \"ground\"",
                "swing_height_reference must be \"foot\" (the paper's) or \"touchdown\", got \"ground\"",
            ),
            (
                "distance_reward = \"backward\"",
                "distance_reward must be \"progress\" (the paper's), \"new_ground\", \"forward\" or \"tracking\", got \"backward\"",
            ),
            (
                "[observation]\nfoot_history_phases = 4",
                "observation.foot_history_phases must be 1 to 3",
            ),
            (
                "[observation]\nfoot_history = false\nfoot_history_phases = 2",
                "foot_history = false turns it off",
            ),
            (
                "orientation_lookahead_m = 1.0\n[observation]\ngoal_line_ahead_m = 1.0",
                "both set R_o's heading target",
            ),
            (
                "stall = { phases = 41, new_ground_m = 0.05 }",
                "stall.phases must be 1 to max_phases (40), got 41",
            ),
            (
                "stall = { phases = 10, new_ground_m = 0.0 }",
                "stall.new_ground_m must be a positive number",
            ),
            ("stall = { phases = 10 }", "missing field `new_ground_m`"),
            (
                "stall = { phases = 10, new_ground_m = 0.05, pace = 1 }",
                "unknown field `pace`",
            ),
        ] {
            let err = from_toml(text).unwrap_err();
            assert!(err.contains(expected), "{text:?} gave {err:?}");
        }
    }
}
