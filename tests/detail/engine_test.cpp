// detail/unscented_engine.hpp's Estimate on its own: on a linear map and a linear measurement the
// unscented prediction and correction are exactly the Kalman filter's (sigma points carry the first two
// moments through a linear map without error), masking equals the update of the reduced model, the gate
// refuses, and only a commit changes the estimate. The filters' tests check the same through the
// public API; these check the arithmetic where it is written, in both covariance forms (the square-root
// form's prediction and correction are Householder factors and downdates, not sums: the same Kalman
// answer). Tolerances: rounding of sums of 2L + 1 terms of size ‖P‖, a few hundred ε. And the shared
// input of a time update: every request answered with input(t) itself, input(t) evaluated once per time.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <gtest/gtest.h>

#include "mjukf/detail/parameter_change_detector.hpp"
#include "mjukf/detail/parameter_error_covariance.hpp"
#include "mjukf/detail/unscented_engine.hpp"
#include "test_support.hpp"

namespace {

using mjukf::Status;
constexpr double kTolerance = 1e-12;

struct LinearCase {
  std::mt19937_64 rng{11};
  Eigen::Matrix3d F = (Eigen::Matrix3d() << 0.9, 0.2, 0.0, -0.1, 0.8, 0.3, 0.0, 0.1, 0.7).finished();
  Eigen::Matrix<double, 2, 3> C = (Eigen::Matrix<double, 2, 3>() << 1, 0, 0.5, 0, 1, -1).finished();
  Eigen::Matrix3d P = mjukf::testing::randomCovariance<3>(rng);
  Eigen::Matrix3d Q = mjukf::testing::randomCovariance<3>(rng, 1e-2);
  Eigen::Matrix2d R = (Eigen::Matrix2d() << 0.3, 0.05, 0.05, 0.2).finished();
  Eigen::Vector3d x = Eigen::Vector3d(0.5, -1.0, 2.0);
  Eigen::Vector2d y = Eigen::Vector2d(0.7, 0.1);
  mjukf::MeasurementGate<double, 2> noGate;
};

template <class Form>
class EngineEstimate : public ::testing::Test {
 protected:
  using Est = mjukf::detail::Estimate<double, 3, 2, mjukf::MerweScaled, Form>;
  static Est makeEstimate(const LinearCase& c) {
    Est e(mjukf::detail::Validated{}, mjukf::SigmaPointParameters<double>{0.7, 2.0, 1.0}, c.Q, c.R);
    EXPECT_TRUE(e.assign(c.x, c.P));
    return e;
  }
};
using Forms = ::testing::Types<mjukf::FullCovariance, mjukf::SquareRootCovariance>;
struct FormName {
  template <class Form>
  static std::string GetName(int) {
    return std::is_same_v<Form, mjukf::FullCovariance> ? "Full" : "SquareRoot";
  }
};
TYPED_TEST_SUITE(EngineEstimate, Forms, FormName);

TYPED_TEST(EngineEstimate, PredictionOfALinearMapIsTheKalmanPrediction) {
  LinearCase c;
  using Est = typename TestFixture::Est;
  Est e = TestFixture::makeEstimate(c);
  ASSERT_EQ(e.draw(e.mean(), e.factor()), Status::Ok);
  for (int i = 0; i < Est::Count; ++i) e.workPoints().col(i) = c.F * e.workPoints().col(i);
  e.predict(c.Q);
  EXPECT_LT((e.candidateMean() - c.F * c.x).cwiseAbs().maxCoeff(), kTolerance);
  // settle() checks the candidate (and the square-root form forms P = S Sᵀ from its factor there).
  ASSERT_EQ(e.settle(mjukf::CovarianceRepair<double>{}), Status::Ok);
  EXPECT_LT((e.candidateCovariance() - (c.F * c.P * c.F.transpose() + c.Q)).cwiseAbs().maxCoeff(), kTolerance);
  EXPECT_LT((e.candidateFactor() * e.candidateFactor().transpose() - e.candidateCovariance()).cwiseAbs().maxCoeff(),
            kTolerance);
  // Nothing is the estimate's until it is committed.
  EXPECT_EQ(e.mean(), c.x);
  EXPECT_FALSE(e.hasPoints());
  e.commitPrediction();
  EXPECT_EQ(e.mean(), e.candidateMean());
  EXPECT_TRUE(e.hasPoints());
}

// A policy's floor (the MJUKF's covariance of η + W e, docs/algorithms.md §5.2): P⁻ is raised to cover
// it by the positive semi-definite part of floor − P⁻, so P⁻ is unchanged where it already covers the
// floor, becomes P⁻ + v vᵀ for a floor P⁻ + v vᵀ, and in general covers both and no more: with
// D = floor − P⁻, P − P⁻ = D⁺ and P − floor = (−D)⁺, whose product is zero (their eigenspaces are
// orthogonal). Tolerances: the rounding of the prediction and the Jacobi rotations (1-Lipschitz:
// backward errors of c L ε ‖·‖_F), and in the square-root form of two triangularisations and S Sᵀ;
// c = 64 covers them with room, on matrices whose norm is taken in each comparison.
TYPED_TEST(EngineEstimate, AFloorRaisesThePredictionToCoverItAndNoMore) {
  LinearCase c;
  using Est = typename TestFixture::Est;
  const auto predictWith = [&c](const Eigen::Matrix3d* floor) {
    Est e = TestFixture::makeEstimate(c);
    EXPECT_EQ(e.draw(e.mean(), e.factor()), Status::Ok);
    for (int i = 0; i < Est::Count; ++i) e.workPoints().col(i) = c.F * e.workPoints().col(i);
    e.predict(c.Q, floor);
    EXPECT_EQ(e.settle(mjukf::CovarianceRepair<double>{}), Status::Ok);
    return e;
  };
  const double eps = std::numeric_limits<double>::epsilon();
  const Eigen::Matrix3d prior = c.F * c.P * c.F.transpose() + c.Q;
  const auto tolerance = [&](const Eigen::Matrix3d& floor) { return 64 * 3 * eps * (prior.norm() + floor.norm()); };
  const auto smallestEigenvalue = [](const Eigen::Matrix3d& m) {
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m).eigenvalues().minCoeff();
  };

