// The recovery policy (recovery.hpp, docs/robustness.md "Recovery"): a sensor fault the filter
// followed is undone by going back to the last healthy estimate; a model no recovery can fix uses up
// its recoveries and keeps its alarm; refusals in a row recover at once; all four filters; settings
// named; no allocation.

#define EIGEN_RUNTIME_NO_MALLOC
#undef NDEBUG  // Eigen reports a forbidden allocation through assert: keep it on in Release builds.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "drifting_walk.hpp"
#include "mjukf/mjukf.hpp"

namespace {

using mjukf::Health;
using RandomWalk = mjukf::testing::DriftingWalk<>;

constexpr double kQ = 0.01, kR = 0.04, kDrift = 0.3;

mjukf::JointUkf<RandomWalk> jointFilter() {
  mjukf::JointUkf<RandomWalk>::Settings s;
  s.initialCovariance.setIdentity();
  s.processNoise(0, 0) = kQ;
  s.measurementNoise(0, 0) = kR;
  return {RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), s};
}

// Feeds `updates` steps of the walk with drift kDrift to `filter` (a filter or a Recovering one) from
// update `first` and truth `x`; the sensor reads `fault` too much during [faultStart, faultEnd).
// Returns the truth at the end.
template <class F>
double run(F& filter, int updates, double fault = 0, int faultStart = 0, int faultEnd = 0, unsigned seed = 1,
           int first = 0, double x = 0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  for (int k = first; k < first + updates; ++k) {
    x += kDrift + std::sqrt(kQ) * normal(rng);
    const double offset = k >= faultStart && k < faultEnd ? fault : 0;
    filter.timeUpdate(double(k), 1.0);
    filter.measurementUpdate(RandomWalk::Meas(x + offset + std::sqrt(kR) * normal(rng)));
  }
  return x;
}

TEST(Recovery, ASensorFaultTakesTheParametersBackToTheLastHealthyBlock) {
  // 20 updates reading 3 too much (15 σ of the noise) from update 510: the block of updates 500–549
  // raises InnovationsTooLarge at its end. The filter goes on from its state at update 550, with the
  // drift estimate and its covariance as they were at the end of the healthy block 450–499.
  auto healthy = jointFilter();
  run(healthy, 500);  // the same data up to the end of the last healthy block
  auto plain = jointFilter();
  run(plain, 550, 3.0, 510, 530);
  EXPECT_EQ(plain.health(), Health::InnovationsTooLarge);
  mjukf::Recovering<mjukf::JointUkf<RandomWalk>> recovering(jointFilter());
  const double truth = run(recovering, 550, 3.0, 510, 530);
  ASSERT_EQ(recovering.recoveries(), 1);
  EXPECT_TRUE(recovering.recoveredInLastCall());
  const auto& record = recovering.lastRecovery();
  EXPECT_EQ(record.alarm, Health::InnovationsTooLarge);
  EXPECT_EQ(record.atUpdate, 550);
  EXPECT_EQ(record.alarmTime, 550.0);
  EXPECT_EQ(record.restoredTime, 500.0);
  const auto& f = recovering.filter();
  EXPECT_EQ(f.time(), 550.0);                       // the present time ...
  EXPECT_EQ(f.state(), plain.state());              // ... and state,
  EXPECT_EQ(f.parameters(), healthy.parameters());  // the healthy parameters and covariance,
  EXPECT_EQ(f.parameterCovariance(), healthy.parameterCovariance());
  EXPECT_EQ(f.covariance()(0, 0), 10 * healthy.covariance()(0, 0));  // the state's inflated,
  EXPECT_EQ(f.covariance()(0, 1), 0.0);                              // uncorrelated (a new pass)
  EXPECT_EQ(f.health(), Health::Ok);                                 // and a fresh monitor
  EXPECT_EQ(f.healthStatistics().blocks, 0);
  // Clean data from here on: no further alarm, no further recovery.
  run(recovering, 400, 0, 0, 0, 5, 550, truth);
  EXPECT_EQ(recovering.recoveries(), 1);
  EXPECT_FALSE(recovering.recoveredInLastCall());
}

TEST(Recovery, BlocksWhoseAlarmDoesNotTriggerARecoveryStillMakeCopies) {
  // R ten times the sensor's and the small-innovation alarm asked for: every block raises
  // InnovationsTooSmall (normalised NIS about 0.17 against a lower bound of about 0.4), which does not
  // trigger a recovery by default. A sensor fault like the test above's (30 too much: S is ten times
  // larger) must still go back to the copy of update 500, not to the filter as it was built.
  const auto tooLargeR = [] {
    mjukf::JointUkf<RandomWalk>::Settings s;
    s.initialCovariance.setIdentity();
    s.processNoise(0, 0) = kQ;
    s.measurementNoise(0, 0) = 10 * kR;
    s.health.flagSmallInnovations = true;
    return mjukf::JointUkf<RandomWalk>(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), s);
  };
  auto plain = tooLargeR();
  run(plain, 500);
  EXPECT_EQ(plain.health(), Health::InnovationsTooSmall);
  EXPECT_EQ(plain.healthStatistics().alarmedBlocks, 10);
  mjukf::Recovering<mjukf::JointUkf<RandomWalk>> recovering(tooLargeR());
  run(recovering, 550, 30.0, 510, 530);
  ASSERT_EQ(recovering.recoveries(), 1);
  EXPECT_EQ(recovering.lastRecovery().alarm, Health::InnovationsTooLarge);
  EXPECT_EQ(recovering.lastRecovery().restoredTime, 500.0);
  EXPECT_EQ(recovering.filter().parameters(), plain.parameters());
}

