#pragma once

/// \file
/// The modified joint UKF (MJUKF): state-only sigma points, each carrying its own parameter vector,
/// updated by a scaled transformation of the measurement error (docs/algorithms.md §5; paper eqs. 8–10).

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/parameter_change_detector.hpp"
#include "mjukf/detail/parameter_error_covariance.hpp"
#include "mjukf/detail/unscented_engine.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/features.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/model.hpp"
#include "mjukf/parameter_bounds.hpp"
#include "mjukf/parameter_sensitivity.hpp"
#include "mjukf/settings_error.hpp"

namespace mjukf {

/// ξ of eq. 9, one per parameter. Assigning one number gives every parameter that ξ (the paper's one
/// scalar, `settings.scaling = -1`); a vector gives each its own (`settings.scaling << -0.5, 0.02`).
template <class Scalar, int ParamDim>
class ParameterScalings : public Eigen::Matrix<Scalar, ParamDim, 1> {
  using Base = Eigen::Matrix<Scalar, ParamDim, 1>;

 public:
  /// ξ = 0 for every parameter.
  ParameterScalings() : Base(Base::Zero()) {}
  /// ξ for every parameter.
  ParameterScalings(Scalar xi) : Base(Base::Constant(xi)) {}  // NOLINT: implicit, as the paper's scalar ξ
  /// One ξ per parameter.
  template <class Other>
  ParameterScalings(const Eigen::MatrixBase<Other>& xi) : Base(xi) {}  // NOLINT: implicit, as a vector
  /// ξ for every parameter.
  ParameterScalings& operator=(Scalar xi) {
    this->setConstant(xi);
    return *this;
  }
  /// One ξ per parameter.
  template <class Other>
  ParameterScalings& operator=(const Eigen::MatrixBase<Other>& xi) {
    Base::operator=(xi);
    return *this;
  }
};

/// Where the automatic MJUKF's step for θ comes from (`ModifiedJointUkfSettings::parameterGain`).
enum class ParameterGain {
  /// The Kalman gain of θ from the joint covariance of the state's and the parameters' errors the
  /// filter follows (docs/algorithms.md §5.3): θ is taken as constant, the data of the whole run count,
  /// and a change of θ is detected in the innovations and widens P_θ (§5.4).
  JointCovariance,
  /// A recursive least-squares gain with a memory of `convergenceTime` (docs/tuning-mjukf.md): the data
  /// are forgotten in proportion to the information that arrives, so θ̂ follows a change within a memory
  /// and averages the noise of a memory only.
  RecursiveLeastSquares,
};

/// Settings of `ModifiedJointUkf` over a model of `StateDim` states, `ParamDim` parameters and
/// `MeasDim` measurements, validated at construction: P₀ and Q of the state x, and the parameter step
/// of eqs. 8–9. Templated on the sizes, not the model; `ModifiedJointUkf<Model>::Settings` or
/// `ModifiedJointUkfSettingsFor<Model>` name it. Every field: docs/settings.md §2, §3 and §6.
template <class Scalar_, int StateDim, int ParamDim, int MeasDim>
struct ModifiedJointUkfSettings : ParameterEstimationSettings<Scalar_, StateDim, MeasDim, ParamDim> {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// The type of P₀ and Q (n × n).
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;
  /// The parameter vector θ.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// The type of T (p × m).
  using Transformation = Eigen::Matrix<Scalar, ParamDim, MeasDim>;
  /// A p × p matrix (Q_θ).
  using ParamMatrix = Eigen::Matrix<Scalar, ParamDim, ParamDim>;
  /// ξ of eq. 9, one per parameter: θᵢ ← θ̂ − diag(ξ) T (y − Yᵢ). One number sets every parameter's
  /// (the paper's scalar ξ). Sign: θ̂ᵣ approaches the truth when ξᵣ (T ψ)ᵣᵣ < 0, ψ = ∂ŷ/∂θ̂ through the
  /// dynamics; with a row of T ≥ 0, ξᵣ is negative when the measurements rise with the parameter (the
  /// tank's ∂y/∂k_flow > 0 takes ξ = −1; ξ = +1 diverges). Too large diverges, too small converges
  /// slowly (docs/tuning-mjukf.md). The default 0 is accepted but leaves the parameters at θ̂₀: set it,
  /// or use `adaptiveScaling`.
  ParameterScalings<Scalar, ParamDim> scaling;
  /// T of eq. 9 (p × m): how much of each measurement's error moves each parameter, and in which
  /// direction. Each row has Σⱼ |tᵣⱼ| = 1 (eq. 14 with signed entries): T only distributes, ξ sets the
  /// size; a row of entries ≥ 0 sums to 1 as in the paper. The default (zero) is therefore refused
  /// unless `automaticTransformation`.
  Transformation transformation = Transformation::Zero();
  /// p_θ of eq. 8: the spacing of the initial per-point parameters θᵢ, evenly over θ̂₀ ± n p_θ; zero (the
  /// default) starts them all at θ̂₀. The automatic modes also take max(|θ̂₀|, (n + 1)|p_θ|) as each
  /// parameter's prior scale.
  Param parameterSpread = Param::Zero();
  /// true: T is computed by the filter at every measurement update from the sensitivities of the
  /// measurements to the parameters through the dynamics (eqs. 14–15; the sensitivities refreshed as
  /// `sensitivityInterval` says), and `transformation` is not used (docs/tuning-mjukf.md). false (the
  /// paper): `transformation` as given.
  bool automaticTransformation = false;
  /// true: ξ is set at every measurement update, for each parameter, from the sensitivities and a gain
  /// of θ (`parameterGain`; docs/tuning-mjukf.md), and `scaling` is not used. false (the paper):
  /// `scaling` as given.
  bool adaptiveScaling = false;
  /// With `adaptiveScaling`: where the gain of θ comes from. The default, the joint covariance's Kalman
  /// gain with a test for a change of θ, was within 1.25 times JUKF's RMSE or better on every studied
  /// case but the battery; the least-squares gain was the default before (docs/tuning-mjukf.md,
  /// docs/studies.md).
  ParameterGain parameterGain = ParameterGain::JointCovariance;
  /// With `adaptiveScaling` and `ParameterGain::JointCovariance`: α, the probability that the test for a
  /// change of θ fires at an update while θ is constant and the model right (docs/algorithms.md §5.4).
  /// It runs at every update, so α is small; a model that does not fit the data, or innovations that are
  /// correlated in time, fire it more often (`detectedParameterChanges()` counts the detections). 0: no
  /// test, θ taken as constant for good. Must be in [0, 1e-3].
  Scalar changeFalseAlarm = Scalar(1e-9);
  /// With `adaptiveScaling`: a memory in seconds of model time. With the joint covariance's gain, the
  /// window of the test for a change of θ (its data fade with this time constant) and the scale of the
  /// easing in; with the least-squares gain, the time over which θ is taken as constant, which a change
  /// of θ is followed within and a longer one averages more noise out. Must be > 0
  /// (docs/tuning-mjukf.md).
  Scalar convergenceTime = Scalar(5);
  /// With `adaptiveScaling`: the least memory in measurement updates, whatever the sampling interval.
  /// With Δt the interval between updates, the memory is the longer of `convergenceTime` and
  /// minimumMemoryUpdates · Δt: millisecond sampling keeps `convergenceTime` (5 s is 1,000–2,500
  /// updates on the plants), sampling every second or slower averages over at least this many updates,
  /// since a memory of a few updates turns each one's noise into a step of the same size
  /// (docs/tuning-mjukf.md). Must be finite and ≥ 1.
  Scalar minimumMemoryUpdates = Scalar(100);
  /// With either automatic mode: the sensitivities are recomputed at every `sensitivityInterval`-th
  /// time update (p extra propagations each) and kept in between; 0: once, at the first time update.
  /// Must be ≥ 0, checked even with both modes off, and 1 with `adaptiveScaling` and
  /// `ParameterGain::JointCovariance`, whose gain needs each step's sensitivities.
  int sensitivityInterval = 1;
  /// true (the default): the filter follows the covariance of θ̂, `parameterCovariance()`
  /// (docs/algorithms.md §5.1), from which the health monitor judges the parameters' motion. It needs
  /// the sensitivities W and ψ that the automatic modes follow anyway; with both modes off it costs p
  /// extra propagations at every `sensitivityInterval`-th time update, and every measurement update n
  /// evaluations of g. false: the paper's MJUKF and its cost (the paper presets), and
  /// `parameterCovariance()` is NaN, unknown.
  bool followParameterCovariance = true;
  /// With `adaptiveScaling`: true (the default) raises each time update's P⁻ to cover the covariance
  /// of the state's error that the uncertainty of θ̂ (`parameterCovariance()`) implies, so that the
  /// state's covariance, and with it the gain, accounts for the model's parameters being uncertain
  /// (docs/algorithms.md §5.2, docs/tuning-mjukf.md), and eases the parameters' steps in over a tenth
  /// of the memory. false: the state's covariance holds what its own sigma points and θᵢ carry alone,
  /// and the easing takes a fiftieth (the automatic MJUKF before this setting).
  bool parameterUncertaintyInState = true;
  /// Q_θ, a random walk of the parameters per time update, symmetric positive semi-definite; only where
  /// the filter follows the covariance of θ̂ (`followParameterCovariance` or an automatic mode), zero
  /// otherwise. It widens that covariance at every time update, and with it the joint covariance's gain
  /// of θ, so that `parameterCovariance()` covers parameters that drift (docs/algorithms.md §5.1). Zero
  /// (the default): θ taken as constant, and a covariance too small for parameters that do drift
  /// (docs/studies.md, "The plant as the filters model it"). As JUKF's Q_θ: the square of how much each
  /// parameter may change per time update.
  ParamMatrix parameterProcessNoise = ParamMatrix::Zero();

