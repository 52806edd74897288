//! `sequence.toml`: what the rest of a sequence is (the only file that names the others).
//!
//! Parsed with serde + `toml`; unknown keys are errors, and so are a wrong `format`, a 4×4
//! that is not a rigid transform, a non-unit initial quaternion, or an empty search box.

use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::Deserialize;

use super::error::{Result, SequenceError, one_line};

/// The format tag this reader accepts.
pub const FORMAT: &str = "evorec-seq/1";

/// Largest deviation of `RᵀR` from `I` (per entry) and of `det R` from 1 accepted in a 4×4.
pub const RIGID_TOLERANCE: f64 = 1e-4;

/// Largest deviation of `|q|` from 1 accepted for `initial_pose.q_xyzw`.
pub const UNIT_QUATERNION_TOLERANCE: f64 = 1e-3;

/// `sequence.toml` as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Must be [`FORMAT`].
    pub format: String,
    /// Free text.
    #[serde(default)]
    pub name: String,
    /// The time origin as a ROS stamp (s since the epoch): `t_s = header.stamp − stamp_origin_s`.
    /// Written by `evorec import`; optional.
    #[serde(default)]
    pub stamp_origin_s: Option<i64>,
    /// `[robot]`.
    pub robot: RobotSection,
    /// `[cameras]`.
    pub cameras: CamerasSection,
    /// `[target]`.
    pub target: TargetSection,
    /// `[search]` (optional).
    pub search: Option<SearchSection>,
}

/// `[robot]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSection {
    /// The URDF, relative to the sequence directory.
    pub urdf: PathBuf,
    /// The link `joints.csv`'s q is measured from.
    pub base_link: String,
    /// The link the camera mount is fixed to.
    pub flange_link: String,
}

/// `[cameras]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CamerasSection {
    /// Left camera_info YAML, relative to the sequence directory.
    pub left: PathBuf,
    /// Right camera_info YAML.
    pub right: PathBuf,
    /// `^CL T_CR`, 4×4 row-major, metres.
    pub right_to_left: [f64; 16],
    /// `^H T_CR`, 4×4 row-major, metres.
    pub flange_to_right: [f64; 16],
}

/// `[target]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TargetSection {
    /// Full edge lengths along x, y, z of `Σ_M` (m).
    pub size_m: [f64; 3],
    /// Hues of faces +x, +y, +z, −x, −y, −z (degrees).
    pub face_hues_deg: [f64; 6],
    /// Pose of the block in the right camera frame at frame 0 (optional).
    pub initial_pose: Option<PoseSection>,
}

/// A pose: translation and quaternion.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseSection {
    /// Translation (m).
    pub t_m: [f64; 3],
    /// Quaternion x, y, z, w.
    pub q_xyzw: [f64; 4],
}

/// `[search]`: the box the block's centre can be in, right camera frame (m).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SearchSection {
    /// Lower corner.
    pub min_m: [f64; 3],
    /// Upper corner.
    pub max_m: [f64; 3],
}

/// `sequence.toml` validated and converted.
#[derive(Debug, Clone)]
pub struct Checked {
    /// The file as written.
    pub raw: Manifest,
    /// `^CL T_CR`.
    pub right_to_left: Isometry3<f64>,
    /// `^H T_CR`.
    pub flange_to_right: Isometry3<f64>,
    /// `^CR T_M` at frame 0, when given.
    pub initial_pose: Option<Isometry3<f64>>,
}

/// Reads and validates `path` (a `sequence.toml`).
///
/// # Errors
/// Missing file, malformed TOML, unknown or missing key, wrong format tag, bad values.
pub fn load(path: &Path) -> Result<Checked> {
    let text = std::fs::read_to_string(path).map_err(|e| SequenceError::file(path, format!("cannot read: {e}")))?;
    parse(&text, path)
}

