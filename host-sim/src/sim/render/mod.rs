//! Stereo renderer for the simulator: an RGB picture of the coloured block, then its hue image
//! through the core's own [`rgb_to_hue`].
//!
//! Unlike the core's exact pixel-centre rasterizer ([`evorec_core::synth::render_block`]) this
//! one aims at what a camera delivers:
//!
//! - each face is its fully saturated hue, Lambert-shaded by a fixed light in the camera frame
//!   plus ambient light, so faces of equal hue differ in brightness but not in hue;
//! - the background is a neutral grey with a mild low-frequency brightness variation (it has
//!   no hue);
//! - edges are anti-aliased (exact area coverage or `n × n` supersampling), so a sub-pixel
//!   change of the pose changes the image; pixels whose whole square lies inside one face or
//!   outside every face take a fast path;
//! - optional per-channel noise (a sum of four uniform 4-bit values, scaled to the requested
//!   standard deviation: close to Gaussian, truncated at ±3.25σ), clamped to `0..=255`;
//! - optional camera-like light ([`light`], a scenario's `[render]` table): a highlight, a cast
//!   shadow, motion blur ([`render_stereo_blurred`]), white balance and a tone curve, chroma
//!   noise and JPEG; all off by default. [`face_stats`] measures what they do to each face.
//!
//! Only faces turned towards the camera are drawn; the block is convex, so their projections
//! do not overlap and no z-buffer is needed. Faces with a corner closer than
//! [`MIN_DEPTH_M`] to the camera plane (or behind it) are skipped.
//!
//! Pixel conventions are the core's (OpenCV's): pixel `(i, j)` covers `[i, i+1) × [j, j+1)`.

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::hue::rgb_to_hue;
use evorec_core::image::{HueImage, ImageError, rgb565_to_rgb888, rgb888_to_rgb565};
use evorec_core::limits::MIN_DEPTH_M;
use evorec_core::model::{Block, FACES};
use evorec_core::tracker::StereoFrame;
use image::{Rgb, RgbImage};
use nalgebra::{Isometry3, Point2};
use rand_core::Rng;

pub mod light;
pub mod stats;
use light::{Band, FaceShader};
pub use light::{Light, ShadowFrame, ToneCurve, jpeg_round_trip};
pub use stats::{FaceStats, face_stats};

/// Half the diagonal of a pixel: a pixel whose centre is farther than this from a line lies
/// entirely on one side of it.
const HALF_DIAGONAL: f32 = 0.707_2;

/// How edge pixels are anti-aliased.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AntiAlias {
    /// One sample at the pixel centre (aliased, like the core's `synth` rasterizer).
    Off,
    /// A regular `n × n` grid of samples in each edge pixel (`n` is clamped to `1..=16`).
    Supersample(u8),
    /// Exact area of each face inside the pixel square (analytic polygon clipping).
    Exact,
}

/// Rendering options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Anti-aliasing of edge pixels.
    pub antialias: AntiAlias,
    /// Standard deviation of the per-channel noise in 8-bit levels (`0` = none).
    pub noise_std: f32,
    /// Light, shading and the camera's imaging ([`Light`]; the default is flat Lambert
    /// shading and nothing else).
    pub light: Light,
    /// Mean grey level of the background (8-bit).
    pub background_level: f32,
    /// Amplitude (8-bit levels) of the background's low-frequency brightness variation.
    pub background_variation: f32,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            antialias: AntiAlias::Exact,
            noise_std: 0.0,
            light: Light::default(),
            background_level: 140.0,
            background_variation: 12.0,
        }
    }
}

impl RenderOptions {
    /// These options with per-channel noise of standard deviation `std` (8-bit levels).
    pub fn with_noise(self, std: f32) -> Self {
        Self { noise_std: std, ..self }
    }

    /// These options with the given anti-aliasing.
    pub fn with_antialias(self, antialias: AntiAlias) -> Self {
        Self { antialias, ..self }
    }

