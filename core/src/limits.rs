//! Compile-time constants: capacities, sample counts and the fixed geometry of the search model.
//!
//! Everything that sizes a buffer or bounds a loop lives here, so the work of one GA generation
//! is a function of these numbers only (see the crate docs for the count).

/// Joint count of the PA-10 arm the default tracker is built for.
pub const PA10_DOF: usize = 7;

/// Default GA population size (individuals evaluated per generation), chosen at run time
/// through [`crate::ga::GaParams::population`] up to the capacity.
pub const DEFAULT_POPULATION: usize = 40;

/// Population capacity of the default [`crate::Tracker`] (its storage; the firmware's): any
/// population from 2 up to this is accepted at run time, and the worst-case work of a
/// generation is that of this many individuals. Equal to [`DEFAULT_POPULATION`], so the
/// firmware's measured worst case is the default configuration's (the host simulator compiles
/// a larger capacity).
pub const POPULATION_CAPACITY: usize = 40;

/// Most GA generations [`crate::tuning::Tuning::generations_per_frame`] may ask for on one
/// frame pair: the work of a frame is at most this many generations' (see the crate docs).
pub const MAX_GENERATIONS_PER_FRAME: u8 = 4;

/// Default number of sample points on each row of the surface-strips model.
pub const DEFAULT_GRID: usize = 8;

/// Distances (metres) inside a face's edge of the rows of inner sample points `S_in,k`
/// that run along that edge. Graded: the nearest row makes the fitness sharp, the deeper ones
/// keep a slope towards the optimum over a wider range. Must be increasing and positive.
///
/// The fitness places the **nearest** row in pixels instead ([`SILHOUETTE_INNER_PX`],
/// [`FOLD_INNER_PX`]): at a fixed distance in metres it would sit 2.3 px inside the edge at
/// 0.7 m, and the edge could move by pixels (several millimetres of depth) without moving any
/// point across it. `INNER_INSETS_M[0]` remains the nearest row of the model's own point lists
/// ([`crate::model::SurfaceStrips::inner_points`], the overlay) and sets how far inside the
/// corners the rows start.
pub const INNER_INSETS_M: [f32; 3] = [0.002, 0.008, 0.025];

/// Distances (metres) outside a face's edge, in the face's plane, of the contour-strip rows
/// `S_out` along that edge. Increasing and positive. The fitness places the nearest one in
/// pixels instead ([`SILHOUETTE_OUTER_PX`]); `OUTER_OFFSETS_M[0]` remains that of the model's
/// point lists.
pub const OUTER_OFFSETS_M: [f32; 2] = [0.003, 0.010];

/// Distance of the nearest inner row inside a **silhouette** edge (a visible face's edge whose
/// neighbour across it is hidden), in pixel widths across the edge at the pose (see
/// `fitness::metres_per_pixel`): it replaces `INNER_INSETS_M[0]` there. Half a width: the
/// row's points lie in pixels whose centres are on the face, so a point-sampling camera sees
/// the face in every one, and an area-sampling one whenever at most half a pixel of face makes
/// a pixel read as the face (its mixed pixels along a silhouette are the face's hue diluted by
/// the background, see `MIN_SATURATION`). With [`SILHOUETTE_OUTER_PX`] the two rows bound the
/// edge to half a pixel at the true pose, whatever the block's distance and the face's slant.
pub const SILHOUETTE_INNER_PX: f32 = 0.5;

/// Distance of the nearest contour row outside a silhouette edge, in pixel widths across the
/// edge: it replaces `OUTER_OFFSETS_M[0]` there. One width: the row's pixels hold no face at
/// the true pose, however little face a camera needs to read a pixel as the face.
pub const SILHOUETTE_OUTER_PX: f32 = 1.0;

/// Distance of the nearest inner row inside a **fold** edge (between two faces that both face
/// the camera), in pixel widths across the edge: it replaces `INNER_INSETS_M[0]` there. One
/// width: the mixed pixels along a fold have a hue between the two faces' that matches neither,
/// so the row keeps out of them.
pub const FOLD_INNER_PX: f32 = 1.0;

/// Rows per edge: inner then outer.
pub const ROWS_PER_EDGE: usize = INNER_INSETS_M.len() + OUTER_OFFSETS_M.len();

