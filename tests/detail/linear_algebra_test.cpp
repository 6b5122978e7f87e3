// detail/linear_algebra.hpp, kernel by kernel, against Eigen's general routines or the definition:
// the fixed-size Cholesky factor and its refusal margin, the triangular solves, the symmetrisation, the
// weighted moments, the whitening of a cross-covariance and the symmetric sigma-point draw. Tolerances
// are rounding bounds: a few ε times the size of the problem and of its entries.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <gtest/gtest.h>

#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/unscented_transform.hpp"
#include "random_matrix.hpp"
#include "test_support.hpp"

namespace {

using mjukf::detail::allFinite;
using mjukf::detail::choleskyLower;
using mjukf::testing::randomNormal;
constexpr double kEps = std::numeric_limits<double>::epsilon();

template <int N>
void expectCholeskyMatchesEigen(std::mt19937_64& rng) {
  const Eigen::Matrix<double, N, N> a = mjukf::testing::randomCovariance<N>(rng);
  Eigen::Matrix<double, N, N> s;
  ASSERT_TRUE(choleskyLower(a, s));
  const Eigen::Matrix<double, N, N> reference = a.llt().matrixL();
  // Backward stable: S Sᵀ = A + E with |E| ≤ c N ε |A|; the factors agree to the condition number.
  EXPECT_LT((s * s.transpose() - a).cwiseAbs().maxCoeff(), 4 * N * kEps * a.cwiseAbs().maxCoeff());
  EXPECT_LT((s - reference).cwiseAbs().maxCoeff(), 1e-10 * reference.cwiseAbs().maxCoeff());
  EXPECT_TRUE((s.template triangularView<Eigen::StrictlyUpper>().toDenseMatrix().array() == 0).all());
}

TEST(LinearAlgebra, CholeskyEqualsEigensAtEverySize) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    expectCholeskyMatchesEigen<1>(rng);
    expectCholeskyMatchesEigen<2>(rng);
    expectCholeskyMatchesEigen<6>(rng);
    expectCholeskyMatchesEigen<13>(rng);
  }
}

