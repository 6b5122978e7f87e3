#pragma once

/// \file
/// What a filter does with a covariance before committing it: symmetrise, check that it has a
/// Cholesky factor, and, when it has none, a bounded repair (a small multiple of the identity).

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/cholesky.hpp"
#include "mjukf/detail/finite.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/status.hpp"

namespace mjukf {

/// The repair of a covariance that is not positive definite, applied to the P of every time and
/// measurement update before it is committed (docs/design.md, docs/robustness.md).
///
/// With s = the mean of |Pᵢᵢ|, attempt k = 0 … maxAttempts − 1 factors P + s·firstJitter·growthᵏ·I;
/// the first that has a Cholesky factor is committed and the step returns `Status::Repaired`. When
/// none has one (or s is zero), the step is refused with `Status::NotPositiveDefinite` and nothing
/// changes. The defaults add at most 16ε·10⁴ ≈ 3.6e-11 (double) of s: they mend a covariance that lost
/// definiteness to rounding, and refuse one that is indefinite for a reason (bad sigma-point weights,
/// a model that does not fit), which jitter would only hide.
template <class Scalar>
struct CovarianceRepair {
  int maxAttempts = 3;  ///< 0 disables the repair: a P without a factor is always refused.
  Scalar firstJitter = Scalar(16) * std::numeric_limits<Scalar>::epsilon();  ///< relative to mean |Pᵢᵢ|, > 0
  Scalar growth = Scalar(100);  ///< factor between attempts, ≥ 1
};

/// \cond INTERNAL
namespace detail {

template <class Scalar>
SettingsError validateRepair(const char* owner, const CovarianceRepair<Scalar>& repair) {
  if (repair.maxAttempts < 0 || repair.maxAttempts > 64) return invalid(owner, "repair.maxAttempts", "must be in [0, 64]");
  if (SettingsError e = requireFinite(owner, "repair.firstJitter", repair.firstJitter)) return e;
  if (SettingsError e = requireFinite(owner, "repair.growth", repair.growth)) return e;
  if (!(repair.firstJitter > 0)) return invalid(owner, "repair.firstJitter", "must be positive");
  if (!(repair.growth >= 1)) return invalid(owner, "repair.growth", "must be >= 1");
  return {};
}

// P ← (P + Pᵀ)/2 in place, a triangle at a time (no temporary, no aliasing). Halved before the sum,
// which gives the same bits as halving after it (subnormal entries aside) but cannot overflow for
// entries near the largest Scalar.
template <class Matrix>
void symmetrize(Matrix& p) {
  using Scalar = typename Matrix::Scalar;
  for (int c = 0; c < p.cols(); ++c)
    for (int r = c + 1; r < p.rows(); ++r) p(r, c) = p(c, r) = Scalar(0.5) * p(r, c) + Scalar(0.5) * p(c, r);
}

// A covariance a filter starts from (P₀, or the argument of reset()): symmetric positive definite as
// given, and still with a Cholesky factor once symmetrised, as every committed P is. An error naming
// `setting` otherwise; after it passes, UnscentedCore::assign() cannot fail on it.
template <class Derived>
SettingsError requireCommittableCovariance(const char* owner, const char* setting,
                                           const Eigen::MatrixBase<Derived>& m) {
  if (SettingsError e = requirePositiveDefinite(owner, setting, m)) return e;
  typename Derived::PlainObject symmetric = m, factor;
  symmetrize(symmetric);
  if (!choleskyLower(symmetric, factor)) return invalid(owner, setting, "must be positive definite");
  return {};
}

// The check and repair of a covariance about to be committed; the workspace is a member, so it
// allocates nothing. The Cholesky factor of the covariance it accepted is kept (`factor()`): the
// filter draws its next sigma points from it instead of factoring the same matrix again.
template <class Scalar, int L>
class CovarianceGuard {
 public:
  using Matrix = Eigen::Matrix<Scalar, L, L>;

  // Symmetrises `cov` and makes sure it has a Cholesky factor: Ok when it had one, Repaired when the
  // repair gave it one (cov then holds the repaired matrix), NotPositiveDefinite or NonFiniteResult
  // when it is refused (cov and factor() are then unspecified). After Ok or Repaired, factor() is the
  // lower Cholesky factor of cov as returned.
  Status settle(Matrix& cov, const CovarianceRepair<Scalar>& repair) {
    symmetrize(cov);
    if (!allFinite(cov)) return Status::NonFiniteResult;
    if (choleskyLower(cov, factor_)) return Status::Ok;
    const Scalar scale = cov.diagonal().cwiseAbs().mean();
    if (!(scale > 0) || !std::isfinite(scale)) return Status::NotPositiveDefinite;
    Scalar jitter = scale * repair.firstJitter;
    for (int attempt = 0; attempt < repair.maxAttempts && std::isfinite(jitter); ++attempt, jitter *= repair.growth) {
      candidate_ = cov;
      candidate_.diagonal().array() += jitter;
      if (!allFinite(candidate_)) break;  // a diagonal near the largest Scalar overflowed
      if (choleskyLower(candidate_, factor_)) {
        cov = candidate_;
        return Status::Repaired;
      }
    }
    return Status::NotPositiveDefinite;
  }

  const Matrix& factor() const { return factor_; }

 private:
  Matrix factor_ = Matrix::Zero();
  Matrix candidate_ = Matrix::Zero();
};

}  // namespace detail
/// \endcond
}  // namespace mjukf
