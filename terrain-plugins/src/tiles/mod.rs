//! A field of spring-loaded tiles: the body of the `elastic` and `varying`
//! terrains.
//!
//! Each tile is a box whose top rests at z = 0, joined to a fixed base by a
//! vertical prismatic joint; the box's body moves along z only (its other
//! axes locked on the body, so the joint solves only its spring and stops).
//! The joint's force-based position motor is the
//! spring: force = k (q_rest - q) - c q', with q_rest set so that the spring
//! also carries the tile's own weight (so an unloaded tile rests exactly at
//! z = 0 against its upper stop and sinks only under load). The joint's
//! travel is limited to [-travel, 0].
//!
//! Stiffness (the paper's definition): the spring is set so that the mean
//! sink of the four tiles under the feet of the robot standing still equals
//! the named depth d. At rest the four springs carry the robot's weight, so
//! sum_i k s_i = m g and mean(s_i) = m g / (4 k) = d, i.e. k = m g / (4 d).
//!
//! Damping: c = 2 zeta sqrt(k m_eff) with m_eff = tile mass + a quarter of
//! the supported mass (the mass one loaded tile carries), so zeta is the
//! damping ratio of a loaded tile.
//!
//! Idle tiles cost no physics time: tiles are inserted asleep, each is its own
//! island (the base is fixed), and rapier only wakes those the robot touches;
//! they fall asleep again once still. (Rapier's first step of a new world
//! wakes them all; `after_step` sends the untouched ones back to sleep.)
//!
//! Hills (`slope=<degrees>`): a tiled region may lie on a hill, rising at
//! the angle from the region's start to its middle and falling to its end
//! (as rigid `slope` regions). Each tile is the same box turned about y, its
//! top face the chord of the hill over its cell, so neighbouring tops meet
//! at the cells' edges. The springs stay vertical, with the same
//! k = m g / (4 d): the load a standing robot puts on the ground is its
//! weight, vertical on any incline, so the standing robot still sinks d
//! (measured vertically) and `elastic:5cm` means the same sink on a slope as
//! on flat ground; the downhill pull of gravity along the incline is held
//! by friction at the feet and by the tiles' locked horizontal axes, as
//! rigid ground holds it. (Springs along the incline's normal would carry
//! m g cos(angle) and sink d cos(angle), and take a second axis of solver
//! work per tile.) Sinks are measured along z.
//!
//! Layout: tile centres lie on multiples of the tile pitch (so a robot placed
//! at a whole number of pitches stands with its feet near tile centres);
//! columns run along x from `-back` to `length - back`, rows across a width
//! centred on y = 0.

mod layout;
mod params;

use rapier3d::prelude::*;

use layout::{FieldLayout, RegionModel};
pub use layout::{RegionLayout, TileRest, TileSpring};
pub use params::{DEFAULT_LENGTH_M, TileParams, friction_decl, tile_param_decls};

use crate::relief::RegionRelief;
use crate::soil::SoilModel;
use crate::spec::TerrainSpec;
use crate::switch::StiffnessSwitch;
use crate::{BuildContext, GroundMesh, Rect, Region, Terrain, TileState, terrain_collider};

/// Thickness of a tile, metres.
pub const TILE_THICKNESS_M: f64 = 0.05;
/// Default friction coefficient of tile and ground surfaces (the Laikago
/// model's lateral friction is 1.0 too). Every terrain collider combines its
/// friction with the robot's by the minimum (rapier's
/// `CoefficientCombineRule::Min`), so a terrain's `friction=<mu>` is the
/// contact's coefficient.
pub const GROUND_FRICTION: f32 = 1.0;

/// A built tile.
#[derive(Debug, Clone, Copy)]
struct Tile {
    body: RigidBodyHandle,
    joint: ImpulseJointHandle,
    spring: TileSpring,
    /// the spring's target above rest that carries the tile's own weight, m
    preload_m: f64,
    /// soil tiles: the model and the permanent sink, m
    soil: Option<(SoilModel, f64)>,
}

