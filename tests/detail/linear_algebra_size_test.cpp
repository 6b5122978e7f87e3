// The kernels of detail/linear_algebra.hpp that are chosen by size: each general (large-size) form
// against the written-out form it replaces, on random inputs at sizes on both sides of its threshold,
// to tolerances derived from the rounding of the two computations (below); the dispatcher at each size
// equals the form its threshold names; and the Cholesky by columns refuses what the unrolled one refuses.
//
// Tolerances. Both forms compute the same sums of the same products in another order. A sum of K
// products computed in any order has an error of at most γ_K Σ|termₖ| (γ_K = K ε / (1 − K ε), Higham,
// Accuracy and Stability of Numerical Algorithms, §3.1), with two more roundings for a term Wᵢ aᵢ bᵢ;
// two such sums differ by at most twice that:
//   outer sums, K = Count points:  |Δ|ᵢⱼ ≤ 2 γ_{Count+2} (|A| |W| |B|ᵀ)ᵢⱼ;
//   P − U Uᵀ, U with m columns:     |Δ|ᵢⱼ ≤ 2 γ_{m+1} (|P| + |U| |U|ᵀ)ᵢⱼ.
// The Cholesky factors: each is backward stable, S Sᵀ = A + E with |E| ≤ γ_{N+1} |S| |S|ᵀ (Higham
// Thm 10.3), so ‖E‖_F ≤ γ_{N+1} N ‖A‖₂ (‖|S||S|ᵀ‖_F ≤ ‖S‖_F² ≤ N ‖A‖₂), and a perturbation E of A moves
// its factor by ‖ΔS‖_F ≤ κ₂(A) ‖E‖_F / (√2 ‖A‖₂) ‖S‖₂ to first order (Sun's bound, Higham Thm 10.8);
// the two factors differ by at most twice that: ‖S₁ − S₂‖_F ≤ √2 κ₂(A) N γ_{N+1} ‖S‖₂. The factor 2
// on top of each bound covers the first-order terms left out (the inputs keep Kε ≪ 1).

#include <cmath>
#include <limits>
#include <random>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "mjukf/detail/linear_algebra.hpp"
#include "random_matrix.hpp"

