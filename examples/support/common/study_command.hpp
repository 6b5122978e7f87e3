#pragma once

// The `study` subcommand: the filters over many noise realisations (docs/studies.md). One run is one
// seed: the plant is simulated with that seed's noise and every filter asked for estimates from the
// same data. Runs go to --jobs threads; each depends on its seed alone and the results are written in
// seed order, so the output is the same for any number of jobs.

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <iostream>
#include <limits>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <type_traits>
#include <vector>

#include <Eigen/Cholesky>

#include "common/atomic_file.hpp"
#include "common/cli.hpp"
#include "common/csv_writer.hpp"
#include "common/estimation.hpp"
#include "common/experiment.hpp"
#include "common/format.hpp"
#include "common/plant.hpp"
#include "common/plot.hpp"
#include "common/report.hpp"
#include "common/statistics.hpp"

namespace mjukf::examples {

/// The most runs (seeds × scenarios) one study may have: each keeps a few numbers per filter, but a
/// typo such as 1-10000000000 should be refused, not attempted.
constexpr std::size_t kMaxStudyRuns = 1'000'000;

/// A run diverged when a final parameter error exceeds this multiple of its scale (see divergedRun()).
constexpr double kDivergenceBound = 1.0;
/// A run is accurate when every final θ̂ᵢ is within this fraction of θᵢ: the runs on which an alarm is
/// a false alarm. (A run that did not diverge may still end 99 % off; its alarm is no false one.)
constexpr double kAccurateBound = 0.1;

namespace detail {

/// "1-100", "7", "1,5,9-12": the seeds in the order given; refuses an empty list, a descending or
/// malformed range, a repeated seed, and more than kMaxStudyRuns seeds.
inline std::vector<std::uint64_t> parseSeeds(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return UsageError("--seeds needs seeds or ranges like 1-100 or 1,5,9-12 (" + why + "), not '" + text + "'");
  };
  const auto number = [&](std::string_view word) {
    std::uint64_t value = 0;
    const auto [end, error] = std::from_chars(word.data(), word.data() + word.size(), value);
    if (word.empty() || error != std::errc() || end != word.data() + word.size())
      throw bad("'" + std::string(word) + "' is not a seed");
    return value;
  };
  std::vector<std::uint64_t> seeds;
  std::set<std::uint64_t> seen;
  std::string_view rest = text;
  while (!rest.empty() || seeds.empty()) {
    const std::size_t comma = rest.find(',');
    const std::string_view item = rest.substr(0, comma);
    const std::size_t dash = item.find('-');
    const std::uint64_t first = number(item.substr(0, dash));
    const std::uint64_t last = dash == std::string_view::npos ? first : number(item.substr(dash + 1));
    if (last < first) throw bad("the range " + std::string(item) + " runs backwards");
    if (last - first >= kMaxStudyRuns || seeds.size() + (last - first) >= kMaxStudyRuns)
      throw bad("more than " + std::to_string(kMaxStudyRuns) + " seeds");
    for (std::uint64_t seed = first;; ++seed) {
      if (!seen.insert(seed).second) throw bad("seed " + std::to_string(seed) + " is given twice");
      seeds.push_back(seed);
      if (seed == last) break;
    }
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
    if (rest.empty()) throw bad("a trailing comma");
  }
  return seeds;
}

template <class Settings, class = void>
struct HasAutomaticModes : std::false_type {};
template <class Settings>
struct HasAutomaticModes<Settings, std::void_t<decltype(std::declval<Settings&>().automaticTransformation = true,
                                                        std::declval<Settings&>().adaptiveScaling = true)>>
    : std::true_type {};

/// A filter of the study: the preset of `kind`, with MJUKF's automatic T and adaptive ξ where `automatic`.
struct StudyFilter {
  std::string name;
  FilterKind kind;
  bool automatic;
};

/// The filters a study can run on `Model`: mjukf-auto only where MJUKF's settings have the automatic
/// modes (automaticTransformation, adaptiveScaling).
template <class Model>
std::vector<StudyFilter> studyFilters() {
  std::vector<StudyFilter> filters{{"jukf", FilterKind::JointUkf, false},
                                   {"mjukf", FilterKind::ModifiedJointUkf, false},
                                   {"dual", FilterKind::DualUkf, false}};
  if constexpr (HasAutomaticModes<ModifiedJointUkfSettingsFor<Model>>::value)
    filters.push_back({"mjukf-auto", FilterKind::ModifiedJointUkf, true});
  return filters;
}

/// Splits a comma-separated list of names and looks each up in `choices`, refusing unknown names,
/// repeats and an empty list, naming `flag`.
template <class Choice>
std::vector<Choice> parseChoices(const std::string& flag, const std::string& text, const std::vector<Choice>& choices) {
  std::string known;
  for (const auto& c : choices) known += (known.empty() ? "" : ", ") + c.name;
  std::vector<Choice> chosen;
  std::string_view rest = text;
  for (;;) {
    const std::size_t comma = rest.find(',');
    const std::string name(rest.substr(0, comma));
    const Choice* found = nullptr;
    for (const auto& c : choices)
      if (c.name == name) found = &c;
    if (found == nullptr) throw UsageError(flag + " takes a comma-separated list of " + known + ", not '" + name + "'");
    for (const auto& c : chosen)
      if (c.name == name) throw UsageError(flag + " names '" + name + "' twice");
    chosen.push_back(*found);
    if (comma == std::string_view::npos) break;
    rest.remove_prefix(comma + 1);
  }
  return chosen;
}

/// A scenario of the study: the true parameters over time, the length of the run and, for the
/// parameter change, the ξ the hand-tuned MJUKF takes there.
template <class Param>
struct StudyScenario {
  std::string name;
  TrueParameters<Param> truth{};
  double duration = 0;
  std::optional<double> scaling;
  /// Q_θ of the dual UKF where the parameters change (its presets have none: constant parameters).
  std::optional<double> parameterProcessNoise;
  /// Faults forced on the filters (the forced scenarios below): the data's y is `measurementGain` × the
  /// plant's (a sensor gain the model gets wrong), and every filter's Q of the state is
  /// `processNoiseScale` × its preset's. `faultAt` (s) is when the fault starts, for the count of
  /// updates to the first alarm.
  double measurementGain = 1;
  double processNoiseScale = 1;
  double faultAt = std::numeric_limits<double>::quiet_NaN();
  /// The plant as the filters model it (`matched`): the data drawn with the dual UKF's preset Q of the
  /// state and Q_θ per measurement interval and its R, and every filter given that Q, Q_θ (the MJUKF
  /// where it follows the covariance of θ̂) and R, with one time update over each whole measurement
  /// interval (FilterSetup::wholeIntervalTimeUpdates).
  bool matchedNoise = false;
  /// Every filter started at the truth (`true-start`): x̂₀ the simulation's true initial state and θ̂₀ the
  /// true parameters, P₀ the preset's. A filter that moves away from the truth on the noise alone shows a
  /// bias of its own, apart from how fast it converges from a first guess.
  bool startAtTruth = false;
};

/// The forced scenarios' sizes: a jump of every parameter by a quarter of its value halfway through,
/// which the presets' constant parameters cannot follow (no Q_θ); a sensor gain 10 % off; a Q of the
/// state ten thousand times too small. Faults a filter cannot absorb: each should end in an alarm.
constexpr double kForcedJump = 1.25, kForcedSensorGain = 1.1, kForcedProcessNoiseScale = 1e-4;

template <class Plant>
std::vector<StudyScenario<typename Plant::Param>> studyScenarios() {
  using Experiment = typename Plant::Experiment;
  std::vector<StudyScenario<typename Plant::Param>> scenarios{
      {"static", {Experiment::Model::trueParameters()}, double(Experiment::duration), std::nullopt, std::nullopt}};
  if (const auto change = Plant::parameterChange())
    scenarios.push_back({"change",
                         {Experiment::Model::trueParameters(), change->after, change->at},
                         change->duration,
                         change->scaling,
                         kChangeParameterProcessNoise});
  const auto forced = [](const char* name, double faultAt) {
    StudyScenario<typename Plant::Param> scenario;
    scenario.name = name;
    scenario.truth = {Experiment::Model::trueParameters()};
    scenario.duration = double(Experiment::duration);
    scenario.faultAt = faultAt;
    return scenario;
  };
  scenarios.push_back(forced("jump", double(Experiment::duration) / 2));
  scenarios.back().truth = {Experiment::Model::trueParameters(), kForcedJump * Experiment::Model::trueParameters(),
                            double(Experiment::duration) / 2};
  scenarios.push_back(forced("sensor-gain", 0));
  scenarios.back().measurementGain = kForcedSensorGain;
  scenarios.push_back(forced("small-q", 0));
  scenarios.back().processNoiseScale = kForcedProcessNoiseScale;
  scenarios.push_back(forced("matched", std::numeric_limits<double>::quiet_NaN()));
  scenarios.back().matchedNoise = true;
  scenarios.push_back(forced("true-start", std::numeric_limits<double>::quiet_NaN()));
  scenarios.back().startAtTruth = true;
  return scenarios;
}

template <int N>
std::array<double, N> filledWithNan() {
  std::array<double, N> values;
  values.fill(std::nan(""));
  return values;
}

/// What the study keeps of one filter's run.
template <int ParamDim>
struct StudyResult {
  std::array<double, ParamDim> rmse{};
  std::array<double, ParamDim> finalEstimate{};
  /// (θ̂ − θ)ᵀ P_θ⁻¹ (θ̂ − θ) at the last row, with the filter's own P_θ; NaN for a filter that reports none.
  double nees = std::nan("");
  bool diverged = false;
  /// The filter's health at the end of the run (health.hpp): its verdict then.
  Health health = Health::Ok;
  /// The first alarm of the run, and the run's complete blocks and those that raised an alarm.
  Health firstAlarm = Health::Ok;
  long blocks = 0;
  long alarmedBlocks = 0;
  /// maxᵢ |θ̂ᵢ − θᵢ| / |θᵢ| at the last row (NaN when the run stopped early).
  double finalRelativeError = std::nan("");
  /// The largest |ρᵢⱼ| (i ≠ j) of the filter's final covariance of θ̂; NaN for a filter that reports none.
  double parameterCorrelation = std::nan("");
  /// The standard deviations of the final θ̂ from that covariance; NaN for a filter that reports none.
  std::array<double, ParamDim> finalSigma = filledWithNan<ParamDim>();
  Status status = Status::Ok;
  /// Measurement updates from the forced fault to the first alarm (health.hpp's `alarmAtUpdate`): 0 for
  /// an alarm at the fault's own update, negative for one raised before the fault; unset without an
  /// alarm or a forced fault.
  std::optional<long> updatesToAlarm;
  long stoppedAtRow = 0;  ///< the refused row, or the last row when the run went through
  long repairs = 0;
  long rejected = 0;
  /// The changes of θ the automatic MJUKF's test found; unset for the other filters.
  std::optional<long> parameterChanges;
};

/// Diverged: the filter refused a step (the run stopped early), or a final parameter estimate is not
/// finite, or for some i the final error |θ̂ᵢ − θᵢ| exceeds kDivergenceBound × the larger of |θᵢ| and
/// the first guess's error |θ̂ᵢ₀ − θᵢ(0)|: the estimate ended farther from the truth than it started
/// and than the truth's own size. (A noisy estimate of a small parameter is not counted as diverged.)
template <class Model>
bool divergedRun(const EstimateRun<Model>& run, const PlantData<Model>& data, const typename Model::Param& firstGuess) {
  if (run.outcome.status != Status::Ok || run.parameters.size() != data.parameterTruth.size()) return true;
  const auto& estimate = run.parameters.back();
  const auto& truth = data.parameterTruth.back();
  for (int i = 0; i < Model::ParamDim; ++i) {
    const double scale = std::max(std::abs(truth(i)), std::abs(firstGuess(i) - data.parameterTruth.front()(i)));
    if (!std::isfinite(estimate(i)) || !(std::abs(estimate(i) - truth(i)) <= kDivergenceBound * scale)) return true;
  }
  return false;
}

/// The setup of `filter` in `scenario`: the experiment's preset, the scenario's ξ for MJUKF, and for
/// mjukf-auto the automatic modes on top of the hand-tuned preset.
template <class Experiment, class Param>
FilterSetup<Experiment> studySetup(const StudyFilter& filter, const StudyScenario<Param>& scenario) {
  auto setup = FilterSetup<Experiment>::paper(filter.kind);
  if (scenario.startAtTruth) {
    setup.initialState = trueInitialState<Experiment>();
    setup.initialParameters = scenario.truth.before;
  }
  if (scenario.scaling) setup.modifiedJointUkf.scaling = *scenario.scaling;
  if (scenario.parameterProcessNoise)
    setup.dualUkf.parameterProcessNoise.diagonal().setConstant(*scenario.parameterProcessNoise);
  constexpr int n = Experiment::Model::StateDim;
  constexpr int p = Experiment::Model::ParamDim;
  setup.ukf.processNoise *= scenario.processNoiseScale;
  setup.jointUkf.processNoise.template topLeftCorner<n, n>() *= scenario.processNoiseScale;
  setup.modifiedJointUkf.processNoise *= scenario.processNoiseScale;
  setup.dualUkf.processNoise *= scenario.processNoiseScale;
  if (scenario.matchedNoise) {
    setup.wholeIntervalTimeUpdates = true;     // Q per time update covers the interval, as the data's w
    const auto plant = Experiment::dualUkf();  // the noise the data is drawn with (matchNoise)
    setup.ukf.processNoise = plant.processNoise;
    setup.ukf.measurementNoise = plant.measurementNoise;
    setup.jointUkf.processNoise.template topLeftCorner<n, n>() = plant.processNoise;
    setup.jointUkf.processNoise.template bottomRightCorner<p, p>() = plant.parameterProcessNoise;
    setup.jointUkf.measurementNoise = plant.measurementNoise;
    setup.modifiedJointUkf.processNoise = plant.processNoise;
    setup.modifiedJointUkf.measurementNoise = plant.measurementNoise;
    setup.dualUkf.processNoise = plant.processNoise;
    setup.dualUkf.parameterProcessNoise = plant.parameterProcessNoise;
    setup.dualUkf.measurementNoise = plant.measurementNoise;
  }
  if constexpr (HasAutomaticModes<decltype(setup.modifiedJointUkf)>::value) {
    if (filter.automatic) {
      setup.modifiedJointUkf.automaticTransformation = true;
      setup.modifiedJointUkf.adaptiveScaling = true;
    }
    // Its Q_θ, where it follows the covariance of θ̂ that Q_θ widens.
    if (scenario.matchedNoise && setup.modifiedJointUkf.followsParameterCovariance())
      setup.modifiedJointUkf.parameterProcessNoise = Experiment::dualUkf().parameterProcessNoise;
  }
  return setup;
}

/// The `matched` scenario's data: the plant with the dual UKF preset's noise, Q and Q_θ per measurement
/// interval and R as independent noise of each measured component (its diagonal: every preset's R is
/// diagonal).
template <class Experiment>
void matchNoise(SimulationOptions<typename Experiment::Model>& options) {
  const auto plant = Experiment::dualUkf();
  ProcessNoise<typename Experiment::Model> noise;
  noise.every = Experiment::measurementEvery;
  noise.state = plant.processNoise.template cast<double>();
  noise.parameters = plant.parameterProcessNoise.template cast<double>();
  options.processNoise = noise;
  options.absoluteNoise = plant.measurementNoise.diagonal().cwiseSqrt();
}

/// Runs work(0) … work(count − 1) on `jobs` threads, calling progress(done) about once a second from
/// this thread while they run. The first exception of any work item is rethrown once all threads stop.
template <class Work, class Progress>
void runInParallel(std::size_t count, unsigned jobs, Work&& work, Progress&& progress) {
  std::atomic<std::size_t> next{0}, done{0};
  std::exception_ptr failure;
  std::mutex mutex;
  std::condition_variable finished;
  const auto worker = [&] {
    for (std::size_t i; (i = next++) < count;) {
      try {
        work(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!failure) failure = std::current_exception();
        next = count;  // start no more work
      }
      {
        const std::lock_guard<std::mutex> lock(mutex);
        ++done;
      }
      finished.notify_one();
    }
  };
  std::vector<std::thread> threads;
  for (unsigned j = 1; j < jobs && j < count; ++j) threads.emplace_back(worker);
  std::thread last(worker);
  {
    std::unique_lock<std::mutex> lock(mutex);
    while (!finished.wait_for(lock, std::chrono::seconds(1), [&] { return done == count || failure; }))
      progress(done.load());
  }
  last.join();
  for (auto& thread : threads) thread.join();
  if (failure) std::rethrow_exception(failure);
}

inline std::string rmseColumn(const Quantity& q) { return std::string("rmse_") + q.name; }

/// Box plots of each parameter's RMSE per filter in `scenario`, from the study's CSV (the script's csv1),
/// leaving out the diverged runs; a filter none of whose runs is left (`shown[f]` false) gets no box, as
/// gnuplot refuses a plot without a point. The PNG and its script join `outputs`.
template <class Plant>
void drawStudyPlot(Plotter& plotter, OutputFiles& outputs, const std::string& png, const std::string& csv,
                   const std::string& scenario, const std::vector<StudyFilter>& filters, const std::vector<bool>& shown,
                   int divergedColumn) {
  constexpr int p = static_cast<int>(Plant::parameters.size());
  std::string tics;
  for (std::size_t f = 0; f < filters.size(); ++f)
    tics +=
        format("%s\"%s%s\" %zu", f > 0 ? ", " : "", filters[f].name.c_str(), shown[f] ? "" : " (all diverged)", f + 1);
  std::string s = "set datafile separator ','\nset grid ytics\nset style fill solid 0.25 border -1\n";
  s += "set style boxplot outliers pointtype 7\nset style data boxplot\nset boxwidth 0.5\nunset key\n";
  s += format("set xtics (%s)\nset xrange [0.4:%zu.6]\n", tics.c_str(), filters.size());
  s += format(
      "set multiplot layout 1,%d title \"%s, %s: parameter RMSE per run over seeds (diverged runs left out)\" font "
      "',12'\n",
      p, Plant::title, scenario.c_str());
  for (int i = 0; i < p; ++i) {
    const Quantity& q = Plant::parameters[std::size_t(i)];
    s += format("set title \"%s\"\nset ylabel \"RMSE %s (%s)\"\n", q.label, q.label, q.unit);
    std::string plot;
    for (std::size_t f = 0; f < filters.size(); ++f)
      if (shown[f])
        plot += format(
            "%scsv1 skip 1 using (%zu):((strcol(2) eq \"%s\" && strcol(3) eq \"%s\" && column(%d) == 0) ? column(%d) : "
            "NaN) lc %zu",
            plot.empty() ? "plot " : ", \\\n     ", f + 1, filters[f].name.c_str(), scenario.c_str(), divergedColumn,
            4 + i, f + 1);
    s += (plot.empty() ? "set yrange [0:1]\nplot 2 notitle" : plot) + "\n";
  }
  s += "unset multiplot\n";
  plotter.drawScript(outputs, png, 420 * p + 100, 500, {csv}, s);
}

}  // namespace detail

