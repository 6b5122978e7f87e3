#pragma once

/// \file
/// The MJUKF's covariance of θ̂ (docs/algorithms.md §5.1; not in the paper): the first-order covariance
/// of the joint error (η, e), e = θ̂ − θ and η = x̂ − x − W e the state's error that the parameters' does not
/// explain (W = ∂x̂/∂θ̂, parameter_sensitivity.hpp), carried through the filter's own steps: its gain
/// K, its parameter gain G = diag(ξ) T, and the dynamics linearised from its sigma points.

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/linear_algebra.hpp"

namespace mjukf::detail {

/// `ByBlocks`: from the size where a product into one triangle is faster than the full product (the
/// covariance kernel's measured border, linear_algebra.hpp), the joint covariance is propagated by blocks
/// and by its lower triangle, mirrored (exactly symmetric); below it, as two full products and an average
/// with the transpose, which keeps the paper's and the gallery's plants (n + p ≤ 8) to the bit. A
/// parameter only so that a test can run both forms at one size.
template <class Scalar, int N, int M, int P,
          bool ByBlocks = atLeast<N + P>(generalKernelsFrom<Scalar>.covarianceTriangle)>
class ParameterErrorCovariance {
 public:
  using Joint = Eigen::Matrix<Scalar, N + P, N + P>;
  using StateMatrix = Eigen::Matrix<Scalar, N, N>;
  using ParamMatrix = Eigen::Matrix<Scalar, P, P>;
  using MeasMatrix = Eigen::Matrix<Scalar, M, M>;
  using StateByParam = Eigen::Matrix<Scalar, N, P>;
  using StateByMeas = Eigen::Matrix<Scalar, N, M>;
  using MeasByState = Eigen::Matrix<Scalar, M, N>;
  using MeasByParam = Eigen::Matrix<Scalar, M, P>;
  using ParamByMeas = Eigen::Matrix<Scalar, P, M>;
  using Points = Eigen::Matrix<Scalar, N, 2 * N + 1>;
  using ParamPoints = Eigen::Matrix<Scalar, P, 2 * N + 1>;

  /// Independent errors: cov(η) = the state's P₀, cov(e) = the parameters' prior.
  void start(const StateMatrix& stateCovariance, const ParamMatrix& parameterCovariance) {
    joint_.setZero();
    joint_.template topLeftCorner<N, N>() = stateCovariance;
    joint_.template bottomRightCorner<P, P>() = parameterCovariance;
    candidate_ = joint_;
    effect_.setZero();
  }
  /// A new state estimate that does not depend on θ̂ (W = 0): cov(η) = its covariance, uncorrelated
  /// with e, which is kept.
  void restartState(const StateMatrix& stateCovariance) {
    joint_.template topLeftCorner<N, N>() = stateCovariance;
    joint_.template topRightCorner<N, P>().setZero();
    joint_.template bottomLeftCorner<P, N>().setZero();
    candidate_ = joint_;
  }

