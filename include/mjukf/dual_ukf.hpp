#pragma once

/// \file
/// The dual UKF: a state filter and a parameter filter side by side (docs/algorithms.md §9).

#include <type_traits>

#include <Eigen/Core>

#include "mjukf/detail/unscented_engine.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/model.hpp"
#include "mjukf/parameter_bounds.hpp"
#include "mjukf/settings_error.hpp"

namespace mjukf {

/// Which parameters the state filter's time update uses; both orderings appear in the literature.
enum class DualUkfOrdering {
  /// θ̂⁻ = θ̂_{k−1}: both filters predict, then both correct with the same measurement (the dual UKF of
  /// Wan and van der Merwe). Per measurement step: 2n + 1 state propagations and 2p + 1 of the mean.
  PriorParameters,
  /// The parameters are corrected first, and the state's time update is run again from x̂_{k−1} with
  /// the corrected θ̂_k before the state is corrected: 2n + 1 more propagations per measurement step.
  UpdatedParameters,
};

/// Settings of `DualUkf` over a model of `StateDim` states, `ParamDim` parameters and `MeasDim`
/// measurements, validated at construction. The shared fields (P₀, Q, R, …) are those of the state
/// filter (x alone), but R is also the parameter filter's (plus `parameterObservationNoise`), `repair`
/// settles both filters' covariances, the gate tests the state filter's update only (a rejection
/// refuses both) and the parameter bounds clamp θ̂; the parameter filter has its own fields below.
/// Templated on the sizes, not the model; `DualUkf<Model>::Settings` or `DualUkfSettingsFor<Model>`
/// name it. Every field: docs/settings.md §2, §3 and §7.
template <class Scalar_, int StateDim, int ParamDim, int MeasDim>
struct DualUkfSettings : ParameterEstimationSettings<Scalar_, StateDim, MeasDim, ParamDim> {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// An n × n matrix, as P₀ and Q of the state filter.
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;
  /// A p × p matrix, as the parameter filter's covariances.
  using ParamMatrix = Eigen::Matrix<Scalar, ParamDim, ParamDim>;
  /// An m × m matrix, as R.
  using MeasMatrix = Eigen::Matrix<Scalar, MeasDim, MeasDim>;
  /// α, β, κ of the parameter filter's sigma points (L = p); not used by the cubature set. α = 0.1 by
  /// default (the state filter's is 1): the parameter filter observes y through the state filter's
  /// prediction at θ̂, extrapolated to each θⱼ to first order by W, and a wide P^θ's points at ±√p σ reach
  /// parameters where the model is unstable or singular (a negative time constant); θ̂ ± 0.1 √p σ stays
  /// near θ̂ (docs/algorithms.md §9).
  SigmaPointParameters<Scalar> parameterSigmaPoints{Scalar(0.1), Scalar(2), Scalar(0)};
  /// P^θ₀, the initial parameter covariance, symmetric positive definite.
  ParamMatrix initialParameterCovariance = ParamMatrix::Zero();
  /// Q_θ of the parameters' random walk, added at every time update, symmetric positive semi-definite.
  ParamMatrix parameterProcessNoise = ParamMatrix::Zero();
  /// Added to the parameter filter's observation noise, which is the state filter's predicted
  /// innovation covariance H P⁻ Hᵀ + R (the state's uncertainty and the sensor's; docs/algorithms.md §9):
  /// any further uncertainty of the observation, e.g. a known model error. Symmetric positive
  /// semi-definite; zero (the default) adds nothing.
  MeasMatrix parameterObservationNoise = MeasMatrix::Zero();
  /// λ ∈ (0, 1] of the parameter time update P^θ⁻ = P^θ / λ + Q_θ; 1 is none (van der Merwe's
  /// forgetting factor is the alternative to Q_θ).
  Scalar parameterForgetting = 1;
  /// Whether the state's time update uses θ̂_{k−1} or the corrected θ̂_k (see DualUkfOrdering).
  DualUkfOrdering ordering = DualUkfOrdering::PriorParameters;
};

/// \cond INTERNAL
namespace detail {

/// The parameter policy of `DualUkf` (docs/algorithms.md §9): a second unscented estimate, of θ, with a
/// random-walk time update, whose sigma points θⱼ are measured through the state filter's prediction
/// from the state the filter would hold had θ been θⱼ all along,
///     Dⱼ = g(Φ_h(x̂_{k−1} + W_G (θⱼ − θ̂); θⱼ), u, θⱼ),   W = ∂x̂/∂θ̂ (the recurrent sensitivity),
/// W_G = W G where the parameters walk (startFromWalk), observed with the state filter's innovation
/// covariance H P⁻ Hᵀ + R. Its measurement update corrects the parameters first, then the state (with
/// the UpdatedParameters ordering, after predicting the state's last step again with the corrected θ̂);
/// the engine commits both or neither.
/// detail/unscented_engine.hpp §3 lists what a policy supplies.
template <class Model, class Integrator, class Settings, class Est>
class DualParameters : public ParameterPolicy<Model, Integrator, Settings, Est> {
  using Base = ParameterPolicy<Model, Integrator, Settings, Est>;

