//! A scene: the robot model and one world built on a terrain spec.

use std::path::Path;
use std::sync::Arc;

use anyhow::{Context, Result};
use robot::{RobotModel, World, WorldConfig};
use terrain_plugins::{BuildContext, Registry, TerrainSpec};

/// The built-in Laikago, or the URDF at `path`.
pub fn load_robot(path: Option<&Path>) -> Result<Arc<RobotModel>> {
    Ok(Arc::new(match path {
        None => RobotModel::laikago(),
        Some(path) => RobotModel::from_urdf_file(path)?,
    }))
}

/// Builds one world: terrain from `spec`, robot standing at (x, y),
/// simulated with `physics`.
pub fn make_world(
    registry: &Registry,
    spec: &TerrainSpec,
    model: Arc<RobotModel>,
    seed: u64,
    xy_m: [f64; 2],
    physics: &WorldConfig,
) -> Result<World> {
    let ctx = BuildContext {
        supported_mass_kg: model.total_mass_kg(),
        seed,
        ..BuildContext::default()
    };
    let terrain = registry.create_from_spec(spec, &ctx)?;
    let extent = terrain.extent();
    if !extent.contains(xy_m) {
        anyhow::bail!(
            "start position ({}, {}) m lies outside terrain {spec}, which covers x {}..{} m, y {}..{} m",
            xy_m[0],
            xy_m[1],
            extent.min_m[0],
            extent.max_m[0],
            extent.min_m[1],
            extent.max_m[1]
        );
    }
    World::new(model, terrain, physics.clone(), xy_m)
        .with_context(|| format!("cannot place the robot on {spec}"))
}
