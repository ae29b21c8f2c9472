//! Tests of the registry, the spec grammar and the built-in terrains.

use proptest::prelude::*;
use rapier3d::prelude::*;

use crate::spec::Surface;
use crate::*;

fn parse(s: &str) -> Result<TerrainSpec, SpecError> {
    Registry::builtin().parse(s)
}

#[test]
fn builtin_specs_parse_to_si_values() {
    let spec = parse("elastic:5cm").unwrap();
    assert_eq!(spec.plugin(), "elastic");
    assert_eq!(spec.depth_range_m("depth"), (0.05, 0.05));
    assert_eq!(spec.length_m("tile"), 0.2);
    assert_eq!(parse("elastic:50mm").unwrap(), spec);
    assert_eq!(parse("elastic:0.05m").unwrap(), spec);

    let varying = parse("varying:2m:2,3,4,5cm,rigid").unwrap();
    assert_eq!(varying.length_m("every"), 2.0);
    assert_eq!(
        varying.surfaces("surfaces"),
        &[
            Surface::elastic(0.02),
            Surface::elastic(0.03),
            Surface::elastic(0.04),
            Surface::elastic(0.05),
            Surface::rigid()
        ]
    );
    let named = parse("elastic:3cm:travel=12cm:length=30m").unwrap();
    assert_eq!(named.length_m("travel"), 0.12);
    assert_eq!(named.length_m("length"), 30.0);
    assert_eq!(parse("rigid").unwrap().plugin(), "rigid");
}

#[test]
fn display_is_canonical_and_round_trips() {
    for (input, canonical) in [
        ("elastic:50mm", "elastic:5cm"),
        ("rigid", "rigid"),
        (
            "varying:200cm:2,3,4,5cm,rigid",
            "varying:2m:2cm,3cm,4cm,5cm,rigid",
        ),
        (
            "elastic:5cm:tile=20cm:travel=12cm",
            "elastic:5cm:travel=12cm",
        ),
        ("elastic:2..5cm", "elastic:2cm..5cm"),
        (
            "elastic:20mm..0.05m:friction=0.5",
            "elastic:2cm..5cm:friction=0.5",
        ),
        ("varying:2m:2..5cm,rigid", "varying:2m:2cm..5cm,rigid"),
        ("rigid:friction=1", "rigid"),
        ("rigid:friction=0.1", "rigid:friction=0.1"),
        ("soil:4cm", "soil:4cm"),
        (
            "varying:2m:5cm,(soil:4cm),(rigid:friction=0.1)",
            "varying:2m:5cm,(soil:4cm),(rigid:friction=0.1)",
        ),
        ("varying:2m:(elastic:5cm),(rigid)", "varying:2m:5cm,rigid"),
        (
            "varying:2m:(slope:10.0),(steps:50mm:0.3m),(slope:5:friction=0.5)",
            "varying:2m:(slope:10),(steps:5cm:30cm),(slope:5:friction=0.5)",
        ),
        (
            "varying:2m:(rough:10mm),(rough:2cm:cell=5cm),5cm",
            "varying:2m:(rough:1cm),(rough:2cm:cell=5cm),5cm",
        ),
        (
            "varying:2m:(elastic:2..5cm:friction=0.4),(soil:3cm:elastic=5mm:recovery=4)",
            "varying:2m:(elastic:2cm..5cm:friction=0.4),(soil:3cm:elastic=5mm:recovery=4)",
        ),
        (
            "varying:2m:(elastic:50mm:friction=1),rigid:travel=20cm",
            "varying:2m:5cm,rigid:travel=20cm",
        ),
        (
            "soil:4cm:elastic=5mm:yield=0.3:recovery=2",
            "soil:4cm:elastic=5mm:yield=0.3:recovery=2",
        ),
        ("elastic:5cm:slope=10.0", "elastic:5cm:slope=10"),
        (
            "varying:4m:5cm,(elastic:50mm:slope=5:friction=0.5),(soil:4cm:slope=10)",
            "varying:4m:5cm,(elastic:5cm:friction=0.5:slope=5),(soil:4cm:slope=10)",
        ),
        (
            "varying:2m:(elastic:5cm:slope=0),rigid",
            "varying:2m:5cm,rigid",
        ),
    ] {
        let spec = parse(input).unwrap();
        assert_eq!(spec.to_string(), canonical);
        assert_eq!(parse(&spec.to_string()).unwrap(), spec);
    }
}

#[test]
fn table_form_shares_the_validation() {
    let registry = Registry::builtin();
    let entries = vec![
        ("depth".to_string(), "5cm".to_string()),
        ("travel".to_string(), "12cm".to_string()),
    ];
    let spec = registry
        .parse_table("[terrain]", "elastic", &entries)
        .unwrap();
    assert_eq!(spec, parse("elastic:5cm:travel=12cm").unwrap());
    let bad = vec![("depth".to_string(), "20cm".to_string())];
    let err = registry
        .parse_table("[terrain]", "elastic", &bad)
        .unwrap_err();
    assert!(err.to_string().contains("beyond the tile travel"), "{err}");
    let missing = registry
        .parse_table("[terrain]", "elastic", &[])
        .unwrap_err();
    assert!(matches!(missing, SpecError::Arity { .. }), "{missing}");
}

