//! Invariants that cross crates: a user's terrain plugin drives the robot's
//! world, determinism, sleeping tiles, collision groups and the contact report.

use nalgebra::Vector3;
use quadwalk_tests::world_on;
use robot::LegName;
use terrain_plugins::rapier3d::prelude::*;
use terrain_plugins::{
    BuildContext, ParamDecl, ParamKind, Rect, Region, Registry, Terrain, TerrainPlugin,
    TerrainSpec, TileState, terrain_collision_groups,
};

/// A user's plugin: rigid ground raised to a given height.
struct RaisedPlugin;

struct Raised {
    spec: TerrainSpec,
    height_m: f64,
    regions: Vec<Region>,
}

impl TerrainPlugin for RaisedPlugin {
    fn name(&self) -> &'static str {
        "raised"
    }
    fn summary(&self) -> &'static str {
        "rigid ground at z = <height>"
    }
    fn params(&self) -> Vec<ParamDecl> {
        vec![ParamDecl::required(
            "height",
            ParamKind::Length,
            "height of the ground",
        )]
    }
    fn create(&self, spec: &TerrainSpec, _ctx: &BuildContext) -> Box<dyn Terrain> {
        let region = Region {
            index: 0,
            label: spec.to_string(),
            x_range_m: (-100.0, 100.0),
            stiffness_n_per_m: None,
            damping_n_s_per_m: None,
            expected_sink_m: 0.0,
        };
        Box::new(Raised {
            spec: spec.clone(),
            height_m: spec.length_m("height"),
            regions: vec![region],
        })
    }
}

impl Terrain for Raised {
    fn spec(&self) -> &TerrainSpec {
        &self.spec
    }
    fn build(&mut self, world: &mut PhysicsWorld) {
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        let block = ColliderBuilder::cuboid(100.0, 100.0, 0.5)
            .translation(Vector::new(0.0, 0.0, self.height_m as f32 - 0.5))
            .collision_groups(terrain_collision_groups());
        world.insert_collider(block, Some(ground));
    }
    fn surface_height_m(&self, _world: &PhysicsWorld, _x_m: f64, _y_m: f64) -> f64 {
        self.height_m
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
            min_m: [-100.0; 2],
            max_m: [100.0; 2],
        }
    }
    fn tile_count(&self) -> usize {
        0
    }
}

#[test]
fn a_users_terrain_plugin_needs_one_register_call() {
    let mut registry = Registry::builtin();
    registry.register(Box::new(RaisedPlugin)).unwrap();
    let mut world = world_on(&registry, "raised:10cm", [0.0, 0.0], 0);
    let report = robot::stand(&mut world, 2.0);
    assert_eq!(report.region, "raised:10cm");
    // Standing on ground 10 cm up: the base sits ~10 cm higher than on rigid ground at z = 0.
    let mut flat = world_on(&registry, "rigid", [0.0, 0.0], 0);
    let flat_report = robot::stand(&mut flat, 2.0);
    let lift = report.base_height_m - flat_report.base_height_m;
    assert!((lift - 0.10).abs() < 0.002, "lift {lift}");
    assert!(report.non_foot_contacts.is_empty());
}

#[test]
fn same_seed_same_simulation_bit_for_bit() {
    let registry = Registry::builtin();
    let run = || {
        let mut world = world_on(&registry, "varying:2m:2,3,4,5cm,rigid", [0.4, 0.0], 11);
        let mut squat = world.squat_rad().to_vec();
        let mut trace = Vec::new();
        for step in 0..480 {
            // Sway the hips to make the tiles work.
            squat[1] = world.squat_rad()[1] + 0.2 * (step as f64 * 0.05).sin();
            world.set_joint_targets_rad(&squat);
            world.step();
            let p = world.base_pose();
            trace.push((
                p.translation.vector,
                world.joint_positions_rad(),
                world.applied_torques_n_m().to_vec(),
            ));
        }
        trace
    };
    let (a, b) = (run(), run());
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        assert!(
            x.0 == y.0 && x.1 == y.1 && x.2 == y.2,
            "diverged at step {i}"
        );
    }
}

