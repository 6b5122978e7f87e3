#pragma once

// The one skeleton under every filter: a time update, an open-loop propagation and a measurement
// update, each "check → draw → propagate or measure → predict or correct → settle → commit", with the
// failure policy of docs/robustness.md (nothing is committed until the whole step has succeeded).
//
// A filter derives from UnscentedEngine<Filter, Model, Integrator, Settings, L> (L: the dimension of
// the vector it draws sigma points for) and supplies
//
//   template <class In> void propagatePoints(const In& input, Scalar t, Scalar h, int steps, Points&);
//   void measurePoints(const Points& points, MeasPoints& measured);        // Yᵢ
//   template <class In> Vector propagateOpenLoop(const In& input, Scalar t, Scalar h, int steps);
//
// and, where it estimates parameters in its own way, hides any of the hooks below (predictParameters,
// correctParameters, constrainMean, commitParameterPrediction, commitParameterCorrection,
// commitOpenLoop), whose defaults do nothing. docs/design.md shows what each filter supplies.

#include <Eigen/Core>

#include "mjukf/detail/finite.hpp"
#include "mjukf/detail/propagation.hpp"
#include "mjukf/detail/unscented_core.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/model.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/status.hpp"

namespace mjukf::detail {

// The status of a step made of two parts that were both taken: Repaired if either was.
constexpr Status combineTaken(Status a, Status b) { return a == Status::Ok ? b : a; }

/// The per-step calls every filter shares: `Ukf`, `JointUkf`, `ModifiedJointUkf` and `DualUkf` derive
/// from this engine and inherit its public members. Each call returns a Status; one other than Ok or
/// Repaired leaves the filter exactly as it was (docs/robustness.md). `L` is the dimension of the
/// vector the filter draws sigma points for.
template <class Filter, class Model_, class Integrator_, class Settings_, int L>
class UnscentedEngine {
  static_assert(!isDiscreteTime<Model_> || std::is_same_v<Integrator_, NoIntegrator<typename Model_::Scalar>>,
                "a discrete-time model (it has transition()) is not integrated: leave the integrator out");

 public:
  /// The model type (model.hpp).
  using Model = Model_;
  /// The one-step integrator of a continuous model (`NoIntegrator` for a discrete-time one).
  using Integrator = Integrator_;
  /// The filter's settings struct.
  using Settings = Settings_;
  /// The model's floating-point type.
  using Scalar = typename Model::Scalar;
  /// n, the dimension of the state x.
  static constexpr int StateDim = Model::StateDim;
  /// p, the number of parameters θ.
  static constexpr int ParamDim = Model::ParamDim;
  /// m, the dimension of the measurement y.
  static constexpr int MeasDim = Model::MeasDim;
  /// The state vector x (n).
  using State = typename Model::State;
  /// The parameter vector θ (p).
  using Param = typename Model::Param;
  /// The measurement vector y (m).
  using Meas = typename Model::Meas;
  /// The input vector u (empty for a model without input).
  using Input = typename Model::Input;
  /// An m × m matrix, as R.
  using MeasMatrix = Eigen::Matrix<Scalar, MeasDim, MeasDim>;
  /// What `lastUpdate()` returns (diagnostics.hpp).
  using Diagnostics = UpdateDiagnostics<Scalar, MeasDim>;

  /// Unscented time update (docs/algorithms.md §2) from t over `steps` steps of size h, with the
  /// model's input signal u(t) evaluated at every stage time (once per distinct stage time, shared by
  /// all sigma points); a model without input (InputDim = 0) needs no `input(t)`. The sigma points are
  /// drawn once at t and propagated through all steps; Q is added once. Returns Ok or Repaired when
  /// the step was committed, otherwise a refusal.
  template <class M = Model>
  Status timeUpdate(Scalar t, Scalar h, int steps = 1) {
    static_assert(needsNoInputArgument<M>, "this model has no input(t): pass the input, timeUpdate(t, h, u)");
    if constexpr (hasInputSignal<M>)
      return timeUpdateWith(SharedSignalInput<Model>(model_), t, h, steps);
    else
      return timeUpdateWith(HeldInput<Model>{noInput_}, t, h, steps);
  }

  /// Unscented time update with the input u held constant over the steps (zero-order hold).
  Status timeUpdate(Scalar t, Scalar h, const Input& u, int steps = 1) {
    if (!allFinite(u)) return Status::NonFiniteInput;
    return timeUpdateWith(HeldInput<Model>{u}, t, h, steps);
  }

