//! OMG CDR (XCDR1, the encoding of ROS 2's `rmw` and of rosbag2's `cdr` messages), read and
//! written by hand for the few fixed message layouts evorec needs (see [`super::msgs`]).
//!
//! A message starts with a 4-byte encapsulation header: `00 01` little-endian or `00 00`
//! big-endian plain CDR, then two option bytes. Primitives are aligned to their size relative
//! to the byte after the header; a string is a `u32` length counting its NUL, the bytes and the
//! NUL; a sequence is a `u32` count and its elements; a fixed array is its elements alone.
//!
//! The reader never panics: every read is bounds-checked and a short or malformed message is
//! a [`CdrError`] saying which field and at which byte offset.

use std::fmt;

/// A malformed CDR message: the field being read, the byte offset and what was wrong.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CdrError {
    /// The field being read (e.g. `header.frame_id`).
    pub field: String,
    /// Byte offset in the message (after the encapsulation header).
    pub offset: usize,
    /// What was wrong.
    pub problem: String,
}

impl fmt::Display for CdrError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "field {} at byte {}: {}", self.field, self.offset, self.problem)
    }
}

impl std::error::Error for CdrError {}

/// Result of a CDR read.
pub type Result<T> = std::result::Result<T, CdrError>;

/// Reads one CDR message.
pub struct Reader<'a> {
    body: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> Reader<'a> {
    /// A reader over `bytes`, checking the encapsulation header.
    ///
    /// # Errors
    /// Fewer than 4 bytes, or an encapsulation other than plain CDR (XCDR2, PL_CDR).
    pub fn new(bytes: &'a [u8]) -> Result<Self> {
        let bad = |problem: String| CdrError { field: "encapsulation header".into(), offset: 0, problem };
        let Some(head) = bytes.get(..4) else {
            return Err(bad(format!("message has {} bytes, fewer than the 4-byte header", bytes.len())));
        };
        let little = match (head[0], head[1]) {
            (0, 1) => true,
            (0, 0) => false,
            (a, b) => return Err(bad(format!("encapsulation {a:02x} {b:02x} is not plain CDR (00 00 or 00 01)"))),
        };
        Ok(Self { body: &bytes[4..], pos: 0, little })
    }

    fn err(&self, field: &str, problem: impl Into<String>) -> CdrError {
        CdrError { field: field.to_owned(), offset: self.pos, problem: problem.into() }
    }

    fn take(&mut self, field: &str, n: usize, align: usize) -> Result<&'a [u8]> {
        let start = self.pos.next_multiple_of(align);
        let end = start.checked_add(n).filter(|e| *e <= self.body.len());
        let Some(end) = end else {
            return Err(self.err(field, format!("needs {n} bytes, the message ends at byte {}", self.body.len())));
        };
        self.pos = end;
        Ok(&self.body[start..end])
    }

    fn array<const N: usize>(&mut self, field: &str) -> Result<[u8; N]> {
        let s = self.take(field, N, N)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        if !self.little {
            a.reverse();
        }
        Ok(a)
    }

    /// A `uint8` (or `bool`, `char`).
    ///
    /// # Errors
    /// The message ends.
    pub fn u8(&mut self, field: &str) -> Result<u8> {
        Ok(self.take(field, 1, 1)?[0])
    }

    /// A `uint32`.
    ///
    /// # Errors
    /// The message ends.
    pub fn u32(&mut self, field: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(self.array::<4>(field)?))
    }

    /// An `int32`.
    ///
    /// # Errors
    /// The message ends.
    pub fn i32(&mut self, field: &str) -> Result<i32> {
        Ok(i32::from_le_bytes(self.array::<4>(field)?))
    }

    /// A `float32`.
    ///
    /// # Errors
    /// The message ends.
    pub fn f32(&mut self, field: &str) -> Result<f32> {
        Ok(f32::from_le_bytes(self.array::<4>(field)?))
    }

    /// A `float64`.
    ///
    /// # Errors
    /// The message ends.
    pub fn f64(&mut self, field: &str) -> Result<f64> {
        Ok(f64::from_le_bytes(self.array::<8>(field)?))
    }

    /// A sequence length, checked against the bytes left (each element taking at least
    /// `min_size` bytes), so a corrupt length cannot make a huge allocation.
    ///
    /// # Errors
    /// The message ends, or the count cannot fit in what is left.
    pub fn len(&mut self, field: &str, min_size: usize) -> Result<usize> {
        let n = self.u32(field)? as usize;
        let left = self.body.len() - self.pos;
        if n.saturating_mul(min_size.max(1)) > left {
            return Err(self.err(field, format!("sequence of {n} elements cannot fit in the {left} bytes left")));
        }
        Ok(n)
    }

    /// A `string` (UTF-8, NUL-terminated).
    ///
    /// # Errors
    /// The message ends, no terminating NUL, or not UTF-8.
    pub fn string(&mut self, field: &str) -> Result<String> {
        let n = self.len(field, 1)?;
        if n == 0 {
            // Some writers encode the empty string with no NUL at all.
            return Ok(String::new());
        }
        let bytes = self.take(field, n, 1)?;
        let Some((&0, text)) = bytes.split_last() else {
            return Err(self.err(field, "string is not NUL-terminated"));
        };
        String::from_utf8(text.to_vec()).map_err(|_| self.err(field, "string is not UTF-8"))
    }

    /// A `uint8[]` sequence, borrowed.
    ///
    /// # Errors
    /// The message ends.
    pub fn bytes(&mut self, field: &str) -> Result<&'a [u8]> {
        let n = self.len(field, 1)?;
        self.take(field, n, 1)
    }

    /// A `float64[]` sequence.
    ///
    /// # Errors
    /// The message ends.
    pub fn f64_seq(&mut self, field: &str) -> Result<Vec<f64>> {
        let n = self.len(field, 8)?;
        (0..n).map(|_| self.f64(field)).collect()
    }

    /// A `float64[N]` fixed array.
    ///
    /// # Errors
    /// The message ends.
    pub fn f64_array<const N: usize>(&mut self, field: &str) -> Result<[f64; N]> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64(field)?;
        }
        Ok(out)
    }

    /// Checks that the message was read to its last byte.
    ///
    /// # Errors
    /// Bytes are left after the last field.
    pub fn finish(&self) -> Result<()> {
        match self.body.len() - self.pos {
            0 => Ok(()),
            n => Err(self.err("end of message", format!("{n} bytes left after the last field"))),
        }
    }

    /// A `string[]` sequence.
    ///
    /// # Errors
    /// The message ends, or a bad string.
    pub fn string_seq(&mut self, field: &str) -> Result<Vec<String>> {
        let n = self.len(field, 4)?;
        (0..n).map(|_| self.string(field)).collect()
    }
}

