#pragma once

// Simulated measurements as the paper makes them (docs/plants.md §4): the plant integrated with I-TR-BDF2 at
// step h from x₀, then white Gaussian noise of one standard deviation for every channel,
// σ = sqrt(var(all states) / 10^(SNR/10)), the variance taken over every channel and sample together.
// The 2019 systems (paper/systems_2019.hpp) are integrated with their own integrator and take
// noise relative to the signal instead: std ρ·|yᵢ| for each component of each sample. The gallery's
// plants (gallery/experiments.hpp) give an absolute standard deviation per measured component. Without
// process noise, the plant follows its model exactly; with it (`SimulationOptions::processNoise`, the
// study's `matched` scenario), it follows the model a filter assumes (docs/studies.md).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

#include "common/cli.hpp"
#include "common/plant_data.hpp"
#include "mjukf/detail/linear_algebra.hpp"
#include "mjukf/detail/validation.hpp"
#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/simulation.hpp"

namespace mjukf::examples {

/// The most rows a simulation may have. A row of data and of each filter's estimates together take
/// about 200 bytes (the robot, `paper`), so this is about 2 GB; the paper's runs have 2·10⁵ rows.
constexpr long kMaxSimulationRows = 10'000'000;

/// Refuses a `flag` duration that is not positive or gives more than kMaxSimulationRows rows at step
/// `h` (checked in double, before the row count is rounded to an integer, which could overflow).
inline void requireSimulationDuration(const char* flag, double duration, double h) {
  if (duration > 0 && duration / h + 1 <= double(kMaxSimulationRows)) return;
  char limit[160];
  std::snprintf(limit, sizeof limit, " needs a time > 0 s of at most %ld steps of h = %g s (%g s), not %g",
                kMaxSimulationRows, h, double(kMaxSimulationRows - 1) * h, duration);
  throw UsageError(flag + std::string(limit));
}

/// Process noise of a simulated plant, as a filter's time update assumes it: after every `every` steps
/// (one measurement interval), w ~ N(0, `state`) is added to the state and the parameters take a
/// random-walk step N(0, `parameters`), both in force from that row on.
template <class Model>
struct ProcessNoise {
  int every = 1;
  Eigen::Matrix<double, Model::StateDim, Model::StateDim> state =
      Eigen::Matrix<double, Model::StateDim, Model::StateDim>::Zero();
  Eigen::Matrix<double, Model::ParamDim, Model::ParamDim> parameters =
      Eigen::Matrix<double, Model::ParamDim, Model::ParamDim>::Zero();
};

/// S with S Sᵀ = C for a process noise C (`setting`), which may be singular (a state without process
/// noise): the library's own check that C is finite, symmetric and positive semi-definite, then the
/// factor of its positive part (detail/linear_algebra.hpp). Throws std::invalid_argument naming it.
template <class Matrix>
Matrix processNoiseRoot(const char* setting, const Matrix& c) {
  if (const auto error = mjukf::detail::requirePositiveSemiDefinite("simulatePlant", setting, c))
    mjukf::detail::throwInvalid(error);
  Matrix root;
  if (!mjukf::detail::positivePartFactor(c, root))
    throw std::invalid_argument("simulatePlant: no factor of the process noise");
  return root;
}

template <class Model>
struct SimulationOptions {
  double duration = 0;  ///< s; rows = round(duration / h) + 1
  double stepSize = 1e-3;
  std::uint64_t seed = 1;
  double snrDb = 30;         ///< +inf for noise-free measurements
  double relativeNoise = 0;  ///< > 0: noise of std relativeNoise·|yᵢ| per component, in place of the SNR
  /// Given: noise of std (*absoluteNoise)ᵢ on measured component i, in place of the SNR.
  std::optional<typename Model::Meas> absoluteNoise;
  typename Model::State initialState = Model::State::Zero();
  TrueParameters<typename Model::Param> parameters{Model::trueParameters()};
  /// Given: process noise on the state and the parameters (none otherwise), drawn from a stream of
  /// its own, so that the measurement noise of a seed is the same draws with and without it.
  std::optional<ProcessNoise<Model>> processNoise;
};

/// The process noise's stream: `seed` xor this.
constexpr std::uint64_t kProcessNoiseStream = 0x9e3779b97f4a7c15u;

/// The noise standard deviation for signal `states` at `snrDb` (docs/plants.md §4).
template <class State>
double noiseStandardDeviation(const std::vector<State>& states, double snrDb) {
  double sum = 0;
  double count = 0;
  for (const auto& x : states) {
    sum += x.sum();
    count += double(x.size());
  }
  const double mean = sum / count;
  double squares = 0;
  for (const auto& x : states) squares += (x.array() - mean).square().sum();
  return std::sqrt(squares / count / std::pow(10.0, snrDb / 10));
}

/// The input of the plant at time t: its signal u(t), or the empty input of a plant without one.
template <class Model>
typename Model::Input inputAt(const Model& model, double t) {
  if constexpr (hasInputSignal<Model>)
    return model.input(typename Model::Scalar(t));
  else
    return typename Model::Input();
}

/// The plant of `options` integrated one measurement interval at a time, w added to the state and the
/// parameters' walk taken at the end of each (ProcessNoise); the state at that row is the one after w,
/// which the row's measurement sees; `data.parameterTruth` (the scheduled parameters on entry) gains
/// the walk from that row on.
template <class Model, class Integrator>
void simulateWithProcessNoise(const Model& model, const Integrator& integrator, const SimulationOptions<Model>& options,
                              PlantData<Model>& data) {
  using State = typename Model::State;
  using Param = typename Model::Param;
  const ProcessNoise<Model>& noise = *options.processNoise;
  if (noise.every < 1) throw std::invalid_argument("simulatePlant: process noise every < 1 step");
  const auto stateRoot = processNoiseRoot("process noise of the state", noise.state);
  const auto parameterRoot = processNoiseRoot("process noise of the parameters", noise.parameters);
  std::mt19937_64 random(options.seed ^ kProcessNoiseStream);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto draw = [&](auto vector) {
    for (int i = 0; i < vector.size(); ++i) vector(i) = normal(random);
    return vector;
  };
  const long rows = static_cast<long>(data.stateTruth.size());
  Param walk = Param::Zero();
  State x = options.initialState;
  data.stateTruth.front() = x;
  for (long start = 0; start < rows - 1; start += noise.every) {
    const long steps = std::min<long>(noise.every, rows - 1 - start);
    const auto row = [start](long k) { return static_cast<std::size_t>(start + k); };
    x = mjukf::simulate(
        model, integrator, x, [&](long k) -> const Param& { return data.parameterTruth[row(k)]; },
        double(start) * options.stepSize, options.stepSize, steps,
        [&](long k, double, const State& xk) { data.stateTruth[row(k)] = xk; });
    if (steps < noise.every) break;  // the last, partial interval: no time update ends it
    x += stateRoot * draw(State());
    walk += parameterRoot * draw(Param());
    data.stateTruth[row(steps)] = x;
    for (long k = start + steps; k < rows && k < start + steps + noise.every; ++k)
      data.parameterTruth[static_cast<std::size_t>(k)] += walk;
  }
}

/// The noise draws depend on `options.seed` alone (one standard normal per component and row, in
/// row order), so a run is reproduced from its seed.
template <class Model, class Integrator = ITrBdf2<double>>
PlantData<Model> simulatePlant(const Model& model, const SimulationOptions<Model>& options,
                               const Integrator& integrator = Integrator()) {
  using State = typename Model::State;
  using Param = typename Model::Param;
  const double h = options.stepSize;
  if (!(options.duration >= 0 && options.duration / h + 1 <= double(kMaxSimulationRows)))
    throw std::invalid_argument("simulatePlant: duration " + std::to_string(options.duration) + " s out of range");
  const long rows = std::lround(options.duration / h) + 1;

  PlantData<Model> data;
  data.stepSize = h;
  data.parameterTruthFromFile = true;
  data.stateTruth.resize(static_cast<std::size_t>(rows));
  data.parameterTruth.resize(static_cast<std::size_t>(rows));
  for (long k = 0; k < rows; ++k) data.parameterTruth[static_cast<std::size_t>(k)] = options.parameters.atRow(k, h);
  // The step from t_k runs with the parameters in force at t_k; the input is evaluated at each stage.
  if (!options.processNoise) {
    mjukf::simulate(
        model, integrator, options.initialState,
        [&](long k) -> const Param& { return data.parameterTruth[static_cast<std::size_t>(k)]; }, 0.0, h, rows - 1,
        [&](long k, double, const State& x) { data.stateTruth[static_cast<std::size_t>(k)] = x; });
  } else {
    simulateWithProcessNoise(model, integrator, options, data);
  }

  const bool relative = options.relativeNoise > 0;
  const bool absolute = options.absoluteNoise.has_value();
  const double sigma =
      relative || absolute || std::isinf(options.snrDb) ? 0.0 : noiseStandardDeviation(data.stateTruth, options.snrDb);
  std::mt19937_64 random(options.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  data.y.resize(static_cast<std::size_t>(rows));
  for (std::size_t k = 0; k < data.y.size(); ++k) {
    data.y[k] =
        measureModel(model, data.stateTruth[k], inputAt(model, static_cast<double>(k) * h), data.parameterTruth[k]);
    for (int c = 0; c < Model::MeasDim; ++c)
      data.y[k](c) += (absolute   ? double((*options.absoluteNoise)(c))
                       : relative ? options.relativeNoise * std::abs(data.y[k](c))
                                  : sigma) *
                      noise(random);
  }
  return data;
}

}  // namespace mjukf::examples
