#!/usr/bin/env bash
# Coverage-guided fuzzing of every model kind's loader and evaluation (libFuzzer through
# libfuzzer-sys, on rustup's stable toolchain: the instrumentation flags are stable).
#
#   fuzz/libfuzzer/run.sh [blob|readers] SECONDS [JOBS]
#
# `blob` (the default) fuzzes every model kind's loader and evaluation from the committed
# corpus fuzz/corpus/ (blobs the trainer wrote); `readers` fuzzes the trainer's file readers
# from fuzz/corpus-readers/, the first byte of an input picking the reader, or only reader k
# with NEUROSURF_FUZZ_READER=k (0-8); its logs count the executions per reader. What it finds is kept in target/fuzz/<target>/corpus; a crash (a
# panic) is written to target/fuzz/<target>/artifacts and fails the run. scripts/test.sh runs a short smoke run; longer campaigns are documented in
# fuzz/README.md.
set -euo pipefail
cd "$(dirname "$0")"
target=blob
if [ "${1:-}" = blob ] || [ "${1:-}" = readers ]; then target=$1; shift; fi
seconds=${1:-60}
jobs=${2:-1}
root=$(cd ../.. && pwd)
# libfuzzer-sys compiles libFuzzer's C++ sources.
if ! command -v c++ >/dev/null; then
    if [ "$(id -u)" -eq 0 ]; then sudo=(); else sudo=(sudo); fi
    "${sudo[@]}" apt-get update -qq
    "${sudo[@]}" apt-get install -y -qq --no-install-recommends g++
fi
export CARGO_TARGET_DIR="$root/target/fuzz/build"
out="$root/target/fuzz/$target"
export RUSTFLAGS="--cfg fuzzing -Cpasses=sancov-module \
 -Cllvm-args=-sanitizer-coverage-level=4 \
 -Cllvm-args=-sanitizer-coverage-inline-8bit-counters \
 -Cllvm-args=-sanitizer-coverage-pc-table \
 -Cllvm-args=-sanitizer-coverage-trace-compares"
# An explicit --target keeps the instrumentation out of build scripts and proc macros.
host=$(rustc -vV | sed -n 's/^host: //p')
features=()
if [ "$target" = readers ]; then features=(--features readers); fi
cargo build --quiet --release --bin "$target" --target "$host" "${features[@]}"
mkdir -p "$out/corpus" "$out/artifacts"
if [ "$target" = readers ]; then seeds=$(cd ../corpus-readers && pwd); else seeds=$(cd ../corpus && pwd); fi
# With JOBS > 1, libFuzzer writes each job's log (fuzz-N.log) to the working folder.
cd "$out"
parallel=()
if [ "$jobs" -gt 1 ]; then parallel=(-jobs="$jobs" -workers="$jobs"); fi
"$CARGO_TARGET_DIR/$host/release/$target" "$out/corpus" "$seeds" "${parallel[@]}" \
    -max_total_time="$seconds" -timeout=5 \
    -artifact_prefix="$out/artifacts/" -print_final_stats=1
