//! The hue fitness of a pose (paper §4.2, eq. 34–35).
//!
//! For one camera with the model at pose `(R, t)` in that camera's frame:
//!
//! ```text
//! F_c = max(0, Σ_k∈visible w_k (Σ_{p ∈ S_in,k} δ(h(p) ≈ b_k)  −  Σ_{p ∈ S_out,k} δ(h(p) ≈ any visible b_k))) / H
//! H   = Σ_k∈visible w_k · |S_in,k|
//! F   = (F_L + F_R) / 2
//! ```
//!
//! where `≈` is the [`HueLut`] tolerance band, a face is visible when it faces the camera at
//! less than ~84° ([`MIN_VISIBLE_COS`]) and spans at least [`MIN_FACE_PX`] pixels, `S_in,k` the
//! inner rows of face `k`, `S_out,k` the outer rows on its silhouette edges (see
//! [`crate::model`]), and `w_k ∈ (0, 1]` the face's weight. With every `w_k = 1` this is the
//! paper's eq. 34. The weight (our addition) ramps up as
//! a face turns into view ([`FULL_VISIBLE_COS`], [`FULL_FACE_PX`]): a face seen as a sliver of
//! a few pixels cannot hold its rows, and counted at full weight it made the true pose score
//! below a pose turned a degree or two to hide it (x/pitch excursions; the measurement is in
//! `docs/method.md`). A pose whose block is not entirely in front of a camera scores 0 in that
//! camera.
//!
//! **The nearest rows are placed in pixels.** The model's rows lie at fixed distances in metres
//! ([`INNER_INSETS_M`], [`OUTER_OFFSETS_M`]), but the nearest row of each edge is placed at a
//! fixed number of pixel widths from the edge as the pose projects it (computed per face and
//! camera at the face's centre, see `metres_per_pixel`): half a width inside a silhouette edge
//! ([`SILHOUETTE_INNER_PX`]), one outside it ([`SILHOUETTE_OUTER_PX`]), one inside a fold
//! ([`FOLD_INNER_PX`]). At 2 mm inside and 3 mm outside (2.3 and 3.4 px at 0.7 m) an edge could
//! move by more than four pixels without moving a point across it: a dead band of several
//! millimetres in depth, where 1 mm moves an edge by 0.1–0.25 px. Between rows half a pixel
//! apart the dead band is half a pixel of edge motion. Same rows, same work: only their offsets
//! change. An [`Evaluator`] with a learnt shift ([`Evaluator::with_edge_shift`], see
//! [`crate::edge`]) moves both silhouette rows outwards by it, for a camera that needs more (or
//! less) of a pixel covered than a quarter to read it as the face.
//!
//! **Bounded work.** Of each pair of opposite faces exactly one can face a camera, so each
//! camera evaluates three faces (the one of each pair on the camera's side): on the board their inner rows
//! always, whether or not a face is visible (the visibility only masks the counts), and the
//! outer rows only where they count, on the silhouette edges of visible faces. Those are at
//! most [`MAX_OUTER_EDGES`] = 6 edges per camera, and the walk is padded to that many, so every
//! pose walks [`SurfaceStrips::WALKED_PER_CAMERA`] points per camera (48·G, 80 % of
//! [`SurfaceStrips::POINTS_PER_CAMERA`]; the outer rows of the other edges are never walked).
//! That constant work is the board's (so the measured worst case is every
//! case); the host walks only the rows that count, the inner rows of visible faces and the
//! outer rows of their silhouette edges (at most as many: the same counts, less work for a
//! pose that shows fewer than three faces or silhouette edges; see `CONSTANT_WORK`). Points
//! outside the image read as "no hue"; nothing is ever read out of bounds.
//!
//! **Per row** (plain pinhole): the perspective division of its two end points, and the step
//! between its points in 16.16 fixed point (see `Affine` for why the affine walk between
//! exactly projected ends samples the model's row). **Per point**: two integer additions, a
//! shift and a multiply-add for the index, the column compare, the slice's bounds check (which
//! is the row test, see `View::walk`), the pixel load (predicated: no branch, so points
//! outside the image cost the same as points inside), for RGB565 one load from the 64 KiB hue
//! table ([`crate::image::RGB565_HUE`]), and one load from the hue match table. **Per pose** the
//! block's axis-aligned structure is used: every row start, step and offset is a multiple of
//! one projected model axis, precomputed once per camera and pose.
//!
//! **Lens distortion.** A camera with [`crate::camera::Distortion`] ≠ 0 takes the distorted
//! kernel, chosen once per camera and pose (a camera without distortion pays nothing): rows are
//! walked in normalised coordinates and every point goes through the plumb_bob polynomial and
//! `K` (about 20 more float operations, and a division per point: it keeps the per-point
//! projection and costs several times the pinhole walk per point). Points beyond the calibrated field (see
//! `distortion_field_r2`) read as outside the image.

use nalgebra::{Matrix3, Vector3};

use crate::camera::{Pinhole, StereoRig};
use crate::hue::HueLut;
use crate::image::{Image, PixelFormat};
use crate::limits::{
    FACE_WEIGHT_ONE, FOLD_INNER_PX, FULL_FACE_PX, FULL_VISIBLE_COS, INNER_INSETS_M, MIN_DEPTH_M, MIN_FACE_PX,
    MIN_VISIBLE_COS, OUTER_OFFSETS_M, SILHOUETTE_INNER_PX, SILHOUETTE_OUTER_PX,
};
use crate::model::{FACES, MAX_OUTER_EDGES, SurfaceStrips};
use crate::pose::Psi;