TEST(LinearAlgebra, CholeskyRefusesSingularIndefiniteAndNonFinite) {
  Eigen::Matrix3d s;
  EXPECT_FALSE(choleskyLower(Eigen::Matrix3d(Eigen::Matrix3d::Constant(0.5)), s));  // rank 1: pivots are rounding
  EXPECT_FALSE(choleskyLower(Eigen::Matrix3d(Eigen::Vector3d(1.0, -1e-3, 1.0).asDiagonal()), s));
  Eigen::Matrix3d nan = Eigen::Matrix3d::Identity();
  nan(2, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(choleskyLower(nan, s));
  EXPECT_FALSE(choleskyLower(Eigen::Matrix3d(Eigen::Vector3d::Constant(INFINITY).asDiagonal()), s));
}

TEST(LinearAlgebra, TriangularSolvesInvertTheFactor) {
  std::mt19937_64 rng(4);
  const Eigen::Matrix4d a = mjukf::testing::randomCovariance<4>(rng);
  Eigen::Matrix4d s;
  ASSERT_TRUE(choleskyLower(a, s));
  const Eigen::Matrix<double, 4, 3> b = Eigen::Matrix<double, 4, 3>::Random();
  Eigen::Matrix<double, 4, 3> x = b;
  mjukf::detail::solveLowerInPlace(s, x);  // S x = b
  EXPECT_LT((s * x - b).cwiseAbs().maxCoeff(), 100 * kEps);
  x = b;
  mjukf::detail::solveUpperInPlace(s, x);  // Sᵀ x = b
  EXPECT_LT((s.transpose() * x - b).cwiseAbs().maxCoeff(), 100 * kEps);
  // U = C S⁻ᵀ, i.e. U Sᵀ = C, column by column.
  const Eigen::Matrix<double, 3, 4> c = Eigen::Matrix<double, 3, 4>::Random();
  Eigen::Matrix<double, 3, 4> u = c;
  mjukf::detail::whitenColumns(s, u);
  EXPECT_LT((u * s.transpose() - c).cwiseAbs().maxCoeff(), 100 * kEps);
}

// smallLu writes out the algorithm Eigen's PartialPivLU runs up to 16 × 16: the same pivots and the same
// factors to the bit, ties between pivot candidates, exactly zero pivots and NaN included.
template <class Matrix>
void expectEigensLu(const Matrix& m, const char* what) {
  constexpr int N = Matrix::RowsAtCompileTime;
  using Scalar = typename Matrix::Scalar;
  const auto mine = mjukf::detail::smallLu(m);
  const Eigen::PartialPivLU<Matrix> eigens(m);
  // Transpositions P (row k swapped with row t(k), in turn): what smallLu stores.
  const Eigen::Transpositions<N, N, int> swaps(mine.rowSwaps);
  Eigen::PermutationMatrix<N, N, int> p;
  p = swaps;
  EXPECT_EQ(p.indices(), eigens.permutationP().indices()) << what;
  for (int j = 0; j < N; ++j)
    for (int i = 0; i < N; ++i) {
      const Scalar a = mine.lu(i, j), b = eigens.matrixLU()(i, j);
      EXPECT_TRUE(std::memcmp(&a, &b, sizeof a) == 0) << what << " (" << i << ", " << j << "): " << a << " vs " << b;
    }
}

TEST(LinearAlgebra, SmallLuIsEigensPartialPivLuBitForBit) {
  std::mt19937_64 rng(11);
  const auto random = randomNormal<Eigen::Matrix<double, 6, 6>>(rng);
  expectEigensLu(random, "random 6 x 6");
  const auto large = randomNormal<Eigen::Matrix<double, 16, 16>>(rng);  // the bound: Eigen's last unblocked size
  expectEigensLu(large, "random 16 x 16");
  // The MJUKF factors a row-major transpose, in double or float.
  const Eigen::Matrix<double, 6, 6, Eigen::RowMajor> rowMajor = random.transpose();
  expectEigensLu(rowMajor, "row-major 6 x 6");
  const Eigen::Matrix<float, 6, 6> single = random.cast<float>();
  expectEigensLu(single, "float 6 x 6");
  Eigen::Matrix4d ties;  // equal candidates in size: the first one is the pivot
  ties << 1, 2, 0, 1, -1, 0, 3, 2, 1, -2, 1, 0, 0, 1, 1, 1;
  expectEigensLu(ties, "ties");
  Eigen::Matrix4d zeroColumn = ties;  // an exactly zero pivot: left in place, the rest factored
  zeroColumn.col(1).setZero();
  expectEigensLu(zeroColumn, "zero pivot");
  Eigen::Matrix4d rankOne = Eigen::Vector4d(1, -2, 3, 0.5) * Eigen::RowVector4d(2, 1, -1, 4);
  expectEigensLu(rankOne, "rank one");
  Eigen::Matrix4d withNan = ties;
  withNan(2, 1) = std::numeric_limits<double>::quiet_NaN();
  expectEigensLu(withNan, "NaN");
  expectEigensLu(Eigen::Matrix<double, 1, 1>(-3.0), "1 x 1");
}

// The MJUKF's θ̂ covariance solves A M = C through M's partial-pivoting LU. Backward stable (Higham,
// Accuracy and Stability of Numerical Algorithms, Thm 9.4): (M + ΔM) X = B with |ΔM| ≤ γ₃ₙ Pᵀ|L||U|,
// so |M X − B| ≤ γ₃ₙ Pᵀ|L||U| |X|; a permuted M makes the pivoting matter. The bound holds for Eigen's
// partitioned LU above 16 × 16 too (the same operations in another order, Higham §13.1).
template <int N>
void expectBackwardStableSolves(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 20; ++trial) {
    auto m = randomNormal<Eigen::Matrix<double, N, N>>(rng);
    const auto b = randomNormal<Eigen::Matrix<double, N, 3>>(rng);
    m.row(0).swap(m.row(N - 1));
    const auto lu = mjukf::detail::partialPivotLu(m);
    Eigen::Matrix<double, N, 3> x = b;
    mjukf::detail::luSolveInPlace(lu, x);
    Eigen::Matrix<double, N, N> factors;
    Eigen::PermutationMatrix<N, N, int> p;
    if constexpr (N <= mjukf::detail::kUnblockedLuBound) {
      factors = lu.lu;
      p = Eigen::Transpositions<N, N, int>(lu.rowSwaps);
    } else {
      factors = lu.matrixLU();
      p = lu.permutationP();
    }
    const Eigen::Matrix<double, N, N> lower = factors.template triangularView<Eigen::UnitLower>();
    const Eigen::Matrix<double, N, N> upper = factors.template triangularView<Eigen::Upper>();
    // The residual in long double, so that its own rounding does not count against the bound.
    using Wide = Eigen::Matrix<long double, N, 3>;
    const Wide residual =
        (m.template cast<long double>() * x.template cast<long double>() - b.template cast<long double>()).cwiseAbs();
    const double gamma = 3 * N * kEps / (1 - 3 * N * kEps);
    const Eigen::Matrix<double, N, 3> bound =
        gamma * (p.transpose() * (lower.cwiseAbs() * upper.cwiseAbs())) * x.cwiseAbs();
    EXPECT_TRUE((residual.array() <= bound.template cast<long double>().array()).all()) << N << ": " << trial;
  }
}

