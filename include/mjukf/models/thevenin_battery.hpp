#pragma once

/// \file
/// A lithium-ion cell as a first-order Thevenin circuit in discrete time: a plant of the gallery
/// (docs/studies.md, "The gallery"), whose measurement, the terminal voltage, depends on the input.

#include <cmath>

#include <Eigen/Core>

namespace mjukf::models {

/// A cell of capacity Q = 2.5 Ah: an open-circuit voltage OCV(z) of the state of charge z, in series
/// with a resistance R₀ and an RC pair (R₁, C₁), sampled every dt with the current i held over the
/// sample (the exact discretisation of the circuit under a zero-order hold):
///
///     z⁺  = z − dt i / Q
///     v₁⁺ = a v₁ + R₁ (1 − a) i,      a = exp(−dt / (R₁ C₁))
///     y   = OCV(z) − v₁ − R₀ i,       OCV(z) = 3.2 + 0.9 z − 0.9 z² + 0.9 z³  (V)
///
/// State x = (z, v₁): the state of charge (0 empty, 1 full) and the voltage over the RC pair in V;
/// parameters θ = (R₀, R₁) in Ω; input u = i, the current in A (> 0 discharging); y = the terminal
/// voltage in V, which depends on the current at the time of the measurement. Known: Q = 9000 A·s,
/// C₁ = 1000 F. OCV rises monotonically from 3.2 V (empty) to 4.1 V (full), with an inflection at z = 1/3.
///
/// True values R₀ = 50 mΩ, R₁ = 30 mΩ (a polarisation time constant R₁ C₁ = 30 s). R₀ enters the
/// measurement linearly, R₁ the transition nonlinearly, through a.
template <class Scalar_ = double>
struct TheveninBattery {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 2: state of charge and the RC pair's voltage.
  static constexpr int StateDim = 2;
  /// p = 2: R₀ and R₁.
  static constexpr int ParamDim = 2;
  /// m = 1: the terminal voltage.
  static constexpr int MeasDim = 1;
  /// One input: the current.
  static constexpr int InputDim = 1;
  /// x = (z, v₁): state of charge (-) and voltage in V.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (R₀, R₁) in Ω.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = (terminal voltage) in V.
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// u = (i) in A, positive when the cell discharges.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  Scalar capacity = Scalar(2.5 * 3600);  ///< Q, the charge of a full cell (A·s): 2.5 Ah
  Scalar capacitance = Scalar(1000);     ///< C₁, the capacitance of the RC pair (F)

  /// The true resistances, θ = (R₀, R₁) = (0.05 Ω, 0.03 Ω).
  static Param trueParameters() { return Param(Scalar(0.05), Scalar(0.03)); }

  /// A pulsed profile of period 600 s: 2.5 A (1C) for 120 s, rest for 180 s, 5 A (2C) for 60 s, a charge
  /// of 1.25 A for 60 s, rest for 180 s. It takes 0.875 A on average: 35% of the charge in an hour.
  Input input(Scalar t) const {
    const Scalar s = t - Scalar(600) * std::floor(t / Scalar(600));
    const Scalar i = s < Scalar(120)   ? Scalar(2.5)
                     : s < Scalar(300) ? Scalar(0)
                     : s < Scalar(360) ? Scalar(5)
                     : s < Scalar(420) ? Scalar(-1.25)
                                       : Scalar(0);
    return Input::Constant(i);
  }

  /// The open-circuit voltage (V) at the state of charge z.
  static Scalar openCircuitVoltage(Scalar z) {
    return Scalar(3.2) + z * (Scalar(0.9) + z * (Scalar(-0.9) + z * Scalar(0.9)));
  }

  /// One sample of length dt with the current u held: z⁺ = z − dt i / Q, v₁⁺ = a v₁ + R₁ (1 − a) i.
  State transition(Scalar /*t*/, Scalar dt, const State& x, const Input& u, const Param& theta) const {
    const Scalar a = std::exp(-dt / (theta(1) * capacitance));
    return State(x(0) - dt * u(0) / capacity, a * x(1) + theta(1) * (Scalar(1) - a) * u(0));
  }

  /// The terminal voltage under the current u: y = OCV(z) − v₁ − R₀ i.
  Meas measurement(const State& x, const Input& u, const Param& theta) const {
    return Meas::Constant(openCircuitVoltage(x(0)) - x(1) - theta(0) * u(0));
  }
};

}  // namespace mjukf::models