#[test]
fn errors_keep_the_input_and_say_what_is_wrong() {
    let cases: &[(&str, &str)] = &[
        ("", "empty"),
        (
            "sand:5cm",
            "unknown terrain \"sand\" (known terrains: rigid, elastic, varying, soil, switch, slope, steps, rough)",
        ),
        ("elastic", "takes 1 positional argument(s), got 0"),
        ("elastic:5cm:3cm", "takes 1 positional argument(s), got 2"),
        ("rigid:5cm", "takes 0 positional argument(s), got 1"),
        ("elastic:5", "has no unit"),
        ("elastic:5xm", "unknown unit \"xm\""),
        ("elastic:abc", "no number"),
        ("elastic:0cm", "greater than zero"),
        ("elastic:-2cm", "greater than zero"),
        ("elastic:NaNcm", "no number"),
        ("elastic:1e400cm", "not a finite number"),
        ("varying:2m:", "the list is empty"),
        ("varying:2m:2,,3cm", "is empty"),
        ("varying:2m:2,3", "no unit"),
        ("elastic:20cm", "beyond the tile travel 15cm"),
        ("varying:2m:2cm,rigid,30cm", "beyond the tile travel"),
        ("elastic:5cm:foo=1", "has no parameter \"foo\""),
        ("elastic:5cm:travel=1cm:travel=2cm", "twice"),
        ("elastic:5cm:damping=-1", "must not be negative"),
        ("elastic:5cm:gap=30cm", "gap 30cm must be smaller"),
        ("varying:5cm:2cm", "shorter than one tile"),
        ("elastic:5..2cm", "to a larger one"),
        ("elastic:0..2cm", "to a larger one"),
        ("elastic:2..5", "no unit"),
        ("elastic:2..30cm", "beyond the tile travel"),
        ("varying:2m:2cm,3..1cm", "to a larger one"),
        ("rigid:friction=-0.1", "must not be negative"),
        ("elastic:5cm:friction=abc", "not a number"),
        ("soil:4cm:elastic=4cm", "must be less than depth"),
        ("soil:4cm:yield=1", "strictly between 0 and 1"),
        ("soil:4cm:yield=0", "strictly between 0 and 1"),
        ("soil:20cm", "beyond the tile travel"),
        ("soil:4cm:recovery=-1", "must not be negative"),
        ("soil", "takes 1 positional argument"),
        (
            "varying:2m:(soil:4cm:tile=10cm)",
            "belongs to the whole terrain",
        ),
        (
            "varying:2m:(varying:1m:2cm)",
            "a region is rigid, elastic, soil or rough ground, a slope or steps, not \"varying\"",
        ),
        ("varying:2m:5cm,(slope:50)", "too steep"),
        (
            "varying:2m:5cm,(steps:5cm:1m)",
            "no room for a step in regions of 2m",
        ),
        (
            "varying:2m:(steps:5cm:30cm:extent=4m)",
            "belongs to the whole terrain",
        ),
        (
            "varying:2m:(slope:10:width=2m)",
            "belongs to the whole terrain",
        ),
        (
            "varying:2m:(rough:1cm:length=4m)",
            "belongs to the whole terrain",
        ),
        ("varying:2m:(soil:4cm", "unbalanced parentheses"),
        ("varying:2m:5cm,(soil:30cm)", "beyond the tile travel"),
        ("varying:2m:(rigid:friction=-1)", "must not be negative"),
        ("slope:50", "too steep"),
        ("elastic:5cm:slope=45", "too steep for tiles (below 45)"),
        (
            "varying:4m:5cm,(elastic:5cm:slope=60)",
            "too steep for tiles",
        ),
        ("switch:2cm:5cm", "takes 3 positional argument"),
        ("slope:-5", "must not be negative"),
        ("steps:40cm:1m", "at most 30cm"),
        ("steps:5cm:5cm", "shorter than 10cm"),
        ("steps:5cm", "takes 2 positional argument"),
        ("rough:20cm", "at most 15cm"),
        ("rough:2cm:cell=1mm", "more than 500000"),
    ];
    for (input, expected) in cases {
        let err = parse(input).expect_err(input).to_string();
        assert!(
            err.contains(expected),
            "{input:?} gave {err:?}, expected it to mention {expected:?}"
        );
        assert!(
            err.contains(&format!("{input:?}")),
            "{err:?} does not quote the input {input:?}"
        );
    }
}

#[test]
fn registry_refuses_duplicate_and_bad_names() {
    struct Named(&'static str);
    impl TerrainPlugin for Named {
        fn name(&self) -> &'static str {
            self.0
        }
        fn summary(&self) -> &'static str {
            "test"
        }
        fn params(&self) -> Vec<ParamDecl> {
            Vec::new()
        }
        fn create(&self, spec: &TerrainSpec, ctx: &BuildContext) -> Box<dyn Terrain> {
            crate::rigid::RigidPlugin.create(spec, ctx)
        }
    }
    let mut registry = Registry::builtin();
    assert_eq!(
        registry.register(Box::new(Named("elastic"))),
        Err(RegistryError::Duplicate("elastic".to_string()))
    );
    assert!(matches!(
        registry.register(Box::new(Named("Bad Name"))),
        Err(RegistryError::BadName(_))
    ));
    registry.register(Box::new(Named("flat"))).unwrap();
    assert_eq!(registry.parse("flat").unwrap().plugin(), "flat");
}

proptest! {
    #[test]
    fn no_input_makes_the_parser_panic(input in any::<String>()) {
        let _ = parse(&input);
    }

    #[test]
    fn spec_like_input_never_panics(input in "[a-z0-9.,:=+-]{0,40}") {
        let _ = parse(&input);
    }

    #[test]
    fn valid_specs_round_trip(
        depth_mm in 1u32..150,
        every_dm in 2u32..200,
        picks in prop::collection::vec(prop_oneof![Just(None), (1u32..150).prop_map(Some)], 1..6),
        travel_mm in prop::option::of(150u32..400),
    ) {
        let travel = travel_mm.map(|t| format!(":travel={t}mm")).unwrap_or_default();
        let elastic = parse(&format!("elastic:{depth_mm}mm{travel}")).unwrap();
        prop_assert_eq!(parse(&elastic.to_string()).unwrap(), elastic.clone());

        let list: Vec<String> = picks.iter().map(|p| p.map_or("rigid".to_string(), |mm| format!("{mm}mm"))).collect();
        let varying = parse(&format!("varying:{every_dm}dm:{}", list.join(",")).replace("dm", "0cm")).unwrap();
        prop_assert_eq!(parse(&varying.to_string()).unwrap(), varying);
    }
}

/// The tile whose centre is at the origin.
fn centre_tile(world: &PhysicsWorld) -> RigidBodyHandle {
    world
        .bodies
        .iter()
        .find(|(_, b)| {
            b.is_dynamic() && b.translation().x.abs() < 0.01 && b.translation().y.abs() < 0.01
        })
        .expect("a tile is centred on the origin")
        .0
}

fn world_with(spec: &str, seed: u64) -> (PhysicsWorld, Box<dyn Terrain>) {
    let ctx = BuildContext {
        seed,
        ..BuildContext::default()
    };
    let mut terrain = Registry::builtin().create(spec, &ctx).unwrap();
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::new(0.0, 0.0, -9.81);
    world.integration_parameters.dt = 1.0 / 240.0;
    terrain.build(&mut world);
    (world, terrain)
}

