// run/<plant>/<filter>: a whole paper run over the reference measurement file (tank 200 s, robot 20 s,
// h = 1 ms) with the paper's schedule (docs/algorithms.md §7), accumulating the RMSE of the parameters as
// the conformance test does. The file is read once, outside the timed loop. Counters: rmse_theta1
// (and rmse_theta2 on the robot), to show the timed runs are the conformance runs. <filter> is ukf,
// jukf, mjukf (the paper's settings) or dual: the dual UKF with the library's settings
// (Experiment::dualUkf(), PriorParameters ordering), the run of `estimate --filter dual`.

#include <string>
#include <type_traits>

#include <benchmark/benchmark.h>

#include "bench_support.hpp"
#include "common/csv.hpp"
#include "paper/rmse.hpp"
#include "paper/schedule.hpp"

namespace mjukf::bench {
namespace {

template <class Experiment>
const char* referenceFile() {
  return std::is_same_v<Experiment, Tank> ? "coupled_tank_reference.csv" : "flexible_joint_reference.csv";
}

template <class Experiment>
const std::vector<typename Experiment::Model::Meas>& referenceMeasurements() {
  using Meas = typename Experiment::Model::Meas;
  static const std::vector<Meas> y = [] {
    const auto table = examples::readCsv(std::string(MJUKF_DATA_DIR) + "/" + referenceFile<Experiment>());
    std::vector<Meas> rows(table.rows());
    for (int c = 0; c < Meas::RowsAtCompileTime; ++c) {
      const auto& column = table.column("y" + std::to_string(c + 1));
      for (std::size_t k = 0; k < rows.size(); ++k) rows[k](c) = column[k];
    }
    return rows;
  }();
  return y;
}

// `make()` gives a filter as the run starts it.
template <class Experiment, class Make>
void wholeRun(benchmark::State& state, Make make) {
  using Model = typename Experiment::Model;
  using Filter = std::invoke_result_t<Make>;
  const auto& y = referenceMeasurements<Experiment>();
  const auto truth = Model::trueParameters();
  Eigen::Matrix<double, Model::ParamDim, 1> rmse = decltype(rmse)::Zero();
  for (auto _ : state) {
    auto filter = make();
    paper::RmseAccumulator<double, Model::ParamDim> accumulator;
    const auto outcome = paper::runSchedule(
        filter, static_cast<long>(y.size()), Experiment::stepSize, Experiment::measurementEvery,
        [&](long k) -> const typename Model::Meas& { return y[static_cast<std::size_t>(k)]; },
        [&](long k, const Filter& f) {
          if (k >= Experiment::rmseFromRow) accumulator.add(f.parameters(), truth);
        });
    if (outcome.status != Status::Ok) {
      state.SkipWithError(("run stopped at row " + std::to_string(outcome.row)).c_str());
      break;
    }
    rmse = accumulator.value();
    benchmark::DoNotOptimize(rmse.data());
  }
  state.counters["rows"] = double(y.size());
  for (int i = 0; i < Model::ParamDim; ++i) state.counters["rmse_theta" + std::to_string(i + 1)] = rmse(i);
}

template <class Experiment, class Make>
void registerRun(const char* filter, Make make) {
  const std::string name = std::string("run/") + plantName<Experiment>() + "/" + filter;
  benchmark::RegisterBenchmark(name.c_str(), wholeRun<Experiment, Make>, make)->Unit(benchmark::kMillisecond);
}

template <FilterKind Kind, class Experiment>
void registerRun() {
  registerRun<Experiment>(filterName(Kind), [] { return makeFilter<Kind, Experiment>(); });
}

const bool registered = [] {
  registerRun<FilterKind::Ukf, Tank>();
  registerRun<FilterKind::Jukf, Tank>();
  registerRun<FilterKind::Mjukf, Tank>();
  registerRun<FilterKind::Dual, Tank>();
  registerRun<FilterKind::Ukf, Robot>();
  registerRun<FilterKind::Jukf, Robot>();
  registerRun<FilterKind::Mjukf, Robot>();
  registerRun<FilterKind::Dual, Robot>();
  return true;
}();

}  // namespace
}  // namespace mjukf::bench
