//! Serial arms from URDF: the chain of joints from a base link to a flange link, as the core's
//! [`Chain`].
//!
//! The file is parsed with the `urdf-rs` crate; [`ArmModel`] walks the kinematic tree from
//! the flange link up to the base link, folds fixed joints into the next movable joint's origin
//! (or the tip transform), and accepts revolute, continuous (no limits) and prismatic joints.
//! Anything else on the chain (floating, planar, spherical joints), a missing link, a flange
//! that is not below the base, a non-unit axis, non-finite numbers or unordered limits is one
//! [`RobotError`] naming the file, the joint or link and what is wrong. Transforms are composed
//! in `f64` and rounded to `f32` once.

use std::path::Path;

use evorec_core::kinematics::{AXIS_TOLERANCE, Chain, ChainError, ChainPart, Frame, JointKind, JointSpec};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// The PA-10 as a URDF, written from its DH table (`robots/pa10.urdf`).
pub const PA10_URDF: &str = include_str!("../../../robots/pa10.urdf");
/// Base link of [`PA10_URDF`].
pub const PA10_BASE_LINK: &str = "base_link";
/// Flange link of [`PA10_URDF`].
pub const PA10_FLANGE_LINK: &str = "flange_link";

/// Why a URDF could not be turned into an arm; every message starts with the file's name.
#[derive(Debug, thiserror::Error)]
pub enum RobotError {
    /// The file could not be read.
    #[error("{file}: cannot read: {error}")]
    Read {
        /// The file.
        file: String,
        /// The I/O error.
        error: std::io::Error,
    },
    /// Not a URDF `urdf-rs` can parse.
    #[error("{file}: not a valid URDF: {message}")]
    Parse {
        /// The file.
        file: String,
        /// The parser's message.
        message: String,
    },
    /// A link named as base or flange (or as a joint's parent) does not exist.
    #[error("{file}: link '{link}' does not exist")]
    MissingLink {
        /// The file.
        file: String,
        /// The missing link.
        link: String,
    },
    /// The flange link is not below the base link in the tree, or the tree is not a tree.
    #[error("{file}: link '{link}': {problem}")]
    Link {
        /// The file.
        file: String,
        /// The link.
        link: String,
        /// What is wrong.
        problem: String,
    },
    /// A joint on the chain is not usable.
    #[error("{file}: joint '{joint}': {problem}")]
    Joint {
        /// The file.
        file: String,
        /// The joint.
        joint: String,
        /// What is wrong.
        problem: String,
    },
    /// The chain has a different number of movable joints than asked for.
    #[error("{file}: the chain from '{base}' to '{flange}' has {found} movable joints, {wanted} are needed")]
    Dof {
        /// The file.
        file: String,
        /// Base link.
        base: String,
        /// Flange link.
        flange: String,
        /// Movable joints on the chain.
        found: usize,
        /// Joints the caller needs.
        wanted: usize,
    },
}

/// One movable joint of the chain, fixed joints before it folded into its origin.
#[derive(Debug, Clone, PartialEq)]
struct ModelJoint {
    origin: Isometry3<f64>,
    axis: Vector3<f64>,
    kind: JointKind,
    limits: (f64, f64),
}

/// The serial chain of a URDF from a base link to a flange link.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmModel {
    /// Names of the movable joints, base to flange (the order of `q`).
    pub joint_names: Vec<String>,
    joints: Vec<ModelJoint>,
    tip: Isometry3<f64>,
    file: String,
    base: String,
    flange: String,
}

