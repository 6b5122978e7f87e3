#pragma once

/// \file
/// I-TR-BDF2, the explicit predictor-based TR-BDF2 of the paper's reference scripts (docs/algorithms.md §6).

#include <cmath>

#include "mjukf/detail/validation.hpp"
#include "mjukf/integrators/tr_bdf2_weights.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"

namespace mjukf {

/// One step of I-TR-BDF2: a trapezoidal stage to t + γh and a BDF2 stage to t + h, each fed an
/// explicit Euler predictor, so there is no Newton solve. Three evaluations of f per step.
///
/// A stepper is stateless apart from its settings: `step(f, t, x, h)` returns the state at t + h,
/// where `f(t, x)` returns ẋ.
template <class Scalar_>
class ITrBdf2 {
 public:
  /// The floating-point type.
  using Scalar = Scalar_;
  /// Order of convergence the paper's variant is declared to reach (its averaged stage slopes keep a
  /// first-order error term; the cross-check against SUNDIALS measures it).
  static constexpr int order = 1;
  /// Evaluations of f per step.
  static constexpr int evaluationsPerStep = 3;

  /// γ = 1/2, the paper's choice.
  ITrBdf2() : ITrBdf2(detail::Validated{}, Scalar(0.5)) {}
#if MJUKF_EXCEPTIONS
  /// `gamma` is the fraction of the step taken by the trapezoidal stage, in (0, 1); throws
  /// std::invalid_argument naming it otherwise. Without exceptions, use `create`.
  explicit ITrBdf2(Scalar gamma) : ITrBdf2(detail::throwIfInvalid(validate(gamma)), gamma) {}
#endif
  /// The stepper, or the SettingsError naming `gamma` when it is not in (0, 1).
  static Result<ITrBdf2> create(Scalar gamma) {
    return detail::resultOf<ITrBdf2>(validate(gamma), [&] { return ITrBdf2(detail::Validated{}, gamma); });
  }
  /// The SettingsError naming `gamma` when it is not in (0, 1), or none: what the constructor would throw.
  static SettingsError validate(Scalar gamma) { return detail::validateStageFraction("mjukf::ITrBdf2", gamma); }

  /// One step of size h from x at time t of ẋ = f(t, x); f is called as `f(Scalar t, const State& x)`.
  template <class F, class State>
  State step(F&& f, Scalar t, const State& x, Scalar h) const {
    const State fk = f(t, x);
    const Scalar gh = weights_.gamma * h;
    // Trapezoidal stage: f_γ = ½ [f(x + γh f_k, t + γh) + f_k],  x_γ = x + (γh/2)(f_k + f_γ).
    const State fGamma = Scalar(0.5) * (f(t + gh, State(x + gh * fk)) + fk);
    const State xGamma = x + (gh / Scalar(2)) * (fk + fGamma);
    // BDF2 stage: f_1 = ½ [f(x + h f_k, t + h) + f_k],
    // x_{k+1} = x_γ / (γ(2−γ)) − (1−γ)²/(γ(2−γ)) x_k + (1−γ)/(2−γ) h f_1.
    const State f1 = Scalar(0.5) * (f(t + h, State(x + h * fk)) + fk);
    return weights_.current * xGamma + weights_.previous * x + (weights_.slope * h) * f1;
  }

  /// γ, the fraction of the step taken by the first stage.
  Scalar gamma() const { return weights_.gamma; }

 private:
  ITrBdf2(detail::Validated, Scalar gamma) : weights_(gamma) {}

  detail::Bdf2Weights<Scalar> weights_;
};

}  // namespace mjukf