/// A face counts as visible only when the cosine between its outward normal and the direction
/// towards the camera exceeds this (≈ 84°): faces seen edge-on hold no usable sample area.
pub const MIN_VISIBLE_COS: f32 = 0.1;

/// A face counts as visible only when its narrowest side spans at least this many pixels
/// across its foreshortened direction (about `f · side · cos θ / distance`): a face seen as
/// a sliver cannot hold its inner rows, and the true pose would score below a pose that hides
/// it. Resolution-dependent on purpose.
pub const MIN_FACE_PX: f32 = 4.0;

/// A visible face's counts (its inner rows, and the outer rows of its silhouette edges) are
/// weighted by how well it is seen: the weight ramps linearly from 0 at [`MIN_VISIBLE_COS`] to
/// 1 at this cosine, and (the smaller of the two) from 0 at [`MIN_FACE_PX`] to 1 at
/// [`FULL_FACE_PX`]. A face turning into view then enters the score gradually instead of all
/// at once with rows that a sliver of a few pixels cannot hold, where the true pose would
/// score below one turned a little to hide that face.
pub const FULL_VISIBLE_COS: f32 = 0.2;

/// See [`FULL_VISIBLE_COS`]: the face width (pixels, as [`MIN_FACE_PX`]) from which a face
/// counts fully.
pub const FULL_FACE_PX: f32 = 8.0;

/// A pose is confirmed ([`crate::status::Status::Tracking`]) only while each camera sees at
/// least this many of its faces at full weight ([`FULL_VISIBLE_COS`], [`FULL_FACE_PX`]). The
/// fitness weighs a face turning into view from nothing at [`MIN_VISIBLE_COS`] (84° from its
/// normal) to full at [`FULL_VISIBLE_COS`] (78.5°), so a pose that shows one face at full weight
/// can tilt towards or away from a neighbouring face by up to 6–12° and trade the tilt for a
/// shift with almost no change of its score: such a view does not pin the orientation to the
/// 5° the status states. The second face seen at full weight does: a tilt about either axis of
/// the face seen whole then moves the outline of one of the two faces.
pub const CONFIRM_FULL_FACES: u32 = 2;

/// The fixed-point unit of a face's weight: weights are whole multiples of `1 / FACE_WEIGHT_ONE`,
/// so that the weighted counts stay integers (exact, the same on every target).
pub const FACE_WEIGHT_ONE: u32 = 256;

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

/// How far (hue units) the colour model may move a face's hue from the configured one, and
/// how much wider than the configured band the search band is ([`crate::colour`]): 13 units =
/// 26°, so a face whose colour the camera moves by up to ±25° is still found.
pub const MAX_HUE_SHIFT: u8 = 13;

/// Frames over which the colour model averages what it learns ([`crate::colour`]): a frame's
/// census moves a face's learnt hue by `1/n` of its offset, `n` the frames the face was seen,
/// at most this many.
pub const COLOUR_FRAMES: u16 = 8;

/// Census points of a face within its search band that a frame needs for the colour model to
/// learn from it ([`crate::colour`]): a quarter of one camera's census of a face with the
/// default grid.
pub const COLOUR_MIN_SAMPLES: u32 = 16;

/// Minimum `max(r, g, b)` for a pixel to have a hue (darker pixels get [`NO_HUE`]): 38 is a
/// value of 0.149, so a face in shadow down to a value of 0.15 keeps its hue.
pub const MIN_VALUE: u8 = 38;

/// Minimum saturation `(max − min) / max`, in 1/255 steps, for a pixel to have a hue.
pub const MIN_SATURATION: u8 = 80;

/// Largest image side accepted by [`crate::image::Image`] and [`crate::camera::Pinhole`]:
/// pixel coordinates stay below 2²² so the fitness can round them exactly (see
/// `fitness::View::index`).
pub const MAX_IMAGE_SIDE: u16 = 2048;

/// Default pixel stride of the acquisition scan ([`crate::acquire`]): every `stride`-th pixel
/// of every `stride`-th row of both images is read, `⌈W/s⌉·⌈H/s⌉` pixels per image
/// (4,800 for 640×480), whatever the status.
pub const DEFAULT_SCAN_STRIDE: u16 = 8;

/// Default number of individuals replaced by poses seeded from the colour blobs
/// ([`crate::acquire`]) in each generation while the tracker is not tracking.
pub const DEFAULT_SEED_IMMIGRANTS: usize = 8;

