// step/<plant>/<filter>[/float]: one measurement step of the paper's schedule (step_cases.hpp), a time
// update over one integrator step followed by a measurement update, on simulated measurements.
// floor/<plant>/<filter>[/float]: the model propagations such a step cannot avoid, written out by
// hand: the filter's points, one I-TR-BDF2 step each (each with the parameters the filter would give
// it), with the input evaluated once per stage time. step/floor is the filter's own overhead.
// open/<plant>/<filter>[/float]: one open-loop step of the mean (the schedule's steps between
// measurements).
// <filter> is ukf, jukf, mjukf (the paper's settings) or dual: the dual UKF with the library's settings
// (Experiment::dualUkf(), PriorParameters ordering), whose floor is its (2n + 1) + (2p + 1) one-step
// propagations: the state filter's 2n + 1 points with θ̂ and the parameter filter's 2p + 1 of x̂, each
// with its θⱼ (docs/design.md). Names without a suffix are double; /float the same in float.
// step/<plant>/<filter>_sr[/float]: the same step with the filter in the square-root covariance form
// (covariance_form.hpp; its floor and open-loop step are the full form's, which the report reuses).
//
// Counters: points (sigma points per time update; the dual: of both its filters, (2n + 1) + (2p + 1)),
// f_evals and u_evals (model derivative and input evaluations per step, counted on one step of a
// counting copy of the model, outside the timed loop).

#include <string>

#include <benchmark/benchmark.h>

#include "bench_support.hpp"
#include "step_cases.hpp"

namespace mjukf::bench {
namespace {

template <FilterKind Kind, class Experiment>
void setCounters(benchmark::State& state, bool measurementStep) {
  const EvaluationCounts counts = countEvaluations<Kind, Experiment>(measurementStep);
  state.counters["points"] = pointCount<Kind, typename Experiment::Model>();
  state.counters["f_evals"] = double(counts.derivative);
  state.counters["u_evals"] = double(counts.input);
}

template <FilterKind Kind, class Experiment, class Form = FullCovariance>
void measurementStep(benchmark::State& state) {
  MeasurementSteps<Kind, Experiment, Form> steps;
  for (auto _ : state) {
    if (!steps.once()) {
      state.SkipWithError(("filter refused step " + std::to_string(steps.row())).c_str());
      break;
    }
  }
  benchmark::DoNotOptimize(steps.filter().state().data());
  setCounters<Kind, Experiment>(state, true);
}

template <FilterKind Kind, class Experiment>
void openLoopStep(benchmark::State& state) {
  OpenLoopSteps<Kind, Experiment> steps;
  for (auto _ : state) {
    if (!steps.once()) {
      state.SkipWithError("open-loop step refused");
      break;
    }
  }
  benchmark::DoNotOptimize(steps.filter().state().data());
  setCounters<Kind, Experiment>(state, false);
}

template <FilterKind Kind, class Experiment>
void floorStep(benchmark::State& state) {
  FloorSteps<Kind, Experiment> steps;
  for (auto _ : state) {
    steps.once();
    benchmark::DoNotOptimize(steps.points().data());
    benchmark::ClobberMemory();
  }
  constexpr int count = pointCount<Kind, typename Experiment::Model>();
  state.counters["points"] = count;
  state.counters["f_evals"] = double(count * ITrBdf2<double>::evaluationsPerStep);
  state.counters["u_evals"] = 3;
}

template <FilterKind Kind, class Experiment>
void registerFilter() {
  using Scalar = typename Experiment::Model::Scalar;
  const std::string suffix = std::string("/") + plantName<Experiment>() + "/" + filterName(Kind) +
                             (std::is_same_v<Scalar, float> ? "/float" : "");
  benchmark::RegisterBenchmark(("step" + suffix).c_str(), measurementStep<Kind, Experiment>);
  benchmark::RegisterBenchmark(("floor" + suffix).c_str(), floorStep<Kind, Experiment>);
  benchmark::RegisterBenchmark(("open" + suffix).c_str(), openLoopStep<Kind, Experiment>);
  const std::string squareRoot = std::string("/") + plantName<Experiment>() + "/" + filterName(Kind) + "_sr" +
                                 (std::is_same_v<Scalar, float> ? "/float" : "");
  benchmark::RegisterBenchmark(("step" + squareRoot).c_str(), measurementStep<Kind, Experiment, SquareRootCovariance>);
}

template <class Experiment>
void registerPlant() {
  registerFilter<FilterKind::Ukf, Experiment>();
  registerFilter<FilterKind::Jukf, Experiment>();
  registerFilter<FilterKind::Mjukf, Experiment>();
  registerFilter<FilterKind::MjukfAuto, Experiment>();
  registerFilter<FilterKind::Dual, Experiment>();
}

const bool registered = [] {
  registerPlant<TankOf<double>>();
  registerPlant<RobotOf<double>>();
  registerPlant<TankOf<float>>();
  registerPlant<RobotOf<float>>();
  return true;
}();

}  // namespace
}  // namespace mjukf::bench
