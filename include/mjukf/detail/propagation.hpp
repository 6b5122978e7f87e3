#pragma once

// Integrating a model over whole integrator steps with a given parameter vector: the one operation
// every filter repeats for each sigma point and for the open-loop mean.

#include <cmath>

#include "mjukf/status.hpp"

namespace mjukf::detail {

// The model's own input signal u(t), evaluated at every stage time.
template <class Model>
struct SignalInput {
  const Model& model;
  typename Model::Input operator()(typename Model::Scalar t) const { return model.input(t); }
};

// An input held constant over the step (zero-order hold), for inputs known only as samples.
template <class Model>
struct HeldInput {
  const typename Model::Input& value;
  const typename Model::Input& operator()(typename Model::Scalar /*t*/) const { return value; }
};

template <class Scalar>
Status checkStep(Scalar t, Scalar h, int steps) {
  if (!std::isfinite(t) || !std::isfinite(h) || !(h > 0) || steps < 1) return Status::InvalidStepSize;
  return Status::Ok;
}

// x(t + steps h) from x(t) by `steps` integrator steps of size h under parameters theta.
template <class Model, class Integrator, class InputSource, class StateExpr>
typename Model::State propagate(const Model& model, const Integrator& integrator, const InputSource& input,
                                const typename Model::Param& theta, typename Model::Scalar t,
                                typename Model::Scalar h, int steps, const StateExpr& x0) {
  using Scalar = typename Model::Scalar;
  using State = typename Model::State;
  const auto rhs = [&](Scalar time, const State& x) -> State {
    return model.derivative(time, x, input(time), theta);
  };
  State x = x0;
  for (int k = 0; k < steps; ++k) x = integrator.step(rhs, t + Scalar(k) * h, x, h);
  return x;
}

}  // namespace mjukf::detail