#[test]
fn stiffness_follows_the_papers_definition() {
    let ctx = BuildContext::default();
    let terrain = Registry::builtin().create("elastic:5cm", &ctx).unwrap();
    let k = terrain.regions()[0].stiffness_n_per_m.unwrap();
    // k = m g / (4 d): the four loaded springs carry the robot's weight.
    assert!((k - 25.567 * 9.81 / 0.2).abs() < 1e-9);
    assert_eq!(terrain.regions()[0].expected_sink_m, 0.05);
}

#[test]
fn a_tile_pressed_and_released_returns_to_rest_within_a_second() {
    let (mut world, terrain) = world_with("elastic:5cm", 0);
    let mut tiles = Vec::new();
    terrain.tiles_in(&world, Rect::around([0.0, 0.0], 0.05), &mut tiles);
    assert_eq!(tiles.len(), 1);
    let handle = centre_tile(&world);

    // Press with a quarter of the robot's weight: it sinks the nominal depth.
    let press_n = 25.567 * 9.81 / 4.0;
    world.bodies[handle].add_force(Vector::new(0.0, 0.0, -press_n as f32), true);
    for _ in 0..480 {
        world.step();
    }
    let pressed = -terrain.surface_height_m(&world, 0.0, 0.0);
    assert!((pressed - 0.05).abs() < 0.002, "pressed sink {pressed}");

    world.bodies[handle].reset_forces(true);
    let mut back_after_secs = None;
    for step in 1..=480 {
        world.step();
        let sink = -terrain.surface_height_m(&world, 0.0, 0.0);
        if sink.abs() <= 0.001 && back_after_secs.is_none() {
            back_after_secs = Some(step as f64 / 240.0);
        }
        if sink.abs() > 0.001 {
            back_after_secs = None; // must stay within 1 mm
        }
    }
    let secs = back_after_secs.expect("the tile never settled within 1 mm of rest");
    assert!(secs < 1.0, "tile took {secs} s to return");
}

#[test]
fn a_tile_pushed_off_centre_and_sideways_moves_only_along_z() {
    // The tile's body is guided, not its joint: a load off the tile's
    // centre and a sideways push (a stance foot's friction) neither tilt
    // nor slide it at all (a prismatic joint's locked rows held the same
    // load to ~3e-9 m and rad, the solver's error), and it still sinks its
    // depth under a quarter of the robot's weight.
    let (mut world, mut terrain) = world_with("elastic:5cm", 0);
    let handle = centre_tile(&world);
    let rest = world.bodies[handle].translation();
    let corner = rest + Vector::new(0.08, -0.08, 0.0);
    for _ in 0..480 {
        let body = &mut world.bodies[handle];
        body.reset_forces(true);
        body.reset_torques(true);
        body.add_force_at_point(
            Vector::new(60.0, -40.0, -STANDING_LOAD_N as f32),
            corner,
            true,
        );
        step(&mut world, &mut terrain);
    }
    let body = &world.bodies[handle];
    let moved = body.translation() - rest;
    assert!(moved.x == 0.0 && moved.y == 0.0, "slid {moved:?}");
    let tilt_rad = body.rotation().angle_between(Rotation::IDENTITY);
    assert!(tilt_rad == 0.0, "tilted {tilt_rad} rad");
    let sink = -terrain.surface_height_m(&world, 0.0, 0.0);
    assert!(
        (sink - 0.05).abs() < 0.002,
        "sink {sink} m under a quarter of the weight"
    );
}

/// One step as the robot's world takes it: the terrain's hooks around
/// rapier's step.
fn step(world: &mut PhysicsWorld, terrain: &mut Box<dyn Terrain>) {
    terrain.before_step(world, 1.0 / 240.0);
    world.step();
    terrain.after_step(world, 1.0 / 240.0);
}

#[test]
fn a_new_fields_tiles_sleep_from_its_second_step_and_still_carry_load() {
    let awake = |world: &PhysicsWorld| {
        world
            .bodies
            .iter()
            .filter(|(_, b)| b.is_dynamic() && !b.is_sleeping())
            .count()
    };
    // rapier's first step wakes every body (its islands are built then)
    let (mut bare, _) = world_with("elastic:5cm", 0);
    bare.step();
    assert_eq!(
        awake(&bare),
        3000,
        "rapier woke the tiles: the hook has work"
    );
    let (mut world, mut terrain) = world_with("elastic:5cm", 0);
    step(&mut world, &mut terrain);
    step(&mut world, &mut terrain);
    assert_eq!(
        awake(&world),
        0,
        "untouched tiles are asleep after two steps"
    );
    // A tile put to sleep this way still hangs on its spring: pressed with
    // a quarter of the robot's weight it sinks the nominal depth.
    let handle = centre_tile(&world);
    let press_n = 25.567 * 9.81 / 4.0;
    world.bodies[handle].add_force(Vector::new(0.0, 0.0, -press_n as f32), true);
    for _ in 0..480 {
        step(&mut world, &mut terrain);
    }
    let pressed = -terrain.surface_height_m(&world, 0.0, 0.0);
    assert!((pressed - 0.05).abs() < 0.002, "pressed sink {pressed}");
}

#[test]
fn a_tile_reset_while_loaded_rests_and_still_carries_load() {
    // `reset` puts a pressed (awake) tile back at rest and to sleep; pressed
    // again, it must still hang on its spring.
    let (mut world, mut terrain) = world_with("elastic:5cm", 0);
    let handle = centre_tile(&world);
    let press_n = 25.567 * 9.81 / 4.0;
    for round in 0..2 {
        world.bodies[handle].add_force(Vector::new(0.0, 0.0, -press_n as f32), true);
        for _ in 0..480 {
            step(&mut world, &mut terrain);
        }
        let pressed = -terrain.surface_height_m(&world, 0.0, 0.0);
        assert!(
            (pressed - 0.05).abs() < 0.002,
            "round {round}: pressed sink {pressed}"
        );
        world.bodies[handle].reset_forces(true);
        terrain.reset(&mut world);
        assert!(terrain.surface_height_m(&world, 0.0, 0.0).abs() < 1e-6);
        assert!(world.bodies[handle].is_sleeping());
    }
}

