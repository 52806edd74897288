//! Hue images: the primitive pixel layer under the fitness (paper §4.2, Fig. 6).
//!
//! A hue image is one byte per pixel, row-major, no padding. A byte `h < HUE_UNITS` is a hue
//! of `2·h` degrees (red 0, green 60 ≙ 120°, blue 120 ≙ 240°); [`NO_HUE`] marks pixels too
//! dark or too grey to have a hue. Bytes `HUE_UNITS..=254` are tolerated and never match.
//!
//! Images themselves (hue bytes or raw RGB565 sensor pixels, [`HueImage`](crate::image::HueImage))
//! live in [`crate::image`], which converts pixels with [`rgb_to_hue`].

use crate::limits::{HUE_UNITS, MIN_SATURATION, MIN_VALUE, NO_HUE};

/// Converts an 8-bit RGB pixel to a hue byte, with integer arithmetic only (cheap on an MCU).
///
/// Pixels with `max(r,g,b) < MIN_VALUE` or saturation `(max−min)/max < MIN_SATURATION/255`
/// get [`NO_HUE`]. Otherwise the HSV hue, rounded to the nearest 2° unit, in `0..HUE_UNITS`.
///
/// The host's tracker reads every sample of an 8-bit RGB frame through this function, so it
/// has no division: the one by `2·(max − min)` is a multiplication by a reciprocal from a
/// table (`HALF_RECIPROCALS`), exact for every pixel.
///
/// # Examples
/// ```
/// use evorec_core::{hue::rgb_to_hue, limits::NO_HUE};
/// assert_eq!(rgb_to_hue(200, 0, 0), 0);     // red, 0°
/// assert_eq!(rgb_to_hue(0, 200, 0), 60);    // green, 120°
/// assert_eq!(rgb_to_hue(0, 0, 200), 120);   // blue, 240°
/// assert_eq!(rgb_to_hue(200, 200, 0), 30);  // yellow, 60°
/// assert_eq!(rgb_to_hue(128, 128, 128), NO_HUE);
/// assert_eq!(rgb_to_hue(10, 0, 0), NO_HUE); // too dark
/// ```
#[inline]
pub const fn rgb_to_hue(r: u8, g: u8, b: u8) -> u8 {
    // `const`: the RGB565 table of `crate::image` is built from this at compile time.
    let max = if r > g { r } else { g };
    let max = if max > b { max } else { b };
    let min = if r < g { r } else { g };
    let min = if min < b { min } else { b };
    let delta = max - min;
    // One test for both (with `MIN_SATURATION > 0` a grey pixel, `delta = 0`, fails the
    // second): `|`, not `||`, so that it is one branch.
    if (max < MIN_VALUE) | ((delta as u32) * 255 < MIN_SATURATION as u32 * max as u32) {
        return NO_HUE;
    }
    let (r, g, b, d) = (r as i32, g as i32, b as i32, delta as i32);
    // Sector offset (in 2° units) and signed position inside it, in [-delta, delta].
    let (offset, diff) = if r >= g && r >= b {
        (0, g - b)
    } else if g >= b {
        (60, b - r)
    } else {
        (120, r - g)
    };
    // 30·diff/delta units = 60°·diff/delta, rounded half up: ⌊(60·diff + delta) / (2·delta)⌋,
    // with 60 units added to the quotient to keep the numerator positive (below 181·255).
    let numerator = (60 * diff + 121 * d) as u64;
    let units = ((numerator * HALF_RECIPROCALS[delta as usize] as u64) >> 32) as i32 - 60;
    // In −30..=150, wrapped into 0..HUE_UNITS.
    let h = offset + units;
    (if h < 0 { h + HUE_UNITS as i32 } else { h }) as u8
}

const _: () = assert!(MIN_SATURATION > 0, "rgb_to_hue relies on the saturation test to reject grey");
const _: () = assert!(HUE_UNITS.is_multiple_of(4), "HueLut::fill_bands_except clears four entries a word");

/// `⌈2³² / (2·d)⌉` for `d = 1..=255` (0 for `d = 0`, never used): for every numerator
/// `n < 2¹⁶`, `(n · HALF_RECIPROCALS[d]) >> 32 = ⌊n / (2·d)⌋`. The reciprocal is too large by
/// less than `2d / 2³²`, which adds less than `n · 2d / 2³² < 2⁻⁶` to the exact quotient, and
/// the exact quotient is at least `1 / (2d) ≥ 2⁻⁹` below the next integer. The test
/// `rgb_to_hue_matches_the_division_everywhere` checks every pixel.
const HALF_RECIPROCALS: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut d = 1;
    while d < 256 {
        table[d] = (1u64 << 32).div_ceil(2 * d as u64) as u32;
        d += 1;
    }
    table
};

