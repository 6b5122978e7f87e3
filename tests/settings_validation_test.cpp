// Wrong settings fail at construction with std::invalid_argument whose message names the setting.
// (Wrong sizes cannot be written: every matrix in the settings is sized at compile time from the model.)

#include <limits>
#include <type_traits>
#include <string>

#include <gtest/gtest.h>

#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/paper/experiments.hpp"

namespace {

using Robot = mjukf::paper::FlexibleJointExperiment<double>;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// Runs `construct` and expects std::invalid_argument mentioning `setting`.
template <class Construct>
void expectRejected(Construct&& construct, const std::string& setting) {
  try {
    construct();
    ADD_FAILURE() << "accepted a bad '" << setting << "'";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(setting), std::string::npos) << "message: " << e.what();
  }
}

template <class Settings, class Mutate>
void expectJointRejected(Mutate&& mutate, const std::string& setting) {
  Settings s = Robot::jointUkf();
  mutate(s);
  expectRejected([&] { mjukf::JointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s); },
                 setting);
}

template <class Mutate>
void expectModifiedRejected(Mutate&& mutate, const std::string& setting) {
  auto s = Robot::modifiedJointUkf();
  mutate(s);
  expectRejected(
      [&] { mjukf::ModifiedJointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s); },
      setting);
}

using JointSettings = mjukf::JointUkfSettings<Robot::Model>;

TEST(SettingsValidation, PaperSettingsAreAccepted) {
  EXPECT_NO_THROW(mjukf::Ukf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::Model::trueParameters(),
                                           Robot::ukf()));
  EXPECT_NO_THROW(mjukf::JointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(),
                                                Robot::jointUkf()));
  EXPECT_NO_THROW(mjukf::ModifiedJointUkf<Robot::Model>(Robot::Model(), Robot::initialState(),
                                                        Robot::initialParameters(), Robot::modifiedJointUkf()));
}

TEST(SettingsValidation, InitialCovarianceMustBeSymmetricPositiveDefinite) {
  expectJointRejected<JointSettings>([](auto& s) { s.initialCovariance(0, 1) = 0.1; }, "initialCovariance");
  expectJointRejected<JointSettings>([](auto& s) { s.initialCovariance(2, 2) = -0.5; }, "initialCovariance");
  expectJointRejected<JointSettings>([](auto& s) { s.initialCovariance(5, 5) = 0.0; }, "initialCovariance");
  expectJointRejected<JointSettings>([](auto& s) { s.initialCovariance(1, 1) = kNan; }, "initialCovariance");
  // Symmetric, positive diagonal, but indefinite: correlation above 1.
  expectJointRejected<JointSettings>([](auto& s) { s.initialCovariance(0, 1) = s.initialCovariance(1, 0) = 0.6; },
                                     "initialCovariance");
  expectModifiedRejected([](auto& s) { s.initialCovariance.setZero(); }, "initialCovariance");
}

TEST(SettingsValidation, ProcessNoiseMustBeSymmetricPositiveSemiDefinite) {
  expectJointRejected<JointSettings>([](auto& s) { s.processNoise(0, 0) = -1e-5; }, "processNoise");
  expectJointRejected<JointSettings>([](auto& s) { s.processNoise(0, 3) = 1e-6; }, "processNoise");
  expectJointRejected<JointSettings>([](auto& s) { s.processNoise(4, 4) = std::numeric_limits<double>::infinity(); },
                                     "processNoise");
  // Zero process noise is semi-definite and legal.
  JointSettings zeroQ = Robot::jointUkf();
  zeroQ.processNoise.setZero();
  EXPECT_NO_THROW(mjukf::JointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(), zeroQ));
}

TEST(SettingsValidation, MeasurementNoiseMustBeSymmetricPositiveDefinite) {
  expectJointRejected<JointSettings>([](auto& s) { s.measurementNoise.setZero(); }, "measurementNoise");
  expectJointRejected<JointSettings>([](auto& s) { s.measurementNoise(1, 2) = 1e-4; }, "measurementNoise");
  expectModifiedRejected([](auto& s) { s.measurementNoise(3, 3) = -1e-3; }, "measurementNoise");
}

