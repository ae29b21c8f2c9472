//! Standing still in the squat: the physical check of a robot on a terrain.

use crate::world::World;

/// Length of the window the settled figures are taken over, s.
pub const SETTLED_WINDOW_SECS: f64 = 5.0;

/// What happened while the robot stood.
#[derive(Debug, Clone, PartialEq)]
pub struct StandReport {
    /// simulated seconds
    pub seconds: f64,
    /// physics steps
    pub steps: u64,
    /// base height above the terrain's resting surface right below it (z = 0
    /// on flat ground) at the end, m
    pub base_height_m: f64,
    /// max minus min base height over the settled window, m
    pub base_height_drift_m: f64,
    /// largest tilt of the base over the whole run, degrees
    pub max_tilt_deg: f64,
    /// mean sink of the tiles under the four feet over the settled window, m
    pub mean_loaded_sink_m: f64,
    /// the sink the terrain's region at the robot promises, m
    pub expected_sink_m: f64,
    /// the terrain region the robot stands in
    pub region: String,
    /// links other than feet that touched the ground at any time
    pub non_foot_contacts: Vec<String>,
    /// the settled window's length, s (the last 5 s, or the second half of a shorter run)
    pub window_secs: f64,
}

/// Lets the robot stand for `seconds` holding its current PD targets.
pub fn stand(world: &mut World, seconds: f64) -> StandReport {
    stand_observed(world, seconds, &mut |_, _| {})
}

