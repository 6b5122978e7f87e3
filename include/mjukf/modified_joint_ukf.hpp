#pragma once

/// \file
/// The modified joint UKF (MJUKF): state-only sigma points, each carrying its own parameter vector,
/// updated by a scaled transformation of the measurement error (algorithms.md §5; paper eqs. 8–10).

#include <cmath>

#include <Eigen/Core>

#include "mjukf/covariance_repair.hpp"
#include "mjukf/detail/finite.hpp"
#include "mjukf/detail/propagation.hpp"
#include "mjukf/detail/time_stepping.hpp"
#include "mjukf/detail/unscented_core.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/diagnostics.hpp"
#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/model.hpp"
#include "mjukf/parameter_bounds.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/status.hpp"

namespace mjukf {

/// Settings of `ModifiedJointUkf`, validated at construction.
template <class Model>
struct ModifiedJointUkfSettings {
  using Scalar = typename Model::Scalar;
  using StateMatrix = Eigen::Matrix<Scalar, Model::StateDim, Model::StateDim>;
  using MeasMatrix = Eigen::Matrix<Scalar, Model::MeasDim, Model::MeasDim>;
  using Param = typename Model::Param;
  using Transformation = Eigen::Matrix<Scalar, Model::ParamDim, Model::MeasDim>;
  SigmaPointParameters<Scalar> sigmaPoints;                ///< α, β, κ
  StateMatrix initialCovariance = StateMatrix::Zero();    ///< P₀ of x, symmetric positive definite
  StateMatrix processNoise = StateMatrix::Zero();         ///< Q of x, symmetric positive semi-definite
  MeasMatrix measurementNoise = MeasMatrix::Zero();       ///< R, symmetric positive definite
  /// false (the paper's Algorithm 1): the measurement update reuses the propagated sigma points, so
  /// P_xy and P_yy leave Q out. true: it draws new points from (x̂⁻, P⁻), which costs one more
  /// Cholesky factorisation and makes the filter the textbook Kalman filter on linear models.
  bool redrawPointsForUpdate = false;
  /// ξ, the scaling parameter of eq. 9. Its sign follows the sign of ∂y/∂θ; too large diverges,
  /// too small converges slowly.
  Scalar scaling = 0;
  /// T of eq. 9 (p × m): how much each measurement's error moves each parameter. Each row sums to 1.
  Transformation transformation = Transformation::Zero();
  /// p_θ of eq. 8: the spacing of the initial per-point parameters θᵢ around θ̂₀.
  Param parameterSpread = Param::Zero();
  /// What a step does with a covariance that is not positive definite before committing it
  /// (covariance_repair.hpp): by default, mend rounding-level losses and refuse the rest.
  CovarianceRepair<Scalar> repair;
  /// The innovation gate of the measurement update (measurement_gating.hpp); off by default.
  MeasurementGate<Scalar, Model::MeasDim> gate;
  /// Box bounds on the estimated parameters (parameter_bounds.hpp); off by default.
  ParameterBounds<Scalar, Model::ParamDim> parameterBounds;
};

/// Modified joint unscented Kalman filter. Sigma points are drawn for the state alone (L = n, 2n + 1
/// points); point i is propagated with its own parameter vector θᵢ, and the θᵢ are moved against the
/// measurement error of their point: a time update costs 2n + 1 model propagations instead of
/// 2(n + p) + 1. Meant for systems whose measurements depend linearly on the parameters through the
/// dynamics.
///
/// Every matrix is sized at compile time and no per-step call allocates. A call that returns a
/// Status other than Ok leaves the filter exactly as it was.
template <class Model_, class Integrator_ = ITrBdf2<typename Model_::Scalar>>
class ModifiedJointUkf : public detail::TimeStepping<ModifiedJointUkf<Model_, Integrator_>, Model_> {
  static_assert(checkModel<Model_, 1>());
  friend class detail::TimeStepping<ModifiedJointUkf, Model_>;

 public:
  using Model = Model_;
  using Integrator = Integrator_;
  using Scalar = typename Model::Scalar;
  static constexpr int StateDim = Model::StateDim;
  static constexpr int ParamDim = Model::ParamDim;
  static constexpr int MeasDim = Model::MeasDim;
  static constexpr int SigmaPointCount = 2 * StateDim + 1;
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Meas = typename Model::Meas;
  using Input = typename Model::Input;
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;
  using MeasMatrix = Eigen::Matrix<Scalar, MeasDim, MeasDim>;
  using Transformation = Eigen::Matrix<Scalar, ParamDim, MeasDim>;
  using ParamPoints = Eigen::Matrix<Scalar, ParamDim, SigmaPointCount>;
  using Diagnostics = UpdateDiagnostics<Scalar, MeasDim>;

  using Settings = ModifiedJointUkfSettings<Model>;

