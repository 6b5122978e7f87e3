// The integration step's check (step_check.hpp, docs/robustness.md "A step too large for the model")
// and the model's own input signal checked like a held input: an oversized step or a unit mix-up is
// refused (or subdivided, when asked), a NaN from input(t) is refused as NonFiniteInput, and the
// check costs what its documentation says.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "mjukf/mjukf.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/simulation.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace {

using mjukf::OversizedStep;
using mjukf::Status;
using mjukf::testing::sameFilter;
using Tank = mjukf::models::CoupledTank<double>;
using TankUkf = mjukf::Ukf<Tank>;

mjukf::UkfSettingsFor<Tank> tankSettings() {
  mjukf::UkfSettingsFor<Tank> s;
  s.initialCovariance = Eigen::Matrix2d::Identity();
  s.processNoise = 1e-6 * Eigen::Matrix2d::Identity();
  s.measurementNoise = 0.09 * Eigen::Matrix2d::Identity();
  return s;
}

// A tank UKF run to its equilibrium (36 cm in both tanks) with steps of 0.1 s, as a user's would be.
TankUkf convergedTank(const mjukf::UkfSettingsFor<Tank>& settings) {
  TankUkf filter(Tank(), Tank::State(30, 30), Tank::trueParameters(), settings);
  const Tank::State equilibrium = Tank::State::Constant(36);
  for (int k = 0; k < 3000; ++k) {
    EXPECT_TRUE(mjukf::taken(filter.timeUpdate(0.1 * k, 0.1)));
    EXPECT_TRUE(mjukf::taken(filter.measurementUpdate(equilibrium)));
  }
  return filter;
}

TEST(StepCheck, AUnitMixUpIsRefusedAndLeavesTheFilterAsItWas) {
  TankUkf filter = convergedTank(tankSettings());
  const TankUkf before = filter;
  // 1000 "seconds" meant as 1000 ms: the levels left -1822 and 1863 cm before the check.
  EXPECT_EQ(filter.timeUpdate(300.0, 1000.0), Status::StepTooLarge);
  EXPECT_TRUE(sameFilter(filter, before));
  EXPECT_EQ(filter.propagateMean(300.0, 1000.0), Status::StepTooLarge);
  EXPECT_TRUE(sameFilter(filter, before));
  // The same interval in steps the dynamics allow is taken: the time constant is about 37 s.
  EXPECT_EQ(filter.timeUpdate(300.0, 1.0, 1000), Status::Ok);
}

TEST(StepCheck, SubdivideTakesTheOversizedStepInStepsThatPass) {
  mjukf::UkfSettingsFor<Tank> settings = tankSettings();
  settings.stepCheck.onOversized = OversizedStep::Subdivide;
  TankUkf filter = convergedTank(settings);
  ASSERT_EQ(filter.timeUpdate(300.0, 1000.0), Status::Ok);
  EXPECT_DOUBLE_EQ(filter.time(), 1300.0);
  // At equilibrium the levels stay there: within a centimetre of 36 cm (they were within 0.1 cm).
  EXPECT_NEAR(filter.state()(0), 36.0, 1.0);
  EXPECT_NEAR(filter.state()(1), 36.0, 1.0);

  // With too few halvings allowed it is refused after all, and nothing changes.
  settings.stepCheck.maxHalvings = 2;
  TankUkf limited = convergedTank(settings);
  const TankUkf before = limited;
  EXPECT_EQ(limited.timeUpdate(300.0, 1000.0), Status::StepTooLarge);
  EXPECT_TRUE(sameFilter(limited, before));
}

TEST(StepCheck, AcceptTakesEveryStepAsGiven) {
  mjukf::UkfSettingsFor<Tank> settings = tankSettings();
  settings.stepCheck.onOversized = OversizedStep::Accept;
  TankUkf filter = convergedTank(settings);
  const Status status = filter.timeUpdate(300.0, 1000.0);
  // Whatever the step did, it was not refused for its size: the nonsense the check exists to stop.
  EXPECT_NE(status, Status::StepTooLarge);
}

TEST(StepCheck, TheFiltersOfThePaperPassWithoutAChange) {
  // Step doubling at the tank's 0.1 s: the error is far inside the tolerance, so the check changes
  // nothing (bit for bit against the check turned off).
  mjukf::UkfSettingsFor<Tank> off = tankSettings();
  off.stepCheck.onOversized = OversizedStep::Accept;
  EXPECT_TRUE(sameFilter(convergedTank(tankSettings()), convergedTank(off)));
}

