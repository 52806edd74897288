//! The report of `evorec timing`: `timing.json`, `timing.md` and the one-line summary.

use std::fmt::Write as _;

use evorec_firmware::timing::{NS_PER_TICK, ticks_to_instructions};
use serde_json::{Value, json};

use super::cycles::assumptions;
use super::{GENERATION_BUDGET, POINT_TARGET, RATIO_TARGET, Range, Results, RunStats, STACK_SIZES_HINT, StackAnalysis};

/// Worst-case stack: the static analysis or the painted mark of a generation, whichever is larger.
fn stack_bytes(r: &Results) -> u32 {
    r.stack.total().max(r.full.stack).max(r.target.as_ref().map_or(0, |t| t.stack))
}

/// The `ff+target` run in `timing.json` (`null` without it).
/// A run's instructions per generation by tracker status: `{status: {frames, min, max}}`.
fn by_status_json(run: &RunStats) -> Value {
    Value::Object(run.by_status.iter().map(|(k, n, r)| (k.as_str().to_owned(), range_json(*n, r))).collect())
}

/// A run's instructions per generation by frame kind: `{kind: {frames, min, max}}`.
fn by_kind_json(run: &RunStats) -> Value {
    Value::Object(run.by_kind.iter().map(|(k, n, r)| (k.name().to_owned(), range_json(*n, r))).collect())
}

/// `{frames, min, max}` of a group of generations.
fn range_json(frames: usize, r: &Range) -> Value {
    json!({"frames": frames, "min": r.min.round(), "max": r.max.round()})
}

fn target_json(r: &Results) -> Value {
    let Some(t) = &r.target else { return Value::Null };
    json!({
        "method": "ff+target",
        "frames": t.generations,
        "instructions_per_generation": {
            "min": t.call.min.round(), "max": t.call.max.round(), "mean": t.call.mean.round(),
            "budget": GENERATION_BUDGET, "within_budget": t.call.max <= GENERATION_BUDGET,
        },
        "phases": { "feedforward": t.feedforward.json(), "evaluate": t.evaluate.json(), "breed": t.breed.json() },
        "generations_with_target_shift": t.target_shifts,
        "target_shift_generations": t.target_shift_call.map(|c| c.json()),
        "instructions_per_point_eval": round2(t.per_point.max),
        "painted_generation_stack_bytes": t.stack,
        "frame_kinds": by_kind_json(t),
        "statuses": by_status_json(t),
        "deadline": { "generations_checked": r.deadline_target.checked, "missed": r.deadline_target.missed, "worst_instructions": r.deadline_target.worst_instructions.round() },
        "cycle_estimate": r.cyc_target.as_ref().map(|c| json!({
            "cycles_per_generation": c.cycles.round(), "microseconds_per_generation": round1(c.microseconds),
            "milliseconds_with_flash_wait_states": round2(c.flash_microseconds / 1000.0),
        })),
        "worst_generation_of_both_methods": r.full.call.max.max(t.call.max).round(),
    })
}