  /// Open-loop propagation of the mean alone (docs/algorithms.md §7), covariance unchanged: the
  /// paper's schedule between measurements. Input from the model's signal u(t), or none when the model
  /// has no input (InputDim = 0).
  template <class M = Model>
  Status propagateMean(Scalar t, Scalar h, int steps = 1) {
    static_assert(needsNoInputArgument<M>, "this model has no input(t): pass the input, propagateMean(t, h, u)");
    if constexpr (hasInputSignal<M>)
      return propagateMeanWith(SignalInput<Model>{model_}, t, h, steps);
    else
      return propagateMeanWith(HeldInput<Model>{noInput_}, t, h, steps);
  }

  /// Open-loop propagation of the mean alone with the input u held constant over the steps.
  Status propagateMean(Scalar t, Scalar h, const Input& u, int steps = 1) {
    if (!allFinite(u)) return Status::NonFiniteInput;
    return propagateMeanWith(HeldInput<Model>{u}, t, h, steps);
  }

  /// Measurement update (docs/algorithms.md §3, Algorithm 1 of the paper). Uses the sigma points of
  /// the last time update as they are (see `redrawPointsForUpdate`); if the filter has none (no time
  /// update since the last update or open-loop propagation), it draws them from the current mean and
  /// covariance. Returns Ok or Repaired when the update was committed (the covariance is symmetrised
  /// and checked before it is), MeasurementRejected when the gate refused it, or another refusal.
  Status measurementUpdate(const Meas& y) { return self().update(y, nullptr); }

  /// Measurement update with only the components where `present` is true (missing channels; the
  /// others, NaN included, are ignored): exactly the update of the model reduced to those components,
  /// with R reduced likewise. A mask with nothing present leaves the estimate as it was.
  Status measurementUpdate(const Meas& y, const MeasurementMask<MeasDim>& present) { return self().update(y, &present); }

  /// The filter built from these initial values and settings, or the SettingsError naming the first
  /// invalid one (Filter::validate): the way to build a filter without exceptions (docs/embedded.md).
  /// The filter is built once, in place in the Result (result.hpp). For Ukf, `initialParameters` are
  /// its fixed parameters.
  static Result<Filter> create(const Model& model, const State& initialState, const Param& initialParameters,
                               const Settings& settings, const Integrator& integrator = Integrator()) {
    return resultOf<Filter>(Filter::validate(initialState, initialParameters, settings), [&] {
      return Filter(Validated{}, model, initialState, initialParameters, settings, integrator);
    });
  }

  /// Innovation, its covariance and the NIS of the last successful measurement update.
  const Diagnostics& lastUpdate() const { return core_.diagnostics(); }
  /// True when the sigma points of the last time update are still the filter's.
  bool hasPropagatedPoints() const { return core_.hasPoints(); }
  /// The model the filter was built with.
  const Model& model() const { return model_; }
  /// The integrator the filter was built with.
  const Integrator& integrator() const { return integrator_; }
  /// The settings the filter was built with (validated at construction).
  const Settings& settings() const { return settings_; }

  /// \cond INTERNAL
 protected:
  using Core = UnscentedCore<Scalar, L, MeasDim>;
  using Vector = typename Core::Vector;
  using Matrix = typename Core::Matrix;
  using Points = typename Core::Points;
  using MeasPoints = typename Core::MeasPoints;
  using Mask = MeasurementMask<MeasDim>;

  // The settings every filter shares, checked in this order after the filter's own initial values:
  // the sigma points, P₀, Q, R, the repair and the gate. The first error, naming the setting, or none.
  static SettingsError validateSettings(const char* owner, const Settings& settings) {
    if (SettingsError e = Core::SigmaPoints::validate(settings.sigmaPoints)) return e;
    if (SettingsError e = requireCommittableCovariance(owner, "initialCovariance (P0)", settings.initialCovariance))
      return e;
    if (SettingsError e = requirePositiveSemiDefinite(owner, "processNoise (Q)", settings.processNoise)) return e;
    if (SettingsError e = requirePositiveDefinite(owner, "measurementNoise (R)", settings.measurementNoise)) return e;
    if (SettingsError e = validateRepair(owner, settings.repair)) return e;
    return validateGate(owner, settings.gate);
  }

  // Starts from `initialMean` and P₀, both accepted by the filter's validate() (which ends with
  // validateSettings): nothing here can fail.
  UnscentedEngine(Validated, const Model& model, const Integrator& integrator, const Settings& settings,
                  const Vector& initialMean)
      : model_(model), integrator_(integrator), settings_(settings), core_(Validated{}, settings.sigmaPoints) {
    core_.assign(initialMean, settings.initialCovariance);  // symmetrised, as every committed P is
  }

