//! `frames.csv` and `joints.csv` (read with `csv`), and the joint state at a capture time.
//!
//! ## Joint state at a frame's capture time
//! A frame's capture time generally falls between two joint samples `t_i ≤ t ≤ t_{i+1}`. Its
//! joint state is interpolated linearly, **q and q̇ each from their own samples**:
//!
//! ```text
//! a = (t − t_i) / (t_{i+1} − t_i),   q(t) = q_i + a (q_{i+1} − q_i),   q̇(t) = q̇_i + a (q̇_{i+1} − q̇_i)
//! ```
//!
//! (q̇ is the controller's measured velocity, not a difference of q). A capture time equal to
//! a sample time takes that sample exactly. A capture time outside `[t_first, t_last]` is an
//! error found when the sequence is loaded, so the feedforward always uses the arm's motion at
//! the moment the image was taken, never an extrapolation or the last sample received.

use std::io::Read;
use std::path::{Path, PathBuf};

use super::error::{Result, SequenceError};

/// Header of `frames.csv`.
pub const FRAMES_HEADER: [&str; 4] = ["index", "t_s", "left", "right"];

/// One row of `frames.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRow {
    /// The frame's index (strictly increasing; gaps are dropped frames).
    pub index: u64,
    /// Capture time (s).
    pub t_s: f64,
    /// Left image, joined to the sequence directory.
    pub left: PathBuf,
    /// Right image, joined to the sequence directory.
    pub right: PathBuf,
    /// 1-based line in `frames.csv`.
    pub line: u64,
}

fn open(path: &Path) -> Result<std::fs::File> {
    std::fs::File::open(path).map_err(|e| SequenceError::file(path, format!("cannot read: {e}")))
}

fn reader<R: Read>(source: R) -> csv::Reader<R> {
    csv::ReaderBuilder::new().trim(csv::Trim::All).comment(None).from_reader(source)
}

fn csv_error(path: &Path, e: &csv::Error) -> SequenceError {
    let err = SequenceError::file(path, e.to_string());
    match e.position() {
        Some(p) => err.at_line(p.line()),
        None => err,
    }
}

fn headers<R: Read>(path: &Path, r: &mut csv::Reader<R>) -> Result<Vec<String>> {
    let h = r.headers().map_err(|e| csv_error(path, &e))?;
    Ok(h.iter().map(str::to_owned).collect())
}

fn number(path: &Path, line: u64, field: &str, text: &str) -> Result<f64> {
    let v: f64 = text
        .parse()
        .map_err(|_| SequenceError::file(path, format!("\"{text}\" is not a number")).at_line(line).in_field(field))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(SequenceError::file(path, format!("{text} is not finite")).at_line(line).in_field(field))
    }
}

/// Reads `frames.csv`; image paths are joined to `dir`.
///
/// # Errors
/// Missing file, wrong header, a row with the wrong number of fields, a non-numeric, NaN or
/// infinite time, indices or times not strictly increasing, no rows.
pub fn read_frames(path: &Path, dir: &Path) -> Result<Vec<FrameRow>> {
    parse_frames(open(path)?, path, dir)
}

/// [`read_frames`] from any byte source (`path` only names it in errors).
///
/// # Errors
/// As [`read_frames`].
pub fn parse_frames(source: impl Read, path: &Path, dir: &Path) -> Result<Vec<FrameRow>> {
    let mut r = reader(source);
    let h = headers(path, &mut r)?;
    if h != FRAMES_HEADER {
        return Err(SequenceError::file(
            path,
            format!("header must be {}, got {}", FRAMES_HEADER.join(","), h.join(",")),
        )
        .at_line(1));
    }
    let mut rows: Vec<FrameRow> = Vec::new();
    for rec in r.records() {
        let rec = rec.map_err(|e| csv_error(path, &e))?;
        let line = rec.position().map_or(0, csv::Position::line);
        let index: u64 = rec[0].parse().map_err(|_| {
            SequenceError::file(path, format!("\"{}\" is not a frame index", &rec[0])).at_line(line).in_field("index")
        })?;
        let t_s = number(path, line, "t_s", &rec[1])?;
        if let Some(prev) = rows.last() {
            if index <= prev.index {
                return Err(SequenceError::file(
                    path,
                    format!("index {index} does not increase (previous {})", prev.index),
                )
                .at_line(line)
                .in_field("index"));
            }
            if t_s <= prev.t_s {
                return Err(SequenceError::file(
                    path,
                    format!("time {t_s} s does not increase (previous {} s)", prev.t_s),
                )
                .at_line(line)
                .in_field("t_s"));
            }
        }
        rows.push(FrameRow { index, t_s, left: dir.join(&rec[2]), right: dir.join(&rec[3]), line });
    }
    if rows.is_empty() {
        return Err(SequenceError::file(path, "no frames"));
    }
    Ok(rows)
}

