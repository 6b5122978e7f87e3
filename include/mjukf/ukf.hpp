#pragma once

/// \file
/// The unscented Kalman filter with known parameters (docs/algorithms.md §1–3).

#include <Eigen/Core>

#include "mjukf/detail/unscented_engine.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/model.hpp"
#include "mjukf/settings_error.hpp"

namespace mjukf {

/// Settings of `Ukf` over a model of `StateDim` states and `MeasDim` measurements, validated at
/// construction: P₀ and Q of the state x. Templated on the sizes, not the model, so one value serves
/// every model of the same shape; `Ukf<Model>::Settings` or `UkfSettingsFor<Model>` name it.
/// Every field: docs/settings.md §2 and §4.
template <class Scalar, int StateDim, int MeasDim>
struct UkfSettings : UnscentedSettings<Scalar, StateDim, MeasDim> {
  /// The type of P₀ and Q (n × n).
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;
};

/// \cond INTERNAL
namespace detail {

/// The parameter policy of `Ukf`: the parameters are known and fixed (detail/unscented_engine.hpp §3
/// lists what a policy supplies).
template <class Model, class Integrator, class Settings, class Est>
class KnownParameters : public ParameterPolicy<Model, Integrator, Settings, Est> {
 public:
  KnownParameters(const Settings&, const typename Model::Param& parameters) : parameters_(parameters) {}

  using Base = ParameterPolicy<Model, Integrator, Settings, Est>;
  using typename Base::Param, typename Base::Points, typename Base::MeasPoints, typename Base::Vector;
  const Param& parameters() const { return parameters_; }
  void reset(const Param& parameters) { parameters_ = parameters; }

  template <class Step>
  Status predictParameters(const Step&, const Est&) {
    return Status::Ok;
  }
  // χᵢ⁺ = Φ_h(χᵢ; t, θ)
  template <class Step>
  void propagatePoints(const Step& step, Points& points) {
    for (int i = 0; i < Base::Count; ++i) points.col(i) = step.propagate(parameters_, points.col(i));
  }
  const typename Est::Matrix& priorFactor(const Est& state) const { return state.factor(); }
  static constexpr bool raisesPriorCovariance = false;
  const typename Est::Matrix* priorCovarianceFloor() const { return nullptr; }  // Q alone
  template <class Step>
  Vector propagateMean(const Step& step, const Vector& mean) {
    return step.propagate(parameters_, mean);
  }
  // Yᵢ = g(χᵢ⁺, u, θ)
  void measurePoints(const Model& model, const typename Base::Input& u, const Points& points, MeasPoints& measured) {
    for (int i = 0; i < Base::Count; ++i) measured.col(i) = measureModel(model, points.col(i), u, parameters_);
  }
  template <class Engine>
  Status update(Engine& engine, const typename Base::Meas& y, const typename Base::Input& u,
                const typename Base::Mask* present) {
    return engine.correctState(y, u, present);
  }
  Status correctParameters(const typename Base::CorrectionOf&) { return Status::Ok; }
  bool constrainMean(Vector&) { return false; }
  void commitPrediction() {}
  void commitCorrection() {}
  void commitOpenLoop(typename Base::Scalar) {}

