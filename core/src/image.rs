//! Camera images in the sensor's own pixel format, and their hue (paper §4.2, Fig. 6).
//!
//! The fitness needs one thing per sample point: the hue of the pixel it hits. Where that hue
//! comes from is the [`PixelFormat`] of the image:
//!
//! - [`Hue`]: one hue byte per pixel, computed beforehand (a host converting whole frames with
//!   [`crate::hue::rgb_to_hue`], or a test rasterizer). A byte `h < HUE_UNITS` is a hue of
//!   `2·h` degrees; [`NO_HUE`] marks pixels without a usable hue.
//! - [`Rgb565`]: what OV7670/OV2640-class sensors deliver over a DCMI-style parallel port,
//!   2 bytes per pixel, little-endian `u16` laid out `rrrrrggggggbbbbb`. It is converted to a
//!   hue **only at the pixels the sample points hit**, with one load from [`RGB565_HUE`], a
//!   64 KiB table (in flash on a board) computed at compile time from the core's integer
//!   [`crate::hue::rgb_to_hue`] on the 565 values widened to 8 bits by bit replication
//!   (`r8 = r5<<3 | r5>>2`, `g8 = g6<<2 | g6>>4`, `b8 = b5<<3 | b5>>2`, so 0 ↦ 0 and the
//!   field's maximum ↦ 255). A whole frame is never converted.
//!
//! An [`Image`] is a validated `width × height` view over any `AsRef<[u8]>` (a camera DMA
//! buffer, a simulator's `Vec<u8>`), row-major, no padding, `BYTES_PER_PIXEL` bytes per pixel.
//! Its size is checked once in [`Image::new_checked`]; after that no accessor can panic.

use core::fmt::Debug;
use core::marker::PhantomData;

use crate::hue::rgb_to_hue;
use crate::limits::{MAX_IMAGE_SIDE, NO_HUE};

/// How the bytes of an image encode its pixels, and how a pixel becomes a hue byte.
pub trait PixelFormat: Copy + Debug + Default + PartialEq + Eq + Send + Sync + 'static {
    /// Bytes per pixel.
    const BYTES_PER_PIXEL: usize;
    /// A human-readable name ("hue", "RGB565").
    const NAME: &'static str;
    /// One pixel as stored.
    type Pixel: Copy;
    /// A pixel whose hue is [`NO_HUE`]: what a sample point outside the image reads (so the
    /// fitness kernel loads it without a branch when the point misses the image).
    const NONE: Self::Pixel;

    /// The whole pixels of a byte buffer (a trailing partial pixel is dropped).
    fn split(bytes: &[u8]) -> &[Self::Pixel];

    /// The hue byte of a pixel (`NO_HUE` when it has none).
    fn hue(px: Self::Pixel) -> u8;
}

/// One precomputed hue byte per pixel.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Hue;

impl PixelFormat for Hue {
    const BYTES_PER_PIXEL: usize = 1;
    const NAME: &'static str = "hue";
    type Pixel = u8;
    const NONE: u8 = NO_HUE;

    #[inline(always)]
    fn split(bytes: &[u8]) -> &[u8] {
        bytes
    }

    #[inline(always)]
    fn hue(px: u8) -> u8 {
        px
    }
}

/// Raw RGB565 sensor pixels: 2 bytes, little-endian `u16` `rrrrrggggggbbbbb`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Rgb565;

impl PixelFormat for Rgb565 {
    const BYTES_PER_PIXEL: usize = 2;
    const NAME: &'static str = "RGB565";
    type Pixel = [u8; 2];
    /// Black: below `MIN_VALUE`, so its [`RGB565_HUE`] entry is [`NO_HUE`].
    const NONE: [u8; 2] = {
        assert!(rgb_to_hue(0, 0, 0) == NO_HUE);
        [0, 0]
    };

    #[inline(always)]
    fn split(bytes: &[u8]) -> &[[u8; 2]] {
        bytes.as_chunks::<2>().0
    }

