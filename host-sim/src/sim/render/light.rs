//! Camera-like light: what a real camera adds to the flat, Lambert-shaded faces of the renderer
//! (the `[render]` table of a scenario, [`crate::sim::scenario`]).
//!
//! Every effect is off in [`Light::default`], which renders exactly what the renderer always
//! has. In the order a frame is made:
//!
//! 1. **Shading**: each face's albedo (its hue at [`Light::albedo_saturation`], full value) lit
//!    by `ambient + diffuse · max(n·l, 0)` from a directional light `l` fixed in the camera
//!    frame ([`Light::light_dir_cam`]);
//! 2. **highlight**: Blinn–Phong, `specular · max(n·h, 0)^shininess` of white added to each
//!    channel (`h` halfway between the light and the viewing direction), which turns part of
//!    a face turned towards the light nearly white. Across a flat face the viewing direction
//!    changes by a few degrees only, so a moderate `shininess` whitens the whole face; a spot
//!    needs a large one (`scenarios/camera_like.toml` uses 1500) and a light near the mirror
//!    direction of the face;
//! 3. **cast shadow**: a band `offset ≤ n̂·p < offset + width` of space (`p` in the right
//!    camera's frame `Σ_CR` or in the block's frame) where the directional light is blocked:
//!    the faces get only the ambient term there (no diffuse, no highlight); in the camera frame
//!    the band's edge sweeps across the faces as the block moves relative to the cameras;
//! 4. **motion blur**: the frame is the mean of `blur_samples` renders at poses evenly spread
//!    over `[t, t + exposure_s]` (`t` the capture time, [`crate::sim::board::World::render`]);
//! 5. **white balance** (per-channel gains) and the **tone curve** (per channel, after the
//!    gains and [`Light::tone_exposure`]; it takes the drawn 8-bit levels, clamped at 255, as
//!    linear light): `linear` (clamped), `srgb` (the sRGB transfer
//!    function) or `filmic` (Narkowicz's fit of the ACES curve,
//!    `x(2.51x + 0.03) / (x(2.43x + 0.59) + 0.14)`), which compresses bright channels more than
//!    dim ones and so moves hues that are not a multiple of 60°;
//! 6. **noise**: the scenario's per-channel noise (`camera.noise_std`), then chroma noise:
//!    `Cb`, `Cr` offsets of standard deviation [`Light::chroma_noise_std`] per pixel, which
//!    leave the luma (BT.601) unchanged;
//! 7. **JPEG**: an encode and decode at [`Light::jpeg_quality`] with the `image` crate's codec.
//!
//! The per-face statistics that show what each effect does are [`super::face_stats`].
//!
//! The keys of a scenario's `[render]` table (every key optional; the values shown are the
//! defaults; a bad value gets one message naming the key, e.g.
//! `render.jpeg_quality: must be in 0..=100, got 101`):
//!
//! ```toml
//! [render]
//! light_dir_cam = [-0.4, -0.6, -1.0] # finite, non-zero: towards the light, camera frame
//! ambient = 0.35           # [0, 1]: brightness of a face the light does not reach
//! diffuse = 0.65           # [0, 1]: Lambert brightness added for a face facing the light
//! albedo_saturation = 1.0  # (0, 1]: HSV saturation of the faces' paint (lower mixes in white)
//! specular = 0.0           # [0, 4]: Blinn–Phong highlight strength (white); 0 = none
//! shininess = 40.0         # [1, 10000]: Blinn–Phong exponent (larger: smaller highlight)
//! shadow_frame = "camera"  # "camera" (Σ_CR) | "block": the frame the cast shadow is fixed in
//! shadow_normal = [1, 0, 0] # finite, non-zero: normal n̂ of the shadow band's planes
//! shadow_offset_m = 0.0    # [-10, 10]: the band is offset ≤ n̂·p < offset + width (m)
//! shadow_width_m = 0.0     # [0, 20]: 0 = no shadow; there the faces get the ambient light only
//! tone_curve = "linear"    # "linear" | "srgb" | "filmic": per channel, after the gains
//! tone_exposure = 1.0      # (0, 16]: factor on every channel before the tone curve
//! white_balance = [1, 1, 1] # each (0, 4]: per-channel gains (a white-balance error)
//! chroma_noise_std = 0.0   # [0, 100]: σ of per-pixel Cb and Cr noise (8-bit levels)
//! exposure_s = 0.0         # [0, min(frame_period_s, 0.5)]: motion blur over [t, t + exposure_s]
//! blur_samples = 5         # 1 ..= 32: renders averaged over the exposure
//! jpeg_quality = 0         # 0 ..= 100: JPEG encode and decode at this quality; 0 = none
//! ```

