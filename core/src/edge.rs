//! Where a camera puts a silhouette: the learnt shift of the nearest silhouette rows (our
//! addition to the fitness of §4.2; `docs/method.md`, "Depth under a camera's light").
//!
//! A pixel that a silhouette edge partly covers reads as the face once the face covers some
//! share `a*` of it, and `a*` is the camera's: it depends on the face's saturation against the
//! background, the tone curve, the white balance and the sensor. The fitness's nearest rows
//! ([`SILHOUETTE_INNER_PX`] inside the edge, [`SILHOUETTE_OUTER_PX`] outside) centre the best
//! poses on the edge for `a* = ¼`; a camera with a larger `a*` shows a smaller block, which
//! the fitness puts farther away (millimetres of depth bias, nearly all of the error under a
//! camera's light). A shift `s` moves both rows outwards by `s` pixel widths; `s = ¼ − a*`
//! centres them again.
//!
//! The evidence is the **disparity**, which the bias does not touch: moving an edge moves it
//! by the same amount in both images. On a frame due for the test ([`EdgeShift::is_due`]) the
//! best pose is scored with the two cameras' views moved [`EDGE_PROBE_DISPARITY_PX`] apart
//! (the block nearer, as the disparity sees it) and as much together (farther), each half in
//! each camera, four single-camera evaluations ([`disparity_pull`]). If the images prefer the
//! nearer disparity, the pose is too far for its disparity: its silhouette is too small, so the
//! rows step inwards; if they prefer the farther one, outwards; a tie leaves them. The steps
//! start at [`EDGE_SHIFT_STEP_PX`], grow while the tests agree and shrink when they turn
//! ([`EdgeShift`]). The shift only learns from a held pose seen alike by both cameras, as the
//! colour model does ([`crate::colour`]), and stays within [`EDGE_SHIFT_RANGE_PX`].
//!
//! **Bounded work.** The test runs on one tracked frame in [`EDGE_PROBE_EVERY`], whether or
//! not it teaches, and the last generation of that frame leaves [`EDGE_PROBE_IDLE`]
//! individuals unevaluated to pay for it; the other tracked frames leave
//! [`TRACKING_IDLE`]. The shift changes where the rows are, not how many.

use nalgebra::Vector3;

use crate::fitness::{Evaluator, clamp_edge_shift};
use crate::image::{Image, PixelFormat};
use crate::limits::{
    EDGE_PROBE_DISPARITY_PX, EDGE_PROBE_EVERY, EDGE_SHIFT_MAX_STEP_PX, EDGE_SHIFT_START_PX, EDGE_SHIFT_STEP_PX,
    MIN_DEPTH_M,
};
#[cfg(doc)]
use crate::limits::{EDGE_PROBE_IDLE, EDGE_SHIFT_RANGE_PX, SILHOUETTE_INNER_PX, SILHOUETTE_OUTER_PX, TRACKING_IDLE};
use crate::pose::Psi;

/// Which way the disparity test pulls the silhouette rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pull {
    /// The images prefer the block nearer than the pose's disparity: the rows move inwards.
    Inwards,
    /// The images prefer the block farther: the rows move outwards.
    Outwards,
    /// Both disparities score the same (or the pose cannot be tested): no step.
    Neither,
}

/// The learnt shift of the nearest silhouette rows, which tracked frame the disparity test
/// runs on, and the size of the next step.
///
/// The step starts at [`EDGE_SHIFT_STEP_PX`], doubles while the tests agree (up to
/// [`EDGE_SHIFT_MAX_STEP_PX`]) and halves when they turn; once a turn brings it back to
/// [`EDGE_SHIFT_STEP_PX`] the shift has bracketed its balance and keeps that step for good.
/// So the walk from the start to a camera's balance takes a few tests instead of tens, and
/// about the balance the shift wanders by the fine step alone.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeShift {
    px: f32,
    frame: u8,
    step_px: f32,
    /// The direction of the last step (`0.0` before the first).
    last: f32,
    settled: bool,
}

