#pragma once

// The one engine under every filter (docs/design.md): a time update, an open-loop propagation and a
// measurement update, each "check → draw → propagate or measure → predict or correct → settle →
// commit", with the failure policy of docs/robustness.md (nothing is committed until the whole step has
// succeeded). Read top to bottom:
//
//   1. propagating a model over a step (the input of the step, `propagate`);
//   2. `Estimate`: one unscented estimate, its committed mean, covariance and factor, its workspace and
//      the arithmetic of docs/algorithms.md §1–3 (draw, predict, correct, settle, commit);
//   3. the parameter policy a filter supplies, checked member by member (`checkParameterPolicy`);
//   4. `UnscentedEngine`: the public per-step calls and the skeleton of each step.
//
// The arithmetic itself is in detail/linear_algebra.hpp.

#include <type_traits>

#include <Eigen/Core>

#include "mjukf/covariance_repair.hpp"
#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/diagnostics.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/model.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/status.hpp"

// GCC and Clang: inline every call made in the function, recursively (what the compiler can see).
// The propagation of the points is the bulk of a step, and left to its own budget the compiler keeps
// the stepper, the model's derivative and Eigen's 4-vector assignments as separate calls there, which
// costs a third more than the same arithmetic inlined (bench/: step against floor). Not when
// optimising for size (-Os, firmware): there the calls are what the build asked for.
#if (defined(__GNUC__) || defined(__clang__)) && !defined(__OPTIMIZE_SIZE__)
#define MJUKF_FLATTEN __attribute__((flatten))
#else
#define MJUKF_FLATTEN
#endif

namespace mjukf::detail {

/// \cond INTERNAL

// ==== 1. Propagating a model over a step ==============================================================

// The model's own input signal u(t), evaluated at every stage time: for the open-loop mean, one point.
template <class Model>
struct SignalInput {
  const Model& model;
  typename Model::Input operator()(typename Model::Scalar t) const { return model.input(t); }
};

// The model's own input signal u(t) for a time update, which propagates all its sigma points over the
// same stage times: the last few distinct times and their values are kept, so u(t) is evaluated once
// per stage time rather than once per point and stage (the values are the same, since input(t) is a
// function of t alone; see model.hpp). Lives for one call; no allocation.
template <class Model>
class SharedSignalInput {
 public:
  using Scalar = typename Model::Scalar;
  using Input = typename Model::Input;

  explicit SharedSignalInput(const Model& model) : model_(model) {}

  const Input& operator()(Scalar t) const {
    // The points ask for the same times in the same order: try the slot after the last one first.
    if (hint_ < size_ && times_[hint_] == t) return hit(hint_);
    for (int i = 0; i < size_; ++i)
      if (times_[i] == t) return hit(i);
    // A miss replaces the oldest entry, so more distinct times than slots only cost the search.
    const int slot = next_;
    next_ = (next_ + 1) % Capacity;
    if (size_ < Capacity) ++size_;
    times_[slot] = t;
    values_[slot] = model_.input(t);
    return hit(slot);
  }

 private:
  // Enough for the stage times of one step of any stepper here (I-TR-BDF2 and RK4 have 3).
  static constexpr int Capacity = 8;

  const Input& hit(int slot) const {
    hint_ = slot + 1 < size_ ? slot + 1 : 0;
    return values_[slot];
  }

  const Model& model_;
  mutable Scalar times_[Capacity];  // only the first size_ are set
  mutable Input values_[Capacity];
  mutable int size_ = 0;
  mutable int next_ = 0;
  mutable int hint_ = 0;
};

// An input held constant over the step (zero-order hold), for inputs known only as samples.
template <class Model>
struct HeldInput {
  const typename Model::Input& value;
  const typename Model::Input& operator()(typename Model::Scalar /*t*/) const { return value; }
};

template <class Scalar>
Status checkStep(Scalar t, Scalar h, int steps) {
  if (!std::isfinite(t) || !std::isfinite(h) || !(h > 0) || steps < 1) return Status::InvalidStepSize;
  return Status::Ok;
}

// x(t + steps h) from x(t) by `steps` steps of size h under parameters theta, each one stepModel
// (model.hpp): an integrator step of a continuous model, or the transition of a discrete-time one.
template <class Model, class Integrator, class InputSource, class StateExpr>
MJUKF_FLATTEN typename Model::State propagate(const Model& model, const Integrator& integrator,
                                              const InputSource& input, const typename Model::Param& theta,
                                              typename Model::Scalar t, typename Model::Scalar h, int steps,
                                              const StateExpr& x0) {
  using Scalar = typename Model::Scalar;
  typename Model::State x = x0;
  for (int k = 0; k < steps; ++k) x = stepModel(model, integrator, t + Scalar(k) * h, h, x, input, theta);
  return x;
}

// One time update's or open-loop propagation's step, as the parameter policy receives it: the model,
// its stepper, the input over the step and the filter's settings; `propagate(θ, x)` is Φ_h over it.
template <class Model, class Integrator, class InputSource, class Settings>
struct TimeStep {
  using Scalar = typename Model::Scalar;
  using InputType = InputSource;
  const Model& model;
  const Integrator& integrator;
  const Settings& settings;
  const InputSource& input;
  Scalar t, h;
  int steps;

