// No per-step call allocates: every filter on both plants and on the 2019 systems, every kind of call,
// including refused ones; the dual filter in both orderings; the automatic MJUKF; every filter over a
// discrete-time model and over a model without input; reset(); and filters large enough (L = 32, 36)
// for the general forms of the kernels chosen by size (detail/linear_algebra.hpp).
// Two independent witnesses: Eigen's own runtime check (EIGEN_RUNTIME_NO_MALLOC makes any Eigen heap
// allocation assert while it is forbidden) and a global operator new that counts every allocation.

#define EIGEN_RUNTIME_NO_MALLOC
#undef NDEBUG  // Eigen reports a forbidden allocation through assert: keep it on in Release builds.

#include <atomic>
#include <cstdlib>
#include <limits>
#include <memory>
#include <new>
#include <type_traits>

#include <gtest/gtest.h>

#include "chain_model.hpp"  // bench/: the scaling benchmark's chain of masses
#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/model.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "no_input_model.hpp"
#include "paper/experiments.hpp"
#include "paper/schedule.hpp"
#include "paper/systems_2019.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace {
std::atomic<long> allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
// GCC (with ASan, -O1) takes free() inside a replacement operator delete for a mismatch with new;
// here both are the replacements above, which use malloc, so the pairing is right.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

