#pragma once

/// \file
/// Measurement masking (missing channels) and the innovation gate (outlier rejection).

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/validation.hpp"

namespace mjukf {

/// Which components of a measurement are present: `present(j)` false means component j is missing
/// and its value, NaN included, is ignored. Pass to `measurementUpdate(y, present)`.
template <int MeasDim>
using MeasurementMask = Eigen::Matrix<bool, MeasDim, 1>;

/// The quantile x of the χ² distribution with `dof` degrees of freedom: P(χ² ≤ x) = probability.
/// For building gates at construction time (series of the regularised incomplete gamma function and
/// bisection, to ~1e-10 relative); not meant for the per-step path. Returns NaN outside 0 < p < 1.
inline double chiSquareQuantile(double probability, int dof) {
  if (!(probability > 0 && probability < 1) || dof < 1) return std::numeric_limits<double>::quiet_NaN();
  const double a = 0.5 * dof;
  // P(a, x/2), the χ² CDF at x, by its power series (converges for every x, ~x terms).
  const auto cdf = [a](double x) {
    const double half = 0.5 * x;
    if (half <= 0) return 0.0;
    double term = 1.0 / a, sum = term;
    for (int n = 1; n < 100000 && term > sum * 1e-17; ++n) {
      term *= half / (a + n);
      sum += term;
    }
    return std::exp(a * std::log(half) - half - std::lgamma(a)) * sum;
  };
  double lo = 0, hi = 2.0 * dof + 10;
  while (cdf(hi) < probability) hi *= 2;
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (cdf(mid) < probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// The innovation gate of a measurement update (off by default).
///
/// An update whose normalised innovation squared NIS = νᵀ P_yy⁻¹ ν, over the k components present,
/// exceeds `nisThreshold(k − 1)` is refused with `Status::MeasurementRejected` and changes nothing. The
/// NIS of a consistent filter is χ²-distributed with k degrees of freedom, so `chiSquare(0.999)` rejects
/// one good measurement in a thousand. Gating needs an R that matches the actual measurement noise:
/// with an R far below it (the paper's tank R = 1e-7) every measurement looks like an outlier. Every
/// field: docs/settings.md §2.
template <class Scalar, int MeasDim>
struct MeasurementGate {
  /// One threshold per measurement component.
  using Thresholds = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// nisThreshold(k − 1) is the largest NIS accepted with k components present; +∞ accepts all.
  Thresholds nisThreshold = Thresholds::Constant(std::numeric_limits<Scalar>::infinity());

  /// The gate at χ² quantile `probability` for every number of components present.
  static MeasurementGate chiSquare(double probability) {
    MeasurementGate gate;
    for (int k = 1; k <= MeasDim; ++k) gate.nisThreshold(k - 1) = Scalar(chiSquareQuantile(probability, k));
    return gate;
  }
};

/// \cond INTERNAL
namespace detail {

template <class Scalar, int MeasDim>
SettingsError validateGate(const char* owner, const MeasurementGate<Scalar, MeasDim>& gate) {
  if (!(gate.nisThreshold.array() > Scalar(0)).all())
    return invalid(owner, "gate.nisThreshold", "must be positive (+infinity turns the gate off)");
  return {};
}

}  // namespace detail
/// \endcond
}  // namespace mjukf
