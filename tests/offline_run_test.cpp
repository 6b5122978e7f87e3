// The offline run (mjukf/offline/run.hpp) gives what stepping the filter by hand gives, bit for bit,
// for all four filters, and reports a refused step's status; the unscented RTS smoother
// (offline/smoother.hpp) on a nonlinear plant is closer to the truth than the filter it smooths.

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/models/dc_motor.hpp"
#include "mjukf/models/van_der_pol.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/offline/run.hpp"
#include "mjukf/offline/smoother.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/ukf.hpp"

namespace {

using mjukf::Status;
using Motor = mjukf::models::DcMotor<double>;
using Rk4 = mjukf::Rk4<double>;
constexpr double kStep = 0.01;
constexpr long kSamples = 120;
// u is NaN here: the time update is refused. The filter then skips an interval the motor turns on in
// (about 1 rad), and the gate refuses most measurements after it: the run reports each one.
constexpr long kNanInput = 100;
constexpr long kOutlier = 70;  // y is far off here: the gate refuses the update
constexpr long kMissing = 55;  // y is NaN here: the update has nothing present

// Settings that run (the test compares calls, not accuracy), with a χ² gate.
template <class Filter>
typename Filter::Settings settingsFor() {
  typename Filter::Settings s;
  s.measurementNoise(0, 0) = 1e-4;
  s.gate = decltype(s.gate)::chiSquare(0.9999);
  s.initialCovariance.setZero();
  s.initialCovariance.template topLeftCorner<2, 2>().diagonal() << 1e-2, 1.0;
  s.processNoise.setZero();
  s.processNoise.template topLeftCorner<2, 2>().diagonal() << 1e-6, 1e-2;
  if constexpr (std::is_same_v<Filter, mjukf::JointUkf<Motor, Rk4>>) {
    s.initialCovariance.template bottomRightCorner<2, 2>().diagonal() << 1e-5, 1e-7;
  } else if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<Motor, Rk4>>) {
    s.scaling = 1e-5;
    s.transformation << 1.0, -1.0;
  } else if constexpr (std::is_same_v<Filter, mjukf::DualUkf<Motor, Rk4>>) {
    s.initialParameterCovariance.diagonal() << 1e-5, 1e-7;
  }
  return s;
}

template <class Filter>
Filter makeFilter() {
  return Filter(Motor(), Motor::State(0.0, 0.0), Motor::trueParameters(), settingsFor<Filter>());
}

struct MotorRecording {
  std::vector<Motor::Input> u;
  std::vector<Motor::Meas> y;
};

MotorRecording motorRecording() {
  std::mt19937_64 random(3);
  std::normal_distribution<double> normal;
  const Motor motor;
  MotorRecording r;
  Motor::State x(0.0, 0.0);
  for (long k = 0; k < kSamples; ++k) {
    const Motor::Input u = motor.input(k * kStep);
    x = mjukf::stepModel(motor, Rk4(), k * kStep, kStep, x, u, Motor::trueParameters());
    Motor::Meas y = motor.measurement(x, Motor::trueParameters()) + Motor::Meas(0.01 * normal(random));
    r.u.push_back(k == kNanInput ? Motor::Input(NAN) : u);
    if (k == kOutlier) y(0) += 100.0;
    if (k == kMissing) y(0) = NAN;
    r.y.push_back(y);
  }
  return r;
}

template <class A, class B>
bool identical(const A& a, const B& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() && (a.array() == b.array()).all();
}

template <class Filter>
class OfflineRun : public ::testing::Test {};
using Filters = ::testing::Types<mjukf::Ukf<Motor, Rk4>, mjukf::JointUkf<Motor, Rk4>,
                                 mjukf::ModifiedJointUkf<Motor, Rk4>, mjukf::DualUkf<Motor, Rk4>>;
TYPED_TEST_SUITE(OfflineRun, Filters);

