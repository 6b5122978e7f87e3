// Hardening (docs/robustness.md): the check and repair of every committed covariance, bad input of
// every kind, a model that blows up, measurement masking and gating, parameter bounds, outliers.
// Every refused call is checked to leave the filter bit for bit as it was, and the filter to go on
// exactly as a copy that never saw the refused call.

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include "mjukf/covariance_repair.hpp"
#include "mjukf/detail/unscented_engine.hpp"  // CovarianceGuard
#include "mjukf/measurement_gating.hpp"
#include "mjukf/simulation.hpp"
#include "paper/experiments.hpp"
#include "paper/rmse.hpp"
#include "paper/schedule.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace {

using mjukf::Status;
using mjukf::testing::sameFilter;
using mjukf::testing::symmetricPositiveDefinite;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = std::numeric_limits<double>::epsilon();

// ---------------------------------------------------------------------------------------------------
// The guard every commit goes through.

using Guard = mjukf::detail::CovarianceGuard<double, 3>;
using Matrix3 = Eigen::Matrix3d;

TEST(CovarianceGuard, SymmetrisesAndAcceptsAPositiveDefiniteMatrix) {
  std::mt19937_64 rng(3);
  Matrix3 p = mjukf::testing::randomCovariance<3>(rng);
  p(0, 2) += 1e-15;  // the rounding asymmetry a product leaves
  const Matrix3 expected = 0.5 * (p + p.transpose());
  Guard guard;
  ASSERT_EQ(guard.settle(p, {}), Status::Ok);
  EXPECT_TRUE((p.array() == p.transpose().array()).all());
  EXPECT_TRUE(p.isApprox(expected, 1e-15));
}

TEST(CovarianceGuard, RepairsARankDeficientMatrixWithinTheBound) {
  const Eigen::Vector3d v(1.0, -2.0, 0.5);
  Matrix3 p = v * v.transpose();  // rank 1: no Cholesky factor
  const Matrix3 before = p;
  const double scale = p.diagonal().cwiseAbs().mean();
  Guard guard;
  ASSERT_EQ(guard.settle(p, {}), Status::Repaired);
  const Matrix3 added = p - before;
  EXPECT_TRUE(added.isDiagonal(0.0));
  const double jitter = added(0, 0);
  EXPECT_TRUE((added.diagonal().array() == jitter).all());
  EXPECT_GT(jitter, 0.0);
  EXPECT_LE(jitter, 16 * kEps * 1e4 * scale) << "more than the documented largest jitter";
  EXPECT_EQ(p.llt().info(), Eigen::Success);
}

TEST(CovarianceGuard, RefusesAnIndefiniteMatrix) {
  Matrix3 p = Eigen::Vector3d(1.0, -0.5, 1.0).asDiagonal();
  Guard guard;
  EXPECT_EQ(guard.settle(p, {}), Status::NotPositiveDefinite);
}

TEST(CovarianceGuard, RefusesZeroAndNonFiniteMatrices) {
  Guard guard;
  Matrix3 zero = Matrix3::Zero();
  EXPECT_EQ(guard.settle(zero, {}), Status::NotPositiveDefinite);
  for (const double bad : {kNan, kInf, -kInf})
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        Matrix3 p = Matrix3::Identity();
        p(r, c) = bad;
        EXPECT_EQ(guard.settle(p, {}), Status::NonFiniteResult) << r << "," << c << " = " << bad;
      }
}

TEST(CovarianceGuard, DisabledRepairRefuses) {
  const Eigen::Vector3d v(1.0, 2.0, 3.0);
  Matrix3 p = v * v.transpose();
  mjukf::CovarianceRepair<double> off;
  off.maxAttempts = 0;
  Guard guard;
  EXPECT_EQ(guard.settle(p, off), Status::NotPositiveDefinite);
}

// ---------------------------------------------------------------------------------------------------
// The review's case: sigma-point weights with a negative central covariance weight (α = 0.572,
// β = −0.749) and y = x₀ + 2.46 x₁². The Kalman correction gives a P that is not positive definite;
// it used to be committed with Status::Ok, after which every time update was refused.

struct Oscillator {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 0, MeasDim = 1, InputDim = 1;
  using State = Eigen::Vector2d;
  using Param = Eigen::Matrix<double, 0, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
  Input input(double) const { return Input::Zero(); }
  State derivative(double, const State& x, const Input&, const Param&) const { return State(x(1), -x(0) - 0.2 * x(1)); }
  Meas measurement(const State& x, const Param&) const { return Meas(x(0) + 2.46 * x(1) * x(1)); }
};

mjukf::Ukf<Oscillator> gapFilter() {
  mjukf::UkfSettingsFor<Oscillator> s;
  s.sigmaPoints = {0.572, -0.749, 0.0};
  s.initialCovariance << 1.7065319924325957, 0.01622298302177394, 0.01622298302177394, 0.67422552795116664;
  s.processNoise = 1e-4 * Eigen::Matrix2d::Identity();
  s.measurementNoise(0) = 0.021972914255648804;
  return mjukf::Ukf<Oscillator>(Oscillator(), Oscillator::State(0.66922428757406494, 0.0012202498235657346), {}, s);
}

