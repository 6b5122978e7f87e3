#pragma once

// Checks of user settings, run once at construction. They throw std::invalid_argument with a message
// that names the offending setting; none of them runs on the per-step path.

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

#include <Eigen/Core>

#include "mjukf/detail/cholesky.hpp"

namespace mjukf::detail {

[[noreturn]] inline void throwInvalid(const char* owner, const char* setting, const std::string& what) {
  throw std::invalid_argument(std::string(owner) + ": setting '" + setting + "' " + what);
}

template <class Scalar, std::enable_if_t<std::is_floating_point_v<Scalar>, int> = 0>
void requireFinite(const char* owner, const char* setting, Scalar value) {
  if (!std::isfinite(value)) throwInvalid(owner, setting, "must be finite");
}

template <class Derived>
void requireFinite(const char* owner, const char* setting, const Eigen::MatrixBase<Derived>& m) {
  if (!m.allFinite()) throwInvalid(owner, setting, "must be finite (it contains NaN or Inf)");
}

// Symmetric to a tolerance relative to the largest entry: generous enough for matrices a user computed
// as products, tight enough to catch a transposed or mistyped entry. Relative, so that a tiny R (the
// tank's is 1e-7) gets the same scrutiny as a large one.
template <class Derived>
void requireSymmetric(const char* owner, const char* setting, const Eigen::MatrixBase<Derived>& m) {
  using Scalar = typename Derived::Scalar;
  requireFinite(owner, setting, m);
  const Scalar tolerance = Scalar(1000) * std::numeric_limits<Scalar>::epsilon() * m.cwiseAbs().maxCoeff();
  if ((m - m.transpose()).cwiseAbs().maxCoeff() > tolerance) throwInvalid(owner, setting, "must be symmetric");
}

template <class Derived>
void requirePositiveDefinite(const char* owner, const char* setting, const Eigen::MatrixBase<Derived>& m) {
  requireSymmetric(owner, setting, m);
  typename Derived::PlainObject factor;
  if (!choleskyLower(m.eval(), factor)) throwInvalid(owner, setting, "must be positive definite");
}

// Positive semi-definite: the smallest eigenvalue may be below zero only by rounding, relative to the
// largest entry (a Q with zero rows is legal). Tested as "Q + δI has a Cholesky factor" with
// δ = 1000ε max|Qᵢⱼ|, which holds exactly when λ_min(Q) > −δ: the rounding of the factorisation itself
// (about Lε max|Qᵢⱼ|) is far below δ. The fixed-size Cholesky here instead of an eigen-solver keeps
// the check cheap to compile for every filter size.
template <class Derived>
void requirePositiveSemiDefinite(const char* owner, const char* setting, const Eigen::MatrixBase<Derived>& m) {
  using Scalar = typename Derived::Scalar;
  requireSymmetric(owner, setting, m);
  const Scalar largest = m.cwiseAbs().maxCoeff();
  if (largest == Scalar(0)) return;  // Q = 0
  typename Derived::PlainObject shifted = m;
  shifted.diagonal().array() += Scalar(1000) * std::numeric_limits<Scalar>::epsilon() * largest;
  typename Derived::PlainObject factor;
  if (!choleskyLower(shifted, factor)) throwInvalid(owner, setting, "must be positive semi-definite");
}

}  // namespace mjukf::detail