/// Match counts of one camera.
///
/// The raw counts are for diagnostics; the score uses the weighted ones, in which every
/// visible face's counts are scaled by its weight (see [`FULL_VISIBLE_COS`]), in units of
/// `1 / FACE_WEIGHT_ONE` point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Counts {
    /// Inner points whose hue matched their face (visible faces only).
    pub inner_matched: u32,
    /// Inner points on visible faces (`H`).
    pub inner_total: u32,
    /// Contour points on silhouette edges whose hue matched a visible face.
    pub strip_matched: u32,
    /// Bitmask of the faces found visible.
    pub visible: u8,
    /// `Σ_k w_k · (inner points of face k that matched)`.
    pub weighted_matched: u32,
    /// `Σ_k w_k · (contour points on face k's silhouette edges that matched)`.
    pub weighted_strip: u32,
    /// `Σ_k w_k · (inner points of face k)`: the weighted `H`.
    pub weighted_total: u32,
}

impl Counts {
    /// `F_c = max(0, matched − strip_matched) / H` over the weighted counts, or 0 when no face
    /// is visible. With every visible face at full weight it is the paper's eq. 34 exactly.
    pub fn score(&self) -> f32 {
        if self.weighted_total == 0 {
            return 0.0;
        }
        let net = self.weighted_matched.saturating_sub(self.weighted_strip);
        net as f32 / self.weighted_total as f32
    }
}

/// Fitness of one pose in both cameras.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Fitness {
    /// `F = (F_L + F_R) / 2`.
    pub total: f32,
    /// Left camera's counts.
    pub left: Counts,
    /// Right camera's counts.
    pub right: Counts,
}

/// Fraction bits of the pinhole kernel's fixed-point pixel coordinates (16.16 in an `i32`).
const FIX_BITS: u32 = 16;
/// `2^FIX_BITS`: one pixel in fixed point.
const FIX_ONE: f32 = (1u32 << FIX_BITS) as f32;
/// Largest `|u|`, `|v|` (pixels) a sample point of a pose may project to for the pinhole
/// kernel; a pose whose block (inflated by the outer rows) could reach farther scores 0 in
/// that camera, as a pose behind it does. Such a block is within centimetres of the camera
/// and mostly outside the field of view: 16384 pixels from the principal point is 80° off
/// the axis for a focal length of 2900 pixels. With it, every fixed-point coordinate of a row
/// walk stays within `±2³⁰` and no addition wraps.
pub const MAX_PIXEL_REACH: f32 = 16384.0;

/// The rows of one edge's strip in homogeneous image coordinates: the first points of its
/// inner rows, the step between points and the whole row `(G − 1)·step`.
struct EdgeRows<const N: usize> {
    /// First points of the rows (the inner rows as [`INNER_INSETS_M`], or the outer rows as
    /// [`OUTER_OFFSETS_M`]).
    starts: [[f32; 3]; N],
    /// Step between the points of a row.
    step: [f32; 3],
    /// `(G − 1)·step`.
    span: [f32; 3],
}

/// How the points of a face's strips score: an inner point 1 when its hue matches the face
/// (`inner`, the face's plane of the [`HueLut`]), an outer point 1 when its hue matches any
/// visible face (`outer`, the visible set's plane): one table load per point either way.
#[derive(Clone, Copy)]
struct Scores<'l> {
    inner: &'l [u8; 256],
    outer: &'l [u8; 256],
}

/// How a camera walks the rows of an edge's strip (`G` points each): the pinhole kernel's
/// [`Affine`] walk or the distorted kernel's [`Lens`].
trait RowWalk {
    /// `Σ plane[hue]` over the `G` points of each of the `N` rows of `edge`.
    fn count_rows<const G: usize, const N: usize>(&self, edge: &EdgeRows<N>, plane: &[u8; 256]) -> u32;
}

/// One row of the pinhole kernel in 16.16 fixed point: its first point (pixel coordinates,
/// `(0, 0)` the corner of the first pixel) and the step between its points.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
struct FixedRow {
    u: i32,
    v: i32,
    du: i32,
    dv: i32,
}

impl FixedRow {
    /// One row from `start` to `start + span`, as [`FixedRow::edge`] makes each (the
    /// board's code: per row, its two divisions).
    #[cfg_attr(not(any(target_arch = "arm", test)), allow(dead_code))]
    #[inline(always)]
    fn new<const G: usize>(start: [f32; 3], span: [f32; 3]) -> Self {
        let end = add(start, span);
        Self::from_ends::<G>(start, 1.0 / start[2], end, 1.0 / end[2])
    }

