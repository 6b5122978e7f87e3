// The health monitor (health.hpp, docs/robustness.md "The health monitor"): each test of the monitor
// raised by innovations or parameters built to raise it and silent on white ones of the right size;
// every filter's health() on cases of each kind; the settings' validation; float.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "drifting_walk.hpp"
#include "mjukf/health.hpp"
#include "mjukf/mjukf.hpp"

namespace {

using mjukf::Health;
using mjukf::Status;
using Monitor = mjukf::detail::HealthMonitor<double, 2, 1>;
using Param1 = Eigen::Matrix<double, 1, 1>;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Feeds `updates` innovations of two components with unit P_yy: e = scale · (AR(1) with coefficient rho,
// of unit variance), the parameter (if moving) drifting by `drift` per update with σ = 1.
Monitor feed(double scale, double rho, long updates, double drift = 0, unsigned seed = 1) {
  mjukf::HealthSettings<double> settings;
  settings.flagSmallInnovations = true;  // every test an alarm
  Monitor monitor(settings);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  Eigen::Vector2d e = Eigen::Vector2d(normal(rng), normal(rng));
  const Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  Param1 theta(0);
  for (long k = 0; k < updates; ++k) {
    e = rho * e + std::sqrt(1 - rho * rho) * Eigen::Vector2d(normal(rng), normal(rng));
    const Eigen::Vector2d innovation = scale * e;
    theta(0) += drift;
    monitor.observeUpdate(innovation, covariance, innovation.squaredNorm(), nullptr, theta, Param1(1), Param1(-kInf),
                          Param1(kInf));
  }
  return monitor;
}

TEST(HealthMonitor, WhiteInnovationsOfTheRightSizeRaiseNoAlarmOverALongRun) {
  // 10⁵ updates, 2000 blocks, three tests each at 1e-6: a false alarm has probability 0.6 %.
  const Monitor monitor = feed(1.0, 0.0, 100000);
  EXPECT_EQ(monitor.health(), Health::Ok);
  EXPECT_EQ(monitor.statistics().blocks, 2000);
  EXPECT_EQ(monitor.statistics().alarmedBlocks, 0);
  // The last block's NIS per degree of freedom is χ²(100)/100: within 0.5 of 1 by 3.5 σ.
  EXPECT_NEAR(monitor.statistics().normalisedNis, 1.0, 0.5);
}

TEST(HealthMonitor, TheBoundsAreTheChiSquareQuantilesOfTheBlock) {
  const Monitor monitor = feed(1.0, 0.0, 50);
  const double alpha = 1e-6;  // the default
  EXPECT_NEAR(monitor.statistics().nisUpperBound * 100, mjukf::chiSquareQuantile(1 - alpha / 2, 100), 1e-6);
  EXPECT_NEAR(monitor.statistics().nisLowerBound * 100, mjukf::chiSquareQuantile(alpha / 2, 100), 1e-6);
  EXPECT_NEAR(std::pow(monitor.statistics().autocorrelationBound, 2), mjukf::chiSquareQuantile(1 - alpha / 2, 1), 1e-9);
}

TEST(HealthMonitor, EachInnovationTestRaisesItsAlarm) {
  // Twice the size P_yy says: NIS ≈ 4 per degree of freedom against a bound of about 1.9.
  EXPECT_EQ(feed(2.0, 0.0, 50).health(), Health::InnovationsTooLarge);
  // A third of it: NIS ≈ 0.11 against a lower bound of about 0.4 (with flagSmallInnovations).
  EXPECT_EQ(feed(1.0 / 3, 0.0, 50).health(), Health::InnovationsTooSmall);
  // Correlated with coefficient 0.8: √50 · 0.8 ≈ 5.7 against a bound of 5.0 (the NIS stays near 1).
  const Monitor correlated = feed(1.0, 0.8, 200);
  EXPECT_EQ(correlated.health(), Health::InnovationsCorrelated);
  EXPECT_GT(correlated.statistics().autocorrelationScore, correlated.statistics().autocorrelationBound);
}

TEST(HealthMonitor, AParameterMovingFarBeyondItsSigmaIsARunaway) {
  // 0.5 σ an update: 24.5 σ between the first and last update of a block, against 10.
  const Monitor monitor = feed(1.0, 0.0, 50, 0.5);
  EXPECT_EQ(monitor.health(), Health::ParameterRunaway);
  EXPECT_NEAR(monitor.statistics().parameterMotionSigmas, 24.5, 1e-9);
  // 0.1 σ an update is 4.9 σ a block: no alarm.
  EXPECT_EQ(feed(1.0, 0.0, 500, 0.1).health(), Health::Ok);
}

TEST(HealthMonitor, AnUnboundedSigmaIsARunaway) {
  // The MJUKF reports σ = +∞ once the error covariance it follows has overflowed.
  mjukf::HealthSettings<double> settings;
  Monitor monitor(settings);
  const Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  std::mt19937_64 rng(4);
  std::normal_distribution<double> normal;
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector2d e(normal(rng), normal(rng));
    const Param1 sigma(k < 60 ? 1.0 : kInf);
    monitor.observeUpdate(e, covariance, e.squaredNorm(), nullptr, Param1(0), sigma, Param1(-kInf), Param1(kInf));
    if (k == 49) {
      EXPECT_EQ(monitor.health(), Health::Ok);
    }
  }
  EXPECT_EQ(monitor.health(), Health::ParameterRunaway);
}

// One block of 50 updates of two components with unit P_yy: innovations of size `scale` (1: white ones
// of the right size, 10: an alarm).
void feedBlock(Monitor& monitor, double scale, std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  const Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d e = scale * Eigen::Vector2d(normal(rng), normal(rng));
    monitor.observeUpdate(e, covariance, e.squaredNorm(), nullptr, Param1(0), Param1(-1), Param1(-kInf), Param1(kInf));
  }
}