  /// Φ_h(x; t, θ) over all the steps.
  template <class StateExpr>
  typename Model::State propagate(const typename Model::Param& theta, const StateExpr& x) const {
    return detail::propagate(model, integrator, input, theta, t, h, steps, x);
  }
  /// The time the step covers, h · steps.
  Scalar interval() const { return h * Scalar(steps); }
};

// ==== 2. One unscented estimate =======================================================================

// The check and repair of a covariance about to be committed; the workspace is a member, so it
// allocates nothing. The Cholesky factor of the covariance it accepted is kept (`factor()`): the
// filter draws its next sigma points from it instead of factoring the same matrix again.
template <class Scalar, int L>
class CovarianceGuard {
 public:
  using Matrix = Eigen::Matrix<Scalar, L, L>;

  // Symmetrises `cov` and makes sure it has a Cholesky factor: Ok when it had one, Repaired when the
  // repair gave it one (cov then holds the repaired matrix), NotPositiveDefinite or NonFiniteResult
  // when it is refused (cov and factor() are then unspecified). After Ok or Repaired, factor() is the
  // lower Cholesky factor of cov as returned. The repair is covariance_repair.hpp's.
  Status settle(Matrix& cov, const CovarianceRepair<Scalar>& repair) {
    symmetrize(cov);
    if (!allFinite(cov)) return Status::NonFiniteResult;
    if (choleskyLower(cov, factor_)) return Status::Ok;
    const Scalar scale = cov.diagonal().cwiseAbs().mean();
    if (!(scale > 0) || !std::isfinite(scale)) return Status::NotPositiveDefinite;
    Scalar jitter = scale * repair.firstJitter;
    for (int attempt = 0; attempt < repair.maxAttempts && std::isfinite(jitter); ++attempt, jitter *= repair.growth) {
      candidate_ = cov;
      candidate_.diagonal().array() += jitter;
      if (!allFinite(candidate_)) break;  // a diagonal near the largest Scalar overflowed
      if (choleskyLower(candidate_, factor_)) {
        cov = candidate_;
        return Status::Repaired;
      }
    }
    return Status::NotPositiveDefinite;
  }

  const Matrix& factor() const { return factor_; }

 private:
  Matrix factor_ = Matrix::Zero();
  Matrix candidate_ = Matrix::Zero();
};

// One unscented estimate of an L-vector measured through M components: the committed mean,
// covariance, its Cholesky factor and propagated sigma points, the workspace a step computes into, and
// the arithmetic of docs/algorithms.md §1–3. A step writes only to the candidates here and commits them
// with one call, so "the stored factor is the Cholesky factor of the committed P" is kept by this class
// alone: nothing else can assign P. The filters' estimate is one; the dual filter's parameters are a
// second.
template <class Scalar, int L, int M, class PointSet = MerweScaled>
class Estimate {
 public:
  using PointSetType = PointSet;
  using SigmaPoints = typename PointSet::template Set<Scalar, L>;
  static constexpr int Count = SigmaPoints::Count;
  using Vector = Eigen::Matrix<Scalar, L, 1>;
  using Matrix = Eigen::Matrix<Scalar, L, L>;
  using Points = typename SigmaPoints::Points;
  using MeasVector = Eigen::Matrix<Scalar, M, 1>;
  using MeasMatrix = Eigen::Matrix<Scalar, M, M>;
  using MeasPoints = Eigen::Matrix<Scalar, M, Count>;
  using CrossMatrix = Eigen::Matrix<Scalar, L, M>;
  using Diagnostics = UpdateDiagnostics<Scalar, M>;
  using Mask = MeasurementMask<M>;
  using Gate = MeasurementGate<Scalar, M>;

