#pragma once

// The `simulate` and `estimate` subcommands, written once for any plant description (plant.hpp).

#include <cstdio>
#include <iostream>
#include <limits>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"
#include "common/cli.hpp"
#include "common/estimation.hpp"
#include "common/experiment.hpp"
#include "common/format.hpp"
#include "common/plant.hpp"
#include "common/simulation.hpp"

namespace mjukf::examples {

/// simulate --out FILE [--duration S] [--seed N] [--snr-db DB] [--change-at T]
template <class Plant>
int simulateCommand(const std::vector<std::string>& words) {
  using Experiment = typename Plant::Experiment;
  using Model = typename Experiment::Model;
  std::set<std::string> known{"--out", "--duration", "--seed", "--change-at"};
  if (hasSnrNoise<Experiment>) known.insert("--snr-db");  // the 2019 systems' and the gallery's noise has none
  const Arguments args(words, known);
  const std::string out = args.requiredText("--out");

  auto options = experimentSimulation<Experiment>(static_cast<std::uint64_t>(args.integer("--seed", 1, 0)),
                                                  {Model::trueParameters()});
  if (args.has("--change-at")) {
    const auto change = Plant::parameterChange();
    if (!change) throw UsageError(std::string(Plant::title) + " has no parameter-change scenario: drop --change-at");
    options.parameters.after = change->after;
    options.parameters.changeAt = args.number("--change-at", change->at);
    if (!(options.parameters.changeAt >= 0)) throw UsageError("--change-at needs a time >= 0");
    options.duration = change->duration;
  }
  options.duration = args.number("--duration", options.duration);
  requireSimulationDuration("--duration", options.duration, options.stepSize);
  options.snrDb = args.number("--snr-db", 30, /*allowInfinity=*/true);

  OutputFiles outputs;
  const OutputFile& file = outputs.add(out);  // before a long simulation: can the file be written?
  const auto data = simulateExperiment<Experiment>(options);
  writePlantData(file, data);
  outputs.commit();
  char noise[64];
  if (hasRelativeNoise<Experiment>)
    std::snprintf(noise, sizeof noise, "noise std %g |x_i|", options.relativeNoise);
  else
    std::snprintf(noise, sizeof noise, "SNR %g dB", options.snrDb);
  std::string noiseText = noise;
  if (options.absoluteNoise) {  // the standard deviation of each measured component
    noiseText = "noise std";
    for (int c = 0; c < Model::MeasDim; ++c) {
      std::snprintf(noise, sizeof noise, "%s %g", c > 0 ? "," : "", double((*options.absoluteNoise)(c)));
      noiseText += noise;
    }
  }
  const char* unit = timeUnit<Plant>;
  std::printf("simulated %s: %ld rows (%.6g %s at h = %g %s), %s, seed %llu -> %s\n", Plant::title, data.rows(),
              options.duration, unit, options.stepSize, unit, noiseText.c_str(),
              static_cast<unsigned long long>(options.seed), out.c_str());
  return kExitOk;
}

namespace detail {

inline FilterKind parseFilterKind(const std::string& name) {
  if (name == "ukf") return FilterKind::Ukf;
  if (name == "jukf") return FilterKind::JointUkf;
  if (name == "mjukf") return FilterKind::ModifiedJointUkf;
  if (name == "dual") return FilterKind::DualUkf;
  throw UsageError("--filter must be ukf, jukf, mjukf or dual, not '" + name + "'");
}

inline DualUkfOrdering parseOrdering(const std::string& name) {
  if (name == "prior") return DualUkfOrdering::PriorParameters;
  if (name == "updated") return DualUkfOrdering::UpdatedParameters;
  throw UsageError("--ordering must be prior or updated, not '" + name + "'");
}

// A diagonal from one number (every entry) or a comma-separated list of all the entries.
template <class Matrix>
void overrideDiagonal(const Arguments& args, const std::string& flag, Matrix& matrix) {
  if (!args.has(flag)) return;
  const auto size = static_cast<std::size_t>(matrix.rows());
  const bool list = args.text(flag).find(',') != std::string::npos;
  const std::vector<double> values = args.numbers(flag, list ? size : 1);
  matrix.setZero();
  for (std::size_t i = 0; i < size; ++i) matrix(long(i), long(i)) = values[list ? i : 0];
}

template <class Vector>
void overrideVector(const Arguments& args, const std::string& flag, Vector& vector) {
  if (!args.has(flag)) return;
  const std::vector<double> values = args.numbers(flag, static_cast<std::size_t>(vector.size()));
  for (std::size_t i = 0; i < values.size(); ++i) vector(long(i)) = values[i];
}

// --p0, --q and --r: the same three diagonals in every filter's settings (the dual's state filter's;
// its parameter filter observes with H P⁻ Hᵀ + R plus its own parameterObservationNoise, --r-theta).
template <class Settings>
void overrideCovariances(const Arguments& args, Settings& settings) {
  overrideDiagonal(args, "--p0", settings.initialCovariance);
  overrideDiagonal(args, "--q", settings.processNoise);
  overrideDiagonal(args, "--r", settings.measurementNoise);
}

// Flags that only make sense for some filters are refused for the others rather than ignored.
inline void requireFilter(const Arguments& args, const std::string& flag, bool applies, const char* which) {
  if (args.has(flag) && !applies) throw UsageError("flag " + flag + " applies to " + which + " only");
}

// The paper's settings for the chosen filter, with every flag given applied on top.
template <class Experiment>
FilterSetup<Experiment> filterSetup(const Arguments& args) {
  auto setup = FilterSetup<Experiment>::paper(parseFilterKind(args.requiredText("--filter")));
  const bool ukf = setup.kind == FilterKind::Ukf;
  const bool jukf = setup.kind == FilterKind::JointUkf;
  const bool mjukf = setup.kind == FilterKind::ModifiedJointUkf;
  const bool dual = setup.kind == FilterKind::DualUkf;
  requireFilter(args, "--xi", mjukf, "mjukf");
  requireFilter(args, "--transform", mjukf, "mjukf");
  requireFilter(args, "--p-theta", mjukf, "mjukf");
  requireFilter(args, "--ordering", dual, "dual");
  requireFilter(args, "--r-theta", dual, "dual");

  setup.measurementEvery =
      static_cast<int>(args.integer("--every", setup.measurementEvery, 1, std::numeric_limits<int>::max()));
  overrideVector(args, "--x0", setup.initialState);
  overrideVector(args, "--theta0", setup.initialParameters);
  // α, β, κ of the dual UKF's state filter; its parameter filter keeps its own (α = 0.1 by default, points
  // near θ̂: docs/algorithms.md §9).
  for (auto* sigma : {&setup.ukf.sigmaPoints, &setup.jointUkf.sigmaPoints, &setup.modifiedJointUkf.sigmaPoints,
                      &setup.dualUkf.sigmaPoints}) {
    sigma->alpha = args.number("--alpha", sigma->alpha);
    sigma->beta = args.number("--beta", sigma->beta);
    sigma->kappa = args.number("--kappa", sigma->kappa);
  }
  if (ukf) {
    overrideCovariances(args, setup.ukf);
  } else if (jukf) {
    overrideCovariances(args, setup.jointUkf);
  } else if (dual) {
    auto& s = setup.dualUkf;
    overrideCovariances(args, s);
    overrideDiagonal(args, "--r-theta", s.parameterObservationNoise);
    if (args.has("--ordering")) s.ordering = parseOrdering(args.text("--ordering"));
  } else {
    auto& s = setup.modifiedJointUkf;
    overrideCovariances(args, s);
    if (args.has("--xi")) {  // one ξ for every parameter, or one per parameter
      const std::string text = args.text("--xi");
      if (text.find(',') == std::string::npos)
        s.scaling = args.number("--xi", 0.0);
      else
        overrideVector(args, "--xi", s.scaling);
    }
    overrideVector(args, "--p-theta", s.parameterSpread);
    if (args.has("--transform")) {
      const auto values = args.numbers("--transform", static_cast<std::size_t>(s.transformation.size()));
      for (long i = 0; i < s.transformation.rows(); ++i)  // row-major, as T is written
        for (long j = 0; j < s.transformation.cols(); ++j)
          s.transformation(i, j) = values[static_cast<std::size_t>(i * s.transformation.cols() + j)];
    }
  }
  return setup;
}

// The filter's health at the end of a run (docs/robustness.md, "The health monitor"): its verdict
// then, the first alarm of the run and where it was raised, how many blocks raised one, and the last
// complete block's statistics.
template <class Model>
void printHealth(const EstimateRun<Model>& run) {
  const auto& h = run.healthStatistics;
  if (h.firstAlarm == Health::Ok)
    std::printf("health: ok (no alarm in %ld blocks of measurement updates)\n", h.blocks);
  else if (run.health == h.firstAlarm)
    std::printf("health: %s (first raised at measurement update %ld; %ld of %ld blocks raised an alarm)\n",
                toString(run.health), h.alarmAtUpdate, h.alarmedBlocks, h.blocks);
  else
    std::printf(
        "health: %s (earlier: %s, first raised at measurement update %ld; %ld of %ld blocks raised an "
        "alarm)\n",
        toString(run.health), toString(h.firstAlarm), h.alarmAtUpdate, h.alarmedBlocks, h.blocks);
  if (h.blocks > 0)
    std::printf(
        "health, last block: normalised NIS %.4g (bounds %.3g, %.3g), lag-one autocorrelation %.3g (bound %.3g), "
        "parameter motion %.3g sigma\n",
        double(h.normalisedNis), double(h.nisLowerBound), double(h.nisUpperBound), double(h.autocorrelationScore),
        double(h.autocorrelationBound), double(h.parameterMotionSigmas));
  if (h.smallInnovationBlocks > 0)
    std::printf(
        "health: in %ld of %ld blocks the innovations were smaller than their covariance (Q or R larger than the "
        "errors; an alarm only with health.flagSmallInnovations)\n",
        h.smallInnovationBlocks, h.blocks);
}

}  // namespace detail

/// estimate --filter ukf|jukf|mjukf|dual --data FILE --out FILE [--xi X] [--ordering O] [--every N] [more settings]
template <class Plant>
int estimateCommand(const std::vector<std::string>& words) {
  using Experiment = typename Plant::Experiment;
  using Model = typename Experiment::Model;
  const Arguments args(
      words, {"--filter", "--data", "--out", "--xi", "--every", "--step", "--rmse-from", "--x0", "--theta0", "--alpha",
              "--beta", "--kappa", "--p0", "--q", "--r", "--p-theta", "--transform", "--ordering", "--r-theta"});
  const auto setup = detail::filterSetup<Experiment>(args);
  const std::string dataPath = args.requiredText("--data");
  const std::string out = args.requiredText("--out");
  const double h = args.number("--step", Experiment::stepSize);
  if (!(h > 0)) throw UsageError("--step needs a positive step size");
  const long rmseFrom = args.integer("--rmse-from", Experiment::rmseFromRow, 0);

  const auto data = loadPlantData<Model>(dataPath, Plant::title, h, Model::trueParameters());
  OutputFiles outputs;
  const OutputFile& file = outputs.add(out);
  EstimateRun<Model> run;
  try {
    run = runFilter(Model(), setup, data);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("bad filter setting: ") + e.what());
  }