TEST(LinearAlgebra, LuSolveIsBackwardStable) {
  expectBackwardStableSolves<6>(5);   // smallLu
  expectBackwardStableSolves<17>(6);  // above its bound: Eigen's PartialPivLU
}

// productWithTranspose against A Bᵀ in long double: each entry a sum of K products, in error by at most
// γ_K Σₖ |a(i, k)| |b(j, k)| (Higham §3.1). Shapes with rows left over below the last register block
// (R not a multiple of two packets) and a narrower last column block (C not a multiple of 4); Lower
// neither reads nor writes the strictly upper triangle (NaN left there stays), Subtract subtracts.
template <class Scalar, int R, int C, int K>
void expectProductWithTranspose(std::mt19937_64& rng) {
  using la = mjukf::detail::ProductPart;
  using Into = mjukf::detail::ProductInto;
  const auto a = randomNormal<Eigen::Matrix<Scalar, R, K>>(rng);
  const auto b = randomNormal<Eigen::Matrix<Scalar, C, K>>(rng);
  const Eigen::Matrix<long double, R, C> exact =
      a.template cast<long double>() * b.template cast<long double>().transpose();
  const double eps = std::numeric_limits<Scalar>::epsilon();
  const Eigen::Matrix<double, R, C> bound =
      K * eps / (1 - K * eps) *
      (a.template cast<double>().cwiseAbs() * b.template cast<double>().cwiseAbs().transpose());
  Eigen::Matrix<Scalar, R, C> full;
  mjukf::detail::productWithTranspose<la::Full, Into::Assign>(a, b, full);
  EXPECT_TRUE(
      ((full.template cast<long double>() - exact).cwiseAbs().array() <= bound.template cast<long double>().array())
          .all())
      << R << " x " << C << " x " << K;
  if constexpr (R == C) {
    const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
    Eigen::Matrix<Scalar, R, C> lower = Eigen::Matrix<Scalar, R, C>::Constant(nan);
    mjukf::detail::productWithTranspose<la::Lower, Into::Assign>(a, b, lower);
    Eigen::Matrix<Scalar, R, C> reduced = Eigen::Matrix<Scalar, R, C>::Constant(nan);
    reduced.template triangularView<Eigen::Lower>().setConstant(Scalar(1));
    mjukf::detail::productWithTranspose<la::Lower, Into::Subtract>(a, b, reduced);
    for (int j = 0; j < C; ++j)
      for (int i = 0; i < R; ++i) {
        if (i < j) {
          EXPECT_TRUE(std::isnan(lower(i, j)) && std::isnan(reduced(i, j))) << i << ", " << j;
          continue;
        }
        EXPECT_EQ(lower(i, j), full(i, j)) << i << ", " << j;  // the same sum as the full product's
        EXPECT_EQ(reduced(i, j), Scalar(1) - full(i, j)) << i << ", " << j;
      }
  }
}