/// Bounds of the learnt shift of the nearest silhouette rows ([`crate::edge`]), in pixel widths
/// outwards: from `−¾` (the inner row 1¼ px inside the edge, the outer ¼ px outside) to `+¼`
/// (¼ px inside, 1¼ px outside). Both rows stay on their sides of the edge (checked at compile
/// time below), a camera reads a pixel as the face once the face covers some share `a*` of it,
/// and the rows centred on the true edge for `a* = ¼` (the fixed rows) move by `¼ − a*`.
pub const EDGE_SHIFT_RANGE_PX: [f32; 2] = [-0.75, 0.25];

/// Where the learnt shift starts ([`crate::edge::EdgeShift::NONE`]): the middle of
/// [`EDGE_SHIFT_RANGE_PX`], the shift of a camera that reads a pixel as the face once the face
/// covers half of it (`a* = ½`). A flat, saturated face on a grey background reads as the face
/// from about a quarter (`a*` = ¼, shift 0); a pale, shaded or tone-mapped face needs more of the
/// pixel (up to ¾), since a mixed pixel's saturation reaches the hue table's floor later. Starting
/// in the middle halves the way to either end, and the depth it biases, before the tests have run.
pub const EDGE_SHIFT_START_PX: f32 = 0.5 * (EDGE_SHIFT_RANGE_PX[0] + EDGE_SHIFT_RANGE_PX[1]);

/// The fine step of the learnt shift ([`crate::edge::EdgeShift`]), in pixel widths: its first
/// step, and every step once it has bracketed its balance. Half a pixel in 50 tests, which at
/// one test every [`EDGE_PROBE_EVERY`] tracked frames is 200 frames, about 7 s at 30 frames per
/// second. Small, because every test steps one way or the other and the shift wanders about its
/// balance by a few steps.
pub const EDGE_SHIFT_STEP_PX: f32 = 0.0025 * EDGE_PROBE_EVERY as f32;

/// The largest step of the learnt shift, in pixel widths: a sixteenth of a pixel. Doubling from
/// [`EDGE_SHIFT_STEP_PX`] while the tests agree, the shift crosses the half pixel from its start
/// to either end of [`EDGE_SHIFT_RANGE_PX`] in 10 tests (40 tracked frames).
pub const EDGE_SHIFT_MAX_STEP_PX: f32 = 0.0625;

/// The disparity test runs on one tracked frame in this many ([`crate::edge`]).
pub const EDGE_PROBE_EVERY: u8 = 4;

/// The change of disparity (pixels) between the two poses the disparity test compares: the
/// cameras' views of the best pose moved this much apart and this much together, half in each
/// camera.
pub const EDGE_PROBE_DISPARITY_PX: f32 = 0.5;

/// Individuals the last generation of a frame that runs the disparity test leaves unevaluated
/// (the last ones: the immigrants' slots first), to pay for the test's four single-camera
/// evaluations (two individuals' worth) with a margin, so that the generation's work stays
/// within the tracked generations' constant ([`TRACKING_IDLE`]).
pub const EDGE_PROBE_IDLE: usize = 3;

/// Individuals the last generation of every other tracked frame leaves unevaluated (the last
/// one, the immigrant's slot): the board's margin while tracking. The learnt shift's row
/// offsets, computed per edge at run time, cost about 14,000 M4 instructions per generation
/// more than fixed ones (measured with the shift held at zero), and without this margin the
/// worst tracked generation of `evorec timing` went over the budget.
pub const TRACKING_IDLE: usize = 1;

const _: () = assert!(EDGE_SHIFT_RANGE_PX[0] > -SILHOUETTE_OUTER_PX && EDGE_SHIFT_RANGE_PX[1] < SILHOUETTE_INNER_PX);
const _: () = assert!(EDGE_SHIFT_RANGE_PX[0] < 0.0 && EDGE_SHIFT_RANGE_PX[1] > 0.0 && EDGE_SHIFT_STEP_PX > 0.0);
const _: () = assert!(EDGE_SHIFT_MAX_STEP_PX >= EDGE_SHIFT_STEP_PX);
const _: () = assert!(EDGE_PROBE_EVERY > 0 && EDGE_PROBE_IDLE >= TRACKING_IDLE);
