#pragma once

/// \file
/// The joint UKF (JUKF): states and parameters in one augmented vector (docs/algorithms.md §4).

#include <Eigen/Core>

#include "mjukf/detail/unscented_engine.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/model.hpp"
#include "mjukf/parameter_bounds.hpp"
#include "mjukf/settings_error.hpp"

namespace mjukf {

/// Settings of `JointUkf` over a model of `StateDim` states, `ParamDim` parameters and `MeasDim`
/// measurements, validated at construction. P₀ and Q are of the augmented vector [x; θ]: their θ block
/// is the parameters' initial uncertainty and random-walk process noise. Templated on the sizes, not
/// the model; `JointUkf<Model>::Settings` or `JointUkfSettingsFor<Model>` name it. Every field:
/// docs/settings.md §2, §3 and §5.
template <class Scalar, int StateDim, int ParamDim, int MeasDim>
struct JointUkfSettings : ParameterEstimationSettings<Scalar, StateDim + ParamDim, MeasDim, ParamDim> {
  /// n + p, the dimension of the augmented vector [x; θ].
  static constexpr int AugmentedDim = StateDim + ParamDim;
  /// The type of P₀ and Q of [x; θ].
  using AugmentedMatrix = Eigen::Matrix<Scalar, AugmentedDim, AugmentedDim>;
};

/// \cond INTERNAL
namespace detail {

/// The parameter policy of `JointUkf`: θ is the tail of the augmented vector [x; θ], constant in the
/// model (θ̇ = 0), with optional bounds on the committed mean (detail/unscented_engine.hpp §3 lists what
/// a policy supplies).
template <class Model, class Integrator, class Settings, class Est>
class AugmentedParameters : public ParameterPolicy<Model, Integrator, Settings, Est> {
 public:
  AugmentedParameters(const Settings& settings, const typename Model::Param&)
      : bounds_(settings.parameterBounds), boundsActive_(settings.parameterBounds.active()) {}

  using Base = ParameterPolicy<Model, Integrator, Settings, Est>;
  using Base::StateDim, Base::ParamDim;
  using typename Base::Param, typename Base::Points, typename Base::MeasPoints, typename Base::Vector;

  template <class Step>
  Status predictParameters(const Step&, const Est&) {
    return Status::Ok;
  }
  // [xᵢ; θᵢ]⁺ = [Φ_h(xᵢ; t, θᵢ); θᵢ]
  template <class Step>
  void propagatePoints(const Step& step, Points& points) {
    for (int i = 0; i < Base::Count; ++i) {
      const Param theta = points.col(i).template tail<ParamDim>();
      points.col(i).template head<StateDim>() = step.propagate(theta, points.col(i).template head<StateDim>());
    }
  }
  const typename Est::Matrix& priorFactor(const Est& state) const { return state.factor(); }
  static constexpr bool raisesPriorCovariance = false;
  const typename Est::Matrix* priorCovarianceFloor() const { return nullptr; }  // Q alone
  template <class Step>
  Vector propagateMean(const Step& step, const Vector& z) {
    Vector next = z;
    next.template head<StateDim>() = step.propagate(Param(z.template tail<ParamDim>()), z.template head<StateDim>());
    return next;
  }
  // Yᵢ = g(xᵢ, u, θᵢ) of zᵢ = [xᵢ; θᵢ]
  void measurePoints(const Model& model, const typename Base::Input& u, const Points& points, MeasPoints& measured) {
    for (int i = 0; i < Base::Count; ++i)
      measured.col(i) =
          measureModel(model, points.col(i).template head<StateDim>(), u, points.col(i).template tail<ParamDim>());
  }
  template <class Engine>
  Status update(Engine& engine, const typename Base::Meas& y, const typename Base::Input& u,
                const typename Base::Mask* present) {
    return engine.correctState(y, u, present);
  }
  Status correctParameters(const typename Base::CorrectionOf&) { return Status::Ok; }
  // The θ block of every committed mean within the bounds (parameter_bounds.hpp).
  bool constrainMean(Vector& z) {
    if (!boundsActive_) return false;
    bounds_.clamp(z.template tail<ParamDim>());
    return true;  // may have moved it
  }
  void commitPrediction() {}
  void commitCorrection() {}
  void commitOpenLoop(typename Base::Scalar) {}

