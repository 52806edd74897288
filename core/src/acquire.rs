//! Acquisition: a pose seed from the colour blobs of a sparse pixel grid.
//!
//! The fitness (eq. 34–35) samples points near the face edges, so it is a needle: a pose
//! scores only when it is within a few centimetres and degrees of the block. A uniform
//! population of 40 does not find that needle in a few dozen generations. The images,
//! though, say roughly where the block is:
//!
//! 1. **Scan** ([`scan`]): every `stride`-th pixel of every `stride`-th row of each image is
//!    looked up in the hue table; per block axis (the pair of opposite faces `k`, `k + 3`) the
//!    number of hits and the sums of their pixel coordinates are kept. Work: `⌈W/s⌉·⌈H/s⌉`
//!    table look-ups per image, whatever the images hold.
//! 2. **Triangulate** the centroid of each axis's hits seen in both images: the centroid of
//!    the visible face of that axis, a point `P_a = C + h_a·n_a` of the block (centre `C`,
//!    half size `h_a`, outward unit normal `n_a` of the face facing the cameras).
//! 3. **Solve** ([`seed_pose`]) for `C` and the axes:
//!    - three faces seen: `C` is the point at distances `h_a` from the three `P_a` (three
//!      spheres), on the far side from the cameras;
//!    - two faces `a`, `b`: `C` is at distances `h_a`, `h_b` from `P_a`, `P_b`, in the plane
//!      through them and the cameras (the third axis is then at right angles to the line of
//!      sight, which is why its faces are not seen);
//!    - one face: `C` lies `h_a` behind `P_a` along the line of sight, and the rotation about
//!      that line is unknown (each seeded individual draws it).
//!
//!    The normals `n_a = (P_a − C)/|P_a − C|` are made orthonormal (Gram–Schmidt, the face
//!    with most hits first). Which of a pair of opposite faces is seen is not known from the
//!    hue when both have the same hue; any sign choice with `det R = +1` is then the same
//!    pose up to a half turn about a block axis, which looks identical.
//! 4. **Seed** ([`seed_immigrant`]): while the tracker is not tracking, a fixed number of
//!    individuals per generation are replaced by the seed pose perturbed at one of three
//!    scales, composed with a random half turn of the block's colour symmetry.
//!
//! Everything is bounded by constants: the scan's pixel count, a fixed arithmetic solve,
//! a fixed number of random draws per seeded individual.

use nalgebra::{Matrix3, Point2, Vector3};
use rand_core::Rng;

use crate::camera::{Pinhole, StereoRig};
use crate::config::{DEFAULT_SCAN_STRIDE, DEFAULT_SEED_IMMIGRANTS};
use crate::ga::unit_f32;
use crate::hue::HueLut;
use crate::image::{Image, PixelFormat};
use crate::math;
use crate::pose::Psi;
use crate::quat;

/// Number of perturbation scales of a seeded individual.
pub const SEED_LEVELS: usize = 3;

/// Why acquisition settings were rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum AcquireError {
    /// The scan stride is 0.
    ZeroStride,
    /// A spread is negative or not finite.
    BadSpread,
    /// More seeded individuals than the population can give (the elite and one child stay).
    TooManySeeds,
}

impl core::fmt::Display for AcquireError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::ZeroStride => f.write_str("scan stride must be at least 1"),
            Self::BadSpread => f.write_str("seed spreads must be finite and non-negative"),
            Self::TooManySeeds => f.write_str("too many seeded individuals for the population"),
        }
    }
}

impl core::error::Error for AcquireError {}

/// Settings of the acquisition; [`AcquireConfig::DEFAULT`] documents the defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AcquireConfig {
    /// Pixel stride of the scan in both directions.
    pub scan_stride: u16,
    /// Individuals replaced by seeded poses per generation while not tracking.
    pub seed_immigrants: usize,
    /// Grid hits of an axis's hue needed in each image for its face to count as seen.
    pub min_face_hits: u32,
    /// Position half-widths (m) of the seeded perturbation, one per scale.
    pub spread_m: [f32; SEED_LEVELS],
    /// Rotation half-widths (rad, per rotation-vector component), one per scale.
    pub spread_rad: [f32; SEED_LEVELS],
}

