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
//! Sample points, all in `Σ_M`, lie on **strips along the four edges of every face**, each
//! strip a set of rows of `G` points parallel to the edge:
//!
//! ```text
//!            outer rows  (S_out)   ·  ·  ·  ·  ·  ·     OUTER_OFFSETS_M beyond the edge
//!                                  ·  ·  ·  ·  ·  ·
//!   edge ─────────────────────────────────────────────
//!            inner rows  (S_in,k)  ·  ·  ·  ·  ·  ·     INNER_INSETS_M inside the edge
//!                                  ·  ·  ·  ·  ·  ·
//!                                  ·  ·  ·  ·  ·  ·
//! ```
//!
//! Only points near the edges tell a good pose from a slightly wrong one, so that is where
//! all the points are; the graded distances give the fitness a slope over a useful range
//! while the nearest rows keep it sharp. The fitness moves the nearest inner and outer rows to
//! fixed distances in pixels from the projected edge (`crate::fitness`); the point lists here
//! keep them at [`INNER_INSETS_M`]`[0]` and [`OUTER_OFFSETS_M`]`[0]`. Outer rows lie in the plane of their face. When face
//! `k` is visible and the face across the edge is not, the edge is on the silhouette and the
//! outer rows project just outside it, whatever the viewpoint (the ray to such a point stays
//! on the camera side of face `k`'s plane before it and on the far side of the hidden face's
//! plane after it, so it never meets the block); on other edges the outer rows fall on the
//! neighbouring face and are not counted.
//!
//! Rows are stored as start point + step, so a projected row is walked with three additions
//! per point (the perspective map is linear in homogeneous coordinates).

use nalgebra::{Point3, Vector3};

use crate::hue;
use crate::limits::{INNER_INSETS_M, OUTER_OFFSETS_M};

/// Number of faces of the block.
pub const FACES: usize = 6;

error_enum! {
    /// Why a block description was rejected.
    pub enum ModelError {
        /// A size or hue is NaN or infinite.
        NonFinite => "block size or hue is not finite",
        /// An edge is not longer than twice the deepest inner inset plus 2 mm.
        TooSmall => "block edge too short for the sample inset",
    }
}

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
    pub const PAPER: Block =
        Block { size_m: [0.100, 0.150, 0.200], face_hues_deg: [0.0, 120.0, 240.0, 0.0, 120.0, 240.0] };

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

/// Writes the sample geometry of face `k` of a block of half edge lengths `half` into `face`
/// (rows from `m0` inside the corners, `steps` intervals per row). Out of line and writing in
/// place (with [`SurfaceStrips::rebuild`]), so that building a model needs no large stack frame
/// on a board.
#[inline(never)]
fn face_samples(face: &mut FaceSamples, k: usize, half: &Vector3<f32>, m0: f32, steps: f32, hue_deg: f32) {
    let a = k % 3;
    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
    let (hb, hc) = (half[b], half[c]);
    let center = Block::normal(k) * half[a];
    let (eb, ec) = (unit(b), unit(c));
    // Edges on the ±b sides run along e_c; edges on the ±c sides run along e_b.
    let along_c = ec * (2.0 * (hc - m0) / steps);
    let along_b = eb * (2.0 * (hb - m0) / steps);
    let start_c = -ec * (hc - m0);
    let start_b = -eb * (hb - m0);
    face.edges = [
        Edge { base: center + eb * hb + start_c, step: along_c, inward: -eb, neighbour: b as u8 },
        Edge { base: center - eb * hb + start_c, step: along_c, inward: eb, neighbour: (b + 3) as u8 },
        Edge { base: center + ec * hc + start_b, step: along_b, inward: -ec, neighbour: c as u8 },
        Edge { base: center - ec * hc + start_b, step: along_b, inward: ec, neighbour: (c + 3) as u8 },
    ];
    face.hue = hue::degrees_to_units(hue_deg);
}

fn unit(axis: usize) -> Vector3<f32> {
    let mut v = Vector3::zeros();
    if let Some(c) = v.get_mut(axis) {
        *c = 1.0;
    }
    v
}

/// One edge of a face and the strip of sample rows along it.
///
/// Row `r` (signed distance `d_r`: [`INNER_INSETS_M`] positive, then [`OUTER_OFFSETS_M`]
/// negated) has the points `base + d_r·inward + i·step`, `i = 0..G`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    /// Start of the rows on the edge line (`Σ_M`, metres).
    pub base: Vector3<f32>,
    /// Step between the points of a row, along the edge.
    pub step: Vector3<f32>,
    /// Unit vector in the face's plane, perpendicular to the edge, pointing into the face.
    pub inward: Vector3<f32>,
    /// The face across this edge.
    pub neighbour: u8,
}

