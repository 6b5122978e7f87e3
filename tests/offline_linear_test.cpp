// The offline tools on a linear-Gaussian model (mjukf/offline/): there the UKF that redraws its points
// for the update is the Kalman filter (ukf_test.cpp), so its unscented RTS smoother must be the linear
// RTS smoother and its log-likelihood the Kalman filter's, both to rounding. The reference below is
// the textbook filter and smoother in plain Eigen, written independently of the library.
//
// Tolerances: every quantity here is O(1) (states, P between 1e-3 and 1), the covariances are well
// conditioned, and the two computations differ only in the order of their floating-point operations:
// measured, the largest differences are 4e-15 (smoothed means), 1e-15 (smoothed covariances) and
// 2e-16 (log-likelihood, relative). The tests allow 1e-12, 250 times the largest of them and far
// below a modelling difference: Q added per step instead of once per time update (three steps per
// sample) moves the smoothed means by 2e-2.

#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "mjukf/joint_ukf.hpp"
#include "mjukf/offline/likelihood.hpp"
#include "mjukf/offline/run.hpp"
#include "mjukf/offline/smoother.hpp"
#include "mjukf/ukf.hpp"

namespace {

// x⁺ = F x + b θ + B u, y = C x, in discrete time: linear in x for a known θ (Ukf), and in [x; θ] jointly
// (JointUkf, θ constant), so that both filters are Kalman filters of a linear system.
struct LinearPlant {
  using Scalar = double;
  static constexpr int StateDim = 3, ParamDim = 1, MeasDim = 2, InputDim = 1;
  using State = Eigen::Matrix<double, StateDim, 1>;
  using Param = Eigen::Matrix<double, ParamDim, 1>;
  using Meas = Eigen::Matrix<double, MeasDim, 1>;
  using Input = Eigen::Matrix<double, InputDim, 1>;

  Eigen::Matrix3d F = (Eigen::Matrix3d() << 0.95, 0.1, 0.0,  //
                       -0.1, 0.9, 0.05,                      //
                       0.0, 0.02, 0.8)
                          .finished();
  Eigen::Vector3d b = Eigen::Vector3d(0.0, 0.1, 0.05);
  Eigen::Vector3d B = Eigen::Vector3d(0.0, 0.2, 0.1);
  Eigen::Matrix<double, 2, 3> C = (Eigen::Matrix<double, 2, 3>() << 1, 0, 0, 0, 0, 1).finished();

  State transition(double, double, const State& x, const Input& u, const Param& theta) const {
    return F * x + b * theta(0) + B * u(0);
  }
  Meas measurement(const State& x, const Param&) const { return C * x; }
};

// The Kalman filter and RTS smoother of z⁺ = A z + c_k (applied `steps` times per sample, Q added once),
// y = H z + v, v ~ N(0, R), with NaN components of y missing; and the log-likelihood of the innovations.
template <int L>
struct Reference {
  using Vector = Eigen::Matrix<double, L, 1>;
  using Matrix = Eigen::Matrix<double, L, L>;
  std::vector<Vector> filteredMean, predictedMean, smoothedMean;
  std::vector<Matrix> filteredCov, predictedCov, smoothedCov;
  double logLikelihood = 0;

