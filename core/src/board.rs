//! The camera-controller board: what a board gives the tracker and takes from it, and the
//! one loop that drives a tracker from any board.
//!
//! A board (the simulator's virtual one, the firmware's semihosting link, a real MCU with two
//! DCMI cameras and a joint-state bus) implements [`CameraController`]:
//!
//! - [`CameraController::next_frame`] blocks until the next synchronised stereo pair, writes
//!   its pixels in the board's [`CameraController::Format`] (hue bytes, or the sensor's raw
//!   RGB565) into the caller's two buffers (row-major, `width·height·BYTES_PER_PIXEL` bytes
//!   each) and returns its [`FrameInfo`] (size, sequence number, capture time). Frames arrive in
//!   capture order; a board that dropped frames says so through the sequence number.
//! - [`CameraController::joint_sample`] returns the newest joint sample `q, q̇` with its time;
//!   the loop asks for it right after each frame.
//! - [`CameraController::publish`] takes the estimate for a frame. It is called once per
//!   accepted frame, in frame order, before the next `next_frame`.
//!
//! Errors follow embedded-hal's pattern: a board's error type implements [`Error`], whose
//! [`ErrorKind`] generic code can act on ([`ErrorKind::EndOfStream`] ends [`run`] normally).

use crate::image::{Image, PixelFormat};
use crate::tracker::{Estimate, JointSample, NoProbe, PhaseProbe, StepError, StereoFrame, Tracker};

/// What went wrong on a board, for generic code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ErrorKind {
    /// Nothing arrived in time.
    Timeout,
    /// A frame was overwritten before it was read.
    FrameOverrun,
    /// The link to the cameras or the joint controller is down.
    LinkDown,
    /// Malformed data on the link (bad magic, CRC, size).
    Protocol,
    /// The source has no more frames (a recording or a simulation ended).
    EndOfStream,
    /// Anything else.
    Other,
}

/// A board error.
pub trait Error: core::fmt::Debug {
    /// The generic kind of this error.
    fn kind(&self) -> ErrorKind;
}

impl Error for core::convert::Infallible {
    fn kind(&self) -> ErrorKind {
        match *self {}
    }
}

impl Error for ErrorKind {
    fn kind(&self) -> ErrorKind {
        *self
    }
}

/// The error type of a board.
pub trait ErrorType {
    /// Error of every method.
    type Error: Error;
}

impl<T: ErrorType + ?Sized> ErrorType for &mut T {
    type Error = T::Error;
}

/// Size, order and time of a frame pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameInfo {
    /// Frame sequence number (consecutive unless frames were dropped).
    pub sequence: u32,
    /// Capture time of both images (µs, the board's clock).
    pub capture_time_us: u64,
    /// Image width (both images).
    pub width: u16,
    /// Image height (both images).
    pub height: u16,
}

/// A camera-controller board with `DOF` arm joints.
pub trait CameraController<const DOF: usize>: ErrorType {
    /// The pixel format of the frames ([`crate::image::Hue`] or [`crate::image::Rgb565`]).
    type Format: PixelFormat;

    /// Waits for the next stereo pair and writes it into `left` and `right`
    /// (`width · height · Format::BYTES_PER_PIXEL` bytes each).
    ///
    /// # Errors
    /// The board's error; [`ErrorKind::EndOfStream`] when there are no more frames.
    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, Self::Error>;

    /// The newest joint sample.
    ///
    /// # Errors
    /// The board's error.
    fn joint_sample(&mut self) -> Result<JointSample<DOF>, Self::Error>;

    /// Publishes the estimate for `frame`.
    ///
    /// # Errors
    /// The board's error.
    fn publish(&mut self, frame: &FrameInfo, estimate: &Estimate) -> Result<(), Self::Error>;
}

