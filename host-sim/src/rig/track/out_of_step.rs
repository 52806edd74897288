//! Stereo pairs that do not belong together, found from the images.
//!
//! A recording whose right images run a constant number of frames behind (or ahead of) the
//! left ones pairs every left image with the wrong right one: the tracker still finds a pose
//! that half fits. The two cameras of a rig see the same motion at the same time, whether the
//! arm moves them or the block moves in front of them, so the amount of change between
//! consecutive frames, per camera, rises and falls together. [`MotionMeter`] measures that
//! change (the mean absolute grey-level difference on a sparse grid of pixels) on the reader
//! thread; [`PairingCheck`] correlates the two series over the last [`WINDOW`] frames at every
//! offset up to [`MAX_OFFSET`] frames and reports an offset when the series agree well there
//! and leave several times more unexplained in step. A recording that ends before its first
//! window is full gets one verdict on all its frames at its end ([`PairingCheck::finish`]), from
//! [`MIN_FRAMES`] on. A scene without motion gives no verdict (nothing to compare),
//! and neither does a motion too smooth to tell an offset of a frame or two from no offset.

use std::collections::VecDeque;

use image::RgbImage;

/// Every `STRIDE`-th pixel along each image axis is sampled.
const STRIDE: u32 = 4;
/// Frames of both series the check correlates (4 s at 30 frames/s).
pub const WINDOW: usize = 120;
/// Frames between two checks once the first window is full.
pub const EVERY: usize = 30;
/// The largest offset looked for, in frames (either way).
pub const MAX_OFFSET: usize = 30;
/// The fewest frames a recording shorter than [`WINDOW`] needs for a verdict at its end (2 s at
/// 30 frames/s). Such a verdict looks for offsets up to a quarter of the frames, so that every
/// correlation it compares spans at least three quarters of them.
pub const MIN_FRAMES: usize = 60;
/// The least offset reported. An offset of one frame is found only where the motion changes
/// from frame to frame (a block turning by jerks, a start or a stop): the two series of a smooth
/// motion agree almost as well in step as one frame apart, and [`MIN_RESIDUAL_RATIO`] then gives
/// no verdict either way.
const MIN_OFFSET: usize = 1;
/// The correlation the series must reach at the offset found.
const MIN_CORRELATION: f64 = 0.8;
/// How many times more of the series' variance in step than at the offset found must be left
/// unexplained (`(1 − r₀) / (1 − r)`): the correlation of a smooth motion falls slowly with the
/// offset, so its level alone does not tell.
const MIN_RESIDUAL_RATIO: f64 = 4.0;

/// The change between consecutive frames of one camera.
#[derive(Debug, Default)]
pub struct MotionMeter {
    previous: Vec<u8>,
    current: Vec<u8>,
}

impl MotionMeter {
    /// The mean absolute grey-level change since the last image this meter saw (0 for the
    /// first, or after a change of image size).
    pub fn measure(&mut self, img: &RgbImage) -> f32 {
        self.current.clear();
        for y in (0..img.height()).step_by(STRIDE as usize) {
            for x in (0..img.width()).step_by(STRIDE as usize) {
                let [r, g, b] = img.get_pixel(x, y).0;
                self.current.push(((u16::from(r) + u16::from(g) + u16::from(b)) / 3) as u8);
            }
        }
        let (now, before) = (&self.current, &self.previous);
        let change = if now.len() == before.len() && !now.is_empty() {
            let sum: u64 = now.iter().zip(before).map(|(a, b)| u64::from(a.abs_diff(*b))).sum();
            sum as f32 / now.len() as f32
        } else {
            0.0
        };
        std::mem::swap(&mut self.previous, &mut self.current);
        change
    }
}

