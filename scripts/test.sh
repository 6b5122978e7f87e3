#!/usr/bin/env bash
# Sets up, builds and runs every test: bash scripts/test.sh [build-dir]
#   1. Release build of everything with g++ (CMake preset `release`) and its whole test suite (the
#      format check of the C++ sources, scripts/check_format.sh, included), then the API reference
#      (target mjukf_docs, doxygen warnings as errors);
#   2. the firmware example built for a Cortex-M4F and run under QEMU, its estimates compared with the
#      host's (scripts/embedded.sh, docs/embedded.md); MJUKF_SKIP_EMBEDDED=1 skips it;
#   3. the same suite built with clang, AddressSanitizer and UndefinedBehaviorSanitizer (preset
#      `asan-ubsan`, in <build-dir>-asan; without the allocation, compile-only and compiler-flag tests,
#      MJUKF_SANITIZER_SUBSET in tests/CMakeLists.txt), then the libFuzzer target of that build on the inputs that
#      once failed and a short smoke run (docs/robustness.md records the long run).
# MJUKF_SKIP_SANITIZERS=1 skips step 3.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${1:-build}
jobs=$(nproc)

cmake --preset release -B "$build"
cmake --build "$build" -j "$jobs"
ctest --test-dir "$build" --output-on-failure -j "$jobs"
# ctest ran the format check (format_check) and would report it skipped without clang-format 14; here
# that is an error (setup.sh installed it).
bash scripts/check_format.sh

# The API reference (docs/Doxyfile.in): any doxygen warning, undocumented public API included, fails.
cmake --build "$build" --target mjukf_docs

[ "${MJUKF_SKIP_EMBEDDED:-0}" = 1 ] || bash scripts/embedded.sh "$build"

[ "${MJUKF_SKIP_SANITIZERS:-0}" = 1 ] && exit 0

# Any sanitizer report fails its test: nothing recovers (-fno-sanitize-recover=all), errors abort.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
cmake --preset asan-ubsan -B "$build-asan"
cmake --build "$build-asan" -j "$jobs"
ctest --test-dir "$build-asan" --output-on-failure -j "$jobs"
fuzz="$build-asan"/tests/fuzz/mjukf_fuzz
"$fuzz" tests/fuzz/regressions/*
"$fuzz" -runs=20000 -seed=1 -max_len=1024
