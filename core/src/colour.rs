//! The block's face colours as the cameras see them, learnt from the images (an addition to
//! §4.2, whose eq. 34 matches every face's configured hue `b_k` within a fixed band).
//!
//! A real camera does not deliver the configured hues: its white balance and tone curve move
//! them (a saturated blue by −15° to −20° through a filmic curve), sky reflections make a face
//! pale, highlights wash part of it out and shadows darken it. The configured hues are
//! therefore only the prior of a colour model that the tracker learns from the pixels its own
//! pose says belong to each face.
//!
//! **Two hue tables.** While the tracker is not tracking (searching, lost), every face matches
//! its configured hue within `tolerance + MAX_HUE_SHIFT` (the *search band*, ±36° with the
//! defaults), so that a block whose colours are off by up to ±25° is still found, except the
//! hues of the scene around the block that the acquisition's scan finds
//! ([`crate::acquire::scene_hues`]): a band that wide can take in a background. While
//! tracking, every face it has learnt matches its learnt band: a centre within `MAX_HUE_SHIFT`
//! of the configured hue and a half-width from the face's measured spread, never narrower than
//! `tolerance` and never wider than the search band. A face not learnt yet keeps the search
//! band: its colour is known only as well as the prior says, and a narrower band would make a
//! pose that shows that face score below one that hides it (a lock that turns the unlearnt face
//! out of view). On a flat image whose faces have their configured hues the learnt band is the
//! configured one, so once every face in view has been learnt the fitness is the paper's.
//!
//! **Learning** ([`ColourModel::learn`]). After a frame's generations, while the block is held
//! (`tracking` or `uncertain`; a candidate not yet held teaches the model nothing), the colour
//! census of that pose (`Evaluator::census`: the hue under the two deeper inner rows of every
//! face it shows each camera, 64·G points per visible face and camera, away from the
//! anti-aliased edges) is tallied per face ([`Tally`]). Only hues within the search band around the face's current
//! centre count (a highlight has no hue, a shadow no hue, and a neighbour's colour at a
//! partly occluded face lies outside the band). Their mean offset from the current centre moves
//! the centre (one mean-shift step per frame); their standard deviation is the face's spread,
//! and the learnt band holds 1.65 of them each side (nine in ten of the face's hues). Both are averaged over frames with weight `1 / min(n, COLOUR_FRAMES)`, `n` the
//! frames the face was seen: the first sighting sets the model, later ones refine it. A face
//! needs [`COLOUR_MIN_SAMPLES`] counted points in a frame to be learnt from.
//!
//! **The scale of the fitness** ([`ColourModel::expected_fitness`]): the fraction of the census
//! points that match their face's learnt band, averaged over the frames it was learnt from. It
//! is what the true pose can score under the current light (about 1 on a flat image, less
//! where highlights and shadows take pixels' hues away); the status thresholds are relative to
//! it (see [`crate::status`]). A census point that shows another face's colour (a hue in
//! another configured colour's search window) is left out of that fraction: no light the
//! search allows gives the face that colour, so the held pose is off the face, and a lock on
//! a wrong pose must not teach the scale that its misses are the light's. The confirmation
//! takes a second average of the same coverage that leans upwards
//! ([`ColourModel::confirming_fitness`]): a frame below it moves it four times less than one
//! above it. The census is taken at the held pose, and a held pose a few millimetres off (a
//! manoeuvring block) covers less of its faces than the true pose does, so the plain average
//! sinks with such frames until poses that far off would be confirmed; the held decision keeps
//! the plain average, which follows the light as it changes.
//!
//! **Bounded work.** A census walks at most three faces per camera (the census of
//! `Evaluator::census`); the tally is a few integer operations per point, the update a few
//! per face, and rebuilding the tracking table ([`crate::hue::HueLut::fill_bands`]) a fixed
//! number of word operations. All integer: host and board agree bit for bit.

use crate::hue::{Band, HueLut, HueSet, hue_distance};
use crate::limits::{COLOUR_FRAMES, COLOUR_MIN_SAMPLES, HUE_UNITS, MAX_HUE_SHIFT};
use crate::model::FACES;

/// The smallest ratio of the best pose's worse camera's fitness to its better camera's at
/// which the tracker learns the face colours from it. Both cameras see the block under the
/// same light, so a pose in step scores alike in both; a pose fitted to a stereo pair out of
/// step does not, and learning from it would lower the expected fitness, the scale of the
/// status thresholds, until the wrong pose passed them.
pub const LEARN_CAMERA_RATIO: f32 = 0.95;