/// A field of tiles on springs, grouped into regions along x.
pub struct TiledTerrain {
    spec: TerrainSpec,
    params: TileParams,
    ctx: BuildContext,
    /// where every region, cell and spring lies (pure, no rapier)
    layout: FieldLayout,
    /// one entry per cell, row-major by column: `None` for rigid cells
    tiles: Vec<Option<Tile>>,
    /// indices in `tiles` of the soil tiles
    soil_tiles: Vec<usize>,
    built: bool,
    /// the world has taken its first step (see [`Terrain::after_step`])
    stepped: bool,
    /// `switch`: when every spring changes, and to what
    switch: Option<StiffnessSwitch>,
    /// simulated time since the last reset, s (kept only with a switch)
    elapsed_secs: f64,
    /// the springs have switched since the last reset
    switched: bool,
}

impl TiledTerrain {
    /// Lays out the field ([`FieldLayout`]); bodies are inserted by
    /// [`Terrain::build`].
    pub fn new(
        spec: TerrainSpec,
        params: TileParams,
        layout: RegionLayout,
        ctx: &BuildContext,
    ) -> Self {
        Self {
            spec,
            params,
            ctx: ctx.clone(),
            layout: FieldLayout::new(&params, &layout, ctx),
            tiles: Vec::new(),
            soil_tiles: Vec::new(),
            built: false,
            stepped: false,
            switch: None,
            elapsed_secs: 0.0,
            switched: false,
        }
    }

    /// The same field, whose springs all switch as `switch` says after
    /// each reset (the `switch` terrain).
    pub fn with_switch(mut self, switch: StiffnessSwitch) -> Self {
        self.switch = Some(switch);
        self
    }

    /// Gives every tile `spring` (`None`: its own from the layout), with the
    /// preload that holds the tile's weight at its rest position. Sleeping
    /// tiles stay asleep: unloaded, they rest where they are under either
    /// spring.
    fn set_springs(&mut self, world: &mut PhysicsWorld, spring: Option<TileSpring>) {
        let g = self.ctx.gravity_m_per_s2;
        for (index, tile) in self.tiles.iter_mut().enumerate() {
            let Some(tile) = tile else {
                continue;
            };
            let Some(s) = spring.or(self.layout.cell_springs[index]) else {
                continue;
            };
            tile.spring = s;
            tile.preload_m = self.params.tile_mass_kg * g / s.stiffness_n_per_m;
            if let Some(joint) = world.impulse_joints.get_mut(tile.joint, false) {
                joint.data.set_motor_position(
                    JointAxis::LinX,
                    tile.preload_m as f32,
                    s.stiffness_n_per_m as f32,
                    s.damping_n_s_per_m as f32,
                );
            }
        }
    }

    fn center_m(&self, ix: usize, iy: usize) -> [f64; 2] {
        [
            self.layout.first_center_m[0] + ix as f64 * self.params.pitch_m,
            self.layout.first_center_m[1] + iy as f64 * self.params.pitch_m,
        ]
    }

    /// The cell (column, row) whose square holds (x, y), if any.
    fn cell_at(&self, x_m: f64, y_m: f64) -> Option<(usize, usize)> {
        let fx = ((x_m - self.layout.first_center_m[0]) / self.params.pitch_m).round();
        let fy = ((y_m - self.layout.first_center_m[1]) / self.params.pitch_m).round();
        let in_range = |f: f64, n: usize| f >= 0.0 && f < n as f64;
        (in_range(fx, self.layout.columns) && in_range(fy, self.layout.rows))
            .then_some((fx as usize, fy as usize))
    }

    /// Height of the fixed base the tiles hang from (top face), metres.
    pub fn base_top_m(&self) -> f64 {
        -(self.params.travel_m + TILE_THICKNESS_M)
    }

    /// Each cell's spring (row-major by column, `None` for rigid cells): the
    /// depths a range drew, for inspection and tests.
    pub fn cell_springs(&self) -> &[Option<TileSpring>] {
        &self.layout.cell_springs
    }

    /// Where the body of tile (ix, iy) rests: its box's centre, m. A flat
    /// tile's box hangs from z = 0; a tile on a hill is the same box turned
    /// about y by its rest top's inclination a, its top face's centre on the
    /// rest top, so its centre lies thickness / 2 below that along the
    /// face's normal (-sin a, 0, cos a).
    fn tile_rest_center_m(&self, ix: usize, iy: usize) -> [f64; 3] {
        let [cx, cy] = self.center_m(ix, iy);
        let half_m = TILE_THICKNESS_M / 2.0;
        match self.layout.column_rest[ix] {
            None => [cx, cy, -half_m],
            Some(rest) => {
                let a = rest.angle_rad();
                [cx + half_m * a.sin(), cy, rest.top_m - half_m * a.cos()]
            }
        }
    }