    /// These options with the given light.
    pub fn with_light(self, light: Light) -> Self {
        Self { light, ..self }
    }
}

/// A pair of RGB frames from a stereo rig.
#[derive(Debug, Clone)]
pub struct StereoImages {
    /// Left camera image.
    pub left: RgbImage,
    /// Right camera image (its frame `Σ_CR` is the one poses are given in).
    pub right: RgbImage,
}

/// The projection of one visible face: four edge lines with unit normals, positive inside.
#[derive(Debug, Clone, Copy)]
struct ScreenFace {
    /// `[a, b, c]` with `a·u + b·v + c` the signed distance (pixels) of `(u, v)` from the edge.
    edges: [[f32; 3]; 4],
    /// Bounding box `[u0, v0, u1, v1]` (continuous pixel coordinates).
    bbox: [f32; 4],
    /// Shaded face colour, 8-bit scale (where [`ScreenFace::shader`] is `None`).
    colour: [f32; 3],
    /// The per-pixel shading of a face with a highlight or a shadow.
    shader: Option<FaceShader>,
    /// The model's face (the core's face order).
    face: usize,
}

impl ScreenFace {
    /// The pixel columns `[lo, hi)` (clamped to `0..width`) of the row whose centres lie at
    /// height `v` and whose centres are at least `t` (signed) from every edge.
    fn row_span(&self, v: f32, t: f32, width: usize) -> (usize, usize) {
        let (mut lo, mut hi) = (f32::NEG_INFINITY, f32::INFINITY);
        for &[a, b, c] in &self.edges {
            let need = t - (b * v + c); // a·u ≥ need
            if a > 0.0 {
                lo = lo.max(need / a);
            } else if a < 0.0 {
                hi = hi.min(need / a);
            } else if need > 0.0 {
                return (0, 0);
            }
        }
        // Column x has its centre at x + ½.
        let wf = width as f32;
        let first = (lo - 0.5).ceil().clamp(0.0, wf) as usize;
        let end = ((hi - 0.5).floor() + 1.0).clamp(0.0, wf) as usize;
        (first, end.max(first))
    }

    /// The face's colour (8-bit scale) at the pixel centre `(u, v)`.
    #[inline(always)]
    fn colour_at(&self, u: f32, v: f32) -> [f32; 3] {
        match &self.shader {
            None => self.colour,
            Some(s) => s.colour_at(u, v),
        }
    }

    /// Signed distances of the point `(u, v)` from the four edges.
    #[inline(always)]
    fn distances(&self, u: f32, v: f32) -> [f32; 4] {
        self.edges.map(|[a, b, c]| a * u + b * v + c)
    }
}

/// Fully saturated, full-value RGB (0..=1) of a hue in degrees.
pub(crate) fn hue_rgb(deg: f32) -> [f32; 3] {
    let h = deg.rem_euclid(360.0) / 60.0;
    // `rem_euclid` can round a tiny negative angle up to exactly 360°.
    let h = if h >= 6.0 { 0.0 } else { h };
    let f = h - h.floor();
    match h as u32 {
        0 => [1.0, f, 0.0],
        1 => [1.0 - f, 1.0, 0.0],
        2 => [0.0, 1.0, f],
        3 => [0.0, 1.0 - f, 1.0],
        4 => [f, 0.0, 1.0],
        _ => [1.0, 0.0, 1.0 - f],
    }
}

/// Projects the camera-facing faces of `block` at `cam_from_model` into the image of `cam`
/// (a cast shadow in the camera frame is taken in this camera's frame).
fn screen_faces(
    cam: &Pinhole,
    cam_from_model: &Isometry3<f32>,
    block: &Block,
    opts: &RenderOptions,
) -> Vec<ScreenFace> {
    screen_faces_shadowed(cam, cam_from_model, block, opts, opts.light.shadow_in_block(cam_from_model))
}