/// `joints.csv`: joint positions and velocities over time.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTable {
    names: Vec<String>,
    times: Vec<f64>,
    /// Per sample: q (`dof` values) then q̇ (`dof` values).
    values: Vec<f64>,
}

/// The joint state at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct JointState {
    /// Positions (rad, or m for prismatic joints).
    pub q: Vec<f64>,
    /// Velocities.
    pub qd: Vec<f64>,
}

impl JointTable {
    /// Reads `joints.csv`, whose columns must be `t_s`, `pos_<name>` for each of `names` in
    /// order, then `vel_<name>` likewise.
    ///
    /// # Errors
    /// Missing file, a header that does not match `names`, a bad row, a NaN or infinite value,
    /// times not strictly increasing, no rows.
    pub fn read(path: &Path, names: &[String]) -> Result<Self> {
        Self::parse(open(path)?, path, names)
    }

    /// [`JointTable::read`] from any byte source (`path` only names it in errors).
    ///
    /// # Errors
    /// As [`JointTable::read`].
    pub fn parse(source: impl Read, path: &Path, names: &[String]) -> Result<Self> {
        let mut r = reader(source);
        let h = headers(path, &mut r)?;
        let expected: Vec<String> = std::iter::once("t_s".to_owned())
            .chain(names.iter().map(|n| format!("pos_{n}")))
            .chain(names.iter().map(|n| format!("vel_{n}")))
            .collect();
        if h != expected {
            return Err(SequenceError::file(
                path,
                format!(
                    "header must name the URDF chain's movable joints in order: expected {}, got {}",
                    expected.join(","),
                    h.join(",")
                ),
            )
            .at_line(1));
        }
        let mut table = Self { names: names.to_vec(), times: Vec::new(), values: Vec::new() };
        for rec in r.records() {
            let rec = rec.map_err(|e| csv_error(path, &e))?;
            let line = rec.position().map_or(0, csv::Position::line);
            let t = number(path, line, "t_s", &rec[0])?;
            if let Some(prev) = table.times.last()
                && t <= *prev
            {
                return Err(SequenceError::file(path, format!("time {t} s does not increase (previous {prev} s)"))
                    .at_line(line)
                    .in_field("t_s"));
            }
            table.times.push(t);
            for (i, text) in rec.iter().enumerate().skip(1) {
                table.values.push(number(path, line, &expected[i], text)?);
            }
        }
        if table.times.is_empty() {
            return Err(SequenceError::file(path, "no joint samples"));
        }
        Ok(table)
    }

    /// A table from samples (for tests and writers): `times[i]`, then `q[i]` and `qd[i]`.
    pub fn from_samples(names: Vec<String>, samples: &[(f64, Vec<f64>, Vec<f64>)]) -> Self {
        let mut t = Self { names, times: Vec::new(), values: Vec::new() };
        for (time, q, qd) in samples {
            t.times.push(*time);
            t.values.extend(q.iter().chain(qd.iter()));
        }
        t
    }

    /// A table from its sample times and, per sample, `q` then `q̇` (`2 × names.len()`
    /// values each).
    pub fn from_flat(names: Vec<String>, times: Vec<f64>, values: Vec<f64>) -> Self {
        debug_assert_eq!(values.len(), times.len() * 2 * names.len());
        Self { names, times, values }
    }

    /// The joint names.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.names.len()
    }

    /// Sample times.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// First and last sample time.
    pub fn span(&self) -> (f64, f64) {
        (self.times[0], self.times[self.times.len() - 1])
    }

    /// Sample `i`'s q and q̇ (`i` < the number of samples).
    pub fn sample(&self, i: usize) -> (&[f64], &[f64]) {
        let n = self.dof();
        let row = &self.values[2 * n * i..2 * n * (i + 1)];
        row.split_at(n)
    }

    /// The joint state at time `t` (see the module docs); `None` outside the samples.
    pub fn at(&self, t: f64) -> Option<JointState> {
        let (first, last) = self.span();
        if !(t >= first && t <= last) {
            return None;
        }
        // First sample after t (≥ 1 since t ≥ first).
        let after = self.times.partition_point(|s| *s <= t);
        let i = after - 1;
        let (q0, qd0) = self.sample(i);
        if self.times[i] == t || after == self.times.len() {
            return Some(JointState { q: q0.to_vec(), qd: qd0.to_vec() });
        }
        let (q1, qd1) = self.sample(after);
        let a = (t - self.times[i]) / (self.times[after] - self.times[i]);
        let lerp = |x0: &[f64], x1: &[f64]| x0.iter().zip(x1).map(|(v0, v1)| v0 + a * (v1 - v0)).collect();
        Some(JointState { q: lerp(q0, q1), qd: lerp(qd0, qd1) })
    }
}