impl AcquireConfig {
    /// Defaults: stride 8 px, 8 seeded individuals, a face seen with 6 hits in each image,
    /// perturbations of 3/10/25 mm and 0.03/0.10/0.25 rad.
    pub const DEFAULT: AcquireConfig = AcquireConfig {
        scan_stride: DEFAULT_SCAN_STRIDE,
        seed_immigrants: DEFAULT_SEED_IMMIGRANTS,
        min_face_hits: 6,
        spread_m: [0.003, 0.010, 0.025],
        spread_rad: [0.03, 0.10, 0.25],
    };

    /// Checks the settings for a population of `population`.
    ///
    /// # Errors
    /// [`AcquireError`].
    pub fn validate(&self, population: usize) -> Result<(), AcquireError> {
        if self.scan_stride == 0 {
            return Err(AcquireError::ZeroStride);
        }
        if !self.spread_m.iter().chain(self.spread_rad.iter()).all(|s| s.is_finite() && *s >= 0.0) {
            return Err(AcquireError::BadSpread);
        }
        if self.seed_immigrants + 2 > population {
            return Err(AcquireError::TooManySeeds);
        }
        Ok(())
    }
}

impl Default for AcquireConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Hue hits of one image's scan, per block axis (faces `a` and `a + 3`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct HueBlobs {
    /// Grid pixels whose hue matches a face of the axis.
    pub count: [u32; 3],
    /// Sum of their column indices.
    pub sum_u: [u64; 3],
    /// Sum of their row indices.
    pub sum_v: [u64; 3],
}

impl HueBlobs {
    /// Grid hits of all axes.
    pub fn total(&self) -> u32 {
        self.count.iter().sum()
    }

    /// Centroid of axis `a`'s hits in continuous pixel coordinates (pixel `(i, j)` covers
    /// `[i, i+1) × [j, j+1)`), `None` without hits.
    pub fn centroid(&self, a: usize) -> Option<Point2<f32>> {
        let n = *self.count.get(a)?;
        if n == 0 {
            return None;
        }
        let inv = 1.0 / n as f32;
        Some(Point2::new(*self.sum_u.get(a)? as f32 * inv + 0.5, *self.sum_v.get(a)? as f32 * inv + 0.5))
    }
}

/// Scans every `stride`-th pixel (offset `stride/2`) of every `stride`-th row of `image`.
/// Reads exactly `⌈(W − o)/s⌉·⌈(H − o)/s⌉` pixels, `o = s/2`; a stride of 0 reads nothing.
/// Pixels of any [`PixelFormat`] are converted to a hue only where the grid reads them.
pub fn scan<B: AsRef<[u8]>, F: PixelFormat>(image: &Image<B, F>, lut: &HueLut, stride: u16) -> HueBlobs {
    let mut blobs = HueBlobs::default();
    if stride == 0 {
        return blobs;
    }
    let (w, s) = (usize::from(image.width()), usize::from(stride));
    let pixels = image.pixels();
    for (v, row) in pixels.chunks_exact(w.max(1)).enumerate().skip(s / 2).step_by(s) {
        for (u, &px) in row.iter().enumerate().skip(s / 2).step_by(s) {
            let m = lut.mask(F::hue(px));
            let axes = (m | (m >> 3)) & 0b111;
            for a in 0..3 {
                let hit = u32::from((axes >> a) & 1);
                if let (Some(c), Some(su), Some(sv)) =
                    (blobs.count.get_mut(a), blobs.sum_u.get_mut(a), blobs.sum_v.get_mut(a))
                {
                    *c += hit;
                    *su += u64::from(hit) * u as u64;
                    *sv += u64::from(hit) * v as u64;
                }
            }
        }
    }
    blobs
}

/// The closest point of the two viewing rays of pixel `right` (right camera) and `left`
/// (left camera), in `Σ_CR`; `None` when the rays are parallel or meet behind a camera.
pub fn triangulate(rig: &StereoRig, right: &Point2<f32>, left: &Point2<f32>) -> Option<Vector3<f32>> {
    let ray = |cam: &crate::camera::Pinhole, p: &Point2<f32>| {
        Vector3::new((p.x - cam.cx()) / cam.fx(), (p.y - cam.cy()) / cam.fy(), 1.0)
    };
    let d1 = ray(&rig.right, right);
    let inv = rig.left_from_right.inverse();
    let o2 = inv.translation.vector;
    let d2 = inv.rotation * ray(&rig.left, left);
    let w0 = -o2;
    let (a, b, c) = (d1.dot(&d1), d1.dot(&d2), d2.dot(&d2));
    let (d, e) = (d1.dot(&w0), d2.dot(&w0));
    let den = a * c - b * b;
    if !(den > 1e-9 * a * c) {
        return None;
    }
    let s = (b * e - c * d) / den;
    let t = (a * e - b * d) / den;
    if !(s > 0.0 && t > 0.0) {
        return None;
    }
    Some((d1 * s + o2 + d2 * t) * 0.5)
}