/// [`screen_faces`] with the cast shadow given in the block's frame.
fn screen_faces_shadowed(
    cam: &Pinhole,
    cam_from_model: &Isometry3<f32>,
    block: &Block,
    opts: &RenderOptions,
    shadow: Option<Band>,
) -> Vec<ScreenFace> {
    let light = opts.light.direction();
    let mut faces = Vec::with_capacity(3);
    for k in 0..FACES {
        let normal = cam_from_model.rotation * Block::normal(k);
        let corners = block.face_corners(k).map(|c| cam_from_model * c);
        let too_close = corners.iter().any(|c| c.z.is_nan() || c.z < MIN_DEPTH_M);
        if too_close || normal.dot(&corners[0].coords) >= 0.0 {
            continue; // back-facing (or NaN), or too close to / behind the camera plane
        }
        let mut quad = [Point2::origin(); 4];
        let mut ok = true;
        for (q, c) in quad.iter_mut().zip(&corners) {
            match cam.project_unbounded(c) {
                Ok(p) => *q = p,
                Err(_) => ok = false,
            }
        }
        if !ok {
            continue;
        }
        // Twice the signed area: its sign tells which side of each edge is inside.
        let area2: f32 = (0..4)
            .map(|i| {
                let (p, q) = (quad[i], quad[(i + 1) % 4]);
                p.x * q.y - q.x * p.y
            })
            .sum();
        if !area2.is_finite() || area2.abs() <= 1e-6 {
            continue; // seen edge-on, or absurdly far off-screen
        }
        let s = area2.signum();
        let mut edges = [[0.0, 0.0, 1.0e9]; 4];
        for (i, e) in edges.iter_mut().enumerate() {
            let (p, q) = (quad[i], quad[(i + 1) % 4]);
            let d = q - p;
            let len = d.norm();
            if len > 1e-9 {
                let (a, b) = (-d.y * s / len, d.x * s / len);
                *e = [a, b, -(a * p.x + b * p.y)];
            }
        }
        let mut bbox = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
        for p in &quad {
            bbox = [bbox[0].min(p.x), bbox[1].min(p.y), bbox[2].max(p.x), bbox[3].max(p.y)];
        }
        let l = &opts.light;
        let lambert = normal.dot(&light).max(0.0);
        let shade = (l.ambient + l.diffuse * lambert).clamp(0.0, 1.0) * 255.0;
        let base = light::albedo(hue_rgb(block.face_hues_deg[k]), l.albedo_saturation);
        let shader = (!l.is_flat()).then(|| FaceShader {
            intrinsics: [cam.fx(), cam.fy(), cam.cx(), cam.cy()],
            normal,
            plane: normal.dot(&corners[0].coords),
            albedo: base,
            light,
            ambient: l.ambient,
            diffuse: l.diffuse,
            specular: l.specular,
            shininess: l.shininess,
            shadow: shadow.map(|b| b.moved(cam_from_model)),
        });
        faces.push(ScreenFace { edges, bbox, colour: base.map(|c| c * shade), shader, face: k });
    }
    faces
}

/// Area of the part of the pixel square `[-½, ½]²` (pixel-local coordinates) on the positive
/// side of all `lines` (`[a, b, e]`: `a·u + b·v + e ≥ 0`).
fn clipped_square_area(lines: &[[f32; 3]; 4]) -> f32 {
    let mut poly = [(0.0f32, 0.0f32); 10];
    let mut next = [(0.0f32, 0.0f32); 10];
    poly[..4].copy_from_slice(&[(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]);
    let mut n = 4usize;
    for &[a, b, e] in lines {
        if e >= HALF_DIAGONAL {
            continue; // the whole square is inside this edge
        }
        if e <= -HALF_DIAGONAL {
            return 0.0;
        }
        let mut m = 0usize;
        for i in 0..n {
            let (p, q) = (poly[i], poly[(i + 1) % n]);
            let dp = a * p.0 + b * p.1 + e;
            let dq = a * q.0 + b * q.1 + e;
            if dp >= 0.0 && m < next.len() {
                next[m] = p;
                m += 1;
            }
            if (dp >= 0.0) != (dq >= 0.0) && m < next.len() {
                let t = dp / (dp - dq);
                next[m] = (p.0 + t * (q.0 - p.0), p.1 + t * (q.1 - p.1));
                m += 1;
            }
        }
        if m < 3 {
            return 0.0;
        }
        poly[..m].copy_from_slice(&next[..m]);
        n = m;
    }
    let mut area2 = 0.0;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        area2 += p.0 * q.1 - q.0 * p.1;
    }
    (0.5 * area2).abs()
}