#[test]
fn switch_tiles_take_the_new_spring_at_their_time_and_the_old_one_after_a_reset() {
    // 2 cm tiles that switch to the spring of 5 cm after 1 s: a tile under a
    // quarter of the standing robot sinks 2 cm, then 5 cm; a reset brings
    // the 2 cm spring back, every round.
    let (mut world, mut terrain) = world_with("switch:2cm:5cm:1", 0);
    assert_eq!(terrain.spec().to_string(), "switch:2cm:5cm:1");
    let (k2, k5) = (
        STANDING_LOAD_N / 0.02,
        terrain.regions()[0].stiffness_n_per_m.unwrap() * 0.02 / 0.05,
    );
    assert!((terrain.regions()[0].stiffness_n_per_m.unwrap() - k2).abs() < 1e-9 * k2);
    assert!(
        terrain
            .details()
            .iter()
            .any(|l| l.contains("5cm") && l.contains(&format!("{k5:.1}"))),
        "{:?}",
        terrain.details()
    );
    for round in 0..2 {
        // 0.83 s: before the switch
        let before = press(&mut world, &mut terrain, STANDING_LOAD_N, 200);
        assert!((before - 0.02).abs() < 0.001, "round {round}: {before}");
        // 1.83 s: after it (damping ratio 0.5 settles within 0.6 s)
        let after = press(&mut world, &mut terrain, STANDING_LOAD_N, 240);
        assert!((after - 0.05).abs() < 0.002, "round {round}: {after}");
        // an unloaded tile stays at rest through the switch
        assert!(terrain.surface_height_m(&world, 1.0, 0.0).abs() < 1e-6);
        let handle = centre_tile(&world);
        world.bodies[handle].reset_forces(true);
        terrain.reset(&mut world);
        assert!(terrain.surface_height_m(&world, 0.0, 0.0).abs() < 1e-6);
    }
    for (spec, expected) in [
        (
            "switch:2cm:5cm:0",
            "at = 0 must be a positive number of seconds",
        ),
        (
            "switch:2cm:20cm:3",
            "depth 20cm is beyond the tile travel 15cm",
        ),
    ] {
        let err = Registry::builtin()
            .create(spec, &BuildContext::default())
            .err()
            .expect("refused")
            .to_string();
        assert!(err.contains(expected), "{spec}: {err}");
    }
}

#[test]
fn idle_tiles_sleep_and_rest_at_the_surface() {
    let (mut world, terrain) = world_with("elastic:5cm", 0);
    for _ in 0..240 {
        world.step();
    }
    let awake = world
        .bodies
        .iter()
        .filter(|(_, b)| b.is_dynamic() && !b.is_sleeping())
        .count();
    assert_eq!(awake, 0, "untouched tiles must stay asleep");
    // the default 40 m field: 200 columns of 15 tiles
    assert_eq!(terrain.tile_count(), 200 * 15);
    for (x, y) in [(0.0, 0.0), (5.1, 0.4), (-1.0, 1.2)] {
        assert!(terrain.surface_height_m(&world, x, y).abs() < 1e-6);
    }
    // Off the field: the fixed base below.
    assert!((terrain.surface_height_m(&world, 0.0, 5.0) + 0.2).abs() < 1e-9);
}

#[test]
fn varying_regions_follow_the_seed_and_start_with_the_first_surface() {
    let (world, terrain) = world_with("varying:2m:2,3,4,5cm,rigid", 7);
    let regions = terrain.regions();
    assert_eq!(regions[0].label, "elastic:2cm");
    assert!(regions.len() >= 9, "{} regions", regions.len());
    // Region boundaries every 2 m (between tile columns) and lookups agree.
    for r in &regions[1..] {
        assert!((r.x_range_m.1 - r.x_range_m.0 - 2.0).abs() < 1e-9 || r.index == regions.len() - 1);
        let mid = (r.x_range_m.0 + r.x_range_m.1) / 2.0;
        assert_eq!(terrain.region_index_at(mid, 0.0), r.index);
    }
    // Same seed, same draw; another seed, another draw somewhere.
    let (_, again) = world_with("varying:2m:2,3,4,5cm,rigid", 7);
    assert_eq!(again.regions(), regions);
    let (_, other) = world_with("varying:2m:2,3,4,5cm,rigid", 8);
    assert_ne!(other.regions(), regions);
    // Rigid regions have no tiles and a surface at z = 0.
    let mut tiles = Vec::new();
    terrain.tiles_in(&world, terrain.extent(), &mut tiles);
    assert_eq!(tiles.len(), 200 * 15);
    let rigid_cells = tiles
        .iter()
        .filter(|t| regions[t.region].stiffness_n_per_m.is_none())
        .count();
    assert_eq!(terrain.tile_count(), 200 * 15 - rigid_cells);
}

/// Presses the tile centred on the origin with `load_n` for `steps`, each
/// step with the terrain's hooks; returns its sink.
fn press(
    world: &mut PhysicsWorld,
    terrain: &mut Box<dyn Terrain>,
    load_n: f64,
    steps: usize,
) -> f64 {
    let handle = centre_tile(world);
    world.bodies[handle].reset_forces(true);
    world.bodies[handle].add_force(Vector::new(0.0, 0.0, -load_n as f32), true);
    for _ in 0..steps {
        step(world, terrain);
    }
    -terrain.surface_height_m(world, 0.0, 0.0)
}

/// A quarter of the standing robot's weight, N.
const STANDING_LOAD_N: f64 = 25.567 * 9.81 / 4.0;

fn soil_model(spec: &str) -> crate::soil::SoilModel {
    crate::soil::SoilParams::from_spec(&parse(spec).unwrap()).model(&BuildContext::default())
}

#[test]
fn soil_follows_its_load_sink_curve_within_five_percent() {
    let spec = "soil:4cm:elastic=1cm:yield=0.5";
    let model = soil_model(spec);
    let (mut world, mut terrain) = world_with(spec, 0);
    // Quasi-static loading of a fresh tile: 0.15, 0.3, ... 1.5 x the standing load.
    for k in 1..=10 {
        let load_n = STANDING_LOAD_N * 0.15 * k as f64;
        let sink_m = press(&mut world, &mut terrain, load_n, 360);
        let expected_m = model.loading_sink_m(load_n);
        assert!(
            (sink_m - expected_m).abs() <= 0.05 * expected_m,
            "load {load_n:.1} N: sink {sink_m} m, curve {expected_m} m"
        );
    }
    // The standing load itself sinks a fresh tile the named depth.
    assert!((model.loading_sink_m(STANDING_LOAD_N) - 0.04).abs() < 1e-12);
}

