// Forced faults of the health monitor's issue: parameters the data cannot inform. A filter that ends far
// from such a parameter's truth must say so, by an alarm or by a standard deviation of θ̂ that still
// covers the truth (docs/robustness.md, "The health monitor", "What it cannot see"): an estimate that
// wanders off under a shrinking σ with health() Ok is the silent failure these tests look for.

#include <cmath>
#include <random>
#include <tuple>
#include <type_traits>
#include <utility>

#include <gtest/gtest.h>

#include "mjukf/mjukf.hpp"

namespace {

using mjukf::Health;

// A tank driven by known inputs, its level measured, u₁ = sin(0.05 k) + 1 and u₂ = 0. With `ProductOnly`
// false, x⁺ = 0.9 x + θ₁ u₁ + θ₂ u₂: nothing in the data depends on θ₂. With it true,
// x⁺ = 0.9 x + θ₁ θ₂ u₁: the data inform the product alone, neither parameter by itself.
template <bool ProductOnly>
struct TwoInputTank {
  using Scalar = double;
  static constexpr int StateDim = 1, ParamDim = 2, MeasDim = 1, InputDim = 2;
  using State = Eigen::Matrix<double, 1, 1>;
  using Param = Eigen::Vector2d;
  using Meas = Eigen::Matrix<double, 1, 1>;
  using Input = Eigen::Vector2d;
  Input input(double t) const { return Input(std::sin(0.05 * t) + 1, 0.0); }
  State transition(double, double, const State& x, const Input& u, const Param& theta) const {
    if constexpr (ProductOnly) return State(0.9 * x(0) + theta(0) * theta(1) * u(0));
    return State(0.9 * x(0) + theta(0) * u(0) + theta(1) * u(1));
  }
  Meas measurement(const State& x, const Param&) const { return x; }
};

constexpr double kQ = 1e-4, kR = 1e-2;
const Eigen::Vector2d kTruth(1.0, 5.0);
const Eigen::Vector2d kGuess(0.5, 2.0);  // θ₂ guessed 3 off: 2.9 σ₀ for JUKF and the dual
const Eigen::Vector2d kPriorSigma(0.5, 1.05);

struct Outcome {
  Eigen::Vector2d estimate;
  Eigen::Matrix2d covariance;  // of θ̂, the filter's own
  Health health = Health::Ok;
};

// `filter` over 2000 updates of seed `seed` of its plant; every step must be taken.
template <class Filter>
Outcome run(Filter filter, unsigned seed) {
  const typename Filter::Model plant;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  typename Filter::Model::State x(0);
  for (int k = 0; k < 2000; ++k) {
    const double t = k;
    x = plant.transition(t, 1, x, plant.input(t), kTruth);
    x(0) += std::sqrt(kQ) * normal(rng);
    const typename Filter::Model::Meas y(x(0) + std::sqrt(kR) * normal(rng));
    EXPECT_TRUE(mjukf::taken(filter.timeUpdate(t, 1.0))) << k;
    EXPECT_TRUE(mjukf::taken(filter.measurementUpdate(y))) << k;
  }
  Outcome out{filter.parameters(), Eigen::Matrix2d::Zero(), filter.health()};
  if constexpr (std::decay_t<decltype(filter.covariance())>::RowsAtCompileTime == 3)  // JUKF: the θ block of P
    out.covariance = filter.covariance().template bottomRightCorner<2, 2>();
  else
    out.covariance = filter.parameterCovariance();
  return out;
}

// Every filter as the gallery sets it up: JUKF and the dual with the prior kPriorSigma, the automatic
// MJUKF with the state's P₀, Q and R alone (its prior scale of θ is then |θ̂₀|).
template <class Plant>
Outcome jointUkf(unsigned seed) {
  mjukf::JointUkfSettingsFor<Plant> s;
  s.initialCovariance.diagonal() << 1, kPriorSigma.array().square();
  s.processNoise(0, 0) = kQ;
  s.measurementNoise(0, 0) = kR;
  return run(mjukf::JointUkf<Plant>(Plant(), typename Plant::State(0), kGuess, s), seed);
}
template <class Plant>
Outcome dualUkf(unsigned seed) {
  mjukf::DualUkfSettingsFor<Plant> s;
  s.initialCovariance(0, 0) = 1;
  s.processNoise(0, 0) = kQ;
  s.measurementNoise(0, 0) = kR;
  s.initialParameterCovariance.diagonal() = kPriorSigma.array().square();
  return run(mjukf::DualUkf<Plant>(Plant(), typename Plant::State(0), kGuess, s), seed);
}
template <class Plant>
Outcome automaticMjukf(unsigned seed) {
  mjukf::ModifiedJointUkfSettingsFor<Plant> s;
  s.initialCovariance(0, 0) = 1;
  s.processNoise(0, 0) = kQ;
  s.measurementNoise(0, 0) = kR;
  s.automaticTransformation = true;
  s.adaptiveScaling = true;
  return run(mjukf::ModifiedJointUkf<Plant>(Plant(), typename Plant::State(0), kGuess, s), seed);
}

// Parameter r's truth within 3.29 of its σ (99.9 %), or an alarm.
void expectCoveredOrFlagged(const Outcome& out, int r, const char* filter) {
  if (out.health != Health::Ok) return;
  const double sigma = std::sqrt(out.covariance(r, r));
  EXPECT_LE(std::abs(out.estimate(r) - kTruth(r)), 3.29 * sigma)
      << filter << ": θ" << r + 1 << " = " << out.estimate(r) << " with σ " << sigma << " and no alarm";
}

TEST(UnobservableParameter, ItStaysWhereThePriorLeftItUnderThePriorsSigma) {
  // What honest means here: no data on θ₂, so θ̂₂ and its σ stay as they started, and θ₁ converges.
  using Plant = TwoInputTank<false>;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    for (const auto& [out, name, priorSigma] : {std::tuple{jointUkf<Plant>(seed), "JUKF", kPriorSigma(1)},
                                                std::tuple{dualUkf<Plant>(seed), "dual", kPriorSigma(1)},
                                                std::tuple{automaticMjukf<Plant>(seed), "MJUKF", kGuess(1)}}) {
      EXPECT_EQ(out.health, Health::Ok) << name;
      EXPECT_NEAR(out.estimate(1), kGuess(1), 1e-9) << name;
      EXPECT_NEAR(std::sqrt(out.covariance(1, 1)), priorSigma, 1e-6 * priorSigma) << name;
      EXPECT_NEAR(out.estimate(0), kTruth(0), 4 * std::sqrt(out.covariance(0, 0))) << name;
      EXPECT_LT(std::sqrt(out.covariance(0, 0)), 0.01) << name << ": θ₁ is observable";
      expectCoveredOrFlagged(out, 1, name);
    }
  }
}

TEST(UnobservableParameter, JointAndModifiedJointCoverAPairOnlyTheProductOfWhichIsObservable) {
  // Only θ₁ θ₂ is observable. JUKF and the automatic MJUKF end somewhere on the ridge θ₁ θ₂ = 5 with
  // standard deviations that cover the truth (1.7 and 2.3 σ for JUKF on seed 1; MJUKF 0.3 σ). The dual UKF
  // does not: it ends at (1.37, 3.66) with σ (0.024, 0.064), 15 and 21 σ from the truth, its NIS
  // about 1 and health() Ok, a confident error no test of the innovations can see, since the data are fit
  // (docs/robustness.md, "What it cannot see"). It is left out here for that reason.
  using Plant = TwoInputTank<true>;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    for (const auto& [out, name] :
         {std::pair{jointUkf<Plant>(seed), "JUKF"}, std::pair{automaticMjukf<Plant>(seed), "MJUKF"}}) {
      EXPECT_NEAR(out.estimate(0) * out.estimate(1), kTruth(0) * kTruth(1), 0.3) << name << ": the product";
      expectCoveredOrFlagged(out, 0, name);
      expectCoveredOrFlagged(out, 1, name);
    }
  }
}

}  // namespace
