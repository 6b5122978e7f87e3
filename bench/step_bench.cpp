// step/<plant>/<filter>: one measurement step of the paper's schedule, a time update over one
// integrator step followed by a measurement update, on simulated measurements.
// floor/<plant>/<filter>: the model propagations such a step cannot avoid, written out by hand: the
// 2L + 1 I-TR-BDF2 steps of the filter's points (each with the parameters the filter would give it),
// with the input evaluated once per stage time. step/floor is the filter's own overhead.
// open/<plant>/<filter>: one open-loop step of the mean (the schedule's steps between measurements).
// <filter> is ukf, jukf, mjukf (the paper's settings) or dual: the dual UKF with the library's settings
// (Experiment::dualUkf(), PriorParameters ordering), whose floor is its (2n + 1) + (2p + 1) one-step
// propagations: the state filter's 2n + 1 points with θ̂ and the parameter filter's 2p + 1 of x̂, each
// with its θⱼ (docs/design.md).
//
// Counters: points (sigma points per time update; the dual: of both its filters, (2n + 1) + (2p + 1)),
// f_evals and u_evals (model derivative and input evaluations per step, counted on one step of a
// counting copy of the model, outside the timed loop).

#include <string>
#include <type_traits>

#include <benchmark/benchmark.h>

#include "bench_support.hpp"
#include "mjukf/dual_ukf.hpp"