  const Eigen::Matrix3d below = prior * 0.5;  // covered already: nothing added
  EXPECT_LT((predictWith(&below).candidateCovariance() - prior).cwiseAbs().maxCoeff(), tolerance(below));

  const Eigen::Vector3d v(0.3, -0.2, 0.5);
  const Eigen::Matrix3d rankOne = prior + v * v.transpose();  // short by v vᵀ: exactly that is added
  EXPECT_LT((predictWith(&rankOne).candidateCovariance() - rankOne).cwiseAbs().maxCoeff(), tolerance(rankOne));

  std::mt19937_64 rng(5);
  int mixed = 0;
  for (int trial = 0; trial < 20; ++trial) {  // D of both signs: the result covers both, and no more
    const Eigen::Matrix3d floor = mjukf::testing::randomCovariance<3>(rng, 0.3 * prior.norm());
    const Eigen::Vector3d inertia = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(floor - prior).eigenvalues();
    mixed += inertia.minCoeff() < 0 && inertia.maxCoeff() > 0;
    const Eigen::Matrix3d p = predictWith(&floor).candidateCovariance();
    const double tol = tolerance(floor);
    EXPECT_GE(smallestEigenvalue(p - floor), -tol) << "trial " << trial;
    EXPECT_GE(smallestEigenvalue(p - prior), -tol) << "trial " << trial;
    EXPECT_LT(((p - prior) * (p - floor)).norm(), tol * (prior.norm() + floor.norm())) << "trial " << trial;
  }
  EXPECT_GE(mixed, 10) << "too few floors neither below nor above the prediction to test the general case";
}

using mjukf::testing::randomNormal;

// A joint covariance J of (η, e) with cross-covariances: random P₀ and P_θ, then a measurement update of
// random gains (not yet committed).
bool startCorrelated(std::mt19937_64& rng, mjukf::detail::ParameterErrorCovariance<double, 3, 2, 2>& covariance) {
  const auto stateCovariance = mjukf::testing::randomCovariance<3>(rng);      // drawn in order: arguments
  const auto parameterCovariance = mjukf::testing::randomCovariance<2>(rng);  // are not
  covariance.start(stateCovariance, parameterCovariance);
  const auto h = randomNormal<Eigen::Matrix<double, 2, 3>>(rng);
  const auto k = randomNormal<Eigen::Matrix<double, 3, 2>>(rng);
  const auto g = randomNormal<Eigen::Matrix2d>(rng);
  const auto psi = randomNormal<Eigen::Matrix2d>(rng);
  const auto w = randomNormal<Eigen::Matrix<double, 3, 2>>(rng);
  return covariance.correct(h, k, g, psi, w, Eigen::Matrix2d::Identity(), nullptr);
}

// The floor the MJUKF gives (detail/parameter_error_covariance.hpp): cov(η + W e) = [I W] J [I W]ᵀ for the
// joint covariance J of (η, e), here a general one (cross-covariances from a measurement update of
// random gains), symmetric to the last bit. Tolerance: sums of n + p products of entries of size 1.
TEST(ParameterErrorCovariance, TheStateErrorCovarianceIsThatOfEtaPlusWe) {
  std::mt19937_64 rng(3);
  mjukf::detail::ParameterErrorCovariance<double, 3, 2, 2> covariance;
  ASSERT_TRUE(startCorrelated(rng, covariance));
  covariance.commit();  // the candidate becomes committed(), which the test can read
  const Eigen::Matrix<double, 5, 5> joint = covariance.committed();
  ASSERT_GT((joint.topRightCorner<3, 2>().cwiseAbs().maxCoeff()), 0.1) << "a J with cross-covariances";
  const Eigen::Matrix<double, 3, 2> w = randomNormal<Eigen::Matrix<double, 3, 2>>(rng);
  Eigen::Matrix<double, 3, 5> map;
  map << Eigen::Matrix3d::Identity(), w;
  Eigen::Matrix3d sigma;
  ASSERT_TRUE(covariance.stateErrorCovariance(w, sigma));
  const Eigen::Matrix3d expected = map * joint * map.transpose();
  EXPECT_LT((sigma - expected).cwiseAbs().maxCoeff(), 64 * std::numeric_limits<double>::epsilon() * expected.norm());
  EXPECT_TRUE(sigma == sigma.transpose());
}

