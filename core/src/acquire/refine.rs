//! Step 4 of the acquisition: damped Gauss–Newton refinement of a seed on the face images.

// `!(x > y)` on purpose: true for NaN too, so a NaN never passes a check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{Matrix3, Point2, Vector3};

use super::{HueBlobs, Seed, column, linalg, seed_pose_from};
use crate::camera::{Pinhole, StereoRig};
use crate::math;
use crate::quat;

/// Gauss–Newton iterations of a complete refinement ([`refine`], [`super::Acquisition`]).
pub const REFINE_ITERATIONS: usize = 6;

/// Area (px²) and area centroid of the image of face `k` of a block with half sizes `half`
/// at `(r, t)` in `cam`'s frame, or zero area when the face is turned away; `None` when a
/// corner is behind the camera.
fn face_image(
    cam: &Pinhole,
    r: &Matrix3<f32>,
    t: &Vector3<f32>,
    half: &[f32; 3],
    k: usize,
) -> Option<(f32, Point2<f32>)> {
    let a = k % 3;
    let sign = if k < 3 { 1.0 } else { -1.0 };
    let n = column(r, a) * sign;
    let centre = t + n * half.get(a).copied().unwrap_or(0.0);
    if n.dot(&centre) >= 0.0 {
        return Some((0.0, Point2::origin()));
    }
    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
    let eb = column(r, b) * half.get(b).copied().unwrap_or(0.0);
    let ec = column(r, c) * half.get(c).copied().unwrap_or(0.0);
    let mut p = [Point2::origin(); 4];
    for (q, (sb, sc)) in p.iter_mut().zip([(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]) {
        let x = centre + eb * sb + ec * sc;
        if !(x.z > 1e-3) {
            return None;
        }
        *q = Point2::new(cam.fx() * x.x / x.z + cam.cx(), cam.fy() * x.y / x.z + cam.cy());
    }
    let (mut area2, mut cx, mut cy) = (0.0f32, 0.0f32, 0.0f32);
    for (i, &p0) in p.iter().enumerate() {
        let p1 = p.get((i + 1) % 4).copied().unwrap_or(p0);
        let cross = p0.x * p1.y - p1.x * p0.y;
        area2 += cross;
        cx += (p0.x + p1.x) * cross;
        cy += (p0.y + p1.y) * cross;
    }
    if area2.abs() < 1e-6 {
        return Some((0.0, Point2::origin()));
    }
    Some((0.5 * area2.abs(), Point2::new(cx / (3.0 * area2), cy / (3.0 * area2))))
}

/// Number of residuals of [`residuals`]: per camera and axis, the centroid (2) and the
/// square root of the area (1).
const RESIDUALS: usize = 2 * 3 * 3;

/// Measured minus predicted face images of the pose `(r, t)` in `Σ_CR`: centroid
/// differences (px) for axes seen in that image, square-root-of-area differences (px) for all.
fn residuals(
    rig: &StereoRig,
    half: &[f32; 3],
    blobs: [&HueBlobs; 2],
    min_hits: u32,
    pixel_area: f32,
    r: &Matrix3<f32>,
    t: &Vector3<f32>,
) -> Option<[f32; RESIDUALS]> {
    let lr = quat::to_rotation_matrix(&rig.left_from_right.rotation);
    let poses = [(*r, *t, &rig.right), (lr * r, lr * t + rig.left_from_right.translation.vector, &rig.left)];
    let mut out = [0.0f32; RESIDUALS];
    let mut slots = out.iter_mut();
    for ((rc, tc, cam), blob) in poses.iter().zip(blobs) {
        for a in 0..3 {
            // The face of the pair that faces the camera (the other one has zero area).
            let (fa, fc) = face_image(cam, rc, tc, half, a)?;
            let (fb, fd) = face_image(cam, rc, tc, half, a + 3)?;
            let (area, centroid) = if fa >= fb { (fa, fc) } else { (fb, fd) };
            let hits = blob.count.get(a).copied().unwrap_or(0);
            let measured = math::sqrt(hits as f32 * pixel_area);
            let (du, dv) = match blob.centroid(a) {
                Some(m) if hits >= min_hits && area > 0.0 => (m.x - centroid.x, m.y - centroid.y),
                _ => (0.0, 0.0),
            };
            for v in [du, dv, measured - math::sqrt(area)] {
                if let Some(slot) = slots.next() {
                    *slot = v;
                }
            }
        }
    }
    Some(out)
}

fn cost(r: &[f32; RESIDUALS]) -> f32 {
    r.iter().map(|x| x * x).sum()
}

/// The pose `(r, t)` moved by `d = [δt; δθ]` (`δθ` a rotation vector applied on the left).
fn moved(r: &Matrix3<f32>, t: &Vector3<f32>, d: &[f32; 6]) -> (Matrix3<f32>, Vector3<f32>) {
    let w = Vector3::new(d[3], d[4], d[5]) * 0.5;
    let n = math::sqrt(1.0 + w.dot(&w));
    let q = nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(1.0 / n, w.x / n, w.y / n, w.z / n));
    (quat::to_rotation_matrix(&q) * r, t + Vector3::new(d[0], d[1], d[2]))
}

/// Everything the residuals are measured against: the blobs of one scan and the rig.
#[derive(Debug, Clone, Copy)]
pub struct Measured<'a> {
    /// The stereo rig.
    pub rig: &'a StereoRig,
    /// The block's half sizes (m).
    pub half: &'a [f32; 3],
    /// Blobs of the left image.
    pub left: &'a HueBlobs,
    /// Blobs of the right image.
    pub right: &'a HueBlobs,
    /// Scan stride (one grid hit stands for `stride²` pixels of area).
    pub stride: u16,
    /// Hits for a face's centroid to count.
    pub min_hits: u32,
}

