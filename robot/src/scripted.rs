//! A scripted crawl: a fixed, repeating sequence of four actions in the
//! paper's action space that walks the robot forward.
//!
//! One cycle is four phases, swinging front-left, rear-right, front-right,
//! rear-left. In every phase:
//! - the base advances `stride_m` along x at a steady rate (control points
//!   stride/3, 2 stride/3, stride);
//! - on top of that the base makes a hump away from the swing foot, over the
//!   triangle of the three stance feet, and is back on the centre line at the
//!   phase end: P1 = P2 = hump, P3 = 0, so it peaks at 3/4 of the hump at
//!   mid-phase. Front-leg swings hump backward (`hump_back_m`), rear-leg
//!   swings forward (`hump_forward_m`), and sideways by `hump_side_m` away
//!   from the swing foot's side;
//! - the swing foot rises late (height control points 0, `lift_m`) and
//!   lands `press_m` below its start height, so it loads the tile it lands
//!   on; frontally it goes from `landing_ahead_m - 4 stride` (where a foot
//!   that stood three phases is) to `landing_ahead_m` ahead of its squat
//!   position; laterally it stays on the squat position.
//!
//! Every phase starts and ends with the base on the centre line, so the four
//! actions repeat unchanged and the crawl does not look at the state.
//!
//! | phase | swing | base hump x | base hump y |
//! | --- | --- | --- | --- |
//! | 0 | FL | -hump_back | -hump_side |
//! | 1 | RR | +hump_forward | +hump_side |
//! | 2 | FR | -hump_back | +hump_side |
//! | 3 | RL | +hump_forward | -hump_side |

use crate::LegName;
use crate::action::{ACTION_SIZE, bound};
use crate::task::SWING_ORDER;

/// The crawl's settings, SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScriptedCrawl {
    /// base travel per phase, m
    pub stride_m: f64,
    /// base hump backward while a front foot swings (control-point value), m
    pub hump_back_m: f64,
    /// base hump forward while a rear foot swings (control-point value), m
    pub hump_forward_m: f64,
    /// base hump sideways, away from the swing foot (control-point value), m
    pub hump_side_m: f64,
    /// base hump upward while the foot swings (control-point value), m
    pub hump_up_m: f64,
    /// net base rise per phase (last height control point), m: makes up
    /// for the sag of the position-controlled legs
    pub rise_m: f64,
    /// base tilt hump that raises the swing foot's corner (roll and pitch control-point value), rad
    pub tilt_rad: f64,
    /// swing foot lift above its start height (control-point value), m
    pub lift_m: f64,
    /// the first height control point as a fraction of `lift_m` (0: the foot
    /// rises late, 1: from the phase start)
    pub lift_first_fraction: f64,
    /// where the swing foot lands ahead of its squat position, m
    pub landing_ahead_m: f64,
    /// how far below its start height the swing foot is placed, m
    pub press_m: f64,
}

impl Default for ScriptedCrawl {
    fn default() -> Self {
        Self {
            stride_m: 0.05,
            hump_back_m: 0.04,
            hump_forward_m: 0.0,
            hump_side_m: 0.04,
            hump_up_m: 0.02,
            rise_m: 0.003,
            tilt_rad: 0.05,
            lift_m: 0.15,
            lift_first_fraction: 0.0,
            landing_ahead_m: 0.125,
            press_m: 0.01,
        }
    }
}

impl ScriptedCrawl {
    /// The action for the `phase`-th phase of an episode (phase 0 swings FL).
    pub fn action(&self, phase: usize) -> [f32; ACTION_SIZE] {
        let swing = SWING_ORDER[phase % 4];
        let hind = matches!(swing, LegName::RearLeft | LegName::RearRight);
        let hump_x = if hind {
            self.hump_forward_m
        } else {
            -self.hump_back_m
        };
        // Away from the swing foot's side: a left foot swings, the base goes right.
        let hump_y = -swing.side_sign() * self.hump_side_m;
        let d = self.stride_m;
        let z = self.hump_up_m;
        let base_points = [
            [d / 3.0 + hump_x, hump_y, z],
            [2.0 * d / 3.0 + hump_x, hump_y, z],
            [d, 0.0, self.rise_m],
        ];
        // Raise the swing corner: roll up on the swing side, pitch the swing end up.
        let roll = swing.side_sign() * self.tilt_rad;
        let pitch = if hind { self.tilt_rad } else { -self.tilt_rad };
        let tilt_points = [[roll, pitch], [roll, pitch], [0.0, 0.0]];
        let first_lift = self.lift_first_fraction * self.lift_m;
        let lift_points = [first_lift, self.lift_m, -self.press_m];
        let shift = if hind {
            crate::action::HIND_FRONTAL_SHIFT_M
        } else {
            0.0
        };
        let before = self.landing_ahead_m - 4.0 * d;
        let frontal_points =
            [before, self.landing_ahead_m, self.landing_ahead_m].map(|x| x + shift);

        // Control-point values in SI (offsets as each bound defines them).
        let mut si = [0.0f64; ACTION_SIZE];
        for p in 0..3 {
            si[p * 3] = base_points[p][0];
            si[p * 3 + 1] = base_points[p][1];
            si[p * 3 + 2] = base_points[p][2];
            si[9 + p * 3] = tilt_points[p][0];
            si[9 + p * 3 + 1] = tilt_points[p][1];
            si[18 + p * 3] = frontal_points[p];
            si[18 + p * 3 + 2] = lift_points[p];
        }
        let mut action = [0.0f32; ACTION_SIZE];
        for (i, a) in action.iter_mut().enumerate() {
            *a = bound(i, hind).unmap(si[i]) as f32;
        }
        action
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::action::curves_from_action;
    use nalgebra::Vector3;

    #[test]
    fn the_crawl_maps_back_to_its_si_values() {
        let crawl = ScriptedCrawl::default();
        let squat = Vector3::new(-0.238, -0.2, -0.35);
        let now = Vector3::new(-0.4, -0.2, -0.34);
        let c = curves_from_action(&crawl.action(1), now, squat, true);
        // RR phase: hump left (away from the right foot), steady stride, back on the centre line.
        assert!((c.base_position.points[1] - Vector3::new(0.05 / 3.0, 0.04, 0.02)).norm() < 1e-6);
        assert!((c.base_position.points[3] - Vector3::new(0.05, 0.0, 0.003)).norm() < 1e-6);
        assert!((c.swing_foot.points[3].x - (squat.x + 0.125 - 0.02)).abs() < 1e-6);
        assert!((c.swing_foot.points[3].z - (now.z - 0.01)).abs() < 1e-6);
        assert!((c.swing_foot.points[2].z - (now.z + 0.15)).abs() < 1e-6);
        // Every value inside [-1, 1] (no clipping of the script).
        for phase in 0..4 {
            assert!(crawl.action(phase).iter().all(|a| a.abs() <= 1.0));
        }
    }
}
