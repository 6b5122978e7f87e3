// The steppers on linear ODEs with exact solutions, their failure behaviour, allocation checks, and
// the filters driven by every stepper. Needs only Eigen.

#define EIGEN_RUNTIME_NO_MALLOC
#undef NDEBUG  // Eigen reports a forbidden allocation through assert: keep it on in Release builds.
#include <Eigen/Core>

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <limits>
#include <stdexcept>
#include <vector>

#include "mjukf/integrators/integrators.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/ukf.hpp"

namespace {

using namespace mjukf;

template <class Scalar>
using Vec2 = Eigen::Matrix<Scalar, 2, 1>;

// ẋ = A x, A = [−0.5 2; −2 −0.5]: x(t) = e^{−t/2} R(−2t) x₀.
template <class Scalar>
Vec2<Scalar> spiral(Scalar /*t*/, const Vec2<Scalar>& x) {
  return Vec2<Scalar>(Scalar(-0.5) * x(0) + Scalar(2) * x(1), Scalar(-2) * x(0) - Scalar(0.5) * x(1));
}
Vec2<double> exactSpiral(double t, const Vec2<double>& x0) {
  const double c = std::cos(2 * t), s = std::sin(2 * t), d = std::exp(-0.5 * t);
  return d * Vec2<double>(c * x0(0) + s * x0(1), -s * x0(0) + c * x0(1));
}

// A time-dependent scalar ODE: ẋ = −x + sin t, x(0) = 1 ⇒ x(t) = (3/2) e^{−t} + (sin t − cos t)/2.
using Vec1 = Eigen::Matrix<double, 1, 1>;
Vec1 forced(double t, const Vec1& x) { return Vec1(-x(0) + std::sin(t)); }
double exactForced(double t) { return 1.5 * std::exp(-t) + 0.5 * (std::sin(t) - std::cos(t)); }

template <class Stepper, class F, class State>
State integrate(const Stepper& stepper, F f, State x, double h, int steps) {
  for (int k = 0; k < steps; ++k) x = stepper.step(f, k * h, x, h);
  return x;
}

// Max error over [0, 2] (not just at the end, where the leading error term can pass through zero).
template <class Stepper, class F, class State, class Exact>
double maxError(const Stepper& stepper, F f, State x, Exact exact, double h, int steps) {
  double worst = 0;
  for (int k = 0; k < steps; ++k) {
    x = stepper.step(f, k * h, x, h);
    worst = std::max(worst, (x - exact((k + 1) * h)).cwiseAbs().maxCoeff());
  }
  return worst;
}

// Observed orders over h = 0.1, 0.05, 0.025, 0.0125 on [0, 2], both problems.
template <class Stepper>
void expectOrder(const Stepper& stepper, double declared) {
  const Vec2<double> x0(1, -0.5);
  double previousSpiral = 0, previousForced = 0;
  for (int i = 0; i < 4; ++i) {
    const double h = 0.1 / double(1 << i);
    const int steps = 20 << i;
    const double spiralError = maxError(
        stepper, spiral<double>, x0, [&](double t) { return exactSpiral(t, x0); }, h, steps);
    const double forcedError = maxError(
        stepper, forced, Vec1(1.0), [](double t) { return Vec1(exactForced(t)); }, h, steps);
    if (i > 0) {
      EXPECT_NEAR(std::log2(previousSpiral / spiralError), declared, 0.15) << "spiral, h = " << h;
      EXPECT_NEAR(std::log2(previousForced / forcedError), declared, 0.15) << "forced, h = " << h;
    }
    previousSpiral = spiralError;
    previousForced = forcedError;
  }
}

TEST(Integrators, DeclaredConstants) {
  static_assert(Rk4<double>::order == 4 && Rk4<double>::evaluationsPerStep == 4);
  static_assert(ExplicitTrBdf2<double>::order == 2 && ExplicitTrBdf2<double>::evaluationsPerStep == 3);
  static_assert(TrBdf2<double>::order == 2 && TrBdf2<double>::evaluationsPerStep == -1);
  static_assert(ITrBdf2<double>::order == 1 && ITrBdf2<double>::evaluationsPerStep == 3);
  SUCCEED();
}

TEST(Integrators, Rk4IsFourthOrder) { expectOrder(Rk4<double>(), 4); }
TEST(Integrators, ExplicitTrBdf2IsSecondOrder) {
  for (double gamma : {0.3, 0.5, 2 - std::sqrt(2.0), 0.8}) expectOrder(ExplicitTrBdf2<double>(gamma), 2);
}
TEST(Integrators, TrBdf2IsSecondOrder) { expectOrder(TrBdf2<double>(), 2); }
TEST(Integrators, ITrBdf2IsFirstOrder) {
  for (double gamma : {0.3, 0.5, 0.8}) expectOrder(ITrBdf2<double>(gamma), 1);
}

// One step on ẋ = λx: x₁ = R(z) x₀ with z = hλ. The local error e^z − R(z) is z²/4 for I-TR-BDF2
// (Σ bᵢcᵢ = 1/4 for every γ) and z³/6 for the explicit variant (Σ bᵢcᵢ = 1/2, no z³ term).
TEST(Integrators, LocalErrorsOnTheTestEquation) {
  using Vec = Eigen::Matrix<double, 1, 1>;
  for (double z : {-1e-3, 1e-3}) {
    const auto f = [](double, const Vec& x) -> Vec { return x; };  // λ = 1, h = z
    for (double gamma : {0.3, 0.5, 0.8}) {
      const double iLocal = std::exp(z) - ITrBdf2<double>(gamma).step(f, 0.0, Vec(1.0), z)(0);
      EXPECT_NEAR(iLocal / (z * z / 4), 1.0, 0.01) << "gamma " << gamma;
      const double eLocal = std::exp(z) - ExplicitTrBdf2<double>(gamma).step(f, 0.0, Vec(1.0), z)(0);
      EXPECT_NEAR(eLocal / (z * z * z / 6), 1.0, 0.01) << "gamma " << gamma;
    }
  }
}

// float: the same methods, rounding aside. 200 steps of relative rounding ~ε_float each.
TEST(Integrators, FloatMatchesDouble) {
  const Vec2<double> x0(1, -0.5);
  const auto check = [&](const auto& stepperF, const auto& stepperD) {
    const Vec2<float> xf = integrate(stepperF, spiral<float>, x0.cast<float>().eval(), 0.01, 200);
    const Vec2<double> xd = integrate(stepperD, spiral<double>, x0, 0.01, 200);
    EXPECT_LT((xf.cast<double>() - xd).cwiseAbs().maxCoeff(), 200 * std::numeric_limits<float>::epsilon());
  };
  check(Rk4<float>(), Rk4<double>());
  check(ExplicitTrBdf2<float>(), ExplicitTrBdf2<double>());
  check(TrBdf2<float>(), TrBdf2<double>());
  check(ITrBdf2<float>(), ITrBdf2<double>());
}

// A stiff problem: ẋ = −10⁴ (x − cos t) − sin t, x(0) = 1, x(t) = cos t. At h = 0.01 (hλ = −100) the
// explicit methods blow up; TR-BDF2 is L-stable and stays second-order accurate.
TEST(Integrators, TrBdf2HandlesStiffness) {
  const auto stiff = [](double t, const Vec1& x) -> Vec1 { return Vec1(-1e4 * (x(0) - std::cos(t)) - std::sin(t)); };
  const Vec1 x = integrate(TrBdf2<double>(), stiff, Vec1(1.0), 0.01, 200);
  EXPECT_NEAR(x(0), std::cos(2.0), 1e-6);
  const Vec1 explicitX = integrate(Rk4<double>(), stiff, Vec1(1.0), 0.01, 200);
  EXPECT_FALSE(std::isfinite(explicitX(0)) && std::abs(explicitX(0) - std::cos(2.0)) < 1);
}

TEST(Integrators, TrBdf2UsesAProvidedJacobian) {
  using Matrix2 = Eigen::Matrix2d;
  const auto jacobian = [](double, const Vec2<double>&) -> Matrix2 {
    Matrix2 a;
    a << -0.5, 2, -2, -0.5;
    return a;
  };
  const auto withJ = withJacobian(spiral<double>, jacobian);
  const TrBdf2<double> stepper;
  TrBdf2Report provided, differenced;
  const Vec2<double> x0(1, -0.5);
  const Vec2<double> a = stepper.tryStep(withJ, 0.0, x0, 0.1, provided);
  const Vec2<double> b = stepper.tryStep(spiral<double>, 0.0, x0, 0.1, differenced);
  ASSERT_TRUE(provided.converged);
  ASSERT_TRUE(differenced.converged);
  EXPECT_EQ(provided.jacobians, 1);
  EXPECT_EQ(provided.evaluations, 1 + provided.iterations);            // no difference quotients
  EXPECT_EQ(differenced.evaluations, 1 + 2 + differenced.iterations);  // n = 2 of them
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-13);
}

