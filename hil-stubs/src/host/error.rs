//! [`HilError`]: why a session failed, with what to do about it.

use std::io;
use std::path::PathBuf;
use std::process::ExitStatus;
use std::string::String;
use std::time::Duration;

use super::{FIRMWARE_BUILD_HINT, FIRMWARE_ENV, QEMU_INSTALL_HINT};
use crate::protocol::{DecodeError, ErrorCode, MsgType};
use crate::setup::SetupError;

/// Why a session failed. The `Display` text says what to do where there is something to do.
#[derive(Debug)]
#[non_exhaustive]
pub enum HilError {
    /// The QEMU executable was not found.
    QemuNotFound {
        /// The program that was looked for.
        program: PathBuf,
    },
    /// The firmware ELF does not exist.
    FirmwareNotFound {
        /// The path that was looked at.
        path: PathBuf,
    },
    /// A file-system or process operation failed.
    Io {
        /// What was being done.
        what: String,
        /// The error.
        source: io::Error,
    },
    /// The setup gives no tracker (checked on the host before QEMU starts).
    Setup(SetupError),
    /// The firmware refused the `CONFIG` (its `ACK` status).
    ConfigRefused {
        /// The status code (see [`SetupError::describe_code`]).
        code: u32,
    },
    /// The firmware sent `ERROR` and stops.
    Firmware {
        /// The code (see [`ErrorCode`]).
        code: u32,
        /// The end of the firmware's log.
        log_tail: String,
    },
    /// QEMU exited (or closed the link) before the conversation ended.
    QemuExited {
        /// Its exit status, if it has exited.
        status: Option<ExitStatus>,
        /// The end of its log.
        log_tail: String,
    },
    /// Nothing arrived in time; QEMU was killed.
    Timeout {
        /// What was awaited.
        waiting_for: &'static str,
        /// How long.
        after: Duration,
        /// The end of QEMU's log.
        log_tail: String,
    },
    /// The firmware sent a malformed message.
    Protocol(DecodeError),
    /// The firmware sent a valid message that does not fit the conversation.
    Unexpected {
        /// What arrived.
        got: MsgType,
        /// Its sequence number.
        sequence: u32,
        /// What was awaited.
        expected: &'static str,
    },
    /// A frame's images are not `width · height · 2` bytes (RGB565) each.
    BadFrame {
        /// `width · height · 2`.
        expected: usize,
        /// Left image length.
        left: usize,
        /// Right image length.
        right: usize,
    },
}

impl std::fmt::Display for HilError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::QemuNotFound { program } => {
                write!(f, "{} not found: install it with `{QEMU_INSTALL_HINT}`", program.display())
            }
            Self::FirmwareNotFound { path } => write!(
                f,
                "firmware image {} not found: build it with `{FIRMWARE_BUILD_HINT}` \
                 (or point {FIRMWARE_ENV} at an ELF)",
                path.display()
            ),
            Self::Io { what, source } => write!(f, "{what}: {source}"),
            Self::Setup(e) => write!(f, "setup gives no tracker: {e}"),
            Self::ConfigRefused { code } => {
                write!(f, "firmware refused the CONFIG: status {code} ({})", SetupError::describe_code(*code))
            }
            Self::Firmware { code, log_tail } => {
                let what = match ErrorCode::from_u32(*code) {
                    Some(ErrorCode::Link) => "link failure",
                    Some(ErrorCode::Decode) => "malformed message",
                    Some(ErrorCode::Unexpected) => "unexpected message",
                    _ => "other failure",
                };
                write!(f, "firmware stopped with error {code} ({what}); its log ends:\n{log_tail}")
            }
            Self::QemuExited { status, log_tail } => match status {
                Some(s) => write!(f, "QEMU exited early ({s}); its log ends:\n{log_tail}"),
                None => write!(f, "QEMU closed the link early; its log ends:\n{log_tail}"),
            },
            Self::Timeout { waiting_for, after, log_tail } => {
                write!(
                    f,
                    "no {waiting_for} from the firmware within {after:?} (QEMU killed); its log ends:\n{log_tail}"
                )
            }
            Self::Protocol(e) => write!(f, "malformed message from the firmware: {e}"),
            Self::Unexpected { got, sequence, expected } => {
                write!(f, "expected {expected} from the firmware, got {got:?} (sequence {sequence})")
            }
            Self::BadFrame { expected, left, right } => {
                write!(f, "frame images have {left} and {right} bytes, width x height x 2 (RGB565) is {expected}")
            }
        }
    }
}

impl std::error::Error for HilError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Self::Io { source, .. } => Some(source),
            Self::Setup(e) => Some(e),
            Self::Protocol(e) => Some(e),
            _ => None,
        }
    }
}

pub(super) fn io_error(what: impl Into<String>) -> impl FnOnce(io::Error) -> HilError {
    let what = what.into();
    move |source| HilError::Io { what, source }
}
