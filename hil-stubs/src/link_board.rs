//! The firmware's board: a [`CameraController`] whose frames and joint samples arrive over the
//! link and whose estimates go back, and [`serve`], the whole firmware conversation
//! (`CONFIG` → `ACK`, frames through the core's [`board::run`], `END` → `DONE`).
//!
//! Both are generic over the link's [`ByteSource`]/[`ByteSink`], so the same code runs on the
//! Cortex-M4 over semihosting FIFOs and in host unit tests over byte buffers.
//!
//! Lock-step guarantee: every `FRAME` the board works on gets exactly one answer before the
//! next message is read, an `ESTIMATE` from [`CameraController::publish`] or, when the tracker
//! refused the frame (the core's loop then skips `publish`), a `REJECTED` sent by the next
//! [`CameraController::next_frame`] (or by [`serve`] at `END`).
//!
//! Faults and overload: a damaged message, a frame whose sequence number is not above the
//! last one, a message of a type not expected, and a frame superseded by a newer one
//! ([`FLAG_NEWER_FOLLOWS`]) get no answer; each is counted by reason ([`DropCounts`], reported
//! in `DONE`) and the board reads on. Only a failing link ends the loop early. A superseded
//! frame costs the board little: its header and size are checked, the rest is skipped in bulk
//! without decoding or CRC ([`LinkReader::newest_frames_only`]), so a burst of frames that
//! arrived during a generation does not delay the newest one behind it.

use evorec_core::Tracker;
use evorec_core::board::{self, CameraController, ErrorKind, ErrorType, FrameInfo, LoopStats};
use evorec_core::tracker::{Estimate, JointSample};

use crate::protocol::{
    ByteSink, ByteSource, DOF, DecodeError, Done, DropCounts, Envelope, ErrorCode, FLAG_NEWER_FOLLOWS, LinkReader,
    Message, MsgType, ReadError, WriteError, read_valid_message, write_message,
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
    rx: LinkReader<R>,
    tx: W,
    joints: JointSample<DOF>,
    /// The last frame received and not answered yet: (sequence, capture time).
    pending: Option<(u32, u64)>,
    /// Sequence number of the last valid frame.
    last_sequence: Option<u32>,
    drops: DropCounts,
}

