// Discrete-time models (model.hpp): a model with `transition` instead of `derivative` is stepped, not
// integrated. The Euler-discretised robot as a discrete model must be, bit for bit, the continuous
// robot under an explicit-Euler stepper: both compute x + h f(t, x, u(t), θ) with the same operations
// in the same order, so any difference, even in the last bit, means the filters do not treat the two
// kinds of model alike (another input time, another step count, another order of steps).

#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "common/csv.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/model.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/ukf.hpp"
#include "paper/experiments.hpp"
#include "paper/schedule.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace {

using mjukf::DualUkfOrdering;
using mjukf::Status;
using mjukf::testing::bitwiseSame;
using mjukf::testing::DiscreteRobot;
using mjukf::testing::Euler;
using mjukf::testing::IsDual;
using mjukf::testing::IsModifiedJoint;
using mjukf::testing::sameFilter;

// ---------------------------------------------------------------------------------------------------
// Compile time: what is discrete, and which integrator a filter takes when none is named.

using Discrete = DiscreteRobot<double>;
using Continuous = mjukf::models::FlexibleJoint<double>;
static_assert(mjukf::isDiscreteTime<Discrete>);
static_assert(mjukf::isDiscreteTime<DiscreteRobot<float>>);
static_assert(!mjukf::isDiscreteTime<Continuous>);
static_assert(mjukf::checkModel<Discrete, 1>());
static_assert(std::is_same_v<mjukf::DefaultIntegrator<Discrete>, mjukf::NoIntegrator<double>>);
static_assert(std::is_same_v<mjukf::DefaultIntegrator<DiscreteRobot<float>>, mjukf::NoIntegrator<float>>);
static_assert(std::is_same_v<mjukf::DefaultIntegrator<Continuous>, mjukf::ITrBdf2<double>>);
static_assert(std::is_same_v<mjukf::Ukf<Discrete>::Integrator, mjukf::NoIntegrator<double>>);
static_assert(std::is_same_v<mjukf::JointUkf<Discrete>::Integrator, mjukf::NoIntegrator<double>>);
static_assert(std::is_same_v<mjukf::ModifiedJointUkf<Discrete>::Integrator, mjukf::NoIntegrator<double>>);
static_assert(std::is_same_v<mjukf::DualUkf<Discrete>::Integrator, mjukf::NoIntegrator<double>>);
static_assert(std::is_same_v<mjukf::DualUkf<DiscreteRobot<float>>::Integrator, mjukf::NoIntegrator<float>>);
static_assert(std::is_same_v<mjukf::Ukf<Continuous>::Integrator, mjukf::ITrBdf2<double>>);
static_assert(std::is_same_v<mjukf::DualUkf<Continuous>::Integrator, mjukf::ITrBdf2<double>>);

// ---------------------------------------------------------------------------------------------------
// The two filters of one kind: over the continuous robot with Euler, and over the discrete robot.

using Robot = mjukf::paper::FlexibleJointExperiment<double>;
using ContinuousIntegrator = Euler<double>;
using DiscreteIntegrator = mjukf::NoIntegrator<double>;

// The robot's preset for filter template F, as the settings of F over `Model`, in the given ordering
// when F is the dual filter.
template <template <class...> class F, class Model>
auto robotSettings(DualUkfOrdering ordering) {
  auto s = mjukf::testing::presetSettings<F, Robot, Model>();
  if constexpr (IsDual<F<Model, mjukf::DefaultIntegrator<Model>>>::value) s.ordering = ordering;
  return s;
}

template <template <class...> class F>
struct Pair {
  using ContinuousFilter = F<Continuous, ContinuousIntegrator>;
  using DiscreteFilter = F<Discrete, DiscreteIntegrator>;
  static ContinuousFilter continuous(DualUkfOrdering ordering) {
    auto s = robotSettings<F, Continuous>(ordering);
    return ContinuousFilter(Continuous(), Robot::initialState(), firstParameters(), s);
  }
  static DiscreteFilter discrete(DualUkfOrdering ordering) {
    auto s = robotSettings<F, Discrete>(ordering);
    return DiscreteFilter(Discrete(), Robot::initialState(), firstParameters(), s);
  }
  // The UKF is given the truth, the others start from the first guess.
  static Robot::Param firstParameters() {
    return std::is_same_v<ContinuousFilter, mjukf::Ukf<Continuous, ContinuousIntegrator>> ? Continuous::trueParameters()
                                                                                          : Robot::initialParameters();
  }
};