  /// Throws std::invalid_argument naming the setting when a setting or the initial values are invalid.
  ModifiedJointUkf(const Model& model, const State& initialState, const Param& initialParameters,
                   const Settings& settings, const Integrator& integrator = Integrator())
      : model_(model), integrator_(integrator), settings_(settings), core_(settings.sigmaPoints),
        state_(initialState), covariance_(settings.initialCovariance), parameters_(initialParameters) {
    constexpr const char* owner = "mjukf::ModifiedJointUkf";
    detail::validateNoiseSettings(owner, settings);
    detail::requireFinite(owner, "initialState", initialState);
    detail::requireFinite(owner, "initialParameters", initialParameters);
    detail::requireFinite(owner, "scaling (xi)", settings.scaling);
    detail::requireFinite(owner, "transformation (T)", settings.transformation);
    detail::requireFinite(owner, "parameterSpread (p_theta)", settings.parameterSpread);
    // The rows of T sum to 1 (paper eq. 14): T only distributes the error, ξ sets its scale. A T that
    // does not is almost always a typo or a transposed matrix.
    const auto rowSums = settings.transformation.rowwise().sum();
    const Scalar tolerance = Scalar(1000) * Eigen::NumTraits<Scalar>::epsilon() * Scalar(MeasDim);
    if ((rowSums.array() - Scalar(1)).abs().maxCoeff() > tolerance)
      detail::throwInvalid(owner, "transformation (T)", "must have rows that each sum to 1");
    detail::validateRepair(owner, settings.repair);
    detail::validateGate(owner, settings.gate);
    detail::validateBounds(owner, settings.parameterBounds, initialParameters);
    boundsActive_ = settings.parameterBounds.active();
    core_.adoptInitialCovariance(owner, covariance_);  // every committed P is exactly symmetric
    // Eq. 8: θᵢ = θ̂₀ − p_θ (n + 1) + p_θ (i + 1), i = 0 … 2n; their mean is θ̂₀.
    for (int i = 0; i < SigmaPointCount; ++i)
      parameterPoints_.col(i) = initialParameters - settings.parameterSpread * Scalar(StateDim + 1) +
                                settings.parameterSpread * Scalar(i + 1);
    if (boundsActive_)
      for (int i = 0; i < SigmaPointCount; ++i) settings.parameterBounds.clamp(parameterPoints_.col(i));
  }

  /// Measurement update: the state as in algorithms.md §3, then the parameters (eqs. 9–10):
  ///
  ///     θᵢ ← θ̂ − ξ T (y − Yᵢ),   θ̂ ← (1 / (2n + 1)) Σ θᵢ
  ///
  /// with Yᵢ = g(χᵢ⁺, θᵢ) and θ̂ the estimate before this update. Uses the sigma points of the last
  /// time update as they are (see `redrawPointsForUpdate`); if the filter has none, it draws them from
  /// the current mean and covariance, paired with the θᵢ in order.
  ///
  /// Returns Ok or Repaired when the update was committed (the covariance is symmetrised and checked
  /// before it is), MeasurementRejected when the gate refused it, or another refusal.
  Status measurementUpdate(const Meas& y) { return update(y, nullptr); }

  /// Measurement update with only the components where `present` is true (missing channels; the
  /// others, NaN included, are ignored): exactly the update of the model reduced to those components,
  /// with R reduced likewise and, in eq. 9, T reduced to the columns present with each row rescaled to
  /// sum to 1 again (eq. 14); a row with no weight on any present component leaves its parameter at θ̂.
  Status measurementUpdate(const Meas& y, const MeasurementMask<MeasDim>& present) { return update(y, &present); }

  const State& state() const { return state_; }
  const StateMatrix& covariance() const { return covariance_; }
  /// θ̂, the plain mean of the per-point parameters (eq. 10).
  const Param& parameters() const { return parameters_; }
  /// The θᵢ, one column per sigma point, in the order of the sigma points.
  const ParamPoints& parameterPoints() const { return parameterPoints_; }
  /// Innovation, its covariance and the NIS of the last successful measurement update.
  const Diagnostics& lastUpdate() const { return diagnostics_; }
  /// True when the sigma points of the last time update are still the filter's.
  bool hasPropagatedPoints() const { return hasPropagatedPoints_; }
  const Model& model() const { return model_; }
  const Integrator& integrator() const { return integrator_; }
  const Settings& settings() const { return settings_; }

