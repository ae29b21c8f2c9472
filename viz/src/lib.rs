//! quadwalk's Rerun logging: streams rollouts (the robot, the phase's Bezier
//! targets, the tiles and their sink, contacts, rewards and torques) to a
//! Rerun viewer, server or `.rrd` file.
//!
//! The simulation knows nothing of Rerun: [`RolloutLogger`] is a
//! [`robot::snapshot::PhaseObserver`] and reads the task through its plain
//! snapshots.
//!
//! # What is logged where
//!
//! | entity path | archetype | when |
//! | --- | --- | --- |
//! | `world/robot/<link>` | `Transform3D` (pose of the link) | every logged frame |
//! | `world/robot/<base>/eye_anchor` | `Points3D`: two points, 0.5 mm, at opposite corners of a box around the base, static; the 3D view's eye tracks them (see the blueprint below) | once |
//! | `world/robot/<link>/shape_<k>` | `Boxes3D`, `Ellipsoids3D`, `Cylinders3D`, `Capsules3D` or `Mesh3D` (its collision shapes), static | once |
//! | `world/base/trajectory` | `LineStrips3D`: the base path so far (a point per centimetre moved, then the current position) | every logged frame |
//! | `world/goal` | `Points3D` | every logged frame of a task (`stand` has no goal) |
//! | `world/observed_goal` | `Points3D`: the point on the goals' line the policy observes (`goal_line_ahead_m`) | every logged frame of a task that observes one |
//! | `world/height_scan` | `Points3D`: the points on the ground whose height the policy observes (`height_scan`) | every logged frame of a task that observes them |
//! | `world/targets/base` | `LineStrips3D`: the base position curve | every phase start |
//! | `world/targets/orientation` | `Arrows3D`: the base up axis along the orientation curve | every phase start |
//! | `world/targets/swing_foot` | `LineStrips3D`: the swing foot curve | every phase start |
//! | `world/targets/landing` | `Points3D`: where the swing foot is sent | every phase start |
//! | `world/terrain/tiles` | `Boxes3D`: the tiles near the robot, top face at the current sink, coloured by sink | every logged frame |
//! | `world/terrain/regions` | `Boxes3D`: one flat box per terrain region, labelled, static | once |
//! | `world/terrain/ground` | `Mesh3D`: the relief's ground (`slope`, `steps`, `rough`: `Terrain::ground_mesh`), static | once, for relief |
//! | `world/contacts` | `Points3D`: ground contact points (feet green, other links red) | every logged frame |
//! | `reward/<term>`, `reward/total` | `Scalars` | every phase end |
//! | `base/height_m`, `base/roll_deg`, `base/pitch_deg` | `Scalars` | every logged frame |
//! | `torque/<joint>` | `Scalars`, N m | every logged frame |
//! | `tiles/sink_m` (one scalar per logged tile) | `Scalars` | every logged frame |
//! | `eval/distance_m` | `Scalars`, one per episode on the `episode` timeline | end of `quadwalk eval` |
//! | `eval/base_height_cm/<terrain>/{mean,mean_plus_std,mean_minus_std}` (`<terrain>`: the type's label with `:` and `,` as `_`) | `Scalars` on the `phase_angle_deg` timeline (the paper's Fig. 4) | end of `quadwalk eval` |
//! | `eval/landing_height_cm/<terrain>` | `Scalars` on the `foot` timeline (0 FR, 1 FL, 2 RR, 3 RL) | end of `quadwalk eval` |
//! | `train/<curve>` (mean return, distance, episode length, losses, entropy, KL, clip fraction, explained variance, phases/s) | `Scalars`, on the `iteration` timeline only | every training iteration |
//!
//! The blueprint (the viewer's layout): the 3D view of `world`, its eye
//! following the base from about 2 m behind, right of and above it, beside
//! the time series of the rewards, the base, the torques and training.
//!
//! Timelines: `sim_time` (seconds of simulated time), `phase` (the phase's
//! index in its episode) and, when set, `iteration` (training).
//!
//! Rerun is the cargo feature `rerun` (on by default). Without it,
//! [`RolloutLogger`] has the same API, logs nothing, and refuses every sink
//! but `off` with an error that says how to get Rerun back.

mod sink;

#[cfg(feature = "rerun")]
mod blueprint;
#[cfg(not(feature = "rerun"))]
mod disabled;
#[cfg(feature = "rerun")]
mod logger;

use std::path::PathBuf;

#[cfg(not(feature = "rerun"))]
pub use disabled::RolloutLogger;
#[cfg(feature = "rerun")]
pub use logger::RolloutLogger;
pub use sink::{DEFAULT_CONNECT_URL, LogRate, RerunSink, SinkParseError};

/// Rerun's application id for quadwalk recordings.
pub const APPLICATION_ID: &str = "quadwalk";

/// Tiles are coloured from grey (at rest) to red at this sink, m.
pub const FULL_COLOUR_SINK_M: f64 = 0.10;

/// A tile's colour, RGB: grey at rest to red at [`FULL_COLOUR_SINK_M`]
/// (and beyond), linear in between. Every view of the tiles uses it.
pub fn sink_colour(sink_m: f64) -> [u8; 3] {
    let u = (sink_m / FULL_COLOUR_SINK_M).clamp(0.0, 1.0);
    let lerp = |a: f64, b: f64| (a + (b - a) * u).round() as u8;
    [lerp(170.0, 230.0), lerp(170.0, 40.0), lerp(170.0, 40.0)]
}

/// Settings of a logger.
#[derive(Debug, Clone, PartialEq)]
pub struct VizSettings {
    /// how often the robot and the tiles are logged
    pub rate: LogRate,
    /// tiles whose centre is within this distance of the base (along x and
    /// along y) are logged, m
    pub tiles_half_side_m: f64,
    /// samples per logged Bezier curve
    pub curve_samples: usize,
}

impl Default for VizSettings {
    fn default() -> Self {
        Self {
            rate: LogRate::PerPhase,
            tiles_half_side_m: 0.7,
            curve_samples: 30,
        }
    }
}

/// Why a logger could not be opened.
#[derive(Debug, thiserror::Error)]
pub enum VizError {
    /// The `.rrd` file cannot be written.
    #[error("cannot write the Rerun recording {path:?}: {source}")]
    Unwritable {
        /// the file
        path: PathBuf,
        /// why
        source: std::io::Error,
    },
    /// Rerun refused to open the sink.
    #[error("cannot open the Rerun sink {sink}: {message}")]
    Sink {
        /// the sink as the user wrote it
        sink: String,
        /// Rerun's error
        message: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_go_from_grey_to_red() {
        assert_eq!(sink_colour(0.0), [170, 170, 170]);
        assert_eq!(sink_colour(FULL_COLOUR_SINK_M / 2.0), [200, 105, 105]);
        assert_eq!(sink_colour(FULL_COLOUR_SINK_M), [230, 40, 40]);
        assert_eq!(sink_colour(1.0), [230, 40, 40]);
    }
}
