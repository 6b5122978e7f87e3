#pragma once

/// \file
/// The Cascaded Tanks benchmark's plant (tests/data/cascaded_tanks/README.md), as a physical model in
/// discrete time for identification from its recorded data (docs/real-data.md, "Cascaded tanks").

#include <algorithm>
#include <cmath>

#include <Eigen/Core>

namespace mjukf::models {

/// Two tanks in cascade: a pump fills the upper tank, which drains through an orifice into the lower
/// tank, which drains into a reservoir; its level is measured. Both levels are in the sensor's volts.
///
///     ẋ₁ = k₄ u − k₁ √x₁                 the pump in, the upper orifice out (Torricelli)
///     ẋ₂ = k₁ √x₁ − k₃ x₂^α               the upper orifice in, the lower orifice out
///
/// - **One k₁ for both ends of the upper orifice.** Only x₂ is measured, so the scale of x₁ is not
///   identifiable: x₁ is counted in lower-tank-equivalent volts, in which what leaves the upper tank
///   is what enters the lower one.
/// - **A free exponent α on the lower outflow.** Torricelli's ½ holds for a sharp orifice far above
///   it; the lower tank's level is read by a sensor whose zero is not the orifice's height, and its
///   outflow pipe has friction, which a free α takes up (it halves the estimation error of ½).
/// - **Upper-tank overflow.** Above h_max the upper tank spills; the fraction k₅ of the spill falls
///   into the lower tank, the rest is lost. The spill is what the step would have put above h_max.
/// - **Lower tank full**, at 10 V (x₂ ≤ 10), and no level below 0.
/// - **Sensor offset.** y = min(x₂ + c, 10): the sensor's zero is c below the orifice's level, and its
///   range ends at 10 V.
///
/// Discrete time: each sample of length dt (4 s in the benchmark) is `subSteps` RK4 steps with the
/// input held, the overflow and the limits applied after each step.
///
/// State x = (x₁, x₂) in V. Parameters, for a filter that needs them unbounded, as logarithms of the
/// positive ones: θ = (ln k₁, ln k₃, ln k₄, ln h_max, ln k₅, ln α, c), 7 of them. Input u = the pump
/// voltage (V); y = the measured level of the lower tank (V).
template <class Scalar_ = double>
struct CascadedTanks {
  /// The floating-point type.
  using Scalar = Scalar_;
  /// n = 2: the upper and the lower level.
  static constexpr int StateDim = 2;
  /// p = 7: ln k₁, ln k₃, ln k₄, ln h_max, ln k₅, ln α, c.
  static constexpr int ParamDim = 7;
  /// m = 1: the lower level as measured.
  static constexpr int MeasDim = 1;
  /// One input: the pump voltage.
  static constexpr int InputDim = 1;
  /// x = (x₁, x₂) in V.
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  /// θ = (ln k₁, ln k₃, ln k₄, ln h_max, ln k₅, ln α, c).
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  /// y = (the lower level as measured) in V.
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  /// u = (the pump voltage) in V.
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  /// The parameters' indices in θ.
  enum Index : int { kLnK1 = 0, kLnK3, kLnK4, kLnHmax, kLnK5, kLnAlpha, kOffset };

  /// Which terms of the model are in force; the identification (examples/cascaded_tanks.cpp, `terms`)
  /// turns them on one after the other to measure what each adds. With a term off, its parameters are
  /// not used.
  struct Terms {
    bool upperOverflow = true;  ///< the upper tank spills above h_max (else it has no ceiling)
    bool lowerFull = true;      ///< x₂ ≤ 10 V
    bool freeExponent = true;   ///< the lower outflow k₃ x₂^α (else α = ½, Torricelli)
    bool sensorOffset = true;   ///< y = x₂ + c (else c = 0)
  };

  Terms terms{};                      ///< which terms the model has (all by default)
  int subSteps = 8;                   ///< RK4 steps per sample
  Scalar lowerCeiling = Scalar(10);   ///< the lower tank's level when full (V)
  Scalar sensorCeiling = Scalar(10);  ///< where the sensor's range ends (V)

  /// The physical parameters, from θ (as the model uses them, the terms off included).
  struct Physical {
    Scalar k1;      ///< outflow coefficient of the upper tank, k₁
    Scalar k3;      ///< outflow coefficient of the lower tank, k₃
    Scalar k4;      ///< pump gain, k₄
    Scalar hMax;    ///< level at which the upper tank spills, h_max (V)
    Scalar k5;      ///< share of the spill that reaches the lower tank, k₅
    Scalar alpha;   ///< exponent of the lower tank's outflow, α
    Scalar offset;  ///< sensor offset, c (V)
  };
  /// The physical parameters of θ.
  Physical physical(const Param& theta) const {
    using std::exp;
    return {exp(theta(kLnK1)),
            exp(theta(kLnK3)),
            exp(theta(kLnK4)),
            exp(theta(kLnHmax)),
            exp(theta(kLnK5)),
            terms.freeExponent ? exp(theta(kLnAlpha)) : Scalar(0.5),
            terms.sensorOffset ? theta(kOffset) : Scalar(0)};
  }

  /// θ from the physical parameters.
  static Param parameters(const Physical& p) {
    using std::log;
    Param theta;
    theta << log(p.k1), log(p.k3), log(p.k4), log(p.hMax), log(p.k5), log(p.alpha), p.offset;
    return theta;
  }

  /// The flows' rates of change ẋ at x under the pump voltage u.
  static State derivative(const State& x, Scalar u, const Physical& p) {
    const Scalar upperOut = p.k1 * power(x(0), Scalar(0.5));
    return State(p.k4 * u - upperOut, upperOut - p.k3 * power(x(1), p.alpha));
  }

  /// One sample of length dt with the pump voltage u held.
  State transition(Scalar /*t*/, Scalar dt, const State& x0, const Input& u, const Param& theta) const {
    const Physical p = physical(theta);
    const Scalar h = dt / Scalar(subSteps);
    State x = x0;
    for (int i = 0; i < subSteps; ++i) {
      const State a = derivative(x, u(0), p);
      const State b = derivative(x + h / 2 * a, u(0), p);
      const State c = derivative(x + h / 2 * b, u(0), p);
      const State d = derivative(x + h * c, u(0), p);
      x += h / 6 * (a + 2 * b + 2 * c + d);
      if (terms.upperOverflow && x(0) > p.hMax) {
        x(1) += p.k5 * (x(0) - p.hMax);  // the share of the spill that falls into the lower tank
        x(0) = p.hMax;
      }
      if (terms.lowerFull) x(1) = std::min(x(1), lowerCeiling);
      x = x.cwiseMax(Scalar(0));
    }
    return x;
  }

  /// The lower level as the sensor reads it: y = min(x₂ + c, 10).
  Meas measurement(const State& x, const Param& theta) const {
    const Scalar offset = terms.sensorOffset ? theta(kOffset) : Scalar(0);
    return Meas::Constant(std::min(x(1) + offset, sensorCeiling));
  }

 private:
  // z^a for a level z, 0 for an empty tank (a sigma point may stray below 0 within a step).
  static Scalar power(Scalar z, Scalar a) { return z > Scalar(0) ? std::pow(z, a) : Scalar(0); }
};

}  // namespace mjukf::models
