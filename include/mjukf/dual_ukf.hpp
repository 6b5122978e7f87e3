#pragma once

/// \file
/// The dual UKF: a state filter and a parameter filter side by side (docs/algorithms.md §9).

#include <type_traits>

#include <Eigen/Core>

#include "mjukf/detail/finite.hpp"
#include "mjukf/detail/propagation.hpp"
#include "mjukf/detail/unscented_core.hpp"
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
/// filter (x alone); the parameter filter has its own below. Templated on the sizes, not the model;
/// `DualUkf<Model>::Settings` or `DualUkfSettingsFor<Model>` name it.
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
  /// α, β, κ of the parameter filter's sigma points (L = p).
  SigmaPointParameters<Scalar> parameterSigmaPoints;
  /// P^θ₀, the initial parameter covariance, symmetric positive definite.
  ParamMatrix initialParameterCovariance = ParamMatrix::Zero();
  /// Q_θ of the parameters' random walk, symmetric positive semi-definite.
  ParamMatrix parameterProcessNoise = ParamMatrix::Zero();
  /// Added to R in the parameter filter's correction: the uncertainty of its observation that R leaves
  /// out, chiefly that of the state estimate x̂_{k−1} it propagates (docs/algorithms.md §9). Symmetric
  /// positive semi-definite; zero (the default) observes with R alone.
  MeasMatrix parameterObservationNoise = MeasMatrix::Zero();
  /// λ ∈ (0, 1] of the parameter time update P^θ⁻ = P^θ / λ + Q_θ; 1 is none (van der Merwe's
  /// forgetting factor is the alternative to Q_θ).
  Scalar parameterForgetting = 1;
  /// Whether the state's time update uses θ̂_{k−1} or the corrected θ̂_k (see DualUkfOrdering).
  DualUkfOrdering ordering = DualUkfOrdering::PriorParameters;
};
/// The settings of `DualUkf<Model>`.
template <class Model>
using DualUkfSettingsFor = DualUkfSettings<typename Model::Scalar, Model::StateDim, Model::ParamDim, Model::MeasDim>;