#[test]
fn only_the_tiles_under_the_feet_wake_up() {
    let registry = Registry::builtin();
    let mut world = world_on(&registry, "elastic:5cm", [0.0, 0.0], 0);
    robot::stand(&mut world, 2.0);
    let awake: Vec<Vector3<f64>> = world
        .physics()
        .bodies
        .iter()
        .filter(|(_, b)| b.is_dynamic() && !b.is_sleeping())
        .filter(|(_, b)| {
            b.colliders()
                .iter()
                .all(|&c| physics_groups(&world, c) == terrain_collision_groups())
        })
        .map(|(_, b)| robot::seam::from_vector(b.translation()))
        .collect();
    let feet_now = world.feet_in_world_m();
    assert!(
        !awake.is_empty() && awake.len() <= 8,
        "{} tiles awake of {}: {awake:?} feet {feet_now:?}",
        awake.len(),
        world.terrain().tile_count()
    );
    let feet = world.feet_in_world_m();
    for tile in &awake {
        let near = feet.iter().any(|f| (f.xy() - tile.xy()).norm() < 0.3);
        assert!(near, "awake tile at {tile} is not under a foot");
    }
}

fn physics_groups(world: &robot::World, collider: ColliderHandle) -> InteractionGroups {
    world.physics().colliders[collider].collision_groups()
}

#[test]
fn a_folded_robot_reports_its_body_on_the_ground() {
    let registry = Registry::builtin();
    let mut world = world_on(&registry, "rigid", [0.0, 0.0], 0);
    robot::stand(&mut world, 1.0);
    assert_eq!(world.ground_contacts().feet, [true; 4]);
    assert!(world.ground_contacts().non_foot_links.is_empty());
    // Swing every leg up over the back: the chassis drops onto the ground.
    let mut tucked = world.squat_rad().to_vec();
    for leg in LegName::ALL {
        tucked[3 * leg.index() + 1] = 3.0;
        tucked[3 * leg.index() + 2] = -0.5;
    }
    world.set_joint_targets_rad(&tucked);
    for _ in 0..480 {
        world.step();
    }
    let contacts = world.ground_contacts();
    assert!(!contacts.non_foot_links.is_empty(), "{contacts:?}");
}

#[test]
fn tiles_meet_only_the_robot() {
    let registry = Registry::builtin();
    let world = world_on(&registry, "elastic:5cm", [0.0, 0.0], 0);
    let physics = world.physics();
    for (_, a) in physics.colliders.iter() {
        for (_, b) in physics.colliders.iter().take(50) {
            let both_terrain = a.collision_groups() == terrain_collision_groups()
                && b.collision_groups() == terrain_collision_groups();
            if both_terrain {
                assert!(!a.collision_groups().test(b.collision_groups()));
            }
        }
    }
    let robot_colliders = physics
        .colliders
        .iter()
        .filter(|(_, c)| c.collision_groups() != terrain_collision_groups())
        .count();
    assert_eq!(
        robot_colliders,
        1 + 4 * 4,
        "chassis box + hip, thigh, shank, toe per leg"
    );
}

#[test]
fn a_robot_standing_on_soil_sinks_while_its_load_exceeds_the_yield_load_then_stops() {
    let registry = Registry::builtin();
    let mut world = world_on(&registry, "soil:4cm", [0.0, 0.0], 0);
    // The mean sink of the four tiles under the feet, every 0.25 s.
    let mut sinks_m = Vec::new();
    let report = robot::stand::stand_observed(&mut world, 5.0, &mut |world, step| {
        if (step + 1) % 60 == 0 {
            let feet = world.feet_in_world_m();
            let sink = feet
                .iter()
                .map(|f| -world.terrain().surface_height_m(world.physics(), f.x, f.y))
                .sum::<f64>()
                / 4.0;
            sinks_m.push(sink);
        }
    });
    assert!(report.non_foot_contacts.is_empty(), "{report:?}");
    // It goes on sinking past the elastic part (1 cm) while the load is
    // above the hardening yield load...
    let first_second = sinks_m[3];
    assert!(first_second > 0.02, "after 1 s: {sinks_m:?}");
    // ...and stops at the named depth (the robot's weight is the standing load).
    let last = *sinks_m.last().unwrap();
    assert!(
        (last - 0.04).abs() < 0.004,
        "final sink {last}: {sinks_m:?}"
    );
    let last_second = last - sinks_m[sinks_m.len() - 5];
    assert!(
        last_second.abs() < 5e-4,
        "still sinking {last_second} m/s: {sinks_m:?}"
    );
    // Sinking only ever goes one way (within the tiles' elastic wobble).
    for pair in sinks_m.windows(2) {
        assert!(pair[1] > pair[0] - 1e-3, "{sinks_m:?}");
    }
}

