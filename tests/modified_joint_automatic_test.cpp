// MJUKF's automatic modes (docs/tuning-mjukf.md): T from the sensitivities (eqs. 14–15) against the
// analytic one on the tank, convergence and tracking with the one default knob, validation of the
// new settings, and the paper's defaults untouched.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/experiment.hpp"
#include "gallery/experiments.hpp"
#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/models/van_der_pol.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/simulation.hpp"
#include "paper/experiments.hpp"
#include "paper/schedule.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace {

using mjukf::Status;
using Tank = mjukf::paper::CoupledTankExperiment<double>;
using Robot = mjukf::paper::FlexibleJointExperiment<double>;

template <class Settings>
Settings automatic(Settings s) {
  s.automaticTransformation = true;
  s.adaptiveScaling = true;
  return s;
}

// y_k = x_k + white noise of standard deviation `noise` per component (none for 0; drawn from `seed`), x
// from `simulate` with `parameterAt(k)`; the truth θ_k beside it.
template <class Model, class Integrator, class ParameterAt>
void simulateNoisy(const Model& model, const Integrator& integrator, const typename Model::State& x0,
                   ParameterAt&& parameterAt, double h, long steps, double noise, std::vector<typename Model::Meas>& y,
                   std::vector<typename Model::Param>& truth, unsigned seed = 7) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  y.resize(static_cast<std::size_t>(steps + 1));
  truth.resize(y.size());
  mjukf::simulate(model, integrator, x0, parameterAt, 0.0, h, steps, [&](long k, double, const auto& x) {
    for (int j = 0; j < Model::MeasDim; ++j)
      y[static_cast<std::size_t>(k)](j) = x(j) + (noise > 0 ? noise * normal(random) : 0.0);
    truth[static_cast<std::size_t>(k)] = parameterAt(k);
  });
}

// The tank: y = x and k_flow enters ḣ₁ = (k_flow u − c₁√h₁)/A₁ linearly. Differentiating the
// integrator's step by hand is the same as integrating the variational system ṡ = (∂f/∂x) s + ∂f/∂k
// beside x with the same explicit method (every stage is an affine combination of evaluations of f,
// and the chain rule goes through each), so this is the exact derivative of the filter's one-step
// map Φ_h at (x̂, θ₀), the point the filter differentiates about (sigma point 0 and its θ₀).
Eigen::Vector2d analyticTankSensitivity(const Tank::Model& m, const Eigen::Vector2d& x0, double k, double h) {
  using Augmented = Eigen::Vector4d;  // (h₁, h₂, ∂h₁/∂k, ∂h₂/∂k)
  const double u = m.pumpVoltage;
  const auto f = [&](double, const Augmented& z) {
    const double r1 = std::sqrt(z(0)), r2 = std::sqrt(z(1));
    Augmented dz;
    dz(0) = (k * u - m.orifice1 * r1) / m.area1;
    dz(1) = (m.orifice1 * r1 - m.orifice2 * r2) / m.area2;
    const double d11 = -m.orifice1 / (2 * r1 * m.area1);
    const double d21 = m.orifice1 / (2 * r1 * m.area2), d22 = -m.orifice2 / (2 * r2 * m.area2);
    dz(2) = d11 * z(2) + u / m.area1;
    dz(3) = d21 * z(2) + d22 * z(3);
    return dz;
  };
  const Augmented z0(x0(0), x0(1), 0, 0);
  const Augmented z1 = mjukf::ITrBdf2<double>().step(f, 0.0, z0, h);
  return z1.tail<2>();
}