namespace mjukf::bench {
namespace {

constexpr long kRows = 20001;  // 20 s of simulated measurements; the filter starts over after them

template <class Experiment>
const std::vector<typename Experiment::Model::Meas>& measurements() {
  static const auto y = simulatedMeasurements<Experiment>(kRows);
  return y;
}

// A filter the benchmarks time: its name, how to make it on a model (the plant's or a counting copy),
// and the points of its floor. `Count` start points, each with its own parameters.
template <class Experiment, int Count>
struct FloorPoints {
  Eigen::Matrix<double, Experiment::Model::StateDim, Count> start;
  Eigen::Matrix<double, Experiment::Model::ParamDim, Count> theta;
};

// UKF, JUKF, MJUKF with the paper's settings (bench_support.hpp).
template <FilterKind Kind, class Experiment_>
struct PaperFilter {
  using Experiment = Experiment_;
  using Model = typename Experiment::Model;
  static constexpr int points = FilterType<Kind, Model>::SigmaPointCount;
  static const char* name() { return filterName(Kind); }
  template <class M = Model>
  static FilterType<Kind, M> make(const M& model = M()) {
    return makeFilter<Kind, Experiment>(model);
  }
  // Points spread about a state of the simulated run, and per-point parameters about the truth (all
  // the truth for the UKF, whose points share theta).
  static FloorPoints<Experiment, points> floorPoints(const typename Model::State& centre) {
    FloorPoints<Experiment, points> f;
    for (int i = 0; i < points; ++i) {
      f.start.col(i) = centre + Model::State::Constant(0.01 * (i - points / 2));
      f.theta.col(i) = Model::trueParameters() + Model::Param::Constant(Kind == FilterKind::Ukf ? 0.0 : 0.001 * i);
    }
    return f;
  }
};

// The paper's settings moved to another model type with the same dimensions (as rebind in
// bench_support.hpp): the shared settings and the parameter filter's.
template <class To, class From>
DualUkfSettings<To> rebindDual(const DualUkfSettings<From>& s) {
  using Shared = ParameterEstimationSettings<double, From::StateDim, From::MeasDim, From::ParamDim>;
  DualUkfSettings<To> r;
  static_cast<Shared&>(r) = static_cast<const Shared&>(s);
  r.parameterSigmaPoints = s.parameterSigmaPoints;
  r.initialParameterCovariance = s.initialParameterCovariance;
  r.parameterProcessNoise = s.parameterProcessNoise;
  r.parameterObservationNoise = s.parameterObservationNoise;
  r.parameterForgetting = s.parameterForgetting;
  r.ordering = s.ordering;
  return r;
}

// The dual UKF with the library's settings (Experiment::dualUkf()), from the paper's first guess.
template <class Experiment_>
struct DualFilter {
  using Experiment = Experiment_;
  using Model = typename Experiment::Model;
  static constexpr int statePoints = DualUkf<Model>::SigmaPointCount;               // 2n + 1
  static constexpr int parameterPoints = DualUkf<Model>::ParameterSigmaPointCount;  // 2p + 1
  static constexpr int points = statePoints + parameterPoints;
  static const char* name() { return "dual"; }
  template <class M = Model>
  static DualUkf<M> make(const M& model = M()) {
    static_assert(std::is_base_of_v<Model, M>);
    return DualUkf<M>(model, Experiment::initialState(), Experiment::initialParameters(),
                      rebindDual<M>(Experiment::dualUkf()));
  }
  // The state filter's points spread about a state of the simulated run, all with θ̂ (the truth); then
  // the parameter filter's: x̂ (that state) with per-point parameters about the truth.
  static FloorPoints<Experiment, points> floorPoints(const typename Model::State& centre) {
    FloorPoints<Experiment, points> f;
    for (int i = 0; i < statePoints; ++i) {
      f.start.col(i) = centre + Model::State::Constant(0.01 * (i - statePoints / 2));
      f.theta.col(i) = Model::trueParameters();
    }
    for (int j = 0; j < parameterPoints; ++j) {
      f.start.col(statePoints + j) = centre;
      f.theta.col(statePoints + j) = Model::trueParameters() + Model::Param::Constant(0.001 * (j - parameterPoints / 2));
    }
    return f;
  }
};

// MJUKF with both automatic modes (T from the sensitivities, adaptive ξ; docs/tuning-mjukf.md) and
// the paper's other settings. Its floor adds the p propagations of the sensitivities' forward
// differences to the 2n + 1 of the points.
template <class Experiment_>
struct AutomaticMjukfFilter {
  using Experiment = Experiment_;
  using Model = typename Experiment::Model;
  using Paper = PaperFilter<FilterKind::Mjukf, Experiment>;
  static constexpr int points = Paper::points + Model::ParamDim;
  static const char* name() { return "mjukf_auto"; }
  template <class M = Model>
  static ModifiedJointUkf<M> make(const M& model = M()) {
    auto settings = rebind<M>(Experiment::modifiedJointUkf());
    settings.automaticTransformation = true;
    settings.adaptiveScaling = true;
    return ModifiedJointUkf<M>(model, Experiment::initialState(), Experiment::initialParameters(), settings);
  }
  static FloorPoints<Experiment, points> floorPoints(const typename Model::State& centre) {
    const auto paper = Paper::floorPoints(centre);
    FloorPoints<Experiment, points> f;
    f.start.leftCols(Paper::points) = paper.start;
    f.theta.leftCols(Paper::points) = paper.theta;
    for (int r = 0; r < Model::ParamDim; ++r) {  // x̂ + δ Wᵣ with θ₀ + δ eᵣ
      f.start.col(Paper::points + r) = centre + Model::State::Constant(1e-6);
      f.theta.col(Paper::points + r) = paper.theta.col(0) + 1e-6 * Model::Param::Unit(r);
    }
    return f;
  }
};

// Evaluations of the derivative and the input in one measurement step, after a few steps to settle.
template <class Filter>
EvaluationCounts countEvaluations(bool measurementStep) {
  using Experiment = typename Filter::Experiment;
  EvaluationCounts counts;
  Counting<typename Experiment::Model> model;
  model.counts = &counts;
  auto filter = Filter::make(model);
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

template <class Filter>
void setCounters(benchmark::State& state, bool measurementStep) {
  const EvaluationCounts counts = countEvaluations<Filter>(measurementStep);
  state.counters["points"] = Filter::points;
  state.counters["f_evals"] = double(counts.derivative);
  state.counters["u_evals"] = double(counts.input);
}

template <class Filter>
void measurementStep(benchmark::State& state) {
  using Experiment = typename Filter::Experiment;
  const auto& y = measurements<Experiment>();
  const double h = Experiment::stepSize;
  const auto fresh = Filter::make();
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
  setCounters<Filter>(state, true);
}

template <class Filter>
void openLoopStep(benchmark::State& state) {
  using Experiment = typename Filter::Experiment;
  const double h = Experiment::stepSize;
  const auto fresh = Filter::make();
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
  setCounters<Filter>(state, false);
}

template <class Filter>
void floorStep(benchmark::State& state) {
  using Experiment = typename Filter::Experiment;
  using Model = typename Experiment::Model;
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Input = typename Model::Input;
  constexpr int Count = Filter::points;
  const Model model;
  const ITrBdf2<double> integrator;
  const double h = Experiment::stepSize;
  const auto initial = Filter::floorPoints(measurements<Experiment>()[1000]);
  const auto& start = initial.start;
  const auto& theta = initial.theta;
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

template <class Filter>
void registerFilter() {
  const std::string suffix =
      std::string("/") + plantName<typename Filter::Experiment>() + "/" + Filter::name();
  benchmark::RegisterBenchmark(("step" + suffix).c_str(), measurementStep<Filter>);
  benchmark::RegisterBenchmark(("floor" + suffix).c_str(), floorStep<Filter>);
  benchmark::RegisterBenchmark(("open" + suffix).c_str(), openLoopStep<Filter>);
}

template <class Experiment>
void registerPlant() {
  registerFilter<PaperFilter<FilterKind::Ukf, Experiment>>();
  registerFilter<PaperFilter<FilterKind::Jukf, Experiment>>();
  registerFilter<PaperFilter<FilterKind::Mjukf, Experiment>>();
  registerFilter<AutomaticMjukfFilter<Experiment>>();
  registerFilter<DualFilter<Experiment>>();
}

const bool registered = [] {
  registerPlant<Tank>();
  registerPlant<Robot>();
  return true;
}();

}  // namespace
}  // namespace mjukf::bench
