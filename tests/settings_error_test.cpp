// The factories and the exception-free path (docs/embedded.md). This file is built twice: as
// settings_error_test (exceptions on) and settings_error_noexcept_test (-fno-exceptions, so
// MJUKF_EXCEPTIONS is 0). In both builds an invalid setting or reset argument is reported by a
// SettingsError naming the owner and the setting, create() then holds no filter, and value() on it
// never yields one (it traps without exceptions, throws with them). With exceptions on, the checked
// constructor throws exactly "<owner>: setting '<setting>' <reason>" of the same error.

#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include <gtest/gtest.h>

#include "mjukf/integrators/explicit_tr_bdf2.hpp"
#include "mjukf/integrators/tr_bdf2.hpp"
#include "mjukf/simulation.hpp"
#include "paper/experiments.hpp"
#include "test_support.hpp"

#if MJUKF_EXCEPTIONS
#include <stdexcept>
#include <string>
#endif

namespace {

using Experiment = mjukf::paper::FlexibleJointExperiment<double>;
using Model = Experiment::Model;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

#if defined(__cpp_exceptions) || defined(__EXCEPTIONS)
static_assert(MJUKF_EXCEPTIONS == 1, "exceptions on: the library throws");
#else
static_assert(MJUKF_EXCEPTIONS == 0, "-fno-exceptions: the library only returns SettingsError");
#endif

// The filter types of the typed suite, each with its preset from the paper.
template <template <class...> class F>
struct FilterKind {
  using Type = F<Model, mjukf::DefaultIntegrator<Model>>;
  static auto settings() { return mjukf::testing::presetSettings<F, Experiment>(); }
  static constexpr bool estimatesParameters = !std::is_same_v<Type, mjukf::Ukf<Model>>;
  static Model::Param initialParameters() {
    return estimatesParameters ? Experiment::initialParameters() : Model::trueParameters();
  }
  static const char* owner() {
    if constexpr (std::is_same_v<Type, mjukf::Ukf<Model>>)
      return "mjukf::Ukf";
    else if constexpr (std::is_same_v<Type, mjukf::JointUkf<Model>>)
      return "mjukf::JointUkf";
    else if constexpr (std::is_same_v<Type, mjukf::ModifiedJointUkf<Model>>)
      return "mjukf::ModifiedJointUkf";
    else
      return "mjukf::DualUkf";
  }
};
using FilterKinds = ::testing::Types<FilterKind<mjukf::Ukf>, FilterKind<mjukf::JointUkf>,
                                     FilterKind<mjukf::ModifiedJointUkf>, FilterKind<mjukf::DualUkf>>;

template <class Kind>
class SettingsErrorTest : public ::testing::Test {};
TYPED_TEST_SUITE(SettingsErrorTest, FilterKinds);

void expectNames(const mjukf::SettingsError& e, const char* owner, const char* setting) {
  ASSERT_TRUE(static_cast<bool>(e)) << "no error reported for '" << setting << "'";
  EXPECT_STREQ(e.owner, owner);
  EXPECT_STREQ(e.setting, setting);
  EXPECT_NE(e.reason, nullptr);
}

// With exceptions on, the checked constructor throws the message of the same error.
template <class Filter, class Settings>
void expectConstructorAgrees(const mjukf::SettingsError& e, const Model::State& x0, const Model::Param& theta0,
                             const Settings& s) {
#if MJUKF_EXCEPTIONS
  try {
    Filter(Model(), x0, theta0, s);
    ADD_FAILURE() << "the constructor accepted what create() refused";
  } catch (const std::invalid_argument& thrown) {
    EXPECT_EQ(std::string(thrown.what()), std::string(e.owner) + ": setting '" + e.setting + "' " + e.reason);
  }
#else
  static_assert(!std::is_constructible_v<Filter, Model, Model::State, Model::Param, Settings>,
                "without exceptions a filter is built by create() only");
  static_cast<void>(e), static_cast<void>(x0), static_cast<void>(theta0), static_cast<void>(s);
#endif
}

// create() with `s` and the initial values must fail naming `setting`, hold no filter, and agree with
// the constructor and validate().
template <class Kind, class Settings>
void expectRefused(const Settings& s, const char* setting, const Model::State& x0 = Experiment::initialState(),
                   const Model::Param& theta0 = Kind::initialParameters()) {
  using Filter = typename Kind::Type;
  const auto made = Filter::create(Model(), x0, theta0, s);
  EXPECT_FALSE(made.ok());
  expectNames(made.error(), Kind::owner(), setting);
  const mjukf::SettingsError validated = Filter::validate(x0, theta0, s);
  EXPECT_STREQ(validated.setting, made.error().setting);
  expectConstructorAgrees<Filter>(made.error(), x0, theta0, s);
}

template <class Filter>
bool sameEstimate(const Filter& a, const Filter& b) {
  return a.state() == b.state() && a.covariance() == b.covariance() && a.parameters() == b.parameters();
}

// ---- Construction --------------------------------------------------------------------------------

TYPED_TEST(SettingsErrorTest, ValidSettingsBuildAWorkingFilter) {
  using Filter = typename TypeParam::Type;
  auto made =
      Filter::create(Model(), Experiment::initialState(), TypeParam::initialParameters(), TypeParam::settings());
  ASSERT_TRUE(made.ok()) << made.error().setting;
  EXPECT_FALSE(static_cast<bool>(made.error()));
  Filter& filter = *made;
  EXPECT_EQ(filter.state(), Experiment::initialState());
  EXPECT_EQ(filter.parameters(), TypeParam::initialParameters());
  EXPECT_EQ(filter.timeUpdate(0.0, Experiment::stepSize), mjukf::Status::Ok);
  EXPECT_EQ(filter.measurementUpdate(Model::Meas::Constant(0.01)), mjukf::Status::Ok);
  // A copy of the Result holds a copy of the filter.
  const auto copy = made;
  ASSERT_TRUE(copy.ok());
  EXPECT_TRUE(sameEstimate(*copy, filter));
}

TYPED_TEST(SettingsErrorTest, InvalidSettingsAreNamedAndGiveNoFilter) {
  auto s = TypeParam::settings();
  s.measurementNoise(1, 1) = -1.0;
  expectRefused<TypeParam>(s, "measurementNoise (R)");
  s = TypeParam::settings();
  s.initialCovariance(0, 1) = 0.3;  // not symmetric
  expectRefused<TypeParam>(s, "initialCovariance (P0)");
  s = TypeParam::settings();
  s.processNoise(2, 2) = kNan;
  expectRefused<TypeParam>(s, "processNoise (Q)");
  s = TypeParam::settings();
  s.sigmaPoints.alpha = 0;
  const auto made = TypeParam::Type::create(Model(), Experiment::initialState(), TypeParam::initialParameters(), s);
  expectNames(made.error(), "mjukf::MerweScaledSigmaPoints", "alpha");
  s = TypeParam::settings();
  s.repair.growth = 0.5;
  expectRefused<TypeParam>(s, "repair.growth");
  s = TypeParam::settings();
  s.gate.nisThreshold(0) = 0;
  expectRefused<TypeParam>(s, "gate.nisThreshold");

  Model::State x0 = Experiment::initialState();
  x0(3) = kNan;
  expectRefused<TypeParam>(TypeParam::settings(), "initialState", x0);
}

TYPED_TEST(SettingsErrorTest, InvalidParameterSettingsAreNamed) {
  if constexpr (TypeParam::estimatesParameters) {
    auto s = TypeParam::settings();
    s.parameterBounds.upper(0) = 0.05;  // below the initial K_τ = 0.1
    expectRefused<TypeParam>(s, "initialParameters");
    s = TypeParam::settings();
    s.parameterBounds.lower(1) = 1;
    s.parameterBounds.upper(1) = 0;
    expectRefused<TypeParam>(s, "parameterBounds");
  }
  if constexpr (std::is_same_v<typename TypeParam::Type, mjukf::ModifiedJointUkf<Model>>) {
    auto s = TypeParam::settings();
    s.transformation(0, 0) += 0.5;
    expectRefused<TypeParam>(s, "transformation (T)");
  }
  if constexpr (std::is_same_v<typename TypeParam::Type, mjukf::DualUkf<Model>>) {
    auto s = TypeParam::settings();
    s.parameterForgetting = 0;
    expectRefused<TypeParam>(s, "parameterForgetting");
    s = TypeParam::settings();
    s.parameterSigmaPoints.kappa = -10;
    const auto made = TypeParam::Type::create(Model(), Experiment::initialState(), TypeParam::initialParameters(), s);
    expectNames(made.error(), "mjukf::MerweScaledSigmaPoints", "kappa");
  }
}

// A Result without a filter never hands one out: value() traps (no exceptions) or throws.
TYPED_TEST(SettingsErrorTest, AFailedResultGivesNoFilter) {
  auto s = TypeParam::settings();
  s.measurementNoise(0, 0) = -1.0;
  auto made = TypeParam::Type::create(Model(), Experiment::initialState(), TypeParam::initialParameters(), s);
  ASSERT_FALSE(made.ok());
#if MJUKF_EXCEPTIONS
  EXPECT_THROW(static_cast<void>(made.value()), std::invalid_argument);
  EXPECT_THROW(static_cast<void>(made->state()), std::invalid_argument);
#else
  EXPECT_DEATH(static_cast<void>(made.value()), "");
  EXPECT_DEATH(static_cast<void>(made->state()), "");
#endif
}

// ---- reset() -------------------------------------------------------------------------------------

// reset() with an invalid argument reports it (returns it, or throws it) and changes nothing.
template <class Filter, class... Args>
void expectResetRefused(Filter& filter, const char* setting, const Args&... args) {
  const Filter before = filter;
#if MJUKF_EXCEPTIONS
  static_assert(std::is_void_v<decltype(filter.reset(args...))>);
  try {
    filter.reset(args...);
    ADD_FAILURE() << "reset accepted a bad '" << setting << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(std::string("setting '") + setting + "'"), std::string::npos) << e.what();
  }
#else
  const mjukf::SettingsError e = filter.reset(args...);
  ASSERT_TRUE(static_cast<bool>(e)) << "reset accepted a bad '" << setting << "'";
  EXPECT_STREQ(e.setting, setting);
#endif
  EXPECT_TRUE(sameEstimate(filter, before));
}

