#pragma once

/// \file
/// What the MJUKF's automatic modes know about the parameters (docs/tuning-mjukf.md): the sensitivity
/// of the state estimate and of the predicted measurement to θ̂ through the dynamics and the filter,
/// the information gathered about θ, and from them T (eqs. 14–15), the least-squares gain of θ, and a
/// per-parameter ξ (eq. 9) fitted to a gain.

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/measurement_gating.hpp"

namespace mjukf {

/// The sensitivities W = ∂x̂/∂θ̂ (n × p) and ψ = ∂ŷ/∂θ̂ (m × p), followed along the run as in a recursive
/// prediction-error method: a time update maps W → A W + B (A = ∂Φ/∂x, B = ∂Φ/∂θ over the interval),
/// a measurement update maps W → W − K ψ (the correction x̂ += K (y − ŷ) pulls the state towards the
/// data, which removes part of its dependence on θ). Both derivatives are forward differences along
/// the direction (W_r, e_r), one extra propagation per parameter.
///
/// Every step writes to candidates; commit*() makes them the state. Fixed sizes, no allocation.
template <class Scalar, int N, int M, int P>
class ParameterSensitivity {
 public:
  /// A state vector x (n).
  using State = Eigen::Matrix<Scalar, N, 1>;
  /// A measurement vector y (m).
  using Meas = Eigen::Matrix<Scalar, M, 1>;
  /// A parameter vector θ (p).
  using Param = Eigen::Matrix<Scalar, P, 1>;
  /// W = ∂x̂/∂θ̂ (n × p), one column per parameter.
  using StateSensitivity = Eigen::Matrix<Scalar, N, P>;
  /// ψ = ∂ŷ/∂θ̂ (m × p), one column per parameter.
  using MeasSensitivity = Eigen::Matrix<Scalar, M, P>;
  /// I (p × p): the information gathered about θ, in units of 1/θ².
  using Information = Eigen::Matrix<Scalar, P, P>;
  /// T of eq. 9 (p × m).
  using Transformation = Eigen::Matrix<Scalar, P, M>;
  /// An m × m matrix: R, or the Cholesky factor S of P_yy.
  using MeasMatrix = Eigen::Matrix<Scalar, M, M>;

  /// Starts from an estimate that does not depend on θ (W = 0) and the prior information
  /// diag(1 / scaleᵣ²): each parameter is known to about its scale. R weighs the measurements in T.
  void start(const Param& scale, const MeasMatrix& measurementNoise) {
    scale_ = scale;
    noiseWeights_ = measurementNoise.diagonal().cwiseSqrt().cwiseInverse();
    state_ = StateSensitivity::Zero();
    measurement_ = MeasSensitivity::Zero();
    information_ = Information::Zero();
    information_.diagonal() = scale.array().square().inverse().matrix();
    priorInformation_ = information_.diagonal();
    openLoopTime_ = sinceCorrection_ = Scalar(0);
    corrections_ = 0;
    largestShare_ = Scalar(0);
    typicalInformation_ = Scalar(0);
    candidateState_ = state_;
    stale_ = false;
  }
  /// Keeps what is known about θ; the new state estimate does not depend on it (W = 0).
  void restartState() {
    state_ = StateSensitivity::Zero();
    candidateState_ = state_;
    openLoopTime_ = Scalar(0);
  }
  /// A new pass over the same record: `restartState`, and the time since the last correction and the
  /// reuse of ψ start again as at `start` (the record's time restarts; no time passed since the last
  /// pass's last update). The information, its prior and the easing's history are kept.
  void restartPass() {
    restartState();
    sinceCorrection_ = Scalar(0);
    stale_ = false;
  }

