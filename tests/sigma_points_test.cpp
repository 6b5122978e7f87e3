// Scaled sigma points (docs/algorithms.md §1): weights, and the moments the points reproduce.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "mjukf/sigma_points.hpp"
#include "test_support.hpp"

namespace {

using mjukf::MerweScaledSigmaPoints;
using mjukf::SigmaPointParameters;
using mjukf::Status;

constexpr double kTight = 1e-12;

// The (α, β, κ) combinations the tests sweep: the paper's, and ones with a negative or large λ.
const SigmaPointParameters<double> kParameterSets[] = {
    {1.0, 2.0, 0.0}, {0.5, 2.0, 1.0}, {1e-2, 2.0, 0.0}, {1.0, 0.0, 3.0}, {2.0, 2.0, -1.0}};

// Rounding in a sum of weights of either sign grows with the sum of their magnitudes: ~1/α² for small α.
double sumRoundingBound(const Eigen::VectorXd& terms) {
  return 4 * std::numeric_limits<double>::epsilon() * terms.size() * terms.cwiseAbs().sum();
}

TEST(SigmaPoints, MeanWeightsSumToOne) {
  for (const auto& p : kParameterSets) {
    MerweScaledSigmaPoints<double, 6> sigma(p);
    EXPECT_NEAR(sigma.meanWeights().sum(), 1.0, sumRoundingBound(sigma.meanWeights()))
        << "alpha " << p.alpha << " kappa " << p.kappa;
  }
}

TEST(SigmaPoints, PaperSettingsGiveZeroCentralMeanWeight) {
  // α = 1, β = 2, κ = 0: λ = 0, Wm₀ = 0, Wc₀ = 2, Wᵢ = 1 / (2L).
  MerweScaledSigmaPoints<double, 4> sigma;
  EXPECT_EQ(sigma.lambda(), 0.0);
  EXPECT_EQ(sigma.meanWeights()(0), 0.0);
  EXPECT_EQ(sigma.covarianceWeights()(0), 2.0);
  EXPECT_EQ(sigma.meanWeights()(1), 1.0 / 8.0);
  EXPECT_EQ(sigma.gamma(), 2.0);
}

// Weighted mean and covariance of the points equal the mean and covariance they were drawn from, for
// a strongly correlated P. Points built from the rows of the Cholesky factor instead of its columns
// reproduce diag(P) at best, so this fails for them.
template <int L>
void expectPointsReproduce(const Eigen::Matrix<double, L, 1>& mean, const Eigen::Matrix<double, L, L>& cov,
                           const SigmaPointParameters<double>& p) {
  MerweScaledSigmaPoints<double, L> sigma(p);
  typename MerweScaledSigmaPoints<double, L>::Points points;
  ASSERT_EQ(sigma.generate(mean, cov, points), Status::Ok);
  const Eigen::Matrix<double, L, 1> m = points * sigma.meanWeights();
  // Covariance about the true mean with the Wm weights: exact for any α (the Wc₀ correction only
  // matters about the sample mean of a nonlinear image).
  Eigen::Matrix<double, L, L> c = Eigen::Matrix<double, L, L>::Zero();
  for (int i = 0; i < points.cols(); ++i)
    c += sigma.meanWeights()(i) * (points.col(i) - mean) * (points.col(i) - mean).transpose();
  const double scale = cov.cwiseAbs().maxCoeff();
  const double pointScale = points.cwiseAbs().maxCoeff();
  EXPECT_LT((m - mean).cwiseAbs().maxCoeff(), sumRoundingBound(sigma.meanWeights()) * pointScale);
  EXPECT_LT((c - cov).cwiseAbs().maxCoeff(), kTight * scale) << "alpha " << p.alpha;
}

TEST(SigmaPoints, ReproduceStronglyCorrelatedCovariance) {
  // Correlation 0.99 between the two components.
  Eigen::Matrix2d cov;
  cov << 1.0, 0.99 * 2.0, 0.99 * 2.0, 4.0;
  for (const auto& p : kParameterSets) expectPointsReproduce<2>(Eigen::Vector2d(1.0, -3.0), cov, p);
}

TEST(SigmaPoints, ReproduceRandomCorrelatedCovariances) {
  std::mt19937_64 rng(42);
  for (int trial = 0; trial < 50; ++trial) {
    const auto cov = mjukf::testing::randomCovariance<6>(rng, 0.1 + trial);
    Eigen::Matrix<double, 6, 1> mean = Eigen::Matrix<double, 6, 1>::LinSpaced(-2.0, 3.0);
    expectPointsReproduce<6>(mean, cov, kParameterSets[trial % 5]);
  }
}

TEST(SigmaPoints, UseColumnsOfTheLowerCholeskyFactor) {
  Eigen::Matrix2d cov;
  cov << 4.0, 2.0, 2.0, 5.0;                // S = [2 0; 1 2]
  MerweScaledSigmaPoints<double, 2> sigma;  // γ = √2
  MerweScaledSigmaPoints<double, 2>::Points points;
  ASSERT_EQ(sigma.generate(Eigen::Vector2d::Zero(), cov, points), Status::Ok);
  const double g = std::sqrt(2.0);
  EXPECT_NEAR(points(0, 1), 2 * g, kTight);  // first column of S is (2, 1)
  EXPECT_NEAR(points(1, 1), 1 * g, kTight);
  EXPECT_NEAR(points(0, 2), 0.0, kTight);  // second column is (0, 2)
  EXPECT_NEAR(points(1, 2), 2 * g, kTight);
  EXPECT_NEAR(points(1, 4), -2 * g, kTight);
}

TEST(SigmaPoints, RefuseCovarianceWithoutCholeskyFactorAndLeavePointsAlone) {
  MerweScaledSigmaPoints<double, 2> sigma;
  MerweScaledSigmaPoints<double, 2>::Points points = MerweScaledSigmaPoints<double, 2>::Points::Constant(7.0);
  const auto before = points;
  Eigen::Matrix2d indefinite;
  indefinite << 1.0, 2.0, 2.0, 1.0;
  EXPECT_EQ(sigma.generate(Eigen::Vector2d::Zero(), indefinite, points), Status::NotPositiveDefinite);
  Eigen::Matrix2d withNan = Eigen::Matrix2d::Identity();
  withNan(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(sigma.generate(Eigen::Vector2d::Zero(), withNan, points), Status::NotPositiveDefinite);
  EXPECT_EQ(sigma.generate(Eigen::Vector2d(0.0, std::numeric_limits<double>::infinity()), Eigen::Matrix2d::Identity(),
                           points),
            Status::NotPositiveDefinite);
  EXPECT_EQ(points, before);
}

TEST(SigmaPoints, RejectInvalidScaling) {
  using Sigma = MerweScaledSigmaPoints<double, 3>;
  EXPECT_THROW(Sigma({0.0, 2.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(Sigma({-1.0, 2.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(Sigma({1.0, 2.0, -3.0}), std::invalid_argument);  // L + λ = α²(L + κ) = 0
  EXPECT_THROW(Sigma({1.0, std::numeric_limits<double>::quiet_NaN(), 0.0}), std::invalid_argument);
  try {
    Sigma({1.0, 2.0, -5.0});
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("kappa"), std::string::npos) << e.what();
  }
}

}  // namespace

// ---- The cubature set ---------------------------------------------------------------------------

// Known answers of the spherical-radial rule of degree 3 for x ~ N(μ, P): the points reproduce μ and P
// exactly (up to rounding), E[xᵢ xⱼ xₖ] about μ is zero (odd moments vanish by symmetry), and the fourth
// moment E[(x₀ − μ₀)⁴] is L σ₀⁴ ... of a diagonal P, where the Gaussian's is 3 σ₀⁴: the rule is exact to
// degree 3 only, which is the textbook limit of the cubature filter.
TEST(CubatureSigmaPoints, ReproduceMeanCovarianceAndOddMomentsExactly) {
  constexpr int L = 5;
  std::mt19937_64 rng(7);
  mjukf::CubatureSigmaPoints<double, L> sigma;
  EXPECT_EQ(sigma.Count, 2 * L);
  EXPECT_NEAR(sigma.meanWeights().sum(), 1.0, 4 * L * std::numeric_limits<double>::epsilon());
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix<double, L, L> p = mjukf::testing::randomCovariance<L>(rng);
    const Eigen::Matrix<double, L, 1> mu = Eigen::Matrix<double, L, 1>::Random();
    Eigen::Matrix<double, L, 2 * L> points;
    ASSERT_EQ(sigma.generate(mu, p, points), Status::Ok);
    const Eigen::Matrix<double, L, 1> mean = points * sigma.meanWeights();
    const Eigen::Matrix<double, L, 2 * L> d = points.colwise() - mu;
    const Eigen::Matrix<double, L, L> cov = d * sigma.covarianceWeights().asDiagonal() * d.transpose();
    // Rounding: each entry is a sum of 2L products of entries of size ~‖P‖.
    const double bound = 16 * L * std::numeric_limits<double>::epsilon() * p.cwiseAbs().maxCoeff();
    EXPECT_LT((mean - mu).cwiseAbs().maxCoeff(), 16 * L * std::numeric_limits<double>::epsilon() * (1 + mu.norm()));
    EXPECT_LT((cov - p).cwiseAbs().maxCoeff(), bound);
    double third = 0;
    for (int i = 0; i < 2 * L; ++i) third += sigma.meanWeights()(i) * d(0, i) * d(1, i) * d(2, i);
    EXPECT_LT(std::abs(third), bound * p.cwiseAbs().maxCoeff());
  }
  const Eigen::Matrix<double, L, L> diagonal = Eigen::Matrix<double, L, 1>::Constant(4.0).asDiagonal();
  Eigen::Matrix<double, L, 2 * L> points;
  ASSERT_EQ(sigma.generate(Eigen::Matrix<double, L, 1>::Zero(), diagonal, points), Status::Ok);
  double fourth = 0;
  for (int i = 0; i < 2 * L; ++i) fourth += sigma.meanWeights()(i) * std::pow(points(0, i), 4);
  EXPECT_NEAR(fourth, L * 16.0, 1e-12);  // σ₀⁴ = 16; the Gaussian's would be 48
}

TEST(CubatureSigmaPoints, HaveNoCentreAndIgnoreTheScalingParameters) {
  using Cubature3 = mjukf::CubatureSigmaPoints<double, 3>;
  EXPECT_FALSE(Cubature3::HasCenter);
  EXPECT_FALSE(Cubature3::validate({-1.0, 0.0, -10.0}));
  EXPECT_DOUBLE_EQ(Cubature3().gamma(), std::sqrt(3.0));
}