/// The verdict on a window: the right camera's series matches the left one's `offset` frames
/// later (negative: earlier).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutOfStep {
    /// Right-image lag in frames (positive: each right image shows what the left one showed
    /// `offset` frames before).
    pub offset: i32,
    /// The correlation of the two series at that offset.
    pub correlation: f64,
    /// Their correlation in step.
    pub in_step: f64,
    /// The window's first and last frame (positions in the recording).
    pub frames: (usize, usize),
    /// The largest offset looked for: an offset found there may be larger still.
    pub reach: i32,
}

impl std::fmt::Display for OutOfStep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (later, n) = if self.offset > 0 { ("later", self.offset) } else { ("earlier", -self.offset) };
        let frames = if n == 1 { "frame" } else { "frames" };
        let or_more = if n >= self.reach { " or more" } else { "" };
        write!(
            f,
            "the stereo pairs are out of step: the right images show the motion of the left ones {n}{or_more} {frames} {later} \
             (frames {}–{}: the image motion of the two cameras correlates {:.2} at that offset, {:.2} in step); \
             pair each left image with the right one taken at the same time (check the recorder's synchroniser or \
             the images' stamps), or pass --no-pairing-check to track anyway",
            self.frames.0, self.frames.1, self.correlation, self.in_step
        )
    }
}

/// The two series over their last [`WINDOW`] frames, and the check on them.
#[derive(Debug, Default)]
pub struct PairingCheck {
    left: VecDeque<f32>,
    right: VecDeque<f32>,
    /// Frames pushed so far.
    pushed: usize,
    /// The position in the recording of the last frame pushed.
    last: usize,
}

impl PairingCheck {
    /// Adds frame `i`'s motion in the two cameras; every 30 frames once [`WINDOW`] are
    /// in, the verdict on the last window if the pairs are out of step.
    pub fn push(&mut self, i: usize, left: f32, right: f32) -> Option<OutOfStep> {
        for (series, v) in [(&mut self.left, left), (&mut self.right, right)] {
            if series.len() == WINDOW {
                series.pop_front();
            }
            series.push_back(v);
        }
        (self.pushed, self.last) = (self.pushed + 1, i);
        if self.pushed < WINDOW || !(self.pushed - WINDOW).is_multiple_of(EVERY) {
            return None;
        }
        self.verdict(MAX_OFFSET)
    }

    /// At the end of a recording: the verdict on all its frames if it ended before the first
    /// window was full and has at least [`MIN_FRAMES`], with offsets up to a quarter of them;
    /// `None` otherwise (a longer recording was checked on its windows).
    pub fn finish(&mut self) -> Option<OutOfStep> {
        let n = self.pushed;
        if !(MIN_FRAMES..WINDOW).contains(&n) {
            return None;
        }
        self.verdict((n / 4).min(MAX_OFFSET))
    }

    /// The verdict on the series held (ending at the last frame pushed), offsets up to
    /// `max_offset`.
    fn verdict(&mut self, max_offset: usize) -> Option<OutOfStep> {
        let (l, r) = (self.left.make_contiguous(), self.right.make_contiguous());
        let last = self.last;
        let first = (last + 1).saturating_sub(l.len());
        let best = OutOfStep { frames: (first, last), ..best_offset(l, r, max_offset)? };
        log::debug!(
            "stereo pairing, frames {}–{}: best offset {} frames (correlation {:.3}), in step {:.3}",
            best.frames.0,
            best.frames.1,
            best.offset,
            best.correlation,
            best.in_step
        );
        best.is_out_of_step().then_some(best)
    }
}

impl OutOfStep {
    /// Whether the offset found is far enough from zero and clearly better than in step.
    fn is_out_of_step(&self) -> bool {
        self.offset.unsigned_abs() as usize >= MIN_OFFSET
            && self.correlation >= MIN_CORRELATION
            && (1.0 - self.in_step) >= MIN_RESIDUAL_RATIO * (1.0 - self.correlation)
    }
}