    #[inline(always)]
    fn hue(px: [u8; 2]) -> u8 {
        rgb565_to_hue(u16::from_le_bytes(px))
    }
}

/// 8-bit RGB pixels, 3 bytes `r, g, b` (what a host decodes from a PNG of a recorded sequence):
/// the hue of a sampled pixel is computed where it is read, by [`rgb_to_hue`], so a host tracker
/// keeps the full 8-bit colour of its recordings without converting whole frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Rgb888;

impl PixelFormat for Rgb888 {
    const BYTES_PER_PIXEL: usize = 3;
    const NAME: &'static str = "RGB888";
    type Pixel = [u8; 3];
    /// Black: below `MIN_VALUE`, so it has no hue.
    const NONE: [u8; 3] = {
        assert!(rgb_to_hue(0, 0, 0) == NO_HUE);
        [0, 0, 0]
    };

    #[inline(always)]
    fn split(bytes: &[u8]) -> &[[u8; 3]] {
        bytes.as_chunks::<3>().0
    }

    #[inline(always)]
    fn hue(px: [u8; 3]) -> u8 {
        rgb_to_hue(px[0], px[1], px[2])
    }
}

/// Packs 8-bit RGB into RGB565 by truncation (the top 5/6/5 bits), as a sensor's output stage
/// does.
///
/// # Examples
/// ```
/// use evorec_core::image::rgb888_to_rgb565;
/// assert_eq!(rgb888_to_rgb565(255, 0, 0), 0xF800);
/// assert_eq!(rgb888_to_rgb565(0, 255, 0), 0x07E0);
/// assert_eq!(rgb888_to_rgb565(0, 0, 255), 0x001F);
/// assert_eq!(rgb888_to_rgb565(0x12, 0x34, 0x56), (0x12 >> 3) << 11 | (0x34 >> 2) << 5 | 0x56 >> 3);
/// ```
pub const fn rgb888_to_rgb565(r: u8, g: u8, b: u8) -> u16 {
    ((r as u16 >> 3) << 11) | ((g as u16 >> 2) << 5) | (b as u16 >> 3)
}

/// Widens an RGB565 value to 8 bits per channel by bit replication.
///
/// # Examples
/// ```
/// use evorec_core::image::rgb565_to_rgb888;
/// assert_eq!(rgb565_to_rgb888(0xFFFF), (255, 255, 255));
/// assert_eq!(rgb565_to_rgb888(0x0000), (0, 0, 0));
/// assert_eq!(rgb565_to_rgb888(0b10000_100000_10000), (0x84, 0x82, 0x84));
/// ```
pub const fn rgb565_to_rgb888(px: u16) -> (u8, u8, u8) {
    let r5 = ((px >> 11) & 0x1F) as u8;
    let g6 = ((px >> 5) & 0x3F) as u8;
    let b5 = (px & 0x1F) as u8;
    ((r5 << 3) | (r5 >> 2), (g6 << 2) | (g6 >> 4), (b5 << 3) | (b5 >> 2))
}

/// The hue byte of every RGB565 value: `RGB565_HUE[px] = rgb_to_hue(rgb565_to_rgb888(px))`,
/// computed at compile time (64 KiB of read-only data; in flash on a board).
pub static RGB565_HUE: [u8; 1 << 16] = rgb565_hue_table();

const fn rgb565_hue_table() -> [u8; 1 << 16] {
    let mut t = [NO_HUE; 1 << 16];
    let mut i = 0usize;
    while i < t.len() {
        let (r, g, b) = rgb565_to_rgb888(i as u16);
        t[i] = rgb_to_hue(r, g, b);
        i += 1;
    }
    t
}