TEST(AutomaticTransformation, EqualsTheAnalyticOneOnTheTank) {
  const Tank::Model model;
  const Eigen::Vector2d x0(5.0, 3.0);  // levels well above the orifices: √h smooth around every point
  const double h = Tank::stepSize;
  auto settings = Tank::modifiedJointUkf();
  settings.automaticTransformation = true;  // ξ stays the paper's −1
  mjukf::ModifiedJointUkf<Tank::Model> filter(model, x0, Tank::initialParameters(), settings);
  const double theta0 = filter.parameterPoints()(0, 0);
  ASSERT_EQ(filter.timeUpdate(0.0, h), Status::Ok);
  ASSERT_EQ(filter.measurementUpdate(Eigen::Vector2d(5.01, 3.0)), Status::Ok);

  const Eigen::Vector2d exact = analyticTankSensitivity(model, x0, theta0, h);
  // W⁻ = D = (Φ(x̂, θ₀ + δ) − Φ(x̂, θ₀)) / δ, then ψ = (g(x̂⁻ + δ W⁻) − g(x̂⁻)) / δ with g = x. Each
  // difference rounds by about ε max|x| / δ per evaluated state (a handful of operations of a few ulps
  // each: 8 ε |x| bounds it), δ = √ε max(|θ|, ...) ≥ √ε |θ₀|; truncation is δ/2 |∂²Φ/∂k²|, which is
  // O(h² u² / A²) × |∂²f/∂h₁²| ≈ 1e-7 × 1e-2 × δ: below the rounding. So |ψ − exact| ≤ 2 × 8 ε |x| / δ.
  const double eps = std::numeric_limits<double>::epsilon();
  const double delta = std::sqrt(eps) * std::abs(theta0);
  const double tolerance = 2 * 8 * eps * x0.cwiseAbs().maxCoeff() / delta;
  const Eigen::Vector2d psi = filter.sensitivity().measurementSensitivity().col(0);
  std::printf("psi (%.12g, %.12g), analytic (%.12g, %.12g), tolerance %.3g\n", psi(0), psi(1), exact(0), exact(1),
              tolerance);
  EXPECT_NEAR(psi(0), exact(0), tolerance);
  EXPECT_NEAR(psi(1), exact(1), tolerance);
  EXPECT_GT(exact(0), 100 * tolerance) << "the test would not see a wrong sensitivity";

  // Eq. 14: the row normalised, T = ψ̃ᵀ / Σ|ψ̃| with ψ̃ⱼ = ψⱼ / √Rⱼⱼ (R is a multiple of I here), so T's
  // error is at most 2 |ψ − exact|₁ / |exact|₁.
  const Eigen::RowVector2d expectedT = exact.transpose() / exact.cwiseAbs().sum();
  const double tTolerance = 2 * 2 * tolerance / exact.cwiseAbs().sum();
  EXPECT_NEAR(filter.transformation()(0, 0), expectedT(0), tTolerance);
  EXPECT_NEAR(filter.transformation()(0, 1), expectedT(1), tTolerance);
  EXPECT_NEAR(filter.transformation().row(0).sum(), 1.0, tTolerance);  // both sensitivities positive
  EXPECT_DOUBLE_EQ(filter.scalings()(0), -1.0);                        // adaptiveScaling off: the setting
}

// The sign convention (docs/tuning-mjukf.md): eq. 9 moves θ̂ by −ξ T (y − Ȳ), and y − Ȳ ≈ ψ (θ − θ̂)
// with ψ = ∂ŷ/∂θ̂, so θ̂ approaches θ when ξ (T ψ) < 0. On the tank T = [0.8 0.2] ≥ 0 and ψ > 0 (a larger
// k_flow fills the tanks faster): ξ = −1 (the paper's) must approach the truth from k̂ = 2, ξ = +1 must
// move away from it. Noise-free data, 20 s.
TEST(ScalingSign, NegativeXiForAMeasurementThatRisesWithTheParameter) {
  const Tank::Model model;
  const double h = Tank::stepSize;
  const long steps = 20000;
  std::vector<Tank::Model::Meas> y;
  std::vector<Tank::Param> truth;
  simulateNoisy(
      model, mjukf::ITrBdf2<double>(), Tank::initialState(), [](long) { return Tank::Model::trueParameters(); }, h,
      steps, 0.0, y, truth);
  const auto finalError = [&](double xi) {
    auto s = Tank::modifiedJointUkf();
    s.scaling = xi;
    mjukf::ModifiedJointUkf<Tank::Model> filter(model, Tank::initialState(), Tank::initialParameters(), s);
    const auto outcome = mjukf::paper::runSchedule(
        filter, steps + 1, h, Tank::measurementEvery,
        [&](long k) -> const Tank::Model::Meas& { return y[static_cast<std::size_t>(k)]; }, [](long, const auto&) {});
    return outcome.status == Status::Ok ? std::abs(filter.parameters()(0) - 6.0)
                                        : std::numeric_limits<double>::infinity();
  };
  const double start = std::abs(Tank::initialParameters()(0) - 6.0);  // 4
  const double negative = finalError(-1.0), positive = finalError(+1.0);
  std::printf("|k - 6| after 20 s: xi = -1: %.3g, xi = +1: %.3g (start %.3g)\n", negative, positive, start);
  EXPECT_LT(negative, 0.1 * start);
  EXPECT_GT(positive, start);
}

