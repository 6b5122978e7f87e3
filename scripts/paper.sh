#!/usr/bin/env bash
# Sets up, builds in Release and runs the main job: JUKF and MJUKF on both plants, as in the paper.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${1:-build}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release
cmake --build "$build" -j "$(nproc)" --target conformance_test
# Until the example programs exist, the main job is the conformance run on the reference data.
"$build/tests/conformance_test" --gtest_brief=1
