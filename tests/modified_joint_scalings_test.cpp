// The hand-tuned MJUKF for sensitivities of any sign (modified_joint_ukf.hpp, docs/tuning-mjukf.md): one
// ξ per parameter, and signed rows of T with Σⱼ |tᵣⱼ| = 1. Eq. 9 moves θᵣ by −ξᵣ Σⱼ tᵣⱼ (yⱼ − Yᵢⱼ), so
// the sign may sit in ξᵣ or in T's row: both give the same filter, and either makes a parameter that
// lowers its measurement converge where the paper's one ξ with T ≥ 0 drives it away.

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "mjukf/integrators/rk4.hpp"
#include "mjukf/modified_joint_ukf.hpp"

namespace {

// Two first-order lags driven by the same input: θ₁ raises y₁, θ₂ lowers y₂ (∂y₁/∂θ₁ > 0 > ∂y₂/∂θ₂).
struct OppositeLags {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 2, MeasDim = 2, InputDim = 1;
  using State = Eigen::Matrix<double, 2, 1>;
  using Param = Eigen::Matrix<double, 2, 1>;
  using Meas = Eigen::Matrix<double, 2, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
  State derivative(double, const State& x, const Input& u, const Param& theta) const {
    return State(-x(0) + theta(0) * u(0), -x(1) - theta(1) * u(0));
  }
  Meas measurement(const State& x, const Param&) const { return x; }
  Input input(double t) const { return Input(1.0 + 0.5 * std::sin(2.0 * t)); }
};

using Filter = mjukf::ModifiedJointUkf<OppositeLags, mjukf::Rk4<double>>;
const OppositeLags::Param kTruth(2.0, 3.0);
const OppositeLags::Param kGuess(1.0, 2.0);
constexpr double kStep = 0.01;

Filter::Settings settingsWith(const Filter::Settings::Transformation& t, const Filter::Param& xi) {
  Filter::Settings s;
  s.initialCovariance.diagonal().setConstant(1e-4);
  s.processNoise.diagonal().setConstant(1e-8);
  s.measurementNoise.diagonal().setConstant(1e-6);
  s.transformation = t;
  s.scaling = xi;
  s.parameterSpread.setConstant(1e-3);
  return s;
}

// Runs `filter` for `seconds` over noise-free measurements of the true plant; the final θ̂.
Filter::Param run(Filter& filter, double seconds) {
  const OppositeLags plant;
  const mjukf::Rk4<double> rk4;
  OppositeLags::State x = OppositeLags::State::Zero();
  const int steps = int(std::lround(seconds / kStep));
  for (int k = 0; k < steps; ++k) {
    x = mjukf::stepModel(
        plant, rk4, k * kStep, kStep, x, [&](double t) { return plant.input(t); }, kTruth);
    EXPECT_TRUE(mjukf::taken(filter.timeUpdate(k * kStep, kStep)));
    EXPECT_TRUE(mjukf::taken(filter.measurementUpdate(plant.measurement(x, kTruth))));
  }
  return filter.parameters();
}

TEST(ModifiedJointScalings, OneNumberSetsEveryParametersScaling) {
  Filter::Settings s;
  s.scaling = -0.25;
  EXPECT_EQ(s.scaling(0), -0.25);
  EXPECT_EQ(s.scaling(1), -0.25);
  s.scaling << -0.5, 0.125;
  EXPECT_EQ(s.scaling(0), -0.5);
  EXPECT_EQ(s.scaling(1), 0.125);
}

TEST(ModifiedJointScalings, SignInScalingOrInTransformationIsTheSameFilter) {
  Filter::Settings::Transformation identity = Filter::Settings::Transformation::Identity();
  Filter::Settings::Transformation signedRow = identity;
  signedRow(1, 1) = -1;
  Filter perParameter(OppositeLags(), OppositeLags::State::Zero(), kGuess, settingsWith(identity, {-0.3, 0.3}));
  Filter signedT(OppositeLags(), OppositeLags::State::Zero(), kGuess, settingsWith(signedRow, {-0.3, -0.3}));
  const Filter::Param a = run(perParameter, 2.0);
  const Filter::Param b = run(signedT, 2.0);
  EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(double) * 2), 0) << a.transpose() << " | " << b.transpose();
  EXPECT_EQ(std::memcmp(perParameter.state().data(), signedT.state().data(), sizeof(double) * 2), 0);
}

TEST(ModifiedJointScalings, OppositeSignSensitivitiesConvergeWithSignedSteps) {
  const Filter::Settings::Transformation identity = Filter::Settings::Transformation::Identity();
  // ξ₂ of the sign of ∂y₂/∂θ₂ < 0: ξ₂ (T ψ)₂₂ < 0 with T = I takes ξ₂ > 0.
  Filter right(OppositeLags(), OppositeLags::State::Zero(), kGuess, settingsWith(identity, {-0.3, 0.3}));
  const Filter::Param found = run(right, 20.0);
  // Noise-free: the error is what remains of the start after 20 s, far below 1 % of each parameter.
  EXPECT_NEAR(found(0), kTruth(0), 0.01 * kTruth(0));
  EXPECT_NEAR(found(1), kTruth(1), 0.01 * kTruth(1));
  // The paper's one ξ < 0 with T ≥ 0 moves θ₂ away from the truth.
  Filter one(OppositeLags(), OppositeLags::State::Zero(), kGuess, settingsWith(identity, {-0.3, -0.3}));
  const Filter::Param away = run(one, 2.0);
  EXPECT_NEAR(away(0), kTruth(0), std::abs(kGuess(0) - kTruth(0)));
  EXPECT_GT(std::abs(away(1) - kTruth(1)), std::abs(kGuess(1) - kTruth(1)));
}

}  // namespace
