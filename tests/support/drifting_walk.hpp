#pragma once

// A scalar random walk with a drift θ per step, measured with noise: x⁺ = x + θ + w, y = x + v. The
// linear-Gaussian plant of the health, recovery and MJUKF-covariance tests.

#include <Eigen/Core>

namespace mjukf::testing {

template <class Scalar_ = double>
struct DriftingWalk {
  using Scalar = Scalar_;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 0;
  using State = Eigen::Matrix<Scalar, 1, 1>;
  using Param = Eigen::Matrix<Scalar, 1, 1>;
  using Meas = Eigen::Matrix<Scalar, 1, 1>;
  using Input = Eigen::Matrix<Scalar, 0, 1>;
  State transition(Scalar, Scalar, const State& x, const Input&, const Param& theta) const {
    return State(x(0) + theta(0));
  }
  Meas measurement(const State& x, const Param&) const { return Meas(x(0)); }
};

}  // namespace mjukf::testing
