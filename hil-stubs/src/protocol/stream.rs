//! The byte-stream layer: the link traits, slice adapters, and reading and writing whole
//! messages (header, payload, CRC).

use evorec_core::tracker::JointSample;

use super::payload::{Dec, decode_small, encode_payload};
use super::{
    BYTES_PER_PIXEL, CRC_LEN, DOF, DecodeError, Envelope, FRAME_FIXED_LEN, Frame, HEADER_LEN, Header,
    MAX_SMALL_PAYLOAD, Message, MsgType,
};
use crate::crc::Crc32;

/// A blocking source of bytes (one end of the link).
pub trait ByteSource {
    /// Error of the underlying link.
    type Error;
    /// Fills `buf` completely, or fails (an end of stream before `buf` is full is an error).
    ///
    /// # Errors
    /// The link's error.
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), Self::Error>;
}

/// A blocking sink of bytes (the other end of the link).
pub trait ByteSink {
    /// Error of the underlying link.
    type Error;
    /// Writes all of `bytes`, or fails.
    ///
    /// # Errors
    /// The link's error.
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Self::Error>;
}

impl<T: ByteSource + ?Sized> ByteSource for &mut T {
    type Error = T::Error;
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), Self::Error> {
        T::read_exact(self, buf)
    }
}

impl<T: ByteSink + ?Sized> ByteSink for &mut T {
    type Error = T::Error;
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Self::Error> {
        T::write_all(self, bytes)
    }
}

/// The input ended in the middle of a message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Truncated;

impl core::fmt::Display for Truncated {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("input ended in the middle of a message")
    }
}

impl core::error::Error for Truncated {}

/// A [`ByteSource`] over a byte slice, consumed from the front.
#[derive(Debug, Clone)]
pub struct SliceSource<'a> {
    rest: &'a [u8],
}

impl<'a> SliceSource<'a> {
    /// Reads from `bytes`.
    pub fn new(bytes: &'a [u8]) -> Self {
        Self { rest: bytes }
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> &'a [u8] {
        self.rest
    }
}

impl ByteSource for SliceSource<'_> {
    type Error = Truncated;
    fn read_exact(&mut self, buf: &mut [u8]) -> Result<(), Truncated> {
        let (head, tail) = self.rest.split_at_checked(buf.len()).ok_or(Truncated)?;
        buf.copy_from_slice(head);
        self.rest = tail;
        Ok(())
    }
}

/// The output buffer is full.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Full;

impl core::fmt::Display for Full {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("output buffer is full")
    }
}

impl core::error::Error for Full {}

/// A [`ByteSink`] into a byte slice.
#[derive(Debug)]
pub struct SliceSink<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl<'a> SliceSink<'a> {
    /// Writes into `buf` from its start.
    pub fn new(buf: &'a mut [u8]) -> Self {
        Self { buf, len: 0 }
    }

    /// Bytes written so far.
    pub fn written(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }
}

impl ByteSink for SliceSink<'_> {
    type Error = Full;
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Full> {
        let end = self.len.checked_add(bytes.len()).ok_or(Full)?;
        self.buf.get_mut(self.len..end).ok_or(Full)?.copy_from_slice(bytes);
        self.len = end;
        Ok(())
    }
}

/// Why [`read_message`] failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReadError<E> {
    /// The link failed.
    Link(E),
    /// The bytes are not a valid message.
    Decode(DecodeError),
}

impl<E> From<DecodeError> for ReadError<E> {
    fn from(e: DecodeError) -> Self {
        Self::Decode(e)
    }
}

impl<E: core::fmt::Display> core::fmt::Display for ReadError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Link(e) => write!(f, "link: {e}"),
            Self::Decode(e) => write!(f, "decode: {e}"),
        }
    }
}

impl<E: core::error::Error + 'static> core::error::Error for ReadError<E> {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Link(e) => Some(e),
            Self::Decode(e) => Some(e),
        }
    }
}

/// Why [`write_message`] failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WriteError<E> {
    /// The link failed.
    Link(E),
    /// A frame's image slices are not `width · height · BYTES_PER_PIXEL` bytes each.
    ImageSize {
        /// `width · height · BYTES_PER_PIXEL`.
        expected: usize,
        /// Left image length.
        left: usize,
        /// Right image length.
        right: usize,
    },
}

impl<E: core::fmt::Display> core::fmt::Display for WriteError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Link(e) => write!(f, "link: {e}"),
            Self::ImageSize { expected, left, right } => {
                write!(f, "frame images have {left} and {right} bytes, width·height·{BYTES_PER_PIXEL} is {expected}")
            }
        }
    }
}

impl<E: core::error::Error + 'static> core::error::Error for WriteError<E> {
    fn source(&self) -> Option<&(dyn core::error::Error + 'static)> {
        match self {
            Self::Link(e) => Some(e),
            Self::ImageSize { .. } => None,
        }
    }
}

fn read_crc<S: ByteSource + ?Sized>(src: &mut S, buf: &mut [u8], crc: &mut Crc32) -> Result<(), ReadError<S::Error>> {
    src.read_exact(buf).map_err(ReadError::Link)?;
    crc.update(buf);
    Ok(())
}

fn check_trailer<S: ByteSource + ?Sized>(src: &mut S, crc: &Crc32) -> Result<(), ReadError<S::Error>> {
    let mut trailer = [0u8; CRC_LEN];
    src.read_exact(&mut trailer).map_err(ReadError::Link)?;
    let received = u32::from_le_bytes(trailer);
    let computed = crc.finish();
    if received == computed { Ok(()) } else { Err(DecodeError::BadCrc { received, computed }.into()) }
}