impl ArmModel {
    /// Reads a URDF file and extracts the chain from `base_link` to `flange_link`.
    ///
    /// # Errors
    /// [`RobotError`] naming the file and the joint or link at fault.
    pub fn from_urdf_file(path: impl AsRef<Path>, base_link: &str, flange_link: &str) -> Result<Self, RobotError> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| RobotError::Read { file: file.clone(), error })?;
        Self::from_urdf_str(&text, base_link, flange_link, &file)
    }

    /// Parses URDF text; `source_name` names it in errors (e.g. the file's path).
    ///
    /// # Errors
    /// [`RobotError`] naming `source_name` and the joint or link at fault.
    pub fn from_urdf_str(
        text: &str,
        base_link: &str,
        flange_link: &str,
        source_name: &str,
    ) -> Result<Self, RobotError> {
        let file = source_name.to_string();
        let robot = urdf_rs::read_from_string(text).map_err(|e| RobotError::Parse {
            file: file.clone(),
            message: crate::recording::text::one_line(&e.to_string()),
        })?;
        plain_names(&robot, &file)?;
        let path = chain_joints(&robot, base_link, flange_link, &file)?;
        let mut joint_names = Vec::new();
        let mut joints = Vec::new();
        let mut pending = Isometry3::identity();
        for joint in path {
            let err = |problem: String| RobotError::Joint { file: file.clone(), joint: joint.name.clone(), problem };
            let origin = pending * pose(&joint.origin).map_err(err)?;
            let kind = match joint.joint_type {
                urdf_rs::JointType::Fixed => {
                    pending = origin;
                    continue;
                }
                urdf_rs::JointType::Revolute | urdf_rs::JointType::Continuous => JointKind::Revolute,
                urdf_rs::JointType::Prismatic => JointKind::Prismatic,
                ref other => {
                    let name = format!("{other:?}").to_lowercase();
                    return Err(err(format!(
                        "type {name} is not supported (revolute, continuous, prismatic and fixed are)"
                    )));
                }
            };
            let limits = match joint.joint_type {
                urdf_rs::JointType::Continuous => (f64::NEG_INFINITY, f64::INFINITY),
                _ => limits(&joint.limit).map_err(err)?,
            };
            joints.push(ModelJoint { origin, axis: unit_axis(&joint.axis.xyz).map_err(err)?, kind, limits });
            joint_names.push(joint.name.clone());
            pending = Isometry3::identity();
        }
        Ok(Self { joint_names, joints, tip: pending, file, base: base_link.into(), flange: flange_link.into() })
    }

    /// Number of movable joints on the chain.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// The core chain (validated by [`Chain::new_checked`]).
    ///
    /// # Errors
    /// [`RobotError::Dof`] when the chain has not `DOF` movable joints, [`RobotError::Joint`]
    /// when the rounded chain fails the core's checks.
    pub fn to_chain<const DOF: usize>(&self) -> Result<Chain<DOF>, RobotError> {
        let specs: Vec<JointSpec> = self
            .joints
            .iter()
            .map(|j| JointSpec {
                origin: frame_f32(&j.origin),
                axis: [j.axis.x as f32, j.axis.y as f32, j.axis.z as f32],
                kind: j.kind,
                q_min: j.limits.0 as f32,
                q_max: j.limits.1 as f32,
            })
            .collect();
        let specs: [JointSpec; DOF] = specs.try_into().map_err(|_| RobotError::Dof {
            file: self.file.clone(),
            base: self.base.clone(),
            flange: self.flange.clone(),
            found: self.dof(),
            wanted: DOF,
        })?;
        Chain::new_checked(&specs, &frame_f32(&self.tip)).map_err(|e| self.chain_error(e))
    }

    fn chain_error(&self, e: ChainError) -> RobotError {
        let part = match e {
            ChainError::NotFinite(p) | ChainError::NotRigid(p) => p,
            ChainError::AxisNotUnit(i) | ChainError::LimitsNotOrdered(i) => ChainPart::Joint(i),
        };
        let joint = match part {
            ChainPart::Joint(i) => self.joint_names.get(i).cloned().unwrap_or_default(),
            ChainPart::Tip => format!("(fixed joints to '{}')", self.flange),
        };
        RobotError::Joint { file: self.file.clone(), joint, problem: format!("in f32: {e}") }
    }
}

