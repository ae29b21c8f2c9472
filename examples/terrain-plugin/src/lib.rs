//! `pontoon:<depth>`: a terrain model written outside quadwalk, the example
//! of `docs/guide/terrains.md` "Adding a terrain model".
//!
//! The ground is a row of pontoons along x: plates 60 cm long (`plate=`) and
//! 1.2 m wide, each on a vertical spring, so the whole robot stands on one or
//! two plates at a time. A plate's spring is set so that the robot standing
//! on one plate alone sinks it `depth`: k = m g / d (the supported mass m
//! from the build context). Plates cannot tilt (prismatic joints); they sink
//! at most `travel`, onto a fixed floor.
//!
//! What quadwalk needs from a plugin, in order: a name and parameters
//! ([`TerrainPlugin`]), bodies and joints built into rapier's world
//! ([`Terrain::build`], colliders in [`terrain_collision_groups`]), the
//! surface height the task reads, the regions eval splits by, and the tiles
//! (here: plates) the Rerun viewer draws, each with its sink
//! ([`Terrain::tiles_in`]).

use terrain_plugins::rapier3d::prelude::*;
use terrain_plugins::{
    BuildContext, ParamDecl, ParamKind, ParamValue, Rect, Region, Terrain, TerrainPlugin,
    TerrainSpec, TileState, terrain_collision_groups,
};

/// Plate thickness, m.
const PLATE_THICKNESS_M: f64 = 0.05;
/// Width of the row of plates (across, y), m.
const WIDTH_M: f64 = 1.2;
/// Damping ratio of a loaded plate.
const DAMPING_RATIO: f64 = 0.5;
/// Gap between neighbouring plates, m.
const GAP_M: f64 = 0.005;

/// The `pontoon` plugin.
pub struct PontoonPlugin;

impl TerrainPlugin for PontoonPlugin {
    fn name(&self) -> &'static str {
        "pontoon"
    }

    fn summary(&self) -> &'static str {
        "wide plates on springs; the robot alone on one sinks it <depth> (e.g. pontoon:3cm)"
    }

    fn params(&self) -> Vec<ParamDecl> {
        vec![
            ParamDecl::required(
                "depth",
                ParamKind::Length,
                "sink of one plate under the standing robot",
            ),
            ParamDecl::optional(
                "plate",
                ParamKind::Length,
                ParamValue::Length(0.6),
                "plate length along x, default 60cm",
            ),
            ParamDecl::optional(
                "travel",
                ParamKind::Length,
                ParamValue::Length(0.15),
                "how far a plate can sink, default 15cm",
            ),
            ParamDecl::optional(
                "length",
                ParamKind::Length,
                ParamValue::Length(20.0),
                "extent along x from 2.5 plates behind the start, default 20m",
            ),
        ]
    }

    fn validate(&self, spec: &TerrainSpec) -> Result<(), String> {
        let (depth, travel) = (spec.length_m("depth"), spec.length_m("travel"));
        if depth >= travel {
            return Err(format!(
                "depth {depth} m must be less than travel {travel} m"
            ));
        }
        let (plate, length) = (spec.length_m("plate"), spec.length_m("length"));
        if plate <= GAP_M || length < 3.0 * plate {
            return Err(format!(
                "plate {plate} m must exceed the 5 mm gap, and length {length} m hold three plates"
            ));
        }
        Ok(())
    }

    fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain> {
        let depth_m = spec.length_m("depth");
        let plate_mass_kg = 2.0;
        // The robot on one plate: k d = m g.
        let stiffness_n_per_m = ctx.supported_mass_kg * ctx.gravity_m_per_s2 / depth_m;
        let loaded_kg = plate_mass_kg + ctx.supported_mass_kg;
        let damping_n_s_per_m = 2.0 * DAMPING_RATIO * (stiffness_n_per_m * loaded_kg).sqrt();
        let plate_m = spec.length_m("plate");
        // Plate centres on multiples of the plate length: the robot placed at
        // x = 0 stands on one plate.
        let first_x_m = -2.5 * plate_m;
        let plates = (spec.length_m("length") / plate_m).floor() as usize;
        Box::new(Pontoons {
            spec: spec.clone(),
            plate_m,
            first_x_m,
            travel_m: spec.length_m("travel"),
            plate_mass_kg,
            stiffness_n_per_m,
            damping_n_s_per_m,
            gravity_m_per_s2: ctx.gravity_m_per_s2,
            handles: Vec::with_capacity(plates),
            plates,
            regions: vec![Region {
                index: 0,
                label: spec.to_string(),
                x_range_m: (first_x_m, first_x_m + plates as f64 * plate_m),
                stiffness_n_per_m: Some(stiffness_n_per_m),
                damping_n_s_per_m: Some(damping_n_s_per_m),
                expected_sink_m: depth_m,
            }],
        })
    }
}