  /// From sigma-point parameters that SigmaPoints::validate accepted (the filter's validate()).
  Estimate(Validated, const SigmaPointParameters<Scalar>& parameters) : sigmaPoints_(Validated{}, parameters) {}

  // ---- The committed estimate ----------------------------------------------------------------------
  const Vector& mean() const { return mean_; }
  const Matrix& covariance() const { return covariance_; }
  /// The lower Cholesky factor of covariance().
  const Matrix& factor() const { return factor_; }
  /// The points of the last time update, while they are still the estimate's (hasPoints()).
  const Points& points() const { return points_; }
  bool hasPoints() const { return hasPoints_; }
  const Diagnostics& diagnostics() const { return diagnostics_; }
  const SigmaPoints& sigmaPoints() const { return sigmaPoints_; }

  /// Makes (mean, cov) the estimate, with cov symmetrised as every committed P is, and forgets the
  /// propagated points; the diagnostics are zeroed. Returns false, changing nothing, when the
  /// symmetrised cov has no Cholesky factor or either is not finite.
  bool assign(const Vector& mean, const Matrix& cov) {
    Matrix symmetric = cov, factor;
    symmetrize(symmetric);
    if (!allFinite(mean) || !allFinite(symmetric) || !choleskyLower(symmetric, factor)) return false;
    mean_ = mean;
    covariance_ = symmetric;
    factor_ = factor;
    hasPoints_ = false;
    diagnostics_ = Diagnostics();
    return true;
  }

  // ---- One step: draw, propagate (the policy), predict or correct, settle, commit ------------------

  /// §1: the points of (mean, S Sᵀ) into workPoints(), from a lower factor S computed earlier (the
  /// committed factor, or another estimate's): nothing is factored here.
  Status draw(const Vector& mean, const Matrix& lowerFactor) {
    if (!allFinite(mean)) return Status::NotPositiveDefinite;
    drawSymmetricPoints<SigmaPoints::HasCenter>(mean, lowerFactor, sigmaPoints_.gamma(), workPoints_);
    return Status::Ok;
  }

  /// §2: x̂⁻ = Σ Wmᵢ χᵢ⁺, P⁻ = Σ Wcᵢ (χᵢ⁺ − x̂⁻)(χᵢ⁺ − x̂⁻)ᵀ + Q from the propagated workPoints(), into
  /// candidateMean() and candidateCovariance().
  void predict(const Matrix& processNoise) {
    weightedMean(workPoints_, sigmaPoints_.meanWeights(), candidateMean_);
    deviations_.noalias() = workPoints_.colwise() - candidateMean_;
    weightedOuterSum(deviations_, deviations_, sigmaPoints_.covarianceWeights(), candidateCovariance_);
    candidateCovariance_ += processNoise;
  }

