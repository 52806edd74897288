//! Acquisition: a pose seed from the colour blobs of a sparse pixel grid, computed in
//! bounded stages, one per generation.
//!
//! The fitness (eq. 34–35) samples points near the face edges, so it is a needle: a pose
//! scores only when it is within a few centimetres and degrees of the block. A uniform
//! population of 40 does not find that needle in a few dozen generations. The images,
//! though, say roughly where the block is:
//!
//! 1. **Scan** ([`scan_part`]): every `stride`-th pixel of every `stride`-th row of each image
//!    is looked up in the hue table; per block axis (the pair of opposite faces `k`, `k + 3`)
//!    the number of hits and the sums of their pixel coordinates are kept, and per hue unit
//!    the sides of the grid's border it was seen on.
//!
//!    **The scene's hues** ([`scene_hues`]). A hue seen on three sides of an image's border
//!    surrounds the view: the block, one convex solid, would have to span the whole image to
//!    reach them. Such a hue (with its neighbours on the hue circle that the grid saw) is the
//!    background's, however near a face's hue it is: a grey scene that the camera's white
//!    balance tints green-yellow falls in the green faces' search band, and counted as green
//!    it would put their blob in the middle of the view. The search table leaves the scene's
//!    hues out ([`crate::colour::Colours::set_scene`]), for the scan and for the fitness alike;
//!    the solve stage takes them from the finished scan, and a scan that finds them changed is
//!    repeated once, with them left out, before it is solved.
//! 2. **Triangulate** the centroid of each axis's hits seen in both images: the centroid of
//!    the visible face of that axis, a point `P_a = C + h_a·n_a` of the block (centre `C`,
//!    half size `h_a`, outward unit normal `n_a` of the face facing the cameras).
//! 3. **Solve** ([`seed_pose`]) for `C` and the axes:
//!    - three faces seen: `C` is the point at distances `h_a` from the three `P_a` (three
//!      spheres), on the far side from the cameras;
//!    - two faces `a`, `b`: `C` is at distances `h_a`, `h_b` from `P_a`, `P_b`, in the plane
//!      through them and the cameras (the third axis is then at right angles to the line of
//!      sight, which is why its faces are not seen);
//!    - one face: `C` lies `h_a` behind `P_a` along the line of sight, and the rotation about
//!      that line is unknown (each seeded individual draws it).
//!
//!    The normals `n_a = (P_a − C)/|P_a − C|` are made orthonormal (Gram–Schmidt, the face
//!    with most hits first). Which of a pair of opposite faces is seen is not known from the
//!    hue when both have the same hue; any sign choice with `det R = +1` is then the same
//!    pose up to a half turn about a block axis, which looks identical.
//! 4. **Refine** ([`Refinement`]) the solutions from all seen faces and from the two with
//!    most hits by damped Gauss–Newton on the faces' image centroids and areas; keep the one
//!    that fits best.
//! 5. **Seed** ([`seed_immigrant`]): while the tracker is not tracking, a fixed number of
//!    individuals per generation are replaced by the seed pose perturbed at one of three
//!    scales, composed with a random half turn of the colour symmetry.
//!
//! ## Bounded work per generation
//! [`Acquisition`] runs these steps as a pipeline of stages, **one stage per generation**,
//! and only while the tracker is not tracking:
//!
//! | stage | work (at most) |
//! |---|---|
//! | scan | [`AcquireConfig::scan_chunk`] grid pixels of each image |
//! | solve | the scene's hues (five passes over the 180 hue units) and the tracker's rebuild of its search table; two solves (all faces, two faces) and one residual evaluation of each |
//! | refine, [`REFINE_ITERATIONS`] times | one Gauss–Newton iteration of each of the two solutions (8 residual evaluations and one 6×6 solve each) |
//!
//! A complete seed takes `⌈grid pixels / scan_chunk⌉ + 1 + REFINE_ITERATIONS` generations
//! (8 for 160×120 or 320×240, 11 for 640×480 with the defaults); the latest seed keeps being
//! used for the seeded individuals while the next one is computed, carried along with the
//! camera by the same feedforward shift as the population (so a seed computed on older frames
//! still lands on the block while the arm moves). Every generation that is not tracking also
//! replaces [`AcquireConfig::seed_immigrants`] children by seeded poses.
//!
//! That extra work is paid for by the GA: a generation that starts in any status but
//! tracking evaluates [`AcquireConfig::idle_individuals`] fewer individuals (the last ones of
//! the population are left as they are, with fitness 0). With the defaults, the worst
//! generation while searching or lost costs less than the worst generation while tracking on
//! the Cortex-M4 (`evorec timing`, frame kinds `searching` and `lost`; checked by
//! `tests/tests/timing_budget.rs`), so the instruction budget is set by tracking alone.

