//! The surface-strips solid model of a coloured block (paper §4.1, Fig. 3–5).
//!
//! The block is centred on its model frame `Σ_M`, edges along the axes, full edge lengths
//! `size_m = [s_x, s_y, s_z]`. Its six faces are numbered
//!
//! ```text
//!   k:     0    1    2    3    4    5
//!   face: +x   +y   +z   −x   −y   −z        (face k and face k+3 are opposite)
//! ```
//!
//! and each has one hue `b_k`. The paper's block is 100 × 150 × 200 mm with red (0°), green
//! (120°) and blue (240°) on the ±x, ±y, ±z pairs.
//!
//! Sample points, all in `Σ_M`:
//! - `S_in,k`: a `G × G` grid on face `k`, its outer rows [`FACE_INSET_M`] inside the edges;
//! - `S_out`: for each edge of each face a row of `G` points in the plane of that face,
//!   [`STRIP_OFFSET_M`] beyond the edge. When face `k` is visible and the face across that
//!   edge is not, the edge is on the silhouette and the row projects just outside it, whatever
//!   the viewpoint (the ray to such a point stays on the camera side of face `k`'s plane before
//!   it and on the far side of the hidden face's plane after it, so it never meets the block).
//!
//! Points are stored as grids (origin + integer steps), so a projected grid can be walked with
//! three additions per point (the perspective map is linear in homogeneous coordinates).

use nalgebra::{Point3, Vector3};

use crate::config::{FACE_INSET_M, STRIP_OFFSET_M};
use crate::hue;

/// Number of faces of the block.
pub const FACES: usize = 6;

/// Why a block description was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ModelError {
    /// A size or hue is NaN or infinite.
    NonFinite,
    /// An edge is not longer than twice [`FACE_INSET_M`] plus 1 mm.
    TooSmall,
}

impl core::fmt::Display for ModelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFinite => f.write_str("block size or hue is not finite"),
            Self::TooSmall => f.write_str("block edge too short for the sample inset"),
        }
    }
}

impl core::error::Error for ModelError {}

/// A rectangular block with one hue per face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Block {
    /// Full edge lengths along x, y, z of `Σ_M` (metres).
    pub size_m: [f32; 3],
    /// Hue of faces +x, +y, +z, −x, −y, −z in degrees.
    pub face_hues_deg: [f32; FACES],
}

impl Block {
    /// The paper's block: 100 × 150 × 200 mm; ±x red, ±y green, ±z blue.
    pub const PAPER: Block = Block {
        size_m: [0.100, 0.150, 0.200],
        face_hues_deg: [0.0, 120.0, 240.0, 0.0, 120.0, 240.0],
    };

    /// Outward unit normal of face `k` (in `Σ_M`).
    pub fn normal(k: usize) -> Vector3<f32> {
        let mut n = Vector3::zeros();
        if let Some(c) = n.get_mut(k % 3) {
            *c = if k < 3 { 1.0 } else { -1.0 };
        }
        n
    }

    /// The eight corners in `Σ_M`.
    pub fn corners(&self) -> [Point3<f32>; 8] {
        let [hx, hy, hz] = self.size_m.map(|s| 0.5 * s);
        let mut out = [Point3::origin(); 8];
        for (i, c) in out.iter_mut().enumerate() {
            let sx = if i & 1 == 0 { -hx } else { hx };
            let sy = if i & 2 == 0 { -hy } else { hy };
            let sz = if i & 4 == 0 { -hz } else { hz };
            *c = Point3::new(sx, sy, sz);
        }
        out
    }

    /// The corners of face `k` in counter-clockwise order seen from outside the block.
    pub fn face_corners(&self, k: usize) -> [Point3<f32>; 4] {
        let a = k % 3;
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let h = Vector3::from(self.size_m.map(|s| 0.5 * s));
        let s = if k < 3 { 1.0 } else { -1.0 };
        let n = Block::normal(k);
        let eb = unit(b) * h[b];
        let ec = unit(c) * h[c];
        let center = n * h[a];
        // (e_b, e_c, n) is right-handed for s = +1; for s = −1 reverse the order.
        let ccw = [center - eb - ec, center + eb - ec, center + eb + ec, center - eb + ec];
        if s > 0.0 { ccw.map(Point3::from) } else { [ccw[0], ccw[3], ccw[2], ccw[1]].map(Point3::from) }
    }
}