 private:
  ParameterBounds<typename Base::Scalar, ParamDim> bounds_;
  bool boundsActive_;
};

}  // namespace detail
/// \endcond

/// The settings of `JointUkf<Model>`.
template <class Model>
using JointUkfSettingsFor = JointUkfSettings<typename Model::Scalar, Model::StateDim, Model::ParamDim, Model::MeasDim>;

/// Joint unscented Kalman filter: estimates z = [x; θ] with L = n + p, the parameters constant in the
/// model (θ̇ = 0). A time update costs 2(n + p) + 1 model propagations.
///
/// Every matrix is sized at compile time and no per-step call allocates. A call that returns a
/// Status other than Ok or Repaired leaves the filter exactly as it was. The per-step calls are those
/// of the shared engine, detail/unscented_engine.hpp; with parameter bounds, the θ block of every
/// committed mean is clamped (parameter_bounds.hpp).
///
/// Template arguments (model, stepper, sigma-point set, covariance form): docs/design.md, "Template
/// arguments of every filter".
template <class Model_, class Integrator_ = DefaultIntegrator<Model_>, class PointSet = MerweScaled,
          class Form = FullCovariance, class Features = AllFeatures>
class JointUkf : public detail::EngineOf<JointUkf<Model_, Integrator_, PointSet, Form, Features>, Model_, Integrator_,
                                         JointUkfSettingsFor<Model_>, detail::AugmentedParameters,
                                         Model_::StateDim + Model_::ParamDim, PointSet, Form, Features> {
  static_assert(checkModel<Model_, 1>());
  using Engine = typename JointUkf::UnscentedEngine;
  friend Engine;

 public:
  /// The model's scalar and vector types (see the engine, detail/unscented_engine.hpp).
  using typename Engine::Param, typename Engine::Scalar, typename Engine::State;
  /// The settings struct of this filter.
  using Settings = JointUkfSettings<typename Model_::Scalar, Model_::StateDim, Model_::ParamDim, Model_::MeasDim>;
  /// n and p: the model's sizes.
  using Engine::StateDim, Engine::ParamDim;
  /// n + p, the dimension of the augmented vector [x; θ].
  static constexpr int AugmentedDim = StateDim + ParamDim;
  /// The number of sigma points: 2(n + p) + 1 (van der Merwe's set, the default) or 2(n + p) (cubature).
  using Engine::SigmaPointCount;
  /// The augmented vector [x; θ].
  using AugmentedState = Eigen::Matrix<Scalar, AugmentedDim, 1>;
  /// The covariance of [x; θ].
  using AugmentedMatrix = Eigen::Matrix<Scalar, AugmentedDim, AugmentedDim>;
  /// An n × n matrix: the covariance of the state block.
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;

  /// Built from the model, x̂₀, θ̂₀, the settings and the stepper: throws std::invalid_argument naming
  /// the first invalid one (`validate`). Without exceptions, build it with `create`
  /// (detail/unscented_engine.hpp).
  using Engine::Engine;
  /// The first invalid initial value or setting, or none: what the constructor would throw.
  static SettingsError validate(const State& initialState, const Param& initialParameters, const Settings& settings) {
    if (SettingsError e = detail::checkInitialValues(kOwner, initialState, initialParameters, settings.parameterBounds))
      return e;
    return Engine::validateSettings(kOwner, settings);
  }

  /// The state block x of the augmented mean.
  State state() const { return augmentedState().template head<StateDim>(); }
  /// The parameter block θ of the augmented mean.
  Param parameters() const { return augmentedState().template tail<ParamDim>(); }
  /// The augmented mean [x̂; θ̂].
  const AugmentedState& augmentedState() const { return this->estimate_.mean(); }
  /// Covariance of the augmented vector [x; θ].
  const AugmentedMatrix& covariance() const { return this->estimate_.covariance(); }
  /// The θ block of the covariance, P_θθ: the uncertainty of `parameters()`.
  Eigen::Matrix<Scalar, ParamDim, ParamDim> parameterCovariance() const {
    return covariance().template bottomRightCorner<ParamDim, ParamDim>();
  }

  /// Starts again from the state, the augmented covariance of [x; θ] and the current parameters.
  /// When one is not finite, the covariance is not symmetric positive definite, or the parameters lie
  /// outside the bounds, it changes nothing and throws std::invalid_argument naming the argument
  /// (without exceptions: returns the SettingsError; ResetResult, settings_error.hpp).
  ResetResult reset(const State& state, const AugmentedMatrix& covariance) {
    return reset(state, covariance, parameters());
  }
  /// Starts again from [state; parameters] and the augmented covariance.
  ResetResult reset(const State& state, const AugmentedMatrix& covariance, const Param& parameters) {
    if (SettingsError e = detail::checkInitialValues(kOwner, state, parameters, this->settings_.parameterBounds,
                                                     "state", "parameters"))
      return detail::report(e);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    this->resetEstimate(augment(state, parameters), covariance);
    return ResetResult();
  }
  /// Starts a new pass over the same record (docs/offline-passes.md): time() back to `startTime`, the
  /// record's t₀, and the estimate to [state; θ̂] with the covariance
  ///
  ///     [ stateCovariance   0    ]
  ///     [ 0                 P_θθ ]
  ///
  /// carrying θ̂ and its covariance block P_θθ as the last pass left them. The cross terms P_xθ are
  /// zeroed: they correlate θ with the state at the end of the record, and say nothing about a state
  /// guessed for its start (kept beside a new state and P they could also make the matrix indefinite).
  /// The same as `reset(state, that matrix)` with the time; a non-finite `startTime` or `state`, or a
  /// `stateCovariance` that is not symmetric positive definite, changes nothing and is reported as
  /// reset() reports it.
  ResetResult startPass(Scalar startTime, const State& state, const StateMatrix& stateCovariance) {
    if (SettingsError e = Engine::checkStartTime(kOwner, startTime)) return detail::report(e);
    if (SettingsError e = detail::requireFinite(kOwner, "state", state)) return detail::report(e);
    if (SettingsError e = detail::requireCommittableCovariance(kOwner, "covariance", stateCovariance))
      return detail::report(e);
    const AugmentedMatrix covariance = passCovariance(stateCovariance);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    this->resetEstimate(augment(state, parameters()), covariance);
    this->restartTime(startTime);
    return ResetResult();
  }
  /// The covariance a new pass starts from with this state covariance: diag(stateCovariance, P_θθ) of
  /// the current estimate (`startPass`).
  AugmentedMatrix passCovariance(const StateMatrix& stateCovariance) const {
    AugmentedMatrix p = AugmentedMatrix::Zero();
    p.template topLeftCorner<StateDim, StateDim>() = stateCovariance;
    p.template bottomRightCorner<ParamDim, ParamDim>() = covariance().template bottomRightCorner<ParamDim, ParamDim>();
    return p;
  }

 private:
  static constexpr const char* kOwner = "mjukf::JointUkf";

  static AugmentedState initialMean(const State& initialState, const Param& initialParameters) {
    return augment(initialState, initialParameters);
  }
  // [x; θ]
  static AugmentedState augment(const State& x, const Param& theta) {
    AugmentedState z;
    z.template head<StateDim>() = x;
    z.template tail<ParamDim>() = theta;
    return z;
  }
};

}  // namespace mjukf