/// Converts hue degrees to the nearest hue unit (any real angle, wrapped into `0..HUE_UNITS`).
pub fn degrees_to_units(deg: f32) -> u8 {
    let units = f32::from(HUE_UNITS);
    let mut u = deg / 2.0;
    // Bounded wrap: a finite f32 angle beyond ±1e6° is nonsense input; clamp it first.
    u = crate::math::clamp(u, -1.0e6, 1.0e6);
    let r = u - units * crate::math::floor(u / units);
    let n = crate::math::round(r) as i32;
    u8::try_from(n.rem_euclid(i32::from(HUE_UNITS))).unwrap_or(0)
}

/// Circular distance between two hue units (0..=90).
pub fn hue_distance(a: u8, b: u8) -> u8 {
    let d = a.abs_diff(b);
    d.min(HUE_UNITS.saturating_sub(d))
}

/// A set of hue units (`0..HUE_UNITS`; other bytes are never members).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct HueSet([u32; HUE_WORDS]);

/// Words of a [`HueSet`].
const HUE_WORDS: usize = (HUE_UNITS as usize).div_ceil(32);

impl HueSet {
    /// No hue.
    pub const EMPTY: Self = Self([0; HUE_WORDS]);

    /// Whether hue byte `h` is in the set.
    pub fn contains(&self, h: u8) -> bool {
        h < HUE_UNITS && self.0.get(usize::from(h / 32)).is_some_and(|w| (w >> (h % 32)) & 1 != 0)
    }

    /// Adds hue byte `h` (bytes `≥ HUE_UNITS` are ignored).
    pub fn insert(&mut self, h: u8) {
        if let Some(w) = self.0.get_mut(usize::from(h / 32)).filter(|_| h < HUE_UNITS) {
            *w |= 1 << (h % 32);
        }
    }

    /// Whether the set is empty.
    pub fn is_empty(&self) -> bool {
        self.0.iter().all(|&w| w == 0)
    }
}

/// Number of face sets with a plane in [`HueLut`]: of each of the block's three pairs of
/// opposite faces `(k, k + 3)` none, the first or the second face (`3³`), which covers every
/// set of faces a camera can see (never both faces of a pair).
const FACE_SETS: usize = 27;

/// The face set of [`HueLut::any`] for a face bitmask: `Σ_a 3^a · s_a` with `s_a` 1 when face
/// `a` is in the mask, else 2 when face `a + 3` is, else 0 (bits 6 and 7 are ignored).
const fn face_set(faces: u8) -> usize {
    let mut set = 0usize;
    let mut a = 0u32;
    let mut weight = 1usize;
    while a < 3 {
        let s = if faces & (1 << a) != 0 {
            1
        } else if faces & (1 << (a + 3)) != 0 {
            2
        } else {
            0
        };
        set += weight * s;
        weight *= 3;
        a += 1;
    }
    set
}

/// [`set_faces`] of every face set.
const SET_FACES: [u8; FACE_SETS] = {
    let mut t = [0u8; FACE_SETS];
    let mut s = 0usize;
    while s < FACE_SETS {
        t[s] = set_faces(s);
        s += 1;
    }
    t
};

/// One face's hue band: hues within `half` units of `centre` (circularly) match it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Band {
    /// Centre, in hue units (`0..HUE_UNITS`).
    pub centre: u8,
    /// Half-width, in hue units.
    pub half: u8,
}

/// [`face_set`] of every 6-bit face mask.
const FACE_SET: [u8; 64] = {
    let mut t = [0u8; 64];
    let mut m = 0usize;
    while m < 64 {
        t[m] = face_set(m as u8) as u8;
        m += 1;
    }
    t
};

/// The face bitmask of face set `set` ([`face_set`]'s inverse on `0..FACE_SETS`).
const fn set_faces(set: usize) -> u8 {
    let (mut faces, mut rest, mut a) = (0u8, set, 0u32);
    while a < 3 {
        match rest % 3 {
            1 => faces |= 1 << a,
            2 => faces |= 1 << (a + 3),
            _ => {}
        }
        rest /= 3;
        a += 1;
    }
    faces
}

