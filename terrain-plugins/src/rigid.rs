//! `rigid`: flat rigid ground, the plane z = 0 (`rigid:friction=0.1` for a
//! slippery one).

use rapier3d::prelude::*;

use crate::spec::{ParamDecl, TerrainSpec};
use crate::tiles::friction_decl;
use crate::{BuildContext, Rect, Region, Terrain, TerrainPlugin, TileState, terrain_collider};

/// Half side of the ground's extent, metres (the collider itself is an
/// infinite half-space).
const HALF_EXTENT_M: f64 = 1.0e4;

/// The `rigid` plugin.
pub struct RigidPlugin;

impl TerrainPlugin for RigidPlugin {
    fn name(&self) -> &'static str {
        "rigid"
    }

    fn summary(&self) -> &'static str {
        "flat rigid ground at z = 0"
    }

    fn params(&self) -> Vec<ParamDecl> {
        vec![friction_decl()]
    }

    fn create(&self, spec: &TerrainSpec, _ctx: &BuildContext) -> Box<dyn Terrain> {
        Box::new(RigidGround {
            spec: spec.clone(),
            friction: spec.number("friction"),
            regions: vec![Region {
                index: 0,
                label: spec.to_string(),
                x_range_m: (-HALF_EXTENT_M, HALF_EXTENT_M),
                stiffness_n_per_m: None,
                damping_n_s_per_m: None,
                expected_sink_m: 0.0,
            }],
        })
    }
}

/// Flat rigid ground.
pub struct RigidGround {
    spec: TerrainSpec,
    friction: f64,
    regions: Vec<Region>,
}

impl Terrain for RigidGround {
    fn spec(&self) -> &TerrainSpec {
        &self.spec
    }

    fn build(&mut self, world: &mut PhysicsWorld) {
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        let plane = terrain_collider(
            ColliderBuilder::halfspace(rapier3d::na::Unit::new_unchecked(Vector::Z)),
            self.friction,
        );
        world.insert_collider(plane, Some(ground));
    }

    fn surface_height_m(&self, _world: &PhysicsWorld, _x_m: f64, _y_m: f64) -> f64 {
        0.0
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }

    fn region_index_at(&self, _x_m: f64, _y_m: f64) -> usize {
        0
    }

    fn tiles_in(&self, _world: &PhysicsWorld, _area: Rect, _out: &mut Vec<TileState>) {}

    fn extent(&self) -> Rect {
        Rect {
            min_m: [-HALF_EXTENT_M; 2],
            max_m: [HALF_EXTENT_M; 2],
        }
    }

    fn tile_count(&self) -> usize {
        0
    }
}
