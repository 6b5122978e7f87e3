#pragma once

// A model without input (InputDim = 0, no input(t) member at all) and each filter over it, for
// no_input_model_test and no_allocation_test.

#include <cmath>
#include <type_traits>

#include <Eigen/Core>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"

namespace mjukf::testing::no_input {

// A damped pendulum with unknown damping c: θ̈ = −sin θ − c θ̇, x = (θ, θ̇), y = x. No `input` member:
// the point of the test.
struct Pendulum {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 1, MeasDim = 2, InputDim = 0;
  using State = Eigen::Matrix<double, StateDim, 1>;
  using Param = Eigen::Matrix<double, ParamDim, 1>;
  using Meas = Eigen::Matrix<double, MeasDim, 1>;
  using Input = Eigen::Matrix<double, InputDim, 1>;

  State derivative(double, const State& x, const Input&, const Param& c) const {
    return State(x(1), -std::sin(x(0)) - c(0) * x(1));
  }
  Meas measurement(const State& x, const Param&) const { return x; }
};

using Rk4 = mjukf::Rk4<double>;
inline const Pendulum::State kStart(1.0, 0.0);
inline const Pendulum::Param kGuess = Pendulum::Param::Constant(0.1);

/// Settings that run (not tuned): the tests compare calls, not accuracy.
template <class Filter>
typename Filter::Settings settingsFor() {
  typename Filter::Settings s;
  s.measurementNoise = 1e-2 * Filter::Settings::MeasMatrix::Identity();
  s.initialCovariance.setIdentity();
  s.initialCovariance *= 0.1;
  s.processNoise.setIdentity();
  s.processNoise *= 1e-6;
  if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<Pendulum, Rk4>>) {
    s.scaling = -0.05;
    s.transformation << 0.2, 0.8;
    s.parameterSpread << 0.01;
  }
  if constexpr (std::is_same_v<Filter, mjukf::DualUkf<Pendulum, Rk4>>) {
    s.initialParameterCovariance << 0.1;
    s.parameterProcessNoise << 1e-6;
  }
  return s;
}

/// The filter over Pendulum with RK4: the UKF given the true c = 0.2, the others from the guess 0.1.
template <class Filter>
Filter makeFilter() {
  if constexpr (std::is_same_v<Filter, mjukf::Ukf<Pendulum, Rk4>>)
    return Filter(Pendulum(), kStart, Pendulum::Param::Constant(0.2), settingsFor<Filter>());
  else
    return Filter(Pendulum(), kStart, kGuess, settingsFor<Filter>());
}

}  // namespace mjukf::testing::no_input
