//! Errors of estimates against the truth, for a simulated run and a recorded sequence alike:
//! the one RMS ([`rms_columns`]), the rotation error, how often `tracking` was wrong, all
//! modulo the block's colour symmetry. Uses only the core, so that both the simulator's
//! experiments and the sequence tracker can use it.
//!
//! A half turn about a block axis maps the box onto itself; when it also maps every face onto
//! a face of the same hue, the two poses give identical images and no tracker can tell them
//! apart. [`colour_symmetries`] finds which of `{I, Rx(π), Ry(π), Rz(π)}` do so for the
//! block's face hues; each frame's truth `^CR T_M` is replaced by the equivalent `^CR T_M · S`
//! nearest (in rotation angle) to the estimate before errors are taken.

use evorec_core::hue::degrees_to_units;
use evorec_core::pose::Psi;
use evorec_core::status::Status;
use nalgebra::{Isometry3, UnitQuaternion, Vector3};
use serde::Serialize;

/// Root mean square of each column of `rows` (`None` for no rows): the one RMS of the
/// simulator's and the sequence tracker's summaries.
pub fn rms_columns<const N: usize>(rows: impl IntoIterator<Item = [f64; N]>) -> Option<[f64; N]> {
    let mut sq = [0.0f64; N];
    let mut n = 0usize;
    for row in rows {
        for (acc, d) in sq.iter_mut().zip(row) {
            *acc += d * d;
        }
        n += 1;
    }
    (n > 0).then(|| sq.map(|s| (s / n as f64).sqrt()))
}

/// The rotation error of a run: RMS and largest angle (degrees) between estimate and truth,
/// in `evorec track`'s, `run`'s and `hil`'s `summary.json`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RotationError {
    /// RMS rotation error (degrees).
    pub rms_rot_deg: f64,
    /// Largest rotation error (degrees).
    pub max_rot_deg: f64,
}

impl RotationError {
    /// Of the per-frame rotation errors `degrees` (`None` when empty).
    pub fn of(degrees: impl IntoIterator<Item = f64> + Clone) -> Option<Self> {
        let [rms] = rms_columns(degrees.clone().into_iter().map(|d| [d]))?;
        Some(Self { rms_rot_deg: rms, max_rot_deg: degrees.into_iter().fold(0.0, f64::max) })
    }
}

/// The pose of an estimate (f64).
pub fn isometry_of(psi: &Psi) -> Isometry3<f64> {
    let t = psi.translation().cast::<f64>();
    let e = psi.eps().cast::<f64>();
    let w = (1.0 - e.norm_squared()).max(0.0).sqrt();
    let q = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(w, e.x, e.y, e.z));
    Isometry3::from_parts(t.into(), q)
}

/// A frame's estimate stays "within" the truth when its position error is at most this (m)…
pub const WITHIN_POSITION_M: f64 = 0.010;
/// …and its rotation error at most this (degrees).
pub const WITHIN_ROTATION_DEG: f64 = 5.0;

/// The half turns (named) that map every face onto a face of the same hue.
/// Faces are +x, +y, +z, −x, −y, −z; face `k` and `k + 3` are opposite.
pub fn colour_symmetries(face_hues_deg: &[f32; 6]) -> Vec<(&'static str, UnitQuaternion<f64>)> {
    let h = face_hues_deg.map(degrees_to_units);
    let same = |a: usize| h[a] == h[a + 3];
    let mut out = vec![("I", UnitQuaternion::identity())];
    for (name, axis, keep) in
        [("Rx(pi)", Vector3::x_axis(), 0), ("Ry(pi)", Vector3::y_axis(), 1), ("Rz(pi)", Vector3::z_axis(), 2)]
    {
        // A half turn about axis `keep` swaps the two other pairs of opposite faces.
        if (0..3).filter(|a| *a != keep).all(same) {
            out.push((name, UnitQuaternion::from_axis_angle(&axis, std::f64::consts::PI)));
        }
    }
    out
}

/// `ψ` (f64) of a pose, with `η ≥ 0`.
pub fn psi_of(iso: &Isometry3<f64>) -> [f64; 6] {
    let t = iso.translation.vector;
    let mut q = *iso.rotation.quaternion();
    if q.w < 0.0 {
        q = -q;
    }
    [t.x, t.y, t.z, q.i, q.j, q.k]
}

