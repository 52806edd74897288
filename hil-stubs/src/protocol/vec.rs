//! `std` helpers for hosts and tests (feature `host`): a growable sink and one-call encoding.

use std::vec::Vec;

use super::{ByteSink, Envelope, Truncated, WriteError, max_encoded_len, write_message};

/// A [`ByteSink`] that collects everything in a `Vec`. It never fails; its error type is
/// [`SliceSource`](super::SliceSource)'s, so the two can be the ends of one link in tests.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct VecSink(pub Vec<u8>);

impl ByteSink for VecSink {
    type Error = Truncated;
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), Truncated> {
        self.0.extend_from_slice(bytes);
        Ok(())
    }
}

/// One message as it goes on the wire (delimiters included).
///
/// # Errors
/// [`WriteError::ImageSize`] for a frame whose images do not match its size.
pub fn encode_to_vec(env: &Envelope<'_>) -> Result<Vec<u8>, WriteError<Truncated>> {
    let mut sink = VecSink(Vec::with_capacity(max_encoded_len(&env.message)));
    write_message(&mut sink, env)?;
    Ok(sink.0)
}
