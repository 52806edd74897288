//! The frames' PNG images: 8-bit RGB or RGBA (alpha ignored), of the calibration's size.

use std::path::Path;

use image::{DynamicImage, ImageFormat, RgbImage};

use super::error::{Result, SequenceError};

/// Decodes one PNG and checks its size against the camera's `width × height`.
///
/// # Errors
/// Missing or unreadable file, not a PNG, not 8-bit RGB/RGBA, wrong size.
pub fn decode(path: &Path, width: u32, height: u32) -> Result<RgbImage> {
    let bytes = std::fs::read(path).map_err(|e| SequenceError::file(path, format!("cannot read: {e}")))?;
    let img = image::load_from_memory_with_format(&bytes, ImageFormat::Png)
        .map_err(|e| SequenceError::file(path, format!("not a readable PNG: {e}")))?;
    let rgb = match img {
        DynamicImage::ImageRgb8(rgb) => rgb,
        DynamicImage::ImageRgba8(_) => img.to_rgb8(),
        other => {
            return Err(SequenceError::file(
                path,
                format!("pixel format {:?} is not supported (8-bit RGB or RGBA only)", other.color()),
            ));
        }
    };
    if rgb.dimensions() != (width, height) {
        return Err(SequenceError::file(
            path,
            format!("image is {}x{}, its camera's calibration says {width}x{height}", rgb.width(), rgb.height()),
        ));
    }
    Ok(rgb)
}
