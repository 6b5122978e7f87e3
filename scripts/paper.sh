#!/usr/bin/env bash
# The main job: sets up, builds in Release and reproduces the paper's Tables 3 and 4 and its figures
# with JUKF and MJUKF on both plants, then identifies a real plant from its recorded data (the Cascaded
# Tanks benchmark).  bash scripts/paper.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
build=${1:-build}
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMJUKF_BUILD_EXAMPLES=ON
cmake --build "$build" -j "$(nproc)" --target mjukf_coupled_tank mjukf_flexible_joint mjukf_cascaded_tanks
out="$build/paper"
tank="$build/examples/mjukf_coupled_tank"
robot="$build/examples/mjukf_flexible_joint"

echo; echo "=== 1. Fresh simulations, as in the paper ==="; echo
"$tank" paper --out-dir "$out/coupled_tank"
echo
"$robot" paper --out-dir "$out/flexible_joint"

# The same on the reference scripts' measurement files: the RMSEs must equal the conformance numbers.
echo; echo "=== 2. The reference measurement files (conformance) ==="; echo
"$tank" paper --data "$build/data/coupled_tank_reference.csv" --out-dir "$out/coupled_tank_reference"
echo
"$robot" paper --data "$build/data/flexible_joint_reference.csv" \
  --change-data "$build/data/flexible_joint_param_change_reference.csv" --out-dir "$out/flexible_joint_reference"

# A real plant: the Cascaded Tanks benchmark's recorded data (docs/real-data.md).
echo; echo "=== 3. A real plant: the Cascaded Tanks benchmark ==="; echo
"$build/examples/mjukf_cascaded_tanks" identify --data tests/data/cascaded_tanks/dataBenchmark.csv \
  --out-dir "$out/cascaded_tanks"
# The same rule with the two records swapped: scored on the record it did not identify on.
echo
"$build/examples/mjukf_cascaded_tanks" crosscheck --data tests/data/cascaded_tanks/dataBenchmark.csv \
  --out-dir "$out/cascaded_tanks"

echo
echo "Tables (*_table.txt), CSV files and PNG plots are in $out/:"
echo "  fresh simulations:  $out/coupled_tank/  $out/flexible_joint/"
echo "  reference files:    $out/coupled_tank_reference/  $out/flexible_joint_reference/"
echo "  cascaded tanks:     $out/cascaded_tanks/ (results.txt, test_simulation.csv and .png, crosscheck.txt)"
echo "What the numbers mean and why they differ from the paper: docs/reproducing-the-paper.md"
