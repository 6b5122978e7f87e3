// The example programs' simulated plant with process noise (examples/support/common/simulation.hpp,
// the study's `matched` scenario): the noise enters at the end of every measurement interval and
// nowhere else, with the covariances asked for, and leaves the measurement noise's draws as they were.

#include <cmath>
#include <cstddef>
#include <stdexcept>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "common/simulation.hpp"
#include "mjukf/integrators/rk4.hpp"

namespace {

using mjukf::examples::ProcessNoise;
using mjukf::examples::simulatePlant;
using mjukf::examples::SimulationOptions;

// A plant that stands still (ẋ = 0, exactly so under RK4): every change of its state is process noise.
struct StillPlant {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 2, MeasDim = 2, InputDim = 0;
  using State = Eigen::Vector2d;
  using Param = Eigen::Vector2d;
  using Meas = Eigen::Vector2d;
  using Input = Eigen::Matrix<double, 0, 1>;
  static Param trueParameters() { return Param(3.0, 4.0); }
  State derivative(double, const State&, const Input&, const Param&) const { return State::Zero(); }
  Meas measurement(const State& x, const Param&) const { return x; }
};

constexpr int kEvery = 4;
constexpr long kIntervals = 1000;

// 1000 whole intervals of 4 steps and 2 steps more (a last, partial interval, which no time update ends).
SimulationOptions<StillPlant> options() {
  SimulationOptions<StillPlant> o;
  o.stepSize = 0.01;
  o.duration = double(kIntervals * kEvery + 2) * o.stepSize;
  o.seed = 7;
  o.initialState = StillPlant::State(1.0, 2.0);
  o.absoluteNoise = StillPlant::Meas(0.1, 0.2);
  ProcessNoise<StillPlant> noise;
  noise.every = kEvery;
  noise.state << 4e-2, 1e-2, 1e-2, 1e-2;  // correlated: the square root is not a diagonal's
  noise.parameters << 1e-4, 0, 0, 9e-4;
  o.processNoise = noise;
  return o;
}

// |Ĉᵢⱼ − Cᵢⱼ| within 4 standard errors of the sample covariance of N zero-mean Gaussian draws,
// var(Ĉᵢⱼ) = (Cᵢⱼ² + Cᵢᵢ Cⱼⱼ) / N: a seed fails it with probability about 6e-5 per entry.
void expectSampleCovariance(const Eigen::Matrix2d& sample, const Eigen::Matrix2d& c, long n) {
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      EXPECT_NEAR(sample(i, j), c(i, j), 4 * std::sqrt((c(i, j) * c(i, j) + c(i, i) * c(j, j)) / double(n)))
          << "(" << i << ", " << j << ")";
}

TEST(PlantSimulation, ProcessNoiseEntersAtTheEndOfEveryIntervalWithItsCovariance) {
  const auto o = options();
  const auto data = simulatePlant(StillPlant(), o, mjukf::Rk4<double>());
  ASSERT_EQ(data.rows(), kIntervals * kEvery + 3);
  EXPECT_EQ(data.stateTruth.front(), o.initialState);
  EXPECT_EQ(data.parameterTruth.front(), StillPlant::trueParameters());
  Eigen::Matrix2d stateSample = Eigen::Matrix2d::Zero(), parameterSample = Eigen::Matrix2d::Zero();
  long intervals = 0;
  for (long k = 1; k < data.rows(); ++k) {
    const auto row = static_cast<std::size_t>(k);
    const Eigen::Vector2d dx = data.stateTruth[row] - data.stateTruth[row - 1];
    const Eigen::Vector2d dtheta = data.parameterTruth[row] - data.parameterTruth[row - 1];
    if (k % kEvery != 0) {  // inside an interval, and the partial one at the end: nothing moves
      EXPECT_EQ(dx, Eigen::Vector2d::Zero()) << "row " << k;
      EXPECT_EQ(dtheta, Eigen::Vector2d::Zero()) << "row " << k;
      continue;
    }
    stateSample += dx * dx.transpose();
    parameterSample += dtheta * dtheta.transpose();
    ++intervals;
  }
  ASSERT_EQ(intervals, kIntervals);
  expectSampleCovariance(stateSample / double(intervals), o.processNoise->state, intervals);
  expectSampleCovariance(parameterSample / double(intervals), o.processNoise->parameters, intervals);
}

// A singular Q (the second state without process noise) leaves that state where it started, and moves
// the first as before; a Q that is not semi-definite is refused.
TEST(PlantSimulation, ASingularQLeavesItsNullDirectionStill) {
  auto o = options();
  o.processNoise->state << 4e-2, 0, 0, 0;
  const auto data = simulatePlant(StillPlant(), o, mjukf::Rk4<double>());
  long moved = 0;
  for (std::size_t k = 0; k < data.stateTruth.size(); ++k) {
    EXPECT_EQ(data.stateTruth[k](1), o.initialState(1)) << k;
    moved += data.stateTruth[k](0) != o.initialState(0);
  }
  EXPECT_GT(moved, kIntervals * kEvery / 2);
  o.processNoise->state << 4e-2, 0, 0, -1e-6;
  EXPECT_THROW(simulatePlant(StillPlant(), o, mjukf::Rk4<double>()), std::invalid_argument);
}

// The process noise has a stream of its own: a seed's measurement noise is the same draws with it.
TEST(PlantSimulation, TheMeasurementNoiseIsTheSameDrawsWithAndWithoutProcessNoise) {
  auto o = options();
  const auto noisy = simulatePlant(StillPlant(), o, mjukf::Rk4<double>());
  o.processNoise.reset();
  const auto still = simulatePlant(StillPlant(), o, mjukf::Rk4<double>());
  ASSERT_EQ(noisy.rows(), still.rows());
  for (std::size_t k = 0; k < still.y.size(); ++k) {
    EXPECT_EQ(still.stateTruth[k], o.initialState) << k;
    const Eigen::Vector2d noiseWith = noisy.y[k] - noisy.stateTruth[k], noiseWithout = still.y[k] - still.stateTruth[k];
    EXPECT_LE((noiseWith - noiseWithout).cwiseAbs().maxCoeff(), 1e-14) << k;  // y = x + e, rounded once each way
  }
}

}  // namespace