 public:
  using Base::StateDim, Base::ParamDim, Base::MeasDim;
  using typename Base::Scalar, typename Base::State, typename Base::Param, typename Base::Meas, typename Base::Input;
  using typename Base::Vector, typename Base::Points, typename Base::MeasPoints, typename Base::Mask;
  /// The parameter filter: an estimate of θ measured through the m components of y, with the state
  /// filter's sigma-point set and covariance form.
  using ParameterEstimate = Estimate<Scalar, ParamDim, MeasDim, typename Est::PointSetType, typename Est::FormType>;
  static constexpr int ParameterCount = ParameterEstimate::Count;

  /// W = ∂x̂/∂θ̂ (n × p).
  using Sensitivity = Eigen::Matrix<Scalar, StateDim, ParamDim>;

  DualParameters(const Settings& s, const Param& initialParameters)
      : estimate_(Validated{}, s.parameterSigmaPoints, s.parameterProcessNoise,
                  s.measurementNoise + s.parameterObservationNoise),
        boundsActive_(s.parameterBounds.active()),
        storesStep_(s.ordering == DualUkfOrdering::UpdatedParameters),
        walks_(s.parameterForgetting != Scalar(1) || !s.parameterProcessNoise.isZero(Scalar(0))) {
    estimate_.assign(initialParameters, s.initialParameterCovariance);  // checked in validate()
  }

  const ParameterEstimate& estimate() const { return estimate_; }
  const Sensitivity& sensitivity() const { return sensitivity_; }
  // Starts the parameter filter again (both arguments checked by the filter's reset()).
  void reset(const Param& parameters, const Eigen::Matrix<Scalar, ParamDim, ParamDim>& covariance) {
    estimate_.assign(parameters, covariance);
    restartState();
  }
  // A state estimate that does not depend on θ̂: W = 0.
  void restartState() {
    sensitivity_.setZero();
    openLoopTime_ = Scalar(0);
    hasPrior_ = false;
  }

  // The parameter time update, θ̂⁻ = θ̂, P^θ⁻ = P^θ / λ + Q_θ (square-root form: S^θ⁻ from
  // [S^θ / √λ | G_θ] by Householder); what the walk does to the state given θ (startFromWalk); and the
  // propagation of x̂_{k−1} + W_G (θⱼ − θ̂) with each θⱼ of (θ̂⁻, P^θ⁻) over the step, into the candidates;
  // then W⁻ = ∂Φ/∂θ̂ of those propagations.
  template <class Step>
  Status predictParameters(const Step& step, const Est& state) {
    const Settings& s = step.settings;
    ParameterEstimate& pe = estimate_;
    pe.predictRandomWalk(s.parameterForgetting, s.parameterProcessNoise);
    const Status settled = pe.settle(s.repair);
    if (!taken(settled)) return settled;
    if (walks_) {
      if (const Status st = startFromWalk(s, state); st != Status::Ok) return st;
    } else {
      candidateStartSensitivity_ = sensitivity_;
      if (storesStep_) candidatePriorFactor_ = state.factor();
    }
    if (const Status drawn = pe.draw(pe.candidateMean(), pe.candidateFactor()); drawn != Status::Ok) return drawn;
    const Param& center = pe.candidateMean();
    for (int j = 0; j < ParameterCount; ++j) {
      const Param theta = pe.workPoints().col(j);
      candidatePropagatedStates_.col(j) =
          step.propagate(theta, State(state.mean() + candidateStartSensitivity_ * (theta - center)));
    }
    if (!allFinite(candidatePropagatedStates_)) return Status::NonFiniteResult;
    // W⁻ = A W_G + B over this step, by the statistical linear regression of the propagations on the θⱼ;
    // the change over the open-loop steps since the last time update (the mean alone was propagated
    // there) is extrapolated from it, first-order right when they are short against the dynamics.
    regressOnParameters(candidatePropagatedStates_, pe.workPoints(), center, pe.candidateFactor(),
                        candidatePredictedSensitivity_);
    const Scalar extrapolation = (openLoopTime_ + step.interval()) / step.interval();
    candidatePredictedSensitivity_ =
        candidateStartSensitivity_ + extrapolation * (candidatePredictedSensitivity_ - candidateStartSensitivity_);
    if (!allFinite(candidatePredictedSensitivity_)) return Status::NonFiniteResult;
    if (s.ordering == DualUkfOrdering::UpdatedParameters) {
      constexpr bool held = std::is_same_v<typename Step::InputType, HeldInput<Model>>;
      candidatePriorMean_ = state.mean();
      candidateStep_.t = step.t;
      candidateStep_.h = step.h;
      candidateStep_.steps = step.steps;
      candidateStep_.fromSignal = !held;
      if constexpr (held) candidateStep_.held = step.input.value;
    }
    return settled;
  }
  // The lower factor the state's time update draws its points from: P_{k−1}'s, or with a random walk
  // the factor of P_{k−1} + W C Wᵀ (startFromWalk).
  const typename Est::Matrix& priorFactor(const Est& state) const {
    return walks_ ? candidatePriorFactor_ : state.factor();
  }
  // χᵢ⁺ = Φ_h(χᵢ; t, θ̂)
  template <class Step>
  void propagatePoints(const Step& step, Points& points) {
    const Param& theta = stateFilterParameters();
    for (int i = 0; i < Base::Count; ++i) points.col(i) = step.propagate(theta, points.col(i));
  }
  static constexpr bool raisesPriorCovariance = false;
  const typename Est::Matrix* priorCovarianceFloor() const { return nullptr; }  // Q alone
  template <class Step>
  Vector propagateMean(const Step& step, const Vector& mean) {
    return step.propagate(estimate_.mean(), mean);
  }
  // Yᵢ = g(χᵢ⁺, u, θ̂)
  void measurePoints(const Model& model, const Input& u, const Points& points, MeasPoints& measured) {
    const Param& theta = stateFilterParameters();
    for (int i = 0; i < Base::Count; ++i) measured.col(i) = measureModel(model, points.col(i), u, theta);
  }