/// Per-column and per-row offsets of the background grey (a smooth, separable variation).
fn background_tables(width: u32, height: u32, opts: &RenderOptions) -> (Vec<f32>, Vec<f32>) {
    use std::f32::consts::TAU;
    let amp = if opts.background_variation.is_finite() { opts.background_variation } else { 0.0 };
    let level = if opts.background_level.is_finite() { opts.background_level } else { 140.0 };
    let (w, h) = (width.max(1) as f32, height.max(1) as f32);
    let cols = (0..width).map(|x| level + 0.6 * amp * (TAU * 0.8 * (x as f32 + 0.5) / w + 0.7).sin()).collect();
    let rows = (0..height).map(|y| 0.4 * amp * (TAU * 0.6 * (y as f32 + 0.5) / h + 0.3).cos()).collect();
    (cols, rows)
}

#[inline(always)]
fn to_u8(v: f32) -> u8 {
    // `as` saturates and maps NaN to 0.
    (v + 0.5) as u8
}

/// Renders the block as seen by `cam`.
///
/// `cam_from_model` is the block's pose in this camera's frame (a cast shadow in the camera
/// frame is taken in this camera's frame); `rng` drives the noise only (it is not touched
/// when `opts.noise_std` and the chroma noise are 0). Never panics: a pose with non-finite
/// values, or a block behind the camera, gives the background alone.
pub fn render<R: Rng + ?Sized>(
    cam: &Pinhole,
    cam_from_model: &Isometry3<f32>,
    block: &Block,
    opts: &RenderOptions,
    rng: &mut R,
) -> RgbImage {
    let shadow = opts.light.shadow_in_block(cam_from_model);
    render_blurred(cam, &[(*cam_from_model, shadow)], block, opts, rng)
}

/// The mean of the scene drawn at each pose of `poses` (the motion blur of one exposure),
/// then developed ([`develop`]). Each pose comes with the cast shadow in the block's frame.
fn render_blurred<R: Rng + ?Sized>(
    cam: &Pinhole,
    poses: &[(Isometry3<f32>, Option<Band>)],
    block: &Block,
    opts: &RenderOptions,
    rng: &mut R,
) -> RgbImage {
    let mut buf = match poses {
        [(one, shadow)] => draw(cam, &screen_faces_shadowed(cam, one, block, opts, *shadow), opts),
        poses => {
            let mut sum = vec![0u32; 3 * usize::from(cam.width()) * usize::from(cam.height())];
            for (pose, shadow) in poses {
                let faces = screen_faces_shadowed(cam, pose, block, opts, *shadow);
                for (s, &b) in sum.iter_mut().zip(&draw(cam, &faces, opts)) {
                    *s += u32::from(b);
                }
            }
            let n = poses.len().max(1) as u32;
            sum.iter().map(|&s| ((s + n / 2) / n) as u8).collect()
        }
    };
    develop(&mut buf, opts, rng);
    let (width, height) = (u32::from(cam.width()), u32::from(cam.height()));
    // The buffer has exactly width·height·3 bytes, so this cannot fail; fall back to a blank
    // image rather than panicking.
    let img = RgbImage::from_raw(width, height, buf).unwrap_or_else(|| RgbImage::new(width, height));
    match opts.light.jpeg_quality {
        0 => img,
        q => light::jpeg_round_trip(&img, q),
    }
}