TYPED_TEST(SettingsErrorTest, ResetReportsItsArgumentsAndChangesNothing) {
  using Filter = typename TypeParam::Type;
  auto made =
      Filter::create(Model(), Experiment::initialState(), TypeParam::initialParameters(), TypeParam::settings());
  ASSERT_TRUE(made.ok());
  Filter& filter = *made;
  ASSERT_EQ(filter.timeUpdate(0.0, Experiment::stepSize), mjukf::Status::Ok);
  ASSERT_EQ(filter.measurementUpdate(Model::Meas::Constant(0.02)), mjukf::Status::Ok);

  const auto good = filter.covariance().eval();
  auto notPositive = good;
  notPositive(0, 0) = -1;
  Model::State nanState = filter.state();
  nanState(1) = kNan;
  expectResetRefused(filter, "covariance", filter.state(), notPositive);
  expectResetRefused(filter, "state", nanState, good);
  Model::Param nanParameters = filter.parameters();
  nanParameters(0) = kNan;
  expectResetRefused(filter, "parameters", filter.state(), good, nanParameters);

  // A valid reset is taken.
  Model::State other = filter.state();
  other(0) += 0.5;
#if MJUKF_EXCEPTIONS
  filter.reset(other, good);
#else
  EXPECT_FALSE(static_cast<bool>(filter.reset(other, good)));
#endif
  EXPECT_EQ(filter.state(), other);
}

