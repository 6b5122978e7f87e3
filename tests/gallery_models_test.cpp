// The gallery's plants (mjukf/models/dc_motor.hpp, thevenin_battery.hpp, lotka_volterra.hpp,
// heated_block.hpp, michaelis_menten.hpp) against what their equations say without going through the
// same code: steady states in closed form, a conserved quantity, the exact discretisation's semigroup
// property, the signs of the sensitivities their documentation states, and their input signals.

#include <cmath>

#include <gtest/gtest.h>

#include "mjukf/model.hpp"
#include "mjukf/models/dc_motor.hpp"
#include "mjukf/models/heated_block.hpp"
#include "mjukf/models/lotka_volterra.hpp"
#include "mjukf/models/michaelis_menten.hpp"
#include "mjukf/models/thevenin_battery.hpp"

namespace {

using mjukf::models::DcMotor;
using mjukf::models::HeatedBlock;
using mjukf::models::LotkaVolterra;
using mjukf::models::MichaelisMentenInfusion;
using mjukf::models::TheveninBattery;

static_assert(mjukf::checkModel<DcMotor<double>, 1>() && mjukf::checkModel<DcMotor<float>, 1>());
static_assert(mjukf::checkModel<TheveninBattery<double>, 1>() && mjukf::isDiscreteTime<TheveninBattery<double>> &&
              mjukf::measurementTakesInput<TheveninBattery<double>>);
static_assert(mjukf::checkModel<LotkaVolterra<double>, 1>() && LotkaVolterra<double>::InputDim == 0);
static_assert(mjukf::checkModel<HeatedBlock<double>, 1>() && mjukf::checkModel<HeatedBlock<long double>, 1>());
static_assert(mjukf::checkModel<MichaelisMentenInfusion<double>, 1>());

// The time average of input(t) over [0, period), sampled every `dt` (the signals are piecewise
// constant on multiples of dt, so the average is exact up to rounding).
template <class Model>
double averageInput(const Model& model, double period, double dt) {
  double sum = 0;
  const long samples = std::lround(period / dt);
  for (long k = 0; k < samples; ++k) sum += model.input((double(k) + 0.5) * dt)(0);
  return sum / double(samples);
}

// At constant voltage the speed settles at ω = K u / (b R + K²): ω̇ is zero there. A larger K raises
// ω̇ and a larger b lowers it (at the truth and at the gallery's first guess, K² < b R), and the
// encoder reads the angle alone. The voltage has mean zero over its 2 s period.
TEST(DcMotor, SteadySpeedAndOppositeSensitivities) {
  const DcMotor<double> model;
  for (const DcMotor<double>::Param& theta : {DcMotor<double>::trueParameters(), DcMotor<double>::Param(0.02, 5e-4)}) {
    const double k = theta(0), b = theta(1), u = 12;
    const double steady = k * u / (b * model.resistance + k * k);
    const DcMotor<double>::State x(3.0, steady);
    EXPECT_NEAR(model.derivative(0, x, DcMotor<double>::Input::Constant(u), theta)(1), 0.0, 1e-9);
    const auto rise = [&](const DcMotor<double>::Param& other) {
      return model.derivative(0, x, DcMotor<double>::Input::Constant(u), other)(1);
    };
    EXPECT_GT(rise(theta + DcMotor<double>::Param(1e-4, 0)), 0.0) << "K raises the speed";
    EXPECT_LT(rise(theta + DcMotor<double>::Param(0, 1e-5)), 0.0) << "b lowers it";
    EXPECT_EQ(model.measurement(x, theta)(0), 3.0);
  }
  EXPECT_NEAR(averageInput(model, 2.0, 1e-3), 0.0, 1e-9);
  EXPECT_EQ(model.input(0.1)(0), 12.0);
  EXPECT_EQ(model.input(1.7)(0), 0.0);
}

// The transition is the exact solution of the circuit under a held current: two samples of dt/2 make
// one of dt. The OCV curve rises from 3.2 V to 4.1 V, and y = OCV(z) − v₁ − R₀ i. The profile takes
// 0.875 A on average.
TEST(TheveninBattery, ExactDiscretisationAndMeasurement) {
  const TheveninBattery<double> model;
  const auto theta = TheveninBattery<double>::trueParameters();
  const TheveninBattery<double>::State x(0.8, 0.05);
  const TheveninBattery<double>::Input i = TheveninBattery<double>::Input::Constant(3.0);
  const auto once = model.transition(0, 1.0, x, i, theta);
  const auto twice = model.transition(0.5, 0.5, model.transition(0, 0.5, x, i, theta), i, theta);
  EXPECT_NEAR(once(0), twice(0), 1e-15);
  EXPECT_NEAR(once(1), twice(1), 1e-15);
  EXPECT_NEAR(once(0), 0.8 - 3.0 / 9000, 1e-15);
  // Held long, v₁ settles at R₁ i.
  auto settled = x;
  for (int k = 0; k < 2000; ++k) settled = model.transition(k, 1.0, settled, i, theta);
  EXPECT_NEAR(settled(1), theta(1) * 3.0, 1e-12);

  EXPECT_DOUBLE_EQ(TheveninBattery<double>::openCircuitVoltage(0), 3.2);
  EXPECT_DOUBLE_EQ(TheveninBattery<double>::openCircuitVoltage(1), 4.1);
  for (double z = 0; z < 1; z += 0.01)
    EXPECT_LT(TheveninBattery<double>::openCircuitVoltage(z), TheveninBattery<double>::openCircuitVoltage(z + 0.01));
  EXPECT_NEAR(model.measurement(x, i, theta)(0), TheveninBattery<double>::openCircuitVoltage(0.8) - 0.05 - 0.05 * 3.0,
              1e-15);
  EXPECT_NEAR(averageInput(model, 600, 1.0), 0.875, 1e-12);
  EXPECT_EQ(model.input(300)(0), 5.0);  // a pulse starts at its first second
  EXPECT_EQ(model.input(299)(0), 0.0);
}

// V = δ x − γ ln x + β y − α ln y is constant along the cycles: V̇ = ∇V · ẋ = 0 at any state.
TEST(LotkaVolterra, ConservedQuantityAndEquilibrium) {
  const LotkaVolterra<double> model;
  const auto theta = LotkaVolterra<double>::trueParameters();
  for (const LotkaVolterra<double>::State& x :
       {LotkaVolterra<double>::State(10, 5), LotkaVolterra<double>::State(0.7, 2.2),
        LotkaVolterra<double>::State(13, 0.9)}) {
    const auto dx = model.derivative(0, x, {}, theta);
    const double gradient0 = theta(0) - theta(1) / x(0);
    const double gradient1 = model.predation - model.preyGrowth / x(1);
    EXPECT_NEAR(gradient0 * dx(0) + gradient1 * dx(1), 0.0, 1e-12);
    EXPECT_EQ(model.measurement(x, theta)(0), x(0));
  }
  const LotkaVolterra<double>::State rest(theta(1) / theta(0), model.preyGrowth / model.predation);
  EXPECT_NEAR(model.derivative(0, rest, {}, theta).norm(), 0.0, 1e-14);
}

// At a steady power P the block is P / G_ba above the room and the element P / G_hb above the block;
// the heat the element takes in, C_h Ṫ_h + C_b Ṫ_b, is P minus the loss G_ba (T_b − T_a).
TEST(HeatedBlock, SteadyStateAndEnergyBalance) {
  const HeatedBlock<double> model;
  const auto theta = HeatedBlock<double>::trueParameters();
  const HeatedBlock<double>::Input power = HeatedBlock<double>::Input::Constant(200);
  const double block = model.ambient + 200 / theta(1);
  const HeatedBlock<double>::State steady(block + 200 / theta(0), block);
  EXPECT_NEAR(model.derivative(0, steady, power, theta).norm(), 0.0, 1e-12);
  const HeatedBlock<double>::State x(41.0, 30.5);
  const auto dx = model.derivative(0, x, power, theta);
  EXPECT_NEAR(model.heaterCapacity * dx(0) + model.blockCapacity * dx(1), 200 - theta(1) * (30.5 - model.ambient),
              1e-10);
  EXPECT_EQ(model.measurement(x, theta), x);
  EXPECT_NEAR(averageInput(model, 600, 0.02), (200 * 200 + 100 * 100) / 600.0, 1e-9);
}

// At a constant rate u < V V_max the concentration settles at c = K_m u / (V V_max − u); the
// elimination is V_max / K_m per hour well below K_m and V_max well above it.
TEST(MichaelisMentenInfusion, SteadyStateAndItsTwoRegimes) {
  const MichaelisMentenInfusion<double> model;
  const auto theta = MichaelisMentenInfusion<double>::trueParameters();
  const double u = 60;
  const MichaelisMentenInfusion<double>::State steady =
      MichaelisMentenInfusion<double>::State::Constant(theta(1) * u / (model.volume * theta(0) - u));
  EXPECT_NEAR(model.derivative(0, steady, MichaelisMentenInfusion<double>::Input::Constant(u), theta)(0), 0.0, 1e-12);
  const auto elimination = [&](double c) {
    return -model.derivative(0, MichaelisMentenInfusion<double>::State::Constant(c),
                             MichaelisMentenInfusion<double>::Input::Zero(), theta)(0);
  };
  EXPECT_NEAR(elimination(1e-6) / 1e-6, theta(0) / theta(1), 1e-6);
  EXPECT_NEAR(elimination(1e6), theta(0), 1e-4);
  EXPECT_EQ(model.input(3)(0), 95.0);
  EXPECT_EQ(model.input(30)(0), 50.0);
  EXPECT_EQ(model.input(50)(0), 80.0);
  EXPECT_EQ(model.input(80)(0), 95.0);  // the fourth day as the first
  EXPECT_EQ(model.input(13)(0), 0.0);
}

}  // namespace
