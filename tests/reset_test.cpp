// reset() on every filter: after any history (here a run on corrupted measurements that drives the
// estimates away), reset(x, P[, θ …]) makes the filter the same, bit for bit, as one constructed with
// those values: everything a caller can observe over the next few hundred steps of the paper's
// schedule, starting with a measurement update that must draw its points from the new estimate (the
// sigma points and, for the dual filter, the prior of the last time update are forgotten). Bad
// arguments throw std::invalid_argument naming the argument and change nothing.

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "common/csv.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"
#include "paper/experiments.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace {

using mjukf::DualUkfOrdering;
using mjukf::Status;
using mjukf::testing::bitwiseSame;
using mjukf::testing::IsDual;
using mjukf::testing::IsModifiedJoint;
using mjukf::testing::sameFilter;
using Robot = mjukf::paper::FlexibleJointExperiment<double>;
using Model = Robot::Model;
using Ukf = mjukf::Ukf<Model>;
using JointUkf = mjukf::JointUkf<Model>;
using ModifiedJointUkf = mjukf::ModifiedJointUkf<Model>;
using DualUkf = mjukf::DualUkf<Model>;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

const std::vector<Model::Meas>& measurements() {
  static const std::vector<Model::Meas> rows = [] {
    const auto table = mjukf::examples::readCsv(std::string(MJUKF_DATA_DIR) + "/flexible_joint_reference.csv");
    std::vector<Model::Meas> y(table.rows());
    for (int c = 0; c < 4; ++c) {
      const auto& column = table.column("y" + std::to_string(c + 1));
      for (std::size_t k = 0; k < y.size(); ++k) y[k](c) = column[k];
    }
    return y;
  }();
  return rows;
}

const Model::Meas& row(long k) { return measurements()[static_cast<std::size_t>(k)]; }

// Rows [from, to) of the paper's schedule: a time and a measurement update every 5th step, the mean
// open loop otherwise. With `corrupt`, the measurements are −4 y + 0.5: the estimates run away.
template <class Filter>
void schedule(Filter& f, long from, long to, bool corrupt = false) {
  for (long k = from; k < to; ++k) {
    const double t = double(k) * Robot::stepSize;
    if ((k + 1) % Robot::measurementEvery == 0) {
      ASSERT_TRUE(mjukf::taken(f.timeUpdate(t, Robot::stepSize))) << "row " << k;
      const Model::Meas y = corrupt ? Model::Meas(-4 * row(k + 1) + Model::Meas::Constant(0.5)) : row(k + 1);
      ASSERT_TRUE(mjukf::taken(f.measurementUpdate(y))) << "row " << k;
    } else {
      ASSERT_TRUE(mjukf::taken(f.propagateMean(t, Robot::stepSize))) << "row " << k;
    }
  }
}

// A filter after 1000 rows on corrupted measurements, ending with a time update (so that it holds
// propagated points, and the dual filter a prior for its UpdatedParameters ordering).
constexpr long kHistory = 1000;
template <class Filter>
Filter diverged(Filter f) {
  schedule(f, 0, kHistory - 1, true);
  EXPECT_TRUE(mjukf::taken(f.timeUpdate(double(kHistory - 1) * Robot::stepSize, Robot::stepSize)));
  EXPECT_TRUE(f.hasPropagatedPoints());
  return f;
}

// After reset, `reset` and `fresh` run the next 600 rows the same: first a measurement update with
// no time update before it, then the schedule.
template <class Filter>
void expectSameFromNowOn(Filter& reset, Filter& fresh) {
  ASSERT_TRUE(sameFilter(reset, fresh)) << "right after reset";
  ASSERT_FALSE(reset.hasPropagatedPoints());
  ASSERT_TRUE(mjukf::taken(reset.measurementUpdate(row(kHistory))));
  ASSERT_TRUE(mjukf::taken(fresh.measurementUpdate(row(kHistory))));
  ASSERT_TRUE(sameFilter(reset, fresh)) << "after the first measurement update";
  for (long k = kHistory; k < kHistory + 600; k += 5) {
    schedule(reset, k, k + 5);
    schedule(fresh, k, k + 5);
    ASSERT_TRUE(sameFilter(reset, fresh)) << "row " << k + 5;
  }
}