/// The hue byte of an RGB565 pixel (one table load; see [`RGB565_HUE`]).
///
/// # Examples
/// ```
/// use evorec_core::{image::{rgb565_to_hue, rgb888_to_rgb565}, limits::NO_HUE};
/// assert_eq!(rgb565_to_hue(rgb888_to_rgb565(200, 0, 0)), 0);
/// assert_eq!(rgb565_to_hue(rgb888_to_rgb565(0, 200, 0)), 60);
/// assert_eq!(rgb565_to_hue(rgb888_to_rgb565(0, 0, 200)), 120);
/// assert_eq!(rgb565_to_hue(0x0000), NO_HUE);
/// assert_eq!(rgb565_to_hue(0xFFFF), NO_HUE);
/// ```
#[inline(always)]
pub fn rgb565_to_hue(px: u16) -> u8 {
    // A u16 index into a 2¹⁶-entry table cannot be out of bounds.
    RGB565_HUE[usize::from(px)]
}

/// Mid grey, `(132, 130, 132)` widened: the RGB565 value [`hue_to_rgb565`] gives pixels
/// without a hue (its table entry is [`NO_HUE`]).
pub const RGB565_GREY: u16 = 0x8410;

/// For every hue byte the most saturated RGB565 value whose [`RGB565_HUE`] entry is that hue
/// (largest `max − min` after widening, then the brightest), computed at compile time from
/// the same table; [`RGB565_GREY`] for bytes `HUE_UNITS..=255`. Every hue unit has one (the
/// table's 65 536 entries cover all 180 units), so `RGB565_HUE[HUE_RGB565[h]] == h`.
pub static HUE_RGB565: [u16; 256] = hue_rgb565_table();

const fn hue_rgb565_table() -> [u16; 256] {
    let mut best = [RGB565_GREY; 256];
    // Score (max − min, max) of the value kept for each hue; 0 = none yet.
    let mut score = [0u32; 256];
    let mut i = 0usize;
    while i < 1 << 16 {
        let (r, g, b) = rgb565_to_rgb888(i as u16);
        let h = rgb_to_hue(r, g, b) as usize;
        if h < crate::limits::HUE_UNITS as usize {
            let (max, min) = (max3(r, g, b) as u32, min3(r, g, b) as u32);
            let s = ((max - min) << 8) | max;
            if s > score[h] {
                score[h] = s;
                best[h] = i as u16;
            }
        }
        i += 1;
    }
    best
}

const fn max3(a: u8, b: u8, c: u8) -> u8 {
    let m = if a > b { a } else { b };
    if m > c { m } else { c }
}

const fn min3(a: u8, b: u8, c: u8) -> u8 {
    let m = if a < b { a } else { b };
    if m < c { m } else { c }
}

/// The RGB565 value a sensor would deliver for a pixel of hue byte `h` (see [`HUE_RGB565`]).
///
/// # Examples
/// ```
/// use evorec_core::image::{hue_to_rgb565, rgb565_to_hue, RGB565_GREY};
/// use evorec_core::limits::NO_HUE;
/// for h in 0..180u8 {
///     assert_eq!(rgb565_to_hue(hue_to_rgb565(h)), h);
/// }
/// assert_eq!(hue_to_rgb565(0), 0xF800); // pure red
/// assert_eq!(hue_to_rgb565(NO_HUE), RGB565_GREY);
/// assert_eq!(rgb565_to_hue(RGB565_GREY), NO_HUE);
/// ```
#[inline]
pub fn hue_to_rgb565(h: u8) -> u16 {
    HUE_RGB565[usize::from(h)]
}

