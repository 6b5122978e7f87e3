// Compiled by ctest and expected to FAIL (tests/compile_fail/CMakeLists.txt): a filter whose parameter
// policy lacks a required hook, or spells it wrongly, must not compile, and the error must name the
// hook. MJUKF_BROKEN_HOOK picks which hook is broken; with it undefined the file compiles (the
// positive control, built with the tests).

#include "mjukf/ukf.hpp"

namespace {

struct Plant {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 0, MeasDim = 1, InputDim = 0;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = Eigen::Matrix<double, 0, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 0, 1>;
  State derivative(double, const State& x, const Input&, const Param&) const { return -x; }
  Meas measurement(const State& x, const Param&) const { return x; }
};

using Settings = mjukf::UkfSettingsFor<Plant>;
using Integrator = mjukf::DefaultIntegrator<Plant>;
using Est = mjukf::detail::Estimate<double, 1, 1>;

// KnownParameters (ukf.hpp) with one hook broken.
struct Policy : mjukf::detail::ParameterPolicy<Plant, Integrator, Settings, Est> {
  Plant::Param theta;
  Policy(const Settings&, const Plant::Param& parameters) : theta(parameters) {}
  template <class Step>
  mjukf::Status predictParameters(const Step&, const Est&) {
    return mjukf::Status::Ok;
  }
#if MJUKF_BROKEN_HOOK != 1  // 1: propagatePoints missing
  template <class Step>
  void propagatePoints(const Step& step, Est::Points& points) {
    for (int i = 0; i < Est::Count; ++i) points.col(i) = step.propagate(theta, points.col(i));
  }
#endif
  const Est::Matrix& priorFactor(const Est& state) const { return state.factor(); }
  const Est::Matrix* priorCovarianceFloor() const { return nullptr; }
  template <class Step>
  Est::Vector propagateMean(const Step& step, const Est::Vector& mean) {
    return step.propagate(theta, mean);
  }
  void measurePoints(const Plant& model, const Plant::Input&, const Est::Points& points, Est::MeasPoints& measured) {
    for (int i = 0; i < Est::Count; ++i) measured.col(i) = model.measurement(points.col(i), theta);
  }
  template <class Engine>
  mjukf::Status update(Engine& engine, const Plant::Meas& y, const Plant::Input& u, const Est::Mask* present) {
    return engine.correctState(y, u, present);
  }
  mjukf::Status correctParameters(const mjukf::detail::Correction<Plant, Settings, Est>&) { return mjukf::Status::Ok; }
  bool constrainMean(Est::Vector&) { return false; }
  void commitPrediction() {}
#if MJUKF_BROKEN_HOOK == 2  // 2: a misspelled hook, which before the checks compiled and was never called
  void commitParameterCorrection() {}
#else
  void commitCorrection() {}
#endif
  void commitOpenLoop(double) {}
};

class Filter : public mjukf::detail::UnscentedEngine<Filter, Plant, Integrator, Settings, Policy, 1> {
  using Engine = mjukf::detail::UnscentedEngine<Filter, Plant, Integrator, Settings, Policy, 1>;
  friend Engine;
  friend Policy;

 public:
  static mjukf::SettingsError validate(const Plant::State&, const Plant::Param&, const Settings& settings) {
    return Engine::validateSettings("Filter", settings);
  }
  const Plant::State& state() const { return estimate_.mean(); }

 private:
  using Engine::Engine;
  static const Plant::State& initialMean(const Plant::State& x0, const Plant::Param&) { return x0; }
};

}  // namespace

int main() {
  Settings settings;
  settings.initialCovariance.setIdentity();
  settings.measurementNoise.setIdentity();
  auto filter = Filter::create(Plant(), Plant::State::Zero(), Plant::Param(), settings);
  if (filter->timeUpdate(0.0, 0.1) != mjukf::Status::Ok) return 1;
  if (filter->measurementUpdate(Plant::Meas::Constant(1.0)) != mjukf::Status::Ok) return 1;
  return filter->state()(0) > 0 ? 0 : 1;
}