std::vector<Robot::Model::Meas> referenceMeasurements() {
  const auto table = mjukf::examples::readCsv(std::string(MJUKF_DATA_DIR) + "/flexible_joint_reference.csv");
  std::vector<Robot::Model::Meas> rows(table.rows());
  for (int c = 0; c < 4; ++c) {
    const auto& column = table.column("y" + std::to_string(c + 1));
    for (std::size_t k = 0; k < rows.size(); ++k) rows[k](c) = column[k];
  }
  return rows;
}

// The values a filter shows at one row of a schedule, flattened: state, covariance, parameters.
template <class Filter>
void appendRow(std::vector<double>& out, const Filter& f) {
  const auto append = [&out](const auto& m) {
    for (Eigen::Index i = 0; i < m.size(); ++i) out.push_back(m.data()[i]);
  };
  append(f.state());
  append(f.covariance());
  append(f.parameters());
  if constexpr (IsDual<Filter>::value) append(f.parameterCovariance());
  if constexpr (IsModifiedJoint<Filter>::value) append(f.parameterPoints());
}

// The paper's schedule (paper::runSchedule: a time and a measurement update every 5th step, the mean
// open loop otherwise) over the whole robot reference file: every row bit for bit the same.
template <template <class...> class F>
void expectPaperScheduleBitForBit(DualUkfOrdering ordering = DualUkfOrdering::PriorParameters) {
  static const std::vector<Robot::Model::Meas> y = referenceMeasurements();
  auto continuous = Pair<F>::continuous(ordering);
  auto discrete = Pair<F>::discrete(ordering);
  std::vector<double> rowsContinuous, rowsDiscrete;
  const auto measurementAt = [&](long k) -> const Robot::Model::Meas& { return y[static_cast<std::size_t>(k)]; };
  const auto c =
      mjukf::paper::runSchedule(continuous, static_cast<long>(y.size()), Robot::stepSize, Robot::measurementEvery,
                                measurementAt, [&](long, const auto& f) { appendRow(rowsContinuous, f); });
  const auto d =
      mjukf::paper::runSchedule(discrete, static_cast<long>(y.size()), Robot::stepSize, Robot::measurementEvery,
                                measurementAt, [&](long, const auto& f) { appendRow(rowsDiscrete, f); });
  ASSERT_EQ(c.status, Status::Ok) << "row " << c.row;
  ASSERT_EQ(d.status, Status::Ok) << "row " << d.row;
  ASSERT_EQ(rowsContinuous.size(), rowsDiscrete.size());
  const std::size_t perRow = rowsContinuous.size() / y.size();
  for (std::size_t i = 0; i < rowsContinuous.size(); ++i)
    ASSERT_TRUE(std::memcmp(&rowsContinuous[i], &rowsDiscrete[i], sizeof(double)) == 0)
        << "row " << i / perRow << ", value " << i % perRow << ": " << rowsContinuous[i] << " vs " << rowsDiscrete[i];
  EXPECT_TRUE(sameFilter(continuous, discrete));
  // The filter did something: the parameter estimators moved their parameters.
  if constexpr (!std::is_same_v<F<Continuous, int>, mjukf::Ukf<Continuous, int>>) {
    EXPECT_GT((discrete.parameters() - Robot::initialParameters()).cwiseAbs().maxCoeff(), 1e-3);
  }
}

TEST(DiscreteModel, UkfEqualsContinuousEulerOnThePaperSchedule) { expectPaperScheduleBitForBit<mjukf::Ukf>(); }
TEST(DiscreteModel, JointUkfEqualsContinuousEulerOnThePaperSchedule) {
  expectPaperScheduleBitForBit<mjukf::JointUkf>();
}
TEST(DiscreteModel, ModifiedJointUkfEqualsContinuousEulerOnThePaperSchedule) {
  expectPaperScheduleBitForBit<mjukf::ModifiedJointUkf>();
}
TEST(DiscreteModel, DualUkfEqualsContinuousEulerOnThePaperSchedule) {
  expectPaperScheduleBitForBit<mjukf::DualUkf>(DualUkfOrdering::PriorParameters);
  expectPaperScheduleBitForBit<mjukf::DualUkf>(DualUkfOrdering::UpdatedParameters);
}

