//! The paper's phase-level action: 27 numbers in [-1, 1] that place the
//! control points of three cubic Bezier curves for one 0.75 s phase.
//!
//! Layout (index ranges into the 27-vector), every coordinate in the base
//! frame at the start of the phase:
//!
//! | indices | curve | control points | bounds (per axis) |
//! | --- | --- | --- | --- |
//! | 0..9 | base position offset (x, y, z), m | P1, P2, P3 | P1, P2 in [-6, 6] cm; P3 in [-4, 8] cm, from the current position |
//! | 9..18 | base orientation offset (roll, pitch, yaw), rad | P1, P2, P3 | [-0.3, 0.3] rad from the current orientation |
//! | 18..27 | swing foot position (x frontal, y lateral, z height), m | P1, P2, P3 | x: [-15, 15] cm from the squat position (front feet), [delta - 15, delta + 15] cm (hind feet, delta = -2 cm); y: [-15, 15] cm from the squat position; z: [-15, 15] cm from the foot's current height (the paper's; or from another origin, see `swing_height_reference`) |
//!
//! Each point's coordinates are consecutive (P1 x, P1 y, P1 z, P2 x, ...).
//! The first control point P0 of every curve is the current value: zero
//! offset for the base curves, the swing foot's current position for the
//! foot curve. The map from [-1, 1] to a bound [lo, hi] is linear:
//! v = lo (1 - u) + hi u with u = (a + 1) / 2, so -1 gives lo, +1 gives hi and 0 the
//! centre. Values outside [-1, 1] (and NaN) are clipped first.

use nalgebra::Vector3;

/// Number of action values.
pub const ACTION_SIZE: usize = 27;
/// Duration of one phase, s.
pub const PHASE_SECS: f64 = 0.75;
/// Samples (IK solves and physics steps) per phase at the paper's 240 Hz:
/// 0.75 s of 1/240 s steps (a world at another `[physics] step_rate_hz`
/// takes [`crate::World::steps_per_phase`]).
pub const SAMPLES_PER_PHASE: usize = 180;
/// Hind-foot frontal shift delta, m.
pub const HIND_FRONTAL_SHIFT_M: f64 = -0.02;

/// A cubic Bezier curve in 3D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CubicBezier {
    /// P0..P3
    pub points: [Vector3<f64>; 4],
}

impl CubicBezier {
    /// The point at t in [0, 1]:
    /// B(t) = (1-t)^3 P0 + 3 (1-t)^2 t P1 + 3 (1-t) t^2 P2 + t^3 P3.
    pub fn at(&self, t: f64) -> Vector3<f64> {
        let t = t.clamp(0.0, 1.0);
        let s = 1.0 - t;
        let [p0, p1, p2, p3] = self.points;
        p0 * (s * s * s) + p1 * (3.0 * s * s * t) + p2 * (3.0 * s * t * t) + p3 * (t * t * t)
    }
}

/// Bounds of one coordinate, SI units, relative to its reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    /// value at a = -1
    pub lo: f64,
    /// value at a = +1
    pub hi: f64,
}

impl Bound {
    const fn new(lo: f64, hi: f64) -> Self {
        Self { lo, hi }
    }

    /// Maps a in [-1, 1] (clipped) linearly onto [lo, hi].
    pub fn map(&self, a: f64) -> f64 {
        let a = if a.is_nan() { 0.0 } else { a.clamp(-1.0, 1.0) };
        let u = (a + 1.0) * 0.5;
        // Written as a blend so that u = 0 and u = 1 give lo and hi exactly.
        self.lo * (1.0 - u) + self.hi * u
    }

    /// The inverse of [`Self::map`] (for scripted policies written in SI).
    pub fn unmap(&self, value: f64) -> f64 {
        (2.0 * (value - self.lo) / (self.hi - self.lo) - 1.0).clamp(-1.0, 1.0)
    }
}