  /// Whether the filter follows the covariance of θ̂ (and the sensitivities W and ψ it needs):
  /// `followParameterCovariance` or either automatic mode.
  bool followsParameterCovariance() const {
    return followParameterCovariance || automaticTransformation || adaptiveScaling;
  }
};

/// \cond INTERNAL
namespace detail {

/// The parameter policy of `ModifiedJointUkf` (docs/algorithms.md §5): every sigma point χᵢ carries its
/// own θᵢ (eq. 8), is propagated and measured with it, and the θᵢ move against their point's
/// measurement error (eq. 9); θ̂ is their mean (eq. 10). With the automatic modes, T and a ξ per
/// parameter come from the sensitivities (parameter_sensitivity.hpp), which P_θ follows too, ξ fitted to
/// the Kalman gain of θ from P_θ's joint covariance (docs/algorithms.md §5.3; a test for a change of θ,
/// detail/parameter_change_detector.hpp) or to a least-squares gain; compiled
/// out (`Features`, features.hpp), their state and code are absent and P_θ is unknown.
/// detail/unscented_engine.hpp §3 lists what a policy supplies.
template <class Model, class Integrator, class Settings, class Est, class Features = AllFeatures>
class ModifiedJointParameters : public ParameterPolicy<Model, Integrator, Settings, Est> {
  using Base = ParameterPolicy<Model, Integrator, Settings, Est>;
  static constexpr bool Automatic = Features::automaticModes;
  // A member of the automatic modes' state: absent (an empty type of its own) when they are compiled out.
  template <class T, int Id>
  using IfAutomatic = std::conditional_t<Automatic, T, Absent<Id>>;

 public:
  using Base::StateDim, Base::ParamDim, Base::MeasDim, Base::Count;
  using typename Base::Points, typename Base::MeasPoints, typename Base::Mask;
  using typename Base::Scalar, typename Base::State, typename Base::Param, typename Base::Meas, typename Base::Vector;
  static_assert(Count == 2 * StateDim + 1,
                "ModifiedJointUkf needs van der Merwe's 2n + 1 sigma points: eqs. 8-10 pair each with its own "
                "theta_i (the cubature set has 2n)");
  using Transformation = Eigen::Matrix<Scalar, ParamDim, MeasDim>;
  using ParamPoints = Eigen::Matrix<Scalar, ParamDim, Count>;
  using ParamMatrix = Eigen::Matrix<Scalar, ParamDim, ParamDim>;
  using Sensitivity = ParameterSensitivity<Scalar, StateDim, MeasDim, ParamDim>;
  using ChangeDetector = detail::ParameterChangeDetector<Scalar, MeasDim, ParamDim>;

