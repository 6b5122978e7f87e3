#pragma once

/// \file
/// An electric heater element in an aluminium block: a plant of the gallery (docs/studies.md, "The
/// gallery") with a fast and a slow time constant, 0.1 s against 200 s.

#include <cmath>

#include <Eigen/Core>

namespace mjukf::models {

/// A heater element of small heat capacity C_h on a block of large C_b, which loses heat to the room at
/// T_a; two thermal nodes:
///
///     C_h Ṫ_h = P − G_hb (T_h − T_b)
///     C_b Ṫ_b = G_hb (T_h − T_b) − G_ba (T_b − T_a)
///
/// State x = (T_h, T_b) in °C; parameters θ = (G_hb, G_ba), the thermal conductances element–block and
/// block–room in W/K; input u = P, the electric power in W; y = x, a thermocouple on each. Known:
/// C_h = 2 J/K, C_b = 2000 J/K (about 2.2 kg of aluminium), T_a = 20 °C.
///
/// True values G_hb = 20 W/K, G_ba = 10 W/K: the element follows the block with the time constant
/// C_h / G_hb = 0.1 s, the block the room with about C_b / G_ba = 200 s (the eigenvalues of the
/// linear system are −10.005 /s and −0.005 /s). At a steady power P the element is P / G_hb above the
/// block and the block P / G_ba above the room.
template <class Scalar_ = double>
struct HeatedBlock {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 2: element and block temperature.
  static constexpr int StateDim = 2;
  /// p = 2: G_hb and G_ba.
  static constexpr int ParamDim = 2;
  /// m = 2: both temperatures are measured.
  static constexpr int MeasDim = 2;
  /// One input: the heater power.
  static constexpr int InputDim = 1;
  /// x = (T_h, T_b) in °C.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (G_hb, G_ba) in W/K.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = (T_h, T_b) in °C.
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// u = (P) in W.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  Scalar heaterCapacity = Scalar(2);    ///< C_h, heat capacity of the element (J/K)
  Scalar blockCapacity = Scalar(2000);  ///< C_b, heat capacity of the block (J/K)
  Scalar ambient = Scalar(20);          ///< T_a, room temperature (°C)

  /// The true conductances, θ = (G_hb, G_ba) = (20 W/K, 10 W/K).
  static Param trueParameters() { return Param(Scalar(20), Scalar(10)); }

  /// A cycle of 600 s: 200 W for 200 s; 100 W switched on and off every 10 s for 200 s; off for 200 s.
  Input input(Scalar t) const {
    const Scalar s = t - Scalar(600) * std::floor(t / Scalar(600));
    const bool pulseOn = std::fmod(s, Scalar(20)) < Scalar(10);
    return Input::Constant(s < Scalar(200) ? Scalar(200) : s < Scalar(400) && pulseOn ? Scalar(100) : Scalar(0));
  }

  /// Ṫ_h = (P − G_hb (T_h − T_b)) / C_h, Ṫ_b = (G_hb (T_h − T_b) − G_ba (T_b − T_a)) / C_b.
  State derivative(Scalar /*t*/, const State& x, const Input& u, const Param& theta) const {
    const Scalar intoBlock = theta(0) * (x(0) - x(1));
    return State((u(0) - intoBlock) / heaterCapacity, (intoBlock - theta(1) * (x(1) - ambient)) / blockCapacity);
  }

  /// Both temperatures are measured: y = x.
  Meas measurement(const State& x, const Param& /*theta*/) const { return x; }
};

}  // namespace mjukf::models