  // The parameters first, into their candidates, then the state; the engine's correctAndCommit commits
  // both (commitCorrection) or neither.
  template <class Engine>
  Status update(Engine& engine, const Meas& y, const Input& u, const Mask* present) {
    const Status parameters = correctParameterFilter(engine, y, u, present);
    if (!taken(parameters)) return parameters;
    correcting_ = true;
    Status state;
    if (engine.settings().ordering == DualUkfOrdering::UpdatedParameters && hasPrior_) {
      useCorrectedParameters_ = true;
      state = predictStateAgain(engine);
      if (taken(state)) {
        auto& est = engine.estimate_;
        if (engine.settings().redrawPointsForUpdate) est.draw(repredictedMean_, est.candidateFactor());
        // The points of the prediction again (or drawn from it), and its factor: the square-root form's
        // correction reads it before it writes its own candidate factor.
        const typename Est::Prior prior{repredictedMean_, repredictedCovariance_, est.candidateFactor(),
                                        est.workPointsPrior()};
        const Status corrected = engine.correctAndCommit(est.workPoints(), prior, y, u, present);
        state = taken(corrected) ? combineTaken(corrected, state) : corrected;
      }
      useCorrectedParameters_ = false;
    } else {
      state = engine.correctState(y, u, present);
    }
    correcting_ = false;
    return taken(state) ? combineTaken(state, parameters) : state;
  }
  // After the state's correction x̂ = x̂⁻ + K (y − ŷ): W = W⁻ − K ψ, ψ = ∂ŷ/∂θ̂ (K = U S⁻¹).
  Status correctParameters(const typename Base::CorrectionOf& c) {
    whitenedSensitivity_ = measurementSensitivity_;
    solveLowerInPlace(c.innovationFactor, whitenedSensitivity_);
    candidateSensitivity_ = priorSensitivity();
    candidateSensitivity_.noalias() -= c.gainFactor * whitenedSensitivity_;
    return allFinite(candidateSensitivity_) ? Status::Ok : Status::NonFiniteResult;
  }
  // x̂ is the state's estimate given θ̂ (its mean conditional on θ̂, which moves with θ̂ by W): a
  // correction that moved θ̂ by Δ moves x̂ by W Δ, so that x̂ stays the estimate given the θ̂ it is
  // committed with (the UpdatedParameters ordering moves x̂_{k−1} before predicting again instead).
  bool constrainMean(Vector& mean) {
    if (!correcting_ || useCorrectedParameters_) return false;
    mean.noalias() += candidateSensitivity_ * (estimate_.candidateMean() - estimate_.mean());
    return true;
  }

