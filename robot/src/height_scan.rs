//! The height scan: how high the base stands above the ground at a grid of
//! points ahead of it (not the paper's; legged_gym's rough-terrain
//! policies observe such a grid). The paper's observation shows the
//! ground only right below the hips (h_b), so a policy meets a crest or a
//! step rather than seeing it coming; with `[task.observation] height_scan
//! = true` it sees the ground up to 1.1 m ahead.
//!
//! The points lie in the base's heading frame (its yaw only, so that they
//! stay spread over the ground as the base pitches and rolls): 6 rows at
//! [`SCAN_AHEAD_M`] ahead of the base's origin along its heading, each of 3
//! points at [`SCAN_ACROSS_M`] to its left. Each value is the base origin's
//! height above the ground's surface at that point now (the tiles' tops as
//! they are, sunk where something stands on them), m, world z: on level
//! ground every value is the base's height; ground that rises ahead gives
//! smaller values row by row.

use nalgebra::{Isometry3, UnitQuaternion, Vector3};

use crate::world::World;

/// Distances of the scan's rows ahead of the base's origin along its
/// heading, m (the front hips are ~0.2 m ahead of it).
pub const SCAN_AHEAD_M: [f64; 6] = [0.1, 0.3, 0.5, 0.7, 0.9, 1.1];

/// Offsets of each row's points to the left of the heading line, m (the
/// feet stand ~0.15 m either side of it).
pub const SCAN_ACROSS_M: [f64; 3] = [-0.15, 0.0, 0.15];

/// Values in a scan: rows ahead, nearest first, each right to left.
pub const HEIGHT_SCAN_POINTS: usize = SCAN_AHEAD_M.len() * SCAN_ACROSS_M.len();

/// One scan: the base's height above the ground at each point, m, in the
/// order of [`scan_points_xy_m`].
pub type HeightScan = [f64; HEIGHT_SCAN_POINTS];

/// The scan's points in the world (x, y), m, for a base at `base_pose`:
/// row by row from the nearest, each right (negative across) to left.
pub fn scan_points_xy_m(base_pose: &Isometry3<f64>) -> [[f64; 2]; HEIGHT_SCAN_POINTS] {
    let (_, _, yaw) = base_pose.rotation.euler_angles();
    let heading = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
    let origin = base_pose.translation.vector;
    std::array::from_fn(|k| {
        let (row, column) = (k / SCAN_ACROSS_M.len(), k % SCAN_ACROSS_M.len());
        let offset = heading * Vector3::new(SCAN_AHEAD_M[row], SCAN_ACROSS_M[column], 0.0);
        [origin.x + offset.x, origin.y + offset.y]
    })
}

/// The scan of `world` now: the base origin's height above the surface at
/// each of [`scan_points_xy_m`], m.
pub fn height_scan_m(world: &World) -> HeightScan {
    let base = world.base_pose();
    let z = base.translation.z;
    scan_points_xy_m(&base).map(|[x, y]| z - world.surface_height_m(x, y))
}

/// The scan's index that the left-right mirror image of point `k` takes
/// (the same row, the column across the heading line).
pub fn mirrored_point(k: usize) -> usize {
    let across = SCAN_ACROSS_M.len();
    let (row, column) = (k / across, k % across);
    row * across + (across - 1 - column)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_worlds::laikago_on;
    use crate::world_config::WorldConfig;
    use nalgebra::Translation3;

    #[test]
    fn the_points_follow_the_heading_and_ignore_pitch_and_roll() {
        let level = Isometry3::from_parts(
            Translation3::new(1.0, 2.0, 0.4),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        let points = scan_points_xy_m(&level);
        // heading +y: "ahead" is +y, "left" is -x
        let [x, y] = points[0];
        assert!((x - (1.0 + 0.15)).abs() < 1e-12 && (y - 2.1).abs() < 1e-12);
        let [x, y] = points[HEIGHT_SCAN_POINTS - 1];
        assert!((x - (1.0 - 0.15)).abs() < 1e-12 && (y - 3.1).abs() < 1e-12);
        // a pitched and rolled base with the same yaw scans the same points
        let tilted = Isometry3::from_parts(
            level.translation,
            UnitQuaternion::from_euler_angles(0.2, -0.3, std::f64::consts::FRAC_PI_2),
        );
        for (a, b) in points.iter().zip(scan_points_xy_m(&tilted)) {
            assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9);
        }
    }

    #[test]
    fn mirroring_swaps_right_and_left_in_each_row_and_twice_is_identity() {
        let base = Isometry3::translation(0.0, 0.0, 0.4);
        let points = scan_points_xy_m(&base);
        for k in 0..HEIGHT_SCAN_POINTS {
            let m = mirrored_point(k);
            assert_eq!(mirrored_point(m), k);
            assert!((points[k][0] - points[m][0]).abs() < 1e-12);
            assert!((points[k][1] + points[m][1]).abs() < 1e-12);
        }
    }

    #[test]
    fn on_level_ground_every_value_is_the_base_height_and_a_slope_ahead_lowers_each_row() {
        let flat = laikago_on("rigid", 3, [0.0, 0.0], WorldConfig::default());
        let z = flat.base_pose().translation.z;
        for h in height_scan_m(&flat) {
            assert!((h - (z - flat.surface_height_m(0.0, 0.0))).abs() < 1e-9);
        }
        // a rigid plane rising along +x at 10 degrees: each row 0.2 m
        // further ahead is tan(10 degrees) x 0.2 m higher
        let slope = laikago_on("slope:10", 3, [0.0, 0.0], WorldConfig::default());
        let scan = height_scan_m(&slope);
        let rise_m = 10f64.to_radians().tan() * 0.2;
        let across = SCAN_ACROSS_M.len();
        for row in 1..SCAN_AHEAD_M.len() {
            for column in 0..across {
                let (near, far) = (
                    scan[(row - 1) * across + column],
                    scan[row * across + column],
                );
                assert!(
                    (near - far - rise_m).abs() < 2e-3,
                    "row {row}: {near} then {far}, {rise_m} apart expected"
                );
            }
        }
    }
}
