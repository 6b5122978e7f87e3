#pragma once

// The workspace and the arithmetic shared by the three filters: draw sigma points, take the moments of
// the propagated points (§2), and the Kalman correction from measured points (§3). The filters only
// say how a point is propagated and measured. Every result goes to an output argument so that a filter
// can check it before committing it (the strong guarantee of the failure policy).

#include <cmath>

#include <Eigen/Core>

#include "mjukf/covariance_repair.hpp"
#include "mjukf/detail/cholesky.hpp"
#include "mjukf/detail/finite.hpp"
#include "mjukf/diagnostics.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/status.hpp"
#include "mjukf/unscented_transform.hpp"

namespace mjukf::detail {

template <class Scalar, int L, int M>
class UnscentedCore {
 public:
  using SigmaPoints = MerweScaledSigmaPoints<Scalar, L>;
  static constexpr int Count = SigmaPoints::Count;
  using Vector = Eigen::Matrix<Scalar, L, 1>;
  using Matrix = Eigen::Matrix<Scalar, L, L>;
  using Points = typename SigmaPoints::Points;
  using MeasVector = Eigen::Matrix<Scalar, M, 1>;
  using MeasMatrix = Eigen::Matrix<Scalar, M, M>;
  using MeasPoints = Eigen::Matrix<Scalar, M, Count>;
  using Gain = Eigen::Matrix<Scalar, L, M>;
  using Diagnostics = UpdateDiagnostics<Scalar, M>;
  using Mask = MeasurementMask<M>;
  using Gate = MeasurementGate<Scalar, M>;

  explicit UnscentedCore(const SigmaPointParameters<Scalar>& parameters) : sigmaPoints_(parameters) {}

  /// Symmetrises the filter's P₀ and keeps its Cholesky factor; throws, naming P₀, when it has none.
  void adoptInitialCovariance(const char* owner, Matrix& p0) { symmetrizeInitialCovariance(owner, p0, committedFactor_); }

  /// §1: draws the points of (mean, P) into workPoints(), leaving points() as they are, where P is
  /// the covariance last committed with commitCovariance() (or adopted at construction): its Cholesky
  /// factor is already known, so nothing is factored here.
  Status draw(const Vector& mean) { return sigmaPoints_.generateFromFactor(mean, committedFactor_, workPoints_); }

  /// `committed` ← `settled`, a covariance that settle() has just accepted, and its factor with it.
  void commitCovariance(Matrix& committed, const Matrix& settled) {
    committed = settled;
    committedFactor_ = guard_.factor();
  }

  /// §2: x̂⁻ = Σ Wmᵢ χᵢ⁺, P⁻ = Σ Wcᵢ (χᵢ⁺ − x̂⁻)(χᵢ⁺ − x̂⁻)ᵀ + Q, from the propagated workPoints().
  void predict(const Matrix& processNoise, Vector& mean, Matrix& cov) {
    unscentedMean(workPoints_, sigmaPoints_.meanWeights(), mean);
    stateDeviations_.noalias() = workPoints_.colwise() - mean;
    weightedOuterSum(stateDeviations_, stateDeviations_, cov);
    cov += processNoise;
  }

  /// §3, from `points` about `predictedMean` and their images measuredPoints(): writes the corrected
  /// mean and covariance and the diagnostics. The inputs are left untouched; on a status other than Ok
  /// the outputs are unspecified. With `present` (may be null: all present), the missing components
  /// get zero rows and columns in P_yy (one on its diagonal), in P_xy and in the innovation: the gain
  /// then has zero columns there and the update is exactly that of the reduced model. `gate` refuses
  /// an update whose NIS exceeds its threshold, before anything is computed from the gain.
  Status correct(const Points& points, const Vector& predictedMean, const Matrix& predictedCov, const MeasVector& y,
                 const MeasMatrix& measurementNoise, const Mask* present, const Gate& gate, Vector& mean,
                 Matrix& cov, Diagnostics& diagnostics) {
    if (!allFinite(measuredPoints_)) return Status::NonFiniteResult;  // the model's g gave NaN or Inf
    MeasVector predictedMeasurement;
    unscentedMean(measuredPoints_, sigmaPoints_.meanWeights(), predictedMeasurement);  // ŷ
    measurementDeviations_.noalias() = measuredPoints_.colwise() - predictedMeasurement;
    stateDeviations_.noalias() = points.colwise() - predictedMean;
    weightedOuterSum(measurementDeviations_, measurementDeviations_, diagnostics.innovationCovariance);
    diagnostics.innovationCovariance += measurementNoise;  // P_yy
    weightedOuterSum(stateDeviations_, measurementDeviations_, crossCovariance_);  // P_xy
    diagnostics.innovation = y - predictedMeasurement;
    int presentCount = M;
    if (present) {
      for (int j = 0; j < M; ++j) {
        if ((*present)(j)) continue;
        diagnostics.innovationCovariance.row(j).setZero();
        diagnostics.innovationCovariance.col(j).setZero();
        diagnostics.innovationCovariance(j, j) = Scalar(1);
        crossCovariance_.col(j).setZero();
        diagnostics.innovation(j) = Scalar(0);  // y(j) may be NaN: overwrite, never multiply by 0
        --presentCount;
      }
    }

    if (!allFinite(diagnostics.innovationCovariance) ||
        !choleskyLower(diagnostics.innovationCovariance, innovationFactor_))
      return Status::InnovationNotPositiveDefinite;
    // NIS = νᵀ P_yy⁻¹ ν = |S⁻¹ ν|² with P_yy = S Sᵀ.
    MeasVector whitened = diagnostics.innovation;
    solveLower(whitened);
    diagnostics.nis = whitened.squaredNorm();
    // An innovation or NIS that overflowed (a model returning huge values) is no measurement to use,
    // even when the gain is zero.
    if (!std::isfinite(diagnostics.nis) || !allFinite(diagnostics.innovation)) return Status::NonFiniteResult;
    if (presentCount > 0 && diagnostics.nis > gate.nisThreshold(presentCount - 1)) return Status::MeasurementRejected;
    // K = P_xy P_yy⁻¹, as Kᵀ = P_yy⁻¹ P_xyᵀ with the Cholesky factor (P_yy is symmetric).
    gainTransposed_ = crossCovariance_.transpose();
    solveLower(gainTransposed_);
    solveUpper(gainTransposed_);
    mean = predictedMean;
    mean.noalias() += gainTransposed_.transpose() * diagnostics.innovation;
    // P = P⁻ − K P_yy Kᵀ = P⁻ − P_xy Kᵀ
    cov = predictedCov;
    cov.noalias() -= crossCovariance_ * gainTransposed_;
    return Status::Ok;
  }