/// The `ff+target` section of `timing.md` (nothing without the run).
fn target_section(s: &mut String, r: &Results) {
    let Some(t) = &r.target else { return };
    let f = &r.full;
    let _ = writeln!(
        s,
        "## Feedforward of the target's motion (`ff+target`, the `target` run)\n\n\
         The same {} frames, population and rows, with `Feedforward::OnWithTarget`: the target motion model is \
         updated in every generation, and once it has observed a velocity (the conveyor frames: {} m/s along world \
         y) every individual but the elite is shifted by the target's twist too. **{} of {} generations fed a non-zero target \
         velocity forward** (`tshift=1` in the `GEN` lines).\n\n\
         | quantity (instructions) | ff: max | ff+target: max | ff+target: mean |\n|---|---:|---:|---:|",
        t.generations,
        evorec_firmware::timing::CONVEYOR_SPEED_M_S,
        t.target_shifts,
        t.generations
    );
    let row = |s: &mut String, name: &str, a: &Range, b: &Range| {
        let _ = writeln!(s, "| {name} | {:.0} | {:.0} | {:.0} |", a.max, b.max, b.mean);
    };
    row(s, "whole generation", &f.call, &t.call);
    row(s, "— feedforward", &f.feedforward, &t.feedforward);
    row(s, "— Evaluate", &f.evaluate, &t.evaluate);
    row(s, "— Breed (+ target filter update)", &f.breed, &t.breed);
    if let Some(c) = &t.target_shift_call {
        let _ = writeln!(s, "| generations with a target shift (whole call) | | {:.0} | {:.0} |", c.max, c.mean);
    }
    let worst = f.call.max.max(t.call.max);
    let _ = writeln!(
        s,
        "\nWorst generation of both methods: {worst:.0} instructions ({}, budget {GENERATION_BUDGET:.0}); \
         ff+target: {:.2} instructions per model point, painted stack {} B, deadline missed by {} of {} \
         generations{}.\n",
        if worst <= GENERATION_BUDGET { "within budget" } else { "**over budget**" },
        t.per_point.max,
        t.stack,
        r.deadline_target.missed,
        r.deadline_target.checked,
        r.cyc_target.as_ref().map_or(String::new(), |c| format!(
            "; ESTIMATE {:.0} cycles = {:.2} ms ({:.2} ms with flash wait states)",
            c.cycles,
            c.microseconds / 1000.0,
            c.flash_microseconds / 1000.0
        ))
    );
}

/// Instructions of one TIMER0 read.
fn read_instructions(r: &Results) -> f64 {
    ticks_to_instructions(u64::from(r.read_pair_ticks))
}

/// The flash wait-state part of `timing.json`.
fn flash_json(r: &Results) -> Value {
    json!({
        "label": format!("ESTIMATE (not a measurement): the above plus flash wait states behind the caches ({})", r.board.memory.label),
        "cycles_per_generation": r.cyc.flash_cycles.round(),
        "milliseconds_per_generation": round2(r.cyc.flash_microseconds / 1000.0),
        "target_milliseconds_per_frame": FRAME_TARGET_MS,
        "within_target": r.cyc.flash_microseconds / 1000.0 <= FRAME_TARGET_MS,
        "point_wait_cycles": r.cyc.flash_point_cycles.round(),
        "rest_wait_cycles": r.cyc.flash_rest_cycles.round(),
        "milliseconds_if_hot_loop_uncached_and_unknown_point_loads_from_flash": round2(r.cyc.flash_uncached_microseconds / 1000.0),
        "milliseconds_if_branches_cost_2": round2(r.cyc_b2.flash_microseconds / 1000.0),
        "hot_loop_span_bytes": r.mix.hot.span_bytes,
        "hot_loop_in_icache": r.mix.hot.cached,
        "flash_loads_per_point": round2(r.mix.point_waits.flash_loads),
        "unknown_base_loads_per_point": round2(r.mix.point_waits.other_loads),
        "rest_static": {
            "instructions": r.mix.rest.instructions, "flash_loads": r.mix.rest_waits.flash_loads,
            "unknown_base_loads": r.mix.rest_waits.other_loads, "branches": r.mix.rest_waits.branches,
            "sequential_fetch_stall_cycles": r.mix.rest_waits.fetch_stall,
        },
        "assumptions": r.board.memory.assumptions,
    })
}

/// One sweep run in `timing.json`.
fn sweep_json(s: &RunStats) -> Value {
    json!({
        "population": s.population, "points_per_row": s.grid, "points_per_individual": s.points_per_individual,
        "frames": s.generations,
        "min": s.call.min.round(), "max": s.call.max.round(), "ratio_max_min": (s.call.ratio() * 1e4).round() / 1e4,
        "evaluate_max": s.evaluate.max.round(), "feedforward_max": s.feedforward.max.round(), "breed_max": s.breed.max.round(),
        "instructions_per_point_eval": round2(s.per_point.max),
        "instructions_per_walked_point": round2(s.per_walked_point.max),
    })
}

