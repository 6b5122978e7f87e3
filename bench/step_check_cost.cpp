// mjukf_step_check_cost: what the step check (step_check.hpp) and the health monitor (health.hpp) cost a
// measurement step. The step is that of the step benchmarks (step_cases.hpp): the tank's UKF with the
// paper's settings, a time update over
// one integrator step (h = 1 ms, I-TR-BDF2) followed by a measurement update, on simulated
// measurements. Four copies of it differ only in `stepCheck` and `health`:
//   default:     the library's defaults (Refuse, tolerance 0.5, a step unchanged is checked every 16
//                calls; the monitor on);
//   every:       the step check with interval = 1, every call checked (the cost when h changes at every call);
//   accept:      OversizedStep::Accept, no check (the filters before the check);
//   unmonitored: the default check with `health.enabled = false`.
// The monitor's cost is default / unmonitored, per repetition.
// Each repetition runs kSteps steps of each copy from the same start, in an order that rotates from one
// repetition to the next, and times each run in thread CPU time; the ratio of a repetition is its
// run's time over the same repetition's `accept` run. Prints the median of the ratios (and their range)
// over the repetitions (argument 1, default 31):
//
//   mjukf_step_check_cost [repetitions]
//
// Built with the benchmarks (scripts/bench.sh builds build-bench/; `cmake --build build-bench --target
// mjukf_step_check_cost`), or alone from the repository's root:
//
//   g++ -std=c++17 -O3 -DNDEBUG -Iinclude -Iexamples/support -Ibench -I/usr/include/eigen3 bench/step_check_cost.cpp

#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "bench_support.hpp"
#include "step_cases.hpp"

namespace mjukf::bench {
namespace {

using Filter = FilterType<FilterKind::Ukf, Tank::Model>;
constexpr long kSteps = 20000;  // one run: 20 s of the schedule's measurement steps

double threadSeconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return double(now.tv_sec) + 1e-9 * double(now.tv_nsec);
}

Filter makeUkf(OversizedStep onOversized, int interval, bool monitored = true) {
  auto settings = Tank::ukf();
  settings.stepCheck.onOversized = onOversized;
  settings.stepCheck.interval = interval;
  settings.health.enabled = monitored;
  return Filter(Tank::Model(), Tank::initialState(), Tank::Model::trueParameters(), settings);
}

// kSteps measurement steps of a copy of `fresh`, in thread CPU seconds; a negative time when one was refused.
double run(const Filter& fresh, double& sink) {
  Filter filter = fresh;
  const auto& y = measurements<Tank>();
  const double h = Tank::stepSize;
  const double start = threadSeconds();
  for (long k = 0; k < kSteps; ++k) {
    Status s = filter.timeUpdate(double(k) * h, h);
    if (s == Status::Ok) s = filter.measurementUpdate(y[static_cast<std::size_t>(k + 1)]);
    if (s != Status::Ok) return -1;
  }
  const double seconds = threadSeconds() - start;
  sink += filter.state()(0);
  return seconds;
}

double median(std::vector<double> xs) {
  std::sort(xs.begin(), xs.end());
  const std::size_t n = xs.size();
  return n % 2 ? xs[n / 2] : (xs[n / 2 - 1] + xs[n / 2]) / 2;
}

}  // namespace
}  // namespace mjukf::bench

int main(int argc, char** argv) {
  using namespace mjukf;
  using namespace mjukf::bench;
  const int repetitions = argc > 1 ? std::atoi(argv[1]) : 31;
  if (repetitions < 1) {
    std::fprintf(stderr, "usage: mjukf_step_check_cost [repetitions >= 1]\n");
    return 64;
  }
  constexpr int kCases = 4, kAccept = 2, kUnmonitored = 3;
  const char* names[kCases] = {"default", "every", "accept", "unmonitored"};
  const Filter fresh[kCases] = {makeUkf(OversizedStep::Refuse, 16), makeUkf(OversizedStep::Refuse, 1),
                                makeUkf(OversizedStep::Accept, 16), makeUkf(OversizedStep::Refuse, 16, false)};
  (void)measurements<Tank>();  // simulated once, outside the timed runs
  double sink = 0;
  for (const Filter& f : fresh) (void)run(f, sink);  // warm-up
  std::vector<double> seconds[kCases], ratios[kCases], monitor;
  for (int r = 0; r < repetitions; ++r) {
    double t[kCases];
    for (int i = 0; i < kCases; ++i) {
      const int c = (r + i) % kCases;
      t[c] = run(fresh[c], sink);
      if (t[c] < 0) {
        std::fprintf(stderr, "the %s filter refused a step\n", names[c]);
        return 1;
      }
    }
    for (int c = 0; c < kCases; ++c) {
      seconds[c].push_back(t[c]);
      ratios[c].push_back(t[c] / t[kAccept]);
    }
    monitor.push_back(t[0] / t[kUnmonitored]);
  }
  std::printf("%d repetitions of %ld measurement steps (tank UKF, h = 1 ms), thread CPU time (checksum %g)\n",
              repetitions, kSteps, sink);
  for (int c = 0; c < kCases; ++c) {
    const auto [low, high] = std::minmax_element(ratios[c].begin(), ratios[c].end());
    std::printf("%-8s median %7.1f ns/step   ratio to accept: median %.4f (range %.4f to %.4f)\n", names[c],
                1e9 * median(seconds[c]) / double(kSteps), median(ratios[c]), *low, *high);
  }
  const auto [low, high] = std::minmax_element(monitor.begin(), monitor.end());
  std::printf("the monitor: default / unmonitored median %.4f (range %.4f to %.4f)\n", median(monitor), *low, *high);
  return 0;
}
