//! ROS `camera_info` YAML (what ROS's `camera_calibration` writes) and its conversion to the
//! core's [`Pinhole`].
//!
//! ## Pixel convention
//! camera_info (and OpenCV) put the **centre** of the top-left pixel at `(0, 0)`; the core
//! puts its top-left **corner** there (pixel `(i, j)` covers `[i, i+1) × [j, j+1)`, see
//! `evorec_core::camera`). So a point at camera_info pixel `(u, v)` is at core pixel
//! `(u + ½, v + ½)`: [`to_pinhole`] adds ½ to `cx` and `cy`, and [`from_pinhole`] takes it off
//! (both tested).
//!
//! `rectification_matrix` and `projection_matrix` are read and checked for shape but not used:
//! evorec matches its model against the raw images with `K` and `D`.

use std::path::Path;

use evorec_core::camera::{Distortion, Pinhole};
use serde::{Deserialize, Serialize};

use super::error::{Result, SequenceError, one_line};

/// A `rows × cols` matrix as camera_info writes it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct YamlMatrix {
    /// Rows.
    pub rows: usize,
    /// Columns.
    pub cols: usize,
    /// Row-major entries.
    pub data: Vec<f64>,
}

/// A camera_info YAML file (other keys are ignored, as ROS's own reader does).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CameraInfo {
    /// Image width (pixels).
    pub image_width: u32,
    /// Image height (pixels).
    pub image_height: u32,
    /// Free text.
    #[serde(default)]
    pub camera_name: String,
    /// `K`, 3×3.
    pub camera_matrix: YamlMatrix,
    /// `plumb_bob` (OpenCV's k1, k2, p1, p2, k3).
    pub distortion_model: String,
    /// `D`.
    pub distortion_coefficients: YamlMatrix,
    /// `R`, 3×3 (not used).
    pub rectification_matrix: YamlMatrix,
    /// `P`, 3×4 (not used).
    pub projection_matrix: YamlMatrix,
}

/// Reads, parses and converts a camera_info YAML file.
///
/// # Errors
/// Missing file, malformed YAML, bad shapes or values, unsupported distortion.
pub fn load(path: &Path) -> Result<(CameraInfo, Pinhole)> {
    let text = std::fs::read_to_string(path).map_err(|e| SequenceError::file(path, format!("cannot read: {e}")))?;
    parse(&text, path)
}

/// Parses and converts camera_info YAML text (`path` only names it in errors).
///
/// # Errors
/// As [`load`].
pub fn parse(text: &str, path: &Path) -> Result<(CameraInfo, Pinhole)> {
    let info: CameraInfo = serde_saphyr::from_str(text).map_err(|e| {
        let err = SequenceError::file(path, first_line(&e.to_string()));
        match e.location() {
            Some(loc) if loc.line() > 0 => err.at_line(loc.line()),
            _ => err,
        }
    })?;
    let cam = to_pinhole(&info).map_err(|(field, msg)| SequenceError::file(path, msg).in_field(field))?;
    Ok((info, cam))
}

fn first_line(text: &str) -> String {
    one_line(text.lines().find(|l| !l.trim().is_empty()).unwrap_or(text))
}

/// The core camera of a camera_info (`cx`, `cy` shifted by +½ pixel, see the module docs).
///
/// # Errors
/// `(field, message)` for a bad shape, a non-finite or non-positive focal length, skew, a size
/// the core does not take, or a distortion model other than plumb_bob with 5 coefficients.
pub fn to_pinhole(info: &CameraInfo) -> std::result::Result<Pinhole, (&'static str, String)> {
    shape(&info.camera_matrix, 3, 3).map_err(|m| ("camera_matrix", m))?;
    shape(&info.rectification_matrix, 3, 3).map_err(|m| ("rectification_matrix", m))?;
    shape(&info.projection_matrix, 3, 4).map_err(|m| ("projection_matrix", m))?;
    let k = &info.camera_matrix.data;
    if k[1] != 0.0 || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0 {
        return Err(("camera_matrix", format!("must be [fx 0 cx; 0 fy cy; 0 0 1] (no skew), got {k:?}")));
    }
    let lens = distortion(info)?;
    let (w, h) = (u16::try_from(info.image_width), u16::try_from(info.image_height));
    let (Ok(w), Ok(h)) = (w, h) else {
        return Err(("image_width", format!("{}x{} is too large", info.image_width, info.image_height)));
    };
    let (fx, fy, cx, cy) = (k[0] as f32, k[4] as f32, k[2] as f32, k[5] as f32);
    let cam = Pinhole::from_opencv(fx, fy, cx, cy, w, h).map_err(|e| ("camera_matrix", e.to_string()))?;
    Ok(cam.with_distortion(lens))
}

/// The lens distortion of a camera_info: OpenCV's plumb_bob `D = [k1, k2, p1, p2, k3]` (an empty
/// `D` means none). The core applies it when it projects the model, so raw images are matched.
fn distortion(info: &CameraInfo) -> std::result::Result<Distortion, (&'static str, String)> {
    let d = &info.distortion_coefficients;
    if info.distortion_model != "plumb_bob" {
        return Err(("distortion_model", format!("\"{}\" is not supported (only plumb_bob)", info.distortion_model)));
    }
    if d.data.len() != d.rows * d.cols || !(d.data.len() == 5 || d.data.is_empty()) {
        return Err(("distortion_coefficients", format!("expected 5 values (k1 k2 p1 p2 k3), got {}", d.data.len())));
    }
    let mut k = [0.0f32; 5];
    for (dst, src) in k.iter_mut().zip(d.data.iter()) {
        *dst = *src as f32;
    }
    Distortion::plumb_bob(k).map_err(|e| ("distortion_coefficients", e.to_string()))
}

fn shape(m: &YamlMatrix, rows: usize, cols: usize) -> std::result::Result<(), String> {
    if m.rows != rows || m.cols != cols || m.data.len() != rows * cols {
        return Err(format!(
            "expected {rows}x{cols} with {} values, got {}x{} with {}",
            rows * cols,
            m.rows,
            m.cols,
            m.data.len()
        ));
    }
    if let Some(i) = m.data.iter().position(|v| !v.is_finite()) {
        return Err(format!("data[{i}] is not finite"));
    }
    Ok(())
}

/// The camera_info of a core camera (inverse of [`to_pinhole`], D = 0, R = I, P = [K | 0]).
pub fn from_pinhole(cam: &Pinhole, name: &str) -> CameraInfo {
    let (fx, fy) = (f64::from(cam.fx()), f64::from(cam.fy()));
    let (cx, cy) = (f64::from(cam.cx()) - 0.5, f64::from(cam.cy()) - 0.5);
    let m = |rows, cols, data: Vec<f64>| YamlMatrix { rows, cols, data };
    CameraInfo {
        image_width: u32::from(cam.width()),
        image_height: u32::from(cam.height()),
        camera_name: name.to_owned(),
        camera_matrix: m(3, 3, vec![fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]),
        distortion_model: "plumb_bob".to_owned(),
        distortion_coefficients: m(1, 5, vec![0.0; 5]),
        rectification_matrix: m(3, 3, vec![1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]),
        projection_matrix: m(3, 4, vec![fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]),
    }
}

/// The YAML text of a camera_info.
///
/// # Errors
/// Serialisation errors (none for finite values).
pub fn to_yaml(info: &CameraInfo) -> std::result::Result<String, String> {
    serde_saphyr::to_string(info).map_err(|e| e.to_string())
}