TEST(IndefiniteUpdate, IsRefusedInsteadOfCommitted) {
  auto filter = gapFilter();
  const auto untouched = filter;
  EXPECT_EQ(filter.measurementUpdate(Oscillator::Meas(0.50714148085419075)), Status::NotPositiveDefinite);
  EXPECT_TRUE(sameFilter(filter, untouched));
  EXPECT_TRUE(symmetricPositiveDefinite(filter.covariance()));
}

TEST(IndefiniteUpdate, FilterIsNeverLeftWithoutACholeskyFactor) {
  // Along a trajectory of the oscillator: every call is either taken, with a symmetric positive
  // definite P, or refused, with nothing changed; and time updates keep being taken.
  auto filter = gapFilter();
  Oscillator::State truth(1.0, 0.0);
  const mjukf::ITrBdf2<double> stepper;
  const double h = 0.01;
  int taken = 0, refused = 0, timeUpdates = 0;
  for (int k = 0; k < 500; ++k) {
    truth = stepper.step([](double, const Oscillator::State& x) { return Oscillator::State(x(1), -x(0) - 0.2 * x(1)); },
                         k * h, truth, h);
    for (int call = 0; call < 2; ++call) {
      const auto before = filter;
      const Status s =
          call == 0 ? filter.timeUpdate(k * h, h) : filter.measurementUpdate(Oscillator().measurement(truth, {}));
      if (mjukf::taken(s)) {
        ++taken;
        timeUpdates += call == 0;
        ASSERT_TRUE(symmetricPositiveDefinite(filter.covariance())) << "step " << k << " " << toString(s);
      } else {
        ++refused;
        ASSERT_TRUE(sameFilter(filter, before)) << "step " << k << " " << toString(s);
      }
    }
  }
  std::printf("gap run: %d calls taken, %d refused, %d of 500 time updates taken\n", taken, refused, timeUpdates);
  EXPECT_EQ(timeUpdates, 500) << "a committed P always has a factor, so time updates are never refused";
}

// ---------------------------------------------------------------------------------------------------
// Every filter on both plants of the paper.

template <class T>
class Hardening : public ::testing::Test {};
template <template <class...> class F, class E>
struct Case : mjukf::testing::PaperFilter<F, E> {
  using Experiment = E;
};
using Robot = mjukf::paper::FlexibleJointExperiment<double>;
using Tank = mjukf::paper::CoupledTankExperiment<double>;
using Cases =
    ::testing::Types<Case<mjukf::Ukf, Robot>, Case<mjukf::JointUkf, Robot>, Case<mjukf::ModifiedJointUkf, Robot>,
                     Case<mjukf::Ukf, Tank>, Case<mjukf::JointUkf, Tank>, Case<mjukf::ModifiedJointUkf, Tank>>;
TYPED_TEST_SUITE(Hardening, Cases);

// A measurement near the model's prediction, so the update is an ordinary one.
template <class Filter>
typename Filter::Meas plausibleMeasurement(const Filter& f) {
  return f.model().measurement(f.state(), f.parameters()) + Filter::Meas::Constant(0.01);
}

// Calls `refused` (expected to return `expected`) and checks nothing changed and that the next
// time and measurement updates give bit for bit what they give on a copy that never saw the call.
template <class Filter, class Call>
void expectNothingLost(Filter& filter, Status expected, Call&& refused, const char* what) {
  const Filter untouched = filter;
  EXPECT_EQ(refused(filter), expected) << what;
  ASSERT_TRUE(sameFilter(filter, untouched)) << what << ": the refused call changed the filter";
  Filter copy = untouched;
  const auto y = plausibleMeasurement(filter);
  EXPECT_TRUE(mjukf::taken(filter.measurementUpdate(y))) << what;
  EXPECT_TRUE(mjukf::taken(copy.measurementUpdate(y))) << what;
  EXPECT_TRUE(sameFilter(filter, copy)) << what << ": the next update differs";
}

TYPED_TEST(Hardening, NonFiniteValueInEveryMeasurementComponent) {
  auto filter = TypeParam::make();
  using Filter = decltype(filter);
  ASSERT_EQ(filter.timeUpdate(0.0, 1e-3), Status::Ok);
  for (int j = 0; j < Filter::MeasDim; ++j)
    for (const double bad : {kNan, kInf, -kInf}) {
      ASSERT_EQ(filter.timeUpdate(0.0, 1e-3), Status::Ok);
      auto y = plausibleMeasurement(filter);
      y(j) = bad;
      expectNothingLost(
          filter, Status::NonFiniteMeasurement, [&](Filter& f) { return f.measurementUpdate(y); }, "non-finite y");
      // The same component declared missing is ignored, whatever its value.
      ASSERT_EQ(filter.timeUpdate(0.0, 1e-3), Status::Ok);
      mjukf::MeasurementMask<Filter::MeasDim> present;
      present.setConstant(true);
      present(j) = false;
      Filter withZero = filter;
      auto y0 = y;
      y0(j) = 0.0;
      EXPECT_EQ(filter.measurementUpdate(y, present), Status::Ok);
      EXPECT_EQ(withZero.measurementUpdate(y0, present), Status::Ok);
      EXPECT_TRUE(sameFilter(filter, withZero));
    }
}

