//! The pixels the fitness kernel reads: a borrowed image reduced to what its inner loop needs,
//! and the two formulations of the walk along a fixed-point row (the board's and the host's).

use super::{FIX_BITS, FixedRow};
use crate::image::{Image, PixelFormat};
use crate::limits::NO_HUE;

/// A borrowed image reduced to what the inner loop needs.
#[derive(Clone, Copy)]
pub(super) struct View<'a, F: PixelFormat> {
    pub(super) pixels: &'a [F::Pixel],
    width: u32,
    height: u32,
}

impl<'a, F: PixelFormat> View<'a, F> {
    pub(super) fn of<B: AsRef<[u8]>>(img: &'a Image<B, F>) -> Self {
        // `pixels.len() == width · height` (at most 2²², see [`MAX_IMAGE_SIDE`]).
        Self { pixels: img.pixels(), width: u32::from(img.width()), height: u32::from(img.height()) }
    }

    /// The hue byte at the point whose pixel coordinates plus one are `(u1, v1)`, or `NO_HUE`
    /// outside the image (the lens kernel's per-point read).
    ///
    /// Pixel `(i, j)` covers `[i, i+1) × [j, j+1)`. The projector adds 1 to both coordinates,
    /// so for every point inside the image `u1, v1 ≥ 1` and the truncating conversion
    /// `as i32` (saturating, NaN → 0: the same definition on every target, one `VCVT` on the
    /// M4) gives `i + 1` and `j + 1` exactly, while every point left of or above the image
    /// gives 0 or less. Minus 1, as unsigned numbers, they are `i` and `j` inside the image and
    /// `≥ width` / `≥ height` everywhere else: one compare per axis.
    #[inline(always)]
    pub(super) fn hue(&self, u1: f32, v1: f32) -> u8 {
        let col = (u1 as i32 as u32).wrapping_sub(1);
        let row = (v1 as i32 as u32).wrapping_sub(1);
        if col >= self.width || row >= self.height {
            return NO_HUE;
        }
        match self.pixels.get((row * self.width + col) as usize) {
            Some(&px) => F::hue(px),
            None => NO_HUE,
        }
    }

    /// The index of the pixel under the fixed-point point `(u, v)`, `row · width + col`
    /// (wrapping), or `u32::MAX` when the column is outside the image: `u >> 16` is `⌊u⌋`
    /// (arithmetic shift), the column, and as an unsigned number it is `≥ width` left of the
    /// image too. The row needs no compare of its own: for any `i32` `v`, `|v >> 16| ≤ 2¹⁵`,
    /// so with a column inside the image the index is `< len` exactly when `0 ≤ row < height`
    /// (a negative row wraps to at least `2³² − 2²⁶ > len`).
    #[inline(always)]
    pub(super) fn index(&self, u: i32, v: i32) -> u32 {
        let col = (u >> FIX_BITS) as u32;
        let index = ((v >> FIX_BITS) as u32).wrapping_mul(self.width).wrapping_add(col);
        if col < self.width { index } else { u32::MAX }
    }

    /// `Σ plane[hue]` over the `G` points of a fixed-point row (the pinhole kernel's inner
    /// loop; `pixels` must not be empty, see [`super::walk_edge`]; `plane` maps [`NO_HUE`] to 0, as
    /// every plane of a [`crate::hue::HueLut`] does).
    ///
    /// Two formulations with the same sums: the board's ([`View::walk_selected`], branch-free,
    /// constant work on the Cortex-M4) and the host's ([`View::walk_checked`], one checked
    /// load per point, the cheaper one for an out-of-order CPU with branch prediction).
    #[inline(always)]
    pub(super) fn walk<const G: usize>(&self, row: &FixedRow, plane: &[u8; 256]) -> u32 {
        #[cfg(target_arch = "arm")]
        let hits = self.walk_selected::<G>(row, plane);
        #[cfg(not(target_arch = "arm"))]
        let hits = self.walk_checked::<G>(row, plane);
        hits
    }

    /// The host's walk: the index ([`View::index`]) of a point outside is past the end, and
    /// the slice's checked read gives [`PixelFormat::NONE`] (no hue, 0 in every plane) for every point
    /// outside the image. The same index and the same pixel as [`View::walk_selected`] for a
    /// point inside, and 0 for a point outside, so the same sum; here the read is a bounds
    /// check and a load (a branch that only a change between inside and outside mispredicts).
    #[cfg_attr(target_arch = "arm", allow(dead_code))]
    #[inline(always)]
    pub(super) fn walk_checked<const G: usize>(&self, row: &FixedRow, plane: &[u8; 256]) -> u32 {
        let (mut u, mut v) = (row.u, row.v);
        let mut hits = 0u32;
        for _ in 0..G {
            let index = self.index(u, v);
            let px = self.pixels.get(index as usize).copied().unwrap_or(F::NONE);
            hits += u32::from(plane[usize::from(F::hue(px))]);
            u = u.wrapping_add(row.du);
            v = v.wrapping_add(row.dv);
        }
        hits
    }

    /// The board's walk (see [`View::walk`]). Per point: the index ([`View::index`]) and
    /// its compare with the length, which is the image test. A point outside reads pixel 0
    /// instead and its score is not added:
    /// the same instructions inside and outside the image and no branch (the index and the
    /// addition are selected, the loads always happen), so every point costs the same.
    #[cfg_attr(not(any(target_arch = "arm", test)), allow(dead_code))]
    #[inline(always)]
    pub(super) fn walk_selected<const G: usize>(&self, row: &FixedRow, plane: &[u8; 256]) -> u32 {
        let (mut u, mut v) = (row.u, row.v);
        let mut hits = 0u32;
        for _ in 0..G {
            let index = self.index(u, v);
            let inside = (index as usize) < self.pixels.len();
            // In bounds either way (pixel 0 exists), so the `None` arm is never taken.
            let px = self.pixels.get(if inside { index as usize } else { 0 }).copied().unwrap_or(F::NONE);
            let score = u32::from(plane[usize::from(F::hue(px))]);
            hits += if inside { score } else { 0 };
            u = u.wrapping_add(row.du);
            v = v.wrapping_add(row.dv);
        }
        hits
    }
}
