// mjukf_instruction_counts: the cases of the step benchmarks (step_cases.hpp), counted in instructions
// instead of timed, so that a change's cost can be judged without the noise of a shared machine.
// Meant to run under callgrind; scripts/instructions.sh does that and prints the table:
//
//   valgrind --tool=callgrind --collect-atstart=no mjukf_instruction_counts [substring]
//
// For each case (<kind>/<plant>/<filter>/<scalar>, kind step, step_sr (the square-root covariance
// form), open or floor; and the smallest chain of the scaling benchmark, n = 2, p = 1, as
// <kind>/chain_n2_p1/<filter>/double, kind step or floor, and the JUKF's step with its time update
// subdivided into 4 and 8 RK4 steps, step4/… and step8/…: chain_cases.hpp) it takes kWarmUp steps
// uncounted, then counts kCounted steps and dumps callgrind's totals under the case's name; per step is
// the total over kCounted. Run natively, it runs the same steps and counts nothing.

#include <cstdio>
#include <cstring>
#include <string>

#include <valgrind/callgrind.h>

#include "bench_support.hpp"
#include "chain_cases.hpp"
#include "step_cases.hpp"

namespace mjukf::bench {
namespace {

constexpr int kWarmUp = 200;
constexpr int kCounted = 1000;

template <class Case>
bool count(const std::string& name, const char* only) {
  if (only && name.find(only) == std::string::npos) return true;
  Case steps;
  for (int i = 0; i < kWarmUp; ++i) steps.once();
  bool ok = true;
  CALLGRIND_TOGGLE_COLLECT;
  for (int i = 0; i < kCounted; ++i) ok = steps.once() && ok;
  CALLGRIND_TOGGLE_COLLECT;
  CALLGRIND_DUMP_STATS_AT(name.c_str());
  std::printf("%s %d%s\n", name.c_str(), kCounted, ok ? "" : " refused");
  return ok;
}

template <FilterKind Kind, class Experiment>
bool countFilter(const char* only) {
  using Scalar = typename Experiment::Model::Scalar;
  const std::string suffix =
      std::string("/") + plantName<Experiment>() + "/" + filterName(Kind) + "/" + scalarName<Scalar>();
  // The square-root form's measurement step (`step_sr/…`); its floor and open-loop step are the full form's.
  return count<MeasurementSteps<Kind, Experiment>>("step" + suffix, only) &&
         count<MeasurementSteps<Kind, Experiment, SquareRootCovariance>>("step_sr" + suffix, only) &&
         count<OpenLoopSteps<Kind, Experiment>>("open" + suffix, only) &&
         count<FloorSteps<Kind, Experiment>>("floor" + suffix, only);
}

template <FilterKind Kind, class Model>
bool countChainFilter(const char* only) {
  const std::string suffix = std::string("/chain_n") + std::to_string(Model::StateDim) + "_p" +
                             std::to_string(Model::ParamDim) + "/" + filterName(Kind) + "/" +
                             scalarName<typename Model::Scalar>();
  if constexpr (Kind == FilterKind::Jukf) {  // the time update subdivided: the JUKF's only
    if (!count<ChainSteps<Kind, Model, 4>>("step4" + suffix, only) ||
        !count<ChainSteps<Kind, Model, 8>>("step8" + suffix, only))
      return false;
  }
  return count<ChainSteps<Kind, Model>>("step" + suffix, only) &&
         count<ChainFloorSteps<Kind, Model>>("floor" + suffix, only);
}

template <class Model>
bool countChain(const char* only) {
  return countChainFilter<FilterKind::Ukf, Model>(only) && countChainFilter<FilterKind::Jukf, Model>(only) &&
         countChainFilter<FilterKind::Mjukf, Model>(only) && countChainFilter<FilterKind::MjukfAuto, Model>(only) &&
         countChainFilter<FilterKind::Dual, Model>(only);
}

template <class Experiment>
bool countPlant(const char* only) {
  return countFilter<FilterKind::Ukf, Experiment>(only) && countFilter<FilterKind::Jukf, Experiment>(only) &&
         countFilter<FilterKind::Mjukf, Experiment>(only) && countFilter<FilterKind::MjukfAuto, Experiment>(only) &&
         countFilter<FilterKind::Dual, Experiment>(only);
}

}  // namespace
}  // namespace mjukf::bench

int main(int argc, char** argv) {
  using namespace mjukf::bench;
  const char* only = argc > 1 ? argv[1] : nullptr;
  const bool ok = countPlant<RobotOf<double>>(only) && countPlant<TankOf<double>>(only) &&
                  countPlant<RobotOf<float>>(only) && countPlant<TankOf<float>>(only) &&
                  countChain<Chain<double, 2, 1>>(only);
  if (!ok) std::fprintf(stderr, "a filter refused a step: its counts are not those of the schedule\n");
  return ok ? 0 : 1;
}