  /// §3 from `points` about the prior (`priorMean`, `priorCov`) and their images `measured` = Yᵢ, into
  /// candidateMean(), candidateCovariance() and candidateDiagnostics(); on a status other than Ok the
  /// candidates are unspecified. With `present` (null: all present), the missing components get zero
  /// rows and columns in P_yy (one on its diagonal), in P_xy and in the innovation: the gain then has
  /// zero columns there and the update is exactly that of the reduced model. `gate` refuses an update
  /// whose NIS exceeds its threshold, before anything is computed from the gain.
  Status correct(const Points& points, const MeasPoints& measured, const Vector& priorMean, const Matrix& priorCov,
                 const MeasVector& y, const MeasMatrix& measurementNoise, const Mask* present, const Gate& gate) {
    if (!allFinite(measured)) return Status::NonFiniteResult;  // the model's g gave NaN or Inf
    Diagnostics& d = candidateDiagnostics_;
    MeasVector predictedMeasurement;
    weightedMean(measured, sigmaPoints_.meanWeights(), predictedMeasurement);  // ŷ
    measurementDeviations_.noalias() = measured.colwise() - predictedMeasurement;
    deviations_.noalias() = points.colwise() - priorMean;
    const auto& weights = sigmaPoints_.covarianceWeights();
    weightedOuterSum(measurementDeviations_, measurementDeviations_, weights, d.innovationCovariance);
    d.innovationCovariance += measurementNoise;                                   // P_yy
    weightedOuterSum(deviations_, measurementDeviations_, weights, gainFactor_);  // P_xy
    d.innovation = y - predictedMeasurement;
    int presentCount = M;
    if (present) {
      for (int j = 0; j < M; ++j) {
        if ((*present)(j)) continue;
        d.innovationCovariance.row(j).setZero();
        d.innovationCovariance.col(j).setZero();
        d.innovationCovariance(j, j) = Scalar(1);
        gainFactor_.col(j).setZero();
        d.innovation(j) = Scalar(0);  // y(j) may be NaN: overwrite, never multiply by 0
        --presentCount;
      }
    }

    if (!allFinite(d.innovationCovariance) || !choleskyLower(d.innovationCovariance, innovationFactor_))
      return Status::InnovationNotPositiveDefinite;
    // With P_yy = S Sᵀ, the gain is K = P_xy P_yy⁻¹ = U S⁻¹ with U = P_xy S⁻ᵀ, so that
    //   K ν = U w with w = S⁻¹ ν (the whitened innovation, whose |w|² is the NIS), and
    //   K P_yy Kᵀ = U Uᵀ:
    // one triangular solve for U instead of two for K, and a P that is symmetric as computed.
    MeasVector whitened = d.innovation;
    solveLowerInPlace(innovationFactor_, whitened);
    d.nis = whitened.squaredNorm();
    // An innovation or NIS that overflowed (a model returning huge values) is no measurement to use,
    // even when the gain is zero.
    if (!std::isfinite(d.nis) || !allFinite(d.innovation)) return Status::NonFiniteResult;
    if (presentCount > 0 && d.nis > gate.nisThreshold(presentCount - 1)) return Status::MeasurementRejected;
    whitenColumns(innovationFactor_, gainFactor_);  // P_xy → U
    candidateMean_ = priorMean;
    candidateMean_.noalias() += gainFactor_ * whitened;  // x̂ = x̂⁻ + K ν
    candidateCovariance_ = priorCov;
    candidateCovariance_.noalias() -= gainFactor_.lazyProduct(gainFactor_.transpose());  // P = P⁻ − K P_yy Kᵀ
    return Status::Ok;
  }

  /// What every step does with the covariance it is about to commit: symmetrise candidateCovariance(),
  /// check it has a Cholesky factor, repair it if not (covariance_repair.hpp). Ok, Repaired, or a
  /// refusal. Only a covariance accepted here is committed.
  Status settle(const CovarianceRepair<Scalar>& repair) { return guard_.settle(candidateCovariance_, repair); }

  /// Commits a time update that settle() accepted: its mean, covariance and factor, and its points.
  void commitPrediction() {
    points_ = workPoints_;
    hasPoints_ = true;
    commitCandidate();
  }
  /// Commits a measurement update that settle() accepted: its mean, covariance, factor and diagnostics.
  /// The points no longer describe the estimate.
  void commitCorrection() {
    diagnostics_ = candidateDiagnostics_;
    hasPoints_ = false;
    commitCandidate();
  }
  /// Commits a new mean alone (an open-loop propagation): P and its factor stay.
  void commitMean(const Vector& mean) {
    mean_ = mean;
    hasPoints_ = false;
  }

  Points& workPoints() { return workPoints_; }
  const Points& workPoints() const { return workPoints_; }
  MeasPoints& measuredPoints() { return measuredPoints_; }
  Vector& candidateMean() { return candidateMean_; }
  const Vector& candidateMean() const { return candidateMean_; }
  Matrix& candidateCovariance() { return candidateCovariance_; }
  const Matrix& candidateCovariance() const { return candidateCovariance_; }
  /// The factor of candidateCovariance() after settle() accepted it.
  const Matrix& candidateFactor() const { return guard_.factor(); }
  /// After correct() returned Ok: U = P_xy S⁻ᵀ and the lower Cholesky factor S of P_yy, so that the
  /// gain is K = U S⁻¹.
  const CrossMatrix& gainFactor() const { return gainFactor_; }
  const MeasMatrix& innovationFactor() const { return innovationFactor_; }

 private:
  void commitCandidate() {
    mean_ = candidateMean_;
    covariance_ = candidateCovariance_;
    factor_ = guard_.factor();
  }

