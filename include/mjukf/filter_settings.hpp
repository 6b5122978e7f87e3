#pragma once

/// \file
/// The settings every filter shares, declared and documented once; each filter's own settings
/// struct derives from these and adds what only it has.

#include <Eigen/Core>

#include "mjukf/covariance_repair.hpp"
#include "mjukf/health.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/parameter_bounds.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/step_check.hpp"

namespace mjukf {

/// Settings of an unscented estimate of an `EstimateDim`-vector (the state x for `Ukf`,
/// `ModifiedJointUkf` and the state filter of `DualUkf`; [x; θ] for `JointUkf`) measured through
/// `MeasDim` components. Validated when a filter is constructed. Every field: docs/settings.md §2.
template <class Scalar_, int EstimateDim, int MeasDim>
struct UnscentedSettings {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// The type of P₀ and Q (the estimate's dimension squared).
  using CovarianceMatrix = Eigen::Matrix<Scalar, EstimateDim, EstimateDim>;
  /// The type of R (m × m).
  using MeasMatrix = Eigen::Matrix<Scalar, MeasDim, MeasDim>;

  /// α, β, κ of van der Merwe's set (L = `EstimateDim`); not used by the cubature set.
  SigmaPointParameters<Scalar> sigmaPoints;
  /// P₀, symmetric positive definite; the default (zero) is refused.
  CovarianceMatrix initialCovariance = CovarianceMatrix::Zero();
  /// Q, symmetric positive semi-definite, added once per time update (however many steps it covers).
  CovarianceMatrix processNoise = CovarianceMatrix::Zero();
  /// R, symmetric positive definite; the default (zero) is refused.
  MeasMatrix measurementNoise = MeasMatrix::Zero();
  /// false (the paper's Algorithm 1): the measurement update reuses the propagated sigma points, so
  /// P_xy and P_yy leave Q out. true: it draws new points from (x̂⁻, P⁻), which costs one more
  /// Cholesky factorisation and makes the filter the textbook Kalman filter on linear models.
  bool redrawPointsForUpdate = false;
  /// What a step does with a covariance that is not positive definite before committing it
  /// (covariance_repair.hpp): by default, mend rounding-level losses and refuse the rest.
  CovarianceRepair<Scalar> repair;
  /// The innovation gate of the measurement update (measurement_gating.hpp); off by default.
  MeasurementGate<Scalar, MeasDim> gate;
  /// The check of the integration step against the model's dynamics (step_check.hpp): an oversized
  /// step is refused by default.
  StepCheck<Scalar> stepCheck;
  /// The health monitor (health.hpp): on by default; what `health()` reports.
  HealthSettings<Scalar> health;
};

/// The shared settings of a filter that also estimates `ParamDim` parameters. Every field:
/// docs/settings.md §2–3.
template <class Scalar, int EstimateDim, int MeasDim, int ParamDim>
struct ParameterEstimationSettings : UnscentedSettings<Scalar, EstimateDim, MeasDim> {
  /// Box bounds on the estimated parameters (parameter_bounds.hpp); off by default.
  ParameterBounds<Scalar, ParamDim> parameterBounds;
};

}  // namespace mjukf
