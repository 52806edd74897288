//! The arm carrying the cameras, from the sequence's URDF (`base_link` → `flange_link`),
//! through [`crate::recording::robot::ArmModel`].

use std::path::Path;

use evorec_core::kinematics::Chain;

use super::error::{Result, SequenceError};
use crate::recording::robot::ArmModel;

/// The arm of a sequence.
#[derive(Debug, Clone)]
pub struct Robot {
    /// Movable joints on the chain, base to flange (the order of `q`).
    pub joint_names: Vec<String>,
    model: ArmModel,
}

impl Robot {
    /// Reads the URDF at `path` and extracts the chain from `base` to `flange`.
    ///
    /// # Errors
    /// Missing or malformed URDF, unknown links, no chain between them, unusable joints.
    pub fn load(path: &Path, base: &str, flange: &str) -> Result<Self> {
        let model = ArmModel::from_urdf_file(path, base, flange).map_err(|e| {
            // The loader's messages start with the file's name; keep it once.
            let text = e.to_string();
            let prefix = format!("{}: ", path.display());
            SequenceError::file(path, text.strip_prefix(&prefix).unwrap_or(&text))
        })?;
        Ok(Self { joint_names: model.joint_names.clone(), model })
    }

    /// Parses URDF `text` (`path` names it in errors) and extracts the chain.
    ///
    /// # Errors
    /// As [`Robot::load`].
    pub fn from_urdf_str(text: &str, base: &str, flange: &str, path: &Path) -> Result<Self> {
        let name = path.display().to_string();
        let model = ArmModel::from_urdf_str(text, base, flange, &name).map_err(|e| {
            let text = e.to_string();
            let prefix = format!("{name}: ");
            SequenceError::file(path, text.strip_prefix(&prefix).unwrap_or(&text))
        })?;
        Ok(Self { joint_names: model.joint_names.clone(), model })
    }

    /// Number of movable joints.
    pub fn dof(&self) -> usize {
        self.joint_names.len()
    }

    /// The core chain of this arm.
    ///
    /// # Errors
    /// A chain whose joint count is not `DOF` or that the core refuses.
    pub fn chain<const DOF: usize>(&self) -> anyhow::Result<Chain<DOF>> {
        Ok(self.model.to_chain::<DOF>()?)
    }
}