  void commitPrediction() {
    estimate_.commitPrediction();
    predictedSensitivity_ = candidatePredictedSensitivity_;
    openLoopTime_ = Scalar(0);
    propagatedStates_ = candidatePropagatedStates_;
    if (storesStep_) {
      priorMean_ = candidatePriorMean_;
      priorFactor_ = candidatePriorFactor_;
      startSensitivity_ = candidateStartSensitivity_;
      step_ = candidateStep_;
      hasPrior_ = true;
    }
  }
  void commitCorrection() {
    estimate_.commitCorrection();
    sensitivity_ = candidateSensitivity_;
    hasPrior_ = false;
  }
  void commitOpenLoop(Scalar interval) {
    estimate_.commitMean(estimate_.mean());  // its θⱼ were propagated from an x̂ that moved on
    openLoopTime_ += interval;
    hasPrior_ = false;
  }

 private:
  using PropagatedStates = Eigen::Matrix<Scalar, StateDim, ParameterCount>;
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;

  // The time step a measurement update of the UpdatedParameters ordering runs again.
  struct StoredStep {
    Scalar t = 0, h = 0;
    int steps = 0;
    bool fromSignal = false;  // the model's u(t), or `held`
    Input held = Input::Zero();
  };

  // The parameters the state filter runs with: θ̂⁻, or θ̂_k while the UpdatedParameters ordering
  // predicts and corrects the state again.
  const Param& stateFilterParameters() const {
    return useCorrectedParameters_ ? estimate_.candidateMean() : estimate_.mean();
  }

  // W⁻ of the last time update, or W when the parameter filter's points were not propagated since.
  const Sensitivity& priorSensitivity() const { return estimate_.hasPoints() ? predictedSensitivity_ : sensitivity_; }

  // ∂z/∂θ (rows × p) by the statistical linear regression of the images zⱼ of the θⱼ of (center, S Sᵀ):
  // Σ Wcⱼ (zⱼ − z̄)(θⱼ − center)ᵀ P⁻¹, exact for z linear in θ.
  template <class Images, class Out>
  void regressOnParameters(const Images& images, const typename ParameterEstimate::Points& thetas, const Param& center,
                           const typename ParameterEstimate::Matrix& lowerFactor, Out& out) {
    const auto& set = estimate_.sigmaPoints();
    Eigen::Matrix<Scalar, Out::RowsAtCompileTime, 1> mean;
    weightedMean(images, set.meanWeights(), mean);
    deviationsFrom(thetas, center, parameterDeviations_);
    Eigen::Matrix<Scalar, ParamDim, Out::RowsAtCompileTime> transposed;
    weightedOuterSum(parameterDeviations_, images.colwise() - mean, set.covarianceWeights(), transposed);
    solveLowerInPlace(lowerFactor, transposed);  // P⁻¹ Σ … = S⁻ᵀ S⁻¹ Σ …
    solveUpperInPlace(lowerFactor, transposed);
    out = transposed.transpose();
  }

  // §3 for the parameter filter (no gate: the state's gate decides), into its candidates, with bounds
  // applied; committed with the state's correction. It observes y through the state filter's prediction,
  // whose innovation covariance H P⁻ Hᵀ + R (the uncertainty of x̂⁻ that its Dⱼ take as known, and the
  // sensor's) is its observation noise, plus parameterObservationNoise.
  template <class Engine>
  Status correctParameterFilter(Engine& engine, const Meas& y, const Input& u, const Mask* present) {
    const Model& model = engine.model();
    const Settings& s = engine.settings();
    ParameterEstimate& pe = estimate_;
    if (const Status st = stateInnovationCovariance(engine, u); st != Status::Ok) return st;
    observationNoise_ += s.parameterObservationNoise;
    if (!pe.useMeasurementNoise(observationNoise_)) return Status::InnovationNotPositiveDefinite;
    const bool drawn = !pe.hasPoints();
    if (drawn)
      if (const Status st = pe.draw(pe.mean(), pe.factor()); st != Status::Ok) return st;
    const auto& thetas = drawn ? pe.workPoints() : pe.points();
    const Param& center = pe.mean();          // θ̂⁻ after a time update: the θⱼ were drawn about it
    for (int j = 0; j < ParameterCount; ++j)  // Dⱼ = g(Φ_h(x̂_{k−1} + W_G (θⱼ − θ̂); θⱼ), u, θⱼ)
      pe.measuredPoints().col(j) = measureModel(
          model,
          drawn ? State(engine.state() + sensitivity_ * (thetas.col(j) - center)) : State(propagatedStates_.col(j)), u,
          thetas.col(j));
    if (!allFinite(pe.measuredPoints())) return Status::NonFiniteResult;
    regressOnParameters(pe.measuredPoints(), thetas, center, pe.factor(), measurementSensitivity_);  // ψ = ∂ŷ/∂θ̂
    if (const Status st =
            pe.correct(thetas, pe.measuredPoints(), pe.prior(drawn), y, observationNoise_, present, noGate_);
        st != Status::Ok)
      return st;
    if (!allFinite(pe.candidateMean())) return Status::NonFiniteResult;
    const Status settled = pe.settle(s.repair);
    if (!taken(settled)) return settled;
    if (boundsActive_) s.parameterBounds.clamp(pe.candidateMean());
    return settled;
  }

