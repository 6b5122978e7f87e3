// The compile-time opt-outs (features.hpp, docs/embedded.md): each filter compiled without its health
// monitor, and the MJUKF without its automatic modes, in double and float, has a smaller object, is
// refused by its factory when its settings ask for what is compiled out (naming the setting and the
// opt-out), and otherwise gives bit for bit the estimates of the filter with everything compiled in
// and those settings off.

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <gtest/gtest.h>

#include "mjukf/mjukf.hpp"
#include "paper/experiments.hpp"

// Every member of the filters without the optional features compiles, for float and double (a member
// never called is otherwise never compiled).
namespace mjukf {
using FeaturesTestLean = Without<feature::HealthMonitor, feature::AutomaticModes>;
#define MJUKF_INSTANTIATE_WITHOUT_FEATURES(Scalar)                                                                    \
  template class Ukf<paper::FlexibleJointExperiment<Scalar>::Model, ITrBdf2<Scalar>, MerweScaled, FullCovariance,     \
                     FeaturesTestLean>;                                                                               \
  template class JointUkf<paper::FlexibleJointExperiment<Scalar>::Model, ITrBdf2<Scalar>, MerweScaled,                \
                          SquareRootCovariance, FeaturesTestLean>;                                                    \
  template class ModifiedJointUkf<paper::FlexibleJointExperiment<Scalar>::Model, ITrBdf2<Scalar>, MerweScaled,        \
                                  FullCovariance, FeaturesTestLean>;                                                  \
  template class ModifiedJointUkf<paper::FlexibleJointExperiment<Scalar>::Model, ITrBdf2<Scalar>, MerweScaled,        \
                                  SquareRootCovariance, Without<feature::AutomaticModes>>;                            \
  template class DualUkf<paper::FlexibleJointExperiment<Scalar>::Model, ITrBdf2<Scalar>, MerweScaled, FullCovariance, \
                         Without<feature::HealthMonitor>>;
MJUKF_INSTANTIATE_WITHOUT_FEATURES(float)
MJUKF_INSTANTIATE_WITHOUT_FEATURES(double)
#undef MJUKF_INSTANTIATE_WITHOUT_FEATURES
}  // namespace mjukf

