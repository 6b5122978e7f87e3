// simulate() and stepModel(): closed-form solutions within RK4's error bound, the input taken from the
// model's signal at every stage time or held, the rows the visitor sees, parameters switched at the
// right row, and bit-for-bit agreement with the hand-written loop it replaced.

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "mjukf/integrators/i_tr_bdf2.hpp"
#include "mjukf/integrators/rk4.hpp"
#include "mjukf/models/flexible_joint.hpp"
#include "mjukf/simulation.hpp"
#include "robustness_support.hpp"

namespace {

using mjukf::testing::bitwiseSame;

// ẋ = −λ x, θ = λ; no input at all (InputDim = 0, no input(t)).
struct Decay {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 0;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = Eigen::Matrix<double, 1, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 0, 1>;
  State derivative(double, const State& x, const Input&, const Param& lambda) const { return -lambda(0) * x; }
  Meas measurement(const State& x, const Param&) const { return x; }
};

// ẋ = u − λ x with the signal u(t) = 4 t³.
struct Driven {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 1, MeasDim = 1, InputDim = 1;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = Eigen::Matrix<double, 1, 1>;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Matrix<double, 1, 1>;
  Input input(double t) const { return Input(4 * t * t * t); }
  State derivative(double, const State& x, const Input& u, const Param& lambda) const { return u - lambda(0) * x; }
  Meas measurement(const State& x, const Param&) const { return x; }
};

using Vec1 = Eigen::Matrix<double, 1, 1>;

struct Row {
  long k;
  double t;
  double x;
};

TEST(Simulation, LinearDecayWithRk4IsWithinItsErrorBound) {
  // One RK4 step on ẋ = −λx multiplies by R(z) = 1 + z + z²/2 + z³/6 + z⁴/24, z = −λh, and
  // |e^z − R(z)| ≤ |z|⁵/120 for z ≤ 0 (Taylor remainder). With 0 < R(z), e^z ≤ 1 (here z = −0.1) the
  // global error after k steps is at most k |z|⁵/120 |x₀|.
  const double lambda = 2, h = 0.05, t0 = 0.5, x0 = 1.5;
  const long steps = 40;
  std::vector<Row> rows;
  const auto last = mjukf::simulate(Decay(), mjukf::Rk4<double>(), Vec1(x0), Vec1(lambda), t0, h, steps,
                                    [&](long k, double t, const Decay::State& x) {
                                      rows.push_back({k, t, x(0)});
                                    });
  ASSERT_EQ(rows.size(), std::size_t(steps + 1));
  const double z = lambda * h;
  double largest = 0;
  for (long k = 0; k <= steps; ++k) {
    const Row& row = rows[std::size_t(k)];
    EXPECT_EQ(row.k, k);
    EXPECT_EQ(row.t, t0 + double(k) * h);  // computed from k, bit for bit
    const double error = std::abs(row.x - x0 * std::exp(-lambda * double(k) * h));
    EXPECT_LE(error, double(k) * std::pow(z, 5) / 120 * x0 + 1e-15) << "row " << k;
    largest = std::max(largest, error);
  }
  EXPECT_EQ(rows.front().x, x0);
  EXPECT_EQ(rows.back().x, last(0));
  EXPECT_GT(largest, 0.0);  // the bound is not met trivially

  // Fourth order: half the step, about a sixteenth of the error at the same time.
  const auto finer = mjukf::simulate(Decay(), mjukf::Rk4<double>(), Vec1(x0), Vec1(lambda), t0, h / 2, 2 * steps,
                                     [](long, double, const Decay::State&) {});
  const double exact = x0 * std::exp(-lambda * double(steps) * h);
  const double ratio = std::abs(last(0) - exact) / std::abs(finer(0) - exact);
  EXPECT_GT(ratio, 14.0);
  EXPECT_LT(ratio, 18.0);
}

TEST(Simulation, SignalInputIsEvaluatedAtEveryStageTime) {
  // λ = 0: ẋ = 4t³, x = t⁴ + c. RK4 reduces to Simpson's rule, exact for a cubic integrand, so only
  // rounding remains; an input held at t_k over each step would be off by O(h).
  const double t0 = 0.25, h = 0.05;
  const long steps = 30;
  const Vec1 none(0.0);
  const auto x = mjukf::simulate(Driven(), mjukf::Rk4<double>(), Vec1(1.0), none, t0, h, steps,
                                 [&](long k, double t, const Driven::State& xk) {
                                   EXPECT_NEAR(xk(0), 1.0 + std::pow(t, 4) - std::pow(t0, 4), 1e-12) << "row " << k;
                                 });
  EXPECT_NEAR(x(0), 1.0 + std::pow(t0 + double(steps) * h, 4) - std::pow(t0, 4), 1e-12);

  // The same through stepModel, one step.
  const auto one = mjukf::stepModel(Driven(), mjukf::Rk4<double>(), t0, h, Vec1(1.0), none);
  EXPECT_NEAR(one(0), 1.0 + std::pow(t0 + h, 4) - std::pow(t0, 4), 1e-14);
}

TEST(Simulation, HeldAndCallableInputs) {
  // A held u = 2: x = x₀ + 2 (t − t₀), exact for any Runge–Kutta method up to rounding.
  const double t0 = 1.0, h = 0.01;
  const long steps = 100;
  const Vec1 none(0.0);
  const auto ignore = [](long, double, const Driven::State&) {};
  const auto held =
      mjukf::simulate(Driven(), mjukf::Rk4<double>(), Vec1(0.5), Driven::Input(2.0), none, t0, h, steps, ignore);
  EXPECT_NEAR(held(0), 0.5 + 2.0 * double(steps) * h, 1e-12);
  // An expression convertible to the input is a held input too.
  const auto zero =
      mjukf::simulate(Driven(), mjukf::Rk4<double>(), Vec1(0.5), Driven::Input::Zero(), none, t0, h, steps, ignore);
  EXPECT_EQ(zero(0), 0.5);
  // A callable input equal to the model's signal gives the model's signal's result bit for bit.
  const Driven model;
  const auto signal = mjukf::simulate(model, mjukf::Rk4<double>(), Vec1(0.5), none, t0, h, steps, ignore);
  const auto callable = mjukf::simulate(
      model, mjukf::Rk4<double>(), Vec1(0.5), [&](double t) { return model.input(t); }, none, t0, h, steps, ignore);
  EXPECT_TRUE(bitwiseSame(signal, callable));
}

TEST(Simulation, ParameterCallableSwitchesAtTheRightRow) {
  // θ_k = λ₁ for the steps from rows k < m, λ₂ from row m on: the same as simulating m steps with λ₁,
  // then the rest with λ₂ from x_m (the decay is autonomous, so the restarted grid's times do not matter).
  const double h = 0.01, lambda1 = 0.5, lambda2 = 3.0;
  const long steps = 50, m = 20;
  const mjukf::ITrBdf2<double> integrator;
  std::vector<long> asked;
  std::vector<double> switched;
  mjukf::simulate(
      Decay(), integrator, Vec1(1.0),
      [&](long k) {
        asked.push_back(k);
        return Vec1(k < m ? lambda1 : lambda2);
      },
      0.0, h, steps, [&](long, double, const Decay::State& x) { switched.push_back(x(0)); });
  std::vector<long> expectedAsked(steps);
  for (long k = 0; k < steps; ++k) expectedAsked[std::size_t(k)] = k;
  EXPECT_EQ(asked, expectedAsked);  // once per step, in order, never for the last row
  ASSERT_EQ(switched.size(), std::size_t(steps + 1));

  std::vector<double> piecewise;
  const auto keep = [&](long, double, const Decay::State& x) { piecewise.push_back(x(0)); };
  const auto xm = mjukf::simulate(Decay(), integrator, Vec1(1.0), Vec1(lambda1), 0.0, h, m, keep);
  piecewise.pop_back();  // x_m again as the first row of the second part
  mjukf::simulate(Decay(), integrator, xm, Vec1(lambda2), double(m) * h, h, steps - m, keep);
  ASSERT_EQ(piecewise.size(), switched.size());
  for (std::size_t k = 0; k < switched.size(); ++k) EXPECT_EQ(switched[k], piecewise[k]) << "row " << k;
  // Rows up to m are those of λ₁ alone; row m + 1 is the first that λ₂ reaches.
  EXPECT_EQ(switched[std::size_t(m)], xm(0));
  EXPECT_LT(switched[std::size_t(m + 1)], xm(0) * std::exp(-lambda1 * h) - 1e-6);
}

TEST(Simulation, ZeroStepsVisitsTheInitialStateOnlyAndNegativeIsRefused) {
  std::vector<Row> rows;
  const auto x = mjukf::simulate(Decay(), mjukf::Rk4<double>(), Vec1(2.0), Vec1(1.0), 3.0, 0.1, 0,
                                 [&](long k, double t, const Decay::State& xk) {
                                   rows.push_back({k, t, xk(0)});
                                 });
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].k, 0);
  EXPECT_EQ(rows[0].t, 3.0);
  EXPECT_EQ(rows[0].x, 2.0);
  EXPECT_EQ(x(0), 2.0);
  EXPECT_THROW(mjukf::simulate(Decay(), mjukf::Rk4<double>(), Vec1(2.0), Vec1(1.0), 0.0, 0.1, -1,
                               [](long, double, const Decay::State&) {}),
               std::invalid_argument);
}

