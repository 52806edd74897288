//! The framed link protocol between the host and the firmware (`no_std`, shared by both).
//!
//! The link is a pair of byte streams (under QEMU: two named FIFOs read and written with
//! semihosting file calls). Every message travels COBS-framed ([`framing`]):
//! `0x00 ‖ COBS(header ‖ payload ‖ CRC) ‖ 0x00`, so a zero byte on the wire always delimits
//! messages and a receiver drops a damaged message and is in step again at the next zero.
//! Before framing a message is
//!
//! ```text
//!  offset  size  field
//!       0     4  magic "EVRC"
//!       4     1  version ([`VERSION`])
//!       5     1  message type (MsgType)
//!       6     2  flags (FLAG_NEWER_FOLLOWS on a FRAME; 0 otherwise)
//!       8     4  sequence number: the frame a FRAME/ESTIMATE/REJECTED is about; 0 otherwise
//!      12     4  payload size in bytes
//!      16     8  capture time (µs, the host's clock) of that frame; 0 otherwise
//!      24     n  payload
//!    24+n     4  CRC-32 (IEEE) over header and payload
//! ```
//!
//! All integers are little-endian; every `f32` travels as its raw IEEE-754 bits
//! ([`f32::to_bits`]), so values cross the link bit-exactly (NaN payloads included).
//!
//! | type          | dir | payload                                                         |
//! |---------------|-----|-----------------------------------------------------------------|
//! | `CONFIG`   1  | h→f | [`Setup`], [`CONFIG_LEN`] bytes                                 |
//! | `FRAME`    2  | h→f | width u16, height u16, joint time u64, q\[7\], q̇\[7\] f32,       |
//! |               |     | then the left and the right image, `w·h` RGB565 pixels each     |
//! |               |     | (row-major, 2 bytes per pixel, little-endian `rrrrrggggggbbbbb`) |
//! | `ESTIMATE` 3  | f→h | ψ\[6\] f32, fitness F f32, F_L and F_R f32, generation u32,      |
//! |               |     | status u8, the target filter's measurement ψ\[6\] f32            |
//! |               |     | (`Estimate::target_measurement`)                                |
//! | `END`      4  | h→f | empty: no more frames                                           |
//! | `ACK`      5  | f→h | status u32 answering CONFIG: 0 = tracker built, else a [`crate::setup::SetupError`] code |
//! | `REJECTED` 6  | f→h | empty: the tracker refused that frame (size, joints, time step) |
//! | `DONE`     7  | f→h | [`Done`]: loop counts, stack high-water mark, [`DropCounts`]    |
//! | `ERROR`    8  | f→h | code u32: the firmware gives up (see [`ErrorCode`])             |
//!
//! The conversation is lock-step: `CONFIG` → `ACK`; then per `FRAME` one `ESTIMATE` or
//! `REJECTED` with the frame's sequence number and capture time; `END` → `DONE`, after which
//! the firmware exits. A damaged message gets no answer (the firmware counts it in
//! [`DropCounts`]; the host times out and goes on), nor does a frame whose sequence number is
//! not above the last one (a duplicate or a late copy), nor a frame with
//! [`FLAG_NEWER_FOLLOWS`] (overload: the board works on the newest frame).
//!
//! Decoding streams: [`read_message`] checks the header as soon as it has arrived, then
//! decodes a frame's images straight into the caller's buffers while the CRC runs, so the
//! firmware needs no second frame buffer. Encoding is [`write_message`]. Both work over the
//! two small traits [`ByteSource`] and [`ByteSink`].

use evorec_core::limits::PA10_DOF;
use evorec_core::pose::Psi;
use evorec_core::tracker::{Estimate, JointSample};
use evorec_core::tuning::{FIELDS, Tuning};

use payload::{Dec, Enc};

pub mod framing;
mod payload;
mod stream;
#[cfg(test)]
pub(crate) mod tests;
#[cfg(any(test, feature = "host"))]
mod vec;

pub use framing::{
    FLAG_NEWER_FOLLOWS, LinkReader, decode, max_encoded_len, raw_len, read_message, read_valid_message, write_message,
    write_message_with_flags,
};
pub use stream::{ByteSink, ByteSource, Full, ReadError, SliceSink, SliceSource, Truncated, WriteError};
#[cfg(any(test, feature = "host"))]
pub use vec::{VecSink, encode_to_vec};

/// Joints of the arm carried in every frame (the PA-10's 7).
pub const DOF: usize = PA10_DOF;

