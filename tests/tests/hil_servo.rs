//! `evorec hil` on a `[servo]` scenario equals `evorec run` on it: the closed loop
//! with the tracker in the firmware under QEMU — every frame rendered from the arm's current
//! state, its estimate computed by the firmware, the servo acting on that estimate — follows
//! bit for bit the same trajectory, with the same estimates, as the loop with the host's
//! tracker. Checked for "ff" and for "ff+target" (whose hand-over predicts with the board's
//! copy of the target filter, fed from the firmware's estimates).
//!
//! Builds the firmware first (`cd hil-stubs && cargo build --release`, a no-op when up to
//! date) and needs qemu-system-arm; `EVOREC_SKIP_HIL=1` skips.

use evorec_core::tuning::Feedforward;
use evorec_firmware::BoardProfile;
use evorec_firmware::host::{HilOptions, build_firmware};
use evorec_sim::experiments::closed_loop::{self, ClosedLoopOutput, LoopOptions};
use evorec_sim::firmware::hil;
use evorec_sim::sim::scenario::Scenario;

/// `scenarios/hil_servo.toml` cut to 3 s (92 frames) with `method`.
fn scenario(method: Feedforward) -> Scenario {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/hil_servo.toml");
    let text = std::fs::read_to_string(path).expect("scenario");
    let mut s = Scenario::from_toml_str(&text).expect("valid scenario");
    s.duration_s = 3.0;
    s.set_method(method);
    s
}

fn run_both(method: Feedforward, firmware: &std::path::Path) -> (ClosedLoopOutput, ClosedLoopOutput) {
    let s = scenario(method);
    let opts = LoopOptions::for_scenario(&s);
    let work = std::env::temp_dir().join(format!("evorec-hil-servo-{}-{}", method.name(), std::process::id()));
    let (on_board, link) = hil::run_closed_loop(&s, &opts, firmware, &work, &HilOptions::default(), || {})
        .unwrap_or_else(|e| panic!("{e:#}"));
    let _ = std::fs::remove_dir_all(&work);
    assert_eq!((link.done.frames, link.done.published, link.lost), (92, 92, 0), "{}", link.describe());
    let on_host = closed_loop::run(&s, &opts, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    (on_board, on_host)
}

fn assert_identical(method: Feedforward, on_board: &ClosedLoopOutput, on_host: &ClosedLoopOutput) {
    let cmp = closed_loop::compare(on_board, on_host);
    println!("{}: {}", method.name(), cmp.describe());
    assert!(cmp.identical(), "{cmp:?}");
    assert_eq!(on_board.run.rows.len(), 92);
    // Every trace row (joints, truth, estimate, fitness, status) and every servo row
    // (command, true servo error, tracking flag, camera speed) is equal.
    assert_eq!(on_board.run.rows, on_host.run.rows);
    assert_eq!(on_board.servo, on_host.servo);
    assert_eq!(on_board.servo_summary, on_host.servo_summary);
    // The loop is closed: the servo moved the camera from 0.1 m off the desired pose towards it
    // while tracking.
    let err = |k: usize| on_board.servo[k].error.translation_norm();
    let last = on_board.servo.len() - 1;
    assert!((err(0) - 0.1).abs() < 2e-3, "{}", err(0));
    assert!(err(last) < 0.03, "{}", err(last));
    assert!(on_board.servo[last].held);
}

#[test]
fn hil_closed_loop_equals_host_closed_loop() {
    if evorec_tests::hil_skipped("hil_servo") {
        return;
    }
    let firmware = build_firmware(BoardProfile::M4).unwrap_or_else(|e| panic!("{e}"));
    let t0 = std::time::Instant::now();
    let (ff_board, ff_host) = run_both(Feedforward::On, &firmware);
    assert_identical(Feedforward::On, &ff_board, &ff_host);
    let (fft_board, fft_host) = run_both(Feedforward::OnWithTarget, &firmware);
    assert_identical(Feedforward::OnWithTarget, &fft_board, &fft_host);
    // The arm's path depends on the estimates: another method's estimates move it differently.
    let other = closed_loop::compare(&ff_board, &fft_board);
    assert!(other.max_joint_diff_rad > 0.0, "{other:?}");
    println!("both methods, firmware and host: {:.1} s", t0.elapsed().as_secs_f64());
}