/// The cycle-estimate part of `timing.json`.
fn cycle_json(r: &Results) -> Value {
    json!({
        "label": format!("ESTIMATE (not a measurement): measured worst-case instruction count x per-class worst-case cycle costs, {}", r.board.part),
        "clock_mhz": r.board.mhz(),
        "branch_cycles": r.board.branch_cycles,
        "cycles_per_generation": r.cyc.cycles.round(),
        "microseconds_per_generation": round1(r.cyc.microseconds),
        "evaluate_cycles": r.cyc_eval.cycles.round(),
        "cycles_per_generation_if_branches_cost_2": r.cyc_b2.cycles.round(),
        "microseconds_per_generation_if_branches_cost_2": round1(r.cyc_b2.microseconds),
        "point_cycles_per_point": round2(r.mix.point.cycles),
        "point_instructions_static": round2(r.mix.point.instructions),
        "point_windows": r.mix.windows,
        "rest_cycles_per_instruction": round2(r.mix.rest.cpi()),
        "point_mix": r.mix.point.classes.iter().map(|(k, v)| ((*k).to_owned(), json!(round2(*v)))).collect::<serde_json::Map<_, _>>(),
        "rest_mix": r.mix.rest.classes.iter().map(|(k, v)| ((*k).to_owned(), json!(v.round()))).collect::<serde_json::Map<_, _>>(),
        "assumptions": assumptions(&r.board),
        "with_flash_wait_states": flash_json(r),
    })
}

/// `timing.json`.
pub(super) fn json(r: &Results) -> Value {
    let stack_bytes = stack_bytes(r);
    let ram_check_fw = r.demo_stack.map(|(u, _)| r.fw_mem.static_ram_bytes + u64::from(u));
    let ram_check_timing = r.timing_mem.static_ram_bytes + u64::from(stack_bytes);
    let ram_bytes = r.board.ram_bytes;
    json!({
        "profile": r.board.profile.name,
        "part": r.board.part,
        "frame_width": r.board.profile.frame_width,
        "frame_height": r.board.profile.frame_height,
        "population": r.full.population,
        "population_capacity": r.full.capacity,
        "points_per_individual": r.full.points_per_individual,
        "walked_points_per_individual": r.full.walked_per_individual,
        "points_per_row": r.full.grid,
        "frames": r.full.generations,
        "frame_source": "generated on the board before each generation (core synth rasterizer + xorshift32 noise); not in the measured window",
        "instructions_per_generation": {
            "min": r.full.call.min.round(), "max": r.full.call.max.round(), "mean": r.full.call.mean.round(),
            "ratio_max_min": (r.full.call.ratio() * 1e4).round() / 1e4,
            "budget": GENERATION_BUDGET, "within_budget": r.full.call.max <= GENERATION_BUDGET,
            "over_budget_percent": round1((r.full.call.max / GENERATION_BUDGET - 1.0) * 100.0),
        },
        "phases": {
            "feedforward": r.full.feedforward.json(),
            "evaluate": r.full.evaluate.json(),
            "breed": r.full.breed.json(),
        },
        "statuses": by_status_json(&r.full),
        "frame_kinds": by_kind_json(&r.full),
        "instructions_per_point_eval": round2(r.full.per_point.max),
        "instructions_per_point_eval_range": { "min": round2(r.full.per_point.min), "max": round2(r.full.per_point.max) },
        "instructions_per_point_eval_marginal": r.marginal.map(round2),
        "instructions_per_walked_point": round2(r.full.per_walked_point.max),
        "point_conventions": "instructions_per_point_eval = Evaluate / (population x model points, 2 x 60 x G: the target's convention, per-pose overhead included); instructions_per_walked_point = Evaluate / (population x points the kernel walks, 2 x 48 x G)",
        "point_eval_target": POINT_TARGET,
        "stack_bytes": stack_bytes,
        "stack": stack_json(r),
        "deadline": {
            "limit_instructions": r.deadline.limit_instructions.round(),
            "generations_checked": r.deadline.checked,
            "missed": r.deadline.missed,
            "worst_instructions": r.deadline.worst_instructions.round(),
            "sweep_generations_checked": r.deadline_sweep.checked,
            "sweep_missed": r.deadline_sweep.missed,
        },
        "static_ram_bytes": r.fw_mem.static_ram_bytes,
        "flash_bytes": r.fw_mem.flash_bytes,
        "ram_bytes": ram_bytes,
        "ram_check": {
            "firmware_static_plus_painted_bytes": ram_check_fw,
            "timing_static_plus_stack_bytes": ram_check_timing,
            "fits": ram_check_fw.is_none_or(|v| v <= ram_bytes) && ram_check_timing <= ram_bytes,
        },
        "timing_firmware": { "flash_bytes": r.timing_mem.flash_bytes, "static_ram_bytes": r.timing_mem.static_ram_bytes },
        "sweep": r.sweep.iter().map(sweep_json).collect::<Vec<_>>(),
        "cycle_estimate": cycle_json(r),
        "ff_target": target_json(r),
        "measurement": measurement_json(r),
    })
}

