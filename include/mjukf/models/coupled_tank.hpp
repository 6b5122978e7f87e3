#pragma once

/// \file
/// The coupled-tank plant (paper eqs. 1–2, Table 1; docs/plants.md §1).

#include <cmath>

#include <Eigen/Core>

namespace mjukf::models {

/// Two stacked water tanks: a pump fills the upper one, which drains through an orifice into the
/// lower one, which drains through a second orifice.
///
///     ḣ₁ = (k_flow u − c₁ √|h₁|) / A₁
///     ḣ₂ = (c₁ √|h₁| − c₂ √|h₂|) / A₂
///
/// State x = (h₁, h₂) in cm, parameter θ = (k_flow) in (cm³/s)/V, input u = pump voltage, y = x.
/// The measurement depends on k_flow linearly through ẋ, the class of system MJUKF is made for.
template <class Scalar_ = double>
struct CoupledTank {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 2: the levels (h₁, h₂).
  static constexpr int StateDim = 2;
  /// p = 1: k_flow.
  static constexpr int ParamDim = 1;
  /// m = 2: both levels are measured.
  static constexpr int MeasDim = 2;
  /// One input: the pump voltage.
  static constexpr int InputDim = 1;
  /// x = (h₁, h₂) in cm.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (k_flow) in (cm³/s)/V.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = (h₁, h₂).
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// u = (pump voltage) in V.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  Scalar area1 = Scalar(15.5179);  ///< A₁, cross-section of the upper tank (cm²)
  Scalar area2 = Scalar(15.5179);  ///< A₂, cross-section of the lower tank (cm²)
  Scalar orifice1 = Scalar(5);     ///< c₁, outflow coefficient of the upper tank
  Scalar orifice2 = Scalar(5);     ///< c₂, outflow coefficient of the lower tank
  Scalar pumpVoltage = Scalar(5);  ///< u = q_i, constant pump voltage (V)

  /// The true flow constant of the paper's experiment, θ = (k_flow) = (6).
  static Param trueParameters() { return Param::Constant(Scalar(6)); }

  /// The pump voltage: constant in the paper's experiment.
  Input input(Scalar /*t*/) const { return Input::Constant(pumpVoltage); }

  /// Eq. 1–2. The |·| under the roots keeps sigma points below the orifice defined.
  State derivative(Scalar /*t*/, const State& x, const Input& u, const Param& theta) const {
    const Scalar outflow1 = orifice1 * std::sqrt(std::abs(x(0)));
    const Scalar outflow2 = orifice2 * std::sqrt(std::abs(x(1)));
    return State((theta(0) * u(0) - outflow1) / area1, (outflow1 - outflow2) / area2);
  }

  /// Both levels are measured: y = x.
  Meas measurement(const State& x, const Param& /*theta*/) const { return x; }
};

}  // namespace mjukf::models