TEST(HealthMonitor, AnAlarmStandsUntilMostRememberedBlocksAreCleanAndTheFirstAlarmStays) {
  mjukf::HealthSettings<double> settings;
  Monitor monitor(settings);
  std::mt19937_64 rng(2);
  feedBlock(monitor, 10, rng);
  EXPECT_EQ(monitor.health(), Health::InnovationsTooLarge);
  EXPECT_EQ(monitor.statistics().alarmAtUpdate, 50);
  feedBlock(monitor, 1, rng);
  EXPECT_EQ(monitor.statistics().lastBlock, Health::Ok);     // the block after is healthy ...
  EXPECT_EQ(monitor.health(), Health::InnovationsTooLarge);  // ... but one of two blocks alarmed
  feedBlock(monitor, 1, rng);
  EXPECT_EQ(monitor.health(), Health::Ok);  // one of three: the filter is healthy now ...
  EXPECT_EQ(monitor.statistics().firstAlarm, Health::InnovationsTooLarge);  // ... which once was not
  EXPECT_EQ(monitor.statistics().alarmedBlocks, 1);
  EXPECT_EQ(monitor.statistics().blocksInMemory, 3);
  EXPECT_EQ(monitor.statistics().alarmedInMemory, 1);
  monitor.clearAlarm();
  EXPECT_EQ(monitor.statistics().firstAlarm, Health::Ok);
  EXPECT_EQ(monitor.statistics().alarmAtUpdate, 0);
}

TEST(HealthMonitor, AnAlarmIsRaisedAtOnceAndStandsWhileHalfTheRememberedBlocksRaisedOne) {
  mjukf::HealthSettings<double> settings;  // verdictMemory 10
  Monitor monitor(settings);
  std::mt19937_64 rng(3);
  for (int b = 0; b < 10; ++b) feedBlock(monitor, 1, rng);
  EXPECT_EQ(monitor.health(), Health::Ok);
  // One alarmed block after ten clean ones raises its alarm at once; the next clean block withdraws it
  // (one of ten).
  feedBlock(monitor, 10, rng);
  EXPECT_EQ(monitor.health(), Health::InnovationsTooLarge);
  feedBlock(monitor, 1, rng);
  EXPECT_EQ(monitor.health(), Health::Ok);
  EXPECT_EQ(monitor.statistics().alarmedInMemory, 1);
  // A filter that went wrong for five blocks and then read quiet: the alarm stands for as long as five of
  // the last ten blocks alarmed, and no longer.
  for (int b = 0; b < 10; ++b) feedBlock(monitor, 1, rng);
  for (int b = 0; b < 5; ++b) feedBlock(monitor, 10, rng);
  for (int b = 0; b < 5; ++b) {
    feedBlock(monitor, 1, rng);
    EXPECT_EQ(monitor.health(), Health::InnovationsTooLarge) << "clean block " << b + 1;
  }
  EXPECT_EQ(monitor.statistics().alarmedInMemory, 5);
  feedBlock(monitor, 1, rng);
  EXPECT_EQ(monitor.health(), Health::Ok);
  // A new pass forgets the remembered blocks; the first alarm and the counts stay.
  for (int b = 0; b < 3; ++b) feedBlock(monitor, 10, rng);
  monitor.restartBlock();
  EXPECT_EQ(monitor.health(), Health::Ok);
  EXPECT_EQ(monitor.statistics().blocksInMemory, 0);
  EXPECT_EQ(monitor.statistics().alarmedBlocks, 9);
  EXPECT_EQ(monitor.statistics().firstAlarm, Health::InnovationsTooLarge);
}