/// Turns a hue image held in the first `pixels` bytes of `buf` into the RGB565 image of
/// those hues ([`hue_to_rgb565`], little-endian, `2·pixels` bytes), in place: how synthetic
/// hue frames (the core's [`crate::synth`] rasterizer) become sensor frames on a board
/// without a second buffer.
///
/// # Errors
/// [`ImageError::TooShort`] if `buf` holds fewer than `2·pixels` bytes (`buf` unchanged).
///
/// # Examples
/// ```
/// use evorec_core::image::{expand_hue_to_rgb565, Rgb565Image};
/// let mut buf = [0u8, 60, 255, 0, 0, 0];
/// expand_hue_to_rgb565(&mut buf, 3).unwrap();
/// let img = Rgb565Image::new_checked(&buf[..], 3, 1).unwrap();
/// assert_eq!([img.hue(0, 0), img.hue(1, 0), img.hue(2, 0)], [Some(0), Some(60), Some(255)]);
/// assert!(expand_hue_to_rgb565(&mut buf[..5], 3).is_err());
/// ```
pub fn expand_hue_to_rgb565(buf: &mut [u8], pixels: usize) -> Result<(), ImageError> {
    let needed = pixels.saturating_mul(2);
    let Some(buf) = buf.get_mut(..needed) else {
        let n = |v: usize| u32::try_from(v).unwrap_or(u32::MAX);
        return Err(ImageError::TooShort { needed: n(needed), got: n(buf.len()) });
    };
    // Back to front: pixel i moves to bytes 2i, 2i+1 ≥ i, so no hue byte is overwritten
    // before it is read.
    for i in (0..pixels).rev() {
        let h = buf.get(i).copied().unwrap_or(crate::limits::NO_HUE);
        if let Some(px) = buf.get_mut(2 * i..2 * i + 2) {
            px.copy_from_slice(&hue_to_rgb565(h).to_le_bytes());
        }
    }
    Ok(())
}

/// Why a buffer is not an image of the given size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ImageError {
    /// Width or height is 0 or above [`MAX_IMAGE_SIDE`].
    BadSize {
        /// Requested width.
        width: u16,
        /// Requested height.
        height: u16,
    },
    /// The buffer is shorter than `width · height · BYTES_PER_PIXEL`.
    TooShort {
        /// Bytes needed.
        needed: u32,
        /// Bytes given.
        got: u32,
    },
}

impl core::fmt::Display for ImageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::BadSize { width, height } => write!(f, "bad image size {width}x{height}"),
            Self::TooShort { needed, got } => write!(f, "image buffer has {got} bytes, needs {needed}"),
        }
    }
}

impl core::error::Error for ImageError {}

/// A validated `width × height` image in pixel format `F` over a byte buffer.
#[derive(Debug, Clone, Copy)]
pub struct Image<B: AsRef<[u8]>, F: PixelFormat = Hue> {
    buf: B,
    width: u16,
    height: u16,
    format: PhantomData<F>,
}

/// An image of precomputed hue bytes.
pub type HueImage<B> = Image<B, Hue>;

/// An image of raw RGB565 sensor pixels.
pub type Rgb565Image<B> = Image<B, Rgb565>;

/// An image of 8-bit RGB pixels (3 bytes per pixel).
pub type Rgb888Image<B> = Image<B, Rgb888>;

impl<B: AsRef<[u8]>, F: PixelFormat> Image<B, F> {
    /// Wraps `buf` as a `width × height` image (extra trailing bytes are ignored).
    ///
    /// # Errors
    /// [`ImageError::BadSize`] or [`ImageError::TooShort`] (fewer than
    /// `width · height · F::BYTES_PER_PIXEL` bytes).
    ///
    /// # Examples
    /// ```
    /// use evorec_core::image::{HueImage, ImageError, Rgb565Image};
    /// let img = HueImage::new_checked([0u8; 12], 4, 3).unwrap();
    /// assert_eq!(img.hue(3, 2), Some(0));
    /// assert_eq!(img.hue(4, 0), None);
    /// assert!(matches!(HueImage::new_checked([0u8; 11], 4, 3), Err(ImageError::TooShort { .. })));
    /// assert!(matches!(Rgb565Image::new_checked([0u8; 12], 4, 3), Err(ImageError::TooShort { needed: 24, got: 12 })));
    /// ```
    pub fn new_checked(buf: B, width: u16, height: u16) -> Result<Self, ImageError> {
        if width == 0 || height == 0 || width > MAX_IMAGE_SIDE || height > MAX_IMAGE_SIDE {
            return Err(ImageError::BadSize { width, height });
        }
        // ≤ 2048² · BYTES_PER_PIXEL: fits u32 for any format up to 1023 bytes per pixel.
        let bpp = u32::try_from(F::BYTES_PER_PIXEL).unwrap_or(u32::MAX);
        let needed = (u32::from(width) * u32::from(height)).saturating_mul(bpp);
        let got = u32::try_from(buf.as_ref().len()).unwrap_or(u32::MAX);
        if got < needed {
            return Err(ImageError::TooShort { needed, got });
        }
        Ok(Self { buf, width, height, format: PhantomData })
    }

