// Wrong settings fail at construction with std::invalid_argument whose message names the setting.
// (Wrong sizes cannot be written: every matrix in the settings is sized at compile time from the model.)

#include <limits>
#include <string>
#include <type_traits>

#include <gtest/gtest.h>

#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "paper/experiments.hpp"

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
  expectRejected(
      [&] { mjukf::JointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s); },
      setting);
}

template <class Mutate>
void expectModifiedRejected(Mutate&& mutate, const std::string& setting) {
  auto s = Robot::modifiedJointUkf();
  mutate(s);
  expectRejected(
      [&] {
        mjukf::ModifiedJointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s);
      },
      setting);
}

template <class Mutate>
void expectDualRejected(Mutate&& mutate, const std::string& setting,
                        const Robot::Param& initialParameters = Robot::initialParameters()) {
  auto s = Robot::dualUkf();
  mutate(s);
  expectRejected([&] { mjukf::DualUkf<Robot::Model>(Robot::Model(), Robot::initialState(), initialParameters, s); },
                 setting);
}

using JointSettings = mjukf::JointUkfSettingsFor<Robot::Model>;

TEST(SettingsValidation, PaperSettingsAreAccepted) {
  EXPECT_NO_THROW(
      mjukf::Ukf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::Model::trueParameters(), Robot::ukf()));
  EXPECT_NO_THROW(mjukf::JointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(),
                                                Robot::jointUkf()));
  EXPECT_NO_THROW(mjukf::ModifiedJointUkf<Robot::Model>(Robot::Model(), Robot::initialState(),
                                                        Robot::initialParameters(), Robot::modifiedJointUkf()));
  EXPECT_NO_THROW(mjukf::DualUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(),
                                               Robot::dualUkf()));
  using Tank = mjukf::paper::CoupledTankExperiment<double>;
  EXPECT_NO_THROW(
      mjukf::DualUkf<Tank::Model>(Tank::Model(), Tank::initialState(), Tank::initialParameters(), Tank::dualUkf()));
  using TankF = mjukf::paper::CoupledTankExperiment<float>;
  EXPECT_NO_THROW(mjukf::DualUkf<TankF::Model>(TankF::Model(), TankF::initialState(), TankF::initialParameters(),
                                               TankF::dualUkf()));
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
  EXPECT_NO_THROW(
      mjukf::JointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(), zeroQ));
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
    expectRejected(
        [&] {
          mjukf::ModifiedJointUkf<typename Experiment::Model>(typename Experiment::Model(), Experiment::initialState(),
                                                              Experiment::initialParameters(), settings);
        },
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
  expectModifiedRejected([](auto& s) { s.sigmaPoints.kappa = -4.5; }, "kappa");              // L + λ < 0 for L = 4
  expectModifiedRejected([](auto& s) { s.sigmaPoints.beta = kNan; }, "beta");
}

TEST(SettingsValidation, ModifiedJointSettings) {
  expectModifiedRejected([](auto& s) { s.transformation(0, 0) = 0.4; }, "transformation");  // row sums to 1.1
  expectModifiedRejected(
      [](auto& s) {
        s.transformation = s.transformation.reverse().eval();
        s.transformation(1, 3) = 0.5;
      },
      "transformation");
  expectModifiedRejected([](auto& s) { s.transformation(1, 1) = kNan; }, "transformation");
  expectModifiedRejected([](auto& s) { s.scaling = kNan; }, "scaling");
  expectModifiedRejected([](auto& s) { s.scaling(1) = kNan; }, "scaling");  // one parameter's ξ
  // Signed entries: the magnitudes of a row sum to 1, not the entries. A row of 0.6, −0.4 sums to 0.2
  // and its magnitudes to 1 (accepted below); 0.6, −0.6 sums to 0 and its magnitudes to 1.2.
  expectModifiedRejected(
      [](auto& s) {
        s.transformation.row(0).setZero();
        s.transformation(0, 0) = 0.6;
        s.transformation(0, 1) = -0.6;
      },
      "transformation");
}