TEST(HealthMonitor, AStandingAlarmIsNamedByTheLatestAlarmedBlock) {
  // Large innovations, then correlated ones (a coefficient of 0.95: √50 · 0.95 ≈ 6.7 against 5.0, the NIS
  // near 1), then a clean block: two of three alarmed, so the alarm stands, named by the later one.
  mjukf::HealthSettings<double> settings;
  Monitor monitor(settings);
  std::mt19937_64 rng(6);
  feedBlock(monitor, 10, rng);
  std::normal_distribution<double> normal;
  const Eigen::Matrix2d covariance = Eigen::Matrix2d::Identity();
  Eigen::Vector2d e(normal(rng), normal(rng));
  for (int k = 0; k < 50; ++k) {
    e = 0.95 * e + std::sqrt(1 - 0.95 * 0.95) * Eigen::Vector2d(normal(rng), normal(rng));
    monitor.observeUpdate(e, covariance, e.squaredNorm(), nullptr, Param1(0), Param1(-1), Param1(-kInf), Param1(kInf));
  }
  ASSERT_EQ(monitor.statistics().lastBlock, Health::InnovationsCorrelated);
  feedBlock(monitor, 1, rng);
  EXPECT_EQ(monitor.health(), Health::InnovationsCorrelated);
  EXPECT_EQ(monitor.statistics().latestAlarm, Health::InnovationsCorrelated);
  EXPECT_EQ(monitor.statistics().firstAlarm, Health::InnovationsTooLarge);
}

TEST(HealthMonitor, ClearForgetsTheRememberedBlocks) {
  mjukf::HealthSettings<double> settings;
  Monitor monitor(settings);
  std::mt19937_64 rng(7);
  for (int b = 0; b < 5; ++b) feedBlock(monitor, 10, rng);
  monitor.clear();
  feedBlock(monitor, 1, rng);
  EXPECT_EQ(monitor.health(), Health::Ok);
  EXPECT_EQ(monitor.statistics().blocksInMemory, 1);
  EXPECT_EQ(monitor.statistics().alarmedInMemory, 0);
}

TEST(HealthMonitor, TheLongestMemoryHoldsSixteenBlocks) {
  mjukf::HealthSettings<double> settings;
  settings.verdictMemory = 16;
  Monitor monitor(settings);
  std::mt19937_64 rng(8);
  for (int b = 0; b < 16; ++b) feedBlock(monitor, 1, rng);
  for (int b = 0; b < 8; ++b) feedBlock(monitor, 10, rng);
  for (int b = 0; b < 8; ++b) feedBlock(monitor, 1, rng);  // eight of the last sixteen: it stands
  EXPECT_EQ(monitor.statistics().blocksInMemory, 16);
  EXPECT_EQ(monitor.statistics().alarmedInMemory, 8);
  EXPECT_EQ(monitor.health(), Health::InnovationsTooLarge);
  feedBlock(monitor, 1, rng);  // seven of sixteen
  EXPECT_EQ(monitor.health(), Health::Ok);
}

TEST(HealthMonitor, AMemoryOfOneBlockIsTheLastBlocksVerdict) {
  mjukf::HealthSettings<double> settings;
  settings.verdictMemory = 1;
  Monitor monitor(settings);
  std::mt19937_64 rng(5);
  for (int b = 0; b < 5; ++b) feedBlock(monitor, 10, rng);
  EXPECT_EQ(monitor.health(), Health::InnovationsTooLarge);
  feedBlock(monitor, 1, rng);
  EXPECT_EQ(monitor.health(), Health::Ok);
}