// Van der Pol (the 2019 paper's case): from μ̂₀ = 5 against μ = 0.2, noise 0.1 on both states. The
// automatic modes with their defaults must bring μ̂ to the truth; "converged" means the RMSE over the
// second half of the run is below 0.05, a quarter of μ itself (a filter that stays at μ̂₀ has 4.8, one
// that diverges is refused or far above).
TEST(AutomaticModes, ConvergeOnVanDerPol) {
  using Model = mjukf::models::VanDerPol<double>;
  using Integrator = mjukf::Rk4<double>;
  const Model model;
  const double h = 0.1;
  const long steps = 1000;
  std::vector<Model::Meas> y;
  std::vector<Model::Param> truth;
  simulateNoisy(
      model, Integrator(), Model::State(1.4, 0.0), [](long) { return Model::trueParameters(); }, h, steps, 0.1, y,
      truth);
  mjukf::ModifiedJointUkfSettingsFor<Model> s;
  s.initialCovariance.diagonal().setConstant(5);
  s.processNoise.diagonal().setConstant(1e-3);
  s.measurementNoise.diagonal().setConstant(0.1);
  s.parameterSpread << 0.5;
  mjukf::ModifiedJointUkf<Model, Integrator> filter(model, Model::State(0, 5), Model::Param(5.0), automatic(s));
  double sum = 0;
  long count = 0;
  const auto outcome = mjukf::paper::runSchedule(
      filter, steps + 1, h, 1, [&](long k) -> const Model::Meas& { return y[static_cast<std::size_t>(k)]; },
      [&](long k, const auto& f) {
        if (k < steps / 2) return;
        sum += std::pow(f.parameters()(0) - 0.2, 2);
        ++count;
      });
  ASSERT_EQ(outcome.status, Status::Ok) << "stopped at row " << outcome.row;
  std::printf("RMSE of mu over the second half: %.4g\n", std::sqrt(sum / double(count)));
  EXPECT_LT(std::sqrt(sum / double(count)), 0.05);
}

// The robot's parameter-change run (the paper's Figs. 12–14): (K_τ, m) = (0.15, 0.21) until t = 5 s,
// then (0.10, 0.30). With the default convergenceTime (5 s) both estimates must have covered 90 % of
// the change 20 s after it (four time constants would cover 98 %), and must not have overshot it by
// more than 10 % on the way (the fixed ξ swings K̂_τ to about −0.2).
TEST(AutomaticModes, TrackTheRobotsParameterChange) {
  const Robot::Model model;
  const double h = Robot::stepSize;
  const long steps = 25000;
  const Robot::Param before = Robot::Model::trueParameters(), after(0.10, 0.30);
  std::vector<Robot::Model::Meas> y;
  std::vector<Robot::Param> truth;
  simulateNoisy(
      model, mjukf::ITrBdf2<double>(), Robot::initialState(),
      [&](long k) { return double(k) * h >= 5.0 ? after : before; }, h, steps, 0.03, y, truth);
  mjukf::ModifiedJointUkf<Robot::Model> filter(model, Robot::initialState(), Robot::initialParameters(),
                                               automatic(Robot::modifiedJointUkf()));
  Robot::Param lowest = Robot::Param::Constant(1e9), highest = -lowest;
  const auto outcome = mjukf::paper::runSchedule(
      filter, steps + 1, h, Robot::measurementEvery,
      [&](long k) -> const Robot::Model::Meas& { return y[static_cast<std::size_t>(k)]; },
      [&](long k, const auto& f) {
        if (double(k) * h < 5.0) return;
        lowest = lowest.cwiseMin(f.parameters());
        highest = highest.cwiseMax(f.parameters());
      });
  ASSERT_EQ(outcome.status, Status::Ok) << "stopped at row " << outcome.row;
  const Robot::Param change = after - before;  // (−0.05, +0.09)
  const Robot::Param covered = (filter.parameters() - before).cwiseQuotient(change);
  std::printf("covered %.3f %.3f, K_tau min %.4f, m max %.4f\n", covered(0), covered(1), lowest(0), highest(1));
  EXPECT_GT(covered(0), 0.9) << filter.parameters().transpose();
  EXPECT_GT(covered(1), 0.9) << filter.parameters().transpose();
  EXPECT_GT(lowest(0), after(0) - 0.1 * std::abs(change(0)));   // K_τ falls: no undershoot below 0.095
  EXPECT_LT(highest(1), after(1) + 0.1 * std::abs(change(1)));  // m rises: no overshoot above 0.309
}

// A gain θ on an input whose size switches: x⁺ = 0.5 x + θ u + w, y = x + v. Through a stretch where u
// is small the data barely see θ: the least-squares gain's memory must not forget what is known (I kept,
// θ̂ held); once u is back, it must forget again and follow a changed θ.
struct SwitchedGain {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = Eigen::Matrix<double, 1, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
  State transition(double, double, const State& x, const Input& u, const Param& theta) const {
    return State(0.5 * x(0) + theta(0) * u(0));
  }
  Meas measurement(const State& x, const Param&) const { return Meas(x(0)); }
};

