//! Camera images of a bag as 8-bit RGB: `sensor_msgs/Image` in `rgb8`, `bgr8`, `rgba8`,
//! `bgra8` and the four 8-bit Bayer mosaics (debayered bilinearly, [`debayer`]), and
//! `sensor_msgs/CompressedImage` in PNG or JPEG (the `image` crate). A mono image is refused:
//! the tracker tells the block's faces apart by hue.

use image::{DynamicImage, ImageFormat, RgbImage};

use super::msgs::{CompressedImage, Image};

/// The colour of each pixel of a 2×2 Bayer tile, row-major (0 = R, 1 = G, 2 = B).
fn bayer_tile(encoding: &str) -> Option<[usize; 4]> {
    match encoding {
        "bayer_rggb8" => Some([0, 1, 1, 2]),
        "bayer_bggr8" => Some([2, 1, 1, 0]),
        "bayer_gbrg8" => Some([1, 2, 0, 1]),
        "bayer_grbg8" => Some([1, 0, 2, 1]),
        _ => None,
    }
}

fn is_mono(encoding: &str) -> bool {
    matches!(encoding, "mono8" | "mono16" | "8UC1" | "16UC1" | "32FC1")
}

/// The encodings [`to_rgb`] reads.
pub const ENCODINGS: &str = "rgb8, bgr8, rgba8, bgra8, bayer_rggb8, bayer_bggr8, bayer_gbrg8, bayer_grbg8";

/// Checks that `encoding` is one [`to_rgb`] reads.
///
/// # Errors
/// A mono or an unknown encoding.
pub fn check_encoding(encoding: &str) -> Result<(), String> {
    if is_mono(encoding) {
        return Err(format!(
            "encoding \"{encoding}\" is mono: a mono image cannot give hue, and evorec tells the block's faces apart by hue"
        ));
    }
    if channels(encoding).is_none() && bayer_tile(encoding).is_none() {
        return Err(format!("unknown encoding \"{encoding}\" (evorec reads {ENCODINGS})"));
    }
    Ok(())
}

fn channels(encoding: &str) -> Option<(usize, [usize; 3])> {
    match encoding {
        "rgb8" => Some((3, [0, 1, 2])),
        "bgr8" => Some((3, [2, 1, 0])),
        "rgba8" => Some((4, [0, 1, 2])),
        "bgra8" => Some((4, [2, 1, 0])),
        _ => None,
    }
}

/// The pixels of a `sensor_msgs/Image` as RGB.
///
/// # Errors
/// A mono or unknown encoding, a size that does not fit `step` and `data`.
pub fn to_rgb(img: &Image<'_>) -> Result<RgbImage, String> {
    check_encoding(&img.encoding)?;
    let (w, h, step) = (img.width as usize, img.height as usize, img.step as usize);
    let bpp = channels(&img.encoding).map_or(1, |c| c.0);
    if w == 0 || h == 0 || step < w * bpp || img.data.len() < step * (h - 1) + w * bpp {
        return Err(format!(
            "{}x{} {} with step {} needs {} bytes, data has {}",
            img.width,
            img.height,
            img.encoding,
            img.step,
            step.max(w * bpp) * h,
            img.data.len()
        ));
    }
    let rows = |y: usize| &img.data[y * step..y * step + w * bpp];
    let mut out = Vec::with_capacity(w * h * 3);
    match (channels(&img.encoding), bayer_tile(&img.encoding)) {
        (Some((3, [0, 1, 2])), _) => (0..h).for_each(|y| out.extend_from_slice(rows(y))),
        (Some((n, order)), _) => {
            for y in 0..h {
                for px in rows(y).chunks_exact(n) {
                    out.extend(order.iter().map(|c| px[*c]));
                }
            }
        }
        (None, Some(tile)) => {
            let raw: Vec<u8> = (0..h).flat_map(|y| rows(y).iter().copied()).collect();
            out = debayer(&raw, w, h, tile);
        }
        (None, None) => return Err(format!("unknown encoding \"{}\"", img.encoding)),
    }
    RgbImage::from_raw(img.width, img.height, out).ok_or_else(|| "image buffer has the wrong size".to_owned())
}

/// Bilinear demosaicing of an 8-bit Bayer image (`tile`: the colours of its top-left 2×2,
/// row-major): each missing colour of a pixel is the mean of that colour among its 8
/// neighbours (2 or 4 of them; at the border, those inside the image), rounded.
pub fn debayer(raw: &[u8], w: usize, h: usize, tile: [usize; 4]) -> Vec<u8> {
    let colour = |x: usize, y: usize| tile[(y & 1) * 2 + (x & 1)];
    let mut out = vec![0u8; w * h * 3];
    for y in 0..h {
        for x in 0..w {
            let own = colour(x, y);
            let mut sum = [0u32; 3];
            let mut n = [0u32; 3];
            for yy in y.saturating_sub(1)..=(y + 1).min(h - 1) {
                for xx in x.saturating_sub(1)..=(x + 1).min(w - 1) {
                    let c = colour(xx, yy);
                    if c != own {
                        sum[c] += u32::from(raw[yy * w + xx]);
                        n[c] += 1;
                    }
                }
            }
            let px = &mut out[(y * w + x) * 3..(y * w + x) * 3 + 3];
            for c in 0..3 {
                px[c] = if c == own {
                    raw[y * w + x]
                } else {
                    (sum[c] + n[c] / 2).checked_div(n[c]).map_or(0, |v| v as u8)
                };
            }
        }
    }
    out
}

