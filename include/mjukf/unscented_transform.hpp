#pragma once

/// \file
/// Weighted moments of sigma-point sets: the unscented transform (docs/algorithms.md §2–3).
///
/// All functions take fixed-size Eigen matrices whose columns are the points, write into output
/// arguments and allocate nothing.

#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"

namespace mjukf {

/// mean = Σ Wmᵢ Xᵢ
template <class Points, class Weights, class Mean>
void unscentedMean(const Eigen::MatrixBase<Points>& points, const Eigen::MatrixBase<Weights>& meanWeights,
                   Eigen::MatrixBase<Mean>& mean) {
  detail::weightedMean(points, meanWeights, mean);
}

/// cov = Σ Wcᵢ (Xᵢ − a)(Yᵢ − b)ᵀ, given the deviations Xᵢ − a and Yᵢ − b as columns. With the same
/// deviations on both sides this is the covariance, otherwise the cross-covariance.
template <class DevX, class DevY, class Weights, class Cov>
void unscentedCovarianceFromDeviations(const Eigen::MatrixBase<DevX>& devX, const Eigen::MatrixBase<DevY>& devY,
                                       const Eigen::MatrixBase<Weights>& covWeights, Eigen::MatrixBase<Cov>& cov) {
  detail::weightedOuterSum(devX, devY, covWeights, cov);
}

/// The unscented transform of a propagated point set: its weighted mean and covariance (§2, without Q).
template <class Points, class Weights, class Mean, class Cov>
void unscentedTransform(const Eigen::MatrixBase<Points>& points, const Eigen::MatrixBase<Weights>& meanWeights,
                        const Eigen::MatrixBase<Weights>& covWeights, Eigen::MatrixBase<Mean>& mean,
                        Eigen::MatrixBase<Cov>& cov) {
  unscentedMean(points, meanWeights, mean);
  const typename Points::PlainObject deviations = points.colwise() - mean;
  unscentedCovarianceFromDeviations(deviations, deviations, covWeights, cov);
}

}  // namespace mjukf
