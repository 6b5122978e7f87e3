#pragma once

/// \file
/// The schedule of the paper's experiments (docs/algorithms.md §7).

#include "mjukf/status.hpp"

namespace mjukf::paper {

/// Where a scheduled run stopped: Status::Ok after the last row, otherwise the status of the refused
/// step and the row whose estimate it would have produced; and how many steps were taken with a
/// repaired covariance and how many measurements the gate rejected on the way.
struct ScheduleOutcome {
  /// Ok after the last row, otherwise the status of the refused step that stopped the run.
  Status status = Status::Ok;
  /// The row the refused step would have produced, or the last row (rows − 1) after a complete run.
  long row = 0;
  long repairs = 0;   ///< steps that returned Status::Repaired (taken)
  long rejected = 0;  ///< measurement updates that returned Status::MeasurementRejected

  /// Counts a step taken with a repair or a measurement the gate rejected, and says whether the run
  /// goes on after `s`: a taken step or a rejected measurement.
  bool goesOn(Status s) {
    repairs += s == Status::Repaired;
    rejected += s == Status::MeasurementRejected;
    return taken(s) || s == Status::MeasurementRejected;
  }
};

/// Drives `filter` over data rows k = 0 … rows − 1 at t_k = k h, the way the paper's experiments do:
/// for k = 0 … rows − 2, when (k + 1) is a multiple of `measurementEvery`, an unscented time update
/// from t_k over one step followed by a measurement update with `measurementAt(k + 1)`; otherwise the
/// mean alone is propagated open loop and P is left as it is.
///
/// `record(k, filter)` is called for every row: row 0 holds the initial estimate and the estimate
/// after step k belongs to row k + 1. The run goes on after a step taken with a repaired covariance
/// and after a measurement the gate rejected (the time update before it stands; both are counted),
/// and stops at the first other refused step.
template <class Filter, class MeasurementAt, class Record>
ScheduleOutcome runSchedule(Filter& filter, long rows, typename Filter::Scalar h, int measurementEvery,
                            MeasurementAt&& measurementAt, Record&& record) {
  using Scalar = typename Filter::Scalar;
  ScheduleOutcome outcome;
  if (rows < 1) return outcome;
  if (measurementEvery < 1) {
    outcome.status = Status::InvalidStepSize;
    return outcome;
  }
  record(0L, static_cast<const Filter&>(filter));
  for (long k = 0; k + 1 < rows; ++k) {
    const Scalar t = Scalar(k) * h;
    Status status;
    if ((k + 1) % measurementEvery == 0) {
      status = filter.timeUpdate(t, h);
      if (outcome.goesOn(status)) status = filter.measurementUpdate(measurementAt(k + 1));
    } else {
      status = filter.propagateMean(t, h);
    }
    if (!outcome.goesOn(status)) {
      outcome.status = status;
      outcome.row = k + 1;
      return outcome;
    }
    record(k + 1, static_cast<const Filter&>(filter));
  }
  outcome.row = rows - 1;
  return outcome;
}

}  // namespace mjukf::paper
