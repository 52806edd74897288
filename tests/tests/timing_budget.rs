//! The default configuration's instructions per GA generation stay under the budget on the
//! Cortex-M4: counted under QEMU `-icount shift=10` with TIMER0 by the timing firmware
//! (`hil-stubs/src/bin/evorec-timing.rs`, run through `evorec_sim::firmware::timing::measure`), so the
//! count is deterministic — never wall time.
//!
//! Population 40, 8 points per row (the core's defaults, `DEFAULT_GRID`), feedforward on, ≥ 100 frames of every kind (blank, target
//! absent, target filling the image, noise, target under noise, tracked, random poses, fast
//! arm, and the acquisition's searching and lost frames): the worst generation must take at
//! most [`GENERATION_BUDGET`] instructions in EVERY tracker status, the worst generation while
//! searching or lost must cost no more than the worst while tracking (so the budget is set by
//! tracking alone), and the spread between tracking frames of a scene must stay within
//! [`RATIO_TARGET`] (bounded, data-independent work; adversarial one-hue and noise frames may
//! only cost less, see the test).
//!
//! The test builds the firmware images of the checked-out source first (`cd hil-stubs && cargo
//! build --release`, a no-op when up to date); `EVOREC_TIMING_ELF` names another image. A
//! failed build or a missing QEMU fails the test with the message that fixes it;
//! `EVOREC_SKIP_HIL=1` skips the test instead.

use std::path::Path;

use evorec_core::status::Status;
use evorec_core::tracker::Feedforward;
use evorec_firmware::timing::CaseKind;
use evorec_sim::firmware::timing::{self, GENERATION_BUDGET, RATIO_TARGET};
use evorec_tests::Failure;

#[test]
fn default_generation_stays_within_the_instruction_budget() -> Result<(), Failure> {
    if evorec_tests::hil_skipped("timing_budget") {
        return Ok(());
    }
    // Builds the firmware images of the checked-out source (a no-op when up to date).
    evorec_firmware::host::build_firmware(evorec_firmware::BoardProfile::M4)?;
    let elf = timing::find_image(&timing::Board::M4, timing::TIMING_IMAGE)?;
    let qemu = timing::find_qemu()?;
    let workdir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("timing_budget");
    let m = timing::measure(&qemu, &timing::Board::M4, &elf, &workdir)?;
    let full = m.runs.iter().find(|r| r.name == "full").ok_or_else(|| Failure("no full run".into()))?;
    let s = full.stats();
    println!(
        "timing_budget: P = {}, G = {}, {} generations: {:.0}..{:.0} instructions (max/min {:.4}), \
         feedforward ≤ {:.0}, evaluate ≤ {:.0}, breed ≤ {:.0}, {:.2} per point; budget {:.0}",
        s.population,
        s.grid,
        s.generations,
        s.call.min,
        s.call.max,
        s.call.ratio(),
        s.feedforward.max,
        s.evaluate.max,
        s.breed.max,
        s.per_point.max,
        GENERATION_BUDGET
    );
    assert_eq!(
        (s.population, s.grid),
        (evorec_core::limits::DEFAULT_POPULATION as u32, evorec_core::limits::DEFAULT_GRID as u32),
        "the full run is not the default configuration"
    );
    assert!(s.generations >= 100, "only {} generations measured", s.generations);
    // The firmware's own watchdog-style deadline check agrees: every generation checked, none
    // over the deadline (= the budget).
    let d = m.deadlines("full");
    assert_eq!(d.checked as usize, s.generations, "{d:?}");
    assert_eq!(d.missed, 0, "{d:?} {:?}", m.missed_lines);
    assert!((d.worst_instructions - s.call.max).abs() < 1.0, "{d:?} against {}", s.call.max);
    // Data independence. On frames of a scene (the target tracked, at random poses, filling the
    // image, behind noise, under a fast arm; or no target at all) the work stays within
    // RATIO_TARGET of the worst case. The adversarial frames (every pixel one face's hue, or
    // pure noise) make the GA spread individuals out of the image, whose points skip the pixel
    // load and cost less: they may lower the minimum, never raise the maximum, which is checked
    // against the budget below over every frame.
    // The held statuses (the paper's constant work); the acquisition's statuses are checked
    // against it below.
    let scene = |k: &CaseKind| !matches!(k, CaseKind::UniformHue | CaseKind::Noise);
    let calls: Vec<f64> = full
        .generations
        .iter()
        .filter(|g| scene(&g.kind) && g.status.holds())
        .map(|g| evorec_firmware::timing::ticks_to_instructions(u64::from(g.call)))
        .collect();
    let (lo, hi) = calls.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &c| (lo.min(c), hi.max(c)));
    assert!(calls.len() >= 80, "only {} tracking scene frames", calls.len());
    // The pinhole kernel reads every point without a data-dependent branch (points outside the
    // image cost what points inside do), so frames of a scene differ only in the GA's and the
    // feedforward's few branches.
    assert!(hi / lo <= RATIO_TARGET, "work depends on the scene: max/min = {:.4} > {RATIO_TARGET}", hi / lo);
    // Every status: bounded, within the budget, and searching/lost no dearer than tracking.
    let worst = |status: Status| {
        let v: Vec<f64> = full
            .generations
            .iter()
            .filter(|g| g.status == status)
            .map(|g| evorec_firmware::timing::ticks_to_instructions(u64::from(g.call)))
            .collect();
        (v.len(), v.into_iter().fold(0.0f64, f64::max))
    };
    let (_, tracking) = worst(Status::Tracking);
    // Every second tracked generation is forced `uncertain` (a hold gone unconfirmed: in
    // `ff+target` it adds the turn probes).
    for status in Status::ALL {
        let (n, max) = worst(status);
        println!("timing_budget: {status}: {n} generations, worst {max:.0} instructions");
        assert!(n >= 10, "only {n} generations measured while {status}");
        assert!(max <= GENERATION_BUDGET, "worst generation while {status}: {max:.0} > {GENERATION_BUDGET:.0}");
        assert!(
            status.holds() || max <= tracking,
            "worst generation while {status} ({max:.0}) costs more than the worst while tracking ({tracking:.0}): \
             raise AcquireConfig::idle_individuals"
        );
    }
    assert!(
        s.call.max <= GENERATION_BUDGET,
        "worst generation takes {:.0} instructions, {:.1} % over the budget of {GENERATION_BUDGET:.0} \
         (evaluate {:.0} = {:.2} per sample point)",
        s.call.max,
        (s.call.max / GENERATION_BUDGET - 1.0) * 100.0,
        s.evaluate.max,
        s.per_point.max
    );
    target_run_stays_within_the_budget(&m)
}

