#pragma once

// The small linear algebra of a filter step, in one place: the finiteness check, the Cholesky factor
// and triangular solves, the symmetrisation of a covariance, the weighted moments of a point set (the
// unscented transform, docs/algorithms.md §1–3) and the symmetric sigma-point draw. Every function takes
// fixed-size Eigen matrices, writes into its arguments and allocates nothing; each is written out where
// Eigen's general path costs more than the arithmetic at these sizes (said at each).

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include <Eigen/Core>

namespace mjukf::detail {

// ---- Finiteness ---------------------------------------------------------------------------------------

// True when no coefficient is NaN or ±Inf. Eigen's allFinite() compares x − x with itself and stops
// at the first mismatch: a branch per coefficient, which on a step's few dozen values costs more than
// the arithmetic it guards. Here x·0 is 0 for a finite x and NaN otherwise, and a sum is NaN as soon
// as one of its terms is, so the check is one vectorised reduction. (Like Eigen's, it needs IEEE
// arithmetic: -ffinite-math-only would let a compiler fold it to true.)
template <class Derived>
bool allFinite(const Eigen::DenseBase<Derived>& m) {
  using Scalar = typename Derived::Scalar;
  return (m.derived().array() * Scalar(0)).sum() == Scalar(0);
}

// True when every present component of y is finite (`present` null: all are present).
template <class Meas, class Mask>
bool presentComponentsFinite(const Meas& y, const Mask* present) {
  if (!present) return allFinite(y);
  for (int j = 0; j < y.size(); ++j)
    if ((*present)(j) && !std::isfinite(y(j))) return false;
  return true;
}

// ---- Cholesky factor and triangular solves ---------------------------------------------------------------
//
// The lower Cholesky factor of a small fixed-size matrix, written out instead of Eigen::LLT because
//  - an LLT member that was never computed holds an indeterminate `info()`, and copying it (copying
//    a filter before its first step) is undefined behaviour, which UBSan reports;
//  - Eigen's LLT also computes the matrix's L1 norm on every call (for rcond()), which nothing here
//    reads, and that is a measurable part of a step at these sizes.

// Calls f(std::integral_constant<int, I>()) for I = 0 … N − 1 in order while it returns true: a loop
// whose index is a compile-time constant, so that every loop below has a fixed trip count and the
// compiler unrolls all of them (nested loops whose bounds depend on an outer index are otherwise kept
// as loops, and at N = 4 their counters and branches cost as much as the arithmetic).
template <class F, int... I>
bool forEachIndexIn(F& f, std::integer_sequence<int, I...>) {
  return (f(std::integral_constant<int, I>()) && ...);
}
template <int N, class F>
bool forEachIndex(F&& f) {
  return forEachIndexIn(f, std::make_integer_sequence<int, N>());
}

// S with A = S Sᵀ, reading only the lower triangle of A (the strictly upper triangle of S is set to
// zero). Returns false, S then unspecified, when A is not numerically positive definite: a pivot
// a_jj − Σₖ s_jk² that is not above N ε a_jj, the size of its own rounding error, or not finite (NaN
// and Inf fail). Without that margin a singular A (0.5 everywhere, say) can pass on a pivot of 1e-16
// that is all rounding, and whether it passes then depends on the order of the sums: a P accepted here
// must also factor in any other correct Cholesky (Eigen's LLT), which the fuzz target checks.
// `s` must not alias `a`.
template <class Scalar, int N>
bool choleskyLower(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& s) {
  // Computed as A = L D Lᵀ (L unit lower triangular), then S = L D^½. The pivots dⱼ are the squares of
  // the diagonal of S, and each column waits only for a division by the pivot before it, not for a
  // square root as well; the square roots are independent and come last. At these sizes the chain of
  // dependent divisions and roots is the cost of the factorisation.
  constexpr Scalar margin = Scalar(N) * std::numeric_limits<Scalar>::epsilon();
  Scalar inversePivot[N];
  const bool positive = forEachIndex<N>([&](auto jIndex) {
    constexpr int j = jIndex.value;
    // s(j, k) for k < j holds Lⱼₖ dₖ here; s(k, j) (upper triangle, free until the end) holds Lⱼₖ.
    Scalar pivot = a(j, j);
    forEachIndex<j>([&](auto k) { return pivot -= s(k.value, j) * s(j, k.value), true; });
    if (!(pivot > margin * a(j, j)) || !(pivot <= std::numeric_limits<Scalar>::max())) return false;  // NaN fails too
    s(j, j) = pivot;
    inversePivot[j] = Scalar(1) / pivot;
    forEachIndex<N - j - 1>([&](auto offset) {
      constexpr int i = j + 1 + offset.value;
      Scalar v = a(i, j);
      forEachIndex<j>([&](auto k) { return v -= s(k.value, i) * s(j, k.value), true; });
      s(i, j) = v;                    // Lᵢⱼ dⱼ
      s(j, i) = v * inversePivot[j];  // Lᵢⱼ
      return true;
    });
    return true;
  });
  if (!positive) return false;
  forEachIndex<N>([&](auto jIndex) {
    constexpr int j = jIndex.value;
    const Scalar root = std::sqrt(s(j, j));
    const Scalar inverseRoot = root * inversePivot[j];  // dⱼ^½ / dⱼ = dⱼ^-½
    forEachIndex<N - j - 1>([&](auto offset) { return s(j + 1 + offset.value, j) *= inverseRoot, true; });
    s(j, j) = root;
    forEachIndex<j>([&](auto i) { return s(i.value, j) = Scalar(0), true; });
    return true;
  });
  return true;
}

// B ← S⁻¹ B and B ← S⁻ᵀ B for a lower-triangular S (a factor from choleskyLower), by substitution a
// row at a time; B is a vector or a matrix. Written out because Eigen's triangular solve with a matrix
// right-hand side takes its general blocked path (packing, level-3 kernels), which at these sizes costs
// more than the arithmetic around it.
template <class Lower, class Rhs>
void solveLowerInPlace(const Lower& s, Rhs& b) {
  for (int i = 0; i < int(s.rows()); ++i) {
    for (int k = 0; k < i; ++k) b.row(i) -= s(i, k) * b.row(k);
    b.row(i) /= s(i, i);
  }
}
template <class Lower, class Rhs>
void solveUpperInPlace(const Lower& s, Rhs& b) {
  for (int i = int(s.rows()) - 1; i >= 0; --i) {
    for (int k = i + 1; k < int(s.rows()); ++k) b.row(i) -= s(k, i) * b.row(k);
    b.row(i) /= s(i, i);
  }
}

// ---- Covariances ----------------------------------------------------------------------------------------

// P ← (P + Pᵀ)/2 in place, a triangle at a time (no temporary, no aliasing). Halved before the sum,
// which gives the same bits as halving after it (subnormal entries aside) but cannot overflow for
// entries near the largest Scalar.
template <class Matrix>
void symmetrize(Matrix& p) {
  using Scalar = typename Matrix::Scalar;
  for (int c = 0; c < p.cols(); ++c)
    for (int r = c + 1; r < p.rows(); ++r) p(r, c) = p(c, r) = Scalar(0.5) * p(r, c) + Scalar(0.5) * p(c, r);
}

// ---- Weighted moments of a point set (the unscented transform, docs/algorithms.md §2–3) ---------------------

// mean = Σ Wmᵢ Xᵢ
template <class Points, class Weights, class Mean>
void weightedMean(const Eigen::MatrixBase<Points>& points, const Eigen::MatrixBase<Weights>& weights,
                  Eigen::MatrixBase<Mean>& mean) {
  mean.noalias() = points * weights;
}

// out = Σ Wcᵢ aᵢ bᵢᵀ of the deviations aᵢ, bᵢ (columns): the covariance when a = b, otherwise the
// cross-covariance. A coefficient-wise product (lazyProduct): left to choose, Eigen takes its general
// GEMM kernel once rows + columns + depth exceed 20 (JUKF on the robot: 6 + 6 + 13), and packing the
// operands then costs more than the whole rest of the step.
template <class DevA, class DevB, class Weights, class Out>
void weightedOuterSum(const Eigen::MatrixBase<DevA>& a, const Eigen::MatrixBase<DevB>& b,
                      const Eigen::MatrixBase<Weights>& weights, Eigen::MatrixBase<Out>& out) {
  out.noalias() = (a * weights.asDiagonal()).lazyProduct(b.transpose());
}

// C ← U = C S⁻ᵀ for a lower-triangular S, i.e. U Sᵀ = C solved a column at a time (the columns of U are
// contiguous). With C = P_xy and P_yy = S Sᵀ, U is the gain's factor: K = U S⁻¹ and K P_yy Kᵀ = U Uᵀ.
template <class Lower, class Cross>
void whitenColumns(const Lower& s, Cross& c) {
  for (int j = 0; j < int(s.rows()); ++j) {
    for (int k = 0; k < j; ++k) c.col(j) -= s(j, k) * c.col(k);
    c.col(j) /= s(j, j);
  }
}

// ---- The symmetric sigma-point draw (docs/algorithms.md §1) ------------------------------------------------

// points = [x̂ (when `center`),  x̂ + γ Sᵢ (i = 1 … L),  x̂ − γ Sᵢ (i = 1 … L)] for the columns Sᵢ of a lower
// factor S of the covariance (P = S Sᵀ; only its lower triangle is read): van der Merwe's scaled set
// (center, γ = √(L + λ)) and the cubature set (no center, γ = √L) alike. Columns of S, not rows: rows
// would be wrong for a correlated P.
template <bool Center, class Vector, class Factor, class Points, class Scalar>
void drawSymmetricPoints(const Vector& mean, const Factor& lowerFactor, Scalar gamma, Points& points) {
  constexpr int L = Vector::RowsAtCompileTime;
  constexpr int first = Center ? 1 : 0;
  for (int i = 0; i < L; ++i) {
    points.col(first + i) = mean;
    points.col(first + L + i) = mean;
    for (int r = i; r < L; ++r) {  // S is lower triangular: rows above the diagonal are zero.
      const Scalar offset = gamma * lowerFactor(r, i);
      points(r, first + i) += offset;
      points(r, first + L + i) -= offset;
    }
  }
  if constexpr (Center) points.col(0) = mean;
}

}  // namespace mjukf::detail