impl<T: CameraController<DOF> + ?Sized, const DOF: usize> CameraController<DOF> for &mut T {
    type Format = T::Format;
    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, Self::Error> {
        T::next_frame(self, left, right)
    }
    fn joint_sample(&mut self) -> Result<JointSample<DOF>, Self::Error> {
        T::joint_sample(self)
    }
    fn publish(&mut self, frame: &FrameInfo, estimate: &Estimate) -> Result<(), Self::Error> {
        T::publish(self, frame, estimate)
    }
}

/// What [`run`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct LoopStats {
    /// Frames received.
    pub frames: u32,
    /// Estimates published.
    pub published: u32,
    /// Frames the tracker refused (bad size, bad joint sample, bad time step).
    pub rejected: u32,
}

/// Drives `tracker` from `board` for at most `max_frames` frames, or until the board reports
/// [`ErrorKind::EndOfStream`]: frame → joint sample → one generation → publish.
///
/// `dt` is the capture-time difference to the last accepted frame (0 for the first). A frame
/// the tracker refuses is counted, logged and skipped; the tracker is unchanged by it. A frame
/// refused because the gap since the last accepted one is longer than
/// [`Tuning::max_dt_s`](crate::tuning::Tuning::max_dt_s) (frames dropped under
/// overload, a stalled camera) becomes the new time base, so the next frame is tracked again
/// instead of every later frame being refused for an ever longer gap.
///
/// # Errors
/// Any board error other than `EndOfStream`.
pub fn run<B, const DOF: usize, const P: usize, const G: usize>(
    board: &mut B,
    tracker: &mut Tracker<DOF, P, G>,
    left_buf: &mut [u8],
    right_buf: &mut [u8],
    max_frames: u32,
) -> Result<LoopStats, B::Error>
where
    B: CameraController<DOF> + ?Sized,
{
    run_probed(board, tracker, left_buf, right_buf, max_frames, &mut NoProbe)
}

/// [`run`] with a [`PhaseProbe`] told the phases of every generation.
///
/// # Errors
/// As [`run`].
pub fn run_probed<B, const DOF: usize, const P: usize, const G: usize>(
    board: &mut B,
    tracker: &mut Tracker<DOF, P, G>,
    left_buf: &mut [u8],
    right_buf: &mut [u8],
    max_frames: u32,
    probe: &mut impl PhaseProbe,
) -> Result<LoopStats, B::Error>
where
    B: CameraController<DOF> + ?Sized,
{
    let mut stats = LoopStats::default();
    let mut last_time: Option<u64> = None;
    for _ in 0..max_frames {
        let info = match board.next_frame(left_buf, right_buf) {
            Ok(info) => info,
            Err(e) if e.kind() == ErrorKind::EndOfStream => break,
            Err(e) => return Err(e),
        };
        stats.frames += 1;
        let joints = board.joint_sample()?;
        let dt_s = match last_time {
            Some(t0) => info.capture_time_us.saturating_sub(t0) as f32 * 1e-6,
            None => 0.0,
        };
        let left = Image::<_, B::Format>::new_checked(&left_buf[..], info.width, info.height);
        let right = Image::<_, B::Format>::new_checked(&right_buf[..], info.width, info.height);
        let (left, right) = match (left, right) {
            (Ok(l), Ok(r)) => (l, r),
            (Err(e), _) | (_, Err(e)) => {
                log::warn!("frame {} refused: {}", info.sequence, e);
                stats.rejected += 1;
                continue;
            }
        };
        let frame = StereoFrame { left, right };
        match tracker.step_probed(&frame, &joints, dt_s, probe) {
            Ok(estimate) => {
                board.publish(&info, &estimate)?;
                stats.published += 1;
                last_time = Some(info.capture_time_us);
            }
            Err(e) => {
                log::warn!("frame {} refused: {}", info.sequence, e);
                stats.rejected += 1;
                if matches!(e, StepError::BadDt(_)) {
                    last_time = Some(info.capture_time_us);
                }
            }
        }
    }
    Ok(stats)
}