    /// How far tile `index` is pushed down from rest, m (along z: the tiles
    /// move vertically on hills too).
    fn tile_sink_m(&self, world: &PhysicsWorld, index: usize, handle: RigidBodyHandle) -> f64 {
        let rest_center_z =
            self.tile_rest_center_m(index / self.layout.rows, index % self.layout.rows)[2];
        world
            .bodies
            .get(handle)
            .map_or(0.0, |body| rest_center_z - body.translation().z as f64)
    }

    /// Puts tile `index` back at rest (top face at z = 0, no velocity) and
    /// to sleep (between episodes; tested to carry load again after it).
    fn put_to_rest(&self, world: &mut PhysicsWorld, index: usize, handle: RigidBodyHandle) {
        if let Some(Some(tile)) = self.tiles.get(index)
            && let Some((_, plastic_m)) = tile.soil
            && plastic_m > 0.0
            && let Some(joint) = world.impulse_joints.get_mut(tile.joint, false)
        {
            let s = tile.spring;
            joint.data.set_motor_position(
                JointAxis::LinX,
                tile.preload_m as f32,
                s.stiffness_n_per_m as f32,
                s.damping_n_s_per_m as f32,
            );
        }
        let Some(body) = world.bodies.get_mut(handle) else {
            return;
        };
        let [x, y, z] = self.tile_rest_center_m(index / self.layout.rows, index % self.layout.rows);
        body.set_translation(Vector::new(x as f32, y as f32, z as f32), false);
        body.set_linvel(Vector::ZERO, false);
        body.set_angvel(Vector::ZERO, false);
        body.sleep();
    }

    /// The tile parameters.
    pub fn params(&self) -> &TileParams {
        &self.params
    }

    /// The relief of region `region`, if it is a relief region.
    fn relief(&self, region: usize) -> Option<&RegionRelief> {
        match &self.layout.models[region] {
            RegionModel::Relief(relief) => Some(relief),
            _ => None,
        }
    }

    /// The unloaded height of the ground at (x, y) in column `ix`: a relief
    /// region's, tiles on a hill their rest top's, else the tiles' and rigid
    /// blocks' top, z = 0, m.
    fn resting_top_m(&self, ix: usize, x_m: f64, y_m: f64) -> f64 {
        if let Some(rest) = self.layout.column_rest[ix] {
            return rest.top_at_m(x_m, self.center_m(ix, 0)[0]);
        }
        self.relief(self.layout.column_region[ix])
            .map_or(0.0, |relief| relief.height_m(x_m, y_m))
    }
}

impl Terrain for TiledTerrain {
    fn spec(&self) -> &TerrainSpec {
        &self.spec
    }

