//! The firmware's board: a [`CameraController`] whose frames and joint samples arrive over the
//! link and whose estimates go back, and [`serve`], the whole firmware conversation
//! (`CONFIG` → `ACK`, frames through the core's [`board::run`], `END` → `DONE`).
//!
//! Both are generic over the link's [`ByteSource`]/[`ByteSink`], so the same code runs on the
//! Cortex-M4 over semihosting FIFOs and in host unit tests over byte buffers.
//!
//! Lock-step guarantee: every `FRAME` gets exactly one answer before the next message is
//! read, an `ESTIMATE` from [`CameraController::publish`] or, when the tracker refused the
//! frame (the core's loop then skips `publish`), a `REJECTED` sent by the next
//! [`CameraController::next_frame`] (or by [`serve`] at `END`).

use evorec_core::Tracker;
use evorec_core::board::{self, CameraController, ErrorKind, ErrorType, FrameInfo, LoopStats};
use evorec_core::tracker::{Estimate, JointSample};

use crate::protocol::{
    ByteSink, ByteSource, DOF, DecodeError, Done, Envelope, ErrorCode, Message, MsgType, ReadError, WriteError,
    read_message, write_message,
};
use crate::setup::SetupError;

/// A board error: the link's error `E`, or a protocol problem.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum LinkError<E> {
    /// Reading or writing the link failed.
    Link(E),
    /// A malformed message arrived.
    Decode(DecodeError),
    /// A valid message of the wrong type arrived.
    Unexpected(MsgType),
    /// The host sent `END`.
    EndOfStream,
    /// A frame to send has images of the wrong size (host-side misuse).
    ImageSize,
}

impl<E> LinkError<E> {
    /// The code the firmware reports in an `ERROR` message.
    pub fn code(&self) -> ErrorCode {
        match self {
            Self::Link(_) => ErrorCode::Link,
            Self::Decode(_) => ErrorCode::Decode,
            Self::Unexpected(_) => ErrorCode::Unexpected,
            Self::EndOfStream | Self::ImageSize => ErrorCode::Other,
        }
    }
}

impl<E> From<ReadError<E>> for LinkError<E> {
    fn from(e: ReadError<E>) -> Self {
        match e {
            ReadError::Link(e) => Self::Link(e),
            ReadError::Decode(e) => Self::Decode(e),
        }
    }
}

impl<E> From<WriteError<E>> for LinkError<E> {
    fn from(e: WriteError<E>) -> Self {
        match e {
            WriteError::Link(e) => Self::Link(e),
            WriteError::ImageSize { .. } => Self::ImageSize,
        }
    }
}

impl<E: core::fmt::Debug> board::Error for LinkError<E> {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::Link(_) => ErrorKind::LinkDown,
            Self::Decode(_) | Self::Unexpected(_) => ErrorKind::Protocol,
            Self::EndOfStream => ErrorKind::EndOfStream,
            Self::ImageSize => ErrorKind::Other,
        }
    }
}

impl<E: core::fmt::Debug> core::fmt::Display for LinkError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Link(e) => write!(f, "link: {e:?}"),
            Self::Decode(e) => write!(f, "protocol: {e}"),
            Self::Unexpected(t) => write!(f, "unexpected {t:?} message"),
            Self::EndOfStream => f.write_str("end of stream"),
            Self::ImageSize => f.write_str("frame images do not match width x height"),
        }
    }
}

/// The link board: receives frames, answers with estimates.
#[derive(Debug)]
pub struct LinkBoard<R, W> {
    rx: R,
    tx: W,
    joints: JointSample<DOF>,
    /// The last frame received and not answered yet: (sequence, capture time).
    pending: Option<(u32, u64)>,
}

impl<R, W, E> LinkBoard<R, W>
where
    R: ByteSource<Error = E>,
    W: ByteSink<Error = E>,
{
    /// A board over the two ends of a link.
    pub fn new(rx: R, tx: W) -> Self {
        Self { rx, tx, joints: JointSample { q: [0.0; DOF], qd: [0.0; DOF], time_us: 0 }, pending: None }
    }

    /// Sends one message.
    ///
    /// # Errors
    /// The link's error.
    pub fn send(&mut self, env: &Envelope<'_>) -> Result<(), LinkError<E>> {
        Ok(write_message(&mut self.tx, env)?)
    }

    /// Answers a received but unpublished frame with `REJECTED`.
    ///
    /// # Errors
    /// The link's error.
    pub fn answer_pending(&mut self) -> Result<(), LinkError<E>> {
        if let Some((sequence, capture_time_us)) = self.pending.take() {
            self.send(&Envelope { sequence, capture_time_us, message: Message::Rejected })?;
        }
        Ok(())
    }

    /// The two ends of the link.
    pub fn into_inner(self) -> (R, W) {
        (self.rx, self.tx)
    }
}