  /// The forward-difference step δ along (Wᵣ, eᵣ) about θ, for an output of size `output` (max norm):
  /// the step that makes the output move by √ε of its size, δ = √ε ‖output‖ / ‖Wᵣ‖ (W ≈ the derivative
  /// being taken), so that the rounding of the difference, ε ‖output‖ / δ, stays √ε relative to the
  /// derivative; kept between √ε and 1 times max(|θᵣ|, its scale). In double that is 1.5e-8 relative at
  /// least; in float (√ε = 3.5e-4) the upper end matters: the tank's one-interval sensitivity
  /// (3e-4 cm per unit of k_flow) against levels of 5 cm asks for δ ≈ 6, capped at |θ|. The models this
  /// filter is meant for are linear in θ, so a large δ costs little truncation.
  Scalar step(const Param& theta, int r, Scalar output) const {
    const Scalar root = std::sqrt(std::numeric_limits<Scalar>::epsilon());
    const Scalar base = std::max(std::abs(theta(r)), scale_(r));
    const Scalar derivative = candidateState_.col(r).cwiseAbs().maxCoeff();
    const Scalar wanted = derivative > Scalar(0) ? output / derivative : Scalar(0);
    return root * std::max(base, std::min(wanted, base / root));
  }

  /// Time update over `interval` (after `openLoopTime()` of open-loop propagation since the last one):
  /// from x₀ = x̂ with parameters θ₀ propagated to x₀⁺, `propagate(x, θ)` the same propagation. W⁻ is
  /// W + (total / interval)(D − W) with D = A W + B measured over this interval alone: the change over
  /// the open-loop steps is extrapolated from it, which is first-order right when the interval between
  /// measurements is short against the dynamics. A non-finite D leaves W as it is.
  template <class Propagate>
  void predict(const State& x0, const Param& theta0, const State& x0Propagated, Scalar interval,
               Propagate&& propagate) {
    candidateState_ = state_;
    const Scalar extrapolation = (openLoopTime_ + interval) / interval;
    const Scalar output = x0Propagated.cwiseAbs().maxCoeff();
    for (int r = 0; r < P; ++r) {
      const Scalar delta = step(theta0, r, output);
      Param theta = theta0;
      theta(r) += delta;
      const State perturbed = propagate(State(x0 + delta * state_.col(r)), theta);
      const State d = (perturbed - x0Propagated) / delta;  // A Wᵣ + Bᵣ
      derivative_.col(r) = detail::allFinite(d) ? d : state_.col(r);
      if (detail::allFinite(d)) candidateState_.col(r) = state_.col(r) + extrapolation * (d - state_.col(r));
    }
    candidateInterval_ = interval;
    candidateStale_ = false;
    extrapolation_ = extrapolation;
  }
  /// A time update without a refresh: W and ψ stay as they are (the next measurement update reuses ψ);
  /// the interval counts towards the next refresh's extrapolation.
  void keepPrediction(Scalar interval) {
    candidateState_ = state_;
    candidateInterval_ = interval;
    candidateStale_ = true;
  }
  /// Accepts the last `predict` or `keepPrediction`: W ← W⁻, and its interval counts as time since
  /// the last correction (and, after `keepPrediction`, as open-loop time).
  void commitPrediction() {
    state_ = candidateState_;
    sinceCorrection_ += candidateInterval_;
    openLoopTime_ = candidateStale_ ? openLoopTime_ + candidateInterval_ : Scalar(0);
    stale_ = candidateStale_;
  }
  /// Counts an open-loop propagation over `interval` (W unchanged) towards the next refresh's
  /// extrapolation and the time since the last correction.
  void commitOpenLoop(Scalar interval) {
    openLoopTime_ += interval;
    sinceCorrection_ += interval;
  }