  // The UpdatedParameters ordering: the state's last time update again, through the engine's own
  // prediction, from x̂_{k−1} (moved by W_G Δθ̂) and the factor it drew from (P_{k−1}'s, or that of
  // P_{k−1} + W C Wᵀ where the parameters walk), with θ̂_k, into repredictedMean_ and
  // repredictedCovariance_ and the engine's work points.
  template <class Engine>
  Status predictStateAgain(Engine& engine) {
    using Settings_ = typename Engine::Settings;
    Status settled;
    if constexpr (hasInputSignal<Model>) {
      if (step_.fromSignal) {
        const SharedSignalInput<Model> input(engine.model());
        const TimeStep<Model, Integrator, SharedSignalInput<Model>, Settings_> step{
            engine.model(), engine.integrator(), engine.settings(), input, step_.t, step_.h, step_.steps};
        settled = engine.predict(step, shiftedPriorMean(), priorFactor_);
      } else {
        settled = predictAgainHeld(engine);
      }
    } else {
      settled = predictAgainHeld(engine);
    }
    if (!taken(settled)) return settled;
    repredictedMean_ = engine.estimate_.candidateMean();
    repredictedCovariance_ = engine.estimate_.candidateCovariance();
    return settled;
  }
  // x̂_{k−1} given the corrected θ̂_k: moved by W_G (θ̂_k − θ̂_{k−1}) (W_G = W without a random walk).
  State shiftedPriorMean() const {
    return priorMean_ + startSensitivity_ * (estimate_.candidateMean() - estimate_.mean());
  }
  template <class Engine>
  Status predictAgainHeld(Engine& engine) {
    const HeldInput<Model> input{step_.held};
    const TimeStep<Model, Integrator, HeldInput<Model>, typename Engine::Settings> step{
        engine.model(), engine.integrator(), engine.settings(), input, step_.t, step_.h, step_.steps};
    return engine.predict(step, shiftedPriorMean(), priorFactor_);
  }

  // The random walk θ_k = θ_{k−1} + η (with forgetting, cov(η) = N = P^θ (1 − λ) / λ + Q_θ) leaves
  // x_{k−1} less tied to θ_k than to θ_{k−1} (docs/algorithms.md §9): given θ_k, θ_{k−1} ~
  // N(θ̂ + G (θ_k − θ̂), C) with G = P^θ (P^θ⁻)⁻¹ and C = P^θ − G P^θ = G N, so x_{k−1} | θ_k ~
  // N(x̂ + W G (θ_k − θ̂), P + W C Wᵀ). Into the candidates: W_G = W G, and the factor of P + W C Wᵀ the
  // state's time update draws from, as P's factor updated by the p columns of W L_C (L_C Lᵀ_C = C): no
  // n × n sum is formed and factored again, so a P far smaller than W C Wᵀ in some direction keeps its
  // factor there. Exact for a plant linear in x and θ (tests/dual_consistency_test.cpp).
  Status startFromWalk(const Settings& s, const Est& state) {
    const ParameterEstimate& pe = estimate_;
    using ParamMatrix = Eigen::Matrix<Scalar, ParamDim, ParamDim>;
    ParamMatrix gainTransposed = pe.covariance();  // Gᵀ = (P^θ⁻)⁻¹ P^θ = S⁻ᵀ S⁻¹ P^θ
    solveLowerInPlace(pe.candidateFactor(), gainTransposed);
    solveUpperInPlace(pe.candidateFactor(), gainTransposed);
    candidateStartSensitivity_.noalias() = sensitivity_ * gainTransposed.transpose();
    // N from the settings rather than as P^θ⁻ − P^θ, which cancels where the walk is small against P^θ;
    // (1 − λ) / λ rather than 1/λ − 1, whose subtraction rounds.
    const Scalar forgetting = s.parameterForgetting;
    const ParamMatrix walk = pe.covariance() * ((Scalar(1) - forgetting) / forgetting) + s.parameterProcessNoise;
    // C in Joseph's form, (I − G) P^θ (I − G)ᵀ + G N Gᵀ: a sum of two semi-definite terms whatever G is
    // (a repaired P^θ⁻ changes G but not N), so its factor exists; psdSquareRoot takes a singular C too.
    const ParamMatrix rest = ParamMatrix::Identity() - gainTransposed.transpose();
    ParamMatrix kept = rest * pe.covariance() * rest.transpose();
    kept.noalias() += gainTransposed.transpose() * walk * gainTransposed;
    symmetrize(kept);
    const Sensitivity spread = sensitivity_ * psdSquareRoot(kept);  // W L_C
    if (!allFinite(spread)) return Status::NonFiniteResult;
    candidatePriorFactor_ = state.factor();
    // Nothing to add (W = 0, as at the start and after a reset, or C = 0): P's factor as it is, bit for
    // bit, where a rotation by a zero column would still round its diagonal.
    if (spread.isZero(Scalar(0))) return Status::Ok;
    if (!choleskyRankUpdate(candidatePriorFactor_, spread, Scalar(1))) return Status::NonFiniteResult;
    return Status::Ok;
  }

