// The square-root factors of detail/linear_algebra.hpp (the square-root form's kernels), in double and
// float, N = 1, 2, 4, 7 (the filters' L is 2–7 on the known plants; a larger N costs gigabytes of
// compiler memory with these unrolled kernels and tests no other code path):
// results against Eigen's LLT of the formed matrix in long double, refusals (rank deficiency, an
// indefinite downdate, NaN and Inf, overflow), and no heap allocation.
//
// Tolerances, from rounding (ε = machine epsilon, twice the unit roundoff u, so k ε ≥ Higham's γ_k):
//  - Householder QR is backward stable column by column (Higham, Accuracy and Stability of Numerical
//    Algorithms, 2nd ed., Thm 19.4): the computed S is the exact factor for A + ΔA with
//    ‖Δaⱼ‖ ≤ γ ‖aⱼ‖, γ = Rows·N·ε the worst case. Then ‖S Sᵀ − AᵀA‖_F ≤ (2γ + γ²) ‖A‖_F².
//  - The R factor's first-order sensitivity (Sun, BIT 31, 1991): ‖ΔR‖_F ≤ √2 κ₂(A) ‖ΔA‖_F / ‖A‖₂ ‖R‖₂,
//    with ‖ΔA‖_F ≤ γ ‖A‖_F ≤ γ √N ‖A‖₂: ‖S − L‖_F ≤ √(2N) κ₂(A) γ ‖S‖₂ against the exact factor L.
//  - A rotation applied to a pair (s, x) (Givens, or the mixed hyperbolic form) makes relative errors
//    of a few ε in each; a coefficient of row i goes through at most N of them. The update is stable
//    in the mixed sense (Stewart 1979; Bojanczyk, Brent, Van Dooren & de Hoog 1987): the computed S'
//    differs from the exact factor of (S + δS)(S + δS)ᵀ ± (v + δv)(v + δv)ᵀ by δS', all of them
//    ≤ 3N ε relative, so ‖S'S'ᵀ − (S Sᵀ ± v vᵀ)‖_F ≤ 6N ε (‖S‖_F² + ‖v‖² + ‖S'‖_F²) with room for
//    second-order terms.
//  - The Cholesky factor's first-order sensitivity (Sun 1991; Higham Thm 10.8): a backward error ΔP
//    moves the factor by ‖ΔL‖_F ≤ 2^(-1/2) κ₂(P) ‖ΔP‖_F / ‖P‖₂ ‖L‖₂.
//  - The reference is Eigen's LLT of the formed matrix in long double (ε ≈ 1.1e-19); its own error,
//    about κ₂(P) N ε_ld relative, is added to each forward bound.
//  - psdSquareRoot, Cholesky with diagonal pivoting stopped at a pivot of N ε max Q_jj: the factor
//    computed is exact for Q + ΔQ with |ΔQ| ≤ (N + 1) ε |G||G|ᵀ (Higham Thm 10.3), ‖|G||G|ᵀ‖_F ≤
//    ‖G‖_F² ≈ tr Q ≤ √N ‖Q‖_F; the Schur complement left out is semi-definite with trace at most
//    N · N ε max Q_jj ≤ N² ε ‖Q‖_F: in all ((N + 1)√N + N²) ε ‖Q‖_F.

#define EIGEN_RUNTIME_NO_MALLOC
#undef NDEBUG  // Eigen reports a forbidden allocation through assert: keep it on in Release builds.

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <type_traits>

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "mjukf/detail/linear_algebra.hpp"

namespace {

using mjukf::detail::choleskyRankOneUpdate;
using mjukf::detail::choleskyRankUpdate;
using mjukf::detail::lowerFactorOfGram;
using mjukf::detail::lowerFactorOfOuter;
using mjukf::detail::outerOfLower;
using mjukf::detail::psdSquareRoot;
using mjukf::detail::rightSolveLowerInPlace;

using LongDouble = long double;
using MatrixLD = Eigen::Matrix<LongDouble, Eigen::Dynamic, Eigen::Dynamic>;

template <class S, int n>
struct Dim {
  using Scalar = S;
  static constexpr int N = n;
};

struct DimName {
  template <class T>
  static std::string GetName(int) {
    return std::string(std::is_same_v<typename T::Scalar, double> ? "double" : "float") + "_N" + std::to_string(T::N);
  }
};

using Dims = ::testing::Types<Dim<double, 1>, Dim<double, 2>, Dim<double, 4>, Dim<double, 7>, Dim<float, 1>,
                              Dim<float, 2>, Dim<float, 4>, Dim<float, 7>>;

template <class D>
class SquareRoot : public ::testing::Test {
 public:
  using Scalar = typename D::Scalar;
  static constexpr int N = D::N;
  static constexpr int Rows = 3 * N;  // the SR-UKF's 2L deviations and L rows of √Q
  using Gram = Eigen::Matrix<Scalar, Rows, N>;
  using Outer = Eigen::Matrix<Scalar, N, Rows>;
  using Square = Eigen::Matrix<Scalar, N, N>;
  using Vector = Eigen::Matrix<Scalar, N, 1>;
  static constexpr LongDouble epsilon = std::numeric_limits<Scalar>::epsilon();
  static constexpr LongDouble referenceEpsilon = std::numeric_limits<LongDouble>::epsilon();

