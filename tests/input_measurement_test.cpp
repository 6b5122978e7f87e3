// A measurement that depends on the input, y = g(x, u, θ) (model.hpp, measurementTakesInput): every
// filter passes the input in force at the measurement time, and gives exactly the update of a model
// whose g(x, θ) reads that input from outside (the workaround it replaces). The model's own input(t) is
// read at the filter's time; a non-finite input is refused and leaves the filter as it was.

#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include <gtest/gtest.h>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"

namespace {

// A discrete-time RC circuit as a battery's: v₁ relaxes towards R₁ i, the charge z falls with i; the
// terminal voltage is ocv(z) − v₁ − R₀ i with R₀ = θ (the series resistance, seen only through u).
struct Circuit {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Matrix<double, StateDim, 1>;
  using Param = Eigen::Matrix<double, ParamDim, 1>;
  using Meas = Eigen::Matrix<double, MeasDim, 1>;
  using Input = Eigen::Matrix<double, InputDim, 1>;
  State transition(double, double dt, const State& x, const Input& u, const Param&) const {
    const double decay = std::exp(-dt / 20.0);
    return State(x(0) - dt * u(0) / 3600.0, decay * x(1) + (1 - decay) * 0.015 * u(0));
  }
  static double terminal(const State& x, double current, double r0) { return 3.4 + 0.7 * x(0) - x(1) - r0 * current; }
};

// y = g(x, u, θ), the input given by the caller.
struct HeldCircuit : Circuit {
  Meas measurement(const State& x, const Input& u, const Param& theta) const {
    return Meas(terminal(x, u(0), theta(0)));
  }
};

// The workaround: y = g(x, θ) reading the present current through a pointer.
struct PointerCircuit : Circuit {
  const double* current = nullptr;
  Meas measurement(const State& x, const Param& theta) const { return Meas(terminal(x, *current, theta(0))); }
};

// y = g(x, u, θ) with the model's own signal u(t).
struct SignalCircuit : HeldCircuit {
  static double current(double t) { return 2.0 + std::sin(0.3 * t); }
  Input input(double t) const { return Input(current(t)); }
};

static_assert(mjukf::measurementTakesInput<HeldCircuit> && mjukf::measurementTakesInput<SignalCircuit>);
static_assert(!mjukf::measurementTakesInput<PointerCircuit>);

template <template <class...> class FilterOf, class Model>
typename FilterOf<Model>::Settings settingsFor() {
  typename FilterOf<Model>::Settings s;
  using Filter = FilterOf<Model>;
  s.measurementNoise(0, 0) = 1e-4;
  s.processNoise.setIdentity();
  s.processNoise *= 1e-8;
  if constexpr (std::is_same_v<Filter, mjukf::JointUkf<Model>>) {
    s.initialCovariance.diagonal() << 1e-2, 1e-4, 1e-3;
  } else {
    s.initialCovariance.diagonal() << 1e-2, 1e-4;
  }
  if constexpr (std::is_same_v<Filter, mjukf::ModifiedJointUkf<Model>>) {
    s.scaling = -0.05;
    s.transformation << 1;
    s.parameterSpread << 0.001;
  }
  if constexpr (std::is_same_v<Filter, mjukf::DualUkf<Model>>) {
    s.initialParameterCovariance << 1e-3;
    s.parameterProcessNoise << 1e-8;
  }
  return s;
}

template <class A, class B>
bool sameBits(const A& a, const B& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(typename A::Scalar) * a.size()) == 0;
}

template <template <class...> class FilterOf>
struct Kind {
  template <class Model>
  using Of = FilterOf<Model>;
};

template <class K>
class InputMeasurement : public ::testing::Test {};
using Kinds =
    ::testing::Types<Kind<mjukf::Ukf>, Kind<mjukf::JointUkf>, Kind<mjukf::ModifiedJointUkf>, Kind<mjukf::DualUkf>>;
TYPED_TEST_SUITE(InputMeasurement, Kinds);

constexpr double kStep = 1.0;  // a battery sampled every second
const Circuit::State kStart(0.9, 0.0);
const Circuit::Param kGuess = Circuit::Param::Constant(0.05);
const Circuit::Param kTruth = Circuit::Param::Constant(0.08);

double currentAt(int k) { return k % 20 < 10 ? 3.0 : 0.5; }  // a pulsed discharge

// Measurements of the true circuit, each with the current in force when it is taken.
std::vector<double> measurements(int count) {
  std::vector<double> y;
  Circuit::State x = kStart;
  for (int k = 1; k <= count; ++k) {
    x = HeldCircuit().transition(0, kStep, x, Circuit::Input(currentAt(k - 1)), kTruth);
    y.push_back(Circuit::terminal(x, currentAt(k), kTruth(0)) + 1e-3 * std::sin(7.0 * k));
  }
  return y;
}