/// A pose found from the blobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Seed {
    /// Block centre in `Σ_CR` (m).
    pub centre: Vector3<f32>,
    /// Rotation `^CR R_M` (columns: the block axes), up to the colour symmetry.
    pub rotation: Matrix3<f32>,
    /// Axes whose face was seen in both images (bit `a`).
    pub faces: u8,
    /// With one face seen, the rotation about its axis is unknown: that axis.
    pub free_axis: Option<usize>,
}

impl Seed {
    /// The seed as a pose (`None` only if the rotation is not one, which the solver avoids).
    pub fn psi(&self) -> Option<Psi> {
        let q = quat::from_rotation_matrix(&self.rotation).ok()?;
        Some(Psi::from_parts(&self.centre, &q))
    }
}

fn unit(v: Vector3<f32>) -> Option<Vector3<f32>> {
    let n2 = v.dot(&v);
    if n2 > 1e-12 && n2.is_finite() { Some(v / math::sqrt(n2)) } else { None }
}

/// A unit vector at right angles to unit `n`.
fn perpendicular(n: &Vector3<f32>) -> Vector3<f32> {
    let w = if n.x.abs() < 0.9 { Vector3::x() } else { Vector3::y() };
    unit(w - n * n.dot(&w)).unwrap_or_else(Vector3::z)
}

/// `C` at distances `r1`, `r2` from `p1`, `p2` in the plane through them and `eye`, on the
/// far side of the line `p1 p2` from `eye`.
fn two_circles(p1: &Vector3<f32>, r1: f32, p2: &Vector3<f32>, r2: f32, eye: &Vector3<f32>) -> Option<Vector3<f32>> {
    let d = p2 - p1;
    let l = math::sqrt(d.dot(&d));
    let ex = unit(d)?;
    let away = p1 - eye;
    let ey = unit(away - ex * ex.dot(&away))?;
    let x = (r1 * r1 - r2 * r2 + l * l) / (2.0 * l);
    let y = math::sqrt((r1 * r1 - x * x).max(0.0));
    Some(p1 + ex * x + ey * y)
}

/// `C` at distances `r[i]` from `p[i]` (three spheres), the solution farther from `eye`.
fn three_spheres(p: &[Vector3<f32>; 3], r: &[f32; 3], eye: &Vector3<f32>) -> Option<Vector3<f32>> {
    let [p1, p2, p3] = p;
    let d12 = p2 - p1;
    let d = math::sqrt(d12.dot(&d12));
    let ex = unit(d12)?;
    let p13 = p3 - p1;
    let i = ex.dot(&p13);
    let ey = unit(p13 - ex * i)?;
    let ez = ex.cross(&ey);
    let j = ey.dot(&p13);
    if !(j.abs() > 1e-4) {
        return None;
    }
    let x = (r[0] * r[0] - r[1] * r[1] + d * d) / (2.0 * d);
    let y = (r[0] * r[0] - r[2] * r[2] + i * i + j * j) / (2.0 * j) - i * x / j;
    let z = math::sqrt((r[0] * r[0] - x * x - y * y).max(0.0));
    let base = p1 + ex * x + ey * y;
    let (a, b) = (base + ez * z, base - ez * z);
    let (da, db) = (a - eye, b - eye);
    Some(if da.dot(&da) >= db.dot(&db) { a } else { b })
}

/// The pose of the block from the blobs of both images, or `None` when no face is seen in
/// both (too few hits) or the geometry is degenerate. `half` are the block's half sizes.
pub fn seed_pose(rig: &StereoRig, half: &[f32; 3], left: &HueBlobs, right: &HueBlobs, min_hits: u32) -> Option<Seed> {
    seed_pose_from(rig, half, left, right, min_hits, 3)
}

