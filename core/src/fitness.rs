//! The hue fitness of a pose (paper §4.2, eq. 34–35).
//!
//! For one camera with the model at pose `(R, t)` in that camera's frame:
//!
//! ```text
//! F_c = max(0, Σ_k∈visible Σ_{p ∈ S_in,k} δ(h(p) ≈ b_k)  −  Σ_{p ∈ S_out} δ(h(p) ≈ any visible b_k)) / H
//! H   = G² · (number of visible faces)
//! F   = (F_L + F_R) / 2
//! ```
//!
//! where `≈` is the [`HueLut`] tolerance band, a face is visible when it faces the camera at
//! less than ~84° ([`MIN_VISIBLE_COS`]) and spans at least [`MIN_FACE_PX`] pixels, `S_in,k` the inner rows of face `k`, `H` their
//! number on the visible faces, and `S_out` the outer rows on silhouette edges only (see
//! [`crate::model`]). A pose whose block is not entirely in front of a camera scores 0 in that
//! camera.
//!
//! **Bounded work.** Of each pair of opposite faces exactly one can face a camera, so each
//! camera evaluates three faces (the one of each pair on the camera's side),
//! [`SurfaceStrips::POINTS_PER_CAMERA`] points, whether or not a face is visible or a strip
//! is on the silhouette: the visibility only masks the counts. Points outside the image read as "no hue"; nothing is ever read
//! out of bounds.
//!
//! **Per point** (plain pinhole): three additions (the row is walked in homogeneous
//! coordinates), one division, two multiplications, two truncating float→int conversions, one
//! unsigned compare per axis, the slice's bounds check, the pixel load, for RGB565 one load
//! from the 64 KiB hue table ([`crate::image::RGB565_HUE`]), and one load from the hue match
//! table. **Per pose** the block's axis-aligned structure is used: every row start, step and
//! offset is a multiple of one projected model axis, precomputed once per camera and pose.
//!
//! **Lens distortion.** A camera with [`crate::camera::Distortion`] ≠ 0 takes the distorted
//! kernel, chosen once per camera and pose (a camera without distortion pays nothing): rows are
//! walked in normalised coordinates and every point goes through the plumb_bob polynomial and
//! `K` (about 20 more float operations). Points beyond the calibrated field (see
//! `distortion_field_r2`) read as outside the image.

use nalgebra::{Matrix3, Vector3};

use crate::camera::{Pinhole, StereoRig};
use crate::config::{
    INNER_INSETS_M, MIN_DEPTH_M, MIN_FACE_PX, MIN_VISIBLE_COS, NO_HUE, OUTER_OFFSETS_M, ROWS_PER_EDGE,
};
use crate::hue::HueLut;
use crate::image::{Image, PixelFormat};
use crate::model::{FACES, ROW_DISTANCES_M, SurfaceStrips};
use crate::pose::Psi;

/// Match counts of one camera.
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
}

impl Counts {
    /// `F_c = max(0, matched − strip_matched) / H`, or 0 when no face is visible.
    pub fn score(&self) -> f32 {
        if self.inner_total == 0 {
            return 0.0;
        }
        let net = self.inner_matched.saturating_sub(self.strip_matched);
        net as f32 / self.inner_total as f32
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

/// A borrowed image reduced to what the inner loop needs.
#[derive(Clone, Copy)]
struct View<'a, F: PixelFormat> {
    pixels: &'a [F::Pixel],
    width: u32,
    height: u32,
}

impl<'a, F: PixelFormat> View<'a, F> {
    fn of<B: AsRef<[u8]>>(img: &'a Image<B, F>) -> Self {
        Self { pixels: img.pixels(), width: u32::from(img.width()), height: u32::from(img.height()) }
    }

