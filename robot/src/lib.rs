//! quadwalk's robot: the model (URDF), leg kinematics and IK, PD control and
//! the physics world that puts the robot on a terrain.

pub mod action;
pub mod controller;
pub mod height_scan;
pub mod kinematics;
pub mod mesh;
pub mod model;
pub mod scripted;
pub mod seam;
pub mod snapshot;
pub mod stand;
pub mod task;
pub mod world;
pub mod world_config;

#[cfg(test)]
mod test_worlds;

pub use kinematics::{IkSolution, KinematicsError, LegKinematics};
pub use model::{LAIKAGO_URDF, LegName, ModelError, RobotModel};
pub use stand::{StandReport, stand};
pub use world::{DT_SECS, GroundContacts, World, WorldError};
pub use world_config::{PdModel, WorldConfig, WorldConfigError};