/// Fixed-point scale of the learnt offsets and spreads: 1/256 hue unit.
const Q: i32 = 256;

/// Fixed-point one of the averaged coverage (fine enough that a `1/128` step of a difference of
/// two thousandths is not lost to the truncation).
const COVERAGE_ONE: i32 = 1 << 16;

/// Half-width of a learnt band in standard deviations of the face's hues, in 1/256: 1.65.
const SPREAD_BAND_Q8: i32 = 422;

/// Frames over which [`ColourModel::expected_fitness`] is averaged, at most: about a second at
/// 30 frames/s, four times the colours' own average, so that a few frames of a wrong pose move
/// the scale of the status little.
const EXPECTED_FITNESS_FRAMES: u16 = 32;

/// A frame whose coverage is below [`ColourModel::confirming_fitness`] moves it this many times
/// less than one above it: it rises over about a second and falls over about four.
const CONFIRMING_FALL_SLOWER: i32 = 4;

/// Lower bound of [`ColourModel::expected_fitness`]: a light that leaves fewer than half of a
/// face's census points its hue is not one the status can be trusted in.
pub const MIN_EXPECTED_FITNESS: f32 = 0.5;

/// The learnt colour of one face.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
struct FaceColour {
    /// Learnt centre minus the configured hue, in 1/256 hue units (within ±`MAX_HUE_SHIFT`).
    offset: i32,
    /// Standard deviation of the face's hues, in 1/256 hue units.
    spread: i32,
    /// Frames the face was learnt from (saturating).
    frames: u16,
}

/// The census of one pose: per face, how many points it had and how many of them saw each hue.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Tally {
    /// Census points per face (with and without a hue).
    points: [u16; FACES],
    /// Per face, the points that saw each hue unit (saturating: a frame's census of a face
    /// has 64 points with the default grid).
    hues: [[u8; HUE_UNITS as usize]; FACES],
}

impl Tally {
    /// Nothing counted.
    pub const EMPTY: Self = Self { points: [0; FACES], hues: [[0; HUE_UNITS as usize]; FACES] };

    /// Counts the hue bytes `hues` seen on face `k` (faces `≥ FACES` are ignored).
    pub fn add(&mut self, k: usize, hues: &[u8]) {
        let (Some(points), Some(counts)) = (self.points.get_mut(k), self.hues.get_mut(k)) else { return };
        for &h in hues {
            *points = points.saturating_add(1);
            if let Some(c) = counts.get_mut(usize::from(h)) {
                *c = c.saturating_add(1);
            }
        }
    }

    /// Census points of face `k` (with and without a hue).
    pub fn points(&self, k: usize) -> u32 {
        self.points.get(k).map_or(0, |&n| u32::from(n))
    }

    /// The points of face `k` whose hue is within `half` units of `centre`, with the sum of
    /// their offsets from `centre` and of their squares.
    pub fn within(&self, k: usize, centre: u8, half: u8) -> Moments {
        let mut m = Moments::default();
        let Some(counts) = self.hues.get(k) else { return m };
        let half = i32::from(half.min(HUE_UNITS / 2 - 1));
        for d in -half..=half {
            let h = (i32::from(centre) + d).rem_euclid(i32::from(HUE_UNITS));
            let n = counts.get(h as usize).map_or(0, |&c| u32::from(c));
            m.count += n;
            m.sum += d * n as i32;
            m.square_sum += d.unsigned_abs() * d.unsigned_abs() * n;
        }
        m
    }
}

/// Counts and moments of the hues of a face's census points within a band ([`Tally::within`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Moments {
    /// Points within the band.
    pub count: u32,
    /// `Σ` their signed offsets from the band's centre (hue units).
    pub sum: i32,
    /// `Σ` their squared offsets.
    pub square_sum: u32,
}

/// `h − centre` wrapped into `−90..90` hue units.
#[inline(always)]
fn signed_offset(h: u8, centre: u8) -> i32 {
    let units = i32::from(HUE_UNITS);
    let d = (i32::from(h) - i32::from(centre)).rem_euclid(units);
    if d >= units / 2 { d - units } else { d }
}

/// The colour model of the block's faces: the configured hues (the prior) and what was learnt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ColourModel {
    prior: [u8; FACES],
    tolerance: u8,
    faces: [FaceColour; FACES],
    /// Averaged fraction of census points within their face's band, in 1/[`COVERAGE_ONE`].
    coverage: i32,
    /// The same, averaged leaning upwards ([`ColourModel::confirming_fitness`]).
    coverage_high: i32,
    /// Frames the coverage was averaged over (saturating).
    coverage_frames: u16,
}