  /// The time update: χᵢ⁺ = Φ(χᵢ, θᵢ) from the symmetric points χ₀ = x̂, χⱼ = x̂ + γ Lⱼ, χⱼ₊ₙ = x̂ − γ Lⱼ.
  /// Their half differences are Δⱼ = (χⱼ⁺ − χⱼ₊ₙ⁺) / 2 = A γLⱼ + B ϑⱼ, ϑⱼ = (θⱼ − θⱼ₊ₙ) / 2, so A (the
  /// dynamics' Jacobian) follows from them once B = ∂Φ/∂θ is known. `derivative` is D = A W + B over this
  /// interval when the sensitivities were refreshed (then A (γL − W ϑ) = Δ − D ϑ), null otherwise (B as
  /// at the last refresh). `predictedSensitivity` is W⁻. Then η⁻ = A η + (A W + B − W⁻) e − w, e unchanged.
  /// After open-loop propagations since the last time update, the sensitivities extrapolate W over them
  /// from this interval's D by `extrapolation` = (open-loop time + interval) / interval; A and B are
  /// extrapolated alike, I + x (A − I) and x B, so that W⁻ stays their image of W.
  /// A random walk of θ by w_θ ~ N(0, `parameterProcessNoise`) at the end of the interval moves e by −w_θ
  /// and η = x̂ − x − W⁻ e by W⁻ w_θ: J gains [W⁻; −I] Q_θ [W⁻; −I]ᵀ (none, to the bit, for Q_θ = 0).
  /// Returns false when A is not finite (the points collapsed); then the prediction is η⁻ = η − w.
  bool predict(const Points& prior, const Points& propagated, const ParamPoints& parameterPoints,
               const StateByParam& sensitivity, const StateByParam* derivative,
               const StateByParam& predictedSensitivity, const StateMatrix& processNoise,
               const ParamMatrix& parameterProcessNoise, Scalar extrapolation) {
    for (int j = 0; j < N; ++j) {
      spread_.col(j) = (prior.col(1 + j) - prior.col(1 + N + j)) * Scalar(0.5);
      change_.col(j) = (propagated.col(1 + j) - propagated.col(1 + N + j)) * Scalar(0.5);
      parameterSpread_.col(j) = (parameterPoints.col(1 + j) - parameterPoints.col(1 + N + j)) * Scalar(0.5);
    }
    // Points drawn from a lower factor (every filter's) have half differences γL, lower triangular; from
    // n + p = 20 (double; 28 in float) and p ≤ n/2, A then needs no n × n LU (below, the code is the paper's
    // plants' and the gallery's, to the bit). Woodbury's form loses accuracy as γL nears singularity even
    // where γL − W ϑ does not: such a γL, or a result that is not finite, takes the LU.
    bool byTriangle = false;
    if constexpr (ByBlocks && 2 * P <= N) byTriangle = isLowerTriangular(spread_) && wellConditionedDiagonal(spread_);
    if (derivative) {
      change_.noalias() -= *derivative * parameterSpread_;
    } else {
      change_.noalias() -= effect_ * parameterSpread_;
    }
    if (byTriangle) {
      jacobianByTriangle(change_, spread_, derivative ? &sensitivity : nullptr, parameterSpread_, jacobian_);
      byTriangle = allFinite(jacobian_);
    }
    if (!byTriangle) {  // A = change · spread⁻¹, i.e. spreadᵀ Aᵀ = changeᵀ
      if (derivative) spread_.noalias() -= sensitivity * parameterSpread_;
      StateMatrix transposed = change_.transpose();
      luSolveInPlace(partialPivotLu(spread_.transpose()), transposed);
      jacobian_ = transposed.transpose();
    }
    const bool found = allFinite(jacobian_);
    if (!found) jacobian_.setIdentity();
    if (derivative && found) effect_ = *derivative - jacobian_ * sensitivity;  // B
    // Over the open-loop time too: A ← I + x (A − I), B ← x B.
    jacobian_ = StateMatrix::Identity() + extrapolation * (jacobian_ - StateMatrix::Identity());
    transition_.setIdentity();
    transition_.template topLeftCorner<N, N>() = jacobian_;
    StateByParam drift = extrapolation * effect_ - predictedSensitivity;
    drift.noalias() += jacobian_ * sensitivity;
    transition_.template topRightCorner<N, P>() = drift;
    if constexpr (ByBlocks) {
      // Z = [[A, C], [0, I]]: (Z J Zᵀ)_ηη = [A C] J [A C]ᵀ by one triangle, (Z J Zᵀ)_eη = (([A C] J)_·e)ᵀ
      // and J_ee unchanged (e's rows are not multiplied through); the lower triangle is mirrored once Q and
      // the walk are in.
      const auto stateRows = transition_.template topRows<N>();
      spreadJoint_.template topRows<N>().noalias() = stateRows * joint_;
      candidate_.template topLeftCorner<N, N>().template triangularView<Eigen::Lower>() =
          spreadJoint_.template topRows<N>() * stateRows.transpose();
      candidate_.template bottomLeftCorner<P, N>() = spreadJoint_.template topRightCorner<N, P>().transpose();
      candidate_.template bottomRightCorner<P, P>() = joint_.template bottomRightCorner<P, P>();
    } else {
      spreadJoint_.noalias() = product(transition_, joint_);
      candidate_.noalias() = product(spreadJoint_, transition_.transpose());
    }
    candidate_.template topLeftCorner<N, N>() += processNoise;
    if (!parameterProcessNoise.isZero(Scalar(0))) {
      const StateByParam walk = predictedSensitivity * parameterProcessNoise;  // W⁻ Q_θ
      candidate_.template topLeftCorner<N, N>().noalias() += walk * predictedSensitivity.transpose();
      candidate_.template topRightCorner<N, P>() -= walk;
      candidate_.template bottomLeftCorner<P, N>() -= walk.transpose();
      candidate_.template bottomRightCorner<P, P>() += parameterProcessNoise;
    }
    if constexpr (ByBlocks) mirrorLowerTriangle(candidate_);  // Q and the walk included
    return found;
  }

