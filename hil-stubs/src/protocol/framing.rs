//! COBS framing: every message travels as `0x00 ‖ COBS(header ‖ payload ‖ CRC) ‖ 0x00`.
//!
//! COBS (Consistent Overhead Byte Stuffing) removes every zero byte from the encoded message,
//! so a zero byte on the wire always delimits messages. A receiver that meets a damaged
//! message (bad header, length or CRC, or a delimiter in the middle of it) drops bytes up to
//! the next zero and is in step again: [`read_message`] returns the [`DecodeError`] of the
//! dropped message and the next call decodes the next one. The leading zero ends whatever a
//! truncated predecessor left unfinished, so a cut message costs only itself.
//!
//! Decoding runs the [`cobs`] crate's streaming state machine ([`cobs::DecoderState`]) over a
//! small read buffer ([`LinkReader`], [`RX_CHUNK`] bytes) and writes the decoded bytes straight
//! where they belong: the header and small payloads into a scratch on the stack, a frame's
//! images into the caller's two receive buffers (no second frame buffer). Inside a run of
//! non-zero bytes whole slices are copied at once. Encoding ([`write_message`]) streams through
//! a run buffer of 255 bytes and an output buffer of [`TX_CHUNK`] bytes.

use cobs::{DecodeResult, DecoderState};

use super::payload::{Dec, decode_small, encode_payload};
use super::stream::{ByteSink, ByteSource, ReadError, SliceSource, Truncated, WriteError};
use super::{
    BYTES_PER_PIXEL, CRC_LEN, DOF, DecodeError, Envelope, FRAME_FIXED_LEN, Frame, HEADER_LEN, Header,
    MAX_SMALL_PAYLOAD, Message, MsgType,
};
use crate::crc::Crc32;
use evorec_core::tracker::JointSample;

/// Size of [`LinkReader`]'s read buffer (bytes read from the link per call at most).
pub const RX_CHUNK: usize = 32;
/// Size of the encoder's output buffer (bytes handed to the sink per call at most).
pub const TX_CHUNK: usize = 256;
/// Longest COBS run: 254 data bytes after a code byte.
const RUN: usize = 255;

/// The receiving end of the link: a [`ByteSource`] with the small read buffer the COBS
/// decoder works from (bytes after a damaged message's delimiter stay buffered for the next
/// message), and the header flags of the last message decoded.
#[derive(Debug)]
pub struct LinkReader<S> {
    src: S,
    buf: [u8; RX_CHUNK],
    pos: usize,
    end: usize,
    flags: u16,
    skip_superseded: bool,
}

impl<S: ByteSource> LinkReader<S> {
    /// Reads from `src`.
    pub fn new(src: S) -> Self {
        Self { src, buf: [0; RX_CHUNK], pos: 0, end: 0, flags: 0, skip_superseded: false }
    }

    /// Reads from `src` as a board that only works on the newest frame: a `FRAME` flagged
    /// [`FLAG_NEWER_FOLLOWS`] is dropped unread ([`DecodeError::Superseded`]) as soon as its
    /// size is checked, its remaining bytes skipped in bulk (see [`read_message`]).
    pub fn newest_frames_only(src: S) -> Self {
        Self { skip_superseded: true, ..Self::new(src) }
    }

    /// The source.
    pub fn get_ref(&self) -> &S {
        &self.src
    }

    /// The source (bytes buffered and not decoded yet are lost).
    pub fn into_inner(self) -> S {
        self.src
    }

    /// Bytes read from the source but not decoded yet.
    pub fn buffered(&self) -> &[u8] {
        self.buf.get(self.pos..self.end).unwrap_or(&[])
    }

    /// The header flags of the last message [`read_message`] returned (see [`super::FLAG_NEWER_FOLLOWS`]).
    pub fn last_flags(&self) -> u16 {
        self.flags
    }

    /// The buffered bytes, reading more (at least one byte) when none are left.
    fn fill(&mut self) -> Result<&[u8], S::Error> {
        if self.pos >= self.end {
            self.end = self.src.read_some(&mut self.buf)?.min(RX_CHUNK);
            self.pos = 0;
        }
        Ok(self.buffered())
    }