TYPED_TEST(OfflineRun, EqualsSteppingByHandBitForBitAndReportsRefusals) {
  using Filter = TypeParam;
  const MotorRecording r = motorRecording();
  Filter byRun = makeFilter<Filter>();
  std::vector<mjukf::offline::Sample<Filter>> trajectory;
  const auto summary = mjukf::offline::run(byRun, mjukf::offline::dataSet<Motor>(0.0, kStep, r.y, r.u), trajectory);
  ASSERT_EQ(trajectory.size(), static_cast<std::size_t>(kSamples));
  EXPECT_EQ(summary.samples, kSamples);
  long refusedTimeUpdates = 0, refusedMeasurementUpdates = 0;

  Filter byHand = makeFilter<Filter>();
  for (long k = 0; k < kSamples; ++k) {
    const mjukf::offline::Sample<Filter>& s = trajectory[k];
    const Status timeUpdate = byHand.timeUpdate(k * kStep, kStep, r.u[k]);
    Status measurementUpdate = timeUpdate;
    if (mjukf::taken(timeUpdate)) {
      if (std::isnan(r.y[k](0)))
        measurementUpdate = byHand.measurementUpdate(r.y[k], mjukf::MeasurementMask<1>(false));
      else
        measurementUpdate = byHand.measurementUpdate(r.y[k]);
    }
    refusedTimeUpdates += mjukf::taken(timeUpdate) ? 0 : 1;
    refusedMeasurementUpdates += mjukf::taken(timeUpdate) && !mjukf::taken(measurementUpdate) ? 1 : 0;
    ASSERT_EQ(s.timeUpdate, timeUpdate) << k;
    ASSERT_EQ(s.measurementUpdate, measurementUpdate) << k;
    ASSERT_EQ(s.time, (k + 1) * kStep) << k;
    ASSERT_EQ(s.measuredComponents, std::isnan(r.y[k](0)) ? 0 : 1) << k;
    ASSERT_TRUE(identical(s.state, byHand.state())) << k;
    ASSERT_TRUE(identical(s.parameters, byHand.parameters())) << k;
    ASSERT_TRUE(identical(s.covariance, byHand.covariance())) << k;
    ASSERT_TRUE(identical(s.diagnostics.innovation, byHand.lastUpdate().innovation)) << k;
    ASSERT_TRUE(identical(s.diagnostics.innovationCovariance, byHand.lastUpdate().innovationCovariance)) << k;
    ASSERT_EQ(s.diagnostics.nis, byHand.lastUpdate().nis) << k;
    ASSERT_EQ(s.health, byHand.health()) << k;
    if constexpr (std::is_same_v<Filter, mjukf::DualUkf<Motor, Rk4>> ||
                  std::is_same_v<Filter, mjukf::ModifiedJointUkf<Motor, Rk4>>) {
      ASSERT_TRUE(identical(s.parameterCovariance, byHand.parameterCovariance())) << k;
    }
    if constexpr (std::is_same_v<Filter, mjukf::JointUkf<Motor, Rk4>>) {
      ASSERT_TRUE(identical(s.parameterCovariance, byHand.covariance().template bottomRightCorner<2, 2>())) << k;
    }
  }
  EXPECT_EQ(summary.refusedTimeUpdates, refusedTimeUpdates);
  EXPECT_EQ(summary.refusedMeasurementUpdates, refusedMeasurementUpdates);
  EXPECT_EQ(refusedTimeUpdates, 1);
  for (long k = 0; k < kNanInput; ++k)  // before the skipped interval, only the outlier is refused
    EXPECT_EQ(trajectory[k].taken(), k != kOutlier) << k;
  EXPECT_EQ(trajectory[kNanInput].timeUpdate, Status::NonFiniteInput);
  EXPECT_EQ(trajectory[kNanInput].measurementUpdate, Status::NonFiniteInput);  // not called
  EXPECT_FALSE(trajectory[kNanInput].taken());
  EXPECT_EQ(trajectory[kOutlier].measurementUpdate, Status::MeasurementRejected);
  EXPECT_TRUE(mjukf::taken(trajectory[kMissing].measurementUpdate));
  EXPECT_TRUE(identical(byRun.state(), byHand.state()));
}

// The smoother steps over a refused time update as the filter did: nothing moved there.
TEST(OfflineSmoother, RefusedTimeUpdateIsTheIdentity) {
  using Filter = mjukf::JointUkf<Motor, Rk4>;
  const MotorRecording r = motorRecording();
  const auto data = mjukf::offline::dataSet<Motor>(0.0, kStep, r.y, r.u);
  Filter filter = makeFilter<Filter>();
  std::vector<mjukf::offline::Sample<Filter>> filtered;
  mjukf::offline::run(filter, data, filtered);
  std::vector<mjukf::offline::SmoothedSample<Filter>> smoothed;
  ASSERT_TRUE(mjukf::offline::smooth(filter, data, filtered, smoothed).ok());
  EXPECT_TRUE(identical(smoothed[kNanInput - 1].mean, smoothed[kNanInput].mean));
  EXPECT_TRUE(identical(smoothed[kNanInput - 1].covariance, smoothed[kNanInput].covariance));
}

// ---- The smoother on a nonlinear plant -------------------------------------------------------------

using Oscillator = mjukf::models::VanDerPol<double>;
constexpr double kOscillatorStep = 0.1;
constexpr long kOscillatorSamples = 300;  // 30 s, about five periods at μ = 1
const Oscillator::Param kMu(1.0);

struct Truth {
  std::vector<Oscillator::State> x;  // at the end of each sample
  std::vector<Oscillator::Meas> y;   // x₁ with noise; x₂ missing (NaN): the smoother must infer it
};

