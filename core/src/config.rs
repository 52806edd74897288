//! Compile-time constants: capacities, sample counts and the fixed geometry of the search model.
//!
//! Everything that sizes a buffer or bounds a loop lives here, so the work of one GA generation
//! is a function of these numbers only (see the crate docs for the count).

/// Joint count of the PA-10 arm the default tracker is built for.
pub const PA10_DOF: usize = 7;

/// Default GA population size (individuals evaluated per generation).
pub const DEFAULT_POPULATION: usize = 40;

/// Default side of the sample grid per face: `G × G` inner points and `G` contour-strip points
/// on each of the face's four edges.
pub const DEFAULT_GRID: usize = 6;

/// Distance (metres) by which the outermost inner sample points of a face sit inside its edges.
///
/// Small, so that the model at the true pose samples inside the face but a shift of a few
/// millimetres moves them off it.
pub const FACE_INSET_M: f32 = 0.002;

/// Distance (metres) of the contour strip `S_out` outside a silhouette edge, measured in the
/// plane of the visible face.
pub const STRIP_OFFSET_M: f32 = 0.003;

/// A face counts as visible only when the cosine between its outward normal and the direction
/// towards the camera exceeds this (≈ 84°): faces seen edge-on hold no usable sample area.
pub const MIN_VISIBLE_COS: f32 = 0.1;

/// Sample points closer to the camera plane than this (metres) make a camera's score zero.
pub const MIN_DEPTH_M: f32 = 0.05;

/// Number of hue units in a full turn: a hue byte `h < HUE_UNITS` is `2·h` degrees
/// (the OpenCV 8-bit convention).
pub const HUE_UNITS: u8 = 180;

/// The hue byte of a pixel without a usable hue (unsaturated or dark). Bytes
/// `HUE_UNITS..=254` never match any face either.
pub const NO_HUE: u8 = 255;

/// Default half-width of the hue match band, in hue units (±5 units = ±10°).
pub const DEFAULT_HUE_TOLERANCE: u8 = 5;

/// Minimum `max(r, g, b)` for a pixel to have a hue (darker pixels get [`NO_HUE`]).
pub const MIN_VALUE: u8 = 40;

/// Minimum saturation `(max − min) / max`, in 1/255 steps, for a pixel to have a hue.
pub const MIN_SATURATION: u8 = 80;

/// Largest image side accepted by [`crate::hue::HueImage`] (keeps `width·height` inside `u32`).
pub const MAX_IMAGE_SIDE: u16 = 4096;
