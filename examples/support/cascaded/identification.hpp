#pragma once

// The Cascaded Tanks benchmark (tests/data/cascaded_tanks/README.md) identified with the filters: the
// benchmark's data, the one rule that sets every filter's settings from the data, the passes of each
// filter over the estimation set, and the benchmark's test (a free run from the test set's input, its
// initial state from the first five measured samples). docs/real-data.md, "Cascaded tanks".

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "common/csv.hpp"
#include "mjukf/dual_ukf.hpp"
#include "mjukf/joint_ukf.hpp"
#include "mjukf/models/cascaded_tanks.hpp"
#include "mjukf/modified_joint_ukf.hpp"
#include "mjukf/offline/initial_state.hpp"

namespace mjukf::cascaded {

using Model = models::CascadedTanks<double>;
using State = Model::State;
using Param = Model::Param;
using Series = std::vector<double>;

/// The benchmark's two experiments.
struct Benchmark {
  Series uEst, yEst, uVal, yVal;
  double samplePeriod = 4;
};

/// Reads dataBenchmark.csv; a malformed file, a missing column, a missing sample or a bad sampling
/// period throws examples::CsvError naming the file and the line.
inline Benchmark loadBenchmark(const std::string& path) {
  const examples::CsvTable table = io::readCsv(path);  // the file ends in a blank line: io's reader
  if (io::CsvProblem problem = table.require({"uEst", "uVal", "yEst", "yVal", "Ts"})) throw examples::CsvError(problem);
  Benchmark b{table.column("uEst"), table.column("yEst"), table.column("uVal"), table.column("yVal"),
              table.column("Ts").empty() ? std::nan("") : table.column("Ts")[0]};
  if (table.rows() < 10) throw examples::CsvError(path, table.line(0), "fewer than 10 samples");
  for (const Series* s : {&b.uEst, &b.yEst, &b.uVal, &b.yVal})
    for (std::size_t k = 0; k < s->size(); ++k)
      if (std::isnan((*s)[k]))
        throw examples::CsvError(path, table.line(k), "a missing sample in uEst, uVal, yEst or yVal");
  if (!(b.samplePeriod > 0) || !std::isfinite(b.samplePeriod))
    throw examples::CsvError(path, table.line(0), "Ts (first row) must be a sampling period > 0");
  return b;
}

/// The free run of the model from x₀ under the held inputs u: the output at each sample (sample 0 is
/// x₀'s own output), `samples` of them (all of u when negative).
inline Series simulate(const Model& model, const Param& theta, const Series& u, State x, double period,
                       long samples = -1) {
  const std::size_t n = samples < 0 ? u.size() : static_cast<std::size_t>(samples);
  Series y(n);
  for (std::size_t k = 0; k < n; ++k) {
    y[k] = model.measurement(x, theta)(0);
    x = model.transition(double(k) * period, period, x, Model::Input(u[k]), theta);
  }
  return y;
}

inline double rmsError(const Series& measured, const Series& simulated, std::size_t first) {
  double sum = 0;
  for (std::size_t k = first; k < measured.size(); ++k)
    sum += (measured[k] - simulated[k]) * (measured[k] - simulated[k]);
  return std::sqrt(sum / double(measured.size() - first));
}

/// The benchmark's initial state from the first five measured samples: x₂(0) = y₀ − c, and x₁(0) the
/// upper level whose free run fits y₀ … y₄ best (least squares; a grid over [0, h_max], as x₁ cannot
/// exceed it, then refined by Levenberg–Marquardt, mjukf/offline/initial_state.hpp).
inline State initialStateFromFirstSamples(const Model& model, const Param& theta, const Series& u, const Series& y,
                                          double period) {
  constexpr int kSamples = 5;
  const Model::Physical p = model.physical(theta);
  const double top = model.terms.upperOverflow ? p.hMax : 100.0;
  State best(0, std::max(y[0] - p.offset, 0.0));
  double bestCost = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 400; ++i) {
    const State x0(top * i / 400, best(1));
    const Series s = simulate(model, theta, u, x0, period, kSamples);
    double cost = 0;
    for (int k = 0; k < kSamples; ++k) cost += (s[k] - y[k]) * (s[k] - y[k]);
    if (cost < bestCost) bestCost = cost, best = x0;
  }
  std::vector<Model::Input> inputs;
  std::vector<Model::Meas> measured;
  for (int k = 0; k < kSamples; ++k) inputs.emplace_back(u[k]), measured.emplace_back(y[k]);
  offline::InitialStateSettings<double, 2, 1> settings;
  settings.fixed << false, true;
  const auto refined = offline::estimateInitialState(model, NoIntegrator<double>(), theta, inputs, measured,
                                                     offline::Sampling<double>{0, period, 1}, kSamples, best, settings);
  return refined.cost <= bestCost / 2 && std::isfinite(refined.state(0)) ? State(refined.state) : best;
}