    /// The hue byte at the point whose pixel coordinates plus one are `(u1, v1)`, or `NO_HUE`
    /// outside the image.
    ///
    /// Pixel `(i, j)` covers `[i, i+1) × [j, j+1)`. The projector adds 1 to both coordinates,
    /// so for every point inside the image `u1, v1 ≥ 1` and the truncating conversion
    /// `as i32` (saturating, NaN → 0: the same definition on every target, one `VCVT` on the
    /// M4) gives `i + 1` and `j + 1` exactly, while every point left of or above the image
    /// gives 0 or less. Minus 1, as unsigned numbers, they are `i` and `j` inside the image and
    /// `≥ width` / `≥ height` everywhere else: one compare per axis.
    #[inline(always)]
    fn hue(&self, u1: f32, v1: f32) -> u8 {
        let col = (u1 as i32 as u32).wrapping_sub(1);
        let row = (v1 as i32 as u32).wrapping_sub(1);
        if col >= self.width || row >= self.height {
            return NO_HUE;
        }
        match self.pixels.get((row * self.width + col) as usize) {
            Some(&px) => F::hue(px),
            None => NO_HUE,
        }
    }
}

/// Sums `score(hue)` over the `G` points `start + i·step` of one row, walked by adding
/// `step` (three additions per point).
#[inline(always)]
fn count_row<const G: usize, F: PixelFormat>(
    view: &View<'_, F>,
    to_pixel: impl Fn(f32, f32, f32) -> (f32, f32),
    score: impl Fn(u8) -> u32,
    start: [f32; 3],
    step: [f32; 3],
) -> u32 {
    let [mut x, mut y, mut w] = start;
    let mut hits = 0u32;
    for _ in 0..G {
        let (u1, v1) = to_pixel(x, y, w);
        hits += score(view.hue(u1, v1));
        x += step[0];
        y += step[1];
        w += step[2];
    }
    hits
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

/// Counts of one camera for the model at `(r, t)` in that camera's frame.
///
/// The work is the same for every pose: see the module docs.
pub fn camera_counts<const G: usize, B: AsRef<[u8]>, F: PixelFormat>(
    model: &SurfaceStrips<G>,
    lut: &HueLut,
    cam: &Pinhole,
    image: &Image<B, F>,
    r: &Matrix3<f32>,
    t: &Vector3<f32>,
) -> Counts {
    let view = View::of(image);
    let half = model.half_size();
    let focal = cam.fx().min(cam.fy());

    // Nearest depth of the block inflated by the outer rows (every sample point is inside it).
    let margin = OUTER_OFFSETS_M.iter().fold(0.0f32, |m, d| m.max(*d));
    let reach = |a: usize| r[(2, a)].abs() * (half[a] + margin);
    let in_front = t.z - (reach(0) + reach(1) + reach(2)) > MIN_DEPTH_M;

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

    // The face of each opposite pair that is on the camera's side, and whether it is visible.
    let mut chosen = [0usize; 3];
    let mut visible_mask = 0u8;
    for (a, (ck, da)) in chosen.iter_mut().zip(d.iter()).enumerate() {
        let k = if *da < 0.0 { a } else { a + 3 };
        *ck = k;
        let dist = da.abs() - half[a];
        let sign = if k < 3 { 1.0 } else { -1.0 };
        let center = t + r.column(a) * (sign * half[a]);
        let c2 = center.dot(&center);
        // Narrowest full side of the face, and its foreshortened size in pixels ≥ MIN_FACE_PX:
        // f · side · (dist / |c|) / |c| ≥ MIN_FACE_PX.
        let side = 2.0 * half[(a + 1) % 3].min(half[(a + 2) % 3]);
        if in_front
            && dist > 0.0
            && dist * dist > MIN_VISIBLE_COS * MIN_VISIBLE_COS * c2
            && focal * side * dist >= MIN_FACE_PX * c2
        {
            visible_mask |= 1 << k;
        }
    }

    let faces = FacePlan { chosen, visible_mask, front: core::array::from_fn(|k| front(k as u8)) };
    // K' with the principal point moved by +1 pixel for `View::hue`.
    let (fx, fy, cx1, cy1) = (cam.fx(), cam.fy(), cam.cx() + 1.0, cam.cy() + 1.0);
    if cam.distortion().is_none() {
        let proj = Projector::new([fx, fy, cx1, cy1], r, t);
        count_faces(model, lut, &view, &proj, &faces, |x, y, w| {
            let inv = 1.0 / w;
            (x * inv, y * inv)
        })
    } else {
        // Normalised coordinates, then the lens, then K'. Beyond `r2_max` the plumb_bob
        // polynomial is outside the calibrated field (and may fold back into the image):
        // such points read as outside.
        distorted_counts(model, lut, &view, cam, r, t, &faces)
    }
}

/// [`count_faces`] through the lens of `cam` (kept out of line so the plain kernel's code and
/// its unrolling do not change with it).
#[inline(never)]
fn distorted_counts<const G: usize, F: PixelFormat>(
    model: &SurfaceStrips<G>,
    lut: &HueLut,
    view: &View<'_, F>,
    cam: &Pinhole,
    r: &Matrix3<f32>,
    t: &Vector3<f32>,
    faces: &FacePlan,
) -> Counts {
    let (fx, fy, cx1, cy1) = (cam.fx(), cam.fy(), cam.cx() + 1.0, cam.cy() + 1.0);
    let (d, r2_max) = (*cam.distortion(), distortion_field_r2(cam));
    let proj = Projector::new([1.0, 1.0, 0.0, 0.0], r, t);
    count_faces(model, lut, view, &proj, faces, move |x, y, w| {
        let inv = 1.0 / w;
        let (xn, yn) = (x * inv, y * inv);
        let (xd, yd) = d.apply(xn, yn);
        if xn * xn + yn * yn <= r2_max { (fx * xd + cx1, fy * yd + cy1) } else { (-1.0, -1.0) }
    })
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

/// The faces one camera evaluates, which of them are visible, and which faces face it.
struct FacePlan {
    chosen: [usize; 3],
    visible_mask: u8,
    front: [bool; FACES],
}

/// The counts of the planned faces, with `to_pixel(x, y, w)` mapping a projected homogeneous
/// point to its pixel coordinates plus one.
#[inline(always)]
fn count_faces<const G: usize, F: PixelFormat>(
    model: &SurfaceStrips<G>,
    lut: &HueLut,
    view: &View<'_, F>,
    proj: &Projector,
    faces: &FacePlan,
    to_pixel: impl Fn(f32, f32, f32) -> (f32, f32) + Copy,
) -> Counts {
    // The block is axis-aligned in Σ_M, so every row vector is a multiple of one column of
    // `proj.m` (the projected axis): per axis, its half size, row start, step and row offsets.
    let (half, reach, row_step) = (model.half_size(), model.row_reach(), model.row_step());
    let axes: [AxisRows; 3] = core::array::from_fn(|x| AxisRows::new(proj, x, half[x], reach[x], row_step[x]));
    let visible_mask = faces.visible_mask;

    let mut counts = Counts { visible: visible_mask, ..Counts::default() };
    for &k in &faces.chosen {
        let bit = 1u8 << k;
        let plane = lut.plane(k);
        let a = k % 3;
        let centre = if k < 3 { add(proj.c, axes[a].half) } else { sub(proj.c, axes[a].half) };
        let (mut inner, mut outer) = (0u32, 0u32);
        // Edges on the ±b sides run along c, those on the ±c sides along b (as `model::Edge`).
        for (side, along) in [((a + 1) % 3, (a + 2) % 3), ((a + 2) % 3, (a + 1) % 3)] {
            let (s, l) = (&axes[side], &axes[along]);
            for positive in [true, false] {
                let (base, neighbour) = if positive {
                    (add(add(centre, s.half), l.start), side)
                } else {
                    (add(sub(centre, s.half), l.start), side + 3)
                };
                // The inward direction is −side on the + side, +side on the − side.
                let row = |r: usize| if positive { sub(base, s.rows[r]) } else { add(base, s.rows[r]) };
                for r in 0..INNER_INSETS_M.len() {
                    inner += count_row::<G, F>(view, to_pixel, |h| u32::from(plane[usize::from(h)]), row(r), l.step);
                }
                let mut hits = 0u32;
                for r in INNER_INSETS_M.len()..ROWS_PER_EDGE {
                    let score = |h| u32::from(lut.mask(h) & visible_mask != 0);
                    hits += count_row::<G, F>(view, to_pixel, score, row(r), l.step);
                }
                // Outer rows count only on silhouette edges (the face across is hidden).
                if !faces.front.get(neighbour).copied().unwrap_or(false) {
                    outer += hits;
                }
            }
        }
        if visible_mask & bit != 0 {
            counts.inner_matched += inner;
            counts.inner_total += SurfaceStrips::<G>::INNER_PER_FACE as u32;
            counts.strip_matched += outer;
        }
    }
    counts
}

/// The projection of the rows that run along, or are offset along, one model axis `x`:
/// every vector is a multiple of `m·e_x`, the `x` column of the projector.
struct AxisRows {
    /// `h_x · m·e_x`: face centre offset and edge offset.
    half: [f32; 3],
    /// `−reach_x · m·e_x`: first point of a row along `x`, relative to its edge's midpoint.
    start: [f32; 3],
    /// `step_x · m·e_x`: step between the points of a row along `x`.
    step: [f32; 3],
    /// `d_r · m·e_x` for every row distance `d_r` of [`ROW_DISTANCES_M`].
    rows: [[f32; 3]; ROWS_PER_EDGE],
}

impl AxisRows {
    #[inline(always)]
    fn new(proj: &Projector, x: usize, half: f32, reach: f32, step: f32) -> Self {
        let col = [proj.m[0][x], proj.m[1][x], proj.m[2][x]];
        let scale = |f: f32| col.map(|v| f * v);
        Self { half: scale(half), start: scale(-reach), step: scale(step), rows: ROW_DISTANCES_M.map(scale) }
    }
}

/// Evaluates poses against a stereo pair: the model, its hue table and the rig, bundled.
#[derive(Debug, Clone, Copy)]
pub struct Evaluator<'m, const G: usize> {
    model: &'m SurfaceStrips<G>,
    lut: &'m HueLut,
    rig: &'m StereoRig,
    left_r: Matrix3<f32>,
    left_t: Vector3<f32>,
}

impl<'m, const G: usize> Evaluator<'m, G> {
    /// Bundles a model, its hue table and a rig.
    pub fn new(model: &'m SurfaceStrips<G>, lut: &'m HueLut, rig: &'m StereoRig) -> Self {
        let lr = &rig.left_from_right;
        Self { model, lut, rig, left_r: crate::quat::to_rotation_matrix(&lr.rotation), left_t: lr.translation.vector }
    }

    /// `F(ψ)` (eq. 35) for a pose given as rotation `r` and translation `t` in `Σ_CR`.
    pub fn evaluate<B: AsRef<[u8]>, F: PixelFormat>(
        &self,
        r: &Matrix3<f32>,
        t: &Vector3<f32>,
        left: &Image<B, F>,
        right: &Image<B, F>,
    ) -> Fitness {
        let right_counts = camera_counts(self.model, self.lut, &self.rig.right, right, r, t);
        let (r_left, t_left) = (self.left_r * r, self.left_r * t + self.left_t);
        let left_counts = camera_counts(self.model, self.lut, &self.rig.left, left, &r_left, &t_left);
        Fitness { total: 0.5 * (left_counts.score() + right_counts.score()), left: left_counts, right: right_counts }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Pinhole;
    use crate::config::DEFAULT_HUE_TOLERANCE;
    use crate::hue::HueImage;
    use crate::model::Block;
    use crate::synth;
    use std::vec;

    const W: u16 = 640;
    const H: u16 = 480;

    fn rig() -> StereoRig {
        StereoRig::parallel(Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, W, H).unwrap(), 0.1).unwrap()
    }

    fn scene(psi: &Psi) -> (std::vec::Vec<u8>, std::vec::Vec<u8>) {
        let rig = rig();
        let iso = psi.try_to_isometry().unwrap();
        let mut right = vec![NO_HUE; usize::from(W) * usize::from(H)];
        let mut left = right.clone();
        synth::render_block(&Block::PAPER, &rig.right, &iso, &mut right).unwrap();
        synth::render_block(&Block::PAPER, &rig.left, &(rig.left_from_right * iso), &mut left).unwrap();
        (left, right)
    }

    #[test]
    fn true_pose_scores_exactly_one_and_perturbations_score_less() {
        let model = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
        let hues = model.faces().map(|f| f.hue);
        let lut = HueLut::new(&hues, DEFAULT_HUE_TOLERANCE);
        let rig = rig();
        let eval = Evaluator::new(&model, &lut, &rig);
        // A corner towards the camera, so three faces are visible: the model diagonal (1,1,1)
        // turned most of the way onto the camera's −z.
        let q = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
        let truth = Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q);
        let (l, r) = scene(&truth);
        let left = HueImage::new_checked(&l[..], W, H).unwrap();
        let right = HueImage::new_checked(&r[..], W, H).unwrap();
        let f = eval.evaluate_psi(&truth, &left, &right);
        assert_eq!(f.total, 1.0, "{f:?}");
        assert_eq!(f.right.visible.count_ones(), 3);
        assert_eq!(f.right.inner_total, 3 * SurfaceStrips::<8>::INNER_PER_FACE as u32);
        // Every perturbation of 8 mm or 0.03 in ε lowers F.
        for i in 0..6 {
            for sign in [-1.0f32, 1.0] {
                let mut p = truth;
                p.0[i] += sign * if i < 3 { 0.008 } else { 0.03 };
                let fp = eval.evaluate_psi(&p, &left, &right).total;
                assert!(fp < 1.0, "gene {i} {sign}: {fp}");
            }
        }
        // Far away poses score (close to) nothing.
        let far = Psi::new([0.25, 0.2, 1.1], [0.0; 3]);
        assert!(eval.evaluate_psi(&far, &left, &right).total < 0.2);
        // A pose behind the camera scores 0 without reading out of bounds.
        let behind = Psi::new([0.0, 0.0, -0.5], [0.0; 3]);
        assert_eq!(eval.evaluate_psi(&behind, &left, &right).total, 0.0);
    }

    /// A fully saturated, bright RGB565 colour of hue byte `h` (black for `NO_HUE`).
    fn hue_to_rgb565(h: u8) -> [u8; 2] {
        if h == NO_HUE {
            return [0, 0];
        }
        let deg = 2.0 * f32::from(h);
        let f = |n: f32| {
            let k = (n + deg / 60.0) % 6.0;
            (255.0 * (1.0 - k.min(4.0 - k).clamp(0.0, 1.0))) as u8
        };
        crate::image::rgb888_to_rgb565(f(5.0), f(3.0), f(1.0)).to_le_bytes()
    }

    #[test]
    fn rgb565_frames_score_as_their_hue_frames() {
        use crate::image::{Rgb565, Rgb565Image};
        let model = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
        let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
        let rig = rig();
        let eval = Evaluator::new(&model, &lut, &rig);
        let q = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
        let truth = Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q);
        let (l, r) = scene(&truth);
        let to565 = |img: &[u8]| img.iter().flat_map(|&h| hue_to_rgb565(h)).collect::<std::vec::Vec<u8>>();
        let (l5, r5) = (to565(&l), to565(&r));
        for (h, px) in l.iter().zip(l5.chunks(2)) {
            assert_eq!(crate::image::rgb565_to_hue(u16::from_le_bytes([px[0], px[1]])), *h);
        }
        let (left, right) =
            (HueImage::new_checked(&l[..], W, H).unwrap(), HueImage::new_checked(&r[..], W, H).unwrap());
        let left5: Rgb565Image<&[u8]> = Rgb565Image::new_checked(&l5[..], W, H).unwrap();
        let right5 = crate::image::Image::<_, Rgb565>::new_checked(&r5[..], W, H).unwrap();
        for i in 0..12 {
            let mut p = truth;
            p.0[i % 6] += if i < 6 { 0.004 } else { -0.02 };
            assert_eq!(eval.evaluate_psi(&p, &left, &right), eval.evaluate_psi(&p, &left5, &right5), "{i}");
        }
        assert_eq!(eval.evaluate_psi(&truth, &left5, &right5).total, 1.0);
    }

