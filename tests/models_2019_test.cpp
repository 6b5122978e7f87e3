// The 2019 MJUKF paper's systems (mjukf/models/van_der_pol.hpp, lorenz.hpp) against evaluations that do
// not go through their `derivative`: a known exact solution differentiated by central differences, the
// known equilibria, the analytic Jacobians, and ∂ẋ/∂θ by differences in θ against the equations.

#include <cmath>

#include <gtest/gtest.h>

#include "mjukf/model.hpp"
#include "mjukf/models/lorenz.hpp"
#include "mjukf/models/van_der_pol.hpp"

namespace {

using mjukf::models::Lorenz;
using mjukf::models::VanDerPol;

static_assert(mjukf::checkModel<VanDerPol<double>, 1>());
static_assert(mjukf::checkModel<Lorenz<double>, 1>());
static_assert(mjukf::checkModel<VanDerPol<float>, 1>() && mjukf::checkModel<Lorenz<long double>, 1>());

// Central difference (f(s + d) − f(s − d)) / 2d: truncation d²/6 |f'''| plus rounding about
// ε |f| / d. With d = 1e-4 and |f|, |f'''| ≤ 1 on the unit circle both are below 1e-9; 1e-8 leaves room.
constexpr double kDelta = 1e-4;
constexpr double kCentralTolerance = 1e-8;

// μ = 0 leaves the harmonic oscillator, whose solution from (1, 0) is x(t) = (cos t, −sin t): the
// model's ẋ at x(t) must be the time derivative of that solution.
TEST(VanDerPol, DerivativeAtZeroDampingIsThatOfTheHarmonicSolution) {
  const VanDerPol<double> model;
  const auto solution = [](double t) { return VanDerPol<double>::State(std::cos(t), -std::sin(t)); };
  for (double t : {0.0, 0.3, 1.7, 2.9, 4.4, 6.0}) {
    const VanDerPol<double>::State difference = (solution(t + kDelta) - solution(t - kDelta)) / (2 * kDelta);
    const auto derivative = model.derivative(t, solution(t), {}, VanDerPol<double>::Param::Zero());
    EXPECT_NEAR(derivative(0), difference(0), kCentralTolerance) << "t = " << t;
    EXPECT_NEAR(derivative(1), difference(1), kCentralTolerance) << "t = " << t;
  }
}

// ẋ is linear in μ with ∂ẋ/∂μ = (0, (1 − x₁²) x₂): a difference in μ is exact up to rounding, so the
// tolerance is a few ε of the terms' size (about 10 here).
TEST(VanDerPol, ParameterSensitivityIsTheDampingTerm) {
  const VanDerPol<double> model;
  const VanDerPol<double>::State x(1.4, -2.5);
  const auto at = [&](double mu) { return model.derivative(0.0, x, {}, VanDerPol<double>::Param::Constant(mu)); };
  const VanDerPol<double>::State sensitivity = (at(0.7) - at(0.2)) / 0.5;
  EXPECT_NEAR(sensitivity(0), 0.0, 1e-13);
  EXPECT_NEAR(sensitivity(1), (1 - 1.4 * 1.4) * -2.5, 1e-13);
  EXPECT_EQ(model.measurement(x, VanDerPol<double>::trueParameters()), x);
  EXPECT_EQ(VanDerPol<double>::trueParameters()(0), 0.2);
}

// The Lorenz system rests at the origin and at C± = (±√(β(ρ − 1)), ±√(β(ρ − 1)), ρ − 1); ẋ there
// is zero up to the rounding of terms of size ρ·|x| ≈ 240 (tolerance 1e-12).
TEST(Lorenz, EquilibriaAreAtRest) {
  const Lorenz<double> model;
  const auto theta = Lorenz<double>::trueParameters();
  const double c = std::sqrt(theta(2) * (theta(1) - 1));
  for (const Lorenz<double>::State& x : {Lorenz<double>::State(0, 0, 0), Lorenz<double>::State(c, c, theta(1) - 1),
                                         Lorenz<double>::State(-c, -c, theta(1) - 1)})
    EXPECT_LT(model.derivative(0.0, x, {}, theta).cwiseAbs().maxCoeff(), 1e-12) << x.transpose();
}

// The Jacobian by central differences against the analytic one,
// [[−σ, σ, 0], [ρ − x₃, −1, −x₁], [x₂, x₁, −β]]; ẋ is quadratic in x, so the central difference is
// exact up to rounding of terms of size about 300 over 2d (tolerance 1e-8).
TEST(Lorenz, JacobianMatchesTheAnalyticOne) {
  const Lorenz<double> model;
  const Lorenz<double>::Param theta(10, 28, 8.0 / 3.0);
  const Lorenz<double>::State x(-3.2, 4.1, 19.5);
  Eigen::Matrix3d analytic;
  analytic << -theta(0), theta(0), 0, theta(1) - x(2), -1, -x(0), x(1), x(0), -theta(2);
  for (int j = 0; j < 3; ++j) {
    const Lorenz<double>::State step = Lorenz<double>::State::Unit(j) * kDelta;
    const Lorenz<double>::State column =
        (model.derivative(0.0, x + step, {}, theta) - model.derivative(0.0, x - step, {}, theta)) / (2 * kDelta);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(column(i), analytic(i, j), 1e-8) << "(" << i << ", " << j << ")";
  }
}

// Each parameter enters one component linearly: ∂ẋ/∂θ = diag(x₂ − x₁, x₁, −x₃), exact in a difference.
TEST(Lorenz, ParameterSensitivitiesAreDiagonal) {
  const Lorenz<double> model;
  const Lorenz<double>::Param theta = Lorenz<double>::trueParameters();
  const Lorenz<double>::State x(-3.2, 4.1, 19.5);
  const Eigen::Vector3d expected(x(1) - x(0), x(0), -x(2));
  for (int j = 0; j < 3; ++j) {
    const Lorenz<double>::State column =
        model.derivative(0.0, x, {}, theta + Lorenz<double>::Param::Unit(j)) - model.derivative(0.0, x, {}, theta);
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(column(i), i == j ? expected(i) : 0.0, 1e-12) << "(" << i << ", " << j << ")";
  }
  EXPECT_EQ(model.measurement(x, theta), x);
}

}  // namespace