/// `timing.json`'s `stack`: static and painted stack.
fn stack_json(r: &Results) -> Value {
    json!({
        "static_generation_bytes": r.stack.generation.bytes,
        "static_callers_bytes": r.stack.callers.bytes,
        "static_total_bytes": r.stack.total(),
        "static_path": r.stack.callers.frames.iter().chain(r.stack.generation.frames.iter())
            .map(|(function, bytes)| json!({ "function": function, "bytes": bytes }))
            .collect::<Vec<_>>(),
        "static_method": r.stack.method,
        "static_image": r.stack.image.display().to_string(),
        "static_prologue_total_bytes": r.stack_prologue.as_ref().map(StackAnalysis::total),
        "indirect_calls_in_generation": r.stack.indirect_calls,
        "recursion": r.stack.recursion,
        "stack_sizes_vs_prologue_mismatches": r.stack.prologue_mismatches.len(),
        "painted_generation_bytes": r.full.stack,
        "firmware_painted_bytes": r.demo_stack.map(|(u, _)| u),
        "firmware_stack_region_bytes": r.demo_stack.map(|(_, s)| s),
    })
}

/// `timing.json`'s `measurement`: how the instructions were counted.
fn measurement_json(r: &Results) -> Value {
    json!({
        "qemu": format!("qemu-system-arm {} -icount shift=10 (1 instruction = 1024 ns virtual)", r.board.qemu_machine().join(" ")),
        "timer": format!("CMSDK APB TIMER0 @ 0x40000000, SYSCLK 25 MHz ({NS_PER_TICK} ns/tick): instructions = ticks * 40 / 1024"),
        "timer_read_pair_ticks": r.read_pair_ticks,
        "timer_read_instructions": round2(read_instructions(r)),
        "window": "instructions_per_generation = the whole Tracker::step_probed call (input checks, 4 probe marks of ~4 instructions each included); phases between probe marks",
        "timing_image": r.timing_elf.display().to_string(),
        "firmware_image": r.firmware_elf.display().to_string(),
    })
}

/// The max/min line of `timing.md`: over every frame, which mixes the tracker's statuses (a
/// searching or lost generation leaves idle individuals unevaluated), and per status.
fn ratio_line(full: &RunStats, verdict: &str) -> String {
    let per_status: Vec<String> =
        full.by_status.iter().map(|(st, n, r)| format!("{} {:.4} ({n} frames)", st.as_str(), r.ratio())).collect();
    format!(
        "- max/min over every frame, all statuses mixed: **{:.4}** (target ≤ {RATIO_TARGET}); per status: {}; \
         worst case {:.0} instructions: {verdict}.",
        full.call.ratio(),
        if per_status.is_empty() { "none".to_owned() } else { per_status.join(", ") },
        full.call.max
    )
}

