//! Steps 2–3 of the acquisition: triangulation of the face centroids and the solve for the
//! block's centre and axes.

// `!(x > y)` on purpose: true for NaN too, so a NaN never passes a check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{Matrix3, Point2, Vector3};

use super::{HueBlobs, linalg};
use crate::camera::StereoRig;
use crate::math;
use crate::pose::Psi;
use crate::quat;

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
    /// The blobs of either image touch its border ([`HueBlobs::touches_border`]): the
    /// centroids and areas are those of the faces' visible parts, so the seed can be off by
    /// more than the block's size.
    pub cut: bool,
}

impl Seed {
    /// The seed as a pose (`None` only if the rotation is not one, which the solver avoids).
    pub fn psi(&self) -> Option<Psi> {
        let q = quat::from_rotation_matrix(&self.rotation).ok()?;
        Some(Psi::from_parts(&self.centre, &q))
    }
}

pub(super) fn unit(v: Vector3<f32>) -> Option<Vector3<f32>> {
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
    order.sort_unstable_by_key(|a| core::cmp::Reverse(weight(*a)));
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
    let mut columns = [Vector3::zeros(); 3];
    for (a, n) in [(a0, n0), (a1, n1), (a2, n2)] {
        if let Some(c) = columns.get_mut(a) {
            *c = n;
        }
    }
    let mut rotation = linalg::from_columns(&columns);
    if rotation.determinant() < 0.0 {
        if let Some(c) = columns.get_mut(a2) {
            *c = -*c;
        }
        rotation = linalg::from_columns(&columns);
    }
    if !centre.iter().all(|c| c.is_finite()) {
        return None;
    }
    let cut = left.touches_border() || right.touches_border();
    Some(Seed { centre, rotation, faces, free_axis, cut })
}