// The values to reset to: a correlated covariance (not the settings' diagonal P₀), a state, and
// parameters other than the first guess.
template <int N>
Eigen::Matrix<double, N, N> someCovariance(unsigned seed) {
  std::mt19937_64 rng(seed);
  return mjukf::testing::randomCovariance<N>(rng, 0.05);
}
const Model::State kState(0.05, -0.2, 0.03, 0.1);
const Model::Param kParameters(0.14, 0.2);

// Every filter that estimates parameters runs with bounds here, wide enough for the truth.
template <class Settings>
Settings bounded(Settings s) {
  s.parameterBounds.lower << 0.05, 0.05;
  s.parameterBounds.upper << 0.3, 0.4;
  return s;
}

// ---------------------------------------------------------------------------------------------------
// reset(...) equals a fresh filter.

TEST(Reset, UkfEqualsAFreshFilter) {
  const Ukf original(Model(), Robot::initialState(), Model::trueParameters(), Robot::ukf());
  const auto P = someCovariance<4>(1);
  auto settings = Robot::ukf();
  settings.initialCovariance = P;
  {  // reset(x, P) keeps the parameters
    Ukf filter = diverged(original);
    EXPECT_FALSE(bitwiseSame(filter.state(), kState));
    filter.reset(kState, P);
    Ukf fresh(Model(), kState, Model::trueParameters(), settings);
    expectSameFromNowOn(filter, fresh);
  }
  {  // reset(x, P, θ) with other parameters
    Ukf filter = diverged(original);
    filter.reset(kState, P, kParameters);
    EXPECT_EQ(filter.parameters(), kParameters);
    Ukf fresh(Model(), kState, kParameters, settings);
    expectSameFromNowOn(filter, fresh);
  }
}

TEST(Reset, JointUkfEqualsAFreshFilter) {
  const auto settings = bounded(Robot::jointUkf());
  const JointUkf original(Model(), Robot::initialState(), Robot::initialParameters(), settings);
  const auto P = someCovariance<6>(2);
  auto freshSettings = settings;
  freshSettings.initialCovariance = P;
  {  // reset(x, P) keeps the current θ̂
    JointUkf filter = diverged(original);
    const Model::Param kept = filter.parameters();
    EXPECT_GT((kept - Robot::initialParameters()).cwiseAbs().maxCoeff(), 1e-3) << "θ̂ did not move";
    filter.reset(kState, P);
    JointUkf fresh(Model(), kState, kept, freshSettings);
    expectSameFromNowOn(filter, fresh);
  }
  {
    JointUkf filter = diverged(original);
    filter.reset(kState, P, kParameters);
    JointUkf fresh(Model(), kState, kParameters, freshSettings);
    expectSameFromNowOn(filter, fresh);
  }
}

TEST(Reset, ModifiedJointUkfEqualsAFreshFilter) {
  auto settings = bounded(Robot::modifiedJointUkf());
  const ModifiedJointUkf original(Model(), Robot::initialState(), Robot::initialParameters(), settings);
  const auto P = someCovariance<4>(3);
  auto freshSettings = settings;
  freshSettings.initialCovariance = P;
  ModifiedJointUkf filter = diverged(original);
  filter.reset(kState, P, kParameters);
  ModifiedJointUkf fresh(Model(), kState, kParameters, freshSettings);
  expectSameFromNowOn(filter, fresh);
}

// reset(x, P) of MJUKF keeps θ̂ and the θᵢ as they are (a fresh filter would spread them by eq. 8), and
// is otherwise the committed (x, P) with no points and no diagnostics.
TEST(Reset, ModifiedJointUkfKeepsItsParameterPoints) {
  const auto settings = bounded(Robot::modifiedJointUkf());
  ModifiedJointUkf filter =
      diverged(ModifiedJointUkf(Model(), Robot::initialState(), Robot::initialParameters(), settings));
  const Model::Param theta = filter.parameters();
  const ModifiedJointUkf::ParamPoints points = filter.parameterPoints();
  const auto P = someCovariance<4>(4);
  filter.reset(kState, P);
  EXPECT_TRUE(bitwiseSame(filter.parameters(), theta));
  EXPECT_TRUE(bitwiseSame(filter.parameterPoints(), points));
  EXPECT_TRUE(bitwiseSame(filter.state(), kState));
  Eigen::Matrix4d symmetric = P;
  mjukf::detail::symmetrize(symmetric);
  EXPECT_TRUE(bitwiseSame(filter.covariance(), symmetric));
  EXPECT_FALSE(filter.hasPropagatedPoints());
  EXPECT_EQ(filter.lastUpdate().nis, 0.0);
  // The θᵢ no longer follow eq. 8 around θ̂ (the history moved them apart): the reset kept them.
  ModifiedJointUkf fresh(Model(), kState, theta, settings);
  EXPECT_FALSE(bitwiseSame(fresh.parameterPoints(), points));
}

