//! Terrain models for quadwalk.
//!
//! A terrain is a [`Terrain`]: it builds its bodies and joints into a rapier
//! [`PhysicsWorld`], may act before each physics step, answers the surface
//! height right below a point, reports each tile's displacement and which
//! region (terrain type) a point lies in. A terrain *model* is a
//! [`TerrainPlugin`]: a name, a summary, declared parameters and a
//! constructor. The [`Registry`] lists plugins and turns specs such as
//! `elastic:5cm` or `varying:2m:2,3,4,5cm,rigid` into terrains.
//!
//! Frames and units: world frame, z up, x the walking direction; SI units
//! throughout (metres, kilograms, newtons, seconds). The resting surface of
//! every built-in terrain is the plane z = 0.
//!
//! Adding a terrain model: implement [`TerrainPlugin`] and [`Terrain`] for
//! your types and call [`Registry::register`]; nothing else changes.

pub mod elastic;
pub mod registry;
pub mod relief;
pub mod rigid;
pub mod soil;
pub mod spec;
pub mod switch;
pub mod tiles;
pub mod units;
pub mod varying;

pub use rapier3d;
use rapier3d::prelude::{
    CoefficientCombineRule, ColliderBuilder, Group, InteractionGroups, InteractionTestMode,
    PhysicsWorld,
};
pub use registry::{Registry, RegistryError, TerrainPlugin};
pub use spec::{ParamDecl, ParamKind, ParamValue, SpecError, Surface, TerrainSpec};

/// Standard gravity, m/s^2.
pub const STANDARD_GRAVITY_M_PER_S2: f64 = 9.81;

/// Collision group of every terrain collider.
pub const TERRAIN_GROUP: Group = Group::GROUP_1;
/// Collision group of every robot collider.
pub const ROBOT_GROUP: Group = Group::GROUP_2;

/// Terrain colliders meet the robot only: tiles never touch each other or the
/// base they hang from.
pub fn terrain_collision_groups() -> InteractionGroups {
    InteractionGroups::new(TERRAIN_GROUP, ROBOT_GROUP, InteractionTestMode::And)
}

/// A terrain surface collider: in [`terrain_collision_groups`], with
/// friction coefficient `friction` combined with the robot's by the minimum
/// (rapier's `CoefficientCombineRule::Min`), so that `friction` is the
/// contact's coefficient wherever it is below the robot's 1.0.
pub fn terrain_collider(builder: ColliderBuilder, friction: f64) -> ColliderBuilder {
    builder
        .friction(friction as f32)
        .friction_combine_rule(CoefficientCombineRule::Min)
        .collision_groups(terrain_collision_groups())
}

/// Robot colliders meet the terrain only (no self-collision).
pub fn robot_collision_groups() -> InteractionGroups {
    InteractionGroups::new(ROBOT_GROUP, TERRAIN_GROUP, InteractionTestMode::And)
}

/// What a terrain needs to know about the world it is built for.
#[derive(Debug, Clone, PartialEq)]
pub struct BuildContext {
    /// Mass the terrain carries when the robot stands still, kg. The elastic
    /// terrain derives its spring stiffness from it (the paper defines
    /// stiffness by the sink of the standing robot).
    pub supported_mass_kg: f64,
    /// Magnitude of gravity, m/s^2.
    pub gravity_m_per_s2: f64,
    /// Seed for any random choice the terrain makes (e.g. region types).
    pub seed: u64,
}

impl Default for BuildContext {
    /// The Laikago's mass (25.567 kg), standard gravity, seed 0.
    fn default() -> Self {
        Self {
            supported_mass_kg: 25.567,
            gravity_m_per_s2: STANDARD_GRAVITY_M_PER_S2,
            seed: 0,
        }
    }
}

/// A stretch of terrain of one type.
#[derive(Debug, Clone, PartialEq)]
pub struct Region {
    /// Index in [`Terrain::regions`].
    pub index: usize,
    /// The region's type as a spec (`elastic:5cm`, `rigid`).
    pub label: String,
    /// Where the region starts and ends along x, metres (world frame).
    pub x_range_m: (f64, f64),
    /// Spring stiffness per tile, N/m; `None` for rigid ground.
    pub stiffness_n_per_m: Option<f64>,
    /// Spring damping per tile, N s/m; `None` for rigid ground.
    pub damping_n_s_per_m: Option<f64>,
    /// Mean sink of the loaded tiles under the robot standing still, m
    /// (0 for rigid ground).
    pub expected_sink_m: f64,
}

/// A tile's state, for visualisation and analysis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileState {
    /// Centre of the tile's top face at rest, world frame, metres.
    pub center_m: [f64; 2],
    /// Side length of the tile's top face, metres.
    pub side_m: f64,
    /// How far the tile is pushed down from rest, metres (positive = down).
    pub sink_m: f64,
    /// Height of the centre of the tile's top face at rest, metres (0 on
    /// flat ground).
    pub rest_top_m: f64,
    /// Rise of the tile's top face along x at rest, dz/dx (0 on flat
    /// ground; tiles on a hill are inclined about y).
    pub rest_slope: f64,
    /// The region the tile belongs to.
    pub region: usize,
}

