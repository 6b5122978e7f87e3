#pragma once

// What the example programs read from an experiment's settings (paper/experiments.hpp,
// paper/systems_2019.hpp) beyond the filters' presets, with the paper's plants' choices where an
// experiment says nothing: the integrator (I-TR-BDF2), the true initial state (the filters' x̂₀) and the
// measurement noise (white, 30 dB SNR; or, where the experiment gives `relativeNoise`, std ρ·|xᵢ|; or,
// where it gives `static Meas noiseStandardDeviation()`, that standard deviation per measured component).

#include <cstdint>
#include <type_traits>

#include "common/simulation.hpp"
#include "mjukf/model.hpp"

namespace mjukf::examples {

namespace detail {
template <class E, class = void>
struct IntegratorOf {
  using type = DefaultIntegrator<typename E::Model>;
};
template <class E>
struct IntegratorOf<E, std::void_t<typename E::Integrator>> {
  using type = typename E::Integrator;
};
template <class E, class = void>
struct HasTrueInitialState : std::false_type {};
template <class E>
struct HasTrueInitialState<E, std::void_t<decltype(E::trueInitialState())>> : std::true_type {};
template <class E, class = void>
struct HasRelativeNoise : std::false_type {};
template <class E>
struct HasRelativeNoise<E, std::void_t<decltype(E::relativeNoise)>> : std::true_type {};
template <class E, class = void>
struct HasAbsoluteNoise : std::false_type {};
template <class E>
struct HasAbsoluteNoise<E, std::void_t<decltype(E::noiseStandardDeviation())>> : std::true_type {};
}  // namespace detail

/// The integrator the plant is simulated with and the filters run: I-TR-BDF2 (none for a
/// discrete-time model, model.hpp) unless the experiment names another (`using Integrator = …`).
template <class Experiment>
using ExperimentIntegrator = typename detail::IntegratorOf<Experiment>::type;

/// True when the experiment's noise is relative to the signal (`relativeNoise`), not set by an SNR.
template <class Experiment>
inline constexpr bool hasRelativeNoise = detail::HasRelativeNoise<Experiment>::value;

/// True when the experiment gives the noise's standard deviation per measured component
/// (`noiseStandardDeviation()`), not an SNR.
template <class Experiment>
inline constexpr bool hasAbsoluteNoise = detail::HasAbsoluteNoise<Experiment>::value;

/// True when the experiment's noise is set by an SNR (`simulate --snr-db`): neither relative nor absolute.
template <class Experiment>
inline constexpr bool hasSnrNoise = !hasRelativeNoise<Experiment> && !hasAbsoluteNoise<Experiment>;

/// The state the simulation starts from: `trueInitialState()`, else the filters' x̂₀.
template <class Experiment>
typename Experiment::State trueInitialState() {
  if constexpr (detail::HasTrueInitialState<Experiment>::value)
    return Experiment::trueInitialState();
  else
    return Experiment::initialState();
}

/// Simulation options of the experiment: its step, duration, true initial state and noise, with the
/// given seed and true parameters.
template <class Experiment>
SimulationOptions<typename Experiment::Model> experimentSimulation(
    std::uint64_t seed, const TrueParameters<typename Experiment::Param>& truth) {
  SimulationOptions<typename Experiment::Model> options;
  options.stepSize = Experiment::stepSize;
  options.duration = Experiment::duration;
  options.seed = seed;
  options.initialState = trueInitialState<Experiment>();
  options.parameters = truth;
  if constexpr (hasRelativeNoise<Experiment>) options.relativeNoise = Experiment::relativeNoise;
  if constexpr (hasAbsoluteNoise<Experiment>) options.absoluteNoise = Experiment::noiseStandardDeviation();
  return options;
}

/// Simulates the experiment's plant with `options` and the experiment's integrator.
template <class Experiment>
PlantData<typename Experiment::Model> simulateExperiment(const SimulationOptions<typename Experiment::Model>& options) {
  return simulatePlant(typename Experiment::Model(), options, ExperimentIntegrator<Experiment>());
}

}  // namespace mjukf::examples