/// The truth equivalent under `symmetries` nearest to `estimate`, and the rotation error (rad).
pub fn aligned_truth(
    estimate: &Isometry3<f64>,
    truth: &Isometry3<f64>,
    symmetries: &[(&'static str, UnitQuaternion<f64>)],
) -> (Isometry3<f64>, f64) {
    let mut best = (*truth, f64::INFINITY);
    for (_, s) in symmetries {
        let cand = Isometry3::from_parts(truth.translation, truth.rotation * s);
        let angle = estimate.rotation.angle_to(&cand.rotation);
        if angle < best.1 {
            best = (cand, angle);
        }
    }
    best
}

/// One frame's errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameError {
    /// Estimate minus aligned truth: x, y, z (m), ε₁, ε₂, ε₃.
    pub d: [f64; 6],
    /// Rotation error (degrees).
    pub rot_deg: f64,
}

impl FrameError {
    /// Whether the estimate is within [`WITHIN_POSITION_M`] and [`WITHIN_ROTATION_DEG`].
    pub fn within(&self) -> bool {
        Vector3::new(self.d[0], self.d[1], self.d[2]).norm() <= WITHIN_POSITION_M && self.rot_deg <= WITHIN_ROTATION_DEG
    }
}

/// The errors of one estimate against one truth, and the aligned truth's ψ.
pub fn frame_error(
    estimate: &Psi,
    truth: &Isometry3<f64>,
    symmetries: &[(&'static str, UnitQuaternion<f64>)],
) -> (FrameError, [f64; 6]) {
    let est = isometry_of(estimate);
    let (aligned, angle) = aligned_truth(&est, truth, symmetries);
    let t = psi_of(&aligned);
    let e = estimate.0.map(f64::from);
    (FrameError { d: std::array::from_fn(|k| e[k] - t[k]), rot_deg: angle.to_degrees() }, t)
}

/// RMS errors of estimates against the truth over a set of frames, per axis of ψ: the one
/// RMS type of every summary (`evorec run`'s accuracy, `evorec track`'s errors, the hand-over).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rms {
    /// RMS x error (mm).
    pub rms_x_mm: f64,
    /// RMS y error (mm).
    pub rms_y_mm: f64,
    /// RMS z error (mm).
    pub rms_z_mm: f64,
    /// RMS ε₁ error.
    pub rms_e1: f64,
    /// RMS ε₂ error.
    pub rms_e2: f64,
    /// RMS ε₃ error.
    pub rms_e3: f64,
    /// Mean x error, estimate − truth (mm): the bias of the position, which the RMS holds
    /// together with the spread (`RMS² = mean² + variance`).
    pub mean_x_mm: f64,
    /// Mean y error, estimate − truth (mm).
    pub mean_y_mm: f64,
    /// Mean z error, estimate − truth (mm): positive when the estimate is farther along the
    /// camera's axis than the block.
    pub mean_z_mm: f64,
    /// The rotation error, where the frames' rotation angles were taken ([`Rms::of`]).
    #[serde(flatten)]
    pub rotation: Option<RotationError>,
    /// Frames.
    pub frames: usize,
}

impl Rms {
    /// The RMS of the differences `estimate − truth` of ψ (m, m, m, ε₁, ε₂, ε₃), without a
    /// rotation error (`None` when empty).
    pub fn of_differences(diffs: impl IntoIterator<Item = [f64; 6]>) -> Option<Self> {
        let mut frames = 0usize;
        let mut sum = [0.0f64; 3];
        let counted = diffs.into_iter().inspect(|d| {
            frames += 1;
            for (acc, v) in sum.iter_mut().zip(d) {
                *acc += v;
            }
        });
        let [x, y, z, e1, e2, e3] = rms_columns::<6>(counted)?;
        let [mx, my, mz] = sum.map(|s| s / frames as f64 * 1e3);
        Some(Self {
            rms_x_mm: x * 1e3,
            rms_y_mm: y * 1e3,
            rms_z_mm: z * 1e3,
            rms_e1: e1,
            rms_e2: e2,
            rms_e3: e3,
            mean_x_mm: mx,
            mean_y_mm: my,
            mean_z_mm: mz,
            rotation: None,
            frames,
        })
    }

    /// The RMS of frame errors, with their rotation error (`None` when empty).
    pub fn of(errors: &[FrameError]) -> Option<Self> {
        let rotation = RotationError::of(errors.iter().map(|e| e.rot_deg))?;
        Self::of_differences(errors.iter().map(|e| e.d)).map(|r| Self { rotation: Some(rotation), ..r })
    }

    /// All zeros over no frames.
    pub const ZERO: Self = Self {
        rms_x_mm: 0.0,
        rms_y_mm: 0.0,
        rms_z_mm: 0.0,
        rms_e1: 0.0,
        rms_e2: 0.0,
        rms_e3: 0.0,
        mean_x_mm: 0.0,
        mean_y_mm: 0.0,
        mean_z_mm: 0.0,
        rotation: None,
        frames: 0,
    };

    /// The RMS of the position error's length (mm).
    pub fn position_mm(&self) -> f64 {
        Vector3::new(self.rms_x_mm, self.rms_y_mm, self.rms_z_mm).norm()
    }

    /// The RMS of the ε error's length.
    pub fn eps_norm(&self) -> f64 {
        Vector3::new(self.rms_e1, self.rms_e2, self.rms_e3).norm()
    }
}

/// How often `tracking` was wrong over a run: the frames reported as tracking whose estimate
/// is not [`FrameError::within`] the truth (more than 10 mm or 5° off, modulo the colour
/// symmetry). In `evorec run`'s and `evorec track`'s `summary.json` (with ground truth) and in
/// `evorec paper --seeds`' per-seed table.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct WrongTracking {
    /// Frames reported as tracking.
    pub tracking_frames: usize,
    /// Of those, the frames whose estimate is not within 10 mm and 5° of the truth.
    pub tracking_wrong_frames: usize,
    /// `tracking_wrong_frames / tracking_frames` (0 without tracking frames).
    pub tracking_wrong_fraction: f64,
    /// The longest run of consecutive frames reported as tracking and wrong.
    pub longest_wrong_tracking_frames: usize,
    /// Frames reported as uncertain (the block held, its pose not confirmed).
    pub uncertain_frames: usize,
    /// Of those, the frames whose estimate is not within 10 mm and 5° of the truth.
    pub uncertain_wrong_frames: usize,
}

impl WrongTracking {
    /// Of the frames' statuses, each with whether its estimate is within the truth.
    pub fn of(frames: impl IntoIterator<Item = (Status, bool)>) -> Self {
        let mut w = Self::default();
        let mut run = 0usize;
        for (status, within) in frames {
            let tracking = status == Status::Tracking;
            let wrong = tracking && !within;
            w.tracking_frames += usize::from(tracking);
            w.tracking_wrong_frames += usize::from(wrong);
            run = if wrong { run + 1 } else { 0 };
            w.longest_wrong_tracking_frames = w.longest_wrong_tracking_frames.max(run);
            let uncertain = status == Status::Uncertain;
            w.uncertain_frames += usize::from(uncertain);
            w.uncertain_wrong_frames += usize::from(uncertain && !within);
        }
        if w.tracking_frames > 0 {
            w.tracking_wrong_fraction = w.tracking_wrong_frames as f64 / w.tracking_frames as f64;
        }
        w
    }
}

/// The first position from which every error is [`FrameError::within`] to the end.
pub fn settled_from(errors: &[FrameError]) -> Option<usize> {
    let last_bad = errors.iter().rposition(|e| !e.within());
    match last_bad {
        None if errors.is_empty() => None,
        None => Some(0),
        Some(k) if k + 1 < errors.len() => Some(k + 1),
        Some(_) => None,
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;

    #[test]
    fn rms_is_the_shared_column_rms() {
        let e = |x: f64, rot: f64| FrameError { d: [x, 0.0, 0.0, 0.0, 0.0, 0.0], rot_deg: rot };
        let r = Rms::of(&[e(0.003, 1.0), e(-0.004, 7.0)]).unwrap();
        assert!((r.rms_x_mm - 12.5f64.sqrt()).abs() < 1e-12);
        // The bias beside the RMS: (3 − 4) / 2 mm, and none on the other axes.
        assert!((r.mean_x_mm + 0.5).abs() < 1e-12 && r.mean_y_mm == 0.0 && r.mean_z_mm == 0.0);
        let rot = r.rotation.unwrap();
        assert!((rot.rms_rot_deg - 25.0f64.sqrt()).abs() < 1e-12);
        assert_eq!((rot.max_rot_deg, r.frames), (7.0, 2));
        let d = Rms::of_differences([[0.003, 0.004, 0.0, 0.0, 0.006, 0.008]]).unwrap();
        assert!((d.position_mm() - 5.0).abs() < 1e-12 && (d.eps_norm() - 0.01).abs() < 1e-15);
        assert_eq!((d.rotation, d.frames), (None, 1));
        assert!((d.mean_x_mm - 3.0).abs() < 1e-12 && (d.mean_y_mm - 4.0).abs() < 1e-12);
        assert_eq!(Rms::of_differences([]), None);
        assert_eq!(Rms::of(&[]), None);
        assert_eq!(rms_columns([[3.0, -4.0], [-3.0, 4.0]]), Some([3.0, 4.0]));
        assert_eq!(rms_columns::<2>([]), None);
    }

    #[test]
    fn symmetries_follow_the_face_hues() {
        let names = |h: [f32; 6]| colour_symmetries(&h).into_iter().map(|(n, _)| n).collect::<Vec<_>>();
        assert_eq!(names([0.0, 120.0, 240.0, 0.0, 120.0, 240.0]), ["I", "Rx(pi)", "Ry(pi)", "Rz(pi)"]);
        // ±y differ: only the half turn about y keeps them.
        assert_eq!(names([0.0, 120.0, 240.0, 0.0, 60.0, 240.0]), ["I", "Ry(pi)"]);
        assert_eq!(names([0.0, 60.0, 120.0, 180.0, 240.0, 300.0]), ["I"]);
    }

    #[test]
    fn a_symmetric_estimate_has_no_rotation_error() {
        let truth = Isometry3::new(Vector3::new(0.01, 0.0, 0.7), Vector3::new(0.3, -0.2, 0.1));
        let flipped = Isometry3::from_parts(
            truth.translation,
            truth.rotation * UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI),
        );
        let est = Psi::from_isometry(&flipped.cast::<f32>());
        let all = colour_symmetries(&[0.0, 120.0, 240.0, 0.0, 120.0, 240.0]);
        let (e, _) = frame_error(&est, &truth, &all);
        assert!(e.rot_deg < 1e-3 && e.d.iter().all(|d| d.abs() < 1e-5), "{e:?}");
        // Without the symmetry the same estimate is 180° off.
        let (e, _) = frame_error(&est, &truth, &all[..1]);
        assert!((e.rot_deg - 180.0).abs() < 1e-3, "{e:?}");
    }

    #[test]
    fn wrong_tracking_counts_tracking_frames_off_the_truth() {
        let (t, s, l, u) = (Status::Tracking, Status::Searching, Status::Lost, Status::Uncertain);
        let frames =
            [(s, false), (t, true), (t, false), (t, false), (u, false), (l, false), (t, false), (u, true), (t, true)];
        let w = WrongTracking::of(frames);
        assert_eq!((w.tracking_frames, w.tracking_wrong_frames, w.longest_wrong_tracking_frames), (5, 3, 2));
        assert_eq!((w.uncertain_frames, w.uncertain_wrong_frames), (2, 1));
        assert!((w.tracking_wrong_fraction - 0.6).abs() < 1e-12);
        assert_eq!(WrongTracking::of([(s, false), (l, true)]), WrongTracking::default());
    }

    #[test]
    fn settling_frame_is_the_first_of_the_final_good_run() {
        let good = FrameError { d: [0.001, 0.0, 0.0, 0.0, 0.0, 0.0], rot_deg: 1.0 };
        let bad = FrameError { d: [0.02, 0.0, 0.0, 0.0, 0.0, 0.0], rot_deg: 1.0 };
        let turned = FrameError { rot_deg: 6.0, ..good };
        assert_eq!(settled_from(&[bad, good, bad, good, good]), Some(3));
        assert_eq!(settled_from(&[good, good]), Some(0));
        assert_eq!(settled_from(&[good, turned]), None);
        assert_eq!(settled_from(&[]), None);
        let r = Rms::of(&[good, bad]).unwrap();
        assert!(
            (r.rms_x_mm - (0.5f64 * (1.0 + 400.0)).sqrt()).abs() < 1e-9
                && r.rotation.map(|x| x.max_rot_deg) == Some(1.0)
        );
    }
}
