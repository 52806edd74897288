//! Embedding `evorec-core` in a camera-controller firmware: the skeleton of a Cortex-M4F board
//! (`thumbv7em-none-eabihf`) with two synchronised cameras, a joint-state stream from the arm
//! controller and a position-based visual servo acting on the estimates.
//!
//! ```sh
//! rustup target add thumbv7em-none-eabihf
//! cargo build -p evorec-core --target thumbv7em-none-eabihf --release --example embed
//! ```
//!
//! It links with the workspace's `memory.x` (an STM32F405/407: 1 MiB flash, 128 KiB of
//! DMA-reachable SRAM); `core/build.rs` hands cortex-m-rt's `link.x` to the linker. Built for
//! the host (`cargo test` builds every example) it only prints how to build it.
//!
//! # Data flow
//!
//! ```text
//! cameras --DMA--> CAPTURE pair --copy in next_frame--> WORK pair --> Tracker::step (board::run)
//! arm controller --1 kHz SysTick--> JOINTS ring --joint_sample (nearest the capture)--> tracker
//! publish --> SERVO_TARGET --1 kHz SysTick: hand-over, Servo::update--> camera twist to the arm
//! ```
//!
//! - **Double buffering.** The cameras' DMA fills the `CAPTURE` pair while the tracker works on
//!   the `WORK` pair. `CameraController::next_frame` waits for the capture in flight, copies it
//!   into the tracker's buffers (two `memcpy`s, a small fraction of a generation) and at once
//!   starts the next capture, so a frame is being exposed while the previous one is tracked.
//! - **Joint samples.** The arm controller's samples arrive in an interrupt and go into a ring;
//!   the tracker gets the one nearest the frame's capture time, which is the time the estimate
//!   carries and the motion feedforward integrates from.
//! - **Hand-over.** `CameraController::publish` leaves the estimate with the joint angles of
//!   its frame in a mailbox; the 1 kHz control interrupt moves it into the camera's current pose
//!   (the arm moved since capture) and runs the core's `Servo` on it, only while the tracker
//!   reports `Status::Tracking` and the estimate is fresh; otherwise the servo brakes to a stop
//!   within its limits.
//! - **Bounded work per frame.** One copy of a fixed size and `generations_per_frame`
//!   generations (the default tuning's 2), whose work is fixed by the population capacity and
//!   the sample rows (see the crate documentation); the interrupt's work is fixed too (a ring
//!   insert, two forward kinematics, one servo step).
//!
//! # Porting
//!
//! Everything hardware-specific is a stub marked `PORT:` saying what to put there (camera and
//! DMA set-up, the capture interrupt, the arm controller's bus, the clock); the rest is
//! board-independent and safe Rust. `hil-stubs/` is a complete firmware that runs under QEMU
//! and feeds its frames over a link instead of cameras.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::cell::{Cell, RefCell};
    use core::sync::atomic::{AtomicBool, AtomicU32, Ordering, compiler_fence};

    use cortex_m::peripheral::SYST;
    use cortex_m::peripheral::syst::SystClkSource;
    use cortex_m_rt::{entry, exception};
    use critical_section::Mutex;
    use evorec_core::board::{self, CameraController, ErrorKind, ErrorType, FrameInfo};
    use evorec_core::camera::{Pinhole, StereoRig};
    use evorec_core::feedforward::CameraTwist;
    use evorec_core::ga::SearchSpace;
    use evorec_core::image::Rgb565;
    use evorec_core::kinematics::PA10;
    use evorec_core::limits::{DEFAULT_GRID, PA10_DOF, POPULATION_CAPACITY};
    use evorec_core::model::Block;
    use evorec_core::pose::Psi;
    use evorec_core::servo::{Servo, ServoConfig, ServoInput, ServoLimits};
    use evorec_core::status::Status;
    use evorec_core::target_motion;
    use evorec_core::tracker::{Estimate, JointSample, Tracker, TrackerConfig};
    use nalgebra::{Isometry3, Translation3, UnitQuaternion};
    use static_cell::ConstStaticCell;

    /// Joints of the arm (the PA-10).
    const DOF: usize = PA10_DOF;

    /// Image size of each camera. PORT: your sensor's window. 128×96 so that two RGB565 pairs
    /// (2 × 49,152 B) fit with the tracker into the 128 KiB of `memory.x`; double-buffered
    /// 160×120 pairs need 153,600 B (an STM32H7-class part), or a single pair the cameras are
    /// triggered into between generations.
    const WIDTH: u16 = 128;
    const HEIGHT: u16 = 96;
    /// Bytes of one RGB565 image (2 per pixel), the layout DCMI-style interfaces deliver.
    const IMAGE_BYTES: usize = WIDTH as usize * HEIGHT as usize * 2;
    /// A stereo pair: left, right.
    type Pair = [[u8; IMAGE_BYTES]; 2];

    /// PORT: the core clock SysTick counts.
    const CORE_CLOCK_HZ: u32 = 168_000_000;
    /// The joint-sample and servo rate.
    const CONTROL_HZ: u32 = 1_000;
    const CONTROL_PERIOD_S: f32 = 1.0 / CONTROL_HZ as f32;
    /// PORT: the cameras' frame period (ms).
    const FRAME_PERIOD_MS: u32 = 33;
    /// A frame later than this ends `board::run` with [`ErrorKind::Timeout`].
    const FRAME_TIMEOUT_US: u64 = 200_000;
    /// An estimate older than this is not servoed on (two frame periods).
    const MAX_ESTIMATE_AGE_US: u64 = 66_000;
    /// Joint samples kept: more than one frame period at [`CONTROL_HZ`].
    const JOINT_RING: usize = 48;

    /// The tracker: the firmware's population capacity and the default sample rows.
    type BoardTracker = Tracker<DOF, POPULATION_CAPACITY, DEFAULT_GRID>;

    /// The pair the cameras' DMA writes (PORT: must be in DMA-reachable RAM; on an STM32F4
    /// not the CCM).
    static CAPTURE: ConstStaticCell<Pair> = ConstStaticCell::new([[0; IMAGE_BYTES]; 2]);
    /// The pair the tracker reads (`board::run`'s buffers).
    static WORK: ConstStaticCell<Pair> = ConstStaticCell::new([[0; IMAGE_BYTES]; 2]);
    /// The tracker, built in place by `Tracker::new_in` (no tracker-sized copy on the stack).
    static TRACKER: ConstStaticCell<Option<BoardTracker>> = ConstStaticCell::new(None);

    /// Milliseconds since start, counted by the control interrupt.
    static MILLIS: AtomicU32 = AtomicU32::new(0);

    /// The board's clock (µs). PORT: a free-running 1 MHz timer (e.g. a 32-bit TIM extended to
    /// 64 bits on overflow), the same clock the joint samples and frames are stamped with.
    fn now_us() -> u64 {
        u64::from(MILLIS.load(Ordering::Relaxed)) * 1_000
    }

    // ---------------------------------------------------------------------------------------
    // Cameras: the capture in flight and its completion interrupt.

    /// When and which frame a finished capture holds.
    #[derive(Debug, Clone, Copy)]
    struct Stamp {
        /// Capture time (µs, [`now_us`]).
        time_us: u64,
        /// The sensors' frame count: a gap says frames were dropped.
        sequence: u32,
    }

    /// Whether a capture is in flight (the DMA owns [`CAPTURE`]).
    static ARMED: AtomicBool = AtomicBool::new(false);
    /// Set by the frame-complete interrupt of an armed capture.
    static DONE: Mutex<Cell<Option<Stamp>>> = Mutex::new(Cell::new(None));
    /// Frames the sensors delivered (captured or not).
    static SENSOR_FRAMES: AtomicU32 = AtomicU32::new(0);

    /// The frame-complete interrupt: both cameras' DMA transfers are done.
    ///
    /// PORT: call this from the interrupt that says the second of the two transfers finished
    /// (DMA transfer-complete or the interface's end-of-frame, e.g. `#[interrupt] fn
    /// DMA2_STREAM1()` with your device crate) and clear that interrupt's flag. Stamp with the
    /// exposure's time, not the read-out's end: subtract the sensor's read-out time.
    fn on_frame_complete(time_us: u64) {
        let sequence = SENSOR_FRAMES.fetch_add(1, Ordering::Relaxed);
        if ARMED.swap(false, Ordering::AcqRel) {
            critical_section::with(|cs| DONE.borrow(cs).set(Some(Stamp { time_us, sequence })));
        }
    }

    /// One capture in flight: the DMA owns the pair until [`Capture::finish`].
    ///
    /// PORT: your HAL's transfer type (one taking `&'static mut` buffers and giving them back
    /// when the transfer is done), in snapshot mode: one frame pair per start.
    struct Capture {
        pair: &'static mut Pair,
    }

    impl Capture {
        /// Starts capturing the next frame pair into `pair`.
        fn start(pair: &'static mut Pair) -> Self {
            critical_section::with(|cs| DONE.borrow(cs).set(None));
            // PORT: point each camera's DMA stream at its image (`pair[0]`, `pair[1]`:
            // `IMAGE_BYTES / 4` words, peripheral to memory), enable the streams and arm a
            // snapshot capture on both camera interfaces; one sync line triggers both sensors so
            // that the two exposures start together. For a single side-by-side stereo stream,
            // capture into one buffer and de-interleave the rows in `CameraBoard::next_frame`.
            compiler_fence(Ordering::Release);
            ARMED.store(true, Ordering::Release);
            Self { pair }
        }

        /// The finished frame's stamp, `None` while the DMA still writes.
        fn done(&self) -> Option<Stamp> {
            critical_section::with(|cs| DONE.borrow(cs).get())
        }

        /// Gives the pair back to the CPU (call after [`Capture::done`] said so).
        fn finish(self) -> &'static mut Pair {
            // PORT: disable the DMA streams. On a Cortex-M7 with data cache, invalidate the
            // pair's cache lines here (`SCB::invalidate_dcache_by_slice`).
            compiler_fence(Ordering::Acquire);
            self.pair
        }
    }

    // ---------------------------------------------------------------------------------------
    // Arm controller: joint samples in, camera twist out.

    /// The newest joint samples, oldest overwritten (filled by the control interrupt).
    struct JointRing {
        samples: [JointSample<DOF>; JOINT_RING],
        next: usize,
        len: usize,
    }

    impl JointRing {
        const fn new() -> Self {
            Self { samples: [JointSample { q: [0.0; DOF], qd: [0.0; DOF], time_us: 0 }; JOINT_RING], next: 0, len: 0 }
        }

        fn push(&mut self, sample: JointSample<DOF>) {
            if let Some(slot) = self.samples.get_mut(self.next) {
                *slot = sample;
            }
            self.next = (self.next + 1) % JOINT_RING;
            self.len = (self.len + 1).min(JOINT_RING);
        }

        /// The sample nearest `time_us`.
        fn nearest(&self, time_us: u64) -> Option<JointSample<DOF>> {
            self.samples.iter().take(self.len).min_by_key(|s| s.time_us.abs_diff(time_us)).copied()
        }
    }

    static JOINTS: Mutex<RefCell<JointRing>> = Mutex::new(RefCell::new(JointRing::new()));

    /// The newest joint sample from the arm controller.
    ///
    /// PORT: read the newest `q` (rad) and `q̇` (rad/s) the arm controller sent (CAN, EtherCAT,
    /// SPI, …), in the joint order and sign of the kinematic chain (`PA10` here; a
    /// `kinematics::Chain` of your arm otherwise), stamped with this board's clock at the time
    /// they were measured.
    fn read_arm_controller(time_us: u64) -> JointSample<DOF> {
        JointSample { q: [0.0, 0.3, 0.0, 1.2, 0.0, 1.0, 0.0], qd: [0.0; DOF], time_us }
    }

    /// Sends the servo's command to the arm controller.
    ///
    /// PORT: the camera twist in the right camera's frame (m/s, rad/s); the arm controller's
    /// resolved-rate loop turns it into joint velocities (or do that here with the chain's
    /// Jacobian, `evorec_core::kinematics`).
    fn send_to_arm_controller(command: &CameraTwist) {
        let _ = command;
    }

    /// The right camera's pose on the flange, `^F T_CR`. PORT: your hand-eye calibration.
    fn flange_to_camera() -> Isometry3<f32> {
        Isometry3::from_parts(Translation3::new(0.05, 0.0, 0.1), UnitQuaternion::identity())
    }

    // ---------------------------------------------------------------------------------------
    // The servo side: what the tracker hands over, and the control interrupt.

    /// The newest estimate for the servo, with the joint angles of its frame.
    #[derive(Debug, Clone, Copy)]
    struct Handover {
        psi: Psi,
        q: [f32; DOF],
        time_us: u64,
        tracking: bool,
    }

    static SERVO_TARGET: Mutex<Cell<Option<Handover>>> = Mutex::new(Cell::new(None));
    static SERVO: Mutex<RefCell<Option<Servo>>> = Mutex::new(RefCell::new(None));

    /// The servo's set-up. PORT: the block's desired pose in the camera, gain and limits.
    fn servo_config() -> ServoConfig {
        ServoConfig {
            desired: Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.6), UnitQuaternion::identity()),
            gain: 2.0,
            limits: ServoLimits {
                max_speed_m_s: 0.2,
                max_rot_speed_rad_s: 0.5,
                max_accel_m_s2: 0.5,
                max_rot_accel_rad_s2: 1.0,
            },
        }
    }

    /// The handed-over estimate as the camera sees it now: into the world with the joint angles
    /// of its frame, back into the camera with the current ones.
    fn servo_input(h: &Handover, q_now: &[f32; DOF]) -> Option<ServoInput> {
        h.psi.validate().ok()?;
        let mount = flange_to_camera();
        let world = target_motion::world_pose(&PA10, &h.q, &mount, &h.psi);
        let camera = PA10.forward(q_now) * mount;
        Some(ServoInput { pose: camera.inverse() * world, target_velocity: CameraTwist::ZERO })
    }

    /// The 1 kHz control interrupt: a joint sample into the ring, one servo step.
    #[exception]
    fn SysTick() {
        let millis = MILLIS.fetch_add(1, Ordering::Relaxed) + 1;
        let now = now_us();
        let sample = read_arm_controller(now);
        critical_section::with(|cs| JOINTS.borrow_ref_mut(cs).push(sample));

        let target = critical_section::with(|cs| SERVO_TARGET.borrow(cs).get());
        let fresh = target.filter(|h| h.tracking && now.saturating_sub(h.time_us) <= MAX_ESTIMATE_AGE_US);
        let input = fresh.and_then(|h| servo_input(&h, &sample.q));
        let command = critical_section::with(|cs| {
            let mut servo = SERVO.borrow_ref_mut(cs);
            let servo = servo.as_mut()?;
            let out = servo.update(input.as_ref(), CONTROL_PERIOD_S).or_else(|_| servo.update(None, CONTROL_PERIOD_S));
            Some(out.map_or(CameraTwist::ZERO, |o| o.command))
        });
        if let Some(command) = command {
            send_to_arm_controller(&command);
        }

        // PORT: delete. Stands in for the cameras: "completes" a frame every frame period.
        if millis.is_multiple_of(FRAME_PERIOD_MS) {
            on_frame_complete(now);
        }
    }

    // ---------------------------------------------------------------------------------------
    // The board the tracker sees.

    /// The camera-controller board: cameras, joint ring and servo mailbox behind the core's
    /// [`CameraController`].
    struct CameraBoard {
        /// The capture in flight (`None` only between two captures, or after a timeout that
        /// [`CameraBoard::restart`] repairs).
        capture: Option<Capture>,
        /// The pair of the capture that timed out, for a restart.
        idle: Option<&'static mut Pair>,
        /// The joint sample handed out with the current frame.
        joints: Option<JointSample<DOF>>,
        /// Capture time of the current frame.
        frame_time_us: u64,
    }

    impl CameraBoard {
        fn new(pair: &'static mut Pair) -> Self {
            Self { capture: Some(Capture::start(pair)), idle: None, joints: None, frame_time_us: 0 }
        }

        /// Starts capturing again after a timeout (PORT: also reset the camera interfaces).
        fn restart(&mut self) {
            if let Some(capture) = self.capture.take() {
                ARMED.store(false, Ordering::Release);
                self.idle = Some(capture.finish());
            }
            if let Some(pair) = self.idle.take() {
                self.capture = Some(Capture::start(pair));
            }
        }
    }

    impl ErrorType for CameraBoard {
        type Error = ErrorKind;
    }

    impl CameraController<DOF> for CameraBoard {
        type Format = Rgb565;

        fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, ErrorKind> {
            let capture = self.capture.take().ok_or(ErrorKind::Other)?;
            let start = now_us();
            let stamp = loop {
                if let Some(stamp) = capture.done() {
                    break stamp;
                }
                if now_us().saturating_sub(start) > FRAME_TIMEOUT_US {
                    self.capture = Some(capture);
                    return Err(ErrorKind::Timeout);
                }
                // Sleeps until the next interrupt (the control tick at the latest).
                cortex_m::asm::wfi();
            };
            let pair = capture.finish();
            let copied = match (left.get_mut(..IMAGE_BYTES), right.get_mut(..IMAGE_BYTES)) {
                (Some(l), Some(r)) => {
                    l.copy_from_slice(&pair[0]);
                    r.copy_from_slice(&pair[1]);
                    true
                }
                _ => false,
            };
            // The next frame is exposed while the tracker works on this one.
            self.capture = Some(Capture::start(pair));
            if !copied {
                return Err(ErrorKind::Other);
            }
            self.frame_time_us = stamp.time_us;
            self.joints = None;
            Ok(FrameInfo { sequence: stamp.sequence, capture_time_us: stamp.time_us, width: WIDTH, height: HEIGHT })
        }

        fn joint_sample(&mut self) -> Result<JointSample<DOF>, ErrorKind> {
            let sample = critical_section::with(|cs| JOINTS.borrow_ref(cs).nearest(self.frame_time_us));
            let sample = sample.ok_or(ErrorKind::LinkDown)?;
            self.joints = Some(sample);
            Ok(sample)
        }

        fn publish(&mut self, _frame: &FrameInfo, estimate: &Estimate) -> Result<(), ErrorKind> {
            let joints = self.joints.ok_or(ErrorKind::Other)?;
            let handover = Handover {
                psi: estimate.psi,
                q: joints.q,
                time_us: estimate.capture_time_us,
                tracking: estimate.status == Status::Tracking,
            };
            critical_section::with(|cs| SERVO_TARGET.borrow(cs).set(Some(handover)));
            Ok(())
        }
    }

    // ---------------------------------------------------------------------------------------
    // Start-up and the main loop.

    /// The tracker's set-up. PORT: your cameras' intrinsics and baseline (a rectified parallel
    /// pair), your block's size and face hues, the hand-eye pose and the search box in the
    /// right camera's frame.
    fn tracker_config() -> Option<TrackerConfig<DOF>> {
        let camera = Pinhole::new_checked(160.0, 160.0, 64.0, 48.0, WIDTH, HEIGHT).ok()?;
        let rig = StereoRig::parallel(camera, 0.1).ok()?;
        let search = SearchSpace::new_checked([-0.4, -0.4, 0.3], [0.4, 0.4, 1.3]).ok()?;
        Some(TrackerConfig::pa10(rig, Block::PAPER, flange_to_camera(), search).with_seed(1))
    }

    /// Builds the tracker into its static. It starts searching (a uniform population; the
    /// colour-blob acquisition seeds it); with the block's pose known at start, seed it there
    /// instead with `tracker.reset_around(&psi, &spread)`.
    #[inline(never)]
    fn build_tracker(slot: &'static mut Option<BoardTracker>) -> Option<&'static mut BoardTracker> {
        Tracker::new_in(slot, tracker_config()?).ok()
    }

    /// Starts the 1 kHz control interrupt.
    fn start_control_tick(mut syst: SYST) {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(CORE_CLOCK_HZ / CONTROL_HZ - 1);
        syst.clear_current();
        syst.enable_counter();
        syst.enable_interrupt();
    }

    /// Stops here for good. PORT: keep the arm stopped and signal the fault (LED, status bus).
    fn halt() -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    #[entry]
    fn main() -> ! {
        let (Some(capture), Some([left, right]), Some(slot)) =
            (CAPTURE.try_take(), WORK.try_take(), TRACKER.try_take())
        else {
            halt()
        };
        let Some(tracker) = build_tracker(slot) else { halt() };
        let Ok(servo) = Servo::new(servo_config()) else { halt() };
        critical_section::with(|cs| *SERVO.borrow_ref_mut(cs) = Some(servo));
        // PORT: clocks, camera sensors (I2C/SCCB registers: RGB565, window, frame rate) and
        // their interfaces, the arm controller's bus; install a `log` logger to see the frames
        // the tracker refuses.
        let Some(peripherals) = cortex_m::Peripherals::take() else { halt() };
        start_control_tick(peripherals.SYST);

        let mut camera = CameraBoard::new(capture);
        loop {
            // `generations_per_frame` generations per frame pair, until the board fails.
            // PORT: log the error, count it, reset the cameras on repeated timeouts.
            if board::run(&mut camera, tracker, left, right, u32::MAX).is_err() {
                // Stop servoing on an old estimate, then capture again; the tracker keeps its
                // state, and the first frame after the gap becomes its new time base.
                critical_section::with(|cs| SERVO_TARGET.borrow(cs).set(None));
                camera.restart();
            }
        }
    }

    /// PORT: bring the arm to a safe stop, record the panic, reset.
    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
        cortex_m::peripheral::SCB::sys_reset()
    }
}

/// Built for the host, this example only says how to build it.
#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "core/examples/embed.rs is firmware for a Cortex-M4F. Build it with\n  \
         rustup target add thumbv7em-none-eabihf\n  \
         cargo build -p evorec-core --target thumbv7em-none-eabihf --release --example embed"
    );
}