    fn consume(&mut self, n: usize) {
        self.pos = self.pos.saturating_add(n).min(self.end);
    }

    /// Drops bytes up to and including the next delimiter.
    fn skip_past_delimiter(&mut self) -> Result<(), S::Error> {
        loop {
            let chunk = self.fill()?;
            let (n, found) = match chunk.iter().position(|&b| b == 0) {
                Some(z) => (z + 1, true),
                None => (chunk.len(), false),
            };
            self.consume(n);
            if found {
                return Ok(());
            }
        }
    }

    /// Drops the rest of a message of which at least `min_left` more wire bytes come before
    /// its end delimiter (true of an intact message): those are read in bulk into `scratch`,
    /// a few large reads checked only for a zero byte, then the rest up to the delimiter as
    /// in [`Self::skip_past_delimiter`]. A zero among the bulk bytes (the message was cut
    /// short) ends the skip there; what was read after it is kept for the next message if it
    /// fits the read buffer, else lost (the next message is then dropped as damaged).
    fn skip_message(&mut self, min_left: usize, scratch: &mut [u8]) -> Result<(), S::Error> {
        let buffered = self.buffered();
        if let Some(z) = buffered.iter().position(|&b| b == 0) {
            self.consume(z + 1);
            return Ok(());
        }
        let mut left = min_left.saturating_sub(buffered.len());
        self.consume(buffered.len());
        while let Some(chunk) = scratch.get_mut(..left.min(scratch.len())).filter(|c| !c.is_empty()) {
            let n = self.src.read_some(chunk)?.min(chunk.len());
            let got = chunk.get(..n).unwrap_or_default();
            // `contains` on bytes is core's word-at-a-time memchr.
            if got.contains(&0) {
                let z = got.iter().position(|&b| b == 0).unwrap_or(n);
                let rest = got.get(z + 1..).unwrap_or_default();
                let keep = if rest.len() <= RX_CHUNK { rest.len() } else { 0 };
                self.end = put(&mut self.buf, 0, rest.get(..keep).unwrap_or_default());
                self.pos = 0;
                return Ok(());
            }
            left -= n;
        }
        self.skip_past_delimiter()
    }
}

/// Where the decoded bytes of one message go, checked as they arrive.
struct Assembly<'b> {
    head: [u8; HEADER_LEN],
    header: Option<Header>,
    /// A small payload, or a frame's fixed part.
    small: [u8; MAX_SMALL_PAYLOAD],
    /// Bytes of `small` in use: the payload size, or [`FRAME_FIXED_LEN`].
    fixed: usize,
    left: &'b mut [u8],
    right: &'b mut [u8],
    /// Bytes of one image (0 but for frames whose fixed part has arrived).
    image: usize,
    trailer: [u8; CRC_LEN],
    /// Decoded bytes so far.
    at: usize,
    crc: Crc32,
}

/// Copies as much of `data` as fits into `dst` from `offset`; returns the bytes used.
fn put(dst: &mut [u8], offset: usize, data: &[u8]) -> usize {
    let room = dst.get_mut(offset..).unwrap_or_default();
    let n = room.len().min(data.len());
    if let (Some(d), Some(s)) = (room.get_mut(..n), data.get(..n)) {
        d.copy_from_slice(s);
    }
    n
}

impl<'b> Assembly<'b> {
    fn new(left: &'b mut [u8], right: &'b mut [u8]) -> Self {
        Self {
            head: [0; HEADER_LEN],
            header: None,
            small: [0; MAX_SMALL_PAYLOAD],
            fixed: 0,
            left,
            right,
            image: 0,
            trailer: [0; CRC_LEN],
            at: 0,
            crc: Crc32::new(),
        }
    }

    /// Payload bytes the header and (for frames) the fixed part announce.
    fn payload_len(&self) -> usize {
        self.fixed + 2 * self.image
    }