// The oscillator with process noise (σ = 0.01 per sample on each state), simulated with RK4 at a tenth
// of the filters' step; x₁ measured with σ = 0.1.
Truth oscillatorTruth(unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  const Oscillator plant;
  Truth truth;
  Oscillator::State x(2.0, 0.0);
  for (long k = 0; k < kOscillatorSamples; ++k) {
    for (int s = 0; s < 10; ++s)
      x = mjukf::stepModel(plant, Rk4(), (10 * k + s) * kOscillatorStep / 10, kOscillatorStep / 10, x, kMu);
    x += 0.01 * Oscillator::State(normal(random), normal(random));
    truth.x.push_back(x);
    truth.y.push_back(Oscillator::Meas(x(0) + 0.1 * normal(random), NAN));
  }
  return truth;
}

struct Rmse {
  double filtered, smoothed;
};

// The RMSE of the states (and, for JUKF, of μ) of the filter and of the smoother against the truth.
template <class Filter, class Settings>
Rmse oscillatorRmse(const Truth& truth, const Oscillator::Param& guess, const Settings& settings, bool ofMu) {
  Filter filter(Oscillator(), Oscillator::State(1.5, 0.5), guess, settings);
  const auto data = mjukf::offline::dataSet<Oscillator>(0.0, kOscillatorStep, truth.y);
  std::vector<mjukf::offline::Sample<Filter>> filtered;
  const auto summary = mjukf::offline::run(filter, data, filtered);
  EXPECT_EQ(summary.refusedTimeUpdates + summary.refusedMeasurementUpdates, 0);
  std::vector<mjukf::offline::SmoothedSample<Filter>> smoothed;
  EXPECT_TRUE(mjukf::offline::smooth(filter, data, filtered, smoothed).ok());
  double f = 0, s = 0;
  for (long k = 0; k < kOscillatorSamples; ++k) {
    if (ofMu) {
      f += (filtered[k].parameters - kMu).squaredNorm();
      s += (smoothed[k].mean.template tail<1>() - kMu).squaredNorm();
    } else {
      f += (filtered[k].state - truth.x[k]).squaredNorm();
      s += (smoothed[k].state() - truth.x[k]).squaredNorm();
    }
  }
  return {std::sqrt(f / kOscillatorSamples), std::sqrt(s / kOscillatorSamples)};
}

// Over five seeds, the smoothed states' RMSE against the truth is well below the filter's, for the UKF
// (μ known) and the JUKF (μ estimated from 0.5), and the JUKF's smoothed μ is closer to the truth
// (every sample's μ estimate uses the whole record). Measured ratios smoothed / filtered over seeds
// 1–5 (printed): UKF states 0.62–0.77, JUKF states 0.47–0.69, JUKF μ 0.14–0.33; the bounds (0.85,
// 0.8, 0.5) leave a margin. The linear case (offline_linear_test.cpp) checks the arithmetic itself.
TEST(OfflineSmoother, ReducesTheRmseOfANonlinearPlant) {
  mjukf::UkfSettingsFor<Oscillator> ukf;
  ukf.initialCovariance.diagonal() << 0.25, 0.25;
  ukf.processNoise.diagonal() << 1e-4, 1e-4;
  ukf.measurementNoise.diagonal() << 0.01, 1.0;  // the second component is never present
  mjukf::JointUkfSettingsFor<Oscillator> joint;
  joint.initialCovariance.diagonal() << 0.25, 0.25, 0.25;
  joint.processNoise.diagonal() << 1e-4, 1e-4, 1e-8;
  joint.measurementNoise = ukf.measurementNoise;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const Truth truth = oscillatorTruth(seed);
    const Rmse states = oscillatorRmse<mjukf::Ukf<Oscillator, Rk4>>(truth, kMu, ukf, false);
    const Rmse jointStates =
        oscillatorRmse<mjukf::JointUkf<Oscillator, Rk4>>(truth, Oscillator::Param(0.5), joint, false);
    const Rmse mu = oscillatorRmse<mjukf::JointUkf<Oscillator, Rk4>>(truth, Oscillator::Param(0.5), joint, true);
    std::printf("seed %u: UKF states %.4f -> %.4f, JUKF states %.4f -> %.4f, JUKF mu %.4f -> %.4f\n", seed,
                states.filtered, states.smoothed, jointStates.filtered, jointStates.smoothed, mu.filtered, mu.smoothed);
    EXPECT_LT(states.smoothed, 0.85 * states.filtered) << seed;
    EXPECT_LT(jointStates.smoothed, 0.8 * jointStates.filtered) << seed;
    EXPECT_LT(mu.smoothed, 0.5 * mu.filtered) << seed;
  }
}

}  // namespace