  ModifiedJointParameters(const Settings& settings, const Param& initialParameters)
      : followsSensitivities_(settings.followsParameterCovariance()), boundsActive_(settings.parameterBounds.active()) {
    spread(settings, initialParameters);
  }

  const Param& parameters() const { return parameters_; }
  const ParamPoints& parameterPoints() const { return parameterPoints_; }
  const Transformation& lastTransformation() const { return transformation_; }
  const Param& lastScalings() const { return scalings_; }
  const Sensitivity& sensitivity() const { return sensitivity_; }
  const ChangeDetector& changeDetector() const { return changeDetector_; }
  ParamMatrix covariance() const {
    if constexpr (Automatic)
      if (followsSensitivities_) return errorCovariance_.parameterCovariance();
    return ParamMatrix::Constant(std::numeric_limits<Scalar>::quiet_NaN());
  }

  // Eq. 8: θᵢ = θ̂₀ − p_θ (n + 1) + p_θ (i + 1), i = 0 … 2n; their mean is θ̂₀. The automatic modes
  // and P_θ start knowing each parameter to about the larger of its size and the half-width of the θᵢ.
  void spread(const Settings& s, const Param& center) {
    if constexpr (Automatic) {
      Param scale = center.cwiseAbs().cwiseMax(s.parameterSpread.cwiseAbs() * Scalar(StateDim + 1));
      for (int r = 0; r < ParamDim; ++r)
        if (!(scale(r) > Scalar(0))) scale(r) = Scalar(1);
      sensitivity_.start(scale, s.measurementNoise);
      errorCovariance_.start(s.initialCovariance, scale.array().square().matrix().asDiagonal());
      changeDetector_.start(s.changeFalseAlarm);
      timeUpdates_ = 0;
      transformation_.setZero();
      scalings_.setZero();
    }
    parameters_ = center;
    for (int i = 0; i < Count; ++i)
      parameterPoints_.col(i) = center - s.parameterSpread * Scalar(StateDim + 1) + s.parameterSpread * Scalar(i + 1);
    if (boundsActive_)
      for (int i = 0; i < Count; ++i) s.parameterBounds.clamp(parameterPoints_.col(i));
  }
  // A new state estimate of covariance P that does not depend on θ̂ (reset of the state alone): W = 0.
  void restartState([[maybe_unused]] const typename Settings::StateMatrix& covariance) {
    if constexpr (Automatic) {
      sensitivity_.restartState();
      errorCovariance_.restartState(covariance);
      changeDetector_.restartWindow();  // the innovations of a state that settles again
    }
  }

  // What the parameter part has learnt (the filter's ParameterKnowledge), and a new pass from it: the
  // sensitivities' schedule restarts as at construction (a refresh at the first time update, W = 0).
  struct Knowledge {
    Param parameters;
    ParamPoints parameterPoints;
    MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Sensitivity, 1> sensitivity;
    MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Transformation, 2> transformation;
    MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Param, 3> scalings;
    MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<ParamMatrix, 4> covariance;
  };
  Knowledge knowledge() const {
    if constexpr (Automatic)
      return Knowledge{parameters_, parameterPoints_, sensitivity_, transformation_, scalings_, covariance()};
    else
      return Knowledge{parameters_, parameterPoints_, {}, {}, {}, {}};
  }
  void startPass(const Knowledge& k, [[maybe_unused]] const typename Settings::StateMatrix& stateCovariance) {
    parameters_ = k.parameters;
    parameterPoints_ = k.parameterPoints;
    if constexpr (Automatic) {
      sensitivity_ = k.sensitivity;
      sensitivity_.restartPass();
      transformation_ = k.transformation;
      scalings_ = k.scalings;
      errorCovariance_.start(stateCovariance, k.covariance);
      changeDetector_.restartWindow();
      timeUpdates_ = 0;
    }
  }

  template <class Step>
  Status predictParameters(const Step&, const Est&) {
    return Status::Ok;
  }
  // χᵢ⁺ = Φ_h(χᵢ; t, θᵢ), each point with its own θᵢ. The automatic modes then follow W = ∂x̂/∂θ̂
  // about point 0 (χ₀ = x̂ with θ₀), whose propagation is the nominal of the forward differences.
  template <class Step>
  void propagatePoints(const Step& step, Points& points) {
    if constexpr (Automatic)
      if (followsSensitivities_) priorPoints_ = points;
    for (int i = 0; i < Count; ++i) {
      const Param theta = parameterPoints_.col(i);
      points.col(i) = step.propagate(theta, points.col(i));
    }
    if constexpr (Automatic) followSensitivities(step, points);
  }
  // W, and P_θ's prediction, over the time update that took priorPoints_ to points.
  template <class Step>
  void followSensitivities(const Step& step, const Points& points) {
    if (!followsSensitivities_) return;
    const int every = step.settings.sensitivityInterval;
    const bool refreshDue = every == 0 ? timeUpdates_ == 0 : timeUpdates_ % every == 0;
    const typename Sensitivity::StateSensitivity before = sensitivity_.stateSensitivity();
    if (refreshDue)
      sensitivity_.predict(priorPoints_.col(0), parameterPoints_.col(0), points.col(0), step.interval(),
                           [&](const State& x, const Param& theta) { return step.propagate(theta, x); });
    else
      sensitivity_.keepPrediction(step.interval());
    const bool found = errorCovariance_.predict(
        priorPoints_, points, parameterPoints_, before, refreshDue ? &sensitivity_.derivative() : nullptr,
        sensitivity_.candidateStateSensitivity(), step.settings.processNoise, step.settings.parameterProcessNoise,
        refreshDue ? sensitivity_.extrapolation() : Scalar(1));
    // The parameters' uncertainty in the state's covariance (docs/algorithms.md §5.2): P⁻ must cover
    // the covariance of η + W⁻ e that P_θ's prediction implies. A Σ that is finite but huge is passed on
    // as it is: the state's covariance then says so.
    coversParameterError_ =
        found && step.settings.adaptiveScaling && step.settings.parameterUncertaintyInState &&
        errorCovariance_.stateErrorCovariance(sensitivity_.candidateStateSensitivity(), stateErrorCovariance_);
  }
  const typename Est::Matrix& priorFactor(const Est& state) const { return state.factor(); }
  // Σ = cov(η + W⁻ e) for this time update's P⁻ to cover (parameterUncertaintyInState), or null.
  static constexpr bool raisesPriorCovariance = Automatic;
  const typename Est::Matrix* priorCovarianceFloor() const {
    if constexpr (Automatic)
      if (coversParameterError_) return &stateErrorCovariance_;
    return nullptr;
  }
  template <class Step>
  Vector propagateMean(const Step& step, const Vector& mean) {
    return step.propagate(parameters_, mean);
  }
  // Yᵢ = g(χᵢ⁺, u, θᵢ); points drawn afresh are paired with the θᵢ in order.
  void measurePoints(const Model& model, const typename Base::Input& u, const Points& points, MeasPoints& measured) {
    for (int i = 0; i < Count; ++i) measured.col(i) = measureModel(model, points.col(i), u, parameterPoints_.col(i));
  }
  template <class Engine>
  Status update(Engine& engine, const Meas& y, const typename Base::Input& u, const Mask* present) {
    return engine.correctState(y, u, present);
  }