use image::RgbImage;
use nalgebra::{Isometry3, Vector3};
use rand_core::Rng;
use serde::Serialize;

/// The frame a [`Light`]'s cast shadow is fixed in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub enum ShadowFrame {
    /// The right camera's frame `Σ_CR` (an occluder carried with the cameras, or the relative
    /// motion of block and cameras moving the shadow's edge across the faces).
    #[default]
    #[serde(rename = "camera")]
    Camera,
    /// The block's own frame (the shadow moves with the block).
    #[serde(rename = "block")]
    Block,
}

/// The per-channel tone curve of a [`Light`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub enum ToneCurve {
    /// `y = x`, clamped to `[0, 1]`.
    #[default]
    #[serde(rename = "linear")]
    Linear,
    /// The sRGB transfer function (linear light to sRGB code values).
    #[serde(rename = "srgb")]
    Srgb,
    /// Narkowicz's fit of the ACES filmic curve: a toe and a per-channel shoulder.
    #[serde(rename = "filmic")]
    Filmic,
}

impl ToneCurve {
    /// Every curve and its name in a scenario file.
    pub const NAMES: [(&'static str, ToneCurve); 3] =
        [("linear", ToneCurve::Linear), ("srgb", ToneCurve::Srgb), ("filmic", ToneCurve::Filmic)];

    /// The curve at `x ≥ 0` (linear light, 1 = the brightest 8-bit level), in `[0, 1]`.
    pub fn apply(self, x: f32) -> f32 {
        let x = x.max(0.0);
        let y = match self {
            Self::Linear => x,
            Self::Srgb if x <= 0.003_130_8 => 12.92 * x,
            Self::Srgb => 1.055 * x.powf(1.0 / 2.4) - 0.055,
            Self::Filmic => x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14),
        };
        y.clamp(0.0, 1.0)
    }
}

/// Camera-like light and imaging: the `[render]` keys of a scenario. Field names are the keys.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Light {
    /// Direction from the surface **towards** the light, in the camera frame (need not be
    /// normalised). The default comes from the upper left, in front of the block.
    pub light_dir_cam: [f32; 3],
    /// Ambient brightness (0..=1) a face has when the light does not reach it. Keep it above
    /// about 0.16 so that unlit faces stay bright enough to have a hue.
    pub ambient: f32,
    /// Diffuse (Lambert) brightness added for a face turned straight at the light.
    pub diffuse: f32,
    /// HSV saturation of the faces' paint (1 = the pure hue; lower mixes in white).
    pub albedo_saturation: f32,
    /// Strength of the white Blinn–Phong highlight (0 = none).
    pub specular: f32,
    /// Blinn–Phong exponent: larger is a smaller, sharper highlight.
    pub shininess: f32,
    /// The frame the cast shadow is fixed in.
    pub shadow_frame: ShadowFrame,
    /// Unit normal `n̂` of the shadow band's planes, in [`Light::shadow_frame`].
    pub shadow_normal: [f32; 3],
    /// Where the band starts along `n̂` (m).
    pub shadow_offset_m: f32,
    /// Width of the band along `n̂` (m); 0 = no shadow.
    pub shadow_width_m: f32,
    /// The per-channel tone curve.
    pub tone_curve: ToneCurve,
    /// Factor on every channel before the tone curve.
    pub tone_exposure: f32,
    /// Per-channel gains `[r, g, b]` before the tone curve (a white-balance error).
    pub white_balance: [f32; 3],
    /// Standard deviation of the per-pixel `Cb` and `Cr` noise (8-bit levels; 0 = none).
    pub chroma_noise_std: f32,
    /// Exposure time (s) the block's motion is blurred over; 0 = no blur.
    pub exposure_s: f32,
    /// Renders averaged over the exposure (used when `exposure_s > 0`).
    pub blur_samples: u32,
    /// JPEG quality 1..=100 of an encode and decode of every image; 0 = none.
    pub jpeg_quality: u8,
}