TEST(LinearAlgebra, ProductWithTransposeIsABTransposed) {
  std::mt19937_64 rng(17);
  expectProductWithTranspose<double, 1, 1, 1>(rng);
  expectProductWithTranspose<double, 1, 6, 9>(rng);  // a single row, which Eigen stores row-major
  expectProductWithTranspose<double, 6, 1, 9>(rng);  // … and a single measurement
  expectProductWithTranspose<double, 1, 1, 9>(rng);
  expectProductWithTranspose<double, 3, 5, 7>(rng);     // no full block of rows
  expectProductWithTranspose<double, 9, 9, 19>(rng);    // one row and one column left over
  expectProductWithTranspose<double, 36, 16, 73>(rng);  // the chain's n = 32 JUKF: P_xy
  expectProductWithTranspose<double, 36, 36, 73>(rng);  // … and P⁻
  expectProductWithTranspose<float, 17, 17, 35>(rng);   // float: blocks of 8 rows, a diagonal inside one
  expectProductWithTranspose<float, 12, 5, 3>(rng);
}

// A plant with one measurement: its deviations are a single row, which Eigen stores row-major. The
// general form of P_xy (from crossProduct on) takes it as the coefficient-wise one does, to the rounding
// of two sums of Count products in different orders: 2 γ_{Count+2} Σ |Wᵢ| |dᵢ| |eᵢ|.
TEST(LinearAlgebra, CrossCovarianceOfASingleMeasurement) {
  constexpr int L = 12, Count = 2 * L + 1;
  const Eigen::Matrix<double, L, Count> d = Eigen::Matrix<double, L, Count>::Random();
  const Eigen::Matrix<double, 1, Count> e = Eigen::Matrix<double, 1, Count>::Random();
  const Eigen::Matrix<double, Count, 1> w = Eigen::Matrix<double, Count, 1>::Random();
  Eigen::Matrix<double, L, 1> general, coefficientwise;
  mjukf::detail::weightedOuterSumProduct(d, e, w, general);
  mjukf::detail::weightedOuterSumCoefficientwise(d, e, w, coefficientwise);
  const double gamma = (Count + 2) * kEps / (1 - (Count + 2) * kEps);
  const Eigen::Matrix<double, L, 1> bound =
      2 * gamma * (d.cwiseAbs() * w.cwiseAbs().asDiagonal() * e.cwiseAbs().transpose());
  EXPECT_TRUE(((general - coefficientwise).cwiseAbs().array() <= bound.array()).all());
}

