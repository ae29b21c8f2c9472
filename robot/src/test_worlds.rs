//! Worlds for the crate's tests: the Laikago at a place on a built-in
//! terrain.

use std::sync::Arc;

use terrain_plugins::{BuildContext, Registry};

use crate::{RobotModel, World, WorldConfig};

/// The Laikago at `xy_m` on the built-in terrain `spec`, built with `seed`
/// and sized for the robot's mass (the springs' stiffness rule).
pub(crate) fn laikago_on(spec: &str, seed: u64, xy_m: [f64; 2], config: WorldConfig) -> World {
    let model = Arc::new(RobotModel::laikago());
    let ctx = BuildContext {
        supported_mass_kg: model.total_mass_kg(),
        seed,
        ..BuildContext::default()
    };
    let terrain = Registry::builtin()
        .create(spec, &ctx)
        .unwrap_or_else(|e| panic!("terrain {spec}: {e}"));
    World::new(model, terrain, config, xy_m).unwrap()
}
