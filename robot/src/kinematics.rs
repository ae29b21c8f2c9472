//! Leg forward kinematics and analytic 3-DoF inverse kinematics, per foot,
//! in the base frame.
//!
//! Each leg is an abduction joint (axis along ±x) followed by hip-pitch and
//! knee joints (axes along ±y). With A, T, K the abduction, hip and knee
//! joint positions and F the foot at q = 0 (base frame), and R_a, R_h, R_k
//! the joint rotations:
//!
//!   foot(q) = A + R_a [ (T - A) + R_h [ (K - T) + R_k (F - K) ] ]
//!
//! IK, for a target p:
//! 1. Abduction. Hip and knee turn about y, so the foot's y in the
//!    abduction frame is a constant l = (F - A)_y. Undoing R_a maps (p - A)'s
//!    (y, z) with radius r onto (l, -sqrt(r^2 - l^2)) (foot below the hip):
//!    theta = atan2(d_z, d_y) - atan2(z', l).
//! 2. Knee, by the law of cosines in the leg's sagittal (x, z) plane. With
//!    a vector's angle alpha = atan2(x, z) (a rotation about y by phi adds phi
//!    to alpha), |u|^2 = L1^2 + L2^2 + 2 L1 L2 cos(alpha_2 + phi_k - alpha_1),
//!    where u is the target from T and L1, L2, alpha_1, alpha_2 the lengths
//!    and zero-pose angles of K - T and F - K. Of the two solutions the one
//!    inside the knee's limits is taken.
//! 3. Hip: phi_h = alpha_u - alpha_w, w = (K - T) + R_k (F - K).
//!
//! Targets out of reach are clamped to the workspace (radius, then joint
//! limits) and flagged; the result is never NaN.

use nalgebra::{Rotation3, Vector2, Vector3};

use crate::model::{LegName, RobotModel};

/// A leg's geometry at q = 0, base frame, metres.
#[derive(Debug, Clone, PartialEq)]
pub struct LegKinematics {
    /// which leg
    pub name: LegName,
    /// abduction joint position
    pub abduction_m: Vector3<f64>,
    /// hip-pitch joint position
    pub hip_m: Vector3<f64>,
    /// knee joint position
    pub knee_m: Vector3<f64>,
    /// foot (toe centre) position
    pub foot_m: Vector3<f64>,
    /// +1 if the abduction axis is +x, -1 if -x
    pub abduction_sign: f64,
    /// +1 if the hip axis is +y, -1 if -y
    pub hip_sign: f64,
    /// +1 if the knee axis is +y, -1 if -y
    pub knee_sign: f64,
    /// joint limits (abduction, hip, knee), rad
    pub limits_rad: [(f64, f64); 3],
}

/// An IK answer: joint angles and whether the target had to be clamped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkSolution {
    /// abduction, hip, knee, rad
    pub q_rad: [f64; 3],
    /// true if the target was out of reach or beyond a joint limit
    pub clamped: bool,
}

/// Why a model's legs do not fit the analytic IK.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("leg {leg}: {message}")]
pub struct KinematicsError {
    /// leg short name
    pub leg: &'static str,
    /// what is wrong
    pub message: String,
}

const AXIS_TOLERANCE: f64 = 1e-3;

fn rot_x(angle: f64) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::x_axis(), angle)
}

fn rot_y(angle: f64) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::y_axis(), angle)
}

/// Angle of an (x, z) vector measured so that a rotation about +y by phi adds phi.
fn sagittal_angle(v: Vector2<f64>) -> f64 {
    v.x.atan2(v.y)
}

