// A model without input (InputDim = 0, no input(t) member at all): every filter's timeUpdate(t, h) and
// propagateMean(t, h), and simulate, take no input argument (model.hpp). Each call is checked against
// the same call with the empty input passed explicitly, which the library has always accepted: the two
// must agree bit for bit, so the new overloads hold the empty input and do nothing else.

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "mjukf/simulation.hpp"
#include "no_input_model.hpp"

namespace {

using namespace mjukf::testing::no_input;

static_assert(!mjukf::hasInputSignal<Pendulum>);
static_assert(mjukf::needsNoInputArgument<Pendulum>);

template <class Filter>
class NoInputModel : public ::testing::Test {};
using Filters = ::testing::Types<mjukf::Ukf<Pendulum, Rk4>, mjukf::JointUkf<Pendulum, Rk4>,
                                 mjukf::ModifiedJointUkf<Pendulum, Rk4>, mjukf::DualUkf<Pendulum, Rk4>>;
TYPED_TEST_SUITE(NoInputModel, Filters);

// The paper's schedule (a time update every 5th step, the mean alone in between) over 20 s of a
// simulated true run with c = 0.2: the calls without input and those with the empty input give the same
// estimate, bit for bit, and every call returns Ok.
TYPED_TEST(NoInputModel, FilterCallsNeedNoInputAndEqualTheEmptyInput) {
  using Filter = TypeParam;
  const double h = 0.01;
  const long steps = 2000;
  std::vector<Pendulum::State> truth;
  mjukf::simulate(Pendulum(), Rk4(), kStart, Pendulum::Param::Constant(0.2), 0.0, h, steps,
                  [&](long, double, const Pendulum::State& x) { truth.push_back(x); });

  Filter implicit = makeFilter<Filter>();
  Filter explicitEmpty = makeFilter<Filter>();
  const Pendulum::Input none;
  double farthest = 0;  // from the start, over the run
  for (long k = 0; k < steps; ++k) {
    const double t = double(k) * h;
    if ((k + 1) % 5 == 0) {
      ASSERT_EQ(implicit.timeUpdate(t, h), mjukf::Status::Ok) << "k = " << k;
      ASSERT_EQ(explicitEmpty.timeUpdate(t, h, none), mjukf::Status::Ok) << "k = " << k;
      ASSERT_EQ(implicit.measurementUpdate(truth[k + 1]), mjukf::Status::Ok) << "k = " << k;
      ASSERT_EQ(explicitEmpty.measurementUpdate(truth[k + 1]), mjukf::Status::Ok) << "k = " << k;
    } else {
      ASSERT_EQ(implicit.propagateMean(t, h), mjukf::Status::Ok) << "k = " << k;
      ASSERT_EQ(explicitEmpty.propagateMean(t, h, none), mjukf::Status::Ok) << "k = " << k;
    }
    ASSERT_EQ(implicit.state(), explicitEmpty.state()) << "k = " << k;
    ASSERT_EQ(implicit.parameters(), explicitEmpty.parameters()) << "k = " << k;
    farthest = std::max(farthest, (implicit.state() - kStart).norm());
  }
  // The runs did something: the estimate followed the swing away from its start at (1, 0); half a
  // period later (about 3.3 s) the true angle is near −0.7 (damped by e^(−0.2 · 3.3 / 2)), 1.7 away.
  EXPECT_GT(farthest, 1.5);
}

// simulate and stepModel without an input argument: the empty input held over every step.
TEST(NoInputModel, SimulateNeedsNoInput) {
  const Pendulum::Param c = Pendulum::Param::Constant(0.2);
  const Pendulum::Input none;
  const Pendulum::State implicit =
      mjukf::simulate(Pendulum(), Rk4(), kStart, c, 0.0, 0.01, 500, [](long, double, const Pendulum::State&) {});
  const Pendulum::State explicitEmpty =
      mjukf::simulate(Pendulum(), Rk4(), kStart, none, c, 0.0, 0.01, 500, [](long, double, const Pendulum::State&) {});
  EXPECT_EQ(implicit, explicitEmpty);
  EXPECT_EQ(mjukf::stepModel(Pendulum(), Rk4(), 0.0, 0.01, kStart, c),
            mjukf::stepModel(Pendulum(), Rk4(), 0.0, 0.01, kStart, none, c));
  EXPECT_NE(implicit, kStart);  // it moved
}

}  // namespace
