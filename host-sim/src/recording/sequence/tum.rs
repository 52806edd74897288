//! The TUM RGB-D trajectory format: one pose per line, `t tx ty tz qx qy qz qw`,
//! space-separated, `#` starts a comment line.

use std::fmt::Write as _;
use std::path::Path;

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};

use super::error::{Result, SequenceError};

/// Largest deviation of `|q|` from 1 accepted in a TUM line.
pub const UNIT_TOLERANCE: f64 = 1e-3;

/// One timed pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TumPose {
    /// Time (s).
    pub t: f64,
    /// The pose.
    pub pose: Isometry3<f64>,
    /// 1-based line in the file it was read from (0 if it was not read).
    pub line: u64,
}

/// Reads a TUM file.
///
/// # Errors
/// Missing file, a line without 8 numbers, a non-finite value, a non-unit quaternion, times
/// not strictly increasing.
pub fn read(path: &Path) -> Result<Vec<TumPose>> {
    let text = std::fs::read_to_string(path).map_err(|e| SequenceError::file(path, format!("cannot read: {e}")))?;
    parse(&text, path)
}

/// Parses TUM text (`path` only names it in errors).
///
/// # Errors
/// As [`read`].
pub fn parse(text: &str, path: &Path) -> Result<Vec<TumPose>> {
    let mut out: Vec<TumPose> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i as u64 + 1;
        let s = raw.trim();
        if s.is_empty() || s.starts_with('#') {
            continue;
        }
        let bad = |msg: String| SequenceError::file(path, msg).at_line(line);
        let v: Vec<f64> = s
            .split_whitespace()
            .map(|w| w.parse::<f64>().map_err(|_| bad(format!("\"{w}\" is not a number"))))
            .collect::<Result<_>>()?;
        if v.len() != 8 {
            return Err(bad(format!("expected 8 numbers (t tx ty tz qx qy qz qw), got {}", v.len())));
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(bad("values must be finite".to_owned()));
        }
        let q = Quaternion::new(v[7], v[4], v[5], v[6]);
        if (q.norm() - 1.0).abs() > UNIT_TOLERANCE {
            return Err(bad(format!("quaternion is not unit (|q| = {})", q.norm())));
        }
        if let Some(prev) = out.last()
            && v[0] <= prev.t
        {
            return Err(bad(format!("time {} s does not increase (previous {} s)", v[0], prev.t)));
        }
        let pose = Isometry3::from_parts(Translation3::new(v[1], v[2], v[3]), UnitQuaternion::from_quaternion(q));
        out.push(TumPose { t: v[0], pose, line });
    }
    Ok(out)
}

/// TUM text of `poses` under a `#` comment line.
pub fn format(comment: &str, poses: &[(f64, Isometry3<f64>)]) -> String {
    format_with(comment, poses, |t| format!("{t:.9}"))
}

/// As [`format()`], each time written by `time`; every line of `comment` becomes a `#` line.
pub fn format_with(comment: &str, poses: &[(f64, Isometry3<f64>)], time: impl Fn(f64) -> String) -> String {
    let mut s = String::new();
    for line in comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    for (t, p) in poses {
        let (tr, q) = (p.translation.vector, p.rotation.coords);
        // coords are x, y, z, w.
        let _ =
            writeln!(s, "{} {:.9} {:.9} {:.9} {:.9} {:.9} {:.9} {:.9}", time(*t), tr.x, tr.y, tr.z, q.x, q.y, q.z, q.w);
    }
    s
}