// P₀, Q and R with NaN or ±Inf in any entry are refused at construction, naming the setting.
TYPED_TEST(Hardening, NonFiniteNoiseSettingsAreRefusedAtConstruction) {
  using Filter = typename TypeParam::Type;
  using Experiment = typename TypeParam::Experiment;
  const auto good = TypeParam::make();
  int refused = 0;
  const auto tryWith = [&](auto settings) {
    try {
      Filter f(good.model(), Experiment::initialState(), Experiment::initialParameters(), settings);
      ADD_FAILURE() << "accepted a non-finite setting";
    } catch (const std::invalid_argument& e) {
      ++refused;
      EXPECT_NE(std::string(e.what()).find("setting"), std::string::npos);
    }
  };
  for (const double bad : {kNan, kInf, -kInf}) {
    const auto base = good.settings();
    for (int r = 0; r < base.initialCovariance.rows(); ++r)
      for (int c = 0; c < base.initialCovariance.cols(); ++c) {
        auto s = base;
        s.initialCovariance(r, c) = bad;
        tryWith(s);
        s = base;
        s.processNoise(r, c) = bad;
        tryWith(s);
      }
    for (int r = 0; r < base.measurementNoise.rows(); ++r)
      for (int c = 0; c < base.measurementNoise.cols(); ++c) {
        auto s = base;
        s.measurementNoise(r, c) = bad;
        tryWith(s);
      }
  }
  const int expected = 3 * (2 * int(good.covariance().size()) + int(good.settings().measurementNoise.size()));
  EXPECT_EQ(refused, expected);
}

// Commits always hold a symmetric P with a Cholesky factor, over a run of the paper's schedule.
TYPED_TEST(Hardening, EveryCommittedCovarianceIsSymmetricPositiveDefinite) {
  auto filter = TypeParam::make();
  using Filter = decltype(filter);
  using Experiment = typename TypeParam::Experiment;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.05);
  long checked = 0;
  const auto outcome = mjukf::paper::runSchedule(
      filter, 5000, Experiment::stepSize, Experiment::measurementEvery,
      [&](long) {
        typename Filter::Meas y = filter.model().measurement(filter.state(), filter.parameters());
        for (int j = 0; j < Filter::MeasDim; ++j) y(j) += noise(rng);
        return y;
      },
      [&](long, const Filter& f) {
        ++checked;
        ASSERT_TRUE(symmetricPositiveDefinite(f.covariance()));
      });
  EXPECT_EQ(outcome.status, Status::Ok);
  EXPECT_EQ(outcome.repairs, 0);
  EXPECT_EQ(checked, 5000);
}

// Every candidate covariance is formed exactly symmetric (one triangle computed and mirrored) and
// settled without a symmetrisation: the committed P is symmetric bit for bit with three outputs too,
// where Eigen's vectorisation of a product over both triangles sums some coefficients in another order
// than their mirror images (the paper's plants, with two and four outputs, did not show it).
struct ThreeOutputs {
  using Scalar = double;
  static constexpr int StateDim = 3, ParamDim = 1, MeasDim = 3, InputDim = 0;
  using State = Eigen::Vector3d;
  using Param = Eigen::Matrix<double, 1, 1>;
  using Meas = Eigen::Vector3d;
  using Input = Eigen::Matrix<double, 0, 1>;
  State derivative(double, const State& x, const Input&, const Param& k) const {
    return State(x(1), -k(0) * x(0) - 0.3 * x(1) + 0.1 * x(2), -0.5 * x(2) + 0.2 * x(0) * x(1));
  }
  Meas measurement(const State& x, const Param&) const {
    return Meas(x(0) + 0.1 * x(2) * x(2), std::sin(x(1)), x(2) - 0.5 * x(0));
  }
};

// Each filter with the settings it needs beyond the common ones (configure).
template <class F>
struct ThreeOutputCase {
  using Filter = F;
  static void configure(typename F::Settings&) {}
};
struct HandTunedMjukf {
  using Filter = mjukf::ModifiedJointUkf<ThreeOutputs>;
  static void configure(Filter::Settings& s) { s.transformation.setConstant(1.0 / 3); }
};
struct AutomaticMjukf {
  using Filter = mjukf::ModifiedJointUkf<ThreeOutputs>;
  static void configure(Filter::Settings& s) {
    s.automaticTransformation = true;
    s.adaptiveScaling = true;
  }
};
struct Dual {
  using Filter = mjukf::DualUkf<ThreeOutputs>;
  static void configure(Filter::Settings& s) { s.initialParameterCovariance(0, 0) = 0.1; }
};
template <class Case>
class CommittedCovariance : public ::testing::Test {};
using SquareRootForm = mjukf::SquareRootCovariance;
using ThreeOutputCases =
    ::testing::Types<ThreeOutputCase<mjukf::Ukf<ThreeOutputs>>, ThreeOutputCase<mjukf::JointUkf<ThreeOutputs>>,
                     HandTunedMjukf, AutomaticMjukf, Dual,
                     ThreeOutputCase<mjukf::Ukf<ThreeOutputs, mjukf::DefaultIntegrator<ThreeOutputs>,
                                                mjukf::MerweScaled, SquareRootForm>>,
                     ThreeOutputCase<mjukf::JointUkf<ThreeOutputs, mjukf::DefaultIntegrator<ThreeOutputs>,
                                                     mjukf::MerweScaled, SquareRootForm>>>;