/// Reads one message from `src`.
///
/// A `FRAME`'s RGB565 images are written into `left[..2·w·h]` and `right[..2·w·h]` and the
/// returned [`Frame`] borrows them; pass empty buffers where no frame is expected (a frame then fails
/// with [`DecodeError::FrameTooLarge`]). The header is checked before any payload is read, the
/// CRC after the whole message; on an error the buffers' contents are unspecified and the
/// stream is out of step (the conversation cannot continue).
///
/// # Errors
/// [`ReadError::Link`] from the source, [`ReadError::Decode`] for a malformed message.
pub fn read_message<'b, S: ByteSource + ?Sized>(
    src: &mut S,
    left: &'b mut [u8],
    right: &'b mut [u8],
) -> Result<Envelope<'b>, ReadError<S::Error>> {
    let mut hb = [0u8; HEADER_LEN];
    src.read_exact(&mut hb).map_err(ReadError::Link)?;
    let header = Header::decode(&hb)?;
    let mut crc = Crc32::new();
    crc.update(&hb);
    let message = if header.kind == MsgType::Frame {
        let mut fixed = [0u8; FRAME_FIXED_LEN];
        read_crc(src, &mut fixed, &mut crc)?;
        let mut d = Dec::new(&fixed);
        let width = d.u16();
        let height = d.u16();
        let time_us = d.u64();
        let q = d.f32s::<DOF>();
        let qd = d.f32s::<DOF>();
        let pixels = u32::from(width) * u32::from(height);
        let image_bytes = u64::from(pixels) * BYTES_PER_PIXEL as u64;
        if u64::from(header.payload_len) != FRAME_FIXED_LEN as u64 + 2 * image_bytes {
            return Err(DecodeError::BadLength { kind: MsgType::Frame, len: header.payload_len }.into());
        }
        // A frame whose bytes do not fit usize (32-bit target) cannot fit the buffers either.
        let n = usize::try_from(image_bytes).unwrap_or(usize::MAX);
        let capacity = left.len().min(right.len()) / BYTES_PER_PIXEL;
        let too_large = DecodeError::FrameTooLarge { pixels, capacity: u32::try_from(capacity).unwrap_or(u32::MAX) };
        let (Some(l), Some(r)) = (left.get_mut(..n), right.get_mut(..n)) else {
            return Err(too_large.into());
        };
        read_crc(src, l, &mut crc)?;
        read_crc(src, r, &mut crc)?;
        check_trailer(src, &crc)?;
        Message::Frame(Frame { width, height, joints: JointSample { q, qd, time_us }, left: l, right: r })
    } else {
        let mut buf = [0u8; MAX_SMALL_PAYLOAD];
        let payload = buf
            .get_mut(..header.payload_len as usize)
            .ok_or(DecodeError::BadLength { kind: header.kind, len: header.payload_len })?;
        read_crc(src, payload, &mut crc)?;
        check_trailer(src, &crc)?;
        decode_small(header.kind, payload)?
    };
    Ok(Envelope { sequence: header.sequence, capture_time_us: header.capture_time_us, message })
}

/// Decodes one complete message from the front of `bytes`; returns it and the bytes it used.
///
/// # Errors
/// [`ReadError::Link`]`(`[`Truncated`]`)` if `bytes` ends early, else as [`read_message`].
pub fn decode<'b>(
    bytes: &[u8],
    left: &'b mut [u8],
    right: &'b mut [u8],
) -> Result<(Envelope<'b>, usize), ReadError<Truncated>> {
    let mut src = SliceSource::new(bytes);
    let env = read_message(&mut src, left, right)?;
    Ok((env, bytes.len() - src.remaining().len()))
}

/// Writes one message to `sink` (header, payload, CRC).
///
/// # Errors
/// [`WriteError::ImageSize`] for a frame whose images are not `width · height ·`
/// [`BYTES_PER_PIXEL`] bytes (nothing is written then), else [`WriteError::Link`].
pub fn write_message<S: ByteSink + ?Sized>(sink: &mut S, env: &Envelope<'_>) -> Result<(), WriteError<S::Error>> {
    let mut small = [0u8; MAX_SMALL_PAYLOAD];
    let (len, images) = encode_payload(&env.message, &mut small);
    let (left, right): (&[u8], &[u8]) = match images {
        Some((l, r)) => (l, r),
        None => (&[], &[]),
    };
    if let Message::Frame(f) = &env.message {
        let expected = usize::from(f.width) * usize::from(f.height) * BYTES_PER_PIXEL;
        if left.len() != expected || right.len() != expected {
            return Err(WriteError::ImageSize { expected, left: left.len(), right: right.len() });
        }
    }
    let payload_len = len + left.len() + right.len();
    let header = Header {
        kind: env.message.kind(),
        sequence: env.sequence,
        payload_len: u32::try_from(payload_len).unwrap_or(u32::MAX),
        capture_time_us: env.capture_time_us,
    }
    .encode();
    let fixed = small.get(..len).unwrap_or(&[]);
    let mut crc = Crc32::new();
    for part in [&header[..], fixed, left, right] {
        crc.update(part);
        sink.write_all(part).map_err(WriteError::Link)?;
    }
    sink.write_all(&crc.finish().to_le_bytes()).map_err(WriteError::Link)
}

/// The encoded size of a message (header, payload and CRC).
pub fn encoded_len(message: &Message<'_>) -> usize {
    let payload = match message {
        Message::Frame(f) => FRAME_FIXED_LEN + 2 * BYTES_PER_PIXEL * usize::from(f.width) * usize::from(f.height),
        m => m.kind().fixed_payload_len().unwrap_or(0),
    };
    HEADER_LEN + payload + CRC_LEN
}