    /// A `FRAME` flagged [`FLAG_NEWER_FOLLOWS`] whose fixed part has arrived, so its size has
    /// been checked against the header and the receive buffers.
    fn superseded_frame(&self) -> bool {
        self.header.is_some_and(|h| h.kind == MsgType::Frame && h.flags & FLAG_NEWER_FOLLOWS != 0)
            && self.at >= HEADER_LEN + FRAME_FIXED_LEN
    }

    /// Takes the next decoded bytes.
    fn push(&mut self, mut data: &[u8]) -> Result<(), DecodeError> {
        while !data.is_empty() {
            let n = self.push_some(data)?;
            data = data.get(n..).unwrap_or_default();
            self.at += n;
        }
        Ok(())
    }

    /// Puts the front of `data` into the part it belongs to; returns the bytes used.
    fn push_some(&mut self, data: &[u8]) -> Result<usize, DecodeError> {
        let Some(header) = self.header else {
            let n = put(&mut self.head, self.at, data);
            self.crc.update(data.get(..n).unwrap_or_default());
            if self.at + n == HEADER_LEN {
                let h = Header::decode(&self.head)?;
                self.fixed = if h.kind == MsgType::Frame { FRAME_FIXED_LEN } else { h.payload_len as usize };
                self.header = Some(h);
            }
            return Ok(n);
        };
        let p = self.at - HEADER_LEN;
        let (fixed, image, payload) = (self.fixed, self.image, self.payload_len());
        let n = if p < fixed {
            let n = put(self.small.get_mut(..fixed).unwrap_or_default(), p, data);
            if p + n == fixed && header.kind == MsgType::Frame {
                self.image = self.frame_image_bytes(&header)?;
            }
            n
        } else if p < fixed + image {
            put(self.left.get_mut(..image).unwrap_or_default(), p - fixed, data)
        } else if p < fixed + 2 * image {
            put(self.right.get_mut(..image).unwrap_or_default(), p - fixed - image, data)
        } else if p < payload + CRC_LEN {
            return Ok(put(&mut self.trailer, p - payload, data));
        } else {
            return Err(DecodeError::BadLength { kind: header.kind, len: header.payload_len });
        };
        self.crc.update(data.get(..n).unwrap_or_default());
        Ok(n)
    }

    /// Checks a frame's image size (from its fixed part) against the header and the buffers.
    fn frame_image_bytes(&self, header: &Header) -> Result<usize, DecodeError> {
        let mut d = Dec::new(&self.small);
        let (width, height) = (d.u16(), d.u16());
        let pixels = u32::from(width) * u32::from(height);
        let image_bytes = u64::from(pixels) * BYTES_PER_PIXEL as u64;
        if u64::from(header.payload_len) != FRAME_FIXED_LEN as u64 + 2 * image_bytes {
            return Err(DecodeError::BadLength { kind: MsgType::Frame, len: header.payload_len });
        }
        let capacity = self.left.len().min(self.right.len()) / BYTES_PER_PIXEL;
        match usize::try_from(image_bytes) {
            Ok(n) if n <= self.left.len() && n <= self.right.len() => Ok(n),
            _ => Err(DecodeError::FrameTooLarge { pixels, capacity: u32::try_from(capacity).unwrap_or(u32::MAX) }),
        }
    }

    /// Ready for the next message (after a damaged one).
    fn reset(&mut self) {
        self.header = None;
        self.fixed = 0;
        self.image = 0;
        self.at = 0;
        self.crc = Crc32::new();
    }