/// What the camera makes of the drawn scene `buf` (RGB bytes): white balance and tone curve,
/// then noise and chroma noise.
fn develop<R: Rng + ?Sized>(buf: &mut [u8], opts: &RenderOptions, rng: &mut R) {
    if let Some(table) = opts.light.tone_table() {
        for px in buf.chunks_exact_mut(3) {
            for (c, t) in px.iter_mut().zip(&table) {
                *c = t[usize::from(*c)];
            }
        }
    }
    if opts.noise_std.is_finite() && opts.noise_std > 0.0 {
        add_noise(buf, opts.noise_std, rng);
    }
    let chroma = opts.light.chroma_noise_std;
    if chroma.is_finite() && chroma > 0.0 {
        light::add_chroma_noise(buf, chroma, rng);
    }
}

/// The scene (the background and the block's `faces`, before the camera's [`develop`]) as RGB
/// bytes.
fn draw(cam: &Pinhole, faces: &[ScreenFace], opts: &RenderOptions) -> Vec<u8> {
    let (width, height) = (u32::from(cam.width()), u32::from(cam.height()));
    let (w, h) = (width as usize, height as usize);
    let (cols, rows) = background_tables(width, height, opts);
    let mut buf = vec![0u8; w * h * 3];
    for (row, &dy) in buf.chunks_exact_mut(w * 3).zip(&rows) {
        for (px, &cx) in row.chunks_exact_mut(3).zip(&cols) {
            px.fill(to_u8(cx + dy));
        }
    }

    if !faces.is_empty() {
        let mut bbox = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
        for f in faces {
            bbox = [bbox[0].min(f.bbox[0]), bbox[1].min(f.bbox[1]), bbox[2].max(f.bbox[2]), bbox[3].max(f.bbox[3])];
        }
        let clamp_to = |v: f32, hi: usize| v.clamp(0.0, hi as f32) as usize;
        let (x0, x1) = (clamp_to(bbox[0].floor() - 1.0, w), clamp_to(bbox[2].ceil() + 1.0, w));
        let (y0, y1) = (clamp_to(bbox[1].floor() - 1.0, h), clamp_to(bbox[3].ceil() + 1.0, h));
        let colours: Vec<[u8; 3]> = faces.iter().map(|f| f.colour.map(to_u8)).collect();
        let n_faces = faces.len().min(3);
        let lines = buf.chunks_exact_mut(w * 3).zip(&rows).enumerate().take(y1).skip(y0);
        for (y, (line, &row_off)) in lines {
            let v = y as f32 + 0.5;
            // Per face: the columns fully inside it, and those not fully outside it.
            let (mut inner, mut touched) = ([(0usize, 0usize); 3], [(0usize, 0usize); 3]);
            let (mut lo, mut hi) = (x1, x0);
            for (k, f) in faces.iter().enumerate().take(3) {
                inner[k] = f.row_span(v, HALF_DIAGONAL, w);
                touched[k] = f.row_span(v, -HALF_DIAGONAL, w);
                if touched[k].0 < touched[k].1 {
                    lo = lo.min(touched[k].0);
                    hi = hi.max(touched[k].1);
                }
            }
            let within = |x: usize, (a, b): (usize, usize)| a <= x && x < b;
            for (x, (px, &col)) in line.chunks_exact_mut(3).zip(&cols).enumerate().take(hi).skip(lo) {
                if let Some(k) = (0..n_faces).find(|&k| within(x, inner[k])) {
                    match &faces[k].shader {
                        None => px.copy_from_slice(&colours[k]),
                        Some(sh) => px.copy_from_slice(&sh.colour_at(x as f32 + 0.5, v).map(to_u8)),
                    }
                } else if (0..n_faces).any(|k| within(x, touched[k])) {
                    shade_pixel(faces, &colours, x as f32 + 0.5, v, col + row_off, opts.antialias, px);
                }
            }
        }
    }

    buf
}