// weightColumns and deviationsFrom form each coefficient by one multiplication or subtraction, as Eigen's
// expressions do: the same bits (compared as bytes, so that −0 and +0 differ) for plain matrices and for
// blocks of a larger one, whose columns are further apart and whose neighbours must stay untouched; rows a
// multiple of the packet size or not, a single row (which Eigen stores row-major), float and double. Where
// Eigen has no vector unit the two functions are Eigen's expressions, and this compares them with
// themselves.
template <class Scalar, int R, int K>
void expectColumnMapsAreEigens(std::mt19937_64& rng) {
  using Points = Eigen::Matrix<Scalar, R, K>;
  const auto points = randomNormal<Points>(rng);
  const auto center = randomNormal<Eigen::Matrix<Scalar, R, 1>>(rng);
  const auto weights = randomNormal<Eigen::Matrix<Scalar, K, 1>>(rng);
  const auto sameBytes = [](const auto& a, const auto& b) {
    for (int k = 0; k < K; ++k)
      for (int i = 0; i < R; ++i)
        if (std::memcmp(&a(i, k), &b(i, k), sizeof(Scalar)) != 0) return false;
    return true;
  };
  // Into a plain matrix, and into a block with a sentinel row above and below and a sentinel column.
  constexpr Scalar kSentinel = Scalar(-7.25);
  Eigen::Matrix<Scalar, R + 2, K + 1> framed = Eigen::Matrix<Scalar, R + 2, K + 1>::Constant(kSentinel);
  auto inner = framed.template block<R, K>(1, 0);
  const auto untouched = [&] {
    Eigen::Matrix<Scalar, R + 2, K + 1> copy = framed;
    copy.template block<R, K>(1, 0).setConstant(kSentinel);
    return (copy.array() == kSentinel).all();
  };
  Points mine;
  const Points weighted = points * weights.asDiagonal();
  mjukf::detail::weightColumns(points, weights, mine);
  EXPECT_TRUE(sameBytes(mine, weighted)) << R << " x " << K;
  mjukf::detail::weightColumns(points, weights, inner);
  EXPECT_TRUE(sameBytes(inner, weighted) && untouched()) << R << " x " << K << ", block";
  const Points deviations = points.colwise() - center;
  mjukf::detail::deviationsFrom(points, center, mine);
  EXPECT_TRUE(sameBytes(mine, deviations)) << R << " x " << K;
  mjukf::detail::deviationsFrom(points, center, inner);
  EXPECT_TRUE(sameBytes(inner, deviations) && untouched()) << R << " x " << K << ", block";
  Points inPlace = points;  // as the dual UKF forms its measurement deviations
  mjukf::detail::deviationsFrom(inPlace, center, inPlace);
  EXPECT_TRUE(sameBytes(inPlace, deviations)) << R << " x " << K << ", in place";
}

// Weights and a centre that are not plain vectors (a row of a matrix, transposed: its coefficients are
// apart in memory; an expression) are read as their values, as Eigen's expressions read them. A first
// version read them as contiguous memory and gave a wrong covariance through the public
// unscentedCovarianceFromDeviations at L ≥ 9, where the weighted sums take weightColumns.
TEST(LinearAlgebra, ColumnMapsReadStridedWeightsAndCentresByValue) {
  constexpr int L = 12, Count = 2 * L + 1;
  std::mt19937_64 rng(20);
  const auto d = randomNormal<Eigen::Matrix<double, L, Count>>(rng);
  const auto weightRows = randomNormal<Eigen::Matrix<double, 2, Count>>(rng);
  const auto centreRows = randomNormal<Eigen::Matrix<double, 2, L>>(rng);
  const Eigen::Matrix<double, Count, 1> weights = weightRows.row(1).transpose();
  const Eigen::Matrix<double, L, 1> centre = centreRows.row(1).transpose();
  Eigen::Matrix<double, L, Count> fromPlain, fromStrided;
  mjukf::detail::weightColumns(d, weights, fromPlain);
  mjukf::detail::weightColumns(d, weightRows.row(1).transpose(), fromStrided);
  EXPECT_EQ(fromStrided, fromPlain);
  mjukf::detail::weightColumns(d, 2 * weights, fromStrided);
  EXPECT_EQ(fromStrided, (d * (2 * weights).asDiagonal()).eval());
  mjukf::detail::deviationsFrom(d, centre, fromPlain);
  mjukf::detail::deviationsFrom(d, centreRows.row(1).transpose(), fromStrided);
  EXPECT_EQ(fromStrided, fromPlain);
  Eigen::Matrix<double, L, L> plain, strided;
  mjukf::unscentedCovarianceFromDeviations(d, d, weights, plain);
  mjukf::unscentedCovarianceFromDeviations(d, d, weightRows.row(1).transpose(), strided);
  EXPECT_EQ(strided, plain);
}