impl ColourModel {
    /// The model that has learnt nothing: every face at its configured hue `prior[k]` (hue
    /// units) with half-width `tolerance` (units, below 90).
    pub const fn new(prior: [u8; FACES], tolerance: u8) -> Self {
        let none = FaceColour { offset: 0, spread: 0, frames: 0 };
        Self {
            prior,
            tolerance,
            faces: [none; FACES],
            coverage: COVERAGE_ONE,
            coverage_high: COVERAGE_ONE,
            coverage_frames: 0,
        }
    }

    /// Forgets everything learnt (the configured hues again).
    pub fn reset(&mut self) {
        *self = Self::new(self.prior, self.tolerance);
    }

    /// Half-width of the search band: `tolerance + MAX_HUE_SHIFT`, below 90 units.
    pub fn search_half_width(&self) -> u8 {
        self.tolerance.saturating_add(MAX_HUE_SHIFT).min(HUE_UNITS / 2 - 1)
    }

    /// The search bands: every face's configured hue ± [`ColourModel::search_half_width`].
    pub fn search_bands(&self) -> [Band; FACES] {
        self.prior.map(|prior| self.search_band(prior))
    }

    /// The search band around the configured hue `prior` (hue units).
    fn search_band(&self, prior: u8) -> Band {
        Band { centre: prior % HUE_UNITS, half: self.search_half_width() }
    }

    /// The faces not learnt yet (bit `k` for face `k`), whose bands are search bands.
    pub fn unlearnt_faces(&self) -> u8 {
        self.faces.iter().enumerate().fold(0, |m, (k, f)| m | (u8::from(f.frames == 0) << k))
    }

    /// The learnt band of every face (the search band for a face not learnt yet).
    pub fn bands(&self) -> [Band; FACES] {
        core::array::from_fn(|k| self.band(k))
    }

    fn band(&self, k: usize) -> Band {
        let (Some(&prior), Some(face)) = (self.prior.get(k), self.faces.get(k)) else {
            return Band { centre: 0, half: self.tolerance };
        };
        // A face not learnt yet is known only to within the prior's uncertainty: its search band.
        if face.frames == 0 {
            return self.search_band(prior);
        }
        let units = i32::from(HUE_UNITS);
        let centre = (i32::from(prior) + round_q(face.offset)).rem_euclid(units);
        // 1.65 standard deviations each side hold about nine in ten of a face's hues.
        let spread = (SPREAD_BAND_Q8 * face.spread / Q + Q - 1) / Q;
        let half = spread.clamp(i32::from(self.tolerance), i32::from(self.search_half_width()));
        Band { centre: u8::try_from(centre).unwrap_or(0), half: u8::try_from(half).unwrap_or(self.tolerance) }
    }

    /// Learns from the census of a pose (see the module docs). Returns whether any band changed.
    pub fn learn(&mut self, tally: &Tally) -> bool {
        let before = self.bands();
        let window = self.search_half_width();
        let mut learnt = [false; FACES];
        for (k, seen) in learnt.iter_mut().enumerate() {
            let Some(band) = before.get(k) else { continue };
            let near = tally.within(k, band.centre, window);
            if near.count >= COLOUR_MIN_SAMPLES {
                self.learn_face(k, band.centre, &near);
                *seen = true;
            }
        }
        // The share of the census points within their face's band, as now learnt, of the points
        // that could show the face: a point with another face's colour shows that face (the
        // pose is off, or the faces are mixed up), not this face under another light.
        let (mut points, mut in_band) = (0u32, 0u32);
        let bands = self.bands();
        for (k, band) in bands.iter().enumerate().filter(|(k, _)| learnt.get(*k) == Some(&true)) {
            points += tally.points(k).saturating_sub(self.other_colours(k, tally));
            in_band += tally.within(k, band.centre, band.half).count;
        }
        if points > 0 {
            self.coverage_frames = self.coverage_frames.saturating_add(1);
            let weight = i32::from(self.coverage_frames.min(EXPECTED_FITNESS_FRAMES));
            let measured = (i64::from(COVERAGE_ONE) * i64::from(in_band) / i64::from(points)) as i32;
            self.coverage += (measured - self.coverage) / weight;
            // The first sighting sets it too; later ones below it move it more slowly.
            let fall = measured < self.coverage_high && self.coverage_frames > 1;
            self.coverage_high +=
                (measured - self.coverage_high) / if fall { CONFIRMING_FALL_SLOWER * weight } else { weight };
        }
        self.bands() != before
    }