/// Colours one pixel (centre `(u, v)`, background grey `bg`) inside the silhouette's box.
#[inline(always)]
fn shade_pixel(faces: &[ScreenFace], colours: &[[u8; 3]], u: f32, v: f32, bg: f32, aa: AntiAlias, px: &mut [u8]) {
    let mut dist = [[0.0f32; 4]; 3];
    let mut any_edge = false;
    for (k, f) in faces.iter().enumerate().take(3) {
        let d = f.distances(u, v);
        let dmin = d[0].min(d[1]).min(d[2]).min(d[3]);
        if dmin >= HALF_DIAGONAL {
            match &f.shader {
                None => px.copy_from_slice(&colours[k]),
                Some(sh) => px.copy_from_slice(&sh.colour_at(u, v).map(to_u8)),
            }
            return; // fully inside face k
        }
        any_edge |= dmin > -HALF_DIAGONAL;
        dist[k] = d;
    }
    if !any_edge {
        return; // fully outside every face: background stays
    }
    let n_faces = faces.len().min(3);
    let mut cover = [0.0f32; 3];
    match aa {
        AntiAlias::Off => {
            if let Some(k) = (0..n_faces).find(|&k| dist[k].iter().all(|&d| d >= 0.0)) {
                cover[k] = 1.0;
            }
        }
        AntiAlias::Supersample(n) => {
            let n = n.clamp(1, 16);
            let step = 1.0 / f32::from(n);
            let weight = step * step;
            for sy in 0..n {
                let dv = (f32::from(sy) + 0.5) * step - 0.5;
                for sx in 0..n {
                    let du = (f32::from(sx) + 0.5) * step - 0.5;
                    for k in 0..n_faces {
                        let inside =
                            faces[k].edges.iter().zip(&dist[k]).all(|(&[a, b, _], &d)| d + a * du + b * dv >= 0.0);
                        if inside {
                            cover[k] += weight;
                            break;
                        }
                    }
                }
            }
        }
        AntiAlias::Exact => {
            for k in 0..n_faces {
                let [a0, a1, a2, a3] = faces[k].edges;
                let [d0, d1, d2, d3] = dist[k];
                let lines = [[a0[0], a0[1], d0], [a1[0], a1[1], d1], [a2[0], a2[1], d2], [a3[0], a3[1], d3]];
                cover[k] = clipped_square_area(&lines);
            }
        }
    }
    let total: f32 = cover.iter().sum();
    let scale = if total > 1.0 { 1.0 / total } else { 1.0 };
    let bg_weight = (1.0 - total * scale).max(0.0);
    let mut face_colour = [[0.0f32; 3]; 3];
    for k in 0..n_faces {
        face_colour[k] = faces[k].colour_at(u, v);
    }
    for (c, out) in px.iter_mut().enumerate() {
        let mut acc = bg * bg_weight;
        for k in 0..n_faces {
            acc += cover[k] * scale * face_colour[k][c];
        }
        *out = to_u8(acc);
    }
}

/// Adds per-channel noise of standard deviation `std` (8-bit levels), clamped.
///
/// Each sample is a sum of four uniform random 4-bit values (Irwin–Hall: mean 30, variance
/// 4·255/12 = 85), mapped through a table to `round(std · z)`, so one `u64` gives four samples
/// (the generator is the main cost). The shape is close to Gaussian, truncated at ±3.25σ.
fn add_noise<R: Rng + ?Sized>(buf: &mut [u8], std: f32, rng: &mut R) {
    // Noise is drawn into a block buffer first, so that adding it vectorises.
    let mut noise = [0i16; 2048];
    for chunk in buf.chunks_mut(noise.len()) {
        fill_noise(&mut noise[..chunk.len().next_multiple_of(4)], std, rng);
        for (b, &n) in chunk.iter_mut().zip(&noise) {
            *b = (i16::from(*b) + n).clamp(0, 255) as u8;
        }
    }
}