// Newton that does not converge never hands back a plausible-looking state.
TEST(Integrators, TrBdf2FailsLoudly) {
  // ẋ = −x², x(0) = 1, h = 0.5: one Newton iteration per round leaves a correction far above the
  // tolerance, even after the retry with a fresh Jacobian.
  const auto quadratic = [](double, const Vec1& x) -> Vec1 { return Vec1(-x(0) * x(0)); };
  TrBdf2Settings<double> oneIteration;
  oneIteration.maxIterations = 1;
  TrBdf2Report report;
  const Vec1 x = TrBdf2<double>(oneIteration).tryStep(quadratic, 0.0, Vec1(1.0), 0.5, report);
  EXPECT_FALSE(report.converged);
  EXPECT_TRUE(std::isnan(x(0)));
  EXPECT_EQ(report.jacobians, 2);  // the retry with a fresh Jacobian happened
  // With the default settings the same step converges; at this large step (h|J| = 1) its local
  // error is 0.0106 (measured).
  const Vec1 converged = TrBdf2<double>().tryStep(quadratic, 0.0, Vec1(1.0), 0.5, report);
  EXPECT_TRUE(report.converged);
  EXPECT_NEAR(converged(0), 1 / 1.5, 0.02);

  // A right-hand side that turns NaN inside the step.
  const auto poisoned = [](double t, const Vec1& x) -> Vec1 {
    return Vec1(t > 0.05 ? std::numeric_limits<double>::quiet_NaN() : -x(0));
  };
  EXPECT_TRUE(std::isnan(TrBdf2<double>().step(poisoned, 0.0, Vec1(1.0), 0.1)(0)));

  TrBdf2Settings<double> bad;
  bad.tolerance = 0;
  EXPECT_THROW(TrBdf2<double>{bad}, std::invalid_argument);
  bad = TrBdf2Settings<double>();
  bad.maxIterations = 0;
  EXPECT_THROW(TrBdf2<double>{bad}, std::invalid_argument);
  EXPECT_THROW(ExplicitTrBdf2<double>(1.0), std::invalid_argument);
  EXPECT_THROW(ExplicitTrBdf2<double>(0.0), std::invalid_argument);
}

