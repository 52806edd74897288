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
use evorec_sim::experiments::experiment;
use evorec_sim::firmware::hil;
use evorec_sim::sim::scenario::Scenario;

#[test]
fn hil_trace_equals_host_trace() {
    if evorec_tests::hil_skipped("hil_matches_run") {
        return;
    }
    // The simulated board (behind `evorec run` and `evorec hil`) delivers RGB565.
    type SimFormat = <evorec_sim::sim::board::SimBoard as CameraController<7>>::Format;
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

/// `CONFIG` carries the target motion model's tuning: an `ff+target` scenario with a conveyor
/// and a tuned `[tracker] target.image_noise_px` gives the same estimates on the firmware as on
/// the host, and the tuning changed them (a firmware running the defaults would differ).
#[test]
fn hil_runs_a_tuned_target_filter_as_the_host() {
    if evorec_tests::hil_skipped("hil_matches_run") {
        return;
    }
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/hil_motion_b_ff.toml");
    let text = std::fs::read_to_string(path).expect("scenario");
    let moving = text
        .replace("method = \"ff\"", "method = \"ff+target\"")
        .replace("[target]\n", "[target]\nconveyor_speed_m_s = 0.05\n");
    assert_ne!(moving, text, "the scenario's method and [target] lines moved");
    assert!(moving.trim_end().ends_with("ga.population = 40"), "[tracker] is the scenario's last table");
    let scenario = |tuning: &str| {
        let mut s = Scenario::from_toml_str(&format!("{moving}{tuning}")).expect("valid scenario");
        s.duration_s = 3.0;
        s
    };
    let tuned = scenario("target.image_noise_px = 2.0\n");
    let firmware = build_firmware(BoardProfile::M4).unwrap_or_else(|e| panic!("{e}"));
    let work = std::env::temp_dir().join(format!("evorec-hil-tuned-filter-{}", std::process::id()));
    let on_board = hil::run(&tuned, &firmware, &work, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    let on_host = experiment::run(&tuned, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    let untuned = experiment::run(&scenario(""), || {}).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(on_board.rows.len(), 92);
    assert_eq!(on_board.rows.len(), on_host.rows.len());
    for (b, h) in on_board.rows.iter().zip(on_host.rows.iter()) {
        assert_eq!(b.estimate.0.map(f32::to_bits), h.estimate.0.map(f32::to_bits), "t = {}", b.t);
        assert_eq!(b.fitness.to_bits(), h.fitness.to_bits(), "t = {}", b.t);
    }
    let changed = on_host.rows.iter().zip(untuned.rows.iter()).filter(|(t, u)| t.estimate != u.estimate).count();
    assert!(changed > 0, "the tuning did not change the run, so this test cannot tell it was sent");
    let _ = std::fs::remove_dir_all(&work);
}

/// The configuration file `evorec config SCENARIO` prints (the scenario's tuning, every other
/// field at its default) given to `evorec hil` with `--config` runs the firmware exactly as
/// without it, and a changed `ga.mutation_prob` in it reaches the firmware (its estimates
/// differ).
#[test]
fn hil_runs_a_configuration_file() {
    if evorec_tests::hil_skipped("hil_matches_run") {
        return;
    }
    use evorec_sim::sim::scenario::TrackerTable;
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/hil_motion_a_ff.toml");
    let mut s = Scenario::load(path).expect("valid scenario");
    s.duration_s = 2.0;
    let printed = TrackerTable(*s.tuning()).to_toml();
    let with_file = |text: &str| {
        let mut c = s;
        c.tracker = TrackerTable::from_toml_str(text, *s.tuning()).expect("valid configuration");
        c
    };
    assert_eq!(with_file(&printed), s, "the printed table reads back to the scenario's tuning");
    let changed = with_file(&printed.replace("ga.mutation_prob = 0.9", "ga.mutation_prob = 0.5"));
    let firmware = build_firmware(BoardProfile::M4).unwrap_or_else(|e| panic!("{e}"));
    let work = std::env::temp_dir().join(format!("evorec-hil-config-file-{}", std::process::id()));
    let plain = hil::run(&s, &firmware, &work, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    let same = hil::run(&with_file(&printed), &firmware, &work, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    let other = hil::run(&changed, &firmware, &work, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    let estimates =
        |o: &experiment::RunOutput| o.rows.iter().map(|r| r.estimate.0.map(f32::to_bits)).collect::<Vec<_>>();
    assert_eq!(estimates(&plain), estimates(&same));
    assert_ne!(estimates(&plain), estimates(&other), "ga.mutation_prob did not reach the firmware");
    let on_host = experiment::run(&changed, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(estimates(&other), estimates(&on_host), "the firmware ran the changed tuning as the host does");
    let _ = std::fs::remove_dir_all(&work);
}
