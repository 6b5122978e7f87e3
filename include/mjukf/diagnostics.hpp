#pragma once

/// \file
/// What the last successful measurement update saw.

#include <Eigen/Core>

namespace mjukf {

/// Diagnostics of a measurement update (docs/algorithms.md §3). Zero until the first successful update;
/// a refused update leaves them as they were.
template <class Scalar, int MeasDim>
struct UpdateDiagnostics {
  Eigen::Matrix<Scalar, MeasDim, 1> innovation = Eigen::Matrix<Scalar, MeasDim, 1>::Zero();  ///< y − ŷ
  Eigen::Matrix<Scalar, MeasDim, MeasDim> innovationCovariance =
      Eigen::Matrix<Scalar, MeasDim, MeasDim>::Zero();  ///< P_yy
  /// Normalised innovation squared (y − ŷ)ᵀ P_yy⁻¹ (y − ŷ): χ²-distributed with MeasDim degrees of
  /// freedom when the filter is consistent.
  Scalar nis = 0;
};

}  // namespace mjukf