/// The line printed at the end of a run.
pub(super) fn summary(r: &Results) -> String {
    let f = &r.full;
    format!(
        "{} at {}: instructions per generation (P = {}, G = {}): min {:.0}, max {:.0} (max/min {:.4}); {:.2} per model point \
         ({:.2} per walked point); stack {} B; flash {} B; static RAM {} B; ESTIMATE {:.0} cycles = {:.0} µs at {:.0} MHz \
         ({:.0} µs with flash wait states); deadline {:.0}: {} of {} generations missed (worst {:.0}){}",
        r.board.profile.name,
        r.board.frame_size(),
        f.population,
        f.grid,
        f.call.min,
        f.call.max,
        f.call.ratio(),
        f.per_point.max,
        f.per_walked_point.max,
        stack_bytes(r),
        r.fw_mem.flash_bytes,
        r.fw_mem.static_ram_bytes,
        r.cyc.cycles,
        r.cyc.microseconds,
        r.board.mhz(),
        r.cyc.flash_microseconds,
        r.deadline.limit_instructions,
        r.deadline.missed,
        r.deadline.checked,
        r.deadline.worst_instructions,
        r.target.as_ref().map_or(String::new(), |t| format!(
            "; ff+target: max {:.0} ({} of {} generations shifted by the target's velocity; ESTIMATE {:.0} µs), \
             {} of {} missed the deadline",
            t.call.max,
            t.target_shifts,
            t.generations,
            r.cyc_target.as_ref().map_or(0.0, |c| c.microseconds),
            r.deadline_target.missed,
            r.deadline_target.checked
        ))
    )
}

/// Target for the worst-case time of one frame (half of a 30 fps period).
pub const FRAME_TARGET_MS: f64 = 16.0;

/// The flash wait-state part of `timing.md`.
fn flash_section(s: &mut String, r: &Results) {
    let (c, w, hot) = (&r.cyc, &r.mix.point_waits, &r.mix.hot);
    let ms = c.flash_microseconds / 1000.0;
    let verdict = if ms <= FRAME_TARGET_MS { "✔" } else { "✘" };
    let mem = &r.board.memory;
    let _ = writeln!(
        s,
        "\n### With flash wait states ({})\n\n\
         **≈ {:.0} cycles = {ms:.2} ms per worst-case generation** (target ≤ {FRAME_TARGET_MS} ms per frame {verdict}): \
         {:.0} zero-wait cycles + {:.0} wait cycles at the sample points + {:.0} in the rest.\n",
        mem.label, c.flash_cycles, c.cycles, c.flash_point_cycles, c.flash_rest_cycles
    );
    let _ = writeln!(
        s,
        "- hot loop: the point windows span {} B, {} the {} B instruction cache;\n\
         - per walked point: {:.2} loads from flash (+{} cycles each), {:.2} loads through registers of unknown provenance \
         (SRAM in the estimate);\n\
         - sensitivity: hot loop missing the cache and every unknown point load from flash: {:.2} ms; every branch \
         at 2 cycles: {:.2} ms.\n",
        hot.span_bytes,
        if hot.cached { "inside" } else { "larger than" },
        mem.icache_bytes,
        w.flash_loads,
        mem.miss_cycles,
        w.other_loads,
        c.flash_uncached_microseconds / 1000.0,
        r.cyc_b2.flash_microseconds / 1000.0
    );
    let _ = writeln!(s, "Wait-state assumptions:\n");
    for a in mem.assumptions {
        let _ = writeln!(s, "- {a}");
    }
}

/// `timing.md`.
pub(super) fn markdown(r: &Results) -> String {
    let mut s = String::new();
    heading(&mut s, r);
    budget_table(&mut s, r);
    target_section(&mut s, r);
    by_kind_and_status(&mut s, &r.full);
    if r.sweep.is_empty() {
        let _ = writeln!(s, "\n(No sweep on this profile: the configuration is chosen on the M4.)");
    } else {
        sweep_table(&mut s, &r.full, &r.sweep);
    }
    cycle_estimate(&mut s, r);
    flash_section(&mut s, r);
    stack_and_memory(&mut s, r);
    let b = &r.board;
    let _ = writeln!(
        s,
        "\nReproduce: `{}` (and optionally `{STACK_SIZES_HINT}`), then \
         `cargo run --release -p evorec-sim -- timing --out DIR --profile {}`.",
        b.build_hint, b.profile.name
    );
    s
}

