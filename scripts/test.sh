#!/usr/bin/env bash
# Sets up, builds and runs the tests: bash scripts/test.sh [--all] [build-dir]
#
# Without --all (what CI runs, within its time): the quick test tier (MJUKF_TEST_TIER=quick,
# tests/CMakeLists.txt lists it and what it leaves out), in build-quick/ unless a build-dir is given:
#   1. Release build of the library, the quick tier, the paper's two example programs and the firmware's
#      host program with g++ (CMake preset `quick`), and their tests under ctest (the format check of the
#      C++ sources, scripts/check_format.sh, included), then the API reference (target mjukf_docs,
#      doxygen warnings as errors);
#   2. the firmware example built for a Cortex-M4F and run under QEMU, its estimates compared with the
#      host's (scripts/embedded.sh, docs/embedded.md); MJUKF_SKIP_EMBEDDED=1 skips it;
#   3. clang with AddressSanitizer and UndefinedBehaviorSanitizer (preset `asan-ubsan`, in
#      <build-dir>-asan): the libFuzzer target on the inputs that once failed and a short smoke run,
#      and the CSV reader's and the engine's tests.
# With --all: every test (preset `release`, with the benchmarks, in build/), the firmware, and then
# the whole suite again under the sanitizers (without the allocation, compile-only and compiler-flag
# tests, MJUKF_SANITIZER_SUBSET in tests/CMakeLists.txt) before the fuzz runs: well over an hour on 2
# cores (README).
# MJUKF_SKIP_SANITIZERS=1 skips step 3.
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: bash scripts/test.sh [--all] [build-dir]"
tier=quick
build=
for arg in "$@"; do
  case $arg in
    --all) tier=all ;;
    -*) echo "error: unknown option $arg; $usage" >&2; exit 2 ;;
    *)
      [ -z "$build" ] || { echo "error: more than one build directory; $usage" >&2; exit 2; }
      build=$arg
      ;;
  esac
done
bash scripts/setup.sh
jobs=$(nproc)
if [ "$tier" = all ]; then
  preset=release
  build=${build:-build}
else
  preset=quick
  build=${build:-build-quick}
fi

cmake --preset "$preset" -B "$build"
cmake --build "$build" -j "$jobs"
# ctest runs the format check (format_check), which would report itself skipped without clang-format 14;
# here that is an error (setup.sh installed it), so the check fails instead.
MJUKF_REQUIRE_CLANG_FORMAT=1 ctest --test-dir "$build" --output-on-failure -j "$jobs"

# The API reference (docs/Doxyfile.in): any doxygen warning, undocumented public API included, fails.
cmake --build "$build" --target mjukf_docs

[ "${MJUKF_SKIP_EMBEDDED:-0}" = 1 ] || bash scripts/embedded.sh "$build"

[ "${MJUKF_SKIP_SANITIZERS:-0}" = 1 ] && exit 0

# Any sanitizer report fails its test: nothing recovers (-fno-sanitize-recover=all), errors abort.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
if [ "$tier" = all ]; then
  cmake --preset asan-ubsan -B "$build-asan"
  cmake --build "$build-asan" -j "$jobs"
  ctest --test-dir "$build-asan" --output-on-failure -j "$jobs"
else
  cmake --preset asan-ubsan -B "$build-asan" -DMJUKF_TEST_TIER=quick -DMJUKF_BUILD_EXAMPLES=OFF
  cmake --build "$build-asan" -j "$jobs" --target mjukf_sanitizer_stage  # the fuzz target and the two tests
  "$build-asan"/tests/csv_reader_test
  "$build-asan"/tests/detail/engine_test
fi
fuzz="$build-asan"/tests/fuzz/mjukf_fuzz
"$fuzz" tests/fuzz/regressions/*
"$fuzz" -runs=20000 -seed=1 -max_len=1024