  std::mt19937_64 random{20010517 + N};

  template <class M>
  void fill(M& m) {
    std::normal_distribution<double> normal;
    for (int i = 0; i < int(m.size()); ++i) m.data()[i] = typename M::Scalar(normal(random));
  }

  // A (Rows × N) = U Σ Vᵀ with singular values from 1 down to 1/condition, geometrically.
  Gram conditioned(double condition) {
    Eigen::MatrixXd u(Rows, N), v(N, N);
    fill(u);
    fill(v);
    const Eigen::MatrixXd qu =
        Eigen::HouseholderQR<Eigen::MatrixXd>(u).householderQ() * Eigen::MatrixXd::Identity(Rows, N);
    const Eigen::MatrixXd qv = Eigen::HouseholderQR<Eigen::MatrixXd>(v).householderQ();
    Eigen::VectorXd sigma(N);
    for (int i = 0; i < N; ++i) sigma(i) = std::pow(condition, -double(i) / std::max(1, N - 1));
    return (qu * sigma.asDiagonal() * qv.transpose()).cast<Scalar>();
  }

  // A lower factor of a well-conditioned P, as the filter has one.
  Square factor() {
    Gram a = conditioned(10);
    Square s;
    EXPECT_TRUE(lowerFactorOfGram(a, s));
    return s;
  }

  static MatrixLD wide(const Eigen::Ref<const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>>& m) {
    return m.template cast<LongDouble>();
  }
  static MatrixLD lowerPart(const Square& s) { return wide(s).template triangularView<Eigen::Lower>(); }
  static MatrixLD lltFactor(const MatrixLD& p) {
    Eigen::LLT<MatrixLD> llt(p);
    EXPECT_EQ(llt.info(), Eigen::Success);
    return llt.matrixL();
  }
  // κ₂ and ‖·‖₂ of a symmetric positive definite matrix.
  static std::pair<LongDouble, LongDouble> conditionAndNorm(const MatrixLD& p) {
    const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(p.cast<double>()).eigenvalues();
    return {LongDouble(lambda.maxCoeff() / lambda.minCoeff()), LongDouble(lambda.maxCoeff())};
  }

  static Vector unit(int k) {
    Vector e = Vector::Zero();
    e(k) = Scalar(1);
    return e;
  }

  static void expectLowerWithPositiveDiagonal(const Square& s) {
    for (int j = 0; j < N; ++j) {
      EXPECT_GT(s(j, j), Scalar(0)) << "diagonal " << j;
      for (int i = 0; i < j; ++i) EXPECT_EQ(s(i, j), Scalar(0)) << "upper (" << i << ", " << j << ")";
    }
  }

  // The Gram factor of `a` in both layouts against LLT(AᵀA), with the bounds at the top of the file.
  void checkGram(const Gram& a, double condition) {
    Gram scratch = a;
    Square s;
    ASSERT_TRUE(lowerFactorOfGram(scratch, s));
    expectLowerWithPositiveDiagonal(s);
    Outer scratchB = a.transpose();
    Square sB;
    ASSERT_TRUE(lowerFactorOfOuter(scratchB, sB));
    expectLowerWithPositiveDiagonal(sB);

    const MatrixLD al = wide(a);
    const MatrixLD p = al.transpose() * al;
    const LongDouble gamma = LongDouble(Rows) * N * epsilon;
    const LongDouble backward = (2 * gamma + gamma * gamma) * al.squaredNorm();
    const MatrixLD reference = lltFactor(p);
    const LongDouble norm2 = wide(s).norm();  // ≥ ‖S‖₂
    const LongDouble forward = std::sqrt(2.0L * N) * LongDouble(condition) * gamma * norm2 +
                               conditionAndNorm(p).first * N * referenceEpsilon * norm2;
    for (const Square* result : {&s, &sB}) {
      const MatrixLD sl = lowerPart(*result);
      EXPECT_LE((sl * sl.transpose() - p).norm(), backward);
      EXPECT_LE((sl - reference).norm(), forward);
    }
    // The two layouts sum in different orders: each within the backward bound of the other.
    EXPECT_LE((lowerPart(s) - lowerPart(sB)).norm(), 2 * std::sqrt(2.0L * N) * LongDouble(condition) * gamma * norm2);
  }