    /// One frame's step of face `k` from the `near` hues of its census around `centre`: the
    /// measured centre relative to the prior, and the spread about it.
    fn learn_face(&mut self, k: usize, centre: u8, near: &Moments) {
        let (Some(face), Some(&prior)) = (self.faces.get_mut(k), self.prior.get(k)) else { return };
        let count = i64::from(near.count.max(1));
        let mean = i64::from(Q) * i64::from(near.sum) / count;
        let measured = Q * signed_offset(centre, prior) + mean as i32;
        let variance = (i64::from(Q * Q) * i64::from(near.square_sum) / count - mean * mean).max(0);
        let spread = crate::math::sqrt(variance as f32) as i32;
        face.frames = face.frames.saturating_add(1);
        let weight = i32::from(face.frames.min(COLOUR_FRAMES));
        let limit = Q * i32::from(MAX_HUE_SHIFT);
        face.offset = (face.offset + (measured - face.offset) / weight).clamp(-limit, limit);
        face.spread += (spread - face.spread) / weight;
    }

    /// Census points of face `k` that show another face's colour: a hue within the search
    /// window of another configured hue whose window does not overlap face `k`'s (no light the
    /// search allows gives face `k` that colour). Each other hue counted once.
    fn other_colours(&self, k: usize, tally: &Tally) -> u32 {
        let Some(&own) = self.prior.get(k) else { return 0 };
        let window = self.search_half_width();
        let mut count = 0;
        for (j, &hue) in self.prior.iter().enumerate() {
            let first = !self.prior.iter().take(j).any(|&p| p == hue);
            if first && hue_distance(hue, own) > 2 * window {
                count += tally.within(k, hue, window).count;
            }
        }
        count
    }

    /// What the true pose is expected to score under the current light: the averaged fraction
    /// of census points within their face's band, at least [`MIN_EXPECTED_FITNESS`] (1 before
    /// anything is learnt).
    pub fn expected_fitness(&self) -> f32 {
        crate::math::clamp(self.coverage as f32 / COVERAGE_ONE as f32, MIN_EXPECTED_FITNESS, 1.0)
    }

    /// The scale of the confirmation ([`crate::status`]): the coverage of
    /// [`ColourModel::expected_fitness`] averaged leaning upwards (see the module docs), at least
    /// [`MIN_EXPECTED_FITNESS`] (1 before anything is learnt).
    pub fn confirming_fitness(&self) -> f32 {
        crate::math::clamp(self.coverage_high as f32 / COVERAGE_ONE as f32, MIN_EXPECTED_FITNESS, 1.0)
    }

    /// The learnt hue of face `k` in degrees (the configured one before it was seen).
    pub fn hue_deg(&self, k: usize) -> f32 {
        let (prior, offset) = (self.prior.get(k).copied().unwrap_or(0), self.faces.get(k).map_or(0, |f| f.offset));
        let deg = 2.0 * (f32::from(prior) + offset as f32 / Q as f32);
        if deg < 0.0 {
            deg + 360.0
        } else if deg >= 360.0 {
            deg - 360.0
        } else {
            deg
        }
    }

    /// Frames face `k` was learnt from (0: never seen).
    pub fn frames_seen(&self, k: usize) -> u16 {
        self.faces.get(k).map_or(0, |f| f.frames)
    }
}

/// The colour model with the hue table the tracker uses: the search table (every face's
/// configured hue ± the search band) while it is not tracking, the tracking table (the learnt
/// bands) while it is. One table, rebuilt when the tracker changes between the two
/// ([`Colours::select`]) and when the learnt bands change.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Colours {
    model: ColourModel,
    lut: HueLut,
    tracking: bool,
    /// Hues of the scene around the block, which no search band matches ([`Colours::set_scene`]).
    scene: HueSet,
}

impl Colours {
    /// Nothing learnt, and an empty table: [`Colours::configure`] builds it in place. Every
    /// byte is zero, so a board writes it without a copy of it in flash.
    pub const EMPTY: Self = Self {
        model: ColourModel {
            prior: [0; FACES],
            tolerance: 0,
            faces: [FaceColour { offset: 0, spread: 0, frames: 0 }; FACES],
            coverage: 0,
            coverage_high: 0,
            coverage_frames: 0,
        },
        lut: HueLut::EMPTY,
        tracking: false,
        scene: HueSet::EMPTY,
    };