// reset(x, P, θ) spreads the θᵢ around θ by eq. 8, θᵢ = θ − p_θ (n + 1) + p_θ (i + 1), clamped to the
// bounds, exactly as a fresh filter does: here p_θ = 0.01 and θ = (0.06, 0.2), so θᵢ(0) runs from
// 0.02 to 0.10 and the lower bound 0.05 clamps the first four.
TEST(Reset, ModifiedJointUkfSpreadsTheParametersByEquation8) {
  const auto settings = bounded(Robot::modifiedJointUkf());
  ModifiedJointUkf filter =
      diverged(ModifiedJointUkf(Model(), Robot::initialState(), Robot::initialParameters(), settings));
  const Model::Param theta(0.06, 0.2);
  const auto P = someCovariance<4>(5);
  filter.reset(kState, P, theta);
  auto freshSettings = settings;
  freshSettings.initialCovariance = P;
  const ModifiedJointUkf fresh(Model(), kState, theta, freshSettings);
  EXPECT_TRUE(bitwiseSame(filter.parameterPoints(), fresh.parameterPoints()));
  EXPECT_TRUE(bitwiseSame(filter.parameters(), theta));
  const Model::Param spread = settings.parameterSpread;
  int clamped = 0;
  for (int i = 0; i < ModifiedJointUkf::SigmaPointCount; ++i) {
    for (int j = 0; j < 2; ++j) {
      const double unclamped = theta(j) + spread(j) * (i - Model::StateDim);
      const double expected =
          std::clamp(unclamped, settings.parameterBounds.lower(j), settings.parameterBounds.upper(j));
      EXPECT_NEAR(filter.parameterPoints()(j, i), expected, 1e-15) << "θ_" << i << "(" << j << ")";
      clamped += expected != unclamped;
    }
  }
  EXPECT_EQ(clamped, 4);
}

template <DualUkfOrdering Ordering>
void expectDualResetsEqualAFreshFilter() {
  auto settings = bounded(Robot::dualUkf());
  settings.ordering = Ordering;
  const DualUkf original(Model(), Robot::initialState(), Robot::initialParameters(), settings);
  const auto P = someCovariance<4>(6);
  const Eigen::Matrix2d Ptheta = someCovariance<2>(7) * 0.01;
  const auto freshSettings = [&](const Eigen::Matrix2d& parameterCovariance) {
    auto s = settings;
    s.initialCovariance = P;
    s.initialParameterCovariance = parameterCovariance;
    return s;
  };
  {  // reset(x, P) keeps θ̂ and P^θ
    DualUkf filter = diverged(original);
    const Model::Param theta = filter.parameters();
    const Eigen::Matrix2d kept = filter.parameterCovariance();
    EXPECT_GT((theta - Robot::initialParameters()).cwiseAbs().maxCoeff(), 1e-3) << "θ̂ did not move";
    filter.reset(kState, P);
    DualUkf fresh(Model(), kState, theta, freshSettings(kept));
    expectSameFromNowOn(filter, fresh);
  }
  {  // reset(x, P, θ) keeps P^θ
    DualUkf filter = diverged(original);
    const Eigen::Matrix2d kept = filter.parameterCovariance();
    filter.reset(kState, P, kParameters);
    DualUkf fresh(Model(), kState, kParameters, freshSettings(kept));
    expectSameFromNowOn(filter, fresh);
  }
  {  // reset(x, P, θ, P^θ)
    DualUkf filter = diverged(original);
    filter.reset(kState, P, kParameters, Ptheta);
    DualUkf fresh(Model(), kState, kParameters, freshSettings(Ptheta));
    expectSameFromNowOn(filter, fresh);
  }
}