/// First four bytes of every message.
pub const MAGIC: [u8; 4] = *b"EVRC";
/// Protocol version carried in every header (13: estimates may carry the status `uncertain`
/// (code 3), and `CONFIG` the tuning field `status.certain_fitness`; 11: `ESTIMATE` carries the target filter's whole
/// measurement ψ\[6\]; 10: `CONFIG` carries the whole tuning as the
/// core's field table, [`evorec_core::tuning::FIELDS`], acquisition and status included; 9:
/// `CONFIG` carries the six parameters of the target motion model; 8: `CONFIG` carries the target filter's
/// parameters; 7: `ESTIMATE` carries the target filter's
/// measured position; 6: `CONFIG` carries the GA's settled mutation levels; 5: COBS framing,
/// header flags, drop counts in `DONE`; 4: `CONFIG` carries the population size; 3:
/// estimates carry the tracker's status; 2: frames carry the sensor's RGB565 pixels; 1: hue
/// frames).
pub const VERSION: u8 = 13;
/// The pixel format of a frame's images on the link: the camera sensor's own RGB565, so the
/// hue is computed on the board (see [`evorec_core::image::Rgb565`]).
pub type LinkFormat = evorec_core::image::Rgb565;
/// Bytes per pixel of a frame's images on the link.
pub const BYTES_PER_PIXEL: usize = <LinkFormat as evorec_core::image::PixelFormat>::BYTES_PER_PIXEL;
/// Header size in bytes.
pub const HEADER_LEN: usize = 24;
/// CRC trailer size in bytes.
pub const CRC_LEN: usize = 4;
/// Size of the tuning inside `CONFIG`: the table's fingerprint ([`evorec_core::tuning::TABLE_ID`]), its field
/// count (u16, +2 reserved), then every field of [`FIELDS`] as 4 bytes in table order (a real
/// as its `f32` bits, an integer as `u32`, a name as the `u32` index of its choice).
pub const TUNING_LEN: usize = 4 + 4 + 4 * FIELDS.len();
/// `CONFIG` payload size: intrinsics and image size, baseline, block, flange-to-camera,
/// search box, seed, the tuning ([`TUNING_LEN`]), initial pose and spread.
pub const CONFIG_LEN: usize = 4 * 4 + 2 * 2 + 4 + 4 * 9 + 4 * 7 + 4 * 6 + 8 + TUNING_LEN + 4 * 12;
/// `FRAME` payload size before the two images.
pub const FRAME_FIXED_LEN: usize = 2 + 2 + 8 + 4 * DOF * 2;
/// `ESTIMATE` payload size: ψ, fitness, the fitness per camera, generation, status code, the
/// filter's measurement ψ.
pub const ESTIMATE_LEN: usize = 4 * 6 + 4 + 4 * 2 + 4 + 1 + 4 * 6;
/// `ACK` payload size.
pub const ACK_LEN: usize = 4;
/// `DONE` payload size: five counts and the [`DropCounts`].
pub const DONE_LEN: usize = 5 * 4 + DropCounts::LEN;
/// `ERROR` payload size.
pub const ERROR_LEN: usize = 4;
/// Largest payload other than a frame's (sizes the decoder's scratch buffer).
pub const MAX_SMALL_PAYLOAD: usize = CONFIG_LEN;

/// Message types.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum MsgType {
    /// Host → firmware: build the tracker.
    Config = 1,
    /// Host → firmware: a stereo frame with its joint sample.
    Frame = 2,
    /// Firmware → host: the estimate for a frame.
    Estimate = 3,
    /// Host → firmware: end of the stream.
    End = 4,
    /// Firmware → host: answer to `CONFIG`.
    Ack = 5,
    /// Firmware → host: the tracker refused a frame.
    Rejected = 6,
    /// Firmware → host: answer to `END`.
    Done = 7,
    /// Firmware → host: fatal error, the firmware exits.
    Error = 8,
}

impl MsgType {
    /// The type of a header byte.
    pub fn from_u8(b: u8) -> Option<Self> {
        Some(match b {
            1 => Self::Config,
            2 => Self::Frame,
            3 => Self::Estimate,
            4 => Self::End,
            5 => Self::Ack,
            6 => Self::Rejected,
            7 => Self::Done,
            8 => Self::Error,
            _ => return None,
        })
    }