/// A row of sprung plates.
pub struct Pontoons {
    spec: TerrainSpec,
    plate_m: f64,
    first_x_m: f64,
    travel_m: f64,
    plate_mass_kg: f64,
    stiffness_n_per_m: f64,
    damping_n_s_per_m: f64,
    gravity_m_per_s2: f64,
    plates: usize,
    handles: Vec<RigidBodyHandle>,
    regions: Vec<Region>,
}

impl Pontoons {
    fn center_x_m(&self, i: usize) -> f64 {
        self.first_x_m + (i as f64 + 0.5) * self.plate_m
    }

    fn plate_at(&self, x_m: f64, y_m: f64) -> Option<usize> {
        let i = ((x_m - self.first_x_m) / self.plate_m).floor();
        (i >= 0.0 && (i as usize) < self.plates && y_m.abs() <= WIDTH_M / 2.0).then_some(i as usize)
    }

    /// How far plate `i` is pushed below rest, m.
    pub fn sink_m(&self, world: &PhysicsWorld, i: usize) -> f64 {
        let rest_z_m = -PLATE_THICKNESS_M / 2.0;
        self.handles
            .get(i)
            .and_then(|h| world.bodies.get(*h))
            .map_or(0.0, |b| rest_z_m - b.translation().z as f64)
    }

    fn floor_top_m(&self) -> f64 {
        -(self.travel_m + PLATE_THICKNESS_M)
    }
}

impl Terrain for Pontoons {
    fn spec(&self) -> &TerrainSpec {
        &self.spec
    }

    fn build(&mut self, world: &mut PhysicsWorld) {
        let base = world.insert_body(RigidBodyBuilder::fixed());
        // A floor under everything, so a foot between or beyond the plates lands somewhere.
        let floor = ColliderBuilder::cuboid(100.0, 100.0, 0.5)
            .translation(Vector::new(0.0, 0.0, (self.floor_top_m() - 0.5) as f32))
            .collision_groups(terrain_collision_groups());
        world.insert_collider(floor, Some(base));
        for i in 0..self.plates {
            let rest = Vector::new(
                self.center_x_m(i) as f32,
                0.0,
                (-PLATE_THICKNESS_M / 2.0) as f32,
            );
            let handle = world.insert_body(RigidBodyBuilder::dynamic().translation(rest));
            let half = Vector::new(
                ((self.plate_m - GAP_M) / 2.0) as f32,
                (WIDTH_M / 2.0) as f32,
                (PLATE_THICKNESS_M / 2.0) as f32,
            );
            let plate = ColliderBuilder::cuboid(half.x, half.y, half.z)
                .mass(self.plate_mass_kg as f32)
                .friction(1.0)
                .collision_groups(terrain_collision_groups());
            world.insert_collider(plate, Some(handle));
            // The spring: a force-based position motor, k (q* - q) - c q',
            // its target raised so that it carries the plate's own weight at q = 0.
            let preload_m = self.plate_mass_kg * self.gravity_m_per_s2 / self.stiffness_n_per_m;
            let joint = PrismaticJointBuilder::new(Vector::Z)
                .local_anchor1(rest)
                .local_anchor2(Vector::ZERO)
                .limits([-self.travel_m as f32, 0.0])
                .motor_model(MotorModel::ForceBased)
                .motor_position(
                    preload_m as f32,
                    self.stiffness_n_per_m as f32,
                    self.damping_n_s_per_m as f32,
                );
            world.impulse_joints.insert(base, handle, joint, true);
            self.handles.push(handle);
        }
    }