    /// The message, once the delimiter has arrived: complete, with a matching CRC. The
    /// receive buffers move into a returned frame.
    fn finish(&mut self) -> Result<Envelope<'b>, DecodeError> {
        let Some(header) = self.header else { return Err(DecodeError::Framing) };
        if self.at != HEADER_LEN + self.payload_len() + CRC_LEN {
            return Err(DecodeError::Framing);
        }
        let received = u32::from_le_bytes(self.trailer);
        let computed = self.crc.finish();
        if received != computed {
            return Err(DecodeError::BadCrc { received, computed });
        }
        let message = if header.kind == MsgType::Frame {
            let mut d = Dec::new(&self.small);
            let (width, height, time_us) = (d.u16(), d.u16(), d.u64());
            let (q, qd) = (d.f32s::<DOF>(), d.f32s::<DOF>());
            let n = self.image;
            if n > self.left.len() || n > self.right.len() {
                return Err(DecodeError::Framing);
            }
            let (left, right) = (core::mem::take(&mut self.left), core::mem::take(&mut self.right));
            let (left, right) = (left.get(..n).unwrap_or_default(), right.get(..n).unwrap_or_default());
            Message::Frame(Frame { width, height, joints: JointSample { q, qd, time_us }, left, right })
        } else {
            decode_small(header.kind, self.small.get(..self.fixed).unwrap_or_default())?
        };
        Ok(Envelope { sequence: header.sequence, capture_time_us: header.capture_time_us, message })
    }
}

/// What feeding a chunk of wire bytes came to.
enum Step {
    /// The chunk is used up, the message goes on.
    More,
    /// The delimiter after a message arrived.
    Complete,
    /// The message is damaged; `in_step` if the byte that showed it was a delimiter.
    Failed(DecodeError, bool),
}

/// Feeds wire bytes to the COBS state machine and the decoded bytes to `asm`; returns the
/// bytes used and the outcome.
fn feed(state: &mut DecoderState, asm: &mut Assembly<'_>, chunk: &[u8]) -> (usize, Step) {
    let mut i = 0;
    while let Some(rest) = chunk.get(i..).filter(|r| !r.is_empty()) {
        // Inside a run every non-zero byte is data: copy it in one piece.
        if let DecoderState::Grab(n) | DecoderState::GrabChain(n) = *state
            && n > 0
        {
            let run = rest.get(..usize::from(n).min(rest.len())).unwrap_or_default();
            let k = run.iter().position(|&b| b == 0).unwrap_or(run.len());
            if k > 0 {
                if let Err(e) = asm.push(run.get(..k).unwrap_or_default()) {
                    return (i + k, Step::Failed(e, false));
                }
                let left = n - k as u8; // k ≤ n
                *state = match *state {
                    DecoderState::GrabChain(_) => DecoderState::GrabChain(left),
                    _ => DecoderState::Grab(left),
                };
                i += k;
                continue;
            }
        }
        let Some(&b) = rest.first() else { break };
        i += 1;
        match state.feed(b) {
            Ok(DecodeResult::NoData | DecodeResult::DataStart) => {}
            Ok(DecodeResult::DataContinue(d)) => {
                if let Err(e) = asm.push(&[d]) {
                    return (i, Step::Failed(e, false));
                }
            }
            Ok(DecodeResult::DataComplete) => return (i, Step::Complete),
            // A delimiter inside a run: the message was cut short; the delimiter is used.
            Err(_) => return (i, Step::Failed(DecodeError::Framing, true)),
        }
    }
    (i, Step::More)
}

/// Reads one message from `rx`.
///
/// A `FRAME`'s RGB565 images are written into `left[..2·w·h]` and `right[..2·w·h]` and the
/// returned [`Frame`] borrows them; pass empty buffers where no frame is expected (a frame then
/// fails with [`DecodeError::FrameTooLarge`]). The header is checked as soon as it has arrived,
/// a frame's size against the buffers before any image byte is stored, the CRC at the
/// delimiter. After a [`ReadError::Decode`] the reader has skipped to the next delimiter, so
/// the next call reads the next message (on an error the buffers' contents are unspecified).
/// A reader made with [`LinkReader::newest_frames_only`] ends a `FRAME` flagged
/// [`FLAG_NEWER_FOLLOWS`] with [`DecodeError::Superseded`] once its fixed part is checked, and
/// skips the rest in bulk reads into `left` (never more than the undecoded payload and CRC).
///
/// # Errors
/// [`ReadError::Link`] from the source (the link is then unusable), [`ReadError::Decode`] for
/// a damaged message (dropped; the stream is in step again).
pub fn read_message<'b, S: ByteSource>(
    rx: &mut LinkReader<S>,
    left: &'b mut [u8],
    right: &'b mut [u8],
) -> Result<Envelope<'b>, ReadError<S::Error>> {
    read_into(rx, &mut Assembly::new(left, right))
}

