#pragma once

/// \file
/// Offline, on the host: the free run of a model over a record (its outputs from x₀ and θ alone, no
/// measurement fed back) and the validation metrics that compare it with the measured outputs, RMS
/// error and fit % (docs/offline-passes.md). Not included by mjukf/mjukf.hpp.

#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>

#include <Eigen/Core>

#include "mjukf/model.hpp"
#include "mjukf/settings_error.hpp"
#include "mjukf/simulation.hpp"

#if MJUKF_EXCEPTIONS
#include <stdexcept>
#endif

namespace mjukf::offline {

/// How a record is sampled: sample k is at t_k = startTime + k · period, and the model is integrated
/// over each period in `subSteps` steps of period / subSteps.
template <class Scalar>
struct Sampling {
  /// t₀, the time of sample 0.
  Scalar startTime = Scalar(0);
  /// The sampling period, > 0.
  Scalar period = Scalar(1);
  /// Integrator steps per period, ≥ 1.
  int subSteps = 1;
};

/// \cond INTERNAL
namespace detail {

// A record's inputs, one per sample, each held over its sampling period (zero-order hold); u_k is also
// the input of the measurement at t_k (the one in force then).
template <class Model, class Inputs>
struct HeldSamples {
  const Inputs& inputs;
  std::size_t size() const { return inputs.size(); }
  typename Model::Input measurementInput(std::size_t k, typename Model::Scalar) const { return inputs[k]; }
  template <class Integrator>
  typename Model::State advance(const Model& model, const Integrator& integrator, const typename Model::State& x,
                                const typename Model::Param& theta, std::size_t k, typename Model::Scalar t,
                                typename Model::Scalar h, int subSteps) const {
    return simulate(model, integrator, x, typename Model::Input(inputs[k]), theta, t, h, subSteps,
                    [](long, typename Model::Scalar, const typename Model::State&) {});
  }
};

// The model's own input signal u(t), at every stage time (none for a model without input): no limit on
// the number of samples.
template <class Model>
struct OwnSignal {
  std::size_t size() const { return std::numeric_limits<std::size_t>::max(); }
  typename Model::Input measurementInput(std::size_t, typename Model::Scalar t) const {
    if constexpr (hasInputSignal<Model>)
      return model.input(t);
    else
      return typename Model::Input();
  }
  template <class Integrator>
  typename Model::State advance(const Model&, const Integrator& integrator, const typename Model::State& x,
                                const typename Model::Param& theta, std::size_t, typename Model::Scalar t,
                                typename Model::Scalar h, int subSteps) const {
    return simulate(model, integrator, x, theta, t, h, subSteps,
                    [](long, typename Model::Scalar, const typename Model::State&) {});
  }
  const Model& model;
};

// A bad argument of the offline tools: std::invalid_argument with exceptions on; otherwise the caller
// returns NaN results.
inline bool refuse([[maybe_unused]] const char* message) {
#if MJUKF_EXCEPTIONS
  throw std::invalid_argument(message);
#else
  return false;
#endif
}

template <class Scalar>
bool validSampling(const Sampling<Scalar>& s) {
  return std::isfinite(s.startTime) && std::isfinite(s.period) && s.period > Scalar(0) && s.subSteps >= 1;
}

// The free run over samples 0 … count − 1, calling visit(k, y_k); returns x at the last sample.
template <class Model, class Integrator, class InputRecord, class Visit>
typename Model::State freeRunWith(const Model& model, const Integrator& integrator, const typename Model::State& x0,
                                  const typename Model::Param& theta, const InputRecord& inputs,
                                  const Sampling<typename Model::Scalar>& sampling, std::size_t count, Visit&& visit) {
  using Scalar = typename Model::Scalar;
  const Scalar h = sampling.period / Scalar(sampling.subSteps);
  typename Model::State x = x0;
  for (std::size_t k = 0; k < count; ++k) {
    const Scalar t = sampling.startTime + Scalar(k) * sampling.period;
    visit(k, measureModel(model, x, inputs.measurementInput(k, t), theta));
    if (k + 1 < count) x = inputs.advance(model, integrator, x, theta, k, t, h, sampling.subSteps);
  }
  return x;
}

}  // namespace detail
/// \endcond

/// The free run of `model` over a record: from x₀ at t₀ under the fixed parameters θ, with the input
/// u_k held over sample k's period, integrated in `sampling.subSteps` steps per period by `simulate`
/// (simulation.hpp), and the simulated outputs
///
///     ŷ_k = g(x_k, u_k, θ)  (or g(x_k, θ); measureModel, model.hpp),   k = 0 … outputs.size() − 1,
///
/// written to `outputs[k]` (a container of `Model::Meas` the caller sized: std::vector, std::array).
/// Sample 0 is the output of x₀ itself. Returns x at the last sample. No measurement is fed back: this
/// is what the model predicts from x₀ alone, the simulation a validation compares with the data.
///
/// `inputs[k]` is `Model::Input` (or converts to it), with at least outputs.size() samples. A shorter
/// input record, a period that is not finite and > 0 or fewer than one sub-step throw
/// std::invalid_argument (without exceptions: the outputs are NaN).
template <class Model, class Integrator, class Inputs, class Outputs>
typename Model::State freeRun(const Model& model, const Integrator& integrator, const typename Model::State& x0,
                              const typename Model::Param& theta, const Inputs& inputs,
                              const Sampling<typename Model::Scalar>& sampling, Outputs& outputs) {
  using Meas = typename Model::Meas;
  const bool valid = (detail::validSampling(sampling) || detail::refuse("freeRun: the sampling is not valid")) &&
                     (inputs.size() >= outputs.size() || detail::refuse("freeRun: fewer inputs than outputs"));
  if (!valid) {
    for (std::size_t k = 0; k < outputs.size(); ++k)
      outputs[k] = Meas::Constant(std::numeric_limits<typename Model::Scalar>::quiet_NaN());
    return Model::State::Constant(std::numeric_limits<typename Model::Scalar>::quiet_NaN());
  }
  return detail::freeRunWith(model, integrator, x0, theta, detail::HeldSamples<Model, Inputs>{inputs}, sampling,
                             outputs.size(), [&outputs](std::size_t k, const Meas& y) { outputs[k] = y; });
}

/// The free run as above with the model's own input signal u(t), evaluated at every stage time as
/// `timeUpdate(t, h)` does, and g at t_k with u(t_k); a model without input (InputDim = 0) needs none.
template <class Model, class Integrator, class Outputs>
typename Model::State freeRun(const Model& model, const Integrator& integrator, const typename Model::State& x0,
                              const typename Model::Param& theta, const Sampling<typename Model::Scalar>& sampling,
                              Outputs& outputs) {
  using Meas = typename Model::Meas;
  static_assert(needsNoInputArgument<Model>, "this model has no input(t): pass the inputs, one per sample");
  if (!(detail::validSampling(sampling) || detail::refuse("freeRun: the sampling is not valid"))) {
    for (std::size_t k = 0; k < outputs.size(); ++k)
      outputs[k] = Meas::Constant(std::numeric_limits<typename Model::Scalar>::quiet_NaN());
    return Model::State::Constant(std::numeric_limits<typename Model::Scalar>::quiet_NaN());
  }
  return detail::freeRunWith(model, integrator, x0, theta, detail::OwnSignal<Model>{model}, sampling, outputs.size(),
                             [&outputs](std::size_t k, const Meas& y) { outputs[k] = y; });
}

// ---- Validation metrics ----------------------------------------------------------------------------------

/// How well simulated outputs ŷ match measured ones y over a range of samples, per output component j:
///
///     rmsError_j   = √( Σ_k (y_kj − ŷ_kj)² / n_j )
///     fitPercent_j = 100 (1 − ‖y_j − ŷ_j‖ / ‖y_j − ȳ_j‖)        (the NRMSE fit of system identification)
///
/// over the samples k of the range where y_kj is not NaN (a missing measurement, skipped), n_j of
/// them, ȳ_j their mean. A fit of 100 % is a perfect match, 0 % no better than the constant ȳ_j, and it
/// can be negative (worse). NaN where n_j = 0, and the fit NaN where the measured y_j is constant
/// (‖y_j − ȳ_j‖ = 0). A simulated NaN against a measured value is not skipped: it makes that component's
/// metrics NaN (the simulation failed there).
template <class Scalar, int MeasDim>
struct OutputComparison {
  /// The RMS error per output, in the output's units.
  Eigen::Matrix<Scalar, MeasDim, 1> rmsError;
  /// The fit in percent per output.
  Eigen::Matrix<Scalar, MeasDim, 1> fitPercent;
  /// n_j: the samples compared per output (those whose measurement is not NaN).
  Eigen::Matrix<long, MeasDim, 1> samples;
};

/// The `OutputComparison` of `measured[k]` and `simulated[k]` (containers of the same Eigen column
/// vector type) over the samples first ≤ k < end. A range beyond either container, or first > end,
/// throws std::invalid_argument (without exceptions: NaN metrics over no samples).
template <class Measured, class Simulated>
auto compareOutputs(const Measured& measured, const Simulated& simulated, std::size_t first, std::size_t end) {
  using Vector = std::decay_t<decltype(measured[0])>;
  using Scalar = typename Vector::Scalar;
  constexpr int M = Vector::RowsAtCompileTime;
  OutputComparison<Scalar, M> c;
  c.samples.setZero();
  const Scalar nan = std::numeric_limits<Scalar>::quiet_NaN();
  c.rmsError.setConstant(nan);
  c.fitPercent.setConstant(nan);
  if (!((first <= end && end <= measured.size() && end <= simulated.size()) ||
        detail::refuse("compareOutputs: the range of samples lies beyond the records")))
    return c;
  // Two passes: the mean first, so that ‖y − ȳ‖ is summed from deviations (no cancellation).
  Eigen::Matrix<Scalar, M, 1> sum = Eigen::Matrix<Scalar, M, 1>::Zero();
  for (std::size_t k = first; k < end; ++k)
    for (int j = 0; j < M; ++j)
      if (!std::isnan(measured[k](j))) {
        sum(j) += measured[k](j);
        ++c.samples(j);
      }
  Eigen::Matrix<Scalar, M, 1> error = Eigen::Matrix<Scalar, M, 1>::Zero(), spread = error;
  for (std::size_t k = first; k < end; ++k)
    for (int j = 0; j < M; ++j)
      if (!std::isnan(measured[k](j))) {
        const Scalar mean = sum(j) / Scalar(c.samples(j));
        error(j) += (measured[k](j) - simulated[k](j)) * (measured[k](j) - simulated[k](j));
        spread(j) += (measured[k](j) - mean) * (measured[k](j) - mean);
      }
  for (int j = 0; j < M; ++j) {
    if (c.samples(j) == 0) continue;
    c.rmsError(j) = std::sqrt(error(j) / Scalar(c.samples(j)));
    if (spread(j) > Scalar(0)) c.fitPercent(j) = Scalar(100) * (Scalar(1) - std::sqrt(error(j) / spread(j)));
  }
  return c;
}

/// `compareOutputs` over every sample of the measured record (the simulated one at least as long).
template <class Measured, class Simulated>
auto compareOutputs(const Measured& measured, const Simulated& simulated) {
  return compareOutputs(measured, simulated, 0, measured.size());
}

}  // namespace mjukf::offline