 private:
  Param parameters_;
};

}  // namespace detail
/// \endcond

/// Unscented Kalman filter of the state of `Model`, whose parameters are known and fixed.
///
/// 2n + 1 sigma points, each propagated with `Integrator` (by default the paper's I-TR-BDF2, or none
/// for a discrete-time model: model.hpp). Every matrix is sized at compile time and no per-step call
/// allocates. A call that returns a Status other than Ok or Repaired leaves the filter exactly as it
/// was. The per-step calls (`timeUpdate`, `propagateMean`, `measurementUpdate`) are those of the shared
/// engine, detail/unscented_engine.hpp.
///
/// Template arguments: docs/design.md, "Template arguments of every filter".
template <class Model_, class Integrator_ = DefaultIntegrator<Model_>, class PointSet = MerweScaled,
          class Form = FullCovariance, class Features = AllFeatures>
class Ukf : public detail::EngineOf<Ukf<Model_, Integrator_, PointSet, Form, Features>, Model_, Integrator_,
                                    UkfSettings<typename Model_::Scalar, Model_::StateDim, Model_::MeasDim>,
                                    detail::KnownParameters, Model_::StateDim, PointSet, Form, Features> {
  static_assert(checkModel<Model_>());
  using Engine = typename Ukf::UnscentedEngine;
  friend Engine;

 public:
  /// The model's scalar and vector types (see the engine, detail/unscented_engine.hpp).
  using typename Engine::Param, typename Engine::Scalar, typename Engine::State;
  /// The settings struct of this filter.
  using Settings = UkfSettings<typename Model_::Scalar, Model_::StateDim, Model_::MeasDim>;
  /// An n × n matrix: the state covariance.
  using StateMatrix = Eigen::Matrix<Scalar, Engine::StateDim, Engine::StateDim>;
  /// The number of sigma points: 2n + 1 (van der Merwe's set, the default) or 2n (cubature).
  using Engine::SigmaPointCount;

  /// Built from the model, x̂₀, the fixed parameters, the settings and the stepper: throws
  /// std::invalid_argument naming the first invalid one (`validate`). Without exceptions, build it with
  /// `create` (detail/unscented_engine.hpp).
  using Engine::Engine;
  /// The first invalid initial value or setting, or none: what the constructor would throw.
  static SettingsError validate(const State& initialState, const Param& parameters, const Settings& settings) {
    if (SettingsError e = detail::requireFinite(kOwner, "initialState", initialState)) return e;
    if (SettingsError e = detail::requireFinite(kOwner, "parameters", parameters)) return e;
    return Engine::validateSettings(kOwner, settings);
  }

  /// The state estimate x̂.
  const State& state() const { return this->estimate_.mean(); }
  /// The state covariance P (n × n).
  const StateMatrix& covariance() const { return this->estimate_.covariance(); }
  /// The fixed parameters the model is evaluated with.
  const Param& parameters() const { return this->policy_.parameters(); }

  /// Starts again from (state, covariance), keeping the parameters: recovers a diverged filter without
  /// rebuilding it. When one is not finite or the covariance is not symmetric positive definite, it
  /// changes nothing and throws std::invalid_argument naming the argument (without exceptions: returns
  /// the SettingsError; ResetResult, settings_error.hpp).
  ResetResult reset(const State& state, const StateMatrix& covariance) {
    return reset(state, covariance, parameters());
  }
  /// Starts again from (state, covariance) with other fixed parameters.
  ResetResult reset(const State& state, const StateMatrix& covariance, const Param& parameters) {
    if (SettingsError e = detail::requireFinite(kOwner, "state", state)) return detail::report(e);
    if (SettingsError e = detail::requireFinite(kOwner, "parameters", parameters)) return detail::report(e);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    this->resetEstimate(state, covariance);
    this->policy_.reset(parameters);
    return ResetResult();
  }
  /// Starts a new pass over the same record (docs/offline-passes.md): time() back to `startTime`, the
  /// record's t₀, and the estimate to (state, covariance), as `reset(state, covariance)` does. The
  /// arguments are checked as there, and a non-finite `startTime` is refused likewise.
  ResetResult startPass(Scalar startTime, const State& state, const StateMatrix& covariance) {
    if (SettingsError e = Engine::checkStartTime(kOwner, startTime)) return detail::report(e);
    if (SettingsError e = detail::requireFinite(kOwner, "state", state)) return detail::report(e);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    this->resetEstimate(state, covariance);
    this->restartTime(startTime);
    return ResetResult();
  }

 private:
  static constexpr const char* kOwner = "mjukf::Ukf";

  static const State& initialMean(const State& initialState, const Param&) { return initialState; }
};

/// The settings of `Ukf<Model>`.
template <class Model>
using UkfSettingsFor = UkfSettings<typename Model::Scalar, Model::StateDim, Model::MeasDim>;

}  // namespace mjukf
