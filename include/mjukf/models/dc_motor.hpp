#pragma once

/// \file
/// A DC motor driving a viscous load, measured by its shaft angle alone: a plant of the gallery
/// (docs/studies.md, "The gallery"), whose two parameters move the one measurement in opposite
/// directions.

#include <cmath>

#include <Eigen/Core>

namespace mjukf::models {

/// A permanent-magnet DC motor on a viscous load (a small pump), voltage-driven, its inductance
/// neglected (the electrical time constant is far below the mechanical one), so that the armature
/// current is i = (u − K ω) / R:
///
///     θ̇ = ω
///     ω̇ = (K (u − K ω) / R − b ω) / J
///
/// State x = (θ, ω) in rad and rad/s; parameters θ = (K, b): the torque constant K in N·m/A (= V·s/rad,
/// the back-EMF constant) and the viscous friction b in N·m·s/rad; input u = armature voltage in V;
/// y = θ, the encoder angle, alone. Known: R = 1 Ω, J = 1e-4 kg·m².
///
/// True values K = 0.01 N·m/A, b = 1e-3 N·m·s/rad: the speed settles at ω = K u / (b R + K²), 9.1 rad/s
/// per volt, with the time constant τ = J R / (b R + K²) = 91 ms. A larger K raises that speed (while
/// K² < b R, as here and at the gallery's first guess K = 0.02, b = 5e-4), a larger b lowers it: the two
/// sensitivities of the measurement have opposite signs.
template <class Scalar_ = double>
struct DcMotor {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 2: angle and speed.
  static constexpr int StateDim = 2;
  /// p = 2: K and b.
  static constexpr int ParamDim = 2;
  /// m = 1: the angle.
  static constexpr int MeasDim = 1;
  /// One input: the armature voltage.
  static constexpr int InputDim = 1;
  /// x = (θ, ω) in rad and rad/s.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (K, b) in N·m/A and N·m·s/rad.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = (θ) in rad.
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// u = (armature voltage) in V.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  Scalar resistance = Scalar(1);  ///< R, armature resistance (Ω)
  Scalar inertia = Scalar(1e-4);  ///< J, inertia of rotor and load (kg·m²)

  /// The true constants, θ = (K, b) = (0.01 N·m/A, 1e-3 N·m·s/rad).
  static Param trueParameters() { return Param(Scalar(0.01), Scalar(1e-3)); }

  /// A multi-step voltage of period 2 s: +12, −6, +6, −12 and 0 V, 0.4 s each (about 4 time constants,
  /// so that both the speed's gain and its time constant show). Its mean is zero, so the angle stays
  /// between 0 and 40 rad.
  Input input(Scalar t) const {
    static constexpr double levels[5] = {12, -6, 6, -12, 0};
    const auto segment = static_cast<long>(std::floor(t / Scalar(0.4)));
    return Input::Constant(Scalar(levels[((segment % 5) + 5) % 5]));
  }

  /// θ̇ = ω, ω̇ = (K (u − K ω) / R − b ω) / J.
  State derivative(Scalar /*t*/, const State& x, const Input& u, const Param& theta) const {
    const Scalar current = (u(0) - theta(0) * x(1)) / resistance;
    return State(x(1), (theta(0) * current - theta(1) * x(1)) / inertia);
  }

  /// The encoder angle alone: y = θ.
  Meas measurement(const State& x, const Param& /*theta*/) const { return Meas::Constant(x(0)); }
};

}  // namespace mjukf::models