  // S' from S ± v vᵀ against LLT of the formed matrix (the bounds at the top of the file).
  void checkUpdated(const Square& before, const MatrixLD& change, const Square& after, LongDouble changeNorm2) {
    const MatrixLD sl = lowerPart(before), sl2 = lowerPart(after);
    const MatrixLD p = sl * sl.transpose() + change;
    const LongDouble backward = 6 * N * epsilon * (sl.squaredNorm() + changeNorm2 + sl2.squaredNorm());
    EXPECT_LE((sl2 * sl2.transpose() - p).norm(), backward);
    const auto [condition, norm] = conditionAndNorm(p);
    const MatrixLD reference = lltFactor(p);
    const LongDouble referenceNorm = std::sqrt(norm);
    const LongDouble forward = (condition / std::sqrt(2.0L)) * (backward / norm) * referenceNorm +
                               condition * N * referenceEpsilon * referenceNorm;
    EXPECT_LE((sl2 - reference).norm(), forward);
  }
};

TYPED_TEST_SUITE(SquareRoot, Dims, DimName);

// ---- The Gram factor -------------------------------------------------------------------------------

TYPED_TEST(SquareRoot, GramFactorIsTheCholeskyFactorOfTheGramMatrix) {
  using T = TestFixture;
  for (int trial = 0; trial < 20; ++trial) {
    typename T::Gram a;
    this->fill(a);
    // Random Gaussian A: κ₂ at most about (√Rows + √N)/(√Rows − √N) ≈ 3.7; 10 covers it for N ≥ 2.
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(a.template cast<double>()).singularValues();
    this->checkGram(a, sv(0) / sv(T::N - 1));
  }
  // Conditioned A, down to the noise of the reference (κ₂(P) = κ₂(A)² against long double).
  for (const double condition : {1e2, std::is_same_v<typename T::Scalar, double> ? 1e5 : 1e3}) {
    for (int trial = 0; trial < 5; ++trial) this->checkGram(this->conditioned(condition), condition);
  }
}

TYPED_TEST(SquareRoot, GramFactorOfScaledInputsIsScaled) {
  using T = TestFixture;
  // Powers of two scale exactly: S(2ᵏA) = 2ᵏ S(A), far from 1 in both directions.
  typename T::Gram a;
  this->fill(a);
  typename T::Gram scratch = a;
  typename T::Square s, scaled;
  ASSERT_TRUE(lowerFactorOfGram(scratch, s));
  for (const int power : {-40, -10, 10, 40}) {
    const auto factor = std::ldexp(typename T::Scalar(1), power);
    scratch = a * factor;
    ASSERT_TRUE(lowerFactorOfGram(scratch, scaled)) << power;
    EXPECT_EQ(scaled, typename T::Square(s * factor)) << power;
  }
}

TYPED_TEST(SquareRoot, GramFactorRefusesARankDeficientMatrix) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  typename T::Square s;
  typename T::Gram a = T::Gram::Zero(), scratch;
  scratch = a;
  EXPECT_FALSE(lowerFactorOfGram(scratch, s)) << "zero";
  typename T::Outer b = T::Outer::Zero();
  EXPECT_FALSE(lowerFactorOfOuter(b, s)) << "zero";
  for (int trial = 0; trial < 20; ++trial) {
    this->fill(a);
    // Only N − 1 nonzero rows (Q = 0 and too few deviations): the last column's remainder is exactly 0.
    scratch = a;
    scratch.template bottomRows<T::Rows - (T::N - 1)>().setZero();
    b = scratch.transpose();
    EXPECT_FALSE(lowerFactorOfGram(scratch, s)) << "rows, trial " << trial;
    EXPECT_FALSE(lowerFactorOfOuter(b, s)) << "rows, trial " << trial;
    // A column twice another (exact): its remainder is rounding, below the 4N ε margin.
    if constexpr (T::N >= 2) {
      scratch = a;
      const int from = trial % T::N, to = (from + 1 + trial / T::N % (T::N - 1)) % T::N;
      scratch.col(to) = Scalar(2) * a.col(from);
      b = scratch.transpose();
      EXPECT_FALSE(lowerFactorOfGram(scratch, s)) << "column, trial " << trial;
      EXPECT_FALSE(lowerFactorOfOuter(b, s)) << "column, trial " << trial;
    }
  }
}

