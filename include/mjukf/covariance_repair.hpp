#pragma once

/// \file
/// What a filter does with a covariance before committing it (formed exactly symmetric): check that it
/// has a Cholesky factor, and, when it has none, a bounded repair (a small multiple of the identity).

#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/status.hpp"

namespace mjukf {

/// The repair of a covariance that is not positive definite, applied to the P of every time and
/// measurement update before it is committed (docs/design.md, docs/robustness.md).
///
/// With s = the mean of |Pᵢᵢ|, attempt k = 0 … maxAttempts − 1 factors P + s·firstJitter·growthᵏ·I;
/// the first that has a Cholesky factor is committed and the step returns `Status::Repaired`. When
/// none has one (or s is zero), the step is refused with `Status::NotPositiveDefinite` and nothing
/// changes. The defaults add at most 16ε·10⁴ ≈ 3.6e-11 (double; 1.9e-2 in float) of s: they mend a
/// covariance that lost definiteness to rounding, and refuse one that is indefinite for a reason (bad
/// sigma-point weights, a model that does not fit), which jitter would only hide. Every field:
/// docs/settings.md §2.
template <class Scalar>
struct CovarianceRepair {
  int maxAttempts = 3;  ///< in [0, 64]; 0 disables the repair: a P without a factor is always refused.
  Scalar firstJitter = Scalar(16) * std::numeric_limits<Scalar>::epsilon();  ///< relative to mean |Pᵢᵢ|, > 0
  Scalar growth = Scalar(100);                                               ///< factor between attempts, ≥ 1
};

/// \cond INTERNAL
namespace detail {

template <class Scalar>
SettingsError validateRepair(const char* owner, const CovarianceRepair<Scalar>& repair) {
  if (repair.maxAttempts < 0 || repair.maxAttempts > 64)
    return invalid(owner, "repair.maxAttempts", "must be in [0, 64]");
  if (SettingsError e = requireFinite(owner, "repair.firstJitter", repair.firstJitter)) return e;
  if (SettingsError e = requireFinite(owner, "repair.growth", repair.growth)) return e;
  if (!(repair.firstJitter > 0)) return invalid(owner, "repair.firstJitter", "must be positive");
  if (!(repair.growth >= 1)) return invalid(owner, "repair.growth", "must be >= 1");
  return {};
}

// A covariance a filter starts from (P₀, or the argument of reset()): symmetric positive definite as
// given, and still with a Cholesky factor once symmetrised (assign() symmetrises it; every committed P
// is exactly symmetric). An error naming `setting` otherwise; after it passes, the engine's
// Estimate::assign() cannot fail on it (detail/unscented_engine.hpp, which also holds the repair
// itself, CovarianceGuard).
template <class Derived>
SettingsError requireCommittableCovariance(const char* owner, const char* setting,
                                           const Eigen::MatrixBase<Derived>& m) {
  if (SettingsError e = requirePositiveDefinite(owner, setting, m)) return e;
  typename Derived::PlainObject symmetric = m, factor;
  symmetrize(symmetric);
  if (!choleskyLower(symmetric, factor)) return invalid(owner, setting, "must be positive definite");
  return {};
}

}  // namespace detail
/// \endcond
}  // namespace mjukf