  // Eqs. 9–10 into the candidates, from the Yᵢ of the state's correction:
  //   θᵢ ← θ̂ − ξ T (y − Yᵢ),   θ̂ ← (1 / (2n + 1)) Σ θᵢ,
  // with one ξ (the paper) or, in the automatic modes, T and one ξ per parameter from the sensitivities.
  Status correctParameters(const typename Base::CorrectionOf& c) {
    const Settings& s = c.settings;
    if constexpr (Automatic) {
      if (followsSensitivities_) {
        changeDetector_.discard();  // a candidate of an update that was refused after this call
        measurementJacobianAt(c);
        const Scalar memory = s.adaptiveScaling ? s.convergenceTime : std::numeric_limits<Scalar>::infinity();
        const Scalar updates = s.adaptiveScaling ? s.minimumMemoryUpdates : std::numeric_limits<Scalar>::infinity();
        const auto measure = [&c](const State& x, const Param& theta) {
          return measureModel(c.model, x, c.input, theta);
        };
        // The easing's first ramp: a tenth of the memory with the parameters' uncertainty in the
        // state's covariance, a fiftieth without it (docs/tuning-mjukf.md, "Easing in").
        const Scalar easing = s.parameterUncertaintyInState ? Scalar(0.1) : Scalar(0.02);
        if (!sensitivity_.correct(c.priorMean, parameters_, nominalMeasurement_, measure, c.gainFactor,
                                  c.innovationFactor, memory, updates, easing, c.present))
          return Status::NonFiniteResult;
      }
    }
    // T and ξ as set, or in the automatic modes from the sensitivities, which overwrite every entry.
    candidateTransformation_ = s.transformation;
    if constexpr (Automatic)
      if (s.automaticTransformation) sensitivity_.transformation(candidateTransformation_);
    if (c.present && !s.automaticTransformation) reduceToPresent(*c.present);
    candidateScalings_ = s.scaling;
    if constexpr (Automatic) {
      widened_ = false;
      if (s.adaptiveScaling) {
        if (s.parameterGain == ParameterGain::JointCovariance) {
          if (!jointCovarianceGain(c)) return Status::NonFiniteResult;
        } else
          sensitivity_.leastSquaresGain(c.innovationFactor, parameterGain_);
        sensitivity_.scaling(candidateTransformation_, parameterGain_, candidateScalings_);
      }
    }

    for (int i = 0; i < Count; ++i) {  // y − Yᵢ; a missing y(j) may be NaN: overwrite, never multiply by 0
      errors_.col(i) = c.y - c.measured.col(i);
      if (c.present)
        for (int j = 0; j < MeasDim; ++j)
          if (!(*c.present)(j)) errors_(j, i) = Scalar(0);
    }
    // Eq. 9 for every point at once, G (y − Yᵢ) with the gain G = diag(ξ) T: each parameter's ξ scales
    // its row of T.
    gain_.noalias() = candidateScalings_.asDiagonal() * candidateTransformation_;
    steps_.noalias() = gain_.lazyProduct(errors_);
    for (int i = 0; i < Count; ++i) {
      candidateParameterPoints_.col(i) = parameters_ - steps_.col(i);
      if (boundsActive_) s.parameterBounds.clamp(candidateParameterPoints_.col(i));
    }
    candidateParameters_ = candidateParameterPoints_.rowwise().sum() / Scalar(Count);  // eq. 10
    if (!allFinite(candidateParameterPoints_) || !allFinite(candidateParameters_)) return Status::NonFiniteResult;
    // P_θ refuses no step of the least-squares gain: an unbounded P_θ is reported (and passed on to the
    // floor of P⁻, §5.2). The joint covariance's gain is taken from it, and a J that is not finite is not
    // committed: the step is refused instead (it would leave every later gain undefined).
    if constexpr (Automatic)
      if (followsSensitivities_ && !correctErrorCovariance(c) && s.adaptiveScaling &&
          s.parameterGain == ParameterGain::JointCovariance)
        return Status::NonFiniteResult;
    return Status::Ok;
  }
  bool constrainMean(Vector&) { return false; }

  void commitPrediction() {
    if constexpr (Automatic) {
      if (!followsSensitivities_) return;
      errorCovariance_.commit();
      sensitivity_.commitPrediction();
      ++timeUpdates_;
    }
  }
  void commitCorrection() {
    parameters_ = candidateParameters_;
    parameterPoints_ = candidateParameterPoints_;
    if constexpr (Automatic) {
      if (!followsSensitivities_) return;
      errorCovariance_.commit();
      sensitivity_.commitCorrection();
      changeDetector_.commit();
      transformation_ = candidateTransformation_;
      scalings_ = candidateScalings_;
    }
  }
  void commitOpenLoop([[maybe_unused]] Scalar interval) {
    if constexpr (Automatic)
      if (followsSensitivities_) sensitivity_.commitOpenLoop(interval);
  }

