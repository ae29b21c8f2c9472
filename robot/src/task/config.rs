//! The task's settings and their named choices.

use super::observation::ObservationConfig;
use crate::action::ACTION_SIZE;

/// Which distance term R_d pays (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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

/// What a policy's action is added to (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
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

/// Settings of the task.
#[derive(Debug, Clone, PartialEq)]
pub struct TaskConfig {
    /// distance from one goal to the next (and from the start to the first), m
    pub goal_spacing_m: f64,
    /// a goal counts as reached within this distance, m
    pub goal_reached_m: f64,
    /// the first goal's distance ahead of the start (+x) is drawn uniformly
    /// from this range (`None`: `goal_spacing_m`, the paper's), m; a goal
    /// anywhere from beside the robot to a spacing ahead, as an episode
    /// longer than a training rollout meets it
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
    /// termination: mean hip height below this, m
    pub min_base_height_m: f64,
    /// termination: |pitch| above this, degrees
    pub max_pitch_deg: f64,
    /// the reward of a terminated phase
    pub termination_reward: f64,
    /// observation switches
    pub observation: ObservationConfig,
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
    pub max_paid_progress_m: Option<f64>,
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
}

impl TaskConfig {
    /// Number of observation values: the switched-on blocks and the prior's.
    pub fn observation_size(&self) -> usize {
        self.observation.size() + self.action_prior.observation_size()
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
            termination_reward: -10.0,
            observation: ObservationConfig::default(),
            settle_secs: 0.5,
            distance_reward: DistanceReward::default(),
            forward_reward_per_m: 40.0,
            target_progress_m: 0.025,
            max_paid_progress_m: None,
            orientation_lookahead_m: 0.0,
            balance_terms: BalanceTerms::default(),
            action_prior: ActionPrior::default(),
        }
    }
}