/// The benchmark's score of θ: the free run over the test set from the initial state of its first five
/// samples, and its RMS error over yVal[5..].
struct TestResult {
  State initialState;
  Series simulated;
  double rms = std::numeric_limits<double>::quiet_NaN();
};

inline TestResult testSimulation(const Model& model, const Param& theta, const Benchmark& b) {
  TestResult r;
  r.initialState = initialStateFromFirstSamples(model, theta, b.uVal, b.yVal, b.samplePeriod);
  r.simulated = simulate(model, theta, b.uVal, r.initialState, b.samplePeriod);
  r.rms = rmsError(b.yVal, r.simulated, 5);
  return r;
}

/// The sensor's noise variance from the data alone: the second difference of a smooth signal sampled
/// well above its bandwidth is almost all noise, and var(Δ²y) = 6 σ² for white noise of variance σ².
inline double sensorNoiseVariance(const Series& y) {
  double sum = 0;
  for (std::size_t k = 2; k < y.size(); ++k) {
    const double d = y[k] - 2 * y[k - 1] + y[k - 2];
    sum += d * d;
  }
  return sum / double(y.size() - 2) / 6;
}

/// The rule that sets every filter's settings (docs/real-data.md, "The rule"), from the estimation set's
/// own noise and from what is known of the plant before any fit.
struct Rule {
  double sensorVariance = 0;               ///< σ², the sensor's noise variance (sensorNoiseVariance)
  double measurementNoise = 0;             ///< R = 100 σ²: what the model cannot explain, (10 σ)² ≈ (0.2 V)²
  double levelNoise = 0;                   ///< Q of each level per sample = σ² / 4: half the sensor's σ of drift
  double parameterSpread = std::log(2.0);  ///< P₀'s σ of each log-parameter: a factor 2
  double offsetSpread = 0.5;               ///< P₀'s σ of the offset c (V)
  double upperLevelGuess = 5;              ///< x₁(0) (V): the middle of the sensor's range
  double upperLevelSpread = 5;             ///< its σ (V): anywhere from empty to full
  double boundWidth = std::log(4.0);       ///< each log-parameter within θ₀ ×/÷ 4 (2 σ of P₀)
  double offsetBound = 3;                  ///< |c| ≤ 3 V
  int passes = 20;                         ///< passes over the estimation set
};

/// Factors on the rule's settings: 1 is the rule, 0.5 and 2 halve and double one (`sensitivity`).
struct RuleFactors {
  double measurementNoise = 1;  ///< on R
  double levelNoise = 1;        ///< on Q
  double parameterSpread = 1;   ///< on P₀ of θ (the variances)
  double upperLevelSpread = 1;  ///< on P₀ of x₁(0) (the variance)
  double boundWidth = 1;        ///< on the bounds' width in log units
  double passes = 1;            ///< on the number of passes
};

/// The first guess θ₀, from what is known of the plant before any fit: both orifices alike (k₁ = k₃),
/// Torricelli's α = ½, the upper tank spilling at the top of the sensor's range (h_max = 10 V) with
/// half the spill reaching the lower tank, no offset; k₃ = 0.05 puts the lower tank's time constant,
/// 2√ȳ/k₃, near 90 s (the step responses of the record take a few minutes), and k₄ puts the lower
/// tank in balance at the estimation set's mean: k₄ ū = k₃ √ȳ.
inline Param firstGuess(const Benchmark& b) {
  double uMean = 0, yMean = 0;
  for (std::size_t k = 0; k < b.uEst.size(); ++k) uMean += b.uEst[k], yMean += b.yEst[k];
  uMean /= double(b.uEst.size());
  yMean /= double(b.yEst.size());
  const double k3 = 0.05;
  return Model::parameters({0.05, k3, k3 * std::sqrt(yMean) / uMean, 10, 0.5, 0.5, 0});
}

