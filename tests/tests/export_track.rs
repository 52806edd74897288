//! The project's own self-contained test of the sequence reader: a simulator scenario exported
//! as `evorec-seq/1` (`evorec export`) and tracked from the files (`evorec track`) gives the
//! very estimates `evorec run` gives on the simulator, bit for bit, with and without
//! feedforward (the export writes capture times on control steps and joint values that read
//! back exactly, see `evorec_sim::rig::export`), reading the PNGs as 8-bit RGB (the default) and
//! as RGB565 (the board's path): the exported PNGs hold the simulated sensor's RGB565 pixels
//! widened to 8 bits, whose hue is the RGB565 table's.

use std::collections::BTreeSet;
use std::path::PathBuf;

use evorec_core::tracker::Feedforward;
use evorec_core::tuning::Tuning;
use evorec_sim::experiments::experiment;
use evorec_sim::recording::sequence::Sequence;
use evorec_sim::rig::{export, track};
use evorec_sim::sim::scenario::Scenario;
use evorec_sim::sim::scenario::fixture;

fn scenario(method: Feedforward) -> Scenario {
    // About 2 s of 160x120 frames, the arm swaying fast enough for the feedforward to matter.
    let mut s = fixture::sway_160x120(2.0);
    s.set_method(method);
    s
}