    /// The rows of one edge, each from `starts[r]` to `starts[r] + span` (homogeneous
    /// coordinates of `K·(R·p + t)` with the first two rows of `K` scaled by `2¹⁶`) walked in
    /// `G − 1` equal steps, the divisions of all rows side by side (independent, so they
    /// overlap, or share a vector division where the CPU has one).
    ///
    /// The conversion truncates towards zero: a point in `(−2⁻¹⁶, 0)` reads column or row 0
    /// instead of −1 (as far off as the fixed point's own resolution).
    #[cfg_attr(target_arch = "arm", allow(dead_code))]
    #[inline(always)]
    fn edge<const G: usize, const N: usize>(starts: &[[f32; 3]; N], span: [f32; 3]) -> [Self; N] {
        let ends = starts.map(|s| add(s, span));
        let i0 = starts.map(|s| 1.0 / s[2]);
        let i1 = ends.map(|e| 1.0 / e[2]);
        core::array::from_fn(|r| Self::from_ends::<G>(starts[r], i0[r], ends[r], i1[r]))
    }

    /// The row from `start` to `end` given `i0 = 1 / start[2]` and `i1 = 1 / end[2]`.
    #[inline(always)]
    fn from_ends<const G: usize>(start: [f32; 3], i0: f32, end: [f32; 3], i1: f32) -> Self {
        let (u0, v0) = (start[0] * i0, start[1] * i0);
        let (u1, v1) = (end[0] * i1, end[1] * i1);
        let per_step = 1.0 / (G - 1) as f32;
        Self { u: u0 as i32, v: v0 as i32, du: ((u1 - u0) * per_step) as i32, dv: ((v1 - v0) * per_step) as i32 }
    }
}

/// The plain pinhole walk: the perspective division at the rows' two ends only, then an
/// affine walk in 16.16 fixed point between them (per point two integer additions, the index,
/// two compares, the pixel load, the tables; see [`View::walk`]).
///
/// **Exactness.** The projection of a straight row is a straight segment, and the affine walk
/// stays on the segment between the exactly projected ends: every point read is the
/// projection of a point of the model's row. Only where along the row it lies differs from
/// the uniform steps of the model: with `w₀`, `w₁` the depths of the row's ends, the image
/// point at parameter `s ∈ [0, 1]` of the affine walk is the projection of the row point at
///
/// ```text
/// s' = s·w₀ / w̃(s),   w̃(s) = (1 − s)·w₁ + s·w₀,   |s' − s| = s(1 − s)·|w₁ − w₀| / w̃(s)
///                                                   ≤ |w₁ − w₀| / (4·min(w₀, w₁)),
/// ```
///
/// second order in the relative depth change across the row (a 150 mm row at 450 mm tilted
/// 45° moves its middle point by 6 % of the row). The rows' distances from their edges, which
/// make the fitness sharp, are exact. The fixed-point steps add at most `G` units of 2⁻¹⁶
/// pixel. See the test `affine_walk_stays_on_the_projected_row`.
struct Affine<'v, 'p, F: PixelFormat> {
    view: &'v View<'p, F>,
}

impl<F: PixelFormat> RowWalk for Affine<'_, '_, F> {
    #[inline(always)]
    fn count_rows<const G: usize, const N: usize>(&self, edge: &EdgeRows<N>, plane: &[u8; 256]) -> u32 {
        // The same rows on host and board: the board walks them inline, the host in `host_edge`.
        #[cfg(target_arch = "arm")]
        let rows = edge.starts.map(|start| FixedRow::new::<G>(start, edge.span));
        #[cfg(target_arch = "arm")]
        return walk_edge::<G, N, F>(self.view, &rows, plane);
        #[cfg(not(target_arch = "arm"))]
        host_edge::<G, N, F>(self.view, &edge.starts, edge.span, plane)
    }
}

/// The host's edge: its rows ([`FixedRow::edge`]) and their walk, out of line (its registers
/// hold the view, the rows and the plane, not the camera's set-up).
#[cfg(not(target_arch = "arm"))]
#[inline(never)]
fn host_edge<const G: usize, const N: usize, F: PixelFormat>(
    view: &View<'_, F>,
    starts: &[[f32; 3]; N],
    span: [f32; 3],
    plane: &[u8; 256],
) -> u32 {
    walk_edge::<G, N, F>(view, &FixedRow::edge::<G, N>(starts, span), plane)
}

/// The integer part of [`Affine`]: `Σ plane[hue]` over the fixed-point rows of one edge,
/// out of line on the board so that its registers hold only the walk (and its code, hence
/// its instruction count, does not move with the code around it); on the host inlined into
/// `host_edge`, which also makes the rows.
#[cfg_attr(target_arch = "arm", inline(never))]
#[cfg_attr(not(target_arch = "arm"), inline(always))]
fn walk_edge<const G: usize, const N: usize, F: PixelFormat>(
    view: &View<'_, F>,
    rows: &[FixedRow; N],
    plane: &[u8; 256],
) -> u32 {
    // Never taken (an image has at least one pixel); it lets the walk read pixel 0 for the
    // points outside the image without a bounds check.
    if view.pixels.is_empty() {
        return 0;
    }
    rows.iter().map(|row| view.walk::<G>(row, plane)).sum()
}

/// The lens walk: every point is walked in normalised homogeneous coordinates (three
/// additions), divided, and mapped to pixels by `to_pixel` (the plumb_bob polynomial and `K`).
struct Lens<'v, 'p, F: PixelFormat, P: Fn(f32, f32, f32) -> (f32, f32)> {
    view: &'v View<'p, F>,
    to_pixel: P,
}