/// The robot standing `seconds` on `spec`: its base x every 0.25 s, its
/// final tilt (degrees) and the stand report.
fn stand_tracking_x(spec: &str, seconds: f64) -> (Vec<f64>, f64, robot::stand::StandReport) {
    let registry = Registry::builtin();
    let mut world = world_on(&registry, spec, [0.0, 0.0], 0);
    let mut xs = Vec::new();
    let report = robot::stand::stand_observed(&mut world, seconds, &mut |world, step| {
        if (step + 1) % 60 == 0 {
            xs.push(world.base_pose().translation.vector.x);
        }
    });
    let up = world.base_pose().rotation * nalgebra::Vector3::z();
    let tilt_deg = up.z.clamp(-1.0, 1.0).acos().to_degrees();
    (xs, tilt_deg, report)
}

#[test]
fn the_robot_stands_on_a_ten_degree_slope_and_slides_down_it_at_mu_0_1() {
    let (xs, tilt_deg, report) = stand_tracking_x("slope:10", 4.0);
    assert!(report.non_foot_contacts.is_empty(), "{report:?}");
    // tilted with the ground (within a few degrees of 10), and still
    assert!((tilt_deg - 10.0).abs() < 4.0, "tilt {tilt_deg}: {report:?}");
    let last_two_seconds = xs[xs.len() - 1] - xs[xs.len() - 9];
    assert!(
        last_two_seconds.abs() < 0.005,
        "crept {last_two_seconds} m: {xs:?}"
    );
    // tan 10 deg = 0.18 > 0.1: it slides down (towards -x), and keeps going
    let (xs, _, _) = stand_tracking_x("slope:10:friction=0.1", 4.0);
    let slid = xs[xs.len() - 1] - xs[3];
    assert!(slid < -0.1, "slid {slid} m: {xs:?}");
}

#[test]
fn the_robot_stands_on_steps_and_rough_ground_at_their_height() {
    for spec in ["steps:5cm:1m", "rough:1cm"] {
        let (xs, tilt_deg, report) = stand_tracking_x(spec, 3.0);
        assert!(report.non_foot_contacts.is_empty(), "{spec}: {report:?}");
        assert!(tilt_deg < 5.0, "{spec}: tilt {tilt_deg}");
        assert!((xs[xs.len() - 1] - xs[3]).abs() < 0.01, "{spec}: {xs:?}");
    }
    // one step up: the same stance 5 cm higher
    let registry = Registry::builtin();
    let mut low = world_on(&registry, "steps:5cm:1m", [0.5, 0.0], 0);
    let mut high = world_on(&registry, "steps:5cm:1m", [1.5, 0.0], 0);
    let (a, b) = (robot::stand(&mut low, 2.0), robot::stand(&mut high, 2.0));
    let lift = high.base_pose().translation.z - low.base_pose().translation.z;
    assert!((lift - 0.05).abs() < 0.003, "lift {lift}");
    // and the same height above the ground under it
    assert!(
        (b.base_height_m - a.base_height_m).abs() < 0.003,
        "{a:?} vs {b:?}"
    );
}

#[test]
fn standing_soles_stay_still_and_slide_with_the_robot_on_a_slippery_slope() {
    let registry = Registry::builtin();
    // standing on rigid ground: every touching sole is still (to 2 mm/s)
    let mut world = world_on(&registry, "rigid", [0.0, 0.0], 0);
    robot::stand(&mut world, 2.0);
    let touching = world.ground_contacts().feet;
    assert_eq!(touching, [true; 4]);
    assert_eq!(world.feet_touching_ground(), touching);
    for (leg, v) in world.foot_sole_velocities_m_per_s().iter().enumerate() {
        assert!(v.norm() < 0.002, "leg {leg}: sole at {v:?} m/s");
    }
    // sliding down a 10 degree slope at friction 0.1: the soles slide with
    // the base (to 1 cm/s), at the same speed down the slope
    let mut world = world_on(&registry, "slope:10:friction=0.1", [0.0, 0.0], 0);
    robot::stand(&mut world, 3.0);
    let (base_v, _) = world.base_velocity();
    assert!(base_v.x < -0.1, "slides down: {base_v:?}");
    for (leg, v) in world.foot_sole_velocities_m_per_s().iter().enumerate() {
        let horizontal = (v.x - base_v.x).hypot(v.y - base_v.y);
        assert!(
            horizontal < 0.01,
            "leg {leg}: sole {v:?} against the base's {base_v:?} m/s"
        );
    }
}