TEST(Reset, DualUkfEqualsAFreshFilterPriorParameters) {
  expectDualResetsEqualAFreshFilter<DualUkfOrdering::PriorParameters>();
}
TEST(Reset, DualUkfEqualsAFreshFilterUpdatedParameters) {
  expectDualResetsEqualAFreshFilter<DualUkfOrdering::UpdatedParameters>();
}

// ---------------------------------------------------------------------------------------------------
// Bad arguments: std::invalid_argument naming the argument, and nothing changes.

// `call` throws std::invalid_argument whose message names 'argument', and the filter is unchanged:
// bitwise the same as a copy taken before, then and after the next measurement update of both.
template <class Filter, class Call>
void expectRejected(Filter& filter, const std::string& argument, Call&& call) {
  const Filter before = filter;
  try {
    call(filter);
    ADD_FAILURE() << "accepted a bad '" << argument << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'" + argument + "'"), std::string::npos) << "message: " << e.what();
  }
  EXPECT_TRUE(sameFilter(filter, before)) << "the refused reset changed the filter (" << argument << ")";
  Filter untouched = before;
  ASSERT_TRUE(mjukf::taken(filter.measurementUpdate(row(kHistory))));
  ASSERT_TRUE(mjukf::taken(untouched.measurementUpdate(row(kHistory))));
  EXPECT_TRUE(sameFilter(filter, untouched)) << "the next update differs (" << argument << ")";
  ASSERT_TRUE(mjukf::taken(filter.timeUpdate(double(kHistory) * Robot::stepSize, Robot::stepSize)));
}

// Covariances reset() must refuse, each with the reason in its name.
template <int N>
std::vector<std::pair<std::string, Eigen::Matrix<double, N, N>>> badCovariances(
    const Eigen::Matrix<double, N, N>& good) {
  std::vector<std::pair<std::string, Eigen::Matrix<double, N, N>>> bad;
  auto m = good;
  m(1, 1) = kNan;
  bad.emplace_back("NaN", m);
  m = good;
  m(0, N - 1) = std::numeric_limits<double>::infinity();
  m(N - 1, 0) = std::numeric_limits<double>::infinity();
  bad.emplace_back("Inf", m);
  m = good;
  m(0, 1) += 0.01;  // asymmetric by far more than rounding
  bad.emplace_back("asymmetric", m);
  m = good;
  m(N - 1, N - 1) = -good(N - 1, N - 1);
  bad.emplace_back("negative diagonal", m);
  m = good;
  m(0, 1) = m(1, 0) = 2 * std::sqrt(good(0, 0) * good(1, 1));  // symmetric, correlation 2: indefinite
  bad.emplace_back("indefinite", m);
  bad.emplace_back("zero", Eigen::Matrix<double, N, N>::Zero());
  return bad;
}

Model::State badState() {
  Model::State x = kState;
  x(2) = kNan;
  return x;
}

// Parameters reset() must refuse: NaN, and (with the bounds of `bounded`) outside the box.
std::vector<Model::Param> badParameters() {
  return {Model::Param(kNan, 0.2), Model::Param(0.14, 0.5), Model::Param(0.01, 0.2)};
}

TEST(Reset, UkfRefusesBadArguments) {
  Ukf filter = diverged(Ukf(Model(), Robot::initialState(), Model::trueParameters(), Robot::ukf()));
  const auto P = someCovariance<4>(8);
  expectRejected(filter, "state", [&](Ukf& f) { f.reset(badState(), P); });
  expectRejected(filter, "state", [&](Ukf& f) { f.reset(badState(), P, kParameters); });
  for (const auto& entry : badCovariances<4>(P)) {
    const auto& bad = entry.second;
    SCOPED_TRACE(entry.first);
    expectRejected(filter, "covariance", [&](Ukf& f) { f.reset(kState, bad); });
    expectRejected(filter, "covariance", [&](Ukf& f) { f.reset(kState, bad, kParameters); });
  }
  // The UKF has no bounds: only non-finite parameters are refused.
  expectRejected(filter, "parameters", [&](Ukf& f) { f.reset(kState, P, Model::Param(kNan, 0.2)); });
  expectRejected(filter, "parameters",
                 [&](Ukf& f) { f.reset(kState, P, Model::Param(0.14, -std::numeric_limits<double>::infinity())); });
}

