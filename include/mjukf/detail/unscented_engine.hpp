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

#include <limits>
#include <type_traits>

#include <Eigen/Core>

#include "mjukf/covariance_form.hpp"
#include "mjukf/covariance_repair.hpp"
#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/diagnostics.hpp"
#include "mjukf/features.hpp"
#include "mjukf/filter_settings.hpp"
#include "mjukf/health.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/model.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/status.hpp"

/// \cond INTERNAL
// A function kept out of its callers, so that its frame does not join theirs.
#if defined(_MSC_VER) && !defined(__clang__)
#define MJUKF_NOINLINE __declspec(noinline)
#else
#define MJUKF_NOINLINE __attribute__((noinline))
#endif
/// \endcond

namespace mjukf::detail {

/// \cond INTERNAL

// ==== 1. Propagating a model over a step ==============================================================

// The model's own input signal u(t), evaluated at every stage time: for the open-loop mean, one point.
template <class Model>
struct SignalInput {
  const Model& model;
  mutable bool nonFinite = false;  // whether input(t) gave NaN or ±Inf at a time it was asked for
  typename Model::Input operator()(typename Model::Scalar t) const {
    typename Model::Input u = model.input(t);
    nonFinite = nonFinite || !allFinite(u);
    return u;
  }
  bool allValuesFinite() const { return !nonFinite; }
};

// The model's own input signal u(t) for a time update, which propagates all its sigma points over the
// same stage times: the first few distinct times and their values are kept, so u(t) is evaluated once
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
    // A miss: u(t) into a free slot, or into the last, which is never searched, once Kept are taken (its
    // reference is read at once, by the model's derivative).
    const int slot = size_ < Kept ? size_++ : Kept;
    times_[slot] = t;
    values_[slot] = model_.input(t);
    nonFinite_ = nonFinite_ || !allFinite(values_[slot]);
    return hit(slot);
  }

  // Whether every value input(t) gave in this call was finite (checked once per distinct time).
  bool allValuesFinite() const { return !nonFinite_; }

 private:
  // Slots: Kept distinct times, the 1 + 2 k stage times of k RK4 or I-TR-BDF2 steps for k up to 3 (a
  // time update subdivided into that many steps), and one for a value not kept. Past them a value is not
  // kept rather than replacing one: the points ask for the times in the same order, so a replacement
  // would evict each value just before the next point asked for it, and every request would miss (the
  // n = 2 chain's JUKF with 4 steps per time update took 1.5 times the instructions that way).
  static constexpr int Slots = 8;
  static constexpr int Kept = Slots - 1;

  const Input& hit(int slot) const {
    hint_ = slot + 1 < size_ ? slot + 1 : 0;
    return values_[slot];
  }

  const Model& model_;
  mutable Scalar times_[Slots];  // the first size_ are kept; the last is the value not kept
  mutable Input values_[Slots];
  mutable int size_ = 0;
  mutable int hint_ = 0;
  mutable bool nonFinite_ = false;
};

