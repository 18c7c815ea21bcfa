#!/usr/bin/env bash
# Every check and every test of the workspace: the README's test command, and CI's.
# Needs only rustup's stable toolchain (with rustfmt and clippy) on a fresh machine.
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n==> %s\n' "$*"; }

step "format"
cargo fmt --all --check
step "lints"
cargo clippy --workspace --all-targets -- -D warnings
step "docs"
RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps --quiet
step "core with its optional features (defmt, serde)"
cargo check -p neurosurf-core --features defmt,serde --quiet
step "tests"
cargo test --workspace
