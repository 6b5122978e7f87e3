// Compiled by ctest and expected to FAIL for each MJUKF_BROKEN_FEATURE (tests/compile_fail/CMakeLists.txt):
// a filter compiled without a feature (features.hpp) has no accessor of it, and the compiler's message
// says why: health() without the health monitor, sensitivity() of an MJUKF without its automatic modes,
// and a tag Without<> does not know. With MJUKF_BROKEN_FEATURE undefined the file compiles and runs the
// filters it builds (the positive control).

#include <cstdio>

#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"

#ifndef MJUKF_BROKEN_FEATURE
#define MJUKF_BROKEN_FEATURE 0
#endif

namespace {

// x' = −θ x, measured directly.
struct Decay {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 0;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = Eigen::Matrix<double, 1, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 0, 1>;
  State transition(double, double dt, const State& x, const Input&, const Param& theta) const {
    return State(x(0) * (1 - dt * theta(0)));
  }
  Meas measurement(const State& x, const Param&) const { return x; }
};

using mjukf::Without;
namespace feature = mjukf::feature;
using Integrator = mjukf::NoIntegrator<double>;
using Bare = Without<feature::HealthMonitor, feature::AutomaticModes>;
using Mjukf = mjukf::ModifiedJointUkf<Decay, Integrator, mjukf::MerweScaled, mjukf::FullCovariance, Bare>;
#if MJUKF_BROKEN_FEATURE == 3  // 3: a tag that is not a feature
using Ukf = mjukf::Ukf<Decay, Integrator, mjukf::MerweScaled, mjukf::FullCovariance, Without<int>>;
#else
using Ukf = mjukf::Ukf<Decay, Integrator, mjukf::MerweScaled, mjukf::FullCovariance, Bare>;
#endif

}  // namespace

int main() {
  Mjukf::Settings settings;
  settings.initialCovariance(0, 0) = 1;
  settings.measurementNoise(0, 0) = 0.01;
  settings.transformation(0, 0) = 1;
  settings.scaling = -0.1;
  settings.health.enabled = false;
  settings.followParameterCovariance = false;  // P_θ goes with the automatic modes
  auto mjukf = Mjukf::create(Decay(), Decay::State(1), Decay::Param(0.5), settings);
  Ukf::Settings ukfSettings;
  ukfSettings.initialCovariance(0, 0) = 1;
  ukfSettings.measurementNoise(0, 0) = 0.01;
  ukfSettings.health.enabled = false;
  auto ukf = Ukf::create(Decay(), Decay::State(1), Decay::Param(0.5), ukfSettings);
  if (!mjukf || !ukf) {
    std::fprintf(stderr, "refused: %s %s\n", mjukf ? "" : mjukf.error().setting, ukf ? "" : ukf.error().setting);
    return 1;
  }
  mjukf->timeUpdate(0.0, 0.1);
  mjukf->measurementUpdate(Decay::Meas(0.9));
  ukf->timeUpdate(0.0, 0.1);
  ukf->measurementUpdate(Decay::Meas(0.9));
#if MJUKF_BROKEN_FEATURE == 1  // 1: health() without the health monitor
  if (ukf->health() != mjukf::Health::Ok) return 1;
#elif MJUKF_BROKEN_FEATURE == 2  // 2: sensitivity() without the automatic modes
  std::printf("%g\n", mjukf->sensitivity().information()(0, 0));
#endif
  std::printf("compiled-out features: x %g, theta %g\n", mjukf->state()(0), mjukf->parameters()(0));
  return 0;
}