/// [`seed_pose`] using at most `max_faces` of the seen faces (those with most hits).
pub fn seed_pose_from(
    rig: &StereoRig,
    half: &[f32; 3],
    left: &HueBlobs,
    right: &HueBlobs,
    min_hits: u32,
    max_faces: usize,
) -> Option<Seed> {
    let min_hits = min_hits.max(1);
    let mut points: [Option<Vector3<f32>>; 3] = [None; 3];
    for (a, p) in points.iter_mut().enumerate() {
        if right.count.get(a).copied().unwrap_or(0) >= min_hits && left.count.get(a).copied().unwrap_or(0) >= min_hits {
            *p = triangulate(rig, &right.centroid(a)?, &left.centroid(a)?);
        }
    }
    // Seen axes, most hits first.
    let mut order = [0usize, 1, 2];
    let weight = |a: usize| match points.get(a) {
        Some(Some(_)) => right.count.get(a).copied().unwrap_or(0) + left.count.get(a).copied().unwrap_or(0),
        _ => 0,
    };
    order.sort_unstable_by(|x, y| weight(*y).cmp(&weight(*x)));
    let seen = order.iter().filter(|a| weight(**a) > 0).count().min(max_faces);
    let eye = rig.left_center_in_right() * 0.5;
    let h = |a: usize| half.get(a).copied().unwrap_or(0.0);
    let pt = |a: usize| points.get(a).copied().flatten();
    let [a0, a1, a2] = order;
    let faces = order.iter().take(seen).fold(0u8, |m, a| m | 1 << a);

    let (centre, free_axis) = match seen {
        3 => {
            let p = [pt(a0)?, pt(a1)?, pt(a2)?];
            let c = three_spheres(&p, &[h(a0), h(a1), h(a2)], &eye)
                .or_else(|| two_circles(&p[0], h(a0), &p[1], h(a1), &eye))?;
            (c, None)
        }
        2 => (two_circles(&pt(a0)?, h(a0), &pt(a1)?, h(a1), &eye)?, None),
        1 => {
            let p = pt(a0)?;
            (p + unit(p - eye)? * h(a0), Some(a0))
        }
        _ => return None,
    };
    // Outward normals of the seen faces, most hits first, made orthonormal.
    let n0 = unit(pt(a0)? - centre).or_else(|| unit(eye - pt(a0)?))?;
    let n1 = match (seen >= 2).then(|| pt(a1)).flatten() {
        Some(p) => unit((p - centre) - n0 * n0.dot(&(p - centre))).unwrap_or_else(|| perpendicular(&n0)),
        None => perpendicular(&n0),
    };
    let mut n2 = n0.cross(&n1);
    if let Some(p) = (seen == 3).then(|| pt(a2)).flatten()
        && n2.dot(&(p - centre)) < 0.0
    {
        n2 = -n2;
    }
    let mut rotation = Matrix3::zeros();
    for (a, n) in [(a0, n0), (a1, n1), (a2, n2)] {
        rotation.set_column(a, &n);
    }
    if rotation.determinant() < 0.0 {
        let flip = -rotation.column(a2);
        rotation.set_column(a2, &flip);
    }
    if !centre.iter().all(|c| c.is_finite()) {
        return None;
    }
    Some(Seed { centre, rotation, faces, free_axis })
}