    fn build(&mut self, world: &mut PhysicsWorld) {
        assert!(!self.built, "a terrain is built into one world, once");
        self.built = true;
        let p = self.params;
        let extent = self.extent();
        let base = world.insert_body(RigidBodyBuilder::fixed());

        // The fixed base under the whole field, and beyond it.
        let base_top = self.base_top_m();
        let margin = 50.0;
        let half_x = (extent.max_m[0] - extent.min_m[0]) / 2.0 + margin;
        let half_y = (extent.max_m[1] - extent.min_m[1]) / 2.0 + margin;
        let floor =
            ColliderBuilder::cuboid(half_x as f32, half_y as f32, 0.5).translation(Vector::new(
                ((extent.min_m[0] + extent.max_m[0]) / 2.0) as f32,
                0.0,
                (base_top - 0.5) as f32,
            ));
        world.insert_collider(terrain_collider(floor, p.friction), Some(base));

        // Rigid and relief regions: one solid block per region, top at z = 0
        // (just below a relief).
        let depth_below = p.travel_m + TILE_THICKNESS_M;
        for ((region, model), friction) in self
            .layout
            .regions
            .iter()
            .zip(&self.layout.models)
            .zip(&self.layout.frictions)
        {
            // Relief: its solids, over a block that stops just below it.
            let top_m = match model {
                RegionModel::Rigid => 0.0,
                RegionModel::Relief(relief) => {
                    for collider in relief.colliders() {
                        world.insert_collider(terrain_collider(collider, *friction), Some(base));
                    }
                    relief.lowest_m() - 0.01
                }
                _ => continue,
            };
            let (x0, x1) = region.x_range_m;
            let thickness_m = depth_below + top_m;
            let block = ColliderBuilder::cuboid(
                ((x1 - x0) / 2.0) as f32,
                ((extent.max_m[1] - extent.min_m[1]) / 2.0) as f32,
                (thickness_m / 2.0) as f32,
            )
            .translation(Vector::new(
                ((x0 + x1) / 2.0) as f32,
                0.0,
                (top_m - thickness_m / 2.0) as f32,
            ));
            world.insert_collider(terrain_collider(block, *friction), Some(base));
        }

        // Elastic cells: a sleeping box on a sprung prismatic joint. The box
        // itself can only move along z (its other five axes are locked on
        // the body, so the solver never sees them), and the joint keeps only
        // the rows it needs on that axis: the spring (a force-based position
        // motor) and the travel limits. A prismatic joint with its five
        // locked rows gives the same motion up to the solver's error, and
        // cost ~20 % of a step of the robot standing on 15 x 5 tiles
        // (docs/notebook/2026-11-29-physics-three-times-faster.md, "Tiles guided by their body").
        let side = p.pitch_m - p.gap_m;
        let g = self.ctx.gravity_m_per_s2;
        self.tiles = Vec::with_capacity(self.layout.columns * self.layout.rows);
        for ix in 0..self.layout.columns {
            let soil = match &self.layout.models[self.layout.column_region[ix]] {
                RegionModel::Soil { model, .. } => Some((*model, 0.0)),
                _ => None,
            };
            for iy in 0..self.layout.rows {
                let Some(s) = self.layout.cell_springs[ix * self.layout.rows + iy] else {
                    self.tiles.push(None);
                    continue;
                };
                let [x, y, z] = self.tile_rest_center_m(ix, iy);
                let rest = Vector::new(x as f32, y as f32, z as f32);
                let body = RigidBodyBuilder::dynamic()
                    .translation(rest)
                    .sleeping(true)
                    .locked_axes(
                        LockedAxes::TRANSLATION_LOCKED_X
                            | LockedAxes::TRANSLATION_LOCKED_Y
                            | LockedAxes::ROTATION_LOCKED,
                    );
                let handle = world.insert_body(body);
                let collider = match self.layout.column_rest[ix] {
                    None => ColliderBuilder::cuboid(
                        (side / 2.0) as f32,
                        (side / 2.0) as f32,
                        (TILE_THICKNESS_M / 2.0) as f32,
                    ),
                    // On a hill: the box turned about y, as long along its
                    // top as its cell's side is wide over the ground.
                    Some(rest) => {
                        let a = rest.angle_rad();
                        ColliderBuilder::cuboid(
                            (side / 2.0 / a.cos()) as f32,
                            (side / 2.0) as f32,
                            (TILE_THICKNESS_M / 2.0) as f32,
                        )
                        .rotation(Vector::new(0.0, -a as f32, 0.0))
                    }
                }
                .mass(p.tile_mass_kg as f32);
                let friction = self.layout.frictions[self.layout.column_region[ix]];
                world.insert_collider(terrain_collider(collider, friction), Some(handle));
                // Spring target above rest so that at q = 0 the spring holds the tile's weight.
                let preload_m = p.tile_mass_kg * g / s.stiffness_n_per_m;
                let joint = PrismaticJointBuilder::new(Vector::Z)
                    .local_anchor1(rest)
                    .local_anchor2(Vector::ZERO)
                    .limits([-p.travel_m as f32, 0.0])
                    .motor_model(MotorModel::ForceBased)
                    .motor_position(
                        preload_m as f32,
                        s.stiffness_n_per_m as f32,
                        s.damping_n_s_per_m as f32,
                    );
                let mut joint: GenericJoint = joint.build().into();
                joint.locked_axes = JointAxesMask::empty();
                let joint = world.impulse_joints.insert(base, handle, joint, false);
                if soil.is_some() {
                    self.soil_tiles.push(self.tiles.len());
                }
                self.tiles.push(Some(Tile {
                    body: handle,
                    joint,
                    spring: s,
                    preload_m,
                    soil,
                }));
            }
        }
    }

