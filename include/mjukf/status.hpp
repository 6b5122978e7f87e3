#pragma once

/// \file
/// The outcome of every per-step call of a filter.

namespace mjukf {

/// What a time update, an open-loop propagation or a measurement update did.
///
/// Any value other than `Status::Ok` means the call was refused and the filter is exactly as it was
/// before the call: estimate, covariance, parameters, sigma points and diagnostics.
enum class Status {
  Ok,                       ///< The step was taken.
  NonFiniteMeasurement,     ///< The measurement contains NaN or ±Inf.
  NonFiniteInput,           ///< The input held over the step contains NaN or ±Inf.
  InvalidStepSize,          ///< The integration step is not finite and positive, or the step count is < 1.
  NotPositiveDefinite,      ///< The covariance to draw sigma points from has no Cholesky factor.
  InnovationNotPositiveDefinite,  ///< The innovation covariance P_yy has no Cholesky factor.
  NonFiniteResult,          ///< The model or the update produced NaN or ±Inf.
};

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
  }
  return "unknown status";
}

}  // namespace mjukf