TYPED_TEST_SUITE(CommittedCovariance, ThreeOutputCases);

TYPED_TEST(CommittedCovariance, IsExactlySymmetricWithThreeOutputs) {
  using Filter = typename TypeParam::Filter;
  typename Filter::Settings s;
  s.initialCovariance.setIdentity();
  s.initialCovariance *= 0.5;
  s.initialCovariance(0, 1) = s.initialCovariance(1, 0) = 0.1;
  s.processNoise = 1e-3 * decltype(s.processNoise)::Identity();
  s.measurementNoise = 1e-2 * Eigen::Matrix3d::Identity();
  TypeParam::configure(s);
  const ThreeOutputs::State x0(1.0, 0.0, 0.5);
  const ThreeOutputs::Param k(2.0);
  Filter filter(ThreeOutputs(), x0, k, s);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (int step = 0; step < 200; ++step) {
    ASSERT_TRUE(mjukf::taken(filter.timeUpdate(0.05 * step, 0.05))) << step;
    ASSERT_TRUE(symmetricPositiveDefinite(filter.covariance())) << "after time update " << step;
    ASSERT_TRUE(mjukf::taken(filter.measurementUpdate(ThreeOutputs::Meas(noise(rng), noise(rng), noise(rng))))) << step;
    ASSERT_TRUE(symmetricPositiveDefinite(filter.covariance())) << "after measurement update " << step;
    if constexpr (std::is_same_v<TypeParam, Dual>) {  // the parameter filter's P^θ too
      ASSERT_TRUE(symmetricPositiveDefinite(filter.parameterCovariance())) << step;
    }
  }
}

// ---------------------------------------------------------------------------------------------------
// A model whose output goes bad on demand: NaN, ±Inf or huge values, in any component of ẋ or of y.

enum class Fault { None, Derivative, Measurement };
struct FaultPlan {
  Fault where = Fault::None;
  int component = 0;
  double value = 0;
};

template <class Base>
struct FaultyModel : Base {
  using typename Base::Input;
  using typename Base::Meas;
  using typename Base::Param;
  using typename Base::Scalar;
  using typename Base::State;
  const FaultPlan* plan = nullptr;  // shared: the filter keeps a copy of the model
  State derivative(Scalar t, const State& x, const Input& u, const Param& theta) const {
    State d = Base::derivative(t, x, u, theta);
    if (plan && plan->where == Fault::Derivative) d(plan->component) = plan->value;
    return d;
  }
  Meas measurement(const State& x, const Param& theta) const {
    Meas y = Base::measurement(x, theta);
    if (plan && plan->where == Fault::Measurement) y(plan->component) = plan->value;
    return y;
  }
};

template <class Experiment, template <class...> class F>
auto makeFaulty(const FaultPlan* plan) {
  using Base = typename Experiment::Model;
  using Model = FaultyModel<Base>;
  using Filter = F<Model, mjukf::ITrBdf2<double>>;
  typename Filter::Settings s;
  if constexpr (std::is_same_v<Filter, mjukf::Ukf<Model, mjukf::ITrBdf2<double>>>) {
    const auto p = Experiment::ukf();
    s.initialCovariance = p.initialCovariance, s.processNoise = p.processNoise, s.measurementNoise = p.measurementNoise;
    Model m;
    m.plan = plan;
    return Filter(m, Experiment::initialState(), Base::trueParameters(), s);
  } else if constexpr (std::is_same_v<Filter, mjukf::JointUkf<Model, mjukf::ITrBdf2<double>>>) {
    const auto p = Experiment::jointUkf();
    s.initialCovariance = p.initialCovariance, s.processNoise = p.processNoise, s.measurementNoise = p.measurementNoise;
    Model m;
    m.plan = plan;
    return Filter(m, Experiment::initialState(), Experiment::initialParameters(), s);
  } else {
    const auto p = Experiment::modifiedJointUkf();
    s.initialCovariance = p.initialCovariance, s.processNoise = p.processNoise, s.measurementNoise = p.measurementNoise;
    s.scaling = p.scaling, s.transformation = p.transformation, s.parameterSpread = p.parameterSpread;
    Model m;
    m.plan = plan;
    return Filter(m, Experiment::initialState(), Experiment::initialParameters(), s);
  }
}

template <class T>
class FaultyModelOutput : public ::testing::Test {};
template <template <class...> class F, class E>
struct FaultCase {
  static auto make(const FaultPlan* plan) { return makeFaulty<E, F>(plan); }
};
using FaultCases = ::testing::Types<FaultCase<mjukf::Ukf, Robot>, FaultCase<mjukf::JointUkf, Robot>,
                                    FaultCase<mjukf::ModifiedJointUkf, Robot>, FaultCase<mjukf::Ukf, Tank>,
                                    FaultCase<mjukf::JointUkf, Tank>, FaultCase<mjukf::ModifiedJointUkf, Tank>>;
TYPED_TEST_SUITE(FaultyModelOutput, FaultCases);

