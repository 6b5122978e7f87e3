// The unscented transform reproduces the mean and covariance of a linear map exactly (to rounding).

#include <random>

#include <gtest/gtest.h>

#include "mjukf/sigma_points.hpp"
#include "mjukf/unscented_transform.hpp"
#include "test_support.hpp"

namespace {

TEST(UnscentedTransform, ReproducesLinearMapMeanAndCovariance) {
  std::mt19937_64 rng(7);
  const mjukf::SigmaPointParameters<double> sets[] = {{1.0, 2.0, 0.0}, {0.3, 2.0, 1.0}, {1.0, 0.0, 2.0}};
  for (int trial = 0; trial < 30; ++trial) {
    const auto& p = sets[trial % 3];
    mjukf::MerweScaledSigmaPoints<double, 4> sigma(p);
    const Eigen::Matrix4d P = mjukf::testing::randomCovariance<4>(rng);
    const auto x = mjukf::testing::randomNormal<Eigen::Vector4d>(rng);
    const auto A = mjukf::testing::randomNormal<Eigen::Matrix<double, 3, 4>>(rng);
    const auto b = mjukf::testing::randomNormal<Eigen::Vector3d>(rng);

    mjukf::MerweScaledSigmaPoints<double, 4>::Points points;
    ASSERT_EQ(sigma.generate(x, P, points), mjukf::Status::Ok);
    const Eigen::Matrix<double, 3, 9> images = (A * points).colwise() + b;
    Eigen::Vector3d mean;
    Eigen::Matrix3d cov;
    mjukf::unscentedTransform(images, sigma.meanWeights(), sigma.covarianceWeights(), mean, cov);

    const Eigen::Vector3d expectedMean = A * x + b;
    const Eigen::Matrix3d expectedCov = A * P * A.transpose();
    const double scale = 1 + expectedCov.cwiseAbs().maxCoeff();
    EXPECT_LT((mean - expectedMean).cwiseAbs().maxCoeff(), 1e-12 * scale) << "trial " << trial;
    EXPECT_LT((cov - expectedCov).cwiseAbs().maxCoeff(), 1e-12 * scale) << "trial " << trial;

    // The cross-covariance of the points and their images is P Aᵀ.
    Eigen::Matrix<double, 4, 3> cross;
    const Eigen::Matrix<double, 4, 9> dx = points.colwise() - x;
    const Eigen::Matrix<double, 3, 9> dy = images.colwise() - mean;
    mjukf::unscentedCovarianceFromDeviations(dx, dy, sigma.covarianceWeights(), cross);
    EXPECT_LT((cross - P * A.transpose()).cwiseAbs().maxCoeff(), 1e-12 * scale) << "trial " << trial;
  }
}

TEST(UnscentedTransform, CapturesSecondOrderTermOfQuadraticMap) {
  // y = x² for x ~ N(m, s²): E[y] = m² + s², exact for the unscented transform of any valid scaling.
  mjukf::MerweScaledSigmaPoints<double, 1> sigma;
  mjukf::MerweScaledSigmaPoints<double, 1>::Points points;
  const double m = 1.5, s2 = 0.25;
  ASSERT_EQ(sigma.generate(Eigen::Matrix<double, 1, 1>(m), Eigen::Matrix<double, 1, 1>(s2), points), mjukf::Status::Ok);
  const Eigen::Matrix<double, 1, 3> images = points.array().square().matrix();
  Eigen::Matrix<double, 1, 1> mean, cov;
  mjukf::unscentedTransform(images, sigma.meanWeights(), sigma.covarianceWeights(), mean, cov);
  EXPECT_NEAR(mean(0), m * m + s2, 1e-14);
}

}  // namespace
