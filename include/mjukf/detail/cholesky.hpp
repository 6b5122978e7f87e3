#pragma once

// The lower Cholesky factor of a small fixed-size matrix, written out instead of Eigen::LLT because
//  - an LLT member that was never computed holds an indeterminate `info()`, and copying it (copying
//    a filter before its first step) is undefined behaviour, which UBSan reports;
//  - Eigen's LLT also computes the matrix's L1 norm on every call (for rcond()), which nothing here
//    reads, and that is a measurable part of a step at these sizes.

#include <cmath>
#include <limits>

#include <Eigen/Core>

namespace mjukf::detail {

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
  for (int j = 0; j < N; ++j) {
    // s(j, k) for k < j holds Lⱼₖ dₖ here; s(k, j) (upper triangle, free until the end) holds Lⱼₖ.
    Scalar pivot = a(j, j);
    for (int k = 0; k < j; ++k) pivot -= s(k, j) * s(j, k);
    if (!(pivot > margin * a(j, j)) || !(pivot <= std::numeric_limits<Scalar>::max())) return false;  // NaN fails too
    s(j, j) = pivot;
    inversePivot[j] = Scalar(1) / pivot;
    for (int i = j + 1; i < N; ++i) {
      Scalar v = a(i, j);
      for (int k = 0; k < j; ++k) v -= s(k, i) * s(j, k);
      s(i, j) = v;                      // Lᵢⱼ dⱼ
      s(j, i) = v * inversePivot[j];    // Lᵢⱼ
    }
  }
  for (int j = 0; j < N; ++j) {
    const Scalar root = std::sqrt(s(j, j));
    const Scalar inverseRoot = root * inversePivot[j];  // dⱼ^½ / dⱼ = dⱼ^-½
    for (int i = j + 1; i < N; ++i) s(i, j) *= inverseRoot;  // Lᵢⱼ dⱼ · dⱼ^-½ = Lᵢⱼ dⱼ^½
    s(j, j) = root;
    for (int i = 0; i < j; ++i) s(i, j) = Scalar(0);
  }
  return true;
}

}  // namespace mjukf::detail