#[test]
fn a_soil_tile_loaded_and_unloaded_stays_down_by_its_permanent_sink() {
    let spec = "soil:4cm";
    let model = soil_model(spec);
    let (mut world, mut terrain) = world_with(spec, 0);
    let loaded_m = press(&mut world, &mut terrain, STANDING_LOAD_N, 480);
    assert!((loaded_m - 0.04).abs() < 0.002, "loaded sink {loaded_m}");
    let unloaded_m = press(&mut world, &mut terrain, 0.0, 480);
    let permanent_m = model.permanent_sink_m(STANDING_LOAD_N);
    assert!((permanent_m - 0.03).abs() < 1e-12);
    assert!(
        (unloaded_m - permanent_m).abs() <= 0.05 * permanent_m,
        "unloaded sink {unloaded_m}, model {permanent_m}"
    );
    // It stays there asleep, and reloading to the same load only takes the
    // elastic part back.
    let later_m = press(&mut world, &mut terrain, 0.0, 480);
    assert!(
        (later_m - unloaded_m).abs() < 2e-4,
        "{later_m} vs {unloaded_m}"
    );
    assert!(world.bodies[centre_tile(&world)].is_sleeping());
    let reloaded_m = press(&mut world, &mut terrain, STANDING_LOAD_N, 480);
    assert!((reloaded_m - 0.04).abs() < 0.002, "reloaded {reloaded_m}");
    // Between episodes the tile is put back fresh.
    press(&mut world, &mut terrain, 0.0, 1);
    terrain.reset(&mut world);
    assert!(terrain.surface_height_m(&world, 0.0, 0.0).abs() < 1e-6);
    let fresh_m = press(&mut world, &mut terrain, 0.5 * STANDING_LOAD_N, 480);
    assert!(
        (fresh_m - model.loading_sink_m(0.5 * STANDING_LOAD_N)).abs() < 5e-4,
        "after reset {fresh_m}"
    );
}

#[test]
fn a_soil_tile_with_recovery_rises_back_with_its_time_constant() {
    let (mut world, mut terrain) = world_with("soil:4cm:recovery=1", 0);
    press(&mut world, &mut terrain, STANDING_LOAD_N, 480);
    let released_m = press(&mut world, &mut terrain, 0.0, 24);
    assert!(released_m > 0.02, "released {released_m}");
    // After 3 more seconds, e^-3 of the permanent sink is left (give or take
    // the tile's own lag behind its spring's rest point).
    let later_m = press(&mut world, &mut terrain, 0.0, 720);
    assert!(later_m < 0.003, "after 3 s: {later_m}");
    let rested_m = press(&mut world, &mut terrain, 0.0, 1440);
    assert!(rested_m < 2e-4, "after 9 s: {rested_m}");
}

#[test]
fn per_tile_depths_cover_their_range_reproducibly_and_each_tile_sinks_its_own() {
    use crate::tiles::{RegionLayout, TileParams, TiledTerrain};
    let field = |seed: u64| {
        let spec = parse("elastic:2..5cm:length=20m").unwrap();
        let ctx = BuildContext {
            seed,
            ..BuildContext::default()
        };
        let layout = RegionLayout::Uniform(Surface::from_depth_range(0.02, 0.05));
        TiledTerrain::new(spec.clone(), TileParams::from_spec(&spec), layout, &ctx)
    };
    let depths = |t: &TiledTerrain| -> Vec<f64> {
        t.cell_springs()
            .iter()
            .flatten()
            .map(|s| s.depth_m)
            .collect()
    };
    let a = depths(&field(3));
    assert_eq!(a.len(), 1500);
    let (min, max) = a
        .iter()
        .fold((f64::MAX, f64::MIN), |(lo, hi), &d| (lo.min(d), hi.max(d)));
    assert!(
        (0.02..0.0205).contains(&min) && (0.0495..=0.05).contains(&max),
        "{min}..{max}"
    );
    let mean = a.iter().sum::<f64>() / a.len() as f64;
    assert!((mean - 0.035).abs() < 0.001, "mean {mean}");
    // a quarter of the draws in each quarter of the range, give or take
    for q in 0..4 {
        let lo = 0.02 + 0.0075 * q as f64;
        let n = a.iter().filter(|&&d| d >= lo && d < lo + 0.0075).count();
        assert!((300..=450).contains(&n), "quarter {q}: {n}");
    }
    assert_eq!(depths(&field(3)), a, "same seed, same depths");
    assert_ne!(depths(&field(4)), a, "another seed, other depths");
    for s in field(3).cell_springs().iter().flatten() {
        assert!((s.stiffness_n_per_m - STANDING_LOAD_N / s.depth_m).abs() < 1e-6);
    }
    // Built from the registry with seed 3, the centre tile sinks its own depth.
    let (mut world, mut terrain) = world_with("elastic:2..5cm", 3);
    let built = field(3);
    // the cell at the origin: its column from the field's first centre, the middle of 15 rows
    let first_x_m = built.extent().min_m[0] + 0.1;
    let (ix, iy) = ((-first_x_m / 0.2).round() as usize, 7);
    let own_m = built.cell_springs()[ix * 15 + iy].unwrap().depth_m;
    let sink_m = press(&mut world, &mut terrain, STANDING_LOAD_N, 480);
    assert!(
        (sink_m - own_m).abs() < 0.002,
        "sink {sink_m}, drawn {own_m}"
    );
}

