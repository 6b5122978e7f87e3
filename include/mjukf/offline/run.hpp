#pragma once

/// \file
/// A filter run over a recorded data set, sample by sample, with everything the filter knows after
/// each sample handed to the caller: a host-side tool (docs/offline-tools.md), not part of the core
/// (`mjukf/mjukf.hpp` does not include it). The run itself allocates nothing; only the caller's
/// container of the whole trajectory, when it passes one, does.

#include <cmath>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "mjukf/diagnostics.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/measurement_gating.hpp"
#include "mjukf/model.hpp"
#include "mjukf/status.hpp"

namespace mjukf::offline {

/// A recorded data set on a regular grid, as views of the caller's arrays (nothing is copied).
///
/// Sample k (k = 0 … samples − 1) is one time update from t_k = startTime + k · stepsPerSample · stepSize
/// over `stepsPerSample` steps of `stepSize`, with the input u_k held over them, then one measurement
/// update with y_k, the measurement at the end of that interval (docs/real-data.md reads such rows
/// from a CSV file). The filter's initial estimate is the one at `startTime`. A NaN component of y_k
/// is missing: the update uses the other components (`measurementUpdate(y, present)`,
/// docs/robustness.md), and a y_k with none present leaves the estimate as it was.
template <class Model>
struct DataSet {
  /// The model's floating-point type.
  using Scalar = typename Model::Scalar;
  /// t₀, the time of the filter's initial estimate and of the first sample's time update.
  Scalar startTime = 0;
  /// h, the step of the stepper (of a discrete-time model, its dt).
  Scalar stepSize = 0;
  /// The steps of size h in one sample: one time update covers them all, with Q added once
  /// (filter_settings.hpp), as `timeUpdate(t, h, u, steps)` does.
  int stepsPerSample = 1;
  /// y_k, `samples` of them.
  const typename Model::Meas* measurements = nullptr;
  /// u_k, `samples` of them, or null: the model's own `input(t)` then, or no input at all
  /// (InputDim = 0). A model with neither needs them: without them every time update is refused
  /// (NonFiniteInput). A measurement that depends on the input (model.hpp) is evaluated with u_k.
  const typename Model::Input* inputs = nullptr;
  /// The number of samples.
  long samples = 0;

