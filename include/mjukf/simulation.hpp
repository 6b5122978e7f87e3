#pragma once

/// \file
/// Simulating a plant: a model integrated over a grid of steps, for simulated measurements, reference
/// trajectories and tests. `stepModel` takes one step; `simulate` takes many and shows each state.

#include <limits>
#include <type_traits>
#include <utility>

#include "mjukf/model.hpp"
#include "mjukf/settings_error.hpp"

#if MJUKF_EXCEPTIONS
#include <stdexcept>
#endif

namespace mjukf {

/// \cond INTERNAL
namespace detail {

// The input a simulation without an explicit one uses: the model's signal u(t), or for a model with
// no input at all (InputDim = 0, no input(t)) the empty vector.
template <class Model>
auto defaultInputs(const Model& model) {
  using Scalar = typename Model::Scalar;
  if constexpr (hasInputSignal<Model>) {
    return [&model](Scalar t) { return model.input(t); };
  } else {
    static_assert(Model::InputDim == 0,
                  "this model has no input(t): pass the input, a held Model::Input or a callable Scalar t -> Input");
    return typename Model::Input();
  }
}

}  // namespace detail
/// \endcond

/// One integrator step as above with the model's own input signal u(t), evaluated at every stage time
/// (a model without `input(t)` must have InputDim = 0; otherwise pass the input).
template <class Model, class Integrator>
typename Model::State stepModel(const Model& model, const Integrator& integrator, typename Model::Scalar t,
                                typename Model::Scalar h, const typename Model::State& x,
                                const typename Model::Param& theta) {
  return stepModel(model, integrator, t, h, x, detail::defaultInputs(model), theta);
}

/// Simulates `model` from x₀ at t₀ over `steps` integrator steps of size h:
///
///     x_{k+1} = stepModel(model, integrator, t_k, h, x_k, inputs, θ_k),   t_k = t₀ + Scalar(k) · h,
///
/// for k = 0 … steps − 1, and calls `visit(k, t_k, x_k)` for k = 0 … steps, in order: steps + 1 calls,
/// the first with x₀ itself. The time of every step is computed from k, never accumulated, so a long
/// run does not drift off its grid. Returns x_steps.
///
/// \param model       the plant (model.hpp).
/// \param integrator  the one-step integrator (`NoIntegrator` for a discrete-time model).
/// \param x0          x₀, the state at t₀.
/// \param t0          t₀, the time of x₀.
/// \param h           the step size.
/// \param steps       the number of steps; must not be negative.
/// \param inputs      u over each step, as for stepModel: a held `Model::Input`, or a callable
///                    `Scalar t -> Model::Input` evaluated at every stage time.
/// \param parameters  θ: a `Model::Param`, the same for every step, or a callable `long k -> Param`
///                    giving θ_k, the parameters in force over the step from t_k (called once per step,
///                    for k = 0 … steps − 1), e.g. to change the plant's parameters at some row.
/// \param visit       called as `visit(long k, Scalar t_k, const Model::State& x_k)`; the reference is
///                    valid during the call only.
/// \throws std::invalid_argument when steps < 0. Without exceptions (settings_error.hpp), steps < 0
///         visits nothing and returns a state of NaN, as a failed stepper step does.
template <class Model, class Integrator, class Inputs, class Parameters, class Visit>
typename Model::State simulate(const Model& model, const Integrator& integrator, const typename Model::State& x0,
                               const Inputs& inputs, const Parameters& parameters, typename Model::Scalar t0,
                               typename Model::Scalar h, long steps, Visit&& visit) {
  using Scalar = typename Model::Scalar;
  using State = typename Model::State;
  using Param = typename Model::Param;
  constexpr bool fixedParameters = std::is_convertible_v<const Parameters&, Param>;
  static_assert(fixedParameters || std::is_invocable_r_v<Param, const Parameters&, long>,
                "the parameters must be a Model::Param or a callable long k -> Model::Param");
  if (steps < 0) {
#if MJUKF_EXCEPTIONS
    throw std::invalid_argument("simulate: steps must not be negative");
#else
    return State::Constant(std::numeric_limits<Scalar>::quiet_NaN());
#endif
  }
  State x = x0;
  // A held input is evaluated once for the whole run rather than once per step.
  const auto input = detail::inputSource<Model>(inputs);
  if constexpr (fixedParameters) {
    const Param theta = parameters;
    for (long k = 0; k < steps; ++k) {
      const Scalar t = t0 + Scalar(k) * h;
      visit(k, t, static_cast<const State&>(x));
      x = stepModel(model, integrator, t, h, x, input, theta);
    }
  } else {
    for (long k = 0; k < steps; ++k) {
      const Scalar t = t0 + Scalar(k) * h;
      visit(k, t, static_cast<const State&>(x));
      const Param theta = parameters(k);
      x = stepModel(model, integrator, t, h, x, input, theta);
    }
  }
  visit(steps, t0 + Scalar(steps) * h, static_cast<const State&>(x));
  return x;
}

/// Simulates `model` as above with the model's own input signal u(t), evaluated at every stage time
/// (a model without `input(t)` must have InputDim = 0; otherwise pass the input).
template <class Model, class Integrator, class Parameters, class Visit>
typename Model::State simulate(const Model& model, const Integrator& integrator, const typename Model::State& x0,
                               const Parameters& parameters, typename Model::Scalar t0, typename Model::Scalar h,
                               long steps, Visit&& visit) {
  return simulate(model, integrator, x0, detail::defaultInputs(model), parameters, t0, h, steps,
                  std::forward<Visit>(visit));
}

}  // namespace mjukf
