#pragma once

/// \file
/// The check of a time update's integration step against the model's dynamics: step doubling on the
/// mean (docs/robustness.md, "A step too large for the model").

#include "mjukf/detail/validation.hpp"
#include "mjukf/settings_error.hpp"

namespace mjukf {

/// What a filter does with an integration step that its check finds too large for the model.
enum class OversizedStep {
  Refuse,     ///< Refuse the call with `Status::StepTooLarge`; the filter is left as it was.
  Subdivide,  ///< Halve the step (and double the count) until it passes, then take the call.
  Accept,     ///< No check at all: every step is taken as given (the filters before the check).
};

/// The check of the integration step of a continuous-time model, run by `timeUpdate` and
/// `propagateMean` (a discrete-time model has no integration step and is never checked).
///
/// Step doubling on two points: the mean x̂, and x̂ + δ with a small offset δᵢ = max(σᵢ/100, √ε (|x̂ᵢ| + σᵢ))
/// (σᵢ = √Pᵢᵢ) whose motion follows the dynamics linearised about the mean, so that a step unstable for
/// the sigma points shows where the mean itself does not move, at an equilibrium. Each is propagated
/// over the call with steps of h as given and with steps of h/2, the input held at its value at the
/// call's start (a jump of the model's `input(t)` inside the step is not integration error). With
/// e = Φ_h(x̂) − Φ_{h/2}∘Φ_{h/2}(x̂), the step doubling estimate of the integration error (2ᵖ − 1 times
/// the error of the half steps for a method of order p: 1 for I-TR-BDF2, first order as used here
/// (docs/integrators.md), 15 for RK4), and Δ = Φ_{h/2}∘Φ_{h/2}(x̂) − x̂, the step fails when for some i
///
///     |eᵢ| > tolerance · (|Δᵢ| + σᵢ),   or the same of the offset's motion, with δᵢ in place of σᵢ,
///
/// that is when the error is not small against both what the step moves the estimate and what the
/// filter does not know about it. Both are scale-free: no unit of the state enters the test. A step
/// inside the stability region of the stepper and resolving the dynamics passes with orders of
/// magnitude to spare; a step of seconds given to a plant of milliseconds (or a unit mix-up, milliseconds
/// passed as seconds) fails by orders of magnitude. NaN or ±Inf from the half steps is the model's
/// fault and refused as `NonFiniteResult`.
///
/// Cost: six propagations of the mean (two points, over h and twice over h/2), against 2L + 1 of sigma
/// points for the call itself. So the check runs on the first time update, whenever the step (h or
/// the step count) differs from the last one checked, and on every `interval`-th call in between,
/// which keeps its mean cost at 6/interval propagations per call. Every field: docs/settings.md §2.
template <class Scalar>
struct StepCheck {
  /// What an oversized step does: refused by default.
  OversizedStep onOversized = OversizedStep::Refuse;
  /// The allowed step doubling difference, relative to |Δᵢ| + σᵢ; > 0. The default refuses a step whose
  /// error estimate is half of what it moves the estimate or more: an unstable or grossly unresolved
  /// step, not a merely inaccurate one (a smaller tolerance asks for accuracy too).
  Scalar tolerance = Scalar(0.5);
  /// A step unchanged since the last check is checked again every `interval` calls; ≥ 1.
  int interval = 16;
  /// With `Subdivide`: the largest number of halvings checked (the step becomes at most h / 2^(maxHalvings
  /// − 1)) before the call is refused with `StepTooLarge` after all; in [0, 20]. A subdivided step is
  /// taken only when the next halving passes the check too: far outside the stability region two
  /// levels of step doubling can agree by coincidence.
  int maxHalvings = 10;
};

/// \cond INTERNAL
namespace detail {

template <class Scalar>
SettingsError validateStepCheck(const char* owner, const StepCheck<Scalar>& check) {
  if (SettingsError e = requireFinite(owner, "stepCheck.tolerance", check.tolerance)) return e;
  if (!(check.tolerance > 0)) return invalid(owner, "stepCheck.tolerance", "must be positive");
  if (check.interval < 1) return invalid(owner, "stepCheck.interval", "must be >= 1");
  if (check.maxHalvings < 0 || check.maxHalvings > 20)
    return invalid(owner, "stepCheck.maxHalvings", "must be in [0, 20]");
  if (check.onOversized != OversizedStep::Refuse && check.onOversized != OversizedStep::Subdivide &&
      check.onOversized != OversizedStep::Accept)
    return invalid(owner, "stepCheck.onOversized", "must be Refuse, Subdivide or Accept");
  return {};
}

}  // namespace detail
/// \endcond
}  // namespace mjukf