  /// Measurement update about the prior (x̂⁻, θ̂), with g the model's measurement and `nominal` =
  /// g(x̂⁻, θ̂): ψ by forward differences of g along (W⁻ᵣ, eᵣ), zero on missing components;
  /// W ← W⁻ − K ψ; the information I ← λ I + (1 − λ) I₀ + ψᵀ P_yy⁻¹ ψ (the prior I₀ is never
  /// forgotten) with the forgetting λ = max(exp(−Δt / memory), exp(−1 / minimumUpdates)), Δt the time
  /// since the last correction (a memory of `memory` time units, and of at least `minimumUpdates`
  /// updates however long the interval); and the weight w of this update's step (`weight()`), eased in
  /// over the first `easing` (a share) of the memory.
  /// `innovationFactor` is the lower Cholesky factor S of P_yy and `whitenedCross` is U = P_xy S⁻ᵀ, so
  /// that K ψ = U (S⁻¹ ψ) (detail/unscented_engine.hpp). Returns false (candidates unspecified) when a
  /// result is not finite.
  template <class Measure, class WhitenedCross>
  bool correct(const State& priorMean, const Param& theta, const Meas& nominal, Measure&& measure,
               const WhitenedCross& whitenedCross, const MeasMatrix& innovationFactor, Scalar memory,
               Scalar minimumUpdates, Scalar easing, const MeasurementMask<M>* present) {
    candidateState_ = state_;
    if (stale_) {
      candidateMeasurement_ = measurement_;
    } else {
      const Scalar output = nominal.cwiseAbs().maxCoeff();
      for (int r = 0; r < P; ++r) {
        const Scalar delta = step(theta, r, output);
        Param perturbed = theta;
        perturbed(r) += delta;
        candidateMeasurement_.col(r) = (measure(State(priorMean + delta * state_.col(r)), perturbed) - nominal) / delta;
      }
    }
    // A missing component has a zero column in U and a unit row and column in S: its ψ does not reach
    // W, so zeroing it first changes nothing there.
    if (present)
      for (int j = 0; j < M; ++j)
        if (!(*present)(j)) candidateMeasurement_.row(j).setZero();
    whitened_ = candidateMeasurement_;
    detail::solveLowerInPlace(innovationFactor, whitened_);               // S⁻¹ ψ
    if (!stale_) candidateState_.noalias() -= whitenedCross * whitened_;  // W − K ψ = W − U S⁻¹ ψ
    if (sinceCorrection_ != forgettingInterval_ || memory != forgettingMemory_ ||
        minimumUpdates != forgettingUpdates_) {  // exp once per schedule
      forgettingInterval_ = sinceCorrection_;
      forgettingMemory_ = memory;
      forgettingUpdates_ = minimumUpdates;
      forgetting_ = std::max(std::exp(-sinceCorrection_ / memory), std::exp(Scalar(-1) / minimumUpdates));
      memoryUpdates_ =
          forgetting_ < Scalar(1) ? Scalar(-1) / std::log(forgetting_) : std::numeric_limits<Scalar>::infinity();
    }
    weight_ = std::min(Scalar(1), Scalar(corrections_ + 1) / (easing * memoryUpdates_));
    if (!(weight_ > Scalar(0))) weight_ = Scalar(1);  // an infinite memory: no easing
    rampComplete_ = weight_ >= Scalar(1);
    // The share of P_yy that is the sensor's noise, tr(R P_yy⁻¹) / m = |S⁻¹ √R|²_F / m: small while the
    // state estimate is uncertain, at its steady level once it has settled. Against the largest share
    // seen so far, it eases the steps in for as long as the state takes to settle, in any time unit.
    noiseShare_ = MeasMatrix(noiseWeights_.cwiseInverse().asDiagonal());
    detail::solveLowerInPlace(innovationFactor, noiseShare_);
    const Scalar share = noiseShare_.squaredNorm() / Scalar(M);
    candidateLargestShare_ = std::max(largestShare_, share);
    if (candidateLargestShare_ > Scalar(0) && std::isfinite(share))
      weight_ = std::min(weight_, share / candidateLargestShare_);
    // The memory forgets the data, never the prior: I = I₀ + Σ λ^(k−j) Jⱼ. Forgetting I₀ too would let
    // the information about a direction the data do not excite decay to zero, and the gain I⁻¹ ψᵀ P_yy⁻¹
    // grow without bound in it (the wind-up of recursive least squares with forgetting), the solve with
    // I amplifying rounding on its way there.
    //
    // And it forgets in proportion to what arrives: an update forgets λʳ with r = min(1, j / j̄), j the
    // information this update brings (in units of the prior, Σ scaleᵣ² Jᵣᵣ) and j̄ its running level.
    // Through a stretch that does not excite θ (a heater off, a motor at rest) r ≈ 0: I is kept and θ̂
    // stays where the data left it, instead of forgetting everything in a memory's time and
    // wandering on noise with the prior's gain. The memory is thus counted in updates' worth of typical
    // information, not in time; j̄ follows j at the same rate r (a lasting drop of excitation still
    // lowers it, slowly). For the first two memories it forgets by time alone (kSettling).
    // Measured on the gallery's heated block (50 seeds): diverged runs 6 → 0, mean NEES of θ̂ 35 → 0.8.
    const Scalar arriving = (whitened_.colwise().squaredNorm().transpose().array() * scale_.array().square()).sum();
    const Scalar ratio = typicalInformation_ > Scalar(0) && Scalar(corrections_) > kSettling * memoryUpdates_
                             ? std::min(Scalar(1), arriving / typicalInformation_)
                             : Scalar(1);
    const Scalar forgettingNow = ratio < Scalar(1) ? std::pow(forgetting_, ratio) : forgetting_;  // λʳ
    candidateTypicalInformation_ =
        typicalInformation_ + (Scalar(1) - forgetting_) * ratio * (arriving - typicalInformation_);
    candidateInformation_ = forgettingNow * information_;
    candidateInformation_.diagonal() += (Scalar(1) - forgettingNow) * priorInformation_;
    candidateInformation_.noalias() += whitened_.transpose() * whitened_;
    return detail::allFinite(candidateMeasurement_) && detail::allFinite(candidateState_) &&
           detail::allFinite(candidateInformation_);
  }
  /// Accepts the last `correct`: W, ψ (unless reused) and I become the candidates'; the time since
  /// the last correction restarts at zero.
  void commitCorrection() {
    state_ = candidateState_;
    if (!stale_) measurement_ = candidateMeasurement_;
    information_ = candidateInformation_;
    typicalInformation_ = candidateTypicalInformation_;
    largestShare_ = candidateLargestShare_;
    ++corrections_;
    sinceCorrection_ = Scalar(0);
    if (!stale_) openLoopTime_ = Scalar(0);
  }