TEST(LinearAlgebra, ColumnMapsAreEigensExpressionsBitForBit) {
  std::mt19937_64 rng(19);
  expectColumnMapsAreEigens<double, 1, 9>(rng);
  expectColumnMapsAreEigens<double, 3, 7>(rng);
  expectColumnMapsAreEigens<double, 4, 9>(rng);
  expectColumnMapsAreEigens<double, 16, 33>(rng);
  expectColumnMapsAreEigens<double, 33, 67>(rng);
  expectColumnMapsAreEigens<float, 1, 5>(rng);
  expectColumnMapsAreEigens<float, 6, 13>(rng);
  expectColumnMapsAreEigens<float, 8, 17>(rng);
  expectColumnMapsAreEigens<float, 16, 33>(rng);
  expectColumnMapsAreEigens<float, 17, 35>(rng);
}

// On x86-64 without FMA, where Eigen's GEMM kernel sums every entry in order of k with one accumulator,
// as productWithTranspose does: the same bits as Eigen's product (the claim in linear_algebra.hpp).
#if defined(__x86_64__) && !defined(__FMA__)
TEST(LinearAlgebra, ProductWithTransposeHasEigensBitsOnX86) {
  std::mt19937_64 rng(18);
  const auto a = randomNormal<Eigen::Matrix<double, 36, 73>>(rng);
  const auto b = randomNormal<Eigen::Matrix<double, 16, 73>>(rng);
  Eigen::Matrix<double, 36, 16> mine, eigens;
  mjukf::detail::productWithTranspose<mjukf::detail::ProductPart::Full, mjukf::detail::ProductInto::Assign>(a, b, mine);
  eigens.noalias() = a * b.transpose();
  EXPECT_EQ(mine, eigens);
}
#endif

TEST(LinearAlgebra, SymmetrizeAveragesTheTwoTrianglesAndKeepsTheDiagonal) {
  Eigen::Matrix3d p;
  p << 1, 2, 3, 4, 5, 6, 7, 8, 9;
  mjukf::detail::symmetrize(p);
  Eigen::Matrix3d expected;
  expected << 1, 3, 5, 3, 5, 7, 5, 7, 9;
  EXPECT_EQ(p, expected);
  Eigen::Matrix2d huge;  // halved before the sum: no overflow near the largest double
  huge << 1, 1.5e308, 1.7e308, 1;
  mjukf::detail::symmetrize(huge);
  EXPECT_TRUE(allFinite(huge));
}

TEST(LinearAlgebra, WeightedMomentsAreTheirDefinitions) {
  std::mt19937_64 rng(5);
  const Eigen::Matrix<double, 3, 7> a = Eigen::Matrix<double, 3, 7>::Random();
  const Eigen::Matrix<double, 2, 7> b = Eigen::Matrix<double, 2, 7>::Random();
  const Eigen::Matrix<double, 7, 1> w = Eigen::Matrix<double, 7, 1>::Random();
  Eigen::Vector3d mean;
  mjukf::detail::weightedMean(a, w, mean);
  Eigen::Matrix<double, 3, 2> outer;
  mjukf::detail::weightedOuterSum(a, b, w, outer);
  Eigen::Vector3d meanByHand = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, 2> outerByHand = Eigen::Matrix<double, 3, 2>::Zero();
  for (int i = 0; i < 7; ++i) {
    meanByHand += w(i) * a.col(i);
    outerByHand += w(i) * a.col(i) * b.col(i).transpose();
  }
  EXPECT_LT((mean - meanByHand).cwiseAbs().maxCoeff(), 16 * kEps);
  EXPECT_LT((outer - outerByHand).cwiseAbs().maxCoeff(), 16 * kEps);
}

