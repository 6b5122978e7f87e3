#pragma once

/// \file
/// The joint UKF (JUKF): states and parameters in one augmented vector (algorithms.md §4).

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

/// Settings of `JointUkf`, validated at construction. Matrices are of the augmented vector [x; θ].
template <class Model>
struct JointUkfSettings {
  using Scalar = typename Model::Scalar;
  static constexpr int AugmentedDim = Model::StateDim + Model::ParamDim;
  using AugmentedMatrix = Eigen::Matrix<Scalar, AugmentedDim, AugmentedDim>;
  using MeasMatrix = Eigen::Matrix<Scalar, Model::MeasDim, Model::MeasDim>;
  SigmaPointParameters<Scalar> sigmaPoints;                      ///< α, β, κ
  AugmentedMatrix initialCovariance = AugmentedMatrix::Zero();  ///< P₀ of [x; θ], symmetric positive definite
  AugmentedMatrix processNoise = AugmentedMatrix::Zero();       ///< Q of [x; θ], positive semi-definite
  MeasMatrix measurementNoise = MeasMatrix::Zero();             ///< R, symmetric positive definite
  /// false (the paper's Algorithm 1): the measurement update reuses the propagated sigma points, so
  /// P_xy and P_yy leave Q out. true: it draws new points from (x̂⁻, P⁻), which costs one more
  /// Cholesky factorisation and makes the filter the textbook Kalman filter on linear models.
  bool redrawPointsForUpdate = false;
  /// What a step does with a covariance that is not positive definite before committing it
  /// (covariance_repair.hpp): by default, mend rounding-level losses and refuse the rest.
  CovarianceRepair<Scalar> repair;
  /// The innovation gate of the measurement update (measurement_gating.hpp); off by default.
  MeasurementGate<Scalar, Model::MeasDim> gate;
  /// Box bounds on the estimated parameters (parameter_bounds.hpp); off by default.
  ParameterBounds<Scalar, Model::ParamDim> parameterBounds;
};

/// Joint unscented Kalman filter: estimates z = [x; θ] with L = n + p, the parameters constant in the
/// model (θ̇ = 0). A time update costs 2(n + p) + 1 model propagations.
///
/// Every matrix is sized at compile time and no per-step call allocates. A call that returns a
/// Status other than Ok leaves the filter exactly as it was.
template <class Model_, class Integrator_ = ITrBdf2<typename Model_::Scalar>>
class JointUkf : public detail::TimeStepping<JointUkf<Model_, Integrator_>, Model_> {
  static_assert(checkModel<Model_, 1>());
  friend class detail::TimeStepping<JointUkf, Model_>;

 public:
  using Model = Model_;
  using Integrator = Integrator_;
  using Scalar = typename Model::Scalar;
  static constexpr int StateDim = Model::StateDim;
  static constexpr int ParamDim = Model::ParamDim;
  static constexpr int MeasDim = Model::MeasDim;
  static constexpr int AugmentedDim = StateDim + ParamDim;
  static constexpr int SigmaPointCount = 2 * AugmentedDim + 1;
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Meas = typename Model::Meas;
  using Input = typename Model::Input;
  using AugmentedState = Eigen::Matrix<Scalar, AugmentedDim, 1>;
  using AugmentedMatrix = Eigen::Matrix<Scalar, AugmentedDim, AugmentedDim>;
  using MeasMatrix = Eigen::Matrix<Scalar, MeasDim, MeasDim>;
  using Diagnostics = UpdateDiagnostics<Scalar, MeasDim>;

  using Settings = JointUkfSettings<Model>;

  /// Throws std::invalid_argument naming the setting when a setting or the initial values are invalid.
  JointUkf(const Model& model, const State& initialState, const Param& initialParameters,
           const Settings& settings, const Integrator& integrator = Integrator())
      : model_(model), integrator_(integrator), settings_(settings), core_(settings.sigmaPoints),
        covariance_(settings.initialCovariance) {
    constexpr const char* owner = "mjukf::JointUkf";
    detail::validateNoiseSettings(owner, settings);
    detail::requireFinite(owner, "initialState", initialState);
    detail::requireFinite(owner, "initialParameters", initialParameters);
    detail::validateRepair(owner, settings.repair);
    detail::validateGate(owner, settings.gate);
    detail::validateBounds(owner, settings.parameterBounds, initialParameters);
    boundsActive_ = settings.parameterBounds.active();
    augmented_.template head<StateDim>() = initialState;
    augmented_.template tail<ParamDim>() = initialParameters;

    core_.adoptInitialCovariance(owner, covariance_);  // every committed P is exactly symmetric
  }