impl Default for Light {
    fn default() -> Self {
        Self {
            light_dir_cam: [-0.4, -0.6, -1.0],
            ambient: 0.35,
            diffuse: 0.65,
            albedo_saturation: 1.0,
            specular: 0.0,
            shininess: 40.0,
            shadow_frame: ShadowFrame::Camera,
            shadow_normal: [1.0, 0.0, 0.0],
            shadow_offset_m: 0.0,
            shadow_width_m: 0.0,
            tone_curve: ToneCurve::Linear,
            tone_exposure: 1.0,
            white_balance: [1.0; 3],
            chroma_noise_std: 0.0,
            exposure_s: 0.0,
            blur_samples: 5,
            jpeg_quality: 0,
        }
    }
}

impl Light {
    /// Whether every key is at its default (a scenario then omits the table).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// The unit light direction (towards the light) in the camera frame; straight at the
    /// camera's view if the key is zero or not finite.
    pub(super) fn direction(&self) -> Vector3<f32> {
        let light = Vector3::from(self.light_dir_cam);
        if light.norm() > 0.0 && light.iter().all(|c| c.is_finite()) {
            light.normalize()
        } else {
            Vector3::new(0.0, 0.0, -1.0)
        }
    }

    /// Whether each face is one flat colour (no highlight, no shadow).
    pub(super) fn is_flat(&self) -> bool {
        self.specular <= 0.0 && self.shadow_width_m <= 0.0
    }

    /// The times `τ` (s after the capture) of the poses the motion blur averages: `blur_samples`
    /// times evenly spread over `[0, exposure_s]`, or `[0]` without blur.
    pub fn blur_times(&self) -> Vec<f64> {
        let n = if self.exposure_s > 0.0 { self.blur_samples.max(1) } else { 1 };
        let step = if n > 1 { f64::from(self.exposure_s) / f64::from(n - 1) } else { 0.0 };
        (0..n).map(|i| f64::from(i) * step).collect()
    }

    /// The shadow band in the block's frame, the block at `cr_from_model` in the camera a
    /// [`ShadowFrame::Camera`] band is fixed in (`Σ_CR`); `None` without a shadow.
    pub(super) fn shadow_in_block(&self, cr_from_model: &Isometry3<f32>) -> Option<Band> {
        if self.shadow_width_m <= 0.0 {
            return None;
        }
        let n = Vector3::from(self.shadow_normal);
        let n = if n.norm() > 0.0 { n.normalize() } else { Vector3::x() };
        let (lo, hi) = (self.shadow_offset_m, self.shadow_offset_m + self.shadow_width_m);
        Some(match self.shadow_frame {
            ShadowFrame::Block => Band { normal: n, lo, hi },
            ShadowFrame::Camera => {
                // n̂·p_cam = (Rᵀn̂)·p_model + n̂·t.
                let shift = n.dot(&cr_from_model.translation.vector);
                Band { normal: cr_from_model.rotation.inverse() * n, lo: lo - shift, hi: hi - shift }
            }
        })
    }

    /// The per-channel table of white balance, exposure and tone curve; `None` when it is the
    /// identity.
    pub(super) fn tone_table(&self) -> Option<[[u8; 256]; 3]> {
        let identity =
            self.tone_curve == ToneCurve::Linear && self.tone_exposure == 1.0 && self.white_balance == [1.0; 3];
        if identity {
            return None;
        }
        let mut table = [[0u8; 256]; 3];
        for (t, gain) in table.iter_mut().zip(self.white_balance) {
            for (v, out) in t.iter_mut().enumerate() {
                let x = v as f32 / 255.0 * gain * self.tone_exposure;
                *out = (255.0 * self.tone_curve.apply(x) + 0.5) as u8;
            }
        }
        Some(table)
    }
}

/// A band `lo ≤ n̂·p < hi` of space (`n̂` unit).
#[derive(Debug, Clone, Copy)]
pub(super) struct Band {
    pub normal: Vector3<f32>,
    pub lo: f32,
    pub hi: f32,
}