const BASE_MID: Bound = Bound::new(-0.06, 0.06);
const BASE_LAST: Bound = Bound::new(-0.04, 0.08);
const ORIENTATION: Bound = Bound::new(-0.3, 0.3);
const FOOT: Bound = Bound::new(-0.15, 0.15);

/// The bound of action value `index` (0..27). `hind` selects the hind-foot
/// frontal bound. Base and height bounds are offsets from the current value;
/// foot frontal and lateral bounds are offsets from the squat position.
pub fn bound(index: usize, hind: bool) -> Bound {
    assert!(index < ACTION_SIZE, "action index {index} out of range");
    let point = (index % 9) / 3; // P1, P2, P3
    let axis = index % 3;
    match index / 9 {
        0 => {
            if point == 2 {
                BASE_LAST
            } else {
                BASE_MID
            }
        }
        1 => ORIENTATION,
        _ => {
            if axis == 0 && hind {
                Bound::new(
                    FOOT.lo + HIND_FRONTAL_SHIFT_M,
                    FOOT.hi + HIND_FRONTAL_SHIFT_M,
                )
            } else {
                FOOT
            }
        }
    }
}

/// The three curves of one phase, in the base frame at the phase start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseCurves {
    /// base position offset from the phase start, m
    pub base_position: CubicBezier,
    /// base orientation offset (roll, pitch, yaw) from the phase start, rad
    pub base_orientation: CubicBezier,
    /// swing foot position, m
    pub swing_foot: CubicBezier,
}

