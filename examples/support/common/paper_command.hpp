#pragma once

// The `paper` subcommand: JUKF and MJUKF with the paper's settings on one data set, the analogue of
// the paper's Table 3 / Table 4 next to the published values, and figures like the paper's; for a
// plant with a parameter-change scenario also that scenario (the robot's Figs. 12–14). Beside them
// runs the dual UKF with the library's settings (Experiment::dualUkf()): the paper has no dual filter,
// so its column has no published value.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "common/atomic_file.hpp"
#include "common/cli.hpp"
#include "common/estimation.hpp"
#include "common/experiment.hpp"
#include "common/format.hpp"
#include "common/plant.hpp"
#include "common/plot.hpp"
#include "common/report.hpp"
#include "common/simulation.hpp"
#include "common/statistics.hpp"

namespace mjukf::examples {

namespace detail {

template <class Model>
struct Comparison {
  EstimateRun<Model> jointUkf;
  EstimateRun<Model> modifiedJointUkf;
  EstimateRun<Model> dualUkf;
  double jointUkfSeconds = 0;  // median loop time
  double modifiedJointUkfSeconds = 0;
  double dualUkfSeconds = 0;
  long rmseFrom = 0;  // first row of the RMSE window (row 0 for a run shorter than the paper's window)
  typename Model::Param jointUkfRmse;
  typename Model::Param modifiedJointUkfRmse;
  typename Model::Param dualUkfRmse;
};

// Runs the three filters `runs` times, alternating so that a slow spell of the machine hits all alike.
template <class Experiment>
Comparison<typename Experiment::Model> compareFilters(const PlantData<typename Experiment::Model>& data,
                                                      const FilterSetup<Experiment>& jointUkf,
                                                      const FilterSetup<Experiment>& modifiedJointUkf,
                                                      const FilterSetup<Experiment>& dualUkf, long runs) {
  using Model = typename Experiment::Model;
  Comparison<Model> result;
  std::vector<double> jointTimes, modifiedTimes, dualTimes;
  for (long r = 0; r < runs; ++r) {
    result.jointUkf = runFilter(Model(), jointUkf, data);
    result.modifiedJointUkf = runFilter(Model(), modifiedJointUkf, data);
    result.dualUkf = runFilter(Model(), dualUkf, data);
    for (const auto& [run, name] : {std::pair{&result.jointUkf, "JUKF"}, std::pair{&result.modifiedJointUkf, "MJUKF"},
                                    std::pair{&result.dualUkf, "the dual UKF"}})
      if (run->outcome.status != Status::Ok)
        throw std::runtime_error(std::string(name) + " refused the step to row " + std::to_string(run->outcome.row) +
                                 ": " + toString(run->outcome.status));
    jointTimes.push_back(result.jointUkf.loopSeconds);
    modifiedTimes.push_back(result.modifiedJointUkf.loopSeconds);
    dualTimes.push_back(result.dualUkf.loopSeconds);
  }
  result.jointUkfSeconds = median(jointTimes);
  result.modifiedJointUkfSeconds = median(modifiedTimes);
  result.dualUkfSeconds = median(dualTimes);
  result.rmseFrom = Experiment::rmseFromRow < data.rows() ? Experiment::rmseFromRow : 0;
  result.jointUkfRmse = parameterRmse(result.jointUkf, data, result.rmseFrom);
  result.modifiedJointUkfRmse = parameterRmse(result.modifiedJointUkf, data, result.rmseFrom);
  result.dualUkfRmse = parameterRmse(result.dualUkf, data, result.rmseFrom);
  return result;
}

// Column numbers (1-based) in the files the figures read.
template <class Model>
int dataParameterColumn(const PlantData<Model>& data, int i) {
  return 2 + Model::MeasDim + (data.stateTruth.empty() ? 0 : Model::StateDim) + i;
}
inline int estimateStateColumn(int i) { return 2 + i; }
template <class Model>
int estimateParameterColumn(int i) {
  return 2 + Model::StateDim + i;
}

inline std::string withUnit(const Quantity& q) { return std::string(q.label) + " (" + q.unit + ")"; }
inline std::string rmseLabel(const Quantity& q) { return "RMSE " + std::string(q.name) + " (" + q.unit + ")"; }

// Parameter estimates of the three filters against the truth, one panel per parameter.
template <class Plant, class Model>
Figure parameterFigure(const std::string& png, const std::string& title, const std::string& dataFile,
                       const PlantData<Model>& data, const std::string& jointFile, const std::string& modifiedFile,
                       const std::string& dualFile) {
  Figure figure{png, title, Model::ParamDim, 1, 1000, 380 * Model::ParamDim, {}};
  const int every = std::max(1, static_cast<int>(data.rows() / 4000));
  for (int i = 0; i < Model::ParamDim; ++i) {
    const Quantity& q = Plant::parameters[std::size_t(i)];
    figure.panels.push_back(
        {std::string(q.label) + " estimates",
         "time t (s)",
         withUnit(q),
         {{jointFile, 1, estimateParameterColumn<Model>(i), "JUKF", "lines lw 1.5 lc rgb '#1f77b4'", every},
          {modifiedFile, 1, estimateParameterColumn<Model>(i), "MJUKF", "lines lw 1.5 lc rgb '#d62728'", every},
          {dualFile, 1, estimateParameterColumn<Model>(i), "dual", "lines lw 1.5 lc rgb '#2ca02c'", every},
          {dataFile, 1, dataParameterColumn(data, i), "truth", "lines lw 2 dt 2 lc rgb 'black'", every}}});
  }
  return figure;
}

// State estimates of JUKF and MJUKF against the measurements, one panel per state.
template <class Plant, class Model>
Figure stateFigure(const std::string& png, const std::string& title, const std::string& dataFile,
                   const PlantData<Model>& data, const std::string& jointFile, const std::string& modifiedFile) {
  const int columns = Model::StateDim > 2 ? 2 : 1;
  const int rows = (Model::StateDim + columns - 1) / columns;
  Figure figure{png, title, rows, columns, columns == 2 ? 1400 : 1000, 380 * rows, {}};
  const int every = std::max(1, static_cast<int>(data.rows() / 4000));
  const int measurementEvery = std::max(1, static_cast<int>(data.rows() / 2000));
  for (int i = 0; i < Model::StateDim; ++i) {
    const Quantity& q = Plant::states[std::size_t(i)];
    figure.panels.push_back(
        {q.label,
         "time t (s)",
         withUnit(q),
         {{dataFile, 1, 2 + i, "measurement", "points pt 7 ps 0.3 lc rgb '#a0a0a0'", measurementEvery},
          {jointFile, 1, estimateStateColumn(i), "JUKF", "lines lw 1.5 lc rgb '#1f77b4'", every},
          {modifiedFile, 1, estimateStateColumn(i), "MJUKF", "lines lw 1.5 lc rgb '#d62728'", every}}});
  }
  return figure;
}

// Writes the data and the filters' estimates (`<prefix>data.csv`, `<prefix>jukf.csv`, `<prefix>mjukf.csv`,
// `<prefix>dual.csv`) and draws `<prefix>parameters.png` (all three filters) and `<prefix>states.png`
// (JUKF and MJUKF), all into `outputs`.
template <class Plant, class Model, class Path>
void writeComparison(const Path& path, const std::string& prefix, const PlantData<Model>& data,
                     const Comparison<Model>& result, const std::string& parameterTitle, const std::string& stateTitle,
                     Plotter& plotter, OutputFiles& outputs) {
  const std::string dataFile = path(prefix + "data.csv"), jointFile = path(prefix + "jukf.csv"),
                    modifiedFile = path(prefix + "mjukf.csv"), dualFile = path(prefix + "dual.csv");
  writePlantData(outputs.add(dataFile), data);
  writeEstimates(outputs.add(jointFile), result.jointUkf, data.stepSize);
  writeEstimates(outputs.add(modifiedFile), result.modifiedJointUkf, data.stepSize);
  writeEstimates(outputs.add(dualFile), result.dualUkf, data.stepSize);
  const std::string title = std::string(Plant::title) + ": ";
  plotter.draw(outputs, parameterFigure<Plant>(path(prefix + "parameters.png"), title + parameterTitle, dataFile, data,
                                               jointFile, modifiedFile, dualFile));
  plotter.draw(outputs, stateFigure<Plant>(path(prefix + "states.png"), title + stateTitle, dataFile, data, jointFile,
                                           modifiedFile));
}

// Loads `path`, or simulates `duration` seconds when it is empty.
template <class Plant>
PlantData<typename Plant::Experiment::Model> paperData(
    const std::string& path, double duration, std::uint64_t seed,
    const TrueParameters<typename Plant::Experiment::Model::Param>& truth, std::string& description) {
  using Model = typename Plant::Experiment::Model;
  const double h = Plant::Experiment::stepSize;
  if (!path.empty()) {
    auto data = loadPlantData<Model>(path, Plant::title, h, truth.before);
    if (!data.parameterTruthFromFile)
      for (long k = 0; k < data.rows(); ++k) data.parameterTruth[std::size_t(k)] = truth.atRow(k, h);
    description = path;
    return data;
  }
  auto options = experimentSimulation<typename Plant::Experiment>(seed, truth);
  options.duration = duration;
  description =
      format("fresh simulation (%g s, seed %llu, 30 dB SNR)", duration, static_cast<unsigned long long>(seed));
  return simulateExperiment<typename Plant::Experiment>(options);
}

}  // namespace detail

/// paper [--data FILE] [--out-dir DIR] [--change-data FILE] [--runs N] [--duration S] [--seed N]
template <class Plant>
int paperCommand(const std::vector<std::string>& words) {
  using Experiment = typename Plant::Experiment;
  using Model = typename Experiment::Model;
  using detail::format;
  namespace fs = std::filesystem;
  const auto change = Plant::parameterChange();
  std::set<std::string> known{"--data", "--out-dir", "--runs", "--duration", "--seed"};
  if (change) known.insert("--change-data");
  const Arguments args(words, known);
  const std::string outDir = args.text("--out-dir", std::string("paper_") + Plant::slug);
  const long runs = args.integer("--runs", 20, 1);
  const auto seed = static_cast<std::uint64_t>(args.integer("--seed", 1, 0));
  // --duration is the length of a fresh simulation: refused, not ignored, when every data set is a file.
  if (args.has("--duration") && args.has("--data") && (!change || args.has("--change-data")))
    throw UsageError("--duration applies to a fresh simulation only, and every data set here comes from a file");
  const double duration = args.number("--duration", Experiment::duration);
  requireSimulationDuration("--duration", duration, Experiment::stepSize);
  std::error_code error;
  fs::create_directories(outDir, error);
  if (error) throw OutputError(outDir + ": cannot create the directory: " + error.message());
  const auto path = [&](const std::string& name) {
    return (fs::path(outDir) / (std::string(Plant::slug) + "_" + name)).string();
  };
  Plotter plotter;
  OutputFiles outputs;  // every file of the run, put in place together at its end (report.finish)
  detail::Report report;
  const auto say = [&](const std::string& line) { report.say(line); };

  // The paper's table: JUKF and MJUKF, the paper's settings, on one data set; beside them the dual UKF
  // with the library's settings (no published value: the paper has no dual filter).
  std::string description;
  const auto data =
      detail::paperData<Plant>(args.text("--data"), duration, seed, {Model::trueParameters()}, description);
  const auto jointSetup = FilterSetup<Experiment>::paper(FilterKind::JointUkf);
  const auto modifiedSetup = FilterSetup<Experiment>::paper(FilterKind::ModifiedJointUkf);
  const auto dualSetup = FilterSetup<Experiment>::paper(FilterKind::DualUkf);
  const auto result = detail::compareFilters(data, jointSetup, modifiedSetup, dualSetup, runs);

  const auto& paper = Plant::published;
  const auto& reference = Plant::reference;
  say(format("%s: analogue of the paper's %s", Plant::title, Plant::table));
  say(format("data: %s, %ld rows; RMSE over t >= %g s; time: median of %ld runs of the estimation loop",
             description.c_str(), data.rows(), double(result.rmseFrom) * Experiment::stepSize, runs));
  say("");
  say(format("%-26s %-37s %-37s", "", "this library (C++)", (std::string("paper ") + Plant::table).c_str()));
  say(format("%-26s %-11s %-12s %-12s %-11s %-12s %-12s", "", "JUKF", "MJUKF", "dual", "JUKF", "MJUKF", "dual"));
  for (int i = 0; i < Model::ParamDim; ++i) {
    const Quantity& q = Plant::parameters[std::size_t(i)];
    say(format("%-26s %-11.7f %-12.7f %-12.7f %-11.5g %-12.5g %-12s", detail::rmseLabel(q).c_str(),
               result.jointUkfRmse(i), result.modifiedJointUkfRmse(i), result.dualUkfRmse(i),
               paper.jukfRmse[std::size_t(i)], paper.mjukfRmse[std::size_t(i)], "-"));
  }
  say(format("%-26s %-11.4g %-12.4g %-12.4g %-11.5g %-12.5g %-12s", "time (s)", result.jointUkfSeconds,
             result.modifiedJointUkfSeconds, result.dualUkfSeconds, paper.jukfSeconds, paper.mjukfSeconds, "-"));
  say(format("%-26s %-37.3f %-37.3f", "time MJUKF / JUKF", result.modifiedJointUkfSeconds / result.jointUkfSeconds,
             paper.mjukfSeconds / paper.jukfSeconds));
  say(format("%-26s %-37.3f %-37s", "time dual / JUKF", result.dualUkfSeconds / result.jointUkfSeconds, "-"));
  say("dual: the library's dual UKF (its own settings, Experiment::dualUkf()); the paper has no dual filter,");
  say("  so there is no published value (-)");
  say("");
  std::string conformance = "conformance RMSEs on the reference file (independent implementation): JUKF";
  for (double v : reference.jukfRmse) conformance += format(" %.10g", v);
  conformance += ", MJUKF";
  for (double v : reference.mjukfRmse) conformance += format(" %.10g", v);
  say(conformance);
  // The scripts' times are recorded figures, not measured by this program: the ratio compares this
  // machine's median with a run on another machine (of the same kind), and says so.
  say("reference Python scripts, one run each, timed once on another 2-core machine (not by this program):");
  say(format("  JUKF %g s, MJUKF %g s (ratio %.3f); this run's medians are %.0fx (JUKF) and %.0fx (MJUKF) below",
             reference.jukfSeconds, reference.mjukfSeconds, reference.mjukfSeconds / reference.jukfSeconds,
             reference.jukfSeconds / result.jointUkfSeconds, reference.mjukfSeconds / result.modifiedJointUkfSeconds));
  say("  those recorded times (a comparison across machines, not a measurement of the scripts on this one)");

  detail::writeComparison<Plant>(path, "", data, result, "parameter estimates", "state estimates and measurements",
                                 plotter, outputs);

  // The parameter-change scenario: the plant changes at `change->at`; MJUKF takes its own ξ.
  if (change) {
    TrueParameters<typename Model::Param> truth{Model::trueParameters(), change->after, change->at};
    const double changeDuration = args.has("--duration") ? duration : change->duration;
    std::string changeDescription;
    const auto changeData =
        detail::paperData<Plant>(args.text("--change-data"), changeDuration, seed, truth, changeDescription);
    auto changeModified = modifiedSetup;
    changeModified.modifiedJointUkf.scaling = change->scaling;
    auto changeDual = dualSetup;
    changeDual.dualUkf.parameterProcessNoise.diagonal().setConstant(kChangeParameterProcessNoise);
    const auto changeResult = detail::compareFilters(changeData, jointSetup, changeModified, changeDual, 1);
    say("");
    std::string what;
    for (int i = 0; i < Model::ParamDim; ++i)
      what += format("%s%s %g -> %g", i > 0 ? ", " : "", Plant::parameters[std::size_t(i)].name, truth.before(i),
                     truth.after(i));
    say(format("%s: parameter change (paper Figs. 12-14): %s at t = %g s; MJUKF xi = %g, dual Q_theta = %g I",
               Plant::title, what.c_str(), change->at, change->scaling, kChangeParameterProcessNoise));
    say(format("data: %s, %ld rows; RMSE over t >= %g s against the changing truth", changeDescription.c_str(),
               changeData.rows(), double(changeResult.rmseFrom) * Experiment::stepSize));
    say(format("%-26s %-11s %-12s %-12s", "", "JUKF", "MJUKF", "dual"));
    for (int i = 0; i < Model::ParamDim; ++i) {
      const Quantity& q = Plant::parameters[std::size_t(i)];
      say(format("%-26s %-11.7f %-12.7f %-12.7f", detail::rmseLabel(q).c_str(), changeResult.jointUkfRmse(i),
                 changeResult.modifiedJointUkfRmse(i), changeResult.dualUkfRmse(i)));
      say(format("%-26s %-11.5f %-12.5f %-12.5f",
                 ("final " + std::string(q.name) + format(" (truth %g)", truth.after(i))).c_str(),
                 changeResult.jointUkf.parameters.back()(i), changeResult.modifiedJointUkf.parameters.back()(i),
                 changeResult.dualUkf.parameters.back()(i)));
    }
    detail::writeComparison<Plant>(path, "change_", changeData, changeResult,
                                   "parameter estimates with a parameter change",
                                   "state estimates with a parameter change", plotter, outputs);
  }

  report.finish(outputs.add(path("table.txt")), outputs);
  return kExitOk;
}

}  // namespace mjukf::examples