/// [`stand`], calling `after_step(world, step)` (0-based) after every
/// physics step (for loggers and viewers).
pub fn stand_observed(
    world: &mut World,
    seconds: f64,
    after_step: &mut dyn FnMut(&World, u64),
) -> StandReport {
    let steps = (seconds / world.dt_secs()).round().max(1.0) as u64;
    let window_secs = SETTLED_WINDOW_SECS.min(seconds / 2.0);
    let window_start = steps.saturating_sub((window_secs / world.dt_secs()).round() as u64);
    let mut max_tilt_rad: f64 = 0.0;
    let (mut min_h, mut max_h) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut sink_sum, mut sink_samples) = (0.0, 0u64);
    let mut non_foot: Vec<String> = Vec::new();
    for step in 0..steps {
        world.step();
        after_step(world, step);
        max_tilt_rad = max_tilt_rad.max(world.tilt_rad());
        for link in world.ground_contacts().non_foot_links {
            if !non_foot.contains(&link) {
                non_foot.push(link);
            }
        }
        if step >= window_start {
            let h = world.base_pose().translation.z;
            min_h = min_h.min(h);
            max_h = max_h.max(h);
            let feet = world.feet_in_world_m();
            let sink: f64 = feet
                .iter()
                .map(|f| world.rest_height_m(f.x, f.y) - world.surface_height_m(f.x, f.y))
                .sum::<f64>()
                / 4.0;
            sink_sum += sink;
            sink_samples += 1;
        }
    }
    let base = world.base_pose().translation.vector;
    let terrain = world.terrain();
    let region = &terrain.regions()[terrain.region_index_at(base.x, base.y)];
    StandReport {
        seconds: steps as f64 * world.dt_secs(),
        steps,
        base_height_m: base.z - world.rest_height_m(base.x, base.y),
        base_height_drift_m: max_h - min_h,
        max_tilt_deg: max_tilt_rad.to_degrees(),
        mean_loaded_sink_m: sink_sum / sink_samples.max(1) as f64,
        expected_sink_m: region.expected_sink_m,
        region: region.label.clone(),
        non_foot_contacts: non_foot,
        window_secs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::WorldConfig;

    fn world_on(spec: &str, xy: [f64; 2], config: WorldConfig) -> World {
        crate::test_worlds::laikago_on(spec, 0, xy, config)
    }

    fn stand_on(spec: &str, xy: [f64; 2], seconds: f64) -> StandReport {
        stand(&mut world_on(spec, xy, WorldConfig::default()), seconds)
    }

    #[test]
    fn standing_on_rigid_ground_does_not_creep() {
        // With converged contacts the squat holds its place: 4.9 mm in 10 s
        // (the motor model at rapier's default passes crept 92 mm).
        let mut world = world_on("rigid", [0.0, 0.0], WorldConfig::default());
        let start = world.base_pose().translation.vector;
        let r = stand(&mut world, 10.0);
        let end = world.base_pose().translation.vector;
        let drift_m = (end.xy() - start.xy()).norm();
        assert!(drift_m < 0.015, "crept {drift_m} m: {r:?}");
        assert!(r.max_tilt_deg < 1.0, "{r:?}");
    }

    #[test]
    fn both_pd_models_hold_the_squat_alike() {
        // The implicit spring (default) and the motor solved to convergence
        // (4 substeps x 4 PGS passes) are the same PD: after 3 s standing
        // on 5 cm tiles the joints agree within 0.01 rad, the base height
        // within 5 mm, and both track the squat within 0.05 rad.
        let motor = WorldConfig {
            pd: crate::PdModel::Motor,
            solver_iterations: 4,
            pgs_iterations: 4,
            ..WorldConfig::default()
        };
        let mut a = world_on("elastic:5cm", [0.0, 0.0], WorldConfig::default());
        let mut b = world_on("elastic:5cm", [0.0, 0.0], motor);
        let (ra, rb) = (stand(&mut a, 3.0), stand(&mut b, 3.0));
        let (qa, qb) = (a.joint_positions_rad(), b.joint_positions_rad());
        for j in 0..qa.len() {
            assert!((qa[j] - qb[j]).abs() < 0.01, "joint {j}: {qa:?} vs {qb:?}");
            for (w, q) in [(&a, &qa), (&b, &qb)] {
                let error = (w.joint_targets_rad()[j] - q[j]).abs();
                assert!(error < 0.05, "joint {j} off its target by {error} rad");
            }
        }
        assert!(
            (ra.base_height_m - rb.base_height_m).abs() < 0.005,
            "{ra:?} vs {rb:?}"
        );
    }

    #[test]
    fn at_half_the_paper_rate_the_squat_stands_as_at_240_hz() {
        // 3 s at 120 Hz are 360 steps of 1/120 s; the robot settles on 5 cm
        // tiles to the base height and sink of 240 Hz within 2 mm.
        let coarse = WorldConfig {
            step_rate_hz: 120,
            ..WorldConfig::default()
        };
        let mut a = world_on("elastic:5cm", [0.0, 0.0], WorldConfig::default());
        let mut b = world_on("elastic:5cm", [0.0, 0.0], coarse);
        let (ra, rb) = (stand(&mut a, 3.0), stand(&mut b, 3.0));
        assert_eq!((ra.steps, rb.steps), (720, 360));
        assert!((b.time_secs() - 3.0).abs() < 1e-9, "{}", b.time_secs());
        for (what, x, y) in [
            ("base height", ra.base_height_m, rb.base_height_m),
            ("sink", ra.mean_loaded_sink_m, rb.mean_loaded_sink_m),
        ] {
            assert!(
                (x - y).abs() < 0.002,
                "{what}: {x} m at 240 Hz, {y} m at 120 Hz"
            );
        }
        assert!(rb.max_tilt_deg < 1.0, "{rb:?}");
        assert!(rb.base_height_drift_m < 0.002, "{rb:?}");
    }

    #[test]
    fn the_default_contact_prediction_is_rapiers() {
        // The shipped policies were trained with rapier's default; a world
        // built from the default config must use it to the bit.
        let world = world_on("rigid", [0.0, 0.0], WorldConfig::default());
        let rapier = terrain_plugins::rapier3d::prelude::IntegrationParameters::default();
        assert_eq!(
            world
                .physics()
                .integration_parameters
                .normalized_prediction_distance
                .to_bits(),
            rapier.normalized_prediction_distance.to_bits()
        );
    }

    #[test]
    fn a_shorter_contact_prediction_holds_the_squat_alike() {
        // Speculative contacts only act when a gap would close within the
        // step: standing still on 5 cm tiles, 5 mm instead of 2 cm gives
        // the same squat (joints within 0.01 rad, base within 5 mm) and
        // the same sink (within 10 % of the named depth).
        let short = WorldConfig {
            prediction_distance_m: 0.005,
            ..WorldConfig::default()
        };
        let mut a = world_on("elastic:5cm", [0.0, 0.0], WorldConfig::default());
        let mut b = world_on("elastic:5cm", [0.0, 0.0], short);
        assert_eq!(
            b.physics().integration_parameters.prediction_distance(),
            0.005
        );
        let (ra, rb) = (stand(&mut a, 3.0), stand(&mut b, 3.0));
        let (qa, qb) = (a.joint_positions_rad(), b.joint_positions_rad());
        for j in 0..qa.len() {
            assert!((qa[j] - qb[j]).abs() < 0.01, "joint {j}: {qa:?} vs {qb:?}");
        }
        assert!(
            (ra.base_height_m - rb.base_height_m).abs() < 0.005,
            "{ra:?} vs {rb:?}"
        );
        assert!((rb.mean_loaded_sink_m - 0.05).abs() <= 0.005, "{rb:?}");
        assert!(rb.non_foot_contacts.is_empty(), "{rb:?}");
    }

    #[test]
    fn the_implicit_spring_pd_is_capped_at_the_effort() {
        // A knee target 1 rad away (clamped to the joint's limit) asks far
        // more than the URDF's 100 N m; the joint gets, and reports, 100.
        let mut world = world_on("rigid", [0.0, 0.0], WorldConfig::default());
        stand(&mut world, 0.5);
        let knee = 2;
        let mut targets = world.joint_targets_rad().to_vec();
        targets[knee] += 1.0;
        world.set_joint_targets_rad(&targets);
        world.step();
        let effort = world.model().joints[knee].effort_n_m;
        let tau = world.applied_torques_n_m()[knee];
        assert!((tau.abs() - effort).abs() < 1e-9, "{tau} vs {effort}");
    }

    #[test]
    fn stands_on_rigid_ground() {
        let r = stand_on("rigid", [0.0, 0.0], 10.0);
        println!("{r:?}");
        assert!(r.max_tilt_deg < 2.0, "{r:?}");
        assert!(r.base_height_drift_m < 0.005, "{r:?}");
        assert!(r.non_foot_contacts.is_empty(), "{r:?}");
        assert!((r.base_height_m - 0.38).abs() < 0.03, "{r:?}");
    }

    #[test]
    fn sinks_the_named_depth_on_elastic_tiles() {
        for (spec, depth) in [("elastic:2cm", 0.02), ("elastic:5cm", 0.05)] {
            let r = stand_on(spec, [0.0, 0.0], 10.0);
            println!("{spec}: {r:?}");
            assert!(
                (r.mean_loaded_sink_m - depth).abs() <= 0.1 * depth,
                "{spec}: {r:?}"
            );
            assert!(r.max_tilt_deg < 5.0, "{spec}: {r:?}");
            assert!(r.non_foot_contacts.is_empty(), "{spec}: {r:?}");
        }
    }

    #[test]
    fn stands_on_a_hill_and_on_stairs_without_sinking_or_sliding() {
        // Region 0 of these runs over [-1.9, 1.9] m: a hill 33 cm high at
        // x = 0, stairs with their top tread over [-0.1, 0.1]. Sinks and
        // heights are measured from the relief, not from z = 0.
        let tan = 10f64.to_radians().tan();
        for (spec, xy) in [
            ("varying:2m:(slope:10)", [0.5, 0.0]),
            ("varying:2m:(steps:5cm:60cm)", [0.0, 0.0]),
        ] {
            let mut world = world_on(spec, xy, WorldConfig::default());
            // placed level above the relief, it lands and settles first
            let landing = stand(&mut world, 2.0);
            assert!(landing.non_foot_contacts.is_empty(), "{spec}: {landing:?}");
            let start = world.base_pose().translation.vector;
            let r = stand(&mut world, 4.0);
            let end = world.base_pose().translation.vector;
            println!("{spec}: {r:?}");
            assert!(r.mean_loaded_sink_m.abs() < 0.002, "{spec}: {r:?}");
            assert!(r.non_foot_contacts.is_empty(), "{spec}: {r:?}");
            assert!(r.base_height_drift_m < 0.005, "{spec}: {r:?}");
            let slid_m = (end.xy() - start.xy()).norm();
            assert!(slid_m < 0.005, "{spec}: slid {slid_m} m in 4 s");
            // above its ground about as on flat ground (0.38 m); on the hill
            // the feet stand up to 0.25 m x tan(10 deg) below the base's point
            assert!(
                (r.base_height_m - 0.38).abs() < 0.03 + 0.25 * tan,
                "{spec}: {r:?}"
            );
        }
    }
}
