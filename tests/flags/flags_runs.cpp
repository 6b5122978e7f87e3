// Runs JUKF, the automatic MJUKF and the dual UKF (without and with a walk of its parameters) over the
// reference files and prints every final estimate to 17 digits. tests/flags/CMakeLists.txt builds it
// twice, as the other tests are built and with -march=native -ffp-contract=fast (fused multiply-adds,
// other vector code), and compares the two outputs (compare_runs.cmake): a filter whose result depends
// on the compiler's rounding choices beyond 1e-6 relative amplifies rounding somewhere, and that is a
// defect (docs/tuning-mjukf.md).

#include <cstdio>
#include <string>
#include <vector>

#include "paper/experiments.hpp"
#include "paper/schedule.hpp"
#include "support/reference_data.hpp"

namespace {

template <class Filter, class Meas>
void run(const char* label, Filter& filter, const std::vector<Meas>& y, double h, int every) {
  const auto outcome = mjukf::paper::runSchedule(
      filter, long(y.size()), h, every, [&](long k) -> const Meas& { return y[std::size_t(k)]; },
      [](long, const Filter&) {});
  std::printf("%s status %s row %ld", label, mjukf::toString(outcome.status), outcome.row);
  for (int r = 0; r < filter.parameters().size(); ++r) std::printf(" %.17g", filter.parameters()(r));
  for (int r = 0; r < filter.state().size(); ++r) std::printf(" %.17g", filter.state()(r));
  std::printf("\n");
}

template <class Experiment>
void runAll(const char* name, const std::string& file) {
  using Model = typename Experiment::Model;
  const auto y = mjukf::testing::referenceMeasurements<typename Model::Meas>(file);
  const double h = Experiment::stepSize;
  const int every = Experiment::measurementEvery;
  mjukf::JointUkf<Model> jukf(Model(), Experiment::initialState(), Experiment::initialParameters(),
                              Experiment::jointUkf());
  run((std::string(name) + " jukf").c_str(), jukf, y, h, every);
  auto automatic = Experiment::modifiedJointUkf();
  automatic.automaticTransformation = true;
  automatic.adaptiveScaling = true;
  mjukf::ModifiedJointUkf<Model> mjukf(Model(), Experiment::initialState(), Experiment::initialParameters(), automatic);
  run((std::string(name) + " mjukf-auto").c_str(), mjukf, y, h, every);
  mjukf::DualUkf<Model> dual(Model(), Experiment::initialState(), Experiment::initialParameters(),
                             Experiment::dualUkf());
  run((std::string(name) + " dual").c_str(), dual, y, h, every);
  // The dual with parameters that walk (its time update's W G and P + W C Wᵀ, docs/algorithms.md §9),
  // the walk the robot's parameter-change run gives it.
  auto walking = Experiment::dualUkf();
  walking.parameterProcessNoise.setIdentity();
  walking.parameterProcessNoise *= 1e-5;
  mjukf::DualUkf<Model> walkingDual(Model(), Experiment::initialState(), Experiment::initialParameters(), walking);
  run((std::string(name) + " dual-walking").c_str(), walkingDual, y, h, every);
}

}  // namespace

int main() {
  runAll<mjukf::paper::CoupledTankExperiment<>>("tank", "coupled_tank_reference.csv");
  runAll<mjukf::paper::FlexibleJointExperiment<>>("robot", "flexible_joint_reference.csv");
  runAll<mjukf::paper::FlexibleJointExperiment<>>("robot-change", "flexible_joint_param_change_reference.csv");
  return 0;
}