TYPED_TEST(FaultyModelOutput, IsRefusedInEveryComponentAndNothingIsLost) {
  FaultPlan plan;
  auto filter = TypeParam::make(&plan);
  using Filter = decltype(filter);
  ASSERT_EQ(filter.timeUpdate(0.0, 1e-3), Status::Ok);
  ASSERT_TRUE(mjukf::taken(filter.measurementUpdate(plausibleMeasurement(filter))));
  int calls = 0;
  // 1e300 overflows the covariance sums; 1e200 overflows P_yy (its square) but not y.
  for (const double bad : {kNan, kInf, -kInf, 1e300, -1e300, 1e200}) {
    for (int j = 0; j < Filter::StateDim; ++j) {
      const auto inject = [&](auto call) {
        return [&plan, j, bad, call](Filter& f) {
          plan = {Fault::Derivative, j, bad};
          const Status s = call(f);
          plan = {};
          return s;
        };
      };
      const Filter before = filter;
      plan = {Fault::Derivative, j, bad};
      const Status s = filter.timeUpdate(0.0, 1e-3);
      plan = {};
      ++calls;
      if (mjukf::taken(s)) {
        // A huge but finite derivative over h = 1 ms can still give finite points: then the step
        // must have committed a finite, symmetric positive definite P.
        ASSERT_TRUE(std::isfinite(bad)) << toString(s);
        ASSERT_TRUE(symmetricPositiveDefinite(filter.covariance()));
        ASSERT_TRUE(filter.state().allFinite());
        filter = before;
      } else {
        ASSERT_TRUE(sameFilter(filter, before)) << toString(s);
        expectNothingLost(filter, s, inject([](Filter& f) { return f.timeUpdate(0.0, 1e-3); }), "derivative fault");
      }
      ++calls;
      const Filter beforeOpen = filter;
      plan = {Fault::Derivative, j, bad};
      const Status open = filter.propagateMean(0.0, 1e-3);
      plan = {};
      if (!mjukf::taken(open))
        ASSERT_TRUE(sameFilter(filter, beforeOpen));
      else
        filter = beforeOpen;
    }
    for (int j = 0; j < Filter::MeasDim; ++j) {
      ASSERT_EQ(filter.timeUpdate(0.0, 1e-3), Status::Ok);
      const Filter before = filter;
      const auto y = plausibleMeasurement(before);  // before the fault: y itself stays ordinary
      plan = {Fault::Measurement, j, bad};
      const Status s = filter.measurementUpdate(y);
      plan = {};
      ++calls;
      EXPECT_FALSE(mjukf::taken(s)) << "y(" << j << ") = " << bad << " gave " << toString(s);
      ASSERT_TRUE(sameFilter(filter, before)) << toString(s);
    }
  }
  EXPECT_GT(calls, 0);
}

// ---------------------------------------------------------------------------------------------------
// Masking: an update with some components missing equals the update of the reduced model.

// The linear test system observed in components 0 and 2 of its three.
TEST(Masking, UkfEqualsTheUpdateOfTheReducedModel) {
  using Full = mjukf::testing::LinearModel<3>;
  using Reduced = mjukf::testing::LinearModel<2>;
  Reduced reduced;
  reduced.C.row(0) = Full().C.row(0);
  reduced.C.row(1) = Full().C.row(2);
  mjukf::UkfSettingsFor<Full> sf;
  mjukf::UkfSettingsFor<Reduced> sr;
  std::mt19937_64 rng(5);
  sf.initialCovariance = sr.initialCovariance = mjukf::testing::randomCovariance<3>(rng);
  sf.processNoise = sr.processNoise = mjukf::testing::randomCovariance<3>(rng, 1e-3);
  sf.measurementNoise = mjukf::testing::randomCovariance<3>(rng, 1e-2);
  const int keep[2] = {0, 2};
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) sr.measurementNoise(r, c) = sf.measurementNoise(keep[r], keep[c]);
  const Eigen::Vector3d x0(0.3, -0.2, 0.1);
  mjukf::Ukf<Full> full(Full(), x0, {}, sf);
  mjukf::Ukf<Reduced> red(reduced, x0, {}, sr);
  const mjukf::MeasurementMask<3> present(true, false, true);
  for (int k = 0; k < 20; ++k) {
    ASSERT_EQ(full.timeUpdate(k * 0.1, 0.1), Status::Ok);
    ASSERT_EQ(red.timeUpdate(k * 0.1, 0.1), Status::Ok);
    const Eigen::Vector3d y(std::sin(k), kNan, std::cos(k));
    ASSERT_EQ(full.measurementUpdate(y, present), Status::Ok);
    ASSERT_EQ(red.measurementUpdate(Eigen::Vector2d(y(0), y(2))), Status::Ok);
    ASSERT_TRUE(full.state().isApprox(red.state(), 1e-12)) << k;
    ASSERT_TRUE(full.covariance().isApprox(red.covariance(), 1e-12)) << k;
    EXPECT_NEAR(full.lastUpdate().nis, red.lastUpdate().nis, 1e-12 * red.lastUpdate().nis);
  }
}

// The tank observed in its upper level alone.
template <class Scalar = double>
struct UpperLevelTank : mjukf::models::CoupledTank<Scalar> {
  using Base = mjukf::models::CoupledTank<Scalar>;
  static constexpr int MeasDim = 1;
  using Meas = Eigen::Matrix<Scalar, 1, 1>;
  Meas measurement(const typename Base::State& x, const typename Base::Param&) const { return Meas(x(0)); }
};

