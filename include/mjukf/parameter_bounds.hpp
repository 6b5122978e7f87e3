#pragma once

/// \file
/// Lower and upper bounds on the estimated parameters of `JointUkf`, `ModifiedJointUkf` and `DualUkf`.

#include <limits>

#include <Eigen/Core>

#include "mjukf/detail/validation.hpp"

namespace mjukf {

/// Box bounds lower ≤ θ ≤ upper on the estimated parameters (off by default: ±∞).
///
/// Applied by clamping what a step commits, never the covariance:
/// - JointUkf: the θ block of the mean after every time and measurement update is clamped; P is left
///   as the update made it. P still describes the spread of the estimate, so sigma points drawn around
///   a clamped mean can lie outside the box by up to γ·σ: use a model that is defined there, or a
///   smaller P₀ and Q for that parameter.
/// - ModifiedJointUkf: each per-point θᵢ is clamped after eq. 9 (every θᵢ is used to propagate a
///   point, so every one must be valid), and θ̂ is their mean (eq. 10), which is then in the box too.
///   The θᵢ of eq. 8 are clamped at construction.
/// - DualUkf: θ̂ is clamped after each correction of the parameter filter; P^θ is left as it is.
/// The initial parameters must lie in the box. Every field: docs/settings.md §3.
template <class Scalar, int ParamDim>
struct ParameterBounds {
  /// The parameter vector θ.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  Param lower = Param::Constant(-std::numeric_limits<Scalar>::infinity());  ///< no NaN
  Param upper = Param::Constant(std::numeric_limits<Scalar>::infinity());   ///< ≥ lower, no NaN

  /// True when some bound is finite (clamping does something).
  bool active() const {
    return (lower.array() > -std::numeric_limits<Scalar>::infinity()).any() ||
           (upper.array() < std::numeric_limits<Scalar>::infinity()).any();
  }
  /// θ clamped to the box, in place.
  template <class Derived>
  void clamp(Eigen::MatrixBase<Derived>&& theta) const {
    theta = theta.cwiseMax(lower).cwiseMin(upper);
  }
  /// Clamps each component of θ into its bounds (components without bounds are left as they are).
  template <class Derived>
  void clamp(Eigen::MatrixBase<Derived>& theta) const {
    theta = theta.cwiseMax(lower).cwiseMin(upper);
  }
};

/// \cond INTERNAL
namespace detail {

// The bounds, and `initial` (named `initialName` in the message) within them.
template <class Scalar, int ParamDim, class Initial>
SettingsError validateBounds(const char* owner, const ParameterBounds<Scalar, ParamDim>& bounds, const Initial& initial,
                             const char* initialName = "initialParameters") {
  if (bounds.lower.hasNaN() || bounds.upper.hasNaN()) return invalid(owner, "parameterBounds", "must not be NaN");
  if (!(bounds.lower.array() <= bounds.upper.array()).all())
    return invalid(owner, "parameterBounds", "must have lower <= upper");
  if (!(initial.array() >= bounds.lower.array()).all() || !(initial.array() <= bounds.upper.array()).all())
    return invalid(owner, initialName, "must lie within parameterBounds");
  return {};
}

// The initial values of a filter that estimates parameters: finite, and the parameters in the bounds.
// `stateName` and `parametersName` are the names the caller gives them (reset() calls them "state" and
// "parameters").
template <class State, class Param, class Scalar, int ParamDim>
SettingsError checkInitialValues(const char* owner, const State& initialState, const Param& initialParameters,
                                 const ParameterBounds<Scalar, ParamDim>& bounds,
                                 const char* stateName = "initialState",
                                 const char* parametersName = "initialParameters") {
  if (SettingsError e = requireFinite(owner, stateName, initialState)) return e;
  if (SettingsError e = requireFinite(owner, parametersName, initialParameters)) return e;
  return validateBounds(owner, bounds, initialParameters, parametersName);
}

}  // namespace detail
/// \endcond
}  // namespace mjukf
