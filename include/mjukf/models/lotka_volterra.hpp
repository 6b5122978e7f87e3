#pragma once

/// \file
/// Lotka–Volterra predator and prey, the predator unmeasured: a plant of the gallery (docs/studies.md,
/// "The gallery"), whose parameters act on the state nobody measures.

#include <Eigen/Core>

namespace mjukf::models {

/// Prey x and predators y (thousands of animals) over time in years:
///
///     ẋ = α x − β x y
///     ẏ = δ x y − γ y
///
/// State x = (x, y); parameters θ = (δ, γ): the predators' growth per prey met, δ in
/// 1/(year·thousand), and their death rate γ in 1/year; no input; y = x, the prey count alone. Known:
/// the prey's growth rate α = 1.1 /year and the predation rate β = 0.4 /(year·thousand).
///
/// True values δ = 0.1, γ = 0.4: the populations cycle about (γ/δ, α/β) = (4, 2.75) with a period of
/// about 2π/√(αγ) = 9.5 years near that point, longer on wide cycles. The parameters estimated are the
/// predator's: the prey is measured, but with the predator count unknown β could not be told from it
/// (the prey sees only β y), so β is taken as known.
template <class Scalar_ = double>
struct LotkaVolterra {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 2: prey and predators.
  static constexpr int StateDim = 2;
  /// p = 2: δ and γ.
  static constexpr int ParamDim = 2;
  /// m = 1: the prey.
  static constexpr int MeasDim = 1;
  /// No input.
  static constexpr int InputDim = 0;
  /// x = (prey, predators) in thousands of animals.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (δ, γ) in 1/(year·thousand) and 1/year.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = (prey) in thousands.
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// The empty input vector.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  Scalar preyGrowth = Scalar(1.1);  ///< α, the prey's growth rate without predators (1/year)
  Scalar predation = Scalar(0.4);   ///< β, prey taken per predator and prey (1/(year·thousand))

  /// The true predator constants, θ = (δ, γ) = (0.1, 0.4).
  static Param trueParameters() { return Param(Scalar(0.1), Scalar(0.4)); }

  /// No input: the empty vector, so that filters and simulations need no input argument.
  Input input(Scalar /*t*/) const { return Input(); }

  /// ẋ = α x − β x y, ẏ = δ x y − γ y.
  State derivative(Scalar /*t*/, const State& x, const Input& /*u*/, const Param& theta) const {
    return State(x(0) * (preyGrowth - predation * x(1)), x(1) * (theta(0) * x(0) - theta(1)));
  }

  /// The prey alone: y = x₁.
  Meas measurement(const State& x, const Param& /*theta*/) const { return Meas::Constant(x(0)); }
};

}  // namespace mjukf::models
