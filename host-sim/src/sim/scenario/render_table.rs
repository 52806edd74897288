//! `[render]`: the camera-like light of a scenario ([`crate::sim::render::Light`]), in a scenario
//! file or in a light file (`--light FILE` of `evorec acquire` and `evorec paper`: a `[render]`
//! table and nothing else).

use std::path::Path;

use toml::{Table, Value};

use super::check::{Bound, check_range, deserialize, float_in, int_in};
use super::raw::{Floats, RawLightFile, RawRender};
use super::{Result, ScenarioError, invalid};
use crate::sim::render::{Light, ShadowFrame, ToneCurve};

/// A finite, non-zero direction (not normalised).
fn direction(field: &str, v: Option<Floats<3>>, default: [f32; 3]) -> Result<[f32; 3]> {
    let v = v.map_or(default.map(f64::from), |f| f.0);
    let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !norm.is_finite() || norm == 0.0 {
        let [x, y, z] = v;
        return Err(invalid(field, format!("must be a finite, non-zero vector, got [{x}, {y}, {z}]")));
    }
    Ok(v.map(|x| x as f32))
}

fn real(field: &str, x: Option<f64>, default: f32, lo: Bound, hi: f64) -> Result<f32> {
    Ok(float_in(field, x, f64::from(default), lo, hi)? as f32)
}

/// Checks a `[render]` table; `frame_period_s` bounds the exposure.
pub(super) fn parse_render(r: RawRender, frame_period_s: f64) -> Result<Light> {
    let d = Light::default();
    let shadow_frame = match r.shadow_frame.as_deref().unwrap_or("camera") {
        "camera" => ShadowFrame::Camera,
        "block" => ShadowFrame::Block,
        other => {
            return Err(invalid("render.shadow_frame", format!("expected \"camera\" or \"block\", got \"{other}\"")));
        }
    };
    let curve = r.tone_curve.as_deref().unwrap_or("linear");
    let tone_curve = ToneCurve::NAMES.iter().find(|(n, _)| *n == curve).map(|(_, c)| *c).ok_or_else(|| {
        invalid("render.tone_curve", format!("expected \"linear\", \"srgb\" or \"filmic\", got \"{curve}\""))
    })?;
    let gains = r.white_balance.map_or(d.white_balance.map(f64::from), |f| f.0);
    for (i, g) in gains.iter().enumerate() {
        check_range(&format!("render.white_balance[{i}]"), *g, Bound::Open(0.0), 4.0)?;
    }
    let exposure_s =
        real("render.exposure_s", r.exposure_s, d.exposure_s, Bound::Closed(0.0), frame_period_s.min(0.5))?;
    Ok(Light {
        light_dir_cam: direction("render.light_dir_cam", r.light_dir_cam, d.light_dir_cam)?,
        ambient: real("render.ambient", r.ambient, d.ambient, Bound::Closed(0.0), 1.0)?,
        diffuse: real("render.diffuse", r.diffuse, d.diffuse, Bound::Closed(0.0), 1.0)?,
        albedo_saturation: real(
            "render.albedo_saturation",
            r.albedo_saturation,
            d.albedo_saturation,
            Bound::Open(0.0),
            1.0,
        )?,
        specular: real("render.specular", r.specular, d.specular, Bound::Closed(0.0), 4.0)?,
        shininess: real("render.shininess", r.shininess, d.shininess, Bound::Closed(1.0), 10_000.0)?,
        shadow_frame,
        shadow_normal: direction("render.shadow_normal", r.shadow_normal, d.shadow_normal)?,
        shadow_offset_m: real(
            "render.shadow_offset_m",
            r.shadow_offset_m,
            d.shadow_offset_m,
            Bound::Closed(-10.0),
            10.0,
        )?,
        shadow_width_m: real("render.shadow_width_m", r.shadow_width_m, d.shadow_width_m, Bound::Closed(0.0), 20.0)?,
        tone_curve,
        tone_exposure: real("render.tone_exposure", r.tone_exposure, d.tone_exposure, Bound::Open(0.0), 16.0)?,
        white_balance: gains.map(|g| g as f32),
        chroma_noise_std: real(
            "render.chroma_noise_std",
            r.chroma_noise_std,
            d.chroma_noise_std,
            Bound::Closed(0.0),
            100.0,
        )?,
        exposure_s,
        blur_samples: int_in("render.blur_samples", r.blur_samples, i64::from(d.blur_samples), 1, 32)? as u32,
        jpeg_quality: int_in("render.jpeg_quality", r.jpeg_quality, i64::from(d.jpeg_quality), 0, 100)? as u8,
    })
}

/// Reads a light file's text: a `[render]` table and nothing else (the exposure bounded by
/// `frame_period_s`, the frame period of the runs it is for).
///
/// # Errors
/// [`ScenarioError::Syntax`], or [`ScenarioError::Invalid`] naming the key.
pub fn light_from_toml_str(text: &str, frame_period_s: f64) -> Result<Light> {
    let table: Table = toml::from_str(text).map_err(|e| ScenarioError::Syntax(e.to_string().trim_end().to_owned()))?;
    if let Some(k) = table.keys().find(|k| *k != "render") {
        return Err(invalid(k.as_str(), "unknown key (a light file holds a [render] table only)"));
    }
    match table.get("render") {
        None => Ok(Light::default()),
        Some(Value::Table(_)) => {
            let raw: RawLightFile = deserialize(text, &table)?;
            parse_render(raw.render.unwrap_or_default(), frame_period_s)
        }
        Some(_) => Err(invalid("render", "expected a table")),
    }
}

/// [`light_from_toml_str`] of a file.
///
/// # Errors
/// [`ScenarioError::Io`], or [`ScenarioError::InFile`] naming the file.
pub fn load_light(path: impl AsRef<Path>, frame_period_s: f64) -> Result<Light> {
    let path = path.as_ref();
    let text =
        std::fs::read_to_string(path).map_err(|source| ScenarioError::Io { path: path.to_path_buf(), source })?;
    light_from_toml_str(&text, frame_period_s)
        .map_err(|e| ScenarioError::InFile { path: path.to_path_buf(), source: Box::new(e) })
}
