#pragma once

/// \file
/// The sigma-point sets a filter can draw (docs/algorithms.md §1): van der Merwe's scaled set, the
/// default, and the spherical-radial cubature set of the cubature Kalman filter. A set is a policy of
/// the filters (their third template argument): its size, its weights and the spread γ of its points
/// about the mean, all fixed at construction. Both sets here are symmetric (x̂ ± γ Sᵢ for the columns
/// Sᵢ of a factor of P, with or without x̂ itself), and a step draws them with
/// detail::drawSymmetricPoints (detail/linear_algebra.hpp).

#include <cmath>

#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/status.hpp"

namespace mjukf {

/// The three scaling parameters of the sigma points. The paper uses α = 1, β = 2, κ = 0. Every field:
/// docs/settings.md §2.
template <class Scalar>
struct SigmaPointParameters {
  Scalar alpha = 1;  ///< Spread of the points around the mean; must be positive.
  Scalar beta = 2;   ///< Prior knowledge of the distribution (2 is optimal for a Gaussian).
  Scalar kappa = 0;  ///< Secondary scaling; L + λ = α²(L + κ) must be positive.
};

/// What every symmetric sigma-point set shares: `Count` points x̂ ± γ Sᵢ for the columns Sᵢ of the lower
/// Cholesky factor of P (with x̂ itself first when `Center`), their mean and covariance weights, and
/// drawing them without allocating. A set derives from it and
/// fills the weights and γ at construction: `MerweScaledSigmaPoints`, `CubatureSigmaPoints`.
template <class Scalar_, int L, bool Center>
class SymmetricSigmaPointSet {
  static_assert(L > 0, "the dimension of the sigma points must be positive");

 public:
  /// The floating-point type.
  using Scalar = Scalar_;
  /// L, the dimension of the vector.
  static constexpr int Dim = L;
  /// The number of points: 2L, and one more at the mean when `HasCenter`.
  static constexpr int Count = 2 * L + (Center ? 1 : 0);
  /// Whether the first point is the mean itself.
  static constexpr bool HasCenter = Center;
  /// A vector of dimension L.
  using Vector = Eigen::Matrix<Scalar, L, 1>;
  /// An L × L matrix.
  using Matrix = Eigen::Matrix<Scalar, L, L>;
  /// The points, one per column.
  using Points = Eigen::Matrix<Scalar, L, Count>;
  /// One weight per point.
  using Weights = Eigen::Matrix<Scalar, Count, 1>;

  /// Writes the points of (mean, cov) into `points`: the mean (when `HasCenter`), then the mean plus
  /// and minus γ times the columns of the lower Cholesky factor of `cov` (only its lower triangle is
  /// read). Returns Status::NotPositiveDefinite, with `points` untouched, when `cov` has no factor or
  /// is not finite. The factor is a local: a filter, which keeps its own factor and draws with
  /// `generateFromFactor`, does not carry an L × L workspace it never uses.
  Status generate(const Vector& mean, const Matrix& cov, Points& points) const {
    Matrix factor;
    if (!detail::allFinite(cov) || !detail::choleskyLower(cov, factor)) return Status::NotPositiveDefinite;
    return generateFromFactor(mean, factor, points);
  }

  /// The same points from a lower Cholesky factor S of the covariance (cov = S Sᵀ) computed earlier:
  /// a filter keeps the factor of the covariance it committed and draws from it without factoring
  /// again. Only the lower triangle of S is read.
  Status generateFromFactor(const Vector& mean, const Matrix& lowerFactor, Points& points) const {
    if (!detail::allFinite(mean)) return Status::NotPositiveDefinite;
    detail::drawSymmetricPoints<HasCenter>(mean, lowerFactor, gamma_, points);
    return Status::Ok;
  }