TYPED_TEST(InputMeasurement, GivenInputEqualsTheModelThatReadsItFromOutside) {
  using Held = typename TypeParam::template Of<HeldCircuit>;
  using Pointer = typename TypeParam::template Of<PointerCircuit>;
  double present = 0;
  PointerCircuit pointerModel;
  pointerModel.current = &present;
  Held held(HeldCircuit(), kStart, kGuess, settingsFor<TypeParam::template Of, HeldCircuit>());
  Pointer pointer(pointerModel, kStart, kGuess, settingsFor<TypeParam::template Of, PointerCircuit>());
  const std::vector<double> y = measurements(60);
  for (int k = 1; k <= 60; ++k) {
    const Circuit::Input before(currentAt(k - 1)), now(currentAt(k));
    ASSERT_TRUE(mjukf::taken(held.timeUpdate((k - 1) * kStep, kStep, before)));
    ASSERT_TRUE(mjukf::taken(pointer.timeUpdate((k - 1) * kStep, kStep, before)));
    present = now(0);
    const Circuit::Meas measured(y[std::size_t(k - 1)]);
    ASSERT_EQ(held.measurementUpdate(measured, now), pointer.measurementUpdate(measured));
    ASSERT_TRUE(sameBits(held.state(), pointer.state())) << "step " << k;
    ASSERT_TRUE(sameBits(held.parameters(), pointer.parameters())) << "step " << k;
    ASSERT_TRUE(sameBits(held.covariance(), pointer.covariance())) << "step " << k;
  }
  // The input reaches the update: the same measurement with the current of the step before moves
  // the estimate elsewhere.
  Held other = held;
  ASSERT_TRUE(mjukf::taken(held.timeUpdate(60 * kStep, kStep, Circuit::Input(0.5))));
  ASSERT_TRUE(mjukf::taken(other.timeUpdate(60 * kStep, kStep, Circuit::Input(0.5))));
  ASSERT_TRUE(mjukf::taken(held.measurementUpdate(Circuit::Meas(3.9), Circuit::Input(3.0))));
  ASSERT_TRUE(mjukf::taken(other.measurementUpdate(Circuit::Meas(3.9), Circuit::Input(0.5))));
  EXPECT_FALSE(sameBits(held.state(), other.state()));
}

TYPED_TEST(InputMeasurement, OwnSignalIsReadAtTheFiltersTime) {
  using Signal = typename TypeParam::template Of<SignalCircuit>;
  const auto settings = settingsFor<TypeParam::template Of, SignalCircuit>();
  Signal own(SignalCircuit(), kStart, kGuess, settings);
  Signal given(SignalCircuit(), kStart, kGuess, settings);
  EXPECT_EQ(own.time(), 0.0);
  const std::vector<double> y = measurements(30);
  for (int k = 1; k <= 30; ++k) {
    const int steps = 1 + k % 3;  // the time is where the last update ended, t + steps h
    const double t = (k - 1) * 3 * kStep;
    ASSERT_TRUE(mjukf::taken(own.timeUpdate(t, kStep, steps)));
    ASSERT_TRUE(mjukf::taken(given.timeUpdate(t, kStep, steps)));
    EXPECT_EQ(own.time(), t + steps * kStep);
    const Circuit::Meas measured(y[std::size_t(k - 1)]);
    ASSERT_EQ(own.measurementUpdate(measured),
              given.measurementUpdate(measured, Circuit::Input(SignalCircuit::current(t + steps * kStep))));
    ASSERT_TRUE(sameBits(own.state(), given.state())) << "step " << k;
    ASSERT_TRUE(sameBits(own.covariance(), given.covariance())) << "step " << k;
  }
  // An open-loop propagation moves the time too.
  const double before = own.time();
  ASSERT_EQ(own.propagateMean(before, kStep, 2), mjukf::Status::Ok);
  EXPECT_EQ(own.time(), before + 2 * kStep);
}

TYPED_TEST(InputMeasurement, NonFiniteInputIsRefusedAndChangesNothing) {
  using Held = typename TypeParam::template Of<HeldCircuit>;
  Held filter(HeldCircuit(), kStart, kGuess, settingsFor<TypeParam::template Of, HeldCircuit>());
  ASSERT_TRUE(mjukf::taken(filter.timeUpdate(0, kStep, Circuit::Input(1.0))));
  const Held before = filter;
  for (const double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(filter.measurementUpdate(Circuit::Meas(3.9), Circuit::Input(bad)), mjukf::Status::NonFiniteInput);
    mjukf::MeasurementMask<1> present;
    present(0) = true;
    EXPECT_EQ(filter.measurementUpdate(Circuit::Meas(3.9), Circuit::Input(bad), present),
              mjukf::Status::NonFiniteInput);
    EXPECT_TRUE(sameBits(filter.state(), before.state()));
    EXPECT_TRUE(sameBits(filter.covariance(), before.covariance()));
    EXPECT_TRUE(sameBits(filter.parameters(), before.parameters()));
    EXPECT_TRUE(filter.hasPropagatedPoints());
  }
}

}  // namespace
