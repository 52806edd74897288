//! The firmware's only `unsafe` code: semihosting file calls and the stack scan.
//!
//! Semihosting (Arm "Semihosting for AArch32 and AArch64", §6) lets code on the target ask the
//! debugger — here QEMU with `-semihosting-config enable=on,target=native` — to open, read and
//! write host files. QEMU resolves relative paths against its working directory; named FIFOs
//! there make a lock-step byte link to a host process.

use core::ffi::CStr;

use cortex_m_semihosting::{nr, syscall};

use crate::link_board::StackUsage;
use crate::protocol::{ByteSink, ByteSource};

/// A semihosting call on a host file failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostIoError {
    /// `SYS_OPEN` returned -1 (no such file, or no permission).
    Open,
    /// `SYS_READ`/`SYS_WRITE` reported an error.
    Io,
    /// The host closed its end (a read returned no bytes).
    EndOfFile,
}

/// How to open a host file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// `fopen(path, "rb")`.
    Read,
    /// `fopen(path, "wb")`.
    Write,
}

/// A file (or FIFO) on the host, opened through semihosting.
#[derive(Debug)]
pub struct HostFile {
    fd: usize,
}

impl HostFile {
    /// Opens `path` (relative to QEMU's working directory). Opening a FIFO blocks until the
    /// host opens its other end.
    ///
    /// # Errors
    /// [`HostIoError::Open`].
    pub fn open(path: &CStr, mode: Mode) -> Result<Self, HostIoError> {
        let mode = match mode {
            Mode::Read => nr::open::R_BINARY,
            Mode::Write => nr::open::W_TRUNC_BINARY,
        };
        let len = path.to_bytes().len();
        // SAFETY: SYS_OPEN takes (pointer to a NUL-terminated name, mode, length without the
        // NUL); `path` is a valid `CStr` that outlives the call, and the host only reads it.
        let fd = unsafe { syscall(nr::OPEN, &[path.as_ptr() as usize, mode, len]) };
        if fd as isize == -1 { Err(HostIoError::Open) } else { Ok(Self { fd }) }
    }
}

impl ByteSource for HostFile {
    type Error = HostIoError;

    fn read_some(&mut self, buf: &mut [u8]) -> Result<usize, HostIoError> {
        let len = buf.len();
        // SAFETY: SYS_READ takes (fd, buffer, length) and writes at most `length` bytes into
        // the buffer; `buf` is a live, exclusively borrowed slice of that length. On a FIFO the
        // host's read returns what is there (at least one byte, or end of file).
        let not_read = unsafe { syscall(nr::READ, &[self.fd, buf.as_mut_ptr() as usize, len]) };
        // The call returns the number of bytes NOT read (so `len` means end of file), or an
        // error value above `len`.
        let got = len.checked_sub(not_read).ok_or(HostIoError::Io)?;
        if got == 0 {
            return Err(HostIoError::EndOfFile);
        }
        Ok(got)
    }
}

impl ByteSink for HostFile {
    type Error = HostIoError;

    fn write_all(&mut self, bytes: &[u8]) -> Result<(), HostIoError> {
        let mut done = 0;
        while let Some(rest) = bytes.get(done..).filter(|r| !r.is_empty()) {
            let len = rest.len();
            // SAFETY: SYS_WRITE takes (fd, buffer, length) and only reads `length` bytes of
            // the buffer; `rest` is a live slice of that length.
            let not_written = unsafe { syscall(nr::WRITE, &[self.fd, rest.as_ptr() as usize, len]) };
            let put = len.checked_sub(not_written).ok_or(HostIoError::Io)?;
            if put == 0 {
                return Err(HostIoError::Io);
            }
            done += put;
        }
        Ok(())
    }
}

impl Drop for HostFile {
    fn drop(&mut self) {
        // SAFETY: SYS_CLOSE takes the descriptor SYS_OPEN returned; it is closed only here.
        let _ = unsafe { syscall(nr::CLOSE, &[self.fd]) };
    }
}

unsafe extern "C" {
    /// Lowest address of the stack region (end of .bss/.uninit), from cortex-m-rt's link.x.
    static _stack_end: u32;
    /// Initial stack pointer (top of RAM), from cortex-m-rt's link.x.
    static _stack_start: u32;
}

/// The stack high-water mark: cortex-m-rt's `paint-stack` filled `_stack_end.._stack_start`
/// with [`cortex_m_rt::STACK_PAINT_VALUE`] before `main`; the lowest word that no longer holds
/// it bounds the deepest stack use so far.
pub fn stack_usage() -> StackUsage {
    let bottom = &raw const _stack_end as usize;
    let top = &raw const _stack_start as usize;
    let mut p = bottom;
    while p < top {
        // SAFETY: `p` is word-aligned (link.x asserts `_stack_end % 4 == 0`) and inside the
        // stack region of RAM, which is always mapped; a volatile read of a word there has no
        // side effects, and words below the stack pointer are not referenced by any Rust value.
        let word = unsafe { core::ptr::read_volatile(p as *const u32) };
        if word != cortex_m_rt::STACK_PAINT_VALUE {
            break;
        }
        p += 4;
    }
    StackUsage { used_bytes: (top - p) as u32, size_bytes: (top - bottom) as u32 }
}