/// Maps an action onto the curves. `swing_foot_now_m` is the swing foot's
/// position at the phase start (the foot curve's P0), `swing_height_origin_m`
/// the height its P1-P3 heights count from (the paper's: `swing_foot_now_m.z`)
/// and `swing_foot_squat_m` its squat position (all base frame); `hind` says
/// whether the swing leg is a hind leg.
pub fn curves_from_action(
    action: &[f32],
    swing_foot_now_m: Vector3<f64>,
    swing_height_origin_m: f64,
    swing_foot_squat_m: Vector3<f64>,
    hind: bool,
) -> PhaseCurves {
    assert_eq!(
        action.len(),
        ACTION_SIZE,
        "an action has {ACTION_SIZE} values"
    );
    let value = |i: usize| bound(i, hind).map(action[i] as f64);
    let point = |curve: usize, p: usize| {
        let base = curve * 9 + p * 3;
        Vector3::new(value(base), value(base + 1), value(base + 2))
    };
    let foot_point = |p: usize| {
        let offset = point(2, p);
        Vector3::new(
            swing_foot_squat_m.x + offset.x,
            swing_foot_squat_m.y + offset.y,
            swing_height_origin_m + offset.z,
        )
    };
    PhaseCurves {
        base_position: CubicBezier {
            points: [Vector3::zeros(), point(0, 0), point(0, 1), point(0, 2)],
        },
        base_orientation: CubicBezier {
            points: [Vector3::zeros(), point(1, 0), point(1, 1), point(1, 2)],
        },
        swing_foot: CubicBezier {
            points: [
                swing_foot_now_m,
                foot_point(0),
                foot_point(1),
                foot_point(2),
            ],
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minus_one_and_plus_one_land_on_the_bounds_and_zero_on_the_centre() {
        let now = Vector3::new(0.2, -0.2, -0.33);
        let squat = Vector3::new(0.2, -0.2, -0.35);
        for hind in [false, true] {
            let lo = curves_from_action(&[-1.0; ACTION_SIZE], now, now.z, squat, hind);
            let hi = curves_from_action(&[1.0; ACTION_SIZE], now, now.z, squat, hind);
            let mid = curves_from_action(&[0.0; ACTION_SIZE], now, now.z, squat, hind);
            let shift = if hind { -0.02 } else { 0.0 };
            for p in 1..3 {
                assert_eq!(lo.base_position.points[p], Vector3::repeat(-0.06));
                assert_eq!(hi.base_position.points[p], Vector3::repeat(0.06));
                assert!(mid.base_position.points[p].norm() < 1e-15);
            }
            assert_eq!(lo.base_position.points[3], Vector3::repeat(-0.04));
            assert_eq!(hi.base_position.points[3], Vector3::repeat(0.08));
            assert!((mid.base_position.points[3] - Vector3::repeat(0.02)).norm() < 1e-15);
            for p in 1..4 {
                assert_eq!(lo.base_orientation.points[p], Vector3::repeat(-0.3));
                assert_eq!(hi.base_orientation.points[p], Vector3::repeat(0.3));
                assert!(mid.base_orientation.points[p].norm() < 1e-15);
                let (l, h, m) = (
                    lo.swing_foot.points[p],
                    hi.swing_foot.points[p],
                    mid.swing_foot.points[p],
                );
                assert!(
                    (l.x - (squat.x - 0.15 + shift)).abs() < 1e-12
                        && (h.x - (squat.x + 0.15 + shift)).abs() < 1e-12
                );
                assert!((m.x - (squat.x + shift)).abs() < 1e-12);
                assert!(
                    (l.y - (squat.y - 0.15)).abs() < 1e-12
                        && (h.y - (squat.y + 0.15)).abs() < 1e-12
                        && (m.y - squat.y).abs() < 1e-12
                );
                assert!(
                    (l.z - (now.z - 0.15)).abs() < 1e-12
                        && (h.z - (now.z + 0.15)).abs() < 1e-12
                        && (m.z - now.z).abs() < 1e-12
                );
            }
        }
    }

    #[test]
    fn each_curve_starts_at_the_current_value() {
        let now = Vector3::new(0.25, -0.18, -0.31);
        let action: Vec<f32> = (0..ACTION_SIZE)
            .map(|i| ((i as f32) * 0.37).sin())
            .collect();
        let c = curves_from_action(&action, now, now.z, Vector3::new(0.2, -0.2, -0.35), false);
        assert_eq!(c.base_position.at(0.0), Vector3::zeros());
        assert_eq!(c.base_orientation.at(0.0), Vector3::zeros());
        assert!((c.swing_foot.at(0.0) - now).norm() < 1e-15);
        assert!((c.swing_foot.at(1.0) - c.swing_foot.points[3]).norm() < 1e-15);
    }

    #[test]
    fn the_foot_heights_count_from_the_origin_and_the_curve_starts_at_the_foot() {
        // a foot 9 cm below the origin (sunk since it landed): P1-P3 are
        // raised by those 9 cm against the paper's origin, P0 stays put
        let now = Vector3::new(0.25, -0.18, -0.40);
        let squat = Vector3::new(0.2, -0.2, -0.35);
        let action: Vec<f32> = (0..ACTION_SIZE)
            .map(|i| ((i as f32) * 0.37).cos())
            .collect();
        let paper = curves_from_action(&action, now, now.z, squat, true);
        let raised = curves_from_action(&action, now, now.z + 0.09, squat, true);
        assert_eq!(raised.swing_foot.points[0], now);
        for p in 1..4 {
            let (a, b) = (paper.swing_foot.points[p], raised.swing_foot.points[p]);
            assert_eq!((a.x, a.y), (b.x, b.y));
            assert!((b.z - a.z - 0.09).abs() < 1e-12, "P{p}: {} {}", a.z, b.z);
        }
        assert_eq!(raised.base_position, paper.base_position);
        assert_eq!(raised.base_orientation, paper.base_orientation);
    }

    #[test]
    fn out_of_range_and_nan_actions_are_clipped() {
        let b = bound(0, false);
        assert_eq!(b.map(5.0), 0.06);
        assert_eq!(b.map(-5.0), -0.06);
        assert_eq!(b.map(f64::NAN), 0.0);
        for v in [-0.06, 0.0, 0.03] {
            assert!((b.map(b.unmap(v)) - v).abs() < 1e-15);
        }
    }
}
