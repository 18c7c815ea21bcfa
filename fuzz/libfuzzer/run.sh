#!/usr/bin/env bash
# Coverage-guided fuzzing of every model kind's loader and evaluation (libFuzzer through
# libfuzzer-sys, on rustup's stable toolchain: the instrumentation flags are stable).
#
#   fuzz/libfuzzer/run.sh SECONDS [JOBS]
#
# Starts from the committed corpus (fuzz/corpus/, blobs the trainer wrote) and keeps what it
# finds in target/fuzz/corpus; a crash (a panic) is written to target/fuzz/artifacts and fails
# the run. scripts/test.sh runs a short smoke run; longer campaigns are documented in
# fuzz/README.md.
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-60}
jobs=${2:-1}
root=$(cd ../.. && pwd)
# libfuzzer-sys compiles libFuzzer's C++ sources.
if ! command -v c++ >/dev/null; then
    if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
    "${sudo[@]}" apt-get update -qq
    "${sudo[@]}" apt-get install -y -qq --no-install-recommends g++
fi
out="$root/target/fuzz"
export CARGO_TARGET_DIR="$out/build"
export RUSTFLAGS="--cfg fuzzing -Cpasses=sancov-module \
 -Cllvm-args=-sanitizer-coverage-level=4 \
 -Cllvm-args=-sanitizer-coverage-inline-8bit-counters \
 -Cllvm-args=-sanitizer-coverage-pc-table \
 -Cllvm-args=-sanitizer-coverage-trace-compares"
# An explicit --target keeps the instrumentation out of build scripts and proc macros.
host=$(rustc -vV | sed -n 's/^host: //p')
cargo build --quiet --release --bin blob --target "$host"
mkdir -p "$out/corpus" "$out/artifacts"
seeds=$(cd ../corpus && pwd)
# With JOBS > 1, libFuzzer writes each job's log (fuzz-N.log) to the working folder.
cd "$out"
parallel=()
if [ "$jobs" -gt 1 ]; then parallel=(-jobs="$jobs" -workers="$jobs"); fi
"$CARGO_TARGET_DIR/$host/release/blob" "$out/corpus" "$seeds" "${parallel[@]}" \
    -max_total_time="$seconds" -timeout=5 \
    -artifact_prefix="$out/artifacts/" -print_final_stats=1
