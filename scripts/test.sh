#!/usr/bin/env bash
# Every check and every test of the workspace: the README's test command, and CI's.
# Needs only rustup's stable toolchain (with rustfmt and clippy), gcc, python3 and apt on a fresh
# machine: firmware-sim/scripts/setup.sh installs the Cortex-M toolchain and QEMU idempotently.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }

step "format"
cargo fmt --all --check
cargo fmt --manifest-path firmware-sim/firmware/Cargo.toml --check
cargo fmt --manifest-path examples/cortex-m/Cargo.toml --check
cargo fmt --manifest-path fuzz/libfuzzer/Cargo.toml --check
step "lints"
cargo clippy --workspace --all-targets -- -D warnings
step "docs"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet
step "core with its optional features (defmt, serde)"
cargo check -p neurosurf-core --features defmt,serde --quiet
step "firmware for the simulated Cortex-M4F (core for thumbv7em-none-eabihf: no std, no heap)"
firmware-sim/scripts/setup.sh >/dev/null
cargo run --quiet -p neurosurf-firmware-sim --example build_firmware
step "tests"
cargo test --workspace
for target in blob readers; do
    step "coverage-guided fuzz smoke run: $target, 30 s from its committed corpus"
    mkdir -p target
    log=target/fuzz-smoke-$target.log
    fuzz/libfuzzer/run.sh "$target" 30 >"$log" 2>&1 || { tail -n 60 "$log"; exit 1; }
    tail -n 6 "$log"
done
