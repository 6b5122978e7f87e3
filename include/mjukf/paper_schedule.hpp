#pragma once

/// \file
/// The schedule of the paper's experiments (algorithms.md §7) and its accuracy metric (§8).

#include <cmath>

#include <Eigen/Core>

#include "mjukf/status.hpp"

namespace mjukf {

/// Where a scheduled run stopped: Status::Ok after the last row, otherwise the status of the refused
/// step and the row whose estimate it would have produced; and how many steps were taken with a
/// repaired covariance and how many measurements the gate rejected on the way.
struct ScheduleOutcome {
  Status status = Status::Ok;
  long row = 0;
  long repairs = 0;   ///< steps that returned Status::Repaired (taken)
  long rejected = 0;  ///< measurement updates that returned Status::MeasurementRejected
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
ScheduleOutcome runPaperSchedule(Filter& filter, long rows, typename Filter::Scalar h, int measurementEvery,
                                 MeasurementAt&& measurementAt, Record&& record) {
  using Scalar = typename Filter::Scalar;
  ScheduleOutcome outcome;
  if (rows < 1) return outcome;
  if (measurementEvery < 1) {
    outcome.status = Status::InvalidStepSize;
    return outcome;
  }
  // Counts a taken-with-repair or gated step and says whether the run goes on.
  const auto goesOn = [&outcome](Status s) {
    outcome.repairs += s == Status::Repaired;
    outcome.rejected += s == Status::MeasurementRejected;
    return taken(s) || s == Status::MeasurementRejected;
  };
  record(0L, static_cast<const Filter&>(filter));
  for (long k = 0; k + 1 < rows; ++k) {
    const Scalar t = Scalar(k) * h;
    Status status;
    if ((k + 1) % measurementEvery == 0) {
      status = filter.timeUpdate(t, h);
      if (goesOn(status)) status = filter.measurementUpdate(measurementAt(k + 1));
    } else {
      status = filter.propagateMean(t, h);
    }
    if (!goesOn(status)) {
      outcome.status = status;
      outcome.row = k + 1;
      return outcome;
    }
    record(k + 1, static_cast<const Filter&>(filter));
  }
  outcome.row = rows - 1;
  return outcome;
}

/// Root-mean-square error of a parameter vector against its truth, accumulated row by row (eq. 16).
/// The squares are summed in double even for float estimates: a float sum over the tank's 180 000 rows
/// would lose about 1% to rounding.
template <class Scalar, int Dim>
class RmseAccumulator {
 public:
  using Vector = Eigen::Matrix<Scalar, Dim, 1>;

  void add(const Vector& estimate, const Vector& truth) {
    sumOfSquares_ += (estimate - truth).template cast<double>().array().square().matrix();
    ++count_;
  }
  /// The RMSE of each component over the rows added so far (NaN before the first row).
  Vector value() const {
    return (sumOfSquares_ / double(count_)).array().sqrt().matrix().template cast<Scalar>();
  }
  long count() const { return count_; }

 private:
  Eigen::Matrix<double, Dim, 1> sumOfSquares_ = Eigen::Matrix<double, Dim, 1>::Zero();
  long count_ = 0;
};

}  // namespace mjukf