TYPED_TEST(SquareRoot, GramFactorOfANearlyRankDeficientMatrix) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  if constexpr (T::N >= 2) {
    // The last column a combination of the others plus η times a random vector: κ₂(A) about 1/η,
    // κ₂(P = AᵀA) about 1/η², beyond what choleskyLower can accept (its last pivot, about η² P_jj, is
    // below its N ε P_jj margin), well within the 4N ε ‖aⱼ‖ margin here. The factor is still
    // accurate to the backward bound.
    const Scalar eta = std::is_same_v<Scalar, double> ? Scalar(1e-9) : Scalar(1e-4);
    for (int trial = 0; trial < 10; ++trial) {
      typename T::Gram a;
      this->fill(a);
      Eigen::Matrix<Scalar, T::N - 1, 1> c;
      Eigen::Matrix<Scalar, T::Rows, 1> noise;
      this->fill(c);
      this->fill(noise);
      a.col(T::N - 1) = a.leftCols(T::N - 1) * c + eta * noise;
      typename T::Gram scratch = a;
      typename T::Square s;
      ASSERT_TRUE(lowerFactorOfGram(scratch, s)) << trial;
      const MatrixLD al = T::wide(a), sl = T::lowerPart(s);
      const LongDouble gamma = LongDouble(T::Rows) * T::N * T::epsilon;
      EXPECT_LE((sl * sl.transpose() - al.transpose() * al).norm(), (2 * gamma + gamma * gamma) * al.squaredNorm());
      // The last pivot is the distance of the last column from the others' span: about η ‖noise‖.
      EXPECT_LT(s(T::N - 1, T::N - 1), 2 * eta * noise.norm());
      EXPECT_GT(s(T::N - 1, T::N - 1), eta * noise.norm() / 100);
    }
  }
}

TYPED_TEST(SquareRoot, GramFactorRefusesNonFiniteAndOverflowingInput) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  typename T::Gram a;
  this->fill(a);
  typename T::Square s;
  const Scalar bad[] = {std::numeric_limits<Scalar>::quiet_NaN(), std::numeric_limits<Scalar>::infinity(),
                        -std::numeric_limits<Scalar>::infinity()};
  for (const Scalar value : bad) {
    for (const int index : {0, T::Rows * T::N / 2, T::Rows * T::N - 1}) {
      typename T::Gram scratch = a;
      scratch.data()[index] = value;
      typename T::Outer b = scratch.transpose();
      EXPECT_FALSE(lowerFactorOfGram(scratch, s)) << value << " at " << index;
      EXPECT_FALSE(lowerFactorOfOuter(b, s)) << value << " at " << index;
    }
  }
  // ‖aⱼ‖² overflows: refused, as P = AᵀA would be, never a factor with Inf in it.
  typename T::Gram scratch = a * std::sqrt(std::numeric_limits<Scalar>::max());
  typename T::Outer b = scratch.transpose();
  EXPECT_FALSE(lowerFactorOfGram(scratch, s));
  EXPECT_FALSE(lowerFactorOfOuter(b, s));
}

// ---- Rank-one and rank-M updates and downdates ----------------------------------------------------