mod linalg;
mod pipeline;
mod refine;
mod seed;
mod solve;
#[cfg(test)]
mod tests;

use linalg::column;
use nalgebra::Point2;

use crate::hue::{HueLut, HueSet};
use crate::image::{Image, PixelFormat};
use crate::limits::{DEFAULT_SCAN_STRIDE, DEFAULT_SEED_IMMIGRANTS, HUE_UNITS};

pub use pipeline::{Acquisition, Stage};
pub use refine::{Measured, REFINE_ITERATIONS, Refinement, best_seed, refine, refine_with_cost};
pub use seed::seed_immigrant;
pub use solve::{Seed, seed_pose, seed_pose_from, triangulate};

/// Number of perturbation scales of a seeded individual.
pub const SEED_LEVELS: usize = 3;

/// Settings of the acquisition; [`AcquireConfig::DEFAULT`] documents the defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AcquireConfig {
    /// Pixel stride of the scan in both directions.
    pub scan_stride: u16,
    /// Grid pixels of each image scanned per generation (the scan stage's bound).
    pub scan_chunk: u32,
    /// Individuals replaced by seeded poses per generation while not tracking.
    pub seed_immigrants: usize,
    /// Individuals not evaluated in a generation that starts in any status but tracking: the
    /// acquisition's work is paid for with theirs.
    pub idle_individuals: usize,
    /// Grid hits of an axis's hue needed in each image for its face to count as seen.
    pub min_face_hits: u32,
    /// Position half-widths (m) of the seeded perturbation, one per scale.
    pub spread_m: [f32; SEED_LEVELS],
    /// Rotation half-widths (rad, per rotation-vector component), one per scale.
    pub spread_rad: [f32; SEED_LEVELS],
}

impl AcquireConfig {
    /// Defaults: stride 8 px, 1,200 grid pixels of each image per generation (a 640×480 image
    /// in 4 generations, 160×120 in one), 8 seeded individuals, 6 idle individuals, a face
    /// seen with 6 hits in each image, perturbations of 3/10/25 mm and 0.03/0.10/0.25 rad.
    pub const DEFAULT: AcquireConfig = AcquireConfig {
        scan_stride: DEFAULT_SCAN_STRIDE,
        scan_chunk: DEFAULT_SCAN_CHUNK,
        seed_immigrants: DEFAULT_SEED_IMMIGRANTS,
        idle_individuals: DEFAULT_IDLE_INDIVIDUALS,
        min_face_hits: 6,
        spread_m: [0.003, 0.010, 0.025],
        spread_rad: [0.03, 0.10, 0.25],
    };
}

/// Default [`AcquireConfig::scan_chunk`].
pub const DEFAULT_SCAN_CHUNK: u32 = 1200;

/// Default [`AcquireConfig::idle_individuals`] (measured: see the module docs).
pub const DEFAULT_IDLE_INDIVIDUALS: usize = 6;

impl Default for AcquireConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Hue hits of one image's scan, per block axis (faces `a` and `a + 3`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HueBlobs {
    /// Grid pixels whose hue matches a face of the axis.
    pub count: [u32; 3],
    /// Sum of their column indices.
    pub sum_u: [u64; 3],
    /// Sum of their row indices.
    pub sum_v: [u64; 3],
    /// Hits (of any axis) in the grid's outermost rows and columns: the block, or something of
    /// its colours, reaches the image border there.
    pub edge: u32,
    /// Per hue unit, the sides of the grid's border it was seen on (bits [`SIDE_TOP`],
    /// [`SIDE_BOTTOM`], [`SIDE_LEFT`], [`SIDE_RIGHT`]) and whether the grid saw it at all
    /// ([`SEEN`]), whether it matches a face or not.
    pub sides: [u8; HUE_UNITS as usize],
}