fn work_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("evorec-export-track-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn check(method: Feedforward, ff: Feedforward, pixels: track::Pixels, tag: &str) {
    let s = scenario(method);
    let dir = work_dir(tag);
    let seq_dir = dir.join("seq");
    let stats = export::export(&s, tag, &seq_dir, None).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(stats.frames, 62);
    assert!(stats.joint_samples > 2000, "1 kHz joint samples: {}", stats.joint_samples);
    let seq = Sequence::load(&seq_dir).unwrap_or_else(|e| panic!("{e}"));
    let tuning = Tuning { feedforward: ff, ..Tuning::DEFAULT };
    let opts = track::TrackOptions { tuning, seed: s.seed, pixels, ..Default::default() };
    let tracked = track::run(&seq, &opts).unwrap_or_else(|e| panic!("{e:#}"));
    let run = experiment::run(&s, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(tracked.rejected, 0);
    assert_eq!(tracked.tracked.len(), run.rows.len());
    for (t, r) in tracked.tracked.iter().zip(&run.rows) {
        assert_eq!(t.q, r.q.to_vec(), "joint positions at t = {}", r.t);
        assert_eq!(t.qd, r.qd.to_vec(), "joint velocities at t = {}", r.t);
        assert_eq!(t.estimate.0.map(f32::to_bits), r.estimate.0.map(f32::to_bits), "estimate at t = {}", r.t);
        assert_eq!(t.fitness.to_bits(), r.fitness.to_bits(), "fitness at t = {}", r.t);
    }
    // The ground truth read back agrees with the simulator's truth (written to 1e-9).
    let ev = track::output::evaluate(&seq, &tracked);
    assert_eq!(ev.summary.out_of_step_warning(), None, "a pair in step looks out of step");
    for (truth, r) in ev.truth.iter().zip(&run.rows) {
        let truth = truth.expect("ground truth");
        let sim = r.truth.0.map(f64::from);
        // Equal up to the colour symmetry the evaluation applies (a half turn flips ε's sign
        // pattern), so compare positions only, and the rotation error against the estimate.
        for k in 0..3 {
            assert!((truth[k] - sim[k]).abs() < 1e-6, "truth {truth:?} vs {sim:?}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn tracking_an_exported_scenario_equals_run_with_feedforward() {
    check(Feedforward::On, Feedforward::On, track::Pixels::Rgb888, "ff");
}

#[test]
fn tracking_an_exported_scenario_equals_run_without_feedforward_read_as_rgb565() {
    check(Feedforward::Off, Feedforward::Off, track::Pixels::Rgb565, "ga");
}

#[test]
fn a_bad_png_found_while_tracking_is_named_and_nothing_is_written() {
    let s = scenario(Feedforward::On);
    let dir = work_dir("bad-png");
    let seq_dir = dir.join("seq");
    export::export(&s, "bad", &seq_dir, None).unwrap_or_else(|e| panic!("{e:#}"));
    std::fs::write(seq_dir.join("right/000040.png"), b"truncated").expect("write");
    // The metadata is good, so loading succeeds; decoding frame 40 fails.
    let seq = Sequence::load(&seq_dir).unwrap_or_else(|e| panic!("{e}"));
    let opts = track::TrackOptions { overlay: BTreeSet::from([3]), ..Default::default() };
    let err = format!("{:#}", track::run(&seq, &opts).expect_err("frame 40 is not a PNG"));
    assert!(err.contains("right/000040.png") && err.contains("not a readable PNG"), "{err}");
    // A bad first frame fails before tracking starts.
    std::fs::write(seq_dir.join("left/000000.png"), b"").expect("write");
    let err = format!("{:#}", track::run(&seq, &opts).expect_err("frame 0 is not a PNG"));
    assert!(err.contains("left/000000.png"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `ff+target` with a tuned target motion model: tracking the exported sequence with the same
/// tuning (`evorec track --config`) gives `evorec run`'s estimates bit for bit, and the
/// tuning changed them (so it reached both trackers).
#[test]
fn a_tuned_target_filter_tracks_as_in_run() {
    let mut s = scenario(Feedforward::OnWithTarget);
    s.target.conveyor_speed_m_s = 0.1;
    let default_run = experiment::run(&s, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    s.tracker.0.target.acceleration_m_s2 = 0.3;
    s.tracker.0.target.image_noise_px = 1.5;
    let tuned_run = experiment::run(&s, || {}).unwrap_or_else(|e| panic!("{e:#}"));
    let differ = default_run.rows.iter().zip(&tuned_run.rows).any(|(a, b)| a.estimate != b.estimate);
    assert!(differ, "the tuning changed nothing in 2 s: the test would prove nothing");
    let dir = work_dir("tuned");
    let seq_dir = dir.join("seq");
    export::export(&s, "tuned", &seq_dir, None).unwrap_or_else(|e| panic!("{e:#}"));
    let seq = Sequence::load(&seq_dir).unwrap_or_else(|e| panic!("{e}"));
    let opts = track::TrackOptions { tuning: *s.tuning(), seed: s.seed, ..Default::default() };
    let tracked = track::run(&seq, &opts).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(tracked.tracked.len(), tuned_run.rows.len());
    for (t, r) in tracked.tracked.iter().zip(&tuned_run.rows) {
        assert_eq!(t.estimate.0.map(f32::to_bits), r.estimate.0.map(f32::to_bits), "estimate at t = {}", r.t);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `frames.csv` of `dir` re-paired: frame `i`'s right image becomes frame `i + offset`'s (the
/// last `offset` frames are dropped), as a constant offset between the two cameras' streams
/// would pair them.
fn pair_out_of_step(dir: &std::path::Path, offset: usize) {
    let path = dir.join("frames.csv");
    let text = std::fs::read_to_string(&path).expect("frames.csv");
    let mut lines = text.lines();
    let header = lines.next().expect("header").to_owned();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let mut out = vec![header];
    for (i, r) in rows.iter().enumerate().take(rows.len().saturating_sub(offset)) {
        out.push(format!("{},{},{},{}", r[0], r[1], r[2], rows[i + offset][3]));
    }
    std::fs::write(&path, out.join("\n") + "\n").expect("write frames.csv");
}

/// Left and right images out of step by a constant number of frames while the arm sways: no
/// pose fits both cameras, and the summary warns, naming the cause; the same export in step
/// gives no warning. (The status does not refuse such pairs: about half the frames here are
/// reported `tracking`. `evorec track`'s pairing check, which stops the run with an error, judges
/// these 112 pairs at their end but finds no offset: on the simulator's flat images the two
/// cameras' image motion hardly correlates even in step.)
#[test]
fn out_of_step_pairs_are_named() {
    let mut s = scenario(Feedforward::On);
    s.duration_s = 4.0;
    let dir = work_dir("out-of-step");
    let seq_dir = dir.join("seq");
    export::export(&s, "out-of-step", &seq_dir, None).unwrap_or_else(|e| panic!("{e:#}"));
    let opts = track::TrackOptions { seed: s.seed, ..Default::default() };
    let in_step = Sequence::load(&seq_dir).unwrap_or_else(|e| panic!("{e}"));
    let tracked = track::run(&in_step, &opts).unwrap_or_else(|e| panic!("{e:#}"));
    let summary = track::output::evaluate(&in_step, &tracked).summary;
    assert_eq!(summary.out_of_step_warning(), None, "in step: {} mismatched", summary.camera_mismatch_frames);
    pair_out_of_step(&seq_dir, 10);
    let seq = Sequence::load(&seq_dir).unwrap_or_else(|e| panic!("{e}"));
    let tracked = track::run(&seq, &opts).unwrap_or_else(|e| panic!("{e:#}"));
    let summary = track::output::evaluate(&seq, &tracked).summary;
    let warning = summary.out_of_step_warning().expect("a warning");
    assert!(warning.starts_with("left and right images look out of step"), "{warning}");
    let _ = std::fs::remove_dir_all(&dir);
}