TEST(HealthMonitor, RefusalsInARowRaiseTheirAlarmAndATakenCallEndsTheStreak) {
  using mjukf::detail::CallKind;
  mjukf::HealthSettings<double> settings;
  Monitor monitor(settings);
  for (int k = 0; k < 9; ++k) monitor.observeStatus(Status::NonFiniteMeasurement, CallKind::Measurement);
  monitor.observeStatus(Status::Ok, CallKind::Measurement);
  for (int k = 0; k < 9; ++k) monitor.observeStatus(Status::MeasurementRejected, CallKind::Measurement);
  EXPECT_EQ(monitor.health(), Health::Ok);
  monitor.observeStatus(Status::NonFiniteResult, CallKind::Measurement);
  EXPECT_EQ(monitor.health(), Health::RepeatedRefusals);
}

TEST(HealthMonitor, RefusedMeasurementsCountAcrossTakenTimeUpdates) {
  // A filter whose gate rejects every measurement (it lost lock) while its time updates are taken.
  using mjukf::detail::CallKind;
  mjukf::HealthSettings<double> settings;
  Monitor monitor(settings);
  for (int k = 0; k < 9; ++k) {
    monitor.observeStatus(Status::Ok, CallKind::Propagation);
    monitor.observeStatus(Status::MeasurementRejected, CallKind::Measurement);
  }
  EXPECT_EQ(monitor.health(), Health::Ok);
  EXPECT_EQ(monitor.statistics().refusalsInARow, 9);
  monitor.observeStatus(Status::Ok, CallKind::Propagation);
  monitor.observeStatus(Status::MeasurementRejected, CallKind::Measurement);
  EXPECT_EQ(monitor.health(), Health::RepeatedRefusals);
}

// ---------------------------------------------------------------------------------------------------
// The filters: a scalar random walk with a drift θ per step, measured with noise: x⁺ = x + θ + w, y = x + v.

using RandomWalk = mjukf::testing::DriftingWalk<>;
constexpr double kQ = 0.01, kR = 0.04;

// The plant with drift `theta`, and a filter of type F whose settings `configure` sets; `rScale` is the
// filter's R over the truth's.
template <class Filter, class Configure>
Filter runOnRandomWalk(double theta, long updates, double rScale, Configure configure, unsigned seed = 1) {
  typename Filter::Settings s;
  s.initialCovariance.setIdentity();
  s.processNoise.setZero();
  s.processNoise(0, 0) = kQ;
  s.measurementNoise(0, 0) = kR * rScale;
  s.redrawPointsForUpdate = true;  // the textbook Kalman filter on this linear model
  configure(s);
  Filter filter(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), s);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  double x = 0;
  for (long k = 0; k < updates; ++k) {
    x += theta + std::sqrt(kQ) * normal(rng);
    EXPECT_TRUE(mjukf::taken(filter.timeUpdate(double(k), 1.0)));
    EXPECT_TRUE(mjukf::taken(filter.measurementUpdate(RandomWalk::Meas(x + std::sqrt(kR) * normal(rng)))));
  }
  return filter;
}

TEST(FilterHealth, AConsistentUkfStaysOkOverALongRun) {
  const auto filter = runOnRandomWalk<mjukf::Ukf<RandomWalk>>(0.0, 20000, 1.0, [](auto&) {});
  EXPECT_EQ(filter.health(), Health::Ok);
  EXPECT_EQ(filter.healthStatistics().blocks, 400);
  EXPECT_EQ(filter.healthStatistics().updates, 20000);
}

TEST(FilterHealth, AnRFarTooSmallOrTooLargeIsFlaggedInTheFirstBlock) {
  const auto small = runOnRandomWalk<mjukf::Ukf<RandomWalk>>(0.0, 50, 0.01, [](auto&) {});
  EXPECT_EQ(small.health(), Health::InnovationsTooLarge);
  EXPECT_EQ(small.healthStatistics().alarmAtUpdate, 50);
  // R a hundred times too large: innovations far smaller than P_yy, counted by default and an alarm
  // when asked for. The gain is then so small that the estimate lags the walk, and the whiteness test,
  // which runs when the NIS test raises nothing, sees its innovations correlated.
  const auto large = runOnRandomWalk<mjukf::Ukf<RandomWalk>>(0.0, 50, 100.0, [](auto&) {});
  EXPECT_EQ(large.health(), Health::InnovationsCorrelated);
  EXPECT_EQ(large.healthStatistics().smallInnovationBlocks, 1);
  EXPECT_LT(large.healthStatistics().normalisedNis, large.healthStatistics().nisLowerBound);
  const auto flagged =
      runOnRandomWalk<mjukf::Ukf<RandomWalk>>(0.0, 50, 100.0, [](auto& s) { s.health.flagSmallInnovations = true; });
  EXPECT_EQ(flagged.health(), Health::InnovationsTooSmall);
  EXPECT_EQ(flagged.healthStatistics().smallInnovationBlocks, 1);
}