/// Reads messages until one decodes, handing the error of every damaged one to `dropped`.
///
/// # Errors
/// The link's error.
pub fn read_valid_message<'b, S: ByteSource>(
    rx: &mut LinkReader<S>,
    left: &'b mut [u8],
    right: &'b mut [u8],
    mut dropped: impl FnMut(DecodeError),
) -> Result<Envelope<'b>, S::Error> {
    let mut asm = Assembly::new(left, right);
    loop {
        match read_into(rx, &mut asm) {
            Ok(env) => return Ok(env),
            Err(ReadError::Decode(e)) => {
                dropped(e);
                asm.reset();
            }
            Err(ReadError::Link(e)) => return Err(e),
        }
    }
}

fn read_into<'b, S: ByteSource>(
    rx: &mut LinkReader<S>,
    asm: &mut Assembly<'b>,
) -> Result<Envelope<'b>, ReadError<S::Error>> {
    let mut state = DecoderState::Idle;
    loop {
        let chunk = rx.fill().map_err(ReadError::Link)?;
        let (used, step) = feed(&mut state, asm, chunk);
        rx.consume(used);
        match step {
            Step::More if rx.skip_superseded && asm.superseded_frame() => {
                // The rest of the message: its undecoded payload and CRC, one wire byte at
                // least for each (a zero travels as a code byte).
                let min_left = (HEADER_LEN + asm.payload_len() + CRC_LEN).saturating_sub(asm.at);
                rx.skip_message(min_left, asm.left).map_err(ReadError::Link)?;
                return Err(ReadError::Decode(DecodeError::Superseded));
            }
            Step::More => {}
            Step::Complete => {
                rx.flags = asm.header.map_or(0, |h| h.flags);
                return asm.finish().map_err(ReadError::Decode);
            }
            Step::Failed(e, in_step) => {
                if !in_step {
                    rx.skip_past_delimiter().map_err(ReadError::Link)?;
                }
                return Err(ReadError::Decode(e));
            }
        }
    }
}

/// Decodes one complete message from the front of `bytes`; returns it and the bytes it used
/// (delimiters included).
///
/// # Errors
/// [`ReadError::Link`]`(`[`Truncated`]`)` if `bytes` ends before the message's delimiter, else
/// as [`read_message`].
pub fn decode<'b>(
    bytes: &[u8],
    left: &'b mut [u8],
    right: &'b mut [u8],
) -> Result<(Envelope<'b>, usize), ReadError<Truncated>> {
    let mut rx = LinkReader::new(SliceSource::new(bytes));
    let env = read_message(&mut rx, left, right)?;
    Ok((env, bytes.len() - rx.get_ref().remaining().len() - rx.buffered().len()))
}

/// A streaming COBS encoder into a [`ByteSink`].
struct CobsWriter<'s, S: ?Sized> {
    sink: &'s mut S,
    /// The current run: its code byte (filled in when the run ends) and up to 254 data bytes.
    run: [u8; RUN],
    run_len: usize,
    out: [u8; TX_CHUNK],
    out_len: usize,
}

impl<'s, S: ByteSink + ?Sized> CobsWriter<'s, S> {
    /// Starts a message (with its leading delimiter).
    fn new(sink: &'s mut S) -> Self {
        Self { sink, run: [0; RUN], run_len: 1, out: [0; TX_CHUNK], out_len: 1 }
    }

    fn push(&mut self, data: &[u8]) -> Result<(), S::Error> {
        for &b in data {
            if b == 0 {
                self.end_run()?;
            } else {
                if let Some(slot) = self.run.get_mut(self.run_len) {
                    *slot = b;
                }
                self.run_len += 1;
                if self.run_len == RUN {
                    self.end_run()?;
                }
            }
        }
        Ok(())
    }

