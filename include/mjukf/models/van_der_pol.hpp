#pragma once

/// \file
/// The Van der Pol oscillator, one of the two systems of the 2019 MJUKF paper (not a plant of the
/// paper this library reproduces; docs/studies.md).

#include <Eigen/Core>

namespace mjukf::models {

/// A self-excited oscillator with nonlinear damping μ:
///
///     ẋ₁ = x₂
///     ẋ₂ = μ (1 − x₁²) x₂ − x₁
///
/// State x = (x₁, x₂), parameter θ = (μ), no input, y = x. The measurement depends on μ only through
/// ẋ₂, linearly.
template <class Scalar_ = double>
struct VanDerPol {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 2: position and velocity.
  static constexpr int StateDim = 2;
  /// p = 1: μ.
  static constexpr int ParamDim = 1;
  /// m = 2: the whole state is measured.
  static constexpr int MeasDim = 2;
  /// No input.
  static constexpr int InputDim = 0;
  /// x = (x₁, x₂) = (position, velocity), dimensionless.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (μ), the dimensionless strength of the nonlinear damping (μ > 0: a limit cycle).
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = x.
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// The empty input vector.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  /// The true damping of the 2019 paper's experiment, θ = (μ) = (0.2).
  static Param trueParameters() { return Param::Constant(Scalar(0.2)); }

  /// No input: the empty vector, so that filters and simulations need no input argument.
  Input input(Scalar /*t*/) const { return Input(); }

  /// ẋ = (x₂, μ (1 − x₁²) x₂ − x₁).
  State derivative(Scalar /*t*/, const State& x, const Input& /*u*/, const Param& theta) const {
    return State(x(1), theta(0) * (Scalar(1) - x(0) * x(0)) * x(1) - x(0));
  }

  /// Both states are measured: y = x.
  Meas measurement(const State& x, const Param& /*theta*/) const { return x; }
};

}  // namespace mjukf::models