template <template <class...> class F>
void expectMaskedTankEqualsReduced() {
  using Full = mjukf::models::CoupledTank<double>;
  using Reduced = UpperLevelTank<double>;
  using FullFilter = F<Full, mjukf::ITrBdf2<double>>;
  using ReducedFilter = F<Reduced, mjukf::ITrBdf2<double>>;
  typename FullFilter::Settings sf;
  typename ReducedFilter::Settings sr;
  const int n = sf.initialCovariance.rows();
  sf.initialCovariance = sr.initialCovariance = Eigen::MatrixXd::Identity(n, n) * 0.5;
  sf.processNoise = sr.processNoise = Eigen::MatrixXd::Identity(n, n) * 1e-5;
  sf.measurementNoise << 0.09, 0.01, 0.01, 0.08;
  sr.measurementNoise << 0.09;
  if constexpr (std::is_same_v<FullFilter, mjukf::ModifiedJointUkf<Full, mjukf::ITrBdf2<double>>>) {
    sf.scaling = sr.scaling = -1;
    sf.transformation << 0.8, 0.2;
    sr.transformation << 1.0;  // the row of T restricted to y₁ and rescaled to sum to 1
    sf.parameterSpread = sr.parameterSpread = Full::Param::Constant(0.1);
  }
  FullFilter full(Full(), Full::State::Zero(), Full::Param::Constant(2.0), sf);
  ReducedFilter red(Reduced(), Full::State::Zero(), Full::Param::Constant(2.0), sr);
  mjukf::testing::TankMeasurements<Full> data(1e-3, 0.3, 17);
  const mjukf::MeasurementMask<2> present(true, false);
  for (long k = 0; k < 2000; ++k) {
    const double t = double(k) * 1e-3;
    ASSERT_EQ(full.timeUpdate(t, 1e-3), Status::Ok);
    ASSERT_EQ(red.timeUpdate(t, 1e-3), Status::Ok);
    auto y = data.at(k + 1);
    y(1) = kNan;
    ASSERT_EQ(full.measurementUpdate(y, present), Status::Ok);
    ASSERT_EQ(red.measurementUpdate(Reduced::Meas(y(0))), Status::Ok);
  }
  EXPECT_TRUE(full.state().isApprox(red.state(), 1e-10));
  EXPECT_TRUE(full.covariance().isApprox(red.covariance(), 1e-10));
  EXPECT_TRUE(full.parameters().isApprox(red.parameters(), 1e-10));
  EXPECT_NE(full.parameters()(0), 2.0);  // the parameter did move
}

TEST(Masking, JointUkfEqualsTheUpdateOfTheReducedModel) { expectMaskedTankEqualsReduced<mjukf::JointUkf>(); }
TEST(Masking, ModifiedJointUkfEqualsTheUpdateOfTheReducedModel) {
  expectMaskedTankEqualsReduced<mjukf::ModifiedJointUkf>();
}

TEST(Masking, AllPresentEqualsThePlainUpdate) {
  auto a = mjukf::testing::PaperFilter<mjukf::ModifiedJointUkf, Robot>::make();
  auto b = a;
  const mjukf::MeasurementMask<4> all = mjukf::MeasurementMask<4>::Constant(true);
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(a.timeUpdate(k * 1e-3, 1e-3), Status::Ok);
    ASSERT_EQ(b.timeUpdate(k * 1e-3, 1e-3), Status::Ok);
    const auto y = plausibleMeasurement(a);
    ASSERT_EQ(a.measurementUpdate(y), Status::Ok);
    ASSERT_EQ(b.measurementUpdate(y, all), Status::Ok);
  }
  EXPECT_TRUE(a.state().isApprox(b.state(), 1e-14));
  EXPECT_TRUE(a.covariance().isApprox(b.covariance(), 1e-14));
  EXPECT_TRUE(a.parameterPoints().isApprox(b.parameterPoints(), 1e-14));
}

// ---------------------------------------------------------------------------------------------------
// Gating.

TEST(Gating, ChiSquareQuantilesAreRight) {
  EXPECT_NEAR(mjukf::chiSquareQuantile(0.95, 1), 3.841458820694124, 1e-9);
  EXPECT_NEAR(mjukf::chiSquareQuantile(0.999, 2), -2 * std::log(0.001), 1e-9);  // closed form for 2 dof
  EXPECT_NEAR(mjukf::chiSquareQuantile(0.99, 4), 13.276704135987622, 1e-9);
  EXPECT_NEAR(mjukf::chiSquareQuantile(0.9999, 6), 27.856, 1e-3);
  EXPECT_TRUE(std::isnan(mjukf::chiSquareQuantile(1.0, 2)));
  EXPECT_TRUE(std::isnan(mjukf::chiSquareQuantile(0.5, 0)));
}

// The tank's filter with an R that matches the noise of the data below (σ = 0.3 cm), gated at χ²
// quantile `probability` (0: no gate).
template <template <class...> class F>
auto gatedTank(double probability) {
  auto filter = mjukf::testing::PaperFilter<F, Tank>::make();
  auto s = filter.settings();
  s.measurementNoise = 0.09 * Eigen::Matrix2d::Identity();
  if (probability > 0) s.gate = decltype(s.gate)::chiSquare(probability);
  using Filter = decltype(filter);
  return Filter(filter.model(), Tank::initialState(), filter.parameters(), s);
}