/// Writes one little-endian CDR message (header `00 01 00 00`).
#[derive(Debug, Default)]
pub struct Writer {
    buf: Vec<u8>,
}

impl Writer {
    /// An empty message (its header written).
    pub fn new() -> Self {
        Self { buf: vec![0, 1, 0, 0] }
    }

    fn align(&mut self, n: usize) {
        while !(self.buf.len() - 4).is_multiple_of(n) {
            self.buf.push(0);
        }
    }

    /// A `uint8`.
    pub fn u8(&mut self, v: u8) {
        self.buf.push(v);
    }

    /// A `uint32`.
    pub fn u32(&mut self, v: u32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// An `int32`.
    pub fn i32(&mut self, v: i32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float32`.
    pub fn f32(&mut self, v: f32) {
        self.align(4);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `float64`.
    pub fn f64(&mut self, v: f64) {
        self.align(8);
        self.buf.extend_from_slice(&v.to_le_bytes());
    }

    /// A `string`.
    pub fn string(&mut self, s: &str) {
        self.u32(u32::try_from(s.len() + 1).unwrap_or(u32::MAX));
        self.buf.extend_from_slice(s.as_bytes());
        self.buf.push(0);
    }

    /// A `uint8[]` sequence.
    pub fn bytes(&mut self, b: &[u8]) {
        self.u32(u32::try_from(b.len()).unwrap_or(u32::MAX));
        self.buf.extend_from_slice(b);
    }

    /// The message's bytes.
    pub fn finish(self) -> Vec<u8> {
        self.buf
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn written_values_read_back_aligned() {
        let mut w = Writer::new();
        w.u8(7);
        w.string("ab");
        w.f64(1.5);
        w.i32(-3);
        w.bytes(&[1, 2, 3]);
        let bytes = w.finish();
        // u8 at 0, string length at 4, "ab\0" at 8..11, f64 at 16.
        assert_eq!(bytes.len(), 4 + 16 + 8 + 4 + 4 + 3);
        let mut r = Reader::new(&bytes).unwrap();
        assert_eq!(r.u8("a").unwrap(), 7);
        assert_eq!(r.string("b").unwrap(), "ab");
        assert_eq!(r.f64("c").unwrap(), 1.5);
        assert_eq!(r.i32("d").unwrap(), -3);
        assert_eq!(r.bytes("e").unwrap(), &[1, 2, 3]);
        let err = r.u32("f").unwrap_err();
        assert_eq!(err.field, "f");
        assert!(err.to_string().contains("message ends"), "{err}");
    }

    #[test]
    fn big_endian_and_bad_headers() {
        let bytes = [0, 0, 0, 0, 0, 0, 0, 5];
        assert_eq!(Reader::new(&bytes).unwrap().u32("n").unwrap(), 5);
        assert!(Reader::new(&[0, 7, 0, 0]).is_err());
        assert!(Reader::new(&[0, 1]).is_err());
        // A sequence count larger than the message is refused before allocating.
        let bytes = [0, 1, 0, 0, 255, 255, 255, 255];
        let err = Reader::new(&bytes).unwrap().f64_seq("d").unwrap_err();
        assert!(err.problem.contains("cannot fit"), "{err}");
    }
}
