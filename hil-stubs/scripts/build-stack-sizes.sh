#!/usr/bin/env bash
# Builds the firmware images a second time with `-Z emit-stack-sizes` (a `.stack_sizes`
# section with every function's frame size, from LLVM) into `$TARGET/stack-sizes/`, where
# `evorec timing` finds them for the static worst-case stack analysis, and lists the largest
# frames. `-Z` needs a nightly feature switch: RUSTC_BOOTSTRAP=1 on the stable toolchain.
#
#   hil-stubs/scripts/build-stack-sizes.sh            # from anywhere in the workspace
#
# TARGET is $CARGO_TARGET_DIR if set, else the workspace's target/. The normal images
# (`cd hil-stubs && cargo build --release`) are not touched: the flags differ, so the
# build goes to its own directory.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
workspace="$(cd "$here/.." && pwd)"
target="${CARGO_TARGET_DIR:-$workspace/target}"
case "$target" in /*) ;; *) target="$workspace/$target" ;; esac
out="$target/stack-sizes"
cd "$here"
RUSTC_BOOTSTRAP=1 RUSTFLAGS="-C link-arg=-Tlink.x -Z emit-stack-sizes" CARGO_TARGET_DIR="$out" \
    cargo build --release --bin evorec-timing --bin evorec-firmware
elf="$out/thumbv7em-none-eabihf/release/evorec-timing"
readobj="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin/llvm-readobj"
[ -x "$readobj" ] || readobj="$(command -v llvm-readobj)" || {
    echo "llvm-readobj not found: rustup component add llvm-tools (or apt-get install -y llvm)" >&2
    exit 1
}
echo "stack-sizes images in $out/thumbv7em-none-eabihf/release/ (evorec-timing, evorec-firmware)"
echo "largest frames of evorec-timing (bytes, function):"
"$readobj" --stack-sizes --demangle "$elf" |
    sed -n 's/^ *Functions: \[\(.*\)\]$/\1/p; s/^ *Size: \(0x[0-9A-Fa-f]*\)$/\1/p' |
    paste - - |
    while IFS=$'\t' read -r name size; do printf '%8d  %s\n' "$size" "$name"; done |
    sort -rn | head -15