TEST(FilterHealth, AWrongFixedParameterIsFlagged) {
  // The UKF takes the drift θ = 0 as known; the plant drifts by 0.3 a step. The filter lags by a
  // constant: its innovations have a mean of about 0.3 / K ≈ 0.8 against a standard deviation of
  // about 0.25, a NIS near 10.
  const auto filter = runOnRandomWalk<mjukf::Ukf<RandomWalk>>(0.3, 500, 1.0, [](auto&) {});
  EXPECT_EQ(filter.health(), Health::InnovationsTooLarge);
  EXPECT_EQ(filter.healthStatistics().alarmAtUpdate, 50);
  // The joint UKF estimates the drift and stays healthy.
  const auto joint =
      runOnRandomWalk<mjukf::JointUkf<RandomWalk>>(0.3, 500, 1.0, [](auto& s) { s.initialCovariance(1, 1) = 1.0; });
  EXPECT_NEAR(joint.parameters()(0), 0.3, 0.05);
  EXPECT_EQ(joint.health(), Health::Ok);
}

TEST(FilterHealth, AJointUkfWhoseParameterIsHeldAtABoundSaysSo) {
  // The drift is 0.12; the bounds say it is at most 0.1. The 0.02 left over barely shows in the
  // innovations (a bias of a fifth of their σ), so the bound is what raises the alarm.
  const auto filter = runOnRandomWalk<mjukf::JointUkf<RandomWalk>>(0.12, 500, 1.0, [](auto& s) {
    s.initialCovariance(1, 1) = 1.0;
    s.parameterBounds.lower << -0.1;
    s.parameterBounds.upper << 0.1;
  });
  EXPECT_EQ(filter.parameters()(0), 0.1);
  EXPECT_EQ(filter.health(), Health::ParameterAtBound);
}

TEST(FilterHealth, RepeatedRefusalsAreFlaggedInEveryFilter) {
  auto refuse = [](auto filter) {
    for (int k = 0; k < 10; ++k)
      EXPECT_EQ(filter.measurementUpdate(RandomWalk::Meas(std::nan(""))), Status::NonFiniteMeasurement);
    return filter.health();
  };
  mjukf::UkfSettingsFor<RandomWalk> ukf;
  ukf.initialCovariance.setIdentity();
  ukf.measurementNoise.setIdentity();
  EXPECT_EQ(refuse(mjukf::Ukf<RandomWalk>(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), ukf)),
            Health::RepeatedRefusals);
  mjukf::JointUkfSettingsFor<RandomWalk> jukf;
  jukf.initialCovariance.setIdentity();
  jukf.measurementNoise.setIdentity();
  EXPECT_EQ(refuse(mjukf::JointUkf<RandomWalk>(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), jukf)),
            Health::RepeatedRefusals);
  mjukf::ModifiedJointUkfSettingsFor<RandomWalk> mjukfSettings;
  mjukfSettings.initialCovariance.setIdentity();
  mjukfSettings.measurementNoise.setIdentity();
  mjukfSettings.transformation.setOnes();
  EXPECT_EQ(refuse(mjukf::ModifiedJointUkf<RandomWalk>(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0),
                                                       mjukfSettings)),
            Health::RepeatedRefusals);
  mjukf::DualUkfSettingsFor<RandomWalk> dual;
  dual.initialCovariance.setIdentity();
  dual.measurementNoise.setIdentity();
  dual.initialParameterCovariance.setIdentity();
  EXPECT_EQ(refuse(mjukf::DualUkf<RandomWalk>(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), dual)),
            Health::RepeatedRefusals);
}

