// The long run (label `long`): 10⁷ integrator steps (10⁴ s at h = 1 ms) of the coupled tank with the
// paper's schedule and settings, on simulated measurements with noise. The covariance must be exactly
// symmetric and positive definite after every update, the estimate finite, the run never refused.

#include <chrono>
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "paper/experiments.hpp"
#include "paper/rmse.hpp"
#include "paper/schedule.hpp"
#include "robustness_support.hpp"

namespace {

using Tank = mjukf::paper::CoupledTankExperiment<double>;
constexpr long kRows = 10'000'001;  // 10⁷ steps

template <class Filter>
void longRun(Filter& filter, const char* name) {
  mjukf::testing::TankMeasurements<Tank::Model> data(Tank::stepSize, 0.3, 2024);
  long updatesChecked = 0, failures = 0;
  mjukf::paper::RmseAccumulator<double, 1> lastHour;
  const auto start = std::chrono::steady_clock::now();
  const auto outcome = mjukf::paper::runSchedule(
      filter, kRows, Tank::stepSize, Tank::measurementEvery,
      [&](long k) -> const Tank::Model::Meas& { return data.at(k); },
      [&](long k, const Filter& f) {
        if (k % Tank::measurementEvery != 0) return;  // P changes only at the updates
        ++updatesChecked;
        const bool ok = mjukf::testing::symmetricPositiveDefinite(f.covariance()) && f.state().allFinite() &&
                        f.parameters().allFinite();
        if (!ok && failures++ < 5) ADD_FAILURE() << name << ": row " << k << " covariance\n" << f.covariance();
        if (k >= kRows - 3'600'001) lastHour.add(f.parameters(), Tank::Model::trueParameters());
      });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "%s: %ld rows (%ld steps), %ld updates checked, status %s, %ld repairs, %ld rejected, "
      "k_flow %.6f (RMSE over the last hour %.3g), %.2f s\n",
      name, outcome.row + 1, outcome.row, updatesChecked, mjukf::toString(outcome.status), outcome.repairs,
      outcome.rejected, filter.parameters()(0), lastHour.value()(0), seconds);
  EXPECT_EQ(outcome.status, mjukf::Status::Ok);
  EXPECT_EQ(outcome.row, kRows - 1);
  EXPECT_EQ(updatesChecked, (kRows - 1) / Tank::measurementEvery + 1);
  EXPECT_EQ(failures, 0);
  EXPECT_TRUE(std::isfinite(lastHour.value()(0)));
}

TEST(LongRun, CoupledTankJointUkfTenMillionSteps) {
  mjukf::JointUkf<Tank::Model> filter(Tank::Model(), Tank::initialState(), Tank::initialParameters(), Tank::jointUkf());
  longRun(filter, "JUKF");
}

TEST(LongRun, CoupledTankModifiedJointUkfTenMillionSteps) {
  mjukf::ModifiedJointUkf<Tank::Model> filter(Tank::Model(), Tank::initialState(), Tank::initialParameters(),
                                              Tank::modifiedJointUkf());
  longRun(filter, "MJUKF");
}

}  // namespace