 private:
  Status update(const Meas& y, const MeasurementMask<MeasDim>* present) {
    if (!detail::presentComponentsFinite(y, present)) return Status::NonFiniteMeasurement;
    const bool drawPoints = settings_.redrawPointsForUpdate || !hasPropagatedPoints_;
    if (drawPoints)
      if (const Status s = core_.draw(state_); s != Status::Ok) return s;
    const auto& points = drawPoints ? core_.workPoints() : core_.points();
    auto& measured = core_.measuredPoints();
    for (int i = 0; i < SigmaPointCount; ++i)  // Yᵢ = g(χᵢ⁺, θᵢ)
      measured.col(i) = model_.measurement(points.col(i), parameterPoints_.col(i));
    if (const Status s = core_.correct(points, state_, covariance_, y, settings_.measurementNoise, present,
                                       settings_.gate, candidateState_, candidateCovariance_, candidateDiagnostics_);
        s != Status::Ok)
      return s;
    if (present) reducedTransformation(*present);
    const Transformation& transformation = present ? maskedTransformation_ : settings_.transformation;
    for (int i = 0; i < SigmaPointCount; ++i) {  // eq. 9
      measurementError_ = y - measured.col(i);
      if (present)  // a missing y(j) may be NaN: overwrite, never multiply by a zero column of T
        for (int j = 0; j < MeasDim; ++j)
          if (!(*present)(j)) measurementError_(j) = Scalar(0);
      candidateParameterPoints_.col(i) = parameters_;
      candidateParameterPoints_.col(i).noalias() -= settings_.scaling * transformation * measurementError_;
      if (boundsActive_) settings_.parameterBounds.clamp(candidateParameterPoints_.col(i));
    }
    candidateParameters_ = candidateParameterPoints_.rowwise().sum() / Scalar(SigmaPointCount);  // eq. 10
    if (!detail::allFinite(candidateState_) || !detail::allFinite(candidateParameterPoints_) ||
        !detail::allFinite(candidateParameters_))
      return Status::NonFiniteResult;
    const Status settled = core_.settle(candidateCovariance_, settings_.repair);
    if (!taken(settled)) return settled;
    state_ = candidateState_;
    core_.commitCovariance(covariance_, candidateCovariance_);
    parameters_ = candidateParameters_;
    parameterPoints_ = candidateParameterPoints_;
    diagnostics_ = candidateDiagnostics_;
    hasPropagatedPoints_ = false;
    return settled;
  }

  // T with the columns of missing components zeroed and each row rescaled to sum to 1 (eq. 14).
  void reducedTransformation(const MeasurementMask<MeasDim>& present) {
    for (int r = 0; r < ParamDim; ++r) {
      Scalar sum = 0;
      for (int j = 0; j < MeasDim; ++j)
        if (present(j)) sum += settings_.transformation(r, j);
      for (int j = 0; j < MeasDim; ++j)
        maskedTransformation_(r, j) = present(j) && sum != Scalar(0) ? settings_.transformation(r, j) / sum : Scalar(0);
    }
  }

  template <class InputSource>
  Status timeUpdateWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = detail::checkStep(t, h, steps); s != Status::Ok) return s;
    if (const Status s = core_.draw(state_); s != Status::Ok) return s;
    auto& points = core_.workPoints();
    for (int i = 0; i < SigmaPointCount; ++i) {  // χᵢ⁺ = Φ_h(χᵢ; t, θᵢ), each point with its own θᵢ
      const Param theta = parameterPoints_.col(i);
      points.col(i) = detail::propagate(model_, integrator_, input, theta, t, h, steps, points.col(i));
    }
    if (!detail::allFinite(points)) return Status::NonFiniteResult;
    core_.predict(settings_.processNoise, candidateState_, candidateCovariance_);
    if (!detail::allFinite(candidateState_)) return Status::NonFiniteResult;
    const Status settled = core_.settle(candidateCovariance_, settings_.repair);
    if (!taken(settled)) return settled;
    core_.commitPoints();
    state_ = candidateState_;
    core_.commitCovariance(covariance_, candidateCovariance_);
    hasPropagatedPoints_ = true;
    return settled;
  }

  template <class InputSource>
  Status propagateMeanWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = detail::checkStep(t, h, steps); s != Status::Ok) return s;
    candidateState_ = detail::propagate(model_, integrator_, input, parameters_, t, h, steps, state_);
    if (!detail::allFinite(candidateState_)) return Status::NonFiniteResult;
    state_ = candidateState_;
    hasPropagatedPoints_ = false;
    return Status::Ok;
  }

  Model model_;
  Integrator integrator_;
  Settings settings_;
  detail::UnscentedCore<Scalar, StateDim, MeasDim> core_;
  State state_;
  StateMatrix covariance_;
  Param parameters_;         // θ̂
  ParamPoints parameterPoints_;  // θᵢ
  Diagnostics diagnostics_;
  bool hasPropagatedPoints_ = false;
  bool boundsActive_ = false;
  // Workspace: results are computed here and committed only when the whole step succeeded.
  State candidateState_;
  StateMatrix candidateCovariance_;
  Param candidateParameters_;
  ParamPoints candidateParameterPoints_;
  Meas measurementError_;
  Transformation maskedTransformation_;
  Diagnostics candidateDiagnostics_;
};

}  // namespace mjukf