// Every other kind of call: time updates over 3 steps with the input signal and with a held input,
// open-loop propagation over 2 steps with both, a measurement update without a time update before
// it, and masked updates; compared after every call.
template <template <class...> class F>
void expectEveryCallBitForBit(DualUkfOrdering ordering = DualUkfOrdering::PriorParameters) {
  static const std::vector<Robot::Model::Meas> y = referenceMeasurements();
  auto continuous = Pair<F>::continuous(ordering);
  auto discrete = Pair<F>::discrete(ordering);
  const double h = Robot::stepSize;
  const mjukf::MeasurementMask<4> present(true, false, true, true);
  long row = 0;
  for (int k = 0; k < 600; ++k) {
    const double t = double(row) * h;
    const Robot::Model::Input u(2.5 * std::cos(0.01 * k));  // a held input other than u(t)
    const Robot::Model::Meas& measured = y[static_cast<std::size_t>(row + 3)];
    Status sc, sd;
    switch (k % 6) {
      case 0:
        sc = continuous.timeUpdate(t, h, u, 3);
        sd = discrete.timeUpdate(t, h, u, 3);
        row += 3;
        break;
      case 1:
        sc = continuous.timeUpdate(t, h, 3);
        sd = discrete.timeUpdate(t, h, 3);
        row += 3;
        break;
      case 2:
        sc = continuous.propagateMean(t, h, u, 2);
        sd = discrete.propagateMean(t, h, u, 2);
        row += 2;
        break;
      case 3:
        sc = continuous.propagateMean(t, h, 2);
        sd = discrete.propagateMean(t, h, 2);
        row += 2;
        break;
      case 4:
        sc = continuous.timeUpdate(t, h, u);
        sd = discrete.timeUpdate(t, h, u);
        row += 1;
        break;
      default:
        sc = continuous.timeUpdate(t, h);
        sd = discrete.timeUpdate(t, h);
        row += 1;
        break;
    }
    ASSERT_EQ(sc, Status::Ok) << "call " << k;
    ASSERT_EQ(sd, Status::Ok) << "call " << k;
    ASSERT_TRUE(sameFilter(continuous, discrete)) << "after the propagation of call " << k;
    if (k % 6 == 2 || k % 6 == 3) continue;  // open loop: no measurement now, the next one then draws
    Robot::Model::Meas withMissing = measured;
    withMissing(1) = std::nan("");
    const bool masked = k % 4 == 1;
    ASSERT_TRUE(mjukf::taken(masked ? continuous.measurementUpdate(withMissing, present)
                                    : continuous.measurementUpdate(measured)));
    ASSERT_TRUE(
        mjukf::taken(masked ? discrete.measurementUpdate(withMissing, present) : discrete.measurementUpdate(measured)));
    ASSERT_TRUE(sameFilter(continuous, discrete)) << "after the measurement update of call " << k;
  }
  // An update with no time update before it (after an open-loop step), then another right after it.
  ASSERT_EQ(continuous.propagateMean(double(row) * h, h), Status::Ok);
  ASSERT_EQ(discrete.propagateMean(double(row) * h, h), Status::Ok);
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(mjukf::taken(continuous.measurementUpdate(y[static_cast<std::size_t>(row + 1)])));
    ASSERT_TRUE(mjukf::taken(discrete.measurementUpdate(y[static_cast<std::size_t>(row + 1)])));
    ASSERT_TRUE(sameFilter(continuous, discrete));
  }
}

TEST(DiscreteModel, UkfEqualsContinuousEulerInEveryCall) { expectEveryCallBitForBit<mjukf::Ukf>(); }
TEST(DiscreteModel, JointUkfEqualsContinuousEulerInEveryCall) { expectEveryCallBitForBit<mjukf::JointUkf>(); }
TEST(DiscreteModel, ModifiedJointUkfEqualsContinuousEulerInEveryCall) {
  expectEveryCallBitForBit<mjukf::ModifiedJointUkf>();
}
TEST(DiscreteModel, DualUkfEqualsContinuousEulerInEveryCall) {
  expectEveryCallBitForBit<mjukf::DualUkf>(DualUkfOrdering::PriorParameters);
  expectEveryCallBitForBit<mjukf::DualUkf>(DualUkfOrdering::UpdatedParameters);
}

// ---------------------------------------------------------------------------------------------------
// What a time update over several steps calls: transition at t, t + h, t + 2h, each over dt = h, with
// the input at the start of each step (the signal's u(t + k h), or the held input).

struct Call {
  double t, dt, u;
};

