#pragma once

/// \file
/// The health monitor of every filter: statistical tests of whether its estimate can still be
/// trusted, on what each measurement update saw (docs/robustness.md, "The health monitor").

#include <cmath>
#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/validation.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/status.hpp"

namespace mjukf {

/// What a filter's health monitor concludes now: `Health::Ok` means no alarm. Every other value names
/// the test that failed (docs/troubleshooting.md, "Health alarms", says what to change).
enum class Health : unsigned char {
  Ok,  ///< No test failed.
  /// Over a block of updates the innovations were larger than their covariance P_yy says (the block's
  /// summed NIS above its χ² bound): the filter is more confident than it should be, because its
  /// covariance collapsed, Q or R is far too small, or the estimate has left the truth.
  InnovationsTooLarge,
  /// The innovations were smaller than P_yy says (summed NIS below its χ² bound): the covariance is far
  /// larger than the errors, because it is exploding or Q or R is far too large. An alarm only with
  /// `HealthSettings::flagSmallInnovations`: otherwise the block is counted
  /// (`HealthStatistics::smallInnovationBlocks`) and the estimate, less certain than it could be but not
  /// wrong by what its covariance says, is not called untrustworthy.
  InnovationsTooSmall,
  /// Successive innovations were correlated (the lag-one autocorrelation of a normalised component
  /// beyond its bound): the model does not explain the data, a wrong structure, a wrong fixed value, or
  /// a change of a parameter the filter does not follow.
  InnovationsCorrelated,
  /// Within one block a parameter estimate moved by more than `runawaySigmas` of its own standard
  /// deviation at the block's start, or its standard deviation is unbounded at the block's end: it is
  /// running away, not converging.
  ParameterRunaway,
  /// A parameter estimate ended a block on one of its `parameterBounds`: the data pull it beyond what
  /// the bounds allow.
  ParameterAtBound,
  /// `refusalStreak` measurement updates in a row were refused (any Status other than Ok and Repaired,
  /// the gate's rejections included, whatever the time updates between them did), or as many time
  /// updates and open-loop propagations in a row.
  RepeatedRefusals,
};

/// A short English description of `health`, for logs and error messages.
constexpr const char* toString(Health health) noexcept {
  switch (health) {
    case Health::Ok: return "ok";
    case Health::InnovationsTooLarge: return "innovations larger than their covariance";
    case Health::InnovationsTooSmall: return "innovations smaller than their covariance";
    case Health::InnovationsCorrelated: return "innovations correlated in time";
    case Health::ParameterRunaway: return "parameter estimate running away";
    case Health::ParameterAtBound: return "parameter estimate at a bound";
    case Health::RepeatedRefusals: return "repeated refusals";
  }
  return "unknown health";
}

/// The settings of the health monitor (every filter's `health` setting). The tests run on blocks of
/// `window` committed measurement updates; each test has the false-alarm probability
/// `falseAlarmProbability` per block on a consistent filter (a linear-Gaussian model with the true
/// Q and R). Every field: docs/settings.md §2.
template <class Scalar>
struct HealthSettings {
  /// false: no test runs, `health()` stays Ok, the statistics stay zero.
  bool enabled = true;
  /// Committed measurement updates per block, ≥ 10.
  int window = 50;
  /// The false-alarm probability of each test per block, in (0, 0.5): the NIS test spends α/2 at each
  /// tail (the lower one an alarm only with `flagSmallInnovations`), the whiteness test α. A run of 10⁴
  /// updates (200 blocks) of a consistent filter raises a false alarm with probability ≈ 3e-4.
  Scalar falseAlarmProbability = Scalar(1e-6);
  /// A parameter moving more than this many of its standard deviations within a block is running
  /// away; > 0. Only filters that report a parameter covariance (JointUkf, DualUkf, an MJUKF that
  /// follows its own) run this test.
  Scalar runawaySigmas = Scalar(10);
  /// Refused calls in a row that raise `RepeatedRefusals`, ≥ 1.
  int refusalStreak = 10;
  /// Whether a block whose NIS sum is below its lower χ² bound raises `InnovationsTooSmall`. false (the
  /// default): it is counted in `smallInnovationBlocks` and raises nothing, since a covariance larger
  /// than the errors overstates the uncertainty instead of hiding it. true: to be told that Q or R is
  /// far too large (docs/troubleshooting.md).
  bool flagSmallInnovations = false;
  /// The blocks the verdict remembers, 1 to 16. A block that fails a test raises its alarm at once, and
  /// the alarm stands while at least half of the last `verdictMemory` complete blocks of the pass (all
  /// of them, while there are fewer) raised one: a filter that diverged does not read Ok again after
  /// one quiet block, and an alarm early in a run that then settles does not stand for the rest of it.
  /// 1: the last block's verdict alone.
  int verdictMemory = 10;
};

/// The numbers behind `health()` (a filter's `healthStatistics()`).
template <class Scalar>
struct HealthStatistics {
  /// The first alarm since construction, `reset` or `clearHealth()`: it stays, so a run that went
  /// wrong and recovered still says so at its end (`health()` is the state now).
  Health firstAlarm = Health::Ok;
  /// The verdict of the last complete block alone (Ok when it raised no alarm).
  Health lastBlock = Health::Ok;
  /// The latest alarm of a block among the last `verdictMemory` (Ok when none raised one): what
  /// `health()` returns when the last block raised it or while at least half of them alarmed, unless a
  /// streak of refusals is under way.
  Health latestAlarm = Health::Ok;
  /// The committed measurement update at which `firstAlarm` was raised (counting from 1); 0 if none.
  long alarmAtUpdate = 0;
  /// Committed measurement updates since construction or `reset`.
  long updates = 0;
  /// Complete blocks.
  long blocks = 0;
  /// Complete blocks that raised an alarm.
  long alarmedBlocks = 0;
  /// Complete blocks whose NIS sum was below its lower bound (alarmed or not, `flagSmallInnovations`).
  long smallInnovationBlocks = 0;
  /// The complete blocks the verdict remembers: the last `verdictMemory` of this pass, or all of them
  /// while there are fewer.
  int blocksInMemory = 0;
  /// Of those, the ones that raised an alarm.
  int alarmedInMemory = 0;
  /// The last complete block's summed NIS over its degrees of freedom (1 on a consistent filter).
  Scalar normalisedNis = 0;
  /// The lower bound `normalisedNis` was tested against, on the same scale.
  Scalar nisLowerBound = 0;
  /// The upper bound `normalisedNis` was tested against, on the same scale.
  Scalar nisUpperBound = 0;
  /// The last complete block's largest |√N r₁| over the measured components (r₁ the lag-one
  /// autocorrelation of the component's normalised innovation; ~N(0, 1) when they are white).
  Scalar autocorrelationScore = 0;
  /// The bound `autocorrelationScore` was tested against.
  Scalar autocorrelationBound = 0;
  /// The last complete block's largest parameter motion in standard deviations (0 without a covariance).
  Scalar parameterMotionSigmas = 0;
  /// Refused calls in a row, now: the longer of the two streaks (measurement updates; propagations).
  int refusalsInARow = 0;
};

/// \cond INTERNAL
namespace detail {

template <class Scalar>
SettingsError validateHealth(const char* owner, const HealthSettings<Scalar>& health) {
  if (health.window < 10) return invalid(owner, "health.window", "must be >= 10");
  if (SettingsError e = requireFinite(owner, "health.falseAlarmProbability", health.falseAlarmProbability)) return e;
  if (!(health.falseAlarmProbability > 0 && health.falseAlarmProbability < Scalar(0.5)))
    return invalid(owner, "health.falseAlarmProbability", "must be in (0, 0.5)");
  if (SettingsError e = requireFinite(owner, "health.runawaySigmas", health.runawaySigmas)) return e;
  if (!(health.runawaySigmas > 0)) return invalid(owner, "health.runawaySigmas", "must be positive");
  if (health.refusalStreak < 1) return invalid(owner, "health.refusalStreak", "must be >= 1");
  if (health.verdictMemory < 1 || health.verdictMemory > 16)
    return invalid(owner, "health.verdictMemory", "must be in [1, 16]");
  return {};
}

// What a call was, for the refusal streaks.
enum class CallKind { Measurement, Propagation };

// The monitor: accumulates one block of updates at a time in fixed-size members (no allocation), and
// tests a block when it is complete. Costs O(m) per update and O(m + p) per block.
template <class Scalar, int MeasDim, int ParamDim>
class HealthMonitor {
 public:
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  using Mask = Eigen::Matrix<bool, MeasDim, 1>;