  /// Eqs. 14–15 from the candidate ψ: Tᵣⱼ = ψ̃ⱼᵣ / Σⱼ |ψ̃ⱼᵣ| with ψ̃ⱼᵣ = ψⱼᵣ / √Rⱼⱼ, the sensitivity
  /// in units of the measurement's noise. T keeps the sign of ψ, so with it ξ < 0 moves every parameter
  /// towards the data; a row whose parameter moves no measurement is zero (that parameter stays).
  void transformation(Transformation& t) const {
    for (int r = 0; r < P; ++r) {
      for (int j = 0; j < M; ++j) t(r, j) = candidateMeasurement_(j, r) * noiseWeights_(j);
      const Scalar sum = t.row(r).cwiseAbs().sum();
      if (sum > Scalar(0))
        t.row(r) /= sum;
      else
        t.row(r).setZero();
    }
  }

  /// The recursive least-squares gain K = I⁻¹ ψᵀ P_yy⁻¹ (p × m) of the candidate information, with
  /// `innovationFactor` the lower Cholesky factor of P_yy (`ParameterGain::RecursiveLeastSquares`,
  /// docs/tuning-mjukf.md). Zero when I has no Cholesky factor.
  void leastSquaresGain(const MeasMatrix& innovationFactor, Transformation& gain) const {
    MeasSensitivity solved = whitened_;
    detail::solveUpperInPlace(innovationFactor, solved);  // P_yy⁻¹ ψ = S⁻ᵀ (S⁻¹ ψ)
    gain = solved.transpose();
    Information informationFactor;
    if (!detail::choleskyLower(candidateInformation_, informationFactor)) {
      gain.setZero();
      return;
    }
    detail::solveLowerInPlace(informationFactor, gain);
    detail::solveUpperInPlace(informationFactor, gain);
  }

  /// The adaptive ξ (docs/tuning-mjukf.md) from a gain K of θ (p × m, θ̂ += K ν): ξᵣ the least-squares
  /// fit of −ξᵣ Tᵣ to the row w Kᵣ, w the easing's weight, so that eq. 9 with T moves θᵣ as w K would, as
  /// far as T's row allows. ξᵣ = 0 for a zero row of T.
  void scaling(const Transformation& t, const Transformation& gain, Param& xi) const {
    for (int r = 0; r < P; ++r) {
      const Scalar norm = t.row(r).squaredNorm();
      xi(r) = norm > Scalar(0) ? -weight_ * gain.row(r).dot(t.row(r)) / norm : Scalar(0);
    }
  }

