//! The arm carrying the cameras, from the sequence's URDF (`base_link` → `flange_link`).
//!
//! INTERIM: until the URDF loader (`crate::robot::ArmModel`) lands, this module reads the
//! chain's movable joint names with `urdf-rs` so that `joints.csv` can be checked, and
//! [`Robot::chain`] reports that URDF kinematics are not available yet.

use std::path::Path;

use evorec_core::kinematics::Chain;

use super::error::{Result, SequenceError};

/// The arm of a sequence.
#[derive(Debug, Clone)]
pub struct Robot {
    /// Movable joints on the chain, base to flange.
    pub joint_names: Vec<String>,
}

impl Robot {
    /// Reads the URDF at `path` and finds the chain from `base` to `flange`.
    ///
    /// # Errors
    /// Missing or malformed URDF, unknown links, no chain between them.
    pub fn load(path: &Path, base: &str, flange: &str) -> Result<Self> {
        let robot = urdf_rs::read_file(path).map_err(|e| SequenceError::file(path, format!("bad URDF: {e}")))?;
        let mut names = Vec::new();
        let mut link = flange.to_owned();
        while link != base {
            let Some(j) = robot.joints.iter().find(|j| j.child.link == link) else {
                return Err(SequenceError::file(
                    path,
                    format!("no chain of joints from link \"{base}\" to \"{flange}\""),
                ));
            };
            if !matches!(j.joint_type, urdf_rs::JointType::Fixed) {
                names.push(j.name.clone());
            }
            link.clone_from(&j.parent.link);
        }
        names.reverse();
        Ok(Self { joint_names: names })
    }

    /// Number of movable joints.
    pub fn dof(&self) -> usize {
        self.joint_names.len()
    }

    /// The core chain of this arm.
    ///
    /// # Errors
    /// Always, until the URDF loader lands.
    pub fn chain<const DOF: usize>(&self) -> anyhow::Result<Chain<DOF>> {
        anyhow::bail!("URDF kinematics are not available yet (waiting for the URDF loader)")
    }
}
