#pragma once

/// \file
/// The unscented Kalman filter with known parameters (algorithms.md §1–3).

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
#include "mjukf/sigma_points.hpp"
#include "mjukf/status.hpp"

namespace mjukf {

/// Settings of `Ukf`, validated at construction.
template <class Model>
struct UkfSettings {
  using Scalar = typename Model::Scalar;
  using StateMatrix = Eigen::Matrix<Scalar, Model::StateDim, Model::StateDim>;
  using MeasMatrix = Eigen::Matrix<Scalar, Model::MeasDim, Model::MeasDim>;
  SigmaPointParameters<Scalar> sigmaPoints;                ///< α, β, κ
  StateMatrix initialCovariance = StateMatrix::Zero();    ///< P₀, symmetric positive definite
  StateMatrix processNoise = StateMatrix::Zero();         ///< Q, symmetric positive semi-definite
  MeasMatrix measurementNoise = MeasMatrix::Zero();       ///< R, symmetric positive definite
  /// false (the paper's Algorithm 1): the measurement update reuses the propagated sigma points, so
  /// P_xy and P_yy leave Q out. true: it draws new points from (x̂⁻, P⁻), which costs one more
  /// Cholesky factorisation and makes the filter the textbook Kalman filter on linear models.
  bool redrawPointsForUpdate = false;
  /// What a step does with a covariance that is not positive definite before committing it
  /// (covariance_repair.hpp): by default, mend rounding-level losses and refuse the rest.
  CovarianceRepair<Scalar> repair;
  /// The innovation gate of the measurement update (measurement_gating.hpp); off by default.
  MeasurementGate<Scalar, Model::MeasDim> gate;
};

/// Unscented Kalman filter of the state of `Model`, whose parameters are known and fixed.
///
/// 2n + 1 sigma points, each propagated with `Integrator`. Every matrix is sized at compile time and
/// no per-step call allocates. A call that returns a Status other than Ok leaves the filter exactly
/// as it was.
template <class Model_, class Integrator_ = ITrBdf2<typename Model_::Scalar>>
class Ukf : public detail::TimeStepping<Ukf<Model_, Integrator_>, Model_> {
  static_assert(checkModel<Model_>());
  friend class detail::TimeStepping<Ukf, Model_>;

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
  using Diagnostics = UpdateDiagnostics<Scalar, MeasDim>;

  using Settings = UkfSettings<Model>;

  /// Throws std::invalid_argument naming the setting when a setting or the initial values are invalid.
  Ukf(const Model& model, const State& initialState, const Param& parameters, const Settings& settings,
      const Integrator& integrator = Integrator())
      : model_(model), integrator_(integrator), settings_(settings), core_(settings.sigmaPoints),
        state_(initialState), covariance_(settings.initialCovariance), parameters_(parameters) {
    constexpr const char* owner = "mjukf::Ukf";
    detail::validateNoiseSettings(owner, settings);
    detail::validateRepair(owner, settings.repair);
    detail::validateGate(owner, settings.gate);
    detail::requireFinite(owner, "initialState", initialState);
    detail::requireFinite(owner, "parameters", parameters);

    core_.adoptInitialCovariance(owner, covariance_);  // every committed P is exactly symmetric
  }

  /// Measurement update, algorithms.md §3 (Algorithm 1 of the paper). Uses the sigma points of the
  /// last time update as they are (see `redrawPointsForUpdate`); if the filter has none (no time update
  /// since the last update or open-loop propagation), it draws them from the current mean and covariance.
  ///
  /// Returns Ok or Repaired when the update was committed (the covariance is symmetrised and checked
  /// before it is), MeasurementRejected when the gate refused it, or another refusal.
  Status measurementUpdate(const Meas& y) { return update(y, nullptr); }

  /// Measurement update with only the components where `present` is true (missing channels; the
  /// others, NaN included, are ignored): exactly the update of the model reduced to those components,
  /// with R reduced likewise. A mask with nothing present leaves the estimate as it was.
  Status measurementUpdate(const Meas& y, const MeasurementMask<MeasDim>& present) { return update(y, &present); }

  const State& state() const { return state_; }
  const StateMatrix& covariance() const { return covariance_; }
  /// The fixed parameters the model is evaluated with.
  const Param& parameters() const { return parameters_; }
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
    // The points of the last time update, or, when there are none, points drawn from the current
    // mean and covariance into the workspace.
    const bool drawPoints = settings_.redrawPointsForUpdate || !hasPropagatedPoints_;
    if (drawPoints)
      if (const Status s = core_.draw(state_); s != Status::Ok) return s;
    const auto& points = drawPoints ? core_.workPoints() : core_.points();
    for (int i = 0; i < SigmaPointCount; ++i)
      core_.measuredPoints().col(i) = model_.measurement(points.col(i), parameters_);  // Yᵢ = g(χᵢ⁺)
    if (const Status s = core_.correct(points, state_, covariance_, y, settings_.measurementNoise, present,
                                       settings_.gate, candidateState_, candidateCovariance_, candidateDiagnostics_);
        s != Status::Ok)
      return s;
    if (!detail::allFinite(candidateState_)) return Status::NonFiniteResult;
    const Status settled = core_.settle(candidateCovariance_, settings_.repair);
    if (!taken(settled)) return settled;
    state_ = candidateState_;
    core_.commitCovariance(covariance_, candidateCovariance_);
    diagnostics_ = candidateDiagnostics_;
    hasPropagatedPoints_ = false;
    return settled;
  }

  template <class InputSource>
  Status timeUpdateWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = detail::checkStep(t, h, steps); s != Status::Ok) return s;
    if (const Status s = core_.draw(state_); s != Status::Ok) return s;
    auto& points = core_.workPoints();
    for (int i = 0; i < SigmaPointCount; ++i)  // χᵢ⁺ = Φ_h(χᵢ; t, θ)
      points.col(i) = detail::propagate(model_, integrator_, input, parameters_, t, h, steps, points.col(i));
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
  Param parameters_;
  Diagnostics diagnostics_;
  bool hasPropagatedPoints_ = false;
  // Workspace: results are computed here and committed only when the whole step succeeded.
  State candidateState_;
  StateMatrix candidateCovariance_;
  Diagnostics candidateDiagnostics_;
};

}  // namespace mjukf