/// study [--seeds LIST] [--filters LIST] [--scenarios LIST] [--jobs N] [--out-dir DIR] [--duration S]
template <class Plant>
int studyCommand(const std::vector<std::string>& words) {
  using Experiment = typename Plant::Experiment;
  using Model = typename Experiment::Model;
  using detail::format;
  namespace fs = std::filesystem;
  constexpr int p = Model::ParamDim;
  const Arguments args(words, {"--seeds", "--filters", "--scenarios", "--jobs", "--out-dir", "--duration"});
  const auto seeds = detail::parseSeeds(args.text("--seeds", "1-20"));
  const auto allFilters = detail::studyFilters<Model>();
  const auto filters = detail::parseChoices(
      "--filters", args.text("--filters", allFilters.size() > 3 ? "jukf,mjukf,mjukf-auto" : "jukf,mjukf"), allFilters);
  const auto scenarios =
      detail::parseChoices("--scenarios", args.text("--scenarios", "static"), detail::studyScenarios<Plant>());
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  const auto jobs = static_cast<unsigned>(args.integer("--jobs", cores, 1, 1024));
  if (args.has("--duration"))  // one length for every scenario: for short trials and tests
    requireSimulationDuration("--duration", args.number("--duration", 0), Experiment::stepSize);
  const std::string outDir = args.text("--out-dir", std::string("study_") + Plant::slug);
  if (seeds.size() * scenarios.size() > kMaxStudyRuns)
    throw UsageError("--seeds and --scenarios make more than " + std::to_string(kMaxStudyRuns) + " runs");

  // The output directory is checked before any run, so that a long study cannot fail at its end: the
  // temporaries of the CSV and the table are made now (the previous files stay until the commit).
  std::error_code error;
  fs::create_directories(outDir, error);
  if (error) throw UsageError("--out-dir " + outDir + ": cannot create the directory: " + error.message());
  const auto path = [&](const std::string& name) {
    return (fs::path(outDir) / (std::string(Plant::slug) + "_" + name)).string();
  };
  const std::string csvPath = path("study.csv");
  OutputFiles outputs;  // every file of the study, put in place together at its end (report.finish)
  const OutputFile* csvFile = nullptr;
  const OutputFile* tableFile = nullptr;
  try {
    csvFile = &outputs.add(csvPath);
    tableFile = &outputs.add(path("study_table.txt"));
  } catch (const OutputError& e) {
    throw UsageError(std::string("--out-dir ") + outDir + ": " + e.what());
  }

  // Run r is scenario r / seeds, seed r % seeds; results[r][f] is filter f's result on it.
  const std::size_t runs = seeds.size() * scenarios.size();
  std::vector<std::vector<detail::StudyResult<p>>> results(runs);
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  const bool terminal = isatty(STDERR_FILENO) != 0;
  bool progressShown = false;
  detail::runInParallel(
      runs, jobs,
      [&](std::size_t r) {
        const auto& scenario = scenarios[r / seeds.size()];
        auto options = experimentSimulation<Experiment>(seeds[r % seeds.size()], scenario.truth);
        options.duration = args.has("--duration") ? args.number("--duration", 0) : scenario.duration;
        if (scenario.matchedNoise) detail::matchNoise<Experiment>(options);
        auto data = simulateExperiment<Experiment>(options);
        for (auto& y : data.y) y *= scenario.measurementGain;
        const long rmseFrom = Experiment::rmseFromRow < data.rows() ? Experiment::rmseFromRow : 0;
        for (const auto& filter : filters) {
          const auto setup = detail::studySetup<Experiment>(filter, scenario);
          const auto run = runFilter(Model(), setup, data);
          detail::StudyResult<p> result;
          const auto rmse = parameterRmse(run, data, rmseFrom);
          for (int i = 0; i < p; ++i) {
            result.rmse[std::size_t(i)] = rmse(i);
            result.finalEstimate[std::size_t(i)] = run.parameters.empty() ? std::nan("") : run.parameters.back()(i);
          }
          result.diverged = detail::divergedRun(run, data, setup.initialParameters);
          if (!run.parameters.empty() && run.parameters.size() == data.parameterTruth.size()) {
            const auto& truth = data.parameterTruth.back();
            result.finalRelativeError =
                ((run.parameters.back() - truth).array().abs() / truth.array().abs()).maxCoeff();
          }
          result.health = run.health;
          result.firstAlarm = run.healthStatistics.firstAlarm;
          result.blocks = run.healthStatistics.blocks;
          result.alarmedBlocks = run.healthStatistics.alarmedBlocks;
          if (run.healthStatistics.firstAlarm != Health::Ok && std::isfinite(scenario.faultAt)) {
            // Updates are counted from 1; the fault's own is the first at or after faultAt.
            const long faultUpdate =
                long(std::ceil(scenario.faultAt / (Experiment::stepSize * setup.measurementEvery) - 1e-9)) + 1;
            result.updatesToAlarm = run.healthStatistics.alarmAtUpdate - faultUpdate;
          }
          if (run.finalParameterCovariance && !run.parameters.empty() && run.outcome.status == Status::Ok) {
            const typename Model::Param error = run.parameters.back() - data.parameterTruth.back();
            const auto factor = run.finalParameterCovariance->llt();
            if (factor.info() == Eigen::Success) result.nees = error.dot(factor.solve(error));
            const auto& c = *run.finalParameterCovariance;
            if (p >= 2 && c.allFinite()) {  // the MJUKF that does not follow its P_θ reports NaN
              double largest = 0;
              for (int i = 0; i < p; ++i)
                for (int j = 0; j < i; ++j)
                  largest = std::max(largest, double(std::abs(c(i, j)) / std::sqrt(c(i, i) * c(j, j))));
              result.parameterCorrelation = largest;
            }
            for (int i = 0; i < p; ++i) result.finalSigma[std::size_t(i)] = std::sqrt(double(c(i, i)));
          }
          result.status = run.outcome.status;
          result.stoppedAtRow = run.outcome.row;
          result.repairs = run.outcome.repairs;
          result.rejected = run.outcome.rejected;
          result.parameterChanges = run.parameterChanges;
          results[r].push_back(result);
        }
      },
      [&](std::size_t done) {
        const double seconds = elapsed();
        std::cerr << (terminal ? "\r" : "")
                  << format("study: %zu/%zu runs done, %.0f s, about %.0f s left", done, runs, seconds,
                            done > 0 ? seconds * double(runs - done) / double(done) : 0.0)
                  << (terminal ? "" : "\n") << std::flush;
        progressShown = true;
      });
  if (progressShown) std::cerr << (terminal ? "\n" : "") << format("study: %zu runs in %.1f s\n", runs, elapsed());

  // The CSV, one row per scenario × seed × filter, in that order.
  std::vector<std::string> header{"seed", "filter", "scenario"};
  for (const auto& q : Plant::parameters) header.push_back(detail::rmseColumn(q));
  header.insert(header.end(), {"diverged", "status", "stopped_at_row", "repairs", "rejected"});
  for (const auto& q : Plant::parameters) header.push_back(std::string("final_") + q.name);
  header.insert(header.end(), {"nees", "health", "updates_to_alarm", "first_alarm", "blocks", "alarmed_blocks",
                               "final_relative_error", "parameter_correlation"});
  for (const auto& q : Plant::parameters) header.push_back(std::string("sigma_") + q.name);
  header.push_back("parameter_changes");
  const int divergedColumn = 4 + p;
  {
    CsvWriter csv(*csvFile, header);
    for (std::size_t r = 0; r < runs; ++r)
      for (std::size_t f = 0; f < filters.size(); ++f) {
        const auto& result = results[r][f];
        csv << std::to_string(seeds[r % seeds.size()]) << filters[f].name << scenarios[r / seeds.size()].name;
        for (double v : result.rmse) csv << v;
        csv << double(result.diverged) << std::string(toString(result.status)) << double(result.stoppedAtRow)
            << double(result.repairs) << double(result.rejected);
        for (double v : result.finalEstimate) csv << v;
        csv << result.nees << std::string(toString(result.health))
            << (result.updatesToAlarm ? double(*result.updatesToAlarm) : std::nan(""))
            << std::string(toString(result.firstAlarm)) << double(result.blocks) << double(result.alarmedBlocks)
            << result.finalRelativeError << result.parameterCorrelation;
        for (double v : result.finalSigma) csv << v;
        csv << (result.parameterChanges ? double(*result.parameterChanges) : std::nan(""));
        csv.endRow();
      }
    csv.close();
  }

  // The table: per scenario and filter, mean ± sd and median of each parameter's RMSE over the runs
  // that did not diverge, and how many diverged.
  detail::Report report;
  const auto say = [&](const std::string& line) { report.say(line); };
  say(format("%s: study over %zu seeds (%s), RMSE over rows >= %ld; statistics over the runs that did not diverge",
             Plant::title, seeds.size(), args.text("--seeds", "1-20").c_str(), Experiment::rmseFromRow));
  say(format(
      "diverged: the filter refused a step, or a final estimate is not finite or off by more than %g x the larger",
      kDivergenceBound));
  say("  of the truth and the first guess's error; alarm: the filter's health monitor said the run ended with an alarm "
      "(its verdict then:");
  say("  an alarm of the last block, or one that stands while half of the last blocks raised one; docs/robustness.md,");
  say("  \"The health monitor\"); unflagged: runs that diverged with every step taken, no alarm,");
  say("  and the truth outside the 99.9 % region of the filter's own covariance of the final θ̂ (none: outside);");
  say(format(
      "  alarm/accurate: of the runs whose every final θ̂ is within %g %% of the truth, those with an alarm at the end",
      100 * kAccurateBound));
  Plotter plotter;
  for (std::size_t s = 0; s < scenarios.size(); ++s) {
    say("");
    say(format("scenario %s", scenarios[s].name.c_str()));
    std::string head = format("%-11s", "filter");
    for (const auto& q : Plant::parameters)
      head += format(" %-30s %-11s", ("RMSE " + std::string(q.name) + " mean +- sd").c_str(), "median");
    say(head + " diverged alarm    unflagged  alarm/accurate  mean NEES of the final θ̂ [95 % band]");
    std::vector<bool> shown;  // whether the filter has a run that did not diverge, for the box plot
    for (std::size_t f = 0; f < filters.size(); ++f) {
      std::string line = format("%-11s", filters[f].name.c_str());
      long diverged = 0;
      for (int i = 0; i < p; ++i) {
        std::vector<double> values;
        for (std::size_t k = 0; k < seeds.size(); ++k) {
          const auto& result = results[s * seeds.size() + k][f];
          if (!result.diverged) values.push_back(result.rmse[std::size_t(i)]);
        }
        diverged = long(seeds.size() - values.size());
        line += values.empty()
                    ? format(" %-30s %-11s", "-", "-")
                    : format(" %-30s %-11.4g",
                             format("%.4g +- %.3g", detail::mean(values), detail::standardDeviation(values)).c_str(),
                             detail::median(values));
      }
      // The mean over the runs of the final NEES is χ²(N p) / N when the filter's P_θ is right.
      std::vector<double> nees;
      for (std::size_t k = 0; k < seeds.size(); ++k) {
        const double v = results[s * seeds.size() + k][f].nees;
        if (std::isfinite(v)) nees.push_back(v);
      }
      const double dof = double(nees.size()) * p;
      const std::string consistency = nees.empty()
                                          ? std::string("  -")
                                          : format("  %.3g [%.3g, %.3g]", detail::mean(nees),
                                                   detail::chiSquareQuantile(dof, -1.959964) / double(nees.size()),
                                                   detail::chiSquareQuantile(dof, 1.959964) / double(nees.size()));
      // A diverged run was flagged when the filter said so: by a refused step (its status), by an alarm
      // (its health), or by a covariance of θ̂ whose 99.9 % region holds the truth (it said it did not
      // know). Unflagged: confidently wrong while every step returned Ok.
      const double covered = detail::chiSquareQuantile(p, 3.090232);
      // For a forced fault: updates from the fault to the first alarm over the diverged runs that raised one.
      long alarmed = 0, unflagged = 0, accurate = 0, alarmedAccurate = 0;
      std::vector<double> toAlarm;
      for (std::size_t k = 0; k < seeds.size(); ++k) {
        const auto& result = results[s * seeds.size() + k][f];
        alarmed += result.health != Health::Ok;
        if (result.finalRelativeError <= kAccurateBound) {
          ++accurate;
          alarmedAccurate += result.health != Health::Ok;
        }
        unflagged +=
            result.diverged && result.status == Status::Ok && result.health == Health::Ok && !(result.nees <= covered);
        if (result.diverged && result.updatesToAlarm) toAlarm.push_back(double(*result.updatesToAlarm));
      }
      std::sort(toAlarm.begin(), toAlarm.end());
      const std::string delay = toAlarm.empty()
                                    ? std::string()
                                    : format("  fault to first alarm, diverged runs: median %.0f [%.0f, %.0f] updates",
                                             detail::median(toAlarm), toAlarm.front(), toAlarm.back());
      say(line +
          format(" %-8s %-8s %-10ld %-14s", format("%ld/%zu", diverged, seeds.size()).c_str(),
                 format("%ld/%zu", alarmed, seeds.size()).c_str(), unflagged,
                 format("%ld/%ld", alarmedAccurate, accurate).c_str()) +
          consistency + delay);
      shown.push_back(diverged < long(seeds.size()));
    }
    detail::drawStudyPlot<Plant>(plotter, outputs, path("study_" + scenarios[s].name + ".png"), csvPath,
                                 scenarios[s].name, filters, shown, divergedColumn);
  }
  report.finish(*tableFile, outputs);
  return kExitOk;
}

}  // namespace mjukf::examples