// The checks are relative to the matrix's own scale: the tank's R is 1e-7, so an absolute tolerance
// would let a transposed or negative entry of that size through.
TEST(SettingsValidation, SmallMatricesAreCheckedRelativeToTheirScale) {
  using TankF = mjukf::paper::CoupledTankExperiment<float>;
  using TankD = mjukf::paper::CoupledTankExperiment<double>;
  auto reject = [](auto settings, const std::string& setting) {
    using Experiment = std::conditional_t<std::is_same_v<typename decltype(settings)::Scalar, float>, TankF, TankD>;
    expectRejected([&] { mjukf::ModifiedJointUkf<typename Experiment::Model>(typename Experiment::Model(),
                                                                           Experiment::initialState(),
                                                                           Experiment::initialParameters(), settings); },
                   setting);
  };
  auto asymmetricR = TankF::modifiedJointUkf();
  asymmetricR.measurementNoise(0, 1) = 5e-8f;
  reject(asymmetricR, "measurementNoise");
  auto indefiniteQ = TankF::modifiedJointUkf();
  indefiniteQ.processNoise(1, 1) = -5e-7f;
  reject(indefiniteQ, "processNoise");
  auto tinyIndefiniteR = TankD::modifiedJointUkf();
  tinyIndefiniteR.measurementNoise << 1e-16, 1e-14, 0.0, 1e-16;  // LLT alone would read only the lower triangle
  reject(tinyIndefiniteR, "measurementNoise");
  auto tinyValidR = TankD::modifiedJointUkf();
  tinyValidR.measurementNoise *= 1e-9;  // R = 1e-16 I is legal, however small
  EXPECT_NO_THROW(mjukf::ModifiedJointUkf<TankD::Model>(TankD::Model(), TankD::initialState(),
                                                         TankD::initialParameters(), tinyValidR));
}

TEST(SettingsValidation, SigmaPointScaling) {
  expectJointRejected<JointSettings>([](auto& s) { s.sigmaPoints.alpha = 0.0; }, "alpha");
  expectJointRejected<JointSettings>([](auto& s) { s.sigmaPoints.alpha = kNan; }, "alpha");
  expectJointRejected<JointSettings>([](auto& s) { s.sigmaPoints.kappa = -6.0; }, "kappa");  // L + λ = 0 for L = 6
  expectModifiedRejected([](auto& s) { s.sigmaPoints.kappa = -4.5; }, "kappa");             // L + λ < 0 for L = 4
  expectModifiedRejected([](auto& s) { s.sigmaPoints.beta = kNan; }, "beta");
}

TEST(SettingsValidation, ModifiedJointSettings) {
  expectModifiedRejected([](auto& s) { s.transformation(0, 0) = 0.4; }, "transformation");  // row sums to 1.1
  expectModifiedRejected([](auto& s) { s.transformation = s.transformation.reverse().eval(); s.transformation(1, 3) = 0.5; },
                         "transformation");
  expectModifiedRejected([](auto& s) { s.transformation(1, 1) = kNan; }, "transformation");
  expectModifiedRejected([](auto& s) { s.scaling = kNan; }, "scaling");
  expectModifiedRejected([](auto& s) { s.parameterSpread(1) = std::numeric_limits<double>::infinity(); },
                         "parameterSpread");
}

TEST(SettingsValidation, InitialValuesMustBeFinite) {
  Robot::State x0 = Robot::initialState();
  x0(2) = kNan;
  expectRejected([&] { mjukf::JointUkf<Robot::Model>(Robot::Model(), x0, Robot::initialParameters(), Robot::jointUkf()); },
                 "initialState");
  Robot::Param theta0 = Robot::initialParameters();
  theta0(1) = kNan;
  expectRejected(
      [&] { mjukf::ModifiedJointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), theta0, Robot::modifiedJointUkf()); },
      "initialParameters");
  expectRejected([&] { mjukf::Ukf<Robot::Model>(Robot::Model(), Robot::initialState(), theta0, Robot::ukf()); },
                 "parameters");
}

TEST(SettingsValidation, IntegratorGamma) {
  expectRejected([] { (void)mjukf::ITrBdf2<double>{0.0}; }, "gamma");
  expectRejected([] { (void)mjukf::ITrBdf2<double>{1.0}; }, "gamma");
  expectRejected([] { (void)mjukf::ITrBdf2<double>{kNan}; }, "gamma");
  EXPECT_NO_THROW(mjukf::ITrBdf2<double>(2.0 - std::sqrt(2.0)));
}

}  // namespace