  HealthMonitor() = default;
  // From validated settings: the χ² and normal quantiles are computed here, once.
  explicit HealthMonitor(const HealthSettings<Scalar>& settings) : settings_(settings) {
    const double alpha = double(settings.falseAlarmProbability);
    const int fullDof = settings.window * MeasDim;
    // Wilson–Hilferty, χ²_q(k) ≈ k (1 − c + z √c)³ with c = 2/(9k), with z fitted to the exact quantile
    // at the block's full degrees of freedom: exact there, within a fraction of a percent for a block
    // with missing components.
    upperZ_ = Scalar(wilsonHilfertyZ(chiSquareQuantile(1 - alpha / 2, fullDof), fullDof));
    lowerZ_ = Scalar(wilsonHilfertyZ(chiSquareQuantile(alpha / 2, fullDof), fullDof));
    // |Z| ≤ z with probability 1 − α/m (Bonferroni over the components): z² is χ²(1)'s quantile.
    autocorrelationBound_ = Scalar(std::sqrt(chiSquareQuantile(1 - alpha / MeasDim, 1)));
    startBlock();
  }

  const HealthStatistics<Scalar>& statistics() const { return stats_; }
  // Now: refusals in a row at the streak's length; else the latest alarm if the last block raised it or
  // while at least half of the remembered blocks raised one; else Ok.
  Health health() const {
    if (settings_.enabled &&
        (measurementRefusals_ >= settings_.refusalStreak || propagationRefusals_ >= settings_.refusalStreak))
      return Health::RepeatedRefusals;
    const bool standing = stats_.alarmedInMemory > 0 && 2 * stats_.alarmedInMemory >= stats_.blocksInMemory;
    return stats_.lastBlock != Health::Ok || standing ? stats_.latestAlarm : Health::Ok;
  }