/// The `target` run (`ff+target`: the target's motion fed forward too, the target filter
/// updated every generation) on the same frames: every generation within the budget and the
/// deadline, and the target path really exercised — the conveyor frames make the filter trust
/// a significant velocity, so some generations shift every individual by it (`tshift=1`).
fn target_run_stays_within_the_budget(m: &timing::Measurement) -> Result<(), Failure> {
    let run = m.runs.iter().find(|r| r.name == "target").ok_or_else(|| Failure("no target (ff+target) run".into()))?;
    let t = run.stats();
    println!(
        "timing_budget: ff+target: {} generations, {:.0}..{:.0} instructions, feedforward ≤ {:.0}, breed ≤ {:.0}; \
         {} generations shifted by the target's velocity (worst {:.0})",
        t.generations,
        t.call.min,
        t.call.max,
        t.feedforward.max,
        t.breed.max,
        t.target_shifts,
        t.target_shift_call.map_or(0.0, |c| c.max)
    );
    assert!(
        run.generations.iter().all(|g| g.method == Feedforward::OnWithTarget),
        "a target-run generation not ff+target"
    );
    assert!(t.generations >= 100, "only {} ff+target generations measured", t.generations);
    assert!(t.call.max <= GENERATION_BUDGET, "worst ff+target generation: {:.0} > {GENERATION_BUDGET:.0}", t.call.max);
    let d = m.deadlines("target");
    assert_eq!((d.checked as usize, d.missed), (t.generations, 0), "{d:?} {:?}", m.missed_lines);
    // The path was exercised: generations on the conveyor, tracking, with the target twist applied.
    let shifted: Vec<_> = run.generations.iter().filter(|g| g.target_shift).collect();
    assert!(!shifted.is_empty(), "no ff+target generation fed a target velocity forward");
    assert!(
        shifted.iter().any(|g| g.kind == CaseKind::Conveyor && g.status == Status::Tracking),
        "no shifted generation on the conveyor frames"
    );
    // The plain ff run never feeds a target velocity forward.
    assert!(m.runs.iter().filter(|r| r.name != "target").flat_map(|r| &r.generations).all(|g| !g.target_shift));
    Ok(())
}

/// The Cortex-M7 profile's table (`evorec timing --profile m7`): the same timing firmware built
/// with feature `m7` (320×240 frames, QEMU `mps2-an500`), run end to end through the report
/// (QEMU, the firmware demo's stack, the disassembly's cycle model, `timing.json`). The
/// generation's work does not depend on the frame size, so the M4's budget holds here too.
#[test]
fn m7_profile_timing_table_is_written() -> Result<(), Failure> {
    if evorec_tests::hil_skipped("timing_budget (M7)") {
        return Ok(());
    }
    evorec_firmware::host::build_firmware(evorec_firmware::BoardProfile::M7)?;
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("timing_m7");
    timing::run(&out, timing::Board::M7)?;
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("timing.json"))?)?;
    let num = |path: &[&str]| {
        path.iter().try_fold(&json, |v, k| v.get(k)).and_then(serde_json::Value::as_f64).unwrap_or(f64::NAN)
    };
    println!(
        "timing_budget (M7): worst {} instructions, {} per model point, {} ms with flash wait states",
        num(&["instructions_per_generation", "max"]),
        num(&["instructions_per_point_eval"]),
        num(&["cycle_estimate", "with_flash_wait_states", "milliseconds_per_generation"])
    );
    assert_eq!(json["profile"], "m7");
    assert_eq!((num(&["frame_width"]), num(&["frame_height"])), (320.0, 240.0));
    assert_eq!(num(&["cycle_estimate", "clock_mhz"]), 480.0);
    assert!(num(&["frames"]) >= 100.0);
    assert!(num(&["instructions_per_generation", "max"]) <= GENERATION_BUDGET);
    // The ff+target run: within the budget, and the target path exercised on the larger frames too.
    assert!(num(&["ff_target", "instructions_per_generation", "max"]) <= GENERATION_BUDGET);
    assert!(num(&["ff_target", "generations_with_target_shift"]) >= 1.0);
    assert_eq!(num(&["ff_target", "deadline", "missed"]), 0.0);
    assert_eq!(num(&["deadline", "missed"]), 0.0);
    // Both point conventions: 960 model points, 768 walked per individual at rows of 8.
    let (model, walked) = (num(&["instructions_per_point_eval"]), num(&["instructions_per_walked_point"]));
    assert!((model * 960.0 - walked * 768.0).abs() < 2.0 * 960.0 * 0.01, "{model} / {walked}");
    assert!(num(&["cycle_estimate", "with_flash_wait_states", "milliseconds_per_generation"]) <= 16.0);
    assert_eq!(json["ram_check"]["fits"], true, "static RAM + stack over 512 KiB");
    Ok(())
}
