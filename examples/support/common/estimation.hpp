#pragma once

// One filter run over a data set with the paper's schedule (docs/algorithms.md §7): which filter, its
// settings (the paper's by default, docs/plants.md §5; the library's for the dual UKF, which the paper
// does not run), and the estimates of every row.

#include <chrono>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "common/experiment.hpp"
#include "common/plant_data.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/health.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"
#include "paper/rmse.hpp"
#include "paper/schedule.hpp"

namespace mjukf::examples {

enum class FilterKind { Ukf, JointUkf, ModifiedJointUkf, DualUkf };

inline const char* filterName(FilterKind kind) {
  switch (kind) {
    case FilterKind::Ukf: return "ukf";
    case FilterKind::JointUkf: return "jukf";
    case FilterKind::ModifiedJointUkf: return "mjukf";
    case FilterKind::DualUkf: return "dual";
  }
  return "?";
}

/// Everything that defines a run; `paper(kind)` gives the paper's settings for `Experiment`.
template <class Experiment>
struct FilterSetup {
  using Model = typename Experiment::Model;
  FilterKind kind = FilterKind::ModifiedJointUkf;
  int measurementEvery = Experiment::measurementEvery;
  /// The paper's schedule (false): the steps between measurements propagate the mean alone and the
  /// time update covers the last step. True: one time update covers every step since the last
  /// measurement (the covariance propagated over all of them), and the rows between hold the estimate.
  bool wholeIntervalTimeUpdates = false;
  typename Model::State initialState = Experiment::initialState();
  /// θ̂₀ of the joint and dual filters; the fixed parameters of the UKF, which estimates none (the truth).
  typename Model::Param initialParameters = Experiment::initialParameters();
  UkfSettingsFor<Model> ukf = Experiment::ukf();
  JointUkfSettingsFor<Model> jointUkf = Experiment::jointUkf();
  ModifiedJointUkfSettingsFor<Model> modifiedJointUkf = Experiment::modifiedJointUkf();
  /// Not in the paper: the library's settings of the dual UKF on the plant (Experiment::dualUkf()).
  DualUkfSettingsFor<Model> dualUkf = Experiment::dualUkf();

