#pragma once

// The synthetic model family of the scaling benchmark (scaling_bench.cpp): a chain of n/2 unit masses,
// mass 0 tied to a wall, each neighbour to the next by a spring with a cubic term and a damper, a known
// force u(t) on mass 0; the n/2 positions are measured. θ: p = 1, the linear stiffness k; p = 4, also the
// cubic stiffness k₃, the damping b and the input gain g. Its cost per derivative grows as n, so a
// filter's overhead against its model floor grows with n as the filter's own arithmetic does.

#include <cmath>

#include <Eigen/Core>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"

namespace mjukf::bench {

template <class Scalar_, int N, int P>
struct Chain {
  static_assert(N % 2 == 0 && (P == 1 || P == 4), "n even (positions and velocities), p 1 or 4");
  using Scalar = Scalar_;
  static constexpr int Masses = N / 2;
  static constexpr int StateDim = N, ParamDim = P, MeasDim = Masses, InputDim = 1;
  using State = Eigen::Matrix<Scalar, StateDim, 1>;
  using Param = Eigen::Matrix<Scalar, ParamDim, 1>;
  using Meas = Eigen::Matrix<Scalar, MeasDim, 1>;
  using Input = Eigen::Matrix<Scalar, InputDim, 1>;

  // k, k₃, b, g; with p = 1 the last three are these constants.
  static Param trueParameters() {
    Param theta;
    if constexpr (P == 1)
      theta << Scalar(4);
    else
      theta << Scalar(4), Scalar(1), Scalar(0.5), Scalar(1);
    return theta;
  }

  State derivative(Scalar, const State& x, const Input& u, const Param& theta) const {
    const Scalar k = theta(0);
    Scalar k3 = Scalar(1), b = Scalar(0.5), g = Scalar(1);
    if constexpr (P == 4) {
      k3 = theta(1);
      b = theta(2);
      g = theta(3);
    }
    State dx;
    dx.template head<Masses>() = x.template tail<Masses>();
    // `force`: the pull of the link into mass i (from the wall for i = 0) against its motion; `next`: that
    // of the link out of it, which pulls it the other way.
    Scalar next = Scalar(0);
    for (int i = Masses - 1; i >= 0; --i) {
      const Scalar stretch = x(i) - (i > 0 ? x(i - 1) : Scalar(0));
      const Scalar rate = x(Masses + i) - (i > 0 ? x(Masses + i - 1) : Scalar(0));
      const Scalar force = k * stretch + k3 * stretch * stretch * stretch + b * rate;
      dx(Masses + i) = next - force;
      next = force;
    }
    dx(Masses) += g * u(0);
    return dx;
  }

  Meas measurement(const State& x, const Param&) const { return x.template head<Masses>(); }

  Input input(Scalar t) const { return Input(Scalar(2) * std::sin(Scalar(3) * t)); }
};

// Settings of each filter on the chain: x̂₀ = 0, θ̂₀ = 0.8 θ, P₀ = 0.1 I (parameters 0.1 too), Q = 1e-6 I,
// R = 1e-4 I. The MJUKF: T spreads each parameter over all measurements equally, a small ξ (the chain is
// for timing: its T and ξ are not tuned for accuracy); automatic: both automatic modes instead.
template <class Model>
struct ChainExperiment {
  using Scalar = typename Model::Scalar;
  static constexpr Scalar stepSize = Scalar(1e-3);
  static typename Model::State initialState() { return Model::State::Zero(); }
  static typename Model::Param initialParameters() { return Scalar(0.8) * Model::trueParameters(); }

  static UkfSettingsFor<Model> ukf() {
    UkfSettingsFor<Model> s;
    s.initialCovariance.diagonal().setConstant(Scalar(0.1));
    s.processNoise.diagonal().setConstant(Scalar(1e-6));
    s.measurementNoise.diagonal().setConstant(Scalar(1e-4));
    return s;
  }
  static JointUkfSettingsFor<Model> jointUkf() {
    JointUkfSettingsFor<Model> s;
    s.initialCovariance.diagonal().setConstant(Scalar(0.1));
    s.processNoise.diagonal().setConstant(Scalar(1e-6));
    s.measurementNoise.diagonal().setConstant(Scalar(1e-4));
    return s;
  }
  static ModifiedJointUkfSettingsFor<Model> modifiedJointUkf(bool automatic) {
    ModifiedJointUkfSettingsFor<Model> s;
    s.initialCovariance.diagonal().setConstant(Scalar(0.1));
    s.processNoise.diagonal().setConstant(Scalar(1e-6));
    s.measurementNoise.diagonal().setConstant(Scalar(1e-4));
    s.scaling = Scalar(-1e-3);
    s.transformation.setConstant(Scalar(1) / Scalar(Model::MeasDim));
    s.parameterSpread.setConstant(Scalar(1e-3));
    s.automaticTransformation = automatic;
    s.adaptiveScaling = automatic;
    // Without the automatic modes, the paper's MJUKF as in the step benchmarks (the paper presets): the
    // covariance of θ̂ not followed, so the filter propagates its 2n + 1 points and nothing else, as its
    // floor assumes (following it costs p more propagations per time update and the joint covariance).
    s.followParameterCovariance = automatic;
    return s;
  }
  static DualUkfSettingsFor<Model> dualUkf() {
    DualUkfSettingsFor<Model> s;
    static_cast<UnscentedSettings<Scalar, Model::StateDim, Model::MeasDim>&>(s) = ukf();
    s.initialParameterCovariance.diagonal().setConstant(Scalar(0.1));
    return s;
  }
};

}  // namespace mjukf::bench