impl EdgeShift {
    /// The shift before any test: [`EDGE_SHIFT_START_PX`], the fine step; the next tracked
    /// frame is due for the test.
    pub const NONE: Self =
        Self { px: EDGE_SHIFT_START_PX, frame: 0, step_px: EDGE_SHIFT_STEP_PX, last: 0.0, settled: false };

    /// The shift, pixel widths outwards (within [`EDGE_SHIFT_RANGE_PX`]).
    pub fn px(&self) -> f32 {
        self.px
    }

    /// Whether the tracked frame about to run is due for the disparity test: one in
    /// [`EDGE_PROBE_EVERY`].
    pub fn is_due(&self) -> bool {
        self.frame == 0
    }

    /// One tracked frame has run.
    pub fn tick(&mut self) {
        self.frame = (self.frame + 1) % EDGE_PROBE_EVERY;
    }

    /// Whether a turn of the tests has brought the step back to [`EDGE_SHIFT_STEP_PX`] for good.
    pub fn settled(&self) -> bool {
        self.settled
    }

    /// One step the way `pull` says, its size as the type's docs describe.
    pub fn learn(&mut self, pull: Pull) {
        let way = match pull {
            Pull::Inwards => -1.0,
            Pull::Outwards => 1.0,
            Pull::Neither => return,
        };
        if !self.settled && self.last != 0.0 {
            let factor = if way == self.last { 2.0 } else { 0.5 };
            self.step_px = crate::math::clamp(factor * self.step_px, EDGE_SHIFT_STEP_PX, EDGE_SHIFT_MAX_STEP_PX);
            self.settled = way != self.last && self.step_px <= EDGE_SHIFT_STEP_PX;
        }
        self.last = way;
        self.px = clamp_edge_shift(self.px + way * self.step_px);
    }
}

impl Default for EdgeShift {
    fn default() -> Self {
        Self::NONE
    }
}

/// The disparity test of `psi` (see the module docs): the fitness with the cameras' views
/// moved [`EDGE_PROBE_DISPARITY_PX`] apart against that with them moved as much together,
/// through `eval` (with its current shift). [`Pull::Neither`] on a tie, a non-finite score, or
/// a pose too near the cameras to test.
pub fn disparity_pull<const G: usize, B: AsRef<[u8]>, F: PixelFormat>(
    eval: &Evaluator<'_, G>,
    psi: &Psi,
    left: &Image<B, F>,
    right: &Image<B, F>,
) -> Pull {
    let (r, t) = (psi.rotation_unchecked(), psi.translation());
    let Some(half) = half_step(eval, &t) else { return Pull::Neither };
    // Seen from the right camera the block moves by `+half` (towards the left camera), from the
    // left one by `−half`: the baseline looks longer by `2·half`, the block nearer.
    let (towards, away) = (t + half, t - half);
    let nearer = eval.evaluate_apart(&r, [&towards, &away], left, right).total;
    let farther = eval.evaluate_apart(&r, [&away, &towards], left, right).total;
    if nearer > farther {
        Pull::Inwards
    } else if farther > nearer {
        Pull::Outwards
    } else {
        Pull::Neither
    }
}

/// Half the test's displacement, along the baseline from the right camera towards the left
/// one (`Σ_CR`): `EDGE_PROBE_DISPARITY_PX · Z / (2·f)` metres, so that the disparity changes by
/// [`EDGE_PROBE_DISPARITY_PX`] in all. `None` for a pose nearer than [`MIN_DEPTH_M`], not
/// finite, or a rig whose cameras coincide.
fn half_step<const G: usize>(eval: &Evaluator<'_, G>, t: &Vector3<f32>) -> Option<Vector3<f32>> {
    let rig = eval.rig();
    let centre = rig.left_center_in_right();
    let length = crate::math::sqrt(centre.dot(&centre));
    let metres = EDGE_PROBE_DISPARITY_PX * t.z / (2.0 * rig.right.fx());
    let half = centre * (metres / length);
    (t.z > MIN_DEPTH_M && length > 0.0 && half.iter().all(|v| v.is_finite())).then_some(half)
}

#[cfg(test)]
mod tests;
