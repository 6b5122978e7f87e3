#!/usr/bin/env bash
# Builds mjukf_bench in Release (plain, and with -march=native in a second build directory), runs every
# benchmark as the median of 5 repetitions, counts instructions per step under callgrind
# (scripts/instructions.sh), times 5 whole `estimate` processes per plant as a user runs them (cold
# runs), keeps the JSON and writes docs/performance.md.
#
#   bash scripts/bench.sh                 # both builds, about 10 minutes on the 2-core machine
#   bash scripts/bench.sh --plain-only    # skip the -march=native build
#   MJUKF_BENCH_FILTER='^(step|floor)/' bash scripts/bench.sh   # a subset (the report shows what ran)
#
# JSON goes to build-bench/results/{plain,native}.json. Timing is noisy on a shared machine: the
# report records the load average before each run; re-run when it is high.
set -euo pipefail
cd "$(dirname "$0")/.."

native=1
[[ "${1:-}" == "--plain-only" ]] && native=0
filter=${MJUKF_BENCH_FILTER:-.}
results=build-bench/results
mkdir -p "$results"
git rev-parse --short HEAD > "$results/commit" 2>/dev/null || echo "?" > "$results/commit"

common=(-DCMAKE_BUILD_TYPE=Release -DMJUKF_WITH_SUNDIALS=OFF -DMJUKF_BUILD_BENCHMARKS=ON)

run() {  # run <build-dir> <name>
  local dir=$1 name=$2
  cmake --build "$dir" -j "$(nproc)" --target mjukf_bench
  uptime | sed 's/.*load average: //' > "$results/$name.load"
  "$dir/bench/mjukf_bench" --benchmark_filter="$filter" --benchmark_repetitions=5 \
    --benchmark_report_aggregates_only=true \
    --benchmark_out="$results/$name.json" --benchmark_out_format=json
}

cmake -S . -B build-bench "${common[@]}" -DMJUKF_BUILD_EXAMPLES=ON -DMJUKF_BENCH_NATIVE=OFF
run build-bench plain

# Cold runs: one `estimate` process each, as a user times it (its loop_seconds), 5 processes per plant.
cmake --build build-bench -j "$(nproc)" --target mjukf_flexible_joint mjukf_coupled_tank
: > "$results/cold.txt"
for plant in flexible_joint coupled_tank; do
  for i in 1 2 3 4 5; do
    seconds=$("build-bench/examples/mjukf_$plant" estimate --filter mjukf --data "build-bench/data/${plant}_reference.csv" \
      --out "$results/cold_$plant.csv" | sed -n 's/^loop_seconds: //p')
    echo "$plant mjukf $seconds" >> "$results/cold.txt"
  done
done

# Instructions per step (deterministic).
bash scripts/instructions.sh build-bench "$results/instructions.txt"
if [[ $native == 1 ]]; then
  cmake -S . -B build-bench-native "${common[@]}" -DMJUKF_BUILD_EXAMPLES=OFF -DMJUKF_BUILD_TESTS=OFF -DMJUKF_BENCH_NATIVE=ON
  run build-bench-native native
fi

python3 bench/report.py "$results" docs/performance.md
echo "wrote docs/performance.md"