    /// After a fresh world's first step, makes every tile that is still at
    /// rest eligible for sleep, so that rapier's own sleep pass puts it to
    /// sleep at the next step. The tiles are inserted asleep, but rapier's first
    /// step (which builds its islands) wakes every body, and an awake body
    /// sleeps only after 0.5 s of rest: without this, each new world solved
    /// all its tile joints (3,000 on the default 40 m field) for its first
    /// 120 steps, the whole settle of an episode. A tile the robot already
    /// touches is moving and stays awake; a sleeping tile wakes on contact,
    /// as in every later step.
    fn after_step(&mut self, world: &mut PhysicsWorld, _dt_secs: f64) {
        if self.stepped {
            return;
        }
        self.stepped = true;
        for (index, tile) in self.tiles.iter().enumerate() {
            let Some(tile) = tile else {
                continue;
            };
            let sink_m = self.tile_sink_m(world, index, tile.body);
            let Some(body) = world.bodies.get_mut(tile.body) else {
                continue;
            };
            let at_rest = sink_m.abs() < 1e-5
                && body.linvel().length() < 1e-4
                && body.angvel().length() < 1e-4;
            if at_rest && !body.is_sleeping() {
                // Eligible now: rapier's own sleep pass takes it out of the
                // active set at the next step (flagging it asleep by hand
                // here, right after the first step, left it integrated
                // without its joint: it fell away).
                let activation = body.activation_mut();
                activation.time_since_can_sleep = activation.time_until_sleep;
            }
        }
    }

    /// Soil: moves each awake tile's permanent sink (and so its spring's
    /// rest point) with the sink it has now (see [`crate::soil`]); with
    /// recovery, a sleeping tile with a permanent sink is woken to rise.
    fn before_step(&mut self, world: &mut PhysicsWorld, dt_secs: f64) {
        if let Some(switch) = self.switch
            && !self.switched
        {
            if self.elapsed_secs >= switch.at_secs {
                let spring = self.params.spring(switch.depth_m, &self.ctx);
                self.set_springs(world, Some(spring));
                self.switched = true;
            }
            self.elapsed_secs += dt_secs;
        }
        for &index in &self.soil_tiles {
            let Some(tile) = self.tiles[index] else {
                continue;
            };
            let Some((model, plastic_m)) = tile.soil else {
                continue;
            };
            let Some(body) = world.bodies.get(tile.body) else {
                continue;
            };
            let recovering = model.recovery_secs > 0.0 && plastic_m > 0.0;
            if body.is_sleeping() && !recovering {
                continue;
            }
            let sink_m = self.tile_sink_m(world, index, tile.body);
            let advanced_m = model.advance(plastic_m, sink_m, dt_secs);
            if advanced_m == plastic_m {
                continue;
            }
            let recovered_m = if recovering && advanced_m < 1e-6 {
                0.0
            } else {
                advanced_m
            };
            // A tile still yielding creeps slowly: keep it awake while its
            // rest point moves (rapier would put it to sleep mid-way).
            let moving = recovering || (recovered_m - plastic_m).abs() > 1e-7;
            if let Some(joint) = world.impulse_joints.get_mut(tile.joint, moving) {
                let s = tile.spring;
                joint.data.set_motor_position(
                    JointAxis::LinX,
                    (tile.preload_m - recovered_m) as f32,
                    s.stiffness_n_per_m as f32,
                    s.damping_n_s_per_m as f32,
                );
            }
            if let Some(Some(tile)) = self.tiles.get_mut(index) {
                tile.soil = Some((model, recovered_m));
            }
        }
    }

    fn reset(&mut self, world: &mut PhysicsWorld) {
        if self.switched {
            self.set_springs(world, None);
            self.switched = false;
        }
        self.elapsed_secs = 0.0;
        for index in 0..self.tiles.len() {
            let Some(tile) = self.tiles[index] else {
                continue;
            };
            let Some(body) = world.bodies.get(tile.body) else {
                continue;
            };
            let yielded = tile.soil.is_some_and(|(_, plastic_m)| plastic_m > 0.0);
            if body.is_sleeping() && !yielded {
                continue; // asleep and elastic means at rest already
            }
            self.put_to_rest(world, index, tile.body);
            if let Some(Some(Tile {
                soil: Some((_, plastic_m)),
                ..
            })) = self.tiles.get_mut(index)
            {
                *plastic_m = 0.0;
            }
        }
    }

