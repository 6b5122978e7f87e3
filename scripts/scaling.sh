#!/usr/bin/env bash
# The scaling page, docs/performance-scaling.md: builds the chain benchmark twice in Release (the kernels
# chosen by size, and the written-out kernels at every size for comparison), runs both one after the
# other as medians of 5 repetitions, optionally the kernel micro-benchmark behind the thresholds and the
# compile-cost measurement, and writes the page with bench/scaling_report.py. Kept apart from
# scripts/bench.sh (docs/performance.md), whose full run is about 10 minutes with two builds of its own.
#
#   bash scripts/scaling.sh [build-dir]               # default build-bench; about 10 minutes of builds
#   MJUKF_SCALING_KERNELS=1 bash scripts/scaling.sh   # also mjukf_kernel_bench (about 20 minutes to build;
#                                                     # the page's products at L = 8 … 36 run in about 20)
#   MJUKF_SCALING_KERNEL_FILTER=. …                   # every kernel and size it has (about 70 minutes)
#   MJUKF_SCALING_COMPILE=1 bash scripts/scaling.sh   # also scripts/compile_cost.sh (about 3 minutes)
#   MJUKF_SCALING_SKIP_BUILD=1 …                     # run what <build-dir> holds, as built
#   MJUKF_SCALING_MIN_TIME=0.2 bash scripts/scaling.sh # Google Benchmark's time per repetition (default 0.5 s)
#
# JSON goes to <build-dir>/results/. Results already there from an earlier run (kernels.json,
# compile_cost.txt) are reported again when not re-measured; without them (a fresh build directory),
# the kernels' and the compile time's sections of the page it replaces are kept as they were, each
# with its own commit.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-bench}
results=$build/results
mkdir -p "$results"
git rev-parse --short HEAD > "$results/commit" 2>/dev/null || echo "?" > "$results/commit"
jobs=$(nproc)

if [[ ${MJUKF_SCALING_SKIP_BUILD:-0} != 1 ]]; then
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMJUKF_WITH_SUNDIALS=OFF -DMJUKF_BUILD_BENCHMARKS=ON >/dev/null
  targets=(mjukf_scaling_bench mjukf_scaling_bench_coefficientwise)
  [[ ${MJUKF_SCALING_KERNELS:-0} == 1 ]] && targets+=(mjukf_kernel_bench)
  cmake --build "$build" -j "$jobs" --target "${targets[@]}"
fi

# The repetitions in random order across all cases (Google Benchmark's random interleaving), so that a
# burst of load on the shared machine spreads over the cases instead of falling on a few neighbours (a
# step measured under it and its floor not).
echo "\`--benchmark_repetitions=5 --benchmark_enable_random_interleaving=true --benchmark_min_time=${MJUKF_SCALING_MIN_TIME:-0.5}\`" > "$results/scaling.options"
run() {  # run <program> <name>
  uptime | sed 's/.*load average: //' > "$results/$2.load"
  "$build/bench/$1" --benchmark_repetitions=5 --benchmark_enable_random_interleaving=true \
    --benchmark_report_aggregates_only=true --benchmark_min_time="${MJUKF_SCALING_MIN_TIME:-0.5}" \
    --benchmark_out="$results/$2.json" --benchmark_out_format=json "${@:3}"
}
run mjukf_scaling_bench scaling
run mjukf_scaling_bench_coefficientwise scaling_coefficientwise
if [[ ${MJUKF_SCALING_KERNELS:-0} == 1 ]]; then
  # The products the page tabulates, at the sizes around and above the thresholds; the kernel run's
  # commit is kept apart, since a later run of the chain benchmark alone leaves kernels.json as it is.
  run mjukf_kernel_bench kernels --benchmark_filter="${MJUKF_SCALING_KERNEL_FILTER:-^kernel/(covariance|cross|subtract)/[a-z_]+/(double|float)/(8|9|11|12|14|16|20|24|28|32|36)\$}"
  cp "$results/commit" "$results/kernels.commit"
fi
if [[ ${MJUKF_SCALING_COMPILE:-0} == 1 ]]; then bash scripts/compile_cost.sh "$results/compile_cost.txt"; fi

python3 bench/scaling_report.py "$results" docs/performance-scaling.md
echo "wrote docs/performance-scaling.md"