impl<R, W, E> ErrorType for LinkBoard<R, W>
where
    R: ByteSource<Error = E>,
    W: ByteSink<Error = E>,
    E: core::fmt::Debug,
{
    type Error = LinkError<E>;
}

impl<R, W, E> CameraController<DOF> for LinkBoard<R, W>
where
    R: ByteSource<Error = E>,
    W: ByteSink<Error = E>,
    E: core::fmt::Debug,
{
    type Format = evorec_core::image::Hue;

    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, Self::Error> {
        self.answer_pending()?;
        let env = read_message(&mut self.rx, left, right)?;
        match env.message {
            Message::Frame(f) => {
                self.joints = f.joints;
                self.pending = Some((env.sequence, env.capture_time_us));
                Ok(FrameInfo {
                    sequence: env.sequence,
                    capture_time_us: env.capture_time_us,
                    width: f.width,
                    height: f.height,
                })
            }
            Message::End => Err(LinkError::EndOfStream),
            other => Err(LinkError::Unexpected(other.kind())),
        }
    }

    fn joint_sample(&mut self) -> Result<JointSample<DOF>, Self::Error> {
        Ok(self.joints)
    }

    fn publish(&mut self, frame: &FrameInfo, estimate: &Estimate) -> Result<(), Self::Error> {
        self.pending = None;
        self.send(&Envelope {
            sequence: frame.sequence,
            capture_time_us: frame.capture_time_us,
            message: Message::Estimate(*estimate),
        })
    }
}

/// Why [`serve`] stopped early.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ServeError<E> {
    /// The link or the protocol failed (an `ERROR` was sent if the link still worked).
    Link(LinkError<E>),
    /// The `CONFIG` gave no tracker (its code was sent in the `ACK`).
    Setup(SetupError),
}

impl<E> From<LinkError<E>> for ServeError<E> {
    fn from(e: LinkError<E>) -> Self {
        Self::Link(e)
    }
}

impl<E: core::fmt::Debug> core::fmt::Display for ServeError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Link(e) => write!(f, "{e}"),
            Self::Setup(e) => write!(f, "setup: {e}"),
        }
    }
}

/// Stack use reported in `DONE`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StackUsage {
    /// High-water mark (bytes).
    pub used_bytes: u32,
    /// Size of the stack region (bytes).
    pub size_bytes: u32,
}

/// The firmware's conversation: waits for `CONFIG`, builds the tracker into `slot` and
/// answers `ACK`, runs [`board::run`] over the link until `END`, answers `DONE` with the loop's
/// counts and `stack()` (called after the last frame) and returns the counts.
///
/// `left`/`right` receive the frames (their length bounds the accepted image size).
///
/// # Errors
/// [`ServeError::Setup`] after a refused `CONFIG` (its `ACK` carries the code);
/// [`ServeError::Link`] for link or protocol failures, after a best-effort `ERROR` message.
pub fn serve<R, W, E, const P: usize, const G: usize>(
    rx: R,
    tx: W,
    slot: &mut Option<Tracker<DOF, P, G>>,
    left: &mut [u8],
    right: &mut [u8],
    stack: impl FnOnce() -> StackUsage,
) -> Result<LoopStats, ServeError<E>>
where
    R: ByteSource<Error = E>,
    W: ByteSink<Error = E>,
    E: core::fmt::Debug,
{
    let mut board = LinkBoard::new(rx, tx);
    let result = serve_on(&mut board, slot, left, right, stack);
    if let Err(ServeError::Link(e)) = &result
        && !matches!(e, LinkError::Link(_))
    {
        // Best effort: the link itself still works, tell the host why we stop.
        let _ = board.send(&Envelope::bare(Message::Error(e.code() as u32)));
    }
    result
}