 private:
  // g(x̂⁻, θ̂), and H = ∂g/∂x there by forward differences, one measurement per state, zero rows for
  // missing components.
  template <class Correction>
  void measurementJacobianAt(const Correction& c) {
    const Scalar root = std::sqrt(std::numeric_limits<Scalar>::epsilon());
    nominalMeasurement_ = measureModel(c.model, State(c.priorMean), c.input, parameters_);
    const Meas& nominal = nominalMeasurement_;
    const auto& prior = errorCovariance_.committed();  // the prediction, committed by the time update
    for (int i = 0; i < StateDim; ++i) {
      Scalar size = std::max(std::abs(c.priorMean(i)), std::sqrt(std::abs(prior(i, i))));
      if (!(size > Scalar(0)) || !std::isfinite(size)) size = Scalar(1);
      State moved = c.priorMean;
      moved(i) += root * size;
      measurementJacobian_.col(i) = (measureModel(c.model, moved, c.input, parameters_) - nominal) / (root * size);
    }
    if (c.present)
      for (int j = 0; j < MeasDim; ++j)
        if (!(*c.present)(j)) measurementJacobian_.row(j).setZero();
  }

  // The joint covariance's gain of θ (docs/algorithms.md §5.3) into parameterGain_, after the test for a
  // change of θ (§5.4) has run on this update's innovation: on a detection δ̂, P_θ is widened by δ̂ δ̂ᵀ for
  // this update (and through it, for good) and the gain taken again. False when there is no gain (S not
  // positive definite, J not finite); a widened gain that fails withdraws the detection instead.
  template <class Correction>
  bool jointCovarianceGain(const Correction& c) {
    const auto& psi = sensitivity_.candidateMeasurementSensitivity();
    if (!errorCovariance_.parameterGain(measurementJacobian_, psi, c.settings.measurementNoise, c.present, nullptr,
                                        parameterGain_, jointInnovationFactor_))
      return false;
    whitenedSensitivity_ = psi;
    detail::solveLowerInPlace(jointInnovationFactor_, whitenedSensitivity_);  // L⁻¹ ψ
    // ν = y − ŷ, the state's innovation (zero where missing), whose mean is zero while θ is constant: ŷ,
    // the points' mean, carries g's curvature over the points' spread and, where g depends on θ, the θᵢ's
    // spread; y − g(x̂⁻, θ̂) lacks both. On the battery the two differed by about 2 mV (its sensor's noise)
    // over the first hundred updates, which fired the test (docs/algorithms.md §5.4).
    Meas whitenedInnovation = c.innovation;
    detail::solveLowerInPlace(jointInnovationFactor_, whitenedInnovation);  // L⁻¹ ν
    // Tested once the easing's first ramp is over, on a window of at least a tenth of the memory.
    Param change;
    if (!changeDetector_.update(whitenedSensitivity_, whitenedInnovation, sensitivity_.forgetting(),
                                kLeastWindowShare * sensitivity_.memoryUpdates(), sensitivity_.rampComplete(), change))
      return true;
    widening_.noalias() = change * change.transpose();
    Transformation widenedGain;
    MeasMatrix widenedFactor;
    widened_ = errorCovariance_.parameterGain(measurementJacobian_, psi, c.settings.measurementNoise, c.present,
                                              &widening_, widenedGain, widenedFactor);
    if (widened_)
      parameterGain_ = widenedGain;
    else
      changeDetector_.discard();
    return true;
  }

  // The covariance of θ̂ (detail/parameter_error_covariance.hpp) with this update's gains: K = U S⁻¹,
  // G = diag(ξ) T, and H from measurementJacobianAt; P_θ widened when the test found a change.
  template <class Correction>
  bool correctErrorCovariance(const Correction& c) {
    stateGainTransposed_ = c.gainFactor.transpose();
    detail::solveUpperInPlace(c.innovationFactor, stateGainTransposed_);  // Kᵀ = S⁻ᵀ Uᵀ
    return errorCovariance_.correct(
        measurementJacobian_, stateGainTransposed_.transpose(), gain_, sensitivity_.candidateMeasurementSensitivity(),
        sensitivity_.candidateStateSensitivity(), c.settings.measurementNoise, widened_ ? &widening_ : nullptr);
  }

  // T with the columns of missing components zeroed and each row rescaled to Σⱼ |tᵣⱼ| = 1 (eq. 14).
  void reduceToPresent(const MeasurementMask<MeasDim>& present) {
    const Transformation t = candidateTransformation_;
    for (int r = 0; r < ParamDim; ++r) {
      Scalar sum = 0;
      for (int j = 0; j < MeasDim; ++j)
        if (present(j)) sum += std::abs(t(r, j));
      for (int j = 0; j < MeasDim; ++j)
        candidateTransformation_(r, j) = present(j) && sum != Scalar(0) ? t(r, j) / sum : Scalar(0);
    }
  }