// SwitchedGain's automatic settings (Q = 1e-4, R = 1e-2), and the plant driven by an input of random sign
// into a filter, with its noise drawn from seed 7.
mjukf::ModifiedJointUkfSettingsFor<SwitchedGain> switchedGainSettings() {
  mjukf::ModifiedJointUkfSettingsFor<SwitchedGain> s;
  s.initialCovariance.setConstant(1.0);
  s.processNoise.setConstant(1e-4);
  s.measurementNoise.setConstant(1e-2);
  return automatic(s);
}
struct SwitchedGainRun {
  std::mt19937_64 rng{7};
  std::normal_distribution<double> normal;
  std::bernoulli_distribution sign;
  double x = 0;
  // `updates` steps of input ±`size` with the truth `theta`; false at a step the filter did not take.
  template <class Filter>
  bool drive(Filter& filter, long updates, double size, double theta) {
    const auto& s = filter.settings();
    for (long k = 0; k < updates; ++k) {
      const SwitchedGain::Input u(sign(rng) ? size : -size);
      x = 0.5 * x + theta * u(0) + std::sqrt(s.processNoise(0, 0)) * normal(rng);
      const SwitchedGain::Meas y(x + std::sqrt(s.measurementNoise(0, 0)) * normal(rng));
      if (!mjukf::taken(filter.timeUpdate(0.0, 1.0, u)) || !mjukf::taken(filter.measurementUpdate(y))) return false;
    }
    return true;
  }
};

TEST(AutomaticModes, AStretchWithoutExcitationForgetsNothingAndExcitationForgetsAgain) {
  auto s = switchedGainSettings();
  s.parameterGain = mjukf::ParameterGain::RecursiveLeastSquares;
  mjukf::ModifiedJointUkf<SwitchedGain> filter(SwitchedGain(), SwitchedGain::State(0), SwitchedGain::Param(0.5), s);
  SwitchedGainRun plant;
  const auto run = [&](long updates, double size, double theta) {
    ASSERT_TRUE(plant.drive(filter, updates, size, theta));
  };
  // The memory is 100 updates (minimumMemoryUpdates; convergenceTime's 5 s are 5 updates here).
  run(1000, 1.0, 1.0);
  const double known = filter.sensitivity().information()(0, 0), held = filter.parameters()(0);
  const double sigma = std::sqrt(filter.parameterCovariance()(0, 0));
  EXPECT_NEAR(held, 1.0, 4 * sigma);
  // 20 memories with an input a hundredth as large: each update brings 10⁻⁴ of its usual information.
  // Forgetting by time alone leaves I at the prior plus 100 such updates' worth, and θ̂ wanders on the
  // noise with the gain that goes with it (measured before the change: I from 1.3e4 to 5.2, θ̂ moved
  // by 0.094, 15 σ).
  run(2000, 0.01, 1.0);
  EXPECT_GT(filter.sensitivity().information()(0, 0), 0.5 * known);
  EXPECT_LT(std::abs(filter.parameters()(0) - held), 3 * sigma);
  // Excited again, with θ changed by 0.2: within 10 memories it is followed to the same accuracy.
  run(1000, 1.0, 1.2);
  EXPECT_NEAR(filter.parameters()(0), 1.2, 4 * sigma);
}

// The joint covariance's gain (the default) takes θ as constant: P_θ shrinks as 1/k and θ̂ averages the
// whole run. A change of θ is found by the test of docs/algorithms.md §5.4, which widens P_θ so that θ̂
// follows. On SwitchedGain, always excited (each update brings about u² / (R + Q) ≈ 100 of information,
// σ_θ ≈ 0.003 after 1,000 updates): 2,000 updates at θ = 1 raise no detection and end within 4 σ; then θ = 1.2
// for 1,000 updates (a change of 60 σ) is found, and θ̂ ends within 4 σ of 1.2. Without the test
// (changeFalseAlarm = 0) nothing is found and θ̂, the average of all the data, stays near
// 1 + 0.2 / 3 ≈ 1.07, more than 10 σ from the truth.
TEST(AutomaticModes, TheJointGainFollowsAChangeOnlyThroughTheTest) {
  auto s = switchedGainSettings();
  ASSERT_EQ(s.parameterGain, mjukf::ParameterGain::JointCovariance) << "the default";
  for (const double falseAlarm : {s.changeFalseAlarm, 0.0}) {
    s.changeFalseAlarm = falseAlarm;
    mjukf::ModifiedJointUkf<SwitchedGain> filter(SwitchedGain(), SwitchedGain::State(0), SwitchedGain::Param(0.5), s);
    SwitchedGainRun plant;
    const auto run = [&](long updates, double theta) { ASSERT_TRUE(plant.drive(filter, updates, 1.0, theta)); };
    run(2000, 1.0);
    const auto sigma = [&] { return std::sqrt(filter.parameterCovariance()(0, 0)); };
    EXPECT_EQ(filter.detectedParameterChanges(), 0) << "a false alarm, alpha " << falseAlarm;
    EXPECT_NEAR(filter.parameters()(0), 1.0, 4 * sigma());
    run(1000, 1.2);
    if (falseAlarm > 0) {
      EXPECT_GE(filter.detectedParameterChanges(), 1);
      EXPECT_NEAR(filter.parameters()(0), 1.2, 4 * sigma());
    } else {
      EXPECT_EQ(filter.detectedParameterChanges(), 0);
      EXPECT_GT(std::abs(filter.parameters()(0) - 1.2), 10 * sigma()) << "without the test θ̂ cannot follow";
    }
  }
}