TEST(LinearAlgebra, SymmetricDrawWithAndWithoutCentre) {
  Eigen::Matrix2d s;
  s << 2, 0, 1, 3;
  const Eigen::Vector2d mean(10, 20);
  Eigen::Matrix<double, 2, 5> merwe;
  mjukf::detail::drawSymmetricPoints<true>(mean, s, 0.5, merwe);
  Eigen::Matrix<double, 2, 5> expected;
  expected << 10, 11, 10, 9, 10,  //
      20, 20.5, 21.5, 19.5, 18.5;
  EXPECT_EQ(merwe, expected);
  Eigen::Matrix<double, 2, 4> cubature;
  mjukf::detail::drawSymmetricPoints<false>(mean, s, 0.5, cubature);
  EXPECT_EQ(cubature, expected.rightCols<4>());
}

TEST(LinearAlgebra, FinitenessChecks) {
  Eigen::Vector3d y(1, 2, 3);
  EXPECT_TRUE(allFinite(y));
  y(1) = -INFINITY;
  EXPECT_FALSE(allFinite(y));
  Eigen::Matrix<bool, 3, 1> present(true, false, true);
  EXPECT_TRUE(mjukf::detail::presentComponentsFinite(y, &present));  // the missing one is ignored
  EXPECT_FALSE(mjukf::detail::presentComponentsFinite(y, static_cast<const Eigen::Matrix<bool, 3, 1>*>(nullptr)));
}

// The PSD part of a symmetric matrix (the MJUKF's floor of P⁻, docs/algorithms.md §5.2) against
// Eigen's eigensolver: A⁺ = V max(D, 0) Vᵀ. The map A → A⁺ is 1-Lipschitz in the Frobenius norm, so an
// A⁺ computed from a backward-stable decomposition (Jacobi: V D Vᵀ = A + F, |F| ≤ c N ε |A|) is within
// that of the true one; 8 N ε |A|_F bounds both computations' errors together.
template <int N>
void expectPositivePartMatchesEigen(std::mt19937_64& rng) {
  using Matrix = Eigen::Matrix<double, N, N>;
  const Matrix a = mjukf::testing::randomSymmetric<N>(rng);
  Matrix e;
  ASSERT_TRUE(mjukf::detail::positivePartFactor(a, e));
  const Eigen::SelfAdjointEigenSolver<Matrix> reference(a);
  const Matrix positive = reference.eigenvectors() * reference.eigenvalues().cwiseMax(0.0).asDiagonal() *
                          reference.eigenvectors().transpose();
  EXPECT_LT((e * e.transpose() - positive).norm(), 8 * N * kEps * a.norm()) << a;
}

// From N = 5 positivePartFactor takes Eigen's tridiagonal solver instead of Jacobi rotations: the two
// algorithms agree to the same bound, and the result has the positive part's defining properties:
// A⁺ − A = A⁻ is positive semi-definite and A⁺ A⁻ = 0 (the two parts live on orthogonal eigenspaces).
template <int N>
void expectTridiagonalPositivePartMatchesJacobi(std::mt19937_64& rng) {
  using Matrix = Eigen::Matrix<double, N, N>;
  const Matrix a = mjukf::testing::randomSymmetric<N>(rng);
  Matrix byRotations, bySolver;
  ASSERT_TRUE(mjukf::detail::positivePartFactorJacobi(a, byRotations));
  ASSERT_TRUE(mjukf::detail::positivePartFactorTridiagonal(a, bySolver));
  const Matrix positive = bySolver * bySolver.transpose();
  const double bound = 8 * N * kEps * a.norm();
  EXPECT_LT((byRotations * byRotations.transpose() - positive).norm(), bound);
  const Matrix negative = positive - a;
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix>(negative).eigenvalues().minCoeff(), -bound);
  EXPECT_LT((positive * negative).norm(), bound * a.norm());
}