    #[test]
    fn distorted_kernel_samples_where_the_lens_projects() {
        use crate::camera::Distortion;
        let model = SurfaceStrips::<8>::new(&Block::PAPER).unwrap();
        let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
        let q = crate::quat::from_angle_axis(2.0, &Vector3::new(-1.0, 1.0, 0.1)).unwrap();
        let truth = Psi::from_parts(&Vector3::new(0.02, -0.01, 0.75), &q);
        let (_, img) = scene(&truth);
        let image = HueImage::new_checked(&img[..], W, H).unwrap();
        let (r, t) = (truth.rotation_unchecked(), truth.translation());
        let plain = rig().right;
        let plain_counts = camera_counts(&model, &lut, &plain, &image, &r, &t);
        // A negligible lens takes the distorted kernel and must count (almost) the same.
        let tiny = plain.with_distortion(Distortion::plumb_bob([1e-7, 0.0, 0.0, 0.0, 0.0]).unwrap());
        let tiny_counts = camera_counts(&model, &lut, &tiny, &image, &r, &t);
        assert_eq!(tiny_counts.visible, plain_counts.visible);
        assert!(
            tiny_counts.inner_matched.abs_diff(plain_counts.inner_matched) <= 2,
            "{tiny_counts:?} {plain_counts:?}"
        );
        // A real lens moves the samples: on the undistorted image, the match drops.
        let barrel = plain.with_distortion(Distortion::plumb_bob([-0.3, 0.1, 0.0, 0.0, 0.0]).unwrap());
        let barrel_counts = camera_counts(&model, &lut, &barrel, &image, &r, &t);
        assert!(barrel_counts.score() < plain_counts.score(), "{barrel_counts:?} {plain_counts:?}");
        assert!(barrel_counts.strip_matched > 0, "{barrel_counts:?}");
        // A point far outside the field never reads a pixel, whatever the polynomial does.
        let p = Psi::new([5.0, 0.0, 0.5], [0.0; 3]);
        let far = camera_counts(&model, &lut, &barrel, &image, &p.rotation_unchecked(), &p.translation());
        assert_eq!(far.inner_matched + far.strip_matched, 0);
    }

    #[test]
    fn a_blank_image_scores_zero() {
        let model = SurfaceStrips::<4>::new(&Block::PAPER).unwrap();
        let lut = HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE);
        let rig = rig();
        let eval = Evaluator::new(&model, &lut, &rig);
        let blank = vec![NO_HUE; usize::from(W) * usize::from(H)];
        let img = HueImage::new_checked(&blank[..], W, H).unwrap();
        let f = eval.evaluate_psi(&Psi::new([0.0, 0.0, 0.7], [0.0; 3]), &img, &img);
        assert_eq!(f.total, 0.0);
        assert!(f.right.inner_total > 0);
    }

    #[test]
    fn score_clamps_at_zero() {
        let c = Counts { inner_matched: 3, inner_total: 10, strip_matched: 7, visible: 1 };
        assert_eq!(c.score(), 0.0);
        let c = Counts { inner_matched: 7, inner_total: 10, strip_matched: 2, visible: 1 };
        assert!((c.score() - 0.5).abs() < 1e-7);
    }
}