  SigmaPoints sigmaPoints_;
  // Committed.
  Vector mean_ = Vector::Zero();
  Matrix covariance_ = Matrix::Zero();
  Matrix factor_ = Matrix::Zero();  // S with covariance_ = S Sᵀ
  Points points_ = Points::Zero();  // χᵢ⁺ of the last time update, used by the measurement update
  bool hasPoints_ = false;
  Diagnostics diagnostics_;
  // Workspace: a step computes here and commits only when the whole step succeeded. Zeroed once at
  // construction, so that copying a filter before its first step copies no indeterminate values.
  Points workPoints_ = Points::Zero();                     // drawn, then propagated in place
  MeasPoints measuredPoints_ = MeasPoints::Zero();         // Yᵢ = g(χᵢ⁺)
  Points deviations_ = Points::Zero();                     // χᵢ⁺ − x̂⁻
  MeasPoints measurementDeviations_ = MeasPoints::Zero();  // Yᵢ − ŷ
  CrossMatrix gainFactor_ = CrossMatrix::Zero();           // P_xy, then U = P_xy S⁻ᵀ
  MeasMatrix innovationFactor_ = MeasMatrix::Zero();       // S with P_yy = S Sᵀ
  Vector candidateMean_ = Vector::Zero();
  Matrix candidateCovariance_ = Matrix::Zero();
  Diagnostics candidateDiagnostics_;
  CovarianceGuard<Scalar, L> guard_;
};

// What a measurement update hands the parameter policy once the state's correction succeeded: the
// measurement, which components are present, the points' images Yᵢ, the prior mean, and the gain's
// factors U = P_xy S⁻ᵀ and S (P_yy = S Sᵀ).
template <class Model, class Settings, class Est>
struct Correction {
  const Model& model;
  const Settings& settings;
  const typename Est::MeasVector& y;
  const typename Est::Mask* present;
  const typename Est::MeasPoints& measured;
  const typename Est::Vector& priorMean;
  const typename Est::CrossMatrix& gainFactor;
  const typename Est::MeasMatrix& innovationFactor;
};

// ==== 3. The parameter policy =========================================================================
//
// How a filter estimates its parameters (none, augmented, MJUKF's eqs. 9–10, dual) is a policy object
// the engine holds and calls. Every member below is required: there are no defaults, so a misspelled
// or missing hook is a compile error naming it (checkParameterPolicy), never a hook silently not
// called. With Est the engine's Estimate, Step a TimeStep and Engine the filter:
//
//   template <class Step> Status predictParameters(const Step&, const Est& state);   before the state's points
//   template <class Step> void propagatePoints(const Step&, Points& points);          χᵢ⁺ = Φ(χᵢ), in place
//   template <class Step> Vector propagateMean(const Step&, const Vector& mean);      the open-loop mean
//   void measurePoints(const Model&, const Points& points, MeasPoints& measured);      Yᵢ = g(χᵢ)
//   template <class Engine> Status update(Engine&, const Meas& y, const Mask* present);  the order of
//                                                    the measurement update (Engine::correctState, or the
//                                                    dual's: parameters first)
//   Status correctParameters(const Correction&);      after the state's correction, into candidates
//   void constrainMean(Vector& candidateMean);        on the settled candidate mean (bounds)
//   void commitPrediction(); void commitCorrection(); void commitOpenLoop(Scalar interval);

#define MJUKF_POLICY_HAS(Name, Call)            \
  template <class P, class = void>              \
  struct PolicyHas_##Name : std::false_type {}; \
  template <class P>                            \
  struct PolicyHas_##Name<P, std::void_t<decltype(Call)>> : std::true_type {};
MJUKF_POLICY_HAS(predictParameters,
                 std::declval<P&>().predictParameters(std::declval<const typename P::CheckStep&>(),
                                                      std::declval<const typename P::CheckEstimate&>()))
MJUKF_POLICY_HAS(propagatePoints,
                 std::declval<P&>().propagatePoints(std::declval<const typename P::CheckStep&>(),
                                                    std::declval<typename P::CheckEstimate::Points&>()))
MJUKF_POLICY_HAS(propagateMean,
                 std::declval<P&>().propagateMean(std::declval<const typename P::CheckStep&>(),
                                                  std::declval<const typename P::CheckEstimate::Vector&>()))
MJUKF_POLICY_HAS(measurePoints,
                 std::declval<P&>().measurePoints(std::declval<const typename P::CheckModel&>(),
                                                  std::declval<const typename P::CheckEstimate::Points&>(),
                                                  std::declval<typename P::CheckEstimate::MeasPoints&>()))
MJUKF_POLICY_HAS(correctParameters,
                 std::declval<P&>().correctParameters(std::declval<const typename P::CheckCorrection&>()))
MJUKF_POLICY_HAS(constrainMean, std::declval<P&>().constrainMean(std::declval<typename P::CheckEstimate::Vector&>()))
MJUKF_POLICY_HAS(commitPrediction, std::declval<P&>().commitPrediction())
MJUKF_POLICY_HAS(commitCorrection, std::declval<P&>().commitCorrection())
MJUKF_POLICY_HAS(commitOpenLoop, std::declval<P&>().commitOpenLoop(typename P::CheckEstimate::Vector::Scalar()))
#undef MJUKF_POLICY_HAS

// Checks, member by member, that `Policy` supplies every hook the engine calls, with the arguments the
// engine passes (the types it is checked with are the policy's Check* aliases, which ParameterPolicy
// declares). `update` is a template on the engine and is checked where the engine calls it.
template <class Policy>
constexpr bool checkParameterPolicy() {
  static_assert(PolicyHas_predictParameters<Policy>::value,
                "parameter policy: missing member predictParameters(const Step&, const Estimate&) -> Status");
  static_assert(PolicyHas_propagatePoints<Policy>::value,
                "parameter policy: missing member propagatePoints(const Step&, Points&)");
  static_assert(PolicyHas_propagateMean<Policy>::value,
                "parameter policy: missing member propagateMean(const Step&, const Vector&) -> Vector");
  static_assert(PolicyHas_measurePoints<Policy>::value,
                "parameter policy: missing member measurePoints(const Model&, const Points&, MeasPoints&)");
  static_assert(PolicyHas_correctParameters<Policy>::value,
                "parameter policy: missing member correctParameters(const Correction&) -> Status");
  static_assert(PolicyHas_constrainMean<Policy>::value, "parameter policy: missing member constrainMean(Vector&)");
  static_assert(PolicyHas_commitPrediction<Policy>::value, "parameter policy: missing member commitPrediction()");
  static_assert(PolicyHas_commitCorrection<Policy>::value, "parameter policy: missing member commitCorrection()");
  static_assert(PolicyHas_commitOpenLoop<Policy>::value,
                "parameter policy: missing member commitOpenLoop(Scalar interval)");
  return true;
}

// The base of every parameter policy: the types its hooks use, and the types it is checked with. It
// supplies no hook.
template <class Model, class Integrator, class Settings, class Est>
struct ParameterPolicy {
  using Scalar = typename Model::Scalar;
  using State = typename Model::State;
  using Param = typename Model::Param;
  using Meas = typename Model::Meas;
  using Input = typename Model::Input;
  using Vector = typename Est::Vector;  // the estimated vector (x, or [x; θ])
  using Points = typename Est::Points;  // its sigma points, one per column
  using MeasPoints = typename Est::MeasPoints;
  using Mask = typename Est::Mask;
  using CorrectionOf = Correction<Model, Settings, Est>;
  static constexpr int StateDim = Model::StateDim, ParamDim = Model::ParamDim, MeasDim = Model::MeasDim;
  static constexpr int Count = Est::Count;  // the number of sigma points