/// A 2 kg box on the ground at the origin, pushed along x by `push` x its
/// weight for 0.3 s (so that on tiles it stays on the tile it sank): how
/// far it moved, m.
fn box_slide_m(spec: &str, push: f64) -> f64 {
    let (mut world, mut terrain) = world_with(spec, 0);
    let mass_kg = 2.0;
    let body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(0.0, 0.0, 0.05))
            .lock_rotations(),
    );
    let cube = ColliderBuilder::cuboid(0.05, 0.05, 0.05)
        .mass(mass_kg)
        .friction(1.0)
        .collision_groups(robot_collision_groups());
    world.insert_collider(cube, Some(body));
    for _ in 0..240 {
        step(&mut world, &mut terrain);
    }
    let start = world.bodies[body].translation().x;
    let push_n = push * f64::from(mass_kg) * 9.81;
    world.bodies[body].add_force(Vector::new(push_n as f32, 0.0, 0.0), true);
    for _ in 0..72 {
        step(&mut world, &mut terrain);
    }
    f64::from(world.bodies[body].translation().x - start)
}

#[test]
fn friction_is_the_contacts_coefficient_on_rigid_ground_and_tiles() {
    // (push - mu) g t^2 / 2 for t = 0.3 s
    let expected_m = 0.5 * 0.1 * 9.81 * 0.09;
    for spec in ["rigid:friction=0.3", "elastic:5cm:friction=0.3"] {
        let held = box_slide_m(spec, 0.2);
        let slid = box_slide_m(spec, 0.4);
        assert!(
            held.abs() < 1e-3,
            "{spec}: pushed at 0.2 m g it moved {held} m"
        );
        assert!(
            (slid - expected_m).abs() < 0.25 * expected_m,
            "{spec}: at 0.4 m g it slid {slid} m, expected {expected_m} m"
        );
    }
    // the default (1.0) holds the same push
    assert!(box_slide_m("rigid", 0.4).abs() < 1e-3);
    assert!(box_slide_m("elastic:5cm", 0.4).abs() < 1e-3);
}

#[test]
fn varying_regions_take_any_surface_spec_with_its_own_friction() {
    let spec = parse("varying:2m:(rigid:friction=0.3),(soil:4cm),5cm:friction=0.8").unwrap();
    let (mut world, mut terrain) = world_with(&spec.to_string(), 0);
    let labels: Vec<&str> = terrain.regions().iter().map(|r| r.label.as_str()).collect();
    assert_eq!(labels[0], "rigid:friction=0.3");
    for label in &labels[1..] {
        assert!(
            ["rigid:friction=0.3", "soil:4cm", "elastic:5cm"].contains(label),
            "{labels:?}"
        );
    }
    // The start region is its own slippery ground: a box slides there as on
    // rigid:friction=0.3.
    let slid = box_slide_m(&spec.to_string(), 0.4);
    let expected_m = 0.5 * 0.1 * 9.81 * 0.09;
    assert!(
        (slid - expected_m).abs() < 0.25 * expected_m,
        "slid {slid} m"
    );
    // A soil region's tiles stay down once loaded.
    let soil = terrain
        .regions()
        .iter()
        .find(|r| r.label == "soil:4cm")
        .expect("seed 0 draws a soil region");
    let x = (soil.x_range_m.0 + soil.x_range_m.1) / 2.0;
    let mut tiles = Vec::new();
    terrain.tiles_in(&world, Rect::around([x, 0.0], 0.11), &mut tiles);
    let tile = tiles[0];
    let (handle, _) = world
        .bodies
        .iter()
        .find(|(_, b)| {
            b.is_dynamic()
                && (f64::from(b.translation().x) - tile.center_m[0]).abs() < 0.01
                && (f64::from(b.translation().y) - tile.center_m[1]).abs() < 0.01
        })
        .unwrap();
    world.bodies[handle].add_force(Vector::new(0.0, 0.0, -STANDING_LOAD_N as f32), true);
    for _ in 0..480 {
        step(&mut world, &mut terrain);
    }
    world.bodies[handle].reset_forces(true);
    for _ in 0..480 {
        step(&mut world, &mut terrain);
    }
    let sink_m = -terrain.surface_height_m(&world, tile.center_m[0], tile.center_m[1]);
    assert!((sink_m - 0.03).abs() < 0.0015, "permanent sink {sink_m}");
}

/// Where a 1 cm ball dropped at (x, y) comes to rest: the height of its
/// lowest point, m.
fn ball_rest_m(spec: &str, seed: u64, x: f64, y: f64) -> f64 {
    let (mut world, mut terrain) = world_with(spec, seed);
    let top = terrain.surface_height_m(&world, x, y) + 0.03;
    let body = world.insert_body(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(x as f32, y as f32, top as f32))
            .lock_rotations()
            .enabled_translations(false, false, true),
    );
    let ball = ColliderBuilder::ball(0.01)
        .mass(0.1)
        .collision_groups(robot_collision_groups());
    world.insert_collider(ball, Some(body));
    for _ in 0..240 {
        step(&mut world, &mut terrain);
    }
    f64::from(world.bodies[body].translation().z) - 0.01
}

#[test]
fn relief_surfaces_are_where_their_colliders_are() {
    for (spec, points) in [
        (
            "varying:2m:(rough:2cm),rigid",
            vec![(0.0, 0.0), (0.33, 0.41), (1.27, -0.88), (-1.23, 1.1)],
        ),
        (
            "slope:10",
            vec![(0.0, 0.0), (1.0, 0.3), (-1.5, -0.5), (7.3, 1.0)],
        ),
        (
            "steps:5cm:1m",
            vec![(-1.0, 0.0), (0.5, 0.0), (1.5, 0.2), (4.7, -1.0)],
        ),
        (
            "rough:2cm",
            vec![(0.0, 0.0), (0.33, 0.41), (2.71, -0.88), (-1.23, 1.1)],
        ),
        (
            // hills: [-2, 2] (apex at 0), [2, 4] (apex at 3), ...
            "varying:2m:(slope:10)",
            vec![(0.0, 0.0), (1.0, 0.3), (2.5, -0.4), (3.0, 1.0), (3.6, -1.0)],
        ),
        (
            // stairs of 30 cm runs in [2, 4]: 5 cm at 2.3, 10 at 2.6, 15 over [2.9, 3.1]
            "varying:2m:(steps:5cm:30cm)",
            vec![
                (2.1, 0.0),
                (2.45, 0.3),
                (2.75, -1.0),
                (3.0, -0.5),
                (3.55, 1.0),
                (3.95, 0.2),
            ],
        ),
    ] {
        let (world, terrain) = world_with(spec, 5);
        for (x, y) in points {
            let h = terrain.surface_height_m(&world, x, y);
            let rest = ball_rest_m(spec, 5, x, y);
            // a ball on a tilted face touches it off-centre: 1 cm x (1/cos - 1)
            assert!(
                (rest - h).abs() < 1.5e-3,
                "{spec} at ({x}, {y}): surface {h}, ball rests at {rest}"
            );
        }
    }
    let (world, slope) = world_with("slope:10", 0);
    assert!((slope.surface_height_m(&world, 1.0, 0.0) - 10f64.to_radians().tan()).abs() < 1e-12);
    let (world, steps) = world_with("steps:5cm:1m", 0);
    assert_eq!(steps.surface_height_m(&world, 2.5, 0.0), 0.1);
    assert_eq!(steps.surface_height_m(&world, -0.5, 0.0), 0.0);
}

