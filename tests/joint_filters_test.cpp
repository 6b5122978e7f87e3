// JUKF (docs/algorithms.md §4) and MJUKF (§5): model propagations per time update, and each filter checked
// against an independent construction of the same step.

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "mjukf/joint_ukf.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/simulation.hpp"
#include "mjukf/ukf.hpp"
#include "paper/experiments.hpp"
#include "test_support.hpp"

namespace {

using mjukf::Status;
using Robot = mjukf::paper::FlexibleJointExperiment<double>;
using Tank = mjukf::paper::CoupledTankExperiment<double>;
using Counting = mjukf::testing::CountingStepper<mjukf::ITrBdf2<double>>;

// Counts the integrator steps of each kind of call; one step of one point is one model propagation.
template <class Filter, class Experiment>
void expectPropagationCounts(Filter filter, long* steps, long perTimeUpdate) {
  const typename Experiment::Model::Meas y = Experiment::Model::Meas::Constant(0.1);
  *steps = 0;
  ASSERT_EQ(filter.timeUpdate(0.0, 1e-3), Status::Ok);
  EXPECT_EQ(*steps, perTimeUpdate);
  *steps = 0;
  ASSERT_EQ(filter.measurementUpdate(y), Status::Ok);
  EXPECT_EQ(*steps, 0);
  *steps = 0;
  ASSERT_EQ(filter.timeUpdate(1e-3, 1e-3, 3), Status::Ok);  // three integrator steps per point
  EXPECT_EQ(*steps, 3 * perTimeUpdate);
  *steps = 0;
  ASSERT_EQ(filter.propagateMean(4e-3, 1e-3), Status::Ok);
  EXPECT_EQ(*steps, 1);
}

template <class Experiment>
void expectPaperCounts(long jointPoints, long modifiedPoints) {
  using Model = typename Experiment::Model;
  long steps = 0;
  const Counting stepper{mjukf::ITrBdf2<double>(), &steps};
  // The filters' own propagations: the step check's (step_check_test.cpp counts those) turned off.
  const auto unchecked = [](auto settings) {
    settings.stepCheck.onOversized = mjukf::OversizedStep::Accept;
    return settings;
  };
  expectPropagationCounts<mjukf::JointUkf<Model, Counting>, Experiment>(
      {Model(), Experiment::initialState(), Experiment::initialParameters(), unchecked(Experiment::jointUkf()),
       stepper},
      &steps, jointPoints);
  expectPropagationCounts<mjukf::ModifiedJointUkf<Model, Counting>, Experiment>(
      {Model(), Experiment::initialState(), Experiment::initialParameters(), unchecked(Experiment::modifiedJointUkf()),
       stepper},
      &steps, modifiedPoints);
  expectPropagationCounts<mjukf::Ukf<Model, Counting>, Experiment>(
      {Model(), Experiment::initialState(), Model::trueParameters(), unchecked(Experiment::ukf()), stepper}, &steps,
      modifiedPoints);
}

TEST(JointFilters, RobotPropagationsPerTimeUpdate) {
  // n = 4, p = 2: JUKF 2(n + p) + 1 = 13, MJUKF and UKF 2n + 1 = 9.
  expectPaperCounts<Robot>(13, 9);
}

TEST(JointFilters, TankPropagationsPerTimeUpdate) {
  // n = 2, p = 1: JUKF 7, MJUKF and UKF 5.
  expectPaperCounts<Tank>(7, 5);
}

// Explicit Euler: x + h f(t, x) leaves a component with zero derivative bit for bit unchanged, so an
// augmented model with θ̇ = 0 integrates exactly like the JUKF's split propagation.
using Euler = mjukf::testing::Euler<double>;

// The robot with its parameters appended to the state, θ̇ = 0: a UKF on it is a JUKF by definition.
struct AugmentedRobot {
  using Robot = mjukf::models::FlexibleJoint<double>;
  using Scalar = double;
  static constexpr int StateDim = 6, ParamDim = 0, MeasDim = 4, InputDim = 1;
  using State = Eigen::Matrix<double, 6, 1>;
  using Param = Eigen::Matrix<double, 0, 1>;
  using Meas = Robot::Meas;
  using Input = Robot::Input;
  Robot robot;
  Input input(double t) const { return robot.input(t); }
  State derivative(double t, const State& z, const Input& u, const Param&) const {
    State dz = State::Zero();
    dz.head<4>() = robot.derivative(t, z.head<4>(), u, z.tail<2>());
    return dz;
  }
  Meas measurement(const State& z, const Param&) const { return robot.measurement(z.head<4>(), z.tail<2>()); }
};

TEST(JointFilters, JointUkfEqualsUkfOnTheAugmentedModel) {
  const auto jointSettings = Robot::jointUkf();
  mjukf::UkfSettingsFor<AugmentedRobot> augmentedSettings;
  augmentedSettings.initialCovariance = jointSettings.initialCovariance;
  augmentedSettings.processNoise = jointSettings.processNoise;
  augmentedSettings.measurementNoise = jointSettings.measurementNoise;
  mjukf::JointUkf<Robot::Model, Euler> joint(Robot::Model(), Robot::initialState(), Robot::initialParameters(),
                                             jointSettings);
  AugmentedRobot::State z0;
  z0 << Robot::initialState(), Robot::initialParameters();
  mjukf::Ukf<AugmentedRobot, Euler> augmented(AugmentedRobot(), z0, AugmentedRobot::Param(), augmentedSettings);

  const double h = 1e-3;
  for (int k = 0; k < 200; ++k) {
    const double t = k * h;
    const Robot::Model::Meas y(std::sin(t), std::cos(t), 0.5 * std::sin(t), 0.1);
    if ((k + 1) % 5 == 0) {
      ASSERT_EQ(joint.timeUpdate(t, h), Status::Ok);
      ASSERT_EQ(augmented.timeUpdate(t, h), Status::Ok);
      ASSERT_EQ(joint.measurementUpdate(y), Status::Ok);
      ASSERT_EQ(augmented.measurementUpdate(y), Status::Ok);
    } else {
      ASSERT_EQ(joint.propagateMean(t, h), Status::Ok);
      ASSERT_EQ(augmented.propagateMean(t, h), Status::Ok);
    }
    ASSERT_LT((joint.augmentedState() - augmented.state()).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
    ASSERT_LT((joint.covariance() - augmented.covariance()).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
  }
  EXPECT_GT((joint.parameters() - Robot::initialParameters()).norm(), 1e-4) << "the parameters never moved";
}

TEST(JointFilters, JointUkfOpenLoopLeavesParametersAndCovarianceAlone) {
  mjukf::JointUkf<Robot::Model> joint(Robot::Model(), Robot::initialState(), Robot::initialParameters(),
                                      Robot::jointUkf());
  const auto P = joint.covariance();
  ASSERT_EQ(joint.propagateMean(0.1, 1e-3, 10), Status::Ok);
  EXPECT_EQ(joint.parameters(), Robot::initialParameters());
  EXPECT_EQ(joint.covariance(), P);
  EXPECT_NE(joint.state(), Robot::initialState());  // the sine input moved the motor
}

TEST(JointFilters, ModifiedJointUkfStartsWithEquation8) {
  auto settings = Robot::modifiedJointUkf();
  settings.parameterSpread << 0.01, 0.02;
  mjukf::ModifiedJointUkf<Robot::Model> filter(Robot::Model(), Robot::initialState(), Robot::initialParameters(),
                                               settings);
  // θᵢ = θ̂₀ − p_θ (n + 1) + p_θ (i + 1) = θ̂₀ + p_θ (i − n), n = 4.
  for (int i = 0; i < 9; ++i) {
    EXPECT_NEAR(filter.parameterPoints()(0, i), 0.1 + 0.01 * (i - 4), 1e-15);
    EXPECT_NEAR(filter.parameterPoints()(1, i), 0.15 + 0.02 * (i - 4), 1e-15);
  }
  EXPECT_EQ(filter.parameters(), Robot::initialParameters());
}

// One MJUKF step rebuilt from the public pieces: draw the state points, propagate each with its θᵢ,
// correct the state (§3), move each θᵢ by eq. 9 and average them (eq. 10).
TEST(JointFilters, ModifiedJointUkfStepMatchesEquations9And10) {
  using Model = Robot::Model;
  const Model model;
  const auto settings = Robot::modifiedJointUkf();
  const Model::State x0(0.1, -0.2, 0.05, 0.3);
  mjukf::ModifiedJointUkf<Model> filter(model, x0, Robot::initialParameters(), settings);
  const auto thetaPoints = filter.parameterPoints();
  const double t = 0.2, h = 1e-3;
  const Model::Meas y(0.12, -0.1, 0.07, 0.2);
  ASSERT_EQ(filter.timeUpdate(t, h), Status::Ok);
  ASSERT_EQ(filter.measurementUpdate(y), Status::Ok);

  mjukf::MerweScaledSigmaPoints<double, 4> sigma(settings.sigmaPoints);
  mjukf::MerweScaledSigmaPoints<double, 4>::Points points;
  ASSERT_EQ(sigma.generate(x0, settings.initialCovariance, points), Status::Ok);
  const mjukf::ITrBdf2<double> stepper;
  for (int i = 0; i < 9; ++i) {
    const Model::Param theta = thetaPoints.col(i);
    points.col(i) = mjukf::stepModel(model, stepper, t, h, Model::State(points.col(i)), theta);
  }
  const auto& wm = sigma.meanWeights();
  const auto& wc = sigma.covarianceWeights();
  const Model::State xPred = points * wm;
  Eigen::Matrix4d PPred = settings.processNoise, Pyy = settings.measurementNoise, Pxy = Eigen::Matrix4d::Zero();
  const Model::Meas yPred = points * wm;  // g(x, θ) = x
  for (int i = 0; i < 9; ++i) {
    PPred += wc(i) * (points.col(i) - xPred) * (points.col(i) - xPred).transpose();
    Pyy += wc(i) * (points.col(i) - yPred) * (points.col(i) - yPred).transpose();
    Pxy += wc(i) * (points.col(i) - xPred) * (points.col(i) - yPred).transpose();
  }
  const Eigen::Matrix4d K = Pxy * Pyy.inverse();
  EXPECT_LT((filter.state() - (xPred + K * (y - yPred))).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LT((filter.covariance() - (PPred - K * Pyy * K.transpose())).cwiseAbs().maxCoeff(), 1e-12);

  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (int i = 0; i < 9; ++i) {
    const Eigen::Vector2d expected =
        Robot::initialParameters() - settings.scaling.asDiagonal() * settings.transformation * (y - points.col(i));
    EXPECT_LT((filter.parameterPoints().col(i) - expected).cwiseAbs().maxCoeff(), 1e-14) << "point " << i;
    sum += expected;
  }
  EXPECT_LT((filter.parameters() - sum / 9.0).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_GT((filter.parameters() - Robot::initialParameters()).norm(), 1e-6) << "eq. 9 moved nothing";
}

// With ξ = 0 and p_θ = 0 every θᵢ stays θ̂ and the MJUKF is a UKF with known parameters.
TEST(JointFilters, ModifiedJointUkfWithFrozenParametersIsTheUkf) {
  auto settings = Tank::modifiedJointUkf();
  settings.scaling = 0.0;
  settings.parameterSpread.setZero();
  const Tank::Param theta = Tank::Model::trueParameters();
  mjukf::ModifiedJointUkf<Tank::Model> modified(Tank::Model(), Tank::initialState(), theta, settings);
  mjukf::Ukf<Tank::Model> ukf(Tank::Model(), Tank::initialState(), theta, Tank::ukf());
  for (int k = 0; k < 100; ++k) {
    const double t = k * 1e-3;
    const Tank::Model::Meas y(0.01 * k, 0.002 * k);
    ASSERT_EQ(modified.timeUpdate(t, 1e-3), Status::Ok);
    ASSERT_EQ(ukf.timeUpdate(t, 1e-3), Status::Ok);
    ASSERT_EQ(modified.measurementUpdate(y), Status::Ok);
    ASSERT_EQ(ukf.measurementUpdate(y), Status::Ok);
  }
  EXPECT_EQ(modified.state(), ukf.state());
  EXPECT_EQ(modified.covariance(), ukf.covariance());
  EXPECT_EQ(modified.parameters(), theta);
}

}  // namespace
