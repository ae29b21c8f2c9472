//! The robot model: a URDF turned into rigid bodies, 12 actuated joints and
//! four 3-DoF legs.
//!
//! Links joined by `fixed` joints are merged into one body (mass, centre of
//! mass and inertia combined; collision shapes kept), so the Laikago's toe
//! spheres become part of the lower legs. The model must be a quadruped:
//! a root body with four chains of three revolute (or continuous) joints,
//! abduction then hip pitch then knee, each chain ending in a sphere (the
//! foot). Legs are named by where their abduction joint sits (front/rear by
//! x, left/right by y, base frame). The foot (the paper's end-effector) is
//! the leg's last body: the lower leg with its toe. Its position is the toe
//! sphere's centre; any of its shapes touching the ground is a foot contact
//! (the third-party Laikago's lower-leg mesh reaches the toe, so a rule that
//! only counted the toe sphere would end every episode on it).
//!
//! Frames: the base frame is the root link's frame (x forward, y left,
//! z up). All quantities are SI.

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Matrix3, Translation3, Unit, UnitQuaternion, Vector3};

/// The built-in Laikago description (written from the Laikago facts).
pub const LAIKAGO_URDF: &str = include_str!("../assets/laikago.urdf");

/// Why a robot description was refused.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("robot description {path}: cannot read it: {source}")]
    Read {
        /// the file
        path: PathBuf,
        /// the I/O error
        source: std::io::Error,
    },
    /// The file is not valid URDF.
    #[error("robot description {path}: not valid URDF: {message}")]
    Parse {
        /// the file
        path: PathBuf,
        /// the parser's message
        message: String,
    },
    /// The URDF is valid but is not a quadruped this toolkit can drive.
    #[error("robot description {path}: {message}")]
    Structure {
        /// the file
        path: PathBuf,
        /// what is wrong
        message: String,
    },
    /// A collision mesh could not be read.
    #[error("robot description {path}: collision mesh {mesh}: {message}")]
    Mesh {
        /// the URDF file
        path: PathBuf,
        /// the mesh file
        mesh: PathBuf,
        /// what is wrong
        message: String,
    },
}

/// The four legs, in the order used for every per-leg array.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LegName {
    /// front right
    FrontRight,
    /// front left
    FrontLeft,
    /// rear right
    RearRight,
    /// rear left
    RearLeft,
}

impl LegName {
    /// All legs in array order: FR, FL, RR, RL.
    pub const ALL: [LegName; 4] = [
        Self::FrontRight,
        Self::FrontLeft,
        Self::RearRight,
        Self::RearLeft,
    ];

    /// Short name (`FR`).
    pub fn short(self) -> &'static str {
        match self {
            Self::FrontRight => "FR",
            Self::FrontLeft => "FL",
            Self::RearRight => "RR",
            Self::RearLeft => "RL",
        }
    }

    /// Index in per-leg arrays.
    pub fn index(self) -> usize {
        self as usize
    }

    /// +1 for left legs, -1 for right legs (the sign of y).
    pub fn side_sign(self) -> f64 {
        match self {
            Self::FrontLeft | Self::RearLeft => 1.0,
            Self::FrontRight | Self::RearRight => -1.0,
        }
    }

    /// Whether this is a hind (rear) leg.
    pub fn is_hind(self) -> bool {
        matches!(self, Self::RearLeft | Self::RearRight)
    }
}

/// A collision shape's geometry, metres.
#[derive(Debug, Clone, PartialEq)]
pub enum Geometry {
    /// a box
    Box {
        /// half extents along the shape's x, y, z
        half_extents_m: Vector3<f64>,
    },
    /// a sphere
    Sphere {
        /// radius
        radius_m: f64,
    },
    /// a cylinder along the shape's z
    Cylinder {
        /// radius
        radius_m: f64,
        /// half the length
        half_length_m: f64,
    },
    /// a capsule along the shape's z (cylinder part of length 2 half_length)
    Capsule {
        /// radius
        radius_m: f64,
        /// half the cylinder part's length
        half_length_m: f64,
    },
    /// the convex hull of a mesh's vertices
    ConvexHull {
        /// vertices, scaled
        points_m: Vec<Vector3<f64>>,
    },
}