#[test]
fn tiles_on_a_hill_are_where_the_surface_says_and_meet_at_their_edges() {
    // 4 m regions: a hill of tiles in [3.9, 7.9], crest at 5.9 (a cell edge)
    let spec = "varying:4m:5cm,(elastic:5cm:slope=10)";
    let (world, terrain) = world_with(spec, 1);
    assert_eq!(terrain.regions()[1].label, "elastic:5cm:slope=10");
    let tan = 10f64.to_radians().tan();
    let (x0, x1) = terrain.regions()[1].x_range_m;
    let hill = |x: f64| tan * (x - x0).min(x1 - x);
    // on the hill's sides the tops are the hill itself
    for x in [4.3, 5.0, 5.65, 6.5, 7.42] {
        let h = terrain.surface_height_m(&world, x, 0.3);
        // (bodies are single precision: a tile at rest is within 1e-6 m)
        assert!(
            (h - hill(x)).abs() < 1e-6,
            "x {x}: surface {h}, hill {}",
            hill(x)
        );
        assert!((terrain.rest_height_m(x, 0.3) - hill(x)).abs() < 1e-12);
    }
    // neighbouring tiles' tops meet at their cells' edges (just either side)
    for edge in [4.5, 5.9, 7.1] {
        let (a, b) = (
            terrain.surface_height_m(&world, edge - 1e-6, 0.0),
            terrain.surface_height_m(&world, edge + 1e-6, 0.0),
        );
        assert!((a - b).abs() < 1e-5, "edge {edge}: {a} and {b}");
    }
    // a ball resting on a tile of the hill (it presses 0.8 mm) is there
    for (x, y) in [(4.6, 0.2), (5.0, -0.4), (6.8, 1.0)] {
        let h = terrain.surface_height_m(&world, x, y);
        let rest = ball_rest_m(spec, 1, x, y);
        assert!(
            (rest - h).abs() < 1.5e-3,
            "at ({x}, {y}): surface {h}, ball rests at {rest}"
        );
    }
    // the viewers' tile states carry the rest top and its inclination
    let mut tiles = Vec::new();
    terrain.tiles_in(&world, crate::Rect::around([5.0, 0.0], 0.05), &mut tiles);
    assert_eq!(tiles.len(), 1);
    assert!((tiles[0].rest_top_m - hill(5.0)).abs() < 1e-9);
    assert!((tiles[0].rest_slope - tan).abs() < 1e-9);
    // flat regions stay flat
    assert!(terrain.surface_height_m(&world, 1.0, 0.0).abs() < 1e-6);
}

#[test]
fn a_rounded_crest_turns_the_slope_gradually_and_keeps_the_sides() {
    // 4 m regions, hill in [3.9, 7.9], crest at 5.9; `crest=1m` rounds
    // [5.4, 6.4] with the parabola that meets both 10-degree sides.
    let tan = 10f64.to_radians().tan();
    let (x0, x1, middle, crest) = (3.9, 7.9, 5.9, 1.0);
    let rounded = |x: f64| {
        let s = (x - middle).abs();
        if s < crest / 2.0 {
            tan * ((x1 - x0) / 2.0 - crest / 4.0) - tan * s * s / crest
        } else {
            tan * (x - x0).min(x1 - x)
        }
    };
    for spec in [
        "varying:4m:5cm,(elastic:5cm:slope=10):crest=1m",
        "varying:4m:5cm,(slope:10):crest=1m",
    ] {
        let (world, terrain) = world_with(spec, 1);
        let (a, b) = terrain.regions()[1].x_range_m;
        assert!(
            (a - x0).abs() < 1e-9 && (b - x1).abs() < 1e-9,
            "{spec}: {a} {b}"
        );
        for x in [4.3, 5.3, 5.6, 5.9, 6.25, 7.42] {
            let rest = terrain.rest_height_m(x, 0.3);
            // tiles rest on chords of 20 cm, the rigid hill on 16 chords
            // of the crest: within 2 mm of the parabola
            assert!(
                (rest - rounded(x)).abs() < 2e-3,
                "{spec} at {x}: rest {rest}, hill {}",
                rounded(x)
            );
            let surface = terrain.surface_height_m(&world, x, 0.3);
            assert!((surface - rest).abs() < 1e-5, "{spec} at {x}: {surface}");
        }
        // the top is lower than the sharp crest's by tan crest / 4
        let sharp_top = tan * (middle - x0);
        assert!(
            (terrain.rest_height_m(middle, 0.0) - (sharp_top - tan * crest / 4.0)).abs() < 2e-3,
            "{spec}"
        );
    }
    // On tiles, neighbours turn by at most tan * 20 cm / 1 m, not by twice
    // the slope at once.
    let (_, terrain) = world_with("varying:4m:5cm,(elastic:5cm:slope=10):crest=1m", 1);
    let (_, sharp) = world_with("varying:4m:5cm,(elastic:5cm:slope=10)", 1);
    let gradients = |t: &dyn Terrain| -> Vec<f64> {
        (0..20)
            .map(|k| x0 + 0.1 + 0.2 * k as f64)
            .map(|x| (t.rest_height_m(x + 0.05, 0.0) - t.rest_height_m(x - 0.05, 0.0)) / 0.1)
            .collect()
    };
    let largest_turn = |g: Vec<f64>| {
        g.windows(2)
            .map(|w| (w[1] - w[0]).abs())
            .fold(0.0, f64::max)
    };
    let (turn, sharp_turn) = (
        largest_turn(gradients(&*terrain)),
        largest_turn(gradients(&*sharp)),
    );
    assert!((sharp_turn - 2.0 * tan).abs() < 1e-9, "sharp: {sharp_turn}");
    assert!(turn < 0.2 * 2.0 * tan / crest + 1e-6, "rounded: {turn}");
    // a crest in a region's own spec is refused: it belongs to the field
    let err = Registry::builtin()
        .create(
            "varying:4m:5cm,(elastic:5cm:slope=10:crest=1m)",
            &BuildContext::default(),
        )
        .err()
        .expect("a region may not set the field's crest");
    assert!(err.to_string().contains("crest"), "{err}");
    // and a crest where there is no hill would be ignored: refused
    for spec in ["elastic:5cm:crest=1m", "varying:4m:5cm,rigid:crest=1m"] {
        let err = Registry::builtin()
            .create(spec, &BuildContext::default())
            .err()
            .expect("a crest needs a hill");
        assert!(err.to_string().contains("has none"), "{spec}: {err}");
    }
}