    fn surface_height_m(&self, world: &PhysicsWorld, x_m: f64, y_m: f64) -> f64 {
        match self.cell_at(x_m, y_m) {
            None => self.base_top_m(),
            Some((ix, iy)) => match self
                .tiles
                .get(ix * self.layout.rows + iy)
                .copied()
                .flatten()
            {
                Some(tile) => {
                    let sink_m = self.tile_sink_m(world, ix * self.layout.rows + iy, tile.body);
                    match self.layout.column_rest[ix] {
                        None => -sink_m,
                        Some(rest) => rest.top_at_m(x_m, self.center_m(ix, iy)[0]) - sink_m,
                    }
                }
                None => self.resting_top_m(ix, x_m, y_m),
            },
        }
    }

    fn rest_height_m(&self, x_m: f64, y_m: f64) -> f64 {
        match self.cell_at(x_m, y_m) {
            None => self.base_top_m(),
            Some((ix, _)) => self.resting_top_m(ix, x_m, y_m),
        }
    }

    fn regions(&self) -> &[Region] {
        &self.layout.regions
    }

    fn region_index_at(&self, x_m: f64, _y_m: f64) -> usize {
        let f = ((x_m - self.layout.first_center_m[0]) / self.params.pitch_m).round();
        let ix = f.clamp(0.0, (self.layout.columns - 1) as f64) as usize;
        self.layout.column_region[ix]
    }

    fn tiles_in(&self, world: &PhysicsWorld, area: Rect, out: &mut Vec<TileState>) {
        let p = self.params.pitch_m;
        let index_range = |min: f64, max: f64, first: f64, n: usize| {
            let lo = ((min - first) / p).ceil().max(0.0);
            let hi = ((max - first) / p).floor().min(n as f64 - 1.0);
            if hi < lo {
                0..0
            } else {
                lo as usize..hi as usize + 1
            }
        };
        let xs = index_range(
            area.min_m[0],
            area.max_m[0],
            self.layout.first_center_m[0],
            self.layout.columns,
        );
        let ys = index_range(
            area.min_m[1],
            area.max_m[1],
            self.layout.first_center_m[1],
            self.layout.rows,
        );
        for ix in xs {
            for iy in ys.clone() {
                let index = ix * self.layout.rows + iy;
                let sink_m = match self.tiles.get(index).copied().flatten() {
                    Some(tile) => self.tile_sink_m(world, index, tile.body),
                    None => 0.0,
                };
                let center_m = self.center_m(ix, iy);
                out.push(TileState {
                    center_m,
                    side_m: p - self.params.gap_m,
                    sink_m,
                    rest_top_m: self.resting_top_m(ix, center_m[0], center_m[1]),
                    rest_slope: self.layout.column_rest[ix].map_or(0.0, |rest| rest.slope),
                    region: self.layout.column_region[ix],
                });
            }
        }
    }

    fn extent(&self) -> Rect {
        let half = self.params.pitch_m / 2.0;
        let last = self.center_m(self.layout.columns - 1, self.layout.rows - 1);
        Rect {
            min_m: [
                self.layout.first_center_m[0] - half,
                self.layout.first_center_m[1] - half,
            ],
            max_m: [last[0] + half, last[1] + half],
        }
    }

    fn change_times_secs(&self) -> Vec<f64> {
        self.switch.iter().map(|s| s.at_secs).collect()
    }

    fn tile_count(&self) -> usize {
        self.layout.cell_springs.iter().flatten().count()
    }

    fn tile_geometry_m(&self) -> Option<(f64, f64)> {
        Some((self.params.pitch_m - self.params.gap_m, self.params.pitch_m))
    }

    /// The relief regions' ground (rough, hills, stairs), if any.
    fn ground_mesh(&self) -> Option<GroundMesh> {
        let mut all = GroundMesh::default();
        for relief in (0..self.layout.models.len()).filter_map(|r| self.relief(r)) {
            let mesh = relief.mesh();
            let first = all.vertices_m.len() as u32;
            all.vertices_m.extend(mesh.vertices_m);
            all.triangles
                .extend(mesh.triangles.iter().map(|t| t.map(|i| i + first)));
        }
        (!all.triangles.is_empty()).then_some(all)
    }

