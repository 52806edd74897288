//! The text of a sequence's files, shared by the writers (`evorec export`, `evorec import`):
//! `sequence.toml` and the tables. Numbers are written with Rust's shortest round-trip
//! formatting, so they read back bit for bit.

use std::fmt::Write as _;

use nalgebra::Isometry3;

use super::manifest::{FORMAT, to_rows};
use super::tables::JointTable;

/// What `sequence.toml` says.
#[derive(Debug, Clone)]
pub struct ManifestFields<'a> {
    /// `name`.
    pub name: &'a str,
    /// A comment written under `name` (e.g. where the sequence came from), or empty.
    pub comment: &'a str,
    /// `stamp_origin_s`: the ROS stamp of time 0 (s), for a sequence imported from a bag.
    pub stamp_origin_s: Option<i64>,
    /// `[robot].base_link`.
    pub base_link: &'a str,
    /// `[robot].flange_link`.
    pub flange_link: &'a str,
    /// `^CL T_CR`.
    pub right_to_left: Isometry3<f64>,
    /// `^H T_CR`.
    pub flange_to_right: Isometry3<f64>,
    /// `[target].size_m`.
    pub size_m: [f64; 3],
    /// `[target].face_hues_deg`.
    pub face_hues_deg: [f64; 6],
    /// `[target].initial_pose`: t (m) and q (x, y, z, w).
    pub initial_pose: Option<([f64; 3], [f64; 4])>,
    /// `[search]`: min and max corner (m).
    pub search: Option<([f64; 3], [f64; 3])>,
}

/// `[a, b, …]` with each number in shortest round-trip form.
pub fn floats(v: &[f64]) -> String {
    let cells: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
    format!("[{}]", cells.join(", "))
}

/// The text of `sequence.toml` (URDF `robot.urdf`, calibration `calib/{left,right}.yaml`).
pub fn manifest_text(m: &ManifestFields<'_>) -> String {
    let mut s = format!("format = \"{FORMAT}\"\nname = {:?}\n", m.name);
    if let Some(origin) = m.stamp_origin_s {
        let _ = writeln!(s, "stamp_origin_s = {origin}");
    }
    for line in m.comment.lines() {
        let _ = writeln!(s, "# {line}");
    }
    let _ = write!(
        s,
        "\n[robot]\nurdf = \"robot.urdf\"\nbase_link = {:?}\nflange_link = {:?}\n\n[cameras]\n\
         left = \"calib/left.yaml\"\nright = \"calib/right.yaml\"\n# ^CL T_CR (4x4, row-major, m)\n\
         right_to_left = {}\n# ^H T_CR (4x4, row-major, m)\nflange_to_right = {}\n\n\
         [target]\nsize_m = {}\nface_hues_deg = {}\n",
        m.base_link,
        m.flange_link,
        floats(&to_rows(&m.right_to_left)),
        floats(&to_rows(&m.flange_to_right)),
        floats(&m.size_m),
        floats(&m.face_hues_deg),
    );
    if let Some((t, q)) = &m.initial_pose {
        let _ = writeln!(s, "initial_pose = {{ t_m = {}, q_xyzw = {} }}", floats(t), floats(q));
    }
    if let Some((lo, hi)) = &m.search {
        let _ = write!(s, "\n[search]\nmin_m = {}\nmax_m = {}\n", floats(lo), floats(hi));
    }
    s
}

/// The header line of `joints.csv` for the chain `names`.
pub fn joints_header(names: &[String]) -> String {
    let mut h = String::from("t_s");
    for prefix in ["pos_", "vel_"] {
        for n in names {
            h.push(',');
            h.push_str(prefix);
            h.push_str(n);
        }
    }
    h.push('\n');
    h
}

/// Appends one `joints.csv` row: `t` as given, then q and q̇ in shortest round-trip form.
pub fn joints_row(out: &mut String, t: &str, q: &[f64], qd: &[f64]) {
    out.push_str(t);
    for v in q.iter().chain(qd) {
        let _ = write!(out, ",{v}");
    }
    out.push('\n');
}

/// The whole `joints.csv` of a table, times in shortest round-trip form too.
pub fn joints_csv(table: &JointTable) -> String {
    let mut s = joints_header(table.names());
    for (i, t) in table.times().iter().enumerate() {
        let (q, qd) = table.sample(i);
        joints_row(&mut s, &format!("{t}"), q, qd);
    }
    s
}

/// The `frames.csv` of `(index, t_s)` rows, images `left/NNNNNN.png` and `right/NNNNNN.png`
/// named by the row's index, times in shortest round-trip form.
pub fn frames_csv(rows: &[(u64, f64)]) -> String {
    let mut s = String::from("index,t_s,left,right\n");
    for (index, t) in rows {
        let _ = writeln!(s, "{index},{t},{},{}", image_path("left", *index), image_path("right", *index));
    }
    s
}

/// `SIDE/NNNNNN.png`, the image of frame `index` as the writers name it.
pub fn image_path(side: &str, index: u64) -> String {
    format!("{side}/{index:06}.png")
}
