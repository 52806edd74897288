//! The timing firmware (thumbv7em-none-eabihf, QEMU `mps2-an386` with `-icount shift=10`):
//! counts the instructions of every phase of one GA generation with TIMER0 (see
//! `evorec_firmware::timing`) and prints one `GEN` line per generation through semihosting.
//!
//! Runs, in order: the default configuration (population 40, 8 points per row) on
//! `timing::FULL_FRAMES` RGB565 frames of every kind (the hue of every sampled pixel is
//! looked up in the core's `RGB565_HUE` table inside the measured window) with feedforward on
//! (`full`, method `ff`), the same frames with the target's motion fed forward too (`target`,
//! method `ff+target`: the target filter's update in every generation, and, once the filter
//! trusts the conveyor's velocity, the target twist applied to every individual; each `GEN`
//! line says whether it was, `tshift=1`), then, on the M4
//! profile, the sweep (populations 20/40/60 × rows of 4/8/12 points, and population 40 with
//! rows of 5, 6 and 7, `Tracker<7, P, G>` monomorphised for each; population 40 with rows of 8
//! is the `full` run) on `timing::SWEEP_FRAMES` frames each. The M7 profile (feature `m7`,
//! 320×240) runs the `full` and `target` runs only: the same code on larger frames. Every frame
//! is made on the board before its generation, so the measured window holds only
//! `Tracker::step_probed`. Before each generation the tracker is
//! put in the status of its frame kind (`CaseKind::forced_status`: searching or lost for those
//! kinds, tracking and uncertain in turn for all others), which decides the generation's work. Before each generation the free stack
//! is painted again, and its high-water mark after the generation is printed too.
//!
//! The rig is `timing::rig_for` the profile's frame size (f = 200 px at 160×120, scaled with
//! the width, so both profiles see the same view).
//!
//! `evorec timing --out DIR [--profile m7]` (host) runs this image and writes the report. Build
//! it with `cd hil-stubs && cargo build --release` (→
//! `target/thumbv7em-none-eabihf/release/evorec-timing`; for the M7 `CARGO_TARGET_DIR=../target/m7
//! cargo build --release --features m7`).
//!
//! Built for the host, this binary only explains how to build the real one.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]
#![deny(unsafe_code)]

#[cfg(target_os = "none")]
mod firmware {
    use cortex_m_rt::entry;
    use cortex_m_semihosting::hprintln;
    use evorec_core::image::{Rgb565, Rgb565Image};
    use evorec_core::model::SurfaceStrips;
    use evorec_core::target_motion::TargetVelocity;
    use evorec_core::tracker::{Feedforward, JointSample, StereoFrame, Tracker};
    use evorec_firmware::cmsdk_timer::{self, Timer0};
    use evorec_firmware::protocol::Setup;
    use evorec_firmware::timing::{
        BANNER, CaseGen, DeadlineReport, DownCounter, FRAME_PERIOD_US, FULL_FRAMES, GenLine, PhaseTicks, PhaseTimer,
        SWEEP_FRAMES, rig_for, schedule,
    };
    use evorec_firmware::{FRAME_HEIGHT, FRAME_WIDTH, PROFILE, rt, selftest, sys};
    use static_cell::ConstStaticCell;

    /// Seed of the frames' noise generator.
    const FRAME_SEED: u32 = 0x00C0_FFEE;

    /// One configuration of the sweep: its tracker type and its timed generation.
    ///
    /// Each configuration is a marker type, so every `generation` has its own symbol
    /// (`<evorec_timing::firmware::P40G5 as evorec_timing::firmware::Timed>::generation`): the
    /// static stack analysis (`evorec timing`) uses it as the root of "one generation".
    trait Timed<const P: usize, const G: usize> {
        /// This configuration's tracker slot inside the shared [`Slot`] (emptied and switched
        /// to this configuration if it held another one).
        fn slot(slot: &mut Slot) -> Option<&mut Option<Tracker<7, P, G>>>;

        /// One generation, timed: ticks of the whole `step_probed` call, of each phase, and
        /// the fitness; `None` if the tracker refused the input.
        fn generation(
            tracker: &mut Tracker<7, P, G>,
            frame: &StereoFrame<'_, Rgb565>,
            joints: &JointSample<7>,
            dt_s: f32,
            timer: &Timer0,
        ) -> Option<(u32, PhaseTicks, f32)>;
    }