  // Everything back to the start (reset()).
  void clear() {
    stats_ = HealthStatistics<Scalar>();
    forgetVerdicts();
    measurementRefusals_ = propagationRefusals_ = 0;
    startBlock();
    blockStarted_ = false;
  }
  // The first alarm only (clearHealth()).
  void clearAlarm() {
    stats_.firstAlarm = Health::Ok;
    stats_.alarmAtUpdate = 0;
  }
  // A new pass: the block under way and the remembered verdicts are dropped (a pass restarted from a
  // healthy estimate starts Ok), the first alarm and the counts kept.
  void restartBlock() {
    startBlock();
    blockStarted_ = false;
    forgetVerdicts();
  }

  // Every public call's outcome: counts refusals in a row, of measurement updates and of propagations
  // (time updates and open-loop propagations) apart, so that a filter whose every measurement is
  // refused (a gate that lost lock) is flagged although its time updates between them are taken.
  void observeStatus(Status status, CallKind kind) {
    if (!settings_.enabled) return;
    int& streak = kind == CallKind::Measurement ? measurementRefusals_ : propagationRefusals_;
    streak = taken(status) ? 0 : streak + 1;
    stats_.refusalsInARow = measurementRefusals_ > propagationRefusals_ ? measurementRefusals_ : propagationRefusals_;
    if (streak >= settings_.refusalStreak) raise(Health::RepeatedRefusals);
  }