// x_k = 0.9 x_{k−1} + θ u, y = x; u(t) = 10 t + 1 so that the input reveals the time it was taken at.
struct RecordingModel {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = State;
  using Meas = State;
  using Input = State;
  std::vector<Call>* calls = nullptr;
  Input input(double t) const { return Input(10 * t + 1); }
  State transition(double t, double dt, const State& x, const Input& u, const Param& theta) const {
    calls->push_back({t, dt, u(0)});
    return State(0.9 * x(0) + theta(0) * u(0));
  }
  Meas measurement(const State& x, const Param&) const { return x; }
};

// `calls` holds `groups` groups of `steps` calls, each at t + k h with dt = h and the given input.
template <class InputAt>
void expectCalls(const std::vector<Call>& calls, int groups, int steps, double t, double h, InputAt&& inputAt) {
  ASSERT_EQ(calls.size(), static_cast<std::size_t>(groups * steps));
  for (int g = 0; g < groups; ++g)
    for (int k = 0; k < steps; ++k) {
      const Call& c = calls[static_cast<std::size_t>(g * steps + k)];
      const double time = t + double(k) * h;
      EXPECT_EQ(c.t, time) << "group " << g << ", step " << k;
      EXPECT_EQ(c.dt, h);
      EXPECT_EQ(c.u, inputAt(time));
    }
}

TEST(DiscreteModel, StepsApplyTheTransitionAtEachStepWithItsInput) {
  std::vector<Call> calls;
  RecordingModel model;
  model.calls = &calls;
  const auto signal = [](double time) { return 10 * time + 1; };
  const auto held = [](double) { return -0.5; };
  mjukf::UkfSettingsFor<RecordingModel> us;
  us.initialCovariance << 1.0;
  us.processNoise << 1e-3;
  us.measurementNoise << 0.1;
  mjukf::Ukf<RecordingModel> ukf(model, RecordingModel::State(1.0), RecordingModel::Param(0.2), us);
  ASSERT_EQ(ukf.timeUpdate(1.0, 0.25, 3), Status::Ok);
  expectCalls(calls, 3, 3, 1.0, 0.25, signal);  // 2n + 1 = 3 points
  calls.clear();
  ASSERT_EQ(ukf.timeUpdate(2.0, 0.125, RecordingModel::Input(-0.5), 4), Status::Ok);
  expectCalls(calls, 3, 4, 2.0, 0.125, held);
  calls.clear();
  ASSERT_EQ(ukf.propagateMean(3.0, 0.5, 2), Status::Ok);
  expectCalls(calls, 1, 2, 3.0, 0.5, signal);
  calls.clear();
  ASSERT_EQ(ukf.propagateMean(4.0, 0.5, RecordingModel::Input(-0.5), 3), Status::Ok);
  expectCalls(calls, 1, 3, 4.0, 0.5, held);
  calls.clear();
  ASSERT_EQ(ukf.measurementUpdate(RecordingModel::Meas(0.4)), Status::Ok);
  EXPECT_TRUE(calls.empty());

  // The dual filter in the UpdatedParameters ordering: its time update propagates the 3 state points
  // and x̂ for each of its 3 parameter points; its measurement update repeats the state's 3 with the
  // same times and inputs, the held one included.
  mjukf::DualUkfSettingsFor<RecordingModel> ds;
  static_cast<mjukf::UnscentedSettings<double, 1, 1>&>(ds) = us;
  ds.initialParameterCovariance << 0.01;
  ds.ordering = DualUkfOrdering::UpdatedParameters;
  mjukf::DualUkf<RecordingModel> dual(model, RecordingModel::State(1.0), RecordingModel::Param(0.2), ds);
  calls.clear();
  ASSERT_EQ(dual.timeUpdate(1.0, 0.25, RecordingModel::Input(-0.5), 2), Status::Ok);
  expectCalls(calls, 6, 2, 1.0, 0.25, held);
  calls.clear();
  ASSERT_EQ(dual.measurementUpdate(RecordingModel::Meas(0.4)), Status::Ok);
  expectCalls(calls, 3, 2, 1.0, 0.25, held);
  calls.clear();
  ASSERT_EQ(dual.timeUpdate(2.0, 0.25, 3), Status::Ok);
  expectCalls(calls, 6, 3, 2.0, 0.25, signal);
  calls.clear();
  ASSERT_EQ(dual.measurementUpdate(RecordingModel::Meas(0.4)), Status::Ok);
  expectCalls(calls, 3, 3, 2.0, 0.25, signal);
}

}  // namespace