    /// Width in pixels.
    pub fn width(&self) -> u16 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u16 {
        self.height
    }

    /// The `width · height · BYTES_PER_PIXEL` image bytes, row-major.
    pub fn bytes(&self) -> &[u8] {
        let n = usize::from(self.width) * usize::from(self.height) * F::BYTES_PER_PIXEL;
        let b = self.buf.as_ref();
        b.get(..n).unwrap_or(b)
    }

    /// The `width · height` pixels, row-major.
    pub fn pixels(&self) -> &[F::Pixel] {
        F::split(self.bytes())
    }

    /// The pixel at column `x`, row `y`, or `None` outside the image.
    pub fn pixel(&self, x: u16, y: u16) -> Option<F::Pixel> {
        if x >= self.width || y >= self.height {
            return None;
        }
        self.pixels().get(usize::from(y) * usize::from(self.width) + usize::from(x)).copied()
    }

    /// The hue byte of the pixel at column `x`, row `y`, or `None` outside the image.
    pub fn hue(&self, x: u16, y: u16) -> Option<u8> {
        self.pixel(x, y).map(F::hue)
    }

    /// Gives the buffer back.
    pub fn into_inner(self) -> B {
        self.buf
    }
}

impl<B: AsRef<[u8]>> Image<B, Hue> {
    /// The hue byte at column `x`, row `y`, or `None` outside the image (as [`Image::hue`]).
    pub fn get(&self, x: u16, y: u16) -> Option<u8> {
        self.hue(x, y)
    }
}