  using CheckModel = Model;
  using CheckEstimate = Est;
  using CheckStep = TimeStep<Model, Integrator, HeldInput<Model>, Settings>;
  using CheckCorrection = Correction<Model, Settings, Est>;
};

/// \endcond

// ==== 4. The engine ===================================================================================

// The status of a step made of two parts that were both taken: Repaired if either was.
constexpr Status combineTaken(Status a, Status b) { return a == Status::Ok ? b : a; }

/// The per-step calls every filter shares: `Ukf`, `JointUkf`, `ModifiedJointUkf` and `DualUkf` derive
/// from this engine and inherit its public members. Each call returns a Status; one other than Ok or
/// Repaired leaves the filter exactly as it was (docs/robustness.md). `L` is the dimension of the
/// vector the filter draws sigma points for; `Policy` is how it estimates parameters (section 3 above).
template <class Filter, class Model_, class Integrator_, class Settings_, class Policy, int L,
          class PointSet = MerweScaled>
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
  /// The sigma points the filter draws (sigma_points.hpp).
  using SigmaPoints = typename PointSet::template Set<Scalar, L>;
  /// The number of sigma points of the filter's estimate.
  static constexpr int SigmaPointCount = SigmaPoints::Count;

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
  Status measurementUpdate(const Meas& y) { return update(y, nullptr); }