  // Whether the next committed update starts or ends a block: where the parameters' σ is read.
  bool atBlockBoundary() const { return !blockStarted_ || updatesInBlock_ + 1 >= settings_.window; }

  // A committed measurement update: its innovation ν, the diagonal of P_yy and its NIS over the
  // components present (`present` null: all). `parameters` and `parameterSigma` (negative: none) are
  // the estimate after the update, for the parameter tests at the block's end.
  template <class InnovationCovariance>
  void observeUpdate(const Meas& innovation, const InnovationCovariance& innovationCovariance, Scalar nis,
                     const Mask* present, const Param& parameters, const Param& parameterSigma, const Param& lowerBound,
                     const Param& upperBound) {
    if (!settings_.enabled) return;
    if (!blockStarted_) {
      blockStartParameters_ = parameters;
      blockStartSigma_ = parameterSigma;
      blockStarted_ = true;
    }
    ++stats_.updates;
    nisSum_ += nis;
    for (int i = 0; i < MeasDim; ++i) {
      const bool here = present == nullptr || (*present)(i);
      if (!here) {
        previousPresent_(i) = false;
        continue;
      }
      ++dof_;
      using std::sqrt;
      const Scalar normalised = innovation(i) / sqrt(innovationCovariance(i, i));
      squares_(i) += normalised * normalised;
      ++count_(i);
      if (previousPresent_(i)) lagProducts_(i) += normalised * previous_(i);
      previous_(i) = normalised;
      previousPresent_(i) = true;
    }
    if (++updatesInBlock_ < settings_.window) return;
    testBlock(parameters, parameterSigma, lowerBound, upperBound);
    startBlock();
    blockStartParameters_ = parameters;
    blockStartSigma_ = parameterSigma;
  }

 private:
  static double wilsonHilfertyZ(double quantile, int dof) {
    const double c = 2.0 / (9.0 * dof);
    return (std::cbrt(quantile / dof) - 1 + c) / std::sqrt(c);
  }
  Scalar wilsonHilferty(Scalar z, int dof) const {
    const Scalar c = Scalar(2) / Scalar(9 * dof);
    const Scalar root = Scalar(1) - c + z * std::sqrt(c);
    return Scalar(dof) * root * root * root;
  }

  void testBlock(const Param& parameters, const Param& parameterSigma, const Param& lowerBound,
                 const Param& upperBound) {
    ++stats_.blocks;
    Health verdict = Health::Ok;
    // Innovation consistency: the block's NIS sum against χ²(dof) at both tails.
    if (dof_ > 0) {
      const Scalar upper = wilsonHilferty(upperZ_, dof_), lower = wilsonHilferty(lowerZ_, dof_);
      stats_.normalisedNis = nisSum_ / Scalar(dof_);
      stats_.nisUpperBound = upper / Scalar(dof_);
      stats_.nisLowerBound = lower / Scalar(dof_);
      if (!(nisSum_ <= upper))
        verdict = Health::InnovationsTooLarge;  // NaN fails too
      else if (nisSum_ < lower) {
        ++stats_.smallInnovationBlocks;
        if (settings_.flagSmallInnovations) verdict = Health::InnovationsTooSmall;
      }
    }
    // Whiteness: √N r₁ per component, r₁ = Σ eₖ eₖ₋₁ / Σ eₖ².
    Scalar worst = 0;
    for (int i = 0; i < MeasDim; ++i) {
      if (count_(i) < 2 || !(squares_(i) > 0)) continue;
      using std::abs, std::sqrt;
      const Scalar score = abs(lagProducts_(i) / squares_(i)) * sqrt(Scalar(count_(i)));
      if (score > worst) worst = score;
    }
    stats_.autocorrelationScore = worst;
    stats_.autocorrelationBound = autocorrelationBound_;
    if (verdict == Health::Ok && worst > autocorrelationBound_) verdict = Health::InnovationsCorrelated;
    // Parameters: motion in the block's starting σ, and the bounds.
    Scalar motion = 0;
    for (int j = 0; j < ParamDim; ++j) {
      if (!(blockStartSigma_(j) > 0)) continue;
      using std::abs;
      const Scalar sigmas = abs(parameters(j) - blockStartParameters_(j)) / blockStartSigma_(j);
      if (!(sigmas <= motion)) motion = sigmas;  // a NaN is kept unless a later larger value replaces it
    }
    stats_.parameterMotionSigmas = motion;
    if (verdict == Health::Ok && !(motion <= settings_.runawaySigmas)) verdict = Health::ParameterRunaway;
    // A σ that has become unbounded (the MJUKF's, when the error covariance it follows overflowed).
    for (int j = 0; j < ParamDim; ++j)
      if (verdict == Health::Ok && parameterSigma(j) == std::numeric_limits<Scalar>::infinity())
        verdict = Health::ParameterRunaway;
    if (verdict == Health::Ok) {
      for (int j = 0; j < ParamDim; ++j) {
        const bool bounded = lowerBound(j) > -std::numeric_limits<Scalar>::infinity() ||
                             upperBound(j) < std::numeric_limits<Scalar>::infinity();
        if (bounded && (parameters(j) <= lowerBound(j) || parameters(j) >= upperBound(j)))
          verdict = Health::ParameterAtBound;
      }
    }
    stats_.lastBlock = verdict;
    remember(verdict);
    if (verdict != Health::Ok) {
      ++stats_.alarmedBlocks;
      raise(verdict);
    }
  }