impl<B: AsRef<[u8]>> Image<B, Rgb565> {
    /// The RGB565 value at column `x`, row `y`, or `None` outside the image.
    pub fn get(&self, x: u16, y: u16) -> Option<u16> {
        self.pixel(x, y).map(u16::from_le_bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::limits::HUE_UNITS;

    #[test]
    fn table_is_rgb_to_hue_of_the_widened_value_everywhere() {
        for px in 0..=u16::MAX {
            let r5 = u32::from(px >> 11);
            let g6 = u32::from((px >> 5) & 0x3F);
            let b5 = u32::from(px & 0x1F);
            // Bit replication, written out; it is within 1 of the linear rescale to 0..=255.
            let (r, g, b) = ((r5 << 3) | (r5 >> 2), (g6 << 2) | (g6 >> 4), (b5 << 3) | (b5 >> 2));
            for (v, bits, max) in [(r, r5, 31), (g, g6, 63), (b, b5, 31)] {
                assert!((v * max).abs_diff(bits * 255) <= max, "{px:#06x}");
            }
            assert_eq!(rgb565_to_rgb888(px), (r as u8, g as u8, b as u8), "{px:#06x}");
            assert_eq!(rgb565_to_hue(px), rgb_to_hue(r as u8, g as u8, b as u8), "{px:#06x}");
            assert!(rgb565_to_hue(px) < HUE_UNITS || rgb565_to_hue(px) == NO_HUE);
        }
    }

    #[test]
    fn rgb888_pixels_give_the_hue_of_their_colour_and_widened_565_the_table_hue() {
        // A 3 x 1 image: red, a widened RGB565 green-blue, grey.
        let cyan = rgb888_to_rgb565(0, 180, 176); // r5 = 0, g6 = 45, b5 = 22
        let (r, g, b) = rgb565_to_rgb888(cyan);
        let bytes = [200, 0, 0, r, g, b, 90, 90, 90];
        let img = Rgb888Image::new_checked(&bytes[..], 3, 1).expect("3 x 1");
        assert_eq!(img.hue(0, 0), Some(0));
        assert_eq!(img.hue(1, 0), Some(rgb565_to_hue(cyan)));
        assert_eq!(img.hue(2, 0), Some(NO_HUE));
        assert_eq!(img.hue(3, 0), None);
        assert!(Rgb888Image::new_checked(&bytes[..8], 3, 1).is_err(), "one byte short");
    }

    #[test]
    fn round_trip_through_565_keeps_the_top_bits() {
        for v in 0..=255u8 {
            let px = rgb888_to_rgb565(v, v, v);
            let (r, g, b) = rgb565_to_rgb888(px);
            assert_eq!((r >> 3, g >> 2, b >> 3), (v >> 3, v >> 2, v >> 3));
            assert_eq!(rgb888_to_rgb565(r, g, b), px);
        }
    }

    #[test]
    fn rgb565_image_is_little_endian_and_checked() {
        let bytes = [0x00u8, 0xF8, 0xE0, 0x07, 0x1F, 0x00, 0xFF, 0xFF];
        let img = Rgb565Image::new_checked(&bytes[..], 2, 2).unwrap();
        assert_eq!(img.get(0, 0), Some(0xF800));
        assert_eq!(img.hue(0, 0), Some(0));
        assert_eq!(img.hue(1, 0), Some(60));
        assert_eq!(img.hue(0, 1), Some(120));
        assert_eq!(img.hue(1, 1), Some(NO_HUE));
        assert_eq!(img.hue(2, 0), None);
        assert_eq!(img.pixels().len(), 4);
        assert_eq!(
            Rgb565Image::new_checked(&bytes[..7], 2, 2).unwrap_err(),
            ImageError::TooShort { needed: 8, got: 7 }
        );
        assert_eq!(
            Rgb565Image::new_checked(&bytes[..], 2, 0).unwrap_err(),
            ImageError::BadSize { width: 2, height: 0 }
        );
    }

    #[test]
    fn every_hue_has_a_saturated_rgb565_value() {
        for h in 0..=255u8 {
            let px = hue_to_rgb565(h);
            if h < HUE_UNITS {
                assert_eq!(rgb565_to_hue(px), h, "{h}");
                let (r, g, b) = rgb565_to_rgb888(px);
                assert!(r.max(g).max(b) - r.min(g).min(b) >= 250, "{h}: {px:#06x}");
            } else {
                assert_eq!(px, RGB565_GREY);
            }
        }
        assert_eq!(rgb565_to_hue(RGB565_GREY), NO_HUE);
    }

    #[test]
    fn expansion_in_place_keeps_every_hue() {
        let hues: [u8; 7] = [0, 1, 59, 60, 179, 200, NO_HUE];
        let mut buf = [0u8; 14];
        buf[..7].copy_from_slice(&hues);
        expand_hue_to_rgb565(&mut buf, 7).unwrap();
        let img = Rgb565Image::new_checked(&buf[..], 7, 1).unwrap();
        for (x, &h) in hues.iter().enumerate() {
            let want = if h < HUE_UNITS { h } else { NO_HUE };
            assert_eq!(img.hue(x as u16, 0), Some(want));
        }
        let mut short = [1u8; 13];
        assert_eq!(expand_hue_to_rgb565(&mut short, 7), Err(ImageError::TooShort { needed: 14, got: 13 }));
        assert_eq!(short, [1u8; 13]);
    }

    #[test]
    fn hue_image_view_is_checked() {
        assert_eq!(
            HueImage::new_checked(&[0u8; 4][..], 0, 4).unwrap_err(),
            ImageError::BadSize { width: 0, height: 4 }
        );
        let img = HueImage::new_checked(&[1u8, 2, 3, 4, 5, 6, 7][..], 3, 2).unwrap();
        assert_eq!(img.pixels().len(), 6);
        assert_eq!(img.get(2, 1), Some(6));
        assert_eq!(img.get(0, 2), None);
    }
}