fn unit(axis: usize) -> Vector3<f32> {
    let mut v = Vector3::zeros();
    if let Some(c) = v.get_mut(axis) {
        *c = 1.0;
    }
    v
}

/// A row of `G` sample points: `origin + i·step`, `i = 0..G`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// First point (`Σ_M`, metres).
    pub origin: Vector3<f32>,
    /// Step between points.
    pub step: Vector3<f32>,
}

/// The sample geometry of one face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceSamples {
    /// Inner grid: point `(i, j)` is `origin + i·du + j·dv`, `i, j = 0..G`.
    pub origin: Vector3<f32>,
    /// Grid step along the first in-plane axis.
    pub du: Vector3<f32>,
    /// Grid step along the second in-plane axis.
    pub dv: Vector3<f32>,
    /// Contour rows beyond the four edges.
    pub strips: [Row; 4],
    /// For each strip, the face across that edge.
    pub neighbour: [u8; 4],
    /// Hue `b_k` in hue units.
    pub hue: u8,
}

/// The surface-strips model of a [`Block`] with `G × G` inner points and `4·G` contour points
/// per face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceStrips<const G: usize> {
    block: Block,
    half: Vector3<f32>,
    faces: [FaceSamples; FACES],
}

impl<const G: usize> SurfaceStrips<G> {
    /// Inner sample points per face.
    pub const INNER_PER_FACE: usize = G * G;
    /// Contour-strip points per face.
    pub const STRIP_PER_FACE: usize = 4 * G;
    /// Sample points evaluated per camera for one pose: always three faces (one of each
    /// opposite pair), visible or not, so the work does not depend on the pose.
    pub const POINTS_PER_CAMERA: usize = 3 * (G * G + 4 * G);

    /// Builds the sample points of `block`.
    ///
    /// # Errors
    /// [`ModelError::NonFinite`] or [`ModelError::TooSmall`].
    pub fn new(block: &Block) -> Result<Self, ModelError> {
        const { assert!(G >= 2, "the sample grid needs at least 2 points per side") };
        if !block.size_m.iter().chain(block.face_hues_deg.iter()).all(|v| v.is_finite()) {
            return Err(ModelError::NonFinite);
        }
        if block.size_m.iter().any(|&s| s <= 2.0 * FACE_INSET_M + 1e-3) {
            return Err(ModelError::TooSmall);
        }
        let half = Vector3::from(block.size_m.map(|s| 0.5 * s));
        let steps = (G - 1) as f32;
        let mut faces = [FaceSamples {
            origin: Vector3::zeros(),
            du: Vector3::zeros(),
            dv: Vector3::zeros(),
            strips: [Row { origin: Vector3::zeros(), step: Vector3::zeros() }; 4],
            neighbour: [0; 4],
            hue: 0,
        }; FACES];
        for (k, (face, hue_deg)) in faces.iter_mut().zip(block.face_hues_deg.iter()).enumerate() {
            let a = k % 3;
            let (b, c) = ((a + 1) % 3, (a + 2) % 3);
            let (hb, hc) = (half[b], half[c]);
            let center = Block::normal(k) * half[a];
            let (eb, ec) = (unit(b), unit(c));
            let du = eb * (2.0 * (hb - FACE_INSET_M) / steps);
            let dv = ec * (2.0 * (hc - FACE_INSET_M) / steps);
            face.origin = center - eb * (hb - FACE_INSET_M) - ec * (hc - FACE_INSET_M);
            face.du = du;
            face.dv = dv;
            face.hue = hue::degrees_to_units(*hue_deg);
            // Rows along e_c beyond the ±b edges, rows along e_b beyond the ±c edges.
            let row_c = center - ec * (hc - FACE_INSET_M);
            let row_b = center - eb * (hb - FACE_INSET_M);
            face.strips = [
                Row { origin: row_c + eb * (hb + STRIP_OFFSET_M), step: dv },
                Row { origin: row_c - eb * (hb + STRIP_OFFSET_M), step: dv },
                Row { origin: row_b + ec * (hc + STRIP_OFFSET_M), step: du },
                Row { origin: row_b - ec * (hc + STRIP_OFFSET_M), step: du },
            ];
            face.neighbour = [b as u8, (b + 3) as u8, c as u8, (c + 3) as u8];
        }
        Ok(Self { block: *block, half, faces })
    }