// No stepper allocates: Eigen aborts on a heap allocation while malloc is disallowed.
template <class Model, class Stepper>
void stepWithoutAllocating(const Stepper& stepper) {
  const Model model;
  const typename Model::Param theta = Model::trueParameters();
  const auto f = [&](typename Model::Scalar t, const typename Model::State& x) ->
      typename Model::State { return model.derivative(t, x, model.input(t), theta); };
  typename Model::State x = Model::State::Constant(typename Model::Scalar(0.5));
  Eigen::internal::set_is_malloc_allowed(false);
  for (int k = 0; k < 10; ++k) x = stepper.step(f, typename Model::Scalar(k) * 1e-3f, x, typename Model::Scalar(1e-3));
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_TRUE(x.allFinite());
}

TEST(Integrators, StepsDoNotAllocate) {
  stepWithoutAllocating<models::CoupledTank<double>>(Rk4<double>());
  stepWithoutAllocating<models::CoupledTank<double>>(ExplicitTrBdf2<double>());
  stepWithoutAllocating<models::CoupledTank<double>>(TrBdf2<double>());
  stepWithoutAllocating<models::CoupledTank<double>>(ITrBdf2<double>());
  stepWithoutAllocating<models::FlexibleJoint<double>>(Rk4<double>());
  stepWithoutAllocating<models::FlexibleJoint<double>>(ExplicitTrBdf2<double>());
  stepWithoutAllocating<models::FlexibleJoint<double>>(TrBdf2<double>());
  stepWithoutAllocating<models::FlexibleJoint<float>>(Rk4<float>());
  stepWithoutAllocating<models::FlexibleJoint<float>>(ExplicitTrBdf2<float>());
  stepWithoutAllocating<models::FlexibleJoint<float>>(TrBdf2<float>());
}