namespace {

using mjukf::FullCovariance;
using mjukf::MerweScaled;
using mjukf::SquareRootCovariance;
using mjukf::Status;
using mjukf::Without;
namespace feature = mjukf::feature;
using Lean = Without<feature::HealthMonitor, feature::AutomaticModes>;
using NoMonitor = Without<feature::HealthMonitor>;
using NoAutomaticModes = Without<feature::AutomaticModes>;

static_assert(std::is_same_v<mjukf::AllFeatures, Without<>>);
static_assert(std::is_same_v<Lean, Without<feature::AutomaticModes, feature::HealthMonitor>>,
              "one type per set of features, whatever the order of the tags");
static_assert(!Lean::healthMonitor && !Lean::automaticModes && !NoMonitor::healthMonitor && NoMonitor::automaticModes &&
              NoAutomaticModes::healthMonitor && !NoAutomaticModes::automaticModes);

template <class Scalar>
using Robot = mjukf::paper::FlexibleJointExperiment<Scalar>;
template <class Scalar>
using Model = typename Robot<Scalar>::Model;
template <class Scalar>
using Stepper = mjukf::DefaultIntegrator<Model<Scalar>>;

// The four filters of the robot with the given features and covariance form, and their settings.
template <class Scalar, class Form, class Features>
struct Filters {
  using Ukf = mjukf::Ukf<Model<Scalar>, Stepper<Scalar>, MerweScaled, Form, Features>;
  using JointUkf = mjukf::JointUkf<Model<Scalar>, Stepper<Scalar>, MerweScaled, Form, Features>;
  using ModifiedJointUkf = mjukf::ModifiedJointUkf<Model<Scalar>, Stepper<Scalar>, MerweScaled, Form, Features>;
  using DualUkf = mjukf::DualUkf<Model<Scalar>, Stepper<Scalar>, MerweScaled, Form, Features>;
};

template <class Matrix>
bool sameBits(const Matrix& a, const Matrix& b) {
  return std::memcmp(a.data(), b.data(), sizeof(typename Matrix::Scalar) * std::size_t(a.size())) == 0;
}

// ---- sizeof ------------------------------------------------------------------------------------------

template <class Scalar, class Form>
void expectSmallerObjects() {
  using Full = Filters<Scalar, Form, mjukf::AllFeatures>;
  using Bare = Filters<Scalar, Form, Lean>;
  using Unmonitored = Filters<Scalar, Form, NoMonitor>;
  using Fixed = Filters<Scalar, Form, NoAutomaticModes>;
  using M = Model<Scalar>;
  constexpr std::size_t monitor = sizeof(mjukf::detail::HealthMonitor<Scalar, M::MeasDim, M::ParamDim>);
  constexpr std::size_t sensitivity = sizeof(mjukf::ParameterSensitivity<Scalar, M::StateDim, M::MeasDim, M::ParamDim>);
  // Without the monitor, each object is smaller by at least the monitor's size (less the alignment
  // padding its removal may leave).
  constexpr std::size_t slack = alignof(typename Full::JointUkf);
  EXPECT_LE(sizeof(typename Unmonitored::Ukf) + monitor, sizeof(typename Full::Ukf) + slack);
  EXPECT_LE(sizeof(typename Unmonitored::JointUkf) + monitor, sizeof(typename Full::JointUkf) + slack);
  EXPECT_LE(sizeof(typename Unmonitored::ModifiedJointUkf) + monitor, sizeof(typename Full::ModifiedJointUkf) + slack);
  EXPECT_LE(sizeof(typename Unmonitored::DualUkf) + monitor, sizeof(typename Full::DualUkf) + slack);
  // Without the automatic modes, the MJUKF is smaller by at least their sensitivities; the other
  // filters have none, and are the same.
  EXPECT_LE(sizeof(typename Fixed::ModifiedJointUkf) + sensitivity, sizeof(typename Full::ModifiedJointUkf) + slack);
  EXPECT_EQ(sizeof(typename Fixed::Ukf), sizeof(typename Full::Ukf));
  EXPECT_EQ(sizeof(typename Fixed::JointUkf), sizeof(typename Full::JointUkf));
  EXPECT_EQ(sizeof(typename Fixed::DualUkf), sizeof(typename Full::DualUkf));
  // Both out.
  EXPECT_LE(sizeof(typename Bare::ModifiedJointUkf) + monitor + sensitivity,
            sizeof(typename Full::ModifiedJointUkf) + slack);
  EXPECT_EQ(sizeof(typename Bare::Ukf), sizeof(typename Unmonitored::Ukf));
  std::printf(
      "sizeof %s %s: UKF %zu -> %zu, JUKF %zu -> %zu, MJUKF %zu -> %zu (monitor out %zu, automatic modes out %zu), "
      "dual UKF %zu -> %zu\n",
      sizeof(Scalar) == 4 ? "float" : "double", mjukf::detail::isSquareRootForm<Form> ? "square root" : "full",
      sizeof(typename Full::Ukf), sizeof(typename Bare::Ukf), sizeof(typename Full::JointUkf),
      sizeof(typename Bare::JointUkf), sizeof(typename Full::ModifiedJointUkf), sizeof(typename Bare::ModifiedJointUkf),
      sizeof(typename Unmonitored::ModifiedJointUkf), sizeof(typename Fixed::ModifiedJointUkf),
      sizeof(typename Full::DualUkf), sizeof(typename Bare::DualUkf));
}

TEST(Features, ObjectsShrinkDouble) {
  expectSmallerObjects<double, FullCovariance>();
  expectSmallerObjects<double, SquareRootCovariance>();
}
TEST(Features, ObjectsShrinkFloat) {
  expectSmallerObjects<float, FullCovariance>();
  expectSmallerObjects<float, SquareRootCovariance>();
}

// ---- The factory refuses what is compiled out ----------------------------------------------------

template <class Filter, class Settings>
void expectRefused(const typename Filter::Param& theta0, const Settings& settings, const char* setting,
                   const char* optOut) {
  using Scalar = typename Filter::Scalar;
  const auto made = Filter::create(Model<Scalar>(), Robot<Scalar>::initialState(), theta0, settings);
  ASSERT_FALSE(made) << setting;
  EXPECT_STREQ(made.error().setting, setting);
  EXPECT_NE(std::string(made.error().reason).find(optOut), std::string::npos) << made.error().reason;
  const mjukf::SettingsError validated = Filter::validate(Robot<Scalar>::initialState(), theta0, settings);
  ASSERT_TRUE(validated);
  EXPECT_STREQ(validated.setting, setting);
#if MJUKF_EXCEPTIONS
  try {
    Filter filter(Model<Scalar>(), Robot<Scalar>::initialState(), theta0, settings);
    ADD_FAILURE() << "the constructor accepted " << setting;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(setting), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(optOut), std::string::npos) << e.what();
  }
#endif
}