/// A collision shape attached to a body.
#[derive(Debug, Clone, PartialEq)]
pub struct CollisionShape {
    /// the shape's frame in the body frame
    pub shape_in_body: Isometry3<f64>,
    /// its geometry
    pub geometry: Geometry,
    /// the URDF link it came from
    pub link: String,
    /// the URDF collision element's name, if any
    pub name: Option<String>,
    /// whether it is part of a foot (any shape of a leg's last body)
    pub is_foot: bool,
}

/// A rigid body: one URDF link plus the links fixed to it.
#[derive(Debug, Clone)]
pub struct Body {
    /// name of the main link
    pub name: String,
    /// mass, kg
    pub mass_kg: f64,
    /// centre of mass in the body frame, m
    pub com_in_body_m: Vector3<f64>,
    /// inertia about the centre of mass, body-frame axes, kg m^2
    pub inertia_kg_m2: Matrix3<f64>,
    /// collision shapes
    pub collisions: Vec<CollisionShape>,
    /// the actuated joint whose child this body is (`None` for the root)
    pub parent_joint: Option<usize>,
}

/// An actuated revolute joint.
#[derive(Debug, Clone)]
pub struct Joint {
    /// URDF name
    pub name: String,
    /// parent body index
    pub parent: usize,
    /// child body index
    pub child: usize,
    /// the child body frame in the parent body frame at q = 0
    pub child_in_parent: Isometry3<f64>,
    /// rotation axis in the child frame (positive q turns the child about it)
    pub axis_in_child: Unit<Vector3<f64>>,
    /// position limits, rad (`None`: continuous)
    pub limits_rad: Option<(f64, f64)>,
    /// torque limit, N m
    pub effort_n_m: f64,
}

/// One leg: its three joints (abduction, hip pitch, knee) and its foot.
#[derive(Debug, Clone)]
pub struct Leg {
    /// which leg
    pub name: LegName,
    /// indices into [`RobotModel::joints`]: abduction, hip, knee
    pub joints: [usize; 3],
    /// the body carrying the foot
    pub foot_body: usize,
    /// the foot sphere's centre in the foot body's frame, m
    pub foot_in_body_m: Vector3<f64>,
    /// the foot sphere's radius, m
    pub foot_radius_m: f64,
}

/// A quadruped: bodies, 12 actuated joints in leg order (FR, FL, RR, RL;
/// abduction, hip, knee each), and its legs.
#[derive(Debug, Clone)]
pub struct RobotModel {
    /// the URDF's robot name
    pub name: String,
    /// bodies; index 0 is the root (base)
    pub bodies: Vec<Body>,
    /// actuated joints, in leg order
    pub joints: Vec<Joint>,
    /// legs, in [`LegName::ALL`] order
    pub legs: [Leg; 4],
}

impl RobotModel {
    /// The built-in Laikago.
    pub fn laikago() -> Self {
        Self::from_urdf_str(LAIKAGO_URDF, Path::new("<built-in laikago.urdf>"), None)
            .expect("the built-in Laikago description is valid")
    }