    macro_rules! configs {
        ($($marker:ident: $p:literal x $g:literal),* $(,)?) => {
            /// The tracker of the configuration being measured. Configurations run one after
            /// the other, so they share one static (the size of the largest tracker) instead
            /// of one each: with two RGB565 frames the ten would not fit 128 KiB of RAM.
            enum Slot {
                /// Before the first run.
                Empty,
                $(
                    /// The tracker of one configuration.
                    $marker(Option<Tracker<7, $p, $g>>),
                )*
            }

            $(
                /// Marker of one configuration.
                struct $marker;

                impl Timed<$p, $g> for $marker {
                    fn slot(slot: &mut Slot) -> Option<&mut Option<Tracker<7, $p, $g>>> {
                        if !matches!(slot, Slot::$marker(_)) {
                            *slot = Slot::$marker(None);
                        }
                        match slot {
                            Slot::$marker(t) => Some(t),
                            _ => None,
                        }
                    }

                    #[inline(never)]
                    fn generation(
                        tracker: &mut Tracker<7, $p, $g>,
                        frame: &StereoFrame<'_, Rgb565>,
                        joints: &JointSample<7>,
                        dt_s: f32,
                        timer: &Timer0,
                    ) -> Option<(u32, PhaseTicks, f32)> {
                        timed_generation(tracker, frame, joints, dt_s, timer)
                    }
                }
            )*
        };
    }

    configs!(
        P20G4: 20 x 4, P20G8: 20 x 8, P20G12: 20 x 12,
        P40G4: 40 x 4, P40G5: 40 x 5, P40G6: 40 x 6, P40G7: 40 x 7, P40G8: 40 x 8, P40G12: 40 x 12,
        P60G4: 60 x 4, P60G8: 60 x 8, P60G12: 60 x 12,
    );

    /// The one tracker slot of all configurations (see [`Slot`]).
    static SLOT: ConstStaticCell<Slot> = ConstStaticCell::new(Slot::Empty);

    /// The body of every [`Timed::generation`]: TIMER0 read before and after
    /// `Tracker::step_probed` (in the tracker's configured mode), and at each phase boundary by
    /// the probe.
    #[inline(always)]
    fn timed_generation<const P: usize, const G: usize>(
        tracker: &mut Tracker<7, P, G>,
        frame: &StereoFrame<'_, Rgb565>,
        joints: &JointSample<7>,
        dt_s: f32,
        timer: &Timer0,
    ) -> Option<(u32, PhaseTicks, f32)> {
        let mut probe = PhaseTimer::new(timer);
        let t0 = timer.read();
        let result = tracker.step_probed(frame, joints, dt_s, &mut probe);
        let t1 = timer.read();
        let estimate = result.ok()?;
        Some((t0.wrapping_sub(t1), probe.phases()?, estimate.fitness))
    }

    /// Runs `frames` generations in mode `feedforward` of a fresh `Tracker<7, P, G>` built into
    /// its place in `slot`; false on any failure (a refused tracker or generation is printed). Never inlined, so that the runs'
    /// locals do not pile up in `main`'s frame, which is on the stack during every generation.
    /// Its own frame is on the stack during every generation too, so everything it does besides
    /// the generation is in never-inlined functions ([`start_run`], `CaseGen::frame`,
    /// [`print_line`]): only the frame generator, the deadline record and one frame's inputs are
    /// its locals.
    #[inline(never)]
    fn run_config<C: Timed<P, G>, const P: usize, const G: usize>(
        name: &str,
        feedforward: Feedforward,
        slot: &mut Slot,
        frames: u32,
        timer: &Timer0,
        left: &mut [u8],
        right: &mut [u8],
    ) -> bool {
        let Some((tracker, mut cases)) = start_run::<C, P, G>(name, feedforward, slot, frames) else { return false };
        let mut deadline = DeadlineReport::default();
        for k in 0..frames {
            let kind = schedule(k, frames);
            let Ok(joints) = cases.frame(k, kind, left, right) else {
                hprintln!("ERROR frame {} not made", k);
                return false;
            };
            let (Ok(l), Ok(r)) = (
                Rgb565Image::new_checked(&*left, FRAME_WIDTH, FRAME_HEIGHT),
                Rgb565Image::new_checked(&*right, FRAME_WIDTH, FRAME_HEIGHT),
            ) else {
                return false;
            };
            let frame = StereoFrame { left: l, right: r };
            let dt_s = if k == 0 { 0.0 } else { FRAME_PERIOD_US as f32 * 1e-6 };
            tracker.set_status(kind.forced_status(k));
            let status = tracker.status();
            // The target velocity this generation shifts the individuals by (the tracker's own
            // computation of it, read outside the measured window).
            let target_shift = feedforward == Feedforward::OnWithTarget
                && tracker.target_feedforward_velocity() != TargetVelocity::ZERO;
            cmsdk_timer::repaint_free_stack();
            let measured = C::generation(tracker, &frame, &joints, dt_s, timer);
            let stack = sys::stack_usage().used_bytes;
            let Some((call, phases, fitness)) = measured else {
                hprintln!("ERROR generation {} refused", k);
                return false;
            };
            if !deadline.check(call) {
                hprintln!("DEADLINE-MISSED k={} call={}", k, call);
            }
            print_line(&GenLine {
                population: P as u32,
                grid: G as u32,
                frame: k,
                kind,
                status,
                method: feedforward,
                target_shift,
                call,
                phases,
                stack,
                fitness,
            });
        }
        hprintln!("{}", deadline);
        true
    }

