// The Cascaded Tanks model (mjukf/models/cascaded_tanks.hpp) against what its equations say: its steady
// state, the upper tank's overflow, the lower tank's and the sensor's ceilings, the terms switched off.

#include <cmath>

#include <gtest/gtest.h>

#include "mjukf/model.hpp"
#include "mjukf/models/cascaded_tanks.hpp"

namespace {

using Tanks = mjukf::models::CascadedTanks<double>;

static_assert(mjukf::checkModel<Tanks, 1>() && mjukf::isDiscreteTime<Tanks>);

Tanks::Param parameters(double k1, double k3, double k4, double hMax, double k5, double alpha, double offset) {
  return Tanks::parameters({k1, k3, k4, hMax, k5, alpha, offset});
}

TEST(CascadedTanksModel, ParametersRoundTrip) {
  const Tanks::Physical p = Tanks().physical(parameters(0.05, 0.1, 0.06, 20, 0.7, 0.3, 0.5));
  EXPECT_NEAR(p.k1, 0.05, 1e-15);
  EXPECT_NEAR(p.k3, 0.1, 1e-15);
  EXPECT_NEAR(p.k4, 0.06, 1e-15);
  EXPECT_NEAR(p.hMax, 20, 1e-13);
  EXPECT_NEAR(p.k5, 0.7, 1e-15);
  EXPECT_NEAR(p.alpha, 0.3, 1e-15);
  EXPECT_EQ(p.offset, 0.5);
}

// In balance, k₄u = k₁√x₁ = k₃x₂^α: a sample leaves the state where it is, and y = x₂ + c.
TEST(CascadedTanksModel, SteadyStateStays) {
  const Tanks model;
  const double k1 = 0.05, k3 = 0.1, k4 = 0.06, alpha = 0.3, u = 3;
  const Tanks::Param theta = parameters(k1, k3, k4, 20, 0.7, alpha, 0.5);
  const Tanks::State steady(std::pow(k4 * u / k1, 2), std::pow(k4 * u / k3, 1 / alpha));
  ASSERT_LT(steady(0), 20);
  ASSERT_LT(steady(1), 10);
  const Tanks::State next = model.transition(0, 4, steady, Tanks::Input(u), theta);
  EXPECT_NEAR(next(0), steady(0), 1e-12);
  EXPECT_NEAR(next(1), steady(1), 1e-12);
  EXPECT_NEAR(model.measurement(steady, theta)(0), steady(1) + 0.5, 1e-15);
}

// Above h_max the upper tank is cut to h_max after the first sub-step, and the share k₅ of what was
// above falls into the lower tank; with the orifices closed, nothing else moves.
TEST(CascadedTanksModel, UpperTankSpillsTheShareK5) {
  const Tanks model;
  const Tanks::Param theta = parameters(1e-12, 1e-12, 0.06, 8, 0.7, 0.5, 0);
  const Tanks::State next = model.transition(0, 4, Tanks::State(9, 2), Tanks::Input(0), theta);
  EXPECT_NEAR(next(0), 8, 1e-9);
  EXPECT_NEAR(next(1), 2 + 0.7 * 1, 1e-9);
}

// The lower tank holds 10 V at most and the sensor reads 10 V at most; no level goes below 0.
TEST(CascadedTanksModel, CeilingsAndFloor) {
  const Tanks model;
  const Tanks::Param theta = parameters(0.05, 0.1, 0.06, 8, 1, 0.5, 0.5);
  const Tanks::State full = model.transition(0, 4, Tanks::State(8, 10), Tanks::Input(10), theta);
  EXPECT_LE(full(1), 10);
  EXPECT_EQ(model.measurement(Tanks::State(1, 9.8), theta)(0), 10);
  const Tanks::State empty = model.transition(0, 4, Tanks::State(0, 0), Tanks::Input(0), theta);
  EXPECT_EQ(empty(0), 0);
  EXPECT_EQ(empty(1), 0);
}

// With the terms off: Torricelli's ½ below, no offset, no ceilings.
TEST(CascadedTanksModel, TermsOff) {
  Tanks model;
  model.terms = {false, false, false, false};
  const Tanks::Param theta = parameters(0.05, 0.1, 0.06, 8, 1, 0.3, 0.5);
  EXPECT_EQ(model.physical(theta).alpha, 0.5);
  EXPECT_EQ(model.measurement(Tanks::State(1, 12), theta)(0), 10);  // the sensor's range still ends at 10
  EXPECT_EQ(model.measurement(Tanks::State(1, 4), theta)(0), 4);
  const Tanks::State next = model.transition(0, 4, Tanks::State(9, 11), Tanks::Input(0), theta);
  EXPECT_GT(next(0), 8);   // no spill
  EXPECT_GT(next(1), 10);  // no ceiling
}

}  // namespace