  /// Measurement update, algorithms.md §3 on the augmented vector, g(z) = g(x, θ). Uses the sigma
  /// points of the last time update as they are (see `redrawPointsForUpdate`); if the filter has none,
  /// it draws them from the current mean and covariance.
  ///
  /// Returns Ok or Repaired when the update was committed (the covariance is symmetrised and checked
  /// before it is), MeasurementRejected when the gate refused it, or another refusal.
  Status measurementUpdate(const Meas& y) { return update(y, nullptr); }

  /// Measurement update with only the components where `present` is true (missing channels; the
  /// others, NaN included, are ignored): exactly the update of the model reduced to those components,
  /// with R reduced likewise.
  Status measurementUpdate(const Meas& y, const MeasurementMask<MeasDim>& present) { return update(y, &present); }

  /// The state block x of the augmented mean.
  State state() const { return augmented_.template head<StateDim>(); }
  /// The parameter block θ of the augmented mean.
  Param parameters() const { return augmented_.template tail<ParamDim>(); }
  const AugmentedState& augmentedState() const { return augmented_; }
  /// Covariance of the augmented vector [x; θ].
  const AugmentedMatrix& covariance() const { return covariance_; }
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
      if (const Status s = core_.draw(augmented_); s != Status::Ok) return s;
    const auto& points = drawPoints ? core_.workPoints() : core_.points();
    for (int i = 0; i < SigmaPointCount; ++i)  // Yᵢ = g(xᵢ, θᵢ) of zᵢ = [xᵢ; θᵢ]
      core_.measuredPoints().col(i) = model_.measurement(points.col(i).template head<StateDim>(),
                                                         points.col(i).template tail<ParamDim>());
    if (const Status s = core_.correct(points, augmented_, covariance_, y, settings_.measurementNoise, present,
                                       settings_.gate, candidateAugmented_, candidateCovariance_,
                                       candidateDiagnostics_);
        s != Status::Ok)
      return s;
    if (!detail::allFinite(candidateAugmented_)) return Status::NonFiniteResult;
    const Status settled = core_.settle(candidateCovariance_, settings_.repair);
    if (!taken(settled)) return settled;
    if (boundsActive_) settings_.parameterBounds.clamp(candidateAugmented_.template tail<ParamDim>());
    augmented_ = candidateAugmented_;
    core_.commitCovariance(covariance_, candidateCovariance_);
    diagnostics_ = candidateDiagnostics_;
    hasPropagatedPoints_ = false;
    return settled;
  }

  template <class InputSource>
  Status timeUpdateWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = detail::checkStep(t, h, steps); s != Status::Ok) return s;
    if (const Status s = core_.draw(augmented_); s != Status::Ok) return s;
    auto& points = core_.workPoints();
    for (int i = 0; i < SigmaPointCount; ++i) {  // [xᵢ; θᵢ]⁺ = [Φ_h(xᵢ; t, θᵢ); θᵢ]
      const Param theta = points.col(i).template tail<ParamDim>();
      points.col(i).template head<StateDim>() =
          detail::propagate(model_, integrator_, input, theta, t, h, steps, points.col(i).template head<StateDim>());
    }
    if (!detail::allFinite(points)) return Status::NonFiniteResult;
    core_.predict(settings_.processNoise, candidateAugmented_, candidateCovariance_);
    if (!detail::allFinite(candidateAugmented_)) return Status::NonFiniteResult;
    const Status settled = core_.settle(candidateCovariance_, settings_.repair);
    if (!taken(settled)) return settled;
    if (boundsActive_) settings_.parameterBounds.clamp(candidateAugmented_.template tail<ParamDim>());
    core_.commitPoints();
    augmented_ = candidateAugmented_;
    core_.commitCovariance(covariance_, candidateCovariance_);
    hasPropagatedPoints_ = true;
    return settled;
  }

  template <class InputSource>
  Status propagateMeanWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = detail::checkStep(t, h, steps); s != Status::Ok) return s;
    const State x = detail::propagate(model_, integrator_, input, parameters(), t, h, steps, state());
    if (!detail::allFinite(x)) return Status::NonFiniteResult;
    augmented_.template head<StateDim>() = x;
    hasPropagatedPoints_ = false;
    return Status::Ok;
  }

  Model model_;
  Integrator integrator_;
  Settings settings_;
  detail::UnscentedCore<Scalar, AugmentedDim, MeasDim> core_;
  AugmentedState augmented_;
  AugmentedMatrix covariance_;
  Diagnostics diagnostics_;
  bool hasPropagatedPoints_ = false;
  bool boundsActive_ = false;
  // Workspace: results are computed here and committed only when the whole step succeeded.
  AugmentedState candidateAugmented_;
  AugmentedMatrix candidateCovariance_;
  Diagnostics candidateDiagnostics_;
};

}  // namespace mjukf