#[test]
fn a_tile_on_a_hill_sinks_its_depth_vertically_under_a_quarter_of_the_robot() {
    // A ball free along z only, as heavy as a quarter of the standing robot,
    // on a tile centre of a 10-degree side: the tilted face pushes it
    // sideways too (into the ball's locked axes and the tile's), and the
    // vertical spring carries the vertical load, so it sinks d along z.
    for (spec, x, depth_m) in [
        ("elastic:5cm:slope=10", 3.0, 0.05),
        ("elastic:2cm:slope=5", 3.0, 0.02),
        ("varying:4m:5cm,(elastic:3cm:slope=10)", 5.0, 0.03),
    ] {
        let (mut world, mut terrain) = world_with(spec, 1);
        let rest = terrain.rest_height_m(x, 0.0);
        let radius = 0.01;
        let body = world.insert_body(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(x as f32, 0.0, (rest + radius + 0.002) as f32))
                .lock_rotations()
                .enabled_translations(false, false, true),
        );
        let ball = ColliderBuilder::ball(radius as f32)
            .mass((STANDING_LOAD_N / 9.81) as f32)
            .collision_groups(robot_collision_groups());
        world.insert_collider(ball, Some(body));
        for _ in 0..720 {
            step(&mut world, &mut terrain);
        }
        let sink_m = rest - terrain.surface_height_m(&world, x, 0.0);
        assert!(
            (sink_m - depth_m).abs() < 0.02 * depth_m,
            "{spec}: sink {sink_m}, expected {depth_m}"
        );
    }
}

#[test]
fn hill_and_stair_regions_rise_to_their_middle_and_join_at_ground_level() {
    let spec = "varying:2m:rigid,(slope:10),(steps:5cm:30cm),5cm";
    let (world, terrain) = world_with(spec, 3);
    let tan = 10f64.to_radians().tan();
    let mut seen = std::collections::BTreeSet::new();
    for region in terrain.regions() {
        let (x0, x1) = region.x_range_m;
        let middle = (x0 + x1) / 2.0;
        let h = |x: f64| terrain.surface_height_m(&world, x, 0.3);
        // every region starts and ends at z = 0: no cliff between regions
        for x in [x0 + 0.01, x1 - 0.01] {
            assert!(
                h(x).abs() < 0.01 * tan + 1e-9,
                "{} at {x}: {}",
                region.label,
                h(x)
            );
        }
        let (top, quarter) = match region.label.as_str() {
            "rigid" | "elastic:5cm" => (0.0, 0.0),
            "slope:10" => (tan * (middle - x0), tan * (middle - x0) / 2.0),
            // 2 m regions: 3 steps up (5, 10, 15 cm) and 3 down
            "steps:5cm:30cm" => (0.15, 0.05),
            other => panic!("region {other} is not in {spec}"),
        };
        assert!(
            (h(middle) - top).abs() < 1e-9,
            "{}: top {}",
            region.label,
            h(middle)
        );
        let at_quarter = h((x0 + middle) / 2.0);
        assert!(
            (at_quarter - quarter).abs() < 1e-9,
            "{}: {at_quarter}",
            region.label
        );
        seen.insert(region.label.clone());
    }
    assert_eq!(seen.len(), 4, "seed 3 draws every surface: {seen:?}");
    // The viewer's mesh holds each hill's two faces and each flight's
    // treads and risers: 2 + (2 x 3 + 1 + 2 x 3) quads per region of each.
    let mesh = terrain.ground_mesh().expect("hills and stairs have a mesh");
    let count = |label: &str| {
        terrain
            .regions()
            .iter()
            .filter(|r| r.label == label)
            .count()
    };
    let quads = 2 * count("slope:10") + 13 * count("steps:5cm:30cm");
    assert_eq!(mesh.triangles.len(), 2 * quads);
    let highest = mesh
        .vertices_m
        .iter()
        .map(|v| v[2])
        .fold(f64::MIN, f64::max);
    assert!((highest - 0.1763).abs() < 1e-3, "highest vertex {highest}");
}

#[test]
fn stairs_levels_fit_the_region() {
    use crate::relief::RegionRelief;
    assert_eq!(RegionRelief::stair_levels(2.0, 0.3), 3);
    assert_eq!(RegionRelief::stair_levels(2.0, 0.5), 1); // exactly 2 runs per side: the top tread keeps 1 m
    assert_eq!(RegionRelief::stair_levels(2.0, 0.99), 1);
    assert_eq!(RegionRelief::stair_levels(2.0, 1.0), 0);
}

#[test]
fn rough_heights_cover_their_amplitude_and_follow_the_seed() {
    let heights = |seed: u64| -> Vec<f64> {
        let (world, terrain) = world_with("rough:3cm:length=4m", seed);
        (0..400)
            .map(|k| {
                let (x, y) = (-2.0 + 0.3 * (k / 20) as f64, -1.0 + 0.1 * (k % 20) as f64);
                terrain.surface_height_m(&world, x, y)
            })
            .collect()
    };
    let a = heights(1);
    assert!(a.iter().all(|h| h.abs() <= 0.03 + 1e-12));
    let spread =
        a.iter().copied().fold(f64::MIN, f64::max) - a.iter().copied().fold(f64::MAX, f64::min);
    assert!(spread > 0.04, "spread {spread}");
    assert_eq!(heights(1), a);
    assert_ne!(heights(2), a);
}