// A tank whose input signal and derivative count their calls.
struct CountingTank : Tank {
  mutable long derivatives = 0;
  double nanFrom = std::numeric_limits<double>::infinity();  // input(t) is NaN from this time on
  Input input(double t) const {
    return Input::Constant(t >= nanFrom ? std::numeric_limits<double>::quiet_NaN() : pumpVoltage);
  }
  State derivative(double t, const State& x, const Input& u, const Param& theta) const {
    ++derivatives;
    return Tank::derivative(t, x, u, theta);
  }
};

TEST(StepCheck, RunsOnANewStepAndEveryIntervalCalls) {
  mjukf::UkfSettingsFor<CountingTank> settings;
  settings.initialCovariance = Eigen::Matrix2d::Identity();
  settings.measurementNoise = 0.09 * Eigen::Matrix2d::Identity();
  mjukf::Ukf<CountingTank, mjukf::Rk4<double>> filter(CountingTank(), Tank::State(30, 30), Tank::trueParameters(),
                                                      settings);
  // RK4: 4 derivatives a step; a UKF of n = 2 propagates 5 points; the check 1 + 2 half steps.
  const long perCall = 5 * 4, perCheck = 3 * 4;
  long previous = 0;
  auto cost = [&] {
    const long now = filter.model().derivatives;
    const long spent = now - previous;
    previous = now;
    return spent;
  };
  ASSERT_EQ(filter.timeUpdate(0.0, 0.1), Status::Ok);
  EXPECT_EQ(cost(), perCall + perCheck);  // the first call is checked
  for (int k = 1; k < settings.stepCheck.interval; ++k) {
    ASSERT_EQ(filter.timeUpdate(0.1 * k, 0.1), Status::Ok);
    EXPECT_EQ(cost(), perCall) << "call " << k;
  }
  ASSERT_EQ(filter.timeUpdate(1.6, 0.1), Status::Ok);
  EXPECT_EQ(cost(), perCall + perCheck);  // the interval-th call with the same step
  ASSERT_EQ(filter.timeUpdate(1.7, 0.05), Status::Ok);
  EXPECT_EQ(cost(), perCall + perCheck);  // a new step size
}

TEST(StepCheck, ANonFiniteInputFromTheModelsSignalIsRefusedAsOne) {
  mjukf::UkfSettingsFor<CountingTank> settings;
  settings.initialCovariance = Eigen::Matrix2d::Identity();
  settings.measurementNoise = 0.09 * Eigen::Matrix2d::Identity();
  CountingTank model;
  model.nanFrom = 1.05;  // inside the step from 1.0: only an inner stage time sees it
  for (OversizedStep action : {OversizedStep::Refuse, OversizedStep::Accept}) {
    settings.stepCheck.onOversized = action;
    mjukf::Ukf<CountingTank, mjukf::Rk4<double>> filter(model, Tank::State(30, 30), Tank::trueParameters(), settings);
    for (int k = 0; k < 10; ++k) ASSERT_EQ(filter.timeUpdate(0.1 * k, 0.1), Status::Ok);
    const auto before = filter;
    EXPECT_EQ(filter.timeUpdate(1.0, 0.1), Status::NonFiniteInput);
    EXPECT_TRUE(sameFilter(filter, before));
    EXPECT_EQ(filter.propagateMean(1.0, 0.1), Status::NonFiniteInput);
    EXPECT_TRUE(sameFilter(filter, before));
  }
}

TEST(StepCheck, InvalidSettingsAreNamed) {
  auto errorOf = [](auto change) {
    mjukf::UkfSettingsFor<Tank> s = tankSettings();
    change(s.stepCheck);
    return TankUkf::validate(Tank::State(30, 30), Tank::trueParameters(), s);
  };
  EXPECT_STREQ(errorOf([](auto& c) { c.tolerance = 0; }).setting, "stepCheck.tolerance");
  EXPECT_STREQ(errorOf([](auto& c) { c.tolerance = std::nan(""); }).setting, "stepCheck.tolerance");
  EXPECT_STREQ(errorOf([](auto& c) { c.interval = 0; }).setting, "stepCheck.interval");
  EXPECT_STREQ(errorOf([](auto& c) { c.maxHalvings = 21; }).setting, "stepCheck.maxHalvings");
  EXPECT_STREQ(errorOf([](auto& c) { c.onOversized = OversizedStep(7); }).setting, "stepCheck.onOversized");
  EXPECT_FALSE(errorOf([](auto&) {}));
}

}  // namespace