template <class Settings>
Settings unmonitored(Settings s) {
  s.health.enabled = false;
  return s;
}

template <class Scalar>
void expectCompiledOutSettingsRefused() {
  using Bare = Filters<Scalar, FullCovariance, Lean>;
  using Unmonitored = Filters<Scalar, FullCovariance, NoMonitor>;
  using Fixed = Filters<Scalar, FullCovariance, NoAutomaticModes>;
  using R = Robot<Scalar>;
  const char* noMonitor = "mjukf::Without<mjukf::feature::HealthMonitor>";
  const char* noAutomatic = "mjukf::Without<mjukf::feature::AutomaticModes>";
  // The monitor is on by default: a filter without it must be told so.
  expectRefused<typename Bare::Ukf>(Model<Scalar>::trueParameters(), R::ukf(), "health.enabled", noMonitor);
  expectRefused<typename Bare::JointUkf>(R::initialParameters(), R::jointUkf(), "health.enabled", noMonitor);
  expectRefused<typename Bare::ModifiedJointUkf>(R::initialParameters(), R::modifiedJointUkf(), "health.enabled",
                                                 noMonitor);
  expectRefused<typename Bare::DualUkf>(R::initialParameters(), R::dualUkf(), "health.enabled", noMonitor);
  expectRefused<typename Unmonitored::ModifiedJointUkf>(R::initialParameters(), R::modifiedJointUkf(), "health.enabled",
                                                        noMonitor);
  // Either automatic mode.
  auto automaticT = unmonitored(R::modifiedJointUkf());
  automaticT.automaticTransformation = true;
  auto adaptive = unmonitored(R::modifiedJointUkf());
  adaptive.adaptiveScaling = true;
  expectRefused<typename Bare::ModifiedJointUkf>(R::initialParameters(), automaticT, "automaticTransformation",
                                                 noAutomatic);
  expectRefused<typename Bare::ModifiedJointUkf>(R::initialParameters(), adaptive, "adaptiveScaling", noAutomatic);
  // The covariance of θ̂ follows the automatic modes' sensitivities: it goes with them.
  auto followed = unmonitored(R::modifiedJointUkf());
  followed.followParameterCovariance = true;
  expectRefused<typename Bare::ModifiedJointUkf>(R::initialParameters(), followed, "followParameterCovariance",
                                                 noAutomatic);
  // Without the automatic modes alone, the monitor may stay on.
  auto monitoredAdaptive = R::modifiedJointUkf();
  monitoredAdaptive.adaptiveScaling = true;
  expectRefused<typename Fixed::ModifiedJointUkf>(R::initialParameters(), monitoredAdaptive, "adaptiveScaling",
                                                  noAutomatic);
  // The settings the features allow are accepted.
  EXPECT_TRUE(Bare::ModifiedJointUkf::create(Model<Scalar>(), R::initialState(), R::initialParameters(),
                                             unmonitored(R::modifiedJointUkf())));
  EXPECT_TRUE(Fixed::ModifiedJointUkf::create(Model<Scalar>(), R::initialState(), R::initialParameters(),
                                              R::modifiedJointUkf()));
}

TEST(Features, FactoryRefusesCompiledOutSettingsDouble) { expectCompiledOutSettingsRefused<double>(); }
TEST(Features, FactoryRefusesCompiledOutSettingsFloat) { expectCompiledOutSettingsRefused<float>(); }

// ---- The same estimates, bit for bit -------------------------------------------------------------

template <class F, class = void>
constexpr bool hasParameterPoints = false;
template <class F>
constexpr bool hasParameterPoints<F, std::void_t<decltype(std::declval<const F&>().parameterPoints())>> = true;
template <class F, class = void>
constexpr bool hasParameterCovariance = false;
template <class F>
constexpr bool hasParameterCovariance<F, std::void_t<decltype(std::declval<const F&>().parameterCovariance())>> = true;
template <class F, class = void>
constexpr bool hasParameters = false;
template <class F>
constexpr bool hasParameters<F, std::void_t<decltype(std::declval<const F&>().parameters())>> = true;

