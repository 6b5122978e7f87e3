#pragma once

/// \file
/// An optional recovery policy (docs/robustness.md, "Recovery"): a filter wrapped in `Recovering`
/// keeps a copy of itself at the end of every healthy block of its health monitor, and when the
/// monitor raises an alarm it takes that copy's parameters back, with the present state under an
/// inflated covariance, counts the recovery and records why. A filter that is not wrapped pays nothing.

#include <utility>

#include <Eigen/Core>

#include "mjukf/detail/validation.hpp"
#include "mjukf/health.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/status.hpp"

namespace mjukf {

/// The settings of `Recovering`. Every field: docs/settings.md §2.
template <class Scalar>
struct RecoverySettings {
  /// The factor on the state covariance of the last healthy estimate, under which the present state
  /// estimate goes on after a recovery; > 1. It must cover how far the present state has strayed.
  Scalar covarianceInflation = Scalar(10);
  /// Recoveries at most; after the last one an alarm stands, as without the policy. ≥ 1.
  int maxRecoveries = 3;
  /// Whether `Health::InnovationsTooSmall` also triggers a recovery. false (the default): innovations
  /// smaller than P_yy say that Q or R is too large, which going back does not change.
  bool onInnovationsTooSmall = false;
};

/// The first invalid field of `settings`, or none.
template <class Scalar>
SettingsError validateRecovery(const RecoverySettings<Scalar>& settings) {
  constexpr const char* owner = "mjukf::Recovering";
  if (SettingsError e = detail::requireFinite(owner, "covarianceInflation", settings.covarianceInflation)) return e;
  if (!(settings.covarianceInflation > Scalar(1))) return detail::invalid(owner, "covarianceInflation", "must be > 1");
  if (settings.maxRecoveries < 1) return detail::invalid(owner, "maxRecoveries", "must be >= 1");
  return SettingsError();
}

/// What the last recovery did (`Recovering::lastRecovery()`).
template <class Scalar>
struct RecoveryRecord {
  /// The alarm that triggered it (`Health::Ok` before the first recovery).
  Health alarm = Health::Ok;
  /// The filter's time() when the alarm was raised.
  Scalar alarmTime = 0;
  /// The time of the healthy estimate whose parameters were taken back.
  Scalar restoredTime = 0;
  /// Measurement updates (committed or not) passed to the wrapper before the alarm.
  long atUpdate = 0;
};

/// `Filter` with the recovery policy: every per-step call goes to the filter, and after each one,
///
/// - a block of the health monitor that ended without an alarm that triggers a recovery (below) makes
///   the filter's present state the one to go back to (a copy of the whole filter: fixed size, no
///   allocation);
/// - an alarm (any but `InnovationsTooSmall` unless `onInnovationsTooSmall`, and `RepeatedRefusals`
///   as soon as it is raised) sends the filter back to that copy's parameters, and all it knew of them,
///   with the present state estimate under the copy's state covariance times `covarianceInflation`, at
///   the present time (the copy's `startPass`), while `maxRecoveries` allows.
///
/// Each recovery is counted (`recoveries()`) and recorded (`lastRecovery()`); the call that caused it
/// returns its own status, and `recoveredInLastCall()` says that the filter was replaced after it. The
/// monitor of the restored filter starts afresh (a new pass clears it): the alarm is in the record.
/// Without a healthy block yet, the parameters go back to those the filter was built with.
template <class Filter>
class Recovering {
 public:
  /// The filter's scalar type.
  using Scalar = typename Filter::Scalar;
  /// The policy's settings.
  using Settings = RecoverySettings<Scalar>;

  /// Wraps `filter` with the default settings.
  explicit Recovering(const Filter& filter) : Recovering(detail::Validated{}, filter, Settings()) {}
#if MJUKF_EXCEPTIONS
  /// Wraps `filter` (a copy); throws std::invalid_argument naming the first invalid setting. Without
  /// exceptions, use `create`.
  Recovering(const Filter& filter, const Settings& settings)
      : Recovering(detail::throwIfInvalid(validateRecovery(settings)), filter, settings) {}
#endif
  /// The wrapped filter, or the SettingsError naming the first invalid setting.
  static Result<Recovering> create(const Filter& filter, const Settings& settings) {
    return detail::resultOf<Recovering>(validateRecovery(settings),
                                        [&] { return Recovering(detail::Validated{}, filter, settings); });
  }