/// The sample geometry of one face.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaceSamples {
    /// The four edges with their strips.
    pub edges: [Edge; 4],
    /// Hue `b_k` in hue units.
    pub hue: u8,
}

/// The most edges whose outer rows count in one camera: those of visible faces whose
/// neighbour across the edge does not face the camera (silhouette edges).
///
/// With `F` the faces that face the camera (at most one of each opposite pair, so `|F| ≤ 3`)
/// and `V ⊆ F` the visible ones, a visible face's four neighbours are the faces of the two
/// other axes, of which exactly `|F| − 1` face the camera: it has `5 − |F|` silhouette edges,
/// and the counting edges number `|V|·(5 − |F|) ≤ |F|·(5 − |F|) ≤ 6` (at `|F|` = 2 or 3).
pub const MAX_OUTER_EDGES: usize = 6;

/// Signed distances of the rows of a strip from its edge (inner positive, outer negative).
pub const ROW_DISTANCES_M: [f32; crate::limits::ROWS_PER_EDGE] = {
    let mut d = [0.0; crate::limits::ROWS_PER_EDGE];
    let mut i = 0;
    while i < INNER_INSETS_M.len() {
        d[i] = INNER_INSETS_M[i];
        i += 1;
    }
    let mut j = 0;
    while j < OUTER_OFFSETS_M.len() {
        d[INNER_INSETS_M.len() + j] = -OUTER_OFFSETS_M[j];
        j += 1;
    }
    d
};

/// The surface-strips model of a [`Block`] with rows of `G` points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceStrips<const G: usize> {
    block: Block,
    half: Vector3<f32>,
    row_reach: [f32; 3],
    row_step: [f32; 3],
    faces: [FaceSamples; FACES],
}

impl<const G: usize> SurfaceStrips<G> {
    /// Inner sample points per face (`n_k`).
    pub const INNER_PER_FACE: usize = 4 * INNER_INSETS_M.len() * G;
    /// Contour-strip points per face.
    pub const OUTER_PER_FACE: usize = 4 * OUTER_OFFSETS_M.len() * G;
    /// Sample points of the three faces a camera evaluates (one of each opposite pair), every
    /// row of every edge.
    pub const POINTS_PER_CAMERA: usize = 3 * (Self::INNER_PER_FACE + Self::OUTER_PER_FACE);
    /// Sample points the fitness walks per camera for one pose on the board, whatever the
    /// pose: the inner rows of the three faces and the outer rows of [`MAX_OUTER_EDGES`] edges
    /// (see `crate::fitness`); the host's bound (it walks only the rows that count).
    pub const WALKED_PER_CAMERA: usize = 3 * Self::INNER_PER_FACE + MAX_OUTER_EDGES * OUTER_OFFSETS_M.len() * G;

    /// The model of nothing (every sample at the block's centre, size 0), to be
    /// [`SurfaceStrips::rebuild`]t where it lives.
    pub const EMPTY: Self = {
        let zero = Vector3::new(0.0, 0.0, 0.0);
        let edge = Edge { base: zero, step: zero, inward: zero, neighbour: 0 };
        Self {
            block: Block { size_m: [0.0; 3], face_hues_deg: [0.0; FACES] },
            half: zero,
            row_reach: [0.0; 3],
            row_step: [0.0; 3],
            faces: [FaceSamples { edges: [edge; 4], hue: 0 }; FACES],
        }
    };

    /// Builds the sample points of `block`.
    ///
    /// # Errors
    /// [`ModelError::NonFinite`] or [`ModelError::TooSmall`].
    pub fn new(block: &Block) -> Result<Self, ModelError> {
        let mut model = Self::EMPTY;
        model.rebuild(block)?;
        Ok(model)
    }

    /// Checks that `block` gives a model ([`SurfaceStrips::new`] succeeds exactly when this
    /// does).
    ///
    /// # Errors
    /// [`ModelError::NonFinite`] or [`ModelError::TooSmall`].
    pub fn check(block: &Block) -> Result<(), ModelError> {
        if !block.size_m.iter().chain(block.face_hues_deg.iter()).all(|v| v.is_finite()) {
            return Err(ModelError::NonFinite);
        }
        let deepest = INNER_INSETS_M.iter().fold(0.0f32, |m, d| m.max(*d));
        if block.size_m.iter().any(|&s| s <= 2.0 * deepest + 2e-3) {
            return Err(ModelError::TooSmall);
        }
        Ok(())
    }