  // observationNoise_ = the state filter's H P⁻ Hᵀ + R from its points of the coming correction, measured
  // with the parameters it runs with.
  template <class Engine>
  Status stateInnovationCovariance(Engine& engine, const Input& u) {
    auto& est = engine.estimate_;
    const bool drawn = engine.settings().redrawPointsForUpdate || !est.hasPoints();
    if (drawn)
      if (const Status st = est.draw(est.mean(), est.factor()); st != Status::Ok) return st;
    const Points& points = drawn ? est.workPoints() : est.points();
    const Param& theta = stateFilterParameters();
    for (int i = 0; i < Base::Count; ++i) stateMeasured_.col(i) = measureModel(engine.model(), points.col(i), u, theta);
    if (!allFinite(stateMeasured_)) return Status::NonFiniteResult;
    Meas mean;
    weightedMean(stateMeasured_, est.sigmaPoints().meanWeights(), mean);
    // In place: each coefficient is read before it is written (the centre, a local, aliases nothing).
    deviationsFrom(stateMeasured_, mean, stateMeasured_);
    weightedCovariance(stateMeasured_, est.sigmaPoints().covarianceWeights(), observationNoise_);
    observationNoise_ += engine.settings().measurementNoise;
    return Status::Ok;
  }

  // The members are in the order of their alignment, for a smaller object: Eigen aligns a fixed-size
  // matrix of a multiple of 16 bytes to 16, so the p-sized ones, the steps, the scalars and the flags
  // come after the others (48 B less in the float robot's policy).
  ParameterEstimate estimate_;  // θ̂, P^θ, the θⱼ
  Eigen::Matrix<Scalar, MeasDim, MeasDim> observationNoise_ = decltype(observationNoise_)::Zero();  // of this step
  MeasurementGate<Scalar, MeasDim> noGate_;
  PropagatedStates propagatedStates_ = PropagatedStates::Zero();  // Φ_h(x̂_{k−1} + W_G Δθⱼ; θⱼ), last time update
  Sensitivity sensitivity_ = Sensitivity::Zero();                 // W = ∂x̂/∂θ̂ after the last correction
  Sensitivity predictedSensitivity_ = Sensitivity::Zero();        // W⁻ of the last time update
  // The UpdatedParameters ordering: the state filter's prior of the last time update (and step_ below).
  State priorMean_ = State::Zero();
  StateMatrix priorFactor_ = StateMatrix::Zero();
  Sensitivity startSensitivity_ = Sensitivity::Zero();  // W_G of the last time update
  // Workspace, committed only with the step that made it (and candidateStep_ below).
  PropagatedStates candidatePropagatedStates_ = PropagatedStates::Zero();
  State candidatePriorMean_ = State::Zero();
  StateMatrix candidatePriorFactor_ = StateMatrix::Zero();       // the factor the state's time update draws from
  Sensitivity candidateStartSensitivity_ = Sensitivity::Zero();  // W_G (startFromWalk), or W
  State repredictedMean_ = State::Zero();
  StateMatrix repredictedCovariance_ = StateMatrix::Zero();
  Sensitivity candidatePredictedSensitivity_ = Sensitivity::Zero();
  Sensitivity candidateSensitivity_ = Sensitivity::Zero();
  Eigen::Matrix<Scalar, MeasDim, ParamDim> measurementSensitivity_ = decltype(measurementSensitivity_)::Zero();  // ψ
  Eigen::Matrix<Scalar, MeasDim, ParamDim> whitenedSensitivity_ = decltype(whitenedSensitivity_)::Zero();
  MeasPoints stateMeasured_ = MeasPoints::Zero();
  typename ParameterEstimate::Points parameterDeviations_ = ParameterEstimate::Points::Zero();
  StoredStep step_;           // the UpdatedParameters ordering's step of the last time update
  StoredStep candidateStep_;  // workspace
  Scalar openLoopTime_ = 0;   // open-loop propagation since the last time update
  bool boundsActive_;
  bool storesStep_;  // the UpdatedParameters ordering
  bool walks_;       // P^θ⁻ ≠ P^θ: Q_θ ≠ 0 or λ < 1 (startFromWalk)
  bool hasPrior_ = false;
  bool useCorrectedParameters_ = false;
  bool correcting_ = false;  // the state's correction of a measurement update is running
};

}  // namespace detail
/// \endcond

/// Dual unscented Kalman filter: a UKF of the state x run with the current parameter estimate θ̂, and a
/// UKF of θ (a random walk) that observes the measurement through the state filter's prediction:
/// its sigma points θⱼ are measured as Dⱼ = g(Φ_h(x̂_{k−1} + W_G (θⱼ − θ̂); t, θⱼ), θⱼ) (docs/algorithms.md
/// §9). The cross-covariance of x and θ is not estimated; W = ∂x̂/∂θ̂ carries the dependence instead.
///
/// A time update predicts both filters (the parameter filter's 2p + 1 propagations of x̂_{k−1} are done
/// here, where the input is known); a measurement update corrects both with R, and commits both or
/// neither. An open-loop propagation moves x̂ with θ̂ and leaves both covariances. A measurement update
/// with no time update before it measures the θⱼ at the current x̂. Parameter bounds clamp θ̂ after
/// each correction. Every matrix is sized at compile time and no per-step call allocates; a call that
/// returns a Status other than Ok or Repaired leaves the filter exactly as it was.
///
/// Template arguments: docs/design.md, "Template arguments of every filter"; the parameter filter has
/// the state filter's sigma-point set and covariance form.
template <class Model_, class Integrator_ = DefaultIntegrator<Model_>, class PointSet = MerweScaled,
          class Form = FullCovariance, class Features = AllFeatures>
class DualUkf : public detail::EngineOf<
                    DualUkf<Model_, Integrator_, PointSet, Form, Features>, Model_, Integrator_,
                    DualUkfSettings<typename Model_::Scalar, Model_::StateDim, Model_::ParamDim, Model_::MeasDim>,
                    detail::DualParameters, Model_::StateDim, PointSet, Form, Features> {
  static_assert(checkModel<Model_, 1>());
  using Engine = typename DualUkf::UnscentedEngine;
  using Policy = typename Engine::PolicyType;
  friend Engine;
  friend Policy;

 public:
  /// The model's scalar and vector types (see the engine, detail/unscented_engine.hpp).
  using typename Engine::Input, typename Engine::Meas, typename Engine::Param, typename Engine::Scalar,
      typename Engine::State;
  /// The settings struct of this filter.
  using Settings = DualUkfSettings<typename Model_::Scalar, Model_::StateDim, Model_::ParamDim, Model_::MeasDim>;
  /// n, p and m: the model's sizes.
  using Engine::StateDim, Engine::ParamDim, Engine::MeasDim;
  /// The number of sigma points of the state filter.
  using Engine::SigmaPointCount;
  /// The number of sigma points of the parameter filter.
  static constexpr int ParameterSigmaPointCount = Policy::ParameterCount;
  /// An n × n matrix: the state filter's covariance.
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;
  /// A p × p matrix: the parameter filter's covariance.
  using ParamMatrix = Eigen::Matrix<Scalar, ParamDim, ParamDim>;

  /// Built from the model, x̂₀, θ̂₀, the settings and the stepper: throws std::invalid_argument naming
  /// the first invalid one (`validate`). Without exceptions, build it with `create`
  /// (detail/unscented_engine.hpp).
  using Engine::Engine;
  /// The first invalid initial value or setting, or none: what the constructor would throw.
  static SettingsError validate(const State& initialState, const Param& initialParameters, const Settings& settings) {
    if (SettingsError e = detail::checkInitialValues(kOwner, initialState, initialParameters, settings.parameterBounds))
      return e;
    if (SettingsError e = detail::requireCommittableCovariance(kOwner, "initialParameterCovariance",
                                                               settings.initialParameterCovariance))
      return e;
    if (SettingsError e =
            detail::requirePositiveSemiDefinite(kOwner, "parameterProcessNoise", settings.parameterProcessNoise))
      return e;
    if (SettingsError e = detail::requirePositiveSemiDefinite(kOwner, "parameterObservationNoise",
                                                              settings.parameterObservationNoise))
      return e;
    if (!(settings.parameterForgetting > 0 && settings.parameterForgetting <= 1))
      return detail::invalid(kOwner, "parameterForgetting", "must lie in (0, 1]");
    if (SettingsError e = Engine::validateSettings(kOwner, settings)) return e;
    return Policy::ParameterEstimate::SigmaPoints::validate(settings.parameterSigmaPoints);
  }

  /// The state estimate x̂.
  const State& state() const { return this->estimate_.mean(); }
  /// The state filter's covariance P (n × n).
  const StateMatrix& covariance() const { return this->estimate_.covariance(); }
  /// θ̂, the parameter filter's mean.
  const Param& parameters() const { return this->policy_.estimate().mean(); }
  /// P^θ, the parameter filter's covariance.
  const ParamMatrix& parameterCovariance() const { return this->policy_.estimate().covariance(); }
  /// W = ∂x̂/∂θ̂ (n × p), the sensitivity of the state estimate to the parameters through the dynamics and
  /// the state's corrections, after the last measurement update: the parameter filter propagates
  /// x̂ + W (θⱼ − θ̂) with each of its θⱼ (x̂ + W G (θⱼ − θ̂) where the parameters walk, docs/algorithms.md
  /// §9).
  const Eigen::Matrix<Scalar, Engine::StateDim, Engine::ParamDim>& sensitivity() const {
    return this->policy_.sensitivity();
  }
  /// Innovation, its covariance and NIS of the parameter filter's last successful correction.
  const UpdateDiagnostics<Scalar, MeasDim>& lastParameterUpdate() const {
    return this->policy_.estimate().diagnostics();
  }

  /// Starts the state filter again from (state, covariance), keeping the parameter filter. When one is
  /// not finite or the covariance is not symmetric positive definite, it changes nothing and throws
  /// std::invalid_argument naming the argument (without exceptions: returns the SettingsError;
  /// ResetResult, settings_error.hpp).
  ResetResult reset(const State& state, const StateMatrix& covariance) {
    return reset(state, covariance, parameters(), parameterCovariance());
  }
  /// Starts again from (state, covariance) and θ̂ = `parameters`, keeping P^θ.
  ResetResult reset(const State& state, const StateMatrix& covariance, const Param& parameters) {
    return reset(state, covariance, parameters, parameterCovariance());
  }
  /// Starts both filters again: (state, covariance) and (parameters, parameterCovariance).
  ResetResult reset(const State& state, const StateMatrix& covariance, const Param& parameters,
                    const ParamMatrix& parameterCovariance) {
    if (SettingsError e = detail::checkInitialValues(kOwner, state, parameters, this->settings_.parameterBounds,
                                                     "state", "parameters"))
      return detail::report(e);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    if (SettingsError e = detail::requireCommittableCovariance(kOwner, "parameterCovariance", parameterCovariance))
      return detail::report(e);
    this->resetEstimate(state, covariance);
    this->policy_.reset(parameters, parameterCovariance);  // checked above
    return ResetResult();
  }
  /// Starts a new pass over the same record (docs/offline-passes.md): time() back to `startTime`, the
  /// record's t₀, and the state filter to (state, covariance), carrying the parameter filter (θ̂, P^θ)
  /// as the last pass left it; the new state does not depend on θ̂ (W = 0). That is what
  /// `reset(state, covariance)` does, with the time: the arguments are checked as there, and a
  /// non-finite `startTime` is refused likewise.
  ResetResult startPass(Scalar startTime, const State& state, const StateMatrix& covariance) {
    if (SettingsError e = Engine::checkStartTime(kOwner, startTime)) return detail::report(e);
    if (SettingsError e = detail::requireFinite(kOwner, "state", state)) return detail::report(e);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    this->resetEstimate(state, covariance);
    this->policy_.reset(parameters(), parameterCovariance());  // the same θ̂ and P^θ, W = 0
    this->restartTime(startTime);
    return ResetResult();
  }

 private:
  static constexpr const char* kOwner = "mjukf::DualUkf";

  static const State& initialMean(const State& initialState, const Param&) { return initialState; }
};

/// The settings of `DualUkf<Model>`.
template <class Model>
using DualUkfSettingsFor = DualUkfSettings<typename Model::Scalar, Model::StateDim, Model::ParamDim, Model::MeasDim>;

}  // namespace mjukf
