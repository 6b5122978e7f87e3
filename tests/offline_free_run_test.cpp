// mjukf/offline/free_run.hpp and initial_state.hpp (docs/offline-passes.md): the free run equals
// `simulate` and a hand loop of `stepModel` bit for bit; RMS error and fit % on numbers worked out by
// hand from their definitions, NaN measurements skipped; the initial state of the tank's upper level,
// which is not measured, recovered from five samples of the lower one.

#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "mjukf/integrators/rk4.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/offline/free_run.hpp"
#include "mjukf/offline/initial_state.hpp"
#include "mjukf/simulation.hpp"

namespace {

using Tank = mjukf::models::CoupledTank<double>;
using Rk4 = mjukf::Rk4<double>;
using mjukf::offline::compareOutputs;
using mjukf::offline::freeRun;
using mjukf::offline::Sampling;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

bool bitwiseEqual(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * std::size_t(a.size())) == 0;
}

// The tank measured through an output that takes the input: y = (h₁, k_flow u), the pump's inflow.
struct TankWithInflow : Tank {
  Meas measurement(const State& x, const Input& u, const Param& theta) const { return Meas(x(0), theta(0) * u(0)); }
};

// The tank with only the lower level measured (the upper one is the state to estimate).
struct LowerLevelTank : Tank {
  static constexpr int MeasDim = 1;
  using Meas = Eigen::Matrix<double, 1, 1>;
  Meas measurement(const State& x, const Param&) const { return Meas(x(1)); }
};

// Pump voltages about the constant 5 V, one per sample.
std::vector<Tank::Input> inputRecord(std::size_t n) {
  std::vector<Tank::Input> u(n);
  for (std::size_t k = 0; k < n; ++k) u[k] = Tank::Input(5.0 + std::sin(0.7 * double(k)));
  return u;
}

// ---- Free run ------------------------------------------------------------------------------------------

// One sub-step per sample and a constant input: the free run is `simulate` measured at every step.
TEST(FreeRun, EqualsSimulateBitForBit) {
  const Tank model;
  const Tank::State x0(8, 3);
  const Sampling<double> sampling{0.25, 0.1, 1};
  constexpr std::size_t n = 200;
  const std::vector<Tank::Input> inputs(n, Tank::Input(4.0));
  std::vector<Tank::Meas> outputs(n);
  const Tank::State last = freeRun(model, Rk4(), x0, Tank::trueParameters(), inputs, sampling, outputs);

  std::vector<Tank::Meas> expected;
  const Tank::State end = mjukf::simulate(
      model, Rk4(), x0, Tank::Input(4.0), Tank::trueParameters(), 0.25, 0.1, long(n) - 1,
      [&](long, double, const Tank::State& x) { expected.push_back(model.measurement(x, Tank::trueParameters())); });
  ASSERT_EQ(expected.size(), n);
  for (std::size_t k = 0; k < n; ++k) ASSERT_TRUE(bitwiseEqual(outputs[k], expected[k])) << "sample " << k;
  EXPECT_TRUE(bitwiseEqual(last, end));
}

// Sub-steps, inputs that change from sample to sample and a measurement that takes the input: a hand
// loop of stepModel with u_k held over [t_k, t_k+1) and ŷ_k = g(x_k, u_k, θ).
TEST(FreeRun, EqualsAHandLoopWithSubStepsAndHeldInputs) {
  const TankWithInflow model;
  const Tank::State x0(2, 7);
  const Tank::Param theta(5.5);
  const Sampling<double> sampling{1.0, 0.5, 4};
  constexpr std::size_t n = 60;
  const auto inputs = inputRecord(n);
  std::vector<Tank::Meas> outputs(n);
  freeRun(model, Rk4(), x0, theta, inputs, sampling, outputs);

  Tank::State x = x0;
  const double h = 0.5 / 4;
  for (std::size_t k = 0; k < n; ++k) {
    const double t = 1.0 + double(k) * 0.5;
    ASSERT_TRUE(bitwiseEqual(outputs[k], model.measurement(x, inputs[k], theta))) << "sample " << k;
    for (int j = 0; j < 4; ++j) x = mjukf::stepModel(model, Rk4(), t + double(j) * h, h, x, inputs[k], theta);
  }
  EXPECT_EQ(outputs[0](1), 5.5 * 5.0) << "ŷ₀ takes u₀";
}