TYPED_TEST(SquareRoot, RankOneUpdateAndDowndateMatchTheFactorOfTheChangedMatrix) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  for (int trial = 0; trial < 20; ++trial) {
    const typename T::Square s = this->factor();
    typename T::Vector u;
    this->fill(u);
    // v = S u: ‖S⁻¹v‖ = ‖u‖, from a small downdate to one that removes 99 % of P in a direction.
    const Scalar size[] = {Scalar(0.1), Scalar(0.5), Scalar(0.9), Scalar(0.995)};
    u *= size[trial % 4] / u.norm();
    const typename T::Vector v = s * u;
    const MatrixLD outer = T::wide(v) * T::wide(v).transpose();
    typename T::Square updated = s, downdated = s;
    ASSERT_TRUE(choleskyRankOneUpdate(updated, v, 1)) << trial;
    ASSERT_TRUE(choleskyRankOneUpdate(downdated, v, -1)) << trial;
    this->checkUpdated(s, outer, updated, T::wide(v).squaredNorm());
    this->checkUpdated(s, -outer, downdated, T::wide(v).squaredNorm());
    // A weight's magnitude is the caller's: only the sign of `sign` is read.
    typename T::Square halved = s;
    ASSERT_TRUE(choleskyRankOneUpdate(halved, v, Scalar(-0.5)));
    EXPECT_EQ(halved, downdated);
    // Down and up again: back to S.
    ASSERT_TRUE(choleskyRankOneUpdate(downdated, v, 1));
    // Two operations: the sum of their bounds, ‖S₁‖ ≤ ‖S‖ in between.
    this->checkUpdated(s, MatrixLD::Zero(T::N, T::N), downdated,
                       2 * T::wide(v).squaredNorm() + 2 * T::wide(s).squaredNorm());
    // A random v for the update, not in any relation to S.
    typename T::Vector w;
    this->fill(w);
    updated = s;
    ASSERT_TRUE(choleskyRankOneUpdate(updated, w, 1));
    this->checkUpdated(s, T::wide(w) * T::wide(w).transpose(), updated, T::wide(w).squaredNorm());
  }
}

TYPED_TEST(SquareRoot, RankOneKernelsNeitherReadNorWriteTheUpperTriangle) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  const typename T::Square s = this->factor();
  typename T::Vector v;
  this->fill(v);
  v = s * v * (Scalar(0.5) / v.norm());
  for (const int sign : {1, -1}) {
    typename T::Square clean = s, marked = s;
    marked.template triangularView<Eigen::StrictlyUpper>().setConstant(std::numeric_limits<Scalar>::quiet_NaN());
    ASSERT_TRUE(choleskyRankOneUpdate(clean, v, sign));
    ASSERT_TRUE(choleskyRankOneUpdate(marked, v, sign));
    EXPECT_EQ(typename T::Square(marked.template triangularView<Eigen::Lower>()), clean) << sign;
    for (int j = 1; j < T::N; ++j) EXPECT_TRUE(std::isnan(marked(0, j)));
  }
}

TYPED_TEST(SquareRoot, RankUpdateByColumnsIsTheRankOneKernelColumnByColumn) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  constexpr int M = 3;
  for (int trial = 0; trial < 10; ++trial) {
    const typename T::Square s = this->factor();
    Eigen::Matrix<Scalar, T::N, M> w;
    this->fill(w);
    // U = S W with ‖W‖₂ ≤ ‖W‖_F = 0.9: P − U Uᵀ = S (I − W Wᵀ) Sᵀ stays positive definite.
    const Eigen::Matrix<Scalar, T::N, M> u = s * w * (Scalar(0.9) / w.norm());
    for (const int sign : {1, -1}) {
      typename T::Square together = s, oneByOne = s;
      ASSERT_TRUE(choleskyRankUpdate(together, u, sign)) << trial;
      for (int i = 0; i < M; ++i) ASSERT_TRUE(choleskyRankOneUpdate(oneByOne, u.col(i), sign)) << trial;
#ifdef __FP_FAST_FMA
      // With fused multiply-adds the compiler may contract the two differently.
      EXPECT_LE((together - oneByOne).norm(), 8 * T::N * T::epsilon * s.norm());
#else
      EXPECT_EQ(together, oneByOne) << "the same operations in another order of independent steps";
#endif
      this->checkUpdated(s, sign * T::wide(u) * T::wide(u).transpose(), together, T::wide(u).squaredNorm());
    }
  }
}