TEST(Recovery, AModelNoRecoveryCanFixUsesUpItsRecoveriesAndKeepsItsAlarm) {
  // A UKF that takes the drift as 0 on a plant drifting by 0.3: every block alarms.
  mjukf::Ukf<RandomWalk>::Settings s;
  s.initialCovariance.setIdentity();
  s.processNoise(0, 0) = kQ;
  s.measurementNoise(0, 0) = kR;
  mjukf::RecoverySettings<double> policy;
  policy.maxRecoveries = 2;
  mjukf::Recovering<mjukf::Ukf<RandomWalk>> filter(
      mjukf::Ukf<RandomWalk>(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), s), policy);
  run(filter, 500);
  EXPECT_EQ(filter.recoveries(), 2);
  EXPECT_EQ(filter.health(), Health::InnovationsTooLarge);
  EXPECT_EQ(filter.lastRecovery().restoredTime, 0.0);  // no block was ever healthy: back to the start
}

TEST(Recovery, RefusalsInARowRecoverAtOnce) {
  mjukf::Recovering<mjukf::JointUkf<RandomWalk>> filter(jointFilter());
  run(filter, 100);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 9; ++k) {
    filter.measurementUpdate(RandomWalk::Meas(nan));
    EXPECT_FALSE(filter.recoveredInLastCall());
  }
  filter.measurementUpdate(RandomWalk::Meas(nan));
  EXPECT_TRUE(filter.recoveredInLastCall());
  EXPECT_EQ(filter.lastRecovery().alarm, Health::RepeatedRefusals);
  EXPECT_EQ(filter.lastRecovery().restoredTime, 100.0);
  EXPECT_EQ(filter.health(), Health::Ok);
}

TEST(Recovery, EveryFilterCanBeWrapped) {
  mjukf::DualUkfSettingsFor<RandomWalk> dual;
  dual.initialCovariance.setIdentity();
  dual.processNoise(0, 0) = kQ;
  dual.measurementNoise(0, 0) = kR;
  dual.initialParameterCovariance(0, 0) = 1;
  mjukf::RecoverySettings<double> policy;
  policy.covarianceInflation = 4;
  mjukf::Recovering<mjukf::DualUkf<RandomWalk>> wrapped(
      mjukf::DualUkf<RandomWalk>(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), dual), policy);
  run(wrapped, 100);
  const auto healthy = wrapped.filter();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int k = 0; k < 10; ++k) wrapped.measurementUpdate(RandomWalk::Meas(nan));
  ASSERT_EQ(wrapped.recoveries(), 1);
  EXPECT_EQ(wrapped.filter().covariance()(0, 0), 4 * healthy.covariance()(0, 0));
  EXPECT_EQ(wrapped.filter().parameterCovariance(), healthy.parameterCovariance());
  EXPECT_EQ(wrapped.filter().parameters(), healthy.parameters());

  mjukf::ModifiedJointUkfSettingsFor<RandomWalk> modified;
  modified.initialCovariance.setIdentity();
  modified.processNoise(0, 0) = kQ;
  modified.measurementNoise(0, 0) = kR;
  modified.automaticTransformation = modified.adaptiveScaling = true;
  mjukf::Recovering<mjukf::ModifiedJointUkf<RandomWalk>> mjukfFilter(
      mjukf::ModifiedJointUkf<RandomWalk>(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), modified));
  run(mjukfFilter, 300, 3.0, 210, 230);
  EXPECT_EQ(mjukfFilter.recoveries(), 1);
  EXPECT_EQ(mjukfFilter.lastRecovery().restoredTime, 200.0);
}

TEST(Recovery, InvalidSettingsAreNamed) {
  mjukf::RecoverySettings<double> s;
  s.covarianceInflation = 1.0;
  const auto a = mjukf::Recovering<mjukf::JointUkf<RandomWalk>>::create(jointFilter(), s);
  ASSERT_FALSE(a.ok());
  EXPECT_STREQ(a.error().setting, "covarianceInflation");
  s = mjukf::RecoverySettings<double>();
  s.maxRecoveries = 0;
  const auto b = mjukf::Recovering<mjukf::JointUkf<RandomWalk>>::create(jointFilter(), s);
  ASSERT_FALSE(b.ok());
  EXPECT_STREQ(b.error().setting, "maxRecoveries");
  EXPECT_THROW(mjukf::Recovering<mjukf::JointUkf<RandomWalk>>(jointFilter(), s), std::invalid_argument);
}

TEST(Recovery, NoCallAllocates) {
  mjukf::Recovering<mjukf::JointUkf<RandomWalk>> filter(jointFilter());
  Eigen::internal::set_is_malloc_allowed(false);
  run(filter, 560, 3.0, 510, 530);  // healthy blocks copied, one recovery
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(filter.recoveries(), 1);
}

}  // namespace