    /// Loads a URDF file; meshes are looked up beside it.
    pub fn from_urdf_file(path: &Path) -> Result<Self, ModelError> {
        let text = std::fs::read_to_string(path).map_err(|source| ModelError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_urdf_str(&text, path, path.parent())
    }

    /// Parses URDF text. `path` names the source in errors; `mesh_dir` is
    /// where relative mesh file names are resolved (`None`: meshes refused).
    pub fn from_urdf_str(
        text: &str,
        path: &Path,
        mesh_dir: Option<&Path>,
    ) -> Result<Self, ModelError> {
        let structure = |message: String| ModelError::Structure {
            path: path.to_path_buf(),
            message,
        };
        let urdf = urdf_rs::read_from_string(text).map_err(|e| ModelError::Parse {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        if urdf.links.is_empty() {
            return Err(structure("has no links".to_string()));
        }

        // The root: the one link that is no joint's child.
        let is_child = |name: &str| urdf.joints.iter().any(|j| j.child.link == name);
        let roots: Vec<&urdf_rs::Link> = urdf.links.iter().filter(|l| !is_child(&l.name)).collect();
        if roots.len() != 1 {
            let names: Vec<&str> = roots.iter().map(|l| l.name.as_str()).collect();
            return Err(structure(format!(
                "needs exactly one root link, found {}: {names:?}",
                roots.len()
            )));
        }
        for joint in &urdf.joints {
            for end in [&joint.parent.link, &joint.child.link] {
                if !urdf.links.iter().any(|l| &l.name == end) {
                    return Err(structure(format!(
                        "joint {} names a link {end:?} that does not exist",
                        joint.name
                    )));
                }
            }
        }

        // Walk the tree from the root, merging fixed children into their parent body.
        let mut bodies: Vec<Body> = Vec::new();
        let mut joints: Vec<Joint> = Vec::new();
        // (link name, body index, link frame in body frame)
        let mut stack: Vec<(String, usize, Isometry3<f64>)> = Vec::new();
        let root = roots[0];
        bodies.push(empty_body(&root.name, None));
        stack.push((root.name.clone(), 0, Isometry3::identity()));
        let mut visited = 0usize;
        while let Some((link_name, body, link_in_body)) = stack.pop() {
            visited += 1;
            if visited > urdf.links.len() {
                return Err(structure("its joints form a loop".to_string()));
            }
            let link = urdf
                .links
                .iter()
                .find(|l| l.name == link_name)
                .expect("checked above");
            add_link(&mut bodies[body], link, &link_in_body, path, mesh_dir)?;
            for joint in urdf.joints.iter().filter(|j| j.parent.link == link_name) {
                let origin = pose(&joint.origin);
                match joint.joint_type {
                    urdf_rs::JointType::Fixed => {
                        stack.push((joint.child.link.clone(), body, link_in_body * origin))
                    }
                    urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => {
                        let axis = Vector3::from(*joint.axis.xyz);
                        let axis = Unit::try_new(axis, 1e-9).ok_or_else(|| {
                            structure(format!("joint {} has a zero axis", joint.name))
                        })?;
                        let limits_rad = (joint.joint_type == urdf_rs::JointType::Revolute
                            && joint.limit.lower.is_finite()
                            && joint.limit.upper.is_finite()
                            && joint.limit.lower < joint.limit.upper)
                            .then_some((joint.limit.lower, joint.limit.upper));
                        let effort_n_m = if joint.limit.effort > 0.0 {
                            joint.limit.effort
                        } else {
                            f64::INFINITY
                        };
                        let child = bodies.len();
                        bodies.push(empty_body(&joint.child.link, Some(joints.len())));
                        joints.push(Joint {
                            name: joint.name.clone(),
                            parent: body,
                            child,
                            child_in_parent: link_in_body * origin,
                            axis_in_child: axis,
                            limits_rad,
                            effort_n_m,
                        });
                        stack.push((joint.child.link.clone(), child, Isometry3::identity()));
                    }
                    ref other => {
                        return Err(structure(format!(
                            "joint {} is {other:?}; only revolute, continuous and fixed joints are supported",
                            joint.name
                        )));
                    }
                }
            }
        }
        for body in &mut bodies {
            if body.mass_kg <= 0.0 {
                return Err(structure(format!(
                    "link {} (with the links fixed to it) has no mass",
                    body.name
                )));
            }
            if body.inertia_kg_m2.iter().all(|v| *v == 0.0) {
                // No inertia given: treat the body as a solid sphere of 5 cm radius.
                let i = 0.4 * body.mass_kg * 0.05 * 0.05;
                body.inertia_kg_m2 = Matrix3::from_diagonal_element(i);
            }
        }

        let legs = find_legs(&bodies, &joints).map_err(structure)?;
        // Re-order joints by leg (FR, FL, RR, RL; abduction, hip, knee).
        let order: Vec<usize> = legs.iter().flat_map(|l| l.joints).collect();
        let mut new_index = vec![0; joints.len()];
        for (new, &old) in order.iter().enumerate() {
            new_index[old] = new;
        }
        let joints: Vec<Joint> = order.iter().map(|&old| joints[old].clone()).collect();
        for body in &mut bodies {
            body.parent_joint = body.parent_joint.map(|j| new_index[j]);
        }
        let mut legs = legs;
        for leg in &mut legs {
            leg.joints = leg.joints.map(|j| new_index[j]);
            for shape in &mut bodies[leg.foot_body].collisions {
                shape.is_foot = true;
            }
        }
        Ok(Self {
            name: urdf.name.clone(),
            bodies,
            joints,
            legs,
        })
    }

    /// Total mass, kg.
    pub fn total_mass_kg(&self) -> f64 {
        self.bodies.iter().map(|b| b.mass_kg).sum()
    }

    /// Each body's frame in the base frame for joint positions `q_rad`
    /// (in joint order).
    pub fn body_poses_in_base(&self, q_rad: &[f64]) -> Vec<Isometry3<f64>> {
        let mut poses = vec![Isometry3::identity(); self.bodies.len()];
        // Bodies are created parent-first, so one pass suffices.
        for (i, body) in self.bodies.iter().enumerate() {
            if let Some(j) = body.parent_joint {
                let joint = &self.joints[j];
                let rotation = UnitQuaternion::from_axis_angle(&joint.axis_in_child, q_rad[j]);
                poses[i] = poses[joint.parent] * joint.child_in_parent * rotation;
            }
        }
        poses
    }

    /// Foot (toe sphere centre) positions in the base frame for `q_rad`.
    pub fn feet_in_base_m(&self, q_rad: &[f64]) -> [Vector3<f64>; 4] {
        let poses = self.body_poses_in_base(q_rad);
        self.legs
            .clone()
            .map(|leg| poses[leg.foot_body] * nalgebra::Point3::from(leg.foot_in_body_m))
            .map(|p| p.coords)
    }

    /// Joint position limits as arrays, rad (infinite where continuous).
    pub fn joint_limits_rad(&self) -> Vec<(f64, f64)> {
        self.joints
            .iter()
            .map(|j| j.limits_rad.unwrap_or((f64::NEG_INFINITY, f64::INFINITY)))
            .collect()
    }
}

fn empty_body(name: &str, parent_joint: Option<usize>) -> Body {
    Body {
        name: name.to_string(),
        mass_kg: 0.0,
        com_in_body_m: Vector3::zeros(),
        inertia_kg_m2: Matrix3::zeros(),
        collisions: Vec::new(),
        parent_joint,
    }
}

fn pose(p: &urdf_rs::Pose) -> Isometry3<f64> {
    let [x, y, z] = *p.xyz;
    let [roll, pitch, yaw] = *p.rpy;
    Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    )
}

/// Adds a link's mass and shapes to a body; `link_in_body` places the link.
fn add_link(
    body: &mut Body,
    link: &urdf_rs::Link,
    link_in_body: &Isometry3<f64>,
    path: &Path,
    mesh_dir: Option<&Path>,
) -> Result<(), ModelError> {
    let inertial = &link.inertial;
    let mass = inertial.mass.value;
    if !mass.is_finite() || mass < 0.0 {
        return Err(ModelError::Structure {
            path: path.to_path_buf(),
            message: format!("link {} has an invalid mass {mass}", link.name),
        });
    }
    if mass > 0.0 {
        let frame = link_in_body * pose(&inertial.origin);
        let i = &inertial.inertia;
        let local = Matrix3::new(
            i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
        );
        let rotation = frame.rotation.to_rotation_matrix();
        let inertia = rotation.matrix() * local * rotation.matrix().transpose();
        let com = frame.translation.vector;
        // Combine about the new centre of mass (parallel axis theorem).
        let total = body.mass_kg + mass;
        let new_com = (body.com_in_body_m * body.mass_kg + com * mass) / total;
        let shift = |m: f64, d: Vector3<f64>| {
            (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * m
        };
        body.inertia_kg_m2 = body.inertia_kg_m2
            + shift(body.mass_kg, body.com_in_body_m - new_com)
            + inertia
            + shift(mass, com - new_com);
        body.com_in_body_m = new_com;
        body.mass_kg = total;
    }
    for collision in &link.collision {
        let shape_in_body = link_in_body * pose(&collision.origin);
        let geometry = match &collision.geometry {
            urdf_rs::Geometry::Box { size } => Geometry::Box {
                half_extents_m: Vector3::from(**size) / 2.0,
            },
            urdf_rs::Geometry::Sphere { radius } => Geometry::Sphere { radius_m: *radius },
            urdf_rs::Geometry::Cylinder { radius, length } => Geometry::Cylinder {
                radius_m: *radius,
                half_length_m: length / 2.0,
            },
            urdf_rs::Geometry::Capsule { radius, length } => Geometry::Capsule {
                radius_m: *radius,
                half_length_m: length / 2.0,
            },
            urdf_rs::Geometry::Mesh { filename, scale } => {
                let scale = scale.map_or(Vector3::repeat(1.0), |s| Vector3::from(*s));
                let points =
                    crate::mesh::load_vertices(filename, mesh_dir).map_err(|(mesh, message)| {
                        ModelError::Mesh {
                            path: path.to_path_buf(),
                            mesh,
                            message,
                        }
                    })?;
                Geometry::ConvexHull {
                    points_m: points
                        .into_iter()
                        .map(|p| p.component_mul(&scale))
                        .collect(),
                }
            }
        };
        let degenerate = match &geometry {
            Geometry::Sphere { radius_m } => *radius_m <= 0.0,
            Geometry::Box { half_extents_m } => half_extents_m.iter().any(|v| *v <= 0.0),
            Geometry::Cylinder {
                radius_m,
                half_length_m,
            }
            | Geometry::Capsule {
                radius_m,
                half_length_m,
            } => *radius_m <= 0.0 || *half_length_m < 0.0,
            Geometry::ConvexHull { points_m } => points_m.len() < 4,
        };
        if !degenerate {
            body.collisions.push(CollisionShape {
                shape_in_body,
                geometry,
                link: link.name.clone(),
                name: collision.name.clone(),
                is_foot: false,
            });
        }
    }
    Ok(())
}

/// Finds the four 3-joint chains from the root to a foot sphere.
fn find_legs(bodies: &[Body], joints: &[Joint]) -> Result<[Leg; 4], String> {
    if joints.len() != 12 {
        return Err(format!(
            "has {} actuated joints; a quadruped here has 12 (3 per leg)",
            joints.len()
        ));
    }
    let model_poses = {
        let mut poses = vec![Isometry3::identity(); bodies.len()];
        for (i, body) in bodies.iter().enumerate() {
            if let Some(j) = body.parent_joint {
                poses[i] = poses[joints[j].parent] * joints[j].child_in_parent;
            }
        }
        poses
    };
    let mut chains = Vec::new();
    for (first, joint) in joints.iter().enumerate().filter(|(_, j)| j.parent == 0) {
        let mut chain = vec![first];
        let mut body = joint.child;
        loop {
            let children: Vec<usize> = joints
                .iter()
                .enumerate()
                .filter(|(_, j)| j.parent == body)
                .map(|(i, _)| i)
                .collect();
            match children.as_slice() {
                [] => break,
                [next] => {
                    chain.push(*next);
                    body = joints[*next].child;
                }
                _ => {
                    return Err(format!(
                        "body {} has {} child joints; legs must be chains",
                        bodies[body].name,
                        children.len()
                    ));
                }
            }
        }
        if chain.len() != 3 {
            return Err(format!(
                "the leg starting at joint {} has {} joints; each leg needs 3 (abduction, hip, knee)",
                joint.name,
                chain.len()
            ));
        }
        // The foot: the sphere on the last body farthest from the knee joint.
        let foot_body = body;
        let foot = bodies[foot_body]
            .collisions
            .iter()
            .filter_map(|c| match c.geometry {
                Geometry::Sphere { radius_m } => {
                    Some((c.shape_in_body.translation.vector, radius_m))
                }
                _ => None,
            })
            .max_by(|a, b| a.0.norm().total_cmp(&b.0.norm()))
            .ok_or_else(|| {
                format!(
                    "the leg ending in body {} has no sphere collision to use as its foot",
                    bodies[foot_body].name
                )
            })?;
        chains.push((chain, foot_body, foot));
    }
    if chains.len() != 4 {
        return Err(format!(
            "has {} legs from the root; a quadruped has 4",
            chains.len()
        ));
    }
    let hip = |c: &(Vec<usize>, usize, (Vector3<f64>, f64))| {
        model_poses[joints[c.0[0]].child].translation.vector
    };
    let mean_x = chains.iter().map(|c| hip(c).x).sum::<f64>() / 4.0;
    let mut legs: [Option<Leg>; 4] = [None, None, None, None];
    for c in &chains {
        let h = hip(c);
        let name = match (h.x > mean_x, h.y > 0.0) {
            (true, false) => LegName::FrontRight,
            (true, true) => LegName::FrontLeft,
            (false, false) => LegName::RearRight,
            (false, true) => LegName::RearLeft,
        };
        if legs[name.index()].is_some() {
            return Err(format!("two legs sit at the {} corner", name.short()));
        }
        legs[name.index()] = Some(Leg {
            name,
            joints: [c.0[0], c.0[1], c.0[2]],
            foot_body: c.1,
            foot_in_body_m: c.2.0,
            foot_radius_m: c.2.1,
        });
    }
    Ok(legs.map(|l| l.expect("four distinct corners")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shared_urdf(name: &str) -> Option<PathBuf> {
        let path = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../shared/robots/laikago")
            .join(name);
        if path.exists() {
            Some(path)
        } else {
            println!(
                "skipped: {} is absent (the shared test data lives beside the checkout)",
                path.display()
            );
            None
        }
    }

    #[test]
    fn built_in_laikago_matches_the_facts() {
        let model = RobotModel::laikago();
        assert!(
            (model.total_mass_kg() - 25.567).abs() < 1e-9,
            "{}",
            model.total_mass_kg()
        );
        assert_eq!(model.joints.len(), 12);
        assert_eq!(model.bodies.len(), 13, "toes merge into the lower legs");
        let feet = model.feet_in_base_m(&[0.0; 12]);
        let expected = [
            [0.0349, -0.1146, -0.4883],
            [0.0349, 0.1169, -0.4883],
            [-0.4024, -0.1146, -0.4883],
            [-0.4024, 0.1169, -0.4883],
        ];
        for (foot, want) in feet.iter().zip(expected) {
            assert!(
                (foot - Vector3::from(want)).norm() < 1e-3,
                "{foot} vs {want:?}"
            );
        }
        for (leg, name) in model.legs.iter().zip(LegName::ALL) {
            assert_eq!(leg.name, name);
            assert_eq!(leg.foot_radius_m, 0.03);
            assert!(model.joints[leg.joints[0]].name.starts_with(name.short()));
            let feet_shapes = model.bodies[leg.foot_body]
                .collisions
                .iter()
                .filter(|c| c.is_foot)
                .count();
            assert_eq!(feet_shapes, 2, "the shank and the toe sphere");
        }
    }

    #[test]
    fn only_the_lower_legs_are_feet() {
        let model = RobotModel::laikago();
        let foot_bodies: Vec<usize> = model.legs.iter().map(|l| l.foot_body).collect();
        for (i, body) in model.bodies.iter().enumerate() {
            let any_foot = body.collisions.iter().any(|c| c.is_foot);
            assert_eq!(any_foot, foot_bodies.contains(&i), "{}", body.name);
        }
    }

    #[test]
    fn third_party_laikago_urdf_agrees_with_the_built_in_model() {
        let Some(path) = shared_urdf("laikago_toes_zup.urdf") else {
            return;
        };
        let theirs = RobotModel::from_urdf_file(&path).unwrap();
        let ours = RobotModel::laikago();
        let mass_ratio = theirs.total_mass_kg() / ours.total_mass_kg();
        assert!(
            (mass_ratio - 1.0).abs() < 0.01,
            "{} kg vs {} kg",
            theirs.total_mass_kg(),
            ours.total_mass_kg()
        );
        let q = [0.0; 12];
        for (a, b) in theirs
            .feet_in_base_m(&q)
            .iter()
            .zip(ours.feet_in_base_m(&q))
        {
            assert!((a - b).norm() < 0.005, "foot {a} vs {b}");
        }
        // Same joint conventions: equal angles give equal feet.
        let q: Vec<f64> = (0..12).map(|i| [0.2, 0.7, -1.4][i % 3]).collect();
        for (a, b) in theirs
            .feet_in_base_m(&q)
            .iter()
            .zip(ours.feet_in_base_m(&q))
        {
            assert!((a - b).norm() < 0.005, "foot {a} vs {b}");
        }
        assert!(
            theirs.bodies[0]
                .collisions
                .iter()
                .any(|c| matches!(c.geometry, Geometry::ConvexHull { .. }))
        );
    }

    #[test]
    fn malformed_descriptions_are_refused_with_the_reason() {
        let path = Path::new("bad.urdf");
        let err = RobotModel::from_urdf_str("<robot name='x'><link", path, None).unwrap_err();
        assert!(matches!(err, ModelError::Parse { .. }), "{err}");
        assert!(
            err.to_string()
                .starts_with("robot description bad.urdf: not valid URDF")
        );

        let one_link = "<robot name='x'><link name='a'><inertial><mass value='1'/><inertia ixx='1' ixy='0' ixz='0' iyy='1' iyz='0' izz='1'/></inertial></link></robot>";
        let err = RobotModel::from_urdf_str(one_link, path, None).unwrap_err();
        assert!(err.to_string().contains("has 0 actuated joints"), "{err}");

        let prismatic = LAIKAGO_URDF.replacen("type=\"revolute\"", "type=\"prismatic\"", 1);
        let err = RobotModel::from_urdf_str(&prismatic, path, None).unwrap_err();
        assert!(
            err.to_string()
                .contains("only revolute, continuous and fixed"),
            "{err}"
        );

        let no_toes = LAIKAGO_URDF.replace(
            "<sphere radius=\"0.03\"/>",
            "<box size=\"0.03 0.03 0.03\"/>",
        );
        let err = RobotModel::from_urdf_str(&no_toes, path, None).unwrap_err();
        assert!(err.to_string().contains("no sphere collision"), "{err}");

        let mesh = LAIKAGO_URDF.replacen(
            "<box size=\"0.577 0.387 0.188\"/>",
            "<mesh filename=\"missing.obj\"/>",
            1,
        );
        let err =
            RobotModel::from_urdf_str(&mesh, path, Some(Path::new("/nonexistent"))).unwrap_err();
        assert!(
            err.to_string().contains("missing.obj: cannot read it"),
            "{err}"
        );

        let err = RobotModel::from_urdf_file(Path::new("/nonexistent/robot.urdf")).unwrap_err();
        assert!(
            err.to_string()
                .starts_with("robot description /nonexistent/robot.urdf: cannot read it"),
            "{err}"
        );
    }
}