TYPED_TEST(SquareRoot, DowndateRefusesAnIndefiniteOrSingularResult) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  for (int trial = 0; trial < 20; ++trial) {
    const typename T::Square s = this->factor();
    typename T::Vector u;
    this->fill(u);
    typename T::Square scratch = s;
    EXPECT_FALSE(choleskyRankOneUpdate(scratch, (s * u * (Scalar(1.25) / u.norm())).eval(), -1)) << "‖S⁻¹v‖ = 1.25";
    scratch = s;
    EXPECT_FALSE(choleskyRankOneUpdate(scratch, (s * u * (Scalar(1.01) / u.norm())).eval(), -1)) << "‖S⁻¹v‖ = 1.01";
    // v a column of S: exactly singular, on the first rotation or on a later one.
    const int column = trial % T::N;
    scratch = s;
    EXPECT_FALSE(choleskyRankOneUpdate(scratch, s.col(column), -1)) << "column " << column;
    // The M-column version: refused as soon as one column is.
    Eigen::Matrix<Scalar, T::N, 2> pair;
    pair << s * u * (Scalar(0.5) / u.norm()), s * u * (Scalar(0.9) / u.norm());  // together 0.25 + 0.81 > 1
    scratch = s;
    EXPECT_FALSE(choleskyRankUpdate(scratch, pair, -1));
  }
  // Exactly singular through every rotation: S with small integers (exact products), v = S u with
  // u = (½, ½, ½, ½) on four coordinates, ‖u‖ = 1 exactly, so S Sᵀ − v vᵀ is exactly singular.
  if constexpr (T::N >= 4) {
    for (int trial = 0; trial < 20; ++trial) {
      typename T::Square s = T::Square::Zero();
      std::uniform_int_distribution<int> small(-2, 2);
      for (int j = 0; j < T::N; ++j) {
        s(j, j) = Scalar(6);
        for (int i = j + 1; i < T::N; ++i) s(i, j) = Scalar(small(this->random));
      }
      typename T::Vector u = T::Vector::Zero();
      for (int placed = 0; placed < 4;) {
        const int i = std::uniform_int_distribution<int>(0, T::N - 1)(this->random);
        if (u(i) == Scalar(0)) u(i) = (placed++ % 2 ? Scalar(-0.5) : Scalar(0.5));
      }
      const typename T::Vector v = s * u;  // small integers and halves: exact
      typename T::Square scratch = s;
      EXPECT_FALSE(choleskyRankOneUpdate(scratch, v, -1)) << trial;
      // Just inside: ‖S⁻¹v‖² = 1 − 2⁻¹⁰ (double) / 1 − 2⁻⁶ (float), far above the 4N ε margin.
      const Scalar inside = std::sqrt(Scalar(1) - std::ldexp(Scalar(1), std::is_same_v<Scalar, double> ? -10 : -6));
      scratch = s;
      const typename T::Vector vInside = v * inside;
      ASSERT_TRUE(choleskyRankOneUpdate(scratch, vInside, -1)) << trial;
      this->checkUpdated(s, -T::wide(vInside) * T::wide(vInside).transpose(), scratch, T::wide(vInside).squaredNorm());
    }
  }
}

TYPED_TEST(SquareRoot, UpdateOfASingularFactor) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  // S = diag(1, …, 1, 0) (a semi-definite P): an update along the missing direction completes it, one
  // along another direction does not.
  typename T::Square s = T::Square::Identity();
  s(T::N - 1, T::N - 1) = Scalar(0);
  typename T::Square scratch = s;
  ASSERT_TRUE(choleskyRankOneUpdate(scratch, T::unit(T::N - 1), 1));
  EXPECT_EQ(scratch, typename T::Square(T::Square::Identity()));
  if constexpr (T::N >= 2) {
    scratch = s;
    EXPECT_FALSE(choleskyRankOneUpdate(scratch, T::unit(0), 1));
  }
  scratch = T::Square::Zero();
  EXPECT_FALSE(choleskyRankOneUpdate(scratch, T::Vector::Zero(), 1));
  scratch = T::Square::Zero();
  EXPECT_FALSE(choleskyRankOneUpdate(scratch, T::Vector::Zero(), -1));
}

TYPED_TEST(SquareRoot, RankUpdatesRefuseNonFiniteInput) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  const typename T::Square s = this->factor();
  typename T::Vector v;
  this->fill(v);
  v = s * v * (Scalar(0.5) / v.norm());
  const Scalar bad[] = {std::numeric_limits<Scalar>::quiet_NaN(), std::numeric_limits<Scalar>::infinity(),
                        -std::numeric_limits<Scalar>::infinity()};
  for (const Scalar value : bad) {
    for (const int sign : {1, -1}) {
      for (int i = 0; i < T::N; ++i) {
        typename T::Vector badV = v;
        badV(i) = value;
        typename T::Square scratch = s;
        EXPECT_FALSE(choleskyRankOneUpdate(scratch, badV, sign)) << value << " in v(" << i << "), sign " << sign;
        for (int j = 0; j <= i; ++j) {
          scratch = s;
          scratch(i, j) = value;
          EXPECT_FALSE(choleskyRankOneUpdate(scratch, v, sign)) << value << " in S(" << i << ", " << j << ")";
        }
      }
      Eigen::Matrix<Scalar, T::N, 2> u;
      u << v, v;
      u(T::N - 1, 1) = value;
      typename T::Square scratch = s;
      EXPECT_FALSE(choleskyRankUpdate(scratch, u, sign)) << value;
    }
  }
  // Overflow: an update by v with ‖v‖² beyond the largest number.
  typename T::Square scratch = s;
  EXPECT_FALSE(choleskyRankOneUpdate(scratch, (T::Vector::Ones() * std::numeric_limits<Scalar>::max()).eval(), 1));
}

