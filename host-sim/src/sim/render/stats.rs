//! Hue, saturation and value statistics of each visible face's pixels at a known pose: what a
//! light does to the colours the tracker sees.

use evorec_core::camera::Pinhole;
use evorec_core::model::Block;
use image::RgbImage;
use nalgebra::Isometry3;
use serde::Serialize;

use super::{RenderOptions, screen_faces};

/// Pixels whose centre is closer than this (pixels) to a face's edge are not counted.
pub const EDGE_MARGIN_PX: f32 = 2.0;

/// HSV statistics of one face's pixels ([`face_stats`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FaceStats {
    /// The face (the core's face order).
    pub face: usize,
    /// Its nominal hue (degrees).
    pub nominal_hue_deg: f32,
    /// Pixels counted (centres at least [`EDGE_MARGIN_PX`] inside the face).
    pub pixels: usize,
    /// Median hue (degrees in `[0, 360)`), taken as the median of each pixel's signed offset
    /// from the nominal hue (pixels without a hue, i.e. grey, are left out).
    pub median_hue_deg: f32,
    /// Median HSV saturation (0..=1).
    pub median_saturation: f32,
    /// Median HSV value (0..=1).
    pub median_value: f32,
    /// Fraction of the pixels whose hue is within ±15° of the nominal hue.
    pub within_15_deg: f32,
    /// Fraction of the pixels that are nearly white (saturation < 0.2, value > 0.85).
    pub near_white: f32,
}

/// HSV of an 8-bit RGB pixel: hue in degrees (`None` for a grey), saturation and value in
/// 0..=1.
pub fn hsv(rgb: [u8; 3]) -> (Option<f32>, f32, f32) {
    let [r, g, b] = rgb.map(|c| f32::from(c) / 255.0);
    let (max, min) = (r.max(g).max(b), r.min(g).min(b));
    let delta = max - min;
    let saturation = if max > 0.0 { delta / max } else { 0.0 };
    if delta <= 0.0 {
        return (None, saturation, max);
    }
    let h = if max == r {
        (g - b) / delta
    } else if max == g {
        2.0 + (b - r) / delta
    } else {
        4.0 + (r - g) / delta
    };
    (Some((60.0 * h).rem_euclid(360.0)), saturation, max)
}

fn median(mut v: Vec<f32>) -> f32 {
    if v.is_empty() {
        return f32::NAN;
    }
    v.sort_by(f32::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// The statistics of each face of `block` that `cam` sees in `img` with the block at
/// `cam_from_model` (the faces turned towards the camera, in the core's face order; a face seen
/// edge-on is left out). A face
/// with no pixel inside the margin has `pixels = 0` and NaN medians.
pub fn face_stats(img: &RgbImage, cam: &Pinhole, cam_from_model: &Isometry3<f32>, block: &Block) -> Vec<FaceStats> {
    screen_faces(cam, cam_from_model, block, &RenderOptions::default())
        .iter()
        .map(|f| {
            let k = f.face;
            let nominal = block.face_hues_deg[k];
            let (mut offsets, mut sats, mut vals) = (Vec::new(), Vec::new(), Vec::new());
            let (mut within, mut white) = (0usize, 0usize);
            let [x0, y0, x1, y1] = f.bbox;
            let (x0, x1) = (x0.max(0.0) as u32, (x1.max(0.0) as u32).min(img.width()));
            let (y0, y1) = (y0.max(0.0) as u32, (y1.max(0.0) as u32).min(img.height()));
            for y in y0..y1 {
                for x in x0..x1 {
                    let d = f.distances(x as f32 + 0.5, y as f32 + 0.5);
                    if d.iter().any(|&d| d < EDGE_MARGIN_PX) {
                        continue;
                    }
                    let (hue, s, v) = hsv(img.get_pixel(x, y).0);
                    if let Some(h) = hue {
                        let off = (h - nominal + 180.0).rem_euclid(360.0) - 180.0;
                        within += usize::from(off.abs() <= 15.0);
                        offsets.push(off);
                    }
                    white += usize::from(s < 0.2 && v > 0.85);
                    sats.push(s);
                    vals.push(v);
                }
            }
            let n = sats.len();
            let frac = |c: usize| if n > 0 { c as f32 / n as f32 } else { f32::NAN };
            FaceStats {
                face: k,
                nominal_hue_deg: nominal,
                pixels: n,
                median_hue_deg: (nominal + median(offsets)).rem_euclid(360.0),
                median_saturation: median(sats),
                median_value: median(vals),
                within_15_deg: frac(within),
                near_white: frac(white),
            }
        })
        .collect()
}