/// Fills `out` with [`add_noise`]'s samples of standard deviation `std`, four from each `u64`
/// of `rng` (a last partial group of four takes a whole `u64`).
fn fill_noise<R: Rng + ?Sized>(out: &mut [i16], std: f32, rng: &mut R) {
    const SUM_MEAN: f32 = 30.0;
    const SUM_STD: f32 = 9.219_544; // √85
    const NIBBLES: u64 = 0x0F0F_0F0F_0F0F_0F0F;
    const BYTES: u64 = 0x00FF_00FF_00FF_00FF;
    let mut table = [0i16; 64];
    for (s, t) in table.iter_mut().enumerate().take(61) {
        let z = (s as f32 - SUM_MEAN) / SUM_STD;
        *t = (std * z).round().clamp(-512.0, 512.0) as i16;
    }
    for quad in out.chunks_mut(4) {
        let x = rng.next_u64();
        // Eight byte lanes of two nibbles each, then four 16-bit lanes of four nibbles.
        let s8 = (x & NIBBLES) + ((x >> 4) & NIBBLES);
        let s16 = (s8 & BYTES) + ((s8 >> 8) & BYTES);
        for (i, n) in quad.iter_mut().enumerate() {
            // Each lane sum is ≤ 60, so the mask keeps it inside the table.
            *n = table[((s16 >> (16 * i)) & 0x3F) as usize];
        }
    }
}

/// Renders both images of a stereo rig; `cr_from_model` is the block's pose in the right
/// camera frame `Σ_CR`. The right image is rendered first, then the left, from the same `rng`.
pub fn render_stereo<R: Rng + ?Sized>(
    rig: &StereoRig,
    cr_from_model: &Isometry3<f32>,
    block: &Block,
    opts: &RenderOptions,
    rng: &mut R,
) -> StereoImages {
    render_stereo_blurred(rig, &[*cr_from_model], block, opts, rng)
}

/// [`render_stereo`] with motion blur: each image is the mean of the block drawn at every pose
/// of `cr_from_model` (in `Σ_CR`, over one exposure). One pose is [`render_stereo`]; no pose
/// gives the background alone.
pub fn render_stereo_blurred<R: Rng + ?Sized>(
    rig: &StereoRig,
    cr_from_model: &[Isometry3<f32>],
    block: &Block,
    opts: &RenderOptions,
    rng: &mut R,
) -> StereoImages {
    let gone = [Isometry3::translation(0.0, 0.0, -10.0)];
    let right_poses = if cr_from_model.is_empty() { &gone[..] } else { cr_from_model };
    // A shadow of the camera frame is where Σ_CR puts it, for both cameras.
    let right: Vec<_> = right_poses.iter().map(|p| (*p, opts.light.shadow_in_block(p))).collect();
    let left: Vec<_> = right.iter().map(|(p, shadow)| (rig.left_from_right * p, *shadow)).collect();
    let right = render_blurred(&rig.right, &right, block, opts, rng);
    let left = render_blurred(&rig.left, &left, block, opts, rng);
    StereoImages { left, right }
}

/// The hue image of `img` (row-major, one byte per pixel), converted pixel by pixel with the
/// core's [`rgb_to_hue`], so the simulator sees exactly what the board would compute.
pub fn hue_image(img: &RgbImage) -> Vec<u8> {
    let mut out = vec![0u8; (img.width() * img.height()) as usize];
    hue_into(img, &mut out);
    out
}

