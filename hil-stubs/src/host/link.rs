//! The byte link to the firmware: [`IoLink`] over `std::io`, the FIFOs, and the reader thread
//! that turns the firmware → host stream into messages (with injected faults, if any).

use std::format;
use std::fs::{self, File};
use std::io::{self, Read, Write};
use std::path::Path;
use std::process::Command;
use std::string::{String, ToString};
use std::sync::mpsc::{self, Receiver};
use std::sync::{Arc, Mutex};
use std::thread;

use super::error::{HilError, io_error};
use crate::faults::{FaultCounts, FaultInjector, MessageSplitter};
use crate::protocol::{
    ByteSink, ByteSource, DecodeError, Envelope, LinkReader, Message, MsgType, ReadError, read_message,
};

/// A [`ByteSource`]/[`ByteSink`] over any `std::io` reader or writer.
#[derive(Debug)]
pub struct IoLink<T>(pub T);

impl<T: Read> ByteSource for IoLink<T> {
    type Error = io::Error;
    fn read_some(&mut self, buf: &mut [u8]) -> Result<usize, io::Error> {
        loop {
            match self.0.read(buf) {
                Ok(0) if !buf.is_empty() => return Err(io::ErrorKind::UnexpectedEof.into()),
                Ok(n) => return Ok(n),
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
    }
}

impl<T: Write> ByteSink for IoLink<T> {
    type Error = io::Error;
    fn write_all(&mut self, bytes: &[u8]) -> Result<(), io::Error> {
        self.0.write_all(bytes)
    }
}

/// What the reader thread hands over (one at a time, so the large variant is not boxed).
#[derive(Debug)]
#[allow(clippy::large_enum_variant)]
pub(super) enum Incoming {
    /// A valid message.
    Message(Envelope<'static>),
    /// A damaged message (dropped).
    Damaged(DecodeError),
    /// The link closed or failed.
    Closed(HilError),
}

/// Replaces whatever is at `path` with a fresh FIFO.
pub(super) fn make_fifo(path: &Path) -> Result<(), HilError> {
    match fs::remove_file(path) {
        Ok(()) => {}
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) => return Err(HilError::Io { what: format!("remove {}", path.display()), source: e }),
    }
    let status =
        Command::new("mkfifo").arg(path).status().map_err(io_error(format!("run mkfifo {}", path.display())))?;
    if status.success() {
        Ok(())
    } else {
        Err(HilError::Io { what: format!("mkfifo {}", path.display()), source: io::Error::other(status.to_string()) })
    }
}

/// The firmware → host stream as the host sees it: the FIFO, with faults injected message
/// by message when a [`FaultInjector`] is given (never into `ACK` and `DONE`, which the
/// firmware does not repeat).
struct ReplyStream {
    file: File,
    faults: Option<FaultInjector>,
    counts: Arc<Mutex<FaultCounts>>,
    splitter: MessageSplitter,
    queue: std::collections::VecDeque<u8>,
}

impl ByteSource for ReplyStream {
    type Error = io::Error;
    fn read_some(&mut self, buf: &mut [u8]) -> Result<usize, io::Error> {
        let mut chunk = [0u8; 4096];
        while self.queue.is_empty() {
            let n = self.file.read(&mut chunk)?;
            if n == 0 {
                return Err(io::ErrorKind::UnexpectedEof.into());
            }
            let data = chunk.get(..n).unwrap_or_default();
            let Some(faults) = self.faults.as_mut() else {
                self.queue.extend(data);
                continue;
            };
            let queue = &mut self.queue;
            self.splitter.push(data, |m| {
                let handshake = matches!(
                    crate::protocol::decode(&m, &mut [], &mut []),
                    Ok((Envelope { message: Message::Ack(_) | Message::Done(_), .. }, _))
                );
                if handshake {
                    queue.extend(faults.release());
                    queue.extend(m);
                } else {
                    queue.extend(faults.pass(&m));
                }
            });
            if let Ok(mut c) = self.counts.lock() {
                *c = faults.counts();
            }
        }
        let n = buf.len().min(self.queue.len());
        for (dst, src) in buf.iter_mut().zip(self.queue.drain(..n)) {
            *dst = src;
        }
        Ok(n)
    }
}

/// Reads messages from the firmware until the link closes; each goes to the channel.
pub(super) fn spawn_reader(
    file: File,
    faults: Option<FaultInjector>,
    counts: Arc<Mutex<FaultCounts>>,
) -> Receiver<Incoming> {
    let (tx, rx) = mpsc::channel();
    thread::spawn(move || {
        let stream =
            ReplyStream { file, faults, counts, splitter: MessageSplitter::default(), queue: Default::default() };
        let mut src = LinkReader::new(stream);
        loop {
            let item = match read_message(&mut src, &mut [], &mut []) {
                Ok(env) => match env.message.detach() {
                    Some(message) => Incoming::Message(Envelope {
                        sequence: env.sequence,
                        capture_time_us: env.capture_time_us,
                        message,
                    }),
                    None => Incoming::Closed(HilError::Unexpected {
                        got: MsgType::Frame,
                        sequence: env.sequence,
                        expected: "a reply",
                    }),
                },
                Err(ReadError::Decode(e)) => Incoming::Damaged(e),
                // End of file (QEMU closed the FIFO) or a read error: the link is gone.
                Err(ReadError::Link(_)) => {
                    Incoming::Closed(HilError::QemuExited { status: None, log_tail: String::new() })
                }
            };
            let stop = matches!(item, Incoming::Closed(_));
            if tx.send(item).is_err() || stop {
                break;
            }
        }
    });
    rx
}