TEST(Simulation, SameBitsAsTheHandWrittenLoopItReplaced) {
  // The robot with I-TR-BDF2, as the tests, examples and benchmarks integrated it before simulate():
  // their expected values and the conformance figures depend on these bits.
  using Model = mjukf::models::FlexibleJoint<double>;
  const Model model;
  const mjukf::ITrBdf2<double> integrator;
  const auto theta = Model::trueParameters();
  const double h = 1e-3;
  const long steps = 2000;
  std::vector<Model::State> byHand(std::size_t(steps + 1));
  byHand[0] = Model::State(0.1, -0.2, 0.0, 0.3);
  for (long k = 0; k < steps; ++k) {
    const auto f = [&](double t, const Model::State& x) { return model.derivative(t, x, model.input(t), theta); };
    byHand[std::size_t(k + 1)] = integrator.step(f, double(k) * h, byHand[std::size_t(k)], h);
  }
  long visited = 0;
  mjukf::simulate(model, integrator, byHand[0], theta, 0.0, h, steps, [&](long k, double, const Model::State& x) {
    ++visited;
    EXPECT_TRUE(bitwiseSame(x, byHand[std::size_t(k)])) << "row " << k;
  });
  EXPECT_EQ(visited, steps + 1);
}

TEST(Simulation, FloatModelFollowsTheDoubleOne) {
  // Compiles for a float model and stepper, with the time grid in float.
  using ModelF = mjukf::models::FlexibleJoint<float>;
  using ModelD = mjukf::models::FlexibleJoint<double>;
  const auto xF = mjukf::simulate(ModelF(), mjukf::ITrBdf2<float>(), ModelF::State::Zero(), ModelF::trueParameters(),
                                  0.0f, 1e-3f, 1000, [](long, float, const ModelF::State&) {});
  const auto xD = mjukf::simulate(ModelD(), mjukf::ITrBdf2<double>(), ModelD::State::Zero(), ModelD::trueParameters(),
                                  0.0, 1e-3, 1000, [](long, double, const ModelD::State&) {});
  EXPECT_LT((xF.cast<double>() - xD).cwiseAbs().maxCoeff(), 1e-4 * (1 + xD.cwiseAbs().maxCoeff()));
}

}  // namespace