// ---- psdSquareRoot --------------------------------------------------------------------------------

TYPED_TEST(SquareRoot, PsdSquareRootOfSemiDefiniteMatrices) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  EXPECT_EQ(psdSquareRoot(typename T::Square(T::Square::Zero())), typename T::Square(T::Square::Zero()));
  const long double psdTolerance = ((T::N + 1) * std::sqrt(static_cast<long double>(T::N)) + T::N * T::N) * T::epsilon;
  const auto check = [&](const typename T::Square& q, const char* what) {
    const typename T::Square g = psdSquareRoot(q);
    ASSERT_TRUE(g.allFinite()) << what;
    const MatrixLD gl = T::wide(g), ql = T::wide(q);
    EXPECT_LE((gl * gl.transpose() - ql).norm(), psdTolerance * ql.norm()) << what;
  };
  for (int trial = 0; trial < 10; ++trial) {
    for (const int rank : {T::N, (T::N + 1) / 2, 1}) {
      Eigen::Matrix<Scalar, T::N, Eigen::Dynamic> h(T::N, rank);
      this->fill(h);
      const typename T::Square q = h * h.transpose();  // rounded: may have eigenvalues of about −ε ‖Q‖
      check(q, rank == T::N ? "full rank" : "rank deficient");
    }
    // A diagonal with zeros, and one badly scaled.
    typename T::Vector d;
    this->fill(d);
    d = d.cwiseAbs();
    d(trial % T::N) = Scalar(0);
    check(typename T::Square(d.asDiagonal()), "diagonal with a zero");
    d(0) = Scalar(1e-30);
    check(typename T::Square(d.asDiagonal()), "diagonal with a tiny entry");
  }
  // Only the lower triangle is read.
  typename T::Square q = T::Square::Identity(), marked = q;
  marked.template triangularView<Eigen::StrictlyUpper>().setConstant(Scalar(7));
  const typename T::Square g = psdSquareRoot(marked);
  EXPECT_LE((g * g.transpose() - q).norm(), psdTolerance * std::sqrt(static_cast<long double>(T::N)));
  // NaN or Inf in: NaN out.
  q(T::N - 1, 0) = std::numeric_limits<Scalar>::quiet_NaN();
  EXPECT_TRUE(psdSquareRoot(q).array().isNaN().all());
}

// ---- P = S Sᵀ and the gain K = U S⁻¹ ---------------------------------------------------------------

TYPED_TEST(SquareRoot, OuterOfLowerIsExactlySymmetricAndAccurate) {
  using T = TestFixture;
  for (int trial = 0; trial < 20; ++trial) {
    typename T::Square s = this->factor(), p;
    s.template triangularView<Eigen::StrictlyUpper>().setConstant(std::numeric_limits<typename T::Scalar>::quiet_NaN());
    outerOfLower(s, p);  // the upper triangle of S is not read
    EXPECT_TRUE((p.array() == p.transpose().array()).all()) << "bit for bit symmetric";
    const MatrixLD sl = T::lowerPart(s);
    const MatrixLD abs = sl.cwiseAbs();
    // A dot product of N terms: |error| ≤ γ_N Σₖ |s_ik||s_jk| (Higham, eq. 3.5), γ_N ≤ N ε.
    const MatrixLD bound = LongDouble(T::N) * T::epsilon * abs * abs.transpose();
    const MatrixLD error = (T::wide(p) - sl * sl.transpose()).cwiseAbs();
    EXPECT_TRUE((error.array() <= bound.array()).all()) << trial;
  }
}

