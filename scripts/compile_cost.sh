#!/usr/bin/env bash
# Compile time and peak memory of one translation unit per filter (UKF, JUKF, MJUKF, dual) on the chain
# of masses of the scaling benchmark (bench/chain_model.hpp, p = 4, RK4) at n = 4 and n = 32, and of one
# unit with all four at n = 4 (and, for comparison, each at n = 32 with the kernels written out at every
# size, as before issue 21): g++ -std=c++17 -O2 -c, timed by /usr/bin/time -v (elapsed wall-clock time
# and maximum resident set size; the compiler's CPU time, user + system, is the figure to compare on a
# shared machine, where wall-clock time also counts other processes). Each unit builds its filter on the
# heap and makes one time and one measurement update, so that every per-step function is compiled.
#
#   bash scripts/compile_cost.sh [output-file]    # default build/results/compile_cost.txt
#
# One line per unit: "<filters> n=<n> cpu_seconds=<s> wall_seconds=<s> max_rss_kb=<kb>"; the load
# average before the run is recorded.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/results/compile_cost.txt}
mkdir -p "$(dirname "$out")"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
eigen=$(pkg-config --cflags eigen3 2>/dev/null || echo -I/usr/include/eigen3)

# $1: filters (space-separated: Ukf JointUkf ModifiedJointUkf DualUkf), $2: n
unit() {
  local n=$2
  echo '#include <memory>'
  echo '#include "chain_model.hpp"'
  echo '#include "mjukf/integrators/rk4.hpp"'
  echo "using Model = mjukf::bench::Chain<double, $n, 4>;"
  echo 'using E = mjukf::bench::ChainExperiment<Model>;'
  for filter in $1; do
    case $filter in
      Ukf) settings='E::ukf()' ;;
      JointUkf) settings='E::jointUkf()' ;;
      ModifiedJointUkf) settings='E::modifiedJointUkf(false)' ;;
      DualUkf) settings='E::dualUkf()' ;;
    esac
    cat <<EOF
int step$filter(const Model::Meas& y) {
  auto f = std::make_unique<mjukf::$filter<Model, mjukf::Rk4<double>>>(Model(), E::initialState(),
                                                                       E::initialParameters(), $settings);
  return int(f->timeUpdate(0.0, 1e-3)) + int(f->measurementUpdate(y));
}
EOF
  done
}

# $1: label, $2: filters, $3: n, $4: extra compiler flags (optional)
measure() {
  local source="$work/$1_n$3.cpp"
  unit "$2" "$3" > "$source"
  /usr/bin/time -v g++ -std=c++17 -O2 -DNDEBUG ${4:-} -Iinclude -Ibench $eigen -c "$source" -o "$work/unit.o" \
    2> "$work/time.txt"
  local cpu wall rss
  cpu=$(awk -F': ' '/User time \(seconds\)|System time \(seconds\)/ { s += $2 } END { print s }' "$work/time.txt")
  wall=$(sed -n 's/.*Elapsed (wall clock) time (h:mm:ss or m:ss): //p' "$work/time.txt" |
    awk -F: '{ s = 0; for (i = 1; i <= NF; ++i) s = s * 60 + $i; print s }')
  rss=$(sed -n 's/.*Maximum resident set size (kbytes): //p' "$work/time.txt")
  echo "$1 n=$3 cpu_seconds=$cpu wall_seconds=$wall max_rss_kb=$rss" | tee -a "$out"
}

{
  echo "# g++ $(g++ -dumpfullversion) -O2, commit $(git rev-parse --short HEAD 2>/dev/null || echo '?')"
  echo "# load average before: $(uptime | sed 's/.*load average: //')"
} > "$out"
for n in 4 32; do
  for filter in Ukf JointUkf ModifiedJointUkf DualUkf; do
    measure "$filter" "$filter" "$n"
  done
done
measure all_four "Ukf JointUkf ModifiedJointUkf DualUkf" 4
# The same units at n = 32 with the kernels written out at every size, as before issue 21.
for filter in Ukf JointUkf ModifiedJointUkf DualUkf; do
  measure "${filter}_written_out" "$filter" 32 -DMJUKF_GENERAL_KERNELS_FROM=1000
done