impl<F: PixelFormat, P: Fn(f32, f32, f32) -> (f32, f32)> RowWalk for Lens<'_, '_, F, P> {
    #[inline(always)]
    fn count_rows<const G: usize, const N: usize>(&self, edge: &EdgeRows<N>, plane: &[u8; 256]) -> u32 {
        let mut hits = 0u32;
        for start in &edge.starts {
            let ([mut x, mut y, mut w], step) = (*start, edge.step);
            for _ in 0..G {
                let (u1, v1) = (self.to_pixel)(x, y, w);
                hits += u32::from(plane[usize::from(self.view.hue(u1, v1))]);
                x += step[0];
                y += step[1];
                w += step[2];
            }
        }
        hits
    }
}

#[inline(always)]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline(always)]
fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `K'·R` and `K'·t`, the pose composed with the intrinsics (principal point shifted by +1
/// pixel for [`View::hue`]'s truncation).
struct Projector {
    m: [[f32; 3]; 3],
    c: [f32; 3],
}

impl Projector {
    /// `K' = [fx 0 cx; 0 fy cy; 0 0 1]`.
    fn new([fx, fy, cx, cy]: [f32; 4], r: &Matrix3<f32>, t: &Vector3<f32>) -> Self {
        let row = |i: usize| [r[(i, 0)], r[(i, 1)], r[(i, 2)]];
        let (r0, r1, r2) = (row(0), row(1), row(2));
        let m = [
            [fx * r0[0] + cx * r2[0], fx * r0[1] + cx * r2[1], fx * r0[2] + cx * r2[2]],
            [fy * r1[0] + cy * r2[0], fy * r1[1] + cy * r2[1], fy * r1[2] + cy * r2[2]],
            r2,
        ];
        let c = [fx * t.x + cx * t.z, fy * t.y + cy * t.z, t.z];
        Self { m, c }
    }
}

/// `a.min(b)` for finite numbers (focal lengths and block sizes are validated finite) as one
/// compare instead of a call to `fminf` with its NaN rules.
#[inline(always)]
fn min_finite(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// The weight of a face, `0..=FACE_WEIGHT_ONE` (see [`FULL_VISIBLE_COS`]), from the distance
/// `dist > 0` of the camera outside the face's plane, the squared distance `c2 > 0` to its
/// centre and `focal · side` (its narrowest side): its cosine to the line of sight is
/// `dist / |c|` and its width in pixels about `focal · side · cos / |c|`. 0 below
/// [`MIN_VISIBLE_COS`] or [`MIN_FACE_PX`] (the face is hidden).
#[inline(always)]
fn face_weight(dist: f32, c2: f32, focal_side: f32) -> u32 {
    let inv = 1.0 / libm::sqrtf(c2);
    let cos = dist * inv;
    let px = focal_side * cos * inv;
    let ramp = |x: f32, lo: f32, hi: f32| (x - lo) / (hi - lo);
    let w = min_finite(ramp(cos, MIN_VISIBLE_COS, FULL_VISIBLE_COS), ramp(px, MIN_FACE_PX, FULL_FACE_PX));
    // Truncating, saturating conversion (NaN → 0): 0 at or below either threshold.
    let one = FACE_WEIGHT_ONE as f32;
    (min_finite(w, 1.0) * one) as u32
}

/// Counts of one camera for the model at `(r, t)` in that camera's frame.
///
/// The work is bounded by the same constant for every pose (on the board it is that
/// constant): see the module docs.
pub fn camera_counts<const G: usize, B: AsRef<[u8]>, F: PixelFormat>(
    model: &SurfaceStrips<G>,
    lut: &HueLut,
    cam: &Pinhole,
    image: &Image<B, F>,
    r: &Matrix3<f32>,
    t: &Vector3<f32>,
) -> Counts {
    counts_walking::<G, B, F, CONSTANT_WORK>(model, lut, cam, image, r, t, 0.0)
}

/// [`camera_counts`] with the nearest silhouette rows moved outwards by `edge_shift_px` pixel
/// widths ([`crate::edge`]), walking every row (`WALK_ALL`, the board's constant work) or only
/// the rows that count: the same counts either way. Out of line (the wrapper inlines, this
/// does not, so the board's code stays in one place per instance).
#[inline(never)]
fn counts_walking<const G: usize, B: AsRef<[u8]>, F: PixelFormat, const WALK_ALL: bool>(
    model: &SurfaceStrips<G>,
    lut: &HueLut,
    cam: &Pinhole,
    image: &Image<B, F>,
    r: &Matrix3<f32>,
    t: &Vector3<f32>,
    edge_shift_px: f32,
) -> Counts {
    let view = View::of(image);
    let faces = face_plan(model, cam, r, t);
    let (fx, fy) = (cam.fx(), cam.fy());
    if cam.distortion().is_none() {
        // K with the pixel coordinates in 16.16 fixed point (scaled by 2¹⁶, exactly).
        let proj = Projector::new([fx * FIX_ONE, fy * FIX_ONE, cam.cx() * FIX_ONE, cam.cy() * FIX_ONE], r, t);
        count_faces::<G, WALK_ALL>(model, lut, &Affine { view: &view }, &proj, &faces, FIX_ONE, edge_shift_px)
    } else {
        // Normalised coordinates, then the lens, then K'. Beyond `r2_max` the plumb_bob
        // polynomial is outside the calibrated field (and may fold back into the image):
        // such points read as outside.
        distorted_counts::<G, F, WALK_ALL>(model, lut, &view, cam, (r, t), &faces, edge_shift_px)
    }
}

/// Which faces one camera evaluates for the model at `(r, t)` in that camera's frame: of each
/// opposite pair the one on the camera's side, its weight (0: hidden, and every face is
/// hidden when the block is not wholly in front of the camera or beyond the fixed point's
/// reach, see [`MAX_PIXEL_REACH`]), and which faces face the camera.
#[inline(always)]
fn face_plan<const G: usize>(model: &SurfaceStrips<G>, cam: &Pinhole, r: &Matrix3<f32>, t: &Vector3<f32>) -> FacePlan {
    let half = model.half_size();
    let focal = min_finite(cam.fx(), cam.fy());

    // Nearest depth of the block inflated by the outer rows (every sample point is inside it).
    let margin = OUTER_OFFSETS_M.iter().fold(0.0f32, |m, d| m.max(*d));
    let inflated = [half[0] + margin, half[1] + margin, half[2] + margin];
    let reach = |i: usize| (0..3).fold(0.0f32, |s, a| s + r[(i, a)].abs() * inflated[a]);
    let near = t.z - reach(2);
    // The pinhole kernel's fixed point holds every sample point (see `MAX_PIXEL_REACH`).
    let fits = |f: f32, c: f32, lateral: f32| f * lateral + c.abs() * near <= MAX_PIXEL_REACH * near;
    let in_front = near > MIN_DEPTH_M
        && (!cam.distortion().is_none()
            || (fits(cam.fx(), cam.cx(), t.x.abs() + reach(0)) && fits(cam.fy(), cam.cy(), t.y.abs() + reach(1))));

    // d_a = (column a of R) · t: the camera is on the +a side of the block iff d_a < −h_a.
    let mut d = [0.0f32; 3];
    for (a, da) in d.iter_mut().enumerate() {
        *da = r.column(a).dot(t);
    }
    let front = |k: u8| -> bool {
        let (a, pos) = (usize::from(k % 3), k < 3);
        let (da, ha) = (d.get(a).copied().unwrap_or(0.0), half[a]);
        if pos { da < -ha } else { da > ha }
    };

    // The face of each opposite pair that is on the camera's side, and its weight (0: hidden).
    let mut chosen = [0usize; 3];
    let mut weight = [0u32; 3];
    for (a, ((ck, wk), da)) in chosen.iter_mut().zip(weight.iter_mut()).zip(d.iter()).enumerate() {
        let k = if *da < 0.0 { a } else { a + 3 };
        *ck = k;
        let dist = da.abs() - half[a];
        let sign = if k < 3 { 1.0 } else { -1.0 };
        let center = t + r.column(a) * (sign * half[a]);
        let c2 = center.dot(&center);
        // Narrowest full side of the face, and its foreshortened size in pixels.
        let side = 2.0 * min_finite(half[(a + 1) % 3], half[(a + 2) % 3]);
        if in_front && dist > 0.0 && c2 > 0.0 {
            *wk = face_weight(dist, c2, focal * side);
        }
    }
    let visible_mask = (0..3).fold(0u8, |m, i| if weight[i] > 0 { m | 1 << chosen[i] } else { m });

    FacePlan { chosen, weight, visible_mask, front: core::array::from_fn(|k| front(k as u8)) }
}

/// The faces one camera sees at full weight (out of line: one copy of the face plan's code).
#[inline(never)]
fn full_faces_of<const G: usize>(model: &SurfaceStrips<G>, cam: &Pinhole, r: &Matrix3<f32>, t: &Vector3<f32>) -> u32 {
    face_plan(model, cam, r, t).weight.iter().filter(|&&w| w >= FACE_WEIGHT_ONE).count() as u32
}

/// [`count_faces`] through the lens of `cam` (kept out of line so the plain kernel's code and
/// its unrolling do not change with it).
#[inline(never)]
fn distorted_counts<const G: usize, F: PixelFormat, const WALK_ALL: bool>(
    model: &SurfaceStrips<G>,
    lut: &HueLut,
    view: &View<'_, F>,
    cam: &Pinhole,
    (r, t): (&Matrix3<f32>, &Vector3<f32>),
    faces: &FacePlan,
    edge_shift_px: f32,
) -> Counts {
    let (fx, fy, cx1, cy1) = (cam.fx(), cam.fy(), cam.cx() + 1.0, cam.cy() + 1.0);
    let (d, r2_max) = (*cam.distortion(), distortion_field_r2(cam));
    let proj = Projector::new([1.0, 1.0, 0.0, 0.0], r, t);
    let to_pixel = move |x: f32, y: f32, w: f32| {
        let inv = 1.0 / w;
        let (xn, yn) = (x * inv, y * inv);
        let (xd, yd) = d.apply(xn, yn);
        if xn * xn + yn * yn <= r2_max { (fx * xd + cx1, fy * yd + cy1) } else { (-1.0, -1.0) }
    };
    // One pixel is `1 / f` in normalised coordinates (the lens itself aside).
    let px_unit = 1.0 / min_finite(fx, fy);
    count_faces::<G, WALK_ALL>(model, lut, &Lens { view, to_pixel }, &proj, faces, px_unit, edge_shift_px)
}

/// The squared normalised radius within which a distorted camera's model is used: twice the
/// squared radius of the farthest image corner seen through the undistorted pinhole (so
/// 41 % beyond it in radius, more than any plumb_bob lens of a usable calibration compresses
/// its corners).
fn distortion_field_r2(cam: &Pinhole) -> f32 {
    let dx = (cam.cx().max(f32::from(cam.width()) - cam.cx())) / cam.fx();
    let dy = (cam.cy().max(f32::from(cam.height()) - cam.cy())) / cam.fy();
    2.0 * (dx * dx + dy * dy)
}

/// The faces one camera evaluates, their weights, which of them are visible (weight > 0),
/// and which faces face it.
struct FacePlan {
    chosen: [usize; 3],
    weight: [u32; 3],
    visible_mask: u8,
    front: [bool; FACES],
}

/// Whether every pose walks the same rows, [`SurfaceStrips::WALKED_PER_CAMERA`] points per
/// camera, those whose counts are discarded included: on the board, so that the measured worst
/// case is every case (`evorec timing`). The host walks only the rows that count (the inner
/// rows of visible faces and the outer rows of their silhouette edges): the same counts, with
/// work bounded by the same constant.
const CONSTANT_WORK: bool = cfg!(target_arch = "arm");

/// The counts of the planned faces, with `walk` counting the rows (every row with
/// `WALK_ALL`, see [`CONSTANT_WORK`]) and the nearest silhouette rows moved outwards by
/// `edge_shift_px`.
#[inline(always)]
fn count_faces<const G: usize, const WALK_ALL: bool>(
    model: &SurfaceStrips<G>,
    lut: &HueLut,
    walk: &impl RowWalk,
    proj: &Projector,
    faces: &FacePlan,
    px_unit: f32,
    edge_shift_px: f32,
) -> Counts {
    // The block is axis-aligned in Σ_M, so every row vector is a multiple of one column of
    // `proj.m` (the projected axis): per axis, its half size, row start, step and row offsets.
    let (half, reach, row_step) = (model.half_size(), model.row_reach(), model.row_step());
    let axes: [AxisRows; 3] = core::array::from_fn(|x| AxisRows::new(proj, x, half[x], reach[x], row_step[x]));
    let visible_mask = faces.visible_mask;
    let (sil_in_px, sil_out_px) = (SILHOUETTE_INNER_PX - edge_shift_px, SILHOUETTE_OUTER_PX + edge_shift_px);

    let mut counts = Counts { visible: visible_mask, ..Counts::default() };
    let mut outer_edges = 0usize;
    for (&k, &w) in faces.chosen.iter().zip(faces.weight.iter()) {
        let visible = visible_mask & (1u8 << k) != 0;
        // The face's axis `a` and the two others in cyclic order, `b = a + 1`, `c = a + 2`
        // (matched, not indexed: no bounds check).
        let [x, y, z] = &axes;
        let (a, (ax, bx, cx)) = match k % 3 {
            0 => (0, (x, y, z)),
            1 => (1, (y, z, x)),
            _ => (2, (z, x, y)),
        };
        let centre = if k < 3 { add(proj.c, ax.half) } else { sub(proj.c, ax.half) };
        let (mut inner, mut outer) = (0u32, 0u32);
        let scores = Scores { inner: lut.plane(k), outer: lut.any(visible_mask) };
        // Metres of the face per pixel across each pair of edges, at the face's centre.
        let mpp = metres_per_pixel(&bx.col, &cx.col, centre, px_unit);
        // Edges on the ±b sides run along c, those on the ±c sides along b (as `model::Edge`).
        for ((side, s, l), mpp) in [((a + 1) % 3, bx, cx), ((a + 2) % 3, cx, bx)].into_iter().zip(mpp) {
            // The nearest rows at fixed numbers of pixel widths from the edge (capped at the
            // second row's distance: a face seen nearly edge-on).
            let near = |px: f32| -> [f32; 3] {
                let d = min_finite(px * mpp, NEAR_ROW_CAP_M);
                s.col.map(|v| d * v)
            };
            let (sil_in, sil_out, fold_in) = (near(sil_in_px), near(sil_out_px), near(FOLD_INNER_PX));
            for positive in [true, false] {
                let (base, neighbour) = if positive {
                    (add(add(centre, s.half), l.start), side)
                } else {
                    (add(sub(centre, s.half), l.start), side + 3)
                };
                let silhouette = !faces.front.get(neighbour).copied().unwrap_or(false);
                // The inward direction is −side on the + side, +side on the − side.
                let at = |d: &[f32; 3]| if positive { sub(base, *d) } else { add(base, *d) };
                // The inner rows of a hidden face do not count: only the board walks them.
                if visible || WALK_ALL {
                    let mut offsets = s.inner;
                    offsets[0] = if silhouette { sil_in } else { fold_in };
                    let rows = EdgeRows { starts: offsets.each_ref().map(at), step: l.step, span: l.span };
                    inner += walk.count_rows::<G, { INNER_INSETS_M.len() }>(&rows, scores.inner);
                }
                // Outer rows count only on silhouette edges (the face across is hidden) of
                // visible faces: the others are not walked.
                if visible && silhouette {
                    let mut offsets = s.outer;
                    offsets[0] = sil_out.map(|v| -v);
                    let rows = EdgeRows { starts: offsets.each_ref().map(at), step: l.step, span: l.span };
                    outer += walk.count_rows::<G, { OUTER_OFFSETS_M.len() }>(&rows, scores.outer);
                    outer_edges += 1;
                }
            }
        }
        if visible {
            let total = SurfaceStrips::<G>::INNER_PER_FACE as u32;
            counts.inner_matched += inner;
            counts.inner_total += total;
            counts.strip_matched += outer;
            counts.weighted_matched += w * inner;
            counts.weighted_total += w * total;
            counts.weighted_strip += w * outer;
        }
    }
    // Constant work (the board): the outer rows of the edges that did not count are walked on
    // a fixed row (and discarded), so every pose walks `MAX_OUTER_EDGES` edges' outer rows.
    if WALK_ALL {
        let [x, ..] = &axes;
        let pad = EdgeRows { starts: x.outer.map(|d| add(proj.c, d)), step: x.step, span: x.span };
        for _ in outer_edges..MAX_OUTER_EDGES {
            core::hint::black_box(walk.count_rows::<G, { OUTER_OFFSETS_M.len() }>(&pad, lut.any(visible_mask)));
        }
    }
    counts
}

/// The projection of the rows that run along, or are offset along, one model axis `x`:
/// every vector is a multiple of `m·e_x`, the `x` column of the projector.
struct AxisRows {
    /// `m·e_x`, the projected axis.
    col: [f32; 3],
    /// `h_x · m·e_x`: face centre offset and edge offset.
    half: [f32; 3],
    /// `−reach_x · m·e_x`: first point of a row along `x`, relative to its edge's midpoint.
    start: [f32; 3],
    /// `step_x · m·e_x`: step between the points of a row along `x`.
    step: [f32; 3],
    /// `2·reach_x · m·e_x = (G − 1)·step`: from the first point of a row along `x` to its last.
    span: [f32; 3],
    /// `d_r · m·e_x` for the inner rows' distances `d_r` ([`INNER_INSETS_M`]).
    inner: [[f32; 3]; INNER_INSETS_M.len()],
    /// `−d_r · m·e_x` for the outer rows' distances `d_r` ([`OUTER_OFFSETS_M`]).
    outer: [[f32; 3]; OUTER_OFFSETS_M.len()],
}

impl AxisRows {
    #[inline(always)]
    fn new(proj: &Projector, x: usize, half: f32, reach: f32, step: f32) -> Self {
        let col = [proj.m[0][x], proj.m[1][x], proj.m[2][x]];
        let scale = |f: f32| col.map(|v| f * v);
        Self {
            col,
            half: scale(half),
            start: scale(-reach),
            step: scale(step),
            span: scale(2.0 * reach),
            inner: INNER_INSETS_M.map(scale),
            outer: OUTER_OFFSETS_M.map(|d| scale(-d)),
        }
    }
}

/// The largest distance of a nearest row from its edge: the second inner row's.
const NEAR_ROW_CAP_M: f32 = INNER_INSETS_M[1];

/// Metres of a face per pixel across its edges, at the point `centre` (homogeneous, `K'·p`)
/// of the face whose in-plane axes project to `col_b` and `col_c`: `[across the ±b edges,
/// across the ±c edges]`. The image moves by `j_x / w²` per metre along axis `x`, with
/// `j_x = (m_x,u·w − u·m_x,w, m_x,v·w − v·m_x,w)`. A row offset along `b` by `d` lies
/// `d·|j_b × j_c| / (w²·|j_c|)` from its edge (running along `c`), and a pixel is
/// `|e_u| + |e_v| = |j_c|₁ / |j_c|` wide across that edge (`e` the edge's unit direction in the
/// image): in pixel widths the row is `d·|j_b × j_c| / (w²·|j_c|₁)` from the edge (no square
/// root). Whatever the edge's slope and the point's place in its pixel, a point half a pixel
/// width inside an edge lies in a pixel whose centre is on the face (at least half of it
/// covered), and a point one width inside (outside) in a pixel wholly on (off) the face;
/// `px_unit` is one pixel in the projector's units (`FIX_ONE` for the pinhole kernel's 16.16
/// fixed point, `1 / f` for the lens kernel's normalised coordinates). A face seen edge-on gives
/// infinities, capped by the caller.
#[inline(always)]
fn metres_per_pixel(col_b: &[f32; 3], col_c: &[f32; 3], centre: [f32; 3], px_unit: f32) -> [f32; 2] {
    let [u, v, w] = centre;
    let j = |c: &[f32; 3]| [c[0] * w - u * c[2], c[1] * w - v * c[2]];
    let (jb, jc) = (j(col_b), j(col_c));
    let cross = (jb[0] * jc[1] - jb[1] * jc[0]).abs();
    let q = w * w * px_unit / cross;
    let width = |a: [f32; 2]| a[0].abs() + a[1].abs();
    [q * width(jc), q * width(jb)]
}

/// `px` within [`EDGE_SHIFT_RANGE_PX`](crate::limits::EDGE_SHIFT_RANGE_PX), the shifts of the
/// silhouette rows that keep both rows on their sides of the edge; NaN gives 0.
pub fn clamp_edge_shift(px: f32) -> f32 {
    let [lo, hi] = crate::limits::EDGE_SHIFT_RANGE_PX;
    if px.is_nan() { 0.0 } else { crate::math::clamp(px, lo, hi) }
}

/// Evaluates poses against a stereo pair: the model, its hue table and the rig, bundled, with
/// the learnt shift of the nearest silhouette rows ([`crate::edge`]; none unless set).
#[derive(Debug, Clone, Copy)]
pub struct Evaluator<'m, const G: usize> {
    model: &'m SurfaceStrips<G>,
    lut: &'m HueLut,
    rig: &'m StereoRig,
    left_r: Matrix3<f32>,
    left_t: Vector3<f32>,
    edge_shift_px: f32,
}

impl<'m, const G: usize> Evaluator<'m, G> {
    /// Bundles a model, its hue table and a rig; the silhouette rows where
    /// [`SILHOUETTE_INNER_PX`] and [`SILHOUETTE_OUTER_PX`] put them.
    pub fn new(model: &'m SurfaceStrips<G>, lut: &'m HueLut, rig: &'m StereoRig) -> Self {
        let lr = &rig.left_from_right;
        Self {
            model,
            lut,
            rig,
            left_r: crate::quat::to_rotation_matrix(&lr.rotation),
            left_t: lr.translation.vector,
            edge_shift_px: 0.0,
        }
    }

    /// Builder: the nearest silhouette rows moved outwards by `px` pixel widths (inwards for
    /// `px < 0`), clamped to [`EDGE_SHIFT_RANGE_PX`](crate::limits::EDGE_SHIFT_RANGE_PX) so that
    /// they stay on their sides of the edge (NaN: no shift).
    #[must_use]
    pub fn with_edge_shift(mut self, px: f32) -> Self {
        self.edge_shift_px = clamp_edge_shift(px);
        self
    }

    /// The rig the poses are evaluated against.
    pub fn rig(&self) -> &StereoRig {
        self.rig
    }

    /// `F(ψ)` (eq. 35) for a pose given as rotation `r` and translation `t` in `Σ_CR`.
    pub fn evaluate<B: AsRef<[u8]>, F: PixelFormat>(
        &self,
        r: &Matrix3<f32>,
        t: &Vector3<f32>,
        left: &Image<B, F>,
        right: &Image<B, F>,
    ) -> Fitness {
        self.evaluate_apart(r, [t, t], left, right)
    }

    /// `F(ψ)` with each camera seeing the block at its own translation, `t_right` in the right
    /// camera and `t_left` in the left one (both in `Σ_CR`, same rotation `r`): a block whose
    /// disparity differs from its pose's (the disparity test of [`crate::edge`]).
    pub fn evaluate_apart<B: AsRef<[u8]>, F: PixelFormat>(
        &self,
        r: &Matrix3<f32>,
        [t_right, t_left]: [&Vector3<f32>; 2],
        left: &Image<B, F>,
        right: &Image<B, F>,
    ) -> Fitness {
        let shift = self.edge_shift_px;
        let right_counts =
            counts_walking::<G, B, F, CONSTANT_WORK>(self.model, self.lut, &self.rig.right, right, r, t_right, shift);
        let (r_left, t_left) = (self.left_r * r, self.left_r * t_left + self.left_t);
        let left_counts = counts_walking::<G, B, F, CONSTANT_WORK>(
            self.model,
            self.lut,
            &self.rig.left,
            left,
            &r_left,
            &t_left,
            shift,
        );
        Fitness { total: 0.5 * (left_counts.score() + right_counts.score()), left: left_counts, right: right_counts }
    }

    /// How many faces of the pose `(r, t)` (in `Σ_CR`) each camera sees at full weight (see
    /// [`FULL_VISIBLE_COS`]), `[left, right]`: a few operations per face, no image access.
    pub fn full_faces(&self, r: &Matrix3<f32>, t: &Vector3<f32>) -> [u32; 2] {
        let (r_left, t_left) = (self.left_r * r, self.left_r * t + self.left_t);
        [full_faces_of(self.model, &self.rig.left, &r_left, &t_left), full_faces_of(self.model, &self.rig.right, r, t)]
    }

    /// The colour census of a pose given as rotation `r` and translation `t` in `Σ_CR` in
    /// both cameras: `visit(k, hues)` with the hue bytes under the census points of each row
    /// of every visible face `k` (see [`crate::colour`]).
    pub fn census<B: AsRef<[u8]>, F: PixelFormat>(
        &self,
        r: &Matrix3<f32>,
        t: &Vector3<f32>,
        left: &Image<B, F>,
        right: &Image<B, F>,
        visit: &mut dyn FnMut(usize, &[u8]),
    ) {
        census::camera_census(self.model, &self.rig.right, right, r, t, visit);
        let (r_left, t_left) = (self.left_r * r, self.left_r * t + self.left_t);
        census::camera_census(self.model, &self.rig.left, left, &r_left, &t_left, visit);
    }

    /// `F(ψ)` for a 6-parameter pose (assumed valid: finite, `|ε| ≤ 1`).
    pub fn evaluate_psi<B: AsRef<[u8]>, F: PixelFormat>(
        &self,
        psi: &Psi,
        left: &Image<B, F>,
        right: &Image<B, F>,
    ) -> Fitness {
        self.evaluate(&psi.rotation_unchecked(), &psi.translation(), left, right)
    }
}

mod census;
mod view;

use view::View;
#[cfg(test)]
mod tests;