  /// Whether a triangular T's diagonal, which bounds its condition number from below, is within √ε of
  /// its largest entry in size: otherwise Woodbury's form would lose what the LU keeps.
  static bool wellConditionedDiagonal(const StateMatrix& triangle) {
    const auto size = triangle.diagonal().cwiseAbs();
    return size.minCoeff() >= std::sqrt(std::numeric_limits<Scalar>::epsilon()) * size.maxCoeff();
  }

  /// A with A (T − W ϑ) = `change` for a lower-triangular T (`triangle`), W = `sensitivity` (null: W ϑ
  /// absent) and ϑ = `parameterSpread`, into `jacobian`: X = change T⁻¹ by substitution, and then by
  /// Woodbury's identity (T − W ϑ)⁻¹ = T⁻¹ + T⁻¹ W C⁻¹ ϑ T⁻¹ with C = I − ϑ T⁻¹ W (p × p),
  /// A = X + (X W) C⁻¹ (ϑ T⁻¹): about n³/2 multiply-adds and O(n² p), where the LU of T − W ϑ and its
  /// solve for n right-hand sides take 4n³/3. Not finite when T or C is singular (predict() then takes
  /// the LU of T − W ϑ, which may be regular).
  static void jacobianByTriangle(const StateMatrix& change, const StateMatrix& triangle,
                                 const StateByParam* sensitivity, const Eigen::Matrix<Scalar, P, N>& parameterSpread,
                                 StateMatrix& jacobian) {
    jacobian = change;
    rightSolveLowerInPlace(triangle, jacobian);  // X = change T⁻¹
    if (!sensitivity) return;
    StateByParam whitened = *sensitivity;
    solveLowerInPlace(triangle, whitened);  // T⁻¹ W
    ParamMatrix c = ParamMatrix::Identity();
    c.noalias() -= parameterSpread * whitened;  // C = I − ϑ T⁻¹ W
    Eigen::Matrix<Scalar, P, N> spreadRight = parameterSpread;
    rightSolveLowerInPlace(triangle, spreadRight);  // ϑ T⁻¹
    // G = X W C⁻¹ from Cᵀ Gᵀ = (X W)ᵀ.
    Eigen::Matrix<Scalar, P, N> g = (jacobian * *sensitivity).transpose();
    luSolveInPlace(partialPivotLu(c.transpose()), g);
    jacobian.noalias() += g.transpose() * spreadRight;
  }

