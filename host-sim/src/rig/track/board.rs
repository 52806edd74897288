//! The sequence as a camera-controller board: a reader thread decodes the PNGs ahead of the
//! tracker (bounded channel) and hands their pixels over in the chosen [`SensorPixels`] format
//! (8-bit RGB as recorded, or RGB565 as a board's sensor delivers them; either way the tracker
//! computes the hue of the pixels it samples only);
//! [`SequenceBoard`] hands them to the core's loop with the joint state interpolated at each
//! capture time, and records every published estimate.

use std::marker::PhantomData;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::thread::JoinHandle;

use evorec_core::board::{CameraController, Error as BoardError, ErrorKind, ErrorType, FrameInfo};
use evorec_core::camera::Pinhole;
use evorec_core::image::{PixelFormat, Rgb565};
use evorec_core::pose::Psi;
use evorec_core::status::Status;
use evorec_core::tracker::{Estimate, JointSample};
use image::RgbImage;
use indicatif::ProgressBar;

use super::hue_table::Rgb888Table;
use super::out_of_step::{MotionMeter, OutOfStep, PairingCheck};
use crate::recording::sequence::{self, FrameRow, JointTable, SequenceError};
use crate::sim::render;

/// Frames decoded ahead of the tracker at most.
pub const READ_AHEAD: usize = 8;

/// A pixel format the tracker can read a decoded PNG in.
pub trait SensorPixels: PixelFormat {
    /// The bytes of `img` in this format, row-major, no padding.
    fn pixels(img: &RgbImage) -> Vec<u8>;

    /// Whatever the format builds before its first pixel is read (nothing by default).
    fn prepare() {}
}

/// The PNG's own 8-bit colour: the hue of a sampled pixel is exact, looked up in the table of
/// every colour (the default of `evorec track`).
impl SensorPixels for Rgb888Table {
    fn pixels(img: &RgbImage) -> Vec<u8> {
        img.as_raw().clone()
    }

    fn prepare() {
        super::hue_table::build();
    }
}

/// The board's path: each channel truncated to RGB565, as a camera sensor delivers it.
impl SensorPixels for Rgb565 {
    fn pixels(img: &RgbImage) -> Vec<u8> {
        render::rgb565_image(img)
    }
}

/// A decoded frame pair.
pub struct Decoded {
    /// Position in `frames.csv` (0-based).
    pub i: usize,
    /// Left image in the board's [`SensorPixels`] format.
    pub left: Vec<u8>,
    /// Right image, same format.
    pub right: Vec<u8>,
    /// The RGB images, kept for frames that get an overlay.
    pub rgb: Option<(RgbImage, RgbImage)>,
    /// The change since the previous frame in the left and the right image
    /// ([`super::out_of_step::MotionMeter`]).
    pub motion: [f32; 2],
}

/// Where the tracker's frames come from: RGB image pairs, in frame order (the PNGs of a
/// sequence directory, [`SequenceFiles`], or the images of a ROS 2 bag, `bag::source::BagFrames`).
pub trait FrameSource: Send {
    /// Hands frames `0..end` (positions in `frames.csv`) to `emit` in order, until `emit`
    /// returns `false`.
    ///
    /// # Errors
    /// The first frame that cannot be read, naming its file (and topic and message).
    fn stream(
        self: Box<Self>,
        end: usize,
        emit: &mut dyn FnMut(usize, RgbImage, RgbImage) -> bool,
    ) -> Result<(), SequenceError>;
}

/// The PNGs of a sequence directory, each pair decoded in parallel.
pub struct SequenceFiles {
    /// `frames.csv`.
    pub frames: Arc<Vec<FrameRow>>,
    /// The left and right cameras (for the image sizes).
    pub cams: (Pinhole, Pinhole),
}

impl FrameSource for SequenceFiles {
    fn stream(
        self: Box<Self>,
        end: usize,
        emit: &mut dyn FnMut(usize, RgbImage, RgbImage) -> bool,
    ) -> Result<(), SequenceError> {
        for (i, f) in self.frames.iter().enumerate().take(end) {
            let (l, r) = sequence::decode_pair(f, &self.cams.0, &self.cams.1)?;
            if !emit(i, l, r) {
                break;
            }
        }
        Ok(())
    }
}