/// [`HueBlobs::sides`] bit of the grid's first row.
pub const SIDE_TOP: u8 = 1;
/// [`HueBlobs::sides`] bit of the grid's last row.
pub const SIDE_BOTTOM: u8 = 2;
/// [`HueBlobs::sides`] bit of the grid's first column.
pub const SIDE_LEFT: u8 = 4;
/// [`HueBlobs::sides`] bit of the grid's last column.
pub const SIDE_RIGHT: u8 = 8;
/// [`HueBlobs::sides`] bit of a hue seen anywhere on the grid.
pub const SEEN: u8 = 16;
/// The four side bits of [`HueBlobs::sides`].
const SIDES: u8 = SIDE_TOP | SIDE_BOTTOM | SIDE_LEFT | SIDE_RIGHT;

impl Default for HueBlobs {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl HueBlobs {
    /// Nothing scanned.
    pub const EMPTY: Self =
        Self { count: [0; 3], sum_u: [0; 3], sum_v: [0; 3], edge: 0, sides: [0; HUE_UNITS as usize] };

    /// Grid hits of all axes.
    pub fn total(&self) -> u32 {
        self.count.iter().sum()
    }

    /// Centroid of axis `a`'s hits in continuous pixel coordinates (pixel `(i, j)` covers
    /// `[i, i+1) × [j, j+1)`), `None` without hits.
    pub fn centroid(&self, a: usize) -> Option<Point2<f32>> {
        let n = *self.count.get(a)?;
        if n == 0 {
            return None;
        }
        let inv = 1.0 / n as f32;
        Some(Point2::new(*self.sum_u.get(a)? as f32 * inv + 0.5, *self.sum_v.get(a)? as f32 * inv + 0.5))
    }

    /// Whether hits lie on the grid's border (see [`HueBlobs::edge`]).
    pub fn touches_border(&self) -> bool {
        self.edge > 0
    }

    /// The block axes (bit `a`) whose faces a hue-table `mask` matches (faces `a` and `a + 3`).
    #[inline(always)]
    fn axes(mask: u8) -> u8 {
        (mask | (mask >> 3)) & 0b111
    }

    /// Records hue byte `h` seen on the border sides `side` (no hue is not recorded).
    #[inline(always)]
    fn mark(&mut self, h: u8, side: u8) {
        if let Some(s) = self.sides.get_mut(usize::from(h)) {
            *s |= side;
        }
    }

