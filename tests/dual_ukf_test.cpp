// DualUkf (docs/algorithms.md §9) against results that do not come from its own code: the plain Ukf where
// the dual filter must reduce to it, a textbook reconstruction of both filters' steps, the optimal
// (augmented) Kalman filter of a linear-Gaussian joint problem, exact propagation counts, and the
// paper's robot data.

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include "mjukf/dual_ukf.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/models/coupled_tank.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/sigma_points.hpp"
#include "mjukf/ukf.hpp"
#include "paper/experiments.hpp"
#include "paper/rmse.hpp"
#include "paper/schedule.hpp"
#include "reference_data.hpp"
#include "robustness_support.hpp"
#include "test_support.hpp"

namespace mjukf {
// Every member compiled for float and double, with an integrator other than the default.
template class DualUkf<models::FlexibleJoint<float>, Rk4<float>>;
template class DualUkf<models::FlexibleJoint<double>, Rk4<double>>;
template class DualUkf<models::CoupledTank<float>, Rk4<float>>;
}  // namespace mjukf

namespace {

using mjukf::DualUkf;
using mjukf::DualUkfOrdering;
using mjukf::Status;
using mjukf::testing::bitwiseSame;
using mjukf::testing::referenceMeasurements;

constexpr DualUkfOrdering kOrderings[] = {DualUkfOrdering::PriorParameters, DualUkfOrdering::UpdatedParameters};

const char* name(DualUkfOrdering ordering) {
  return ordering == DualUkfOrdering::PriorParameters ? "PriorParameters" : "UpdatedParameters";
}

// Explicit Euler, one evaluation of f per step: the model's derivative count is then the number of
// propagations of a point over one step.
using Euler = mjukf::testing::Euler<double>;

// The shared (state filter) settings of a dual filter, as the settings of a Ukf.
template <class Scalar, int N, int P, int M>
mjukf::UkfSettings<Scalar, N, M> stateSettings(const mjukf::DualUkfSettings<Scalar, N, P, M>& dual) {
  mjukf::UkfSettings<Scalar, N, M> s;
  static_cast<mjukf::UnscentedSettings<Scalar, N, M>&>(s) = dual;
  return s;
}

// True when the state filters of the two are bit for bit the same: estimate, covariance, diagnostics.
template <class A, class B>
bool sameStateFilter(const A& a, const B& b) {
  return bitwiseSame(a.state(), b.state()) && bitwiseSame(a.covariance(), b.covariance()) &&
         bitwiseSame(a.lastUpdate().innovation, b.lastUpdate().innovation) &&
         bitwiseSame(a.lastUpdate().innovationCovariance, b.lastUpdate().innovationCovariance) &&
         bitwiseSame(Eigen::Matrix<double, 1, 1>(a.lastUpdate().nis),
                     Eigen::Matrix<double, 1, 1>(b.lastUpdate().nis)) &&
         a.hasPropagatedPoints() == b.hasPropagatedPoints();
}

// ---------------------------------------------------------------------------------------------------
// Models.

// A damped nonlinear oscillator whose dynamics and measurement ignore θ:
//   ẋ₁ = x₂,  ẋ₂ = −x₁ − 0.3 x₂ + 0.5 sin x₁ + u(t),  y = x₁ + 0.1 x₂².
struct ThetaFreeOscillator {
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Vector2d;
  using Param = Eigen::Matrix<double, 1, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
  Input input(double t) const { return Input(std::sin(1.3 * t)); }
  State derivative(double, const State& x, const Input& u, const Param&) const {
    return State(x(1), -x(0) - 0.3 * x(1) + 0.5 * std::sin(x(0)) + u(0));
  }
  Meas measurement(const State& x, const Param&) const { return Meas(x(0) + 0.1 * x(1) * x(1)); }
};

// A forced spring–damper, linear in x, with θ in the dynamics:
//   ẋ₁ = x₂,  ẋ₂ = −k x₁ − c x₂ + u(t),  y = x₁,  u(t) = sin 1.3t,
// θ = (k, c) with P = 2, or θ = (k) with c = 0.4 with P = 1. `evaluations`, when set, counts the
// calls of derivative (shared through a pointer: the filter keeps a copy of the model).
template <int P>
struct Spring {
  static_assert(P == 1 || P == 2);
  using Scalar = double;
  static constexpr int StateDim = 2, ParamDim = P, MeasDim = 1, InputDim = 1;
  using State = Eigen::Vector2d;
  using Param = Eigen::Matrix<double, P, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
  long* evaluations = nullptr;

