#!/usr/bin/env bash
# Sets up, builds and runs every test: bash scripts/test.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${1:-build}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMJUKF_BUILD_TESTS=ON -DMJUKF_BUILD_EXAMPLES=ON \
  -DMJUKF_BUILD_BENCHMARKS=ON -DMJUKF_WITH_SUNDIALS=ON
cmake --build "$build" -j "$(nproc)"
ctest --test-dir "$build" --output-on-failure -j "$(nproc)"
