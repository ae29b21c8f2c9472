//! Shared helpers for quadwalk's cross-crate tests.

use std::sync::Arc;

use robot::{RobotModel, World, WorldConfig};
use terrain_plugins::{BuildContext, Registry};

/// A world with the built-in Laikago standing at (x, y) on `spec`.
pub fn world_on(registry: &Registry, spec: &str, xy_m: [f64; 2], seed: u64) -> World {
    let model = Arc::new(RobotModel::laikago());
    let ctx = BuildContext {
        supported_mass_kg: model.total_mass_kg(),
        seed,
        ..BuildContext::default()
    };
    let terrain = registry.create(spec, &ctx).expect("valid spec");
    World::new(model, terrain, WorldConfig::default(), xy_m).expect("the Laikago fits")
}