/// The heading and the firmware configuration the counts are of.
fn heading(s: &mut String, r: &Results) {
    let (full, b) = (&r.full, &r.board);
    let _ = writeln!(
        s,
        "# Worst-case timing and memory of one GA generation ({}, profile `{}`, QEMU `{}`, `-icount shift=10`)\n",
        b.part, b.profile.name, b.profile.qemu_machine
    );
    let _ = writeln!(
        s,
        "Firmware configuration: population {} (run-time; capacity {}), {} points per row ({} model sample points per individual, \
         both cameras; {} walked), {} frames, feedforward on. {} generations on frames made on the board: every kind below, one tracker \
         running through all of them. Instructions are counted with TIMER0 on QEMU's instruction clock \
         (`ticks · 40 / 1024`, deterministic); a generation is the whole `Tracker::step_probed` call.\n",
        full.population,
        full.capacity,
        full.grid,
        full.points_per_individual,
        full.walked_per_individual,
        b.frame_size(),
        full.generations
    );
}

/// The instructions per generation against the budget, by phase and per point.
fn budget_table(s: &mut String, r: &Results) {
    let (full, marginal, read_ins) = (&r.full, r.marginal, read_instructions(r));
    let _ = writeln!(s, "| quantity | min | max | mean | target |\n|---|---:|---:|---:|---|");
    let row = |s: &mut String, name: &str, r: &Range, target: &str| {
        let _ = writeln!(s, "| {name} | {:.0} | {:.0} | {:.0} | {target} |", r.min, r.max, r.mean);
    };
    row(s, "instructions per generation", &full.call, &format!("≤ {GENERATION_BUDGET:.0}"));
    let d = &r.deadline;
    let _ = writeln!(
        s,
        "| generations over the firmware's deadline ({:.0} instructions) | | {} of {} | worst {:.0} | 0 {} (sweep: {} of {}, not budgeted) |",
        d.limit_instructions,
        d.missed,
        d.checked,
        d.worst_instructions,
        if d.missed == 0 { "✔" } else { "✘" },
        r.deadline_sweep.missed,
        r.deadline_sweep.checked
    );
    row(s, "— feedforward", &full.feedforward, "");
    row(s, "— projection + fitness (Evaluate)", &full.evaluate, "");
    row(s, "— selection/crossover/mutation (Breed)", &full.breed, "");
    let _ = writeln!(
        s,
        "| instructions per model point (Evaluate / ({} · {}), the target's convention) | {:.2} | {:.2} | {:.2} | ≤ {POINT_TARGET} |",
        full.population, full.points_per_individual, full.per_point.min, full.per_point.max, full.per_point.mean
    );
    let _ = writeln!(
        s,
        "| instructions per walked point (Evaluate / ({} · {})) | {:.2} | {:.2} | {:.2} | |",
        full.population,
        full.walked_per_individual,
        full.per_walked_point.min,
        full.per_walked_point.max,
        full.per_walked_point.mean
    );
    let _ = writeln!(s);
    let verdict = if full.call.max <= GENERATION_BUDGET {
        "within budget".to_owned()
    } else {
        format!("**over budget by {:.1} %**", (full.call.max / GENERATION_BUDGET - 1.0) * 100.0)
    };
    let _ = writeln!(s, "{}", ratio_line(full, &verdict));
    let _ = writeln!(
        s,
        "- per point: the Evaluate phase divided by the points; it includes the per-pose overhead (ψ → rotation, two \
         projectors, face choice and visibility, row starts, the GA's best-of bookkeeping). The model has 60 points per \
         row length and camera (the target's convention); the kernel walks 48 of them (the outer rows only on the at most \
         6 silhouette edges, `SurfaceStrips::WALKED_PER_CAMERA`). Marginal cost of a model point \
         (Evaluate at 8 minus 4 points per row, population 40): {}.",
        marginal.map_or("n/a".to_owned(), |v| format!("{v:.2} instructions"))
    );
    let _ = writeln!(
        s,
        "- one TIMER0 read costs {read_ins:.2} instructions; the 4 probe marks add ≈ 16 to a generation.\n"
    );
}