TEST(Gating, AnOutlierIsRejectedAndNothingIsLost) {
  auto filter = gatedTank<mjukf::JointUkf>(0.999);
  using Filter = decltype(filter);
  mjukf::testing::TankMeasurements<Tank::Model> data(1e-3, 0.3, 23);
  for (long k = 0; k < 1000; ++k) {
    ASSERT_EQ(filter.timeUpdate(k * 1e-3, 1e-3), Status::Ok);
    (void)filter.measurementUpdate(data.at(k + 1));  // a rare good measurement may be gated too
  }
  ASSERT_EQ(filter.timeUpdate(1.0, 1e-3), Status::Ok);
  auto outlier = data.at(1001);
  outlier(1) += 50.0;
  expectNothingLost(
      filter, Status::MeasurementRejected, [&](Filter& f) { return f.measurementUpdate(outlier); }, "outlier");
  // With the outlying channel declared missing, the rest of the measurement is used.
  ASSERT_EQ(filter.timeUpdate(1.0, 1e-3), Status::Ok);
  EXPECT_EQ(filter.measurementUpdate(outlier, mjukf::MeasurementMask<2>(true, false)), Status::Ok);
}

TEST(Gating, UsesTheThresholdOfTheComponentsPresent) {
  auto filter = mjukf::testing::PaperFilter<mjukf::Ukf, Tank>::make();
  auto s = filter.settings();
  s.gate.nisThreshold << 1e-30, 1e30;  // one component present: reject all; two: accept all
  mjukf::Ukf<Tank::Model> gated(filter.model(), Tank::initialState(), filter.parameters(), s);
  ASSERT_EQ(gated.timeUpdate(0.0, 1e-3), Status::Ok);
  const auto y = plausibleMeasurement(gated);
  const auto before = gated;
  EXPECT_EQ(gated.measurementUpdate(y, mjukf::MeasurementMask<2>(false, true)), Status::MeasurementRejected);
  EXPECT_TRUE(sameFilter(gated, before));
  EXPECT_EQ(gated.measurementUpdate(y), Status::Ok);
}

TEST(Gating, InvalidThresholdsAreRefused) {
  auto s = Tank::ukf();
  for (const double bad : {0.0, -1.0, kNan}) {
    s.gate.nisThreshold(1) = bad;
    EXPECT_THROW(mjukf::Ukf<Tank::Model>(Tank::Model(), Tank::initialState(), Tank::Model::trueParameters(), s),
                 std::invalid_argument);
  }
}

// Outliers: 1% of the measurements replaced by gross ones (±20 cm, ~70σ). With the gate on, the
// RMSE of k_flow stays within 10% of the run on clean data; without it, it does not.
template <template <class...> class F>
double tankRmse(double gateProbability, double outlierFraction, unsigned long long seed) {
  auto filter = gatedTank<F>(gateProbability);
  using Filter = decltype(filter);
  mjukf::testing::TankMeasurements<Tank::Model> data(1e-3, 0.3, seed);
  std::mt19937_64 pick(seed + 1);
  std::uniform_real_distribution<double> uniform;
  mjukf::paper::RmseAccumulator<double, 1> rmse;
  Tank::Model::Meas y;
  const auto outcome = mjukf::paper::runSchedule(
      filter, 200001, 1e-3, Tank::measurementEvery,
      [&](long k) -> const Tank::Model::Meas& {
        y = data.at(k);
        if (uniform(pick) < outlierFraction) y(uniform(pick) < 0.5 ? 0 : 1) += uniform(pick) < 0.5 ? 20.0 : -20.0;
        return y;
      },
      [&](long k, const Filter& f) {
        if (k >= Tank::rmseFromRow) rmse.add(f.parameters(), Tank::Model::trueParameters());
      });
  EXPECT_EQ(outcome.status, Status::Ok);
  EXPECT_EQ(outcome.repairs, 0);
  std::printf("  gate %g, outliers %g: rmse %.6g, %ld measurements rejected\n", gateProbability, outlierFraction,
              rmse.value()(0), outcome.rejected);
  return rmse.value()(0);
}

template <template <class...> class F>
void expectOutliersHandled(const char* name) {
  const double clean = tankRmse<F>(0.9999, 0.0, 41);
  const double gated = tankRmse<F>(0.9999, 0.01, 41);
  const double ungated = tankRmse<F>(0.0, 0.01, 41);
  std::printf("%s: clean %.6g, 1%% outliers gated %.6g (ratio %.4f), ungated %.6g (ratio %.4f)\n", name, clean, gated,
              gated / clean, ungated, ungated / clean);
  EXPECT_LE(gated, 1.1 * clean);
  EXPECT_GT(ungated, 1.1 * clean) << "the outliers are not gross enough to test the gate";
}

TEST(Gating, OnePercentGrossOutliersJointUkf) { expectOutliersHandled<mjukf::JointUkf>("JUKF"); }
TEST(Gating, OnePercentGrossOutliersModifiedJointUkf) { expectOutliersHandled<mjukf::ModifiedJointUkf>("MJUKF"); }

// ---------------------------------------------------------------------------------------------------
// Parameter bounds.