    fn end_run(&mut self) -> Result<(), S::Error> {
        let len = self.run_len.min(RUN);
        if let Some(code) = self.run.first_mut() {
            *code = len as u8; // 1..=255
        }
        if self.out_len + len > TX_CHUNK {
            self.flush()?;
        }
        self.out_len += put(&mut self.out, self.out_len, self.run.get(..len).unwrap_or_default());
        self.run_len = 1;
        Ok(())
    }

    fn flush(&mut self) -> Result<(), S::Error> {
        let n = self.out_len;
        self.out_len = 0;
        self.sink.write_all(self.out.get(..n).unwrap_or_default())
    }

    /// Ends the message with its delimiter.
    fn finish(mut self) -> Result<(), S::Error> {
        self.end_run()?;
        if self.out_len == TX_CHUNK {
            self.flush()?;
        }
        self.out_len += put(&mut self.out, self.out_len, &[0]);
        self.flush()
    }
}

/// Header flag of a `FRAME`: a newer complete frame follows right behind this one (the
/// camera interface's "next frame ready"); a board that is behind drops this one.
pub const FLAG_NEWER_FOLLOWS: u16 = 1;

/// Writes one message to `sink` (header flags 0).
///
/// # Errors
/// As [`write_message_with_flags`].
pub fn write_message<S: ByteSink + ?Sized>(sink: &mut S, env: &Envelope<'_>) -> Result<(), WriteError<S::Error>> {
    write_message_with_flags(sink, env, 0)
}

/// Writes one message to `sink`: `0x00 ‖ COBS(header ‖ payload ‖ CRC) ‖ 0x00`, the header
/// carrying `flags`.
///
/// # Errors
/// [`WriteError::ImageSize`] for a frame whose images are not `width · height ·`
/// [`BYTES_PER_PIXEL`] bytes (nothing is written then), else [`WriteError::Link`].
pub fn write_message_with_flags<S: ByteSink + ?Sized>(
    sink: &mut S,
    env: &Envelope<'_>,
    flags: u16,
) -> Result<(), WriteError<S::Error>> {
    let mut small = [0u8; MAX_SMALL_PAYLOAD];
    let (len, images) = encode_payload(&env.message, &mut small);
    let (left, right): (&[u8], &[u8]) = images.unwrap_or((&[], &[]));
    if let Message::Frame(f) = &env.message {
        let expected = usize::from(f.width) * usize::from(f.height) * BYTES_PER_PIXEL;
        if left.len() != expected || right.len() != expected {
            return Err(WriteError::ImageSize { expected, left: left.len(), right: right.len() });
        }
    }
    let payload_len = len + left.len() + right.len();
    let header = Header {
        kind: env.message.kind(),
        flags,
        sequence: env.sequence,
        payload_len: u32::try_from(payload_len).unwrap_or(u32::MAX),
        capture_time_us: env.capture_time_us,
    }
    .encode();
    let fixed = small.get(..len).unwrap_or(&[]);
    let mut crc = Crc32::new();
    let mut w = CobsWriter::new(sink);
    for part in [&header[..], fixed, left, right] {
        crc.update(part);
        w.push(part).map_err(WriteError::Link)?;
    }
    w.push(&crc.finish().to_le_bytes()).map_err(WriteError::Link)?;
    w.finish().map_err(WriteError::Link)
}

/// The size of a message before framing: header, payload and CRC.
pub fn raw_len(message: &Message<'_>) -> usize {
    let payload = match message {
        Message::Frame(f) => FRAME_FIXED_LEN + 2 * BYTES_PER_PIXEL * usize::from(f.width) * usize::from(f.height),
        m => m.kind().fixed_payload_len().unwrap_or(0),
    };
    HEADER_LEN + payload + CRC_LEN
}

/// The most bytes a message takes on the wire: [`raw_len`], one COBS code byte per 254 bytes
/// (and one more), and the two delimiters.
pub fn max_encoded_len(message: &Message<'_>) -> usize {
    let raw = raw_len(message);
    raw + raw / 254 + 1 + 2
}