/// An axis-aligned rectangle in the ground plane, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rect {
    /// smallest x, y
    pub min_m: [f64; 2],
    /// largest x, y
    pub max_m: [f64; 2],
}

impl Rect {
    /// The square of half-side `half_side_m` around `center_m`.
    pub fn around(center_m: [f64; 2], half_side_m: f64) -> Self {
        Self {
            min_m: [center_m[0] - half_side_m, center_m[1] - half_side_m],
            max_m: [center_m[0] + half_side_m, center_m[1] + half_side_m],
        }
    }

    /// Whether the point lies inside (borders included).
    pub fn contains(&self, point_m: [f64; 2]) -> bool {
        (self.min_m[0]..=self.max_m[0]).contains(&point_m[0])
            && (self.min_m[1]..=self.max_m[1]).contains(&point_m[1])
    }
}

/// Triangles of a static ground surface, for viewers.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GroundMesh {
    /// vertices, world frame, metres
    pub vertices_m: Vec<[f64; 3]>,
    /// triangles as indices into `vertices_m`, counter-clockwise from above
    pub triangles: Vec<[u32; 3]>,
}

impl GroundMesh {
    /// Adds the quadrilateral a, b, c, d (counter-clockwise from above).
    pub fn push_quad(&mut self, corners: [[f64; 3]; 4]) {
        let first = self.vertices_m.len() as u32;
        self.vertices_m.extend(corners);
        self.triangles.push([first, first + 1, first + 2]);
        self.triangles.push([first, first + 2, first + 3]);
    }
}

/// A terrain in a physics world.
///
/// Life cycle: a plugin creates it from a spec, [`Terrain::build`] inserts its
/// bodies, colliders and joints into a world (once), then the world calls
/// [`Terrain::before_step`] before every physics step and
/// [`Terrain::after_step`] after it. Queries take the world the terrain was
/// built into.
pub trait Terrain: Send {
    /// The spec this terrain was made from, in canonical form.
    fn spec(&self) -> &TerrainSpec;
    /// Inserts the terrain's bodies, colliders and joints. Terrain colliders
    /// must use [`terrain_collision_groups`].
    fn build(&mut self, world: &mut PhysicsWorld);
    /// Called before every physics step (e.g. to apply custom forces or
    /// recycle tiles). Default: nothing.
    fn before_step(&mut self, _world: &mut PhysicsWorld, _dt_secs: f64) {}
    /// Called after every physics step (e.g. to put idle parts to sleep).
    /// Default: nothing.
    fn after_step(&mut self, _world: &mut PhysicsWorld, _dt_secs: f64) {}
    /// Puts every moving part back at rest (between episodes). Default:
    /// nothing (a terrain without moving parts).
    fn reset(&mut self, _world: &mut PhysicsWorld) {}
    /// Height of the surface right below (x, y), world frame, metres.
    fn surface_height_m(&self, world: &PhysicsWorld, x_m: f64, y_m: f64) -> f64;
    /// Height of the surface right below (x, y) with nothing on it (every
    /// tile at rest), world frame, metres: what a sink is measured from.
    /// Default: 0, flat ground whose top is z = 0 (relief overrides it).
    fn rest_height_m(&self, _x_m: f64, _y_m: f64) -> f64 {
        0.0
    }
    /// The terrain's regions, ordered along x.
    fn regions(&self) -> &[Region];
    /// Index of the region (x, y) lies in.
    fn region_index_at(&self, x_m: f64, y_m: f64) -> usize;
    /// Appends the state of every tile whose centre lies in `area` to `out`.
    /// Terrains without tiles append nothing.
    fn tiles_in(&self, world: &PhysicsWorld, area: Rect, out: &mut Vec<TileState>);
    /// The part of the ground plane the terrain covers, metres.
    fn extent(&self) -> Rect;
    /// Number of tiles (0 for terrains without tiles).
    fn tile_count(&self) -> usize;
    /// Side of one tile's top face and the distance between tile centres,
    /// metres; `None` for terrains without tiles.
    fn tile_geometry_m(&self) -> Option<(f64, f64)> {
        None
    }
    /// The static ground's shape for viewers, where it is not the plane
    /// z = 0 (relief): triangles in the world frame. Default: none (flat
    /// ground; tiles are drawn from [`Terrain::tiles_in`]).
    fn ground_mesh(&self) -> Option<GroundMesh> {
        None
    }
    /// Times after each [`Terrain::reset`] at which the terrain changes by
    /// itself, s, in order (the `switch` terrain's springs): `quadwalk
    /// eval` measures how the robot responds to the first. Default: none.
    fn change_times_secs(&self) -> Vec<f64> {
        Vec::new()
    }
    /// Lines `quadwalk terrain show` prints after the regions: what else a
    /// user should know about this terrain's model (e.g. a load-sink
    /// curve). Default: none.
    fn details(&self) -> Vec<String> {
        Vec::new()
    }
}

#[cfg(test)]
mod tests;