// Without an input record, the model's own signal u(t) at every stage time, as simulate takes it.
TEST(FreeRun, WithTheModelsOwnSignalEqualsSimulate) {
  Tank model;
  model.pumpVoltage = 3.0;
  const Sampling<double> sampling{0.0, 0.2, 3};
  std::vector<Tank::Meas> outputs(40);
  freeRun(model, Rk4(), Tank::State(1, 1), Tank::trueParameters(), sampling, outputs);
  Tank::State x(1, 1);
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    ASSERT_TRUE(bitwiseEqual(outputs[k], x)) << "sample " << k;
    x = mjukf::simulate(model, Rk4(), x, Tank::trueParameters(), 0.2 * double(k), 0.2 / 3, 3,
                        [](long, double, const Tank::State&) {});
  }
}

TEST(FreeRun, RefusesBadArguments) {
  const Tank model;
  std::vector<Tank::Meas> outputs(5);
  const auto inputs = inputRecord(4);
  EXPECT_THROW(
      freeRun(model, Rk4(), Tank::State(1, 1), Tank::trueParameters(), inputs, Sampling<double>{0, 1, 1}, outputs),
      std::invalid_argument)
      << "fewer inputs than outputs";
  const auto enough = inputRecord(5);
  for (const Sampling<double>& bad :
       {Sampling<double>{0, 0, 1}, Sampling<double>{0, -1, 1}, Sampling<double>{0, 1, 0}, Sampling<double>{kNan, 1, 1}})
    EXPECT_THROW(freeRun(model, Rk4(), Tank::State(1, 1), Tank::trueParameters(), enough, bad, outputs),
                 std::invalid_argument);
}

// ---- Validation metrics -----------------------------------------------------------------------------------

using Scalar1 = Eigen::Matrix<double, 1, 1>;
std::vector<Scalar1> column(std::initializer_list<double> values) {
  std::vector<Scalar1> v;
  for (double x : values) v.push_back(Scalar1(x));
  return v;
}

// y = (1, 2, 3, 4), ŷ = (1, 2, 3, 6): Σ (y − ŷ)² = 4 over 4 samples, RMS = 1; ȳ = 2.5,
// Σ (y − ȳ)² = 2.25 + 0.25 + 0.25 + 2.25 = 5, fit = 100 (1 − √(4/5)) = 100 (1 − 0.894427190999916) %.
TEST(ValidationMetrics, RmsAndFitOfAHandWorkedExample) {
  const auto c = compareOutputs(column({1, 2, 3, 4}), column({1, 2, 3, 6}));
  EXPECT_EQ(c.samples(0), 4);
  EXPECT_DOUBLE_EQ(c.rmsError(0), 1.0);
  EXPECT_NEAR(c.fitPercent(0), 10.5572809000084, 1e-11);
}

// A NaN measurement is skipped, whatever was simulated there: the example above with two missing
// samples between its four gives the same numbers.
TEST(ValidationMetrics, SkipsNanMeasurements) {
  const auto c = compareOutputs(column({1, kNan, 2, 3, kNan, 4}), column({1, 50, 2, 3, kNan, 6}));
  EXPECT_EQ(c.samples(0), 4);
  EXPECT_DOUBLE_EQ(c.rmsError(0), 1.0);
  EXPECT_NEAR(c.fitPercent(0), 10.5572809000084, 1e-11);
}

// Two outputs, each with its own missing samples, over a range of samples [1, 4):
//   output 0: y = (2, 4, 6) and ŷ = (2, 4, 9) → RMS √(9/3) = √3; ȳ = 4, Σ (y − ȳ)² = 8, fit 100 (1 − √(9/8));
//   output 1: y = (NaN, 1, 3) and ŷ = (0, 2, 3) → RMS √(1/2); ȳ = 2, Σ (y − ȳ)² = 2, fit 100 (1 − √(1/2)).
TEST(ValidationMetrics, PerOutputOverARange) {
  using Two = Eigen::Vector2d;
  const std::vector<Two> measured{Two(100, 100), Two(2, kNan), Two(4, 1), Two(6, 3), Two(-7, 8)};
  const std::vector<Two> simulated{Two(0, 0), Two(2, 0), Two(4, 2), Two(9, 3), Two(0, 0)};
  const auto c = compareOutputs(measured, simulated, 1, 4);
  EXPECT_EQ(c.samples(0), 3);
  EXPECT_EQ(c.samples(1), 2);
  EXPECT_DOUBLE_EQ(c.rmsError(0), std::sqrt(3.0));
  EXPECT_DOUBLE_EQ(c.rmsError(1), std::sqrt(0.5));
  EXPECT_NEAR(c.fitPercent(0), 100 * (1 - std::sqrt(9.0 / 8.0)), 1e-12);
  EXPECT_NEAR(c.fitPercent(1), 100 * (1 - std::sqrt(0.5)), 1e-12);
}