    /// Rebuilds this model in place as [`SurfaceStrips::new`]`(block)`, with no temporary
    /// model (a board builds its tracker's model where it lives). On error it is unchanged.
    ///
    /// # Errors
    /// As [`SurfaceStrips::check`].
    pub fn rebuild(&mut self, block: &Block) -> Result<(), ModelError> {
        const { assert!(G >= 2, "a sample row needs at least 2 points") };
        Self::check(block)?;
        let m0 = INNER_INSETS_M.iter().fold(f32::MAX, |m, d| m.min(*d));
        let half = Vector3::from(block.size_m.map(|s| 0.5 * s));
        let steps = (G - 1) as f32;
        for (k, (face, hue_deg)) in self.faces.iter_mut().zip(block.face_hues_deg.iter()).enumerate() {
            face_samples(face, k, &half, m0, steps, *hue_deg);
        }
        self.block = *block;
        self.half = half;
        self.row_reach = [half.x - m0, half.y - m0, half.z - m0];
        self.row_step = self.row_reach.map(|r| 2.0 * r / steps);
        Ok(())
    }

    /// Per axis `x`: a row running along `x` starts at coordinate `−row_reach[x]` (and ends at
    /// `+row_reach[x]`), i.e. the smallest inner inset inside the block's corners.
    pub fn row_reach(&self) -> [f32; 3] {
        self.row_reach
    }

    /// Per axis `x`: the step between consecutive points of a row running along `x`.
    pub fn row_step(&self) -> [f32; 3] {
        self.row_step
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

    fn rows(&self, k: usize, inner: bool) -> impl Iterator<Item = Point3<f32>> + '_ {
        self.faces.get(k).into_iter().flat_map(|f| f.edges).flat_map(move |e| {
            ROW_DISTANCES_M
                .iter()
                .filter(move |d| (**d > 0.0) == inner)
                .flat_map(move |d| (0..G).map(move |i| Point3::from(e.base + e.inward * *d + e.step * i as f32)))
        })
    }

    /// The inner points `S_in,k` of face `k` (empty for `k ≥ 6`).
    pub fn inner_points(&self, k: usize) -> impl Iterator<Item = Point3<f32>> + '_ {
        self.rows(k, true)
    }

    /// The contour-strip points of face `k` on all four edges (empty for `k ≥ 6`).
    pub fn outer_points(&self, k: usize) -> impl Iterator<Item = Point3<f32>> + '_ {
        self.rows(k, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inner_points_lie_on_their_faces_and_strips_outside() {
        let m = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
        let h = m.half_size();
        for k in 0..FACES {
            let n = Block::normal(k);
            let a = k % 3;
            let inner: std::vec::Vec<_> = m.inner_points(k).collect();
            assert_eq!(inner.len(), SurfaceStrips::<8>::INNER_PER_FACE);
            for p in &inner {
                assert!((p.coords.dot(&n) - h[a]).abs() < 1e-6);
                for ax in (0..3).filter(|&ax| ax != a) {
                    assert!(p[ax].abs() <= h[ax] - INNER_INSETS_M[0] + 1e-6, "{p}");
                }
            }
            let outer: std::vec::Vec<_> = m.outer_points(k).collect();
            assert_eq!(outer.len(), SurfaceStrips::<8>::OUTER_PER_FACE);
            for p in &outer {
                // In the face's plane, beyond exactly one edge, by one of the offsets.
                assert!((p.coords.dot(&n) - h[a]).abs() < 1e-6);
                let beyond: std::vec::Vec<usize> = (0..3).filter(|&ax| ax != a && p[ax].abs() > h[ax]).collect();
                assert_eq!(beyond.len(), 1);
                let ax = beyond[0];
                let off = p[ax].abs() - h[ax];
                assert!(OUTER_OFFSETS_M.iter().any(|o| (off - o).abs() < 1e-6), "{off}");
            }
            for e in m.faces()[k].edges {
                let nb = usize::from(e.neighbour);
                // The inward direction points away from the neighbour face.
                assert!((e.inward + Block::normal(nb)).norm() < 1e-6);
            }
        }
        assert_eq!(SurfaceStrips::<8>::POINTS_PER_CAMERA, 3 * 4 * 5 * 8);
        assert_eq!(SurfaceStrips::<8>::WALKED_PER_CAMERA, 48 * 8);
    }

    #[test]
    fn hues_and_validation() {
        let m = SurfaceStrips::<4>::new(&Block::PAPER).unwrap();
        let hues: std::vec::Vec<u8> = m.faces().iter().map(|f| f.hue).collect();
        assert_eq!(ROW_DISTANCES_M, [0.002, 0.008, 0.025, -0.003, -0.010]);
        assert_eq!(hues, [0, 60, 120, 0, 60, 120]);
        let tiny = Block { size_m: [0.05, 0.1, 0.1], ..Block::PAPER };
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