/// Gauss–Newton iterations of [`refine`].
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
    let n = r.column(a) * sign;
    let centre = t + n * half.get(a).copied().unwrap_or(0.0);
    if n.dot(&centre) >= 0.0 {
        return Some((0.0, Point2::origin()));
    }
    let (b, c) = ((a + 1) % 3, (a + 2) % 3);
    let eb = r.column(b) * half.get(b).copied().unwrap_or(0.0);
    let ec = r.column(c) * half.get(c).copied().unwrap_or(0.0);
    let mut p = [Point2::origin(); 4];
    for (q, (sb, sc)) in p.iter_mut().zip([(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]) {
        let x = centre + eb * sb + ec * sc;
        if !(x.z > 1e-3) {
            return None;
        }
        *q = Point2::new(cam.fx() * x.x / x.z + cam.cx(), cam.fy() * x.y / x.z + cam.cy());
    }
    let (mut area2, mut cx, mut cy) = (0.0f32, 0.0f32, 0.0f32);
    for i in 0..4 {
        let (p0, p1) = (p[i], p[(i + 1) % 4]);
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

/// Refines a seed by damped Gauss–Newton on the face images: the pose whose faces project
/// with the measured centroids and areas in both images (the solver's triangulated face
/// centroids are biased by perspective, a few millimetres and degrees). Fixed work:
/// [`REFINE_ITERATIONS`] iterations of 7 residual evaluations (numeric Jacobian) and one
/// 6×6 solve; a step is kept only when it lowers the squared residual.
pub fn refine(
    rig: &StereoRig,
    half: &[f32; 3],
    left: &HueBlobs,
    right: &HueBlobs,
    stride: u16,
    min_hits: u32,
    seed: &Seed,
) -> Seed {
    refine_with_cost(rig, half, left, right, stride, min_hits, seed).0
}

/// [`refine`] and the final sum of squared residuals (px²; infinite if the pose cannot be
/// projected).
pub fn refine_with_cost(
    rig: &StereoRig,
    half: &[f32; 3],
    left: &HueBlobs,
    right: &HueBlobs,
    stride: u16,
    min_hits: u32,
    seed: &Seed,
) -> (Seed, f32) {
    let pixel_area = f32::from(stride) * f32::from(stride);
    let blobs = [right, left];
    let (mut r, mut t) = (seed.rotation, seed.centre);
    let Some(mut res) = residuals(rig, half, blobs, min_hits, pixel_area, &r, &t) else {
        return (*seed, f32::INFINITY);
    };
    let mut lambda = 1e-2f32;
    const STEP: [f32; 6] = [1e-3, 1e-3, 1e-3, 2e-3, 2e-3, 2e-3];
    for _ in 0..REFINE_ITERATIONS {
        let mut jac = nalgebra::SMatrix::<f32, RESIDUALS, 6>::zeros();
        for (j, h) in STEP.iter().enumerate() {
            let mut d = [0.0f32; 6];
            if let Some(x) = d.get_mut(j) {
                *x = *h;
            }
            let (rj, tj) = moved(&r, &t, &d);
            let Some(rp) = residuals(rig, half, blobs, min_hits, pixel_area, &rj, &tj) else {
                return (*seed, cost(&res));
            };
            for (i, (a, b)) in rp.iter().zip(res.iter()).enumerate() {
                jac[(i, j)] = (a - b) / h;
            }
        }
        let rv = nalgebra::SVector::<f32, RESIDUALS>::from_column_slice(&res);
        let jtj = jac.transpose() * jac;
        let jtr = jac.transpose() * rv;
        let mut a = jtj;
        for k in 0..6 {
            a[(k, k)] += lambda * (jtj[(k, k)] + 1e-6);
        }
        let Some(inv) = a.try_inverse() else { break };
        let step = -(inv * jtr);
        let d: [f32; 6] = core::array::from_fn(|k| step[k]);
        let (rn, tn) = moved(&r, &t, &d);
        match residuals(rig, half, blobs, min_hits, pixel_area, &rn, &tn) {
            Some(new) if cost(&new) < cost(&res) && d.iter().all(|x| x.is_finite()) => {
                (r, t, res) = (rn, tn, new);
                lambda *= 0.3;
            }
            _ => lambda *= 10.0,
        }
    }
    // Re-orthonormalise (the small rotations are exact up to rounding).
    match quat::from_rotation_matrix(&r) {
        Ok(q) => (Seed { centre: t, rotation: quat::to_rotation_matrix(&q), ..*seed }, cost(&res)),
        Err(_) => (*seed, f32::INFINITY),
    }
}

/// The seed of a frame pair: the solutions from all seen faces and from the two with most
/// hits (a small third face's centroid is the least reliable), each refined ([`refine`]);
/// the one whose face images fit best. Fixed work: at most two solves and two refinements.
pub fn best_seed(
    rig: &StereoRig,
    half: &[f32; 3],
    left: &HueBlobs,
    right: &HueBlobs,
    stride: u16,
    min_hits: u32,
) -> Option<Seed> {
    let mut best: Option<(Seed, f32)> = None;
    for faces in [3, 2] {
        let Some(s) = seed_pose_from(rig, half, left, right, min_hits, faces) else { continue };
        let (s, c) = refine_with_cost(rig, half, left, right, stride, min_hits, &s);
        if best.is_none_or(|(_, b)| c < b) {
            best = Some((s, c));
        }
    }
    best.map(|(s, _)| s)
}

/// The half turn about block axis `k − 1` (`k = 0`: identity) as a column sign pattern.
fn half_turn(r: &Matrix3<f32>, k: u32) -> Matrix3<f32> {
    let mut out = *r;
    for a in 0..3usize {
        if k != 0 && a as u32 != k - 1 {
            let c = -out.column(a);
            out.set_column(a, &c);
        }
    }
    out
}

/// Seeded individual `index` of a generation: index 0 is the seed itself, every other one
/// the seed perturbed at a scale picked at random (uniform within `±spread` per position
/// axis, a rotation vector uniform within `±spread_rad` per component), with a random
/// rotation about the free axis if the seed has one. Every individual is then turned by a
/// random half turn of the colour symmetry. Draws exactly 9 random numbers.
pub fn seed_immigrant<R: Rng + ?Sized>(seed: &Seed, index: usize, config: &AcquireConfig, rng: &mut R) -> Option<Psi> {
    let u: [f32; 9] = core::array::from_fn(|_| unit_f32(rng));
    let exact = index == 0;
    let level = ((u[0] * SEED_LEVELS as f32) as usize).min(SEED_LEVELS - 1);
    let (sm, sr) = if exact {
        (0.0, 0.0)
    } else {
        (config.spread_m.get(level).copied().unwrap_or(0.0), config.spread_rad.get(level).copied().unwrap_or(0.0))
    };
    let centre = seed.centre + Vector3::new(2.0 * u[1] - 1.0, 2.0 * u[2] - 1.0, 2.0 * u[3] - 1.0) * sm;
    let half_rv = Vector3::new(2.0 * u[4] - 1.0, 2.0 * u[5] - 1.0, 2.0 * u[6] - 1.0) * (0.5 * sr);
    let n = math::sqrt(1.0 + half_rv.dot(&half_rv));
    let small = nalgebra::UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(
        1.0 / n,
        half_rv.x / n,
        half_rv.y / n,
        half_rv.z / n,
    ));
    let mut r = quat::to_rotation_matrix(&small) * seed.rotation;
    if let Some(a) = seed.free_axis
        && !exact
    {
        let axis = seed.rotation.column(a).into_owned();
        let spin = quat::from_angle_axis(core::f32::consts::TAU * u[7], &axis).ok()?;
        r = quat::to_rotation_matrix(&spin) * r;
    }
    let r = half_turn(&r, (u[8] * 4.0) as u32 % 4);
    let q = quat::from_rotation_matrix(&r).ok()?;
    Some(Psi::from_parts(&centre, &q))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Pinhole;
    use crate::config::{DEFAULT_HUE_TOLERANCE, NO_HUE};
    use crate::model::{Block, SurfaceStrips};
    use crate::hue::HueImage;
    use crate::synth;
    use rand_core::SeedableRng;
    use rand_xoshiro::Xoshiro128PlusPlus;
    use std::vec;

    const W: u16 = 640;
    const H: u16 = 480;

    fn rig() -> StereoRig {
        StereoRig::parallel(Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, W, H).unwrap(), 0.1).unwrap()
    }

    fn lut() -> HueLut {
        let model = SurfaceStrips::<4>::new(&Block::PAPER).unwrap();
        HueLut::new(&model.faces().map(|f| f.hue), DEFAULT_HUE_TOLERANCE)
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

    /// Smallest rotation angle between `r` and `truth` over the colour symmetry's half turns.
    fn angle_mod_symmetry(r: &Matrix3<f32>, truth: &Matrix3<f32>) -> f32 {
        (0..4)
            .map(|k| {
                let d = half_turn(r, k).transpose() * truth;
                let c = ((d.trace() - 1.0) * 0.5).clamp(-1.0, 1.0);
                c.acos()
            })
            .fold(f32::MAX, f32::min)
    }

    #[test]
    fn scan_reads_a_fixed_grid_and_counts_hues_per_axis() {
        let (w, h) = (40u16, 30u16);
        let mut px = vec![NO_HUE; usize::from(w) * usize::from(h)];
        // One red pixel on the grid (stride 8, offset 4) and one off it.
        px[4 * 40 + 12] = 0;
        px[5 * 40 + 12] = 0;
        px[12 * 40 + 20] = 60; // green
        let img = HueImage::new_checked(&px[..], w, h).unwrap();
        let b = scan(&img, &lut(), 8);
        assert_eq!(b.count, [1, 1, 0]);
        assert_eq!((b.sum_u[0], b.sum_v[0]), (12, 4));
        assert_eq!(b.centroid(1), Some(Point2::new(20.5, 12.5)));
        assert_eq!(b.centroid(2), None);
        assert_eq!(scan(&img, &lut(), 0).total(), 0);
    }

    #[test]
    fn triangulation_inverts_the_projection() {
        let rig = rig();
        let p = Vector3::new(0.05, -0.03, 0.8);
        let (r, l) =
            rig.project_model_point(&nalgebra::Isometry3::translation(p.x, p.y, p.z), &nalgebra::Point3::origin());
        let q = triangulate(&rig, &r.unwrap(), &l.unwrap()).unwrap();
        assert!((q - p).norm() < 1e-5, "{q}");
        // Rays that diverge (negative disparity) meet behind the cameras.
        assert_eq!(triangulate(&rig, &Point2::new(400.0, 240.0), &Point2::new(300.0, 240.0)), None);
    }

    #[test]
    fn seed_is_close_to_the_truth_for_random_poses() {
        let rig = rig();
        let half = Block::PAPER.size_m.map(|s| 0.5 * s);
        let mut rng = Xoshiro128PlusPlus::seed_from_u64(5);
        let (mut worst_t, mut worst_r, mut n) = (0.0f32, 0.0f32, 0);
        for _ in 0..40 {
            let u: [f32; 6] = core::array::from_fn(|_| unit_f32(&mut rng));
            let eps = Vector3::new(2.0 * u[3] - 1.0, 2.0 * u[4] - 1.0, 2.0 * u[5] - 1.0);
            if eps.norm() > 1.0 {
                continue;
            }
            let truth = Psi::new([0.1 * u[0] - 0.05, 0.1 * u[1] - 0.05, 0.6 + 0.3 * u[2]], eps.into());
            let (l, r) = scene(&truth);
            let (l, r) = (HueImage::new_checked(&l[..], W, H).unwrap(), HueImage::new_checked(&r[..], W, H).unwrap());
            let (bl, br) = (scan(&l, &lut(), 8), scan(&r, &lut(), 8));
            let seed = seed_pose(&rig, &half, &bl, &br, 6).unwrap();
            let dt = (seed.centre - truth.translation()).norm();
            worst_t = worst_t.max(dt);
            if seed.free_axis.is_none() {
                worst_r = worst_r.max(angle_mod_symmetry(&seed.rotation, &truth.rotation_unchecked()));
            }
            n += 1;
            let psi = seed.psi().unwrap();
            assert!(psi.validate().is_ok());
        }
        assert!(n > 15);
        assert!(worst_t < 0.03, "worst centre error {worst_t} m");
        assert!(worst_r < 0.35, "worst rotation error {worst_r} rad");
    }

    #[test]
    fn nothing_seen_gives_no_seed_and_immigrants_draw_a_fixed_count() {
        let rig = rig();
        let none = HueBlobs::default();
        assert_eq!(seed_pose(&rig, &[0.05, 0.075, 0.1], &none, &none, 6), None);
        let seed =
            Seed { centre: Vector3::new(0.0, 0.0, 0.7), rotation: Matrix3::identity(), faces: 1, free_axis: Some(2) };
        let mut r1 = Xoshiro128PlusPlus::seed_from_u64(3);
        let mut r2 = Xoshiro128PlusPlus::seed_from_u64(3);
        let p0 = seed_immigrant(&seed, 0, &AcquireConfig::DEFAULT, &mut r1).unwrap();
        assert!((p0.translation() - seed.centre).norm() < 1e-7);
        for _ in 0..9 {
            r2.next_u32();
        }
        assert_eq!(r1.next_u32(), r2.next_u32());
        for i in 1..20 {
            let p = seed_immigrant(&seed, i, &AcquireConfig::DEFAULT, &mut r1).unwrap();
            assert!(p.validate().is_ok());
            assert!((p.translation() - seed.centre).norm() < 0.025 * 1.8);
        }
    }

    #[test]
    fn config_validation() {
        assert!(AcquireConfig::DEFAULT.validate(40).is_ok());
        assert_eq!(
            AcquireConfig { scan_stride: 0, ..AcquireConfig::DEFAULT }.validate(40),
            Err(AcquireError::ZeroStride)
        );
        assert_eq!(AcquireConfig::DEFAULT.validate(9), Err(AcquireError::TooManySeeds));
        let bad = AcquireConfig { spread_m: [f32::NAN, 0.0, 0.0], ..AcquireConfig::DEFAULT };
        assert_eq!(bad.validate(40), Err(AcquireError::BadSpread));
    }
}