TEST(FilterHealth, ResetClearsTheHealthAndDisabledMonitorsStaySilent) {
  auto filter = runOnRandomWalk<mjukf::Ukf<RandomWalk>>(0.0, 50, 0.01, [](auto&) {});
  ASSERT_EQ(filter.health(), Health::InnovationsTooLarge);
  filter.reset(RandomWalk::State(0), Eigen::Matrix<double, 1, 1>::Identity());
  EXPECT_EQ(filter.health(), Health::Ok);
  EXPECT_EQ(filter.healthStatistics().updates, 0);
  const auto off = runOnRandomWalk<mjukf::Ukf<RandomWalk>>(0.0, 50, 0.01, [](auto& s) { s.health.enabled = false; });
  EXPECT_EQ(off.health(), Health::Ok);
  EXPECT_EQ(off.healthStatistics().blocks, 0);
}

TEST(FilterHealth, FloatFiltersRunTheSameTests) {
  mjukf::HealthSettings<float> settings;
  mjukf::detail::HealthMonitor<float, 1, 1> monitor(settings);
  const Eigen::Matrix<float, 1, 1> covariance = Eigen::Matrix<float, 1, 1>::Identity();
  const Eigen::Matrix<float, 1, 1> none = Eigen::Matrix<float, 1, 1>::Constant(-1);
  const Eigen::Matrix<float, 1, 1> lower =
      Eigen::Matrix<float, 1, 1>::Constant(-std::numeric_limits<float>::infinity());
  for (int k = 0; k < 50; ++k)
    monitor.observeUpdate(Eigen::Matrix<float, 1, 1>(3.0f), covariance, 9.0f, nullptr, none, none, lower, -lower);
  EXPECT_EQ(monitor.health(), Health::InnovationsTooLarge);
}

TEST(FilterHealth, AGatedFilterThatLostLockIsFlagged) {
  // The gate is set at χ²(1) 0.999; after 100 good updates the sensor reads 100 higher, so every
  // measurement is rejected while the time updates between them are taken.
  mjukf::UkfSettingsFor<RandomWalk> s;
  s.initialCovariance.setIdentity();
  s.processNoise(0, 0) = kQ;
  s.measurementNoise(0, 0) = kR;
  s.gate = mjukf::MeasurementGate<double, 1>::chiSquare(0.999);
  mjukf::Ukf<RandomWalk> filter(RandomWalk(), RandomWalk::State(0), RandomWalk::Param(0), s);
  std::mt19937_64 rng(4);
  std::normal_distribution<double> normal;
  double x = 0;
  for (int k = 0; k < 120; ++k) {
    x += std::sqrt(kQ) * normal(rng);
    ASSERT_TRUE(mjukf::taken(filter.timeUpdate(double(k), 1.0)));
    const double offset = k < 100 ? 0.0 : 100.0;
    const Status status = filter.measurementUpdate(RandomWalk::Meas(x + offset + std::sqrt(kR) * normal(rng)));
    EXPECT_EQ(mjukf::taken(status), k < 100) << "update " << k;
  }
  EXPECT_EQ(filter.health(), Health::RepeatedRefusals);
}

TEST(FilterHealth, InvalidSettingsAreNamed) {
  auto errorOf = [](auto change) {
    mjukf::UkfSettingsFor<RandomWalk> s;
    s.initialCovariance.setIdentity();
    s.measurementNoise.setIdentity();
    change(s.health);
    return mjukf::Ukf<RandomWalk>::validate(RandomWalk::State(0), RandomWalk::Param(0), s);
  };
  EXPECT_STREQ(errorOf([](auto& h) { h.window = 9; }).setting, "health.window");
  EXPECT_STREQ(errorOf([](auto& h) { h.falseAlarmProbability = 0.5; }).setting, "health.falseAlarmProbability");
  EXPECT_STREQ(errorOf([](auto& h) { h.falseAlarmProbability = std::nan(""); }).setting,
               "health.falseAlarmProbability");
  EXPECT_STREQ(errorOf([](auto& h) { h.runawaySigmas = 0; }).setting, "health.runawaySigmas");
  EXPECT_STREQ(errorOf([](auto& h) { h.refusalStreak = 0; }).setting, "health.refusalStreak");
  EXPECT_STREQ(errorOf([](auto& h) { h.verdictMemory = 0; }).setting, "health.verdictMemory");
  EXPECT_STREQ(errorOf([](auto& h) { h.verdictMemory = 17; }).setting, "health.verdictMemory");
  EXPECT_FALSE(errorOf([](auto& h) { h.verdictMemory = 16; }));
  EXPECT_FALSE(errorOf([](auto&) {}));
}

}  // namespace