/// Starts the reader thread for frames `0..end` of `source`; `keep_rgb(i)` says which frames
/// keep their RGB images. The pixels are converted to `F` on this thread. The thread stops at
/// the first error (sent as the last item) or when the receiver is dropped.
pub fn spawn_reader<F: SensorPixels>(
    source: Box<dyn FrameSource>,
    end: usize,
    keep_rgb: Arc<dyn Fn(usize) -> bool + Send + Sync>,
) -> (Receiver<Result<Decoded, SequenceError>>, JoinHandle<()>) {
    let (tx, rx): (SyncSender<_>, _) = sync_channel(READ_AHEAD);
    let handle = std::thread::spawn(move || {
        let mut meters = [MotionMeter::default(), MotionMeter::default()];
        let mut emit = |i: usize, l: RgbImage, r: RgbImage| {
            let (left, right) = rayon::join(|| F::pixels(&l), || F::pixels(&r));
            let motion = [meters[0].measure(&l), meters[1].measure(&r)];
            let rgb = keep_rgb(i).then_some((l, r));
            tx.send(Ok(Decoded { i, left, right, rgb, motion })).is_ok()
        };
        if let Err(e) = source.stream(end, &mut emit) {
            let _ = tx.send(Err(e));
        }
    });
    (rx, handle)
}

/// Why the sequence board stopped.
#[derive(Debug, Clone, PartialEq)]
pub enum SeqBoardError {
    /// All frames were delivered.
    EndOfStream,
    /// A PNG could not be decoded.
    Decode(SequenceError),
    /// The reader thread stopped without saying why.
    ReaderGone,
    /// The caller's buffers are smaller than a frame.
    BufferTooSmall,
    /// The images of the two cameras do not belong together.
    OutOfStep(OutOfStep),
}

impl BoardError for SeqBoardError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::EndOfStream => ErrorKind::EndOfStream,
            Self::Decode(_) | Self::ReaderGone | Self::BufferTooSmall | Self::OutOfStep(_) => ErrorKind::Other,
        }
    }
}

impl std::fmt::Display for SeqBoardError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::EndOfStream => f.write_str("end of the sequence"),
            Self::Decode(e) => write!(f, "{e}"),
            Self::ReaderGone => f.write_str("the image reader thread stopped"),
            Self::BufferTooSmall => f.write_str("frame buffers are too small"),
            Self::OutOfStep(v) => write!(f, "{v}"),
        }
    }
}

/// One tracked frame.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackedFrame {
    /// Position in `frames.csv`.
    pub i: usize,
    /// Joint positions at the capture time (as given to the tracker).
    pub q: Vec<f32>,
    /// Joint velocities at the capture time.
    pub qd: Vec<f32>,
    /// The estimate.
    pub estimate: Psi,
    /// Its fitness.
    pub fitness: f32,
    /// The best pose's fitness in the left and the right camera (`Estimate::camera_fitness`).
    pub camera_fitness: [f32; 2],
    /// The tracker's status after this frame.
    pub status: Status,
    /// The pose the tracker's target filter is fed with ([`Estimate::target_measurement`]).
    pub target_measurement: Psi,
}

/// The board over a sequence, delivering frames in pixel format `F`.
pub struct SequenceBoard<'a, F> {
    frames: &'a [FrameRow],
    joints: &'a JointTable,
    size: (u16, u16),
    rx: Receiver<Result<Decoded, SequenceError>>,
    first: Option<Decoded>,
    next: usize,
    end: usize,
    current: Option<(usize, Vec<f32>, Vec<f32>)>,
    /// Published frames, in order.
    pub tracked: Vec<TrackedFrame>,
    /// RGB images kept for overlays: (position in frames.csv, left, right).
    pub kept: Vec<(usize, RgbImage, RgbImage)>,
    progress: Option<ProgressBar>,
    /// The check of the stereo pairing, unless switched off.
    pairing: Option<PairingCheck>,
    format: PhantomData<F>,
}