// The same on a plant with one measured output and two parameters of opposite-sign sensitivity, the
// gallery's DC motor (its angle measured; K raises the speed, b lowers it): both parameters step up by
// 30 % halfway through its 20 s. With the test (the default) the change is found and both end within
// 1 % of the new truth (measured over 20 seeds: 0.04 % and 0.13 % on average); without it θ̂ averages the
// two halves and ends more than 5 % off (measured: 16 % each). Seeds of this test's own.
TEST(AutomaticModes, TheJointGainFollowsAChangeOfTwoParametersFromOneOutput) {
  using Experiment = mjukf::gallery::DcMotorExperiment<double>;
  using Model = Experiment::Model;
  using Integrator = mjukf::examples::ExperimentIntegrator<Experiment>;
  const Model model;
  const double h = Experiment::stepSize;
  const long steps = static_cast<long>(Experiment::duration / h + 0.5);
  const Model::Param before = Model::trueParameters(), after = 1.3 * before;
  const auto truthAt = [&](long k) { return k < steps / 2 ? before : after; };
  for (const unsigned seed : {101u, 102u, 103u}) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> normal;
    std::vector<Model::Meas> y(static_cast<std::size_t>(steps + 1));
    mjukf::simulate(model, Integrator(), Experiment::trueInitialState(), truthAt, 0.0, h, steps,
                    [&](long k, double t, const auto& x) {
                      Model::Meas m = mjukf::measureModel(model, Model::State(x), model.input(t), truthAt(k));
                      for (int j = 0; j < Model::MeasDim; ++j)
                        m(j) += Experiment::noiseStandardDeviation()(j) * normal(rng);
                      y[static_cast<std::size_t>(k)] = m;
                    });
    for (const double falseAlarm : {Experiment::modifiedJointUkf().changeFalseAlarm, 0.0}) {
      auto s = Experiment::modifiedJointUkf();
      s.changeFalseAlarm = falseAlarm;
      mjukf::ModifiedJointUkf<Model, Integrator> filter(model, Experiment::initialState(),
                                                        Experiment::initialParameters(), s);
      const auto outcome = mjukf::paper::runSchedule(
          filter, steps + 1, h, Experiment::measurementEvery,
          [&](long k) -> const Model::Meas& { return y[static_cast<std::size_t>(k)]; }, [](long, const auto&) {});
      ASSERT_EQ(outcome.status, Status::Ok) << "seed " << seed << ", row " << outcome.row;
      const Model::Param error = (filter.parameters() - after).cwiseQuotient(after).cwiseAbs();
      if (falseAlarm > 0) {
        EXPECT_GE(filter.detectedParameterChanges(), 1) << "seed " << seed;
        EXPECT_LT(error.maxCoeff(), 0.01) << "seed " << seed << ": " << filter.parameters().transpose();
      } else {
        EXPECT_EQ(filter.detectedParameterChanges(), 0);
        EXPECT_GT(error.maxCoeff(), 0.05) << "seed " << seed << ": without the test θ̂ cannot follow";
      }
    }
  }
}

// Off by default, and while off the new settings change nothing: a run with them set to other values
// is bit for bit the paper's.
TEST(AutomaticModes, OffTheNewSettingsChangeNothing) {
  auto other = Tank::modifiedJointUkf();
  other.parameterUncertaintyInState = false;
  other.convergenceTime = 0.5;
  other.sensitivityInterval = 3;
  mjukf::ModifiedJointUkf<Tank::Model> paper(Tank::Model(), Tank::initialState(), Tank::initialParameters(),
                                             Tank::modifiedJointUkf());
  mjukf::ModifiedJointUkf<Tank::Model> changed(Tank::Model(), Tank::initialState(), Tank::initialParameters(), other);
  EXPECT_FALSE(Tank::modifiedJointUkf().automaticTransformation);
  EXPECT_FALSE(Tank::modifiedJointUkf().adaptiveScaling);
  const Tank::Model::Meas y(1.0, 0.5);
  for (int k = 0; k < 200; ++k) {
    ASSERT_EQ(paper.timeUpdate(k * Tank::stepSize, Tank::stepSize), Status::Ok);
    ASSERT_EQ(changed.timeUpdate(k * Tank::stepSize, Tank::stepSize), Status::Ok);
    ASSERT_EQ(paper.measurementUpdate(y), Status::Ok);
    ASSERT_EQ(changed.measurementUpdate(y), Status::Ok);
  }
  EXPECT_TRUE(mjukf::testing::sameFilter(paper, changed));
  EXPECT_NE(paper.parameters()(0), Tank::initialParameters()(0)) << "the run did move the parameter";
}

