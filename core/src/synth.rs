//! An ideal hue rasterizer for bring-up and tests, no_std and allocation-free.
//!
//! [`render_block`] paints the visible faces of a [`Block`] into a hue image with one sample
//! at each pixel centre (no anti-aliasing, no shading, no noise): the image the fitness was
//! designed for. It runs on the board as well, so on-target tests can make their own frames.
//! The simulator has a realistic renderer; this one is exact by construction.

use nalgebra::{Isometry3, Point2};

use crate::camera::Pinhole;
use crate::hue;
use crate::image::ImageError;
use crate::model::{Block, FACES};

/// Paints the faces of `block` at `cam_from_model` (the block's pose in the camera frame) that
/// face the camera into `out` (row-major, `cam.width() × cam.height()`). Pixels not covered
/// keep their value. Faces with a corner behind the camera are skipped.
///
/// # Errors
/// [`ImageError::TooShort`] if `out` is smaller than the camera image.
pub fn render_block(
    block: &Block,
    cam: &Pinhole,
    cam_from_model: &Isometry3<f32>,
    out: &mut [u8],
) -> Result<(), ImageError> {
    let (w, h) = (usize::from(cam.width()), usize::from(cam.height()));
    if out.len() < w * h {
        return Err(ImageError::TooShort { needed: (w * h) as u32, got: out.len() as u32 });
    }
    for k in 0..FACES {
        let n_cam = cam_from_model.rotation * Block::normal(k);
        let corners = block.face_corners(k).map(|c| cam_from_model * c);
        let Some(c0) = corners.first() else { continue };
        if n_cam.dot(&c0.coords) >= 0.0 {
            continue; // back-facing
        }
        let mut quad = [Point2::origin(); 4];
        let mut ok = true;
        for (q, c) in quad.iter_mut().zip(corners.iter()) {
            match cam.project_unbounded(c) {
                Ok(p) => *q = p,
                Err(_) => ok = false,
            }
        }
        if !ok {
            continue;
        }
        let hue = hue::degrees_to_units(block.face_hues_deg.get(k).copied().unwrap_or(0.0));
        fill_convex(&quad, hue, w, h, out);
    }
    Ok(())
}

/// Sets every pixel whose centre lies inside the convex polygon `poly` to `value`.
pub fn fill_convex(poly: &[Point2<f32>; 4], value: u8, w: usize, h: usize, out: &mut [u8]) {
    let (mut x0, mut y0, mut x1, mut y1) = (f32::MAX, f32::MAX, f32::MIN, f32::MIN);
    for p in poly {
        x0 = x0.min(p.x);
        y0 = y0.min(p.y);
        x1 = x1.max(p.x);
        y1 = y1.max(p.y);
    }
    let clampi = |v: f32, hi: usize| -> usize { crate::math::clamp(v, 0.0, hi as f32) as usize };
    let (xa, xb) = (clampi(x0 - 1.0, w), clampi(x1 + 1.0, w));
    let (ya, yb) = (clampi(y0 - 1.0, h), clampi(y1 + 1.0, h));
    for y in ya..yb {
        for x in xa..xb {
            let (px, py) = (x as f32 + 0.5, y as f32 + 0.5);
            let mut pos = false;
            let mut neg = false;
            for i in 0..4 {
                let (Some(a), Some(b)) = (poly.get(i), poly.get((i + 1) % 4)) else { continue };
                let cross = (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x);
                pos |= cross > 0.0;
                neg |= cross < 0.0;
            }
            if !(pos && neg)
                && let Some(o) = out.get_mut(y * w + x)
            {
                *o = value;
            }
        }
    }
}

/// The stereo pair and frames shared by the core's unit tests (fitness, acquisition).
#[cfg(test)]
pub(crate) mod test_scene {
    use std::vec;
    use std::vec::Vec;

    use crate::camera::{Pinhole, StereoRig};
    use crate::limits::NO_HUE;
    use crate::model::Block;
    use crate::pose::Psi;

    /// Image width of [`rig`]'s cameras.
    pub(crate) const W: u16 = 640;
    /// Image height of [`rig`]'s cameras.
    pub(crate) const H: u16 = 480;

    /// A parallel stereo pair, 0.1 m baseline, `f = 800` px, `W × H` images.
    pub(crate) fn rig() -> StereoRig {
        StereoRig::parallel(Pinhole::new_checked(800.0, 800.0, 320.0, 240.0, W, H).unwrap(), 0.1).unwrap()
    }

    /// The hue frames `(left, right)` of [`Block::PAPER`] at `psi` (in the right camera's frame).
    pub(crate) fn scene(psi: &Psi) -> (Vec<u8>, Vec<u8>) {
        let rig = rig();
        let iso = psi.try_to_isometry().unwrap();
        let mut right = vec![NO_HUE; usize::from(W) * usize::from(H)];
        let mut left = right.clone();
        super::render_block(&Block::PAPER, &rig.right, &iso, &mut right).unwrap();
        super::render_block(&Block::PAPER, &rig.left, &(rig.left_from_right * iso), &mut left).unwrap();
        (left, right)
    }
}
