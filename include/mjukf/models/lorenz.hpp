#pragma once

/// \file
/// The Lorenz system, one of the two systems of the 2019 MJUKF paper (not a plant of the paper this
/// library reproduces; docs/studies.md).

#include <Eigen/Core>

namespace mjukf::models {

/// The chaotic convection model of Lorenz (1963):
///
///     ẋ₁ = σ (x₂ − x₁)
///     ẋ₂ = x₁ (ρ − x₃) − x₂
///     ẋ₃ = x₁ x₂ − β x₃
///
/// State x = (x₁, x₂, x₃), parameters θ = (σ, ρ, β) in this order, no input, y = x. Each parameter
/// enters one component of ẋ, linearly.
template <class Scalar_ = double>
struct Lorenz {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 3: x₁, x₂, x₃.
  static constexpr int StateDim = 3;
  /// p = 3: σ, ρ and β.
  static constexpr int ParamDim = 3;
  /// m = 3: the whole state is measured.
  static constexpr int MeasDim = 3;
  /// No input.
  static constexpr int InputDim = 0;
  /// x = (x₁, x₂, x₃), dimensionless: the convection intensity and the horizontal and vertical
  /// temperature deviations.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (σ, ρ, β), dimensionless: the Prandtl number, the (scaled) Rayleigh number and the geometric
  /// factor of the convection cell.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = x.
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// The empty input vector.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  /// The classic chaotic parameters of the 2019 paper's experiment, θ = (σ, ρ, β) = (10, 28, 8/3).
  static Param trueParameters() { return Param(Scalar(10), Scalar(28), Scalar(8) / Scalar(3)); }

  /// No input: the empty vector, so that filters and simulations need no input argument.
  Input input(Scalar /*t*/) const { return Input(); }

  /// ẋ = (σ (x₂ − x₁), x₁ (ρ − x₃) − x₂, x₁ x₂ − β x₃).
  State derivative(Scalar /*t*/, const State& x, const Input& /*u*/, const Param& theta) const {
    const Scalar sigma = theta(0), rho = theta(1), beta = theta(2);
    return State(sigma * (x(1) - x(0)), x(0) * (rho - x(2)) - x(1), x(0) * x(1) - beta * x(2));
  }

  /// Every state is measured: y = x.
  Meas measurement(const State& x, const Param& /*theta*/) const { return x; }
};

}  // namespace mjukf::models