    /// The payload size of every type but `FRAME` (whose size depends on the image).
    pub const fn fixed_payload_len(self) -> Option<usize> {
        match self {
            Self::Config => Some(CONFIG_LEN),
            Self::Frame => None,
            Self::Estimate => Some(ESTIMATE_LEN),
            Self::End | Self::Rejected => Some(0),
            Self::Ack => Some(ACK_LEN),
            Self::Done => Some(DONE_LEN),
            Self::Error => Some(ERROR_LEN),
        }
    }
}

/// Why received bytes are not a valid message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum DecodeError {
    /// The first four bytes are not [`MAGIC`].
    BadMagic([u8; 4]),
    /// Unsupported protocol version.
    BadVersion(u8),
    /// Unknown message type byte.
    UnknownType(u8),
    /// The payload size does not fit the message type (or the frame's image size).
    BadLength {
        /// Message type.
        kind: MsgType,
        /// Payload size in the header.
        len: u32,
    },
    /// A frame has more pixels than the receiver's image buffers hold.
    FrameTooLarge {
        /// `width · height` of the frame.
        pixels: u32,
        /// Pixels one receive buffer holds.
        capacity: u32,
    },
    /// The CRC trailer does not match the message.
    BadCrc {
        /// CRC in the trailer.
        received: u32,
        /// CRC computed over header and payload.
        computed: u32,
    },
    /// A field holds a value outside its range (e.g. a feedforward flag other than 0/1/2).
    BadValue,
    /// The message's framing is broken: it ended (at a delimiter) before its announced size,
    /// or a delimiter arrived inside a COBS run (a cut or damaged message).
    Framing,
    /// Not damage: a `FRAME` flagged [`FLAG_NEWER_FOLLOWS`], dropped unread by a reader that
    /// works only on the newest frame ([`LinkReader::newest_frames_only`]). Its header and
    /// size were checked; its images and CRC were skipped, not decoded.
    Superseded,
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Self::BadMagic(m) => write!(f, "bad magic {m:02x?}"),
            Self::BadVersion(v) => write!(f, "unsupported protocol version {v} (expected {VERSION})"),
            Self::UnknownType(t) => write!(f, "unknown message type {t}"),
            Self::BadLength { kind, len } => write!(f, "{kind:?} message with bad payload size {len}"),
            Self::FrameTooLarge { pixels, capacity } => {
                write!(f, "frame of {pixels} pixels exceeds the {capacity}-pixel buffers")
            }
            Self::BadCrc { received, computed } => {
                write!(f, "CRC mismatch: received {received:#010x}, computed {computed:#010x}")
            }
            Self::BadValue => f.write_str("field value out of range"),
            Self::Framing => f.write_str("message cut short (delimiter inside the message)"),
            Self::Superseded => f.write_str("frame superseded by a newer one (skipped unread)"),
        }
    }
}

impl core::error::Error for DecodeError {}

/// Codes carried by an `ERROR` message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u32)]
#[non_exhaustive]
pub enum ErrorCode {
    /// The link failed (read or write error, or end of stream in the middle of a message).
    Link = 1,
    /// A malformed message arrived ([`DecodeError`]).
    Decode = 2,
    /// A valid message arrived where another was expected (e.g. `FRAME` before `CONFIG`).
    Unexpected = 3,
    /// Any other failure.
    Other = 4,
}

impl ErrorCode {
    /// The code of a received `ERROR` value.
    pub fn from_u32(v: u32) -> Option<Self> {
        Some(match v {
            1 => Self::Link,
            2 => Self::Decode,
            3 => Self::Unexpected,
            4 => Self::Other,
            _ => return None,
        })
    }
}

