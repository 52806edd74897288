//! Link fault injection between the host and the firmware on QEMU.
//!
//! - Damaged, dropped, duplicated, truncated and delayed REPLIES at 10 % (the firmware's input
//!   clean): the firmware's tracker sees exactly what the host's sees, so every estimate the
//!   host accepts must equal the host tracker's estimate for that frame bit for bit — a damaged
//!   estimate accepted would differ. Lost answers are allowed and counted.
//! - Faults in BOTH directions at 1 % and 10 %: the run finishes (no hang, no give-up), the
//!   firmware reports what it dropped by reason, and the counts add up with the faults injected.
//!
//! Builds the firmware first and needs qemu-system-arm; `EVOREC_SKIP_HIL=1` skips.

use std::time::Duration;

use evorec_firmware::BoardProfile;
use evorec_firmware::faults::FaultConfig;
use evorec_firmware::host::{HilOptions, build_firmware};
use evorec_sim::experiments::experiment;
use evorec_sim::firmware::hil;
use evorec_sim::sim::scenario::Scenario;

fn scenario(seconds: f64) -> Scenario {
    evorec_sim::sim::scenario::fixture::hil_motion_a_ff(seconds)
}

fn skip() -> bool {
    evorec_tests::hil_skipped("hil_faults")
}

fn options(to_firmware: Option<FaultConfig>, to_host: Option<FaultConfig>) -> HilOptions {
    HilOptions {
        faults_to_firmware: to_firmware,
        faults_to_host: to_host,
        lost_timeout: Duration::from_millis(500),
        ..HilOptions::default()
    }
}

#[test]
fn damaged_replies_are_never_accepted() {
    if skip() {
        return;
    }
    let s = scenario(4.0);
    let firmware = build_firmware(BoardProfile::M4).unwrap_or_else(|e| panic!("{e}"));
    let work = std::env::temp_dir().join(format!("evorec-hil-faults-replies-{}", std::process::id()));
    let opts = options(None, Some(FaultConfig::from_rate(0.10, 11)));
    let (on_board, link) =
        hil::run_with_options(&s, &firmware, &work, &opts, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    let on_host = experiment::run(&s, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    assert!(link.faults_received.total() >= 5, "too few faults to test anything: {link:?}");
    assert_eq!(link.faults_sent.total(), 0);
    // The firmware saw every frame and answered each.
    assert_eq!(link.done.frames as usize, on_host.rows.len());
    assert_eq!(link.done.drops.damaged() + link.done.drops.sequence, 0);
    // Every accepted estimate is the firmware's (= the host tracker's) for that very frame.
    let mut matched = 0;
    for b in &on_board.rows {
        let h = on_host.rows.iter().find(|h| h.t == b.t).unwrap_or_else(|| panic!("no host row at t = {}", b.t));
        assert_eq!(b.estimate.0.map(f32::to_bits), h.estimate.0.map(f32::to_bits), "t = {}", b.t);
        assert_eq!(b.fitness.to_bits(), h.fitness.to_bits(), "t = {}", b.t);
        matched += 1;
    }
    assert_eq!(matched + link.lost as usize, on_host.rows.len(), "{link:?}");
    assert!(link.lost > 0 && link.host_drops.damaged() + link.host_drops.sequence > 0, "{link:?}");
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn the_firmware_keeps_running_and_reports_at_1_and_10_percent_faults() {
    if skip() {
        return;
    }
    let s = scenario(4.0);
    let frames = evorec_sim::sim::board::frame_total(&s);
    let firmware = build_firmware(BoardProfile::M4).unwrap_or_else(|e| panic!("{e}"));
    for (rate, seed) in [(0.01, 3), (0.10, 5)] {
        let work = std::env::temp_dir().join(format!("evorec-hil-faults-{seed}-{}", std::process::id()));
        let opts = options(Some(FaultConfig::from_rate(rate, seed)), Some(FaultConfig::from_rate(rate, seed + 100)));
        let (out, link) = hil::run_with_options(&s, &firmware, &work, &opts, || {}).unwrap_or_else(|e| panic!("{e:#}"));
        println!("{rate}: {}", link.describe());
        let d = link.done;
        // Frames the tracker worked on got one answer each; estimates published = rows + the
        // ones lost on the way back.
        assert_eq!(d.frames, d.published + d.rejected);
        assert!(d.frames <= frames && d.frames + 2 * link.faults_sent.total() >= frames, "{link:?}");
        assert!(out.rows.len() as u32 <= d.published);
        // Lost frames are the ones a fault hit, in one direction or the other.
        assert!(link.lost <= link.faults_sent.total() + link.faults_received.total(), "{link:?}");
        if rate >= 0.1 {
            assert!(link.faults_sent.total() > 0 && d.drops.damaged() > 0, "{link:?}");
            assert!(out.rows.len() as u32 >= frames / 2, "the tracker kept running: {} of {frames}", out.rows.len());
        }
        let _ = std::fs::remove_dir_all(&work);
    }
}