  /// Measurement update with only the components where `present` is true (missing channels; the
  /// others, NaN included, are ignored): exactly the update of the model reduced to those components,
  /// with R reduced likewise. A mask with nothing present leaves the estimate as it was.
  Status measurementUpdate(const Meas& y, const MeasurementMask<MeasDim>& present) { return update(y, &present); }

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

#if MJUKF_EXCEPTIONS
  /// The filter built from these initial values and settings; throws std::invalid_argument naming the
  /// first invalid one (Filter::validate). Without exceptions, build it with `create`. For Ukf,
  /// `initialParameters` are its fixed parameters. Each filter inherits this constructor.
  UnscentedEngine(const Model& model, const State& initialState, const Param& initialParameters,
                  const Settings& settings, const Integrator& integrator = Integrator())
      : UnscentedEngine(throwIfInvalid(Filter::validate(initialState, initialParameters, settings)), model,
                        initialState, initialParameters, settings, integrator) {}
#endif

  /// Innovation, its covariance and the NIS of the last successful measurement update.
  const Diagnostics& lastUpdate() const { return estimate_.diagnostics(); }
  /// True when the sigma points of the last time update are still the filter's.
  bool hasPropagatedPoints() const { return estimate_.hasPoints(); }
  /// The model the filter was built with.
  const Model& model() const { return model_; }
  /// The integrator the filter was built with.
  const Integrator& integrator() const { return integrator_; }
  /// The settings the filter was built with (validated at construction).
  const Settings& settings() const { return settings_; }

  /// \cond INTERNAL
 protected:
  using Est = Estimate<Scalar, L, MeasDim, PointSet>;
  using Vector = typename Est::Vector;
  using Matrix = typename Est::Matrix;
  using Points = typename Est::Points;
  using MeasPoints = typename Est::MeasPoints;
  using Mask = MeasurementMask<MeasDim>;
  static_assert(checkParameterPolicy<Policy>());
  friend Policy;
  using PolicyType = Policy;

  // The settings every filter shares, checked in this order after the filter's own initial values:
  // the sigma points, P₀, Q, R, the repair and the gate. The first error, naming the setting, or none.
  static SettingsError validateSettings(const char* owner, const Settings& settings) {
    if (SettingsError e = SigmaPoints::validate(settings.sigmaPoints)) return e;
    if (SettingsError e = requireCommittableCovariance(owner, "initialCovariance (P0)", settings.initialCovariance))
      return e;
    if (SettingsError e = requirePositiveSemiDefinite(owner, "processNoise (Q)", settings.processNoise)) return e;
    if (SettingsError e = requirePositiveDefinite(owner, "measurementNoise (R)", settings.measurementNoise)) return e;
    if (SettingsError e = validateRepair(owner, settings.repair)) return e;
    return validateGate(owner, settings.gate);
  }

  // The filter from values its validate() accepted (it ends with validateSettings): the estimate starts
  // from Filter::initialMean(x̂₀, θ̂₀) and P₀, the policy from (settings, θ̂₀); nothing here can fail.
  UnscentedEngine(Validated, const Model& model, const State& initialState, const Param& initialParameters,
                  const Settings& settings, const Integrator& integrator)
      : model_(model),
        integrator_(integrator),
        settings_(settings),
        estimate_(Validated{}, settings.sigmaPoints),
        policy_(settings, initialParameters) {
    // symmetrised, as every committed P is
    estimate_.assign(Filter::initialMean(initialState, initialParameters), settings.initialCovariance);
  }

  // The covariance argument of reset() checked like P₀; reset() changes nothing when it fails. The mean
  // is checked by the filter, which names its parts.
  static SettingsError checkResetCovariance(const char* owner, const Matrix& covariance) {
    return requireCommittableCovariance(owner, "covariance", covariance);
  }
  // Commits a reset that checkResetCovariance() accepted: cannot fail.
  void resetEstimate(const Vector& mean, const Matrix& covariance) { estimate_.assign(mean, covariance); }

  // ---- The skeleton --------------------------------------------------------------------------------

  template <class InputSource>
  using Step = TimeStep<Model, Integrator, InputSource, Settings>;

