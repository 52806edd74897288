//! The host side of the hardware-in-the-loop link (feature `host`, needs std).
//!
//! [`HilSession`] runs the firmware ELF under QEMU (`mps2-an386`, Cortex-M4F) and talks to it
//! over two named FIFOs in a working directory, with the [`crate::protocol`]:
//!
//! ```no_run
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use evorec_firmware::host::{HilSession, Reply, default_firmware_path};
//! use evorec_firmware::protocol::Frame;
//! # let setup: evorec_firmware::protocol::Setup = todo!();
//! // Two RGB565 images (2 bytes per pixel), as the cameras deliver them.
//! # let (left, right, joints) = (vec![0u8; 160 * 120 * 2], vec![0u8; 160 * 120 * 2], todo!());
//! let mut hil = HilSession::start(&default_firmware_path(), "out/hil".as_ref(), &setup)?;
//! let frame = Frame { width: 160, height: 120, joints, left: &left, right: &right };
//! match hil.step(1, 33_333, &frame)? {
//!     Reply::Estimate(e) => println!("ψ = {:?}, F = {}", e.psi, e.fitness),
//!     Reply::Rejected => println!("the tracker refused the frame"),
//!     Reply::Lost => println!("no valid reply in time (a damaged link): the frame is lost"),
//! }
//! let summary = hil.finish()?; // END → DONE, QEMU exits with success
//! println!("stack high-water mark: {} bytes", summary.done.stack_used_bytes);
//! # Ok(()) }
//! ```
//!
//! In the working directory the session creates `evorec-h2f.fifo` and `evorec-f2h.fifo`
//! (replacing stale ones) and `firmware.log` (QEMU's stdout and stderr: the firmware's `log`
//! output). Both sides open the FIFOs in the same order (host→firmware first), because
//! opening a FIFO blocks until its other end is opened. Every wait is bounded
//! ([`HilOptions`]); a QEMU that exits or hangs is reported with the tail of its log, and
//! dropping a session kills QEMU.

use std::format;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::string::{String, ToString};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::{Duration, Instant};
use std::vec::Vec;

use evorec_core::Tracker;
use evorec_core::tracker::Estimate;

use crate::BoardProfile;
use crate::faults::{FaultConfig, FaultCounts, FaultInjector};
use crate::protocol::{
    Done, DropCounts, Envelope, FLAG_NEWER_FOLLOWS, Frame, Message, Setup, WriteError, write_message_with_flags,
};

mod error;
mod firmware;
mod link;

pub use error::HilError;
use error::io_error;
pub use firmware::{build_firmware, default_firmware_path, profile_target_dir};
pub use link::IoLink;
use link::{Incoming, make_fifo, spawn_reader};

/// How to install QEMU on Debian/Ubuntu.
pub const QEMU_INSTALL_HINT: &str = "apt-get update && apt-get install -y qemu-system-arm";
/// How to build the firmware.
pub const FIRMWARE_BUILD_HINT: &str = "cd hil-stubs && cargo build --release";
/// Environment variable naming the firmware ELF (overrides [`default_firmware_path`]'s search).
pub const FIRMWARE_ENV: &str = "EVOREC_FIRMWARE_ELF";
/// Host → firmware FIFO name (in the working directory).
pub const HOST_TO_FIRMWARE: &str = "evorec-h2f.fifo";
/// Firmware → host FIFO name.
pub const FIRMWARE_TO_HOST: &str = "evorec-f2h.fifo";
/// QEMU's output file name.
pub const LOG_FILE: &str = "firmware.log";
/// With faults: how often `CONFIG` and `END` are sent before the session gives up waiting.
pub const HANDSHAKE_TRIES: u32 = 8;

/// Session settings; [`HilOptions::default`] states the defaults.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HilOptions {
    /// The QEMU executable (default `qemu-system-arm`, found through `PATH`).
    pub qemu: PathBuf,
    /// The board the firmware was built for: QEMU's `-cpu` and `-machine` (default
    /// [`BoardProfile::M4`]; [`BoardProfile::M7`] for an image built with the `m7` feature).
    pub profile: BoardProfile,
    /// Longest wait for QEMU to open the link (default 30 s).
    pub start_timeout: Duration,
    /// Longest wait for any one reply, and for QEMU to exit after `DONE` (default 60 s).
    pub reply_timeout: Duration,
    /// Link fault injection into the messages to the firmware (default none). With faults in
    /// either direction, a frame whose answer does not come within
    /// [`HilOptions::lost_timeout`] is [`Reply::Lost`], damaged and out-of-sequence replies are
    /// dropped and counted, and `CONFIG` and `END` are sent again when their answer does not
    /// come.
    pub faults_to_firmware: Option<FaultConfig>,
    /// Link fault injection into the replies (default none; never into `ACK` and `DONE`).
    pub faults_to_host: Option<FaultConfig>,
    /// With faults: how long to wait for a frame's answer (default 1 s).
    pub lost_timeout: Duration,
}

