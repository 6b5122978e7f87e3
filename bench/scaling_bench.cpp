// scaling/<filter>/n<N>/p<P> and scaling_floor/<filter>/n<N>/p<P>: one measurement step (a time update
// over one 1 ms RK4 step, then a measurement update) of each filter on the chain of chain_model.hpp,
// and its floor as step_bench.cpp defines it: the filter's points, one RK4 step each with the parameters
// the filter would give it, with the input evaluated once per stage time (t, t + h/2, t + h). <filter>
// as in step_bench.cpp: ukf (θ fixed at the truth), jukf, mjukf (T and ξ fixed), mjukf_auto (both
// automatic modes), dual. Counters: L, the augmented dimension of the state filter (n + p for the
// JUKF, n otherwise), and points (propagations per time update, as step_cases.hpp counts them).
//
// This file is compiled once per state dimension, MJUKF_CHAIN_STATE_DIM = n (CMake), both p in each, so
// that no translation unit holds all sizes; the filters live on the heap (152–192 KB each at n = 32).

#include <memory>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "bench_support.hpp"
#include "chain_model.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/simulation.hpp"

namespace mjukf::bench {
namespace {

constexpr long kChainRows = 5001;  // 5 s of measurements; a case starts over after them

template <FilterKind Kind, class Model>
using ChainFilter = std::conditional_t<
    Kind == FilterKind::Ukf, Ukf<Model, Rk4<typename Model::Scalar>>,
    std::conditional_t<Kind == FilterKind::Jukf, JointUkf<Model, Rk4<typename Model::Scalar>>,
                       std::conditional_t<Kind == FilterKind::Dual, DualUkf<Model, Rk4<typename Model::Scalar>>,
                                          ModifiedJointUkf<Model, Rk4<typename Model::Scalar>>>>>;

template <FilterKind Kind, class Model>
std::unique_ptr<ChainFilter<Kind, Model>> makeChainFilter() {
  using E = ChainExperiment<Model>;
  using Filter = ChainFilter<Kind, Model>;
  const Model model;
  if constexpr (Kind == FilterKind::Ukf)
    return std::make_unique<Filter>(model, E::initialState(), Model::trueParameters(), E::ukf());
  else if constexpr (Kind == FilterKind::Jukf)
    return std::make_unique<Filter>(model, E::initialState(), E::initialParameters(), E::jointUkf());
  else if constexpr (Kind == FilterKind::Dual)
    return std::make_unique<Filter>(model, E::initialState(), E::initialParameters(), E::dualUkf());
  else
    return std::make_unique<Filter>(model, E::initialState(), E::initialParameters(),
                                    E::modifiedJointUkf(Kind == FilterKind::MjukfAuto));
}

// y_k = x(k h) + v_k with the true parameters, RK4 from rest; v_k Gaussian with R's variance.
template <class Model>
const std::vector<typename Model::Meas>& chainMeasurements() {
  static const auto y = [] {
    using Scalar = typename Model::Scalar;
    const Model model;
    const auto theta = Model::trueParameters();
    std::mt19937_64 rng(2024);
    std::normal_distribution<double> normal(0.0, 1e-2);
    std::vector<typename Model::Meas> rows(static_cast<std::size_t>(kChainRows));
    simulate(model, Rk4<Scalar>(), Model::State::Zero().eval(), theta, Scalar(0), ChainExperiment<Model>::stepSize,
             kChainRows - 1, [&](long k, Scalar, const typename Model::State& x) {
               auto& row = rows[static_cast<std::size_t>(k)];
               row = model.measurement(x, theta);
               for (int c = 0; c < row.size(); ++c) row(c) += Scalar(normal(rng));
             });
    return rows;
  }();
  return y;
}

template <FilterKind Kind, class Model>
constexpr int chainPointCount() {
  using F = ChainFilter<Kind, Model>;
  if constexpr (Kind == FilterKind::Dual)
    return F::SigmaPointCount + F::ParameterSigmaPointCount;
  else if constexpr (Kind == FilterKind::MjukfAuto)
    return F::SigmaPointCount + Model::ParamDim;
  else
    return F::SigmaPointCount;
}

template <FilterKind Kind, class Model>
void setChainCounters(benchmark::State& state) {
  state.counters["L"] = Kind == FilterKind::Jukf ? Model::StateDim + Model::ParamDim : Model::StateDim;
  state.counters["points"] = chainPointCount<Kind, Model>();
}

template <FilterKind Kind, class Model>
void chainStep(benchmark::State& state) {
  using Scalar = typename Model::Scalar;
  const auto fresh = makeChainFilter<Kind, Model>();
  auto filter = makeChainFilter<Kind, Model>();
  const auto& y = chainMeasurements<Model>();
  const Scalar h = ChainExperiment<Model>::stepSize;
  long k = 0;
  for (auto _ : state) {
    if (k + 1 == kChainRows) {
      *filter = *fresh;
      k = 0;
    }
    Status s = filter->timeUpdate(Scalar(k) * h, h);
    if (s == Status::Ok) s = filter->measurementUpdate(y[static_cast<std::size_t>(k + 1)]);
    ++k;
    if (s != Status::Ok) {
      state.SkipWithError(("filter refused step " + std::to_string(k)).c_str());
      break;
    }
  }
  benchmark::DoNotOptimize(filter->state().data());
  setChainCounters<Kind, Model>(state);
}

// The floor: as step_cases.hpp's FloorSteps, with RK4 (stage times t, t + h/2, t + h) and the chain's
// points spread the same way about a state of the simulated run.
template <FilterKind Kind, class Model>
void chainFloor(benchmark::State& state) {
  using Scalar = typename Model::Scalar;
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Input = typename Model::Input;
  constexpr int Count = chainPointCount<Kind, Model>();
  constexpr int statePoints = ChainFilter<Kind, Model>::SigmaPointCount;
  const Model model;
  const Rk4<Scalar> integrator;
  auto start = std::make_unique<Eigen::Matrix<Scalar, Model::StateDim, Count>>();
  auto points = std::make_unique<Eigen::Matrix<Scalar, Model::StateDim, Count>>();
  auto thetas = std::make_unique<Eigen::Matrix<Scalar, Model::ParamDim, Count>>();
  State centre = State::Zero();
  centre.template head<Model::MeasDim>() = chainMeasurements<Model>()[1000];
  const Param truth = Model::trueParameters();
  const Scalar step = Scalar(0.01), thetaStep = Kind == FilterKind::Ukf ? Scalar(0) : Scalar(0.001);
  for (int i = 0; i < Count; ++i) {
    const bool extra = i >= statePoints;  // the dual's parameter points, the automatic MJUKF's differences
    start->col(i) = extra ? centre : State(centre + State::Constant(step * Scalar(i - statePoints / 2)));
    thetas->col(i) = truth + Param::Constant(thetaStep * Scalar(extra ? i - statePoints : i));
  }
  *points = *start;
  const Scalar h = ChainExperiment<Model>::stepSize;
  long k = 0;
  for (auto _ : state) {
    if (k + 1 == kChainRows) {
      *points = *start;
      k = 0;
    }
    const Scalar t = Scalar(k) * h, tEnd = t + h;
    const Input u0 = model.input(t), uHalf = model.input(t + h / Scalar(2)), u1 = model.input(tEnd);
    for (int i = 0; i < Count; ++i) {
      const Param theta = thetas->col(i);
      const auto f = [&](Scalar time, const State& x) -> State {
        return model.derivative(time, x, time <= t ? u0 : (time >= tEnd ? u1 : uHalf), theta);
      };
      points->col(i) = integrator.step(f, t, State(points->col(i)), h);
    }
    ++k;
    benchmark::DoNotOptimize(points->data());
    benchmark::ClobberMemory();
  }
  setChainCounters<Kind, Model>(state);
}

template <FilterKind Kind, class Model>
void registerChainFilter() {
  const std::string suffix = std::string("/") + filterName(Kind) + "/n" + std::to_string(Model::StateDim) + "/p" +
                             std::to_string(Model::ParamDim);
  benchmark::RegisterBenchmark(("scaling" + suffix).c_str(), chainStep<Kind, Model>);
  benchmark::RegisterBenchmark(("scaling_floor" + suffix).c_str(), chainFloor<Kind, Model>);
}

template <class Model>
void registerChain() {
  registerChainFilter<FilterKind::Ukf, Model>();
  registerChainFilter<FilterKind::Jukf, Model>();
  registerChainFilter<FilterKind::Mjukf, Model>();
  registerChainFilter<FilterKind::MjukfAuto, Model>();
  registerChainFilter<FilterKind::Dual, Model>();
}

const bool registered = [] {
  registerChain<Chain<double, MJUKF_CHAIN_STATE_DIM, 1>>();
  registerChain<Chain<double, MJUKF_CHAIN_STATE_DIM, 4>>();
  return true;
}();

}  // namespace
}  // namespace mjukf::bench