  template <class InputSource>
  Status timeUpdateWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = checkStep(t, h, steps); s != Status::Ok) return s;
    const Step<InputSource> step{model_, integrator_, settings_, input, t, h, steps};
    const Status parameters = policy_.predictParameters(step, estimate_);
    if (!taken(parameters)) return parameters;
    const Status settled = predict(step, estimate_.mean(), estimate_.factor());
    if (!taken(settled)) return settled;
    policy_.constrainMean(estimate_.candidateMean());
    estimate_.commitPrediction();
    policy_.commitPrediction();
    return combineTaken(settled, parameters);
  }

  // §2 from (mean, S Sᵀ) over `step`, into the estimate's candidates: draw, propagate (the policy),
  // predict, settle. The time update's, and the dual filter's second prediction of a step.
  template <class StepType>
  Status predict(const StepType& step, const Vector& mean, const Matrix& lowerFactor) {
    if (const Status s = estimate_.draw(mean, lowerFactor); s != Status::Ok) return s;
    policy_.propagatePoints(step, estimate_.workPoints());
    if (!allFinite(estimate_.workPoints())) return Status::NonFiniteResult;
    estimate_.predict(settings_.processNoise);
    if (!allFinite(estimate_.candidateMean())) return Status::NonFiniteResult;
    return estimate_.settle(settings_.repair);
  }

  template <class InputSource>
  Status propagateMeanWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = checkStep(t, h, steps); s != Status::Ok) return s;
    const Step<InputSource> step{model_, integrator_, settings_, input, t, h, steps};
    const Vector mean = policy_.propagateMean(step, estimate_.mean());
    if (!allFinite(mean)) return Status::NonFiniteResult;
    estimate_.commitMean(mean);
    policy_.commitOpenLoop(step.interval());
    return Status::Ok;
  }

  // The measurement update: the policy says in which order its parts run (every filter but the dual
  // one calls correctState).
  Status update(const Meas& y, const Mask* present) {
    if (!presentComponentsFinite(y, present)) return Status::NonFiniteMeasurement;
    return policy_.update(static_cast<Filter&>(*this), y, present);
  }

  // §3 about the committed estimate, from the points of the last time update (or points drawn now).
  Status correctState(const Meas& y, const Mask* present) {
    const bool drawPoints = settings_.redrawPointsForUpdate || !estimate_.hasPoints();
    if (drawPoints)
      if (const Status s = estimate_.draw(estimate_.mean(), estimate_.factor()); s != Status::Ok) return s;
    return correctAndCommit(drawPoints ? estimate_.workPoints() : estimate_.points(), estimate_.mean(),
                            estimate_.covariance(), y, present);
  }

  // §3 from `points` about a prior, then the policy's parameter correction, then the checks and the
  // commit of both.
  Status correctAndCommit(const Points& points, const Vector& priorMean, const Matrix& priorCovariance, const Meas& y,
                          const Mask* present) {
    policy_.measurePoints(model_, points, estimate_.measuredPoints());
    if (const Status s = estimate_.correct(points, estimate_.measuredPoints(), priorMean, priorCovariance, y,
                                           settings_.measurementNoise, present, settings_.gate);
        s != Status::Ok)
      return s;
    const Status parameters = policy_.correctParameters(
        Correction<Model, Settings, Est>{model_, settings_, y, present, estimate_.measuredPoints(), priorMean,
                                         estimate_.gainFactor(), estimate_.innovationFactor()});
    if (!taken(parameters)) return parameters;
    if (!allFinite(estimate_.candidateMean())) return Status::NonFiniteResult;
    const Status settled = estimate_.settle(settings_.repair);
    if (!taken(settled)) return settled;
    policy_.constrainMean(estimate_.candidateMean());
    estimate_.commitCorrection();
    policy_.commitCorrection();
    return combineTaken(settled, parameters);
  }

  Model model_;
  Integrator integrator_;
  Settings settings_;
  Est estimate_;
  Policy policy_;

 private:
  // The input of a model without one (InputDim = 0): an empty vector, held over every step.
  static inline const Input noInput_{};
  /// \endcond
};

/// \cond INTERNAL
// The engine of filter `Filter` over `Model`, with the parameter policy template `PolicyOf` (given the
// model, stepper, settings and estimate) and an estimate of dimension L drawn with `PointSet`.
template <class Filter, class Model, class Integrator, class Settings,
          template <class, class, class, class> class PolicyOf, int L, class PointSet>
using EngineOf = UnscentedEngine<
    Filter, Model, Integrator, Settings,
    PolicyOf<Model, Integrator, Settings, Estimate<typename Model::Scalar, L, Model::MeasDim, PointSet>>, L, PointSet>;

/// \endcond

}  // namespace mjukf::detail