/// Dual unscented Kalman filter: a UKF of the state x run with the current parameter estimate θ̂, and a
/// UKF of θ (a random walk) that observes the measurement through the state filter's prediction:
/// its sigma points θⱼ are measured as Dⱼ = g(Φ_h(x̂_{k−1}; t, θⱼ), θⱼ). The cross-covariance of x and
/// θ is not estimated.
///
/// A time update predicts both filters (the parameter filter's 2p + 1 propagations of x̂_{k−1} are done
/// here, where the input is known); a measurement update corrects both with R, and commits both or
/// neither. An open-loop propagation moves x̂ with θ̂ and leaves both covariances. A measurement update
/// with no time update before it measures the θⱼ at the current x̂. Parameter bounds clamp θ̂ after
/// each correction. Every matrix is sized at compile time and no per-step call allocates; a call that
/// returns a Status other than Ok or Repaired leaves the filter exactly as it was.
///
/// The stepper `Integrator_` of a continuous model is by default the paper's I-TR-BDF2, which is first
/// order: at a coarse step choose `Rk4` on purpose (docs/getting-started.md §4 measures the difference).
template <class Model_, class Integrator_ = DefaultIntegrator<Model_>>
class DualUkf : public detail::UnscentedEngine<DualUkf<Model_, Integrator_>, Model_, Integrator_,
                                               DualUkfSettingsFor<Model_>, Model_::StateDim> {
  static_assert(checkModel<Model_, 1>());
  using Engine = detail::UnscentedEngine<DualUkf<Model_, Integrator_>, Model_, Integrator_, DualUkfSettingsFor<Model_>,
                                         Model_::StateDim>;
  friend Engine;

 public:
  /// The model's scalar and vector types (see the engine, detail/unscented_engine.hpp).
  using typename Engine::Input, typename Engine::Meas, typename Engine::Param, typename Engine::Scalar,
      typename Engine::State;
  /// The settings struct of this filter.
  using Settings = DualUkfSettingsFor<Model_>;
  /// n, p and m: the model's sizes.
  using Engine::StateDim, Engine::ParamDim, Engine::MeasDim;
  static constexpr int SigmaPointCount = 2 * StateDim + 1;           ///< of the state filter
  static constexpr int ParameterSigmaPointCount = 2 * ParamDim + 1;  ///< of the parameter filter
  /// An n × n matrix: the state filter's covariance.
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;
  /// A p × p matrix: the parameter filter's covariance.
  using ParamMatrix = Eigen::Matrix<Scalar, ParamDim, ParamDim>;

#if MJUKF_EXCEPTIONS
  /// Throws std::invalid_argument naming the setting when a setting or the initial values are invalid
  /// (`validate`). Without exceptions, build it with `create` (detail/unscented_engine.hpp).
  DualUkf(const Model_& model, const State& initialState, const Param& initialParameters, const Settings& settings,
          const Integrator_& integrator = Integrator_())
      : DualUkf(detail::throwIfInvalid(validate(initialState, initialParameters, settings)), model, initialState,
                initialParameters, settings, integrator) {}
#endif
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
    return ParameterCore::SigmaPoints::validate(settings.parameterSigmaPoints);
  }

  /// The state estimate x̂.
  const State& state() const { return this->core_.mean(); }
  /// The state filter's covariance P (n × n).
  const StateMatrix& covariance() const { return this->core_.covariance(); }
  /// θ̂, the parameter filter's mean.
  const Param& parameters() const { return parameterCore_.mean(); }
  /// P^θ, the parameter filter's covariance.
  const ParamMatrix& parameterCovariance() const { return parameterCore_.covariance(); }
  /// Innovation, its covariance and NIS of the parameter filter's last successful correction.
  const UpdateDiagnostics<Scalar, MeasDim>& lastParameterUpdate() const { return parameterCore_.diagnostics(); }

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
    parameterCore_.assign(parameters, parameterCovariance);  // checked above
    hasPrior_ = false;
    return ResetResult();
  }

 private:
  static constexpr const char* kOwner = "mjukf::DualUkf";
  using ParameterCore = detail::UnscentedCore<Scalar, ParamDim, MeasDim>;
  using PropagatedStates = Eigen::Matrix<Scalar, StateDim, ParameterSigmaPointCount>;

  // The time step a measurement update of the UpdatedParameters ordering runs again.
  struct Step {
    Scalar t = 0, h = 0;
    int steps = 0;
    bool fromSignal = false;  // the model's u(t), or `held`
    Input held = Input::Zero();
  };

  DualUkf(detail::Validated, const Model_& model, const State& initialState, const Param& initialParameters,
          const Settings& settings, const Integrator_& integrator)
      : Engine(detail::Validated{}, model, integrator, settings, initialState),
        parameterCore_(detail::Validated{}, settings.parameterSigmaPoints),
        parameterNoise_(settings.measurementNoise + settings.parameterObservationNoise),
        boundsActive_(settings.parameterBounds.active()) {
    parameterCore_.assign(initialParameters, settings.initialParameterCovariance);  // checked in validate()
  }

  // The parameters the state filter runs with: θ̂⁻, or θ̂_k while the UpdatedParameters ordering
  // predicts and corrects the state again.
  const Param& stateFilterParameters() const {
    return useCorrectedParameters_ ? parameterCore_.candidateMean() : parameterCore_.mean();
  }

  // ---- Engine hooks --------------------------------------------------------------------------------

  // χᵢ⁺ = Φ_h(χᵢ; t, θ̂)
  template <class InputSource>
  void propagatePoints(const InputSource& input, Scalar t, Scalar h, int steps, typename Engine::Points& points) {
    const Param& theta = stateFilterParameters();
    for (int i = 0; i < SigmaPointCount; ++i)
      points.col(i) = detail::propagate(this->model_, this->integrator_, input, theta, t, h, steps, points.col(i));
  }
  // Yᵢ = g(χᵢ⁺, θ̂)
  void measurePoints(const typename Engine::Points& points, typename Engine::MeasPoints& measured) {
    const Param& theta = stateFilterParameters();
    for (int i = 0; i < SigmaPointCount; ++i) measured.col(i) = this->model_.measurement(points.col(i), theta);
  }
  template <class InputSource>
  State propagateOpenLoop(const InputSource& input, Scalar t, Scalar h, int steps) {
    return detail::propagate(this->model_, this->integrator_, input, parameters(), t, h, steps, state());
  }
  void commitOpenLoop() {
    parameterCore_.commitMean(parameterCore_.mean());  // its θⱼ were propagated from an x̂ that moved on
    hasPrior_ = false;
  }

  // The parameter time update, θ̂⁻ = θ̂, P^θ⁻ = P^θ / λ + Q_θ, and the propagation of x̂_{k−1} with each
  // θⱼ of (θ̂⁻, P^θ⁻) over the step, into the candidates.
  template <class InputSource>
  Status predictParameters(const InputSource& input, Scalar t, Scalar h, int steps) {
    const Settings& s = this->settings_;
    ParameterCore& pc = parameterCore_;
    pc.candidateMean() = pc.mean();
    pc.candidateCovariance() = pc.covariance() / s.parameterForgetting + s.parameterProcessNoise;
    const Status settled = pc.settle(s.repair);
    if (!taken(settled)) return settled;
    if (const Status drawn = pc.drawFrom(pc.candidateMean(), pc.candidateFactor()); drawn != Status::Ok) return drawn;
    for (int j = 0; j < ParameterSigmaPointCount; ++j) {
      const Param theta = pc.workPoints().col(j);
      candidatePropagatedStates_.col(j) =
          detail::propagate(this->model_, this->integrator_, input, theta, t, h, steps, state());
    }
    if (!detail::allFinite(candidatePropagatedStates_)) return Status::NonFiniteResult;
    if (this->settings_.ordering == DualUkfOrdering::UpdatedParameters) {
      candidatePriorMean_ = state();
      candidatePriorFactor_ = this->core_.factor();
      candidateStep_.t = t;
      candidateStep_.h = h;
      candidateStep_.steps = steps;
      candidateStep_.fromSignal = !std::is_same_v<InputSource, detail::HeldInput<Model_>>;
      if constexpr (std::is_same_v<InputSource, detail::HeldInput<Model_>>) candidateStep_.held = input.value;
    }
    return settled;
  }
  void commitParameterPrediction() {
    parameterCore_.commitPrediction();
    propagatedStates_ = candidatePropagatedStates_;
    if (this->settings_.ordering == DualUkfOrdering::UpdatedParameters) {
      priorMean_ = candidatePriorMean_;
      priorFactor_ = candidatePriorFactor_;
      step_ = candidateStep_;
      hasPrior_ = true;
    }
  }
  void commitParameterCorrection() {
    parameterCore_.commitCorrection();
    hasPrior_ = false;
  }

  // ---- The measurement update: parameters, then the state ------------------------------------------
  // The parameter filter is corrected first, into its candidates; the engine's correction of the state
  // then commits both (commitParameterCorrection) or neither.

  Status update(const Meas& y, const typename Engine::Mask* present) {
    if (!detail::presentComponentsFinite(y, present)) return Status::NonFiniteMeasurement;
    const Status parameters = correctParameterFilter(y, present);
    if (!taken(parameters)) return parameters;
    Status state;
    if (this->settings_.ordering == DualUkfOrdering::UpdatedParameters && hasPrior_) {
      useCorrectedParameters_ = true;
      state = predictStateAgain();
      if (taken(state)) {
        const Status corrected = this->correctAndCommit(redrawnOrPredictedPoints(), repredictedMean_,
                                                        repredictedCovariance_, y, present);
        state = taken(corrected) ? detail::combineTaken(corrected, state) : corrected;
      }
      useCorrectedParameters_ = false;
    } else {
      state = Engine::update(y, present);
    }
    return taken(state) ? detail::combineTaken(state, parameters) : state;
  }

  // §3 for the parameter filter (R + parameterObservationNoise as the observation noise; no gate: the state's gate decides), into
  // its candidates, with bounds applied; committed with the state's correction.
  Status correctParameterFilter(const Meas& y, const typename Engine::Mask* present) {
    ParameterCore& pc = parameterCore_;
    const bool drawn = !pc.hasPoints();
    if (drawn)
      if (const Status s = pc.draw(pc.mean()); s != Status::Ok) return s;
    const auto& thetas = drawn ? pc.workPoints() : pc.points();
    for (int j = 0; j < ParameterSigmaPointCount; ++j)  // Dⱼ = g(Φ_h(x̂_{k−1}; θⱼ), θⱼ)
      pc.measuredPoints().col(j) =
          this->model_.measurement(drawn ? state() : State(propagatedStates_.col(j)), thetas.col(j));
    if (const Status s = pc.correct(thetas, pc.mean(), pc.covariance(), y, parameterNoise_, present, noGate_);
        s != Status::Ok)
      return s;
    if (!detail::allFinite(pc.candidateMean())) return Status::NonFiniteResult;
    const Status settled = pc.settle(this->settings_.repair);
    if (!taken(settled)) return settled;
    if (boundsActive_) this->settings_.parameterBounds.clamp(pc.candidateMean());
    return settled;
  }

  // The UpdatedParameters ordering: the state's last time update again, from x̂_{k−1} and the factor
  // of P_{k−1}, with θ̂_k, into repredictedMean_/repredictedCovariance_ and the engine's work points.
  Status predictStateAgain() {
    auto& core = this->core_;
    if (const Status s = core.drawFrom(priorMean_, priorFactor_); s != Status::Ok) return s;
    if constexpr (hasInputSignal<Model_>) {
      if (step_.fromSignal)
        propagatePoints(detail::SharedSignalInput<Model_>(this->model_), step_.t, step_.h, step_.steps,
                        core.workPoints());
      else
        propagatePoints(detail::HeldInput<Model_>{step_.held}, step_.t, step_.h, step_.steps, core.workPoints());
    } else {
      propagatePoints(detail::HeldInput<Model_>{step_.held}, step_.t, step_.h, step_.steps, core.workPoints());
    }
    if (!detail::allFinite(core.workPoints())) return Status::NonFiniteResult;
    core.predict(this->settings_.processNoise);
    if (!detail::allFinite(core.candidateMean())) return Status::NonFiniteResult;
    const Status settled = core.settle(this->settings_.repair);
    if (!taken(settled)) return settled;
    repredictedMean_ = core.candidateMean();
    repredictedCovariance_ = core.candidateCovariance();
    return settled;
  }
  const typename Engine::Points& redrawnOrPredictedPoints() {
    auto& core = this->core_;
    if (this->settings_.redrawPointsForUpdate) core.drawFrom(repredictedMean_, core.candidateFactor());
    return core.workPoints();
  }

  ParameterCore parameterCore_;  // θ̂, P^θ, the θⱼ
  typename Settings::MeasMatrix parameterNoise_;  // R + parameterObservationNoise
  bool boundsActive_;
  MeasurementGate<Scalar, MeasDim> noGate_;
  PropagatedStates propagatedStates_ = PropagatedStates::Zero();  // Φ_h(x̂_{k−1}; θⱼ) of the last time update
  // The UpdatedParameters ordering: the state filter's prior of the last time update and its step.
  State priorMean_ = State::Zero();
  StateMatrix priorFactor_ = StateMatrix::Zero();
  Step step_;
  bool hasPrior_ = false;
  bool useCorrectedParameters_ = false;
  // Workspace, committed only with the step that made it.
  PropagatedStates candidatePropagatedStates_;
  State candidatePriorMean_;
  StateMatrix candidatePriorFactor_;
  Step candidateStep_;
  State repredictedMean_;
  StateMatrix repredictedCovariance_;
};

}  // namespace mjukf