namespace {

using mjukf::Status;

// Counts the heap allocations made by `body`, with Eigen's allocations forbidden meanwhile.
template <class Body>
long allocationsDuring(Body&& body) {
  const long before = allocations.load();
  Eigen::internal::set_is_malloc_allowed(false);
  body();
  Eigen::internal::set_is_malloc_allowed(true);
  return allocations.load() - before;
}

template <class T>
class NoAllocation : public ::testing::Test {};

template <template <class...> class F, class E>
struct Case : mjukf::testing::PaperFilter<F, E> {};

// The dual filter with the experiment's dualUkf() settings, in the given ordering.
template <class E, mjukf::DualUkfOrdering Ordering, template <class...> class F = mjukf::DualUkf>
struct DualCase {
  using Model = typename E::Model;
  static F<Model> make() {
    auto s = E::dualUkf();
    s.ordering = Ordering;
    return F<Model>(Model(), E::initialState(), E::initialParameters(), s);
  }
};

using mjukf::testing::DiscreteRobot;  // the robot as a discrete-time model: no integrator
using mjukf::testing::IsDual;
using mjukf::testing::IsUkf;
using mjukf::testing::SquareRoot;
static_assert(mjukf::isDiscreteTime<DiscreteRobot<double>>);

// Each filter over DiscreteRobot with the robot's settings for it (the settings' shared part is the same
// type for both models: only the model parameter of the settings template differs).
template <template <class...> class F, class Scalar,
          mjukf::DualUkfOrdering Ordering = mjukf::DualUkfOrdering::PriorParameters>
struct DiscreteCase {
  using E = mjukf::paper::FlexibleJointExperiment<Scalar>;
  using Model = DiscreteRobot<Scalar>;
  using Filter = F<Model, mjukf::NoIntegrator<Scalar>>;
  static Filter make() {
    auto s = mjukf::testing::presetSettings<F, E, Model>();
    if constexpr (IsDual<Filter>::value) s.ordering = Ordering;
    const auto theta0 = IsUkf<Filter>::value ? E::Model::trueParameters() : E::initialParameters();
    return Filter(Model(), E::initialState(), theta0, s);
  }
};

// `Base`'s MJUKF with both automatic modes on (T from the sensitivities, adaptive ξ).
template <class Base>
struct Automatic {
  static auto make() {
    const auto paper = Base::make();
    auto s = paper.settings();
    s.automaticTransformation = true;
    s.adaptiveScaling = true;
    return std::decay_t<decltype(paper)>(paper.model(), paper.state(), paper.parameters(), s);
  }
};

// `Base`'s dual filter with parameters that walk (Q_θ ≠ 0, λ < 1): its time update starts from W G and
// P + W C Wᵀ (docs/algorithms.md §9), a path the presets, whose parameters are constant, never take.
template <class Base>
struct Walking {
  static auto make() {
    const auto preset = Base::make();
    auto s = preset.settings();
    using Scalar = typename decltype(preset)::Scalar;
    s.parameterProcessNoise.setIdentity();
    s.parameterProcessNoise *= Scalar(1e-8);
    s.parameterForgetting = Scalar(0.999);
    return std::decay_t<decltype(preset)>(preset.model(), preset.state(), preset.parameters(), s);
  }
};

// `Base`'s hand-tuned MJUKF following the covariance of θ̂ (the presets, the paper's, do not).
template <class Base>
struct FollowingParameterCovariance {
  static auto make() {
    const auto paper = Base::make();
    auto s = paper.settings();
    s.followParameterCovariance = true;
    return std::decay_t<decltype(paper)>(paper.model(), paper.state(), paper.parameters(), s);
  }
};

// `Base` with α = 0.5 (β = 2, κ = 0): the centre point's covariance weight is negative (Wc₀ = −0.25 for
// L = 6), which the square-root form applies as a rank-one downdate.
template <class Base>
struct AlphaBelowOne {
  static auto make() {
    const auto paper = Base::make();
    auto s = paper.settings();
    s.sigmaPoints.alpha = 0.5;
    return std::decay_t<decltype(paper)>(paper.model(), paper.state(), paper.parameters(), s);
  }
};

// issue 10 (part A): the 2019 MJUKF paper's systems, with their integrator (RK4) and no input.
template <template <class...> class F, class E>
struct Case2019 {
  using Model = typename E::Model;
  static F<Model, typename E::Integrator> make() {
    return {Model(), E::initialState(), E::initialParameters(), mjukf::testing::presetSettings<F, E>()};
  }
};
using VanDerPol = mjukf::paper::VanDerPolExperiment<double>;
using Lorenz = mjukf::paper::LorenzExperiment<double>;

using Robot = mjukf::paper::FlexibleJointExperiment<double>;
using Tank = mjukf::paper::CoupledTankExperiment<double>;
using RobotF = mjukf::paper::FlexibleJointExperiment<float>;
constexpr auto kPrior = mjukf::DualUkfOrdering::PriorParameters;
constexpr auto kUpdated = mjukf::DualUkfOrdering::UpdatedParameters;
#ifdef MJUKF_NO_ALLOCATION_CORE
// The quick tier's core (tests/CMakeLists.txt): each filter kind, in double and float, the automatic
// MJUKF, the dual with parameters that walk, a discrete-time model and the square-root form, one case each.
using Cases =
    ::testing::Types<Case<mjukf::Ukf, Robot>, Case<mjukf::JointUkf, Tank>, Case<mjukf::ModifiedJointUkf, RobotF>,
                     Walking<DualCase<Robot, kUpdated>>, Automatic<Case<mjukf::ModifiedJointUkf, Robot>>,
                     DiscreteCase<mjukf::DualUkf, double, kPrior>, Case<SquareRoot<mjukf::JointUkf>::Filter, Robot>>;
#else
using Cases = ::testing::Types<
    Case<mjukf::Ukf, Robot>, Case<mjukf::JointUkf, Robot>, Case<mjukf::ModifiedJointUkf, Robot>, Case<mjukf::Ukf, Tank>,
    Case<mjukf::JointUkf, Tank>, Case<mjukf::ModifiedJointUkf, Tank>, Case<mjukf::ModifiedJointUkf, RobotF>,
    Case<mjukf::JointUkf, RobotF>, DualCase<Robot, kPrior>, DualCase<Robot, kUpdated>, DualCase<Tank, kPrior>,
    DualCase<Tank, kUpdated>, DualCase<RobotF, kPrior>, DualCase<RobotF, kUpdated>, DiscreteCase<mjukf::Ukf, double>,
    DiscreteCase<mjukf::JointUkf, double>, DiscreteCase<mjukf::ModifiedJointUkf, double>,
    DiscreteCase<mjukf::DualUkf, double>, DiscreteCase<mjukf::DualUkf, double, kUpdated>,
    DiscreteCase<mjukf::ModifiedJointUkf, float>, Case2019<mjukf::JointUkf, VanDerPol>,
    Case2019<mjukf::ModifiedJointUkf, VanDerPol>, Case2019<mjukf::DualUkf, VanDerPol>,
    Case2019<mjukf::JointUkf, Lorenz>, Case2019<mjukf::ModifiedJointUkf, Lorenz>, Walking<DualCase<Robot, kPrior>>,
    Walking<DualCase<Robot, kUpdated>>, Walking<DualCase<RobotF, kPrior>>,
    Automatic<Case<mjukf::ModifiedJointUkf, Robot>>, Automatic<Case<mjukf::ModifiedJointUkf, Tank>>,
    Automatic<Case<mjukf::ModifiedJointUkf, RobotF>>, Automatic<DiscreteCase<mjukf::ModifiedJointUkf, double>>,
    Automatic<DiscreteCase<mjukf::ModifiedJointUkf, float>>, Automatic<Case2019<mjukf::ModifiedJointUkf, VanDerPol>>,
    Automatic<Case2019<mjukf::ModifiedJointUkf, Lorenz>>,
    FollowingParameterCovariance<Case<mjukf::ModifiedJointUkf, Robot>>,
    FollowingParameterCovariance<DiscreteCase<mjukf::ModifiedJointUkf, float>>,
    // The square-root form (covariance_form.hpp).
    Case<SquareRoot<mjukf::Ukf>::Filter, Robot>, Case<SquareRoot<mjukf::JointUkf>::Filter, Robot>,
    Case<SquareRoot<mjukf::ModifiedJointUkf>::Filter, Tank>, Case<SquareRoot<mjukf::JointUkf>::Filter, RobotF>,
    DualCase<Robot, kPrior, SquareRoot<mjukf::DualUkf>::Filter>,
    DualCase<Robot, kUpdated, SquareRoot<mjukf::DualUkf>::Filter>,
    Walking<DualCase<Robot, kUpdated, SquareRoot<mjukf::DualUkf>::Filter>>,
    DiscreteCase<SquareRoot<mjukf::DualUkf>::Filter, float, kUpdated>,
    Automatic<Case<SquareRoot<mjukf::ModifiedJointUkf>::Filter, Robot>>,
    AlphaBelowOne<Case<SquareRoot<mjukf::JointUkf>::Filter, Robot>>, AlphaBelowOne<Case<mjukf::JointUkf, Robot>>>;
#endif
TYPED_TEST_SUITE(NoAllocation, Cases);

TYPED_TEST(NoAllocation, EveryPerStepCall) {
  auto filter = TypeParam::make();  // construction may allocate (exception messages); steps may not
  using Filter = decltype(filter);
  using Scalar = typename Filter::Scalar;
  using Meas = typename Filter::Meas;
  const Meas y = Meas::Constant(Scalar(0.01));
  Meas bad = y;
  bad(0) = std::numeric_limits<Scalar>::quiet_NaN();
  const typename Filter::Input u = Filter::Input::Constant(Scalar(1));
  const Scalar h = Scalar(1e-3);
  Status status[10];
  const long count = allocationsDuring([&] {
    status[0] = filter.timeUpdate(Scalar(0), h);
    status[1] = filter.measurementUpdate(y);
    status[2] = filter.propagateMean(h, h);
    status[3] = filter.measurementUpdate(y);  // without a time update: draws its own points
    status[4] = filter.timeUpdate(2 * h, h, u, 3);
    status[5] = filter.propagateMean(5 * h, h, u, 2);
    status[6] = filter.measurementUpdate(bad);     // refused
    status[7] = filter.timeUpdate(Scalar(0), -h);  // refused
    status[8] = filter.timeUpdate(7 * h, h, 4);
    status[9] = filter.measurementUpdate(y);
    (void)filter.lastUpdate().nis;
  });
  EXPECT_EQ(count, 0) << "heap allocations in per-step calls";
  for (int i : {0, 1, 2, 3, 4, 5, 8, 9}) EXPECT_EQ(status[i], Status::Ok) << "call " << i;
  EXPECT_EQ(status[6], Status::NonFiniteMeasurement);
  EXPECT_EQ(status[7], Status::InvalidStepSize);
}

TYPED_TEST(NoAllocation, PaperScheduleRun) {
  auto filter = TypeParam::make();
  using Filter = decltype(filter);
  using Scalar = typename Filter::Scalar;
  const typename Filter::Meas y = Filter::Meas::Constant(Scalar(0.01));
  mjukf::paper::ScheduleOutcome outcome;
  const long count = allocationsDuring([&] {
    outcome = mjukf::paper::runSchedule(
        filter, 500, Scalar(1e-3), 5, [&](long) -> const typename Filter::Meas& { return y; },
        [](long, const Filter&) {});
  });
  EXPECT_EQ(count, 0);
  EXPECT_EQ(outcome.status, Status::Ok);
}

// The hardening paths: masked updates, gated (rejected) updates, active parameter bounds, and the
// covariance repair.
TYPED_TEST(NoAllocation, MaskingGatingBoundsAndRepair) {
  const auto paper = TypeParam::make();
  using Filter = std::decay_t<decltype(paper)>;
  using Scalar = typename Filter::Scalar;
  using Meas = typename Filter::Meas;
  auto settings = paper.settings();
  if constexpr (Filter::ParamDim > 0 && !IsUkf<Filter>::value) {
    settings.parameterBounds.lower = paper.parameters() - Filter::Param::Constant(Scalar(1));
    settings.parameterBounds.upper = paper.parameters() + Filter::Param::Constant(Scalar(1));
  }
  Filter bounded(paper.model(), paper.state(), paper.parameters(), settings);
  settings.gate.nisThreshold.setConstant(Scalar(1e-30));  // rejects everything
  Filter gated(paper.model(), paper.state(), paper.parameters(), settings);
  Meas y = Meas::Constant(Scalar(0.01));
  mjukf::MeasurementMask<Filter::MeasDim> present = mjukf::MeasurementMask<Filter::MeasDim>::Constant(true);
  present(0) = false;
  Meas withMissing = y;
  withMissing(0) = std::numeric_limits<Scalar>::quiet_NaN();
  const Scalar h = Scalar(1e-3);
  mjukf::detail::CovarianceGuard<Scalar, 3> guard;
  Eigen::Matrix<Scalar, 3, 3> rankOne = Eigen::Matrix<Scalar, 3, 1>(1, 2, 3) * Eigen::Matrix<Scalar, 1, 3>(1, 2, 3);
  const mjukf::CovarianceRepair<Scalar> repair;
  Status status[7];
  const long count = allocationsDuring([&] {
    status[0] = bounded.timeUpdate(Scalar(0), h);
    status[1] = bounded.measurementUpdate(withMissing, present);
    status[2] = bounded.timeUpdate(h, h);
    status[3] = bounded.measurementUpdate(y);
    status[4] = gated.timeUpdate(Scalar(0), h);
    status[5] = gated.measurementUpdate(y);
    status[6] = guard.settle(rankOne, repair);
  });
  EXPECT_EQ(count, 0) << "heap allocations in per-step calls";
  for (int i : {0, 1, 2, 3, 4}) EXPECT_EQ(status[i], Status::Ok) << "call " << i;
  EXPECT_EQ(status[5], Status::MeasurementRejected);
  EXPECT_EQ(status[6], Status::Repaired);
}

// reset() with valid arguments, every overload, then the steps after it.
TYPED_TEST(NoAllocation, Reset) {
  auto filter = TypeParam::make();
  using Filter = decltype(filter);
  using Scalar = typename Filter::Scalar;
  using Covariance = std::decay_t<decltype(filter.covariance())>;
  const typename Filter::State x = filter.state() + Filter::State::Constant(Scalar(0.01));
  const Covariance P = Scalar(2) * filter.covariance();
  const typename Filter::Param theta = filter.parameters();
  const typename Filter::Meas y = Filter::Meas::Constant(Scalar(0.01));
  const Scalar h = Scalar(1e-3);
  ASSERT_EQ(filter.timeUpdate(Scalar(0), h), Status::Ok);
  Status status[6];
  const long count = allocationsDuring([&] {
    filter.reset(x, P);
    status[0] = filter.timeUpdate(h, h);
    filter.reset(x, P, theta);
    status[1] = filter.measurementUpdate(y);
    status[2] = filter.timeUpdate(2 * h, h);
    if constexpr (IsDual<Filter>::value) filter.reset(x, P, theta, filter.parameterCovariance());
    status[3] = filter.measurementUpdate(y);
    status[4] = filter.timeUpdate(3 * h, h);
    status[5] = filter.measurementUpdate(y);
  });
  EXPECT_EQ(count, 0) << "heap allocations in reset or the steps after it";
  for (int i = 0; i < 6; ++i) EXPECT_EQ(status[i], Status::Ok) << "call " << i;
}

// Every filter over a model without input (no_input_model.hpp): the calls without an input argument.
template <class Filter>
void expectNoAllocationWithoutInput() {
  auto filter = mjukf::testing::no_input::makeFilter<Filter>();
  const typename Filter::Meas y = Filter::Meas::Constant(0.5);
  Status status[4];
  const long count = allocationsDuring([&] {
    status[0] = filter.timeUpdate(0.0, 0.01);
    status[1] = filter.measurementUpdate(y);
    status[2] = filter.propagateMean(0.01, 0.01);
    status[3] = filter.timeUpdate(0.02, 0.01, 3);
  });
  EXPECT_EQ(count, 0) << "heap allocations in per-step calls without input";
  for (int i = 0; i < 4; ++i) EXPECT_EQ(status[i], Status::Ok) << "call " << i;
}

TEST(NoAllocation, CallsWithoutInput) {
  using mjukf::testing::no_input::Pendulum;
  using mjukf::testing::no_input::Rk4;
  expectNoAllocationWithoutInput<mjukf::Ukf<Pendulum, Rk4>>();
  expectNoAllocationWithoutInput<mjukf::JointUkf<Pendulum, Rk4>>();
  expectNoAllocationWithoutInput<mjukf::ModifiedJointUkf<Pendulum, Rk4>>();
  expectNoAllocationWithoutInput<mjukf::DualUkf<Pendulum, Rk4>>();
}

#ifndef MJUKF_NO_ALLOCATION_CORE
// The kernels' general forms (matrix products, rank-k update, the factor by columns; detail/linear_algebra.hpp)
// allocate nothing either: a JUKF at L = 36 and a float UKF at L = 32 on the chain of masses, on the heap
// (about 190 KB and 60 KB), and an automatic MJUKF at n = 20 (Eigen's eigensolver, the joint covariance
// by blocks).
template <class Filter>
void expectNoAllocationAtLargeSize(const typename Filter::Param& theta, const typename Filter::Settings& settings) {
  using Model = typename Filter::Model;
  using Scalar = typename Model::Scalar;
  auto filter = std::make_unique<Filter>(Model(), Model::State::Constant(Scalar(0.1)), theta, settings);
  const typename Model::Meas y = Model::Meas::Constant(Scalar(0.1));
  Status status[4];
  const long count = allocationsDuring([&] {
    status[0] = filter->timeUpdate(Scalar(0), Scalar(1e-3));
    status[1] = filter->measurementUpdate(y);
    status[2] = filter->timeUpdate(Scalar(1e-3), Scalar(1e-3));
    status[3] = filter->measurementUpdate(y);
  });
  EXPECT_EQ(count, 0) << "heap allocations in per-step calls at large L";
  for (int i = 0; i < 4; ++i) EXPECT_EQ(status[i], Status::Ok) << "call " << i;
}

TEST(NoAllocation, GeneralKernelsAtLargeSize) {
  using ChainD = mjukf::bench::Chain<double, 32, 4>;
  using ChainF = mjukf::bench::Chain<float, 32, 4>;
  using JointD = mjukf::JointUkf<ChainD, mjukf::Rk4<double>>;
  using UkfF = mjukf::Ukf<ChainF, mjukf::Rk4<float>>;
  expectNoAllocationAtLargeSize<JointD>(ChainD::trueParameters(), mjukf::bench::ChainExperiment<ChainD>::jointUkf());
  expectNoAllocationAtLargeSize<UkfF>(ChainF::trueParameters(), mjukf::bench::ChainExperiment<ChainF>::ukf());
  // The automatic MJUKF at n = 20: its floor of P⁻ by Eigen's eigensolver (positivePartFactor, from
  // n = 5), its joint covariance by blocks and one triangle (ParameterErrorCovariance, from n + p = 20).
  using ChainM = mjukf::bench::Chain<double, 20, 1>;
  using AutomaticD = mjukf::ModifiedJointUkf<ChainM, mjukf::Rk4<double>>;
  expectNoAllocationAtLargeSize<AutomaticD>(ChainM::trueParameters(),
                                            mjukf::bench::ChainExperiment<ChainM>::modifiedJointUkf(true));
}

#endif

// The witnesses work: an allocation inside the window is seen by both.
int* volatile sink = nullptr;  // volatile: the compiler may not elide the new/delete pair

TEST(NoAllocationWitness, CountsAnAllocation) {
  const long count = allocationsDuring([] {
    sink = new int(3);
    delete sink;
  });
  EXPECT_EQ(count, 1);
}

TEST(NoAllocationWitness, EigenRefusesAHeapMatrix) {
  EXPECT_DEATH(allocationsDuring([] {
                 Eigen::MatrixXd dynamic(3, 3);
                 dynamic.setZero();
                 sink = reinterpret_cast<int*>(dynamic.data());
               }),
               "is_malloc_allowed");
}

}  // namespace