/// Parses and validates the text of a `sequence.toml` (`path` only names it in errors).
///
/// # Errors
/// As [`load`].
pub fn parse(text: &str, path: &Path) -> Result<Checked> {
    let raw: Manifest = toml::from_str(text).map_err(|e| {
        let err = SequenceError::file(path, one_line(e.message()));
        match e.span() {
            Some(span) => err.at_line(line_of(text, span.start)),
            None => err,
        }
    })?;
    let bad = |field: &str, msg: String| SequenceError::file(path, msg).in_field(field);
    if raw.format != FORMAT {
        return Err(bad("format", format!("expected \"{FORMAT}\", got \"{}\"", raw.format)));
    }
    let right_to_left = rigid(&raw.cameras.right_to_left).map_err(|m| bad("cameras.right_to_left", m))?;
    let flange_to_right = rigid(&raw.cameras.flange_to_right).map_err(|m| bad("cameras.flange_to_right", m))?;
    for (i, s) in raw.target.size_m.iter().enumerate() {
        if !(s.is_finite() && *s > 0.0 && *s <= 2.0) {
            return Err(bad(&format!("target.size_m[{i}]"), format!("must be in (0, 2] m, got {s}")));
        }
    }
    for (i, h) in raw.target.face_hues_deg.iter().enumerate() {
        if !(h.is_finite() && (0.0..360.0).contains(h)) {
            return Err(bad(&format!("target.face_hues_deg[{i}]"), format!("must be in [0, 360), got {h}")));
        }
    }
    let initial_pose = match &raw.target.initial_pose {
        Some(p) => Some(pose(p).map_err(|m| bad("target.initial_pose", m))?),
        None => None,
    };
    if let Some(s) = &raw.search {
        for i in 0..3 {
            let (lo, hi) = (s.min_m[i], s.max_m[i]);
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(bad("search", format!("min_m[{i}] = {lo} must be finite and below max_m[{i}] = {hi}")));
            }
        }
        if let Some(p) = &initial_pose {
            let t = p.translation.vector;
            if (0..3).any(|i| t[i] < s.min_m[i] || t[i] > s.max_m[i]) {
                return Err(bad("target.initial_pose", format!("t_m = {:?} is outside [search]", t.as_slice())));
            }
        }
    }
    Ok(Checked { raw, right_to_left, flange_to_right, initial_pose })
}

/// 1-based line of byte offset `at` in `text`.
pub fn line_of(text: &str, at: usize) -> u64 {
    text.as_bytes().iter().take(at).filter(|b| **b == b'\n').count() as u64 + 1
}

/// A rigid transform from a row-major 4×4; a message when it is not one.
///
/// # Errors
/// Non-finite entries, a last row other than `[0 0 0 1]`, `RᵀR ≠ I` or `det R ≠ 1` beyond
/// [`RIGID_TOLERANCE`].
pub fn rigid(m: &[f64; 16]) -> std::result::Result<Isometry3<f64>, String> {
    if let Some(i) = m.iter().position(|v| !v.is_finite()) {
        return Err(format!("entry {i} is not finite"));
    }
    if m[12..] != [0.0, 0.0, 0.0, 1.0] {
        return Err(format!("last row must be [0, 0, 0, 1], got {:?}", &m[12..]));
    }
    let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
    let err = (r.transpose() * r - Matrix3::identity()).abs().max();
    let det = r.determinant();
    if err > RIGID_TOLERANCE || (det - 1.0).abs() > RIGID_TOLERANCE {
        return Err(format!(
            "not a rigid transform: max |RᵀR − I| = {err:.2e}, det R = {det:.6} (tolerance {RIGID_TOLERANCE:e})"
        ));
    }
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    Ok(Isometry3::from_parts(Translation3::new(m[3], m[7], m[11]), q))
}

/// The row-major 4×4 of an isometry (for writers).
pub fn to_rows(iso: &Isometry3<f64>) -> [f64; 16] {
    let h = iso.to_homogeneous();
    std::array::from_fn(|i| h[(i / 4, i % 4)])
}

fn pose(p: &PoseSection) -> std::result::Result<Isometry3<f64>, String> {
    if !p.t_m.iter().chain(p.q_xyzw.iter()).all(|v| v.is_finite()) {
        return Err("values must be finite".to_owned());
    }
    let [x, y, z, w] = p.q_xyzw;
    let q = Quaternion::new(w, x, y, z);
    let norm = q.norm();
    if (norm - 1.0).abs() > UNIT_QUATERNION_TOLERANCE {
        return Err(format!("q_xyzw must be a unit quaternion, |q| = {norm}"));
    }
    Ok(Isometry3::from_parts(Vector3::from(p.t_m).into(), UnitQuaternion::from_quaternion(q)))
}