  Reference(const Matrix& A, const std::vector<Vector>& offsets, int steps, const Eigen::Matrix<double, 2, L>& H,
            const Matrix& Q, const Eigen::Matrix2d& R, Vector x, Matrix P, const std::vector<Eigen::Vector2d>& y) {
    const long n = static_cast<long>(y.size());
    Matrix Asteps = Matrix::Identity();
    for (int s = 0; s < steps; ++s) Asteps = A * Asteps;
    for (long k = 0; k < n; ++k) {
      for (int s = 0; s < steps; ++s) {
        x = A * x + offsets[k];
        P = A * P * A.transpose();
      }
      P += Q;
      predictedMean.push_back(x);
      predictedCov.push_back(P);
      std::vector<int> present;
      for (int j = 0; j < 2; ++j)
        if (!std::isnan(y[k](j))) present.push_back(j);
      const int m = static_cast<int>(present.size());
      if (m > 0) {
        Eigen::MatrixXd Hr(m, L), Rr(m, m);
        Eigen::VectorXd yr(m);
        for (int i = 0; i < m; ++i) {
          Hr.row(i) = H.row(present[i]);
          yr(i) = y[k](present[i]);
          for (int j = 0; j < m; ++j) Rr(i, j) = R(present[i], present[j]);
        }
        const Eigen::MatrixXd S = Hr * P * Hr.transpose() + Rr;
        const Eigen::VectorXd nu = yr - Hr * x;
        const Eigen::MatrixXd K = P * Hr.transpose() * S.inverse();
        x += K * nu;
        P -= K * S * K.transpose();
        logLikelihood += -0.5 * (m * std::log(2 * M_PI) + std::log(S.determinant()) + nu.dot(S.inverse() * nu));
      }
      filteredMean.push_back(x);
      filteredCov.push_back(P);
    }
    smoothedMean = filteredMean;
    smoothedCov = filteredCov;
    for (long k = n - 2; k >= 0; --k) {
      const Matrix G = filteredCov[k] * Asteps.transpose() * predictedCov[k + 1].inverse();
      smoothedMean[k] = filteredMean[k] + G * (smoothedMean[k + 1] - predictedMean[k + 1]);
      smoothedCov[k] = filteredCov[k] + G * (smoothedCov[k + 1] - predictedCov[k + 1]) * G.transpose();
    }
  }
};

constexpr double kTolerance = 1e-12;  // see the top of the file
const LinearPlant::Param kTheta(0.7);

// 60 samples of the plant with process and measurement noise, every 7th missing its first component
// and every 11th missing both.
struct Recording {
  std::vector<LinearPlant::Meas> y;
  std::vector<LinearPlant::Input> u;
  int steps = 1;
  mjukf::offline::DataSet<LinearPlant> data() const {
    return mjukf::offline::dataSet<LinearPlant>(0.0, 0.1, y, u, steps);
  }
};

Recording record(int steps, unsigned seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal;
  const LinearPlant plant;
  Recording r;
  r.steps = steps;
  LinearPlant::State x(1.0, -0.5, 0.3);
  for (int k = 0; k < 60; ++k) {
    const LinearPlant::Input u(std::sin(0.3 * k));
    for (int s = 0; s < steps; ++s) x = plant.transition(0, 0, x, u, kTheta);
    x += 0.03 * Eigen::Vector3d(normal(random), normal(random), normal(random));
    LinearPlant::Meas y = plant.C * x + 0.1 * LinearPlant::Meas(normal(random), normal(random));
    if (k % 7 == 3) y(0) = NAN;
    if (k % 11 == 5) y.setConstant(NAN);
    r.u.push_back(u);
    r.y.push_back(y);
  }
  return r;
}

mjukf::UkfSettingsFor<LinearPlant> ukfSettings() {
  mjukf::UkfSettingsFor<LinearPlant> s;
  s.initialCovariance = Eigen::Vector3d(0.5, 0.3, 0.2).asDiagonal();
  s.initialCovariance(0, 1) = s.initialCovariance(1, 0) = 0.1;
  s.processNoise = 1e-3 * Eigen::Matrix3d::Identity();
  s.measurementNoise = 1e-2 * Eigen::Matrix2d::Identity();
  s.redrawPointsForUpdate = true;  // the textbook Kalman filter on a linear model
  return s;
}

mjukf::JointUkfSettingsFor<LinearPlant> jointSettings() {
  mjukf::JointUkfSettingsFor<LinearPlant> s;
  s.initialCovariance.setZero();
  s.initialCovariance.topLeftCorner<3, 3>() = ukfSettings().initialCovariance;
  s.initialCovariance(3, 3) = 0.25;
  s.initialCovariance(3, 1) = s.initialCovariance(1, 3) = 0.05;
  s.processNoise.setZero();
  s.processNoise.topLeftCorner<3, 3>() = 1e-3 * Eigen::Matrix3d::Identity();
  s.processNoise(3, 3) = 1e-6;
  s.measurementNoise = 1e-2 * Eigen::Matrix2d::Identity();
  s.redrawPointsForUpdate = true;
  return s;
}

const LinearPlant::State kStart(0.8, -0.3, 0.0);

// The reference of the UKF with θ known: z = x, A = F, c_k = b θ + B u_k.
Reference<3> ukfReference(const Recording& r) {
  const LinearPlant plant;
  std::vector<Eigen::Vector3d> offsets;
  for (const auto& u : r.u) offsets.push_back(plant.b * kTheta(0) + plant.B * u(0));
  const auto s = ukfSettings();
  return Reference<3>(plant.F, offsets, r.steps, plant.C, s.processNoise, s.measurementNoise, kStart,
                      s.initialCovariance, r.y);
}

// The reference of the JUKF: z = [x; θ], A = [F b; 0 1], c_k = [B u_k; 0], H = [C 0].
Reference<4> jointReference(const Recording& r, double thetaGuess) {
  const LinearPlant plant;
  Eigen::Matrix4d A = Eigen::Matrix4d::Identity();
  A.topLeftCorner<3, 3>() = plant.F;
  A.topRightCorner<3, 1>() = plant.b;
  std::vector<Eigen::Vector4d> offsets;
  for (const auto& u : r.u) offsets.push_back((Eigen::Vector4d() << plant.B * u(0), 0.0).finished());
  Eigen::Matrix<double, 2, 4> H = Eigen::Matrix<double, 2, 4>::Zero();
  H.leftCols<3>() = plant.C;
  const auto s = jointSettings();
  return Reference<4>(A, offsets, r.steps, H, s.processNoise, s.measurementNoise,
                      (Eigen::Vector4d() << kStart, thetaGuess).finished(), s.initialCovariance, r.y);
}

template <int L, class Smoothed>
void expectSmootherEqualsRts(const Reference<L>& ref, const std::vector<Smoothed>& smoothed) {
  ASSERT_EQ(smoothed.size(), ref.smoothedMean.size());
  double meanError = 0, covError = 0;
  for (std::size_t k = 0; k < smoothed.size(); ++k) {
    meanError = std::max(meanError, (smoothed[k].mean - ref.smoothedMean[k]).cwiseAbs().maxCoeff());
    covError = std::max(covError, (smoothed[k].covariance - ref.smoothedCov[k]).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(meanError, kTolerance);
  EXPECT_LT(covError, kTolerance);
  // The smoother did something: the first sample's smoothed mean is not the filtered one.
  EXPECT_GT((ref.smoothedMean[0] - ref.filteredMean[0]).norm(), 1e-3);
  std::printf("largest difference from the linear RTS smoother: mean %.2e, covariance %.2e\n", meanError, covError);
}

void expectUkfSmootherEqualsRts(int steps) {
  const Recording r = record(steps, 5);
  mjukf::Ukf<LinearPlant> filter(LinearPlant(), kStart, kTheta, ukfSettings());
  std::vector<mjukf::offline::Sample<decltype(filter)>> filtered;
  const mjukf::offline::RunSummary summary = mjukf::offline::run(filter, r.data(), filtered);
  EXPECT_EQ(summary.refusedTimeUpdates + summary.refusedMeasurementUpdates, 0);
  const Reference<3> ref = ukfReference(r);
  for (std::size_t k = 0; k < filtered.size(); ++k)  // the filter is the Kalman filter (ukf_test.cpp)
    ASSERT_LT((filtered[k].state - ref.filteredMean[k]).cwiseAbs().maxCoeff(), kTolerance) << k;
  std::vector<mjukf::offline::SmoothedSample<decltype(filter)>> smoothed;
  ASSERT_TRUE(mjukf::offline::smooth(filter, r.data(), filtered, smoothed).ok());
  expectSmootherEqualsRts(ref, smoothed);
}

TEST(OfflineSmoother, UkfEqualsLinearRtsSmoother) { expectUkfSmootherEqualsRts(1); }

TEST(OfflineSmoother, UkfEqualsLinearRtsSmootherOverSeveralStepsPerSample) { expectUkfSmootherEqualsRts(3); }

TEST(OfflineSmoother, JointUkfEqualsLinearRtsSmootherOfTheAugmentedSystem) {
  for (int steps : {1, 2}) {
    const Recording r = record(steps, 9);
    const LinearPlant::Param guess(0.2);
    mjukf::JointUkf<LinearPlant> filter(LinearPlant(), kStart, guess, jointSettings());
    std::vector<mjukf::offline::Sample<decltype(filter)>> filtered;
    mjukf::offline::run(filter, r.data(), filtered);
    std::vector<mjukf::offline::SmoothedSample<decltype(filter)>> smoothed;
    ASSERT_TRUE(mjukf::offline::smooth(filter, r.data(), filtered, smoothed).ok());
    const Reference<4> ref = jointReference(r, guess(0));
    expectSmootherEqualsRts(ref, smoothed);
    // The θ block of the sample is the θ block of the augmented covariance.
    EXPECT_EQ(filtered.back().parameterCovariance(0, 0), filtered.back().covariance(3, 3));
    EXPECT_EQ(smoothed.front().parameters()(0), smoothed.front().mean(3));
  }
}

TEST(OfflineLikelihood, EqualsKalmanFilterLogLikelihood) {
  for (int steps : {1, 3}) {
    const Recording r = record(steps, 17);
    mjukf::Ukf<LinearPlant> filter(LinearPlant(), kStart, kTheta, ukfSettings());
    const auto sum = mjukf::offline::logLikelihood(filter, r.data());
    ASSERT_TRUE(sum.ok());
    const double reference = ukfReference(r).logLikelihood;
    EXPECT_LT(std::abs(sum.value - reference), kTolerance * std::abs(reference)) << sum.value << " " << reference;
    std::printf("log-likelihood %.15g, relative difference from the Kalman filter %.2e\n", sum.value,
                std::abs(sum.value - reference) / std::abs(reference));
    // 60 samples, 5 with nothing present (k = 5, 16, 27, 38, 49), 8 more with one component of two.
    EXPECT_EQ(sum.terms, 55);
    EXPECT_EQ(sum.components, 2 * 55 - 8);
  }
}

TEST(OfflineLikelihood, JointUkfEqualsKalmanFilterOfTheAugmentedSystem) {
  const Recording r = record(1, 23);
  const LinearPlant::Param guess(0.2);
  mjukf::JointUkf<LinearPlant> filter(LinearPlant(), kStart, guess, jointSettings());
  const auto sum = mjukf::offline::logLikelihood(filter, r.data());
  const double reference = jointReference(r, guess(0)).logLikelihood;
  EXPECT_LT(std::abs(sum.value - reference), kTolerance * std::abs(reference));
}

// A parameter vector scored by a Ukf built on it: the Kalman filter's likelihood of that θ, largest
// near the θ the data were made with.
TEST(OfflineLikelihood, ScoresAParameterVector) {
  const Recording r = record(1, 31);
  const LinearPlant plant;
  double best = -INFINITY, bestTheta = 0;
  for (double theta = 0.0; theta <= 1.4001; theta += 0.1) {
    const auto sum = mjukf::offline::logLikelihood(plant, LinearPlant::Param(theta), kStart, ukfSettings(), r.data());
    ASSERT_TRUE(sum.ok());
    if (std::abs(theta - kTheta(0)) < 1e-12) {
      EXPECT_LT(std::abs(sum.value - ukfReference(r).logLikelihood), kTolerance * std::abs(sum.value));
    }
    if (sum.value > best) best = sum.value, bestTheta = theta;
  }
  std::printf("the largest log-likelihood on the grid: theta = %.1f (the data's: %.1f)\n", bestTheta, kTheta(0));
  EXPECT_NEAR(bestTheta, kTheta(0), 0.3);
  // Invalid settings: −∞ and the error, never a value.
  auto bad = ukfSettings();
  bad.measurementNoise.setZero();
  const auto refused = mjukf::offline::logLikelihood(plant, kTheta, kStart, bad, r.data());
  EXPECT_FALSE(refused.ok());
  EXPECT_TRUE(static_cast<bool>(refused.error));
  EXPECT_EQ(refused.value, -INFINITY);
}

}  // namespace
