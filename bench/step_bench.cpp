// step/<plant>/<filter>: one measurement step of the paper's schedule, a time update over one
// integrator step followed by a measurement update, on simulated measurements.
// floor/<plant>/<filter>: the model propagations such a step cannot avoid, written out by hand: the
// 2L + 1 I-TR-BDF2 steps of the filter's points (each with the parameters the filter would give it),
// with the input evaluated once per stage time. step/floor is the filter's own overhead.
// open/<plant>/<filter>: one open-loop step of the mean (the schedule's steps between measurements).
//
// Counters: points (sigma points per time update), f_evals and u_evals (model derivative and input
// evaluations per step, counted on one step of a counting copy of the model, outside the timed loop).

#include <string>

#include <benchmark/benchmark.h>

#include "bench_support.hpp"

namespace mjukf::bench {
namespace {

constexpr long kRows = 20001;  // 20 s of simulated measurements; the filter starts over after them

template <class Experiment>
const std::vector<typename Experiment::Model::Meas>& measurements() {
  static const auto y = simulatedMeasurements<Experiment>(kRows);
  return y;
}

// Evaluations of the derivative and the input in one measurement step, after a few steps to settle.
template <FilterKind Kind, class Experiment>
EvaluationCounts countEvaluations(bool measurementStep) {
  EvaluationCounts counts;
  Counting<typename Experiment::Model> model;
  model.counts = &counts;
  auto filter = makeFilter<Kind, Experiment>(model);
  const auto& y = measurements<Experiment>();
  const double h = Experiment::stepSize;
  for (long k = 0; k < 10; ++k) {
    (void)filter.timeUpdate(double(k) * h, h);
    (void)filter.measurementUpdate(y[static_cast<std::size_t>(k + 1)]);
  }
  counts = {};
  if (measurementStep) {
    (void)filter.timeUpdate(10 * h, h);
    (void)filter.measurementUpdate(y[11]);
  } else {
    (void)filter.propagateMean(10 * h, h);
  }
  return counts;
}

template <FilterKind Kind, class Experiment>
void setCounters(benchmark::State& state, bool measurementStep) {
  const EvaluationCounts counts = countEvaluations<Kind, Experiment>(measurementStep);
  state.counters["points"] = FilterType<Kind, typename Experiment::Model>::SigmaPointCount;
  state.counters["f_evals"] = double(counts.derivative);
  state.counters["u_evals"] = double(counts.input);
}

template <FilterKind Kind, class Experiment>
void measurementStep(benchmark::State& state) {
  const auto& y = measurements<Experiment>();
  const double h = Experiment::stepSize;
  const auto fresh = makeFilter<Kind, Experiment>();
  auto filter = fresh;
  long k = 0;
  for (auto _ : state) {
    if (k + 1 == kRows) {
      filter = fresh;
      k = 0;
    }
    Status s = filter.timeUpdate(double(k) * h, h);
    if (s == Status::Ok) s = filter.measurementUpdate(y[static_cast<std::size_t>(k + 1)]);
    if (s != Status::Ok) {
      state.SkipWithError(("filter refused step " + std::to_string(k)).c_str());
      break;
    }
    ++k;
  }
  benchmark::DoNotOptimize(filter.state().data());
  setCounters<Kind, Experiment>(state, true);
}

template <FilterKind Kind, class Experiment>
void openLoopStep(benchmark::State& state) {
  const double h = Experiment::stepSize;
  const auto fresh = makeFilter<Kind, Experiment>();
  auto filter = fresh;
  long k = 0;
  for (auto _ : state) {
    if (k + 1 == kRows) {
      filter = fresh;
      k = 0;
    }
    if (filter.propagateMean(double(k) * h, h) != Status::Ok) {
      state.SkipWithError("open-loop step refused");
      break;
    }
    ++k;
  }
  benchmark::DoNotOptimize(filter.state().data());
  setCounters<Kind, Experiment>(state, false);
}

template <FilterKind Kind, class Experiment>
void floorStep(benchmark::State& state) {
  using Model = typename Experiment::Model;
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Input = typename Model::Input;
  constexpr int Count = FilterType<Kind, Model>::SigmaPointCount;
  const Model model;
  const ITrBdf2<double> integrator;
  const double h = Experiment::stepSize;
  // Points spread about a state of the simulated run, and per-point parameters about the truth (all
  // the truth for the UKF, whose points share theta).
  const State centre = measurements<Experiment>()[1000];
  Eigen::Matrix<double, Model::StateDim, Count> start;
  Eigen::Matrix<double, Model::ParamDim, Count> theta;
  for (int i = 0; i < Count; ++i) {
    start.col(i) = centre + State::Constant(0.01 * (i - Count / 2));
    theta.col(i) = Model::trueParameters() + Param::Constant(Kind == FilterKind::Ukf ? 0.0 : 0.001 * i);
  }
  auto points = start;
  long k = 0;
  int evaluations = 0;
  for (auto _ : state) {
    if (k + 1 == kRows) {
      points = start;
      k = 0;
    }
    const double t = double(k) * h;
    const double tEnd = t + h;
    // The input at the three stage times of I-TR-BDF2, once for all points.
    const Input u0 = model.input(t), uGamma = model.input(t + integrator.gamma() * h), u1 = model.input(tEnd);
    for (int i = 0; i < Count; ++i) {
      const Param th = theta.col(i);
      const auto f = [&](double time, const State& x) -> State {
        return model.derivative(time, x, time <= t ? u0 : (time >= tEnd ? u1 : uGamma), th);
      };
      points.col(i) = integrator.step(f, t, State(points.col(i)), h);
    }
    benchmark::DoNotOptimize(points.data());
    benchmark::ClobberMemory();
    ++k;
    evaluations = 3;
  }
  state.counters["points"] = Count;
  state.counters["f_evals"] = double(Count * ITrBdf2<double>::evaluationsPerStep);
  state.counters["u_evals"] = double(evaluations);
}

template <FilterKind Kind, class Experiment>
void registerFilter() {
  const std::string suffix = std::string("/") + plantName<Experiment>() + "/" + filterName(Kind);
  benchmark::RegisterBenchmark(("step" + suffix).c_str(), measurementStep<Kind, Experiment>);
  benchmark::RegisterBenchmark(("floor" + suffix).c_str(), floorStep<Kind, Experiment>);
  benchmark::RegisterBenchmark(("open" + suffix).c_str(), openLoopStep<Kind, Experiment>);
}

template <class Experiment>
void registerPlant() {
  registerFilter<FilterKind::Ukf, Experiment>();
  registerFilter<FilterKind::Jukf, Experiment>();
  registerFilter<FilterKind::Mjukf, Experiment>();
}

const bool registered = [] {
  registerPlant<Tank>();
  registerPlant<Robot>();
  return true;
}();

}  // namespace
}  // namespace mjukf::bench