impl<R, W, E> LinkBoard<R, W>
where
    R: ByteSource<Error = E>,
    W: ByteSink<Error = E>,
{
    /// A board over the two ends of a link.
    pub fn new(rx: R, tx: W) -> Self {
        Self {
            rx: LinkReader::newest_frames_only(rx),
            tx,
            joints: JointSample { q: [0.0; DOF], qd: [0.0; DOF], time_us: 0 },
            pending: None,
            last_sequence: None,
            drops: DropCounts::default(),
        }
    }

    /// Messages dropped so far, by reason.
    pub fn drops(&self) -> DropCounts {
        self.drops
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

    /// The two ends of the link (bytes read but not decoded yet are lost).
    pub fn into_inner(self) -> (R, W) {
        (self.rx.into_inner(), self.tx)
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
    type Format = crate::protocol::LinkFormat;

    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, Self::Error> {
        self.answer_pending()?;
        loop {
            let drops = &mut self.drops;
            let env = read_valid_message(&mut self.rx, &mut *left, &mut *right, |e| drops.count(&e))
                .map_err(LinkError::Link)?;
            let f = match env.message {
                Message::Frame(f) => f,
                Message::End => return Err(LinkError::EndOfStream),
                _ => {
                    self.drops.unexpected = self.drops.unexpected.saturating_add(1);
                    continue;
                }
            };
            if self.last_sequence.is_some_and(|s| env.sequence <= s) {
                self.drops.sequence = self.drops.sequence.saturating_add(1);
                continue;
            }
            self.last_sequence = Some(env.sequence);
            if self.rx.last_flags() & FLAG_NEWER_FOLLOWS != 0 {
                self.drops.superseded = self.drops.superseded.saturating_add(1);
                continue;
            }
            self.joints = f.joints;
            self.pending = Some((env.sequence, env.capture_time_us));
            return Ok(FrameInfo {
                sequence: env.sequence,
                capture_time_us: env.capture_time_us,
                width: f.width,
                height: f.height,
            });
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
    let tracker = configure(board, slot, left, right)?;
    let stats = board::run(board, tracker, left, right, u32::MAX)?;
    board.answer_pending()?;
    let s = stack();
    board.send(&Envelope::bare(Message::Done(Done {
        frames: stats.frames,
        published: stats.published,
        rejected: stats.rejected,
        stack_used_bytes: s.used_bytes,
        stack_size_bytes: s.size_bytes,
        drops: board.drops,
    })))?;
    Ok(stats)
}

/// Waits for `CONFIG`, builds the tracker into `slot` and answers `ACK`. Out of line, so that
/// the configuration, the tracker's construction and their log lines are off the stack while
/// the frames are tracked (the link path's stack high-water mark).
#[inline(never)]
fn configure<'s, R, W, E, const P: usize, const G: usize>(
    board: &mut LinkBoard<R, W>,
    slot: &'s mut Option<Tracker<DOF, P, G>>,
    left: &mut [u8],
    right: &mut [u8],
) -> Result<&'s mut Tracker<DOF, P, G>, ServeError<E>>
where
    R: ByteSource<Error = E>,
    W: ByteSink<Error = E>,
    E: core::fmt::Debug,
{
    let drops = &mut board.drops;
    let env = read_valid_message(&mut board.rx, left, right, |e| drops.count(&e)).map_err(LinkError::Link)?;
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
        setup.tuning.feedforward
    );
    Ok(tracker)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::tests::sample_setup;
    use crate::protocol::{
        BYTES_PER_PIXEL, Frame, LinkReader, SliceSource, Truncated, VecSink, encode_to_vec, read_message,
        write_message_with_flags,
    };
    use evorec_core::image::{RGB565_GREY, Rgb565Image, hue_to_rgb565};
    use std::vec;
    use std::vec::Vec;

    fn encode(env: &Envelope<'_>) -> Vec<u8> {
        encode_to_vec(env).unwrap()
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
        let mut rx = LinkReader::new(SliceSource::new(bytes));
        let mut out = Vec::new();
        while !rx.get_ref().remaining().is_empty() || !rx.buffered().is_empty() {
            out.push(read_message(&mut rx, &mut [], &mut []).unwrap());
        }
        out
    }

    #[test]
    fn full_conversation_answers_every_frame_in_order() {
        let setup = sample_setup();
        let n = usize::from(setup.width) * usize::from(setup.height) * BYTES_PER_PIXEL;
        // Grey left, a band of face-hue pixels on the right.
        let l: Vec<u8> = (0..n / 2).flat_map(|_| RGB565_GREY.to_le_bytes()).collect();
        let r: Vec<u8> =
            (0..n / 2).flat_map(|i| hue_to_rgb565(if i % 160 < 40 { 60 } else { 255 }).to_le_bytes()).collect();
        let small = vec![0u8; 100 * BYTES_PER_PIXEL];
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
            left: Rgb565Image::new_checked(&l[..], setup.width, setup.height).unwrap(),
            right: Rgb565Image::new_checked(&r[..], setup.width, setup.height).unwrap(),
        };
        let j = JointSample { q: [0.1; DOF], qd: [0.02; DOF], time_us: 0 };
        let e1 = host.step(&frame, &j, 0.0).unwrap();
        // The loop's time step: capture-time difference to the last accepted frame (1 → 3).
        let dt = (3 * 33_333u64 - 33_333) as f32 * 1e-6;
        let e3 = host.step(&frame, &j, dt).unwrap();
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
        let l = [0u8; 8];
        let input = encode(&frame_env(1, 2, 2, &l, &l));
        let mut out = VecSink::default();
        let mut slot: Option<Tracker> = None;
        let (mut lb, mut rb) = ([0u8; 8], [0u8; 8]);
        let r = serve(SliceSource::new(&input), &mut out, &mut slot, &mut lb, &mut rb, StackUsage::default);
        assert_eq!(r, Err(ServeError::Link(LinkError::Unexpected(MsgType::Frame))));
        assert_eq!(replies(&out.0)[0].message, Message::Error(ErrorCode::Unexpected as u32));
    }

    /// Runs `serve` on `input` with receive buffers of the sample setup's size; returns the
    /// result and the replies.
    fn serve_bytes(input: &[u8]) -> (Result<LoopStats, ServeError<Truncated>>, Vec<Envelope<'static>>) {
        let setup = sample_setup();
        let n = usize::from(setup.width) * usize::from(setup.height) * BYTES_PER_PIXEL;
        let mut out = VecSink::default();
        let mut slot: Option<Tracker> = None;
        let (mut lb, mut rb) = (vec![0u8; n], vec![0u8; n]);
        let r = serve(SliceSource::new(input), &mut out, &mut slot, &mut lb, &mut rb, StackUsage::default);
        (r, replies(&out.0))
    }

    #[test]
    fn damaged_messages_are_dropped_counted_and_the_stream_resynchronises() {
        let setup = sample_setup();
        let n = usize::from(setup.width) * usize::from(setup.height) * BYTES_PER_PIXEL;
        let l = vec![0x55u8; n];
        let (w, h) = (setup.width, setup.height);
        let mut input = b"garbage before the config".to_vec();
        input.extend(encode(&Envelope::bare(Message::Config(setup))));
        let mut flipped = encode(&frame_env(1, w, h, &l, &l));
        flipped[100] ^= 1; // bad CRC
        input.extend(flipped);
        let cut = encode(&frame_env(2, w, h, &l, &l));
        input.extend(&cut[..cut.len() / 2]); // truncated: ended by the next message's delimiter
        input.extend(encode(&frame_env(3, w, h, &l, &l)));
        input.extend(encode(&frame_env(3, w, h, &l, &l))); // duplicate
        input.extend(encode(&frame_env(2, w, h, &l, &l))); // late
        input.extend(encode(&Envelope::bare(Message::Config(setup)))); // unexpected
        let mut superseded = Vec::new();
        let mut sink = VecSink::default();
        write_message_with_flags(&mut sink, &frame_env(4, w, h, &l, &l), FLAG_NEWER_FOLLOWS).unwrap();
        superseded.extend(sink.0);
        input.extend(superseded);
        input.extend(encode(&frame_env(5, w, h, &l, &l)));
        input.extend(encode(&Envelope::bare(Message::End)));
        let (r, got) = serve_bytes(&input);
        assert_eq!(r.unwrap(), LoopStats { frames: 2, published: 2, rejected: 0 });
        let kinds: Vec<(MsgType, u32)> = got.iter().map(|e| (e.message.kind(), e.sequence)).collect();
        assert_eq!(kinds, [(MsgType::Ack, 0), (MsgType::Estimate, 3), (MsgType::Estimate, 5), (MsgType::Done, 0)]);
        let Message::Done(done) = got[3].message else { panic!("no DONE") };
        assert_eq!(
            done.drops,
            DropCounts {
                header: 1,  // the garbage in front: its first 24 bytes are no header
                framing: 1, // the cut frame
                crc: 1,
                sequence: 2,
                unexpected: 1,
                superseded: 1,
                ..DropCounts::default()
            }
        );
    }

    #[test]
    fn a_gap_longer_than_max_dt_refuses_one_frame_then_tracking_resumes() {
        // Frames 2..=20 dropped (say, superseded under overload): frame 21 comes 0.67 s after
        // frame 1, more than max_dt_s = 0.5 s. It is refused and becomes the time base; frame
        // 22 is tracked again (before, every later frame was refused for an ever longer gap).
        let setup = sample_setup();
        assert_eq!(setup.tuning.max_dt_s, 0.5);
        let n = usize::from(setup.width) * usize::from(setup.height) * BYTES_PER_PIXEL;
        let l = vec![0u8; n];
        let mut input = encode(&Envelope::bare(Message::Config(setup)));
        for k in [1u32, 21, 22, 23] {
            input.extend(encode(&frame_env(k, setup.width, setup.height, &l, &l)));
        }
        input.extend(encode(&Envelope::bare(Message::End)));
        let (r, got) = serve_bytes(&input);
        assert_eq!(r.unwrap(), LoopStats { frames: 4, published: 3, rejected: 1 });
        let kinds: Vec<(MsgType, u32)> = got.iter().map(|e| (e.message.kind(), e.sequence)).collect();
        assert_eq!(
            kinds,
            [
                (MsgType::Ack, 0),
                (MsgType::Estimate, 1),
                (MsgType::Rejected, 21),
                (MsgType::Estimate, 22),
                (MsgType::Estimate, 23),
                (MsgType::Done, 0)
            ]
        );
    }

    #[test]
    fn a_newer_frame_behind_supersedes_older_ones_so_latency_stays_one_frame() {
        // Overload: frames offered at twice the rate the board works them off (two per
        // generation, the older one flagged). The board answers only the newest of each pair.
        let setup = sample_setup();
        let n = usize::from(setup.width) * usize::from(setup.height) * BYTES_PER_PIXEL;
        let l = vec![0u8; n];
        let mut sink = VecSink::default();
        write_message(&mut sink, &Envelope::bare(Message::Config(setup))).unwrap();
        for k in 1..=20u32 {
            let flags = if k % 2 == 1 { FLAG_NEWER_FOLLOWS } else { 0 };
            write_message_with_flags(&mut sink, &frame_env(k, setup.width, setup.height, &l, &l), flags).unwrap();
        }
        write_message(&mut sink, &Envelope::bare(Message::End)).unwrap();
        let (r, got) = serve_bytes(&sink.0);
        assert_eq!(r.unwrap().frames, 10);
        let answered: Vec<u32> =
            got.iter().filter(|e| e.message.kind() == MsgType::Estimate).map(|e| e.sequence).collect();
        assert_eq!(answered, (1..=10).map(|k| 2 * k).collect::<Vec<_>>());
        let Some(Message::Done(done)) = got.last().map(|e| e.message) else { panic!("no DONE") };
        assert_eq!(done.drops.superseded, 10);
    }
}