impl Measured<'_> {
    fn residuals(&self, r: &Matrix3<f32>, t: &Vector3<f32>) -> Option<[f32; RESIDUALS]> {
        let pixel_area = f32::from(self.stride) * f32::from(self.stride);
        residuals(self.rig, self.half, [self.right, self.left], self.min_hits, pixel_area, r, t)
    }
}

/// Step size of the numeric Jacobian (m for the position, rad for the rotation).
const STEP: [f32; 6] = [1e-3, 1e-3, 1e-3, 2e-3, 2e-3, 2e-3];

/// A damped Gauss–Newton refinement of a seed on the face images, one iteration at a time:
/// the pose whose faces project with the measured centroids and areas in both images (the
/// solver's triangulated face centroids are biased by perspective, a few millimetres and
/// degrees). [`Refinement::start`] costs one residual evaluation, each
/// [`Refinement::iterate`] at most 8 (a forward-difference Jacobian and the trial step) and
/// one 6×6 solve; a step is kept only when it lowers the squared residual.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Refinement {
    seed: Seed,
    r: Matrix3<f32>,
    t: Vector3<f32>,
    res: [f32; RESIDUALS],
    lambda: f32,
    /// The pose cannot be projected (a corner behind a camera): nothing more to do.
    stuck: bool,
    /// The seed itself could be projected.
    projected: bool,
}

impl Refinement {
    /// Starts refining `seed` against `m`.
    pub fn start(m: &Measured<'_>, seed: &Seed) -> Self {
        let (r, t) = (seed.rotation, seed.centre);
        let res = m.residuals(&r, &t);
        Self {
            seed: *seed,
            r,
            t,
            res: res.unwrap_or([0.0; RESIDUALS]),
            lambda: 1e-2,
            stuck: res.is_none(),
            projected: res.is_some(),
        }
    }

    /// One damped Gauss–Newton iteration (nothing once the pose could not be projected).
    pub fn iterate(&mut self, m: &Measured<'_>) {
        if self.stuck {
            return;
        }
        // Columns of the forward-difference Jacobian.
        let mut jac = [[0.0f32; RESIDUALS]; 6];
        for ((j, h), col) in STEP.iter().enumerate().zip(jac.iter_mut()) {
            let mut d = [0.0f32; 6];
            if let Some(x) = d.get_mut(j) {
                *x = *h;
            }
            let (rj, tj) = moved(&self.r, &self.t, &d);
            let Some(rp) = m.residuals(&rj, &tj) else {
                self.stuck = true;
                return;
            };
            for (x, (a, b)) in col.iter_mut().zip(rp.iter().zip(self.res.iter())) {
                *x = (a - b) / h;
            }
        }
        // `JᵀJ + λ·(diag JᵀJ + 10⁻⁶)` and `Jᵀr`.
        let (mut a, jtr) = linalg::normal_equations(&jac, &self.res);
        for (k, row) in a.iter_mut().enumerate() {
            if let Some(x) = row.get_mut(k) {
                *x += self.lambda * (*x + 1e-6);
            }
        }
        let Some(d) = linalg::gauss_newton_step(a, &jtr) else {
            self.lambda *= 10.0;
            return;
        };
        let (rn, tn) = moved(&self.r, &self.t, &d);
        match m.residuals(&rn, &tn) {
            Some(new) if cost(&new) < cost(&self.res) && d.iter().all(|x| x.is_finite()) => {
                (self.r, self.t, self.res) = (rn, tn, new);
                self.lambda *= 0.3;
            }
            _ => self.lambda *= 10.0,
        }
    }

    /// The refined seed and its sum of squared residuals (px²; infinite if the seed could not
    /// be projected at the start).
    pub fn result(&self) -> (Seed, f32) {
        let (r, t) = (self.r, self.t);
        // Re-orthonormalise (the small rotations are exact up to rounding).
        match quat::from_rotation_matrix(&r) {
            Ok(q) if self.projected => {
                (Seed { centre: t, rotation: quat::to_rotation_matrix(&q), ..self.seed }, cost(&self.res))
            }
            _ => (self.seed, f32::INFINITY),
        }
    }
}

/// Refines a seed completely against `m`: [`Refinement::start`] and [`REFINE_ITERATIONS`]
/// iterations.
pub fn refine(m: &Measured<'_>, seed: &Seed) -> Seed {
    refine_with_cost(m, seed).0
}

/// [`refine`] and the final sum of squared residuals (px²; infinite if the pose cannot be
/// projected).
pub fn refine_with_cost(m: &Measured<'_>, seed: &Seed) -> (Seed, f32) {
    let mut refinement = Refinement::start(m, seed);
    for _ in 0..REFINE_ITERATIONS {
        refinement.iterate(m);
    }
    refinement.result()
}

/// The seed of a frame pair in one go (what [`super::Acquisition`] computes over several
/// generations): the solutions from all seen faces and from the two with most hits (a small
/// third face's centroid is the least reliable), each refined ([`refine`]); the one whose
/// face images fit best.
pub fn best_seed(
    rig: &StereoRig,
    half: &[f32; 3],
    left: &HueBlobs,
    right: &HueBlobs,
    stride: u16,
    min_hits: u32,
) -> Option<Seed> {
    let mut best: Option<(Seed, f32)> = None;
    let m = Measured { rig, half, left, right, stride, min_hits };
    for faces in [3, 2] {
        let Some(s) = seed_pose_from(rig, half, left, right, min_hits, faces) else { continue };
        let (s, c) = refine_with_cost(&m, &s);
        if best.is_none_or(|(_, b)| c < b) {
            best = Some((s, c));
        }
    }
    best.map(|(s, _)| s)
}
