#pragma once

/// \file
/// An explicit, second-order TR-BDF2: I-TR-BDF2's stages fed the plain predictor slopes.

#include "mjukf/detail/validation.hpp"

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

  /// `gamma` is the fraction of the step taken by the trapezoidal stage, in (0, 1).
  explicit ExplicitTrBdf2(Scalar gamma = Scalar(0.5)) : gamma_(gamma) {
    if (!(gamma > 0 && gamma < 1))
      detail::throwInvalid("mjukf::ExplicitTrBdf2", "gamma", "must lie in (0, 1)");
    const Scalar bdf2 = gamma * (Scalar(2) - gamma);  // γ(2 − γ)
    currentWeight_ = Scalar(1) / bdf2;
    previousWeight_ = -(Scalar(1) - gamma) * (Scalar(1) - gamma) / bdf2;
    slopeWeight_ = (Scalar(1) - gamma) / (Scalar(2) - gamma);
  }

  /// One step of size h from x at time t of ẋ = f(t, x); f is called as `f(Scalar t, const State& x)`.
  template <class F, class State>
  State step(F&& f, Scalar t, const State& x, Scalar h) const {
    const Scalar gh = gamma_ * h;
    const State k1 = f(t, x);
    const State k2 = f(t + gh, State(x + gh * k1));
    const State xGamma = x + (gh / Scalar(2)) * (k1 + k2);
    const State k3 = f(t + h, State(x + h * k1));
    return currentWeight_ * xGamma + previousWeight_ * x + (slopeWeight_ * h) * k3;
  }

  /// γ, the fraction of the step taken by the first stage.
  Scalar gamma() const { return gamma_; }

 private:
  Scalar gamma_;
  Scalar currentWeight_;   // 1 / (γ(2−γ))
  Scalar previousWeight_;  // −(1−γ)² / (γ(2−γ))
  Scalar slopeWeight_;     // (1−γ) / (2−γ)
};

}  // namespace mjukf