impl LegKinematics {
    /// Extracts the geometry of every leg of `model`, checking that the axes
    /// are abduction along x and hip/knee along y.
    pub fn from_model(model: &RobotModel) -> Result<[LegKinematics; 4], KinematicsError> {
        let zero = vec![0.0; model.joints.len()];
        let poses = model.body_poses_in_base(&zero);
        let legs = model.legs.clone();
        let mut out = Vec::with_capacity(4);
        for leg in legs {
            let err = |message: String| KinematicsError {
                leg: leg.name.short(),
                message,
            };
            let mut positions = [Vector3::zeros(); 3];
            let mut signs = [0.0; 3];
            let mut limits = [(0.0, 0.0); 3];
            for (k, &j) in leg.joints.iter().enumerate() {
                let joint = &model.joints[j];
                let pose = poses[joint.child];
                positions[k] = pose.translation.vector;
                let axis = pose.rotation * joint.axis_in_child.into_inner();
                let (want, label) = if k == 0 {
                    (Vector3::x(), "x")
                } else {
                    (Vector3::y(), "y")
                };
                let dot = axis.dot(&want);
                if (dot.abs() - 1.0).abs() > AXIS_TOLERANCE {
                    return Err(err(format!(
                        "joint {} turns about ({:.3}, {:.3}, {:.3}) in the base frame; expected an axis along {label}",
                        joint.name, axis.x, axis.y, axis.z
                    )));
                }
                signs[k] = dot.signum();
                limits[k] = joint
                    .limits_rad
                    .unwrap_or((-std::f64::consts::PI, std::f64::consts::PI));
            }
            let foot = poses[leg.foot_body] * nalgebra::Point3::from(leg.foot_in_body_m);
            out.push(LegKinematics {
                name: leg.name,
                abduction_m: positions[0],
                hip_m: positions[1],
                knee_m: positions[2],
                foot_m: foot.coords,
                abduction_sign: signs[0],
                hip_sign: signs[1],
                knee_sign: signs[2],
                limits_rad: limits,
            });
        }
        Ok([
            out[0].clone(),
            out[1].clone(),
            out[2].clone(),
            out[3].clone(),
        ])
    }

    /// Foot position in the base frame for joint angles `q_rad`.
    pub fn forward(&self, q_rad: [f64; 3]) -> Vector3<f64> {
        let r_a = rot_x(self.abduction_sign * q_rad[0]);
        let r_h = rot_y(self.hip_sign * q_rad[1]);
        let r_k = rot_y(self.knee_sign * q_rad[2]);
        self.abduction_m
            + r_a
                * ((self.hip_m - self.abduction_m)
                    + r_h * ((self.knee_m - self.hip_m) + r_k * (self.foot_m - self.knee_m)))
    }

    /// Joint angles that put the foot at `target_m` (base frame).
    pub fn inverse(&self, target_m: Vector3<f64>) -> IkSolution {
        let mut clamped = !target_m.iter().all(|v| v.is_finite());
        let target_m = if clamped { self.foot_m } else { target_m };
        let d = target_m - self.abduction_m;

        // 1. Abduction: the foot's y in the abduction frame is fixed.
        let lateral = self.foot_m.y - self.abduction_m.y;
        let mut r = d.y.hypot(d.z);
        if r < lateral.abs() {
            clamped = true;
            r = lateral.abs();
        }
        let z_in_abduction = -(r * r - lateral * lateral).max(0.0).sqrt();
        let theta = d.z.atan2(d.y) - z_in_abduction.atan2(lateral);
        let theta = wrap_angle(theta);

        // 2. Knee: law of cosines in the sagittal plane of the abduction frame.
        let hip_from_abd = self.hip_m - self.abduction_m;
        let u = Vector2::new(d.x - hip_from_abd.x, z_in_abduction - hip_from_abd.z);
        let v1 = Vector2::new(self.knee_m.x - self.hip_m.x, self.knee_m.z - self.hip_m.z);
        let v2 = Vector2::new(self.foot_m.x - self.knee_m.x, self.foot_m.z - self.knee_m.z);
        let (l1, l2) = (v1.norm(), v2.norm());
        let reach_max = (l1 + l2) * (1.0 - 1e-12);
        let reach_min = (l1 - l2).abs() * (1.0 + 1e-12) + 1e-12;
        let mut u_len = u.norm();
        let u_dir = if u_len > 1e-12 {
            u / u_len
        } else {
            Vector2::new(0.0, -1.0)
        };
        if u_len > reach_max {
            clamped = true;
            u_len = reach_max;
        } else if u_len < reach_min {
            clamped = true;
            u_len = reach_min;
        }
        let u = u_dir * u_len;
        let cos_beta = ((u_len * u_len - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)).clamp(-1.0, 1.0);
        let beta = cos_beta.acos();
        let (a1, a2) = (sagittal_angle(v1), sagittal_angle(v2));
        let knee_limits = self.limits_rad[2];
        let candidates = [beta, -beta].map(|b| wrap_angle((b - a2 + a1) * self.knee_sign));
        let knee = *candidates
            .iter()
            .min_by(|a, b| {
                limit_violation(**a, knee_limits).total_cmp(&limit_violation(**b, knee_limits))
            })
            .expect("two candidates");

        // 3. Hip: turn the two-link chain onto the target direction.
        let w = v1 + rot2(self.knee_sign * knee) * v2;
        let hip = wrap_angle((sagittal_angle(u) - sagittal_angle(w)) * self.hip_sign);

        let mut q = [theta * self.abduction_sign, hip, knee];
        for (k, q_k) in q.iter_mut().enumerate() {
            let (lo, hi) = self.limits_rad[k];
            if *q_k < lo || *q_k > hi {
                clamped = true;
                *q_k = q_k.clamp(lo, hi);
            }
        }
        IkSolution { q_rad: q, clamped }
    }
}