  /// The Kalman gain of θ for the measurement update in progress (docs/algorithms.md §5.3): about the
  /// committed prediction J⁻, with P_θ widened by `widening` when not null (a detected change, §5.4),
  /// ν = −H η⁻ − ψ e + v has covariance S = [H ψ] J⁻ [H ψ]ᵀ + R, and θ − θ̂ = −e has covariance
  /// J_eη Hᵀ + P_θ ψᵀ with it, so K_θ = (J_eη Hᵀ + P_θ ψᵀ) S⁻¹. The rows of H and ψ of missing components
  /// are zero; `present` gives S a unit row and column there, which zeroes K_θ's column. K_θ into `gain`,
  /// S's lower Cholesky factor into `innovationFactor`; false (both unspecified) when S is not positive
  /// definite or K_θ not finite.
  template <class Mask>
  bool parameterGain(const MeasByState& jacobian, const MeasByParam& sensitivity, const MeasMatrix& measurementNoise,
                     const Mask* present, const ParamMatrix* widening, ParamByMeas& gain,
                     MeasMatrix& innovationFactor) {
    const Joint& prior = priorWidenedBy(widening);
    measured_.template leftCols<N>() = jacobian;
    measured_.template rightCols<P>() = sensitivity;
    measuredSpread_.noalias() = product(measured_, prior);  // [H ψ] J⁻
    MeasMatrix innovation = measurementNoise;
    innovation.noalias() += product(measuredSpread_, measured_.transpose());
    if (present)
      for (int j = 0; j < M; ++j)
        if (!(*present)(j)) {
          innovation.row(j).setZero();
          innovation.col(j).setZero();
          innovation(j, j) = Scalar(1);
        }
    symmetrize(innovation);
    if (!allFinite(innovation) || !choleskyLower(innovation, innovationFactor)) return false;
    // K_θᵀ = S⁻¹ (J⁻_e· [H ψ]ᵀ), the last p columns of ([H ψ] J⁻)ᵀ: J⁻ is symmetric.
    Eigen::Matrix<Scalar, M, P> solved = measuredSpread_.template rightCols<P>();
    solveLowerInPlace(innovationFactor, solved);
    solveUpperInPlace(innovationFactor, solved);
    gain = solved.transpose();
    return allFinite(gain);
  }

  /// The measurement update: ν = −H η⁻ − ψ e + v; the filter's state moves by K ν and θ̂ by −G ν, and W
  /// becomes `correctedSensitivity` (W⁺); about J⁻ with P_θ widened by `widening` when not null. Then
  ///   e⁺ = (I + G ψ) e + G H η⁻ − G v,
  ///   η⁺ = (I − K H − W⁺ G H) η⁻ − W⁺ G ψ e + (K + W⁺ G) v.
  /// Columns of missing components are zero in H's rows, K and G. Returns false when the result is not
  /// finite.
  bool correct(const MeasByState& jacobian, const StateByMeas& gain, const ParamByMeas& parameterGain,
               const MeasByParam& sensitivity, const StateByParam& correctedSensitivity,
               const MeasMatrix& measurementNoise, const ParamMatrix* widening) {
    // The error's map Z = [[I − K H − W⁺ G H, −W⁺ G ψ], [G H, I + G ψ]] and its noise V = [K + W⁺ G; −G].
    const Eigen::Matrix<Scalar, P, N> parameterFromState = parameterGain * jacobian;  // G H
    const ParamMatrix parameterFromParameter = parameterGain * sensitivity;           // G ψ
    transition_.setIdentity();
    transition_.template topLeftCorner<N, N>().noalias() -= gain * jacobian;
    transition_.template topLeftCorner<N, N>().noalias() -= correctedSensitivity * parameterFromState;
    transition_.template topRightCorner<N, P>().noalias() = -correctedSensitivity * parameterFromParameter;
    transition_.template bottomLeftCorner<P, N>() = parameterFromState;
    transition_.template bottomRightCorner<P, P>() += parameterFromParameter;
    noiseMap_.template topRows<N>() = gain;
    noiseMap_.template topRows<N>().noalias() += correctedSensitivity * parameterGain;
    noiseMap_.template bottomRows<P>() = -parameterGain;
    spreadJoint_.noalias() = product(transition_, priorWidenedBy(widening));  // the committed prediction
    noiseSpread_.noalias() = noiseMap_ * measurementNoise;
    if constexpr (ByBlocks) {  // one triangle of Z J⁻ Zᵀ + V R Vᵀ, mirrored
      candidate_.template triangularView<Eigen::Lower>() = spreadJoint_ * transition_.transpose();
      candidate_.template triangularView<Eigen::Lower>() += noiseSpread_ * noiseMap_.transpose();
      mirrorLowerTriangle(candidate_);
    } else {
      candidate_.noalias() = product(spreadJoint_, transition_.transpose());
      candidate_.noalias() += product(noiseSpread_, noiseMap_.transpose());
      spreadJoint_ = candidate_.transpose();  // symmetric as committed
      candidate_ = (candidate_ + spreadJoint_) * Scalar(0.5);
    }
    return allFinite(candidate_);
  }