TEST(Reset, JointUkfRefusesBadArguments) {
  JointUkf filter =
      diverged(JointUkf(Model(), Robot::initialState(), Robot::initialParameters(), bounded(Robot::jointUkf())));
  const auto P = someCovariance<6>(9);
  expectRejected(filter, "state", [&](JointUkf& f) { f.reset(badState(), P); });
  expectRejected(filter, "state", [&](JointUkf& f) { f.reset(badState(), P, kParameters); });
  for (const auto& entry : badCovariances<6>(P)) {
    const auto& bad = entry.second;
    SCOPED_TRACE(entry.first);
    expectRejected(filter, "covariance", [&](JointUkf& f) { f.reset(kState, bad); });
    expectRejected(filter, "covariance", [&](JointUkf& f) { f.reset(kState, bad, kParameters); });
  }
  for (const Model::Param& theta : badParameters())
    expectRejected(filter, "parameters", [&](JointUkf& f) { f.reset(kState, P, theta); });
}

TEST(Reset, ModifiedJointUkfRefusesBadArguments) {
  ModifiedJointUkf filter = diverged(
      ModifiedJointUkf(Model(), Robot::initialState(), Robot::initialParameters(), bounded(Robot::modifiedJointUkf())));
  const auto P = someCovariance<4>(10);
  expectRejected(filter, "state", [&](ModifiedJointUkf& f) { f.reset(badState(), P); });
  expectRejected(filter, "state", [&](ModifiedJointUkf& f) { f.reset(badState(), P, kParameters); });
  for (const auto& entry : badCovariances<4>(P)) {
    const auto& bad = entry.second;
    SCOPED_TRACE(entry.first);
    expectRejected(filter, "covariance", [&](ModifiedJointUkf& f) { f.reset(kState, bad); });
    expectRejected(filter, "covariance", [&](ModifiedJointUkf& f) { f.reset(kState, bad, kParameters); });
  }
  for (const Model::Param& theta : badParameters())
    expectRejected(filter, "parameters", [&](ModifiedJointUkf& f) { f.reset(kState, P, theta); });
}

template <DualUkfOrdering Ordering>
void expectDualRefusesBadArguments() {
  auto settings = bounded(Robot::dualUkf());
  settings.ordering = Ordering;
  DualUkf filter = diverged(DualUkf(Model(), Robot::initialState(), Robot::initialParameters(), settings));
  const auto P = someCovariance<4>(11);
  const Eigen::Matrix2d Ptheta = someCovariance<2>(12) * 0.01;
  expectRejected(filter, "state", [&](DualUkf& f) { f.reset(badState(), P); });
  expectRejected(filter, "state", [&](DualUkf& f) { f.reset(badState(), P, kParameters); });
  expectRejected(filter, "state", [&](DualUkf& f) { f.reset(badState(), P, kParameters, Ptheta); });
  for (const auto& entry : badCovariances<4>(P)) {
    const auto& bad = entry.second;
    SCOPED_TRACE(entry.first);
    expectRejected(filter, "covariance", [&](DualUkf& f) { f.reset(kState, bad); });
    expectRejected(filter, "covariance", [&](DualUkf& f) { f.reset(kState, bad, kParameters); });
    expectRejected(filter, "covariance", [&](DualUkf& f) { f.reset(kState, bad, kParameters, Ptheta); });
  }
  for (const Model::Param& theta : badParameters()) {
    expectRejected(filter, "parameters", [&](DualUkf& f) { f.reset(kState, P, theta); });
    expectRejected(filter, "parameters", [&](DualUkf& f) { f.reset(kState, P, theta, Ptheta); });
  }
  for (const auto& entry : badCovariances<2>(Ptheta)) {
    const auto& bad = entry.second;
    SCOPED_TRACE(entry.first);
    expectRejected(filter, "parameterCovariance", [&](DualUkf& f) { f.reset(kState, P, kParameters, bad); });
  }
}

TEST(Reset, DualUkfRefusesBadArgumentsPriorParameters) {
  expectDualRefusesBadArguments<DualUkfOrdering::PriorParameters>();
}
TEST(Reset, DualUkfRefusesBadArgumentsUpdatedParameters) {
  expectDualRefusesBadArguments<DualUkfOrdering::UpdatedParameters>();
}

}  // namespace