TEST(SettingsValidation, ModifiedJointSignedTransformationAndPerParameterScalingAreAccepted) {
  auto s = Robot::modifiedJointUkf();
  s.transformation.row(0).setZero();
  s.transformation(0, 0) = 0.6;
  s.transformation(0, 1) = -0.4;
  s.scaling << -0.002, 0.003;
  EXPECT_FALSE(mjukf::ModifiedJointUkf<Robot::Model>::validate(Robot::initialState(), Robot::initialParameters(), s));
  expectModifiedRejected([](auto& s) { s.parameterSpread(1) = std::numeric_limits<double>::infinity(); },
                         "parameterSpread");
}

// The MJUKF's Q_θ (parameterProcessNoise): symmetric positive semi-definite, and zero where the filter
// does not follow the covariance of θ̂ (the paper preset: a Q_θ there would change nothing, so it is
// refused by name rather than ignored).
TEST(SettingsValidation, ModifiedJointParameterProcessNoise) {
  expectModifiedRejected([](auto& s) { s.parameterProcessNoise(0, 0) = 1e-6; }, "parameterProcessNoise");
  const auto followed = [](auto& s) { s.followParameterCovariance = true; };
  expectModifiedRejected(
      [&](auto& s) {
        followed(s);
        s.parameterProcessNoise(0, 0) = -1e-6;
      },
      "parameterProcessNoise");
  expectModifiedRejected(
      [&](auto& s) {
        followed(s);
        s.parameterProcessNoise(0, 1) = 1e-6;  // not symmetric
      },
      "parameterProcessNoise");
  auto s = Robot::modifiedJointUkf();
  followed(s);
  s.parameterProcessNoise.diagonal().setConstant(1e-6);
  EXPECT_FALSE(mjukf::ModifiedJointUkf<Robot::Model>::validate(Robot::initialState(), Robot::initialParameters(), s));
}

TEST(SettingsValidation, InitialValuesMustBeFinite) {
  Robot::State x0 = Robot::initialState();
  x0(2) = kNan;
  expectRejected(
      [&] { mjukf::JointUkf<Robot::Model>(Robot::Model(), x0, Robot::initialParameters(), Robot::jointUkf()); },
      "initialState");
  Robot::Param theta0 = Robot::initialParameters();
  theta0(1) = kNan;
  expectRejected(
      [&] {
        mjukf::ModifiedJointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), theta0, Robot::modifiedJointUkf());
      },
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

// The dual filter's own settings, each named in the message; the shared ones (those of its state
// filter) as for the other filters.
TEST(SettingsValidation, DualUkfParameterFilterSettings) {
  // P^θ₀: symmetric positive definite. The default (zero) is not.
  expectDualRejected([](auto& s) { s.initialParameterCovariance.setZero(); }, "initialParameterCovariance");
  expectDualRejected([](auto& s) { s.initialParameterCovariance(1, 1) = -1e-3; }, "initialParameterCovariance");
  expectDualRejected([](auto& s) { s.initialParameterCovariance(0, 1) = 1e-4; }, "initialParameterCovariance");
  expectDualRejected([](auto& s) { s.initialParameterCovariance(0, 0) = kNan; }, "initialParameterCovariance");
  expectDualRejected([](auto& s) { s.initialParameterCovariance(0, 1) = s.initialParameterCovariance(1, 0) = 2e-3; },
                     "initialParameterCovariance");  // correlation 2: indefinite
  // Q_θ and the observation noise: symmetric positive semi-definite.
  expectDualRejected([](auto& s) { s.parameterProcessNoise(0, 0) = -1e-5; }, "parameterProcessNoise");
  expectDualRejected([](auto& s) { s.parameterProcessNoise(1, 0) = 1e-6; }, "parameterProcessNoise");
  expectDualRejected([](auto& s) { s.parameterProcessNoise(1, 1) = kNan; }, "parameterProcessNoise");
  expectDualRejected([](auto& s) { s.parameterProcessNoise(0, 1) = s.parameterProcessNoise(1, 0) = 1e-4; },
                     "parameterProcessNoise");  // symmetric, eigenvalues 1e-5 ± 1e-4
  expectDualRejected([](auto& s) { s.parameterObservationNoise(2, 2) = -0.05; }, "parameterObservationNoise");
  expectDualRejected([](auto& s) { s.parameterObservationNoise(0, 3) = 0.01; }, "parameterObservationNoise");
  expectDualRejected([](auto& s) { s.parameterObservationNoise(1, 1) = std::numeric_limits<double>::infinity(); },
                     "parameterObservationNoise");
  // λ ∈ (0, 1].
  for (const double lambda : {0.0, -0.5, 1.0 + 1e-12, 2.0, kNan, std::numeric_limits<double>::infinity()})
    expectDualRejected([lambda](auto& s) { s.parameterForgetting = lambda; }, "parameterForgetting");
  // The first guess within the bounds, and the bounds themselves.
  expectDualRejected([](auto& s) { s.parameterBounds.lower << 0.12, 0.0; }, "initialParameters");
  expectDualRejected([](auto& s) { s.parameterBounds.upper << 1.0, 0.14; }, "initialParameters");
  expectDualRejected(
      [](auto& s) {
        s.parameterBounds.lower << 0.2, 0.0;
        s.parameterBounds.upper << 0.1, 1.0;
      },
      "parameterBounds");
  expectDualRejected([](auto& s) { s.parameterBounds.upper(1) = kNan; }, "parameterBounds");
  // The initial values.
  expectDualRejected([](auto&) {}, "initialParameters", Robot::Param(0.1, kNan));
  Robot::State x0 = Robot::initialState();
  x0(1) = kNan;
  auto valid = Robot::dualUkf();
  expectRejected([&] { mjukf::DualUkf<Robot::Model>(Robot::Model(), x0, Robot::initialParameters(), valid); },
                 "initialState");
  // The parameter filter's sigma points.
  expectDualRejected([](auto& s) { s.parameterSigmaPoints.alpha = 0.0; }, "alpha");
  expectDualRejected([](auto& s) { s.parameterSigmaPoints.kappa = -2.0; }, "kappa");  // L + λ = 0 for L = p = 2
}