  static Param trueParameters() {
    if constexpr (P == 2)
      return Param(2.0, 0.4);
    else
      return Param(2.0);
  }
  Input input(double t) const { return Input(std::sin(1.3 * t)); }
  State derivative(double, const State& x, const Input& u, const Param& theta) const {
    if (evaluations) ++*evaluations;
    const double damping = P == 2 ? theta(P - 1) : 0.4;
    return State(x(1), -theta(0) * x(0) - damping * x(1) + u(0));
  }
  Meas measurement(const State& x, const Param&) const { return Meas(x(0)); }
};

// ẋ = −x + θ + u(t), y = x, u(t) = 0.5 sin 0.7t: a constant unknown level θ, linear and Gaussian in
// [x; θ] jointly, so its optimal filter is the Kalman filter of the augmented vector.
struct Level {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = State;
  using Meas = State;
  using Input = State;
  Input input(double t) const { return Input(0.5 * std::sin(0.7 * t)); }
  State derivative(double, const State& x, const Input& u, const Param& theta) const {
    return State(-x(0) + theta(0) + u(0));
  }
  Meas measurement(const State& x, const Param&) const { return x; }
};

// The truth of a model under parameters θ, integrated with `Stepper` at step h, and its measurement
// with white Gaussian noise of standard deviation sigma (std::mt19937_64, fixed seed).
template <class Model, class Stepper>
class Simulation {
 public:
  Simulation(const Model& model, const typename Model::State& x0, const typename Model::Param& theta, double h,
             double sigma, unsigned long long seed)
      : model_(model), x_(x0), theta_(theta), h_(h), sigma_(sigma), random_(seed) {}
  // The measurement after one more step from t.
  typename Model::Meas next(double t) {
    x_ = stepper_.step(
        [&](double s, const typename Model::State& x) { return model_.derivative(s, x, model_.input(s), theta_); }, t,
        x_, h_);
    typename Model::Meas y = model_.measurement(x_, theta_);
    for (int i = 0; i < Model::MeasDim; ++i) y(i) += sigma_ * noise_(random_);
    return y;
  }