fn serve_on<R, W, E, const P: usize, const G: usize>(
    board: &mut LinkBoard<R, W>,
    slot: &mut Option<Tracker<DOF, P, G>>,
    left: &mut [u8],
    right: &mut [u8],
    stack: impl FnOnce() -> StackUsage,
) -> Result<LoopStats, ServeError<E>>
where
    R: ByteSource<Error = E>,
    W: ByteSink<Error = E>,
    E: core::fmt::Debug,
{
    let env = read_message(&mut board.rx, left, right).map_err(LinkError::from)?;
    let setup = match env.message {
        Message::Config(setup) => setup,
        other => return Err(LinkError::Unexpected(other.kind()).into()),
    };
    let tracker = match setup.build_tracker_in(slot) {
        Ok(t) => t,
        Err(e) => {
            log::error!("CONFIG refused: {e}");
            board.send(&Envelope::bare(Message::Ack(e.code())))?;
            return Err(ServeError::Setup(e));
        }
    };
    board.send(&Envelope::bare(Message::Ack(0)))?;
    log::info!(
        "tracker ready: {}x{} px, population {P}, grid {G}, feedforward {:?}",
        setup.width,
        setup.height,
        setup.feedforward
    );
    let stats = board::run(board, tracker, setup.feedforward, left, right, u32::MAX)?;
    board.answer_pending()?;
    let s = stack();
    board.send(&Envelope::bare(Message::Done(Done {
        frames: stats.frames,
        published: stats.published,
        rejected: stats.rejected,
        stack_used_bytes: s.used_bytes,
        stack_size_bytes: s.size_bytes,
    })))?;
    Ok(stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::tests::sample_setup;
    use crate::protocol::{Frame, SliceSource, Truncated};
    use evorec_core::config::NO_HUE;
    use std::vec;
    use std::vec::Vec;

    /// A sink that collects everything (never fails).
    #[derive(Default)]
    struct VecSink(Vec<u8>);

    impl ByteSink for VecSink {
        type Error = Truncated;
        fn write_all(&mut self, bytes: &[u8]) -> Result<(), Truncated> {
            self.0.extend_from_slice(bytes);
            Ok(())
        }
    }

    fn encode(env: &Envelope<'_>) -> Vec<u8> {
        let mut s = VecSink::default();
        write_message(&mut s, env).unwrap();
        s.0
    }

    fn frame_env<'a>(seq: u32, w: u16, h: u16, l: &'a [u8], r: &'a [u8]) -> Envelope<'a> {
        Envelope {
            sequence: seq,
            capture_time_us: u64::from(seq) * 33_333,
            message: Message::Frame(Frame {
                width: w,
                height: h,
                joints: JointSample { q: [0.1; DOF], qd: [0.02; DOF], time_us: u64::from(seq) * 33_333 },
                left: l,
                right: r,
            }),
        }
    }

    fn replies(bytes: &[u8]) -> Vec<Envelope<'static>> {
        let mut src = SliceSource::new(bytes);
        let mut out = Vec::new();
        while !src.remaining().is_empty() {
            out.push(read_message(&mut src, &mut [], &mut []).unwrap());
        }
        out
    }

    #[test]
    fn full_conversation_answers_every_frame_in_order() {
        let setup = sample_setup();
        let n = usize::from(setup.width) * usize::from(setup.height);
        let (l, r) = (vec![NO_HUE; n], vec![NO_HUE; n]);
        let small = vec![NO_HUE; 100];
        let mut input = encode(&Envelope::bare(Message::Config(setup)));
        input.extend(encode(&frame_env(1, setup.width, setup.height, &l, &r)));
        input.extend(encode(&frame_env(2, 10, 10, &small, &small))); // wrong size: refused
        input.extend(encode(&frame_env(3, setup.width, setup.height, &l, &r)));
        input.extend(encode(&frame_env(4, 10, 10, &small, &small))); // refused, answered at END
        input.extend(encode(&Envelope::bare(Message::End)));

        let mut out = VecSink::default();
        let mut slot: Option<Tracker> = None;
        let (mut lb, mut rb) = (vec![0u8; n], vec![0u8; n]);
        let stats = serve(SliceSource::new(&input), &mut out, &mut slot, &mut lb, &mut rb, || StackUsage {
            used_bytes: 1,
            size_bytes: 2,
        })
        .unwrap();
        assert_eq!(stats, LoopStats { frames: 4, published: 2, rejected: 2 });

        let got = replies(&out.0);
        let kinds: Vec<(MsgType, u32)> = got.iter().map(|e| (e.message.kind(), e.sequence)).collect();
        assert_eq!(
            kinds,
            [
                (MsgType::Ack, 0),
                (MsgType::Estimate, 1),
                (MsgType::Rejected, 2),
                (MsgType::Estimate, 3),
                (MsgType::Rejected, 4),
                (MsgType::Done, 0)
            ]
        );
        assert_eq!(got[0].message, Message::Ack(0));
        assert_eq!(got[3].capture_time_us, 3 * 33_333);
        assert!(matches!(got[5].message, Message::Done(Done { frames: 4, published: 2, stack_size_bytes: 2, .. })));

        // The estimates are exactly those of a host tracker built from the same setup.
        let mut host: Tracker = setup.build_tracker().unwrap();
        let frame = evorec_core::StereoFrame {
            left: evorec_core::hue::HueImage::new_checked(&l[..], setup.width, setup.height).unwrap(),
            right: evorec_core::hue::HueImage::new_checked(&r[..], setup.width, setup.height).unwrap(),
        };
        let j = JointSample { q: [0.1; DOF], qd: [0.02; DOF], time_us: 0 };
        let e1 = host.step(&frame, &j, 0.0, setup.feedforward).unwrap();
        // The loop's time step: capture-time difference to the last accepted frame (1 → 3).
        let dt = (3 * 33_333u64 - 33_333) as f32 * 1e-6;
        let e3 = host.step(&frame, &j, dt, setup.feedforward).unwrap();
        assert_eq!(got[1].message, Message::Estimate(e1));
        assert_eq!(got[3].message, Message::Estimate(e3));
    }

    #[test]
    fn refused_config_is_acked_with_its_code() {
        let mut setup = sample_setup();
        setup.fx = -1.0;
        let input = encode(&Envelope::bare(Message::Config(setup)));
        let mut out = VecSink::default();
        let mut slot: Option<Tracker> = None;
        let r = serve(SliceSource::new(&input), &mut out, &mut slot, &mut [], &mut [], StackUsage::default);
        assert!(matches!(r, Err(ServeError::Setup(SetupError::Camera(_)))));
        assert_eq!(replies(&out.0)[0].message, Message::Ack(1));
        assert!(slot.is_none());
    }

    #[test]
    fn frame_before_config_is_a_protocol_error() {
        let l = [0u8; 4];
        let input = encode(&frame_env(1, 2, 2, &l, &l));
        let mut out = VecSink::default();
        let mut slot: Option<Tracker> = None;
        let (mut lb, mut rb) = ([0u8; 4], [0u8; 4]);
        let r = serve(SliceSource::new(&input), &mut out, &mut slot, &mut lb, &mut rb, StackUsage::default);
        assert_eq!(r, Err(ServeError::Link(LinkError::Unexpected(MsgType::Frame))));
        assert_eq!(replies(&out.0)[0].message, Message::Error(ErrorCode::Unexpected as u32));
    }

    #[test]
    fn corrupt_frame_stops_the_loop_with_an_error_message() {
        let setup = sample_setup();
        let n = usize::from(setup.width) * usize::from(setup.height);
        let l = vec![NO_HUE; n];
        let mut input = encode(&Envelope::bare(Message::Config(setup)));
        let mut frame = encode(&frame_env(1, setup.width, setup.height, &l, &l));
        frame[100] ^= 1;
        input.extend(frame);
        let mut out = VecSink::default();
        let mut slot: Option<Tracker> = None;
        let (mut lb, mut rb) = (vec![0u8; n], vec![0u8; n]);
        let r = serve(SliceSource::new(&input), &mut out, &mut slot, &mut lb, &mut rb, StackUsage::default);
        assert!(matches!(r, Err(ServeError::Link(LinkError::Decode(DecodeError::BadCrc { .. })))));
        let got = replies(&out.0);
        assert_eq!(got.last().map(|e| e.message), Some(Message::Error(ErrorCode::Decode as u32)));
        // The corrupt frame is only known as corrupt at its end: it is not answered.
        assert_eq!(got.len(), 2);
    }
}