  /// What every step does with the covariance it is about to commit: symmetrise it, check it has a
  /// Cholesky factor, repair it if not (covariance_repair.hpp). Ok, Repaired, or a refusal.
  /// Only a covariance accepted here may be committed, and only with commitCovariance().
  Status settle(Matrix& cov, const CovarianceRepair<Scalar>& repair) { return guard_.settle(cov, repair); }

  /// Makes the work points the filter's points, once the step that made them has succeeded.
  void commitPoints() { points_ = workPoints_; }

  Points& workPoints() { return workPoints_; }
  const Points& points() const { return points_; }
  MeasPoints& measuredPoints() { return measuredPoints_; }
  const MeasPoints& measuredPoints() const { return measuredPoints_; }
  const SigmaPoints& sigmaPoints() const { return sigmaPoints_; }

 private:
  // Σ Wcᵢ aᵢ bᵢᵀ (unscentedCovarianceFromDeviations) as a coefficient-wise product. Left to choose,
  // Eigen takes its general GEMM kernel once rows + columns + depth exceed 20 (JUKF on the robot:
  // 6 + 6 + 13), and packing the operands then costs more than the whole rest of the step.
  template <class DevA, class DevB, class Out>
  void weightedOuterSum(const DevA& a, const DevB& b, Out& out) const {
    out.noalias() = (a * sigmaPoints_.covarianceWeights().asDiagonal()).lazyProduct(b.transpose());
  }

  // B ← S⁻¹ B and B ← S⁻ᵀ B with the lower Cholesky factor S of P_yy, by substitution a row at a time.
  // Written out because Eigen's solve with a matrix right-hand side takes its general blocked path
  // (packing, level-3 kernels), which costs more than all the rest of the update at these sizes.
  template <class Rhs>
  void solveLower(Rhs& b) const {
    const MeasMatrix& s = innovationFactor_;
    for (int i = 0; i < M; ++i) {
      for (int k = 0; k < i; ++k) b.row(i) -= s(i, k) * b.row(k);
      b.row(i) /= s(i, i);
    }
  }
  template <class Rhs>
  void solveUpper(Rhs& b) const {
    const MeasMatrix& s = innovationFactor_;
    for (int i = M - 1; i >= 0; --i) {
      for (int k = i + 1; k < M; ++k) b.row(i) -= s(k, i) * b.row(k);
      b.row(i) /= s(i, i);
    }
  }

  SigmaPoints sigmaPoints_;
  Points points_;                 // the filter's propagated points χᵢ⁺, used by the measurement update
  Points workPoints_;             // drawn, then propagated in place, before they are committed
  MeasPoints measuredPoints_;     // Yᵢ = g(χᵢ⁺)
  Points stateDeviations_;        // χᵢ⁺ − x̂⁻
  MeasPoints measurementDeviations_;  // Yᵢ − ŷ
  Gain crossCovariance_;          // P_xy
  Eigen::Matrix<Scalar, M, L> gainTransposed_;  // Kᵀ
  MeasMatrix innovationFactor_;   // S with P_yy = S Sᵀ
  CovarianceGuard<Scalar, L> guard_;
  Matrix committedFactor_;        // the Cholesky factor of the filter's committed P
};

}  // namespace mjukf::detail