    /// Counts a grid pixel at `(u, v)` whose hue-table mask is `mask`.
    #[inline(always)]
    fn add(&mut self, mask: u8, u: usize, v: usize) {
        let axes = Self::axes(mask);
        if axes == 0 {
            return;
        }
        for (a, ((c, su), sv)) in
            self.count.iter_mut().zip(self.sum_u.iter_mut()).zip(self.sum_v.iter_mut()).enumerate()
        {
            if (axes >> a) & 1 != 0 {
                *c += 1;
                *su += u as u64;
                *sv += v as u64;
            }
        }
    }
}

/// The scan grid of a `width × height` image: `(columns, rows)`, `⌈(W − o)/s⌉ × ⌈(H − o)/s⌉`
/// with the offset `o = s/2`; `(0, 0)` for a stride of 0.
pub fn grid_size(width: u16, height: u16, stride: u16) -> (u32, u32) {
    if stride == 0 {
        return (0, 0);
    }
    let (s, o) = (u32::from(stride), u32::from(stride / 2));
    let n = |side: u16| u32::from(side).saturating_sub(o).div_ceil(s);
    (n(width), n(height))
}

/// Scans grid pixels `start .. start + count` of `image` (row-major grid indices, see
/// [`grid_size`]) into `blobs` and returns the index after the last one read (the grid's
/// size once it is done). Reads at most `count` pixels, whatever the image holds. Pixels of
/// any [`PixelFormat`] are converted to a hue only where the grid reads them.
pub fn scan_part<B: AsRef<[u8]>, F: PixelFormat>(
    image: &Image<B, F>,
    lut: &HueLut,
    stride: u16,
    start: u32,
    count: u32,
    blobs: &mut HueBlobs,
) -> u32 {
    let (gw, gh) = grid_size(image.width(), image.height(), stride);
    let end = start.saturating_add(count).min(gw * gh);
    let (w, s, o) = (usize::from(image.width()), stride as usize, usize::from(stride / 2));
    let pixels = image.pixels();
    if s == 0 || gw == 0 {
        // No grid (a zero stride or an image narrower than it): nothing to read.
        return end;
    }
    let mut i = start;
    while i < end {
        let gy = i / gw;
        let row_end = end.min((gy + 1) * gw);
        let v = o + gy as usize * s;
        let row = pixels.get(v * w..(v + 1) * w).unwrap_or(&[]);
        let first = (i - gy * gw) as usize;
        let n = (row_end - i) as usize;
        let before = blobs.total();
        // Every hue the row shows is seen; in the first and last grid rows, on that side too.
        let side = (u8::from(gy == 0) * SIDE_TOP) | (u8::from(gy + 1 == gh) * SIDE_BOTTOM);
        for (k, px) in row.iter().skip(o + first * s).step_by(s).take(n).enumerate() {
            let h = F::hue(*px);
            blobs.mark(h, SEEN | side);
            blobs.add(lut.mask(h), o + (first + k) * s, v);
        }
        // The border: every hit of the first and last grid rows, and the first and last grid
        // pixels of the other rows (read again), with the sides their hues were seen on.
        if side != 0 {
            blobs.edge += blobs.total() - before;
        }
        let last = (gw as usize).saturating_sub(1);
        for (gx, end_side) in [(0, SIDE_LEFT), (last, SIDE_RIGHT)] {
            if (first..first + n).contains(&gx)
                && let Some(px) = row.get(o + gx * s)
            {
                let h = F::hue(*px);
                blobs.mark(h, end_side);
                blobs.edge += u32::from(side == 0 && HueBlobs::axes(lut.mask(h)) != 0);
            }
        }
        i = row_end;
    }
    end
}

/// The hues of the scene around the block in a scan of both images (`left`, `right`): every
/// hue seen on at least [`SCENE_SIDES`] sides of either image's grid border, and the hues next
/// to them on the hue circle that the grid saw (the spread of the same surface's colour, across
/// gaps of one hue unit: a tinted grey's hue moves in steps where a sensor's 5-bit channels
/// differ by one count). The block is one convex solid: to reach three sides of an image it
/// would have to span the whole image, so a colour seen there surrounds the view (a
/// background, a floor, a grey scene tinted by the white balance). Bounded work: five passes
/// over the hue units.
pub fn scene_hues(left: &HueBlobs, right: &HueBlobs) -> HueSet {
    let mut scene = HueSet::EMPTY;
    let units = usize::from(HUE_UNITS);
    let marks = |h: usize| {
        let h = h % units;
        (left.sides.get(h).copied().unwrap_or(0), right.sides.get(h).copied().unwrap_or(0))
    };
    for (h, unit) in (0..HUE_UNITS).zip(0..units) {
        let (l, r) = marks(unit);
        if (l & SIDES).count_ones().max((r & SIDES).count_ones()) >= SCENE_SIDES {
            scene.insert(h);
        }
    }
    if scene.is_empty() {
        return scene;
    }
    // Grown along the circle both ways; two laps each way reach across the wrap.
    let seen = |h: usize| marks(h).0 | marks(h).1 != 0;
    for step in [1, units - 1] {
        let mut h = 0usize;
        for _ in 0..2 * units {
            let next = (h + step) % units;
            if scene.contains(h as u8) && (seen(next) || seen(next + step)) {
                scene.insert(next as u8);
            }
            h = next;
        }
    }
    scene
}

/// Sides of an image's grid border a hue must be seen on to be the scene's ([`scene_hues`]).
pub const SCENE_SIDES: u32 = 3;

/// Scans the whole grid of `image` (see [`scan_part`]): `⌈(W − o)/s⌉·⌈(H − o)/s⌉` pixels;
/// a stride of 0 reads nothing.
pub fn scan<B: AsRef<[u8]>, F: PixelFormat>(image: &Image<B, F>, lut: &HueLut, stride: u16) -> HueBlobs {
    let mut blobs = HueBlobs::default();
    scan_part(image, lut, stride, 0, u32::MAX, &mut blobs);
    blobs
}