/// A 256-entry table: bit `k` of `lut[h]` is set when hue byte `h` matches the hue `b_k` of
/// face `k` within the tolerance band (a real camera never returns exactly `b_k`, so the
/// Kronecker δ of eq. 34 is applied to the quantised, banded hue).
///
/// Beside the bitmasks it holds one byte plane per set of faces a camera can see (see
/// [`HueLut::any`]): `1` where the hue matches a face of the set. The fitness kernel scores
/// every sample point with one load from a plane, the face's own for the inner points and
/// the visible faces' for the contour points (7 KiB in all).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HueLut {
    table: [u8; 256],
    sets: [[u8; 256]; FACE_SETS],
}

impl HueLut {
    /// The table that matches nothing (every entry 0).
    pub const EMPTY: Self = Self { table: [0; 256], sets: [[0; 256]; FACE_SETS] };

    /// Table for up to 8 face hues (in hue units) with a band of `±tolerance` units.
    /// `NO_HUE` and bytes `≥ HUE_UNITS` match nothing.
    pub fn new(face_hues: &[u8], tolerance: u8) -> Self {
        let mut lut = Self::EMPTY;
        lut.fill(face_hues, tolerance);
        lut
    }

    /// Rebuilds this table in place as [`HueLut::new`]`(face_hues, tolerance)`, with no
    /// temporary table (a board builds its tracker's table where it lives).
    pub fn fill(&mut self, face_hues: &[u8], tolerance: u8) {
        for h in 0..=u8::MAX {
            let mut mask = 0u8;
            if h < HUE_UNITS {
                for (k, &b) in face_hues.iter().take(8).enumerate() {
                    if hue_distance(h, b % HUE_UNITS) <= tolerance {
                        mask |= 1 << k;
                    }
                }
            }
            self.table[usize::from(h)] = mask;
        }
        self.fill_sets();
    }

    /// Rebuilds this table in place from one band per face (up to 8; a half-width of 90 or
    /// more matches every hue): the same table as [`HueLut::fill`] where every band has the same
    /// half-width. Bounded work: the bands' entries, then the planes a word at a time.
    pub fn fill_bands(&mut self, bands: &[Band]) {
        self.fill_bands_except(bands, &HueSet::EMPTY, 0);
    }

    /// [`HueLut::fill_bands`], with the hues of `except` matching none of the faces `faces`
    /// (bit `k` for face `k`). The same bounded work.
    pub fn fill_bands_except(&mut self, bands: &[Band], except: &HueSet, faces: u8) {
        self.table = [0; 256];
        let units = i32::from(HUE_UNITS);
        for (k, band) in bands.iter().take(8).enumerate() {
            let half = i32::from(band.half.min(HUE_UNITS / 2));
            let centre = i32::from(band.centre % HUE_UNITS);
            // A band of 90 or more wraps onto itself: its last entry would be its first.
            let last = if 2 * half >= units { centre - half + units - 1 } else { centre + half };
            for h in centre - half..=last {
                if let Some(entry) = self.table.get_mut(h.rem_euclid(units) as usize) {
                    *entry |= 1 << k;
                }
            }
        }
        // Four entries a word: byte `i` of `clear` is `faces` where hue `h + i` is in `except`
        // (the four bits spread to the bytes' low bits by one multiplication).
        for (j, entries) in self.table.chunks_exact_mut(4).take(usize::from(HUE_UNITS) / 4).enumerate() {
            let bits = except.0.get(j / 8).map_or(0, |w| (w >> (4 * (j % 8))) & 0xF);
            let clear = ((bits * 0x0020_4081) & 0x0101_0101) * u32::from(faces);
            let kept = u32::from_le_bytes([entries[0], entries[1], entries[2], entries[3]]) & !clear;
            entries.copy_from_slice(&kept.to_le_bytes());
        }
        self.fill_sets();
    }

    /// The face-set planes from the bitmask table, four entries per word operation: for a byte
    /// `m ≤ 0x3F` of the masks of one face set, `(m + 0x7F) & 0x80` is `0x80` exactly when
    /// `m ≠ 0` (no carry leaves the byte), shifted down to 1.
    fn fill_sets(&mut self) {
        for (plane, set) in self.sets.iter_mut().zip(SET_FACES) {
            let faces = u32::from(set) * 0x0101_0101;
            for (out, masks) in plane.chunks_exact_mut(4).zip(self.table.chunks_exact(4)) {
                let m = u32::from_le_bytes([masks[0], masks[1], masks[2], masks[3]]) & faces & 0x3F3F_3F3F;
                let hit = ((m + 0x7F7F_7F7F) & 0x8080_8080) >> 7;
                out.copy_from_slice(&hit.to_le_bytes());
            }
        }
    }

