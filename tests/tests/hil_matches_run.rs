//! `evorec hil` equals `evorec run`: the same scenario at the firmware's 160x120 frames gives
//! bit-identical traces whether the tracker runs on the host or in the firmware under QEMU.
//! Both get the simulated board's RGB565 frames (the cameras' own format); each computes the
//! hue of the pixels it samples.
//!
//! Builds the firmware first (`cd hil-stubs && cargo build --release`, a no-op when up to
//! date) and needs qemu-system-arm.

use evorec_core::board::CameraController;
use evorec_core::image::{PixelFormat, Rgb565};
use evorec_firmware::BoardProfile;
use evorec_firmware::host::build_firmware;
use evorec_sim::{experiment, hil, scenario::Scenario};

#[test]
fn hil_trace_equals_host_trace() {
    if evorec_tests::hil_skipped("hil_matches_run") {
        return;
    }
    // The simulated board (behind `evorec run` and `evorec hil`) delivers RGB565.
    type SimFormat = <evorec_sim::sim::SimBoard as CameraController<7>>::Format;
    assert_eq!(SimFormat::NAME, Rgb565::NAME);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/hil_motion_b_ff.toml");
    let text = std::fs::read_to_string(path).expect("scenario");
    let mut s = Scenario::from_toml_str(&text).expect("valid scenario");
    s.duration_s = 6.0;
    let firmware = build_firmware(BoardProfile::M4).unwrap_or_else(|e| panic!("{e}"));
    let work = std::env::temp_dir().join(format!("evorec-hil-matches-run-{}", std::process::id()));
    let on_board = hil::run(&s, &firmware, &work, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    let on_host = experiment::run(&s, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(on_board.rows.len(), 183);
    assert_eq!(on_board.rows.len(), on_host.rows.len());
    for (b, h) in on_board.rows.iter().zip(on_host.rows.iter()) {
        assert_eq!(b.estimate.0.map(f32::to_bits), h.estimate.0.map(f32::to_bits), "t = {}", b.t);
        assert_eq!(b.fitness.to_bits(), h.fitness.to_bits(), "t = {}", b.t);
    }
    assert_eq!(on_board.summary.accuracy, on_host.summary.accuracy);
    let _ = std::fs::remove_dir_all(&work);
}

/// The firmware's CONFIG carries no target-filter tuning, so a scenario that tunes
/// `[target_filter]` is refused before QEMU starts rather than compared against a firmware that
/// ran the defaults.
#[test]
fn hil_refuses_a_tuned_target_filter() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/hil_motion_b_ff.toml");
    let text = std::fs::read_to_string(path).expect("scenario");
    let mut s = Scenario::from_toml_str(&(text + "\n[target_filter]\nacceleration_lead_s = 0\n")).expect("valid");
    s.duration_s = 0.1;
    let work = std::env::temp_dir().join(format!("evorec-hil-tuned-filter-{}", std::process::id()));
    let firmware = work.join("no-firmware-needed");
    let e = hil::run(&s, &firmware, &work, || {}).err().map(|e| format!("{e:#}")).unwrap_or_default();
    assert!(e.contains("tunes [target_filter]"), "{e}");
    let _ = std::fs::remove_dir_all(&work);
}