/// Everything the firmware builds its tracker from (the `CONFIG` payload).
///
/// The arm is the PA-10 and the rig two identical parallel cameras; [`crate::setup`] converts
/// this to and from [`evorec_core::TrackerConfig`], bit-exactly, so host and firmware build
/// identical trackers from the same `Setup`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Setup {
    /// Focal length along u (pixels).
    pub fx: f32,
    /// Focal length along v (pixels).
    pub fy: f32,
    /// Principal point u (pixels).
    pub cx: f32,
    /// Principal point v (pixels).
    pub cy: f32,
    /// Image width (pixels), both cameras.
    pub width: u16,
    /// Image height (pixels), both cameras.
    pub height: u16,
    /// Stereo baseline (m): the left camera sits this far along −x of the right one.
    pub baseline_m: f32,
    /// Block edge lengths along x, y, z (m).
    pub block_size_m: [f32; 3],
    /// Face hues +x, +y, +z, −x, −y, −z (degrees).
    pub face_hues_deg: [f32; 6],
    /// `^H T_CR` translation (m).
    pub flange_to_camera_t: [f32; 3],
    /// `^H T_CR` rotation as a unit quaternion `[w, i, j, k]`.
    pub flange_to_camera_q: [f32; 4],
    /// Search-space lower position bounds (m, `Σ_CR`).
    pub search_min: [f32; 3],
    /// Search-space upper position bounds (m, `Σ_CR`).
    pub search_max: [f32; 3],
    /// GA seed.
    pub seed: u64,
    /// Every tuning parameter, sent field by field through the core's table.
    pub tuning: Tuning,
    /// Pose the population starts around ([`evorec_core::Tracker::reset_around`]).
    pub initial_psi: Psi,
    /// Per-gene spread of the initial population.
    pub initial_spread: [f32; 6],
}

/// A stereo frame with its joint sample (the `FRAME` payload); sequence number and capture
/// time travel in the [`Envelope`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame<'a> {
    /// Width of both images.
    pub width: u16,
    /// Height of both images.
    pub height: u16,
    /// Joint positions and velocities and their sample time.
    pub joints: JointSample<DOF>,
    /// Left RGB565 image, exactly `width · height · `[`BYTES_PER_PIXEL`] bytes.
    pub left: &'a [u8],
    /// Right RGB565 image, exactly `width · height · `[`BYTES_PER_PIXEL`] bytes.
    pub right: &'a [u8],
}

/// Messages a receiver dropped, by reason (the firmware's are reported in `DONE`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DropCounts {
    /// Cut short or with a delimiter inside ([`DecodeError::Framing`]).
    pub framing: u32,
    /// Bad magic, version or type.
    pub header: u32,
    /// Payload size wrong for the type, or a frame larger than the buffers.
    pub length: u32,
    /// CRC mismatch.
    pub crc: u32,
    /// A field out of range ([`DecodeError::BadValue`]).
    pub value: u32,
    /// A valid frame whose sequence number is not above the last one (duplicate or late).
    pub sequence: u32,
    /// A valid message of a type not expected there (e.g. a second `CONFIG`).
    pub unexpected: u32,
    /// Frames superseded by a newer one (overload, [`FLAG_NEWER_FOLLOWS`]).
    pub superseded: u32,
}

impl DropCounts {
    /// Encoded size (eight `u32`).
    pub const LEN: usize = 8 * 4;

    /// Counts one message dropped for `e`.
    pub fn count(&mut self, e: &DecodeError) {
        let c = match e {
            DecodeError::Framing => &mut self.framing,
            DecodeError::BadMagic(_) | DecodeError::BadVersion(_) | DecodeError::UnknownType(_) => &mut self.header,
            DecodeError::BadLength { .. } | DecodeError::FrameTooLarge { .. } => &mut self.length,
            DecodeError::BadCrc { .. } => &mut self.crc,
            DecodeError::BadValue => &mut self.value,
            DecodeError::Superseded => &mut self.superseded,
        };
        *c = c.saturating_add(1);
    }

    /// Messages dropped as damaged (framing, header, length, CRC, value).
    pub fn damaged(&self) -> u32 {
        [self.framing, self.header, self.length, self.crc, self.value].iter().fold(0u32, |a, &b| a.saturating_add(b))
    }

    /// The counts in wire order.
    pub fn to_array(self) -> [u32; 8] {
        [self.framing, self.header, self.length, self.crc, self.value, self.sequence, self.unexpected, self.superseded]
    }

    /// The counts from wire order.
    pub fn from_array(a: [u32; 8]) -> Self {
        let [framing, header, length, crc, value, sequence, unexpected, superseded] = a;
        Self { framing, header, length, crc, value, sequence, unexpected, superseded }
    }
}

/// The firmware's report at the end of the stream (the `DONE` payload).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Done {
    /// Frames received.
    pub frames: u32,
    /// Estimates published.
    pub published: u32,
    /// Frames the tracker refused.
    pub rejected: u32,
    /// Stack high-water mark (bytes below the top of RAM ever written).
    pub stack_used_bytes: u32,
    /// Size of the stack region (top of RAM down to the end of the statics).
    pub stack_size_bytes: u32,
    /// Messages the firmware dropped, by reason.
    pub drops: DropCounts,
}

