#pragma once

// The lower Cholesky factor of a small fixed-size matrix, written out instead of Eigen::LLT because
//  - an LLT member that was never computed holds an indeterminate `info()`, and copying it (copying
//    a filter before its first step) is undefined behaviour, which UBSan reports;
//  - Eigen's LLT also computes the matrix's L1 norm on every call (for rcond()), which nothing here
//    reads, and that is a measurable part of a step at these sizes.
// The arithmetic is Eigen's unblocked left-looking algorithm: column j from the rows above it.

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
  constexpr Scalar margin = Scalar(N) * std::numeric_limits<Scalar>::epsilon();
  for (int j = 0; j < N; ++j) {
    Scalar sumOfSquares = 0;
    for (int k = 0; k < j; ++k) sumOfSquares += s(j, k) * s(j, k);
    const Scalar pivot = a(j, j) - sumOfSquares;
    if (!(pivot > margin * a(j, j)) || !(pivot <= std::numeric_limits<Scalar>::max())) return false;
    const Scalar diagonal = std::sqrt(pivot);
    s(j, j) = diagonal;
    for (int i = j + 1; i < N; ++i) {
      Scalar dot = 0;
      for (int k = 0; k < j; ++k) dot += s(i, k) * s(j, k);
      s(i, j) = (a(i, j) - dot) / diagonal;
    }
    for (int i = 0; i < j; ++i) s(i, j) = Scalar(0);
  }
  return true;
}

}  // namespace mjukf::detail