TEST(Bounds, JointUkfClampsTheMeanAndLeavesTheCovarianceAlone) {
  auto s = Tank::jointUkf();
  s.parameterBounds.upper << 3.0;  // the truth is 6: the bound holds the estimate down
  mjukf::JointUkf<Tank::Model> filter(Tank::Model(), Tank::initialState(), Tank::initialParameters(), s);
  mjukf::testing::TankMeasurements<Tank::Model> data(1e-3, 0.3, 5);
  bool reached = false;
  for (long k = 0; k < 20000; ++k) {
    ASSERT_TRUE(mjukf::taken(filter.timeUpdate(k * 1e-3, 1e-3)));
    ASSERT_LE(filter.parameters()(0), 3.0);
    ASSERT_TRUE(mjukf::taken(filter.measurementUpdate(data.at(k + 1))));
    ASSERT_LE(filter.parameters()(0), 3.0);
    ASSERT_TRUE(symmetricPositiveDefinite(filter.covariance()));
    reached = reached || filter.parameters()(0) == 3.0;
  }
  EXPECT_TRUE(reached);
}

TEST(Bounds, ModifiedJointUkfClampsEveryPerPointParameter) {
  auto s = Robot::modifiedJointUkf();
  s.parameterBounds.lower << 0.09, 0.14;
  s.parameterBounds.upper << 0.11, 0.16;  // tight around the first guess; the truth lies outside
  mjukf::ModifiedJointUkf<Robot::Model> filter(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s);
  const auto inBox = [&](const auto& theta) {
    return (theta.array() >= s.parameterBounds.lower.array()).all() &&
           (theta.array() <= s.parameterBounds.upper.array()).all();
  };
  for (int i = 0; i < filter.parameterPoints().cols(); ++i) ASSERT_TRUE(inBox(filter.parameterPoints().col(i)));
  const Robot::Model model;
  const auto theta = Robot::Model::trueParameters();
  std::vector<Robot::State> truth;
  mjukf::simulate(model, mjukf::ITrBdf2<double>(), Robot::State::Zero(), theta, 0.0, 1e-3, 2000,
                  [&](long, double, const Robot::State& x) { truth.push_back(x); });
  for (int k = 0; k < 2000; ++k) {
    ASSERT_TRUE(mjukf::taken(filter.timeUpdate(k * 1e-3, 1e-3)));
    ASSERT_TRUE(mjukf::taken(filter.measurementUpdate(model.measurement(truth[std::size_t(k + 1)], theta))));
    for (int i = 0; i < filter.parameterPoints().cols(); ++i) ASSERT_TRUE(inBox(filter.parameterPoints().col(i)));
    ASSERT_TRUE(inBox(filter.parameters()));
  }
}

TEST(Bounds, InfiniteBoundsChangeNothing) {
  auto s = Robot::jointUkf();
  mjukf::JointUkf<Robot::Model> plain(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s);
  s.parameterBounds.lower.setConstant(-kInf);
  s.parameterBounds.upper.setConstant(kInf);
  mjukf::JointUkf<Robot::Model> bounded(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s);
  for (int k = 0; k < 200; ++k) {
    ASSERT_EQ(plain.timeUpdate(k * 1e-3, 1e-3), bounded.timeUpdate(k * 1e-3, 1e-3));
    const auto y = plausibleMeasurement(plain);
    ASSERT_EQ(plain.measurementUpdate(y), bounded.measurementUpdate(y));
  }
  EXPECT_TRUE(sameFilter(plain, bounded));
}

TEST(Bounds, InvalidBoundsAreRefused) {
  const auto make = [](auto settings) {
    return mjukf::JointUkf<Tank::Model>(Tank::Model(), Tank::initialState(), Tank::initialParameters(), settings);
  };
  auto s = Tank::jointUkf();
  s.parameterBounds.lower << 3.0;
  s.parameterBounds.upper << 1.0;
  EXPECT_THROW(make(s), std::invalid_argument);  // lower > upper
  s = Tank::jointUkf();
  s.parameterBounds.lower << kNan;
  EXPECT_THROW(make(s), std::invalid_argument);
  s = Tank::jointUkf();
  s.parameterBounds.lower << 2.5;  // the first guess, 2, is outside
  EXPECT_THROW(make(s), std::invalid_argument);
  auto m = Tank::modifiedJointUkf();
  m.parameterBounds.upper << 1.0;
  EXPECT_THROW(mjukf::ModifiedJointUkf<Tank::Model>(Tank::Model(), Tank::initialState(), Tank::initialParameters(), m),
               std::invalid_argument);
}

TEST(Repair, InvalidSettingsAreRefused) {
  auto s = Tank::jointUkf();
  const auto make = [](auto settings) {
    return mjukf::JointUkf<Tank::Model>(Tank::Model(), Tank::initialState(), Tank::initialParameters(), settings);
  };
  for (const int attempts : {-1, 65}) {
    s = Tank::jointUkf();
    s.repair.maxAttempts = attempts;
    EXPECT_THROW(make(s), std::invalid_argument);
  }
  for (const double bad : {0.0, -1.0, kNan, kInf}) {
    s = Tank::jointUkf();
    s.repair.firstJitter = bad;
    EXPECT_THROW(make(s), std::invalid_argument);
  }
  s = Tank::jointUkf();
  s.repair.growth = 0.5;
  EXPECT_THROW(make(s), std::invalid_argument);
}

}  // namespace