    /// The start of a [`run_config`]: the configuration, the frame generator and the tracker
    /// built into its place in `slot`, and the `RUN` line; `None` on any failure (a refused
    /// tracker is printed).
    /// Never inlined: the configuration's copies are off the stack while generations run.
    #[inline(never)]
    fn start_run<'s, C: Timed<P, G>, const P: usize, const G: usize>(
        name: &str,
        feedforward: Feedforward,
        slot: &'s mut Slot,
        frames: u32,
    ) -> Option<(&'s mut Tracker<7, P, G>, CaseGen)> {
        let mut config = selftest::tracker_config().ok()?;
        config.tuning.feedforward = feedforward;
        // One generation per measured step: the counts are per generation, and a frame costs
        // `generations_per_frame` of them.
        config.tuning.generations_per_frame = 1;
        // The board profile's frame size (160×120 on the M4, 320×240 on the M7).
        config.rig = rig_for(FRAME_WIDTH, FRAME_HEIGHT).ok()?;
        let cases = CaseGen::new(config.rig, config.flange_to_camera, FRAME_SEED).ok()?;
        let start = cases.truth(0, false);
        let mut setup = Setup::from_tracker_config(&config, &start, &selftest::SPREAD).ok()?;
        // Every configuration runs at its full capacity (the worst case of that storage).
        setup.tuning.ga.population = P;
        let slot = C::slot(slot)?;
        let Ok(tracker) = setup.build_tracker_in(slot) else {
            hprintln!("ERROR tracker {}x{} refused", P, G);
            return None;
        };
        hprintln!(
            "RUN name={} method={} p={} g={} frames={} points_per_camera={} walked_per_camera={} width={} height={} \
             profile={}",
            name,
            feedforward,
            P,
            G,
            frames,
            SurfaceStrips::<G>::POINTS_PER_CAMERA,
            SurfaceStrips::<G>::WALKED_PER_CAMERA,
            FRAME_WIDTH,
            FRAME_HEIGHT,
            PROFILE.name
        );
        Some((tracker, cases))
    }

    /// Prints one `GEN` line. Never inlined: the formatting's locals are not in
    /// [`run_config`]'s frame.
    #[inline(never)]
    fn print_line(line: &GenLine) {
        hprintln!("{}", line);
    }

    #[entry]
    fn main() -> ! {
        hprintln!("{}", BANNER);
        let Some([left, right]) = rt::frame_buffers() else { rt::exit(false) };
        let timer = Timer0::start();
        // Ticks of two back-to-back reads: the cost of one read, as seen by the counter.
        let (a, b) = (timer.read(), timer.read());
        hprintln!("CALIBRATION read_pair={}", a.wrapping_sub(b));

        // The "full" run is the core's default configuration; fail to build if it moves.
        const {
            assert!(evorec_core::limits::DEFAULT_POPULATION == 40 && evorec_core::limits::DEFAULT_GRID == 8);
        };
        let Some(slot) = SLOT.try_take() else { rt::exit(false) };
        let full = run_config::<P40G8, 40, 8>("full", Feedforward::On, slot, FULL_FRAMES, &timer, left, right)
            && run_config::<P40G8, 40, 8>("target", Feedforward::OnWithTarget, slot, FULL_FRAMES, &timer, left, right);
        // The sweep chooses the configuration, on the M4 (the M7 runs the same code).
        let ok = full && (cfg!(feature = "m7") || sweep(slot, &timer, left, right));
        hprintln!("END {}", if ok { "ok" } else { "failed" });
        rt::exit(ok)
    }

    /// The sweep: every configuration but the default one (the `full` run) on
    /// [`SWEEP_FRAMES`] frames each; false on the first failure.
    fn sweep(slot: &mut Slot, timer: &Timer0, left: &mut [u8], right: &mut [u8]) -> bool {
        run_config::<P20G4, 20, 4>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P20G8, 20, 8>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P20G12, 20, 12>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P40G4, 40, 4>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P40G5, 40, 5>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P40G6, 40, 6>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P40G7, 40, 7>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P40G12, 40, 12>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P60G4, 60, 4>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P60G8, 60, 8>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
            && run_config::<P60G12, 60, 12>("sweep", Feedforward::On, slot, SWEEP_FRAMES, timer, left, right)
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "evorec-timing runs on a Cortex-M4F (thumbv7em-none-eabihf) under QEMU, not on the host.\n\
         Build it:   cd hil-stubs && cargo build --release\n\
         Measure:    cargo run --release -p evorec-sim -- timing --out out/timing\n\
         (needs `rustup target add thumbv7em-none-eabihf` and \
         `apt-get update && apt-get install -y qemu-system-arm`)"
    );
}