namespace {

namespace la = mjukf::detail;
using mjukf::testing::randomNormal;

template <class Scalar>
constexpr double gamma(int k) {
  const double u = std::numeric_limits<Scalar>::epsilon();
  return k * u / (1 - k * u);
}

// Random SPD matrix A = F Fᵀ + 0.1 N I, its condition number below a few hundred.
template <class Scalar, int N>
Eigen::Matrix<Scalar, N, N> randomSpd(std::mt19937_64& rng) {
  const auto f = randomNormal<Eigen::Matrix<double, N, N>>(rng);
  const Eigen::Matrix<double, N, N> a = f * f.transpose() + 0.1 * N * Eigen::Matrix<double, N, N>::Identity();
  return a.template cast<Scalar>();
}

// Weights of van der Merwe's set with α = 0.5 (a negative centre weight, as the filters can have).
template <class Scalar, int Count>
Eigen::Matrix<Scalar, Count, 1> weights() {
  constexpr int L = Count / 2;
  const double alpha = 0.5, lambda = alpha * alpha * L - L;
  Eigen::Matrix<Scalar, Count, 1> w = Eigen::Matrix<Scalar, Count, 1>::Constant(Scalar(1 / (2 * (L + lambda))));
  w(0) = Scalar(lambda / (L + lambda) + (1 - alpha * alpha + 2));
  return w;
}

template <class Scalar, int L>
void expectOuterSumsAgree(std::mt19937_64& rng) {
  constexpr int Count = 2 * L + 1, M = (L + 1) / 2;
  const auto d = randomNormal<Eigen::Matrix<Scalar, L, Count>>(rng);
  const auto e = randomNormal<Eigen::Matrix<Scalar, M, Count>>(rng);
  const auto w = weights<Scalar, Count>();
  Eigen::Matrix<Scalar, L, L> old, lower, gemm, triangle, chosen;
  la::weightedOuterSumCoefficientwise(d, d, w, old);
  la::weightedCovarianceLowerCoefficientwise(d, w, lower);
  la::mirrorLowerTriangle(lower);
  la::weightedOuterSumProduct(d, d, w, gemm);
  la::mirrorLowerTriangle(gemm);
  la::weightedCovarianceLowerTriangle(d, w, triangle);
  la::mirrorLowerTriangle(triangle);
  la::weightedCovariance(d, w, chosen);
  const Eigen::Matrix<double, L, L> bound =
      2 * 2 * gamma<Scalar>(Count + 2) *
      (d.cwiseAbs() * w.cwiseAbs().asDiagonal() * d.cwiseAbs().transpose()).template cast<double>();
  EXPECT_TRUE(((gemm - old).template cast<double>().cwiseAbs().array() <= bound.array()).all()) << "L = " << L;
  EXPECT_TRUE(((triangle - old).template cast<double>().cwiseAbs().array() <= bound.array()).all()) << "L = " << L;
  EXPECT_TRUE(((lower - old).template cast<double>().cwiseAbs().array() <= bound.array()).all()) << "L = " << L;
  const auto sizes = la::generalKernelsFrom<Scalar>;
  EXPECT_EQ(chosen, L >= sizes.covarianceProduct ? triangle : lower) << "L = " << L;
  // The lower triangle by register blocks is the full product's, entry by entry (the same sums).
  using Square = Eigen::Matrix<Scalar, L, L>;
  const Square triangleLower = triangle.template triangularView<Eigen::Lower>();
  const Square gemmLower = gemm.template triangularView<Eigen::Lower>();
  EXPECT_EQ(triangleLower, gemmLower) << "L = " << L;
  EXPECT_EQ(chosen, chosen.transpose()) << "L = " << L;  // mirrored: exactly symmetric

  Eigen::Matrix<Scalar, L, M> crossOld, crossNew, crossChosen;
  la::weightedOuterSumCoefficientwise(d, e, w, crossOld);
  la::weightedOuterSumProduct(d, e, w, crossNew);
  la::weightedOuterSum(d, e, w, crossChosen);
  const Eigen::Matrix<double, L, M> crossBound =
      2 * 2 * gamma<Scalar>(Count + 2) *
      (d.cwiseAbs() * w.cwiseAbs().asDiagonal() * e.cwiseAbs().transpose()).template cast<double>();
  EXPECT_TRUE(((crossNew - crossOld).template cast<double>().cwiseAbs().array() <= crossBound.array()).all());
  EXPECT_EQ(crossChosen, L >= sizes.crossProduct ? crossNew : crossOld) << "L = " << L;
}

template <class Scalar, int L>
void expectSubtractionsAgree(std::mt19937_64& rng) {
  constexpr int M = (L + 1) / 2;
  const Eigen::Matrix<Scalar, L, L> p = randomSpd<Scalar, L>(rng);
  const auto u = randomNormal<Eigen::Matrix<Scalar, L, M>>(rng, 0.1);
  Eigen::Matrix<Scalar, L, L> old = p, rank = p, chosen = p;
  la::subtractOuterCoefficientwise(old, u);
  la::subtractOuterRankUpdate(rank, u);
  la::subtractOuter(chosen, u);
  const Eigen::Matrix<double, L, L> bound =
      2 * 2 * gamma<Scalar>(M + 1) * (p.cwiseAbs() + u.cwiseAbs() * u.cwiseAbs().transpose()).template cast<double>();
  EXPECT_TRUE(((rank - old).template cast<double>().cwiseAbs().array() <= bound.array()).all()) << "L = " << L;
  EXPECT_EQ(rank, rank.transpose());
  // Both forms are exactly symmetric (one triangle, mirrored): what settle() takes without symmetrising.
  EXPECT_EQ(old, old.transpose()) << "L = " << L;
  EXPECT_EQ(chosen, L >= la::generalKernelsFrom<Scalar>.subtractRankUpdate ? rank : old) << "L = " << L;
}

template <class Scalar, int N>
void expectFactorsAgree(std::mt19937_64& rng) {
  const Eigen::Matrix<Scalar, N, N> a = randomSpd<Scalar, N>(rng);
  Eigen::Matrix<Scalar, N, N> unrolled, byColumns, chosen;
  // The unrolled factor's code and compile time grow as N³: from the threshold on, where the library no
  // longer instantiates it, the reference is Eigen's LLT (backward stable as well: the same bound).
  if constexpr (N < la::generalKernelsFrom<Scalar>.cholesky) {
    ASSERT_TRUE(la::choleskyLowerUnrolled(a, unrolled));
  } else {
    unrolled = a.llt().matrixL();
  }
  ASSERT_TRUE(la::choleskyLowerByColumns(a, byColumns));
  ASSERT_TRUE(la::choleskyLower(a, chosen));
  const Eigen::Matrix<double, N, N> ad = a.template cast<double>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> eigen(ad);
  const double kappa = eigen.eigenvalues().maxCoeff() / eigen.eigenvalues().minCoeff();
  const double normS = std::sqrt(eigen.eigenvalues().maxCoeff());  // ‖S‖₂ = ‖A‖₂^½
  const double bound = 2 * std::sqrt(2.0) * kappa * N * gamma<Scalar>(N + 1) * normS;
  EXPECT_LE((byColumns - unrolled).template cast<double>().norm(), bound) << "N = " << N << ", κ = " << kappa;
  EXPECT_TRUE((byColumns.template triangularView<Eigen::StrictlyUpper>().toDenseMatrix().array() == 0).all());
  EXPECT_EQ(chosen, N >= la::generalKernelsFrom<Scalar>.cholesky ? byColumns : unrolled) << "N = " << N;
}

// What the unrolled factor refuses, the one by columns refuses: rank one (pivots of rounding), indefinite,
// NaN below the diagonal, Inf on it.
template <class Scalar, int N>
void expectSameRefusals() {
  using Matrix = Eigen::Matrix<Scalar, N, N>;
  Matrix s;
  const Matrix rankOne = Matrix::Constant(Scalar(0.5));
  Matrix indefinite = Matrix::Identity();
  indefinite(N - 1, N - 1) = Scalar(-1e-3);
  Matrix nan = Matrix::Identity();
  nan(N - 1, N - 2) = std::numeric_limits<Scalar>::quiet_NaN();
  const Matrix inf = Matrix::Identity() * std::numeric_limits<Scalar>::infinity();
  const Matrix* refused[] = {&rankOne, &indefinite, &nan, &inf};
  for (const Matrix* m : refused) {
    if constexpr (N < la::generalKernelsFrom<Scalar>.cholesky) {
      EXPECT_FALSE(la::choleskyLowerUnrolled(*m, s));
    }
    EXPECT_FALSE(la::choleskyLowerByColumns(*m, s));
  }
  // Just above and below the margin N ε a_jj on the last pivot: the same verdict from both.
  for (const double factor : {0.5, 4.0}) {
    Matrix nearSingular = Matrix::Identity();
    nearSingular(N - 1, N - 1) = Scalar(1 + factor * N * std::numeric_limits<Scalar>::epsilon());
    nearSingular(N - 1, 0) = nearSingular(0, N - 1) = Scalar(1);
    EXPECT_EQ(la::choleskyLowerByColumns(nearSingular, s), factor > 1) << factor;
    if constexpr (N < la::generalKernelsFrom<Scalar>.cholesky) {
      EXPECT_EQ(la::choleskyLowerUnrolled(nearSingular, s), factor > 1) << factor;
    }
  }
}

template <class Scalar, int L>
void expectAllAgree(std::mt19937_64& rng) {
  for (int trial = 0; trial < 10; ++trial) {
    expectOuterSumsAgree<Scalar, L>(rng);
    expectSubtractionsAgree<Scalar, L>(rng);
    expectFactorsAgree<Scalar, L>(rng);
  }
}

// Sizes on both sides of each threshold (double 9, 11, 20: 8 | 9, 9 | 11, 11 | 20; float 9, 14, 24,
// 28: 8 | 14, 8 | 14, 14 | 28, 14 | 28) and the chain's largest L = 36 (where Eigen's LLT takes its
// blocked path, from 32). Few sizes: the unrolled factor costs minutes of compile time at L ≈ 20.
TEST(LinearAlgebraBySize, GeneralFormsAgreeWithTheWrittenOutOnesDouble) {
  std::mt19937_64 rng(21);
  expectAllAgree<double, 8>(rng);
  expectAllAgree<double, 9>(rng);
  expectAllAgree<double, 11>(rng);
  expectAllAgree<double, 20>(rng);
  expectAllAgree<double, 36>(rng);
}

TEST(LinearAlgebraBySize, GeneralFormsAgreeWithTheWrittenOutOnesFloat) {
  std::mt19937_64 rng(22);
  expectAllAgree<float, 8>(rng);
  expectAllAgree<float, 14>(rng);
  expectAllAgree<float, 28>(rng);
  expectAllAgree<float, 36>(rng);
}

TEST(LinearAlgebraBySize, CholeskyByColumnsRefusesWhatTheUnrolledOneRefuses) {
  expectSameRefusals<double, 4>();
  expectSameRefusals<double, 11>();
  expectSameRefusals<double, 36>();
  expectSameRefusals<float, 36>();
}

}  // namespace