  /// The covariance of the state's error that the candidate implies (docs/algorithms.md §5.2): the
  /// state's error is η + W e, so cov = J_ηη + W J_eη + J_ηe Wᵀ + W P_θ Wᵀ with J the candidate
  /// cov((η, e)) and W = `sensitivity` (W⁻ after a `predict`). Into `covariance`, exactly symmetric;
  /// false when it is not finite.
  bool stateErrorCovariance(const StateByParam& sensitivity, StateMatrix& covariance) {
    carried_.noalias() = sensitivity * candidate_.template bottomRightCorner<P, P>();  // W P_θ
    carried_ += candidate_.template topRightCorner<N, P>();                            // + J_ηe: cov(x̃, e)
    covariance.noalias() = sensitivity * carried_.transpose();                         // W cov(e, x̃)
    covariance.noalias() += candidate_.template topRightCorner<N, P>() * sensitivity.transpose();  // J_ηe Wᵀ
    covariance += candidate_.template topLeftCorner<N, N>();                                       // + J_ηη
    symmetrize(covariance);
    return allFinite(covariance);
  }

  void commit() { joint_ = candidate_; }

  /// P_θ = cov(e), as committed.
  ParamMatrix parameterCovariance() const { return joint_.template bottomRightCorner<P, P>(); }
  /// cov((η, e)) as committed.
  const Joint& committed() const { return joint_; }

 private:
  // A product with (n + p)-row or -column factors: coefficient by coefficient below the size from which
  // the covariance kernels take their general form (covarianceProduct, linear_algebra.hpp), from it
  // Eigen's choice. Eigen
  // itself takes the coefficient-wise product up to 7 × 7 and compiles its general product from 8 × 8
  // (about 1.4 s of a unit), where the two gave the same bits (1,000 random 8 × 8 products with depth 2, 4
  // and 8, double and float, x86-64 -O2 and -O3, no FMA; Eigen's general product splits its sums on AVX
  // float, AVX-512 and NEON, where the last bits may differ).
  template <class Lhs, class Rhs>
  static auto product(const Lhs& lhs, const Rhs& rhs) {
    if constexpr (atLeast<N + P>(generalKernelsFrom<Scalar>.covarianceProduct))
      return lhs * rhs;
    else
      return lhs.lazyProduct(rhs);
  }

  // J⁻ as committed, or a copy of it with P_θ widened.
  const Joint& priorWidenedBy(const ParamMatrix* widening) {
    if (!widening) return joint_;
    widened_ = joint_;
    widened_.template bottomRightCorner<P, P>() += *widening;
    return widened_;
  }

  Joint joint_ = Joint::Zero();                 // cov((η, e)) as committed
  Joint candidate_ = Joint::Zero();             // after the step in progress
  StateByParam effect_ = StateByParam::Zero();  // B = ∂Φ/∂θ from the last refresh of the sensitivities
  // Workspace.
  StateMatrix spread_ = StateMatrix::Zero(), change_ = StateMatrix::Zero(), jacobian_ = StateMatrix::Zero();
  Eigen::Matrix<Scalar, P, N> parameterSpread_ = Eigen::Matrix<Scalar, P, N>::Zero();
  Joint transition_ = Joint::Zero(), spreadJoint_ = Joint::Zero();
  Eigen::Matrix<Scalar, N + P, M> noiseMap_ = Eigen::Matrix<Scalar, N + P, M>::Zero();
  Eigen::Matrix<Scalar, N + P, M> noiseSpread_ = Eigen::Matrix<Scalar, N + P, M>::Zero();
  StateByParam carried_ = StateByParam::Zero();                                         // cov(x̃, e) = J_ηe + W P_θ
  Joint widened_ = Joint::Zero();                                                       // J⁻ with P_θ widened
  Eigen::Matrix<Scalar, M, N + P> measured_ = Eigen::Matrix<Scalar, M, N + P>::Zero();  // [H ψ]
  Eigen::Matrix<Scalar, M, N + P> measuredSpread_ = Eigen::Matrix<Scalar, M, N + P>::Zero();  // [H ψ] J⁻
};

}  // namespace mjukf::detail