  const bool updated = setup.dualUkf.ordering == DualUkfOrdering::UpdatedParameters;
  const char* unit = timeUnit<Plant>;
  std::printf("%s%s on %s: %ld rows, h = %g %s, a measurement every %d steps\n", filterName(setup.kind),
              setup.kind != FilterKind::DualUkf ? ""
              : updated                         ? " (ordering: updated)"
                                                : " (ordering: prior)",
              dataPath.c_str(), data.rows(), h, unit, setup.measurementEvery);
  // A run that stopped writes nothing: its rows 0…k−1 would look like a whole file of a shorter run.
  if (run.outcome.status != Status::Ok)
    throw std::runtime_error(detail::format("the filter refused the step to row %ld (t = %g %s): %s; %s not written",
                                            run.outcome.row, double(run.outcome.row) * h, unit,
                                            toString(run.outcome.status), out.c_str()));
  writeEstimates(file, run, h);
  outputs.commit();
  // Short runs have no rows past the paper's start of the RMSE window: take all of them, and say so.
  const long from = rmseFrom < data.rows() ? rmseFrom : 0;
  std::printf("parameter RMSE over rows >= %ld (t >= %g %s)%s, truth: %s\n", from, double(from) * h, unit,
              from != rmseFrom ? " (the run is shorter than --rmse-from)" : "",
              data.parameterTruthFromFile ? "theta*_true columns" : "the plant's true constants");
  const auto rmse = parameterRmse(run, data, from);
  const auto& last = run.parameters.back();
  for (int i = 0; i < Model::ParamDim; ++i)
    std::printf("rmse_theta%d: %.10g  # %s (%s), final estimate %.6g, truth %.6g%s\n", i + 1, rmse(i),
                Plant::parameters[std::size_t(i)].name, Plant::parameters[std::size_t(i)].unit, last(i),
                data.parameterTruth.back()(i),
                setup.kind == FilterKind::Ukf ? " (fixed: ukf estimates no parameters)" : "");
  std::printf("loop_seconds: %.6g\n", run.loopSeconds);
  detail::printHealth(run);
  std::printf("wrote %s\n", out.c_str());
  return kExitOk;
}

}  // namespace mjukf::examples
