#pragma once

/// \file
/// Scaled sigma points of van der Merwe (docs/algorithms.md §1).

#include <cmath>

#include <Eigen/Core>

#include "mjukf/detail/cholesky.hpp"
#include "mjukf/detail/finite.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/status.hpp"

namespace mjukf {

/// The three scaling parameters of the sigma points. The paper uses α = 1, β = 2, κ = 0.
template <class Scalar>
struct SigmaPointParameters {
  Scalar alpha = 1;  ///< Spread of the points around the mean; must be positive.
  Scalar beta = 2;   ///< Prior knowledge of the distribution (2 is optimal for a Gaussian).
  Scalar kappa = 0;  ///< Secondary scaling; L + λ = α²(L + κ) must be positive.
};

/// The 2L + 1 scaled sigma points of an L-dimensional Gaussian and their weights.
///
/// The weights are computed once at construction; `generate` draws the points of a mean and
/// covariance without allocating (the Cholesky workspace is a member).
template <class Scalar_, int L>
class MerweScaledSigmaPoints {
  static_assert(L > 0, "the dimension of the sigma points must be positive");

 public:
  /// The floating-point type.
  using Scalar = Scalar_;
  /// L, the dimension of the vector.
  static constexpr int Dim = L;
  /// 2L + 1 points.
  static constexpr int Count = 2 * L + 1;
  /// A vector of dimension L.
  using Vector = Eigen::Matrix<Scalar, L, 1>;
  /// An L × L matrix.
  using Matrix = Eigen::Matrix<Scalar, L, L>;
  /// The points, one per column.
  using Points = Eigen::Matrix<Scalar, L, Count>;
  /// One weight per point.
  using Weights = Eigen::Matrix<Scalar, Count, 1>;

  /// The default parameters (α = 1, β = 2, κ = 0), which are valid for every L.
  MerweScaledSigmaPoints() : MerweScaledSigmaPoints(detail::Validated{}, SigmaPointParameters<Scalar>{}) {}
#if MJUKF_EXCEPTIONS
  /// Throws std::invalid_argument naming the parameter when α ≤ 0, a value is not finite, or
  /// L + λ ≤ 0 (`validate`). Without exceptions, use `create`.
  explicit MerweScaledSigmaPoints(const SigmaPointParameters<Scalar>& parameters)
      : MerweScaledSigmaPoints(detail::throwIfInvalid(validate(parameters)), parameters) {}
#endif
  /// The points of `parameters`, or the SettingsError naming the invalid one.
  static Result<MerweScaledSigmaPoints> create(const SigmaPointParameters<Scalar>& parameters) {
    return detail::resultOf<MerweScaledSigmaPoints>(
        validate(parameters), [&] { return MerweScaledSigmaPoints(detail::Validated{}, parameters); });
  }
  /// The error of the first invalid parameter (α ≤ 0, a value not finite, or L + λ ≤ 0), or none.
  static SettingsError validate(const SigmaPointParameters<Scalar>& parameters) {
    constexpr const char* owner = "mjukf::MerweScaledSigmaPoints";
    if (SettingsError e = detail::requireFinite(owner, "alpha", parameters.alpha)) return e;
    if (SettingsError e = detail::requireFinite(owner, "beta", parameters.beta)) return e;
    if (SettingsError e = detail::requireFinite(owner, "kappa", parameters.kappa)) return e;
    if (!(parameters.alpha > 0)) return detail::invalid(owner, "alpha", "must be positive");
    // L + λ computed as the constructor does, rounding included: a tiny α²(L + κ) can round to L + λ = 0.
    const Scalar lambda = parameters.alpha * parameters.alpha * (Scalar(L) + parameters.kappa) - Scalar(L);
    const Scalar spread = Scalar(L) + lambda;
    if (!(spread > 0) || !std::isfinite(spread))
      return detail::invalid(owner, "kappa", "gives L + lambda <= 0 (needs alpha^2 (L + kappa) > 0)");
    return {};
  }
  /// From parameters that `validate` accepted (the filters' cores, after their own validation).
  MerweScaledSigmaPoints(detail::Validated, const SigmaPointParameters<Scalar>& parameters) : parameters_(parameters) {
    const Scalar alpha2 = parameters.alpha * parameters.alpha;
    lambda_ = alpha2 * (Scalar(L) + parameters.kappa) - Scalar(L);  // λ = α²(L + κ) − L
    const Scalar spread = Scalar(L) + lambda_;                      // L + λ
    gamma_ = std::sqrt(spread);
    meanWeights_.setConstant(Scalar(1) / (Scalar(2) * spread));
    covarianceWeights_ = meanWeights_;
    meanWeights_(0) = lambda_ / spread;
    covarianceWeights_(0) = meanWeights_(0) + Scalar(1) - alpha2 + parameters.beta;
  }

  /// Writes the points of (mean, cov) into `points`: column 0 is the mean, columns 1…L and L+1…2L
  /// are the mean plus and minus γ times the columns of the lower Cholesky factor of `cov` (only its
  /// lower triangle is read). Returns Status::NotPositiveDefinite, with `points` untouched, when `cov`
  /// has no factor or is not finite.
  Status generate(const Vector& mean, const Matrix& cov, Points& points) {
    if (!detail::allFinite(cov) || !detail::choleskyLower(cov, factor_)) return Status::NotPositiveDefinite;
    return generateFromFactor(mean, factor_, points);
  }

  /// The same points from a lower Cholesky factor S of the covariance (cov = S Sᵀ) computed earlier:
  /// a filter keeps the factor of the covariance it committed and draws from it without factoring
  /// again. Only the lower triangle of S is read.
  Status generateFromFactor(const Vector& mean, const Matrix& lowerFactor, Points& points) const {
    if (!detail::allFinite(mean)) return Status::NotPositiveDefinite;
    for (int i = 0; i < L; ++i) {
      // Columns of S, where cov = S Sᵀ (rows would be wrong for a correlated cov).
      points.col(1 + i) = mean;
      points.col(1 + L + i) = mean;
      for (int r = i; r < L; ++r) {  // S is lower triangular: rows above the diagonal are zero.
        const Scalar offset = gamma_ * lowerFactor(r, i);
        points(r, 1 + i) += offset;
        points(r, 1 + L + i) -= offset;
      }
    }
    points.col(0) = mean;
    return Status::Ok;
  }

  /// The mean weights Wmᵢ (docs/algorithms.md §1).
  const Weights& meanWeights() const { return meanWeights_; }
  /// The covariance weights Wcᵢ (docs/algorithms.md §1).
  const Weights& covarianceWeights() const { return covarianceWeights_; }
  /// α, β, κ.
  const SigmaPointParameters<Scalar>& parameters() const { return parameters_; }
  /// λ = α² (L + κ) − L.
  Scalar lambda() const { return lambda_; }
  /// γ = √(L + λ), the scale of the points' spread.
  Scalar gamma() const { return gamma_; }

 private:
  SigmaPointParameters<Scalar> parameters_;
  Scalar lambda_;
  Scalar gamma_;
  Weights meanWeights_;
  Weights covarianceWeights_;
  Matrix factor_ = Matrix::Zero();  // workspace of generate()
};

}  // namespace mjukf