  /// t_k, computed from k (never accumulated, so that a long record does not drift off its grid).
  Scalar sampleTime(long k) const { return startTime + Scalar(k) * Scalar(stepsPerSample) * stepSize; }
};

/// The data set of the measurements `y` (and the held inputs `u`, unless empty) of the caller's
/// vectors, which must outlive it, on the grid (t₀, h, steps per sample).
template <class Model>
DataSet<Model> dataSet(typename Model::Scalar startTime, typename Model::Scalar stepSize,
                       const std::vector<typename Model::Meas>& y, const std::vector<typename Model::Input>& u = {},
                       int stepsPerSample = 1) {
  DataSet<Model> data;
  data.startTime = startTime;
  data.stepSize = stepSize;
  data.stepsPerSample = stepsPerSample;
  data.measurements = y.data();
  data.inputs = u.empty() ? nullptr : u.data();
  data.samples = static_cast<long>(y.size());
  return data;
}

/// \cond INTERNAL
namespace detail {

// The parameter covariance of a filter that has one (`parameterCovariance()`): JointUkf's θ block,
// DualUkf's parameter filter, ModifiedJointUkf's P_θ (NaN when it does not follow one). Ukf's
// parameters are known (docs/offline-tools.md), so its samples have no such member.
template <class Filter>
inline constexpr bool hasParameterCovariance = mjukf::detail::hasParameterCovariance<Filter>;

template <class Scalar, int ParamDim, bool Present>
struct ParameterCovarianceField {};
template <class Scalar, int ParamDim>
struct ParameterCovarianceField<Scalar, ParamDim, true> {
  /// The covariance of θ̂ (p × p): JointUkf's θ block of its covariance, DualUkf's parameter filter's.
  Eigen::Matrix<Scalar, ParamDim, ParamDim> parameterCovariance = Eigen::Matrix<Scalar, ParamDim, ParamDim>::Zero();
};

}  // namespace detail
/// \endcond

/// What a filter knows after one sample of a run: the statuses of the sample's two calls and the
/// filter's accessors read after them.
template <class Filter>
struct Sample : detail::ParameterCovarianceField<typename Filter::Scalar, Filter::ParamDim,
                                                 detail::hasParameterCovariance<Filter>> {
  /// The model's floating-point type.
  using Scalar = typename Filter::Scalar;
  /// What `filter.covariance()` returns: n × n, or (n + p) × (n + p) of [x; θ] for `JointUkf`.
  using Covariance = std::decay_t<decltype(std::declval<const Filter&>().covariance())>;

  /// t_{k+1}, the end of the sample's interval: where the measurement was taken.
  Scalar time = 0;
  /// The time update's status (status.hpp).
  Status timeUpdate = Status::Ok;
  /// The measurement update's status; when the time update was refused the measurement update is not
  /// called (its y belongs to a time the filter did not reach) and this repeats the time update's.
  Status measurementUpdate = Status::Ok;
  /// The number of components of y_k present (not NaN); 0 to m.
  int measuredComponents = 0;
  /// x̂ after the sample.
  typename Filter::State state = Filter::State::Zero();
  /// θ̂ after the sample: the fixed parameters of `Ukf`.
  typename Filter::Param parameters = Filter::Param::Zero();
  /// `filter.covariance()` after the sample (see `Covariance`).
  Covariance covariance = Covariance::Zero();
  /// `filter.lastUpdate()` after the sample: innovation, P_yy and NIS of this sample's update when it
  /// was taken, else of an earlier one (diagnostics.hpp). With components missing, their entries are
  /// those of the reduced update (zero innovation, an identity row and column of P_yy).
  UpdateDiagnostics<Scalar, Filter::MeasDim> diagnostics;
  /// `health()` after the sample (health.hpp): the first alarm of the run so far, or Ok.
  Health health = Health::Ok;

  /// True when both calls of the sample were taken (Ok or Repaired).
  bool taken() const { return mjukf::taken(timeUpdate) && mjukf::taken(measurementUpdate); }
};

/// What a whole run did: how many of its calls were refused.
struct RunSummary {
  long samples = 0;                    ///< samples run
  long refusedTimeUpdates = 0;         ///< time updates refused (their measurement update not called)
  long refusedMeasurementUpdates = 0;  ///< measurement updates called and refused (gate included)
};

/// The present components of y (its finite ones; a NaN is missing), and how many.
template <int MeasDim, class Meas>
int presentComponents(const Meas& y, MeasurementMask<MeasDim>& present) {
  int count = 0;
  for (int j = 0; j < MeasDim; ++j) {
    present(j) = !std::isnan(y(j));
    count += present(j) ? 1 : 0;
  }
  return count;
}

/// One sample k of `data` on `filter`: its time update, then (when that was taken) its measurement
/// update, exactly the calls a loop written by hand makes (the plain `measurementUpdate(y)` when every
/// component is present, the masked one otherwise). Writes the outcome into `sample`.
template <class Filter>
void runSample(Filter& filter, const DataSet<typename Filter::Model>& data, long k, Sample<Filter>& sample) {
  using Model = typename Filter::Model;
  constexpr int m = Model::MeasDim;
  const typename Model::Scalar t = data.sampleTime(k);
  const typename Model::Meas& y = data.measurements[k];
  if (data.inputs) {
    sample.timeUpdate = filter.timeUpdate(t, data.stepSize, data.inputs[k], data.stepsPerSample);
  } else if constexpr (needsNoInputArgument<Model>) {
    sample.timeUpdate = filter.timeUpdate(t, data.stepSize, data.stepsPerSample);
  } else {
    sample.timeUpdate = Status::NonFiniteInput;  // the model needs u_k and the data set has none
  }
  MeasurementMask<m> present;
  sample.measuredComponents = presentComponents<m>(y, present);
  if (!mjukf::taken(sample.timeUpdate)) {
    sample.measurementUpdate = sample.timeUpdate;
  } else {
    const bool all = sample.measuredComponents == m;
    if constexpr (measurementTakesInput<Model> && !hasInputSignal<Model>) {
      // u_k, or (no inputs, so InputDim = 0: the time update was taken) the empty input
      const typename Model::Input u = data.inputs ? data.inputs[k] : typename Model::Input();
      sample.measurementUpdate = all ? filter.measurementUpdate(y, u) : filter.measurementUpdate(y, u, present);
    } else if constexpr (measurementTakesInput<Model>) {
      if (data.inputs)
        sample.measurementUpdate =
            all ? filter.measurementUpdate(y, data.inputs[k]) : filter.measurementUpdate(y, data.inputs[k], present);
      else  // the model's own input(t) at the filter's time
        sample.measurementUpdate = all ? filter.measurementUpdate(y) : filter.measurementUpdate(y, present);
    } else {
      sample.measurementUpdate = all ? filter.measurementUpdate(y) : filter.measurementUpdate(y, present);
    }
  }
  sample.time = data.sampleTime(k + 1);
  sample.state = filter.state();
  sample.parameters = filter.parameters();
  sample.covariance = filter.covariance();
  if constexpr (detail::hasParameterCovariance<Filter>) sample.parameterCovariance = filter.parameterCovariance();
  sample.diagnostics = filter.lastUpdate();
  sample.health = filter.health();
}

/// Runs `filter` from where it is over every sample of `data` (runSample) and calls
/// `visit(long k, const Sample<Filter>&)` after each, in order. Allocates nothing itself. Returns what
/// was refused; the filter is left after the last sample.
template <class Filter, class Visit,
          std::enable_if_t<std::is_invocable_v<Visit&, long, const Sample<Filter>&>, int> = 0>
RunSummary run(Filter& filter, const DataSet<typename Filter::Model>& data, Visit&& visit) {
  RunSummary summary;
  Sample<Filter> sample;
  for (long k = 0; k < data.samples; ++k) {
    runSample(filter, data, k, sample);
    ++summary.samples;
    if (!mjukf::taken(sample.timeUpdate))
      ++summary.refusedTimeUpdates;
    else if (!mjukf::taken(sample.measurementUpdate))
      ++summary.refusedMeasurementUpdates;
    visit(k, static_cast<const Sample<Filter>&>(sample));
  }
  return summary;
}

/// Runs `filter` over `data` as above and stores every sample in `trajectory` (cleared first; sample
/// k at index k): the record the smoother (offline/smoother.hpp) reads.
template <class Filter>
RunSummary run(Filter& filter, const DataSet<typename Filter::Model>& data, std::vector<Sample<Filter>>& trajectory) {
  trajectory.clear();
  trajectory.reserve(static_cast<std::size_t>(data.samples > 0 ? data.samples : 0));
  return run(filter, data, [&trajectory](long, const Sample<Filter>& sample) { trajectory.push_back(sample); });
}

}  // namespace mjukf::offline