  /// The filter as it is now (after any recovery).
  const Filter& filter() const { return filter_; }
  /// Recoveries so far.
  int recoveries() const { return recoveries_; }
  /// What the last recovery did.
  const RecoveryRecord<Scalar>& lastRecovery() const { return last_; }
  /// Whether the filter was sent back to its last healthy state after the last call.
  bool recoveredInLastCall() const { return recoveredInLastCall_; }
  /// The filter's health now, as `Filter::health()`.
  Health health() const { return filter_.health(); }

  /// `Filter::timeUpdate` with the same arguments, then the policy.
  template <class... Args>
  Status timeUpdate(Args&&... args) {
    const Status status = filter_.timeUpdate(std::forward<Args>(args)...);
    afterCall();
    return status;
  }
  /// `Filter::propagateMean` with the same arguments, then the policy.
  template <class... Args>
  Status propagateMean(Args&&... args) {
    const Status status = filter_.propagateMean(std::forward<Args>(args)...);
    afterCall();
    return status;
  }
  /// `Filter::measurementUpdate` with the same arguments, then the policy.
  template <class... Args>
  Status measurementUpdate(Args&&... args) {
    const Status status = filter_.measurementUpdate(std::forward<Args>(args)...);
    ++measurementCalls_;
    afterCall();
    return status;
  }

 private:
  Recovering(detail::Validated, const Filter& filter, const Settings& settings)
      : filter_(filter), healthy_(filter), settings_(settings) {}

  bool triggers(Health health) const {
    if (health == Health::Ok) return false;
    return health != Health::InnovationsTooSmall || settings_.onInnovationsTooSmall;
  }

  void afterCall() {
    recoveredInLastCall_ = false;
    const long blocks = filter_.healthStatistics().blocks;
    const bool blockEnded = blocks != blocksSeen_;
    blocksSeen_ = blocks;
    const Health health = filter_.health();
    if (triggers(health) && (blockEnded || health == Health::RepeatedRefusals)) {
      if (recoveries_ < settings_.maxRecoveries) recover(health);
      return;
    }
    // The block raised no alarm that triggers a recovery (one that does not, InnovationsTooSmall by
    // default, standing or not, does not stop the copies), and no streak of refusals is under way.
    if (blockEnded && !triggers(filter_.healthStatistics().lastBlock) && health != Health::RepeatedRefusals)
      healthy_ = filter_;
  }

  // Back to the last healthy filter, but at the present time and state: its parameters (and all it
  // knew of them) with the present state estimate, under the healthy state covariance inflated. The
  // state is not taken from the copy: a block old, it would be as far from the truth as the plant moved
  // since. A new pass (`startPass`) does exactly this, and clears the monitor.
  void recover(Health alarm) {
    last_.alarm = alarm;
    last_.alarmTime = filter_.time();
    last_.restoredTime = healthy_.time();
    last_.atUpdate = measurementCalls_;
    const auto state = filter_.state();
    const Scalar time = filter_.time();
    filter_ = healthy_;
    constexpr int n = Filter::StateDim;
    const Eigen::Matrix<Scalar, n, n> covariance =
        settings_.covarianceInflation * healthy_.covariance().template topLeftCorner<n, n>();
    filter_.startPass(time, state, covariance);
    blocksSeen_ = filter_.healthStatistics().blocks;
    ++recoveries_;
    recoveredInLastCall_ = true;
  }

  Filter filter_;
  Filter healthy_;  // the filter at the end of its last healthy block
  Settings settings_;
  RecoveryRecord<Scalar> last_;
  long blocksSeen_ = 0;
  long measurementCalls_ = 0;
  int recoveries_ = 0;
  bool recoveredInLastCall_ = false;
};

}  // namespace mjukf