impl StereoImages {
    /// Both images' hue planes ([`hue_into`]) written into `left` and `right` (`width·height`
    /// bytes each), as the core's frame pair.
    ///
    /// # Errors
    /// The core's [`ImageError`] when a buffer does not hold an image of the images' size.
    pub fn hue_frame<'a>(&self, left: &'a mut [u8], right: &'a mut [u8]) -> Result<StereoFrame<'a>, ImageError> {
        hue_into(&self.left, left);
        hue_into(&self.right, right);
        let side = |v: u32| u16::try_from(v).unwrap_or(u16::MAX);
        let (w, h) = (side(self.right.width()), side(self.right.height()));
        Ok(StereoFrame { left: HueImage::new_checked(&*left, w, h)?, right: HueImage::new_checked(&*right, w, h)? })
    }
}

/// `img` as RGB565 bytes ([`rgb565_into`] into a new buffer of `2·width·height` bytes).
pub fn rgb565_image(img: &RgbImage) -> Vec<u8> {
    let mut out = vec![0u8; 2 * (img.width() * img.height()) as usize];
    rgb565_into(img, &mut out);
    out
}

/// [`hue_image`] into a caller's buffer (the first `width·height` bytes; a shorter buffer gets
/// as many pixels as it holds).
pub fn hue_into(img: &RgbImage, out: &mut [u8]) {
    for (d, p) in out.iter_mut().zip(img.as_raw().chunks_exact(3)) {
        *d = rgb_to_hue(p[0], p[1], p[2]);
    }
}

/// `img` as the RGB565 pixels a camera sensor delivers (2 bytes per pixel, little-endian,
/// each channel truncated to its top 5/6/5 bits by the core's [`rgb888_to_rgb565`]) into a
/// caller's buffer (the first `2·width·height` bytes; a shorter buffer gets as many whole
/// pixels as it holds). The simulator's boards hand these bytes to the tracker, on the host
/// and over the firmware link alike.
pub fn rgb565_into(img: &RgbImage, out: &mut [u8]) {
    for (d, p) in out.chunks_exact_mut(2).zip(img.as_raw().chunks_exact(3)) {
        d.copy_from_slice(&rgb888_to_rgb565(p[0], p[1], p[2]).to_le_bytes());
    }
}

/// `img` as the simulated sensor delivered it, saved as 8-bit RGB: each pixel truncated to
/// RGB565 ([`rgb565_into`]'s values) and widened back by bit replication
/// ([`rgb565_to_rgb888`]). The core's RGB565 hue table is built the same way, so a tracker
/// reading these 8-bit pixels computes exactly the hue the simulator's tracker looked up.
pub fn sensor_rgb(img: &RgbImage) -> RgbImage {
    let mut out = img.clone();
    for p in out.pixels_mut() {
        let (r, g, b) = rgb565_to_rgb888(rgb888_to_rgb565(p[0], p[1], p[2]));
        *p = Rgb([r, g, b]);
    }
    out
}

/// Draws a small `+` mark (3 × 3 pixels) of `colour` at each point given in continuous pixel
/// coordinates (pixel `(i, j)` covers `[i, i+1) × [j, j+1)`); points outside the image or not
/// finite are skipped, marks are clipped at the border. Used to overlay the projected search
/// model on a frame (the paper's Fig. 4).
pub fn draw_points(img: &mut RgbImage, points: &[(f32, f32)], colour: [u8; 3]) {
    let (w, h) = (img.width() as f32, img.height() as f32);
    for &(u, v) in points {
        if !((0.0..w).contains(&u) && (0.0..h).contains(&v)) {
            continue;
        }
        let (x, y) = (u as i64, v as i64);
        for (dx, dy) in [(0, 0), (-1, 0), (1, 0), (0, -1), (0, 1)] {
            let (Ok(px), Ok(py)) = (u32::try_from(x + dx), u32::try_from(y + dy)) else { continue };
            if px < img.width() && py < img.height() {
                img.put_pixel(px, py, Rgb(colour));
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests;

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod light_tests;
