// Several passes over one record (docs/offline-passes.md): startPass(t₀, x, P) sends a filter back to
// the record's start with a new state and everything it learnt about θ. A second pass must resume
// exactly where the first ended: a filter that is handed the same parameter knowledge (another filter,
// with another history, for MJUKF; a fresh one built from θ̂ and its covariance for JUKF and the dual
// filter) runs the second pass the same, bit for bit, and the knowledge right after startPass is the
// first pass's last, field by field. reset() is unchanged (tests/reset_test.cpp).

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"
#include "paper/experiments.hpp"
#include "robustness_support.hpp"

namespace {

using mjukf::testing::bitwiseSame;
using mjukf::testing::sameFilter;
using Tank = mjukf::paper::CoupledTankExperiment<double>;
using Model = Tank::Model;
using Ukf = mjukf::Ukf<Model>;
using JointUkf = mjukf::JointUkf<Model>;
using ModifiedJointUkf = mjukf::ModifiedJointUkf<Model>;
using DualUkf = mjukf::DualUkf<Model>;

// The record: the tank from rest at h = 5 ms for 10 s, both levels with noise of σ = 3e-4 cm (R = 1e-7,
// the settings' own), rows 0 … kRows.
constexpr double kStep = 0.005;
constexpr long kRows = 2000;
const std::vector<Model::Meas>& record() {
  static const std::vector<Model::Meas> rows = [] {
    mjukf::testing::TankMeasurements<Model> source(kStep, std::sqrt(1e-7), 20);
    std::vector<Model::Meas> y;
    for (long k = 0; k <= kRows; ++k) y.push_back(source.next());
    return y;
  }();
  return rows;
}

// One pass: a time update from t_k and the measurement of row k + 1, for k in [from, to); `each` after
// every row.
template <class Filter, class Each>
void pass(Filter& f, long from, long to, Each&& each) {
  for (long k = from; k < to; ++k) {
    ASSERT_TRUE(mjukf::taken(f.timeUpdate(double(k) * kStep, kStep))) << "row " << k;
    ASSERT_TRUE(mjukf::taken(f.measurementUpdate(record()[static_cast<std::size_t>(k + 1)]))) << "row " << k;
    each(k);
  }
}
template <class Filter>
void pass(Filter& f) {
  pass(f, 0, kRows, [](long) {});
}

// `a` and `b` run the whole record the same, bit for bit, after every row, and are the same right away.
template <class Filter>
void expectSameSecondPass(Filter& a, Filter& b) {
  ASSERT_TRUE(sameFilter(a, b)) << "right after startPass";
  ASSERT_EQ(a.time(), b.time());
  pass(a, 0, kRows, [&](long k) {
    pass(b, k, k + 1, [](long) {});
    ASSERT_TRUE(sameFilter(a, b)) << "row " << k;
  });
}

// The second pass's start: a state and covariance other than the first pass's.
const Model::State kStart(0.2, 0.1);
Eigen::Matrix2d startCovariance() { return Eigen::Matrix2d(Eigen::Vector2d(0.3, 0.2).asDiagonal()); }

template <class Settings>
Settings automatic(Settings s) {
  s.automaticTransformation = true;
  s.adaptiveScaling = true;
  return s;
}

// ---------------------------------------------------------------------------------------------------
// MJUKF with both automatic modes: the knowledge carries θ̂, the θᵢ and the information.

TEST(MultiPass, ModifiedJointUkfResumesWhereTheFirstPassEnded) {
  const auto settings = automatic(Tank::modifiedJointUkf());
  ModifiedJointUkf first(Model(), Tank::initialState(), Tank::initialParameters(), settings);
  pass(first);
  const ModifiedJointUkf ended = first;  // as pass 1 left it
  EXPECT_GT(std::abs(ended.parameters()(0) - Tank::initialParameters()(0)), 1.0) << "θ̂ did not move";

  first.startPass(0.0, kStart, startCovariance());
  // The knowledge is the first pass's last, field by field; the state part is new.
  EXPECT_TRUE(bitwiseSame(first.parameters(), ended.parameters()));
  EXPECT_TRUE(bitwiseSame(first.parameterPoints(), ended.parameterPoints()));
  EXPECT_TRUE(bitwiseSame(first.sensitivity().information(), ended.sensitivity().information()));
  EXPECT_TRUE(bitwiseSame(first.sensitivity().measurementSensitivity(), ended.sensitivity().measurementSensitivity()));
  EXPECT_TRUE(bitwiseSame(first.transformation(), ended.transformation()));
  EXPECT_TRUE(bitwiseSame(first.scalings(), ended.scalings()));
  EXPECT_TRUE(first.sensitivity().stateSensitivity().isZero(0.0)) << "the new state does not depend on θ̂";
  EXPECT_TRUE(bitwiseSame(first.state(), kStart));
  EXPECT_TRUE(bitwiseSame(first.covariance(), startCovariance()));
  EXPECT_FALSE(first.hasPropagatedPoints());
  EXPECT_EQ(first.time(), 0.0);
  EXPECT_EQ(ended.time(), double(kRows - 1) * kStep + kStep);  // where the last time update ended

  // Another filter, with another history (its own first pass from another guess), handed the same
  // knowledge, runs the second pass the same: nothing else of the first filter carries over.
  ModifiedJointUkf other(Model(), Model::State(1, 1), Model::Param::Constant(9.0), settings);
  pass(other, 0, kRows / 2, [](long) {});
  other.startPass(0.0, kStart, startCovariance(), ended.parameterKnowledge());
  expectSameSecondPass(first, other);
}

// Without the automatic modes there is no information: the knowledge is θ̂ and the θᵢ.
TEST(MultiPass, ModifiedJointUkfOfThePaperCarriesItsParameterPoints) {
  const auto settings = Tank::modifiedJointUkf();
  ModifiedJointUkf first(Model(), Tank::initialState(), Tank::initialParameters(), settings);
  pass(first);
  const ModifiedJointUkf ended = first;
  first.startPass(0.0, kStart, startCovariance());
  EXPECT_TRUE(bitwiseSame(first.parameterPoints(), ended.parameterPoints()));
  ModifiedJointUkf other(Model(), Tank::initialState(), Tank::initialParameters(), settings);
  other.startPass(0.0, kStart, startCovariance(), ended.parameterKnowledge());
  expectSameSecondPass(first, other);
}

// What a second pass is for: it starts from the first's θ̂ instead of the first guess (k_flow = 2, the
// truth 6), and ends nearer the truth than the first did.
TEST(MultiPass, ModifiedJointUkfSecondPassStartsWhereTheFirstEnded) {
  ModifiedJointUkf filter(Model(), Tank::initialState(), Tank::initialParameters(),
                          automatic(Tank::modifiedJointUkf()));
  pass(filter);
  const double afterFirst = std::abs(filter.parameters()(0) - 6.0);
  filter.startPass(0.0, Tank::initialState(), Tank::modifiedJointUkf().initialCovariance);
  pass(filter);
  const double afterSecond = std::abs(filter.parameters()(0) - 6.0);
  std::printf("|k_flow - 6| after pass 1: %.3g, after pass 2: %.3g\n", afterFirst, afterSecond);
  EXPECT_LT(afterFirst, 0.05);         // measured: 6.7e-3
  EXPECT_LT(afterSecond, afterFirst);  // measured: 7.4e-4
}

// ---------------------------------------------------------------------------------------------------
// JUKF: θ̂ and the θ block of the covariance carry over, the cross terms are zeroed. A fresh filter
// from [x; θ̂] and diag(P, P_θθ) runs the second pass the same.

TEST(MultiPass, JointUkfResumesWhereTheFirstPassEnded) {
  const auto settings = Tank::jointUkf();
  JointUkf first(Model(), Tank::initialState(), Tank::initialParameters(), settings);
  pass(first);
  const JointUkf ended = first;
  EXPECT_GT(std::abs(ended.parameters()(0) - Tank::initialParameters()(0)), 1.0) << "θ̂ did not move";
  EXPECT_NE(ended.covariance()(0, 2), 0.0) << "no cross terms to zero";

  first.startPass(0.0, kStart, startCovariance());
  EXPECT_TRUE(bitwiseSame(first.parameters(), ended.parameters()));
  const JointUkf::AugmentedMatrix& P = first.covariance();
  EXPECT_EQ(P(2, 2), ended.covariance()(2, 2)) << "P_θθ carried bit for bit";
  EXPECT_TRUE(P.topRightCorner(2, 1).isZero(0.0));
  EXPECT_TRUE(P.bottomLeftCorner(1, 2).isZero(0.0));
  EXPECT_TRUE(bitwiseSame(Eigen::Matrix2d(P.topLeftCorner<2, 2>()), startCovariance()));
  EXPECT_EQ(first.time(), 0.0);

  auto freshSettings = settings;
  freshSettings.initialCovariance = ended.passCovariance(startCovariance());
  JointUkf fresh(Model(), kStart, ended.parameters(), freshSettings);
  expectSameSecondPass(first, fresh);
}

// ---------------------------------------------------------------------------------------------------
// The dual filter keeps its parameter filter (θ̂, P^θ); the UKF its fixed θ. Both equal a fresh filter.

TEST(MultiPass, DualUkfResumesWhereTheFirstPassEnded) {
  auto settings = Tank::dualUkf();
  settings.measurementNoise.diagonal().setConstant(1e-7);
  DualUkf first(Model(), Tank::initialState(), Tank::initialParameters(), settings);
  pass(first);
  const DualUkf ended = first;
  first.startPass(0.0, kStart, startCovariance());
  EXPECT_TRUE(bitwiseSame(first.parameters(), ended.parameters()));
  EXPECT_TRUE(bitwiseSame(first.parameterCovariance(), ended.parameterCovariance()));
  EXPECT_TRUE(first.sensitivity().isZero(0.0));
  EXPECT_EQ(first.time(), 0.0);

  auto freshSettings = settings;
  freshSettings.initialCovariance = startCovariance();
  freshSettings.initialParameterCovariance = ended.parameterCovariance();
  DualUkf fresh(Model(), kStart, ended.parameters(), freshSettings);
  expectSameSecondPass(first, fresh);
}

TEST(MultiPass, UkfStartsAgainAtTheRecordsStart) {
  const auto settings = Tank::ukf();
  Ukf first(Model(), Tank::initialState(), Model::trueParameters(), settings);
  pass(first);
  first.startPass(0.0, kStart, startCovariance());
  EXPECT_EQ(first.time(), 0.0);
  auto freshSettings = settings;
  freshSettings.initialCovariance = startCovariance();
  Ukf fresh(Model(), kStart, Model::trueParameters(), freshSettings);
  expectSameSecondPass(first, fresh);
}

// ---------------------------------------------------------------------------------------------------
// The time, and what startPass refuses.

// startPass sets time() to the record's start, whatever it is; reset() leaves the time where it was.
TEST(MultiPass, StartPassSetsTheTimeResetKeepsIt) {
  ModifiedJointUkf filter(Model(), Tank::initialState(), Tank::initialParameters(), Tank::modifiedJointUkf());
  pass(filter, 0, 10, [](long) {});
  ModifiedJointUkf reset = filter;
  reset.reset(kStart, startCovariance());
  EXPECT_EQ(reset.time(), 9 * kStep + kStep);  // where the last time update ended
  filter.startPass(-3.5, kStart, startCovariance());
  EXPECT_EQ(filter.time(), -3.5);
}

// A non-finite start time or state, or a covariance that is not positive definite, is refused naming
// the argument, and the filter is unchanged.
template <class Filter, class Call>
void expectRefused(Filter& filter, const std::string& argument, Call&& call) {
  const Filter before = filter;
  try {
    call(filter);
    ADD_FAILURE() << "accepted a bad '" << argument << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'" + argument + "'"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(sameFilter(filter, before)) << argument;
  EXPECT_EQ(filter.time(), before.time()) << argument;
}

TEST(MultiPass, StartPassRefusesBadArguments) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  const Eigen::Matrix2d indefinite = (Eigen::Matrix2d() << 1, 2, 2, 1).finished();
  const Model::State badState(nan, 0);
  {
    ModifiedJointUkf filter(Model(), Tank::initialState(), Tank::initialParameters(), Tank::modifiedJointUkf());
    pass(filter, 0, 10, [](long) {});
    expectRefused(filter, "startTime", [&](auto& f) { f.startPass(nan, kStart, startCovariance()); });
    expectRefused(filter, "state", [&](auto& f) { f.startPass(0.0, badState, startCovariance()); });
    expectRefused(filter, "covariance", [&](auto& f) { f.startPass(0.0, kStart, indefinite); });
    auto knowledge = filter.parameterKnowledge();
    knowledge.parameters(0) = nan;
    expectRefused(filter, "parameters", [&](auto& f) { f.startPass(0.0, kStart, startCovariance(), knowledge); });
  }
  {
    JointUkf filter(Model(), Tank::initialState(), Tank::initialParameters(), Tank::jointUkf());
    pass(filter, 0, 10, [](long) {});
    expectRefused(filter, "startTime", [&](auto& f) { f.startPass(nan, kStart, startCovariance()); });
    expectRefused(filter, "state", [&](auto& f) { f.startPass(0.0, badState, startCovariance()); });
    expectRefused(filter, "covariance", [&](auto& f) { f.startPass(0.0, kStart, indefinite); });
  }
  {
    DualUkf filter(Model(), Tank::initialState(), Tank::initialParameters(), Tank::dualUkf());
    pass(filter, 0, 10, [](long) {});
    expectRefused(filter, "startTime", [&](auto& f) { f.startPass(nan, kStart, startCovariance()); });
    expectRefused(filter, "covariance", [&](auto& f) { f.startPass(0.0, kStart, indefinite); });
  }
  {
    Ukf filter(Model(), Tank::initialState(), Model::trueParameters(), Tank::ukf());
    expectRefused(filter, "startTime", [&](auto& f) { f.startPass(nan, kStart, startCovariance()); });
    expectRefused(filter, "state", [&](auto& f) { f.startPass(0.0, badState, startCovariance()); });
  }
}

}  // namespace