impl Band {
    /// The band in another frame: `other_from_this` maps this band's frame into it.
    pub fn moved(&self, other_from_this: &Isometry3<f32>) -> Band {
        let normal = other_from_this.rotation * self.normal;
        let shift = normal.dot(&other_from_this.translation.vector);
        Band { normal, lo: self.lo + shift, hi: self.hi + shift }
    }

    fn contains(&self, p: &Vector3<f32>) -> bool {
        let d = self.normal.dot(p);
        self.lo <= d && d < self.hi
    }
}

/// The per-pixel shading of one face (highlight, shadow), in the frame of the camera.
#[derive(Debug, Clone, Copy)]
pub(super) struct FaceShader {
    /// Intrinsics `[fx, fy, cx, cy]` to turn a pixel into its viewing ray.
    pub intrinsics: [f32; 4],
    /// Outward unit normal and `n·p` of the face's plane.
    pub normal: Vector3<f32>,
    pub plane: f32,
    /// The face's albedo (0..=1 per channel).
    pub albedo: [f32; 3],
    /// Unit direction towards the light.
    pub light: Vector3<f32>,
    pub ambient: f32,
    pub diffuse: f32,
    pub specular: f32,
    pub shininess: f32,
    /// The shadow band in this camera's frame.
    pub shadow: Option<Band>,
}

impl FaceShader {
    /// The face's colour (8-bit scale) where the pixel centre `(u, v)`'s ray meets its plane.
    pub fn colour_at(&self, u: f32, v: f32) -> [f32; 3] {
        let [fx, fy, cx, cy] = self.intrinsics;
        let ray = Vector3::new((u - cx) / fx, (v - cy) / fy, 1.0);
        let along = self.normal.dot(&ray);
        let p = if along.abs() > 1e-9 { ray * (self.plane / along) } else { ray };
        let lit = !self.shadow.is_some_and(|b| b.contains(&p));
        let lambert = if lit { self.normal.dot(&self.light).max(0.0) } else { 0.0 };
        let shade = (self.ambient + self.diffuse * lambert).clamp(0.0, 1.0);
        let view = -p.try_normalize(1e-12).unwrap_or_else(Vector3::z);
        let half = (self.light + view).try_normalize(1e-12).unwrap_or(view);
        let spec = if lit && lambert > 0.0 {
            self.specular * self.normal.dot(&half).max(0.0).powf(self.shininess)
        } else {
            0.0
        };
        self.albedo.map(|c| 255.0 * (c * shade + spec))
    }
}

/// The albedo of a face of hue colour `pure` (0..=1, full saturation) at `saturation`.
pub(super) fn albedo(pure: [f32; 3], saturation: f32) -> [f32; 3] {
    if saturation >= 1.0 { pure } else { pure.map(|c| 1.0 - saturation * (1.0 - c)) }
}

/// Adds chroma noise (`Cb`, `Cr` offsets of standard deviation `std`, luma unchanged).
pub(super) fn add_chroma_noise<R: Rng + ?Sized>(buf: &mut [u8], std: f32, rng: &mut R) {
    let mut offsets = vec![0i16; 2 * (buf.len() / 3)];
    super::fill_noise(&mut offsets, std, rng);
    for (px, cbcr) in buf.chunks_exact_mut(3).zip(offsets.chunks_exact(2)) {
        let (cb, cr) = (f32::from(cbcr[0]), f32::from(cbcr[1]));
        let delta = [1.402 * cr, -0.344_136 * cb - 0.714_136 * cr, 1.772 * cb];
        for (c, d) in px.iter_mut().zip(delta) {
            *c = (f32::from(*c) + d).round().clamp(0.0, 255.0) as u8;
        }
    }
}

/// `img` encoded as JPEG at `quality` (1..=100) and decoded again; `img` itself if the codec
/// fails.
pub fn jpeg_round_trip(img: &RgbImage, quality: u8) -> RgbImage {
    let mut bytes = Vec::new();
    let encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, quality.clamp(1, 100));
    if img.write_with_encoder(encoder).is_err() {
        return img.clone();
    }
    image::load_from_memory_with_format(&bytes, image::ImageFormat::Jpeg)
        .map(|d| d.to_rgb8())
        .unwrap_or_else(|_| img.clone())
}