    fn reset(&mut self, world: &mut PhysicsWorld) {
        for i in 0..self.plates {
            let rest = Vector::new(
                self.center_x_m(i) as f32,
                0.0,
                (-PLATE_THICKNESS_M / 2.0) as f32,
            );
            if let Some(body) = world.bodies.get_mut(self.handles[i]) {
                body.set_translation(rest, false);
                body.set_linvel(Vector::ZERO, false);
                body.set_angvel(Vector::ZERO, false);
            }
        }
    }

    fn surface_height_m(&self, world: &PhysicsWorld, x_m: f64, y_m: f64) -> f64 {
        match self.plate_at(x_m, y_m) {
            Some(i) => -self.sink_m(world, i),
            None => self.floor_top_m(),
        }
    }

    fn regions(&self) -> &[Region] {
        &self.regions
    }

    fn region_index_at(&self, _x_m: f64, _y_m: f64) -> usize {
        0
    }

    /// The viewer draws each plate as a square tile of side `side_m` at its
    /// centre, coloured and lowered by its sink; a plate is shown as the
    /// square of its length.
    fn tiles_in(&self, world: &PhysicsWorld, area: Rect, out: &mut Vec<TileState>) {
        for i in 0..self.plates {
            let center_m = [self.center_x_m(i), 0.0];
            if area.contains(center_m) {
                out.push(TileState {
                    center_m,
                    side_m: self.plate_m - GAP_M,
                    sink_m: self.sink_m(world, i),
                    rest_top_m: 0.0,
                    rest_slope: 0.0,
                    region: 0,
                });
            }
        }
    }

    fn extent(&self) -> Rect {
        Rect {
            min_m: [self.first_x_m, -WIDTH_M / 2.0],
            max_m: [
                self.first_x_m + self.plates as f64 * self.plate_m,
                WIDTH_M / 2.0,
            ],
        }
    }

    fn tile_count(&self) -> usize {
        self.plates
    }

    fn tile_geometry_m(&self) -> Option<(f64, f64)> {
        Some((self.plate_m - GAP_M, self.plate_m))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use terrain_plugins::Registry;

    fn registry() -> Registry {
        let mut registry = Registry::builtin();
        registry.register(Box::new(PontoonPlugin)).unwrap();
        registry
    }

    #[test]
    fn a_plate_carrying_the_robots_weight_sinks_the_named_depth() {
        let ctx = BuildContext::default();
        let mut terrain = registry().create("pontoon:3cm", &ctx).unwrap();
        let mut world = PhysicsWorld::new();
        world.gravity = Vector::new(0.0, 0.0, -9.81);
        world.integration_parameters.dt = 1.0 / 240.0;
        terrain.build(&mut world);
        // The plate centred on x = 0.6 m, pressed with the robot's weight for 3 s.
        let (handle, _) = world
            .bodies
            .iter()
            .find(|(_, b)| b.is_dynamic() && (b.translation().x - 0.6).abs() < 0.01)
            .expect("a plate is centred on x = 0.6 m");
        let weight_n = ctx.supported_mass_kg * ctx.gravity_m_per_s2;
        world.bodies[handle].add_force(Vector::new(0.0, 0.0, -weight_n as f32), true);
        for _ in 0..720 {
            terrain.before_step(&mut world, 1.0 / 240.0);
            world.step();
        }
        let sink_m = -terrain.surface_height_m(&world, 0.6, 0.0);
        assert!(
            (sink_m - 0.03).abs() < 0.002,
            "sink {sink_m} m, expected 3 cm"
        );
        // its neighbours carry nothing
        assert!(terrain.surface_height_m(&world, 1.2, 0.0).abs() < 1e-4);
        // and reset puts it back
        terrain.reset(&mut world);
        assert!(terrain.surface_height_m(&world, 0.6, 0.0).abs() < 1e-6);
    }

    #[test]
    fn bad_parameters_are_refused_with_the_input_named() {
        let err = registry().parse("pontoon:20cm").unwrap_err().to_string();
        assert!(
            err.contains("pontoon:20cm") && err.contains("travel"),
            "{err}"
        );
        let err = registry()
            .parse("pontoon:3cm:plate=1cm:length=2cm")
            .unwrap_err()
            .to_string();
        assert!(err.contains("length"), "{err}");
    }
}