    /// The plane of face `k < 6`: `plane(k)[h] == (mask(h) >> k) & 1` (one load and one
    /// addition per point when counting matches of a single face). `k ≥ 6` gives the plane
    /// of no face (every entry 0).
    #[inline(always)]
    pub fn plane(&self, k: usize) -> &[u8; 256] {
        self.any(u8::try_from(k).ok().and_then(|k| 1u8.checked_shl(u32::from(k))).unwrap_or(0))
    }

    /// The plane of a set of faces: `any(faces)[h] == u8::from(mask(h) & faces != 0)` for
    /// every set with at most one face of each opposite pair `(a, a + 3)` of the block's six
    /// faces (the faces one camera can see). Of a pair given both, only face `a` counts; bits 6
    /// and 7 are ignored.
    #[inline(always)]
    pub fn any(&self, faces: u8) -> &[u8; 256] {
        let set = FACE_SET.get(usize::from(faces & 0x3F)).copied().unwrap_or(0);
        self.sets.get(usize::from(set)).unwrap_or(&self.sets[0])
    }

    /// The face bitmask of hue byte `h`.
    #[inline(always)]
    pub fn mask(&self, h: u8) -> u8 {
        // Indexing a [u8; 256] by a u8 cannot go out of bounds.
        self.table[usize::from(h)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_hue_set_holds_hue_units_only() {
        let mut s = HueSet::EMPTY;
        assert!(s.is_empty());
        for h in [0, 31, 32, 179, 180, NO_HUE] {
            s.insert(h);
        }
        assert!([0, 31, 32, 179].iter().all(|&h| s.contains(h)));
        assert!([1, 33, 178, 180, NO_HUE].iter().all(|&h| !s.contains(h)));
        // Bands without the set's hues for the faces asked: face 0's band loses 179 and 0, face
        // 1's keeps 0.
        let mut lut = HueLut::EMPTY;
        lut.fill_bands_except(&[Band { centre: 0, half: 2 }, Band { centre: 2, half: 2 }], &s, 1);
        assert_eq!((lut.mask(0), lut.mask(1), lut.mask(2), lut.mask(179)), (2, 3, 3, 0));
        assert_eq!(lut.plane(0)[1], 1);
        assert_eq!(lut.plane(0)[0], 0);
    }

    #[test]
    fn rgb_to_hue_covers_the_circle() {
        assert_eq!(rgb_to_hue(255, 0, 255), 150); // magenta 300°
        assert_eq!(rgb_to_hue(0, 255, 255), 90); // cyan 180°
        assert_eq!(rgb_to_hue(255, 0, 4), 0); // -0.94° = 359.06° = unit 179.53, rounds to 180 ≡ 0
        assert_eq!(rgb_to_hue(255, 0, 12), 179); // -2.82° = 357.18° = unit 178.6, rounds to 179
        assert_eq!(rgb_to_hue(255, 128, 0), 15); // orange 30.1°
        // Brightness does not change hue.
        assert_eq!(rgb_to_hue(100, 50, 0), rgb_to_hue(200, 100, 0));
    }

    /// The definition, with divisions: the sector of the largest channel, then
    /// `⌊(60·diff + delta) / (2·delta)⌋` wrapped into `0..HUE_UNITS`.
    fn rgb_to_hue_by_division(r: u8, g: u8, b: u8) -> u8 {
        let (max, min) = (r.max(g).max(b), r.min(g).min(b));
        let delta = i32::from(max) - i32::from(min);
        if max < MIN_VALUE || delta * 255 < i32::from(MIN_SATURATION) * i32::from(max) || delta == 0 {
            return NO_HUE;
        }
        let (r, g, b) = (i32::from(r), i32::from(g), i32::from(b));
        let max = i32::from(max);
        // The first channel equal to the largest names the sector.
        let (offset, diff) = match max {
            m if m == r => (0, g - b),
            m if m == g => (60, b - r),
            _ => (120, r - g),
        };
        let h = offset + (60 * diff + delta).div_euclid(2 * delta);
        h.rem_euclid(i32::from(HUE_UNITS)) as u8
    }

    #[test]
    fn rgb_to_hue_matches_the_division_everywhere() {
        for r in 0..=255u8 {
            for g in 0..=255u8 {
                for b in 0..=255u8 {
                    assert_eq!(rgb_to_hue(r, g, b), rgb_to_hue_by_division(r, g, b), "rgb {r},{g},{b}");
                }
            }
        }
    }

    #[test]
    fn rgb_to_hue_matches_float_reference_everywhere() {
        for r in (0..=255).step_by(5) {
            for g in (0..=255).step_by(5) {
                for b in (0..=255).step_by(5) {
                    let h = rgb_to_hue(r as u8, g as u8, b as u8);
                    let (rf, gf, bf) = (r as f64, g as f64, b as f64);
                    let max = rf.max(gf).max(bf);
                    let min = rf.min(gf).min(bf);
                    let d = max - min;
                    if max < f64::from(MIN_VALUE) || d * 255.0 < f64::from(MIN_SATURATION) * max || d == 0.0 {
                        assert_eq!(h, NO_HUE);
                        continue;
                    }
                    let deg = if max == rf {
                        60.0 * (gf - bf) / d
                    } else if max == gf {
                        60.0 * (bf - rf) / d + 120.0
                    } else {
                        60.0 * (rf - gf) / d + 240.0
                    };
                    let units = deg.rem_euclid(360.0) / 2.0;
                    let dist = (f64::from(h) - units).abs();
                    assert!(dist.min(180.0 - dist) <= 0.5 + 1e-9, "rgb {r},{g},{b}: {h} vs {units}");
                }
            }
        }
    }

    #[test]
    fn lut_bands_wrap_around_red() {
        let lut = HueLut::new(&[0, 60, 120, 0, 60, 120], 5);
        assert_eq!(lut.mask(0), 0b001001);
        assert_eq!(lut.mask(175), 0b001001);
        assert_eq!(lut.mask(174), 0);
        assert_eq!(lut.mask(65), 0b010010);
        assert_eq!(lut.mask(66), 0);
        assert_eq!(lut.mask(NO_HUE), 0);
        assert_eq!(lut.mask(200), 0);
        for h in 0..=255u8 {
            for k in 0..8 {
                assert_eq!(lut.plane(k)[usize::from(h)], (lut.mask(h) >> k) & 1);
            }
            // Every set of faces one camera can see: of each opposite pair none or one.
            for set in 0..27u32 {
                let faces = (0..3).fold(0u8, |m, a| match set / 3u32.pow(a) % 3 {
                    1 => m | 1 << a,
                    2 => m | 1 << (a + 3),
                    _ => m,
                });
                assert_eq!(lut.any(faces)[usize::from(h)], u8::from(lut.mask(h) & faces != 0), "{faces:#b} {h}");
            }
        }
        let seven = HueLut::new(&[0, 60, 120, 0, 60, 120, 30], 5);
        assert_eq!(seven.mask(30), 1 << 6);
        assert_eq!(seven.plane(6)[30], 0, "no plane for a seventh face");
        let mut refilled = HueLut::new(&[90], 30);
        refilled.fill(&[0, 60, 120, 0, 60, 120], 5);
        assert_eq!(refilled, lut);
    }

    #[test]
    fn bands_of_one_width_are_the_table_of_that_tolerance() {
        let hues = [0, 60, 120, 0, 60, 120];
        for tolerance in [0, 5, 18, 44, 89, 90, 120] {
            let bands = hues.map(|centre| Band { centre, half: tolerance });
            let mut lut = HueLut::EMPTY;
            lut.fill_bands(&bands);
            assert_eq!(lut, HueLut::new(&hues, tolerance), "tolerance {tolerance}");
        }
        // Bands of different widths, wrapping round red.
        let mut lut = HueLut::EMPTY;
        lut.fill_bands(&[Band { centre: 2, half: 10 }, Band { centre: 50, half: 3 }]);
        assert_eq!((lut.mask(172), lut.mask(171), lut.mask(12), lut.mask(13)), (1, 0, 1, 0));
        assert_eq!((lut.mask(47), lut.mask(46), lut.mask(53), lut.mask(54)), (2, 0, 2, 0));
        assert_eq!(lut.any(0b11)[50], 1);
        assert_eq!(lut.any(0b100)[50], 0);
    }

    #[test]
    fn degree_conversion_wraps() {
        assert_eq!(degrees_to_units(0.0), 0);
        assert_eq!(degrees_to_units(240.0), 120);
        assert_eq!(degrees_to_units(-2.0), 179);
        assert_eq!(degrees_to_units(359.2), 0);
        assert_eq!(degrees_to_units(720.0 + 120.0), 60);
        assert_eq!(hue_distance(2, 178), 4);
    }
}