impl<'a, F> SequenceBoard<'a, F> {
    /// A board delivering frames `0..end`: `first` is frame 0, already decoded, and `rx` the
    /// reader thread's channel for the others. With `check_pairing` it stops with
    /// [`SeqBoardError::OutOfStep`] when the two cameras' images do not belong together.
    pub fn new(
        seq: &'a sequence::Sequence,
        first: Decoded,
        rx: Receiver<Result<Decoded, SequenceError>>,
        end: usize,
        progress: Option<ProgressBar>,
        check_pairing: bool,
    ) -> Self {
        Self {
            frames: &seq.frames,
            joints: &seq.joints,
            size: (seq.rig.right.width(), seq.rig.right.height()),
            rx,
            first: Some(first),
            next: 0,
            end,
            current: None,
            tracked: Vec::with_capacity(end),
            kept: Vec::new(),
            progress,
            pairing: check_pairing.then(PairingCheck::default),
            format: PhantomData,
        }
    }

    /// The published frames and the kept RGB images. The rest goes, the reader's channel
    /// with it, so a reader still waiting to send a frame stops.
    pub fn into_outputs(self) -> (Vec<TrackedFrame>, Vec<(usize, RgbImage, RgbImage)>) {
        (self.tracked, self.kept)
    }

    fn capture_time_us(&self, i: usize) -> u64 {
        // Relative to the first frame, so recordings stamped with epoch times work too.
        ((self.frames[i].t_s - self.frames[0].t_s) * 1e6).round().max(0.0) as u64
    }
}

impl<F> ErrorType for SequenceBoard<'_, F> {
    type Error = SeqBoardError;
}

impl<const DOF: usize, F: SensorPixels> CameraController<DOF> for SequenceBoard<'_, F> {
    type Format = F;

    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, SeqBoardError> {
        if self.next >= self.end {
            // A recording too short for the pairing check's window is judged as a whole here.
            if let Some(v) = self.pairing.as_mut().and_then(PairingCheck::finish) {
                return Err(SeqBoardError::OutOfStep(v));
            }
            return Err(SeqBoardError::EndOfStream);
        }
        let d = match self.first.take() {
            Some(d) => d,
            None => self.rx.recv().map_err(|_| SeqBoardError::ReaderGone)?.map_err(SeqBoardError::Decode)?,
        };
        let n = F::BYTES_PER_PIXEL * usize::from(self.size.0) * usize::from(self.size.1);
        if left.len() < n || right.len() < n || d.left.len() != n || d.right.len() != n {
            return Err(SeqBoardError::BufferTooSmall);
        }
        left[..n].copy_from_slice(&d.left);
        right[..n].copy_from_slice(&d.right);
        if let Some(v) = self.pairing.as_mut().and_then(|c| c.push(d.i, d.motion[0], d.motion[1])) {
            return Err(SeqBoardError::OutOfStep(v));
        }
        if let Some((l, r)) = d.rgb {
            self.kept.push((d.i, l, r));
        }
        let state = self.joints.at(self.frames[d.i].t_s);
        let (q, qd) = match state {
            Some(s) if s.q.len() == DOF && s.qd.len() == DOF => {
                (s.q.iter().map(|v| *v as f32).collect(), s.qd.iter().map(|v| *v as f32).collect())
            }
            // Checked at load time; a NaN sample is refused by the tracker, not used.
            _ => (vec![f32::NAN; DOF], vec![f32::NAN; DOF]),
        };
        self.current = Some((d.i, q, qd));
        self.next += 1;
        if let Some(p) = &self.progress {
            p.inc(1);
        }
        Ok(FrameInfo {
            sequence: u32::try_from(self.frames[d.i].index).unwrap_or(u32::MAX),
            capture_time_us: self.capture_time_us(d.i),
            width: self.size.0,
            height: self.size.1,
        })
    }

    fn joint_sample(&mut self) -> Result<JointSample<DOF>, SeqBoardError> {
        let (i, q, qd) = self.current.as_ref().ok_or(SeqBoardError::ReaderGone)?;
        let arr = |v: &[f32]| std::array::from_fn(|k| v.get(k).copied().unwrap_or(f32::NAN));
        Ok(JointSample { q: arr(q), qd: arr(qd), time_us: self.capture_time_us(*i) })
    }

    fn publish(&mut self, _frame: &FrameInfo, estimate: &Estimate) -> Result<(), SeqBoardError> {
        if let Some((i, q, qd)) = self.current.take() {
            self.tracked.push(TrackedFrame {
                i,
                q,
                qd,
                estimate: estimate.psi,
                fitness: estimate.fitness,
                camera_fitness: estimate.camera_fitness,
                status: estimate.status,
                target_measurement: estimate.target_measurement,
            });
        }
        Ok(())
    }
}
