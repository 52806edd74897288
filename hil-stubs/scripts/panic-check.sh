#!/usr/bin/env bash
# No panic path from the link decoder and Tracker::step. Two checks on the panic
# probe image (src/bin/evorec-panic-check.rs: only `read_message` and `Tracker::step` behind
# the `#[inline(never)]` roots `decode_root` and `step_root`):
#
# 1. panic-never: build the probe with the feature `panic-never`, whose panic handler calls a
#    symbol defined nowhere. It links only if no panic survives optimisation anywhere in the
#    image (tracker construction included).
# 2. call graph: build the probe normally, disassemble it (llvm-objdump from the llvm-tools
#    component), build the call graph from `bl`/`b`/`b.w` to named functions, and list every
#    call to a panic entry point (core::panicking::*, panic_bounds_check, slice_*_fail,
#    unwrap_failed, expect_failed, …) in a function reachable from each root, with the
#    caller. Calls made through function pointers are not followed (the decoder and the step
#    make none).
#
# Prints every panic call site of the image with its source line, and `panic call sites
# reachable from decode_root: N` / `step_root: M`; exits non-zero if N or M is not zero.
# Usage: hil-stubs/scripts/panic-check.sh
set -euo pipefail
cd "$(dirname "$0")/.."

rustup component add llvm-tools >/dev/null 2>&1 || true
bindir="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
objdump="$bindir/llvm-objdump"
target_dir="${CARGO_TARGET_DIR:-$PWD/../target}"
elf="$target_dir/thumbv7em-none-eabihf/release/evorec-panic-check"
never_log="$target_dir/panic-never.log"

status=0
echo "== 1. panic-never build of the probe (links only without surviving panics; informational:"
echo "   the image also holds tracker construction, whose panics part 2 lists)"
if cargo build --release --bin evorec-panic-check --features panic-never >"$never_log" 2>&1; then
    echo "panic-never: the probe links: no panic survives optimisation in decode, step or construction"
else
    if grep -q evorec_panic_is_reachable "$never_log"; then
        echo "panic-never: link FAILED, a panic survives (see $never_log):"
        grep -A3 "evorec_panic_is_reachable" "$never_log" | head -20
    else
        cat "$never_log"
        exit 2
    fi
fi

echo "== 2. call graph of the probe's disassembly"
cargo build --release --bin evorec-panic-check >/dev/null
"$objdump" -d -l --demangle --no-show-raw-insn "$elf" >"$elf.dis"
python3 - "$elf.dis" <<'PY' || status=1
import re, sys

text = open(sys.argv[1], encoding="utf-8", errors="replace").read().splitlines()
func_re = re.compile(r"^[0-9a-f]+ <(.+)>:$")
call_re = re.compile(r"\s(bl|blx|b|b\.w|beq\.w|bne\.w|b[a-z]{2}(?:\.w)?)\s+(?:0x)?[0-9a-f]+ <([^>+]+)(\+0x[0-9a-f]+)?>")
panic_re = re.compile(
    r"core::panicking::|panic_bounds_check|slice_(start|end)_index_(len_)?fail|slice_index_order_fail"
    r"|unwrap_failed|expect_failed|panic_fmt|panic_const|core::option::expect|core::result::unwrap"
    r"|rust_begin_unwind|str_index_overflow_fail|slice_error_fail|len_mismatch_fail|assert_failed")

# `-l` puts "; file:line" comments (outermost inlined frame first) before the instructions.
calls, cur, where = {}, None, []
for line in text:
    m = func_re.match(line)
    if m:
        cur, where = m.group(1), []
        calls.setdefault(cur, [])
        continue
    if cur is None:
        continue
    if line.startswith("; /") or line.startswith("; ."):
        src = line[2:].strip()
        where = [src] if not where or where[-1] == "@" else where + [src]
        continue
    if line.startswith(";"):
        continue
    c = call_re.search(line)
    if c and c.group(2) != cur:
        frames = [w for w in where if w != "@"]
        ours = [w for w in frames if "/.cargo/registry/" not in w and "/rustlib/" not in w]
        calls[cur].append((c.group(2), line.strip() + "  at " + (ours[-1] if ours else (frames[-1] if frames else "?"))))
    where = where + ["@"] if where and where[-1] != "@" else where

def is_panic(name):
    return bool(panic_re.search(name))

def reachable(root):
    roots = [f for f in calls if root in f]
    if not roots:
        print(f"root {root} not found in the disassembly", file=sys.stderr)
        sys.exit(2)
    seen, stack = set(roots), list(roots)
    while stack:
        f = stack.pop()
        for callee, _ in calls.get(f, []):
            if callee not in seen and not is_panic(callee):
                seen.add(callee)
                stack.append(callee)
    return seen

all_sites = [(f, callee, insn) for f in sorted(calls) if not is_panic(f) for callee, insn in calls[f] if is_panic(callee)]
print(f"panic call sites in the whole probe image: {len(all_sites)}")
for f, callee, insn in all_sites:
    print(f"  {f}\n      -> {callee}   [{insn}]")
total = 0
for root in ["decode_root", "step_root"]:
    funcs = reachable(root)
    sites = [(f, callee, insn) for f in sorted(funcs) if not is_panic(f) for callee, insn in calls[f] if is_panic(callee)]
    print(f"panic call sites reachable from {root}: {len(sites)} (in {len(funcs)} functions)")
    for f, callee, insn in sites:
        print(f"  {f}\n      -> {callee}   [{insn}]")
    total += len(sites)
sys.exit(1 if total else 0)
PY
exit $status