impl Default for HilOptions {
    fn default() -> Self {
        Self {
            qemu: PathBuf::from("qemu-system-arm"),
            profile: BoardProfile::M4,
            start_timeout: Duration::from_secs(30),
            reply_timeout: Duration::from_secs(60),
            faults_to_firmware: None,
            faults_to_host: None,
            lost_timeout: Duration::from_secs(1),
        }
    }
}

/// The firmware's answer to a frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reply {
    /// The estimate of the generation run on the frame.
    Estimate(Estimate),
    /// The tracker refused the frame (wrong size, non-finite joints, time step out of range).
    Rejected,
    /// No valid answer came in time (only with fault injection: the frame or its answer was
    /// damaged, dropped or delayed).
    Lost,
}

/// What a finished session reports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Summary {
    /// The firmware's `DONE`: loop counts and stack high-water mark.
    pub done: Done,
    /// QEMU's output (the firmware's log).
    pub log_path: PathBuf,
    /// The host's side of the link: replies it dropped, by reason (damaged, out-of-sequence).
    pub host_drops: DropCounts,
    /// Frames that got no valid answer in time ([`Reply::Lost`]).
    pub lost: u32,
    /// Faults injected into the host → firmware direction.
    pub faults_sent: FaultCounts,
    /// Faults injected into the firmware → host direction.
    pub faults_received: FaultCounts,
}

/// A running firmware under QEMU with an open link; see the [module docs](self).
#[derive(Debug)]
pub struct HilSession {
    qemu: Child,
    exited: Option<ExitStatus>,
    tx: Option<File>,
    rx: Receiver<Incoming>,
    log_path: PathBuf,
    options: HilOptions,
    faults: Option<FaultInjector>,
    /// Faults in either direction: lenient waiting (see [`HilOptions::faults_to_firmware`]).
    fault_mode: bool,
    reply_faults: Arc<Mutex<FaultCounts>>,
    host_drops: DropCounts,
    lost: u32,
}

impl HilSession {
    /// [`HilSession::start_with`] with [`HilOptions::default`].
    ///
    /// # Errors
    /// As [`HilSession::start_with`].
    pub fn start(firmware: &Path, workdir: &Path, setup: &Setup) -> Result<Self, HilError> {
        Self::start_with(firmware, workdir, setup, &HilOptions::default())
    }