    /// A depth range's draw (smallest, mean and largest tile depth) and a
    /// soil's load-sink curve: a fresh tile's sink under each load while
    /// loading, and the permanent sink once unloaded.
    fn details(&self) -> Vec<String> {
        let mut lines = Vec::new();
        if let Some(switch) = self.switch {
            let spring = self.params.spring(switch.depth_m, &self.ctx);
            lines.push(format!(
                "every tile switches to the spring of {} ({:.1} N/m, damping {:.1} N s/m) {} s after each reset",
                crate::units::format_length(switch.depth_m),
                spring.stiffness_n_per_m,
                spring.damping_n_s_per_m,
                switch.at_secs
            ));
        }
        for (region, model) in self.layout.regions.iter().zip(&self.layout.models) {
            let in_region = |ix: usize| self.layout.column_region[ix] == region.index;
            let crest = (0..self.layout.columns)
                .filter(|&ix| in_region(ix))
                .filter_map(|ix| self.layout.column_rest[ix].map(|rest| (rest.top_m, ix)))
                .max_by(|a, b| a.0.total_cmp(&b.0));
            if let Some((top_m, ix)) = crest {
                lines.push(format!(
                    "region {} ({}): tiles on a hill, their tops {:.1} cm high at x = {:.2} m (springs vertical)",
                    region.index,
                    region.label,
                    top_m * 100.0,
                    self.center_m(ix, 0)[0]
                ));
            }
            match model {
                RegionModel::ElasticRange { .. } => {
                    let depths: Vec<f64> = (0..self.layout.columns)
                        .filter(|&ix| in_region(ix))
                        .flat_map(|ix| {
                            (0..self.layout.rows).map(move |iy| ix * self.layout.rows + iy)
                        })
                        .filter_map(|i| self.layout.cell_springs[i].map(|s| s.depth_m))
                        .collect();
                    let n = depths.len().max(1) as f64;
                    let (lo, hi) = depths
                        .iter()
                        .fold((f64::MAX, f64::MIN), |(lo, hi), &d| (lo.min(d), hi.max(d)));
                    lines.push(format!(
                        "region {} ({}): {} tiles drew depths {:.2}..{:.2} cm, mean {:.2} cm (seed {})",
                        region.index,
                        region.label,
                        depths.len(),
                        lo * 100.0,
                        hi * 100.0,
                        depths.iter().sum::<f64>() / n * 100.0,
                        self.ctx.seed
                    ));
                }
                RegionModel::Soil { model, .. } => {
                    let standing_n = self.ctx.supported_mass_kg * self.ctx.gravity_m_per_s2 / 4.0;
                    lines.push(format!(
                        "region {} ({}): k_r {:.1} N/m, yield load {:.1} N, hardening {:.1} N/m, recovery {}",
                        region.index,
                        region.label,
                        model.reload_stiffness_n_per_m,
                        model.yield_load_n,
                        model.hardening_n_per_m,
                        if model.recovery_secs > 0.0 {
                            format!("tau {} s", model.recovery_secs)
                        } else {
                            "none".to_string()
                        }
                    ));
                    lines.push(
                        "  load (N)  x standing  sink loading (cm)  permanent sink (cm)"
                            .to_string(),
                    );
                    for k in 0..=8 {
                        let load_n = standing_n * 0.25 * k as f64;
                        lines.push(format!(
                            "  {:8.1}  {:10.2}  {:17.2}  {:19.2}",
                            load_n,
                            0.25 * k as f64,
                            model.loading_sink_m(load_n) * 100.0,
                            model.permanent_sink_m(load_n) * 100.0
                        ));
                    }
                }
                RegionModel::Relief(relief) => match relief {
                    RegionRelief::Hill { x_m: (x0, x1), .. } => {
                        let middle = (x0 + x1) / 2.0;
                        lines.push(format!(
                            "region {} ({}): a hill {:.1} cm high at x = {:.2} m",
                            region.index,
                            region.label,
                            relief.height_m(middle, 0.0) * 100.0,
                            middle
                        ));
                    }
                    RegionRelief::Stairs {
                        x_m: (x0, x1),
                        length_m,
                        ..
                    } => {
                        let middle = (x0 + x1) / 2.0;
                        lines.push(format!(
                            "region {} ({}): {} steps up to {:.1} cm at x = {:.2} m, and down",
                            region.index,
                            region.label,
                            RegionRelief::stair_levels(x1 - x0, *length_m),
                            relief.height_m(middle, 0.0) * 100.0,
                            middle
                        ));
                    }
                    RegionRelief::Grid(_) => {}
                },
                _ => {}
            }
        }
        lines
    }
}
