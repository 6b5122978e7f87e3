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

// The level's Q and R, the same in every filter.
template <class Settings>
void setLevelNoise(Settings& s) {
  s.processNoise(0, 0) = kQ;
  s.measurementNoise(0, 0) = kR;
}

// Every filter as the gallery sets it up: JUKF and the dual with the prior kPriorSigma, the automatic
// MJUKF with the state's P₀, Q and R alone (its prior scale of θ is then |θ̂₀|).
template <class Plant>
Outcome jointUkf(unsigned seed) {
  mjukf::JointUkfSettingsFor<Plant> s;
  s.initialCovariance.diagonal() << 1, kPriorSigma.array().square();
  setLevelNoise(s);
  return run(mjukf::JointUkf<Plant>(Plant(), typename Plant::State(0), kGuess, s), seed);
}
template <class Plant>
Outcome dualUkf(unsigned seed) {
  mjukf::DualUkfSettingsFor<Plant> s;
  s.initialCovariance(0, 0) = 1;
  setLevelNoise(s);
  s.initialParameterCovariance.diagonal() = kPriorSigma.array().square();
  return run(mjukf::DualUkf<Plant>(Plant(), typename Plant::State(0), kGuess, s), seed);
}
template <class Plant>
Outcome automaticMjukf(unsigned seed) {
  mjukf::ModifiedJointUkfSettingsFor<Plant> s;
  s.initialCovariance(0, 0) = 1;
  setLevelNoise(s);
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
  // What honest means here: no data on θ₂, so θ̂₂ and its σ stay as they started (the prior, which holds
  // the truth 2.9 σ₀ away), and θ₁ converges.
  using Plant = TwoInputTank<false>;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    for (const auto& [out, name, priorSigma] : {std::tuple{jointUkf<Plant>(seed), "JUKF", kPriorSigma(1)},
                                                std::tuple{dualUkf<Plant>(seed), "dual", kPriorSigma(1)},
                                                std::tuple{automaticMjukf<Plant>(seed), "MJUKF", kGuess(1)}}) {
      EXPECT_EQ(out.health, Health::Ok) << name;
      EXPECT_NEAR(out.estimate(1), kGuess(1), 1e-9) << name;
      EXPECT_NEAR(std::sqrt(out.covariance(1, 1)), priorSigma, 1e-6 * priorSigma) << name;
      // θ₁: a least-squares fit of y⁺ − 0.9 y on u₁ over 2000 updates has σ ≈ 0.0025 (noise variance about
      // Q + 1.81 R, E[u₁²] = 1.5). The filters, which know that the level is smooth, do better (about a
      // tenth of it): their σ must be below twice that, and the error within 3.29 of their σ.
      EXPECT_LT(std::sqrt(out.covariance(0, 0)), 2 * 0.0025) << name;
      EXPECT_LE(std::abs(out.estimate(0) - kTruth(0)), 3.29 * std::sqrt(out.covariance(0, 0))) << name;
    }
  }
}

TEST(UnobservableParameter, JointAndModifiedJointCoverAPairOnlyTheProductOfWhichIsObservable) {
  // Only c = θ₁ θ₂ is observable, as θ₁ above: both filters must get it within 8 σ of the least-squares
  // fit (0.02; their curvature bias was at most 0.004 on these seeds), and end somewhere on the ridge
  // θ₁ θ₂ = 5 with standard deviations that cover the truth (JUKF
  // 1.7 and 2.3 σ on seed 1, the MJUKF 0.3 σ). JUKF's sigma points carry the mean of the product,
  // θ̂₁ θ̂₂ + P₁₂, which is what it fits (θ̂₁ θ̂₂ itself is 5.23 on seed 1); the MJUKF's points each carry
  // their own θ, whose mean it fits.
  using Plant = TwoInputTank<true>;
  constexpr double kProductTolerance = 8 * 0.0025;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(testing::Message() << "seed " << seed);
    const Outcome joint = jointUkf<Plant>(seed);
    EXPECT_NEAR(joint.estimate(0) * joint.estimate(1) + joint.covariance(0, 1), kTruth.prod(), kProductTolerance);
    const Outcome modified = automaticMjukf<Plant>(seed);
    EXPECT_NEAR(modified.estimate.prod(), kTruth.prod(), kProductTolerance);
    for (const auto& [out, name] : {std::pair{joint, "JUKF"}, std::pair{modified, "MJUKF"}}) {
      expectCoveredOrFlagged(out, 0, name);
      expectCoveredOrFlagged(out, 1, name);
    }
  }
}

TEST(UnobservableParameter, TheDualIsConfidentlyWrongOnThePairAsDocumented) {
  // The limitation docs/robustness.md ("What it cannot see") records, pinned so that the page changes
  // with the filter: the dual's P^θ shrinks along the ridge too, and it ends far off under a small σ,
  // the output fit (the product right), health() Ok.
  using Plant = TwoInputTank<true>;
  const Outcome out = dualUkf<Plant>(1);
  EXPECT_EQ(out.health, Health::Ok);
  EXPECT_NEAR(out.estimate.prod(), kTruth.prod(), 8 * 0.0025);
  const double offBy = std::abs(out.estimate(0) - kTruth(0)) / std::sqrt(out.covariance(0, 0));
  EXPECT_GT(offBy, 10) << "θ₁ is now within " << offBy << " σ: update docs/robustness.md";
  EXPECT_LT(out.covariance(0, 1) / std::sqrt(out.covariance(0, 0) * out.covariance(1, 1)), -0.9999);
}

}  // namespace
