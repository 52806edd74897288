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
//! out of bounds. Per point: three additions (grid walk in homogeneous coordinates), one
//! division, two multiplications, two float→int conversions, a bounds test, two table loads.

use nalgebra::{Matrix3, Vector3};

use crate::camera::{Pinhole, StereoRig};
use crate::config::{INNER_INSETS_M, MIN_DEPTH_M, MIN_FACE_PX, MIN_VISIBLE_COS, NO_HUE, OUTER_OFFSETS_M};
use crate::hue::HueLut;
use crate::image::{Image, PixelFormat};
use crate::model::SurfaceStrips;
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
}

impl<'a, F: PixelFormat> View<'a, F> {
    fn of<B: AsRef<[u8]>>(img: &'a Image<B, F>) -> Self {
        Self { pixels: img.pixels(), width: u32::from(img.width()) }
    }

    /// 1 if pixel `(u, v)` (wrapping values from [`round_bits`]) is inside the image and its
    /// hue mask intersects `want`, else 0.
    ///
    /// Rounding uses the exact float trick `(v + 1.5·2²³).to_bits() − bits(1.5·2²³)`, which is
    /// the round-to-nearest integer for |v| < 2²²; every value outside that range, negative,
    /// infinite or NaN lands far outside `0..width` as an unsigned number, so one unsigned
    /// compare per axis rejects it. Branch-free, no saturating conversion, and the same IEEE
    /// operations on every target.
    #[inline(always)]
    fn hit(&self, lut: &HueLut, want: u8, u: u32, v: u32) -> u32 {
        // Row-major index in 64 bits (no wrap-around); the slice's own bounds check then rejects
        // every v outside the image, so only u needs a test of its own.
        let index = if u < self.width { u64::from(v) * u64::from(self.width) + u64::from(u) } else { u64::MAX };
        let h = match usize::try_from(index).ok().and_then(|i| self.pixels.get(i)) {
            Some(&px) => F::hue(px),
            None => NO_HUE,
        };
        u32::from(lut.mask(h) & want != 0)
    }
}

/// Counts the points of one row whose hue mask intersects `want`. The row has `G` points
/// `start + i·step`, walked by adding `step` (three additions per point).
#[inline(always)]
fn count_row<const G: usize, F: PixelFormat>(
    view: &View<'_, F>,
    lut: &HueLut,
    want: u8,
    start: [f32; 3],
    step: [f32; 3],
) -> u32 {
    let [mut x, mut y, mut w] = start;
    let mut hits = 0u32;
    for _ in 0..G {
        let inv = 1.0 / w;
        hits += view.hit(lut, want, round_bits(x * inv), round_bits(y * inv));
        x += step[0];
        y += step[1];
        w += step[2];
    }
    hits
}

/// `1.5 · 2²³`: adding it to a float of magnitude below 2²² leaves the rounded integer in the
/// low mantissa bits.
const ROUND_MAGIC: f32 = 12_582_912.0;

/// Round-to-nearest of `v` as a wrapping `u32` (see [`View::sample`]).
#[inline(always)]
fn round_bits(v: f32) -> u32 {
    (v + ROUND_MAGIC).to_bits().wrapping_sub(ROUND_MAGIC.to_bits())
}

#[inline(always)]
fn add(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// `K'·R` and `K'·t`, the pose composed with the intrinsics (principal point shifted by −½
/// pixel for [`View::sample`]'s rounding).
struct Projector {
    m: [[f32; 3]; 3],
    c: [f32; 3],
}

impl Projector {
    fn new(cam: &Pinhole, r: &Matrix3<f32>, t: &Vector3<f32>) -> Self {
        let (fx, fy, cx, cy) = (cam.fx(), cam.fy(), cam.cx() - 0.5, cam.cy() - 0.5);
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

    #[inline(always)]
    fn dir(&self, v: &Vector3<f32>) -> [f32; 3] {
        let [a, b, c] = self.m;
        [
            a[0] * v.x + a[1] * v.y + a[2] * v.z,
            b[0] * v.x + b[1] * v.y + b[2] * v.z,
            c[0] * v.x + c[1] * v.y + c[2] * v.z,
        ]
    }

    #[inline(always)]
    fn point(&self, v: &Vector3<f32>) -> [f32; 3] {
        add(self.dir(v), self.c)
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
    let proj = Projector::new(cam, r, t);
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

    let mut counts = Counts { visible: visible_mask, ..Counts::default() };
    for &k in &chosen {
        let Some(face) = model.faces().get(k) else { continue };
        let bit = 1u8 << k;
        let (mut inner, mut outer) = (0u32, 0u32);
        for edge in &face.edges {
            let step = proj.dir(&edge.step);
            let base = proj.point(&edge.base);
            let inward = proj.dir(&edge.inward);
            let row_start = |dist: f32| -> [f32; 3] {
                [base[0] + dist * inward[0], base[1] + dist * inward[1], base[2] + dist * inward[2]]
            };
            for &dist in &INNER_INSETS_M {
                inner += count_row::<G, F>(&view, lut, bit, row_start(dist), step);
            }
            let mut hits = 0u32;
            for &dist in &OUTER_OFFSETS_M {
                hits += count_row::<G, F>(&view, lut, visible_mask, row_start(-dist), step);
            }
            // Outer rows count only on silhouette edges (the face across is hidden).
            if !front(edge.neighbour) {
                outer += hits;
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
