#pragma once

/// \file
/// An explicit, second-order TR-BDF2: I-TR-BDF2's stages fed the plain predictor slopes.

#include "mjukf/detail/validation.hpp"
#include "mjukf/integrators/tr_bdf2_weights.hpp"
#include "mjukf/result.hpp"
#include "mjukf/settings_error.hpp"

namespace mjukf {

/// One step of an explicit TR-BDF2 that reaches second order at I-TR-BDF2's cost of three evaluations
/// of f per step (docs/algorithms.md §6 describes I-TR-BDF2; this variant differs only in the slopes):
///
///     k₁ = f(t, x)
///     k₂ = f(t + γh, x + γh k₁)                                   Euler predictor to t + γh
///     x_γ = x + (γh/2)(k₁ + k₂)                                   trapezoidal stage (Heun)
///     k₃ = f(t + h, x + h k₁)                                     Euler predictor to t + h
///     x(t + h) ≈ x_γ / (γ(2−γ)) − (1−γ)²/(γ(2−γ)) x + (1−γ)/(2−γ) h k₃   BDF2 stage
///
/// I-TR-BDF2 feeds the stages ½(k₂ + k₁) and ½(k₃ + k₁) instead; written as a Runge–Kutta method its
/// weights then satisfy Σ bᵢcᵢ = 1/4 for every γ (the second-order condition asks 1/2), which leaves
/// a local error of (h²/4)·ẍ, i.e. first order. Here Σ bᵢ = 1 and Σ bᵢcᵢ = 1/2 for every γ ∈ (0, 1),
/// so the method is second order (Σ bᵢcᵢ² ≠ 1/3: not third). It is explicit, so unlike the classic
/// implicit TR-BDF2 it is not L-stable and is not meant for stiff models.
///
/// Stateless apart from γ; with fixed-size Eigen vectors it allocates nothing.
template <class Scalar_>
class ExplicitTrBdf2 {
 public:
  /// The floating-point type.
  using Scalar = Scalar_;
  /// The order of convergence.
  static constexpr int order = 2;
  /// Evaluations of f per step.
  static constexpr int evaluationsPerStep = 3;

  /// γ = 1/2, the paper's choice.
  ExplicitTrBdf2() : ExplicitTrBdf2(detail::Validated{}, Scalar(0.5)) {}
#if MJUKF_EXCEPTIONS
  /// `gamma` is the fraction of the step taken by the trapezoidal stage, in (0, 1); throws
  /// std::invalid_argument naming it otherwise. Without exceptions, use `create`.
  explicit ExplicitTrBdf2(Scalar gamma) : ExplicitTrBdf2(detail::throwIfInvalid(validate(gamma)), gamma) {}
#endif
  /// The stepper, or the SettingsError naming `gamma` when it is not in (0, 1).
  static Result<ExplicitTrBdf2> create(Scalar gamma) {
    return detail::resultOf<ExplicitTrBdf2>(validate(gamma),
                                            [&] { return ExplicitTrBdf2(detail::Validated{}, gamma); });
  }
  /// The SettingsError naming `gamma` when it is not in (0, 1), or none: what the constructor would throw.
  static SettingsError validate(Scalar gamma) { return detail::validateStageFraction("mjukf::ExplicitTrBdf2", gamma); }

  /// One step of size h from x at time t of ẋ = f(t, x); f is called as `f(Scalar t, const State& x)`.
  template <class F, class State>
  State step(F&& f, Scalar t, const State& x, Scalar h) const {
    const Scalar gh = weights_.gamma * h;
    const State k1 = f(t, x);
    const State k2 = f(t + gh, State(x + gh * k1));
    const State xGamma = x + (gh / Scalar(2)) * (k1 + k2);
    const State k3 = f(t + h, State(x + h * k1));
    return weights_.current * xGamma + weights_.previous * x + (weights_.slope * h) * k3;
  }

  /// γ, the fraction of the step taken by the first stage.
  Scalar gamma() const { return weights_.gamma; }

 private:
  ExplicitTrBdf2(detail::Validated, Scalar gamma) : weights_(gamma) {}

  detail::Bdf2Weights<Scalar> weights_;
};

}  // namespace mjukf