inline Rule makeRule(const Benchmark& b) {
  Rule rule;
  rule.sensorVariance = sensorNoiseVariance(b.yEst);
  rule.measurementNoise = 100 * rule.sensorVariance;
  rule.levelNoise = rule.sensorVariance / 4;
  return rule;
}

/// The estimation set's free-run error of θ, from the initial state its first five samples give (as
/// the benchmark sets the test's).
inline double estimationError(const Model& model, const Param& theta, const Benchmark& b) {
  const State x0 = initialStateFromFirstSamples(model, theta, b.uEst, b.yEst, b.samplePeriod);
  return rmsError(b.yEst, simulate(model, theta, b.uEst, x0, b.samplePeriod), 0);
}

/// The settings the three filters share, with the rule's factors applied.
struct SharedSettings {
  Eigen::Matrix<double, 2, 2> stateCovariance = Eigen::Matrix<double, 2, 2>::Zero();
  Eigen::Matrix<double, 2, 2> levelNoise = Eigen::Matrix<double, 2, 2>::Zero();
  Eigen::Matrix<double, 1, 1> measurementNoise;
  Eigen::Matrix<double, 7, 7> parameterCovariance = Eigen::Matrix<double, 7, 7>::Zero();
  ParameterBounds<double, 7> bounds;
  int passes = 0;
};

inline SharedSettings sharedSettings(const Rule& rule, const RuleFactors& f, const Param& theta0) {
  SharedSettings s;
  s.stateCovariance(0, 0) = rule.upperLevelSpread * rule.upperLevelSpread * f.upperLevelSpread;
  s.stateCovariance(1, 1) = rule.sensorVariance;  // x₂(0) is the first measurement, less its offset
  s.levelNoise.diagonal().setConstant(rule.levelNoise * f.levelNoise);
  s.measurementNoise << rule.measurementNoise * f.measurementNoise;
  for (int i = 0; i < 6; ++i)
    s.parameterCovariance(i, i) = rule.parameterSpread * rule.parameterSpread * f.parameterSpread;
  s.parameterCovariance(6, 6) = rule.offsetSpread * rule.offsetSpread * f.parameterSpread;
  s.bounds.lower = theta0.array() - rule.boundWidth * f.boundWidth;
  s.bounds.upper = theta0.array() + rule.boundWidth * f.boundWidth;
  // A fraction of the spill, and an exponent between Torricelli's and a film's, are at most 1.
  s.bounds.upper(Model::kLnK5) = std::min(s.bounds.upper(Model::kLnK5), 0.0);
  s.bounds.upper(Model::kLnAlpha) = std::min(s.bounds.upper(Model::kLnAlpha), 0.0);
  s.bounds.lower(Model::kOffset) = -rule.offsetBound;
  s.bounds.upper(Model::kOffset) = rule.offsetBound;
  s.passes = std::max(1, static_cast<int>(std::lround(rule.passes * f.passes)));
  return s;
}

/// What a filter's identification gave.
struct Identified {
  Param theta;
  int bestPass = -1;
  double estimationRms = std::numeric_limits<double>::infinity();
  long refused = 0;                ///< steps a filter refused, over every pass
  std::vector<double> passErrors;  ///< each pass's estimation RMS
  double innovationRms = 0;        ///< the RMS innovation of the best pass
};

