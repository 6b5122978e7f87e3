#pragma once

// Checks of user settings, run once at construction (and by reset()). Each returns a SettingsError
// naming the offending setting, or none; none of them runs on the per-step path, throws or allocates.
// With exceptions on, the filters turn an error into std::invalid_argument (throwInvalid below).

#include <cmath>
#include <limits>
#include <type_traits>

#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/settings_error.hpp"

#if MJUKF_EXCEPTIONS
#include <stdexcept>
#include <string>
#endif

namespace mjukf::detail {

// The tag of a filter's or stepper's constructor that takes settings already validated: only its own
// create() and checked constructor call it, after validate() passed.
struct Validated {};

constexpr SettingsError invalid(const char* owner, const char* setting, const char* reason) {
  return SettingsError{owner, setting, reason};
}

#if MJUKF_EXCEPTIONS
[[noreturn]] inline void throwInvalid(const SettingsError& error) {
  throw std::invalid_argument(std::string(error.owner) + ": setting '" + error.setting + "' " + error.reason);
}
// For a checked constructor: `: Filter(throwIfInvalid(validate(...)), ...)`.
inline Validated throwIfInvalid(const SettingsError& error) {
  if (error) throwInvalid(error);
  return Validated{};
}
#endif

// The ResetResult of reset(): throws `error` with exceptions on, returns it otherwise.
inline ResetResult report(const SettingsError& error) {
#if MJUKF_EXCEPTIONS
  if (error) throwInvalid(error);
#else
  return error;
#endif
}

template <class Scalar, std::enable_if_t<std::is_floating_point_v<Scalar>, int> = 0>
SettingsError requireFinite(const char* owner, const char* setting, Scalar value) {
  if (!std::isfinite(value)) return invalid(owner, setting, "must be finite");
  return {};
}

template <class Derived>
SettingsError requireFinite(const char* owner, const char* setting, const Eigen::MatrixBase<Derived>& m) {
  if (!m.allFinite()) return invalid(owner, setting, "must be finite (it contains NaN or Inf)");
  return {};
}

// Symmetric to a tolerance relative to the largest entry: generous enough for matrices a user computed
// as products, tight enough to catch a transposed or mistyped entry. Relative, so that a tiny R (the
// tank's is 1e-7) gets the same scrutiny as a large one.
template <class Derived>
SettingsError requireSymmetric(const char* owner, const char* setting, const Eigen::MatrixBase<Derived>& m) {
  using Scalar = typename Derived::Scalar;
  if (SettingsError e = requireFinite(owner, setting, m)) return e;
  const Scalar tolerance = Scalar(1000) * std::numeric_limits<Scalar>::epsilon() * m.cwiseAbs().maxCoeff();
  if ((m - m.transpose()).cwiseAbs().maxCoeff() > tolerance) return invalid(owner, setting, "must be symmetric");
  return {};
}

template <class Derived>
SettingsError requirePositiveDefinite(const char* owner, const char* setting, const Eigen::MatrixBase<Derived>& m) {
  if (SettingsError e = requireSymmetric(owner, setting, m)) return e;
  typename Derived::PlainObject factor;
  if (!choleskyLower(m.eval(), factor)) return invalid(owner, setting, "must be positive definite");
  return {};
}

// Positive semi-definite: the smallest eigenvalue may be below zero only by rounding, relative to the
// largest entry (a Q with zero rows is legal). Tested as "Q + δI has a Cholesky factor" with
// δ = 1000ε max|Qᵢⱼ|, which holds exactly when λ_min(Q) > −δ: the rounding of the factorisation itself
// (about Lε max|Qᵢⱼ|) is far below δ. The fixed-size Cholesky here instead of an eigen-solver keeps
// the check cheap to compile for every filter size.
template <class Derived>
SettingsError requirePositiveSemiDefinite(const char* owner, const char* setting, const Eigen::MatrixBase<Derived>& m) {
  using Scalar = typename Derived::Scalar;
  if (SettingsError e = requireSymmetric(owner, setting, m)) return e;
  const Scalar largest = m.cwiseAbs().maxCoeff();
  if (largest == Scalar(0)) return {};  // Q = 0
  typename Derived::PlainObject shifted = m;
  shifted.diagonal().array() += Scalar(1000) * std::numeric_limits<Scalar>::epsilon() * largest;
  typename Derived::PlainObject factor;
  if (!choleskyLower(shifted, factor)) return invalid(owner, setting, "must be positive semi-definite");
  return {};
}

}  // namespace mjukf::detail