  /// The mean weights Wmᵢ (docs/algorithms.md §1).
  const Weights& meanWeights() const { return meanWeights_; }
  /// The covariance weights Wcᵢ (docs/algorithms.md §1).
  const Weights& covarianceWeights() const { return covarianceWeights_; }
  /// γ, the scale of the points' spread.
  Scalar gamma() const { return gamma_; }

 protected:
  /// Weights and γ zero until the derived set sets them.
  SymmetricSigmaPointSet() = default;

  Weights meanWeights_ = Weights::Zero();        ///< Wmᵢ, set by the derived set
  Weights covarianceWeights_ = Weights::Zero();  ///< Wcᵢ, set by the derived set
  Scalar gamma_ = 0;                             ///< γ, set by the derived set
};

/// The 2L + 1 scaled sigma points of an L-dimensional Gaussian and their weights.
///
/// The weights are computed once at construction; `generate` draws the points of a mean and
/// covariance without allocating.
template <class Scalar_, int L>
class MerweScaledSigmaPoints : public SymmetricSigmaPointSet<Scalar_, L, true> {
  using Base = SymmetricSigmaPointSet<Scalar_, L, true>;
  using Base::covarianceWeights_, Base::gamma_, Base::meanWeights_;

 public:
  using typename Base::Scalar;

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

  /// α, β, κ.
  const SigmaPointParameters<Scalar>& parameters() const { return parameters_; }
  /// λ = α² (L + κ) − L.
  Scalar lambda() const { return lambda_; }

 private:
  SigmaPointParameters<Scalar> parameters_;
  Scalar lambda_;
};

/// The 2L points of the spherical-radial cubature rule of degree 3 (the cubature Kalman filter,
/// Arasaratnam and Haykin 2009): x̂ ± √L Sᵢ for the columns Sᵢ of the lower Cholesky factor of P, each
/// with weight 1/(2L), for the mean and the covariance alike. No point at the mean and no weight below
/// zero, so P⁻ is a sum of positive terms for every L (the scaled set with κ = 0 and α = 1 gives the
/// centre a zero mean weight; with α < 1 its weight turns negative). It integrates polynomials up to
/// degree 3 exactly, as the scaled set does, and has no parameters: the filters' `sigmaPoints` setting
/// (α, β, κ) is not used with it. The MJUKF cannot take it: its eqs. 8–10 pair 2n + 1 points with
/// their θᵢ.
template <class Scalar_, int L>
class CubatureSigmaPoints : public SymmetricSigmaPointSet<Scalar_, L, false> {
  using Base = SymmetricSigmaPointSet<Scalar_, L, false>;

 public:
  using typename Base::Scalar;

  /// The set (it has no parameters).
  CubatureSigmaPoints() {
    this->meanWeights_.setConstant(Scalar(1) / Scalar(Base::Count));  // 1/(2L)
    this->covarianceWeights_ = this->meanWeights_;
    this->gamma_ = std::sqrt(Scalar(L));  // √L
  }
  /// The filters build their sets from their `sigmaPoints` setting; the cubature set does not use it.
  CubatureSigmaPoints(detail::Validated, const SigmaPointParameters<Scalar>&) : CubatureSigmaPoints() {}
  /// Always valid: the set has no parameters, and `parameters` is not used.
  static SettingsError validate(const SigmaPointParameters<Scalar>& /*parameters*/) { return {}; }
};

/// Selects van der Merwe's scaled set (the default) as a filter's sigma points: the last template
/// argument of `Ukf`, `JointUkf`, `ModifiedJointUkf` and `DualUkf`.
struct MerweScaled {
  /// The set at dimension L.
  template <class Scalar, int L>
  using Set = MerweScaledSigmaPoints<Scalar, L>;
};

/// Selects the cubature set as a filter's sigma points (not for `ModifiedJointUkf`).
struct Cubature {
  /// The set at dimension L.
  template <class Scalar, int L>
  using Set = CubatureSigmaPoints<Scalar, L>;
};

}  // namespace mjukf