TEST(LinearAlgebra, PositivePartFactorBySolverMatchesRotations) {
  static_assert(mjukf::detail::kTridiagonalPositivePartFrom == 5);
  std::mt19937_64 rng(17);
  for (int trial = 0; trial < 20; ++trial) {
    expectTridiagonalPositivePartMatchesJacobi<5>(rng);
    expectTridiagonalPositivePartMatchesJacobi<8>(rng);
    expectTridiagonalPositivePartMatchesJacobi<16>(rng);
    expectTridiagonalPositivePartMatchesJacobi<32>(rng);
  }
  // Both scale A by a power of two first: the all-ones 8 × 8 times max/4 has the eigenvalue 2 max, whose
  // square root is finite (Eigen's own scaling by the largest entry overflowed it), and a subnormal A is
  // decomposed (2⁻ᵏ for its k overflowed in one power). The positive part of c 1 1ᵀ is all of it.
  using Matrix8 = Eigen::Matrix<double, 8, 8>;
  for (const double c : {std::numeric_limits<double>::max() / 4, 1e-310}) {
    const Matrix8 a = Matrix8::Constant(c);
    Matrix8 bySolver, byRotations;
    ASSERT_TRUE(mjukf::detail::positivePartFactorTridiagonal(a, bySolver)) << c;
    ASSERT_TRUE(mjukf::detail::positivePartFactorJacobi(a, byRotations)) << c;
    // Compared as (E Eᵀ) / c entry by entry, E / √c first so that nothing overflows.
    for (const Matrix8* e : {&bySolver, &byRotations}) {
      const Matrix8 unit = *e / std::sqrt(c);
      EXPECT_LT((unit * unit.transpose() - Matrix8::Ones()).cwiseAbs().maxCoeff(), 64 * kEps) << c;
    }
  }
}

TEST(LinearAlgebra, PositivePartFactorIsThePositiveSemiDefinitePart) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    expectPositivePartMatchesEigen<1>(rng);
    expectPositivePartMatchesEigen<2>(rng);
    expectPositivePartMatchesEigen<3>(rng);
    expectPositivePartMatchesEigen<4>(rng);
    expectPositivePartMatchesEigen<6>(rng);
  }
  // Semi-definite: all of it; negative definite: none of it, exactly; not finite: refused.
  std::mt19937_64 other(5);
  const Eigen::Matrix4d covariance = mjukf::testing::randomCovariance<4>(other);
  Eigen::Matrix4d e;
  ASSERT_TRUE(mjukf::detail::positivePartFactor(covariance, e));
  EXPECT_LT((e * e.transpose() - covariance).norm(), 32 * kEps * covariance.norm());
  ASSERT_TRUE(mjukf::detail::positivePartFactor(Eigen::Matrix4d(-covariance), e));
  EXPECT_TRUE((e.array() == 0).all()) << e;
  Eigen::Matrix4d broken = covariance;
  broken(1, 2) = broken(2, 1) = std::nan("");
  EXPECT_FALSE(mjukf::detail::positivePartFactor(broken, e));
  // Scaled by an even power of two inside: bit for bit the same result for A and 4ᵏ A scaled back, and
  // a finite A near the overflow threshold (|A|²_F = inf) is decomposed, not left at its diagonal:
  // [[1, 2], [2, 1]] has the eigenvalues 3 and −1, so its positive part is 1.5 everywhere.
  const Eigen::Matrix4d indefinite = covariance - 2 * mjukf::testing::randomCovariance<4>(other);
  Eigen::Matrix4d scaled;
  ASSERT_TRUE(mjukf::detail::positivePartFactor(indefinite, e));
  ASSERT_TRUE(mjukf::detail::positivePartFactor(Eigen::Matrix4d(indefinite * 0x1p40), scaled));
  EXPECT_TRUE((scaled * 0x1p-20 == e)) << "scaling by 4^20 changed the rounding";
  const Eigen::Matrix2d huge = (Eigen::Matrix2d() << 1, 2, 2, 1).finished() * 1e300;
  Eigen::Matrix2d hugeFactor;
  ASSERT_TRUE(mjukf::detail::positivePartFactor(huge, hugeFactor));
  EXPECT_LT(((hugeFactor * hugeFactor.transpose()) / 1e300 - Eigen::Matrix2d::Constant(1.5)).norm(), 32 * kEps);
}

}  // namespace
