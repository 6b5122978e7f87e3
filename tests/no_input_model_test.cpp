// A model without input (InputDim = 0, no input(t) member at all): every filter's timeUpdate(t, h) and
// propagateMean(t, h), and simulate, take no input argument (model.hpp). Each call is checked against
// the same call with the empty input passed explicitly, which the library has always accepted: the two
// must agree bit for bit, so the new overloads hold the empty input and do nothing else.

#include <gtest/gtest.h>

#include <algorithm>
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

// The Van der Pol oscillator with unknown damping μ: ẋ₁ = x₂, ẋ₂ = μ (1 − x₁²) x₂ − x₁, y = x.
// No `input` member: the point of the test.
struct VanDerPol {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 1, MeasDim = 2, InputDim = 0;
  using State = Eigen::Matrix<double, StateDim, 1>;
  using Param = Eigen::Matrix<double, ParamDim, 1>;
  using Meas = Eigen::Matrix<double, MeasDim, 1>;
  using Input = Eigen::Matrix<double, InputDim, 1>;

  State derivative(double, const State& x, const Input&, const Param& mu) const {
    return State(x(1), mu(0) * (1 - x(0) * x(0)) * x(1) - x(0));
  }
  Meas measurement(const State& x, const Param&) const { return x; }
};

static_assert(!mjukf::hasInputSignal<VanDerPol>);
static_assert(mjukf::needsNoInputArgument<VanDerPol>);

using Rk4 = mjukf::Rk4<double>;
const VanDerPol::State kStart(2.0, 0.0);
const VanDerPol::Param kGuess = VanDerPol::Param::Constant(0.5);

template <class Filter>
typename Filter::Settings settingsFor() {
  typename Filter::Settings s;
  s.measurementNoise = 1e-2 * Filter::Settings::MeasMatrix::Identity();
  s.initialCovariance.setIdentity();
  s.initialCovariance *= 0.1;
  s.processNoise.setIdentity();
  s.processNoise *= 1e-6;
  if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<VanDerPol, Rk4>>) {
    s.scaling = -0.05;
    s.transformation << 0.2, 0.8;
    s.parameterSpread << 0.01;
  }
  if constexpr (std::is_same_v<Filter, mjukf::DualUkf<VanDerPol, Rk4>>) {
    s.initialParameterCovariance << 0.1;
    s.parameterProcessNoise << 1e-6;
  }
  return s;
}

template <class Filter>
Filter makeFilter() {
  if constexpr (std::is_same_v<Filter, mjukf::Ukf<VanDerPol, Rk4>>)
    return Filter(VanDerPol(), kStart, VanDerPol::Param::Constant(1.0), settingsFor<Filter>());
  else
    return Filter(VanDerPol(), kStart, kGuess, settingsFor<Filter>());
}

template <class Filter>
class NoInputModel : public ::testing::Test {};
using Filters = ::testing::Types<mjukf::Ukf<VanDerPol, Rk4>, mjukf::JointUkf<VanDerPol, Rk4>,
                                 mjukf::ModifiedJointUkf<VanDerPol, Rk4>, mjukf::DualUkf<VanDerPol, Rk4>>;
TYPED_TEST_SUITE(NoInputModel, Filters);

// The paper's schedule (a time update every 5th step, the mean alone in between) over 20 s of a
// simulated true run with μ = 1: the calls without input and those with the empty input give the same
// estimate, bit for bit, and every call returns Ok.
TYPED_TEST(NoInputModel, FilterCallsNeedNoInputAndEqualTheEmptyInput) {
  using Filter = TypeParam;
  const double h = 0.01;
  const long steps = 2000;
  std::vector<VanDerPol::State> truth;
  mjukf::simulate(VanDerPol(), Rk4(), kStart, VanDerPol::Param::Constant(1.0), 0.0, h, steps,
                  [&](long, double, const VanDerPol::State& x) { truth.push_back(x); });

  Filter implicit = makeFilter<Filter>();
  Filter explicitEmpty = makeFilter<Filter>();
  const VanDerPol::Input none;
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
  // The runs did something: the estimate followed the oscillation (amplitude 2 about 0) away from its
  // start at (2, 0); half a period later the true state is near (−2, 0), 4 away.
  EXPECT_GT(farthest, 2.0);
}

// simulate and stepModel without an input argument: the empty input held over every step.
TEST(NoInputModel, SimulateNeedsNoInput) {
  const VanDerPol::Param mu = VanDerPol::Param::Constant(1.0);
  const VanDerPol::Input none;
  const VanDerPol::State implicit = mjukf::simulate(VanDerPol(), Rk4(), kStart, mu, 0.0, 0.01, 500,
                                                    [](long, double, const VanDerPol::State&) {});
  const VanDerPol::State explicitEmpty = mjukf::simulate(VanDerPol(), Rk4(), kStart, none, mu, 0.0, 0.01, 500,
                                                         [](long, double, const VanDerPol::State&) {});
  EXPECT_EQ(implicit, explicitEmpty);
  EXPECT_EQ(mjukf::stepModel(VanDerPol(), Rk4(), 0.0, 0.01, kStart, mu),
            mjukf::stepModel(VanDerPol(), Rk4(), 0.0, 0.01, kStart, none, mu));
  EXPECT_NE(implicit, kStart);  // it moved
}

}  // namespace