TEST(SettingsValidation, DualUkfSharedSettings) {
  expectDualRejected([](auto& s) { s.initialCovariance.setZero(); }, "initialCovariance");
  expectDualRejected([](auto& s) { s.initialCovariance(0, 1) = 0.1; }, "initialCovariance");
  expectDualRejected([](auto& s) { s.initialCovariance(3, 3) = -0.5; }, "initialCovariance");
  expectDualRejected([](auto& s) { s.processNoise(2, 2) = -1e-5; }, "processNoise");
  expectDualRejected([](auto& s) { s.processNoise(0, 3) = 1e-6; }, "processNoise");
  expectDualRejected([](auto& s) { s.measurementNoise.setZero(); }, "measurementNoise");
  expectDualRejected([](auto& s) { s.measurementNoise(1, 2) = 1e-4; }, "measurementNoise");
  expectDualRejected([](auto& s) { s.sigmaPoints.kappa = -4.0; }, "kappa");  // L + λ = 0 for L = n = 4
  expectDualRejected([](auto& s) { s.repair.maxAttempts = -1; }, "repair.maxAttempts");
  expectDualRejected([](auto& s) { s.gate.nisThreshold(0) = 0.0; }, "gate.nisThreshold");
}

// The limits of the dual filter's settings are legal: Q_θ = 0, no observation noise beyond R (the
// defaults), λ = 1 and a small λ, bounds touching the first guess.
TEST(SettingsValidation, DualUkfLimitsAreAccepted) {
  const auto make = [](const mjukf::DualUkfSettingsFor<Robot::Model>& s) {
    return mjukf::DualUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s);
  };
  auto s = Robot::dualUkf();
  s.parameterProcessNoise.setZero();
  s.parameterObservationNoise.setZero();
  EXPECT_NO_THROW(make(s));
  s.parameterForgetting = 1.0;
  EXPECT_NO_THROW(make(s));
  s.parameterForgetting = 1e-3;
  EXPECT_NO_THROW(make(s));
  s.parameterBounds.lower = Robot::initialParameters();
  s.parameterBounds.upper = Robot::initialParameters();
  EXPECT_NO_THROW(make(s));
  s = Robot::dualUkf();
  s.parameterProcessNoise << 1e-5, 1e-5, 1e-5, 1e-5;  // singular, positive semi-definite
  EXPECT_NO_THROW(make(s));
}

}  // namespace