/// The whole call by kind of frame and by tracker status.
fn by_kind_and_status(s: &mut String, full: &RunStats) {
    let _ = writeln!(
        s,
        "## By kind of frame (whole call, instructions)\n\n| frames | n | min | max |\n|---|---:|---:|---:|"
    );
    for (k, n, r) in &full.by_kind {
        let _ = writeln!(s, "| {} | {n} | {:.0} | {:.0} |", k.name(), r.min, r.max);
    }
    let _ = writeln!(
        s,
        "\n## By tracker status (whole call, instructions)\n\nThe status decides the work of a generation: \
         while searching or lost, the acquisition runs one bounded stage and `AcquireConfig::idle_individuals` \
         individuals are not evaluated; an uncertain generation (forced as a hold unconfirmed for `DOUBT_FRAMES`) \
         adds the turn probes in `ff+target`. The budget is set by tracking when the other rows' max is lower.\n\n\
         | status | n | min | max |\n|---|---:|---:|---:|"
    );
    for (st, n, r) in &full.by_status {
        let _ = writeln!(s, "| {} | {n} | {:.0} | {:.0} |", st.as_str(), r.min, r.max);
    }
}

/// The cycle estimate of the worst generation from the instruction mix.
fn cycle_estimate(s: &mut String, r: &Results) {
    let (full, cyc, cyc_b2, mix, b) = (&r.full, &r.cyc, &r.cyc_b2, &r.mix, &r.board);
    let _ = writeln!(
        s,
        "\n## Cycle ESTIMATE for a {:.0} MHz {} (not a measurement)\n\n\
         **≈ {:.0} cycles = {:.0} µs per worst-case generation** ({:.0} cycles in the {} walked sample points at {:.1} cycles \
         each, {:.0} in the rest at {:.2} cycles per instruction).\n",
        b.mhz(),
        b.part,
        cyc.cycles,
        cyc.microseconds,
        cyc.point_cycles,
        full.population * full.walked_per_individual,
        mix.point.cycles,
        cyc.rest_cycles,
        mix.rest.cpi()
    );
    let _ = writeln!(
        s,
        "Sensitivity: with every branch at 2 cycles instead of {:.0} (a 1-cycle refill), {:.0} cycles = {:.0} µs.\n",
        b.branch_cycles, cyc_b2.cycles, cyc_b2.microseconds
    );
    let _ = writeln!(
        s,
        "One sample point ({} windows between the pixel loads of the fitness kernel's walk; {:.1} static instructions per point):\n",
        mix.windows, mix.point.instructions
    );
    let _ = writeln!(s, "| class (worst-case cycles) | instructions per point |\n|---|---:|");
    for (k, v) in &mix.point.classes {
        let _ = writeln!(s, "| {k} | {v:.2} |");
    }
    let _ = writeln!(s, "\nAssumptions:\n");
    for a in assumptions(b) {
        let _ = writeln!(s, "- {a}");
    }
}