    /// The model of `prior` (hue units per face) and `tolerance` with nothing learnt, and the
    /// search table.
    pub fn new(prior: [u8; FACES], tolerance: u8) -> Self {
        let mut colours = Self::EMPTY;
        colours.configure(prior, tolerance);
        colours
    }

    /// Rebuilds everything in place for `prior` and `tolerance`: nothing learnt, the search
    /// table.
    pub fn configure(&mut self, prior: [u8; FACES], tolerance: u8) {
        self.model = ColourModel::new(prior, tolerance);
        self.tracking = false;
        self.scene = HueSet::EMPTY;
        self.rebuild();
    }

    /// Takes `scene` as the hues of the scene around the block (the acquisition's scan finds
    /// them, [`crate::acquire::scene_hues`]): a search band matches none of them, so that a
    /// background whose colour falls in a face's search band (a grey scene tinted by the white
    /// balance, a coloured floor) is neither scanned nor scored as that face. A learnt band
    /// keeps them: it was measured on the face itself. Rebuilds the table when they change, and
    /// on the board every time (the tracker calls it on the acquisition's solve stage only, so
    /// that stage's work is constant).
    ///
    /// When a search band that matched none of the scene's hues starts losing some, a warning
    /// says so: a background of a face's own colour hides that face from the search.
    pub fn set_scene(&mut self, scene: &HueSet) {
        let changed = *scene != self.scene;
        let before = if changed { self.scene_in_search_bands() } else { [0; FACES] };
        if changed || cfg!(target_arch = "arm") {
            self.scene = *scene;
            self.rebuild();
        }
        if changed {
            self.report_scene(&before);
        }
    }

    /// Warns of every search band that loses hues to the scene now and lost none `before`.
    #[inline(never)]
    fn report_scene(&self, before: &[u8; FACES]) {
        let bands = self.model.search_bands();
        for (k, ((lost, was), band)) in self.scene_in_search_bands().iter().zip(before).zip(bands).enumerate() {
            // Faces of the same configured hue share their band: it is reported once.
            if *lost > 0 && *was == 0 && !bands.iter().take(k).any(|b| *b == band) {
                log::warn!(
                    "the scene around the block shows {}° of the search band {}° ± {}° (a face's configured hue): the search leaves those hues out",
                    2 * u32::from(*lost),
                    2 * u32::from(band.centre),
                    2 * u32::from(band.half),
                );
            }
        }
    }

    /// Per face, how many hue units of its search band are the scene's (left out of the search).
    #[inline(never)]
    pub fn scene_in_search_bands(&self) -> [u8; FACES] {
        let mut lost = [0u8; FACES];
        for (n, band) in lost.iter_mut().zip(self.model.search_bands()) {
            for h in (0..HUE_UNITS).filter(|&h| self.scene.contains(h)) {
                *n += u8::from(hue_distance(h, band.centre) <= band.half);
            }
        }
        lost
    }

    /// The table the fitness and the acquisition use.
    pub fn lut(&self) -> &HueLut {
        &self.lut
    }

    /// Whether [`Colours::lut`] is the tracking table.
    pub fn is_tracking(&self) -> bool {
        self.tracking
    }

    /// Makes [`Colours::lut`] the tracking table (`tracking`) or the search table, rebuilding
    /// it if it is not that one already.
    pub fn select(&mut self, tracking: bool) {
        if tracking != self.tracking {
            self.tracking = tracking;
            self.rebuild();
        }
    }

    /// The colour model.
    pub fn model(&self) -> &ColourModel {
        &self.model
    }

    /// Learns from a census tally ([`ColourModel::learn`]) and rebuilds the tracking table if
    /// it is in use: on the board every time (constant work, so the measured worst case is
    /// every case), on a host only when a band changed.
    pub fn learn(&mut self, tally: &Tally) {
        let changed = self.model.learn(tally);
        if self.tracking && (changed || cfg!(target_arch = "arm")) {
            self.rebuild();
        }
    }

    fn rebuild(&mut self) {
        let (bands, searched) = if self.tracking {
            (self.model.bands(), self.model.unlearnt_faces())
        } else {
            (self.model.search_bands(), u8::MAX)
        };
        self.lut.fill_bands_except(&bands, &self.scene, searched);
    }
}

/// `x / Q` rounded to the nearest integer, halves away from zero.
fn round_q(x: i32) -> i32 {
    if x >= 0 { (x + Q / 2) / Q } else { -((-x + Q / 2) / Q) }
}

#[cfg(test)]
mod tests;
