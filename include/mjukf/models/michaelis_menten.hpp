#pragma once

/// \file
/// A drug infused into one compartment and eliminated by a saturable enzyme (Michaelis–Menten): a plant
/// of the gallery (docs/studies.md, "The gallery") with a parameter that enters nonlinearly.

#include <cmath>

#include <Eigen/Core>

namespace mjukf::models {

/// The plasma concentration c of a drug given by intravenous infusion at the rate u into a volume of
/// distribution V, eliminated at the saturable rate V_max c / (K_m + c):
///
///     ċ = u / V − V_max c / (K_m + c)
///
/// State x = (c) in mg/L; parameters θ = (V_max, K_m): the largest elimination rate in mg/(L·h) and the
/// concentration of half that rate in mg/L; input u = the infusion rate in mg/h; time in hours;
/// y = c. Known: V = 50 L.
///
/// True values V_max = 2 mg/(L·h), K_m = 5 mg/L. V_max enters linearly, K_m through the denominator.
/// Well below K_m the elimination is first order with the rate constant V_max / K_m = 0.4 /h (a
/// half-life of 1.7 h), and only that ratio shows; well above K_m it is zero order at V_max, and K_m
/// does not show. Both are found only from a run that crosses c ≈ K_m, as the infusions below do.
template <class Scalar_ = double>
struct MichaelisMentenInfusion {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 1: the concentration.
  static constexpr int StateDim = 1;
  /// p = 2: V_max and K_m.
  static constexpr int ParamDim = 2;
  /// m = 1: the concentration.
  static constexpr int MeasDim = 1;
  /// One input: the infusion rate.
  static constexpr int InputDim = 1;
  /// x = (c) in mg/L.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (V_max, K_m) in mg/(L·h) and mg/L.
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = (c) in mg/L.
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// u = (infusion rate) in mg/h.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  Scalar volume = Scalar(50);  ///< V, the volume of distribution (L)

  /// The true constants, θ = (V_max, K_m) = (2 mg/(L·h), 5 mg/L).
  static Param trueParameters() { return Param(Scalar(2), Scalar(5)); }

  /// Days of 24 h: an infusion for the first 12 h of each, at 95, 50 and 80 mg/h on days 1, 2 and 3
  /// (then again), none for the other 12 h. The concentration peaks at 10.4, 4.1 and 8.0 mg/L: twice
  /// K_m, about K_m and between, and falls to about 0.1 mg/L each night.
  Input input(Scalar t) const {
    static constexpr double rates[3] = {95, 50, 80};
    const auto day = static_cast<long>(std::floor(t / Scalar(24)));
    const bool infusing = t - Scalar(24) * Scalar(day) < Scalar(12);
    return Input::Constant(infusing ? Scalar(rates[((day % 3) + 3) % 3]) : Scalar(0));
  }

  /// ċ = u / V − V_max c / (K_m + c).
  State derivative(Scalar /*t*/, const State& x, const Input& u, const Param& theta) const {
    return State::Constant(u(0) / volume - theta(0) * x(0) / (theta(1) + x(0)));
  }

  /// The concentration: y = c.
  Meas measurement(const State& x, const Param& /*theta*/) const { return x; }
};

}  // namespace mjukf::models
