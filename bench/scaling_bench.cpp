// scaling/<filter>/n<N>/p<P> and scaling_floor/<filter>/n<N>/p<P>: one measurement step (a time update
// over one 1 ms RK4 step, then a measurement update) of each filter on the chain of chain_model.hpp,
// and its floor as step_bench.cpp defines it: the filter's points, one RK4 step each with the parameters
// the filter would give it, with the input evaluated once per stage time (t, t + h/2, t + h). <filter>
// as in step_bench.cpp: ukf (θ fixed at the truth), jukf, mjukf (T and ξ fixed), mjukf_auto (both
// automatic modes), dual. The cases are chain_cases.hpp's, which the instruction counter shares.
// Counters: L, the augmented dimension of the state filter (n + p for the JUKF, n otherwise), and
// points (propagations per time update, as step_cases.hpp counts them).
//
// This file is compiled once per state dimension, MJUKF_CHAIN_STATE_DIM = n (CMake), both p in each, so
// that no translation unit holds all sizes; the filters live on the heap (152–192 KB each at n = 32).

#include <string>

#include <benchmark/benchmark.h>

#include "chain_cases.hpp"

namespace mjukf::bench {
namespace {

template <FilterKind Kind, class Model>
void setChainCounters(benchmark::State& state) {
  state.counters["L"] = Kind == FilterKind::Jukf ? Model::StateDim + Model::ParamDim : Model::StateDim;
  state.counters["points"] = chainPointCount<Kind, Model>();
}

template <FilterKind Kind, class Model>
void chainStep(benchmark::State& state) {
  ChainSteps<Kind, Model> steps;
  for (auto _ : state) {
    if (!steps.once()) {
      state.SkipWithError(("filter refused step " + std::to_string(steps.row())).c_str());
      break;
    }
  }
  benchmark::DoNotOptimize(steps.filter().state().data());
  setChainCounters<Kind, Model>(state);
}

template <FilterKind Kind, class Model>
void chainFloor(benchmark::State& state) {
  ChainFloorSteps<Kind, Model> steps;
  for (auto _ : state) {
    steps.once();
    benchmark::DoNotOptimize(steps.points().data());
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
