#pragma once

/// \file
/// The outcome of every per-step call of a filter.

namespace mjukf {

/// What a time update, an open-loop propagation or a measurement update did.
///
/// Two values mean the step was taken: `Status::Ok`, and `Status::Repaired` when the covariance the
/// step produced had to be repaired before it was committed (see covariance_repair.hpp); test with
/// `taken(status)`. Every other value means the call was refused and the filter is exactly as it was
/// before the call: estimate, covariance, parameters, sigma points and diagnostics. (Its health monitor
/// counts the refusal: a streak of them is an alarm, health.hpp.)
///
/// `Repaired` only occurs when a step would otherwise have been refused with `NotPositiveDefinite`,
/// so code written as `status == Status::Ok` keeps its meaning: it treats a repaired step as one to
/// look at, never a refused one as taken.
enum class Status {
  Ok,                    ///< The step was taken.
  NonFiniteMeasurement,  ///< A (present) component of the measurement is NaN or ±Inf.
  NonFiniteInput,        ///< The input held over the step contains NaN or ±Inf.
  InvalidStepSize,       ///< The integration step is not finite and positive, or the step count is < 1.
  /// The covariance to draw sigma points from, or the one the step would commit, has no Cholesky
  /// factor, and the bounded repair (when enabled) did not give it one.
  NotPositiveDefinite,
  InnovationNotPositiveDefinite,  ///< The innovation covariance P_yy has no Cholesky factor.
  NonFiniteResult,                ///< The model or the update produced NaN or ±Inf.
  /// The step was taken, with a covariance made positive definite by the documented repair (a small
  /// multiple of the identity added to it).
  Repaired,
  /// The measurement update was refused by the gate: its normalised innovation squared exceeded the
  /// threshold (measurement_gating.hpp). The estimate is unchanged; the measurement was an outlier.
  MeasurementRejected,
  /// The integration step is too large for the model's dynamics: its step doubling error estimate
  /// exceeded the tolerance (step_check.hpp), and the settings say to refuse such a step (or it still
  /// did after the largest number of halvings).
  StepTooLarge,
};

/// True when the step was taken (`Ok` or `Repaired`), false when it was refused.
constexpr bool taken(Status status) noexcept { return status == Status::Ok || status == Status::Repaired; }

/// A short English description of `status`, for logs and error messages.
constexpr const char* toString(Status status) noexcept {
  switch (status) {
    case Status::Ok: return "ok";
    case Status::NonFiniteMeasurement: return "non-finite measurement";
    case Status::NonFiniteInput: return "non-finite input";
    case Status::InvalidStepSize: return "invalid step size or step count";
    case Status::NotPositiveDefinite: return "covariance is not positive definite";
    case Status::InnovationNotPositiveDefinite: return "innovation covariance is not positive definite";
    case Status::NonFiniteResult: return "non-finite result";
    case Status::Repaired: return "ok after a covariance repair";
    case Status::MeasurementRejected: return "measurement rejected by the gate";
    case Status::StepTooLarge: return "integration step too large for the model's dynamics";
  }
  return "unknown status";
}

}  // namespace mjukf