/// Refuses link and joint names with control characters (a name with a line break would
/// split every later message that quotes it).
fn plain_names(robot: &urdf_rs::Robot, file: &str) -> Result<(), RobotError> {
    let bad = |name: &str| name.chars().any(char::is_control);
    if let Some(l) = robot.links.iter().find(|l| bad(&l.name)) {
        let link = l.name.escape_debug().to_string();
        return Err(RobotError::Link { file: file.into(), link, problem: "name holds a control character".into() });
    }
    if let Some(j) = robot.joints.iter().find(|j| bad(&j.name)) {
        let joint = j.name.escape_debug().to_string();
        return Err(RobotError::Joint { file: file.into(), joint, problem: "name holds a control character".into() });
    }
    if let Some(j) = robot.joints.iter().find(|j| bad(&j.parent.link) || bad(&j.child.link)) {
        let joint = j.name.clone();
        let problem = "parent or child link name holds a control character".into();
        return Err(RobotError::Joint { file: file.into(), joint, problem });
    }
    Ok(())
}

/// The joints from `base` down to `flange`, in that order.
fn chain_joints<'a>(
    robot: &'a urdf_rs::Robot,
    base: &str,
    flange: &str,
    file: &str,
) -> Result<Vec<&'a urdf_rs::Joint>, RobotError> {
    for link in [base, flange] {
        if !robot.links.iter().any(|l| l.name == link) {
            return Err(RobotError::MissingLink { file: file.into(), link: link.into() });
        }
    }
    let mut path = Vec::new();
    let mut link = flange;
    while link != base {
        let mut parents = robot.joints.iter().filter(|j| j.child.link == link);
        let Some(joint) = parents.next() else {
            return Err(RobotError::Link {
                file: file.into(),
                link: flange.into(),
                problem: format!("is not below '{base}' (walking up from it ends at '{link}')"),
            });
        };
        if let Some(other) = parents.next() {
            return Err(RobotError::Link {
                file: file.into(),
                link: link.into(),
                problem: format!("is the child of two joints ('{}' and '{}')", joint.name, other.name),
            });
        }
        if path.len() >= robot.joints.len() {
            return Err(RobotError::Link {
                file: file.into(),
                link: link.into(),
                problem: "lies on a cycle of joints".into(),
            });
        }
        path.push(joint);
        link = &joint.parent.link;
    }
    path.reverse();
    Ok(path)
}

/// `Trans(xyz) · Rz(yaw) · Ry(pitch) · Rx(roll)` of a URDF `<origin>`.
fn pose(p: &urdf_rs::Pose) -> Result<Isometry3<f64>, String> {
    let (xyz, rpy) = (p.xyz.0, p.rpy.0);
    if !xyz.iter().chain(rpy.iter()).all(|v| v.is_finite()) {
        return Err(format!("origin xyz {} rpy {} is not finite", triple(&xyz), triple(&rpy)));
    }
    let r = Rotation3::from_euler_angles(rpy[0], rpy[1], rpy[2]);
    Ok(Isometry3::from_parts(Translation3::from(Vector3::from(xyz)), UnitQuaternion::from_rotation_matrix(&r)))
}

/// The axis, normalised when its length is 1 within the core's tolerance.
fn unit_axis(v: &urdf_rs::Vec3) -> Result<Vector3<f64>, String> {
    let a = Vector3::from(v.0);
    let n = a.norm();
    if n.is_finite() && (n - 1.0).abs() <= f64::from(AXIS_TOLERANCE) {
        Ok(a / n)
    } else {
        Err(format!("axis {} is not a unit vector", triple(&v.0)))
    }
}

/// `(lower, upper)` of a revolute or prismatic joint.
fn limits(l: &urdf_rs::JointLimit) -> Result<(f64, f64), String> {
    if l.lower.is_nan() || l.upper.is_nan() || l.lower >= l.upper {
        return Err(format!(
            "limits lower {} upper {} are not an interval (is <limit lower=.. upper=..> missing?)",
            l.lower, l.upper
        ));
    }
    Ok((l.lower, l.upper))
}

fn triple(v: &[f64; 3]) -> String {
    format!("({}, {}, {})", v[0], v[1], v[2])
}

/// An `f64` isometry rounded to the core's frame.
fn frame_f32(iso: &Isometry3<f64>) -> Frame {
    let r: Matrix3<f32> = iso.rotation.to_rotation_matrix().into_inner().cast();
    Frame::from_parts(&r, &iso.translation.vector.cast())
}