TYPED_TEST(SquareRoot, RightSolveGivesTheGain) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  constexpr int L = 3;
  for (int trial = 0; trial < 20; ++trial) {
    const typename T::Square s = this->factor();
    Eigen::Matrix<Scalar, L, T::N> u, k;
    this->fill(u);
    k = u;
    rightSolveLowerInPlace(s, k);
    // A triangular solve is backward stable row by row: K (S + ΔS) = U with |ΔS| ≤ γ_N |S| (Higham,
    // Thm 8.5), so |K S − U| ≤ N ε |K| |S|.
    const MatrixLD sl = T::lowerPart(s), kl = T::wide(k);
    const MatrixLD bound = LongDouble(T::N) * T::epsilon * kl.cwiseAbs() * sl.cwiseAbs();
    const MatrixLD residual = (kl * sl - T::wide(u)).cwiseAbs();
    EXPECT_TRUE((residual.array() <= bound.array()).all()) << trial;
  }
}

// ---- The SR-UKF's use, and allocation ---------------------------------------------------------------

TYPED_TEST(SquareRoot, TimeUpdateFactorIsTheFactorOfTheUnscentedCovariance) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  constexpr int N = T::N, Count = 2 * N + 1;
  // S from [√Wcᵢ (χᵢ − x̂), i ≥ 1 | G] and the centre point's weight Wc₀ (positive: an update; negative:
  // a downdate), against the factor of P = Σ Wcᵢ dᵢ dᵢᵀ + Q.
  for (const Scalar centreWeight : {Scalar(2), Scalar(-0.2)}) {
    Eigen::Matrix<Scalar, N, Count> d;
    this->fill(d);
    d.col(0) *= Scalar(0.1);  // the centre point's deviation is small (zero for a linear model)
    typename T::Square h;
    this->fill(h);
    const typename T::Square q = Scalar(0.01) * h * h.transpose();
    const typename T::Square g = psdSquareRoot(q);
    const Scalar weight = Scalar(1) / Scalar(2 * N);
    typename T::Outer b;
    b.template leftCols<2 * N>() = std::sqrt(weight) * d.template rightCols<2 * N>();
    b.template rightCols<N>() = g;
    typename T::Square s;
    ASSERT_TRUE(lowerFactorOfOuter(b, s));
    const typename T::Vector centre = std::sqrt(std::abs(centreWeight)) * d.col(0);
    ASSERT_TRUE(choleskyRankOneUpdate(s, centre, centreWeight));
    MatrixLD p = T::wide(q);
    for (int i = 0; i < Count; ++i)
      p += LongDouble(i == 0 ? centreWeight : weight) * T::wide(d.col(i)) * T::wide(d.col(i)).transpose();
    // The Gram factor's bound on ‖B‖_F², then the rank-one bound with ‖S‖_F² = ‖B‖_F² (to rounding)
    // and ‖S'‖_F² ≤ ‖B‖_F² + ‖c‖².
    const MatrixLD sl = T::lowerPart(s);
    const LongDouble gamma = LongDouble(T::Rows) * N * T::epsilon;
    const LongDouble b2 = weight * T::wide(d.rightCols(2 * N)).squaredNorm() + T::wide(q).trace();
    const LongDouble c2 = T::wide(centre).squaredNorm();
    const LongDouble bound = (2 * gamma + gamma * gamma) * b2 + 6 * N * T::epsilon * (2 * b2 + 2 * c2);
    EXPECT_LE((sl * sl.transpose() - p).norm(), bound) << centreWeight;
  }
}

TYPED_TEST(SquareRoot, KernelsDoNotAllocate) {
  using T = TestFixture;
  using Scalar = typename T::Scalar;
  typename T::Gram a;
  this->fill(a);
  typename T::Outer b = a.transpose();
  typename T::Square s, s2, q = T::Square::Identity(), g;
  typename T::Vector v;
  this->fill(v);
  Eigen::Matrix<Scalar, T::N, 3> u;
  this->fill(u);
  bool ok = true;
  Eigen::internal::set_is_malloc_allowed(false);
  ok = lowerFactorOfGram(a, s) && ok;
  ok = lowerFactorOfOuter(b, s2) && ok;
  ok = choleskyRankOneUpdate(s, v, 1) && ok;
  ok = choleskyRankOneUpdate(s, (Scalar(0.1) * v).eval(), -1) && ok;
  ok = choleskyRankUpdate(s2, u, 1) && ok;
  outerOfLower(s, q);
  Eigen::Matrix<Scalar, 3, T::N> gain = u.transpose();
  rightSolveLowerInPlace(s2, gain);
  q.setIdentity();
  g = psdSquareRoot(q);  // construction-time, but it does not allocate either
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_TRUE(ok);
  EXPECT_TRUE(g.allFinite());
}

}  // namespace
