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
// zero). Returns false, S then unspecified, when a pivot is not positive and finite: A has no factor
// (or holds NaN or Inf). `s` must not alias `a`.
template <class Scalar, int N>
bool choleskyLower(const Eigen::Matrix<Scalar, N, N>& a, Eigen::Matrix<Scalar, N, N>& s) {
  for (int j = 0; j < N; ++j) {
    Scalar pivot = a(j, j);
    for (int k = 0; k < j; ++k) pivot -= s(j, k) * s(j, k);
    if (!(pivot > Scalar(0)) || !(pivot <= std::numeric_limits<Scalar>::max())) return false;  // NaN fails too
    const Scalar diagonal = std::sqrt(pivot);
    s(j, j) = diagonal;
    for (int i = j + 1; i < N; ++i) {
      Scalar v = a(i, j);
      for (int k = 0; k < j; ++k) v -= s(i, k) * s(j, k);
      s(i, j) = v / diagonal;
    }
    for (int i = 0; i < j; ++i) s(i, j) = Scalar(0);
  }
  return true;
}

}  // namespace mjukf::detail