// A random walk of θ in the joint covariance's prediction (ModifiedJointUkfSettings::parameterProcessNoise):
// θ ← θ + w_θ at the end of the interval moves (η, e) by ([W⁻; −I] w_θ), so the prediction with Q_θ is
// the one without it plus [W⁻; −I] Q_θ [W⁻; −I]ᵀ, from the same points. Tolerance: products of n + p
// entries of size 1, to 64 ε of J's norm; with Q_θ = 0 the two are the same bits.
TEST(ParameterErrorCovariance, ARandomWalkOfThetaWidensTheJointPredictionByItsImage) {
  using Covariance = mjukf::detail::ParameterErrorCovariance<double, 3, 2, 2>;
  std::mt19937_64 rng(11);
  Covariance still, walking, zero;
  ASSERT_TRUE(startCorrelated(rng, still));
  still.commit();
  walking = zero = still;
  const auto prior = randomNormal<Covariance::Points>(rng);
  const auto propagated = randomNormal<Covariance::Points>(rng);
  const auto parameterPoints = randomNormal<Covariance::ParamPoints>(rng);
  const auto sensitivity = randomNormal<Covariance::StateByParam>(rng);
  const auto derivative = randomNormal<Covariance::StateByParam>(rng);
  const auto predicted = randomNormal<Covariance::StateByParam>(rng);
  const Eigen::Matrix3d q = mjukf::testing::randomCovariance<3>(rng);
  const Eigen::Matrix2d walk = mjukf::testing::randomCovariance<2>(rng);
  ASSERT_TRUE(still.predict(prior, propagated, parameterPoints, sensitivity, &derivative, predicted, q,
                            Eigen::Matrix2d::Zero(), 1.0));
  ASSERT_TRUE(walking.predict(prior, propagated, parameterPoints, sensitivity, &derivative, predicted, q, walk, 1.0));
  ASSERT_TRUE(zero.predict(prior, propagated, parameterPoints, sensitivity, &derivative, predicted, q,
                           Eigen::Matrix2d::Zero(), 1.0));
  still.commit();
  walking.commit();
  zero.commit();
  EXPECT_TRUE(zero.committed() == still.committed());
  Eigen::Matrix<double, 5, 2> image;
  image << predicted, -Eigen::Matrix2d::Identity();
  const Eigen::Matrix<double, 5, 5> expected = still.committed() + image * walk * image.transpose();
  EXPECT_LT((walking.committed() - expected).cwiseAbs().maxCoeff(),
            64 * std::numeric_limits<double>::epsilon() * expected.norm());
  EXPECT_TRUE(walking.parameterCovariance() == still.parameterCovariance() + walk);
  // Independently of that formula: a walk at the interval's end leaves the state's error x̂ − x = η + W⁻ e
  // as it was, so cov(η + W⁻ e) must not change (a wrong sign of the cross terms would add 4 W⁻ Q_θ W⁻ᵀ).
  Eigen::Matrix3d stateError, stateErrorWalking;
  ASSERT_TRUE(still.stateErrorCovariance(predicted, stateError));
  ASSERT_TRUE(walking.stateErrorCovariance(predicted, stateErrorWalking));
  EXPECT_LT((stateErrorWalking - stateError).cwiseAbs().maxCoeff(),
            64 * std::numeric_limits<double>::epsilon() * expected.norm());
}