  // The members are in the order of their alignment, for a smaller object: Eigen aligns a fixed-size
  // matrix of a multiple of 16 bytes to 16, so the m × (2n + 1) and p × m ones come before the p-sized
  // ones, and the counter and the flags come last (the float robot's policy: 480 → 464 B without the
  // automatic modes, 3,024 → 2,960 B with them, on the Cortex-M4F).
  // Workspace of the parameter correction: y − Yᵢ and G = diag(ξ) T.
  Eigen::Matrix<Scalar, MeasDim, Count> errors_ = Eigen::Matrix<Scalar, MeasDim, Count>::Zero();
  Transformation gain_ = Transformation::Zero();
  Param parameters_ = Param::Zero();                   // θ̂
  ParamPoints parameterPoints_ = ParamPoints::Zero();  // θᵢ
  // Workspace of the parameter correction, committed with the state's.
  Param candidateParameters_ = Param::Zero();
  ParamPoints candidateParameterPoints_ = ParamPoints::Zero();
  ParamPoints steps_ = ParamPoints::Zero();  // ξ T (y − Yᵢ), workspace only
  // What the automatic modes and P_θ follow; absent when the automatic modes are compiled out.
  // cov((η, θ̂ − θ)) (detail/parameter_error_covariance.hpp), and the workspace of its update.
  using ErrorCovariance = detail::ParameterErrorCovariance<Scalar, StateDim, MeasDim, ParamDim>;
  using MeasurementByState = Eigen::Matrix<Scalar, MeasDim, StateDim>;
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<ErrorCovariance, 5> errorCovariance_;
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Points, 6> priorPoints_{Points::Zero()};
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<MeasurementByState, 7> measurementJacobian_{MeasurementByState::Zero()};
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<MeasurementByState, 8> stateGainTransposed_{MeasurementByState::Zero()};
  // Σ of the time update in progress (parameterUncertaintyInState), and whether it applies (a flag at
  // the end).
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<typename Est::Matrix, 9> stateErrorCovariance_{Est::Matrix::Zero()};
  // The gain of θ of the update in progress (p × m), and the joint covariance's workspace for it: S's
  // factor L, L⁻¹ ψ, g(x̂⁻, θ̂) (shared with the sensitivities), and P_θ's widening on a detected change
  // (and whether it applies, a flag at the end).
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Transformation, 12> parameterGain_{Transformation::Zero()};
  using MeasMatrix = Eigen::Matrix<Scalar, MeasDim, MeasDim>;
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<MeasMatrix, 13> jointInnovationFactor_{MeasMatrix::Zero()};
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<typename Sensitivity::MeasSensitivity, 14> whitenedSensitivity_{
      Sensitivity::MeasSensitivity::Zero()};
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Meas, 15> nominalMeasurement_{Meas::Zero()};  // g(x̂⁻, θ̂)
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<ParamMatrix, 16> widening_{ParamMatrix::Zero()};
  // The test for a change tests a window of at least this share of the memory (docs/algorithms.md §5.4).
  static constexpr Scalar kLeastWindowShare = Scalar(0.1);
  // The automatic modes' state (committed with the parameters).
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Sensitivity, 1> sensitivity_;
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<ChangeDetector, 11> changeDetector_;
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Transformation, 3> transformation_{Transformation::Zero()};
  Transformation candidateTransformation_ = Transformation::Zero();
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<Param, 4> scalings_{Param::Zero()};
  Param candidateScalings_ = Param::Zero();
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<long, 2> timeUpdates_{0};
  // An automatic mode or followParameterCovariance: W, ψ and P_θ followed (never, compiled out).
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<bool, 0> followsSensitivities_;
  bool boundsActive_;
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<bool, 10> coversParameterError_{false};  // Σ applies
  MJUKF_NO_UNIQUE_ADDRESS IfAutomatic<bool, 17> widened_{false};               // the widening applies
};

// The policy with the filter's features bound: the engine takes a policy of four arguments.
template <class Features>
struct ModifiedJointParametersWith {
  template <class Model, class Integrator, class Settings, class Est>
  using Policy = ModifiedJointParameters<Model, Integrator, Settings, Est, Features>;
};

}  // namespace detail
/// \endcond

/// Modified joint unscented Kalman filter. Sigma points are drawn for the state alone (L = n, 2n + 1
/// points); point i is propagated with its own parameter vector θᵢ, and the θᵢ are moved against the
/// measurement error of their point: a time update costs 2n + 1 model propagations instead of
/// 2(n + p) + 1. Meant for systems whose measurements depend linearly on the parameters through the
/// dynamics.
///
/// Every matrix is sized at compile time and no per-step call allocates. A call that returns a
/// Status other than Ok or Repaired leaves the filter exactly as it was. The per-step calls are those
/// of the shared engine, detail/unscented_engine.hpp; the measurement update then moves the parameters
/// (eqs. 9–10):
///
///     θᵢ ← θ̂ − ξ T (y − Yᵢ),   θ̂ ← (1 / (2n + 1)) Σ θᵢ
///
/// with Yᵢ = g(χᵢ⁺, θᵢ), θ̂ the estimate before this update and one ξ per parameter (diag(ξ) T). A masked
/// update reduces T to the columns present, each row rescaled to Σⱼ |tᵣⱼ| = 1 again (eq. 14); a row with no weight on
/// any present component leaves its parameter at θ̂. The settings `automaticTransformation` and `adaptiveScaling` set T
/// and one ξ per parameter from the sensitivities instead, for p more propagations per time update
/// (parameter_sensitivity.hpp, docs/tuning-mjukf.md).
///
/// Template arguments: docs/design.md, "Template arguments of every filter"; the sigma-point set must
/// have 2n + 1 points. Eqs. 9–10 touch no covariance, so they are the same in both covariance forms.
/// `Without<feature::AutomaticModes>` (features.hpp) compiles the automatic modes, and P_θ with them, out.
template <class Model_, class Integrator_ = DefaultIntegrator<Model_>, class PointSet = MerweScaled,
          class Form = FullCovariance, class Features = AllFeatures>
class ModifiedJointUkf
    : public detail::EngineOf<
          ModifiedJointUkf<Model_, Integrator_, PointSet, Form, Features>, Model_, Integrator_,
          ModifiedJointUkfSettings<typename Model_::Scalar, Model_::StateDim, Model_::ParamDim, Model_::MeasDim>,
          detail::ModifiedJointParametersWith<Features>::template Policy, Model_::StateDim, PointSet, Form, Features> {
  static_assert(checkModel<Model_, 1>());
  using Engine = typename ModifiedJointUkf::UnscentedEngine;
  friend Engine;

 public:
  /// The model's scalar and vector types (see the engine, detail/unscented_engine.hpp).
  using typename Engine::Meas, typename Engine::Param, typename Engine::Scalar, typename Engine::State;
  /// The settings struct of this filter.
  using Settings =
      ModifiedJointUkfSettings<typename Model_::Scalar, Model_::StateDim, Model_::ParamDim, Model_::MeasDim>;
  /// n, p and m: the model's sizes.
  using Engine::StateDim, Engine::ParamDim, Engine::MeasDim;
  /// 2n + 1 sigma points, each with its own parameter vector θᵢ.
  using Engine::SigmaPointCount;
  /// An n × n matrix: the state covariance.
  using StateMatrix = Eigen::Matrix<Scalar, StateDim, StateDim>;
  /// T of eq. 9 (p × m).
  using Transformation = Eigen::Matrix<Scalar, ParamDim, MeasDim>;
  /// The per-point parameter vectors θᵢ, one column per sigma point.
  using ParamPoints = Eigen::Matrix<Scalar, ParamDim, SigmaPointCount>;
  /// What the automatic modes follow about θ (parameter_sensitivity.hpp): W, ψ and the information.
  using Sensitivity = ParameterSensitivity<Scalar, StateDim, MeasDim, ParamDim>;

  /// Built from the model, x̂₀, θ̂₀, the settings and the stepper: throws std::invalid_argument naming
  /// the first invalid one (`validate`). Without exceptions, build it with `create`
  /// (detail/unscented_engine.hpp).
  using Engine::Engine;
  /// The first invalid initial value or setting, or none: what the constructor would throw.
  static SettingsError validate(const State& initialState, const Param& initialParameters, const Settings& settings) {
    if (SettingsError e = detail::checkInitialValues(kOwner, initialState, initialParameters, settings.parameterBounds))
      return e;
    if constexpr (!Features::automaticModes) {
      constexpr const char* compiledOut =
          "must be false: the filter is compiled without its automatic modes "
          "(mjukf::Without<mjukf::feature::AutomaticModes>)";
      if (settings.automaticTransformation) return detail::invalid(kOwner, "automaticTransformation", compiledOut);
      if (settings.adaptiveScaling) return detail::invalid(kOwner, "adaptiveScaling", compiledOut);
      if (settings.followParameterCovariance) return detail::invalid(kOwner, "followParameterCovariance", compiledOut);
    }
    if (SettingsError e = detail::requireFinite(kOwner, "scaling (xi)", settings.scaling)) return e;
    if (SettingsError e = detail::requireFinite(kOwner, "transformation (T)", settings.transformation)) return e;
    if (SettingsError e = detail::requireFinite(kOwner, "parameterSpread (p_theta)", settings.parameterSpread))
      return e;
    if (settings.adaptiveScaling && !(std::isfinite(settings.convergenceTime) && settings.convergenceTime > 0))
      return detail::invalid(kOwner, "convergenceTime", "must be finite and > 0 (seconds)");
    if (settings.adaptiveScaling &&
        !(std::isfinite(settings.minimumMemoryUpdates) && settings.minimumMemoryUpdates >= 1))
      return detail::invalid(kOwner, "minimumMemoryUpdates", "must be finite and >= 1 (measurement updates)");
    if (settings.sensitivityInterval < 0) return detail::invalid(kOwner, "sensitivityInterval", "must be >= 0");
    if (SettingsError e =
            detail::requirePositiveSemiDefinite(kOwner, "parameterProcessNoise", settings.parameterProcessNoise))
      return e;
    if (!settings.followsParameterCovariance() && !settings.parameterProcessNoise.isZero(Scalar(0)))
      return detail::invalid(kOwner, "parameterProcessNoise",
                             "must be zero when the covariance of the parameters is not followed "
                             "(followParameterCovariance false, both automatic modes off)");
    if (settings.adaptiveScaling && !(settings.parameterGain == ParameterGain::JointCovariance ||
                                      settings.parameterGain == ParameterGain::RecursiveLeastSquares))
      return detail::invalid(kOwner, "parameterGain", "must be JointCovariance or RecursiveLeastSquares");
    // The joint covariance's gain linearises about this step's ψ and W; one reused from an earlier step
    // made θ̂ confidently wrong (the gallery's predator–prey: errors of 25–56 σ at sensitivityInterval 2).
    if (settings.adaptiveScaling && settings.parameterGain == ParameterGain::JointCovariance &&
        settings.sensitivityInterval != 1)
      return detail::invalid(kOwner, "sensitivityInterval",
                             "must be 1 with parameterGain JointCovariance, whose gain needs this step's "
                             "sensitivities (RecursiveLeastSquares allows another)");
    if (settings.adaptiveScaling &&
        !(settings.changeFalseAlarm >= 0 && settings.changeFalseAlarm <= Scalar(detail::kLargestFalseAlarm)))
      return detail::invalid(kOwner, "changeFalseAlarm", "must be in [0, 1e-3] (a probability per update; 0: no test)");
    // Each row of T has Σⱼ |tᵣⱼ| = 1 (paper eq. 14, with signed entries): T only distributes the error
    // and its direction, ξ sets its scale. A T that does not is almost always a typo or a transposed
    // matrix. (With automaticTransformation, T is the filter's.)
    const auto rowSums = settings.transformation.cwiseAbs().rowwise().sum();
    const Scalar tolerance = Scalar(1000) * Eigen::NumTraits<Scalar>::epsilon() * Scalar(MeasDim);
    if (!settings.automaticTransformation && (rowSums.array() - Scalar(1)).abs().maxCoeff() > tolerance)
      return detail::invalid(kOwner, "transformation (T)", "must have rows whose magnitudes each sum to 1");
    return Engine::validateSettings(kOwner, settings);
  }

  /// The state estimate x̂.
  const State& state() const { return this->estimate_.mean(); }
  /// The state covariance P (n × n).
  const StateMatrix& covariance() const { return this->estimate_.covariance(); }
  /// θ̂, the plain mean of the per-point parameters (eq. 10).
  const Param& parameters() const { return this->policy_.parameters(); }
  /// The θᵢ, one column per sigma point, in the order of the sigma points.
  const ParamPoints& parameterPoints() const { return this->policy_.parameterPoints(); }
  /// T of the last measurement update (with `automaticTransformation`, from the sensitivities; zero
  /// before the first update), else the setting.
  const Transformation& transformation() const {
    if constexpr (Features::automaticModes)
      if (this->settings_.automaticTransformation) return this->policy_.lastTransformation();
    return this->settings_.transformation;
  }
  /// ξ of the last measurement update, per parameter (with `adaptiveScaling`; zero before the first
  /// update), else the setting for every parameter.
  Param scalings() const {
    if constexpr (Features::automaticModes)
      if (this->settings_.adaptiveScaling) return this->policy_.lastScalings();
    return Param(this->settings_.scaling);
  }
  /// What the automatic modes know (W = ∂x̂/∂θ̂, ψ = ∂ŷ/∂θ̂ of the last update, the information about
  /// θ); not followed, and zero, when neither mode is on and `followParameterCovariance` is false. Not
  /// available in a filter compiled `Without<feature::AutomaticModes>`.
  template <class F = Features>
  const Sensitivity& sensitivity() const {
    static_assert(F::automaticModes,
                  "this ModifiedJointUkf is compiled without its automatic modes "
                  "(mjukf::Without<mjukf::feature::AutomaticModes>): sensitivity() is not available");
    return this->policy_.sensitivity();
  }
  /// How many changes of θ the automatic MJUKF's test has found since the start (docs/algorithms.md §5.4;
  /// with `adaptiveScaling` and `ParameterGain::JointCovariance`, else 0): each widened P_θ by the
  /// change's estimate. A count that grows through a run says the parameters move, or that the model
  /// does not fit the data. Not available in a filter compiled `Without<feature::AutomaticModes>`.
  template <class F = Features>
  long detectedParameterChanges() const {
    static_assert(F::automaticModes,
                  "this ModifiedJointUkf is compiled without its automatic modes "
                  "(mjukf::Without<mjukf::feature::AutomaticModes>): detectedParameterChanges() is not available");
    return this->policy_.changeDetector().changes();
  }
  /// P_θ, the covariance of θ̂ (p × p; docs/algorithms.md §5.1): the first-order covariance of θ̂'s
  /// error through the gains this filter used, from the prior diag(sᵣ²), sᵣ the larger of |θ̂₀ᵣ| and
  /// (n + 1)|p_θᵣ|. It takes θ as constant and the model as right; NaN (unknown) when
  /// `followParameterCovariance` and both automatic modes are off, and in a filter compiled
  /// `Without<feature::AutomaticModes>`.
  Eigen::Matrix<Scalar, ParamDim, ParamDim> parameterCovariance() const { return this->policy_.covariance(); }

  /// Starts again from (state, covariance), keeping θ̂ and the θᵢ (and, in the automatic modes, the
  /// information about θ; the new state does not depend on θ̂, W = 0). When one is not finite or the
  /// covariance is not symmetric positive definite, it changes nothing and throws
  /// std::invalid_argument naming the argument (without exceptions: returns the SettingsError;
  /// ResetResult, settings_error.hpp).
  ResetResult reset(const State& state, const StateMatrix& covariance) {
    if (SettingsError e = detail::requireFinite(kOwner, "state", state)) return detail::report(e);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    this->resetEstimate(state, covariance);
    this->policy_.restartState(covariance);
    return ResetResult();
  }
  /// Everything the filter has learnt about θ, carried from one pass over a record to the next
  /// (`startPass`): θ̂, the θᵢ and, in the automatic modes, the sensitivities' state (the information
  /// about θ with its prior, the easing's history) and the last T and ξ.
  using ParameterKnowledge = typename Engine::PolicyType::Knowledge;
  /// What the filter has learnt about θ so far (`startPass` carries it into a new pass).
  ParameterKnowledge parameterKnowledge() const { return this->policy_.knowledge(); }
  /// Starts a new pass over the same record (docs/offline-passes.md): time() back to `startTime`, the
  /// record's t₀, and the state to (state, covariance), keeping θ̂, the θᵢ and the automatic modes'
  /// information about θ as the last pass left them. The new state does not depend on θ̂ (W = 0), and
  /// the sensitivities start again as at construction: refreshed at the first time update, no time
  /// since a correction. Unlike `reset(state, covariance)`, which keeps the time and the sensitivities'
  /// schedule (a recovery within one run). Arguments checked as reset() checks them, and a non-finite
  /// `startTime` likewise.
  ResetResult startPass(Scalar startTime, const State& state, const StateMatrix& covariance) {
    return startPass(startTime, state, covariance, parameterKnowledge());
  }
  /// A new pass as above from `knowledge`, taken by `parameterKnowledge()` of this filter or of another
  /// of the same type (a run over another record of the same plant); it comes with the prior scale and
  /// the noise weights of the filter it was taken from. Its θ̂ and θᵢ must be finite and θ̂ within the
  /// bounds (reported as 'parameters').
  ResetResult startPass(Scalar startTime, const State& state, const StateMatrix& covariance,
                        const ParameterKnowledge& knowledge) {
    if (SettingsError e = Engine::checkStartTime(kOwner, startTime)) return detail::report(e);
    if (SettingsError e = detail::checkInitialValues(kOwner, state, knowledge.parameters,
                                                     this->settings_.parameterBounds, "state", "parameters"))
      return detail::report(e);
    if (SettingsError e = detail::requireFinite(kOwner, "parameters", knowledge.parameterPoints))
      return detail::report(e);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    this->resetEstimate(state, covariance);
    this->policy_.startPass(knowledge, covariance);
    this->restartTime(startTime);
    return ResetResult();
  }
  /// Starts again from (state, covariance) and θ̂ = `parameters`, the θᵢ spread around it by eq. 8 and
  /// the automatic modes' knowledge of θ back to its prior, as at construction. The parameters must
  /// also be finite and within the bounds.
  ResetResult reset(const State& state, const StateMatrix& covariance, const Param& parameters) {
    if (SettingsError e = detail::checkInitialValues(kOwner, state, parameters, this->settings_.parameterBounds,
                                                     "state", "parameters"))
      return detail::report(e);
    if (SettingsError e = Engine::checkResetCovariance(kOwner, covariance)) return detail::report(e);
    this->resetEstimate(state, covariance);
    this->policy_.spread(this->settings_, parameters);
    this->policy_.restartState(covariance);
    return ResetResult();
  }

 private:
  static constexpr const char* kOwner = "mjukf::ModifiedJointUkf";

  static const State& initialMean(const State& initialState, const Param&) { return initialState; }
};

/// The settings of `ModifiedJointUkf<Model>`.
template <class Model>
using ModifiedJointUkfSettingsFor =
    ModifiedJointUkfSettings<typename Model::Scalar, Model::StateDim, Model::ParamDim, Model::MeasDim>;

}  // namespace mjukf