/// The offset within `±max_offset` at which two series of equal length correlate best
/// (`frames` left at 0); `None` where either is constant.
fn best_offset(left: &[f32], right: &[f32], max_offset: usize) -> Option<OutOfStep> {
    let in_step = correlation(left, right, 0)?;
    let reach = i32::try_from(max_offset).unwrap_or(i32::MAX);
    let (offset, best) = (-reach..=reach)
        .filter_map(|k| correlation(left, right, k).map(|c| (k, c)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    Some(OutOfStep { offset, correlation: best, in_step, frames: (0, 0), reach })
}

/// Pearson's correlation of `left[t]` with `right[t + offset]` over their overlap (the first
/// frame of each series, a change from nothing, left out); `None` where either is constant.
pub fn correlation(left: &[f32], right: &[f32], offset: i32) -> Option<f64> {
    let n = left.len().min(right.len());
    let (a, b) = if offset >= 0 {
        let k = offset as usize;
        (left.get(1..n.checked_sub(k)?)?, right.get(1 + k..n)?)
    } else {
        let k = offset.unsigned_abs() as usize;
        (left.get(1 + k..n)?, right.get(1..n.checked_sub(k)?)?)
    };
    let m = a.len() as f64;
    if m < 2.0 {
        return None;
    }
    let mean = |s: &[f32]| s.iter().map(|v| f64::from(*v)).sum::<f64>() / m;
    let (ma, mb) = (mean(a), mean(b));
    let (mut sab, mut saa, mut sbb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (dx, dy) = (f64::from(*x) - ma, f64::from(*y) - mb);
        sab += dx * dy;
        saa += dx * dx;
        sbb += dy * dy;
    }
    (saa > 1e-12 && sbb > 1e-12).then(|| sab / (saa * sbb).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A motion that rises and falls irregularly, as an arm's and a belt's do together.
    fn motion(n: usize) -> Vec<f32> {
        (0..n).map(|t| t as f32 * 0.05).map(|t| 3.0 + (t * 1.3).sin() + 0.6 * (t * 0.37).sin().powi(2)).collect()
    }

    fn verdict(left: &[f32], right: &[f32]) -> Option<OutOfStep> {
        let mut check = PairingCheck::default();
        left.iter().zip(right).enumerate().filter_map(|(i, (l, r))| check.push(i, *l, *r)).next()
    }

    #[test]
    fn pairs_in_step_give_no_verdict() {
        let m = motion(400);
        assert_eq!(verdict(&m, &m), None);
    }

    #[test]
    fn right_images_fifteen_frames_late_are_found_with_their_offset() {
        let m = motion(400);
        let (left, right) = (&m[15..], &m[..m.len() - 15]);
        let v = verdict(left, right).expect("out of step");
        assert_eq!(v.offset, 15, "{v}");
        assert!(v.correlation > 0.99 && 1.0 - v.in_step > MIN_RESIDUAL_RATIO * (1.0 - v.correlation), "{v}");
        assert_eq!(v.frames, (0, WINDOW - 1));
        assert!(v.to_string().contains("15 frames later"), "{v}");
        let v = verdict(right, left).expect("out of step the other way");
        assert_eq!(v.offset, -15, "{v}");
        assert!(v.to_string().contains("15 frames earlier"), "{v}");
    }

    /// The verdict of a recording of `left.len()` frames: on its windows, else at its end.
    fn verdict_with_end(left: &[f32], right: &[f32]) -> Option<OutOfStep> {
        let mut check = PairingCheck::default();
        let on_windows = left.iter().zip(right).enumerate().filter_map(|(i, (l, r))| check.push(i, *l, *r)).next();
        on_windows.or_else(|| check.finish())
    }

    #[test]
    fn a_recording_shorter_than_the_window_is_judged_at_its_end() {
        let m = motion(200);
        for n in [MIN_FRAMES, 90, WINDOW - 1] {
            let (left, right) = (&m[15..15 + n], &m[..n]);
            assert_eq!(verdict(left, right), None, "{n} frames: no window is full");
            let v = verdict_with_end(left, right).unwrap_or_else(|| panic!("{n} frames: out of step at the end"));
            assert_eq!((v.offset, v.frames), (15, (0, n - 1)), "{n} frames: {v}");
            assert_eq!(verdict_with_end(&m[..n], &m[..n]), None, "{n} frames in step");
        }
        let n = MIN_FRAMES - 1;
        assert_eq!(verdict_with_end(&m[15..15 + n], &m[..n]), None, "too short to judge");
        // Offsets up to a quarter of the frames are looked for: a larger one is named as that many or more.
        let n = 80;
        let v = verdict_with_end(&m[25..25 + n], &m[..n]).expect("25 frames of 80 out of step");
        assert_eq!(v.offset, 20, "{v}");
        assert!(v.to_string().contains("20 or more frames later"), "{v}");
    }

    #[test]
    fn a_recording_checked_on_its_windows_gets_no_second_verdict_at_its_end() {
        let m = motion(400);
        let mut check = PairingCheck::default();
        let (left, right) = (&m[15..], &m[..m.len() - 15]);
        let found = left.iter().zip(right).enumerate().filter_map(|(i, (l, r))| check.push(i, *l, *r)).count();
        assert!(found > 0, "out of step on its windows");
        assert_eq!(check.finish(), None);
    }

    /// A motion that changes from frame to frame (a block turned by jerks), with a little
    /// noise of each camera's own (`camera` picks it).
    fn jerky(n: usize, camera: u32) -> Vec<f32> {
        let hash = |t: u32| (t.wrapping_mul(2_654_435_761) >> 16) % 1000;
        (0..n as u32).map(|t| 2.0 + hash(t) as f32 * 0.003 + hash(t ^ (camera << 20)) as f32 * 0.0002).collect()
    }

    #[test]
    fn one_frame_out_of_step_is_found_where_the_motion_changes_from_frame_to_frame() {
        let (l, r) = (jerky(401, 1), jerky(401, 2));
        assert_eq!(verdict(&l[..400], &r[..400]), None, "in step");
        // Each right image shows what the left one showed a frame before.
        let v = verdict(&l[1..], &r[..400]).expect("one frame out of step");
        assert_eq!(v.offset, 1, "{v}");
        assert!(v.to_string().contains("1 frame later"), "{v}");
    }

    #[test]
    fn a_smooth_motion_in_step_with_each_cameras_own_noise_gives_no_verdict() {
        // Over a frame the smooth motion changes less than the noise the two cameras do not
        // share: the series agree about as well one frame apart as in step, so nothing is claimed.
        let m = motion(400);
        for noise in [0.05f32, 0.2, 0.5] {
            let (l, r): (Vec<f32>, Vec<f32>) = m
                .iter()
                .zip(jerky(400, 1).iter().zip(jerky(400, 2)))
                .map(|(v, (a, b))| (v + noise * (a - 3.5), v + noise * (b - 3.5)))
                .unzip();
            assert_eq!(verdict(&l, &r), None, "noise {noise}");
        }
    }

    #[test]
    fn a_still_scene_gives_no_verdict() {
        let noise: Vec<f32> =
            (0..400u32).map(|t| 2.0 + ((t.wrapping_mul(2_654_435_761) >> 20) % 7) as f32 * 0.01).collect();
        let other: Vec<f32> = noise.iter().rev().copied().collect();
        assert_eq!(verdict(&noise, &other), None);
        assert_eq!(verdict(&[1.0; 400], &[1.0; 400]), None);
    }

    #[test]
    fn the_meter_measures_the_change_between_frames() {
        let mut meter = MotionMeter::default();
        let dark = RgbImage::from_pixel(16, 8, image::Rgb([10, 10, 10]));
        let light = RgbImage::from_pixel(16, 8, image::Rgb([40, 40, 40]));
        assert_eq!(meter.measure(&dark), 0.0);
        assert_eq!(meter.measure(&light), 30.0);
        assert_eq!(meter.measure(&light), 0.0);
        assert_eq!(meter.measure(&RgbImage::new(8, 8)), 0.0, "a new size starts over");
    }
}