/// One message.
// `Config` is the large variant (~280 bytes); messages are handled one at a time and there is
// no allocator on the target, so it is not boxed.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Message<'a> {
    /// `CONFIG`.
    Config(Setup),
    /// `FRAME`.
    Frame(Frame<'a>),
    /// `ESTIMATE` (the frame is named by the envelope).
    Estimate(Estimate),
    /// `END`.
    End,
    /// `ACK` with its status (0 = ok).
    Ack(u32),
    /// `REJECTED`.
    Rejected,
    /// `DONE`.
    Done(Done),
    /// `ERROR` with its code (see [`ErrorCode`]).
    Error(u32),
}

impl Message<'_> {
    /// The message's type.
    pub fn kind(&self) -> MsgType {
        match self {
            Self::Config(_) => MsgType::Config,
            Self::Frame(_) => MsgType::Frame,
            Self::Estimate(_) => MsgType::Estimate,
            Self::End => MsgType::End,
            Self::Ack(_) => MsgType::Ack,
            Self::Rejected => MsgType::Rejected,
            Self::Done(_) => MsgType::Done,
            Self::Error(_) => MsgType::Error,
        }
    }

    /// The message without borrowed images, or `None` for a `FRAME`.
    pub fn detach(self) -> Option<Message<'static>> {
        Some(match self {
            Self::Config(s) => Message::Config(s),
            Self::Frame(_) => return None,
            Self::Estimate(e) => Message::Estimate(e),
            Self::End => Message::End,
            Self::Ack(s) => Message::Ack(s),
            Self::Rejected => Message::Rejected,
            Self::Done(d) => Message::Done(d),
            Self::Error(c) => Message::Error(c),
        })
    }
}

/// A message with the header fields that name its frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Envelope<'a> {
    /// Frame sequence number (`FRAME`, `ESTIMATE`, `REJECTED`), else 0.
    pub sequence: u32,
    /// Capture time of that frame (µs), else 0.
    pub capture_time_us: u64,
    /// The message.
    pub message: Message<'a>,
}

impl<'a> Envelope<'a> {
    /// A message that names no frame (sequence and time 0).
    pub fn bare(message: Message<'a>) -> Self {
        Self { sequence: 0, capture_time_us: 0, message }
    }
}

/// A decoded header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// Message type.
    pub kind: MsgType,
    /// Flags ([`FLAG_NEWER_FOLLOWS`]); unknown bits are carried, not interpreted.
    pub flags: u16,
    /// Sequence number.
    pub sequence: u32,
    /// Payload size.
    pub payload_len: u32,
    /// Capture time (µs).
    pub capture_time_us: u64,
}

impl Header {
    /// The header's bytes.
    pub fn encode(&self) -> [u8; HEADER_LEN] {
        let mut out = [0u8; HEADER_LEN];
        let mut e = Enc::new(&mut out);
        e.bytes(&MAGIC);
        e.u8(VERSION);
        e.u8(self.kind as u8);
        e.u16(self.flags);
        e.u32(self.sequence);
        e.u32(self.payload_len);
        e.u64(self.capture_time_us);
        out
    }

    /// Parses and checks a header (magic, version, type, and the size of fixed-size types).
    ///
    /// # Errors
    /// [`DecodeError::BadMagic`], [`DecodeError::BadVersion`], [`DecodeError::UnknownType`]
    /// or [`DecodeError::BadLength`].
    pub fn decode(bytes: &[u8; HEADER_LEN]) -> Result<Self, DecodeError> {
        let mut d = Dec::new(bytes);
        let magic: [u8; 4] = d.take();
        if magic != MAGIC {
            return Err(DecodeError::BadMagic(magic));
        }
        let version = d.u8();
        if version != VERSION {
            return Err(DecodeError::BadVersion(version));
        }
        let t = d.u8();
        let kind = MsgType::from_u8(t).ok_or(DecodeError::UnknownType(t))?;
        let flags = d.u16();
        let sequence = d.u32();
        let payload_len = d.u32();
        let capture_time_us = d.u64();
        let len_ok = match kind.fixed_payload_len() {
            Some(n) => payload_len as usize == n,
            None => payload_len as usize >= FRAME_FIXED_LEN,
        };
        if !len_ok {
            return Err(DecodeError::BadLength { kind, len: payload_len });
        }
        Ok(Self { kind, flags, sequence, payload_len, capture_time_us })
    }
}