// A perfect match is 100 %; a constant measured output has no fit; no samples, no metrics; a simulated
// NaN against a measurement is not skipped.
TEST(ValidationMetrics, EdgeCases) {
  const auto perfect = compareOutputs(column({1, 3, 2}), column({1, 3, 2}));
  EXPECT_EQ(perfect.rmsError(0), 0.0);
  EXPECT_EQ(perfect.fitPercent(0), 100.0);
  const auto constant = compareOutputs(column({2, 2, 2}), column({1, 2, 3}));
  EXPECT_DOUBLE_EQ(constant.rmsError(0), std::sqrt(2.0 / 3.0));
  EXPECT_TRUE(std::isnan(constant.fitPercent(0)));
  const auto none = compareOutputs(column({kNan, kNan}), column({1, 2}));
  EXPECT_EQ(none.samples(0), 0);
  EXPECT_TRUE(std::isnan(none.rmsError(0)) && std::isnan(none.fitPercent(0)));
  const auto failed = compareOutputs(column({1, 2, 3}), column({1, kNan, 3}));
  EXPECT_TRUE(std::isnan(failed.rmsError(0)) && std::isnan(failed.fitPercent(0)));
  EXPECT_THROW(compareOutputs(column({1, 2}), column({1, 2}), 1, 3), std::invalid_argument);
  EXPECT_THROW(compareOutputs(column({1, 2}), column({1}), 0, 2), std::invalid_argument);
}

// ---- Initial state ------------------------------------------------------------------------------------------

// The plant: levels (8, 3) cm at t = 0, pump voltages about 5 V held over periods of 1 s, RK4 with 10
// sub-steps; five samples of the lower level h₂, i.e. 4 s over which h₁ reaches it through
// ∂ḣ₂/∂h₁ = c₁ / (2 √h₁ A₂) ≈ 0.057 /s.
const LowerLevelTank kPlant;
const Tank::State kTruth(8, 3);
const Sampling<double> kSampling{0.0, 1.0, 10};
constexpr std::size_t kSamples = 5;

std::vector<LowerLevelTank::Meas> lowerLevel(const Tank::State& x0) {
  std::vector<LowerLevelTank::Meas> y(kSamples);
  freeRun(kPlant, Rk4(), x0, Tank::trueParameters(), inputRecord(kSamples), kSampling, y);
  return y;
}

using Settings = mjukf::offline::InitialStateSettings<double, 2, 1>;

// Noise-free: the residual is zero at the truth, so the error left is the last step's, below the
// stopping test's 1e-10 (|x| + 1) ≈ 1e-9 cm, and Gauss–Newton's convergence makes the error after it
// far smaller still; the floor is the outputs' rounding, ε |y| / |∂y/∂h₁| ≈ 1e-15 · 3 / 0.1 ≈ 3e-14 cm.
// 1e-8 cm is ten times the stopping bound.
TEST(InitialState, RecoversTheUnmeasuredLevelFromFiveNoiseFreeSamples) {
  const auto y = lowerLevel(kTruth);
  Settings settings;
  settings.fixed << false, true;  // h₂ is measured: held at y₀
  const auto fixed = mjukf::offline::estimateInitialState(kPlant, Rk4(), Tank::trueParameters(), inputRecord(kSamples),
                                                          y, kSampling, kSamples, Tank::State(2, y[0](0)), settings);
  EXPECT_TRUE(fixed.converged);
  EXPECT_TRUE(fixed.observable);
  EXPECT_NEAR(fixed.state(0), 8.0, 1e-8);
  EXPECT_EQ(fixed.state(1), y[0](0)) << "a fixed component is not moved";
  EXPECT_EQ(fixed.covariance(1, 1), 0.0);
  EXPECT_GT(fixed.initialCost, 1e3 * fixed.cost);
  std::printf("h1 from 2 cm: %.15g in %d iterations\n", fixed.state(0), fixed.iterations);

  // Both levels free, from a poor guess of both.
  const auto free = mjukf::offline::estimateInitialState(kPlant, Rk4(), Tank::trueParameters(), inputRecord(kSamples),
                                                         y, kSampling, kSamples, Tank::State(20, 1));
  EXPECT_TRUE(free.converged);
  EXPECT_NEAR(free.state(0), 8.0, 1e-8);
  EXPECT_NEAR(free.state(1), 3.0, 1e-8);
}