// Everything both filters show of their estimate, bit for bit.
template <class A, class B>
::testing::AssertionResult sameEstimates(const A& a, const B& b) {
  const auto differ = [](const char* what) { return ::testing::AssertionFailure() << what << " differs"; };
  if (!sameBits(a.state(), b.state())) return differ("state");
  if (!sameBits(a.covariance(), b.covariance())) return differ("covariance");
  if (!sameBits(a.lastUpdate().innovation, b.lastUpdate().innovation)) return differ("innovation");
  if (!sameBits(a.lastUpdate().innovationCovariance, b.lastUpdate().innovationCovariance))
    return differ("innovation covariance");
  if (std::memcmp(&a.lastUpdate().nis, &b.lastUpdate().nis, sizeof a.lastUpdate().nis) != 0) return differ("NIS");
  const auto timeA = a.time(), timeB = b.time();
  if (std::memcmp(&timeA, &timeB, sizeof timeA) != 0) return differ("time");
  if (a.hasPropagatedPoints() != b.hasPropagatedPoints()) return differ("hasPropagatedPoints");
  if constexpr (hasParameters<A>)
    if (!sameBits(a.parameters(), b.parameters())) return differ("parameters");
  if constexpr (hasParameterPoints<A>) {
    if (!sameBits(a.parameterPoints(), b.parameterPoints())) return differ("parameterPoints");
    if (!sameBits(a.transformation(), b.transformation())) return differ("transformation");
    if (!sameBits(a.scalings(), b.scalings())) return differ("scalings");
  }
  if constexpr (hasParameterCovariance<A>)
    if (!sameBits(a.parameterCovariance(), b.parameterCovariance())) return differ("parameterCovariance");
  return ::testing::AssertionSuccess();
}

// The robot simulated in Scalar with the true parameters, every state measured with noise of σ = 0.03
// (a fixed-seed xorshift32, as the firmware example); the paper's schedule (a time and measurement
// update every 5 rows, open-loop propagation between), every third update without the second
// component, over `rows` rows. Every call goes to each filter; their statuses must agree and their
// estimates be the same bit for bit after each call.
template <class Scalar, class Reference, class... Others>
void runInStep(long rows, Reference& reference, Others&... others) {
  using M = Model<Scalar>;
  const M model;
  const Stepper<Scalar> stepper;
  typename M::State x = Robot<Scalar>::initialState();
  std::uint32_t random = 2463534242u;
  const auto gaussian = [&random] {
    Scalar sum = 0;
    for (int i = 0; i < 12; ++i) {
      random ^= random << 13;
      random ^= random >> 17;
      random ^= random << 5;
      sum += Scalar(random >> 8) * Scalar(1.0f / 16777216.0f);
    }
    return sum - Scalar(6);
  };
  const Scalar h = Robot<Scalar>::stepSize;
  mjukf::MeasurementMask<M::MeasDim> partial = mjukf::MeasurementMask<M::MeasDim>::Constant(true);
  partial(1) = false;
  long updates = 0;
  for (long row = 1; row < rows; ++row) {
    const Scalar t = Scalar(row - 1) * h;
    x = mjukf::stepModel(model, stepper, t, h, x, M::trueParameters());
    const auto everyFilter = [&](auto&& call) {
      const Status expected = call(reference);
      ASSERT_TRUE(mjukf::taken(expected)) << "row " << row << ": " << mjukf::toString(expected);
      const auto check = [&](auto& other) {
        EXPECT_EQ(call(other), expected) << "row " << row;
        EXPECT_TRUE(sameEstimates(reference, other)) << "row " << row;
      };
      (check(others), ...);
    };
    if (row % Robot<Scalar>::measurementEvery != 0) {
      everyFilter([&](auto& f) { return f.propagateMean(t, h); });
      continue;
    }
    typename M::Meas y;
    for (int j = 0; j < M::MeasDim; ++j) y(j) = x(j) + Scalar(0.03) * gaussian();
    everyFilter([&](auto& f) { return f.timeUpdate(t, h); });
    if (++updates % 3 == 0)
      everyFilter([&](auto& f) { return f.measurementUpdate(y, partial); });
    else
      everyFilter([&](auto& f) { return f.measurementUpdate(y); });
    if (::testing::Test::HasFailure()) return;
  }
}