  // The last verdictMemory blocks, a bit each (1: alarmed), newest in bit 0.
  void remember(Health verdict) {
    const unsigned memoryMask = (1u << settings_.verdictMemory) - 1u;
    recentAlarms_ = ((recentAlarms_ << 1) | (verdict != Health::Ok ? 1u : 0u)) & memoryMask;
    if (verdict != Health::Ok) stats_.latestAlarm = verdict;
    int alarmed = 0;
    for (unsigned bits = recentAlarms_; bits != 0; bits &= bits - 1) ++alarmed;
    stats_.alarmedInMemory = alarmed;
    if (stats_.blocksInMemory < settings_.verdictMemory) ++stats_.blocksInMemory;
    if (alarmed == 0) stats_.latestAlarm = Health::Ok;
  }
  void forgetVerdicts() {
    recentAlarms_ = 0;
    stats_.blocksInMemory = stats_.alarmedInMemory = 0;
    stats_.latestAlarm = Health::Ok;
  }

  void raise(Health alarm) {
    if (stats_.firstAlarm != Health::Ok) return;
    stats_.firstAlarm = alarm;
    stats_.alarmAtUpdate = stats_.updates;
  }

  void startBlock() {
    updatesInBlock_ = 0;
    dof_ = 0;
    nisSum_ = 0;
    squares_.setZero();
    lagProducts_.setZero();
    count_.setZero();
    previous_.setZero();
    previousPresent_.setConstant(false);
  }

  HealthSettings<Scalar> settings_;
  HealthStatistics<Scalar> stats_;
  Scalar upperZ_ = 0, lowerZ_ = 0, autocorrelationBound_ = 0;
  // The block under way.
  int updatesInBlock_ = 0, dof_ = 0;
  Scalar nisSum_ = 0;
  Meas squares_ = Meas::Zero(), lagProducts_ = Meas::Zero(), previous_ = Meas::Zero();
  Eigen::Matrix<int, MeasDim, 1> count_ = Eigen::Matrix<int, MeasDim, 1>::Zero();
  Mask previousPresent_ = Mask::Constant(false);
  bool blockStarted_ = false;
  int measurementRefusals_ = 0, propagationRefusals_ = 0;
  unsigned recentAlarms_ = 0;
  Param blockStartParameters_ = Param::Zero(), blockStartSigma_ = Param::Constant(Scalar(-1));
};

}  // namespace detail
/// \endcond
}  // namespace mjukf