 private:
  Model model_;
  typename Model::State x_;
  typename Model::Param theta_;
  Stepper stepper_;
  double h_, sigma_;
  std::mt19937_64 random_;
  std::normal_distribution<double> noise_{0.0, 1.0};
};

// ---------------------------------------------------------------------------------------------------
// (a) θ plays no part: the dual filter's state filter is the Ukf, bit for bit.

// On a model that ignores θ, the parameter filter's Dⱼ = g(Φ_h(x̂; θⱼ), θⱼ) are all the same vector D,
// and with parameter sigma points α = 1, κ = 0 (Wm = (0, ½, ½) for p = 1) their mean is
// 0·D + ½D + ½D = D exactly, so P_θD and the parameter gain are exactly zero. (The default α = 0.1
// weighs D by −99, 50 and 50, whose sum rounds away from D: θ̂ would then move by rounding, which is
// not what this test is about, so it sets α = 1.) The state filter then
// runs with θ̂ = θ̂₀ throughout, which the model ignores anyway, and the UpdatedParameters ordering's
// second time update repeats the first from the same mean and factor: in both orderings every state
// quantity must equal the Ukf's with the same state settings bit for bit, over a schedule that mixes
// time updates over one and several steps, held inputs, open-loop propagation and redrawn points.
TEST(DualUkf, IndependentOfThetaItIsTheUkfBitForBit) {
  using Model = ThetaFreeOscillator;
  mjukf::DualUkfSettingsFor<Model> dualSettings;
  dualSettings.initialCovariance = Eigen::Vector2d(0.5, 0.3).asDiagonal();
  dualSettings.initialCovariance(0, 1) = dualSettings.initialCovariance(1, 0) = 0.1;
  dualSettings.processNoise = 1e-4 * Eigen::Matrix2d::Identity();
  dualSettings.measurementNoise << 0.01;
  dualSettings.initialParameterCovariance << 0.3;
  dualSettings.parameterProcessNoise << 1e-3;
  dualSettings.parameterObservationNoise << 0.02;
  dualSettings.parameterForgetting = 0.99;
  dualSettings.parameterSigmaPoints = {1.0, 2.0, 0.0};  // exact weights (above)
  const Model::State x0(0.4, -0.1);
  const Model::Param theta0(0.7);
  const double h = 0.01;
  for (const DualUkfOrdering ordering : kOrderings) {
    for (const bool redraw : {false, true}) {
      SCOPED_TRACE(std::string(name(ordering)) + (redraw ? ", redrawn points" : ""));
      auto s = dualSettings;
      s.ordering = ordering;
      s.redrawPointsForUpdate = redraw;
      DualUkf<Model, mjukf::Rk4<double>> dual(Model(), x0, theta0, s);
      mjukf::Ukf<Model, mjukf::Rk4<double>> ukf(Model(), x0, theta0, stateSettings(s));
      Simulation<Model, mjukf::Rk4<double>> truth(Model(), Model::State(0.6, 0.0), theta0, h, 0.1, 42);
      for (int k = 0; k < 1500; ++k) {
        const double t = k * h;
        const Model::Meas y = truth.next(t);
        if (k % 3 != 2) {
          ASSERT_EQ(dual.propagateMean(t, h), Status::Ok);
          ASSERT_EQ(ukf.propagateMean(t, h), Status::Ok);
        } else if (k % 9 == 2) {
          const Model::Input u(0.3 * std::cos(t));
          ASSERT_EQ(dual.timeUpdate(t, h, u, 2), Status::Ok);
          ASSERT_EQ(ukf.timeUpdate(t, h, u, 2), Status::Ok);
        } else {
          ASSERT_EQ(dual.timeUpdate(t, h, 1 + k % 2), Status::Ok);
          ASSERT_EQ(ukf.timeUpdate(t, h, 1 + k % 2), Status::Ok);
        }
        ASSERT_TRUE(sameStateFilter(dual, ukf)) << "after the time update of step " << k;
        if (k % 3 == 2) {
          ASSERT_EQ(dual.measurementUpdate(y), Status::Ok);
          ASSERT_EQ(ukf.measurementUpdate(y), Status::Ok);
          ASSERT_TRUE(sameStateFilter(dual, ukf)) << "after the measurement update of step " << k;
          // The gain is exactly zero: θ̂ never moves (P^θ does: the random walk and λ).
          ASSERT_TRUE(bitwiseSame(dual.parameters(), theta0)) << "step " << k;
        }
      }
      EXPECT_GT(dual.parameterCovariance()(0, 0), dualSettings.initialParameterCovariance(0, 0));
    }
  }
}

// ---------------------------------------------------------------------------------------------------
// (b) A known parameter: P^θ₀ = 1e-24 I and Q_θ = 0 on the spring, whose dynamics use θ.

// Each correction moves θ̂ by K_θ ν = P_θD P_DD⁻¹ ν, and for this scalar measurement P_DD ≥ R = σ², so
//   |K_θ ν| ≤ Σⱼ |Wcⱼ| |θⱼ − θ̂| |Dⱼ − D̂| |ν| / σ².
// Here |θⱼ − θ̂| ≤ γ √P^θ = 0.1 √2 · 1e-12 (the default α = 0.1, β = 2, κ = 0, p = 2: γ = 0.1 √2,
// Σ|Wcⱼ| = 96.01 + 4 · 25 = 196.01), and |Dⱼ − D̂| is the sensitivity over one step,
// ∂x₁(t + h)/∂θ = −(h²/2)(x₁, x₂) + O(h³), times that, plus the rounding of D itself:
// ≤ 5e-4 · 1.5e-13 + 4 ε · 2.5 ≤ 3e-15 while |x̂| < 2.5 (asserted). With |ν| < 5 (asserted) and
// σ² = 0.0025: |K_θ ν| ≤ 196.01 · 1.5e-13 · 3e-15 · 5 / 0.0025 ≈ 2e-22, and P^θ only
// shrinks. That is five orders of magnitude below half an ulp of θ = (2, 0.4) (≥ 2.7e-17), so
// θ̂ + K_θ ν rounds back to θ: θ̂ must stay θ bit for bit. The state filter then runs with exactly θ,
// and the tolerance this gives on the state is zero: it equals the Ukf given the true θ bit for bit,
// in both orderings (the second time update of UpdatedParameters repeats the first).
TEST(DualUkf, WithAKnownParameterItIsTheUkfGivenTheTruth) {
  using Model = Spring<2>;
  const Model::Param theta = Model::trueParameters();
  mjukf::DualUkfSettingsFor<Model> s;
  s.initialCovariance = Eigen::Vector2d(0.2, 0.2).asDiagonal();
  s.processNoise = 1e-5 * Eigen::Matrix2d::Identity();
  s.measurementNoise << 0.05 * 0.05;
  s.initialParameterCovariance = 1e-24 * Eigen::Matrix2d::Identity();
  s.parameterProcessNoise.setZero();
  const double h = 0.01;
  for (const DualUkfOrdering ordering : kOrderings) {
    SCOPED_TRACE(name(ordering));
    s.ordering = ordering;
    DualUkf<Model, mjukf::Rk4<double>> dual(Model(), Model::State::Zero(), theta, s);
    mjukf::Ukf<Model, mjukf::Rk4<double>> ukf(Model(), Model::State::Zero(), theta, stateSettings(s));
    Simulation<Model, mjukf::Rk4<double>> truth(Model(), Model::State(0.5, 0.0), theta, h, 0.05, 7);
    double largestInnovation = 0;
    for (int k = 0; k < 2000; ++k) {
      const double t = k * h;
      const Model::Meas y = truth.next(t);
      ASSERT_EQ(dual.timeUpdate(t, h), Status::Ok);
      ASSERT_EQ(ukf.timeUpdate(t, h), Status::Ok);
      ASSERT_EQ(dual.measurementUpdate(y), Status::Ok);
      ASSERT_EQ(ukf.measurementUpdate(y), Status::Ok);
      ASSERT_TRUE(bitwiseSame(dual.parameters(), theta)) << "θ̂ moved at step " << k;
      ASSERT_TRUE(sameStateFilter(dual, ukf)) << "step " << k;
      ASSERT_LE(dual.parameterCovariance().maxCoeff(), 1e-24);
      largestInnovation = std::max(largestInnovation, std::abs(dual.lastParameterUpdate().innovation(0)));
      ASSERT_LT(dual.state().cwiseAbs().maxCoeff(), 2.5) << "the bound above assumed |x̂| < 2.5";
    }
    EXPECT_LT(largestInnovation, 5.0) << "the bound above assumed |ν| < 5";
  }
}

// ---------------------------------------------------------------------------------------------------
// (c) A linear-Gaussian joint problem: the level ẋ = −x + θ + u observed in noise.

// The optimal filter of [x; θ] here is the Kalman filter of the augmented vector, with the transition
// of the Rk4 step (linear in x and θ: F = Rk4 image of x = 1 with θ = u = 0, G = image of x = 0 with
// θ = 1): its posterior σ_θ is the smallest standard deviation any filter given the same data can
// have, so a dual filter reporting less would be over-confident.
double optimalParameterSigma(double h, double sigma, double p0, double ptheta0, double q, int steps) {
  using V = Eigen::Matrix<double, 1, 1>;
  const mjukf::Rk4<double> rk4;
  const double F = rk4.step([](double, const V& x) { return V(-x(0)); }, 0.0, V(1.0), h)(0);
  const double G = rk4.step([](double, const V& x) { return V(-x(0) + 1.0); }, 0.0, V(0.0), h)(0);
  Eigen::Matrix2d A, P = Eigen::Vector2d(p0, ptheta0).asDiagonal();
  A << F, G, 0.0, 1.0;
  const Eigen::RowVector2d H(1.0, 0.0);
  for (int k = 0; k < steps; ++k) {
    P = A * P * A.transpose();
    P(0, 0) += q;
    const double S = (H * P * H.transpose())(0) + sigma * sigma;
    const Eigen::Vector2d K = P * H.transpose() / S;
    P -= K * S * K.transpose();
  }
  return std::sqrt(P(1, 1));
}

// Truth θ = 1.5 from a first guess of 0.5 (P^θ₀ = 1, Q_θ = 0), σ = 0.05 white noise on y = x at every
// step of h = 0.02 over 200 s (10 000 steps), truth and filter integrated with the same Rk4 steps.
// The bounds:
//  - at the end |θ̂ − θ| ≤ 3 σ_θ, with σ_θ the filter's own √P^θ: a consistent Gaussian estimate exceeds
//    that once in 370 (this seed: |θ̂ − θ| = 3.2e-4 against σ_θ = 5.05e-4);
//  - σ_θ within 1 % of σ_θ of the optimal filter above (5.05e-4 here). Here, where x and θ enter
//    linearly, the parameter filter's observation (x̂_{k−1} + W Δθⱼ propagated, with the state's
//    innovation covariance as its noise) is the exact marginal likelihood of θ, so the dual UKF is the
//    optimal filter up to rounding and the W regression's O(P^θ) approximation (measured 2e-4 relative
//    below it). A parameter filter that propagated x̂_{k−1} as if exact and observed with R alone reported
//    σ_θ = 0.025, 50 times the optimal, learning from the data as if it knew less;
//  - the RMS error over the last quarter is below a fifth of that over the first (measured 0.053 and
//    0.0025 PriorParameters, 0.045 and 0.0025 UpdatedParameters; 11–20× over seeds 1–6).
TEST(DualUkf, LinearGaussianLevelConvergesToTheTruth) {
  const double h = 0.02, sigma = 0.05, thetaTrue = 1.5;
  const int steps = 10000;
  mjukf::DualUkfSettingsFor<Level> s;
  s.initialCovariance << 0.25;
  s.processNoise << 1e-8;
  s.measurementNoise << sigma * sigma;
  s.initialParameterCovariance << 1.0;
  s.parameterProcessNoise << 0.0;
  const double optimal = optimalParameterSigma(h, sigma, 0.25, 1.0, 1e-8, steps);
  for (const DualUkfOrdering ordering : kOrderings) {
    SCOPED_TRACE(name(ordering));
    s.ordering = ordering;
    DualUkf<Level, mjukf::Rk4<double>> dual(Level(), Level::State(0.0), Level::Param(0.5), s);
    Simulation<Level, mjukf::Rk4<double>> truth(Level(), Level::State(0.2), Level::Param(thetaTrue), h, sigma, 2024);
    double firstQuarter = 0, lastQuarter = 0;
    for (int k = 0; k < steps; ++k) {
      const double t = k * h;
      const Level::Meas y = truth.next(t);
      ASSERT_EQ(dual.timeUpdate(t, h), Status::Ok) << k;
      ASSERT_EQ(dual.measurementUpdate(y), Status::Ok) << k;
      const double e = dual.parameters()(0) - thetaTrue;
      if (k < steps / 4) firstQuarter += e * e;
      if (k >= steps - steps / 4) lastQuarter += e * e;
    }
    firstQuarter = std::sqrt(firstQuarter / (steps / 4));
    lastQuarter = std::sqrt(lastQuarter / (steps / 4));
    const double error = dual.parameters()(0) - thetaTrue;
    const double reported = std::sqrt(dual.parameterCovariance()(0, 0));
    std::printf("%s: θ̂ − θ = %.3g, σ_θ = %.3g (optimal %.3g), RMS error first quarter %.3g, last %.3g\n",
                name(ordering), error, reported, optimal, firstQuarter, lastQuarter);
    EXPECT_LE(std::abs(error), 3 * reported);
    EXPECT_NEAR(reported, optimal, 0.01 * optimal);
    EXPECT_LT(lastQuarter, firstQuarter / 5);
  }
}

// ---------------------------------------------------------------------------------------------------
// (d) The two orderings: different algorithms, with different costs.

// Per measurement step, a time update propagates the 2n + 1 state points and x̂_{k−1} once per
// parameter point (2p + 1); the UpdatedParameters ordering runs the state's 2n + 1 again in the
// measurement update. With Euler (one derivative per step) and n = 2, p = 1: 5 + 3 = 8 per step of a
// time update, 5 per step of the repeated one; nothing else propagates, and a measurement update that
// has no time update before it (after an update or an open-loop step) repeats nothing.
TEST(DualUkf, PropagationCountsOfBothOrderings) {
  using Model = Spring<1>;
  constexpr long state = 2 * Model::StateDim + 1, parameters = 2 * Model::ParamDim + 1;
  static_assert(state == 5 && parameters == 3);
  for (const DualUkfOrdering ordering : kOrderings) {
    SCOPED_TRACE(name(ordering));
    const long again = ordering == DualUkfOrdering::UpdatedParameters ? state : 0;
    long evaluations = 0;
    Model model;
    model.evaluations = &evaluations;
    mjukf::DualUkfSettingsFor<Model> s;
    s.initialCovariance = 0.1 * Eigen::Matrix2d::Identity();
    s.processNoise = 1e-5 * Eigen::Matrix2d::Identity();
    s.measurementNoise << 1e-2;
    s.initialParameterCovariance << 0.1;
    s.ordering = ordering;
    s.stepCheck.onOversized = mjukf::OversizedStep::Accept;  // the filter's own propagations alone
    DualUkf<Model, Euler> dual(model, Model::State(0.1, 0.0), Model::Param(1.5), s);
    const Model::Meas y(0.05);
    const double h = 1e-2;
    const auto count = [&](auto call) {
      evaluations = 0;
      EXPECT_TRUE(mjukf::taken(call()));
      return evaluations;
    };
    EXPECT_EQ(count([&] { return dual.timeUpdate(0.0, h); }), state + parameters);
    EXPECT_EQ(count([&] { return dual.measurementUpdate(y); }), again);
    EXPECT_EQ(count([&] { return dual.measurementUpdate(y); }), 0);  // no time update before it
    EXPECT_EQ(count([&] { return dual.timeUpdate(h, h, 3); }), 3 * (state + parameters));
    EXPECT_EQ(count([&] { return dual.measurementUpdate(y); }), 3 * again);
    EXPECT_EQ(count([&] { return dual.timeUpdate(4 * h, h, Model::Input(0.5), 2); }), 2 * (state + parameters));
    EXPECT_EQ(count([&] { return dual.measurementUpdate(y); }), 2 * again);
    EXPECT_EQ(count([&] { return dual.propagateMean(6 * h, h); }), 1);
    EXPECT_EQ(count([&] { return dual.measurementUpdate(y); }), 0);
    EXPECT_EQ(count([&] { return dual.timeUpdate(7 * h, h); }), state + parameters);
    evaluations = 0;
    EXPECT_EQ(dual.measurementUpdate(Model::Meas(std::nan(""))), Status::NonFiniteMeasurement);
    EXPECT_EQ(evaluations, 0);  // refused before anything runs
    EXPECT_EQ(count([&] { return dual.measurementUpdate(y); }), again);
  }
}

// The textbook dual UKF step, written out from docs/algorithms.md §9 with the public pieces: the parameter
// filter's time update P^θ⁻ = P^θ/λ + Q_θ, its points θⱼ of (θ̂, P^θ⁻), x̂_{k−1} + W (θⱼ − θ̂) propagated
// with each (W the filter's sensitivity before the step), Dⱼ = g(·, θⱼ), and the unscented correction
// with the state filter's innovation covariance `stateInnovation` (H P⁻ Hᵀ + R) plus
// parameterObservationNoise, by explicit inverse.
template <class Model, class Stepper, class InputAt>
void parameterStep(const Model& model, const mjukf::DualUkfSettingsFor<Model>& s, const typename Model::State& x,
                   const Eigen::Matrix<double, Model::StateDim, Model::ParamDim>& W, const typename Model::Param& theta,
                   Eigen::Matrix<double, Model::ParamDim, Model::ParamDim>& P, typename Model::Param& thetaOut,
                   InputAt&& inputAt, double t, double h, int steps, const typename Model::Meas& y,
                   const Eigen::Matrix<double, Model::MeasDim, Model::MeasDim>& stateInnovation) {
  constexpr int p = Model::ParamDim, m = Model::MeasDim;
  using PointSet = mjukf::MerweScaledSigmaPoints<double, p>;
  PointSet sigma(s.parameterSigmaPoints);
  typename PointSet::Points thetas;
  const Eigen::Matrix<double, p, p> prior = P / s.parameterForgetting + s.parameterProcessNoise;
  ASSERT_EQ(sigma.generate(theta, prior, thetas), Status::Ok);
  Eigen::Matrix<double, m, PointSet::Count> D;
  const Stepper stepper;
  for (int j = 0; j < PointSet::Count; ++j) {
    const typename Model::Param thetaJ = thetas.col(j);
    typename Model::State xj = x + W * (thetaJ - theta);
    for (int i = 0; i < steps; ++i)
      xj = stepper.step(
          [&](double time, const typename Model::State& z) { return model.derivative(time, z, inputAt(time), thetaJ); },
          t + i * h, xj, h);
    D.col(j) = model.measurement(xj, thetaJ);
  }
  const auto& wm = sigma.meanWeights();
  const auto& wc = sigma.covarianceWeights();
  const Eigen::Matrix<double, m, 1> predicted = D * wm;
  Eigen::Matrix<double, m, m> Pyy = stateInnovation + s.parameterObservationNoise;
  Eigen::Matrix<double, p, m> Pty = Eigen::Matrix<double, p, m>::Zero();
  for (int j = 0; j < PointSet::Count; ++j) {
    Pyy += wc(j) * (D.col(j) - predicted) * (D.col(j) - predicted).transpose();
    Pty += wc(j) * (thetas.col(j) - theta) * (D.col(j) - predicted).transpose();
  }
  const Eigen::Matrix<double, p, m> K = Pty * Pyy.inverse();
  thetaOut = theta + K * (y - predicted);
  P = prior - K * Pyy * K.transpose();
}

// Each step of both orderings rebuilt from outside. The parameters' random walk first (§9): with
// P^θ⁻ = P^θ / λ + Q_θ, G = P^θ (P^θ⁻)⁻¹ and C = P^θ − P^θ (P^θ⁻)⁻¹ P^θ (the textbook conditional
// covariance, where the library computes G N), x_{k−1} given θ_k is x̂_{k−1} + W G (θ_k − θ̂) with
// covariance P_{k−1} + W C Wᵀ. The parameter filter by the textbook step above, from that start, observing
// with the innovation covariance of a Ukf started at (x̂_{k−1}, P_{k−1} + W C Wᵀ) and run over the same step
// with θ̂_{k−1}; the state filter as that Ukf (PriorParameters), its estimate then moved by
// W_k (θ̂_k − θ̂_{k−1}), or as a Ukf started at x̂_{k−1} + W G (θ̂_k − θ̂_{k−1}) with the corrected θ̂_k
// (UpdatedParameters, which runs the time update again). Everything differs from the library's only in the
// order of a few hundred operations on O(1) numbers (rounding ≲ 100 ε ≈ 2e-14 per step, not compounded:
// each step starts again from the library's values), so 1e-12 absolute; without a walk (Q_θ = 0, λ = 1)
// the state filter's covariance bit for bit. Time updates over 1 and 3 steps and with a held input,
// λ = 0.98, Q_θ ≠ 0 (and both zero) and R_obs ≠ 0, with and without redrawn points.
TEST(DualUkf, EachStepIsTheTextbookDualStepInBothOrderings) {
  using Model = Spring<2>;
  const Model model;
  mjukf::DualUkfSettingsFor<Model> base;
  base.initialCovariance << 0.2, 0.05, 0.05, 0.3;
  base.processNoise = 1e-4 * Eigen::Matrix2d::Identity();
  base.measurementNoise << 0.01;
  base.initialParameterCovariance << 0.3, 0.02, 0.02, 0.05;
  base.parameterProcessNoise = 1e-5 * Eigen::Matrix2d::Identity();
  base.parameterObservationNoise << 0.003;
  base.parameterForgetting = 0.98;
  base.parameterSigmaPoints = {0.8, 2.0, 0.5};
  const double h = 0.01;
  for (const bool walking : {true, false}) {
    for (const DualUkfOrdering ordering : kOrderings) {
      for (const bool redraw : {false, true}) {
        SCOPED_TRACE(std::string(name(ordering)) + (redraw ? ", redrawn points" : "") + (walking ? "" : ", no walk"));
        auto s = base;
        s.ordering = ordering;
        s.redrawPointsForUpdate = redraw;
        if (!walking) {
          s.parameterProcessNoise.setZero();
          s.parameterForgetting = 1;
        }
        // Without a walk the state filter's prior is P's own factor: its covariance must then be the Ukf's
        // bit for bit (it shares the dual's code path and factors the same exactly symmetric P).
        const auto sameCovariance = [&](const Eigen::Matrix2d& a, const Eigen::Matrix2d& b) {
          return walking ? (a - b).cwiseAbs().maxCoeff() < 1e-12 : bitwiseSame(a, b);
        };
        DualUkf<Model, mjukf::Rk4<double>> dual(model, Model::State(0.3, 0.0), Model::Param(1.2, 0.7), s);
        Simulation<Model, mjukf::Rk4<double>> truth(model, Model::State(0.5, 0.0), Model::trueParameters(), h, 0.1, 3);
        double moved = 0;
        for (int k = 0; k < 300; ++k) {
          const double t = k * h;
          const Model::Meas y = truth.next(t);
          const Model::State x = dual.state();
          const Eigen::Matrix2d P = dual.covariance();
          const Model::Param theta = dual.parameters();
          const Eigen::Matrix2d W = dual.sensitivity();
          Eigen::Matrix2d Ptheta = dual.parameterCovariance();
          const int steps = k % 3 == 1 ? 3 : 1;
          const bool held = k % 3 == 2;
          const Model::Input u(0.25);
          ASSERT_EQ(held ? dual.timeUpdate(t, h, u, steps) : dual.timeUpdate(t, h, steps), Status::Ok) << k;
          ASSERT_EQ(dual.measurementUpdate(y), Status::Ok) << k;

          const Eigen::Matrix2d predicted = Ptheta / s.parameterForgetting + s.parameterProcessNoise;
          const Eigen::Matrix2d G = Ptheta * predicted.inverse();
          const Eigen::Matrix2d C = Ptheta - Ptheta * predicted.inverse() * Ptheta;
          const Eigen::Matrix2d startSensitivity = walking ? Eigen::Matrix2d(W * G) : W;
          auto us = stateSettings(s);
          us.initialCovariance = P;
          if (walking) {
            us.initialCovariance += W * C * W.transpose();
            us.initialCovariance = 0.5 * (us.initialCovariance + us.initialCovariance.transpose()).eval();
          }
          mjukf::Ukf<Model, mjukf::Rk4<double>> prior(model, x, theta, us);
          ASSERT_EQ(held ? prior.timeUpdate(t, h, u, steps) : prior.timeUpdate(t, h, steps), Status::Ok);
          ASSERT_EQ(prior.measurementUpdate(y), Status::Ok);

          Model::Param thetaNext;
          parameterStep<Model, mjukf::Rk4<double>>(
              model, s, x, startSensitivity, theta, Ptheta, thetaNext,
              [&](double time) { return held ? u : model.input(time); }, t, h, steps, y,
              prior.lastUpdate().innovationCovariance);
          ASSERT_LT((dual.parameters() - thetaNext).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
          ASSERT_LT((dual.parameterCovariance() - Ptheta).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;

          const Model::Param moveOfTheta = dual.parameters() - theta;
          if (ordering == DualUkfOrdering::PriorParameters) {
            ASSERT_TRUE(sameCovariance(dual.covariance(), prior.covariance())) << "step " << k;
            const Model::State expected = prior.state() + dual.sensitivity() * moveOfTheta;
            ASSERT_LT((dual.state() - expected).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
          } else {
            mjukf::Ukf<Model, mjukf::Rk4<double>> again(model, Model::State(x + startSensitivity * moveOfTheta),
                                                        dual.parameters(), us);
            ASSERT_EQ(held ? again.timeUpdate(t, h, u, steps) : again.timeUpdate(t, h, steps), Status::Ok);
            ASSERT_EQ(again.measurementUpdate(y), Status::Ok);
            ASSERT_TRUE(sameCovariance(dual.covariance(), again.covariance())) << "step " << k;
            ASSERT_LT((dual.state() - again.state()).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
          }
          moved = std::max(moved, (dual.parameters() - theta).cwiseAbs().maxCoeff());
        }
        EXPECT_GT(moved, 1e-3) << "the parameters never moved: the test would not see a wrong θ";
      }
    }
  }
}

// The orderings are different algorithms where θ enters the dynamics. Their first correction of θ is
// the same (both parameter filters propagate x̂₀ with the same θⱼ), but the state's is not: the second
// time update of UpdatedParameters uses θ̂₁ ≠ θ̂₀. From then on x̂ differs, so the parameter filters,
// which propagate x̂_{k−1}, part too. Over 5 s the gaps are small, since θ̂ moves little per step, but
// far above rounding (~1e-16 here): measured max |Δx̂| = 5.7e-6, max |Δθ̂| = 8.6e-9; asserted above
// a tenth of that.
TEST(DualUkf, OrderingsDifferWhereThetaDrivesTheDynamics) {
  using Model = Spring<2>;
  mjukf::DualUkfSettingsFor<Model> s;
  s.initialCovariance = 0.2 * Eigen::Matrix2d::Identity();
  s.processNoise = 1e-4 * Eigen::Matrix2d::Identity();
  s.measurementNoise << 0.01;
  s.initialParameterCovariance = 0.1 * Eigen::Matrix2d::Identity();
  s.parameterProcessNoise = 1e-6 * Eigen::Matrix2d::Identity();
  auto updated = s;
  updated.ordering = DualUkfOrdering::UpdatedParameters;
  DualUkf<Model, mjukf::Rk4<double>> prior(Model(), Model::State(0.3, 0.0), Model::Param(1.2, 0.7), s);
  DualUkf<Model, mjukf::Rk4<double>> corrected(Model(), Model::State(0.3, 0.0), Model::Param(1.2, 0.7), updated);
  Simulation<Model, mjukf::Rk4<double>> truth(Model(), Model::State(0.5, 0.0), Model::trueParameters(), 0.01, 0.1, 11);
  double stateGap = 0, parameterGap = 0;
  for (int k = 0; k < 500; ++k) {
    const Model::Meas y = truth.next(k * 0.01);
    ASSERT_EQ(prior.timeUpdate(k * 0.01, 0.01), Status::Ok);
    ASSERT_EQ(corrected.timeUpdate(k * 0.01, 0.01), Status::Ok);
    if (k == 0) {
      EXPECT_TRUE(bitwiseSame(prior.state(), corrected.state()));  // both predicted with θ̂₀
    }
    ASSERT_EQ(prior.measurementUpdate(y), Status::Ok);
    ASSERT_EQ(corrected.measurementUpdate(y), Status::Ok);
    if (k == 0) {
      EXPECT_TRUE(bitwiseSame(prior.parameters(), corrected.parameters()));
      EXPECT_TRUE(bitwiseSame(prior.parameterCovariance(), corrected.parameterCovariance()));
      EXPECT_FALSE(bitwiseSame(prior.state(), corrected.state()));
    }
    stateGap = std::max(stateGap, (prior.state() - corrected.state()).cwiseAbs().maxCoeff());
    parameterGap = std::max(parameterGap, (prior.parameters() - corrected.parameters()).cwiseAbs().maxCoeff());
  }
  std::printf("max |x̂ (prior) − x̂ (updated)| = %.3g, max |θ̂ (prior) − θ̂ (updated)| = %.3g\n", stateGap, parameterGap);
  EXPECT_GT(stateGap, 5.7e-7);
  EXPECT_GT(parameterGap, 8.6e-10);
}

// ---------------------------------------------------------------------------------------------------
// (e) The paper's robot data with the library's dual UKF settings.

// paper::FlexibleJointExperiment::dualUkf() over flexible_joint_reference.csv with the paper's
// schedule (I-TR-BDF2, h = 1 ms, a measurement every 5 steps): the run completes and the RMSE of θ
// from row 2000 (t ≥ 2 s) is finite and below the error of the first guess, |θ₀ − θ| = (0.05, 0.06).
// Seen when written (not asserted to this precision): RMSE (K_τ, m) = (0.00671, 0.00982) with
// PriorParameters, (0.00659, 0.00969) with UpdatedParameters; final θ̂ ≈ (0.1526, 0.2204) and
// (0.1526, 0.2203); σ_θ = (0.029, 0.053), no repairs. (JUKF's conformance RMSE is (0.0267, 0.0343),
// MJUKF's (0.0067, 0.0087).)
TEST(DualUkf, PaperRobotReferenceRun) {
  using Robot = mjukf::paper::FlexibleJointExperiment<double>;
  using Model = Robot::Model;
  const auto y = referenceMeasurements<Model::Meas>("flexible_joint_reference.csv");
  const Model::Param truth = Model::trueParameters();
  const Model::Param firstGuessError = (Robot::initialParameters() - truth).cwiseAbs();
  for (const DualUkfOrdering ordering : kOrderings) {
    SCOPED_TRACE(name(ordering));
    auto s = Robot::dualUkf();
    s.ordering = ordering;
    DualUkf<Model> filter(Model(), Robot::initialState(), Robot::initialParameters(), s);
    mjukf::paper::RmseAccumulator<double, 2> rmse;
    const auto outcome = mjukf::paper::runSchedule(
        filter, static_cast<long>(y.size()), Robot::stepSize, Robot::measurementEvery,
        [&](long k) -> const Model::Meas& { return y[static_cast<std::size_t>(k)]; },
        [&](long k, const DualUkf<Model>& f) {
          if (k >= Robot::rmseFromRow) rmse.add(f.parameters(), truth);
        });
    ASSERT_EQ(outcome.status, Status::Ok) << "stopped at row " << outcome.row;
    EXPECT_EQ(outcome.repairs, 0);
    EXPECT_EQ(rmse.count(), static_cast<long>(y.size()) - Robot::rmseFromRow);
    const Model::Param value = rmse.value();
    std::printf("%s: RMSE (K_tau, m) = (%.6g, %.6g), final θ̂ = (%.6g, %.6g), σ_θ = (%.3g, %.3g)\n", name(ordering),
                value(0), value(1), filter.parameters()(0), filter.parameters()(1),
                std::sqrt(filter.parameterCovariance()(0, 0)), std::sqrt(filter.parameterCovariance()(1, 1)));
    EXPECT_TRUE(value.allFinite());
    EXPECT_LT(value(0), firstGuessError(0));
    EXPECT_LT(value(1), firstGuessError(1));
  }
}

// ---------------------------------------------------------------------------------------------------
// float and double: both run a short schedule of the robot and the tank.

template <class Experiment>
void expectShortScheduleRuns(const std::string& file, long rows) {
  using Model = typename Experiment::Model;
  using Scalar = typename Model::Scalar;
  const auto y = referenceMeasurements<typename Model::Meas>(file);
  for (const DualUkfOrdering ordering : kOrderings) {
    SCOPED_TRACE(name(ordering));
    auto s = Experiment::dualUkf();
    s.ordering = ordering;
    DualUkf<Model> filter(Model(), Experiment::initialState(), Experiment::initialParameters(), s);
    const auto outcome = mjukf::paper::runSchedule(
        filter, rows, Experiment::stepSize, Experiment::measurementEvery,
        [&](long k) -> const typename Model::Meas& { return y[static_cast<std::size_t>(k)]; },
        [](long, const DualUkf<Model>&) {});
    ASSERT_EQ(outcome.status, Status::Ok) << "stopped at row " << outcome.row;
    EXPECT_TRUE(filter.state().allFinite());
    EXPECT_TRUE(filter.parameters().allFinite());
    EXPECT_TRUE(mjukf::testing::symmetricPositiveDefinite(filter.covariance()));
    EXPECT_TRUE(mjukf::testing::symmetricPositiveDefinite(filter.parameterCovariance()));
    EXPECT_NE(filter.parameters(), Experiment::initialParameters());
    static_assert(std::is_same_v<typename DualUkf<Model>::Scalar, Scalar>);
  }
}

TEST(DualUkf, FloatAndDoubleRunAShortSchedule) {
  expectShortScheduleRuns<mjukf::paper::FlexibleJointExperiment<double>>("flexible_joint_reference.csv", 2000);
  expectShortScheduleRuns<mjukf::paper::FlexibleJointExperiment<float>>("flexible_joint_reference.csv", 2000);
  expectShortScheduleRuns<mjukf::paper::CoupledTankExperiment<double>>("coupled_tank_reference.csv", 4000);
  expectShortScheduleRuns<mjukf::paper::CoupledTankExperiment<float>>("coupled_tank_reference.csv", 4000);
}

}  // namespace