  /// The weight w of the step of the measurement update in progress: the smaller of
  /// (k + 1) / (easing · memory in updates) for the k-th update since the start and the share of P_yy that is
  /// sensor noise against the largest share seen, at most 1. While the state estimate settles from its
  /// first guess the innovations are mostly its error, not the parameters'; easing the steps in keeps
  /// that error from moving θ̂ early (docs/tuning-mjukf.md). The information is not weighed: it only says
  /// how much is known, and a weight on it would cancel in the step once the data outweigh the prior.
  Scalar weight() const { return weight_; }
  /// Whether the update in progress is past the easing's first ramp, (k + 1) / (easing · memory) ≥ 1.
  bool rampComplete() const { return rampComplete_; }
  /// λ of the memory for the update in progress, max(exp(−Δt / memory), exp(−1 / minimumUpdates)).
  Scalar forgetting() const { return forgetting_; }
  /// The memory in measurement updates, −1 / ln λ (infinite for λ = 1).
  Scalar memoryUpdates() const { return memoryUpdates_; }

  /// ψ of the measurement update in progress (after `correct`, before `commitCorrection`).
  const MeasSensitivity& candidateMeasurementSensitivity() const { return candidateMeasurement_; }
  /// W of the step in progress (after `predict` or `correct`, before its commit).
  const StateSensitivity& candidateStateSensitivity() const { return candidateState_; }
  /// D = A W + B of the last `predict`, over its interval alone (a column whose difference was not
  /// finite: W's).
  const StateSensitivity& derivative() const { return derivative_; }
  /// The factor of the last `predict`'s extrapolation, (open-loop time + interval) / interval: W⁻ =
  /// W + factor · (D − W).
  Scalar extrapolation() const { return extrapolation_; }

  /// W = ∂x̂/∂θ̂ of the last committed update.
  const StateSensitivity& stateSensitivity() const { return state_; }
  /// ψ = ∂ŷ/∂θ̂ of the last measurement update.
  const MeasSensitivity& measurementSensitivity() const { return measurement_; }
  /// I, the information about θ after the last measurement update (the prior diag(1 / scaleᵣ²) before one).
  const Information& information() const { return information_; }

 private:
  Param scale_ = Param::Ones();
  StateSensitivity state_ = StateSensitivity::Zero();      // W
  MeasSensitivity measurement_ = MeasSensitivity::Zero();  // ψ
  Information information_ = Information::Identity();      // I
  Param priorInformation_ = Param::Ones();                 // the diagonal of I₀ = diag(1 / scaleᵣ²)
  Scalar openLoopTime_ = 0;                                // open-loop propagation since W was last predicted
  Scalar sinceCorrection_ = 0;                             // model time since the last measurement update
  // Candidates and workspace.
  StateSensitivity candidateState_ = StateSensitivity::Zero();
  MeasSensitivity candidateMeasurement_ = MeasSensitivity::Zero();
  Information candidateInformation_ = Information::Identity();
  StateSensitivity derivative_ = StateSensitivity::Zero();  // D of the last predict
  Scalar extrapolation_ = 1;                                // and its extrapolation factor
  Scalar candidateInterval_ = 0;
  bool stale_ = false;  // the last time update did not refresh W: reuse ψ
  bool candidateStale_ = false;
  Meas noiseWeights_ = Meas::Ones();  // 1 / √Rⱼⱼ
  // λ of the last interval, and the memory in updates it makes, −1 / ln λ.
  Scalar forgettingInterval_ = -1, forgettingMemory_ = -1, forgettingUpdates_ = -1, forgetting_ = 1;
  Scalar memoryUpdates_ = std::numeric_limits<Scalar>::infinity();
  bool rampComplete_ = true;                                         // the update in progress is past the first ramp
  Scalar weight_ = 1;                                                // w of the update in progress
  Scalar largestShare_ = 0, candidateLargestShare_ = 0;              // the largest tr(R P_yy⁻¹) / m seen
  Scalar typicalInformation_ = 0, candidateTypicalInformation_ = 0;  // j̄, the running level of j
  // Forgetting by time alone for the first kSettling memories: what the updates bring while the state
  // and θ̂ settle from the first guess is computed about a wrong θ̂ and must not be kept.
  static constexpr Scalar kSettling = Scalar(2);
  MeasMatrix noiseShare_ = MeasMatrix::Zero();  // S⁻¹ √R
  long corrections_ = 0;                        // measurement updates since the start
  // Workspace, zeroed once so that copying an object (a filter is built from a copy of its policy)
  // copies no indeterminate values.
  MeasSensitivity whitened_ = MeasSensitivity::Zero();
};

}  // namespace mjukf
