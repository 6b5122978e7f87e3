#pragma once

/// \file
/// The classic fourth-order Runge–Kutta method.

namespace mjukf {

/// One step of the classic Runge–Kutta method (Kutta 1901), explicit, order 4, four evaluations of f:
///
///     k₁ = f(t, x)
///     k₂ = f(t + h/2, x + (h/2) k₁)
///     k₃ = f(t + h/2, x + (h/2) k₂)
///     k₄ = f(t + h,   x + h k₃)
///     x(t + h) ≈ x + (h/6)(k₁ + 2k₂ + 2k₃ + k₄)
///
/// Stateless; `step(f, t, x, h)` returns the state at t + h, where `f(t, x)` returns ẋ. With
/// fixed-size Eigen vectors it allocates nothing. Not for stiff models: it is stable only while
/// h·λ stays inside its region (|hλ| ≲ 2.8 on the negative real axis).
template <class Scalar_>
class Rk4 {
 public:
  /// The floating-point type.
  using Scalar = Scalar_;
  /// The order of convergence.
  static constexpr int order = 4;
  /// Evaluations of f per step.
  static constexpr int evaluationsPerStep = 4;

  /// One step of size h from x at time t of ẋ = f(t, x); f is called as `f(Scalar t, const State& x)`.
  template <class F, class State>
  State step(F&& f, Scalar t, const State& x, Scalar h) const {
    const Scalar half = h / Scalar(2);
    const State k1 = f(t, x);
    const State k2 = f(t + half, State(x + half * k1));
    const State k3 = f(t + half, State(x + half * k2));
    const State k4 = f(t + h, State(x + h * k3));
    return x + (h / Scalar(6)) * (k1 + Scalar(2) * (k2 + k3) + k4);
  }
};

}  // namespace mjukf