/// The pixels of a `sensor_msgs/CompressedImage` (PNG or JPEG) as RGB.
///
/// # Errors
/// A format other than PNG or JPEG, undecodable data, a mono image.
pub fn compressed_to_rgb(img: &CompressedImage<'_>) -> Result<RgbImage, String> {
    let format = image::guess_format(img.data)
        .map_err(|_| format!("format \"{}\": the data is neither PNG nor JPEG (no known signature)", img.format))?;
    if !matches!(format, ImageFormat::Png | ImageFormat::Jpeg) {
        return Err(format!("unknown encoding: compressed data is {format:?}, evorec reads PNG and JPEG"));
    }
    let decoded = image::load_from_memory_with_format(img.data, format)
        .map_err(|e| format!("cannot decode the {format:?} data: {e}"))?;
    match decoded {
        DynamicImage::ImageRgb8(rgb) => Ok(rgb),
        DynamicImage::ImageRgba8(_) => Ok(decoded.to_rgb8()),
        DynamicImage::ImageLuma8(_) | DynamicImage::ImageLumaA8(_) | DynamicImage::ImageLuma16(_) => {
            Err(format!("the {format:?} image is mono: a mono image cannot give hue"))
        }
        other => Err(format!("the {format:?} image has pixel format {:?} (8-bit RGB or RGBA only)", other.color())),
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::rig::bag::msgs::Header;

    fn mosaic(rgb: &RgbImage, tile: [usize; 4]) -> Vec<u8> {
        let mut raw = Vec::new();
        for (x, y, p) in rgb.enumerate_pixels() {
            let _ = x;
            raw.push(p.0[tile[((y & 1) * 2 + (x & 1)) as usize]]);
        }
        raw
    }

    #[test]
    fn debayering_a_uniform_mosaic_gives_its_colour_everywhere() {
        for enc in ["bayer_rggb8", "bayer_bggr8", "bayer_gbrg8", "bayer_grbg8"] {
            let tile = bayer_tile(enc).unwrap();
            let rgb = RgbImage::from_pixel(7, 5, image::Rgb([200, 90, 30]));
            let raw = mosaic(&rgb, tile);
            let img = Image {
                header: Header { stamp_ns: 0, frame_id: String::new() },
                height: 5,
                width: 7,
                encoding: enc.into(),
                is_bigendian: 0,
                step: 7,
                data: &raw,
            };
            assert_eq!(to_rgb(&img).unwrap(), rgb, "{enc}");
        }
    }

    #[test]
    fn debayering_is_bilinear_on_a_ramp() {
        // Each channel a linear ramp in x: bilinear interpolation reproduces it inside.
        let rgb =
            RgbImage::from_fn(10, 6, |x, _| image::Rgb([(10 * x) as u8, (20 + 10 * x) as u8, (40 + 10 * x) as u8]));
        let tile = bayer_tile("bayer_grbg8").unwrap();
        let out = debayer(&mosaic(&rgb, tile), 10, 6, tile);
        for y in 0..6 {
            for x in 1..9 {
                let i = (y * 10 + x) * 3;
                assert_eq!(&out[i..i + 3], &rgb.get_pixel(x as u32, y as u32).0, "({x}, {y})");
            }
        }
    }

    #[test]
    fn channel_orders_and_padding() {
        let data = [1u8, 2, 3, 9, 4, 5, 6, 9, 0, 0];
        let mut img = Image {
            header: Header { stamp_ns: 0, frame_id: String::new() },
            height: 1,
            width: 2,
            encoding: "bgra8".into(),
            is_bigendian: 0,
            step: 10,
            data: &data,
        };
        assert_eq!(to_rgb(&img).unwrap().into_raw(), vec![3, 2, 1, 6, 5, 4]);
        img.encoding = "mono8".into();
        assert!(to_rgb(&img).unwrap_err().contains("cannot give hue"));
        img.encoding = "yuv422".into();
        assert!(to_rgb(&img).unwrap_err().contains("unknown encoding \"yuv422\""));
        img.encoding = "rgb8".into();
        img.width = 4;
        assert!(to_rgb(&img).unwrap_err().contains("needs"));
    }

    #[test]
    fn compressed_png_and_jpeg_decode_and_mono_is_refused() {
        let rgb = RgbImage::from_pixel(8, 8, image::Rgb([10, 200, 30]));
        for fmt in [ImageFormat::Png, ImageFormat::Jpeg] {
            let mut bytes = std::io::Cursor::new(Vec::new());
            rgb.write_to(&mut bytes, fmt).unwrap();
            let c = CompressedImage {
                header: Header { stamp_ns: 0, frame_id: String::new() },
                format: "x".into(),
                data: bytes.get_ref(),
            };
            let back = compressed_to_rgb(&c).unwrap();
            assert_eq!(back.dimensions(), (8, 8));
            assert!(back.pixels().all(|p| p.0.iter().zip([10, 200, 30]).all(|(a, b)| a.abs_diff(b) <= 4)));
        }
        let mut bytes = std::io::Cursor::new(Vec::new());
        image::GrayImage::from_pixel(4, 4, image::Luma([7])).write_to(&mut bytes, ImageFormat::Png).unwrap();
        let c = CompressedImage {
            header: Header { stamp_ns: 0, frame_id: String::new() },
            format: "png".into(),
            data: bytes.get_ref(),
        };
        assert!(compressed_to_rgb(&c).unwrap_err().contains("cannot give hue"));
    }
}