    /// Checks `setup` on the host, creates the FIFOs in `workdir` (created if missing), starts
    /// QEMU on `firmware` there, opens the link, sends `CONFIG` and waits for the `ACK`.
    ///
    /// # Errors
    /// [`HilError::Setup`], [`HilError::FirmwareNotFound`], [`HilError::QemuNotFound`],
    /// [`HilError::ConfigRefused`], or a failure of the link or QEMU.
    pub fn start_with(firmware: &Path, workdir: &Path, setup: &Setup, options: &HilOptions) -> Result<Self, HilError> {
        let _: Tracker = setup.build_tracker().map_err(HilError::Setup)?;
        if !firmware.is_file() {
            return Err(HilError::FirmwareNotFound { path: firmware.to_path_buf() });
        }
        let firmware = firmware.canonicalize().map_err(io_error(format!("resolve {}", firmware.display())))?;
        fs::create_dir_all(workdir).map_err(io_error(format!("create {}", workdir.display())))?;
        let h2f = workdir.join(HOST_TO_FIRMWARE);
        let f2h = workdir.join(FIRMWARE_TO_HOST);
        for fifo in [&h2f, &f2h] {
            make_fifo(fifo)?;
        }
        let log_path = workdir.join(LOG_FILE);
        let log = File::create(&log_path).map_err(io_error(format!("create {}", log_path.display())))?;
        let log_err = log.try_clone().map_err(io_error("duplicate the log handle"))?;
        let qemu = Command::new(&options.qemu)
            .args(["-cpu", options.profile.qemu_cpu, "-machine", options.profile.qemu_machine, "-nographic"])
            .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
            .arg(&firmware)
            .current_dir(workdir)
            .stdin(Stdio::null())
            .stdout(log)
            .stderr(log_err)
            .spawn()
            .map_err(|e| match e.kind() {
                io::ErrorKind::NotFound => HilError::QemuNotFound { program: options.qemu.clone() },
                _ => HilError::Io { what: format!("start {}", options.qemu.display()), source: e },
            })?;
        let (_unused_tx, rx) = mpsc::channel();
        let mut session = Self {
            qemu,
            exited: None,
            tx: None,
            rx,
            log_path,
            options: options.clone(),
            faults: options.faults_to_firmware.map(FaultInjector::new),
            fault_mode: options.faults_to_firmware.is_some() || options.faults_to_host.is_some(),
            reply_faults: Arc::default(),
            host_drops: DropCounts::default(),
            lost: 0,
        };
        let deadline = Instant::now() + options.start_timeout;
        session.tx = Some(session.open_fifo(&h2f, true, deadline)?);
        let from_fw = session.open_fifo(&f2h, false, deadline)?;
        let reply_faults = options.faults_to_host.map(FaultInjector::new);
        session.rx = spawn_reader(from_fw, reply_faults, Arc::clone(&session.reply_faults));

        match session.handshake(&Envelope::bare(Message::Config(*setup)), "ACK")? {
            Envelope { message: Message::Ack(0), .. } => Ok(session),
            Envelope { message: Message::Ack(code), .. } => Err(HilError::ConfigRefused { code }),
            env => Err(unexpected(&env, "ACK")),
        }
    }