// ---- Every filter with every stepper ------------------------------------------------------------

// JUKF on the tank from k_flow = 2, noiseless measurements simulated by the same stepper at 10 ms:
// the estimate must move most of the way to 6 within 20 s.
template <class Stepper>
void jointUkfConverges(const Stepper& stepper) {
  using Tank = models::CoupledTank<double>;
  const Tank tank;
  JointUkfSettingsFor<Tank> settings;
  settings.initialCovariance = Eigen::Vector3d(1, 1, 10).asDiagonal();
  settings.processNoise = Eigen::Vector3d(1e-6, 1e-6, 1e-6).asDiagonal();
  settings.measurementNoise = Eigen::Vector2d(1e-4, 1e-4).asDiagonal();
  JointUkf<Tank, Stepper> filter(tank, Tank::State::Zero(), Tank::Param::Constant(2), settings, stepper);
  const double h = 0.01;
  std::vector<Tank::State> truth;
  simulate(tank, stepper, Tank::State::Zero(), Tank::trueParameters(), 0.0, h, 2000,
           [&](long, double, const Tank::State& x) { truth.push_back(x); });
  for (int k = 0; k < 2000; ++k) {
    ASSERT_EQ(filter.timeUpdate(k * h, h), Status::Ok);
    ASSERT_EQ(filter.measurementUpdate(truth[std::size_t(k + 1)]), Status::Ok);
  }
  EXPECT_NEAR(filter.parameters()(0), 6.0, 0.4);
}

TEST(Integrators, JointUkfWithEveryStepper) {
  jointUkfConverges(Rk4<double>());
  jointUkfConverges(ExplicitTrBdf2<double>());
  jointUkfConverges(TrBdf2<double>());
}

TEST(Integrators, UkfAndModifiedJointUkfWithOtherSteppers) {
  using Robot = models::FlexibleJoint<double>;
  const Robot robot;
  ModifiedJointUkfSettingsFor<Robot> settings;
  settings.initialCovariance = Eigen::Matrix4d::Identity() * 1e-2;
  settings.processNoise = Eigen::Matrix4d::Identity() * 1e-8;
  settings.measurementNoise = Eigen::Matrix4d::Identity() * 1e-4;
  settings.scaling = -1e-4;
  settings.transformation = Eigen::Matrix<double, 2, 4>::Constant(0.25);
  settings.parameterSpread = Robot::Param(1e-3, 1e-3);
  ModifiedJointUkf<Robot, Rk4<double>> mjukf(robot, Robot::State::Zero(), Robot::Param(0.1, 0.15), settings);
  ModifiedJointUkf<Robot, TrBdf2<double>> implicitMjukf(robot, Robot::State::Zero(), Robot::Param(0.1, 0.15), settings);
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(mjukf.timeUpdate(k * 1e-3, 1e-3), Status::Ok);
    ASSERT_EQ(mjukf.measurementUpdate(Robot::Meas::Zero()), Status::Ok);
    ASSERT_EQ(implicitMjukf.timeUpdate(k * 1e-3, 1e-3), Status::Ok);
    ASSERT_EQ(implicitMjukf.measurementUpdate(Robot::Meas::Zero()), Status::Ok);
  }
  EXPECT_TRUE(mjukf.parameters().allFinite());
  EXPECT_LT((mjukf.state() - implicitMjukf.state()).cwiseAbs().maxCoeff(), 1e-4);

  using TankF = models::CoupledTank<float>;
  UkfSettingsFor<TankF> ukfSettings;
  ukfSettings.initialCovariance = Eigen::Vector2f(1, 1).asDiagonal();
  ukfSettings.processNoise = Eigen::Vector2f(1e-6f, 1e-6f).asDiagonal();
  ukfSettings.measurementNoise = Eigen::Vector2f(1e-2f, 1e-2f).asDiagonal();
  Ukf<TankF, ExplicitTrBdf2<float>> ukf(TankF(), TankF::State::Zero(), TankF::trueParameters(), ukfSettings);
  for (int k = 0; k < 100; ++k) {
    ASSERT_EQ(ukf.timeUpdate(float(k) * 0.01f, 0.01f), Status::Ok);
    ASSERT_EQ(ukf.measurementUpdate(TankF::Meas::Zero()), Status::Ok);
  }
  EXPECT_TRUE(ukf.state().allFinite());
}

}  // namespace