// Q_θ (parameterProcessNoise) reaches the covariance of θ̂ the filter follows: a time update leaves P_θ
// as it was but for Q_θ (θ does not move in it: docs/algorithms.md §5.1), with both automatic modes and
// with followParameterCovariance alone; Q_θ = 0 leaves it exactly. Tolerance: P_θ is the lower-right block
// of T J Tᵀ, whose rows for θ are (0, I): sums of products with exact zeros, to a few ε of P_θ.
TEST(AutomaticModes, TheParameterWalkWidensTheParameterCovarianceAtEachTimeUpdate) {
  Eigen::Matrix2d walk;
  walk << 4e-6, 1e-6, 1e-6, 9e-6;
  auto followed = Robot::modifiedJointUkf();
  followed.followParameterCovariance = true;
  for (const auto& base : {automatic(Robot::modifiedJointUkf()), followed}) {
    auto s = base;
    s.parameterProcessNoise = walk;
    mjukf::ModifiedJointUkf<Robot::Model> walking(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s);
    mjukf::ModifiedJointUkf<Robot::Model> still(Robot::Model(), Robot::initialState(), Robot::initialParameters(),
                                                base);
    const Robot::Model::Meas y = Robot::Model::Meas::Constant(0.01);
    for (int k = 0; k < 5; ++k) {
      const Eigen::Matrix2d before = walking.parameterCovariance(), beforeStill = still.parameterCovariance();
      ASSERT_EQ(walking.timeUpdate(k * Robot::stepSize, Robot::stepSize), Status::Ok);
      ASSERT_EQ(still.timeUpdate(k * Robot::stepSize, Robot::stepSize), Status::Ok);
      const double tol = 8 * std::numeric_limits<double>::epsilon() * before.norm();
      EXPECT_LT((walking.parameterCovariance() - (before + walk)).cwiseAbs().maxCoeff(), tol) << k;
      EXPECT_LT((still.parameterCovariance() - beforeStill).cwiseAbs().maxCoeff(), tol) << k;
      ASSERT_TRUE(mjukf::taken(walking.measurementUpdate(y)));
      ASSERT_TRUE(mjukf::taken(still.measurementUpdate(y)));
    }
  }
}

// The gallery's predator–prey (docs/studies.md): the prey counted, the predators guessed 2.5 times too
// few, both parameters in the predators' equation, the gallery's settings rule. Without the parameters'
// uncertainty in the state's covariance (docs/algorithms.md §5.2) the filter pulled δ̂ to its bound within
// a few updates and then trusted that model over the data (15 of 50 `study` runs diverged); with it (the
// default) every run must end within 10 % of the truth (the study's RMSEs are 0.7 % and 0.6 %) and within
// 4 of its own standard deviations of it (observed: at most 2.3; 4 σ is exceeded by chance with
// probability 6e-5 per comparison for a filter whose σ means what it says), in the full and the
// square-root form and with the sensitivities refreshed at every second time update (with the
// least-squares gain, the joint covariance's refusing that: docs/tuning-mjukf.md, "The joint covariance's gain"). Ten
// noise sequences of this test's own, none of them `study`'s.
TEST(AutomaticModes, AnUnmeasuredStateGuessedWrongDoesNotMisleadTheParameters) {
  using Experiment = mjukf::gallery::PredatorPreyExperiment<double>;
  using Model = Experiment::Model;
  using Integrator = Experiment::Integrator;
  enum class Variant { Default, Without, SquareRoot, RefreshEverySecond };
  const Model model;
  const double h = Experiment::stepSize;
  const long steps = static_cast<long>(Experiment::duration / h);
  const Model::Param truth = Model::trueParameters();
  std::vector<Model::Meas> y;  // the prey counted (y = x₁), the noise sequence of the seed in hand
  std::vector<Model::Param> truths;
  const auto run = [&](Variant variant, Model::Param& estimate, Model::Param& sigma) {
    auto s = Experiment::modifiedJointUkf();
    s.parameterUncertaintyInState = variant != Variant::Without;
    if (variant == Variant::RefreshEverySecond) {  // refused with the joint covariance's gain (docs/tuning-mjukf.md)
      s.sensitivityInterval = 2;
      s.parameterGain = mjukf::ParameterGain::RecursiveLeastSquares;
    }
    const auto finish = [&](auto& filter) {
      const auto outcome = mjukf::paper::runSchedule(
          filter, steps + 1, h, Experiment::measurementEvery,
          [&](long k) -> const Model::Meas& { return y[static_cast<std::size_t>(k)]; }, [](long, const auto&) {});
      estimate = filter.parameters();
      sigma = filter.parameterCovariance().diagonal().cwiseSqrt();
      return outcome.status == Status::Ok;
    };
    if (variant == Variant::SquareRoot) {
      mjukf::ModifiedJointUkf<Model, Integrator, mjukf::MerweScaled, mjukf::SquareRootCovariance> filter(
          model, Experiment::initialState(), Experiment::initialParameters(), s);
      return finish(filter);
    }
    mjukf::ModifiedJointUkf<Model, Integrator> filter(model, Experiment::initialState(),
                                                      Experiment::initialParameters(), s);
    return finish(filter);
  };
  double largestRatio = 0;
  const auto expectFound = [&](Variant variant, unsigned seed) {
    Model::Param estimate, sigma;
    ASSERT_TRUE(run(variant, estimate, sigma)) << "seed " << seed;
    const Model::Param error = (estimate - truth).cwiseAbs();
    std::printf("variant %d, seed %u: delta %.5f (sigma %.2g), gamma %.5f (sigma %.2g)\n", int(variant), seed,
                estimate(0), sigma(0), estimate(1), sigma(1));
    for (int r = 0; r < Model::ParamDim; ++r) {
      EXPECT_LT(error(r), 0.1 * truth(r)) << "variant " << int(variant) << ", seed " << seed << ", parameter " << r;
      EXPECT_LT(error(r), 4 * sigma(r)) << "variant " << int(variant) << ", seed " << seed << ", parameter " << r;
      largestRatio = std::max(largestRatio, error(r) / sigma(r));
    }
  };
  int misled = 0;
  for (unsigned seed = 1; seed <= 10; ++seed) {
    simulateNoisy(
        model, Integrator(), Experiment::trueInitialState(), [&](long) { return truth; }, h, steps,
        Experiment::noiseStandardDeviation()(0), y, truths, seed);
    expectFound(Variant::Default, seed);
    if (seed <= 3) {
      expectFound(Variant::SquareRoot, seed);
      expectFound(Variant::RefreshEverySecond, seed);
    }
    Model::Param without, unused;
    const bool ok = run(Variant::Without, without, unused);
    if (!ok || ((without - truth).cwiseAbs().array() > 0.5 * truth.array()).any()) ++misled;
  }
  std::printf(
      "largest error / sigma %.2f; without the parameters' uncertainty in the state's covariance: %d of 10 "
      "misled\n",
      largestRatio, misled);
  EXPECT_GE(misled, 1) << "the case no longer shows what the setting is for";
}