    /// The block this model samples.
    pub fn block(&self) -> &Block {
        &self.block
    }

    /// Half edge lengths.
    pub fn half_size(&self) -> Vector3<f32> {
        self.half
    }

    /// Sample geometry of all faces.
    pub fn faces(&self) -> &[FaceSamples; FACES] {
        &self.faces
    }

    /// The `G²` inner points of face `k` (empty for `k ≥ 6`).
    pub fn inner_points(&self, k: usize) -> impl Iterator<Item = Point3<f32>> + '_ {
        let face = self.faces.get(k);
        (0..G * G).filter_map(move |n| {
            let f = face?;
            Some(Point3::from(f.origin + f.du * (n % G) as f32 + f.dv * (n / G) as f32))
        })
    }

    /// The `G` points of contour strip `e` (0..4) of face `k`.
    pub fn strip_points(&self, k: usize, e: usize) -> impl Iterator<Item = Point3<f32>> + '_ {
        let row = self.faces.get(k).and_then(|f| f.strips.get(e));
        (0..G).filter_map(move |i| {
            let r = row?;
            Some(Point3::from(r.origin + r.step * i as f32))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inner_points_lie_on_their_faces_and_strips_outside() {
        let m = SurfaceStrips::<6>::new(&Block::PAPER).unwrap();
        let h = m.half_size();
        for k in 0..FACES {
            let n = Block::normal(k);
            let a = k % 3;
            let pts: std::vec::Vec<_> = m.inner_points(k).collect();
            assert_eq!(pts.len(), 36);
            for p in &pts {
                assert!((p.coords.dot(&n) - h[a]).abs() < 1e-6);
                for ax in 0..3 {
                    assert!(p[ax].abs() <= h[ax] - FACE_INSET_M + 1e-6 || ax == a);
                }
            }
            for e in 0..4 {
                let s: std::vec::Vec<_> = m.strip_points(k, e).collect();
                assert_eq!(s.len(), 6);
                for p in &s {
                    // In the face's plane, beyond exactly one edge by the strip offset.
                    assert!((p.coords.dot(&n) - h[a]).abs() < 1e-6);
                    let beyond = (0..3).filter(|&ax| ax != a && p[ax].abs() > h[ax]).count();
                    assert_eq!(beyond, 1);
                    let nb = usize::from(m.faces()[k].neighbour[e]);
                    let nn = Block::normal(nb);
                    assert!((p.coords.dot(&nn) - h[nb % 3] - STRIP_OFFSET_M).abs() < 1e-6);
                }
            }
        }
        assert_eq!(SurfaceStrips::<6>::POINTS_PER_CAMERA, 180);
    }

    #[test]
    fn hues_and_validation() {
        let m = SurfaceStrips::<4>::new(&Block::PAPER).unwrap();
        let hues: std::vec::Vec<u8> = m.faces().iter().map(|f| f.hue).collect();
        assert_eq!(hues, [0, 60, 120, 0, 60, 120]);
        let tiny = Block { size_m: [0.004, 0.1, 0.1], ..Block::PAPER };
        assert_eq!(SurfaceStrips::<4>::new(&tiny), Err(ModelError::TooSmall));
        let nan = Block { size_m: [f32::NAN, 0.1, 0.1], ..Block::PAPER };
        assert_eq!(SurfaceStrips::<4>::new(&nan), Err(ModelError::NonFinite));
    }

    #[test]
    fn face_corners_are_counter_clockwise_from_outside() {
        for k in 0..FACES {
            let c = Block::PAPER.face_corners(k);
            let n = (c[1] - c[0]).cross(&(c[2] - c[1]));
            assert!(n.dot(&Block::normal(k)) > 0.0, "face {k}");
        }
    }
}
