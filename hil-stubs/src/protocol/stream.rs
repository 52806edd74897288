//! The byte-stream layer: the link traits, slice adapters and the read/write errors.

use super::{BYTES_PER_PIXEL, DecodeError};

/// A blocking source of bytes (one end of the link).
pub trait ByteSource {
    /// Error of the underlying link.
    type Error;
    /// Reads at least one and at most `buf.len()` bytes into `buf` (`buf` is never empty),
    /// blocking only until one byte is there; returns how many. The end of the stream is an
    /// error.
    ///
    /// # Errors
    /// The link's error.
    fn read_some(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error>;
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
    fn read_some(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        T::read_some(self, buf)
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
    fn read_some(&mut self, buf: &mut [u8]) -> Result<usize, Truncated> {
        let n = buf.len().min(self.rest.len());
        if n == 0 {
            return Err(Truncated);
        }
        let (head, tail) = self.rest.split_at(n);
        buf.get_mut(..n).ok_or(Truncated)?.copy_from_slice(head);
        self.rest = tail;
        Ok(n)
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

/// Why [`super::read_message`] failed.
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

/// Why [`super::write_message`] failed.
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