// The test for a change of θ (docs/algorithms.md §5.4) assumes innovations of mean zero while θ is constant.
// The gallery's battery measures y = OCV(z) − v₁ − R₀ i with OCV curved (OCV'' ≈ 3 V at z = 0.9) and starts
// with the charge known to σ = 0.1: ŷ, the points' mean, and g(x̂⁻, θ̂) then differ by about 2 mV over the
// first hundred updates (measured), against a sensor of 2 mV. Started at the true state and parameters,
// over 100 one-hour runs (seeds of this test's own), the test took y − g(x̂⁻, θ̂) and fired in 33 runs,
// first between updates 97 and 121, then again as the widened P_θ moved θ̂: 211 detections (measured);
// with y − ŷ it fired once (update 399, just after the first 5 A pulse). With white innovations, α = 1e-9
// per update would allow 4e-4 detections in these 360,000 updates: what remains is the innovations'
// correlation in time, which the test does not model (§5.4). At most 3 runs with a detection: the bias
// fired in ten times as many.
TEST(AutomaticModes, ACurvedMeasurementDoesNotFireTheChangeTest) {
  using Experiment = mjukf::gallery::BatteryExperiment<double>;
  using Model = Experiment::Model;
  const Model model;
  const Model::Param truth = Model::trueParameters();
  const long samples = static_cast<long>(Experiment::duration / Experiment::stepSize + 0.5);
  long detections = 0, runsWithDetections = 0;
  for (unsigned seed = 301; seed <= 400; ++seed) {
    std::mt19937_64 random(seed);
    std::normal_distribution<double> normal(0.0, 1.0);
    mjukf::ModifiedJointUkf<Model> filter(model, Experiment::trueInitialState(), truth, Experiment::modifiedJointUkf());
    Model::State x = Experiment::trueInitialState();
    for (long k = 0; k < samples; ++k) {
      const double t = double(k) * Experiment::stepSize;
      x = model.transition(t, Experiment::stepSize, x, model.input(t), truth);
      const Model::Meas y = model.measurement(x, model.input(t + Experiment::stepSize), truth) +
                            Model::Meas::Constant(Experiment::noiseStandardDeviation()(0) * normal(random));
      Status status = filter.timeUpdate(t, Experiment::stepSize);
      if (mjukf::taken(status)) status = filter.measurementUpdate(y);
      ASSERT_TRUE(mjukf::taken(status)) << "seed " << seed << ", sample " << k << ": " << mjukf::toString(status);
    }
    detections += filter.detectedParameterChanges();
    runsWithDetections += filter.detectedParameterChanges() > 0 ? 1 : 0;
  }
  std::printf("detections %ld in %ld of 100 runs\n", detections, runsWithDetections);
  EXPECT_LE(runsWithDetections, 3);
}

