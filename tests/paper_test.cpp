// The paper layer: the schedule (docs/algorithms.md §7), which call happens at which row and where a
// refused step stops the run; and the RMSE.

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <gtest/gtest.h>

#include "mjukf/status.hpp"
#include "paper/rmse.hpp"
#include "paper/schedule.hpp"

namespace {

using mjukf::Status;

// Records the calls the schedule makes, as text, and refuses the call numbered `refuseAt`.
struct RecordingFilter {
  using Scalar = double;
  using Param = Eigen::Matrix<double, 1, 1>;
  std::vector<std::string> calls;
  int refuseAt = -1;

  Status note(std::string call) {
    calls.push_back(std::move(call));
    return static_cast<int>(calls.size()) - 1 == refuseAt ? Status::NonFiniteResult : Status::Ok;
  }
  Status timeUpdate(double t, double h) { return note("T " + std::to_string(t) + " " + std::to_string(h)); }
  Status propagateMean(double t, double) { return note("P " + std::to_string(t)); }
  Status measurementUpdate(long row) { return note("M " + std::to_string(row)); }
};

TEST(PaperSchedule, TimeAndMeasurementUpdateEveryNthStepOpenLoopOtherwise) {
  RecordingFilter filter;
  std::vector<long> recorded;
  const auto outcome = mjukf::paper::runSchedule(
      filter, 8, 0.5, 3, [](long k) { return k; }, [&](long k, const RecordingFilter&) { recorded.push_back(k); });
  EXPECT_EQ(outcome.status, Status::Ok);
  EXPECT_EQ(outcome.row, 7);
  // k = 0 … 6: (k + 1) mod 3 = 0 at k = 2 and 5: time update from t_k, then y_{k+1}.
  const std::vector<std::string> expected = {"P 0.000000", "P 0.500000", "T 1.000000 0.500000", "M 3",
                                             "P 1.500000", "P 2.000000", "T 2.500000 0.500000", "M 6",
                                             "P 3.000000"};
  EXPECT_EQ(filter.calls, expected);
  EXPECT_EQ(recorded, (std::vector<long>{0, 1, 2, 3, 4, 5, 6, 7}));  // row 0: the initial estimate
}

TEST(PaperSchedule, StopsAtTheFirstRefusedStep) {
  RecordingFilter filter;
  filter.refuseAt = 3;  // the measurement update with y_3
  std::vector<long> recorded;
  const auto outcome = mjukf::paper::runSchedule(
      filter, 8, 0.5, 3, [](long k) { return k; }, [&](long k, const RecordingFilter&) { recorded.push_back(k); });
  EXPECT_EQ(outcome.status, Status::NonFiniteResult);
  EXPECT_EQ(outcome.row, 3);
  EXPECT_EQ(filter.calls.size(), 4u);
  EXPECT_EQ(recorded, (std::vector<long>{0, 1, 2}));
}

TEST(PaperSchedule, RmseAccumulatorIsTheRootMeanSquare) {
  mjukf::paper::RmseAccumulator<double, 2> rmse;
  rmse.add(Eigen::Vector2d(1.0, 0.0), Eigen::Vector2d(0.0, 0.0));
  rmse.add(Eigen::Vector2d(-1.0, 2.0), Eigen::Vector2d(0.0, 0.0));
  rmse.add(Eigen::Vector2d(2.0, 4.0), Eigen::Vector2d(1.0, 2.0));
  EXPECT_EQ(rmse.count(), 3);
  EXPECT_DOUBLE_EQ(rmse.value()(0), 1.0);
  EXPECT_DOUBLE_EQ(rmse.value()(1), std::sqrt(8.0 / 3.0));
}

}  // namespace