  static FilterSetup paper(FilterKind kind) {
    FilterSetup setup;
    setup.kind = kind;
    if (kind == FilterKind::Ukf) setup.initialParameters = Model::trueParameters();
    return setup;
  }
};

/// The estimate of every row, and how the run went.
template <class Model>
struct EstimateRun {
  std::vector<typename Model::State> state;
  std::vector<typename Model::Param> parameters;
  paper::ScheduleOutcome outcome;
  double loopSeconds = 0;  ///< wall time of the schedule loop alone
  /// The filter's own covariance of θ̂ at the end (JUKF's θ block, the dual's P^θ); empty for a filter
  /// that reports none.
  std::optional<Eigen::Matrix<typename Model::Scalar, Model::ParamDim, Model::ParamDim>> finalParameterCovariance;
  /// The filter's health at the end of the run (its verdict then) and the statistics behind it (the first alarm among
  /// them) (health.hpp; docs/robustness.md, "The health monitor").
  Health health = Health::Ok;
  HealthStatistics<typename Model::Scalar> healthStatistics;
  /// The changes of θ the automatic MJUKF's test found (docs/algorithms.md §5.4); empty for the others.
  std::optional<long> parameterChanges;
};

namespace detail {

template <class Filter, class = void>
struct HasParameterCovariance : std::false_type {};
template <class Filter>
struct HasParameterCovariance<Filter, std::void_t<decltype(std::declval<const Filter&>().parameterCovariance())>>
    : std::true_type {};

template <class Filter, class = void>
struct HasChangeTest : std::false_type {};
template <class Filter>
struct HasChangeTest<Filter, std::void_t<decltype(std::declval<const Filter&>().detectedParameterChanges())>>
    : std::true_type {};

// The covariance of θ̂ a filter reports: the dual's P^θ, JUKF's θ block of P; none for the others.
template <class Filter>
std::optional<Eigen::Matrix<typename Filter::Scalar, Filter::ParamDim, Filter::ParamDim>> parameterCovarianceOf(
    const Filter& filter) {
  constexpr int n = Filter::StateDim, p = Filter::ParamDim;
  if constexpr (HasParameterCovariance<Filter>::value)
    return filter.parameterCovariance();
  else if constexpr (std::decay_t<decltype(filter.covariance())>::RowsAtCompileTime == n + p)
    return filter.covariance().template bottomRightCorner<p, p>();
  else
    return std::nullopt;
}

// The schedule of FilterSetup::wholeIntervalTimeUpdates: at each measurement row, one time update over
// the `measurementEvery` steps since the last and the measurement update; every row records the
// estimate then in force. A refused step stops the run there (a gated measurement goes on).
template <class Filter, class MeasurementAt, class Record>
paper::ScheduleOutcome wholeIntervalSchedule(Filter& filter, long rows, typename Filter::Scalar h, int measurementEvery,
                                             MeasurementAt&& measurementAt, Record&& record) {
  using Scalar = typename Filter::Scalar;
  paper::ScheduleOutcome outcome;
  if (rows < 1) return outcome;
  if (measurementEvery < 1) {
    outcome.status = Status::InvalidStepSize;
    return outcome;
  }
  record(0L, static_cast<const Filter&>(filter));
  for (long k = 1; k < rows; ++k) {
    if (k % measurementEvery == 0) {
      Status status = filter.timeUpdate(Scalar(k - measurementEvery) * h, h, measurementEvery);
      if (outcome.goesOn(status)) status = filter.measurementUpdate(measurementAt(k));
      if (!outcome.goesOn(status)) {
        outcome.status = status;
        outcome.row = k;
        return outcome;
      }
    }
    record(k, static_cast<const Filter&>(filter));
  }
  outcome.row = rows - 1;
  return outcome;
}

template <class Filter, class Model>
EstimateRun<Model> runSchedule(Filter& filter, const PlantData<Model>& data, int measurementEvery,
                               bool wholeIntervals = false) {
  EstimateRun<Model> run;
  // Filled with zeros here, so the pages are touched before the clock starts: left to the loop, their
  // first-touch page faults were part of a single run's loop_seconds.
  run.state.assign(data.y.size(), Model::State::Zero());
  run.parameters.assign(data.y.size(), Model::Param::Zero());
  const auto start = std::chrono::steady_clock::now();
  const auto measurementAt = [&](long k) -> const typename Model::Meas& { return data.y[static_cast<std::size_t>(k)]; };
  const auto record = [&](long k, const Filter& f) {
    run.state[static_cast<std::size_t>(k)] = f.state();
    run.parameters[static_cast<std::size_t>(k)] = f.parameters();
  };
  run.outcome = wholeIntervals
                    ? wholeIntervalSchedule(filter, data.rows(), data.stepSize, measurementEvery, measurementAt, record)
                    : paper::runSchedule(filter, data.rows(), data.stepSize, measurementEvery, measurementAt, record);
  run.loopSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.finalParameterCovariance = parameterCovarianceOf(filter);
  run.health = filter.health();
  run.healthStatistics = filter.healthStatistics();
  if constexpr (HasChangeTest<Filter>::value)
    if (filter.settings().adaptiveScaling) run.parameterChanges = filter.detectedParameterChanges();
  if (run.outcome.status != Status::Ok) {  // keep only the rows that were estimated
    run.state.resize(static_cast<std::size_t>(run.outcome.row));
    run.parameters.resize(static_cast<std::size_t>(run.outcome.row));
  }
  return run;
}

}  // namespace detail

/// Runs the filter of `setup` over `data`. Throws std::invalid_argument (naming the setting) when the
/// settings are invalid.
template <class Experiment>
EstimateRun<typename Experiment::Model> runFilter(const typename Experiment::Model& model,
                                                  const FilterSetup<Experiment>& setup,
                                                  const PlantData<typename Experiment::Model>& data) {
  using Model = typename Experiment::Model;
  using Integrator = ExperimentIntegrator<Experiment>;
  switch (setup.kind) {
    case FilterKind::Ukf: {
      Ukf<Model, Integrator> filter(model, setup.initialState, setup.initialParameters, setup.ukf);
      return detail::runSchedule(filter, data, setup.measurementEvery, setup.wholeIntervalTimeUpdates);
    }
    case FilterKind::JointUkf: {
      JointUkf<Model, Integrator> filter(model, setup.initialState, setup.initialParameters, setup.jointUkf);
      return detail::runSchedule(filter, data, setup.measurementEvery, setup.wholeIntervalTimeUpdates);
    }
    case FilterKind::ModifiedJointUkf: {
      ModifiedJointUkf<Model, Integrator> filter(model, setup.initialState, setup.initialParameters,
                                                 setup.modifiedJointUkf);
      return detail::runSchedule(filter, data, setup.measurementEvery, setup.wholeIntervalTimeUpdates);
    }
    case FilterKind::DualUkf: {
      DualUkf<Model, Integrator> filter(model, setup.initialState, setup.initialParameters, setup.dualUkf);
      return detail::runSchedule(filter, data, setup.measurementEvery, setup.wholeIntervalTimeUpdates);
    }
  }
  throw std::logic_error("unknown filter kind");
}

/// RMSE of each parameter over rows `fromRow` … (eq. 16), against the data's parameter truth.
template <class Model>
typename Model::Param parameterRmse(const EstimateRun<Model>& run, const PlantData<Model>& data, long fromRow) {
  paper::RmseAccumulator<typename Model::Scalar, Model::ParamDim> rmse;
  for (long k = fromRow; k < static_cast<long>(run.parameters.size()); ++k)
    rmse.add(run.parameters[static_cast<std::size_t>(k)], data.parameterTruth[static_cast<std::size_t>(k)]);
  return rmse.value();
}

/// Writes the estimates as t, x1…xn, theta1…thetap, one row per data row, to `file` (atomic_file.hpp).
template <class Model>
void writeEstimates(const OutputFile& file, const EstimateRun<Model>& run, double h) {
  std::vector<std::string> header{"t"};
  for (const auto& names : {numberedNames("x", Model::StateDim), numberedNames("theta", Model::ParamDim)})
    header.insert(header.end(), names.begin(), names.end());
  CsvWriter out(file, header);
  for (std::size_t k = 0; k < run.state.size(); ++k) {
    out << static_cast<double>(k) * h;
    out.fields(run.state[k]).fields(run.parameters[k]);
    out.endRow();
  }
  out.close();
}

}  // namespace mjukf::examples