// An input held constant over the step (zero-order hold), for inputs known only as samples.
template <class Model>
struct HeldInput {
  const typename Model::Input& value;
  const typename Model::Input& operator()(typename Model::Scalar /*t*/) const { return value; }
  bool allValuesFinite() const { return true; }  // the caller checked it before the step
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
    return settleSymmetric(cov, repair);
  }
  // settle() of a cov that is exactly symmetric already, as every candidate of a step is formed (one
  // triangle computed and mirrored; S Sᵀ in the square-root form): the symmetrisation would change
  // nothing, and at L = 6 it cost about as much as the finiteness check and half the factorisation.
  // (settle() is for a matrix of unknown symmetry.)
  Status settleSymmetric(Matrix& cov, const CovarianceRepair<Scalar>& repair) {
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

/// How the sigma points of a measurement update relate to its prior (x̂⁻, P⁻ = S⁻ S⁻ᵀ): what the
/// square-root form's posterior factor may rely on (docs/algorithms.md §10; the full form reads none
/// of it). With Δχᵢ = χᵢ − x̂⁻:
enum class PriorPoints {
  /// drawn from (x̂⁻, S⁻) by the symmetric draw: x̂⁻ is their weighted mean and Σ Wcᵢ Δχᵢ Δχᵢᵀ = P⁻;
  Drawn,
  /// propagated, and (x̂⁻, P⁻) predicted from exactly these points, x̂⁻ = Σ Wmᵢ χᵢ and
  /// P⁻ = Σ Wcᵢ Δχᵢ Δχᵢᵀ + Q, neither repaired nor clamped afterwards;
  Predicted,
  /// neither (a mean clamped to parameter bounds, a repaired P⁻): only P⁻ = S⁻ S⁻ᵀ is known.
  Other,
};

/// The prior of a measurement update: its mean, covariance and lower factor, and how the points the
/// update measures relate to them.
template <class Vector, class Matrix>
struct PriorOf {
  const Vector& mean;
  const Matrix& covariance;
  const Matrix& factor;
  PriorPoints points;
};

// What only the square-root form keeps: an empty base of the estimate in the full form (so the full
// form's estimate is as large as before), in the square-root form the factors of the noises (computed
// once, at construction), √|Wcᵢ|, the candidate factor and where it came from, how the points relate to
// the estimates, and the workspace of the Householder triangularisations.
template <class Scalar, int L, int M, int Count, class Form>
struct SquareRootPart {};

template <class Scalar, int L, int M, int Count>
struct SquareRootPart<Scalar, L, M, Count, SquareRootCovariance> {
  using Matrix = Eigen::Matrix<Scalar, L, L>;
  using MeasMatrix = Eigen::Matrix<Scalar, M, M>;
  // Where the candidate's factor and covariance come from.
  enum class Candidate {
    Factor,               // S obtained without subtraction; P = S Sᵀ is formed when it is settled
    FactorAndCovariance,  // S and P both given (a correction that changed nothing)
    CovarianceOnly,       // S could not be obtained: the full form's P, settled by the CovarianceGuard
  };

  Matrix processNoiseRoot = Matrix::Zero();              // G with G Gᵀ = Q
  MeasMatrix measurementNoiseRoot = MeasMatrix::Zero();  // the lower Cholesky factor of R
  Eigen::Matrix<Scalar, Count, 1> weightRoots = Eigen::Matrix<Scalar, Count, 1>::Zero();  // √|Wcᵢ|
  Matrix candidateFactor = Matrix::Zero();
  Candidate candidate = Candidate::CovarianceOnly;
  Status settled = Status::Ok;                   // what the last settle() returned
  PriorPoints workPrior = PriorPoints::Other;    // the work points and the candidate (mean, factor)
  PriorPoints pointsPrior = PriorPoints::Other;  // the committed points and the committed estimate
  Eigen::Matrix<Scalar, L, 1> predictedMean = Eigen::Matrix<Scalar, L, 1>::Zero();  // Σ Wmᵢ χᵢ, unclamped
  // Workspace.
  Eigen::Matrix<Scalar, L, Count + L> predictionStack = Eigen::Matrix<Scalar, L, Count + L>::Zero();  // [√Wc Δχ | G]
  Eigen::Matrix<Scalar, M, Count + M> innovationStack = Eigen::Matrix<Scalar, M, Count + M>::Zero();  // [√Wc ΔY | √R]
  Eigen::Matrix<Scalar, L, Count + L + M> posteriorStack =  // [√Wc (Δχ − K ΔY) | G or 0 | K √R]
      Eigen::Matrix<Scalar, L, Count + L + M>::Zero();
  Eigen::Matrix<Scalar, L, M> gain = Eigen::Matrix<Scalar, L, M>::Zero();  // K = U S_y⁻¹
  MeasMatrix maskedNoise = MeasMatrix::Zero();                             // R' of a masked update
  MeasMatrix maskedNoiseRoot = MeasMatrix::Zero();                         // its lower Cholesky factor
  bool noiseRootValid = true;  // the factor of R (or R') of the last correction exists
};

// One unscented estimate of an L-vector measured through M components: the committed mean,
// covariance, its lower factor and propagated sigma points, the workspace a step computes into, and
// the arithmetic of docs/algorithms.md §1–3 in the covariance form `Form` (covariance_form.hpp; the
// square-root form's is §10, in `if constexpr` branches beside the full form's). A step writes only to
// the candidates here and commits them with one call, so "the stored factor is a lower factor of the
// committed P" is kept by this class alone: nothing else can assign P. In the full form the factor is
// the Cholesky factor of P; in the square-root form it is the S the step propagated, and P = S Sᵀ is
// formed from it once per committed step (L²(L + 1)/2 multiply-adds) so that covariance() can be
// returned by reference. The filters' estimate is one; the dual filter's parameters are a second.
template <class Scalar, int L, int M, class PointSet = MerweScaled, class Form = FullCovariance>
class Estimate : private SquareRootPart<Scalar, L, M, PointSet::template Set<Scalar, L>::Count, Form> {
  static_assert(isCovarianceForm<Form>, "the covariance form is FullCovariance or SquareRootCovariance");
  static constexpr bool SquareRoot = isSquareRootForm<Form>;

 public:
  using PointSetType = PointSet;
  using FormType = Form;
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
  using Prior = PriorOf<Vector, Matrix>;

  /// From sigma-point parameters that SigmaPoints::validate accepted (the filter's validate()) and the
  /// process and measurement noise Q and R the steps will pass (Q symmetric positive semi-definite,
  /// R positive definite). The square-root form keeps their factors, G with G Gᵀ = Q (psdSquareRoot: Q
  /// may be singular or zero) and the Cholesky factor of R; the full form reads Q and R where a step
  /// passes them and keeps nothing.
  Estimate(Validated, const SigmaPointParameters<Scalar>& parameters, const Matrix& processNoise,
           const MeasMatrix& measurementNoise)
      : sigmaPoints_(Validated{}, parameters) {
    if constexpr (SquareRoot) {
      sr().processNoiseRoot = psdSquareRoot(processNoise);
      if (!choleskyLower(measurementNoise, sr().measurementNoiseRoot))
        sr().measurementNoiseRoot = psdSquareRoot(measurementNoise);
      sr().weightRoots = sigmaPoints_.covarianceWeights().cwiseAbs().cwiseSqrt();
    } else {
      (void)processNoise;
      (void)measurementNoise;
    }
  }

  // ---- The committed estimate ----------------------------------------------------------------------
  const Vector& mean() const { return mean_; }
  const Matrix& covariance() const { return covariance_; }
  /// A lower factor of covariance(): its Cholesky factor (full form), or the propagated S of which it
  /// is S Sᵀ (square-root form).
  const Matrix& factor() const { return factor_; }
  /// The points of the last time update, while they are still the estimate's (hasPoints()).
  const Points& points() const { return pointSets_[workSet_ ^ 1]; }
  bool hasPoints() const { return hasPoints_; }
  // The measurement noise of the next correct() when it is not the one given at construction (the dual
  // filter's parameter filter observes through the state's uncertainty, which changes every step). The
  // full form reads it from correct()'s argument; the square-root form factors it here. False when it
  // has no Cholesky factor (the square-root form's factor is then unspecified until the next call).
  bool useMeasurementNoise(const MeasMatrix& measurementNoise) {
    if constexpr (SquareRoot)
      return choleskyLower(measurementNoise, sr().measurementNoiseRoot);
    else
      return static_cast<void>(measurementNoise), true;
  }
  const Diagnostics& diagnostics() const { return diagnostics_; }
  /// The diagnostics of the measurement update in progress (after correct(), before its commit).
  const Diagnostics& candidateDiagnostics() const { return candidateDiagnostics_; }
  const SigmaPoints& sigmaPoints() const { return sigmaPoints_; }
  /// The committed estimate as the prior of a measurement update: of its own points() (`drawnNow`
  /// false, hasPoints()), or of points just drawn from it (true).
  Prior prior(bool drawnNow) const {
    PriorPoints points = PriorPoints::Other;
    if constexpr (SquareRoot) points = drawnNow ? PriorPoints::Drawn : sr().pointsPrior;
    return Prior{mean_, covariance_, factor_, points};
  }

  /// Makes (mean, cov) the estimate, with cov symmetrised as every committed P is, and forgets the
  /// propagated points; the diagnostics are zeroed. Returns false, changing nothing, when the
  /// symmetrised cov has no Cholesky factor or either is not finite. Both forms keep that factor.
  bool assign(const Vector& mean, const Matrix& cov) {
    Matrix symmetric = cov, factor;
    symmetrize(symmetric);
    if (!allFinite(mean) || !allFinite(symmetric) || !choleskyLower(symmetric, factor)) return false;
    mean_ = mean;
    covariance_ = symmetric;
    factor_ = factor;
    hasPoints_ = false;
    deviationsHold_ = Deviations::Other;
    diagnostics_ = Diagnostics();
    return true;
  }

  // ---- One step: draw, propagate (the policy), predict or correct, settle, commit ------------------

  /// §1: the points of (mean, S Sᵀ) into workPoints(), from a lower factor S computed earlier (the
  /// committed factor, or another estimate's): nothing is factored here.
  Status draw(const Vector& mean, const Matrix& lowerFactor) {
    if (!allFinite(mean)) return Status::NotPositiveDefinite;
    drawSymmetricPoints<SigmaPoints::HasCenter>(mean, lowerFactor, sigmaPoints_.gamma(), workPoints());
    if constexpr (SquareRoot) sr().workPrior = PriorPoints::Drawn;
    return Status::Ok;
  }

  /// §2: x̂⁻ = Σ Wmᵢ χᵢ⁺, P⁻ = Σ Wcᵢ (χᵢ⁺ − x̂⁻)(χᵢ⁺ − x̂⁻)ᵀ + Q from the propagated workPoints(), into
  /// candidateMean() and candidateCovariance(). `floor` (may be null) is a covariance a policy knows the
  /// prior's error to have (the MJUKF's, with the parameters' uncertainty, docs/algorithms.md §5.2):
  /// P⁻ is raised to cover it, P⁻ += E Eᵀ with E Eᵀ the positive semi-definite part of floor − P⁻, so
  /// that P⁻ ⪰ floor and P⁻ is unchanged where it already covers it. E enters P⁻ as Q does: the
  /// measurement update's P_xy and P_yy still come from the propagated points (unless
  /// redrawPointsForUpdate). Square-root form (§10): S⁻ from [√Wcᵢ (χᵢ⁺ − x̂⁻) for Wcᵢ ≥ 0 | G] by
  /// Householder, then a rank-one downdate by √|Wcᵢ| (χᵢ⁺ − x̂⁻) for each Wcᵢ < 0, then with a floor S⁻
  /// from [S⁻ | E] (and the prior's points count as Other: the posterior is a downdate of S⁻); when a
  /// factor fails, the full form's P⁻ for settle() to check and repair.
  /// `MayRaise` false (a policy whose priorCovarianceFloor() is always null): the raise is not compiled
  /// in, so that such a filter's code holds no positive part (from n = 5 Eigen's eigensolver, which
  /// links malloc into a firmware image).
  template <bool MayRaise = true>
  void predict(const Matrix& processNoise, const Matrix* floor = nullptr) {
    weightedMean(workPoints(), sigmaPoints_.meanWeights(), candidateMean_);
    deviationsFrom(workPoints(), candidateMean_, deviations_);
    deviationsHold_ = Deviations::OfWorkPoints;
    if constexpr (SquareRoot) {
      sr().predictedMean = candidateMean_;
      sr().workPrior = floor ? PriorPoints::Other : PriorPoints::Predicted;
      sr().predictionStack.template rightCols<L>() = sr().processNoiseRoot;
      bool factored = weightedFactor(deviations_, sr().predictionStack, sr().candidateFactor);
      if constexpr (MayRaise) factored = factored && (!floor || raiseFactorToFloor(*floor));
      if (factored) {
        sr().candidate = SquareRootPart_::Candidate::Factor;
        return;
      }
      sr().candidate = SquareRootPart_::Candidate::CovarianceOnly;
    }
    // One triangle of Σ Wcᵢ Δχᵢ Δχᵢᵀ + Q, mirrored: exactly symmetric (Q enters by its lower triangle).
    weightedCovarianceLower(deviations_, sigmaPoints_.covarianceWeights(), candidateCovariance_);
    candidateCovariance_ += processNoise;
    mirrorLowerTriangle(candidateCovariance_);
    if constexpr (MayRaise)
      if (floor) raiseToFloor(*floor, candidateCovariance_);
  }

  /// E with E Eᵀ the positive semi-definite part of floor − P (1-Lipschitz in both: the rounding of the
  /// difference is not amplified); false when the difference is not finite.
  static bool shortfallFactor(const Matrix& floor, const Matrix& covariance, Matrix& added) {
    Matrix shortfall = floor - covariance;
    symmetrize(shortfall);
    return positivePartFactor(shortfall, added);
  }
  /// P += E Eᵀ (shortfallFactor), exactly symmetric as P was. A non-finite difference leaves P as it is,
  /// for settle() to judge.
  static void raiseToFloor(const Matrix& floor, Matrix& covariance) {
    Matrix added;
    if (!shortfallFactor(floor, covariance, added)) return;
    covariance.noalias() += added * added.transpose();
    mirrorLowerTriangle(covariance);
  }
  /// The square-root form's raiseToFloor: E from P⁻ = S⁻ S⁻ᵀ, then S⁻ from [S⁻ | E] by one
  /// triangularisation. In a function of its own, so that the filters without a floor do not carry its
  /// stack in their frame.
  template <class F = Form>
  MJUKF_NOINLINE bool raiseFactorToFloor(const Matrix& floor) {
    static_assert(isSquareRootForm<F>);
    Matrix covariance, added;
    outerOfLower(sr().candidateFactor, covariance);
    if (!shortfallFactor(floor, covariance, added)) return false;
    Eigen::Matrix<Scalar, L, 2 * L> stack;
    stack.template leftCols<L>() = sr().candidateFactor;
    stack.template rightCols<L>() = added;
    return lowerFactorOfOuter(stack, sr().candidateFactor);
  }

  /// The dual filter's parameter time update (docs/algorithms.md §9), a random walk with forgetting:
  /// x̂⁻ = x̂, P⁻ = P / λ + Q into the candidates. Square-root form: S⁻ from [S / √λ | G] by Householder,
  /// or the full form's P⁻ when that fails.
  void predictRandomWalk(Scalar forgetting, const Matrix& processNoise) {
    candidateMean_ = mean_;
    deviationsHold_ = Deviations::Other;
    if constexpr (SquareRoot) {
      sr().workPrior = PriorPoints::Other;  // no points yet: the caller draws them from the candidate
      Eigen::Matrix<Scalar, L, 2 * L> stack;
      stack.template leftCols<L>() = factor_ / std::sqrt(forgetting);
      stack.template rightCols<L>() = sr().processNoiseRoot;
      if (lowerFactorOfOuter(stack, sr().candidateFactor)) {
        sr().candidate = SquareRootPart_::Candidate::Factor;
        return;
      }
      sr().candidate = SquareRootPart_::Candidate::CovarianceOnly;
    }
    candidateCovariance_ = covariance_ / forgetting + processNoise;
    mirrorLowerTriangle(candidateCovariance_);  // exactly symmetric, as settle() takes it
  }

  /// §3 from `points` about `prior` and their images `measured` = Yᵢ, into candidateMean(),
  /// candidateCovariance() and candidateDiagnostics(); on a status other than Ok the candidates are
  /// unspecified. With `present` (null: all present), the missing components get zero rows and columns
  /// in P_yy (one on its diagonal), in P_xy and in the innovation: the gain then has zero columns there
  /// and the update is exactly that of the reduced model. `gate` refuses an update whose NIS exceeds
  /// its threshold, before anything is computed from the gain. The square-root form (§10) factors P_yy
  /// by Householder as P⁻ in predict(), and computes the posterior factor without subtracting
  /// covariances where the prior's points allow it (prior.points Drawn or Predicted), by downdates of
  /// S⁻ otherwise; when a factor cannot be obtained so, it falls back to the full form's matrix.
  Status correct(const Points& points, const MeasPoints& measured, const Prior& prior, const MeasVector& y,
                 const MeasMatrix& measurementNoise, const Mask* present, const Gate& gate) {
    // The model's g gave NaN or ±Inf: with every component present this shows as P_yy without a factor
    // (a non-finite Yᵢ makes its row of P_yy NaN), so it is told apart only on that path, below.
    if (present && !allFinite(measured)) return Status::NonFiniteResult;
    Diagnostics& d = candidateDiagnostics_;
    MeasVector predictedMeasurement;
    weightedMean(measured, sigmaPoints_.meanWeights(), predictedMeasurement);  // ŷ
    deviationsFrom(measured, predictedMeasurement, measurementDeviations_);
    // Δχᵢ = χᵢ⁺ − x̂⁻: still in deviations_ when these are the committed points about the committed mean
    // as the time update formed them (its predict(), and a mean no policy moved since).
    const bool formed =
        deviationsHold_ == Deviations::OfCommittedPoints && &points == &this->points() && &prior.mean == &mean_;
    if (!formed) deviationsFrom(points, prior.mean, deviations_);
    deviationsHold_ = Deviations::Other;  // the square-root posterior writes Δχᵢ − K ΔYᵢ here
    const auto& weights = sigmaPoints_.covarianceWeights();
    if constexpr (!SquareRoot) {
      weightedCovariance(measurementDeviations_, weights, d.innovationCovariance);
      d.innovationCovariance += measurementNoise;  // P_yy
    }
    weightedOuterSum(deviations_, measurementDeviations_, weights, gainFactor_);  // P_xy
    d.innovation = y - predictedMeasurement;
    int presentCount = M;
    if (present) {
      for (int j = 0; j < M; ++j) {
        if ((*present)(j)) continue;
        if constexpr (SquareRoot) {
          measurementDeviations_.row(j).setZero();  // P_yy's row and column j are made by innovationFactor()
        } else {
          d.innovationCovariance.row(j).setZero();
          d.innovationCovariance.col(j).setZero();
          d.innovationCovariance(j, j) = Scalar(1);
        }
        gainFactor_.col(j).setZero();
        d.innovation(j) = Scalar(0);  // y(j) may be NaN: overwrite, never multiply by 0
        --presentCount;
      }
    }

    bool factored;
    if constexpr (SquareRoot)
      factored = squareRootInnovationFactor(measurementNoise, present, presentCount);
    else
      factored = choleskyLower(d.innovationCovariance, innovationFactor_);  // fails on NaN and ±Inf too
    if (!factored) return allFinite(measured) ? Status::InnovationNotPositiveDefinite : Status::NonFiniteResult;
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
    candidateMean_ = prior.mean;
    candidateMean_.noalias() += gainFactor_ * whitened;  // x̂ = x̂⁻ + K ν
    if constexpr (SquareRoot) {
      if (squareRootPosterior(prior, presentCount)) return Status::Ok;
      sr().candidate = SquareRootPart_::Candidate::CovarianceOnly;
    }
    candidateCovariance_ = prior.covariance;
    subtractOuter(candidateCovariance_, gainFactor_);  // P = P⁻ − K P_yy Kᵀ
    return Status::Ok;
  }

  /// What every step does with the covariance it is about to commit: check that candidateCovariance()
  /// is finite and has a Cholesky factor, repair it if not (covariance_repair.hpp). Ok, Repaired, or a
  /// refusal. The candidate is exactly symmetric as formed (predict(), predictRandomWalk() and correct()
  /// compute one triangle and mirror it), so it is not symmetrised here. Only a covariance accepted here
  /// is committed. Square-root form: a factor obtained without subtraction is accepted when it is finite
  /// with a positive diagonal (Ok; P = S Sᵀ is formed here, exactly symmetric), NonFiniteResult
  /// otherwise; the full form's P of a step whose factor could not be obtained goes through the same
  /// check and repair as in the full form, so that every status means the same in both forms.
  Status settle(const CovarianceRepair<Scalar>& repair) {
    if constexpr (SquareRoot) {
      using Candidate = typename SquareRootPart_::Candidate;
      Status s;
      if (sr().candidate == Candidate::CovarianceOnly) {
        s = guard_.settleSymmetric(candidateCovariance_, repair);
        if (taken(s)) sr().candidateFactor = guard_.factor();
      } else {
        if (sr().candidate == Candidate::Factor) outerOfLower(sr().candidateFactor, candidateCovariance_);
        const bool positive = (sr().candidateFactor.diagonal().array() > Scalar(0)).all();
        s = positive && allFinite(sr().candidateFactor) && allFinite(candidateCovariance_) ? Status::Ok
                                                                                           : Status::NonFiniteResult;
      }
      sr().settled = s;
      return s;
    } else {
      return guard_.settleSymmetric(candidateCovariance_, repair);
    }
  }

  /// How workPoints() relate to the candidate (mean, factor) after settle(): Drawn from them, Predicted
  /// (predict() formed them from these points, settled Ok and the mean was not moved since), or Other.
  /// Only the square-root form tracks it (the full form: always Other).
  PriorPoints workPointsPrior() const {
    if constexpr (SquareRoot) {
      if (sr().workPrior != PriorPoints::Predicted) return sr().workPrior;
      const bool asPredicted = sr().settled == Status::Ok && candidateMean_ == sr().predictedMean;
      return asPredicted ? PriorPoints::Predicted : PriorPoints::Other;
    } else {
      return PriorPoints::Other;
    }
  }

  /// Commits a time update that settle() accepted: its mean, covariance and factor, and its points.
  /// `meanAsPredicted`: the candidate mean is still predict()'s (no policy moved it), so that the
  /// deviations predict() formed are those of the committed points about the committed mean, and the
  /// measurement update that follows reads them instead of forming them again.
  void commitPrediction(bool meanAsPredicted = false) {
    if constexpr (SquareRoot) sr().pointsPrior = workPointsPrior();
    workSet_ ^= 1;  // the work points become the committed ones: swapped, not copied
    hasPoints_ = true;
    deviationsHold_ = meanAsPredicted && deviationsHold_ == Deviations::OfWorkPoints ? Deviations::OfCommittedPoints
                                                                                     : Deviations::Other;
    commitCandidate();
  }
  /// Commits a measurement update that settle() accepted: its mean, covariance, factor and diagnostics.
  /// The points no longer describe the estimate.
  void commitCorrection() {
    diagnostics_ = candidateDiagnostics_;
    hasPoints_ = false;
    deviationsHold_ = Deviations::Other;
    commitCandidate();
  }
  /// Commits a new mean alone (an open-loop propagation): P and its factor stay.
  void commitMean(const Vector& mean) {
    mean_ = mean;
    hasPoints_ = false;
    deviationsHold_ = Deviations::Other;
  }

  Points& workPoints() { return pointSets_[workSet_]; }
  const Points& workPoints() const { return pointSets_[workSet_]; }
  MeasPoints& measuredPoints() { return measuredPoints_; }
  Vector& candidateMean() { return candidateMean_; }
  const Vector& candidateMean() const { return candidateMean_; }
  Matrix& candidateCovariance() { return candidateCovariance_; }
  const Matrix& candidateCovariance() const { return candidateCovariance_; }
  /// The lower factor of candidateCovariance() after settle() accepted it.
  const Matrix& candidateFactor() const {
    if constexpr (SquareRoot)
      return sr().candidateFactor;
    else
      return guard_.factor();
  }
  /// After correct() returned Ok: U = P_xy S⁻ᵀ and the lower factor S of P_yy (Cholesky, or
  /// Householder in the square-root form), so that the gain is K = U S⁻¹.
  const CrossMatrix& gainFactor() const { return gainFactor_; }
  const MeasMatrix& innovationFactor() const { return innovationFactor_; }

 private:
  using SquareRootPart_ = SquareRootPart<Scalar, L, M, Count, Form>;
  SquareRootPart_& sr() { return *this; }
  const SquareRootPart_& sr() const { return *this; }

  void commitCandidate() {
    mean_ = candidateMean_;
    covariance_ = candidateCovariance_;
    factor_ = candidateFactor();
  }

  // ---- The square-root form (docs/algorithms.md §10) ------------------------------------------------

  // S with S Sᵀ = Σ Wcᵢ dᵢ dᵢᵀ + E Eᵀ, E the columns of `stack` after the first Count, which the caller
  // has set: the dᵢ of nonnegative weight, scaled by √Wcᵢ, are triangularised together with E
  // (lowerFactorOfOuter; a point of negative weight leaves a zero column), then S is downdated by
  // √|Wcᵢ| dᵢ for each negative weight (Wc₀ < 0 when α < 0.52 with β = 2, κ = 0). False when either fails.
  template <int Rows, int Cols>
  bool weightedFactor(const Eigen::Matrix<Scalar, Rows, Count>& d, Eigen::Matrix<Scalar, Rows, Cols>& stack,
                      Eigen::Matrix<Scalar, Rows, Rows>& s) const {
    static_assert(Cols >= Count, "the stack holds the weighted deviations first");
    const auto& weights = sigmaPoints_.covarianceWeights();
    for (int i = 0; i < Count; ++i) {
      if (weights(i) < Scalar(0))
        stack.col(i).setZero();
      else
        stack.col(i) = sr().weightRoots(i) * d.col(i);
    }
    if (!lowerFactorOfOuter(stack, s)) return false;
    for (int i = 0; i < Count; ++i)
      if (weights(i) < Scalar(0) && !choleskyRankOneUpdate(s, sr().weightRoots(i) * d.col(i), -1)) return false;
    return true;
  }

  // The factor S_y of P_yy into innovationFactor_ and P_yy = S_y S_yᵀ into the diagnostics. S_y from
  // [√Wcᵢ ΔYᵢ | √R'] (weightedFactor), where a masked update has zeroed the rows of ΔY of the missing
  // components and R' is R with their rows and columns zeroed and 1 on the diagonal, so that
  // S_y S_yᵀ is the full form's P_yy in exact arithmetic (S_y then has the unit vector as row and column
  // j). When that fails: the full form's P_yy and its Cholesky factor. False when neither exists.
  template <class F = Form>
  bool squareRootInnovationFactor(const MeasMatrix& measurementNoise, const Mask* present, int presentCount) {
    static_assert(isSquareRootForm<F>);
    Diagnostics& d = candidateDiagnostics_;
    const MeasMatrix* noiseRoot = &sr().measurementNoiseRoot;
    bool obtained = true;
    if (present && presentCount < M) {
      sr().maskedNoise = measurementNoise;
      for (int j = 0; j < M; ++j) {
        if ((*present)(j)) continue;
        sr().maskedNoise.row(j).setZero();
        sr().maskedNoise.col(j).setZero();
        sr().maskedNoise(j, j) = Scalar(1);
      }
      obtained = choleskyLower(sr().maskedNoise, sr().maskedNoiseRoot);
      noiseRoot = &sr().maskedNoiseRoot;
    }
    sr().noiseRootValid = obtained;
    if (obtained) {
      sr().innovationStack.template rightCols<M>() = *noiseRoot;
      obtained = weightedFactor(measurementDeviations_, sr().innovationStack, innovationFactor_);
    }
    if (obtained) {
      outerOfLower(innovationFactor_, d.innovationCovariance);
      if (allFinite(d.innovationCovariance)) return true;
    }
    // The full form's P_yy (ΔY's missing rows are zero already).
    weightedCovariance(measurementDeviations_, sigmaPoints_.covarianceWeights(), d.innovationCovariance);
    d.innovationCovariance += measurementNoise;
    if (present)
      for (int j = 0; j < M; ++j) {
        if ((*present)(j)) continue;
        d.innovationCovariance.row(j).setZero();
        d.innovationCovariance.col(j).setZero();
        d.innovationCovariance(j, j) = Scalar(1);
      }
    return choleskyLower(d.innovationCovariance, innovationFactor_);  // fails on NaN and ±Inf too
  }

  // The posterior factor into sr().candidateFactor (docs/algorithms.md §10), after U = gainFactor_:
  //  - nothing present (K = 0): the prior's factor and covariance, unchanged;
  //  - points Drawn from the prior or Predicted with it (the identity of §10 holds), with an obtained
  //    factor of R': the array form, S⁺ from [√Wcᵢ (Δχᵢ − K ΔYᵢ) | G (Predicted) | K √R'], downdated
  //    for negative weights (weightedFactor), no subtraction of covariances;
  //  - otherwise: S⁻ downdated by the M columns of U, S⁺ S⁺ᵀ = P⁻ − U Uᵀ.
  // False when the factor could not be obtained (the caller then forms the full form's P). (A template,
  // as the one above, so that only the square-root form instantiates it.)
  template <class F = Form>
  bool squareRootPosterior(const Prior& prior, int presentCount) {
    static_assert(isSquareRootForm<F>);
    using Candidate = typename SquareRootPart_::Candidate;
    if (presentCount == 0) {
      if (&prior.factor != &sr().candidateFactor) sr().candidateFactor = prior.factor;
      candidateCovariance_ = prior.covariance;
      sr().candidate = Candidate::FactorAndCovariance;
      return true;
    }
    sr().candidate = Candidate::Factor;
    const bool maskedRoot = presentCount < M;
    if (prior.points != PriorPoints::Other && sr().noiseRootValid) {
      // K = U S_y⁻¹; the deviations become Δχᵢ − K ΔYᵢ (ΔY's missing rows are zero, and so are K's
      // columns there).
      sr().gain = gainFactor_;
      rightSolveLowerInPlace(innovationFactor_, sr().gain);
      deviations_.noalias() -= sr().gain.lazyProduct(measurementDeviations_);
      auto& stack = sr().posteriorStack;
      if (prior.points == PriorPoints::Predicted)
        stack.template middleCols<L>(Count) = sr().processNoiseRoot;
      else
        stack.template middleCols<L>(Count).setZero();
      const MeasMatrix& noiseRoot = maskedRoot ? sr().maskedNoiseRoot : sr().measurementNoiseRoot;
      stack.template rightCols<M>().noalias() = sr().gain.lazyProduct(noiseRoot);
      return weightedFactor(deviations_, stack, sr().candidateFactor);
    }
    if (&prior.factor != &sr().candidateFactor) sr().candidateFactor = prior.factor;
    return choleskyRankUpdate(sr().candidateFactor, gainFactor_, -1);
  }

  SigmaPoints sigmaPoints_;
  // Committed.
  Vector mean_ = Vector::Zero();
  Matrix covariance_ = Matrix::Zero();
  Matrix factor_ = Matrix::Zero();  // lower S with covariance_ = S Sᵀ
  bool hasPoints_ = false;
  // The points: pointSets_[workSet_] are the work points (drawn, then propagated in place), the other
  // the committed χᵢ⁺ of the last time update (points(), read by the measurement update). A time update's
  // commit swaps the two (workSet_ ^= 1) instead of copying L × (2L + 1) values.
  unsigned char workSet_ = 0;
  // What deviations_ holds: predict()'s workPoints() − candidateMean_, or points() − mean_ since a
  // commitPrediction(true), or anything else. (Both bytes sit in the padding after hasPoints_.)
  enum class Deviations : unsigned char { Other, OfWorkPoints, OfCommittedPoints };
  Deviations deviationsHold_ = Deviations::Other;
  Diagnostics diagnostics_;
  // Workspace: a step computes here and commits only when the whole step succeeded. Zeroed once at
  // construction, so that copying a filter before its first step copies no indeterminate values.
  Points pointSets_[2] = {Points::Zero(), Points::Zero()};
  MeasPoints measuredPoints_ = MeasPoints::Zero();         // Yᵢ = g(χᵢ⁺)
  Points deviations_ = Points::Zero();                     // χᵢ⁺ − x̂⁻ (square-root posterior: − K ΔYᵢ)
  MeasPoints measurementDeviations_ = MeasPoints::Zero();  // Yᵢ − ŷ
  CrossMatrix gainFactor_ = CrossMatrix::Zero();           // P_xy, then U = P_xy S⁻ᵀ
  MeasMatrix innovationFactor_ = MeasMatrix::Zero();       // S with P_yy = S Sᵀ
  Vector candidateMean_ = Vector::Zero();
  Matrix candidateCovariance_ = Matrix::Zero();
  Diagnostics candidateDiagnostics_;
  CovarianceGuard<Scalar, L> guard_;
};

// What a measurement update hands the parameter policy once the state's correction succeeded: the
// measurement, its input, which components are present, the points' images Yᵢ, the prior mean, the gain's
// factors U = P_xy S⁻ᵀ and S (P_yy = S Sᵀ), and the innovation y − ŷ.
template <class Model, class Settings, class Est>
struct Correction {
  const Model& model;
  const Settings& settings;
  const typename Est::MeasVector& y;
  const typename Model::Input& input;  // in force at the measurement time
  const typename Est::Mask* present;
  const typename Est::MeasPoints& measured;
  const typename Est::Vector& priorMean;
  const typename Est::CrossMatrix& gainFactor;
  const typename Est::MeasMatrix& innovationFactor;
  const typename Est::MeasVector& innovation;  // ν = y − ŷ, ŷ the points' weighted mean (zero where missing)
};

// ==== 3. The parameter policy =========================================================================
//
// How a filter estimates its parameters (none, augmented, MJUKF's eqs. 9–10, dual) is a policy object
// the engine holds and calls. Every member below is required: there are no defaults, so a misspelled
// or missing hook is a compile error naming it (checkParameterPolicy), never a hook silently not
// called. With Est the engine's Estimate, Step a TimeStep and Engine the filter:
//
//   template <class Step> Status predictParameters(const Step&, const Est& state);   before the state's points
//   const Matrix& priorFactor(const Est& state) const; the lower factor the time update draws the state's
//                                                    points from (after predictParameters): state.factor(),
//                                                    or the dual's, widened by its parameters' random walk
//   template <class Step> void propagatePoints(const Step&, Points& points);          χᵢ⁺ = Φ(χᵢ), in place
//   const Matrix* priorCovarianceFloor() const;       a covariance this time update's P⁻ must cover, or null
//   static constexpr bool raisesPriorCovariance;      optional, the one member with a default (true, always
//                                                    safe): false when the floor is always null, so that
//                                                    the raise is not compiled in
//   template <class Step> Vector propagateMean(const Step&, const Vector& mean);      the open-loop mean
//   void measurePoints(const Model&, const Input& u, const Points& points, MeasPoints& measured);
//                                                    Yᵢ = g(χᵢ, u)
//   template <class Engine> Status update(Engine&, const Meas& y, const Input& u, const Mask* present);
//                                                    the order of
//                                                    the measurement update (Engine::correctState, or the
//                                                    dual's: parameters first)
//   Status correctParameters(const Correction&);      after the state's correction, into candidates
//   bool constrainMean(Vector& candidateMean);        on the settled candidate mean (bounds); false
//                                                    when it left the mean as it was
//   void commitPrediction(); void commitCorrection(); void commitOpenLoop(Scalar interval);

// Accepts a bool and nothing else (not a void, not an int), in an unevaluated call.
template <class T, class = std::enable_if_t<std::is_same_v<T, bool>>>
void returnsBool(T);

#define MJUKF_POLICY_HAS(Name, Call)            \
  template <class P, class = void>              \
  struct PolicyHas_##Name : std::false_type {}; \
  template <class P>                            \
  struct PolicyHas_##Name<P, std::void_t<decltype(Call)>> : std::true_type {};
MJUKF_POLICY_HAS(predictParameters,
                 std::declval<P&>().predictParameters(std::declval<const typename P::CheckStep&>(),
                                                      std::declval<const typename P::CheckEstimate&>()))
MJUKF_POLICY_HAS(priorFactor,
                 static_cast<const typename P::CheckEstimate::Matrix&>(
                     std::declval<const P&>().priorFactor(std::declval<const typename P::CheckEstimate&>())))
MJUKF_POLICY_HAS(propagatePoints,
                 std::declval<P&>().propagatePoints(std::declval<const typename P::CheckStep&>(),
                                                    std::declval<typename P::CheckEstimate::Points&>()))
MJUKF_POLICY_HAS(priorCovarianceFloor,
                 static_cast<const typename P::CheckEstimate::Matrix*>(std::declval<const P&>().priorCovarianceFloor()))
MJUKF_POLICY_HAS(propagateMean,
                 std::declval<P&>().propagateMean(std::declval<const typename P::CheckStep&>(),
                                                  std::declval<const typename P::CheckEstimate::Vector&>()))
MJUKF_POLICY_HAS(measurePoints,
                 std::declval<P&>().measurePoints(std::declval<const typename P::CheckModel&>(),
                                                  std::declval<const typename P::CheckModel::Input&>(),
                                                  std::declval<const typename P::CheckEstimate::Points&>(),
                                                  std::declval<typename P::CheckEstimate::MeasPoints&>()))
MJUKF_POLICY_HAS(correctParameters,
                 std::declval<P&>().correctParameters(std::declval<const typename P::CheckCorrection&>()))
MJUKF_POLICY_HAS(constrainMean,
                 returnsBool(std::declval<P&>().constrainMean(std::declval<typename P::CheckEstimate::Vector&>())))
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
  static_assert(PolicyHas_priorFactor<Policy>::value,
                "parameter policy: missing member priorFactor(const Estimate&) const -> const Matrix&");
  static_assert(PolicyHas_propagatePoints<Policy>::value,
                "parameter policy: missing member propagatePoints(const Step&, Points&)");
  static_assert(PolicyHas_priorCovarianceFloor<Policy>::value,
                "parameter policy: missing member priorCovarianceFloor() const -> const Matrix* (null: none)");
  static_assert(PolicyHas_propagateMean<Policy>::value,
                "parameter policy: missing member propagateMean(const Step&, const Vector&) -> Vector");
  static_assert(
      PolicyHas_measurePoints<Policy>::value,
      "parameter policy: missing member measurePoints(const Model&, const Input&, const Points&, MeasPoints&)");
  static_assert(PolicyHas_correctParameters<Policy>::value,
                "parameter policy: missing member correctParameters(const Correction&) -> Status");
  static_assert(PolicyHas_constrainMean<Policy>::value, "parameter policy: missing member bool constrainMean(Vector&)");
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

// Whether a policy's priorCovarianceFloor() can return a covariance: its `static constexpr bool
// raisesPriorCovariance`, true where it does not say (the raise is then compiled in, as it must be for a
// floor to be honoured). The UKF's, JUKF's and dual's policies, and the MJUKF's without its automatic
// modes, say false.
template <class P, class = void>
inline constexpr bool raisesPriorCovariance = true;
template <class P>
inline constexpr bool raisesPriorCovariance<P, std::void_t<decltype(P::raisesPriorCovariance)>> =
    P::raisesPriorCovariance;

/// \endcond

// ==== 4. The engine ===================================================================================

// The status of a step made of two parts that were both taken: Repaired if either was.
constexpr Status combineTaken(Status a, Status b) { return a == Status::Ok ? b : a; }

// Whether a filter reports a covariance of its parameters (JointUkf, DualUkf), and whether its
// settings have parameter bounds: what the health monitor's parameter tests use.
template <class Filter, class = void>
constexpr bool hasParameterCovariance = false;
template <class Filter>
constexpr bool
    hasParameterCovariance<Filter, std::void_t<decltype(std::declval<const Filter&>().parameterCovariance())>> = true;
template <class Filter, class = void>
constexpr bool hasParametersAccessor = false;
template <class Filter>
constexpr bool hasParametersAccessor<Filter, std::void_t<decltype(std::declval<const Filter&>().parameters())>> = true;
template <class Settings, class = void>
constexpr bool hasParameterBounds = false;
template <class Settings>
constexpr bool hasParameterBounds<Settings, std::void_t<decltype(std::declval<const Settings&>().parameterBounds)>> =
    true;

/// The per-step calls every filter shares: `Ukf`, `JointUkf`, `ModifiedJointUkf` and `DualUkf` derive
/// from this engine and inherit its public members. Each call returns a Status; one other than Ok or
/// Repaired leaves the filter exactly as it was (docs/robustness.md). `L` is the dimension of the
/// vector the filter draws sigma points for; `Policy` is how it estimates parameters (section 3 above);
/// `Features` what is compiled in (features.hpp).
template <class Filter, class Model_, class Integrator_, class Settings_, class Policy, int L,
          class PointSet = MerweScaled, class Form = FullCovariance, class Features_ = AllFeatures>
class UnscentedEngine {
  static_assert(!isDiscreteTime<Model_> || std::is_same_v<Integrator_, NoIntegrator<typename Model_::Scalar>>,
                "a discrete-time model (it has transition()) is not integrated: leave the integrator out");
  static_assert(isFeatureSet<Features_>, "the features are AllFeatures or mjukf::Without<...> (features.hpp)");

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
  /// The covariance form: `FullCovariance` or `SquareRootCovariance` (covariance_form.hpp).
  using CovarianceForm = Form;
  /// What is compiled in: `AllFeatures` or `Without<…>` (features.hpp).
  using Features = Features_;

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
  /// covariance. Returns Ok or Repaired when the update was committed (the covariance, exactly symmetric
  /// as formed, is checked before it is), MeasurementRejected when the gate refused it, or another refusal.
  ///
  /// When the model's measurement depends on the input (`measurementTakesInput`, model.hpp), the input
  /// is the model's `input(t)` at the filter's time, `time()`; a model without `input(t)` must be given
  /// it, `measurementUpdate(y, u)`. A non-finite input is refused (NonFiniteInput).
  template <class M = Model>
  Status measurementUpdate(const Meas& y) {
    return updateWithOwnInput<M>(y, nullptr);
  }

  /// Measurement update with only the components where `present` is true (missing channels; the
  /// others, NaN included, are ignored): exactly the update of the model reduced to those components,
  /// with R reduced likewise. A mask with nothing present leaves the estimate as it was.
  template <class M = Model>
  Status measurementUpdate(const Meas& y, const MeasurementMask<MeasDim>& present) {
    return updateWithOwnInput<M>(y, &present);
  }

  /// Measurement update of a model whose measurement depends on the input, y = g(x, u, θ), with the
  /// input u in force at the measurement time.
  template <class M = Model, std::enable_if_t<measurementTakesInput<M>, int> = 0>
  Status measurementUpdate(const Meas& y, const Input& u) {
    return updateWithInput(y, u, nullptr);
  }

  /// The masked measurement update with the input u in force at the measurement time.
  template <class M = Model, std::enable_if_t<measurementTakesInput<M>, int> = 0>
  Status measurementUpdate(const Meas& y, const Input& u, const MeasurementMask<MeasDim>& present) {
    return updateWithInput(y, u, &present);
  }

  /// The filter's time: where its last committed time update or open-loop propagation ended (t + steps·h),
  /// 0 before the first. A measurement that depends on the input is evaluated with the model's
  /// `input(time())`.
  Scalar time() const { return time_; }

  /// The health monitor's verdict now (health.hpp): the alarm of the last complete block of measurement
  /// updates if it failed a test, an alarm that stands while at least half of the blocks the monitor
  /// remembers (`health.verdictMemory`) raised one, or a streak of refusals under way; otherwise
  /// `Health::Ok`.
  /// The first alarm since construction, `reset` or `clearHealth()` stays in
  /// `healthStatistics().firstAlarm`, with the update that raised it.
  /// Not available in a filter compiled `Without<feature::HealthMonitor>`.
  template <class F = Features>
  Health health() const {
    static_assert(F::healthMonitor,
                  "this filter is compiled without its health monitor (mjukf::Without<mjukf::feature::HealthMonitor>): "
                  "health(), healthStatistics() and clearHealth() are not available");
    if constexpr (F::healthMonitor) return health_.health();
  }
  /// The statistics behind `health()`: the first alarm, the last block's normalised NIS and
  /// autocorrelation against their bounds, the parameters' motion, counts of blocks, alarms and refusals.
  template <class F = Features>
  const HealthStatistics<Scalar>& healthStatistics() const {
    static_assert(F::healthMonitor,
                  "this filter is compiled without its health monitor (mjukf::Without<mjukf::feature::HealthMonitor>): "
                  "health(), healthStatistics() and clearHealth() are not available");
    if constexpr (F::healthMonitor) return health_.statistics();
  }
  /// Clears the first alarm (after the user acted on it); the statistics go on.
  template <class F = Features>
  void clearHealth() {
    static_assert(F::healthMonitor,
                  "this filter is compiled without its health monitor (mjukf::Without<mjukf::feature::HealthMonitor>): "
                  "health(), healthStatistics() and clearHealth() are not available");
    if constexpr (F::healthMonitor) health_.clearAlarm();
  }

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
  using Est = Estimate<Scalar, L, MeasDim, PointSet, Form>;
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
    if (SettingsError e = validateStepCheck(owner, settings.stepCheck)) return e;
    if constexpr (Features::healthMonitor) {
      if (SettingsError e = validateHealth(owner, settings.health)) return e;
    } else if (settings.health.enabled) {
      return invalid(owner, "health.enabled",
                     "must be false: the filter is compiled without its health monitor "
                     "(mjukf::Without<mjukf::feature::HealthMonitor>)");
    }
    return validateGate(owner, settings.gate);
  }

  // The filter from values its validate() accepted (it ends with validateSettings): the estimate starts
  // from Filter::initialMean(x̂₀, θ̂₀) and P₀, the policy from (settings, θ̂₀); nothing here can fail.
  UnscentedEngine(Validated, const Model& model, const State& initialState, const Param& initialParameters,
                  const Settings& settings, const Integrator& integrator)
      : model_(model),
        integrator_(integrator),
        settings_(settings),
        estimate_(Validated{}, settings.sigmaPoints, settings.processNoise, settings.measurementNoise),
        policy_(settings, initialParameters),
        health_(settings.health) {
    // symmetrised, as every committed P is
    estimate_.assign(Filter::initialMean(initialState, initialParameters), settings.initialCovariance);
  }

  // The covariance argument of reset() checked like P₀; reset() changes nothing when it fails. The mean
  // is checked by the filter, which names its parts.
  static SettingsError checkResetCovariance(const char* owner, const Matrix& covariance) {
    return requireCommittableCovariance(owner, "covariance", covariance);
  }
  // Commits a reset that checkResetCovariance() accepted: cannot fail.
  void resetEstimate(const Vector& mean, const Matrix& covariance) {
    estimate_.assign(mean, covariance);
    if constexpr (Features::healthMonitor) health_.clear();
  }
  // The start time of a new pass over a record (startPass()), checked like an initial value.
  static SettingsError checkStartTime(const char* owner, Scalar startTime) {
    return requireFinite(owner, "startTime", startTime);
  }
  // A new pass starts at the record's t₀: time() is where the next measurement's input is read.
  void restartTime(Scalar startTime) {
    time_ = startTime;
    if constexpr (Features::healthMonitor) health_.restartBlock();
  }

  // ---- The skeleton --------------------------------------------------------------------------------

  template <class InputSource>
  using Step = TimeStep<Model, Integrator, InputSource, Settings>;

  // The step check (step_check.hpp) of a call from t over `steps` steps of h: Ok when the step
  // passes or is not due for a check; with OversizedStep::Subdivide, h is halved and `steps` doubled
  // until it passes (the same subdivision is then applied to the same request until its next check);
  // StepTooLarge otherwise. Only the mean is propagated here, into locals: nothing is committed.
  template <class InputSource>
  Status checkIntegrationStep(const InputSource& input, Scalar t, Scalar& h, int& steps) {
    if constexpr (isDiscreteTime<Model>) {
      return Status::Ok;
    } else {
      const StepCheck<Scalar>& check = settings_.stepCheck;
      if (check.onOversized == OversizedStep::Accept) return Status::Ok;
      const bool sameRequest = h == checkedStepSize_ && steps == checkedStepCount_;
      if (sameRequest && callsSinceStepCheck_ + 1 < check.interval) {
        pendingStepCheck_ = {checkedStepSize_, checkedStepCount_, checkedHalvings_, callsSinceStepCheck_ + 1};
        h /= Scalar(1 << checkedHalvings_);
        steps <<= checkedHalvings_;
        return Status::Ok;
      }
      const Scalar requestedSize = h;
      const int requestedCount = steps;
      // The input held at its value at t: a jump of the model's input(t) inside the step would make the
      // full and the half steps differ at any h, which is not what the check measures.
      const Input start = input(t);
      const HeldInput<Model> held{start};
      // The mean, and the mean with a small offset (a hundredth of σ, at least √ε of its size) whose
      // motion follows the dynamics linearised about the mean: where the mean does not move (an
      // equilibrium), a step unstable for the sigma points around it shows in the offset's growth.
      const Vector& mean = estimate_.mean();
      const Vector sigma = estimate_.covariance().diagonal().cwiseMax(Scalar(0)).cwiseSqrt();
      using std::sqrt;
      const Scalar rootEpsilon = sqrt(std::numeric_limits<Scalar>::epsilon());
      const Vector offset = (Scalar(0.01) * sigma).cwiseMax(rootEpsilon * (mean.cwiseAbs() + sigma));
      const Vector perturbed = mean + offset;
      StepDoubling doubling{mean, perturbed, mean, perturbed};
      const auto propagateBoth = [&](Scalar size, int count, Vector& ofMean, Vector& ofPerturbed) {
        const Step<HeldInput<Model>> step{model_, integrator_, settings_, held, t, size, count};
        ofMean = policy_.propagateMean(step, mean);
        ofPerturbed = policy_.propagateMean(step, perturbed);
      };
      propagateBoth(h, steps, doubling.full, doubling.fullPerturbed);
      // Step doubling is an estimate: far outside the stability region two levels can agree by
      // coincidence. So a subdivided step is taken only when the next halving passes too.
      bool candidate = false;  // the level before this one passed (and was a subdivision)
      for (int halvings = 0;; ++halvings) {
        propagateBoth(h / 2, 2 * steps, doubling.halves, doubling.halvesPerturbed);
        // The model's own fault (NaN or ±Inf even from the smaller steps), not the step's size.
        if (!allFinite(doubling.halves) || !allFinite(doubling.halvesPerturbed)) return Status::NonFiniteResult;
        const bool passed = doubling.passes(mean, offset, sigma, check.tolerance);
        if (passed && (halvings == 0 || candidate)) {
          if (candidate) {  // the level before this one: the check's h was halved once more since
            h *= 2;
            steps /= 2;
          }
          pendingStepCheck_ = {requestedSize, requestedCount, candidate ? halvings - 1 : 0, 0};
          return Status::Ok;
        }
        candidate = passed;
        if (check.onOversized != OversizedStep::Subdivide || halvings == check.maxHalvings ||
            steps > std::numeric_limits<int>::max() / 4)
          return Status::StepTooLarge;
        h /= 2;
        steps *= 2;
        doubling.full = doubling.halves;
        doubling.fullPerturbed = doubling.halvesPerturbed;
      }
    }
  }

  // One level of the step check: the mean and the perturbed mean over the call's steps of h (full) and
  // of h/2 (halves).
  struct StepDoubling {
    Vector full, fullPerturbed, halves, halvesPerturbed;

    // For every component i (step_check.hpp), with e the difference between the two propagations and Δ
    // the half steps' move: |eᵢ| ≤ tolerance (|Δᵢ| + σᵢ) for the mean, and the same for the offset's
    // motion with the offset in place of σ. False on NaN or ±Inf.
    bool passes(const Vector& mean, const Vector& offset, const Vector& sigma, Scalar tolerance) const {
      using std::abs;
      for (int i = 0; i < L; ++i) {
        const Scalar meanError = abs(full(i) - halves(i));
        const Scalar meanScale = abs(halves(i) - mean(i)) + sigma(i);
        const Scalar offsetError = abs((fullPerturbed(i) - full(i)) - (halvesPerturbed(i) - halves(i)));
        // Plus the rounding of the two propagations, which the difference of two large values keeps.
        const Scalar offsetScale = abs(halvesPerturbed(i) - halves(i)) + offset(i) +
                                   Scalar(64) * std::numeric_limits<Scalar>::epsilon() * abs(halves(i));
        if (!(meanError <= tolerance * meanScale) || !(offsetError <= tolerance * offsetScale)) return false;
      }
      return true;
    }
  };

  template <class InputSource>
  Status timeUpdateWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    const Status status = timeUpdateUnmonitored(input, t, h, steps);
    if constexpr (Features::healthMonitor) health_.observeStatus(status, CallKind::Propagation);
    return status;
  }
  template <class InputSource>
  Status timeUpdateUnmonitored(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = checkStep(t, h, steps); s != Status::Ok) return s;
    const Status checked = checkIntegrationStep(input, t, h, steps);  // may subdivide h
    if (!input.allValuesFinite()) return Status::NonFiniteInput;
    if (checked != Status::Ok) return checked;
    const Step<InputSource> step{model_, integrator_, settings_, input, t, h, steps};
    const Status parameters = policy_.predictParameters(step, estimate_);
    if (!input.allValuesFinite()) return Status::NonFiniteInput;
    if (!taken(parameters)) return parameters;
    const Status settled = predict(step, estimate_.mean(), policy_.priorFactor(estimate_));
    if (!input.allValuesFinite()) return Status::NonFiniteInput;  // the model's input(t) gave NaN or ±Inf
    if (!taken(settled)) return settled;
    const bool moved = policy_.constrainMean(estimate_.candidateMean());
    estimate_.commitPrediction(!moved);
    policy_.commitPrediction();
    commitStepCheck();
    time_ = t + step.interval();
    return combineTaken(settled, parameters);
  }

  // §2 from (mean, S Sᵀ) over `step`, into the estimate's candidates: draw, propagate (the policy),
  // predict, settle. The time update's, and the dual filter's second prediction of a step.
  template <class StepType>
  Status predict(const StepType& step, const Vector& mean, const Matrix& lowerFactor) {
    if (const Status s = estimate_.draw(mean, lowerFactor); s != Status::Ok) return s;
    policy_.propagatePoints(step, estimate_.workPoints());
    estimate_.template predict<raisesPriorCovariance<Policy>>(settings_.processNoise, policy_.priorCovarianceFloor());
    // The points are committed with the prediction, and are not checked apart: a NaN or ±Inf among them
    // makes x̂⁻ = Σ Wmᵢ χᵢ⁺ NaN or ±Inf (even with a zero weight: 0 · NaN and 0 · Inf are NaN), checked here.
    if (!allFinite(estimate_.candidateMean())) return Status::NonFiniteResult;
    return estimate_.settle(settings_.repair);
  }

  template <class InputSource>
  Status propagateMeanWith(const InputSource& input, Scalar t, Scalar h, int steps) {
    const Status status = propagateMeanUnmonitored(input, t, h, steps);
    if constexpr (Features::healthMonitor) health_.observeStatus(status, CallKind::Propagation);
    return status;
  }
  template <class InputSource>
  Status propagateMeanUnmonitored(const InputSource& input, Scalar t, Scalar h, int steps) {
    if (const Status s = checkStep(t, h, steps); s != Status::Ok) return s;
    const Status checked = checkIntegrationStep(input, t, h, steps);  // may subdivide h
    if (!input.allValuesFinite()) return Status::NonFiniteInput;
    if (checked != Status::Ok) return checked;
    const Step<InputSource> step{model_, integrator_, settings_, input, t, h, steps};
    const Vector mean = policy_.propagateMean(step, estimate_.mean());
    if (!input.allValuesFinite()) return Status::NonFiniteInput;  // the model's input(t) gave NaN or ±Inf
    if (!allFinite(mean)) return Status::NonFiniteResult;
    estimate_.commitMean(mean);
    policy_.commitOpenLoop(step.interval());
    commitStepCheck();
    time_ = t + step.interval();
    return Status::Ok;
  }

  // The measurement update with the input the filter finds itself: none needed, or the model's u(t) at
  // the filter's time.
  template <class M>
  Status updateWithOwnInput(const Meas& y, const Mask* present) {
    if constexpr (measurementTakesInput<M>) {
      static_assert(hasInputSignal<M>,
                    "this model's measurement depends on the input and it has no input(t): pass the input, "
                    "measurementUpdate(y, u)");
      return updateWithInput(y, model_.input(time_), present);
    } else {
      return updateWithInput(y, noInput_, present);
    }
  }

  // The measurement update: the policy says in which order its parts run (every filter but the dual
  // one calls correctState). The input reaches g, and is checked, only when the measurement takes it.
  Status updateWithInput(const Meas& y, const Input& u, const Mask* present) {
    const Status status = updateUnmonitored(y, u, present);
    if constexpr (Features::healthMonitor) {
      health_.observeStatus(status, CallKind::Measurement);
      if (taken(status)) observeCommittedUpdate(present);
    }
    return status;
  }
  Status updateUnmonitored(const Meas& y, const Input& u, const Mask* present) {
    if (!presentComponentsFinite(y, present)) return Status::NonFiniteMeasurement;
    if constexpr (measurementTakesInput<Model>)
      if (!allFinite(u)) return Status::NonFiniteInput;
    return policy_.update(static_cast<Filter&>(*this), y, u, present);
  }

  // What the health monitor sees of a committed update: its diagnostics, and the parameters with
  // their standard deviations (where the filter has a covariance of them) and bounds.
  void observeCommittedUpdate(const Mask* present) {
    if (!settings_.health.enabled) return;
    const Filter& filter = static_cast<const Filter&>(*this);
    const Diagnostics& d = estimate_.diagnostics();
    Param sigma = Param::Constant(Scalar(-1));
    if constexpr (hasParameterCovariance<Filter>)  // read only where a block starts
      if (health_.atBlockBoundary()) sigma = filter.parameterCovariance().diagonal().cwiseSqrt();
    Param lower = Param::Constant(-std::numeric_limits<Scalar>::infinity());
    Param upper = Param::Constant(std::numeric_limits<Scalar>::infinity());
    if constexpr (hasParameterBounds<Settings>) {
      lower = settings_.parameterBounds.lower;
      upper = settings_.parameterBounds.upper;
    }
    Param parameters = Param::Zero();  // a filter of the engine's own tests may have no parameters()
    if constexpr (hasParametersAccessor<Filter>) parameters = filter.parameters();
    health_.observeUpdate(d.innovation, d.innovationCovariance, d.nis, present, parameters, sigma, lower, upper);
  }

  // §3 about the committed estimate, from the points of the last time update (or points drawn now).
  Status correctState(const Meas& y, const Input& u, const Mask* present) {
    const bool drawPoints = settings_.redrawPointsForUpdate || !estimate_.hasPoints();
    if (drawPoints)
      if (const Status s = estimate_.draw(estimate_.mean(), estimate_.factor()); s != Status::Ok) return s;
    return correctAndCommit(drawPoints ? estimate_.workPoints() : estimate_.points(), estimate_.prior(drawPoints), y, u,
                            present);
  }

  // §3 from `points` about a prior, then the policy's parameter correction, then the checks and the
  // commit of both.
  Status correctAndCommit(const Points& points, const typename Est::Prior& prior, const Meas& y, const Input& u,
                          const Mask* present) {
    policy_.measurePoints(model_, u, points, estimate_.measuredPoints());
    if (const Status s = estimate_.correct(points, estimate_.measuredPoints(), prior, y, settings_.measurementNoise,
                                           present, settings_.gate);
        s != Status::Ok)
      return s;
    const Status parameters = policy_.correctParameters(Correction<Model, Settings, Est>{
        model_, settings_, y, u, present, estimate_.measuredPoints(), prior.mean, estimate_.gainFactor(),
        estimate_.innovationFactor(), estimate_.candidateDiagnostics().innovation});
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
  Scalar time_ = 0;  // where the last time update or open-loop propagation ended
  // The health monitor, absent when it is compiled out.
  using MonitorOrAbsent =
      std::conditional_t<Features::healthMonitor, HealthMonitor<Scalar, MeasDim, ParamDim>, Absent<>>;
  MJUKF_NO_UNIQUE_ADDRESS MonitorOrAbsent health_;
  // The last request (h, steps) the step check passed, the halvings it needed, and the calls since.
  Scalar checkedStepSize_ = 0;
  int checkedStepCount_ = 0;
  int checkedHalvings_ = 0;
  int callsSinceStepCheck_ = 0;
  // What the check of the call under way found, committed with the call (a refused call changes nothing,
  // the check's schedule included).
  struct StepCheckRecord {
    Scalar stepSize;
    int stepCount, halvings, callsSinceCheck;
  };
  StepCheckRecord pendingStepCheck_{0, 0, 0, 0};
  void commitStepCheck() {
    if constexpr (!isDiscreteTime<Model>) {
      if (settings_.stepCheck.onOversized == OversizedStep::Accept) return;
      checkedStepSize_ = pendingStepCheck_.stepSize;
      checkedStepCount_ = pendingStepCheck_.stepCount;
      checkedHalvings_ = pendingStepCheck_.halvings;
      callsSinceStepCheck_ = pendingStepCheck_.callsSinceCheck;
    }
  }

 private:
  // The input of a model without one (InputDim = 0): an empty vector, held over every step.
  static inline const Input noInput_{};
  /// \endcond
};

/// \cond INTERNAL
// The engine of filter `Filter` over `Model`, with the parameter policy template `PolicyOf` (given the
// model, stepper, settings and estimate) and an estimate of dimension L drawn with `PointSet`, in the
// covariance form `Form`.
template <class Filter, class Model, class Integrator, class Settings,
          template <class, class, class, class> class PolicyOf, int L, class PointSet, class Form,
          class Features = AllFeatures>
using EngineOf = UnscentedEngine<
    Filter, Model, Integrator, Settings,
    PolicyOf<Model, Integrator, Settings, Estimate<typename Model::Scalar, L, Model::MeasDim, PointSet, Form>>, L,
    PointSet, Form, Features>;

/// \endcond

}  // namespace mjukf::detail
