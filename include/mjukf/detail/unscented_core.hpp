#pragma once

// One unscented estimate: the committed mean, covariance, its Cholesky factor and propagated sigma
// points, the workspace a step computes into, and the arithmetic of docs/algorithms.md §1–3. A filter
// step writes only to the candidates here and commits them with one call, so "the stored factor is the
// Cholesky factor of the committed P" is kept by this class alone: nothing else can assign P.

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
  using Diagnostics = UpdateDiagnostics<Scalar, M>;
  using Mask = MeasurementMask<M>;
  using Gate = MeasurementGate<Scalar, M>;

  /// From sigma-point parameters that SigmaPoints::validate accepted (the filter's validate()).
  UnscentedCore(Validated, const SigmaPointParameters<Scalar>& parameters) : sigmaPoints_(Validated{}, parameters) {}

  // ---- The committed estimate ----------------------------------------------------------------------
  const Vector& mean() const { return mean_; }
  const Matrix& covariance() const { return covariance_; }
  /// The lower Cholesky factor of covariance().
  const Matrix& factor() const { return factor_; }
  /// The points of the last time update, while they are still the estimate's (hasPoints()).
  const Points& points() const { return points_; }
  bool hasPoints() const { return hasPoints_; }
  const Diagnostics& diagnostics() const { return diagnostics_; }

  /// Makes (mean, cov) the estimate, with cov symmetrised as every committed P is, and forgets the
  /// propagated points; the diagnostics are zeroed. Returns false, changing nothing, when the
  /// symmetrised cov has no Cholesky factor or either is not finite.
  bool assign(const Vector& mean, const Matrix& cov) {
    Matrix symmetric = cov, factor;
    symmetrize(symmetric);
    if (!allFinite(mean) || !allFinite(symmetric) || !choleskyLower(symmetric, factor)) return false;
    mean_ = mean;
    covariance_ = symmetric;
    factor_ = factor;
    hasPoints_ = false;
    diagnostics_ = Diagnostics();
    return true;
  }

  // ---- One step: draw, propagate (the filter), predict or correct, settle, commit -------------------

  /// §1: the points of (mean, P) into workPoints(), with P the committed covariance, whose factor is
  /// known: nothing is factored here.
  Status draw(const Vector& mean) { return sigmaPoints_.generateFromFactor(mean, factor_, workPoints_); }
  /// §1 from another estimate's mean and factor (the dual filter's re-prediction).
  Status drawFrom(const Vector& mean, const Matrix& lowerFactor) {
    return sigmaPoints_.generateFromFactor(mean, lowerFactor, workPoints_);
  }

  /// §2: x̂⁻ = Σ Wmᵢ χᵢ⁺, P⁻ = Σ Wcᵢ (χᵢ⁺ − x̂⁻)(χᵢ⁺ − x̂⁻)ᵀ + Q from the propagated workPoints(), into
  /// candidateMean() and candidateCovariance().
  void predict(const Matrix& processNoise) {
    unscentedMean(workPoints_, sigmaPoints_.meanWeights(), candidateMean_);
    deviations_.noalias() = workPoints_.colwise() - candidateMean_;
    weightedOuterSum(deviations_, deviations_, candidateCovariance_);
    candidateCovariance_ += processNoise;
  }

  /// §3 from `points` about the prior (`priorMean`, `priorCov`) and their images measuredPoints(), into
  /// candidateMean(), candidateCovariance() and candidateDiagnostics(); on a status other than Ok the
  /// candidates are unspecified. With `present` (null: all present), the missing components get zero
  /// rows and columns in P_yy (one on its diagonal), in P_xy and in the innovation: the gain then has
  /// zero columns there and the update is exactly that of the reduced model. `gate` refuses an update
  /// whose NIS exceeds its threshold, before anything is computed from the gain.
  Status correct(const Points& points, const Vector& priorMean, const Matrix& priorCov, const MeasVector& y,
                 const MeasMatrix& measurementNoise, const Mask* present, const Gate& gate) {
    if (!allFinite(measuredPoints_)) return Status::NonFiniteResult;  // the model's g gave NaN or Inf
    Diagnostics& d = candidateDiagnostics_;
    MeasVector predictedMeasurement;
    unscentedMean(measuredPoints_, sigmaPoints_.meanWeights(), predictedMeasurement);  // ŷ
    measurementDeviations_.noalias() = measuredPoints_.colwise() - predictedMeasurement;
    deviations_.noalias() = points.colwise() - priorMean;
    weightedOuterSum(measurementDeviations_, measurementDeviations_, d.innovationCovariance);
    d.innovationCovariance += measurementNoise;                                 // P_yy
    weightedOuterSum(deviations_, measurementDeviations_, crossCovariance_);  // P_xy
    d.innovation = y - predictedMeasurement;
    int presentCount = M;
    if (present) {
      for (int j = 0; j < M; ++j) {
        if ((*present)(j)) continue;
        d.innovationCovariance.row(j).setZero();
        d.innovationCovariance.col(j).setZero();
        d.innovationCovariance(j, j) = Scalar(1);
        crossCovariance_.col(j).setZero();
        d.innovation(j) = Scalar(0);  // y(j) may be NaN: overwrite, never multiply by 0
        --presentCount;
      }
    }

    if (!allFinite(d.innovationCovariance) || !choleskyLower(d.innovationCovariance, innovationFactor_))
      return Status::InnovationNotPositiveDefinite;
    // With P_yy = S Sᵀ, the gain is K = P_xy P_yy⁻¹ = U S⁻¹ with U = P_xy S⁻ᵀ, so that
    //   K ν = U w with w = S⁻¹ ν (the whitened innovation, whose |w|² is the NIS), and
    //   K P_yy Kᵀ = U Uᵀ:
    // one triangular solve for U instead of two for K, and a P that is symmetric as computed.
    MeasVector whitened = d.innovation;
    solveLowerInPlace(innovationFactor_, whitened);
    d.nis = whitened.squaredNorm();
    // An innovation or NIS that overflowed (a model returning huge values) is no measurement to use,
    // even when the gain is zero.
    if (!std::isfinite(d.nis) || !allFinite(d.innovation)) return Status::NonFiniteResult;
    if (presentCount > 0 && d.nis > gate.nisThreshold(presentCount - 1)) return Status::MeasurementRejected;
    whitenCrossCovariance();  // U
    candidateMean_ = priorMean;
    candidateMean_.noalias() += crossCovariance_ * whitened;  // x̂ = x̂⁻ + K ν
    candidateCovariance_ = priorCov;
    candidateCovariance_.noalias() -= crossCovariance_.lazyProduct(crossCovariance_.transpose());  // P = P⁻ − K P_yy Kᵀ
    return Status::Ok;
  }

  /// What every step does with the covariance it is about to commit: symmetrise candidateCovariance(),
  /// check it has a Cholesky factor, repair it if not (covariance_repair.hpp). Ok, Repaired, or a
  /// refusal. Only a covariance accepted here is committed.
  Status settle(const CovarianceRepair<Scalar>& repair) { return guard_.settle(candidateCovariance_, repair); }

  /// Commits a time update that settle() accepted: its mean, covariance and factor, and its points.
  void commitPrediction() {
    points_ = workPoints_;
    hasPoints_ = true;
    commitCandidate();
  }
  /// Commits a measurement update that settle() accepted: its mean, covariance, factor and diagnostics.
  /// The points no longer describe the estimate.
  void commitCorrection() {
    diagnostics_ = candidateDiagnostics_;
    hasPoints_ = false;
    commitCandidate();
  }
  /// Commits a new mean alone (an open-loop propagation): P and its factor stay.
  void commitMean(const Vector& mean) {
    mean_ = mean;
    hasPoints_ = false;
  }

  Points& workPoints() { return workPoints_; }
  MeasPoints& measuredPoints() { return measuredPoints_; }
  const MeasPoints& measuredPoints() const { return measuredPoints_; }
  Vector& candidateMean() { return candidateMean_; }
  const Vector& candidateMean() const { return candidateMean_; }
  Matrix& candidateCovariance() { return candidateCovariance_; }
  /// The factor of candidateCovariance() after settle() accepted it.
  const Matrix& candidateFactor() const { return guard_.factor(); }
  const SigmaPoints& sigmaPoints() const { return sigmaPoints_; }
  /// After correct() returned Ok: U = P_xy S⁻ᵀ and the lower Cholesky factor S of P_yy, so that the
  /// gain is K = U S⁻¹ (the MJUKF's automatic modes read them to follow the sensitivity of the
  /// estimate to the parameters).
  const Eigen::Matrix<Scalar, L, M>& candidateWhitenedCrossCovariance() const { return crossCovariance_; }
  const MeasMatrix& candidateInnovationFactor() const { return innovationFactor_; }

 private:
  void commitCandidate() {
    mean_ = candidateMean_;
    covariance_ = candidateCovariance_;
    factor_ = guard_.factor();
  }

  // Σ Wcᵢ aᵢ bᵢᵀ (unscentedCovarianceFromDeviations) as a coefficient-wise product. Left to choose,
  // Eigen takes its general GEMM kernel once rows + columns + depth exceed 20 (JUKF on the robot:
  // 6 + 6 + 13), and packing the operands then costs more than the whole rest of the step.
  template <class DevA, class DevB, class Out>
  void weightedOuterSum(const DevA& a, const DevB& b, Out& out) const {
    out.noalias() = (a * sigmaPoints_.covarianceWeights().asDiagonal()).lazyProduct(b.transpose());
  }

  // P_xy ← U = P_xy S⁻ᵀ, i.e. U Sᵀ = P_xy solved a column at a time (columns of U are contiguous).
  // Written out because Eigen's triangular solve with a matrix right-hand side takes its general
  // blocked path (packing, level-3 kernels), which costs more than all the rest of the update here.
  void whitenCrossCovariance() {
    const MeasMatrix& s = innovationFactor_;
    for (int j = 0; j < M; ++j) {
      for (int k = 0; k < j; ++k) crossCovariance_.col(j) -= s(j, k) * crossCovariance_.col(k);
      crossCovariance_.col(j) /= s(j, j);
    }
  }

  SigmaPoints sigmaPoints_;
  // Committed.
  Vector mean_ = Vector::Zero();
  Matrix covariance_ = Matrix::Zero();
  Matrix factor_ = Matrix::Zero();  // S with covariance_ = S Sᵀ
  Points points_ = Points::Zero();  // χᵢ⁺ of the last time update, used by the measurement update
  bool hasPoints_ = false;
  Diagnostics diagnostics_;
  // Workspace: a step computes here and commits only when the whole step succeeded. Zeroed once at
  // construction, so that copying a filter before its first step copies no indeterminate values.
  Points workPoints_ = Points::Zero();                // drawn, then propagated in place
  MeasPoints measuredPoints_ = MeasPoints::Zero();    // Yᵢ = g(χᵢ⁺)
  Points deviations_ = Points::Zero();                // χᵢ⁺ − x̂⁻
  MeasPoints measurementDeviations_ = MeasPoints::Zero();  // Yᵢ − ŷ
  Eigen::Matrix<Scalar, L, M> crossCovariance_ = Eigen::Matrix<Scalar, L, M>::Zero();  // P_xy, then U = P_xy S⁻ᵀ
  MeasMatrix innovationFactor_ = MeasMatrix::Zero();  // S with P_yy = S Sᵀ
  Vector candidateMean_ = Vector::Zero();
  Matrix candidateCovariance_ = Matrix::Zero();
  Diagnostics candidateDiagnostics_;
  CovarianceGuard<Scalar, L> guard_;
};

}  // namespace mjukf::detail
