//! The hue of every 8-bit RGB colour in one table (16 MiB, built once per process): the
//! sequence tracker reads a recorded frame's sample points through it ([`Rgb888Table`]). Each
//! entry is the core's [`rgb_to_hue`] of its colour, so the tracker sees the same hue bytes as
//! through [`Rgb888`], with one load per sample point instead of the
//! arithmetic (`cargo bench -p evorec-sim --bench track_frame`, `docs/timing.md`).

use std::sync::LazyLock;

use evorec_core::hue::rgb_to_hue;
use evorec_core::image::{PixelFormat, Rgb888};

/// Colours in the table: 2⁸ per channel.
const COLOURS: usize = 1 << 24;

/// `rgb_to_hue(r, g, b)` at index `r << 16 | g << 8 | b`.
static TABLE: LazyLock<Box<[u8; COLOURS]>> = LazyLock::new(|| {
    let table: Vec<u8> = (0..COLOURS).map(|c| rgb_to_hue((c >> 16) as u8, (c >> 8) as u8, c as u8)).collect();
    match table.into_boxed_slice().try_into() {
        Ok(t) => t,
        Err(_) => unreachable!("the table has one entry per colour"),
    }
});

/// Builds the table now, if no one has yet (it is otherwise built at the first pixel read:
/// about 60 ms in a release build, which the first frame would pay).
pub fn build() {
    LazyLock::force(&TABLE);
}

/// 8-bit RGB pixels, 3 bytes `r, g, b`, as [`Rgb888`], whose hue is read
/// from the table of every colour.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Rgb888Table;

/// Everything but the hue is [`Rgb888`]'s.
impl PixelFormat for Rgb888Table {
    const BYTES_PER_PIXEL: usize = Rgb888::BYTES_PER_PIXEL;
    const NAME: &'static str = Rgb888::NAME;
    type Pixel = <Rgb888 as PixelFormat>::Pixel;
    const NONE: Self::Pixel = Rgb888::NONE;

    #[inline(always)]
    fn split(bytes: &[u8]) -> &[Self::Pixel] {
        Rgb888::split(bytes)
    }

    #[inline(always)]
    fn hue(px: Self::Pixel) -> u8 {
        let [r, g, b] = px.map(usize::from);
        TABLE[r << 16 | g << 8 | b]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_colour_reads_the_cores_hue() {
        for r in 0..=255u8 {
            for g in 0..=255u8 {
                for b in 0..=255u8 {
                    let px = [r, g, b];
                    assert_eq!(Rgb888Table::hue(px), Rgb888::hue(px), "colour {px:?}");
                }
            }
        }
        assert_eq!(Rgb888Table::hue(Rgb888Table::NONE), evorec_core::limits::NO_HUE);
    }
}