/// Passes over the estimation set. Each pass is a filter made afresh by `makeFilter(θ)` from the last
/// pass's θ̂ (so P₀ of θ is the rule's at every pass: each pass moves θ̂ by what the record says against
/// the same prior, and the iteration stops moving where the record agrees with θ̂), started at the
/// first sample; the result is the pass whose θ̂ fits the estimation set best in a free run.
template <class MakeFilter>
Identified identify(const Model& model, const Benchmark& b, const SharedSettings& shared, const Param& theta0,
                    MakeFilter makeFilter) {
  Identified best;
  best.theta = theta0;
  Param start = theta0;
  const double h = b.samplePeriod;
  for (int pass = 0; pass < shared.passes; ++pass) {
    auto filter = makeFilter(start);
    double innovations = 0;
    long updates = 0;
    for (std::size_t k = 0; k < b.yEst.size(); ++k) {
      if (k > 0 && !taken(filter.timeUpdate(double(k - 1) * h, h, Model::Input(b.uEst[k - 1])))) {
        ++best.refused;  // the estimate stays as it was; the record goes on
        continue;
      }
      if (!taken(filter.measurementUpdate(Model::Meas(b.yEst[k])))) {
        ++best.refused;
        continue;
      }
      innovations += filter.lastUpdate().innovation.squaredNorm();
      ++updates;
    }
    start = filter.parameters();
    shared.bounds.clamp(start);  // a mean of clamped values can stray out by a rounding
    const double error = estimationError(model, start, b);
    best.passErrors.push_back(error);
    if (error < best.estimationRms) {
      best.estimationRms = error, best.theta = start, best.bestPass = pass;
      best.innovationRms = std::sqrt(innovations / double(std::max(updates, 1L)));
    }
  }
  return best;
}

/// The JUKF, with the rule's settings.
inline Identified identifyJoint(const Model& model, const Benchmark& b, const Rule& rule, const RuleFactors& f = {}) {
  const Param theta0 = firstGuess(b);
  const SharedSettings shared = sharedSettings(rule, f, theta0);
  JointUkfSettingsFor<Model> s;
  s.initialCovariance.topLeftCorner<2, 2>() = shared.stateCovariance;
  s.initialCovariance.bottomRightCorner<7, 7>() = shared.parameterCovariance;
  s.processNoise.topLeftCorner<2, 2>() = shared.levelNoise;  // θ constant within a pass
  s.measurementNoise = shared.measurementNoise;
  s.parameterBounds = shared.bounds;
  const State x0(rule.upperLevelGuess, b.yEst[0]);
  return identify(model, b, shared, theta0, [&](const Param& theta) { return JointUkf<Model>(model, x0, theta, s); });
}

/// The MJUKF in its automatic mode (T and ξ from the sensitivities), with the rule's state settings;
/// its prior scale of θ is the rule's spread.
inline Identified identifyModified(const Model& model, const Benchmark& b, const Rule& rule,
                                   const RuleFactors& f = {}) {
  const Param theta0 = firstGuess(b);
  const SharedSettings shared = sharedSettings(rule, f, theta0);
  ModifiedJointUkfSettingsFor<Model> s;
  s.initialCovariance = shared.stateCovariance;
  s.processNoise = shared.levelNoise;
  s.measurementNoise = shared.measurementNoise;
  s.parameterBounds = shared.bounds;
  s.automaticTransformation = true;
  s.adaptiveScaling = true;
  // The automatic modes take (n + 1)|p_θ| as each parameter's prior scale: the rule's σ of θ.
  s.parameterSpread = shared.parameterCovariance.diagonal().cwiseSqrt() / double(Model::StateDim + 1);
  const State x0(rule.upperLevelGuess, b.yEst[0]);
  return identify(model, b, shared, theta0,
                  [&](const Param& theta) { return ModifiedJointUkf<Model>(model, x0, theta, s); });
}

/// The dual UKF, with the rule's settings; its parameter filter has P₀ of θ from the rule and no
/// process noise (θ constant within a pass).
inline Identified identifyDual(const Model& model, const Benchmark& b, const Rule& rule, const RuleFactors& f = {}) {
  const Param theta0 = firstGuess(b);
  const SharedSettings shared = sharedSettings(rule, f, theta0);
  DualUkfSettingsFor<Model> s;
  s.initialCovariance = shared.stateCovariance;
  s.processNoise = shared.levelNoise;
  s.measurementNoise = shared.measurementNoise;
  s.initialParameterCovariance = shared.parameterCovariance;
  s.parameterBounds = shared.bounds;
  const State x0(rule.upperLevelGuess, b.yEst[0]);
  return identify(model, b, shared, theta0, [&](const Param& theta) { return DualUkf<Model>(model, x0, theta, s); });
}

}  // namespace mjukf::cascaded