  // The covariance argument of reset() checked like P₀; reset() changes nothing when it fails. The mean
  // is checked by the filter, which names its parts.
  static SettingsError checkResetCovariance(const char* owner, const Matrix& covariance) {
    return requireCommittableCovariance(owner, "covariance", covariance);
  }
  // Commits a reset that checkResetCovariance() accepted: cannot fail.
  void resetEstimate(const Vector& mean, const Matrix& covariance) { core_.assign(mean, covariance); }

  // ---- The skeleton --------------------------------------------------------------------------------

  template <class InputSource>
  Status timeUpdateWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = checkStep(t, h, steps); s != Status::Ok) return s;
    const Status parameters = self().predictParameters(input, t, h, steps);
    if (!taken(parameters)) return parameters;
    if (const Status s = core_.draw(core_.mean()); s != Status::Ok) return s;
    self().propagatePoints(input, t, h, steps, core_.workPoints());
    if (!allFinite(core_.workPoints())) return Status::NonFiniteResult;
    core_.predict(settings_.processNoise);
    if (!allFinite(core_.candidateMean())) return Status::NonFiniteResult;
    const Status settled = core_.settle(settings_.repair);
    if (!taken(settled)) return settled;
    self().constrainMean(core_.candidateMean());
    core_.commitPrediction();
    self().commitParameterPrediction();
    return combineTaken(settled, parameters);
  }

  template <class InputSource>
  Status propagateMeanWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = checkStep(t, h, steps); s != Status::Ok) return s;
    const Vector mean = self().propagateOpenLoop(input, t, h, steps);
    if (!allFinite(mean)) return Status::NonFiniteResult;
    core_.commitMean(mean);
    self().commitOpenLoop();
    return Status::Ok;
  }

  // The measurement update of a filter whose prior is its committed estimate (every filter but the
  // dual one in its "updated parameters" ordering).
  Status update(const Meas& y, const Mask* present) {
    if (!presentComponentsFinite(y, present)) return Status::NonFiniteMeasurement;
    const bool drawPoints = settings_.redrawPointsForUpdate || !core_.hasPoints();
    if (drawPoints)
      if (const Status s = core_.draw(core_.mean()); s != Status::Ok) return s;
    return correctAndCommit(drawPoints ? core_.workPoints() : core_.points(), core_.mean(), core_.covariance(), y,
                            present);
  }

  // §3 from `points` about a prior, then the filter's parameter correction, then the checks and the
  // commit of both.
  Status correctAndCommit(const Points& points, const Vector& priorMean, const Matrix& priorCovariance, const Meas& y,
                          const Mask* present) {
    self().measurePoints(points, core_.measuredPoints());
    if (const Status s = core_.correct(points, priorMean, priorCovariance, y, settings_.measurementNoise, present,
                                       settings_.gate);
        s != Status::Ok)
      return s;
    const Status parameters = self().correctParameters(y, present);
    if (!taken(parameters)) return parameters;
    if (!allFinite(core_.candidateMean())) return Status::NonFiniteResult;
    const Status settled = core_.settle(settings_.repair);
    if (!taken(settled)) return settled;
    self().constrainMean(core_.candidateMean());
    core_.commitCorrection();
    self().commitParameterCorrection();
    return combineTaken(settled, parameters);
  }

  // ---- Hooks: the defaults do nothing --------------------------------------------------------------

  // Before the state's time update: the parameters' own prediction, into the filter's candidates.
  template <class InputSource>
  Status predictParameters(const InputSource&, Scalar, Scalar, int) {
    return Status::Ok;
  }
  // After the state's correction succeeded: the parameters' correction, into the filter's candidates.
  Status correctParameters(const Meas&, const Mask*) { return Status::Ok; }
  // On the candidate mean, once its covariance is settled (parameter bounds of the augmented vector).
  void constrainMean(Vector&) {}
  void commitParameterPrediction() {}
  void commitParameterCorrection() {}
  void commitOpenLoop() {}

  Model model_;
  Integrator integrator_;
  Settings settings_;
  Core core_;

 private:
  // The input of a model without one (InputDim = 0): an empty vector, held over every step.
  static inline const Input noInput_{};

  Filter& self() { return static_cast<Filter&>(*this); }
  /// \endcond
};

}  // namespace mjukf::detail
