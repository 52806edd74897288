//! The colour census of a pose ([`crate::colour`]): the hue byte under every other point of
//! the two deeper inner rows ([`INNER_INSETS_M`]`[1..]`, 8 and 25 mm inside the edges) of every
//! face the pose shows a camera. The nearest row is left out: half a pixel inside a silhouette
//! edge, its pixels mix the face with the background.
//!
//! Bounded work: at most three faces per camera, `4 · 2 · ⌈G/2⌉` points each, every point
//! projected on its own through the camera ([`Pinhole::project_unbounded`], lens included):
//! a few hundred points per frame, against the tens of thousands the fitness reads, in little
//! code.

use nalgebra::{Matrix3, Point3, Vector3};

use super::{View, face_plan};
use crate::camera::Pinhole;
use crate::image::{Image, PixelFormat};
use crate::limits::{INNER_INSETS_M, NO_HUE};
use crate::model::SurfaceStrips;

/// Points of a census row: every other point of a model row of `G` points.
const fn census_points(g: usize) -> usize {
    g.div_ceil(2)
}

/// `visit(k, hues)` for every census row of every visible face `k` of the model at `(r, t)`
/// in the frame of camera `cam`, `hues` the hue bytes of `image` under its points ([`NO_HUE`]
/// outside the image).
#[inline(never)]
pub(super) fn camera_census<const G: usize, B: AsRef<[u8]>, F: PixelFormat>(
    model: &SurfaceStrips<G>,
    cam: &Pinhole,
    image: &Image<B, F>,
    r: &Matrix3<f32>,
    t: &Vector3<f32>,
    visit: &mut dyn FnMut(usize, &[u8]),
) {
    let view = View::of(image);
    let faces = face_plan(model, cam, r, t);
    let mut hues = [NO_HUE; G];
    let row = hues.get_mut(..census_points(G)).unwrap_or_default();
    for (&k, &w) in faces.chosen.iter().zip(faces.weight.iter()) {
        let Some(face) = model.faces().get(k).filter(|_| w > 0) else { continue };
        for edge in &face.edges {
            for &d in INNER_INSETS_M.iter().skip(1) {
                let start = edge.base + edge.inward * d;
                for (i, h) in row.iter_mut().enumerate() {
                    let p = r * (start + edge.step * (2 * i) as f32) + t;
                    // Pixel coordinates plus one, as `View::hue` reads them.
                    *h = cam.project_unbounded(&Point3::from(p)).map_or(NO_HUE, |uv| view.hue(uv.x + 1.0, uv.y + 1.0));
                }
                visit(k, row);
            }
        }
    }
}