// Each filter without its monitor (and the MJUKF without its automatic modes) against the full one with
// the monitor on (the default) and off: the monitor only watches, so all three agree.
template <class Scalar, class Form>
void expectSameEstimates(long rows) {
  using Full = Filters<Scalar, Form, mjukf::AllFeatures>;
  using Bare = Filters<Scalar, Form, Lean>;
  using R = Robot<Scalar>;
  const Model<Scalar> model;
  const auto x0 = R::initialState();
  {
    typename Full::Ukf full(model, x0, Model<Scalar>::trueParameters(), R::ukf());
    typename Full::Ukf off(model, x0, Model<Scalar>::trueParameters(), unmonitored(R::ukf()));
    auto bare = Bare::Ukf::create(model, x0, Model<Scalar>::trueParameters(), unmonitored(R::ukf()));
    ASSERT_TRUE(bare);
    runInStep<Scalar>(rows, full, off, *bare);
  }
  {
    typename Full::JointUkf full(model, x0, R::initialParameters(), R::jointUkf());
    typename Full::JointUkf off(model, x0, R::initialParameters(), unmonitored(R::jointUkf()));
    auto bare = Bare::JointUkf::create(model, x0, R::initialParameters(), unmonitored(R::jointUkf()));
    ASSERT_TRUE(bare);
    runInStep<Scalar>(rows, full, off, *bare);
  }
  {
    typename Full::ModifiedJointUkf full(model, x0, R::initialParameters(), R::modifiedJointUkf());
    typename Full::ModifiedJointUkf off(model, x0, R::initialParameters(), unmonitored(R::modifiedJointUkf()));
    auto bare = Bare::ModifiedJointUkf::create(model, x0, R::initialParameters(), unmonitored(R::modifiedJointUkf()));
    ASSERT_TRUE(bare);
    runInStep<Scalar>(rows, full, off, *bare);
    // A new pass from what each learnt, and a reset with new parameters (eq. 8's spread again).
    // (A refused one throws, which fails the test.)
    const auto p0 = R::modifiedJointUkf().initialCovariance;
    full.startPass(Scalar(0), x0, p0, full.parameterKnowledge());
    off.startPass(Scalar(0), x0, p0, off.parameterKnowledge());
    bare->startPass(Scalar(0), x0, p0, bare->parameterKnowledge());
    EXPECT_TRUE(sameEstimates(full, *bare));
    runInStep<Scalar>(rows / 4, full, off, *bare);
    full.reset(x0, p0, R::initialParameters());
    off.reset(x0, p0, R::initialParameters());
    bare->reset(x0, p0, R::initialParameters());
    runInStep<Scalar>(rows / 4, full, off, *bare);
  }
  {
    typename Full::DualUkf full(model, x0, R::initialParameters(), R::dualUkf());
    typename Full::DualUkf off(model, x0, R::initialParameters(), unmonitored(R::dualUkf()));
    auto bare = Bare::DualUkf::create(model, x0, R::initialParameters(), unmonitored(R::dualUkf()));
    ASSERT_TRUE(bare);
    runInStep<Scalar>(rows, full, off, *bare);
  }
}

TEST(Features, SameEstimatesDouble) { expectSameEstimates<double, FullCovariance>(4000); }
TEST(Features, SameEstimatesFloat) { expectSameEstimates<float, FullCovariance>(4000); }
TEST(Features, SameEstimatesFloatSquareRoot) { expectSameEstimates<float, SquareRootCovariance>(2000); }

// The MJUKF's automatic modes on, without the monitor: the same as with it, sensitivities included.
template <class Scalar>
void expectSameAutomaticModes(long rows) {
  using Full = Filters<Scalar, FullCovariance, mjukf::AllFeatures>;
  using Unmonitored = Filters<Scalar, FullCovariance, NoMonitor>;
  using R = Robot<Scalar>;
  auto settings = R::modifiedJointUkf();
  settings.automaticTransformation = true;
  settings.adaptiveScaling = true;
  typename Full::ModifiedJointUkf full(Model<Scalar>(), R::initialState(), R::initialParameters(), settings);
  auto bare = Unmonitored::ModifiedJointUkf::create(Model<Scalar>(), R::initialState(), R::initialParameters(),
                                                    unmonitored(settings));
  ASSERT_TRUE(bare);
  runInStep<Scalar>(rows, full, *bare);
  EXPECT_TRUE(sameBits(full.sensitivity().information(), bare->sensitivity().information()));
  EXPECT_TRUE(sameBits(full.sensitivity().stateSensitivity(), bare->sensitivity().stateSensitivity()));
  EXPECT_TRUE(sameBits(full.sensitivity().measurementSensitivity(), bare->sensitivity().measurementSensitivity()));
  EXPECT_FALSE(full.sensitivity().information().isZero()) << "the automatic modes ran";
}

TEST(Features, AutomaticModesWithoutMonitorDouble) { expectSameAutomaticModes<double>(2000); }
TEST(Features, AutomaticModesWithoutMonitorFloat) { expectSameAutomaticModes<float>(2000); }

}  // namespace