// The bound with noise, from the linearisation: with white noise σ on y, x̂₀ − x₀ ≈ (JᵀJ)⁻¹ Jᵀ e has the
// covariance σ² (JᵀJ)⁻¹, J = ∂(ŷ₀ … ŷ₄)/∂x₀. J is taken here by central differences of the free run
// (which equals simulate, above), independently of the estimator's forward differences. The estimator's
// covariance must agree with it, and over 300 noise draws the errors of ĥ₁ stay within 5 σ_h₁ with a
// spread within 20 % of σ_h₁ (the sample standard deviation of 300 draws is within ±8 % at 2 σ).
TEST(InitialState, WithNoiseTheErrorIsWithinTheLinearisedBound) {
  constexpr double sigma = 0.01;
  const auto exact = lowerLevel(kTruth);
  Eigen::Matrix<double, kSamples, 2> j;
  for (int i = 0; i < 2; ++i) {
    const double delta = 1e-5;
    Tank::State up = kTruth, down = kTruth;
    up(i) += delta;
    down(i) -= delta;
    const auto yUp = lowerLevel(up), yDown = lowerLevel(down);
    for (std::size_t k = 0; k < kSamples; ++k) j(int(k), i) = (yUp[k](0) - yDown[k](0)) / (2 * delta);
  }
  const Eigen::Matrix2d expectedCovariance = sigma * sigma * (j.transpose() * j).inverse();
  const double sigmaH1 = std::sqrt(expectedCovariance(0, 0));
  std::printf("sigma(h1) = %.4g cm, sigma(h2) = %.4g cm for sigma(y) = %.3g cm\n", sigmaH1,
              std::sqrt(expectedCovariance(1, 1)), sigma);

  Settings settings;
  settings.noiseStd << sigma;
  std::mt19937_64 random(11);
  std::normal_distribution<double> normal(0.0, sigma);
  double sum = 0, sumSquares = 0, largest = 0;
  constexpr int draws = 300;
  for (int d = 0; d < draws; ++d) {
    auto y = exact;
    for (auto& v : y) v(0) += normal(random);
    const auto e = mjukf::offline::estimateInitialState(kPlant, Rk4(), Tank::trueParameters(), inputRecord(kSamples), y,
                                                        kSampling, kSamples, Tank::State(4, y[0](0)), settings);
    ASSERT_TRUE(e.converged) << "draw " << d;
    if (d == 0) {
      EXPECT_NEAR(e.covariance(0, 0), expectedCovariance(0, 0), 0.05 * expectedCovariance(0, 0))
          << "the estimator's covariance against the test's";
    }
    const double error = e.state(0) - kTruth(0);
    sum += error;
    sumSquares += error * error;
    largest = std::max(largest, std::abs(error));
  }
  const double mean = sum / draws, spread = std::sqrt(sumSquares / draws - mean * mean);
  std::printf("over %d draws: mean error %.3g cm, spread %.4g cm, largest %.3g cm\n", draws, mean, spread, largest);
  EXPECT_LT(largest, 5 * sigmaH1);
  EXPECT_NEAR(spread, sigmaH1, 0.2 * sigmaH1);
  EXPECT_LT(std::abs(mean), 4 * sigmaH1 / std::sqrt(double(draws)));
}

// One sample says nothing of h₁ (y₀ = h₂₀): not observable, and said so.
TEST(InitialState, OneSampleDoesNotDetermineTheUpperLevel) {
  const auto y = lowerLevel(kTruth);
  const auto e = mjukf::offline::estimateInitialState(kPlant, Rk4(), Tank::trueParameters(), inputRecord(kSamples), y,
                                                      kSampling, 1, Tank::State(4, 1));
  EXPECT_FALSE(e.observable);
  EXPECT_TRUE(std::isinf(e.covariance(0, 0)));
  EXPECT_EQ(e.state(0), 4.0) << "h₁ has no reason to move";
  EXPECT_NEAR(e.state(1), 3.0, 1e-8) << "h₂ is y₀";
}

TEST(InitialState, RefusesBadArguments) {
  const auto y = lowerLevel(kTruth);
  const auto inputs = inputRecord(kSamples);
  EXPECT_THROW(
      mjukf::offline::estimateInitialState(kPlant, Rk4(), Tank::trueParameters(), inputs, y, kSampling, 0, kTruth),
      std::invalid_argument);
  EXPECT_THROW(
      mjukf::offline::estimateInitialState(kPlant, Rk4(), Tank::trueParameters(), inputs, y, kSampling, 6, kTruth),
      std::invalid_argument);
  Settings bad;
  bad.noiseStd << 0.0;
  EXPECT_THROW(
      mjukf::offline::estimateInitialState(kPlant, Rk4(), Tank::trueParameters(), inputs, y, kSampling, 5, kTruth, bad),
      std::invalid_argument);
}

}  // namespace