/// A rotation about +y acting on (x, z).
fn rot2(phi: f64) -> nalgebra::Matrix2<f64> {
    let (s, c) = phi.sin_cos();
    nalgebra::Matrix2::new(c, s, -s, c)
}

fn wrap_angle(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let wrapped = (a + std::f64::consts::PI).rem_euclid(two_pi) - std::f64::consts::PI;
    if wrapped.is_finite() { wrapped } else { 0.0 }
}

fn limit_violation(q: f64, (lo, hi): (f64, f64)) -> f64 {
    (lo - q).max(0.0) + (q - hi).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn legs() -> [LegKinematics; 4] {
        LegKinematics::from_model(&RobotModel::laikago()).unwrap()
    }

    #[test]
    fn analytic_fk_matches_the_model_tree() {
        let model = RobotModel::laikago();
        let legs = legs();
        let mut q = vec![0.0; 12];
        for (i, v) in q.iter_mut().enumerate() {
            *v = 0.1 * (i as f64 + 1.0) * if i % 3 == 2 { -1.0 } else { 1.0 };
        }
        let feet = model.feet_in_base_m(&q);
        for (leg, kin) in legs.iter().enumerate() {
            let p = kin.forward([q[3 * leg], q[3 * leg + 1], q[3 * leg + 2]]);
            assert!(
                (p - feet[leg]).norm() < 1e-12,
                "leg {leg}: {p} vs {}",
                feet[leg]
            );
        }
    }

    #[test]
    fn positive_abduction_moves_each_foot_outward() {
        for kin in legs() {
            let out = kin.forward([0.2, 0.0, -1.0]).y - kin.forward([0.0, 0.0, -1.0]).y;
            assert!(out * kin.name.side_sign() > 0.0, "{:?}", kin.name);
        }
    }

    #[test]
    fn wide_squat_is_reachable() {
        for kin in legs() {
            let target = Vector3::new(kin.abduction_m.x, 0.2 * kin.name.side_sign(), -0.35);
            let sol = kin.inverse(target);
            assert!(!sol.clamped, "{:?}: {sol:?}", kin.name);
            assert!((kin.forward(sol.q_rad) - target).norm() < 1e-7);
        }
    }

    #[test]
    fn unreachable_targets_are_clamped_never_nan() {
        let kin = &legs()[0];
        for target in [
            Vector3::new(0.0, 0.0, -5.0),
            Vector3::new(0.2, -0.08, -0.03),
            Vector3::new(f64::NAN, 0.0, 0.0),
            Vector3::new(0.0, 0.0, 3.0),
            Vector3::new(f64::INFINITY, 1.0, -1.0),
        ] {
            let sol = kin.inverse(target);
            assert!(sol.clamped, "{target}");
            assert!(sol.q_rad.iter().all(|q| q.is_finite()));
            for k in 0..3 {
                let (lo, hi) = kin.limits_rad[k];
                assert!(sol.q_rad[k] >= lo && sol.q_rad[k] <= hi);
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        /// FK(IK(p)) = p within 0.1 mm over the reachable workspace: sample
        /// joint angles inside the limits with the foot below the hip.
        #[test]
        fn fk_of_ik_returns_the_target(
            leg in 0usize..4,
            abduction in -0.6f64..0.6,
            hip in -0.8f64..1.6,
            knee in -2.1f64..-0.3,
        ) {
            let kin = &legs()[leg];
            // The workspace IK serves: the foot below the hip (in the abduction frame).
            let below = kin.forward([0.0, hip, knee]).z - kin.abduction_m.z;
            prop_assume!(below < -0.05);
            let target = kin.forward([abduction, hip, knee]);
            let sol = kin.inverse(target);
            prop_assert!(!sol.clamped, "{sol:?} for {target}");
            let back = kin.forward(sol.q_rad);
            prop_assert!((back - target).norm() < 1e-4, "{back} vs {target}");
        }
    }
}