    /// Sends `env` and waits for the next valid message; with faults, sends `env` again
    /// (up to [`HANDSHAKE_TRIES`] times) while no answer comes within the lost timeout.
    fn handshake(&mut self, env: &Envelope<'_>, waiting_for: &'static str) -> Result<Envelope<'static>, HilError> {
        if !self.fault_mode {
            self.send(env, 0)?;
            return self.recv(waiting_for);
        }
        for _ in 0..HANDSHAKE_TRIES {
            self.send(env, 0)?;
            let deadline = Instant::now() + self.options.lost_timeout;
            loop {
                match self.recv_until(deadline)? {
                    None => break,
                    // Late answers to frames may still arrive: not what is awaited.
                    Some(got) if matches!(got.message, Message::Estimate(_) | Message::Rejected) => {
                        self.host_drops.sequence += 1;
                    }
                    Some(got) => return Ok(got),
                }
            }
        }
        self.recv(waiting_for)
    }

    /// Sends one frame pair (`sequence`, `capture_time_us` as the board's `FrameInfo`) and
    /// waits for the firmware's answer.
    ///
    /// # Errors
    /// [`HilError::BadFrame`], or a failure of the link or QEMU.
    pub fn step(&mut self, sequence: u32, capture_time_us: u64, frame: &Frame<'_>) -> Result<Reply, HilError> {
        self.send(&Envelope { sequence, capture_time_us, message: Message::Frame(*frame) }, 0)?;
        self.answer_to(sequence, frame.joints.time_us)
    }

    /// Overload: offers `frames` back to back, each but the last flagged
    /// [`FLAG_NEWER_FOLLOWS`] (the camera delivered them while the board was busy), and waits
    /// for the answer to the last; the board drops the older ones (counted in `DONE` as
    /// `superseded`) and answers only the newest.
    ///
    /// # Errors
    /// As [`HilSession::step`].
    pub fn step_burst(&mut self, frames: &[(u32, u64, Frame<'_>)]) -> Result<Option<(u32, Reply)>, HilError> {
        let Some(((last_seq, _, last), older)) = frames.split_last() else { return Ok(None) };
        for (sequence, capture_time_us, frame) in older {
            let env =
                Envelope { sequence: *sequence, capture_time_us: *capture_time_us, message: Message::Frame(*frame) };
            self.send(&env, FLAG_NEWER_FOLLOWS)?;
        }
        let (_, t, _) = frames[frames.len() - 1];
        self.send(&Envelope { sequence: *last_seq, capture_time_us: t, message: Message::Frame(*last) }, 0)?;
        Ok(Some((*last_seq, self.answer_to(*last_seq, last.joints.time_us)?)))
    }

    /// Waits for the answer to frame `sequence`. Without faults the next message must be it;
    /// with faults, damaged and out-of-sequence replies are dropped (counted) and no answer
    /// within the lost timeout is [`Reply::Lost`].
    fn answer_to(&mut self, sequence: u32, joint_time_us: u64) -> Result<Reply, HilError> {
        if !self.fault_mode {
            let env = self.recv("ESTIMATE")?;
            return match env.message {
                // The firmware's tracker stamps its estimate with the joint sample's time.
                Message::Estimate(e) if env.sequence == sequence => {
                    Ok(Reply::Estimate(Estimate { capture_time_us: joint_time_us, ..e }))
                }
                Message::Rejected if env.sequence == sequence => Ok(Reply::Rejected),
                _ => Err(unexpected(&env, "ESTIMATE or REJECTED for the frame just sent")),
            };
        }
        let deadline = Instant::now() + self.options.lost_timeout;
        loop {
            let Some(env) = self.recv_until(deadline)? else {
                self.lost += 1;
                return Ok(Reply::Lost);
            };
            match env.message {
                Message::Estimate(e) if env.sequence == sequence => {
                    return Ok(Reply::Estimate(Estimate { capture_time_us: joint_time_us, ..e }));
                }
                Message::Rejected if env.sequence == sequence => return Ok(Reply::Rejected),
                Message::Estimate(_) | Message::Rejected => self.host_drops.sequence += 1,
                _ => self.host_drops.unexpected += 1,
            }
        }
    }

    /// Sends `END`, waits for `DONE` and for QEMU to exit with success.
    ///
    /// # Errors
    /// A failure of the link, or QEMU exiting with failure ([`HilError::QemuExited`]).
    pub fn finish(mut self) -> Result<Summary, HilError> {
        let done = match self.handshake(&Envelope::bare(Message::End), "DONE")? {
            Envelope { message: Message::Done(d), .. } => d,
            env => return Err(unexpected(&env, "DONE")),
        };
        let summary = Summary {
            done,
            log_path: self.log_path.clone(),
            host_drops: self.host_drops,
            lost: self.lost,
            faults_sent: self.faults.as_ref().map(FaultInjector::counts).unwrap_or_default(),
            faults_received: self.reply_faults.lock().map(|c| *c).unwrap_or_default(),
        };
        self.tx = None;
        let status = self.wait_exit(self.options.reply_timeout)?;
        match status {
            Some(s) if s.success() => Ok(summary),
            Some(s) => Err(HilError::QemuExited { status: Some(s), log_tail: self.log_tail() }),
            None => {
                self.kill();
                Err(HilError::Timeout {
                    waiting_for: "exit after DONE",
                    after: self.options.reply_timeout,
                    log_tail: self.log_tail(),
                })
            }
        }
    }

    /// QEMU's output file (the firmware's log).
    pub fn log_path(&self) -> &Path {
        &self.log_path
    }

    fn send(&mut self, env: &Envelope<'_>, flags: u16) -> Result<(), HilError> {
        let mut bytes = IoLink(Vec::with_capacity(crate::protocol::max_encoded_len(&env.message)));
        write_message_with_flags(&mut bytes, env, flags).map_err(|e| match e {
            WriteError::ImageSize { expected, left, right } => HilError::BadFrame { expected, left, right },
            WriteError::Link(e) => HilError::Io { what: "encode a message".to_string(), source: e },
        })?;
        let wire = match self.faults.as_mut() {
            Some(f) => f.pass(&bytes.0),
            None => bytes.0,
        };
        let Some(tx) = self.tx.as_mut() else {
            return Err(HilError::Io { what: "send".to_string(), source: io::ErrorKind::NotConnected.into() });
        };
        match tx.write_all(&wire).and_then(|()| tx.flush()) {
            Ok(()) => Ok(()),
            // A broken pipe means QEMU went away: report that rather than the pipe.
            Err(e) if e.kind() == io::ErrorKind::BrokenPipe => Err(self.link_closed()),
            Err(e) => Err(HilError::Io { what: "write to the firmware FIFO".to_string(), source: e }),
        }
    }

    fn recv(&mut self, waiting_for: &'static str) -> Result<Envelope<'static>, HilError> {
        match self.recv_until(Instant::now() + self.options.reply_timeout)? {
            Some(env) => Ok(env),
            None => {
                self.kill();
                Err(HilError::Timeout { waiting_for, after: self.options.reply_timeout, log_tail: self.log_tail() })
            }
        }
    }

    /// The next valid message before `deadline` (`None` after it). A damaged message is an
    /// error without faults; with faults it is counted and skipped.
    fn recv_until(&mut self, deadline: Instant) -> Result<Option<Envelope<'static>>, HilError> {
        loop {
            let wait = deadline.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(wait) {
                Ok(Incoming::Message(Envelope { message: Message::Error(code), .. })) => {
                    let _ = self.wait_exit(Duration::from_secs(5));
                    return Err(HilError::Firmware { code, log_tail: self.log_tail() });
                }
                Ok(Incoming::Message(env)) => return Ok(Some(env)),
                Ok(Incoming::Damaged(e)) if self.fault_mode => self.host_drops.count(&e),
                Ok(Incoming::Damaged(e)) => return Err(HilError::Protocol(e)),
                Ok(Incoming::Closed(HilError::QemuExited { .. })) | Err(RecvTimeoutError::Disconnected) => {
                    return Err(self.link_closed());
                }
                Ok(Incoming::Closed(e)) => return Err(e),
                Err(RecvTimeoutError::Timeout) => return Ok(None),
            }
        }
    }

    /// The link closed: wait a little for QEMU's exit status and report it.
    fn link_closed(&mut self) -> HilError {
        let status = self.wait_exit(Duration::from_secs(5)).ok().flatten();
        HilError::QemuExited { status, log_tail: self.log_tail() }
    }

    /// Opens one FIFO end while watching QEMU; a blocked open is released by opening the FIFO
    /// read-write ourselves (which never blocks on Linux).
    fn open_fifo(&mut self, path: &Path, write: bool, deadline: Instant) -> Result<File, HilError> {
        let (tx, rx) = mpsc::channel();
        let p = path.to_path_buf();
        let opener = thread::spawn(move || {
            let _ = tx.send(OpenOptions::new().read(!write).write(write).open(&p));
        });
        loop {
            match rx.recv_timeout(Duration::from_millis(20)) {
                Ok(r) => {
                    let _ = opener.join();
                    return r.map_err(io_error(format!("open {}", path.display())));
                }
                Err(RecvTimeoutError::Disconnected) => {
                    return Err(HilError::Io {
                        what: format!("open {}", path.display()),
                        source: io::Error::other("opener thread failed"),
                    });
                }
                Err(RecvTimeoutError::Timeout) => {}
            }
            let exited = self.try_exited()?;
            let timed_out = Instant::now() > deadline;
            if exited.is_some() || timed_out {
                let _release = OpenOptions::new().read(true).write(true).open(path);
                let _ = opener.join();
                if timed_out && exited.is_none() {
                    self.kill();
                    return Err(HilError::Timeout {
                        waiting_for: "link open",
                        after: self.options.start_timeout,
                        log_tail: self.log_tail(),
                    });
                }
                return Err(HilError::QemuExited { status: exited, log_tail: self.log_tail() });
            }
        }
    }

    fn try_exited(&mut self) -> Result<Option<ExitStatus>, HilError> {
        if self.exited.is_none() {
            self.exited = self.qemu.try_wait().map_err(io_error("poll QEMU"))?;
        }
        Ok(self.exited)
    }

    /// Waits up to `limit` for QEMU to exit.
    fn wait_exit(&mut self, limit: Duration) -> Result<Option<ExitStatus>, HilError> {
        let deadline = Instant::now() + limit;
        loop {
            if let Some(s) = self.try_exited()? {
                return Ok(Some(s));
            }
            if Instant::now() > deadline {
                return Ok(None);
            }
            thread::sleep(Duration::from_millis(5));
        }
    }

    fn kill(&mut self) {
        if self.exited.is_none() {
            let _ = self.qemu.kill();
            self.exited = self.qemu.wait().ok();
        }
    }

    /// The last lines of QEMU's log.
    fn log_tail(&self) -> String {
        let text = fs::read(&self.log_path).unwrap_or_default();
        let start = text.len().saturating_sub(2000);
        String::from_utf8_lossy(text.get(start..).unwrap_or_default()).into_owned()
    }
}

impl Drop for HilSession {
    fn drop(&mut self) {
        self.tx = None;
        self.kill();
    }
}

fn unexpected(env: &Envelope<'_>, expected: &'static str) -> HilError {
    HilError::Unexpected { got: env.message.kind(), sequence: env.sequence, expected }
}