// The robot whose derivative is NaN away from `*centre` while `*armed` (pointers: the filter keeps a
// copy of the model): the sigma points fail, while the propagations of the sensitivities, about the
// mean, succeed.
struct FlakyRobot : Robot::Model {
  const bool* armed = nullptr;
  const Robot::Model::State* centre = nullptr;
  State derivative(double t, const State& x, const Input& u, const Param& theta) const {
    if (*armed && (x - *centre).cwiseAbs().maxCoeff() > 1e-3) return State::Constant(std::nan(""));
    return Robot::Model::derivative(t, x, u, theta);
  }
};

// A time update refused after the automatic modes computed their candidates (W from the propagations
// about the mean) leaves W, ψ, the information, T and ξ as they were, and the next steps are bit for bit
// those of a filter that never saw the refused call. (The typed failure-policy tests run the automatic
// mode through the other refusals.)
TEST(AutomaticModes, RefusedStepsLeaveTheAdaptiveStateUnchanged) {
  bool armed = false;
  Robot::Model::State centre = Robot::Model::State::Zero();
  FlakyRobot model;
  model.armed = &armed;
  model.centre = &centre;
  mjukf::ModifiedJointUkf<FlakyRobot> filter(model, Robot::initialState(), Robot::initialParameters(),
                                             automatic(Robot::modifiedJointUkf()));
  const double h = Robot::stepSize;
  const Robot::Model::Meas y = Robot::Model::Meas::Constant(0.02);
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(filter.timeUpdate(2 * k * h, h), Status::Ok);
    ASSERT_EQ(filter.measurementUpdate(y), Status::Ok);
    ASSERT_EQ(filter.propagateMean((2 * k + 1) * h, h), Status::Ok);
  }
  ASSERT_GT(filter.sensitivity().stateSensitivity().cwiseAbs().maxCoeff(), 0.0);
  ASSERT_GT(filter.sensitivity().measurementSensitivity().cwiseAbs().maxCoeff(), 0.0);
  const auto untouched = filter;
  centre = filter.state();
  armed = true;
  EXPECT_EQ(filter.timeUpdate(100 * h, h), Status::NonFiniteResult);
  armed = false;
  EXPECT_TRUE(mjukf::testing::sameFilter(filter, untouched));
  auto other = untouched;
  for (auto* f : {&filter, &other}) {
    ASSERT_EQ(f->propagateMean(100 * h, h), Status::Ok);  // the open-loop time counts in W's extrapolation
    ASSERT_EQ(f->timeUpdate(101 * h, h), Status::Ok);
    ASSERT_EQ(f->measurementUpdate(y), Status::Ok);
  }
  EXPECT_TRUE(mjukf::testing::sameFilter(filter, other));
}

TEST(AutomaticModes, SettingsAreValidated) {
  const auto construct = [](const auto& s) {
    mjukf::ModifiedJointUkf<Robot::Model>(Robot::Model(), Robot::initialState(), Robot::initialParameters(), s);
  };
  const auto expectRejected = [&](const auto& s, const std::string& setting) {
    try {
      construct(s);
      ADD_FAILURE() << "accepted a bad '" << setting << "'";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(setting), std::string::npos) << e.what();
    }
  };
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::infinity(), std::nan("")}) {
    auto s = automatic(Robot::modifiedJointUkf());
    s.convergenceTime = bad;
    expectRejected(s, "convergenceTime");
    s = automatic(Robot::modifiedJointUkf());
    s.minimumMemoryUpdates = bad;
    expectRejected(s, "minimumMemoryUpdates");
  }
  for (double bad : {-1e-9, 1.0, 2.0, std::numeric_limits<double>::infinity(), std::nan("")}) {
    auto s = automatic(Robot::modifiedJointUkf());
    s.changeFalseAlarm = bad;
    expectRejected(s, "changeFalseAlarm");
  }
  auto s = automatic(Robot::modifiedJointUkf());
  s.parameterGain = static_cast<mjukf::ParameterGain>(7);  // not one of the enumerators
  expectRejected(s, "parameterGain");
  s = automatic(Robot::modifiedJointUkf());
  s.changeFalseAlarm = 0;  // no test: allowed
  EXPECT_NO_THROW(construct(s));
  s.sensitivityInterval = 2;  // the joint covariance's gain needs this step's sensitivities
  expectRejected(s, "sensitivityInterval");
  s.parameterGain = mjukf::ParameterGain::RecursiveLeastSquares;
  EXPECT_NO_THROW(construct(s));
  s.sensitivityInterval = -1;
  expectRejected(s, "sensitivityInterval");
  // The filter's own T is used: a T that does not sum to 1 per row is not an error then.
  s = automatic(Robot::modifiedJointUkf());
  s.transformation.setZero();
  EXPECT_NO_THROW(construct(s));
  s.automaticTransformation = false;
  expectRejected(s, "transformation (T)");
  // Off, convergenceTime is not used and not checked.
  auto off = Robot::modifiedJointUkf();
  off.convergenceTime = 0;
  EXPECT_NO_THROW(construct(off));
}

}  // namespace
