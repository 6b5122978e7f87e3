// A model without input (InputDim = 0, no input(t) member at all): every filter's timeUpdate(t, h) and
// propagateMean(t, h), and simulate, take no input argument (model.hpp). Each call is checked against
// the same call with the empty input passed explicitly, which the library has always accepted: the two
// must agree bit for bit, so the new overloads hold the empty input and do nothing else.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/ukf.hpp"

namespace {

// A damped pendulum with unknown damping c: θ̈ = −sin θ − c θ̇, x = (θ, θ̇), y = x. No `input` member:
// the point of the test.
struct Pendulum {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 1, MeasDim = 2, InputDim = 0;
  using State = Eigen::Matrix<double, StateDim, 1>;
  using Param = Eigen::Matrix<double, ParamDim, 1>;
  using Meas = Eigen::Matrix<double, MeasDim, 1>;
  using Input = Eigen::Matrix<double, InputDim, 1>;

  State derivative(double, const State& x, const Input&, const Param& c) const {
    return State(x(1), -std::sin(x(0)) - c(0) * x(1));
  }
  Meas measurement(const State& x, const Param&) const { return x; }
};

static_assert(!mjukf::hasInputSignal<Pendulum>);
static_assert(mjukf::needsNoInputArgument<Pendulum>);

using Rk4 = mjukf::Rk4<double>;
const Pendulum::State kStart(1.0, 0.0);
const Pendulum::Param kGuess = Pendulum::Param::Constant(0.1);

template <class Filter>
typename Filter::Settings settingsFor() {
  typename Filter::Settings s;
  s.measurementNoise = 1e-2 * Filter::Settings::MeasMatrix::Identity();
  s.initialCovariance.setIdentity();
  s.initialCovariance *= 0.1;
  s.processNoise.setIdentity();
  s.processNoise *= 1e-6;
  if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<Pendulum, Rk4>>) {
    s.scaling = -0.05;
    s.transformation << 0.2, 0.8;
    s.parameterSpread << 0.01;
  }
  if constexpr (std::is_same_v<Filter, mjukf::DualUkf<Pendulum, Rk4>>) {
    s.initialParameterCovariance << 0.1;
    s.parameterProcessNoise << 1e-6;
  }
  return s;
}

template <class Filter>
Filter makeFilter() {
  if constexpr (std::is_same_v<Filter, mjukf::Ukf<Pendulum, Rk4>>)
    return Filter(Pendulum(), kStart, Pendulum::Param::Constant(0.2), settingsFor<Filter>());
  else
    return Filter(Pendulum(), kStart, kGuess, settingsFor<Filter>());
}

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
  const Pendulum::State implicit = mjukf::simulate(Pendulum(), Rk4(), kStart, c, 0.0, 0.01, 500,
                                                    [](long, double, const Pendulum::State&) {});
  const Pendulum::State explicitEmpty = mjukf::simulate(Pendulum(), Rk4(), kStart, none, c, 0.0, 0.01, 500,
                                                         [](long, double, const Pendulum::State&) {});
  EXPECT_EQ(implicit, explicitEmpty);
  EXPECT_EQ(mjukf::stepModel(Pendulum(), Rk4(), 0.0, 0.01, kStart, c),
            mjukf::stepModel(Pendulum(), Rk4(), 0.0, 0.01, kStart, none, c));
  EXPECT_NE(implicit, kStart);  // it moved
}

}  // namespace
