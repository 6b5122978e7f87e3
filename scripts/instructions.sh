#!/usr/bin/env bash
# Instructions per step of every filter and plant, counted by callgrind: deterministic figures that a
# change's cost can be judged by without the noise of a shared machine.
#
#   bash scripts/instructions.sh [build-dir] [out-file]   # default build-bench, table on stdout
#
# Builds mjukf_instruction_counts (bench/instruction_counts.cpp) in the build directory (configured by
# scripts/bench.sh, or here with the same options), runs it under valgrind --tool=callgrind, and
# prints a Markdown table: instructions per measurement step, per open-loop step and per floor step
# (the model propagations a measurement step cannot avoid), for double and float. Takes about a minute.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-bench}
out=${2:-/dev/stdout}
command -v valgrind >/dev/null || { echo "error: valgrind is not installed (Debian: apt-get install valgrind)" >&2; exit 1; }
[ -f "$build/CMakeCache.txt" ] || cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMJUKF_BUILD_EXAMPLES=OFF \
  -DMJUKF_WITH_SUNDIALS=OFF -DMJUKF_BUILD_BENCHMARKS=ON -DMJUKF_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j "$(nproc)" --target mjukf_instruction_counts >/dev/null
dumps=$(mktemp -d)
trap 'rm -rf "$dumps"' EXIT
valgrind --tool=callgrind --collect-atstart=no --callgrind-out-file="$dumps/cg.out" \
  "$build/bench/mjukf_instruction_counts" > "$dumps/cases.txt" 2> "$dumps/valgrind.log" ||
  { cat "$dumps/valgrind.log" >&2; exit 1; }
python3 bench/instruction_report.py "$dumps" "$(git rev-parse --short HEAD 2>/dev/null || echo '?')" > "$out"
