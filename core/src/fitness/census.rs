//! The colour census of a pose ([`crate::colour`]): the hue byte under every point of the two
//! deeper inner rows ([`INNER_INSETS_M`]`[1..]`, 8 and 25 mm inside the edges) of every face the
//! pose shows a camera. The nearest row is left out: half a pixel inside a silhouette edge, its
//! pixels mix the face with the background.
//!
//! Bounded work: at most three faces per camera, `4 · 2 · G` points each, read as the fitness
//! reads them (the same fixed-point rows, or the lens kernel).

use nalgebra::{Matrix3, Vector3};

use super::{
    Affine, AxisRows, EdgeRows, FIX_ONE, FacePlan, Lens, Projector, RowWalk, View, edge_rows_at, face_axes, face_plan,
    lens_to_pixel,
};
use crate::camera::Pinhole;
use crate::image::{Image, PixelFormat};
use crate::model::SurfaceStrips;

/// `visit(k, h)` for every census point of every visible face `k` of the model at `(r, t)` in
/// the frame of camera `cam`, `h` the hue byte of `image` under it.
pub(super) fn camera_census<const G: usize, B: AsRef<[u8]>, F: PixelFormat>(
    model: &SurfaceStrips<G>,
    cam: &Pinhole,
    image: &Image<B, F>,
    r: &Matrix3<f32>,
    t: &Vector3<f32>,
    visit: &mut impl FnMut(usize, u8),
) {
    let view = View::of(image);
    let faces = face_plan(model, cam, r, t);
    if cam.distortion().is_none() {
        let (fx, fy, cx, cy) = (cam.fx(), cam.fy(), cam.cx(), cam.cy());
        let proj = Projector::new([fx * FIX_ONE, fy * FIX_ONE, cx * FIX_ONE, cy * FIX_ONE], r, t);
        census_faces(model, &Affine { view: &view }, &proj, &faces, visit);
    } else {
        let proj = Projector::new([1.0, 1.0, 0.0, 0.0], r, t);
        census_faces(model, &Lens { view: &view, to_pixel: lens_to_pixel(cam) }, &proj, &faces, visit);
    }
}

/// The census of the planned faces, with `walk` reading the rows.
fn census_faces<const G: usize>(
    model: &SurfaceStrips<G>,
    walk: &impl RowWalk,
    proj: &Projector,
    faces: &FacePlan,
    visit: &mut impl FnMut(usize, u8),
) {
    let (half, reach, row_step) = (model.half_size(), model.row_reach(), model.row_step());
    let axes: [AxisRows; 3] = core::array::from_fn(|x| AxisRows::new(proj, x, half[x], reach[x], row_step[x]));
    for (&k, &w) in faces.chosen.iter().zip(faces.weight.iter()) {
        if w == 0 {
            continue;
        }
        let (_, bx, cx, centre) = face_axes(&axes, proj, k);
        for (s, l) in [(bx, cx), (cx, bx)] {
            for positive in [true, false] {
                let at = edge_rows_at(centre, s, l, positive);
                let [_, deeper @ ..] = &s.inner;
                let rows = EdgeRows { starts: deeper.each_ref().map(&at), step: l.step, span: l.span };
                walk.visit_rows::<G, 2>(&rows, &mut |h| visit(k, h));
            }
        }
    }
}
