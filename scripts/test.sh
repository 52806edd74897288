#!/usr/bin/env bash
# The project's test command (README.md, .ci/run): installs what the tests need if it is missing, builds
# the firmware, then runs every test: the workspace's (host, simulator, and the HIL tests that
# drive the firmware under QEMU) and the firmware's on-target tests under QEMU.
set -euo pipefail
cd "$(dirname "$0")/.."

rustup target list --installed | grep -qx thumbv7em-none-eabihf || rustup target add thumbv7em-none-eabihf
if ! command -v qemu-system-arm >/dev/null; then
    if [ "$(id -u)" = 0 ]; then
        apt-get update && apt-get install -y qemu-system-arm
    else
        echo "qemu-system-arm is missing: sudo apt-get update && sudo apt-get install -y qemu-system-arm" >&2
        exit 1
    fi
fi

echo "== firmware (thumbv7em-none-eabihf, release)"
(cd hil-stubs && cargo build --release)

echo "== workspace tests"
cargo test --workspace

echo "== on-target tests (QEMU)"
(cd hil-stubs && cargo test --release --test on_target)
