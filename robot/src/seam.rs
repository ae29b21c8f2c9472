//! The one conversion seam between rapier's glam `f32` math and the
//! nalgebra `f64` math used for kinematics, control and observations.

use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};
use terrain_plugins::rapier3d::math::{Matrix, Pose, Rotation, Vector};

/// nalgebra vector -> rapier vector.
pub fn to_vector(v: &Vector3<f64>) -> Vector {
    Vector::new(v.x as f32, v.y as f32, v.z as f32)
}

/// rapier vector -> nalgebra vector.
pub fn from_vector(v: Vector) -> Vector3<f64> {
    Vector3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// nalgebra rotation -> rapier rotation.
pub fn to_rotation(q: &UnitQuaternion<f64>) -> Rotation {
    Rotation::from_xyzw(q.i as f32, q.j as f32, q.k as f32, q.w as f32).normalize()
}

/// rapier rotation -> nalgebra rotation.
pub fn from_rotation(q: Rotation) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(
        q.w as f64, q.x as f64, q.y as f64, q.z as f64,
    ))
}

/// nalgebra isometry -> rapier pose.
pub fn to_pose(iso: &Isometry3<f64>) -> Pose {
    Pose::from_parts(
        to_vector(&iso.translation.vector),
        to_rotation(&iso.rotation),
    )
}

/// rapier pose -> nalgebra isometry.
pub fn from_pose(pose: &Pose) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::from(from_vector(pose.translation)),
        from_rotation(pose.rotation),
    )
}

/// nalgebra matrix -> rapier matrix.
pub fn to_matrix(m: &Matrix3<f64>) -> Matrix {
    Matrix::from_cols(
        to_vector(&m.column(0).into_owned()),
        to_vector(&m.column(1).into_owned()),
        to_vector(&m.column(2).into_owned()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_round_trip() {
        let iso = Isometry3::new(Vector3::new(0.1, -0.2, 0.3), Vector3::new(0.4, 0.5, -0.6));
        let back = from_pose(&to_pose(&iso));
        assert!((back.translation.vector - iso.translation.vector).norm() < 1e-6);
        assert!(back.rotation.angle_to(&iso.rotation) < 1e-6);
        let m = Matrix3::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0);
        let r = to_matrix(&m);
        assert_eq!(r.col(0).y, 4.0);
        assert_eq!(r.col(2).x, 3.0);
    }
}