/// Static and painted stack, flash and static RAM, and the deepest static path.
fn stack_and_memory(s: &mut String, r: &Results) {
    let (full, stack, stack_prologue, b) = (&r.full, &r.stack, r.stack_prologue.as_ref(), &r.board);
    let (fw, timing, demo_stack) = (r.fw_mem, r.timing_mem, r.demo_stack);
    let _ = writeln!(s, "\n## Stack and memory\n");
    let _ = writeln!(s, "| quantity | bytes | how |\n|---|---:|---|");
    let _ = writeln!(
        s,
        "| static worst case, one generation (below the generation function) | {} | {} |",
        stack.generation.bytes, stack.method
    );
    let _ = writeln!(s, "| static worst case, `Reset` → generation | {} | same, deepest caller path |", stack.total());
    if let Some(p) = stack_prologue {
        let _ = writeln!(s, "| same from the prologues of the measured image | {} | cross-check |", p.total());
    }
    let _ = writeln!(
        s,
        "| painted high-water mark, one generation (max over the run) | {} | stack re-painted before each generation |",
        full.stack
    );
    if let Some((u, sz)) = demo_stack {
        let _ = writeln!(
            s,
            "| firmware painted high-water mark (demo, 30 frames, incl. tracker construction) | {u} | of a {sz}-byte stack region |"
        );
    }
    let _ = writeln!(
        s,
        "| firmware flash (`.vector_table + .text + .rodata + .data`) | {} | ELF section headers |",
        fw.flash_bytes
    );
    let _ = writeln!(
        s,
        "| firmware static RAM (`.data + .bss + .uninit`) | {} | ELF section headers |",
        fw.static_ram_bytes
    );
    if let Some((u, _)) = demo_stack {
        let total = fw.static_ram_bytes + u64::from(u);
        let _ =
            writeln!(s, "| firmware static RAM + painted stack | {total} | of {} ({}) |", b.ram_bytes, b.memory_map);
    }
    let _ = writeln!(
        s,
        "| timing firmware flash / static RAM (one tracker slot) | {} / {} | ELF section headers |",
        timing.flash_bytes, timing.static_ram_bytes
    );
    let _ = writeln!(
        s,
        "\nIndirect calls reachable from the generation: {}; recursion: {}.\n\nDeepest static path:\n",
        stack.indirect_calls,
        if stack.recursion { "yes (bound void)" } else { "none" }
    );
    for (name, frame) in stack.callers.frames.iter().chain(stack.generation.frames.iter()) {
        let _ = writeln!(s, "- {frame:>6} B  `{name}`");
    }
}

/// The sweep's table (the `full` run is its population-40, rows-of-8 line).
fn sweep_table(s: &mut String, full: &RunStats, sweep: &[RunStats]) {
    let _ = writeln!(
        s,
        "\n## Sweep: population × points per row ({} frames each, every kind; P = 40 with rows of 8 is the `full` run)\n\n\
         | population | points/row | model points/individual | min | max | max/min | Evaluate max | per model point (max) | per walked point (max) |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        sweep.first().map_or(0, |r| r.generations)
    );
    let mut rows: Vec<&RunStats> = sweep.iter().chain(std::iter::once(full)).collect();
    rows.sort_by_key(|r| (r.population, r.grid));
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.0} | {:.0} | {:.4} | {:.0} | {:.2} | {:.2} |",
            r.population,
            r.grid,
            r.points_per_individual,
            r.call.min,
            r.call.max,
            r.call.ratio(),
            r.evaluate.max,
            r.per_point.max,
            r.per_walked_point.max
        );
    }
}

pub(super) fn round1(v: f64) -> f64 {
    (v * 10.0).round() / 10.0
}

pub(super) fn round2(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use evorec_core::status::Status;

    #[test]
    fn the_ratio_line_names_the_mix_and_gives_each_status() {
        let range = |min: f64, max: f64| Range { min, max, mean: 0.5 * (min + max) };
        let full = RunStats {
            population: 40,
            capacity: 40,
            grid: 8,
            points_per_individual: 960,
            walked_per_individual: 768,
            generations: 30,
            call: range(100.0, 130.0),
            feedforward: range(1.0, 1.0),
            evaluate: range(90.0, 120.0),
            breed: range(9.0, 9.0),
            per_point: range(0.1, 0.1),
            per_walked_point: range(0.1, 0.1),
            stack: 0,
            by_kind: Vec::new(),
            by_status: vec![(Status::Tracking, 20, range(125.0, 130.0)), (Status::Searching, 10, range(100.0, 104.0))],
            target_shifts: 0,
            target_shift_call: None,
        };
        assert_eq!(
            ratio_line(&full, "within budget"),
            "- max/min over every frame, all statuses mixed: **1.3000** (target ≤ 1.05); per status: tracking 1.0400 \
             (20 frames), searching 1.0400 (10 frames); worst case 130 instructions: within budget."
        );
    }
}
