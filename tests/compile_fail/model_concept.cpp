// Compiled by ctest and expected to FAIL for each MJUKF_BROKEN_MODEL (tests/compile_fail/CMakeLists.txt):
// a model that breaks the concept of model.hpp must not compile, and checkModel's message must name
// the function. With MJUKF_BROKEN_MODEL undefined the file compiles and runs (the positive control).

#include <cstdio>

#include "mjukf/modified_joint_ukf.hpp"

#ifndef MJUKF_BROKEN_MODEL
#define MJUKF_BROKEN_MODEL 0
#endif

namespace {

// A discrete-time plant whose measurement depends on the input (no input(t): the input is passed).
struct Plant {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Matrix<double, 2, 1>;
  using Param = Eigen::Matrix<double, 1, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
#if MJUKF_BROKEN_MODEL == 2  // 2: derivative returning a vector of 3 entries
  Eigen::Vector3d derivative(double, const State& x, const Input&, const Param&) const { return {x(0), x(1), 0}; }
#elif MJUKF_BROKEN_MODEL == 3  // 3: transition returning a vector of 1 entry
  Eigen::Matrix<double, 1, 1> transition(double, double, const State& x, const Input&, const Param&) const {
    return x.head<1>();
  }
#else
  State transition(double, double dt, const State& x, const Input& u, const Param&) const {
    return State(x(0) + dt * x(1), 0.9 * x(1) + dt * u(0));
  }
#endif
#if MJUKF_BROKEN_MODEL == 1  // 1: measurement returning a vector of 2 entries for MeasDim = 1
  Eigen::Vector2d measurement(const State& x, const Input&, const Param&) const { return x; }
#else
  Meas measurement(const State& x, const Input& u, const Param& theta) const { return Meas(x(0) + theta(0) * u(0)); }
#endif
#if MJUKF_BROKEN_MODEL == 4  // 4: both forms of the measurement
  Meas measurement(const State& x, const Param&) const { return Meas(x(0)); }
#endif
};

}  // namespace

int main() {
  mjukf::ModifiedJointUkfSettingsFor<Plant> settings;
  settings.initialCovariance.setIdentity();
  settings.processNoise.diagonal().setConstant(1e-4);
  settings.measurementNoise(0, 0) = 1e-2;
  settings.scaling = -0.1;
  settings.transformation(0, 0) = 1;
  mjukf::ModifiedJointUkf<Plant> filter(Plant(), Plant::State::Zero(), Plant::Param::Constant(0.5), settings);
  const Plant::Input u = Plant::Input::Constant(1);
  if (!mjukf::taken(filter.timeUpdate(0, 0.1, u))) return 1;
#if MJUKF_BROKEN_MODEL == 5  // 5: the update without the input its measurement needs
  const mjukf::Status updated = filter.measurementUpdate(Plant::Meas::Constant(1));
#else
  const mjukf::Status updated = filter.measurementUpdate(Plant::Meas::Constant(1), u);
#endif
  std::printf("%s\n", mjukf::toString(updated));
  return mjukf::taken(updated) ? 0 : 1;
}