// ---- Steppers, sigma points, simulate ------------------------------------------------------------

template <class Made>
void expectStepperRefused(const Made& made, const char* owner, const char* setting) {
  EXPECT_FALSE(made.ok());
  expectNames(made.error(), owner, setting);
}

TEST(SettingsError, SteppersAndSigmaPoints) {
  expectStepperRefused(mjukf::ITrBdf2<double>::create(1.5), "mjukf::ITrBdf2", "gamma");
  expectStepperRefused(mjukf::ExplicitTrBdf2<float>::create(0.0f), "mjukf::ExplicitTrBdf2", "gamma");
  mjukf::TrBdf2Settings<double> newton;
  newton.maxIterations = 0;
  expectStepperRefused(mjukf::TrBdf2<double>::create(newton), "mjukf::TrBdf2", "maxIterations");
  mjukf::SigmaPointParameters<double> points;
  points.beta = kNan;
  expectStepperRefused(mjukf::MerweScaledSigmaPoints<double, 3>::create(points), "mjukf::MerweScaledSigmaPoints",
                       "beta");

  const auto stepper = mjukf::ITrBdf2<double>::create(0.25);
  ASSERT_TRUE(stepper.ok());
  EXPECT_EQ(stepper->gamma(), 0.25);
#if !MJUKF_EXCEPTIONS
  static_assert(!std::is_constructible_v<mjukf::ITrBdf2<double>, double>);
  static_assert(!std::is_constructible_v<mjukf::TrBdf2<double>, mjukf::TrBdf2Settings<double>>);
  static_assert(
      !std::is_constructible_v<mjukf::MerweScaledSigmaPoints<double, 3>, mjukf::SigmaPointParameters<double>>);
#endif
}

// simulate() with steps < 0: throws with exceptions on, otherwise visits nothing and returns NaN.
TEST(SettingsError, SimulateWithNegativeSteps) {
  int visits = 0;
  const auto run = [&] {
    return mjukf::simulate(Model(), mjukf::ITrBdf2<double>(), Experiment::initialState(), Model::trueParameters(), 0.0,
                           1e-3, -1, [&](long, double, const Model::State&) { ++visits; });
  };
#if MJUKF_EXCEPTIONS
  EXPECT_THROW(run(), std::invalid_argument);
#else
  EXPECT_TRUE(run().array().isNaN().all());
#endif
  EXPECT_EQ(visits, 0);
}

}  // namespace
