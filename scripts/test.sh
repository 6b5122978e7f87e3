#!/usr/bin/env bash
# Sets up, builds and runs every test: bash scripts/test.sh [build-dir]
#   1. Release build of everything (CMake preset `release`) and its whole test suite;
#   2. AddressSanitizer + UndefinedBehaviorSanitizer build of the library tests (preset `asan-ubsan`,
#      in <build-dir>-asan), the suite without the `long` label;
#   3. a smoke run of the libFuzzer target (preset `fuzz`, in <build-dir>-fuzz), when clang can link it.
# MJUKF_SKIP_SANITIZERS=1 runs step 1 only.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${1:-build}
jobs=$(nproc)

cmake --preset release -B "$build"
cmake --build "$build" -j "$jobs"
ctest --test-dir "$build" --output-on-failure -j "$jobs"

[ "${MJUKF_SKIP_SANITIZERS:-0}" = 1 ] && exit 0

# Sanitizers: a refusal to recover from any report (-fno-sanitize-recover=all) fails the test.
cmake --preset asan-ubsan -B "$build-asan"
cmake --build "$build-asan" -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$build-asan" --output-on-failure -j "$jobs" -LE long

if [ -f tests/fuzz/CMakeLists.txt ]; then
  cmake --preset fuzz -B "$build-fuzz"
  cmake --build "$build-fuzz" -j "$jobs"
  # The inputs that once failed, then a short smoke run; docs/robustness.md records the long run.
  "$build-fuzz"/tests/fuzz/mjukf_fuzz tests/fuzz/regressions/*
  "$build-fuzz"/tests/fuzz/mjukf_fuzz -runs=20000 -seed=1 -max_len=1024
fi
