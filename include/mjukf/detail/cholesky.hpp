#pragma once

// The lower Cholesky factor of a small fixed-size matrix, written out instead of Eigen::LLT because
//  - an LLT member that was never computed holds an indeterminate `info()`, and copying it (copying
//    a filter before its first step) is undefined behaviour, which UBSan reports;
//  - Eigen's LLT also computes the matrix's L1 norm on every call (for rcond()), which nothing here
//    reads, and that is a measurable part of a step at these sizes.

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>

#include <Eigen/Core>

namespace mjukf::detail {

// S with A = S Sᵀ, reading only the lower triangle of A (the strictly upper triangle of S is set to
// zero). Returns false, S then unspecified, when A is not numerically positive definite: a pivot
// a_jj − Σₖ s_jk² that is not above N ε a_jj, the size of its own rounding error, or not finite (NaN
// and Inf fail). Without that margin a singular A (0.5 everywhere, say) can pass on a pivot of 1e-16
// that is all rounding, and whether it passes then depends on the order of the sums: a P accepted here
// must also factor in any other correct Cholesky (Eigen's LLT), which the fuzz target checks.
// `s` must not alias `a`.
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

}  // namespace mjukf::detail