// The joint covariance's gain of θ (docs/algorithms.md §5.3) is the Kalman gain of the augmented linear
// model: with z = (η, e) of covariance J and ν = −[H ψ] z + v, θ − θ̂ = −e, K_θ = cov(−e, ν) S⁻¹. Against
// that formula written out, for a general J (cross-covariances), with P_θ widened, and with a component
// missing (its column of K_θ zero, the rest the gain of the reduced model). Tolerance: a solve with S of
// condition below 1e3 on entries of size 1, 1e-12.
TEST(ParameterErrorCovariance, TheParameterGainIsTheKalmanGainOfTheJointModel) {
  std::mt19937_64 rng(5);
  mjukf::detail::ParameterErrorCovariance<double, 3, 2, 2> covariance;
  ASSERT_TRUE(startCorrelated(rng, covariance));
  covariance.commit();
  const Eigen::Matrix<double, 5, 5> joint = covariance.committed();
  const Eigen::Matrix<double, 2, 3> h = randomNormal<Eigen::Matrix<double, 2, 3>>(rng);
  const Eigen::Matrix2d psi = randomNormal<Eigen::Matrix2d>(rng),
                        r = (Eigen::Matrix2d() << 0.3, 0.05, 0.05, 0.2).finished();
  const Eigen::Matrix2d widening = mjukf::testing::randomCovariance<2>(rng);
  const auto expected = [&](const Eigen::Matrix<double, 5, 5>& j, const Eigen::Matrix<double, 2, 3>& hh,
                            const Eigen::Matrix2d& pp) {
    Eigen::Matrix<double, 2, 5> map;
    map << hh, pp;
    const Eigen::Matrix2d s = map * j * map.transpose() + r;
    return Eigen::Matrix2d(j.bottomRows<2>() * map.transpose() * s.inverse());
  };
  Eigen::Matrix2d gain, factor;
  using Mask = Eigen::Matrix<bool, 2, 1>;
  ASSERT_TRUE(covariance.parameterGain(h, psi, r, static_cast<const Mask*>(nullptr), nullptr, gain, factor));
  EXPECT_LT((gain - expected(joint, h, psi)).cwiseAbs().maxCoeff(), 1e-12);
  Eigen::Matrix<double, 5, 5> widened = joint;
  widened.bottomRightCorner<2, 2>() += widening;
  ASSERT_TRUE(covariance.parameterGain(h, psi, r, static_cast<const Mask*>(nullptr), &widening, gain, factor));
  EXPECT_LT((gain - expected(widened, h, psi)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_TRUE(covariance.committed() == joint) << "the widening reaches the candidate only";
  // Component 1 missing: its rows of H and ψ are zero (as the filter passes them), S gets a unit entry.
  const Mask present(true, false);
  Eigen::Matrix<double, 2, 3> h0 = h;
  Eigen::Matrix2d psi0 = psi;
  h0.row(1).setZero();
  psi0.row(1).setZero();
  ASSERT_TRUE(covariance.parameterGain(h0, psi0, r, &present, nullptr, gain, factor));
  Eigen::Matrix<double, 1, 5> map0;
  map0 << h.row(0), psi.row(0);
  const double s0 = (map0 * joint * map0.transpose())(0, 0) + r(0, 0);
  const Eigen::Vector2d reduced = joint.bottomRows<2>() * map0.transpose() / s0;
  EXPECT_LT((gain.col(0) - reduced).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_TRUE(gain.col(1).isZero());
}

// The measurement update of J with P_θ widened (a detected change, §5.4) is the update of the J whose
// P_θ is larger by the widening, bit for bit (the same sums in the same order), and the committed J is
// not touched until commit().
TEST(ParameterErrorCovariance, AWidenedUpdateIsTheUpdateOfTheWidenedCovariance) {
  std::mt19937_64 rng(9);
  const Eigen::Matrix3d stateCovariance = mjukf::testing::randomCovariance<3>(rng);
  const Eigen::Matrix2d parameterCovariance = mjukf::testing::randomCovariance<2>(rng);
  const Eigen::Matrix2d widening = mjukf::testing::randomCovariance<2>(rng);
  mjukf::detail::ParameterErrorCovariance<double, 3, 2, 2> widenedInCorrect, widenedAtStart;
  widenedInCorrect.start(stateCovariance, parameterCovariance);
  widenedAtStart.start(stateCovariance, Eigen::Matrix2d(parameterCovariance + widening));
  const Eigen::Matrix<double, 2, 3> h = randomNormal<Eigen::Matrix<double, 2, 3>>(rng);
  const Eigen::Matrix<double, 3, 2> k = randomNormal<Eigen::Matrix<double, 3, 2>>(rng),
                                    w = randomNormal<Eigen::Matrix<double, 3, 2>>(rng);
  const Eigen::Matrix2d g = randomNormal<Eigen::Matrix2d>(rng), psi = randomNormal<Eigen::Matrix2d>(rng);
  const Eigen::Matrix<double, 5, 5> before = widenedInCorrect.committed();
  ASSERT_TRUE(widenedInCorrect.correct(h, k, g, psi, w, Eigen::Matrix2d::Identity(), &widening));
  ASSERT_TRUE(widenedAtStart.correct(h, k, g, psi, w, Eigen::Matrix2d::Identity(), nullptr));
  EXPECT_TRUE(widenedInCorrect.committed() == before) << "the widening reaches the candidate only";
  widenedInCorrect.commit();
  widenedAtStart.commit();
  EXPECT_TRUE(widenedInCorrect.committed() == widenedAtStart.committed());
}

// From n + p = 20 (double) the joint covariance is propagated by blocks and by one triangle
// (ParameterErrorCovariance's ByBlocks): a predict (with Q and a random walk Q_θ) and a correct from the
// same J and inputs give the two full products' result to rounding (sums of n + p products of entries of
// size up to about 10, so 64 ε of J's norm per map), and an exactly symmetric J.
TEST(ParameterErrorCovariance, TheMapsByBlocksAreTheFullProducts) {
  constexpr int n = 17, m = 5, p = 3;
  using Blocks = mjukf::detail::ParameterErrorCovariance<double, n, m, p, true>;
  using Full = mjukf::detail::ParameterErrorCovariance<double, n, m, p, false>;
  static_assert(std::is_same_v<Blocks, mjukf::detail::ParameterErrorCovariance<double, n, m, p>>,
                "the default form at n + p = 20");
  std::mt19937_64 rng(23);
  Blocks blocks;
  Full full;
  const Eigen::Matrix<double, n, n> stateCovariance = mjukf::testing::randomCovariance<n>(rng);
  const Eigen::Matrix<double, p, p> parameterCovariance = mjukf::testing::randomCovariance<p>(rng);
  blocks.start(stateCovariance, parameterCovariance);
  full.start(stateCovariance, parameterCovariance);
  const auto h = randomNormal<Eigen::Matrix<double, m, n>>(rng);
  const auto k = randomNormal<Eigen::Matrix<double, n, m>>(rng);
  const auto g = randomNormal<Eigen::Matrix<double, p, m>>(rng);
  const auto psi = randomNormal<Eigen::Matrix<double, m, p>>(rng);
  const auto w = randomNormal<Eigen::Matrix<double, n, p>>(rng);
  const Eigen::Matrix<double, m, m> r = mjukf::testing::randomCovariance<m>(rng);
  const auto expectSame = [&](const char* step) {
    const auto& expected = full.committed();
    EXPECT_LT((blocks.committed() - expected).cwiseAbs().maxCoeff(),
              64 * std::numeric_limits<double>::epsilon() * expected.norm())
        << step;
    EXPECT_TRUE(blocks.committed() == blocks.committed().transpose()) << step;
  };
  // Each step of `blocks` twice before its commit: the second must not read what the first left in the
  // candidate (every entry of its lower triangle written anew).
  ASSERT_TRUE(blocks.correct(h, k, g, psi, w, r, nullptr));
  ASSERT_TRUE(blocks.correct(h, k, g, psi, w, r, nullptr));
  ASSERT_TRUE(full.correct(h, k, g, psi, w, r, nullptr));
  blocks.commit();
  full.commit();
  expectSame("correct");
  // Points whose half differences are well conditioned, so that A is found from them.
  Blocks::Points prior = randomNormal<Blocks::Points>(rng);
  prior.middleCols<n>(1) =
      Eigen::Matrix<double, n, n>::Identity() * 10 + 0.1 * randomNormal<Eigen::Matrix<double, n, n>>(rng);
  prior.rightCols<n>() = -prior.middleCols<n>(1);
  const auto propagated = randomNormal<Blocks::Points>(rng);
  const auto parameterPoints = randomNormal<Blocks::ParamPoints>(rng);
  const auto sensitivity = randomNormal<Blocks::StateByParam>(rng);
  const auto derivative = randomNormal<Blocks::StateByParam>(rng);
  const auto predicted = randomNormal<Blocks::StateByParam>(rng);
  const Eigen::Matrix<double, n, n> q = mjukf::testing::randomCovariance<n>(rng);
  const Eigen::Matrix<double, p, p> walk = mjukf::testing::randomCovariance<p>(rng);
  ASSERT_TRUE(blocks.predict(prior, propagated, parameterPoints, sensitivity, &derivative, predicted, q, walk, 1.5));
  ASSERT_TRUE(blocks.predict(prior, propagated, parameterPoints, sensitivity, &derivative, predicted, q, walk, 1.5));
  ASSERT_TRUE(full.predict(prior, propagated, parameterPoints, sensitivity, &derivative, predicted, q, walk, 1.5));
  blocks.commit();
  full.commit();
  expectSame("predict");
}

// A lower-triangular n × n matrix near 3 I (condition number about 5), and a matrix's condition number.
template <int N>
Eigen::Matrix<double, N, N> wellConditionedLower(std::mt19937_64& rng) {
  using Matrix = Eigen::Matrix<double, N, N>;
  return Matrix(Matrix::Identity() * 3 + 0.3 * randomNormal<Matrix>(rng)).template triangularView<Eigen::Lower>();
}
template <class Matrix>
double conditionNumber(const Matrix& m) {
  const Eigen::JacobiSVD<Matrix> svd(m);
  return svd.singularValues()(0) / svd.singularValues()(svd.singularValues().size() - 1);
}

// From n + p = 20 the dynamics' Jacobian A of points drawn from a lower factor, A (T − W ϑ) = change with
// T = γL lower triangular, comes from substitutions with T and a p × p system (Woodbury's identity)
// instead of the LU of T − W ϑ. The same A up to rounding: the LU's relative error is about n κ ε, κ the
// condition number of T − W ϑ; Woodbury's grows with κ(T) too (predict() takes the LU where T's
// diagonal says κ(T) > 1/√ε), and T here is well conditioned (κ(T) about 5), so n κ ε bounds both.
TEST(ParameterErrorCovariance, TheJacobianByTriangleSolvesTheSystemTheLuSolves) {
  constexpr int n = 17, p = 3;
  using Covariance = mjukf::detail::ParameterErrorCovariance<double, n, 5, p>;
  using Matrix = Eigen::Matrix<double, n, n>;
  std::mt19937_64 rng(29);
  for (int trial = 0; trial < 20; ++trial) {
    const Matrix triangle = wellConditionedLower<n>(rng);
    const auto change = randomNormal<Matrix>(rng);
    const auto sensitivity = randomNormal<Eigen::Matrix<double, n, p>>(rng);
    const auto parameterSpread = randomNormal<Eigen::Matrix<double, p, n>>(rng);
    for (const bool withSensitivity : {false, true}) {
      const Matrix spread = withSensitivity ? Matrix(triangle - sensitivity * parameterSpread) : triangle;
      const Matrix expected = spread.transpose().fullPivLu().solve(change.transpose()).transpose();
      Matrix jacobian;
      Covariance::jacobianByTriangle(change, triangle, withSensitivity ? &sensitivity : nullptr, parameterSpread,
                                     jacobian);
      const double kappa = conditionNumber(spread);
      EXPECT_LT((jacobian - expected).norm(), 4 * n * kappa * std::numeric_limits<double>::epsilon() * expected.norm())
          << "trial " << trial << (withSensitivity ? ", with W ϑ" : "") << ", κ " << kappa;
    }
  }
}

// And predict() takes that path where the points' half differences are lower triangular: the same
// prediction as the full products and the LU, to the solve's rounding, and not the same bits as the
// same form given points an ulp off triangular, which take the LU.
TEST(ParameterErrorCovariance, APredictionFromPointsOfALowerFactorIsTheLusToRounding) {
  constexpr int n = 17, m = 5, p = 3;
  using Blocks = mjukf::detail::ParameterErrorCovariance<double, n, m, p, true>;
  using Full = mjukf::detail::ParameterErrorCovariance<double, n, m, p, false>;
  using Matrix = Eigen::Matrix<double, n, n>;
  std::mt19937_64 rng(31);
  Blocks blocks, blocksByLu;
  Full full;
  const Matrix stateCovariance = mjukf::testing::randomCovariance<n>(rng);
  const Eigen::Matrix<double, p, p> parameterCovariance = mjukf::testing::randomCovariance<p>(rng);
  blocks.start(stateCovariance, parameterCovariance);
  blocksByLu.start(stateCovariance, parameterCovariance);
  full.start(stateCovariance, parameterCovariance);
  const Eigen::Matrix<double, n, 1> mean = randomNormal<Eigen::Matrix<double, n, 1>>(rng);
  const Matrix factor = wellConditionedLower<n>(rng);
  Blocks::Points prior;
  prior.col(0) = mean;
  for (int j = 0; j < n; ++j) {
    prior.col(1 + j) = mean + factor.col(j);
    prior.col(1 + n + j) = mean - factor.col(j);
  }
  const auto propagated = randomNormal<Blocks::Points>(rng);
  const auto parameterPoints = randomNormal<Blocks::ParamPoints>(rng);
  const auto sensitivity = randomNormal<Blocks::StateByParam>(rng);
  const auto derivative = randomNormal<Blocks::StateByParam>(rng);
  const auto predicted = randomNormal<Blocks::StateByParam>(rng);
  const Matrix q = mjukf::testing::randomCovariance<n>(rng);
  const Eigen::Matrix<double, p, p> walk = mjukf::testing::randomCovariance<p>(rng);
  // ϑ, the half differences of the points' parameters.
  Eigen::Matrix<double, p, n> parameterSpread;
  for (int j = 0; j < n; ++j)
    parameterSpread.col(j) = (parameterPoints.col(1 + j) - parameterPoints.col(1 + n + j)) / 2;
  for (const bool refreshed : {true, false}) {
    const Blocks::StateByParam* d = refreshed ? &derivative : nullptr;
    ASSERT_TRUE(blocks.predict(prior, propagated, parameterPoints, sensitivity, d, predicted, q, walk, 1.5));
    ASSERT_TRUE(full.predict(prior, propagated, parameterPoints, sensitivity, d, predicted, q, walk, 1.5));
    Blocks::Points offTriangle = prior;
    // χ₁'s first component one ulp up: the half differences' (0, 1) entry is then half an ulp of it.
    offTriangle(0, 2) = std::nextafter(offTriangle(0, 2), 1e300);
    ASSERT_TRUE(blocksByLu.predict(offTriangle, propagated, parameterPoints, sensitivity, d, predicted, q, walk, 1.5));
    blocks.commit();
    blocksByLu.commit();
    full.commit();
    EXPECT_FALSE(blocks.committed() == blocksByLu.committed()) << "the triangle's path was not taken";
    const Matrix spread = refreshed ? Matrix(factor - sensitivity * parameterSpread) : factor;
    const double kappa = conditionNumber(spread);
    // A's relative error is n κ ε; it enters the prediction three times (A J Aᵀ and B = D − A W). The
    // factor 8 is a margin for the norms of the products' terms against the result's.
    const auto& expected = full.committed();
    EXPECT_LT((blocks.committed() - expected).norm(),
              8 * 3 * n * kappa * std::numeric_limits<double>::epsilon() * expected.norm())
        << (refreshed ? "refreshed" : "between refreshes") << ", κ " << kappa;
    EXPECT_TRUE(blocks.committed() == blocks.committed().transpose());
  }
}

// The test's threshold, χ²ₚ's upper quantile, against the closed forms of the tail: P(χ²₁ > x) =
// erfc(√(x/2)), P(χ²₂ > x) = e^(−x/2), P(χ²₄ > x) = e^(−x/2)(1 + x/2). Its asymptotic form is exact for
// p = 2 and 4 and off by the series' next term, (s − 1)(s − 2)/y² = 0.75/y² for p = 1 (y = x/2).
TEST(ParameterChangeDetector, TheThresholdIsTheChiSquaredQuantile) {
  for (const double alpha : {1e-6, 1e-9, 1e-12}) {
    const double x1 = mjukf::detail::chiSquaredUpperQuantile(1, alpha);
    const double x2 = mjukf::detail::chiSquaredUpperQuantile(2, alpha);
    const double x4 = mjukf::detail::chiSquaredUpperQuantile(4, alpha);
    EXPECT_NEAR(std::erfc(std::sqrt(x1 / 2)) / alpha, 1.0, 1.0 / (x1 * x1 / 4)) << alpha;
    EXPECT_NEAR(std::exp(-x2 / 2) / alpha, 1.0, 1e-10) << alpha;
    EXPECT_NEAR(std::exp(-x4 / 2) * (1 + x4 / 2) / alpha, 1.0, 1e-10) << alpha;
    EXPECT_LT(x1, x2);
    EXPECT_LT(x2, x4);
  }
}

// A scalar θ seen through y = ψ θ + v (v of standard deviation 1, ψ cycling over 0.5, 0.75, 1): with θ̂
// at the truth, 20,000 updates at α = 1e-9 raise no detection (the chance of one is at most 20,000 α =
// 2e-5 over these correlated tests); with θ off by 1 from update 5,000 and a memory of 200 updates, z
// grows by about ψ̄² ≈ 0.6 per update after the jump and passes χ²₁'s 37 within about 60, well within
// a memory. δ̂ = I⁻¹ s is the change as if it had been there over the whole window, so for a change
// inside the window it is smaller, of the right sign. The detection and δ̂ are the same, to rounding,
// when S is taken 100 times too small (ν and ψ whitened by a wrong L).
TEST(ParameterChangeDetector, FindsAJumpWithinAMemoryAndNothingWithout) {
  using Detector = mjukf::detail::ParameterChangeDetector<double, 1, 1>;
  const double lambda = std::exp(-1.0 / 200);
  const auto run = [&](double jump, double scale, long& detectedAt, double& estimate, long& detections) {
    Detector detector;
    detector.start(1e-9);
    std::mt19937_64 rng(17);
    std::normal_distribution<double> normal;
    detectedAt = -1;
    detections = 0;
    for (long k = 0; k < 20000; ++k) {
      const double psi = 0.5 + 0.25 * double(k % 3);
      const double offset = k >= 5000 ? jump : 0.0;
      const double nu = psi * offset + normal(rng);  // ν = y − ψ θ̂
      Eigen::Matrix<double, 1, 1> whitenedPsi, whitenedNu, change;
      whitenedPsi(0) = psi / scale;  // L = scale: S = scale²
      whitenedNu(0) = nu / scale;
      if (detector.update(whitenedPsi, whitenedNu, lambda, 20, true, change)) {
        ++detections;
        if (detectedAt < 0) {
          detectedAt = k;
          estimate = change(0);
        }
      }
      detector.commit();
    }
    EXPECT_EQ(detector.changes(), detections);
  };
  long at = 0, detections = 0;
  double estimate = 0;
  run(0.0, 1.0, at, estimate, detections);
  EXPECT_EQ(detections, 0) << "a false alarm at update " << at;
  run(1.0, 1.0, at, estimate, detections);
  ASSERT_GE(at, 5000);
  EXPECT_LT(at, 5200) << "found within a memory";
  EXPECT_GT(estimate, 0.0);
  EXPECT_LT(estimate, 1.0 + 4.0 / std::sqrt(0.25 * double(at - 5000 + 1))) << "no more than the jump and 4 σ";
  long atSmall = 0, detectionsSmall = 0;
  double estimateSmall = 0;
  run(1.0, 0.1, atSmall, estimateSmall, detectionsSmall);
  EXPECT_EQ(atSmall, at);
  EXPECT_NEAR(estimateSmall, estimate, 1e-9 * std::abs(estimate));
  EXPECT_EQ(detectionsSmall, detections);
}

// Innovations that a constant θ cannot explain (ν ≈ 10 σ every update): an armed test with α = 1e-9
// fires (the control, the first time once its window holds the threshold's 37 updates: z ≤ the count),
// a disarmed one (the filter still easing its steps in) keeps its window empty and never tests, and
// α = 0 never tests either.
TEST(ParameterChangeDetector, DisarmedOrWithoutAFalseAlarmProbabilityItNeverFires) {
  using Detector = mjukf::detail::ParameterChangeDetector<double, 1, 1>;
  Eigen::Matrix<double, 1, 1> psi, nu, change;
  psi(0) = 1;
  Detector armed, disarmed, off;
  armed.start(1e-9);
  disarmed.start(1e-9);
  off.start(0.0);
  EXPECT_EQ(off.threshold(), std::numeric_limits<double>::infinity());
  long firstDetection = -1;
  for (int k = 0; k < 1000; ++k) {
    nu(0) = k % 2 ? 10.0 : 9.0;
    if (armed.update(psi, nu, 0.99, 20, true, change) && firstDetection < 0) firstDetection = k;
    armed.commit();
    EXPECT_FALSE(disarmed.update(psi, nu, 0.99, 20, false, change));
    disarmed.commit();
    EXPECT_FALSE(off.update(psi, nu, 0.99, 20, true, change));
    off.commit();
  }
  EXPECT_EQ(firstDetection, long(std::ceil(armed.threshold())) - 1) << "the control fires as soon as it may";
  EXPECT_GT(armed.changes(), 10);
  EXPECT_EQ(disarmed.changes(), 0);
  EXPECT_EQ(disarmed.statistic(), 0.0) << "never tested";
  EXPECT_EQ(off.changes(), 0);
  EXPECT_EQ(off.statistic(), 0.0) << "never tested";
}

TYPED_TEST(EngineEstimate, CorrectionOfALinearMeasurementIsTheKalmanUpdate) {
  LinearCase c;
  using Est = typename TestFixture::Est;
  Est e = TestFixture::makeEstimate(c);
  ASSERT_EQ(e.draw(e.mean(), e.factor()), Status::Ok);
  for (int i = 0; i < Est::Count; ++i) e.measuredPoints().col(i) = c.C * e.workPoints().col(i);
  ASSERT_EQ(e.correct(e.workPoints(), e.measuredPoints(), e.prior(true), c.y, c.R, nullptr, c.noGate), Status::Ok);
  const Eigen::Matrix2d S = c.C * c.P * c.C.transpose() + c.R;
  const Eigen::Matrix<double, 3, 2> K = c.P * c.C.transpose() * S.inverse();
  const Eigen::Vector2d innovation = c.y - c.C * c.x;
  EXPECT_LT((e.candidateMean() - (c.x + K * innovation)).cwiseAbs().maxCoeff(), kTolerance);
  // The gain's factors: K = U S⁻¹ with S the lower factor of P_yy.
  const Eigen::Matrix2d s = e.innovationFactor();
  EXPECT_LT((s * s.transpose() - S).cwiseAbs().maxCoeff(), kTolerance);
  EXPECT_LT((e.gainFactor() * s.inverse() - K).cwiseAbs().maxCoeff(), kTolerance);
  ASSERT_EQ(e.settle(mjukf::CovarianceRepair<double>{}), Status::Ok);
  EXPECT_LT((e.candidateCovariance() - (c.P - K * S * K.transpose())).cwiseAbs().maxCoeff(), kTolerance);
  e.commitCorrection();
  EXPECT_NEAR(e.diagnostics().nis, innovation.dot(S.inverse() * innovation), kTolerance);
  EXPECT_LT((e.diagnostics().innovationCovariance - S).cwiseAbs().maxCoeff(), kTolerance);
}

TYPED_TEST(EngineEstimate, AMaskedCorrectionIsTheUpdateOfTheReducedModel) {
  LinearCase c;
  using Est = typename TestFixture::Est;
  Est e = TestFixture::makeEstimate(c);
  ASSERT_EQ(e.draw(e.mean(), e.factor()), Status::Ok);
  for (int i = 0; i < Est::Count; ++i) e.measuredPoints().col(i) = c.C * e.workPoints().col(i);
  Eigen::Vector2d y = c.y;
  y(1) = std::numeric_limits<double>::quiet_NaN();  // missing: never read
  const Eigen::Matrix<bool, 2, 1> present(true, false);
  ASSERT_EQ(e.correct(e.workPoints(), e.measuredPoints(), e.prior(true), y, c.R, &present, c.noGate), Status::Ok);
  const Eigen::RowVector3d c0 = c.C.row(0);
  const double s = c0 * c.P * c0.transpose() + c.R(0, 0);
  const Eigen::Vector3d k = c.P * c0.transpose() / s;
  EXPECT_LT((e.candidateMean() - (c.x + k * (c.y(0) - c0 * c.x))).cwiseAbs().maxCoeff(), kTolerance);
  ASSERT_EQ(e.settle(mjukf::CovarianceRepair<double>{}), Status::Ok);
  EXPECT_LT((e.candidateCovariance() - (c.P - k * s * k.transpose())).cwiseAbs().maxCoeff(), kTolerance);
}

TYPED_TEST(EngineEstimate, TheGateRefusesAnOutlierAndANonFiniteImageIsRefused) {
  LinearCase c;
  using Est = typename TestFixture::Est;
  Est e = TestFixture::makeEstimate(c);
  ASSERT_EQ(e.draw(e.mean(), e.factor()), Status::Ok);
  for (int i = 0; i < Est::Count; ++i) e.measuredPoints().col(i) = c.C * e.workPoints().col(i);
  const auto gate = mjukf::MeasurementGate<double, 2>::chiSquare(0.999);
  const Eigen::Vector2d outlier = c.C * c.x + Eigen::Vector2d(50.0, -50.0);
  EXPECT_EQ(e.correct(e.workPoints(), e.measuredPoints(), e.prior(true), outlier, c.R, nullptr, gate),
            Status::MeasurementRejected);
  e.measuredPoints()(1, 3) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(e.correct(e.workPoints(), e.measuredPoints(), e.prior(true), c.y, c.R, nullptr, c.noGate),
            Status::NonFiniteResult);
  EXPECT_EQ(e.mean(), c.x);  // nothing committed
}

TYPED_TEST(EngineEstimate, AssignRefusesWhatHasNoFactorAndChangesNothing) {
  LinearCase c;
  using Est = typename TestFixture::Est;
  Est e = TestFixture::makeEstimate(c);
  const Eigen::Matrix3d before = e.covariance();
  EXPECT_FALSE(e.assign(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Constant(1.0)));
  EXPECT_FALSE(e.assign(Eigen::Vector3d::Constant(NAN), Eigen::Matrix3d::Identity()));
  EXPECT_EQ(e.mean(), c.x);
  EXPECT_EQ(e.covariance(), before);
}

// A model's input signal that counts its evaluations; its value is a function of t alone, as model.hpp
// requires, and differs at every time asked below.
struct CountingSignal {
  using Scalar = double;
  using Input = Eigen::Vector2d;
  mutable int evaluations = 0;
  Input input(double t) const {
    ++evaluations;
    return Input(t, -3.0 * t);
  }
};

// The points of a time update ask for the same times in the same order (RK4: t, t + h/2 twice, t + h per
// step); each answer must be input(t) exactly. The first 7 distinct times are kept (three RK4 steps):
// input(t) is evaluated once for each of them and once per request of any later one, which replaces none
// of them (a replacement would make every request of the next point miss).
TEST(SharedSignalInput, AnswersEveryRequestWithInputAtThatTimeAndKeepsTheFirstTimes) {
  constexpr int kept = 7;
  // (steps, one more time after them): 3 steps fill the kept times exactly, one more is not kept.
  for (const auto& [steps, extra] : {std::pair{1, false}, {2, false}, {3, false}, {3, true}, {4, false}, {8, false}}) {
    const CountingSignal signal;
    const mjukf::detail::SharedSignalInput<CountingSignal> shared(signal);
    std::vector<double> times;
    for (int k = 0; k < steps; ++k)
      for (const double c : {0.0, 0.5, 0.5, 1.0}) times.push_back(0.1 * k + 0.1 * c);
    if (extra) times.push_back(-0.5);
    constexpr int points = 7;
    for (int i = 0; i < points; ++i)
      for (const double t : times) ASSERT_EQ(shared(t), signal.input(t)) << "steps " << steps << ", point " << i;
    // The distinct times in the order first asked (a step's end and the next one's start may round
    // apart), the first `kept` of them kept.
    std::vector<double> firstAsked;
    for (const double t : times)
      if (std::find(firstAsked.begin(), firstAsked.end(), t) == firstAsked.end()) firstAsked.push_back(t);
    const std::set<double> keptTimes(firstAsked.begin(), firstAsked.begin() + std::min<int>(kept, firstAsked.size()));
    const auto requestsNotKept =
        std::count_if(times.begin(), times.end(), [&](double t) { return !keptTimes.count(t); });
    const int evaluations = signal.evaluations - points * static_cast<int>(times.size());  // less the ASSERTs'
    EXPECT_EQ(evaluations, static_cast<int>(keptTimes.size()) + points * static_cast<int>(requestsNotKept))
        << "steps " << steps;
    if (steps <= 3 && !extra) {
      EXPECT_EQ(evaluations, static_cast<int>(firstAsked.size())) << "steps " << steps;
    }
    EXPECT_TRUE(shared.allValuesFinite());
    // Out of order: a time asked before, then the first one, then a new one.
    const std::size_t middle = times.size() / 2;
    EXPECT_EQ(shared(times[middle]), signal.input(times[middle]));
    EXPECT_EQ(shared(times[0]), signal.input(times[0]));
    EXPECT_EQ(shared(-1.0), signal.input(-1.0));
  }
}

}  // namespace
